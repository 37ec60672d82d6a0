"""What a Farkas certificate proves about the ORIGINAL problem: global or bounded (:func:`scope`).

The rules (exact proof: global; a homogeneous problem's float certificate: no point with relative
margin above ``rho``, a radius ``1 / rho`` in the normalisation margin >= 1; otherwise "no solution with
``||x||_inf <= R``") are in the docstring of :mod:`lmic.certify.farkas`. Split out of it; it
re-exports :func:`scope` and :func:`is_homogeneous`.

Examples
--------
>>> import scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
>>> p = Problem([Variable("p", "scalar", (1, 1))], [LMI("p > 0", 1, sp.csc_matrix([[0., 1.]]))],
...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
>>> is_homogeneous(p)
True
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from lmic.ir.problem import Problem

__all__ = ["scope", "is_homogeneous"]


def is_homogeneous(problem: Problem) -> bool:
    """True when every LMI has ``F0 = 0`` and every linear row ``a0 = 0`` (a conic feasible set).

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("p", "scalar", (1, 1))], [LMI("p > 0", 1, sp.csc_matrix([[0., 1.]]))],
    ...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
    >>> is_homogeneous(p)
    True
    """
    for lmi in problem.lmis:
        col0 = lmi.coeffs.tocsc()[:, 0]
        if col0.nnz and np.any(col0.toarray()):
            return False
    if len(problem.linear):
        a0 = problem.linear.A.tocsc()[:, 0]
        if a0.nnz and np.any(a0.toarray()):
            return False
    return True


def scope(problem: Problem, verification: dict[str, Any] | None, exact: dict[str, Any] | None = None) -> dict[str, Any]:
    """What a Farkas certificate proves about the original problem: global, bounded or nothing.

    Rules in the module docstring ("Global or bounded").

    Parameters
    ----------
    problem : Problem
        The original problem (never a reduction of it).
    verification : dict or None
        :func:`verify_farkas`'s report.
    exact : dict or None
        :func:`prove_infeasible`'s report, when an exact proof was tried.

    Returns
    -------
    dict
        ``scope`` (``"global"``, ``"bounded"`` or ``None``), ``radius`` (bounded: no solution with
        ``||x||_inf <= radius``; ``inf`` for global), ``basis`` (``"exact"``, ``"homogeneous"``,
        ``"float"``), ``rho`` (homogeneous: relative-margin bound) and ``statement`` (one line).

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> from lmic.certify.farkas_ray import verify_farkas
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("p", "scalar", (1, 1))],
    ...             [LMI("p > 0", 1, sp.csc_matrix([[0., 1.]])), LMI("-p > 0", 1, sp.csc_matrix([[0., -1.]]))],
    ...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
    >>> f = {"lmis": [np.eye(1), np.eye(1)]}
    >>> v = verify_farkas(p, f)
    >>> scope(p, v)["scope"]                    # scale-free: a float certificate bounds the relative margin
    'bounded'
    >>> from lmic.certify.farkas_exact import prove_infeasible
    >>> scope(p, v, prove_infeasible(p, f, v))["scope"]
    'global'
    >>> q = Problem([Variable("p", "scalar", (1, 1))],
    ...             [LMI("p >= 0", 1, sp.csc_matrix([[0., 1.]]), strict=False),
    ...              LMI("-1 - p >= 0", 1, sp.csc_matrix([[-1., -1.0000001]]), strict=False)],
    ...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
    >>> s = scope(q, verify_farkas(q, {"lmis": [np.eye(1), np.eye(1)]}, repair=False))
    >>> s["scope"], f"{s['radius']:.6g}"
    ('bounded', '1e+07')
    """
    if exact is not None and exact.get("proven"):
        return {
            "scope": "global",
            "radius": math.inf,
            "basis": "exact",
            "rho": None,
            "statement": f"infeasible: exact rational Farkas certificate ({exact.get('kind')})",
        }
    v = verification or {}
    if not v.get("verified"):
        return {"scope": None, "radius": None, "basis": None, "rho": None, "statement": "no verified certificate"}
    g0, tau = float(v.get("g0") or 0.0), float(v.get("tau") or 0.0)
    radius = float(v.get("radius") or 0.0)
    if v.get("kind") == "strict" and tau > 0 and is_homogeneous(problem):
        # a scale-free problem: every point with margin mu has mu <= rho ||x||_inf, at any scale.
        # That bounds the RELATIVE margin; it does not exclude a point with a smaller one: a
        # Hurwitz A with an eigenvalue at -3e-8 and ill-conditioned eigenvectors has Lyapunov
        # solutions of relative margin 1e-10 below such a rho (tests/certify/test_farkas_scope.py).
        # In the normalisation margin >= 1 it is a radius, R = 1 / rho: bounded, never global.
        mb = v.get("margin_bound")
        rho = float(mb) if mb is not None else None
        if rho is not None and rho > 0 and math.isfinite(rho):
            return {
                "scope": "bounded",
                "radius": 1.0 / rho,
                "basis": "homogeneous",
                "rho": rho,
                "statement": (
                    "homogeneous (scale-free) problem: no point has relative margin above "
                    f"{rho:.3g} (margin per unit of ||x||_inf, strict Farkas certificate), i.e. no "
                    f"solution with margin >= 1 and ||x||_inf < {1.0 / rho:.6g}; a point with a "
                    "smaller relative margin is not excluded (an exact proof, --exact, decides)"
                ),
            }
    if g0 < 0 and radius > 0 and not math.isfinite(radius):
        # a float check cannot show g_k = 0 exactly (its own rounding is not accounted for), so
        # an infinite radius is not a statement lmic can make: nothing beyond the float
        # residual's rounding level is claimed, and that level was not recorded
        return {
            "scope": None,
            "radius": None,
            "basis": "float",
            "rho": None,
            "statement": (
                "the float residual vanishes, but float arithmetic cannot prove it zero: "
                "no radius is claimed; an exact proof (--exact) decides"
            ),
        }
    if g0 < 0 and radius > 0:
        floor = float(v.get("residual_floor") or 0.0)
        raw = v.get("residual_raw")  # sum |g_k| before the rounding floor (older records: from the radius)
        by_rounding = float(raw) <= floor if raw is not None else -g0 / radius <= floor * (1 + 1e-9)
        limit = "; the radius is set by the rounding of the float check itself" if by_rounding else ""
        return {
            "scope": "bounded",
            "radius": radius,
            "basis": "float",
            "rho": None,
            "statement": (
                f"no solution with ||x||_inf <= {radius:.6g} (float Farkas certificate, residual "
                f"{float(v.get('rel_residual') or 0.0):.2g}{limit}); a larger solution is not excluded "
                "(an exact proof, --exact, decides)"
            ),
        }
    return {
        "scope": None,
        "radius": None,
        "basis": "float",
        "rho": None,
        "statement": "the certificate bounds the margin only (separation >= 0): no infeasibility shown",
    }
