"""``auto``: a route of backends chosen from the problem's size and shape.

The rule (measured numbers in ``docs/backends.md``, ``benchmarks/routes.py``):

* Strict feasibility problems above a tiny size (``sum d_i^2 >`` :data:`SMALL_FEASIBILITY`):
  **SCS first** at tolerance :data:`FIRST_ORDER_TOL`, certified, then **CVXOPT** only if the
  certificate fails. SCS takes the fixed-margin route of :mod:`lmic.reductions.strict` (a point
  with relative margin ``10 tol = 1e-2`` under the trace normalisation, verified, max-margin
  only if it is not): on ``qib.thm1`` at n = 40 it is certified in ~0.3 s where hand-written
  CVXPY + Clarabel takes 30-140 s. Below the crossover, Clarabel (the embedded default solver).
* Other small problems (``sum of d_i^2 <= SMALL`` and ``n <= SMALL_N``): Clarabel (all solvers
  take milliseconds; Clarabel is the most accurate).
* Larger optimisation problems: the interior-point method that suits the shape
  (:func:`schur_complement_shape`): CVXOPT (Schur complement) when the variables are at most the
  dimension of the PSD cone, Clarabel otherwise, then the other, then SDPA (it stops short of a
  certified optimum on the bounded-real lemma). With ``first_order`` (``auto:first-order``) SCS
  comes first; :mod:`lmic.routes` stops when its enclosure meets ``--gap``. Backends that are
  not installed, or cannot take the problem (Clarabel refuses PSD blocks whose dense KKT block
  would not fit in memory), are left out of the route.

:class:`AutoBackend` runs the first backend of the route; the solve policy (:mod:`lmic.policy`)
starts from this route and escalates through the rest of its order.

Examples
--------
>>> AutoBackend.name
'auto'
"""

from __future__ import annotations

from typing import ClassVar

from lmic.backends.base import Backend, SolveOptions
from lmic.backends.lowering import has_strict
from lmic.ir.problem import Problem
from lmic.solution import Solution

__all__ = [
    "AutoBackend",
    "route",
    "choose",
    "step_options",
    "schur_complement_shape",
    "SMALL",
    "SMALL_N",
    "SMALL_FEASIBILITY",
    "FIRST_ORDER_TOL",
    "FIRST_ORDER_OPTIMISATION",
]

#: tolerance of a first-order step of the route: its answer is certified, not trusted, and
#: the normalised margin (~0.1 on qib.thm1) is far above it
FIRST_ORDER_TOL = 1e-3

#: problems with ``sum d_i^2`` at most this and at most :data:`SMALL_N` variables are "small"
SMALL = 2500
SMALL_N = 200
#: strict feasibility problems with ``sum d_i^2`` at most this go to Clarabel; above it the
#: certified first-order route is faster (measured crossover on qib.thm1: n = 4, sum d_i^2 = 160,
#: 25 ms both; n = 6, sum d_i^2 = 360: SCS 31 ms, Clarabel 51 ms; docs/backends.md)
SMALL_FEASIBILITY = 256
#: optimisation problems that are not small start with a first-order solve (SCS) whose
#: enclosure may already meet ``--gap``; measured off: on the bounded-real lemma SCS at a
#: moderate tolerance never met a 1e-4 gap and the interior-point step was needed anyway
#: (benchmarks/routes.py, docs/backends.md)
FIRST_ORDER_OPTIMISATION = False


def _size(problem: Problem) -> tuple[int, int]:
    return sum(lmi.dim**2 for lmi in problem.lmis), problem.n


