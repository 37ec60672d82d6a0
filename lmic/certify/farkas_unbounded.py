"""Unboundedness: an exact improving ray of an optimisation problem (its dual is infeasible).

A solver that reports ``unbounded`` (SDPA's "dual infeasible", SDPLIB's infd1) claims a
direction ``d`` along which the objective decreases without leaving the feasible set. In the
minimisation form (``q = s c``, ``s = -1`` for ``max``) ``d`` is an *improving ray* when

* ``q . d < 0`` (the objective strictly decreases along ``d``),
* ``sum_k d_k F_i^(k) >= 0`` for every LMI (its homogeneous part: ``F_i(x + t d) = F_i(x) + t
  sum_k d_k F_i^(k)``, so a feasible ``x`` stays feasible, strict or not),
* ``a_r . d = 0`` on ``eq`` rows and ``a_r . d >= 0`` on ``ge`` rows.

**What it proves.** With an improving ray, the dual problem is infeasible, and the optimal
value is ``-inf`` (``+inf`` for ``max``) *if the problem has a feasible point*; without one
it is infeasible. :func:`ray_problem` is the feasibility problem whose points are improving
rays (normalised ``q . d <= -1``, LMIs strict so that the point has a margin);
:func:`prove_improving_ray` checks a ray in exact rational arithmetic (the ray rounded to a
dyadic rational, every condition checked exactly, every LMI proved PSD by
:func:`lmic.certify.psd.prove_psd`).

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
>>> # min -t s.t. t >= 1: unbounded along d = 1
>>> p = Problem([Variable("t", "scalar", (1, 1))], [LMI("t >= 1", 1, sp.csc_matrix([[-1.0, 1.0]]), strict=False)],
...             LinearConstraints.empty(1), Objective("min", [0.0, -1.0]))
>>> prove_improving_ray(p, np.array([1.0]))["proven"], prove_improving_ray(p, np.array([-1.0]))["proven"]
(True, False)
"""

from __future__ import annotations

import dataclasses
from fractions import Fraction
from typing import Any

import numpy as np
import scipy.sparse as sp

from lmic.ir.problem import LinearConstraints, Objective, Problem

__all__ = ["ray_problem", "prove_improving_ray", "audit_unbounded", "RAY_BITS"]

#: the ray is rounded to a multiple of ``2^-RAY_BITS`` (relative to its largest entry)
RAY_BITS = 30
#: the longest entry of a recorded ray the audit reads (lmic writes about 20 characters)
RAY_TEXT_MAX = 64


def _q(problem: Problem) -> np.ndarray:
    s = -1.0 if problem.objective.sense == "max" else 1.0
    return s * np.asarray(problem.objective.c, dtype=float)


def ray_problem(problem: Problem, strict: bool = True) -> Problem:
    """The feasibility problem of improving rays of ``problem`` (module docstring).

    Every LMI keeps its homogeneous part only (constant column zero) and is made strict (with
    ``strict=False``: non-strict, for rays on the boundary of the recession cone, e.g. when a
    homogeneous part has a zero diagonal entry); every row keeps its kind with a zero constant;
    one row ``-1 - q . d >= 0`` is added.

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("t", "scalar", (1, 1))], [LMI("t >= 1", 1, sp.csc_matrix([[-1.0, 1.0]]))],
    ...             LinearConstraints.empty(1), Objective("min", [0.0, -1.0]))
    >>> r = ray_problem(p)
    >>> r.objective.sense, r.lmis[0].coeffs.toarray().tolist(), r.linear.A.toarray().tolist()
    ('feasibility', [[0.0, 1.0]], [[-1.0, 1.0]])
    """
    lmis = []
    for lmi in problem.lmis:
        C = sp.csc_matrix(lmi.coeffs, copy=True).tolil()
        C[:, 0] = 0.0
        lmis.append(dataclasses.replace(lmi, coeffs=sp.csc_matrix(C), strict=strict))
    lin = problem.linear
    q = _q(problem)
    row = sp.csr_matrix(np.concatenate([[-1.0], -q[1:]])[None, :])
    if len(lin):
        A = sp.csr_matrix(lin.A, copy=True).tolil()
        A[:, 0] = 0.0
        new_A = sp.vstack([sp.csr_matrix(A), row]).tocsr()
    else:
        new_A = row
    linear = LinearConstraints(
        new_A,
        list(lin.kinds) + ["ge"],
        [False] * len(lin) + [False],
        list(lin.names) + ["improvement q.d <= -1"],
    )
    return Problem(
        list(problem.variables),
        lmis,
        linear,
        Objective("feasibility", np.zeros(problem.n + 1)),
        meta={"ray_of": problem.meta.get("theorem") if problem.meta else None},
    )


def _exact_dot(row: np.ndarray, d: list[Fraction]) -> Fraction:
    return sum((Fraction(float(a)) * v for a, v in zip(row, d, strict=True) if a != 0.0), Fraction(0))


def prove_improving_ray(problem: Problem, d: np.ndarray) -> dict[str, Any]:
    """Prove in exact arithmetic that ``d`` (rounded to :data:`RAY_BITS` bits) is an improving ray.

    Returns
    -------
    dict
        ``proven`` (bool), ``reason``, ``ray`` (the rounded ray as strings of fractions when
        proven), ``slope`` (``q . d``, a float rounded from the exact value).
    """
    from lmic.certify.exact import round_point

    d = np.asarray(d, dtype=float).ravel()
    if d.size != problem.n or not np.all(np.isfinite(d)) or not np.any(d):
        return {"proven": False, "reason": "no finite non-zero ray of the right length"}
    top = float(np.max(np.abs(d)))
    point = round_point(d / top, RAY_BITS)  # a positive multiple of a ray is a ray
    return _prove_rational_ray(problem, point)


