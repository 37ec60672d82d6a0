"""A dual bound valid in a box only: VSDP's bound for an approximately feasible dual point.

When no dual point can be proved feasible (:mod:`lmic.certify.enclosure_dual`), the identity
of :mod:`lmic.certify.enclosure`

    ``q_0 + q . x = sum_i <F_i(x), Z_i> + sum_r y_r l_r(x) + (q_0 - g_0(u)) + rho . x``

(``rho = q_{1:} - g_{1:}(u)``) still bounds the objective of every feasible ``x`` *with
``||x||_inf <= R``* (Jansen, Chaykin and Keil 2007, the bound ``b'y + sum_j min(0,
lambda_min(Z_j)) xbar_j`` with ``xbar`` an upper bound of the primal's eigenvalues):

* ``F_i(x) >= 0`` gives ``<F_i(x), Z_i> >= min(0, lambda_i) tr F_i(x)`` with ``lambda_i`` a
  rigorous lower bound of ``lambda_min(Z_i)`` and ``tr F_i(x) <= |t_i0| + R ||t_i||_1``;
* a ``ge`` row gives ``y_r l_r(x) >= min(0, y_r) (|a_r0| + R ||a_r||_1)``; an ``eq`` row 0;
* ``rho . x >= -R ||rho||_1``, with ``|rho|`` enclosed as in the float proof.

The bound is **conditional**: it says nothing about solutions outside the box, so lmic never
reports it as the enclosure's end, only next to it (``conditional``), with its radius, as
``infeasible-bounded`` is reported next to infeasibility. Its radius is chosen by the caller
(:func:`lmic.certify.enclosure.enclosure`: ten times the certified point's largest entry).

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
>>> p = Problem([Variable("t", "scalar", (1, 1))], [LMI("t >= 2", 1, sp.csc_matrix([[-2.0, 1.0]]))],
...             LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
>>> r = box_bound(p, {"lmis": [np.array([[1.0 - 1e-9]])], "linear": []}, 10.0)
>>> r["proven"], 1.99999 < r["lower"] <= 2.0
(True, True)
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from lmic.certify.enclosure_float import _SAFE, _down, _gamma, lambda_min_lower
from lmic.certify.enclosure_repair import _jacobian, _pack, _parse, _prepare, _scale, _target
from lmic.errors import CertificateError
from lmic.ir.problem import Problem
from lmic.ir.svec import tril_rows_cols

__all__ = ["RADIUS_FACTOR", "box_bound", "best_box_bound", "verify_box_bound"]

#: the box radius is this times the largest entry of the certified point (at least 1)
RADIUS_FACTOR = 10.0


def box_bound(problem: Problem, duals: dict[str, Any], radius: float) -> dict[str, Any]:
    """A lower bound of the minimisation form's objective over feasible ``x`` with
    ``||x||_inf <= radius`` (module docstring), from the dual point as it stands.

    Returns
    -------
    dict
        ``proven`` (bool), ``lower``, ``radius``, ``norm`` (``"inf"``), ``reason``, ``dual``
        (the point, JSON-ready).

    >>> import numpy as np, scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("t", "scalar", (1, 1))], [LMI("t >= 2", 1, sp.csc_matrix([[-2.0, 1.0]]))],
    ...             LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
    >>> box_bound(p, {"lmis": [np.eye(1)], "linear": []}, 5.0)["lower"] <= 2.0
    True
    """
    R = float(radius)
    if not (math.isfinite(R) and R > 0):
        return {"proven": False, "reason": f"radius {radius!r} is not a positive number"}
    try:
        mats, y = _parse(problem, duals)
    except CertificateError as exc:
        return {"proven": False, "reason": str(exc)}
    _, q = _target(problem)
    J, _ = _jacobian(problem)
    u = _pack(problem, mats, y)
    m = u.size
    gm = _gamma(m + 2)
    absu = np.abs(u)
    g = J @ u
    Ja = abs(J)
    rho_bar = (np.abs(q[1:] - g[1:]) + gm * (np.abs(q[1:]) + (Ja @ absu)[1:])) * _SAFE
    loss = R * float(np.sum(rho_bar)) * _SAFE
    for lmi, Z in zip(problem.lmis, mats, strict=True):
        if not lmi.dim:
            continue
        lam = lambda_min_lower(Z)
        if lam >= 0:
            continue
        if not math.isfinite(lam):
            return {"proven": False, "reason": f"no eigenvalue bound for the multiplier of LMI '{lmi.name}'"}
        i, j = tril_rows_cols(lmi.dim)
        t = np.asarray(abs(lmi.coeffs.tocsr()[np.flatnonzero(i == j)]).sum(axis=0)).ravel()
        trace_sup = (float(t[0]) + R * float(np.sum(t[1:]))) * (1.0 + _gamma(lmi.dim + problem.n + 2)) * _SAFE
        loss += -lam * trace_sup * _SAFE
    lin = problem.linear
    if len(lin):
        A = abs(lin.A.tocsr())
        sup = (np.asarray(A[:, 0].toarray()).ravel() + R * np.asarray(A[:, 1:].sum(axis=1)).ravel()) * _SAFE
        for r, kind in enumerate(lin.kinds):
            if kind == "ge" and y[r] < 0:
                loss += -float(y[r]) * float(sup[r]) * (1.0 + _gamma(problem.n + 2)) * _SAFE
    j0 = np.asarray(J[0].toarray()).ravel()
    g0_err = gm * float(np.abs(j0) @ absu) * _SAFE
    lower = _down(_down(q[0] - float(g[0])) - (g0_err + loss) * _SAFE)
    return {
        "proven": bool(math.isfinite(lower)),
        "lower": lower,
        "radius": R,
        "norm": "inf",
        "reason": f"valid only for solutions with ||x||_inf <= {R:.3g} (VSDP's bound for an approximate dual point)",
        "dual": {"lmis": [Z.tolist() for Z in mats], "linear": y.tolist()},
    }


def best_box_bound(
    problem: Problem, duals: dict[str, Any], radius: float, deadline: float | None = None
) -> dict[str, Any]:
    """The better :func:`box_bound` of the solver's dual point as it stands and of the same
    point projected onto the cone and repaired (:func:`lmic.certify.enclosure_repair._prepare`
    without shift: its residual is at round-off). With ``deadline`` (a
    :func:`time.perf_counter` value), the repair is skipped once it is passed, and its steps
    stop there.

    >>> import numpy as np, scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("t", "scalar", (1, 1))], [LMI("t >= 2", 1, sp.csc_matrix([[-2.0, 1.0]]))],
    ...             LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
    >>> best_box_bound(p, {"lmis": [np.array([[0.9]])], "linear": []}, 5.0)["lower"] <= 2.0
    True
    """
    import time

    best = box_bound(problem, duals, radius)
    if deadline is not None and time.perf_counter() > deadline:
        return best
    try:
        mats, y = _parse(problem, duals)
        _, q = _target(problem)
        J, ranges = _jacobian(problem)
        mats, y, _ = _prepare(problem, J, ranges, q, mats, y, 0.0, _scale(problem, mats, y), deadline=deadline)
    except (CertificateError, np.linalg.LinAlgError, ValueError, FloatingPointError):
        return best
    other = box_bound(problem, {"lmis": mats, "linear": y}, radius)
    if other["proven"] and (not best["proven"] or other["lower"] > best["lower"]):
        return other
    return best


def verify_box_bound(problem: Problem, record: dict[str, Any]) -> dict[str, Any]:
    """Re-prove a recorded box bound from its dual point and radius (``lmic audit``).

    >>> import numpy as np, scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("t", "scalar", (1, 1))], [LMI("t >= 2", 1, sp.csc_matrix([[-2.0, 1.0]]))],
    ...             LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
    >>> r = box_bound(p, {"lmis": [np.eye(1)], "linear": []}, 5.0)
    >>> verify_box_bound(p, r)["ok"], verify_box_bound(p, dict(r, lower=2.5))["ok"]
    (True, False)
    """
    if not record.get("dual") or record.get("lower") is None or record.get("radius") is None:
        return {"ok": False, "lower": None, "reason": "no dual point or radius recorded"}
    res = box_bound(problem, record["dual"], float(record["radius"]))
    if not res["proven"]:
        return {"ok": False, "lower": None, "reason": res["reason"]}
    if float(record["lower"]) > res["lower"]:
        return {
            "ok": False,
            "lower": res["lower"],
            "reason": f"recorded box bound {float(record['lower']):.17g} exceeds the bound the dual point proves "
            f"({res['lower']:.17g})",
        }
    return {"ok": True, "lower": res["lower"], "reason": "box bound re-proved from the recorded dual point"}
