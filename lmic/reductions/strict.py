"""Strict inequalities: the reduction every backend shares.

Interior-point and first-order solvers only know closed cones, so strict constraints are
reduced to closed ones before lowering, and the answer is mapped back. Two reductions exist;
``SolveOptions.strict`` chooses between them (:data:`STRATEGIES`).

``fixed-margin``
    Every strict LMI becomes ``F_i(x) >= delta I`` and every strict row ``a0 + a . x >= delta``;
    the objective is kept (optimisation problems) or is ``0`` (feasibility problems). For an
    optimisation problem ``delta = max(SolveOptions.margin, 10 tol)`` (absolute, default
    ``1e-7``; never below ten times the solver's tolerance, so that the solver's own error
    cannot use the margin up: SCS, whose tolerance is floored at ``1e-6``, gets ``1e-5``). For
    a feasibility problem:

    * *scale-free* problems (every LMI has ``F0 = 0`` and every row ``a0 = 0``: the feasible set
      is a cone, e.g. Lyapunov-type LMIs ``A^T P + P A < 0, P > 0``): the scale of ``x`` is
      fixed by ``trace F_i(x) <= dim F_i`` for every strict LMI (``a . x <= 1`` for strict
      rows), and ``delta = max(SolveOptions.relative_margin, 10 tol)`` (default
      :data:`RELATIVE_MARGIN`, ``1e-4``) is then a margin *relative to the mean eigenvalue*: any point returned has
      ``lambda_min(F_i) >= 1e-4 * trace(F_i) / dim(F_i)``, eight orders of magnitude above the
      float64 evaluation error the certifier allows for, and far below the relative margins of
      the problems met in practice (``0.01 .. 0.3``; a problem whose best relative margin is
      below ``1e-4`` goes on to ``max-margin``, which decides it);
    * other problems: ``delta = max(SolveOptions.margin, 10 tol)`` (absolute), the closed
      constraints as given (there is a constant term to give the scale).

    Without an objective an interior-point method stops at the first point that meets the
    constraints to the tolerance, typically in a third of the iterations of ``max-margin``
    (Clarabel on ``qib.thm1``, n = 20: 6 against 17). The margin the point *achieves* is
    measured and recorded (``Solution.margin``: ``min_i lambda_min(F_i) / (trace F_i / dim F_i)``
    for scale-free problems, ``min_i lambda_min(F_i)`` otherwise, strict rows included) and
    the imposed one in ``Solution.info["imposed_margin"]``.

``max-margin`` (feasibility problems)
    Add a scalar ``t`` and solve ``max t`` subject to ``F_i(x) >= t I`` for every strict LMI,
    ``a0 + a . x >= t`` for every strict row, the closed constraints unchanged, ``t <= 1`` and,
    for scale-free problems, the same trace normalisation (``t`` is then a relative margin, and
    ``x`` cannot drift to infinity: SDPA fed the raw homogeneous LMI returns ``P ~ 1e17``).
    ``t* = Solution.margin`` is the problem's own number, the same on every backend. Decisions:

    * solver ``optimal`` and ``t* > 10 tol``, or ``0 < t* <= 10 tol`` at a point that verifies
      (:func:`verify_point`): ``feasible``;
    * solver ``optimal`` and ``t* <= 0``, or ``0 < t* <= 10 tol`` with a dual that verifies as a
      Farkas certificate: ``infeasible``, with the dual of the margin problem as Farkas
      certificate (``Z_i >= 0``, ``sum tr Z_i + sum y_strict <= 1``,
      ``sum_i <F_i^(k), Z_i> + a_k . y = 0``, ``farkas["strict"] = True``);
    * solver ``optimal`` and ``0 < t* <= 10 tol`` otherwise: ``inaccurate`` (undecided at this
      tolerance: SCS at ``1e-3`` finds ``t* = 1.4e-3`` on ``nonuniform.thm1`` flexible-arm,
      whose ``t*`` is positive);
    * solver ``inaccurate`` (e.g. Clarabel ``AlmostSolved``) and ``t* < -10 tol``:
      ``infeasible`` **only if** the dual of the margin problem, restricted to the original
      constraints, verifies as a Farkas certificate of the original problem by the certifier's
      own test (:func:`lmic.certify.farkas.verify_farkas`: residuals relative to the
      coefficient scale, separation ``g_0 < -tol c_0``). Otherwise it stays ``inaccurate`` and
      the message says why. By weak duality every dual point bounds
      ``t <= <F0, Z> + a0 . y + y_cap``; a dual with ``A'(Z, y) = 0`` and negative value is a
      closed infeasibility certificate whatever the primal point, which near such a supremum
      is typically huge (``|x| ~ 1e5``, why the solver could not reach full accuracy). The
      sign of ``t*`` alone proves nothing: an inaccurate solve is not evidence.

``auto`` (the default)
    Optimisation problems: ``fixed-margin``. Feasibility problems:

    * *small* problems (:func:`is_small`: ``sum d_i^2 <=`` :data:`SMALL_PSD` and ``n <=``
      :data:`SMALL_N`, solves of milliseconds) on an interior-point solver: ``max-margin``
      first. Its ``t*`` is the problem's own number, reproducible across backends (what
      ``lmic crosscheck`` compares), and one solve decides feasibility or infeasibility. If it
      ends ``inaccurate`` or in an ``error`` without a decision (the supremum of the margin is
      often approached only as ``|x| -> inf``: ``uio_dt.thm3_2`` at ``gamma = 45``, where Clarabel
      stops ``AlmostSolved`` at ``t = -3.1`` with ``P ~ 1e8``), ``fixed-margin`` is tried and
      kept if it decides (its point verifies, or its Farkas ray proves the original problem
      infeasible).
    * larger problems, and first-order solvers (SCS) at any size: ``fixed-margin`` first, kept
      when it decides: its point is a *verified strictly feasible point* (solver ``optimal`` and
      every LMI and row holds at ``x`` by the certifier's rules, :func:`verify_point`), or its
      Farkas ray proves the original problem infeasible. Otherwise ``max-margin`` decides.

Every attempt is listed in ``Solution.info["strict_attempts"]`` and the strategy of the
returned answer in ``Solution.strategy``.

Examples
--------
>>> import scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
>>> from lmic.options import SolveOptions
>>> p = Problem([Variable("p", "scalar", (1, 1))], [LMI("p > 0", 1, sp.csc_matrix([[0., 1.]]))],
...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
>>> plan(p, SolveOptions())
['max-margin', 'fixed-margin']
>>> reduced, inverse = reduce(p, SolveOptions())
>>> inverse.strategy, inverse.scale_free, reduced.n, reduced.objective.sense
('max-margin', True, 2, 'max')
>>> reduced, inverse = reduce(p, SolveOptions(), "fixed-margin")
>>> inverse.margin, reduced.n, reduced.objective.sense
(0.0001, 1, 'feasibility')
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import scipy.sparse as sp

from lmic.certify.check import Tolerances, lmi_report
from lmic.certify.farkas import ray_report, verify_farkas
from lmic.ir.problem import LinearConstraints, Objective, Problem, Variable
from lmic.ir.svec import tril_size
from lmic.options import SolveOptions
from lmic.solution import Solution

__all__ = [
    "STRATEGIES",
    "RELATIVE_MARGIN",
    "SMALL_PSD",
    "SMALL_N",
    "StrictInverse",
    "plan",
    "reduce",
    "invert",
    "solve",
    "has_strict",
    "is_scale_free",
    "is_small",
    "verify_point",
    "achieved_margin",
    "MARGIN_VARIABLE",
]

#: the values of ``SolveOptions.strict``
STRATEGIES = ("auto", "max-margin", "fixed-margin")

#: default relative margin of the fixed-margin feasibility solve of a scale-free problem
RELATIVE_MARGIN = 1e-4

#: ``auto`` treats problems with ``sum d_i^2 <= SMALL_PSD`` and ``n <= SMALL_N`` as small: every
#: shipped example (at most 474 and 54; Clarabel's max-margin solve <= 0.09 s); ``qib.thm1`` at
#: n = 10 (1000 and 106) is not (max-margin 0.18 s, 15 iterations, against 6)
SMALL_PSD = 800
SMALL_N = 100

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


def is_small(problem: Problem) -> bool:
    """``sum d_i^2 <= SMALL_PSD`` and ``n <= SMALL_N`` (solves of milliseconds).

    >>> from lmic.testing.conformance import lyapunov_problem
    >>> is_small(lyapunov_problem(-np.eye(3))), is_small(lyapunov_problem(-np.eye(40)))
    (True, False)
    """
    psd = sum(lmi.dim**2 for lmi in problem.lmis)
    return psd <= SMALL_PSD and problem.n <= SMALL_N


def plan(problem: Problem, options: SolveOptions, first_order: bool = False) -> list[str]:
    """The reductions :func:`solve` tries, in order (``[]``: nothing is strict).

    ``first_order``: the solver is a first-order method (SCS), for which ``auto`` always tries
    ``fixed-margin`` first (a maximal margin is an optimum it approaches slowly: 1e5 iterations
    on ``nonuniform.thm1`` chua, where the fixed-margin point takes 4500; on flexible-arm, whose
    largest margin is tiny, it is the reverse: 57000 against 3200, docs/backends.md).

    >>> from lmic.testing.conformance import lyapunov_problem
    >>> plan(lyapunov_problem(-np.eye(40)), SolveOptions())
    ['fixed-margin', 'max-margin']
    >>> plan(lyapunov_problem(-np.eye(2)), SolveOptions()), plan(lyapunov_problem(-np.eye(2)), SolveOptions(), True)
    (['max-margin', 'fixed-margin'], ['fixed-margin', 'max-margin'])
    >>> plan(lyapunov_problem(-np.eye(2)), SolveOptions(strict="max-margin"))
    ['max-margin']
    """
    choice = options.strict
    if choice not in STRATEGIES:
        raise ValueError(f"strict strategy '{choice}' unknown; choose one of {', '.join(STRATEGIES)}")
    if not has_strict(problem):
        return []
    if problem.objective.sense != "feasibility":
        return ["fixed-margin"]
    if choice != "auto":
        return [choice]
    if is_small(problem) and not first_order:
        return ["max-margin", "fixed-margin"]
    return ["fixed-margin", "max-margin"]


def _diagonal_positions(d: int) -> np.ndarray:
    """Storage positions of the diagonal entries (column-major lower triangle).

    >>> _diagonal_positions(3).tolist()
    [0, 3, 5]
    """
    j = np.arange(d)
    return j * d - j * (j - 1) // 2


def _identity_tril(d: int) -> np.ndarray:
    out = np.zeros(tril_size(d))
    out[_diagonal_positions(d)] = 1.0
    return out


def _trace_row(lmi: Any) -> np.ndarray:
    """``[tr F0, tr F_1, ..., tr F_n]`` of one LMI (one pass over its entries)."""
    C = lmi.coeffs.tocoo()
    on_diagonal = np.zeros(C.shape[0], dtype=bool)
    on_diagonal[_diagonal_positions(lmi.dim)] = True
    keep = on_diagonal[C.row]
    return np.bincount(C.col[keep], weights=C.data[keep], minlength=C.shape[1])


def _shift(lmi: Any, margin: float) -> Any:
    """``lmi`` with ``F0 - margin I`` and not strict."""
    C = lmi.coeffs.tocoo()
    d = _diagonal_positions(lmi.dim)
    coeffs = sp.csc_matrix(
        (
            np.concatenate([C.data, np.full(len(d), -margin)]),
            (np.concatenate([C.row, d]), np.concatenate([C.col, np.zeros(len(d), dtype=C.col.dtype)])),
        ),
        shape=C.shape,
    )
    return replace(lmi, coeffs=coeffs, strict=False)


def reduce(
    problem: Problem, options: SolveOptions, strategy: str | None = None, first_order: bool = False
) -> tuple[Problem, StrictInverse]:
    """A closed problem for one reduction, and the data to map its answer back.

    ``strategy`` defaults to the first step of :func:`plan`. Returns ``problem`` itself
    (strategy ``"none"``) when nothing is strict.
    """
    n_rows = len(problem.linear)
    sense = problem.objective.sense
    steps = plan(problem, options, first_order)
    if not steps:
        return problem, StrictInverse("none", problem.n, n_rows, sense=sense)
    strategy = strategy or steps[0]
    if strategy == "max-margin" and sense != "feasibility":
        raise ValueError("the max-margin reduction applies to feasibility problems only")
    if strategy == "max-margin":
        return _max_margin(problem)
    absolute = max(options.margin, 10.0 * options.tol)
    if sense != "feasibility":
        return _fixed_margin(problem, absolute), StrictInverse(
            "fixed-margin", problem.n, n_rows, margin=absolute, sense=sense
        )
    scale_free = is_scale_free(problem)
    delta = max(options.relative_margin, 10.0 * options.tol) if scale_free else absolute
    reduced = _fixed_margin(problem, delta, normalise=scale_free)
    return reduced, StrictInverse("fixed-margin", problem.n, n_rows, margin=delta, scale_free=scale_free, sense=sense)


def _fixed_margin(problem: Problem, margin: float, normalise: bool = False) -> Problem:
    lmis = []
    norm_rows = []
    n = problem.n
    for lmi in problem.lmis:
        if lmi.strict:
            if normalise:  # trace F(x) <= d  <=>  d - sum_k x_k tr F_k >= 0
                norm_rows.append(np.concatenate([[float(lmi.dim)], -_trace_row(lmi)[1:]]))
            lmi = _shift(lmi, margin)
        lmis.append(lmi)
    lin = problem.linear
    A = lin.A.tolil(copy=True)
    strict_rows = np.flatnonzero(np.asarray(lin.strict, dtype=bool)) if len(lin) else []
    for r in strict_rows:
        if normalise:  # a . x <= 1
            norm_rows.append(np.concatenate([[1.0], -lin.A[r].toarray().ravel()[1:]]))
        A[r, 0] = A[r, 0] - margin
    kinds, names = list(lin.kinds), list(lin.names)
    A = A.tocsr()
    if norm_rows:
        A = (
            sp.vstack([A, sp.csr_matrix(np.vstack(norm_rows))], format="csr")
            if len(lin)
            else (sp.csr_matrix(np.vstack(norm_rows)))
        )
        kinds += ["ge"] * len(norm_rows)
        names += [f"scale normalisation {k}" for k in range(len(norm_rows))]
    linear = LinearConstraints(A, kinds, [False] * len(kinds), names)
    objective = problem.objective
    if objective.sense == "feasibility":
        objective = Objective("feasibility", np.zeros(n + 1))
    return replace(problem, lmis=lmis, linear=linear, objective=objective)


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
            norm_rows.append(np.concatenate([[float(lmi.dim)], -_trace_row(lmi)[1:], [0.0]]))
    lin = problem.linear
    strict_mask = np.asarray(lin.strict, dtype=bool) if len(lin) else np.zeros(0, dtype=bool)
    t_col = -strict_mask.astype(float).reshape(-1, 1)
    A = sp.hstack([lin.A, sp.csr_matrix(t_col)], format="csr") if len(lin) else sp.csr_matrix((0, n + 2))
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
        list(lin.names) + ["margin t <= 1"] + [f"scale normalisation {k}" for k in range(len(norm_rows))],
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


def achieved_margin(problem: Problem, x: np.ndarray, scale_free: bool) -> float:
    """The margin ``x`` achieves on the strict constraints of ``problem``.

    ``min_i lambda_min(F_i(x)) / (trace F_i(x) / d_i)`` over the strict LMIs and
    ``(a0 + a . x) / |a . x|`` over the strict rows when ``scale_free``; the absolute
    ``lambda_min`` and row values otherwise. ``inf`` when nothing is strict.

    >>> from lmic.testing.conformance import lyapunov_problem
    >>> float(achieved_margin(lyapunov_problem(-np.eye(1)), np.array([2.0]), True))
    1.0
    """
    from lmic.certify.spectra import block_spectrum

    x = np.asarray(x, dtype=float)
    values = [math.inf]
    for lmi in problem.lmis:
        if not lmi.strict or lmi.dim == 0:
            continue
        F, eig = block_spectrum(lmi, x)  # shared with verify_point and the certifier
        lmin = float(eig[0])
        if scale_free:
            mean = float(np.trace(F)) / lmi.dim
            lmin = lmin / mean if mean > 0 else -math.inf
        values.append(lmin)
    lin = problem.linear
    if len(lin) and any(lin.strict):
        res = lin.residuals(x)
        for r in np.flatnonzero(np.asarray(lin.strict, dtype=bool)):
            v = float(res[r])
            if scale_free:
                v = 1.0 if v > 0 else -math.inf
            values.append(v)
    return float(min(values))


def verify_point(problem: Problem, x: np.ndarray | None) -> tuple[bool, str]:
    """Whether every LMI and row of ``problem`` holds at ``x`` by the certifier's rules.

    The LMIs are judged by :func:`lmic.certify.check.lmi_report` (strict LMIs: ``lambda_min``
    positive beyond float64 doubt, relative to the term scale; closed ones to ``1e-8``
    relative); rows likewise. Returns ``(ok, reason)``.

    >>> from lmic.testing.conformance import lyapunov_problem
    >>> verify_point(lyapunov_problem(-np.eye(1)), np.array([1.0]))
    (True, '')
    >>> verify_point(lyapunov_problem(-np.eye(1)), np.array([0.0]))[0]
    False
    """
    if x is None or not np.all(np.isfinite(x)):
        return False, "no finite point"
    tol = Tolerances()
    for lmi in problem.lmis:
        rep = lmi_report(lmi, x, tol)
        if not rep["ok"]:
            return False, f"LMI '{lmi.name}': lambda_min {rep['min_eig']:.3g}"
    lin = problem.linear
    if len(lin):
        xx = np.concatenate([[1.0], x])
        res = np.asarray(lin.A @ xx).ravel()
        scale = np.asarray(abs(lin.A) @ np.abs(xx)).ravel()
        for r, kind in enumerate(lin.kinds):
            allowed = tol.rel * scale[r] + 1e-15
            if kind == "eq":
                ok = abs(res[r]) <= allowed
            elif lin.strict[r]:
                ok = res[r] > tol.strict_rel * scale[r] and scale[r] > 0
            else:
                ok = res[r] >= -allowed
            if not ok:
                return False, f"row '{lin.names[r]}': {res[r]:.3g}"
    return True, ""


def invert(
    solution: Solution,
    inverse: StrictInverse,
    options: SolveOptions,
    problem: Problem | None = None,
) -> Solution:
    """Map a reduced problem's solution back to the original problem's space and statuses.

    ``problem`` (the original) lets the fixed-margin feasibility answer record the margin its
    point achieves, and lets an inaccurate max-margin answer with a clearly negative ``t*`` be
    checked for a Farkas certificate.
    """
    solution.strategy = inverse.strategy
    if inverse.strategy == "none":
        return solution
    if solution.status == "unbounded" and (inverse.sense == "feasibility"):
        # neither reduction of a feasibility problem has an objective that can diverge
        solution.status = "error"
        solution.message = (
            f"the solver reported 'unbounded' ({solution.native_status}) for the "
            f"{inverse.strategy} problem, whose objective is bounded: a solver failure"
        )
        solution.info.pop("ray", None)
    if inverse.strategy == "fixed-margin":
        solution.margin = inverse.margin
        if solution.farkas is not None:
            solution.farkas = dict(solution.farkas, margin=inverse.margin)
        if inverse.sense == "feasibility":
            n_lmis = len(problem.lmis) if problem is not None else None
            if n_lmis is not None:
                solution.duals = _restrict(solution.duals, n_lmis, inverse.n_rows) or {}
                if solution.farkas is not None:
                    solution.farkas = _restrict(solution.farkas, n_lmis, inverse.n_rows)
            solution.info["imposed_margin"] = inverse.margin
            solution.info["scale_free"] = inverse.scale_free
            solution.objective = None
            if problem is not None and solution.x is not None:
                solution.margin = achieved_margin(problem, solution.x, inverse.scale_free)
            if solution.status == "optimal":
                if solution.margin is not None and solution.margin <= 0:
                    solution.status = "inaccurate"
                    solution.message = (
                        f"the solver's point misses the strict constraints (margin {solution.margin:.3g}); "
                        "it met the closed ones only to its tolerance"
                    )
                else:
                    solution.status = "feasible"
            elif solution.status == "infeasible":
                solution.message = (
                    f"no point with margin {inverse.margin:g}"
                    + (" (relative, under the trace normalisation)" if inverse.scale_free else "")
                    + "; a smaller margin may exist (strict='max-margin' decides)"
                )
        return solution
    n_lmis = len(problem.lmis) if problem is not None else len(solution.duals.get("lmis", []) or [])
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
        if t > threshold or (t > 0 and problem is not None and verify_point(problem, solution.x)[0]):
            solution.status = "feasible"
        elif t <= 0 or problem is None or _dual_verifies(duals, problem):
            solution.status = "infeasible"
            solution.message = f"maximal margin t* = {t:.3g} <= 0: the strict constraints cannot be met"
            if t > 0:
                solution.message = (
                    f"maximal margin t* = {t:.3g} is within the tolerance of 0 and the dual of the margin "
                    "problem proves the strict constraints infeasible"
                )
            if duals.get("lmis") is not None:
                solution.farkas = dict(duals, strict=True)
        else:
            solution.status = "inaccurate"
            solution.message = (
                f"maximal margin t* = {t:.3g} is positive but within {threshold:.1g} (10 tol) of 0: the point "
                "does not verify and the dual is no Farkas certificate; a tighter tolerance decides"
            )
    elif solution.status == "inaccurate" and t is not None and problem is not None:
        _inaccurate_max_margin(solution, t, duals, problem, options)
    return solution


def _dual_verifies(duals: dict, problem: Problem) -> bool:
    """Whether the max-margin dual (restricted to the original constraints) is a Farkas ray."""
    if duals.get("lmis") is None or len(duals["lmis"]) != len(problem.lmis):
        return False
    try:
        return bool(verify_farkas(problem, duals).get("verified"))
    except Exception:  # noqa: BLE001 - a malformed dual is just not a certificate
        return False


def _inaccurate_max_margin(solution: Solution, t: float, duals: dict, problem: Problem, options: SolveOptions) -> None:
    """Issue an ``infeasible`` for an inaccurate max-margin solve only on a verified dual."""
    threshold = 10.0 * max(options.tol, 1e-12)
    if t >= -threshold:
        return
    report: dict[str, Any] = {"verified": False, "reason": "the solver returned no dual"}
    if duals.get("lmis") is not None and len(duals["lmis"]) == len(problem.lmis):
        report = ray_report(problem, duals)
    if report.get("verified"):
        solution.status = "infeasible"
        solution.farkas = dict(duals, strict=True)
        solution.message = (
            f"max-margin solve inaccurate ({solution.native_status}) at t* = {t:.3g} < "
            f"-{threshold:.1g}, and its dual verifies as a {report.get('kind', '')} Farkas "
            "certificate: infeasible"
        )
    else:
        why = report.get("reason") or "residuals above tolerance"
        solution.message = (
            f"max-margin solve inaccurate ({solution.native_status}) at t* = {t:.3g}: suggests "
            f"infeasibility, but its dual is not a verified Farkas certificate ({why})"
        )


def _attempt_record(sol: Solution) -> dict[str, Any]:
    return {
        "strategy": sol.strategy,
        "status": sol.status,
        "native_status": sol.native_status,
        "margin": sol.margin,
        "iterations": sol.iterations,
        "solve_s": sol.solve_s,
    }


def solve(
    problem: Problem,
    options: SolveOptions,
    run: Callable[[Problem, SolveOptions], Solution],
    first_order: bool = False,
) -> Solution:
    """Solve ``problem`` through ``run`` (a closed-problem solver), strict constraints reduced.

    Follows :func:`plan`; see the module docstring for when a second reduction runs. The
    returned solution's ``solve_s`` is the sum over the attempts.

    >>> from lmic.backends.registry import get_backend
    >>> from lmic.testing.conformance import lyapunov_problem
    >>> sol = solve(lyapunov_problem(-np.eye(2)), SolveOptions(), get_backend("clarabel")._run)
    >>> sol.status, sol.strategy, round(sol.margin, 6)
    ('feasible', 'max-margin', 0.5)
    """
    steps = plan(problem, options, first_order)
    if not steps:
        return run(problem, options)
    attempts: list[Solution] = []
    for k, strategy in enumerate(steps):
        reduced, inverse = reduce(problem, options, strategy)
        sol = invert(run(reduced, options), inverse, options, problem)
        attempts.append(sol)
        if k == len(steps) - 1 or _decided(sol, problem, strategy, steps):
            break
    chosen = _choose(attempts, problem)
    chosen.solve_s = sum(a.solve_s for a in attempts)
    if len(steps) > 1 or problem.objective.sense == "feasibility":
        chosen.info["strict_attempts"] = [_attempt_record(a) for a in attempts]
    return chosen


def _verified(sol: Solution, problem: Problem) -> bool:
    if sol.status not in ("optimal", "feasible") or sol.x is None:
        return False
    ok, why = verify_point(problem, sol.x)
    if not ok:
        sol.info["verification"] = why
    return ok


def _proven_infeasible(sol: Solution, problem: Problem) -> bool:
    """A fixed-margin ``infeasible`` whose Farkas ray also proves the original problem infeasible."""
    if sol.status != "infeasible" or not sol.farkas or sol.farkas.get("lmis") is None:
        return False
    try:
        report = verify_farkas(problem, {k: sol.farkas[k] for k in ("lmis", "linear") if k in sol.farkas})
    except Exception:  # noqa: BLE001 - a malformed ray is just not a proof
        return False
    if report.get("verified"):
        if report.get("kind") == "strict":
            sol.farkas["strict"] = True
        sol.message = (
            f"no point with margin {sol.info.get('imposed_margin', 0):g}, and the Farkas ray "
            f"proves the original problem infeasible ({report.get('kind', '')})"
        )
        return True
    return False


def _decided(sol: Solution, problem: Problem, strategy: str, steps: list[str]) -> bool:
    """Whether the attempt ``sol`` ends the plan."""
    if strategy == "fixed-margin":
        return _verified(sol, problem) or _proven_infeasible(sol, problem)
    # max-margin first (small problems): a decision unless the solve itself failed
    return sol.status in ("feasible", "optimal", "infeasible", "unbounded")


def _choose(attempts: list[Solution], problem: Problem) -> Solution:
    """The answer to return: the last attempt, unless an earlier one is better."""
    last = attempts[-1]
    if len(attempts) == 1:
        return last
    first = attempts[0]
    if first.strategy == "max-margin":
        # max-margin failed; the fixed-margin retry is kept if it decides
        return last if _verified(last, problem) or _proven_infeasible(last, problem) else first
    # fixed-margin first did not verify: max-margin decides, unless it failed outright and the
    # fixed-margin point at least has a positive margin
    if last.status in ("error", "inaccurate") and last.status != "infeasible":
        if first.x is not None and first.margin is not None and first.margin > 0:
            if last.x is None or last.margin is None or last.margin < first.margin:
                return first
    return last
