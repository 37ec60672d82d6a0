"""Strict inequalities: the reduction every backend shares (``StrictToMarginBridge``).

Interior-point and first-order solvers only know closed cones, so strict constraints are
reduced before lowering and the answer is mapped back (:func:`reduce`, :func:`invert`):

``max-margin`` (feasibility problems with strict constraints)
    Add a scalar ``t`` and solve ``max t`` subject to ``F_i(x) >= t I`` for every strict LMI,
    ``a0 + a . x >= t`` for every strict row, the closed constraints unchanged, and ``t <= 1``.
    When the problem is *scale-free* (every LMI has ``F0 = 0`` and every row ``a0 = 0``, so
    its feasible set is a cone, e.g. Lyapunov-type LMIs ``A^T P + P A < 0, P > 0``) the scale
    of ``x`` is fixed by ``trace F_i(x) <= dim F_i`` for every strict LMI (and ``a . x <= 1``
    for strict rows). Then ``t`` is a *relative* margin, ``lambda_min / mean eigenvalue``, which
    an interior-point solver maximises without ``x`` drifting to infinity (SDPA fed the raw
    homogeneous LMI returns ``P ~ 1e17``) and which a first-order solver can meet with an error
    much smaller than the margin itself. ``t* <= 10 tol`` means no ``x`` satisfies the strict
    constraints: status ``infeasible``, and the dual of the margin problem
    (``Z_i >= 0``, ``sum tr Z_i + sum y_strict = 1``, ``sum_i <F_i^(k), Z_i> + a_k . y = 0``)
    is returned in ``Solution.farkas`` with ``farkas["strict"] = True``.

``fixed-margin`` (optimisation problems)
    Every strict LMI becomes ``F_i(x) >= margin I`` and every strict row ``a0 + a . x >= margin``
    with ``margin = SolveOptions.margin``.

The strategy and the margin are recorded in ``Solution.strategy`` and ``Solution.margin``.

Examples
--------
>>> import scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
>>> from lmic.backends.base import SolveOptions
>>> p = Problem([Variable("p", "scalar", (1, 1))], [LMI("p > 0", 1, sp.csc_matrix([[0., 1.]]))],
...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
>>> reduced, inverse = reduce(p, SolveOptions())
>>> inverse.strategy, inverse.scale_free, reduced.n, reduced.objective.sense
('max-margin', True, 2, 'max')
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp

from lmic.backends.base import SolveOptions
from lmic.ir.problem import LinearConstraints, Objective, Problem, Variable
from lmic.ir.svec import tril_rows_cols, tril_size
from lmic.solution import Solution

__all__ = ["StrictInverse", "reduce", "invert", "has_strict", "is_scale_free", "MARGIN_VARIABLE"]

#: name of the margin variable added by the ``max-margin`` strategy
MARGIN_VARIABLE = "_lmic_margin_t"


@dataclass
class StrictInverse:
    """What :func:`invert` needs to map a reduced problem's solution back."""

    strategy: str
    n: int
    n_rows: int
    margin: float | None = None
    scale_free: bool = False
    sense: str = "feasibility"


def has_strict(problem: Problem) -> bool:
    """True when some LMI or linear row is strict.

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("p", "scalar", (1, 1))], [LMI("p>=0", 1, sp.csc_matrix([[0., 1.]]),
    ...             strict=False)], LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
    >>> has_strict(p)
    False
    """
    return any(lmi.strict for lmi in problem.lmis) or any(problem.linear.strict)


def is_scale_free(problem: Problem) -> bool:
    """True when every LMI has ``F0 = 0`` and every linear row ``a0 = 0`` (a conic feasible set).

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("p", "scalar", (1, 1))], [LMI("p>1", 1, sp.csc_matrix([[-1., 1.]]))],
    ...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
    >>> is_scale_free(p)
    False
    """
    if not all(lmi.homogeneous for lmi in problem.lmis):
        return False
    a0 = problem.linear.A[:, 0]
    return a0.nnz == 0 or not np.any(a0.toarray())


def _identity_tril(d: int) -> np.ndarray:
    i, j = tril_rows_cols(d)
    return (i == j).astype(float)


def reduce(problem: Problem, options: SolveOptions) -> tuple[Problem, StrictInverse]:
    """A closed problem equivalent to ``problem`` for the solver, and the data to map back.

    Returns ``problem`` itself (strategy ``"none"``) when nothing is strict.
    """
    lin = problem.linear
    n_rows = len(lin)
    if not has_strict(problem):
        return problem, StrictInverse("none", problem.n, n_rows, sense=problem.objective.sense)
    if problem.objective.sense != "feasibility":
        return _fixed_margin(problem, options.margin), StrictInverse(
            "fixed-margin", problem.n, n_rows, margin=options.margin, sense=problem.objective.sense
        )
    return _max_margin(problem)


