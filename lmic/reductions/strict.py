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
      A first-order solver gets the point test of the original problem as
      ``SolveOptions.accept`` (:func:`point_test`): SCS pauses every few iterations and stops at
      the first iterate that verifies (``qib.thm1``: iteration 6 instead of its own convergence
      test at 25), the certifier judging the answer as always.

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

from collections.abc import Callable
from dataclasses import replace
from typing import Any

from lmic.ir.problem import Problem
from lmic.options import SolveOptions

# the private names are re-exported for the callers that used them before the split
# (lmic.backends.strict, the deprecated alias, names some of them)
from lmic.reductions.strict_common import (  # noqa: F401
    StrictInverse,
    _diagonal_positions,
    _identity_tril,
    _restrict,
    _trace_row,
    has_strict,
    is_scale_free,
    point_test,
    verify_point,
)
from lmic.reductions.strict_fixed import _fixed_margin, _shift, achieved_margin, invert_fixed  # noqa: F401
from lmic.reductions.strict_max import (  # noqa: F401
    MARGIN_VARIABLE,
    _dual_verifies,
    _inaccurate_max_margin,
    _max_margin,
    invert_max,
)
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


def is_small(problem: Problem) -> bool:
    """``sum d_i^2 <= SMALL_PSD`` and ``n <= SMALL_N`` (solves of milliseconds).

    >>> import numpy as np
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

    >>> import numpy as np
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
        return invert_fixed(solution, inverse, problem)
    return invert_max(solution, inverse, options, problem)


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

    >>> import numpy as np
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
        opts = options
        if first_order and strategy == "fixed-margin" and problem.objective.sense == "feasibility":
            # any point of the original problem decides: a first-order solver may stop at the
            # first iterate that verifies (SolveOptions.accept), long before its own test
            opts = replace(options, accept=point_test(problem))
        sol = invert(run(reduced, opts), inverse, options, problem)
        attempts.append(sol)
        if k == len(steps) - 1 or _decided(sol, problem, strategy, steps):
            break
    chosen = _choose(attempts, problem)
    chosen.solve_s = sum(a.solve_s for a in attempts)
    if len(steps) > 1 or problem.objective.sense == "feasibility":
        chosen.info["strict_attempts"] = [_attempt_record(a) for a in attempts]
    # a Farkas ray of an attempt not returned (fixed-margin's, when max-margin decided nothing):
    # the caller's certifier may still prove it (lmic.policy: an exact proof of the ray)
    rays = [a for a in attempts if a is not chosen and a.status == "infeasible" and a.farkas is not None]
    if rays:
        chosen.info["unchosen_rays"] = rays
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
    from lmic.certify.farkas import verify_farkas  # only for an infeasible answer (import time)

    try:
        report = verify_farkas(problem, {k: sol.farkas[k] for k in ("lmis", "linear") if k in sol.farkas})
    except Exception:  # noqa: BLE001 - a malformed ray is just not a proof
        return False
    if report.get("verified"):
        if report.get("kind") == "strict":
            sol.farkas["strict"] = True
        sol.message = (
            f"no point with margin {sol.info.get('imposed_margin', 0):g}, and the Farkas ray meets "
            f"the original problem's conditions in floating point ({report.get('kind', '')}; the "
            "verdict says what the certifier proves of it)"
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
