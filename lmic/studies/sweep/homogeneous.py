"""A parameter multiplying one positive scalar of a scale-free theorem: fixed to 1, it enters affinely.

Split out of :mod:`lmic.studies.sweep.enclosed` (which uses these helpers). When every LMI and
row of a theorem is homogeneous (``F0 = 0``, ``a0 = 0``: the feasible set is a cone), the
parameter ``p`` changes the coefficients of one scalar decision variable ``w`` only (affinely,
``beta omega`` in ``qib.thm1``) and a strict row ``w > 0`` holds, then ``w = 1`` loses nothing
(any solution ``x`` gives ``x / w``) and ``p`` enters the constant terms of the fixed problem
(:func:`fix_scalar`) affinely: the supremum is the optimum of one convex problem.

Examples
--------
>>> unfix(np.array([2.0, 3.0]), 1).tolist()
[2.0, 1.0, 3.0]
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np
import scipy.sparse as sp

from lmic.ir.problem import LinearConstraints, Objective, Problem, Variable

__all__ = ["AFFINE_RTOL", "fix_scalar", "unfix", "homogeneous_scalar"]

#: relative tolerance of the numeric affinity check of the bound data
AFFINE_RTOL = 1e-10


def _columns(problem: Problem) -> list[sp.csc_matrix]:
    return [sp.csc_matrix(lmi.coeffs) for lmi in problem.lmis] + [sp.csc_matrix(problem.linear.A)]


def _same_structure(a: Problem, b: Problem) -> bool:
    if a.n != b.n or len(a.lmis) != len(b.lmis) or len(a.linear) != len(b.linear):
        return False
    if a.linear.kinds != b.linear.kinds or a.linear.strict != b.linear.strict:
        return False
    return all(x.dim == y.dim and x.strict == y.strict for x, y in zip(a.lmis, b.lmis, strict=True))


def _scale_free(p: Problem) -> bool:
    """Every LMI has ``F0 = 0`` and every row ``a0 = 0`` (exactly): the feasible set is a cone."""
    return all(lmi.homogeneous for lmi in p.lmis) and not (
        len(p.linear) and np.any(sp.csc_matrix(p.linear.A)[:, 0].toarray())
    )


def _positive_scalar(p: Problem, k: int) -> bool:
    """A strict row ``c x_k > 0`` (``c > 0``, nothing else) holds in ``p``: every feasible ``x`` has ``x_k > 0``."""
    if not len(p.linear):
        return False
    A = sp.csr_matrix(p.linear.A)
    for r in range(A.shape[0]):
        if p.linear.kinds[r] != "ge" or not p.linear.strict[r]:
            continue
        row = A.getrow(r)
        if row.nnz == 1 and row.indices[0] == 1 + k and row.data[0] > 0:
            return True
    return False


def _moving_column(probs: list[Problem], values: list[float]) -> tuple[int | None, str]:
    """The one decision variable whose coefficients change (affinely) with the value, if exactly one does."""
    p0 = probs[0]
    if not all(_same_structure(p0, q) for q in probs[1:]):
        return None, "the bound problems differ in structure"
    moving: set[int] = set()
    for q in probs[1:]:
        for M0, M1 in zip(_columns(p0), _columns(q), strict=True):
            D = (M1 - M0).tocsc()
            if not D.shape[0]:
                continue
            scale = max(abs(M0).max() if M0.nnz else 0.0, abs(M1).max() if M1.nnz else 0.0, 1.0)
            big = np.abs(D).max(axis=0).toarray().ravel() > AFFINE_RTOL * scale
            moving.update(int(j) - 1 for j in np.flatnonzero(big))
    if len(moving) != 1 or -1 in moving:
        return None, f"the parameter changes the coefficients of {len(moving - {-1})} decision variables"
    k = moving.pop()
    v0 = values[0]
    for M0, M1, M2 in zip(*(_columns(q) for q in probs[:3]), strict=True):
        scale = max(abs(M0).max() if M0.nnz else 0.0, 1.0)
        g1 = (M1[:, 1 + k] - M0[:, 1 + k]).toarray().ravel() / (values[1] - v0)
        g2 = (M2[:, 1 + k] - M0[:, 1 + k]).toarray().ravel() / (values[2] - v0)
        if np.max(np.abs(g1 - g2), initial=0.0) > AFFINE_RTOL * scale * max(1.0, *map(abs, values)):
            return None, "the coefficients of the decision variable are not affine in the parameter"
    return k, ""


def fix_scalar(p: Problem, k: int) -> Problem:
    """``p`` with the scalar decision variable at index ``k`` fixed to 1 (its column made the constant).

    For a scale-free problem with a strict row ``x_k > 0`` this loses nothing: any solution
    ``x`` gives the solution ``x / x_k`` with ``x_k = 1``, and conversely. The row ``x_k > 0``
    (now ``1 > 0``) is dropped; the objective, derived quantities and checks too (the point is
    certified on the theorem's own problem with ``x_k = 1`` put back, :func:`unfix`).

    >>> from lmic.ir.problem import LMI
    >>> P = Problem([Variable("a", "scalar", (1, 1)), Variable("w", "scalar", (1, 1), offset=1)],
    ...     [LMI("w - a > 0", 1, sp.csc_matrix([[0.0, -1.0, 1.0]]))],
    ...     LinearConstraints(sp.csr_matrix([[0.0, 0.0, 1.0]]), ["ge"], [True], ["w > 0"]),
    ...     Objective("feasibility", [0.0, 0.0, 0.0]))
    >>> F = fix_scalar(P, 1)
    >>> F.n, F.lmis[0].coeffs.toarray().tolist(), len(F.linear)
    (1, [[1.0, -1.0]], 0)
    """
    keep = [j for j in range(1 + p.n) if j != 1 + k]

    def fixed(M: Any) -> sp.csc_matrix:
        M = sp.csc_matrix(M)
        out = M[:, keep].tolil()
        out[:, 0] = M[:, [0]] + M[:, [1 + k]]
        return sp.csc_matrix(out)

    variables: list[Variable] = []
    offset = 0
    for v in p.variables:
        if v.offset == k and v.size == 1:
            continue
        variables.append(replace(v, offset=offset))
        offset += v.size
    A = sp.csr_matrix(p.linear.A)
    # ``c x_k >= 0`` / ``> 0`` with ``c > 0`` holds at ``x_k = 1``: dropped (any other row stays)
    rows = [
        r
        for r in range(A.shape[0])
        if not (
            p.linear.kinds[r] == "ge"
            and A.getrow(r).nnz == 1
            and A.getrow(r).indices[0] == 1 + k
            and A.getrow(r).data[0] > 0
        )
    ]
    linear = LinearConstraints(
        sp.csr_matrix(fixed(A[rows, :])) if rows else sp.csr_matrix((0, offset + 1)),
        [p.linear.kinds[r] for r in rows],
        [p.linear.strict[r] for r in rows],
        [p.linear.names[r] for r in rows],
    )
    return Problem(
        variables=variables,
        lmis=[replace(lmi, coeffs=fixed(lmi.coeffs)) for lmi in p.lmis],
        linear=linear,
        objective=Objective("feasibility", np.zeros(offset + 1)),
        data=p.data,
        meta=dict(p.meta),
    )


def unfix(x: np.ndarray, k: int | None) -> np.ndarray:
    """The theorem's point from a point of :func:`fix_scalar` (``x_k = 1`` put back).

    >>> unfix(np.array([2.0, 3.0]), 1).tolist(), unfix(np.array([2.0]), None).tolist()
    ([2.0, 1.0, 3.0], [2.0])
    """
    return np.asarray(x, dtype=float) if k is None else np.insert(np.asarray(x, dtype=float), k, 1.0)


def homogeneous_scalar(probs: list[Problem], values: list[float]) -> tuple[int | None, str]:
    """The scalar ``x_k > 0`` the parameter multiplies in a scale-free problem (``None``, why, if none)."""
    if not all(_scale_free(q) for q in probs):
        return None, "the problem is not scale-free"
    k, why = _moving_column(probs, values)
    if k is None:
        return None, why
    var = next((v for v in probs[0].variables if v.offset <= k < v.offset + v.size), None)
    if var is None or var.size != 1:
        return None, "the parameter multiplies a matrix variable"
    if not all(_positive_scalar(q, k) for q in probs):
        return None, f"the parameter multiplies {var.name}, which is not constrained positive"
    return k, var.name