def _fixed_margin(problem: Problem, margin: float) -> Problem:
    lmis = []
    for lmi in problem.lmis:
        if lmi.strict:
            shift = sp.csc_matrix(
                (
                    -margin * _identity_tril(lmi.dim),
                    (np.arange(tril_size(lmi.dim)), np.zeros(tril_size(lmi.dim), int)),
                ),
                shape=lmi.coeffs.shape,
            )
            lmi = replace(lmi, coeffs=lmi.coeffs + shift, strict=False)
        lmis.append(lmi)
    lin = problem.linear
    A = lin.A.tolil(copy=True)
    strict_rows = np.flatnonzero(np.asarray(lin.strict, dtype=bool)) if len(lin) else []
    for r in strict_rows:
        A[r, 0] = A[r, 0] - margin
    linear = LinearConstraints(A.tocsr(), list(lin.kinds), [False] * len(lin), list(lin.names))
    return replace(problem, lmis=lmis, linear=linear)


def _max_margin(problem: Problem) -> tuple[Problem, StrictInverse]:
    n = problem.n
    scale_free = is_scale_free(problem)
    t_var = Variable(MARGIN_VARIABLE, "scalar", (1, 1), offset=n)
    lmis = []
    norm_rows = []
    for lmi in problem.lmis:
        m = tril_size(lmi.dim)
        col = -_identity_tril(lmi.dim) if lmi.strict else np.zeros(m)
        coeffs = sp.hstack([lmi.coeffs, sp.csc_matrix(col.reshape(-1, 1))], format="csc")
        lmis.append(replace(lmi, coeffs=coeffs, strict=False))
        if lmi.strict and scale_free:
            # trace F(x) <= d  <=>  d - sum_k x_k tr F_k >= 0
            tr = np.asarray(lmi.coeffs[_identity_tril(lmi.dim) > 0].sum(axis=0)).ravel()
            norm_rows.append(np.concatenate([[float(lmi.dim)], -tr[1:], [0.0]]))
    lin = problem.linear
    strict_mask = np.asarray(lin.strict, dtype=bool) if len(lin) else np.zeros(0, dtype=bool)
    t_col = -strict_mask.astype(float).reshape(-1, 1)
    A = (
        sp.hstack([lin.A, sp.csr_matrix(t_col)], format="csr")
        if len(lin)
        else sp.csr_matrix((0, n + 2))
    )
    if scale_free:
        for r in np.flatnonzero(strict_mask):
            a = lin.A[r].toarray().ravel()
            norm_rows.append(np.concatenate([[1.0], -a[1:], [0.0]]))
    cap = np.zeros(n + 2)
    cap[0], cap[-1] = 1.0, -1.0  # 1 - t >= 0
    extra = sp.csr_matrix(np.vstack([cap, *norm_rows]))
    linear = LinearConstraints(
        sp.vstack([A, extra], format="csr"),
        list(lin.kinds) + ["ge"] * extra.shape[0],
        [False] * (len(lin) + extra.shape[0]),
        list(lin.names)
        + ["margin t <= 1"]
        + [f"scale normalisation {k}" for k in range(len(norm_rows))],
    )
    c = np.zeros(n + 2)
    c[-1] = 1.0
    reduced = Problem(
        variables=[*problem.variables, t_var],
        lmis=lmis,
        linear=linear,
        objective=Objective("max", c),
        data=problem.data,
        derived=[],
        checks=[],
        meta=dict(problem.meta),
    )
    return reduced, StrictInverse("max-margin", n, len(lin), scale_free=scale_free)


def _restrict(duals: dict | None, n_lmis: int, n_rows: int) -> dict | None:
    if not duals:
        return duals
    out = dict(duals)
    if "lmis" in out and out["lmis"] is not None:
        out["lmis"] = list(out["lmis"])[:n_lmis]
    if "linear" in out and out["linear"] is not None:
        out["linear"] = np.asarray(out["linear"], dtype=float)[:n_rows]
    return out


def invert(solution: Solution, inverse: StrictInverse, options: SolveOptions) -> Solution:
    """Map a reduced problem's solution back to the original problem's space and statuses."""
    solution.strategy = inverse.strategy
    if inverse.strategy == "none":
        return solution
    if inverse.strategy == "fixed-margin":
        solution.margin = inverse.margin
        if solution.farkas is not None:
            solution.farkas = dict(solution.farkas, margin=inverse.margin)
        return solution
    n_lmis = len(solution.duals.get("lmis", []) or [])
    x = solution.x
    t = None
    if x is not None and len(x) == inverse.n + 1:
        t = float(x[-1])
        solution.x = x[: inverse.n]
    solution.margin = t
    solution.objective = None
    duals = _restrict(solution.duals, n_lmis, inverse.n_rows) or {}
    solution.duals = duals
    if solution.farkas is not None:
        solution.farkas = _restrict(solution.farkas, n_lmis, inverse.n_rows)
    solution.info["scale_free"] = inverse.scale_free
    threshold = 10.0 * max(options.tol, 1e-12)
    if solution.status in ("optimal", "feasible") and t is not None:
        if t <= threshold:
            solution.status = "infeasible"
            solution.message = (
                f"maximal margin t* = {t:.3g} <= {threshold:.1g}: "
                "the strict constraints cannot be met"
            )
            if duals.get("lmis") is not None:
                solution.farkas = dict(duals, strict=True)
        else:
            solution.status = "feasible"
    return solution
