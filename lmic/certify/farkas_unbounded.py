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

__all__ = ["ray_problem", "prove_improving_ray", "RAY_BITS"]

#: the ray is rounded to a multiple of ``2^-RAY_BITS`` (relative to its largest entry)
RAY_BITS = 30


def _q(problem: Problem) -> np.ndarray:
    s = -1.0 if problem.objective.sense == "max" else 1.0
    return s * np.asarray(problem.objective.c, dtype=float)


def ray_problem(problem: Problem) -> Problem:
    """The feasibility problem of improving rays of ``problem`` (module docstring).

    Every LMI keeps its homogeneous part only (constant column zero) and is made strict; every
    row keeps its kind with a zero constant; one row ``-1 - q . d >= 0`` is added.

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
        lmis.append(dataclasses.replace(lmi, coeffs=sp.csc_matrix(C), strict=True))
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
    from lmic.certify.exact import exact_matrix, round_point
    from lmic.certify.psd import prove_psd

    d = np.asarray(d, dtype=float).ravel()
    if d.size != problem.n or not np.all(np.isfinite(d)) or not np.any(d):
        return {"proven": False, "reason": "no finite non-zero ray of the right length"}
    top = float(np.max(np.abs(d)))
    point = round_point(d / top, RAY_BITS)  # a positive multiple of a ray is a ray
    dq = [Fraction(v) for v in point.fractions()]
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
