"""``auto``: a route of backends chosen from the problem's size and shape.

The rule (measured numbers in ``docs/backends.md``):

* Strict feasibility problems that are not small: **SCS first** at tolerance
  :data:`FIRST_ORDER_TOL`, certified, then **CVXOPT** only if the certificate fails. SCS takes
  the fixed-margin route of :mod:`lmic.reductions.strict` (a point with relative margin
  ``10 tol = 1e-2`` under the trace normalisation, verified, max-margin only if it is not): on
  ``qib.thm1`` at n = 40 it is certified in ~0.3 s, 25 iterations, where hand-written CVXPY +
  Clarabel takes ~22 s (``benchmarks/backends.py``, docs/backends.md); CVXOPT is the faster
  interior-point backend on these dense block LMIs (0.4-0.6x Clarabel's time).
* Small problems (``sum of d_i^2 <= SMALL`` and ``n <= SMALL_N``): Clarabel alone (all solvers
  take milliseconds; Clarabel is the most accurate default).
* Optimisation problems of larger size: SDPA, then CVXOPT, then Clarabel if the certificate
  fails (a first-order solver is not accurate enough for optimal values). Backends that are not
  installed, or cannot take the problem (Clarabel refuses PSD blocks whose dense KKT block would
  not fit in memory), are left out of the route.

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

__all__ = ["AutoBackend", "route", "choose", "step_options", "SMALL", "SMALL_N", "FIRST_ORDER_TOL"]

#: tolerance of a first-order step of the route: its answer is certified, not trusted, and
#: the normalised margin (~0.1 on qib.thm1) is far above it
FIRST_ORDER_TOL = 1e-3

#: problems with ``sum d_i^2`` at most this and at most :data:`SMALL_N` variables are "small"
SMALL = 2500
SMALL_N = 200


def _size(problem: Problem) -> tuple[int, int]:
    return sum(lmi.dim**2 for lmi in problem.lmis), problem.n


def route(problem: Problem) -> list[str]:
    """The backends ``auto`` tries for ``problem``, in order.

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("t", "scalar", (1, 1))], [LMI("t>0", 1, sp.csc_matrix([[0., 1.]]))],
    ...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
    >>> route(p)
    ['clarabel']
    """
    psd, n = _size(problem)
    if psd <= SMALL and n <= SMALL_N:
        chain = ["clarabel"]
    elif problem.objective.sense == "feasibility" and has_strict(problem):
        chain = ["scs", "cvxopt"]
    else:  # SDPA is the fastest interior point on large LMI-form problems (SDPLIB, docs/backends.md)
        chain = ["sdpa", "cvxopt", "clarabel"]
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
