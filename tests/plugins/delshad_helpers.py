"""Helpers for the tests of the Delshad thesis Papers C-F plugins (uio_dt, descriptor, uir, obs_control).

* ``cvx_max_margin`` / ``cvx_min``: the *independent* CVXPY formulations the random-system tests
  compare the plugins with, under the same conventions as lmic's strict-inequality reduction
  (feasibility: maximise ``t`` with every strict LMI ``M <= -t I`` and ``t <= 1``; optimisation:
  every strict ``M <= -1e-7 I``).
* ``exact_projector``, ``pinv``: the pre-processing, computed here with scipy's null space (not
  with the plugins' helpers).
* ``fix_variables``, ``with_fixed_margin``, ``point``: IR manipulations used to audit published
  points (a variable fixed by equality rows) and to run a feasibility problem with a fixed small
  margin (the bisection of uio_dt.thm4_1).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import cvxpy as cp
import numpy as np
import scipy.linalg
import scipy.sparse as sp

from lmic.ir.problem import LinearConstraints, Objective, Problem
from lmic.solution import Solution

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
MARGIN = 1e-7


def example(name: str) -> str:
    """Path of a shipped example system file."""
    path = EXAMPLES / name
    assert path.is_file(), path
    return str(path)


# -- independent pre-processing -------------------------------------------------------------------


def pinv(X: np.ndarray) -> np.ndarray:
    """Moore-Penrose pseudo-inverse (numpy)."""
    return np.linalg.pinv(np.atleast_2d(X))


def exact_projector(X: np.ndarray) -> np.ndarray:
    """``I - X X^+`` as ``W W^T`` with ``W`` an orthonormal basis of the left null space of X."""
    X = np.atleast_2d(X)
    W = scipy.linalg.null_space(X.T)
    return W @ W.T if W.size else np.zeros((X.shape[0], X.shape[0]))


# -- independent CVXPY formulations ----------------------------------------------------------------


def _sym(M):
    return (M + M.T) / 2


def uio_thm4_1_block(P, d13, d23, rho, n: int, q: int):
    """Paper C Theorem 4.1, LMI (25) (catalogue 4.3) as a CVXPY block, from its ``d13``, ``d23``
    (``<< 0`` is the condition)."""
    Z = np.zeros
    return cp.bmat(
        [
            [-P, Z((n, q)), d13, np.eye(n)],
            [Z((q, n)), -np.eye(q), d23, Z((q, n))],
            [d13.T, d23.T, -P, Z((n, n))],
            [np.eye(n), Z((n, q)), Z((n, n)), -rho * np.eye(n)],
        ]
    )


def uir_big_block(PN, P, M, Gam, a13, a14, a33, a34, rho, n: int, nw: int, nh: int):
    """Paper E Theorems 4.1 / 5.1, the main LMI (catalogue 6.2-6.3) as a CVXPY block from its
    entries (``<< 0`` is the condition)."""
    Z = np.zeros
    return cp.bmat(
        [
            [PN + PN.T, P @ M, a13, a14],
            [(P @ M).T, -Gam, Z((n, nw)), Z((n, nh))],
            [a13.T, Z((nw, n)), a33, a34],
            [a14.T, Z((nh, n)), a34.T, -rho * np.eye(nh)],
        ]
    )


def cvx_max_margin(neg_strict: list, extra: list | None = None) -> float | None:
    """``max t`` s.t. ``M <= -t I`` for each ``M`` of ``neg_strict``, ``t <= 1``; returns t*.

    ``extra`` holds further (closed) cvxpy constraints. ``None`` when the solver fails.
    """
    t = cp.Variable()
    cons = [t <= 1] + list(extra or [])
    for M in neg_strict:
        d = M.shape[0]
        cons.append(_sym(M) + t * np.eye(d) << 0)
    prob = cp.Problem(cp.Maximize(t), cons)
    prob.solve(solver=cp.CLARABEL)
    if prob.status not in ("optimal", "optimal_inaccurate"):
        return None
    return float(t.value)


def cvx_min(objective, neg_strict: list, pos_scalars: list | None = None, extra: list | None = None):
    """``min objective`` s.t. ``M <= -1e-7 I`` for every strict LMI, scalars ``>= 1e-7``.

    Returns ``(status, value)``.
    """
    cons = list(extra or [])
    for M in neg_strict:
        cons.append(_sym(M) + MARGIN * np.eye(M.shape[0]) << 0)
    for s in pos_scalars or []:
        cons.append(s >= MARGIN)
    prob = cp.Problem(cp.Minimize(objective), cons)
    try:
        prob.solve(solver=cp.CLARABEL)
    except cp.error.SolverError:
        return "error", None
    return prob.status, (None if prob.value is None else float(prob.value))


# -- IR manipulations -----------------------------------------------------------------------------


def point(prob: Problem, **values) -> np.ndarray:
    """``x`` with the given variable values (zeros for the others)."""
    full = {}
    for v in prob.variables:
        full[v.name] = values.get(v.name, np.zeros(v.shape) if v.kind != "scalar" else 0.0)
    return prob.pack(full)


def certify_point(prob: Problem, x: np.ndarray, **kwargs):
    """Certify a given point (e.g. a published solution) as if a solver had returned it."""
    from lmic.certify import certify

    return certify(prob, Solution("feasible", x=np.asarray(x, dtype=float)), **kwargs)


def fix_variables(prob: Problem, **values) -> Problem:
    """The same problem with the given variables fixed by equality rows (the others free)."""
    rows = []
    for name, value in values.items():
        var = prob.variable(name)
        packed = var.pack(value)
        for k, val in enumerate(packed):
            row = np.zeros(1 + prob.n)
            row[0] = -val
            row[1 + var.offset + k] = 1.0
            rows.append(row)
    A = sp.vstack([prob.linear.A, sp.csr_matrix(np.array(rows))], format="csr")
    lin = prob.linear
    linear = LinearConstraints(
        A,
        list(lin.kinds) + ["eq"] * len(rows),
        list(lin.strict) + [False] * len(rows),
        list(lin.names) + [f"fixed {n}" for n in values for _ in range(prob.variable(n).size)],
    )
    return dataclasses.replace(prob, linear=linear)


def with_fixed_margin(prob: Problem) -> Problem:
    """A feasibility problem as ``min 0``, so strict LMIs get the fixed margin 1e-7 (not max-margin)."""
    return dataclasses.replace(prob, objective=Objective("min", np.zeros(1 + prob.n)))


def largest_eig(M: np.ndarray) -> float:
    """Largest eigenvalue of a symmetric matrix."""
    return float(np.linalg.eigvalsh(0.5 * (M + M.T))[-1])


def bisect(feasible, lo: float, hi: float, tol: float) -> tuple[float, float]:
    """Bisection for the supremum of a monotone feasibility predicate; ``feasible(lo)`` holds."""
    assert feasible(lo)
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        if feasible(mid):
            lo = mid
        else:
            hi = mid
    return lo, hi