def _prove_rational_ray(problem: Problem, point: Any) -> dict[str, Any]:
    """:func:`prove_improving_ray` on an exact rational ray (an :class:`ExactPoint`)."""
    from lmic.certify.exact import exact_matrix
    from lmic.certify.psd import prove_psd

    dq = [Fraction(v) for v in point.fractions()]
    if not any(dq):
        return {"proven": False, "reason": "the ray is zero"}
    q = _q(problem)
    slope = _exact_dot(q[1:], dq)
    if not slope < 0:
        return {"proven": False, "reason": f"the objective does not decrease along the ray (q.d = {float(slope):.3g})"}
    lin = problem.linear
    if len(lin):
        A = lin.A.toarray()
        for r, kind in enumerate(lin.kinds):
            v = _exact_dot(A[r, 1:], dq)
            if (kind == "eq" and v != 0) or (kind == "ge" and v < 0):
                return {"proven": False, "reason": f"row '{lin.names[r]}' is not kept along the ray"}
    for lmi in problem.lmis:
        C = sp.csc_matrix(lmi.coeffs, copy=True).tolil()
        C[:, 0] = 0.0
        hom = dataclasses.replace(lmi, coeffs=sp.csc_matrix(C))
        res = prove_psd(exact_matrix(hom, point))
        if not res["proven"]:
            return {
                "proven": False,
                "reason": f"LMI '{lmi.name}': its homogeneous part is not proved PSD along the ray",
            }
    return {
        "proven": True,
        "reason": "exact improving ray: q.d < 0, every LMI's homogeneous part proved PSD and every row kept, "
        "in exact rational arithmetic",
        "ray": [str(v) for v in dq],
        "slope": float(slope),
    }


def audit_unbounded(problem: Problem, record: Any) -> dict[str, Any]:
    """Re-prove a certificate's ``unbounded`` section: its ray, exactly, on ``problem``.

    The ray is read from fraction strings (``"-3/8"``; no evaluation of text): dyadic, as
    :func:`prove_improving_ray` writes it (denominators powers of two, at most
    :data:`RAY_TEXT_MAX` characters an entry, so that a forged file cannot make the exact proof
    run on huge integers). Every condition of an improving ray is proved again in rational
    arithmetic, and the recorded ``sense`` and ``slope`` must match the problem and the exact
    ``q.d`` rounded to float.

    Returns
    -------
    dict
        ``ok`` (bool), ``field`` (the first field at fault, or ``None``) and ``message``.

    Examples
    --------
    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("t", "scalar", (1, 1))], [LMI("t >= 1", 1, sp.csc_matrix([[-1.0, 1.0]]))],
    ...             LinearConstraints.empty(1), Objective("min", [0.0, -1.0]))
    >>> audit_unbounded(p, {"ray": ["1"], "slope": -1.0, "sense": "min"})["ok"]
    True
    >>> audit_unbounded(p, {"ray": ["-1"], "slope": 1.0, "sense": "min"})["field"]
    'unbounded.ray'
    >>> audit_unbounded(p, {"ray": ["1/3"], "slope": -1 / 3, "sense": "min"})["message"]
    'unbounded.ray entries must be dyadic (denominators powers of two), as lmic writes them'
    """
    import math
    import re

    from lmic.certify.exact import ExactPoint

    def fail(fld: str, why: str) -> dict[str, Any]:
        return {"ok": False, "field": fld, "message": why}

    if not isinstance(record, dict):
        return fail("unbounded", "unbounded is not an object")
    if record.get("sense") != problem.objective.sense or problem.objective.sense == "feasibility":
        return fail(
            "unbounded.sense",
            f"unbounded.sense is {record.get('sense')!r}, the IR's objective {problem.objective.sense!r}",
        )
    ray = record.get("ray")
    pattern = re.compile(r"-?[0-9]+(/[0-9]+)?")
    if not isinstance(ray, list) or len(ray) != problem.n:
        return fail("unbounded.ray", f"unbounded.ray needs {problem.n} entries")
    if not all(isinstance(v, str) and pattern.fullmatch(v) for v in ray):
        return fail("unbounded.ray", "unbounded.ray entries must be integers or fractions 'p/q'")
    if any(len(v) > RAY_TEXT_MAX for v in ray):
        return fail("unbounded.ray", f"unbounded.ray entries are at most {RAY_TEXT_MAX} characters")
    try:
        fracs = [Fraction(v) for v in ray]
    except ZeroDivisionError:
        return fail("unbounded.ray", "unbounded.ray has a zero denominator")
    if any(f.denominator & (f.denominator - 1) for f in fracs):
        return fail(
            "unbounded.ray", "unbounded.ray entries must be dyadic (denominators powers of two), as lmic writes them"
        )
    den = math.lcm(*(f.denominator for f in fracs)) if fracs else 1
    res = _prove_rational_ray(problem, ExactPoint([int(f * den) for f in fracs], den))
    if not res["proven"]:
        return fail("unbounded.ray", f"the recorded ray is not an improving ray: {res['reason']}")
    if record.get("slope") != res["slope"]:
        return fail(
            "unbounded.slope", f"unbounded.slope differs: recorded {record.get('slope')}, recomputed {res['slope']}"
        )
    return {"ok": True, "field": None, "message": res["reason"]}