def schur_complement_shape(problem: Problem) -> bool:
    """Whether a Schur-complement interior-point method (CVXOPT, SDPA) suits ``problem``.

    They factor an ``m x m`` matrix (``m`` variables) built from the PSD blocks, so they win when
    the variables are few against the PSD dimension: ``m <= sum d_i (d_i + 1) / 2`` (the
    dimension of the PSD cone). Otherwise Clarabel's sparse KKT system is cheaper.

    >>> from lmic.testing.conformance import lyapunov_problem
    >>> import numpy as np
    >>> schur_complement_shape(lyapunov_problem(-np.eye(3)))
    True
    """
    cone = sum(lmi.dim * (lmi.dim + 1) // 2 for lmi in problem.lmis)
    return problem.n <= cone and bool(problem.lmis)


def route(problem: Problem, first_order: bool | None = None) -> list[str]:
    """The backends ``auto`` tries for ``problem``, in order.

    ``first_order`` forces (``True``) or skips (``False``) the first-order step of an
    optimisation problem that is not small; ``None`` is :data:`FIRST_ORDER_OPTIMISATION`.

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("t", "scalar", (1, 1))], [LMI("t>0", 1, sp.csc_matrix([[0., 1.]]))],
    ...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
    >>> route(p)
    ['clarabel']
    """
    psd, n = _size(problem)
    feasibility = problem.objective.sense == "feasibility"
    small = psd <= SMALL and n <= SMALL_N
    if feasibility and has_strict(problem):
        # the certified first-order route (trace normalisation, fixed margin, certified) above
        # the measured crossover; Clarabel, the embedded default solver, below it
        chain = ["clarabel"] if psd <= SMALL_FEASIBILITY and n <= SMALL_N else ["scs", "cvxopt"]
    elif small:
        chain = ["clarabel"]
    else:
        # interior point by shape: Schur complement (CVXOPT) when the variables are few against
        # the PSD dimension, Clarabel otherwise; SDPA last (on the bounded-real lemma it stops
        # short of a certified optimum: docs/backends.md)
        ipm = ["cvxopt", "clarabel"] if schur_complement_shape(problem) else ["clarabel", "cvxopt"]
        fo = FIRST_ORDER_OPTIMISATION if first_order is None else first_order
        chain = (["scs"] if fo and not feasibility else []) + ipm + ["sdpa"]
    usable = [name for name in chain if _usable(name, problem)]
    if not usable:  # e.g. Clarabel cannot take a small problem on a small machine
        usable = [name for name in ("sdpa", "cvxopt", "scs") if _usable(name, problem)]
    return usable or chain


def _usable(name: str, problem: Problem) -> bool:
    """Installed here, and able to take the problem (Clarabel refuses PSD blocks too large for memory)."""
    from lmic.backends.registry import get_backend
    from lmic.errors import LmicError

    try:
        backend = get_backend(name)
    except LmicError:
        return False
    ok = backend.supports(problem, explain=True)
    return bool(ok[0] if isinstance(ok, tuple) else ok)


def step_options(name: str, options: SolveOptions | None) -> SolveOptions:
    """Options for one step of the route: first-order steps run at :data:`FIRST_ORDER_TOL`.

    >>> step_options("scs", SolveOptions(tol=1e-8)).tol
    0.001
    """
    from dataclasses import replace

    options = options or SolveOptions()
    if name == "scs":
        return replace(options, tol=max(options.tol, FIRST_ORDER_TOL))
    return options


def choose(problem: Problem) -> str:
    """The first backend of :func:`route`."""
    return route(problem)[0]


class AutoBackend(Backend):
    """Runs the first backend of :func:`route`; the choice is in ``Solution.info["auto_route"]``."""

    name: ClassVar[str] = "auto"
    description: ClassVar[str] = "route by size and shape, certificate-checked fallback (docs/backends.md)"
    STATUS_MAP: ClassVar[dict[str, str]] = {}

    def solve(self, problem: Problem, options: SolveOptions | None = None) -> Solution:
        from lmic.backends.registry import get_backend

        chain = route(problem)
        sol = get_backend(chain[0]).solve(problem, step_options(chain[0], options))
        sol.info["auto_route"] = chain
        return sol

    def _solve(self, problem: Problem, options: SolveOptions) -> Solution:
        from lmic.backends.registry import get_backend

        return get_backend(choose(problem))._solve(problem, options)
