"""The backend interface every solver plugin implements.

A backend is a class with class attributes ``name``, ``requires`` (importable module name ->
pip package), ``STATUS_MAP`` (native status -> :data:`lmic.solution.STATUSES`) and
``capabilities``, and the methods :meth:`Backend.is_available`, :meth:`Backend.supports` and
:meth:`Backend.solve`. Native solver modules are imported inside methods, never at import time.

A backend declares three things (about 100 lines each, :mod:`lmic.backends.clarabel` for one):

1. its status tables (``STATUS_MAP``, ``INEXACT_INFEASIBLE``, ``INEXACT_UNBOUNDED``,
   ``TIME_LIMIT``; the rules are in :mod:`lmic.backends.outcomes`);
2. its settings from the options, :meth:`Backend.settings` (one function);
3. one call from the closed problem to a native result, :meth:`Backend.call`, which lowers
   (:mod:`lmic.backends.lowering`), runs the solver and inverts its answer into a
   :class:`~lmic.backends.results.NativeResult`; the shared mapping
   (:func:`lmic.backends.results.to_solution`) makes the :class:`Solution`.

:meth:`Backend.solve` is the *backend-level* solve: the closed problem as given (a strict
constraint is solved as its closure ``>= 0``), with the time limit (:mod:`lmic.backends.sandbox`)
and any crash turned into a ``status="error"`` :class:`Solution`. It runs **no reduction**: the
engine composes reductions and backends. :func:`lmic.reductions.pipeline.solve` is the solve of
a problem with strict constraints (the elimination of unused entries, the strict reduction and
the check of inexact infeasibility rays); the policy (:mod:`lmic.policy`) uses it.

Examples
--------
>>> Backend.INEXACT_INFEASIBLE
frozenset()
"""

from __future__ import annotations

import importlib
import importlib.util
import time
from abc import ABC
from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import Any, ClassVar, TypeVar

from lmic.backends.lowering import problem_kinds
from lmic.backends.results import NativeResult, to_solution
from lmic.backends.sandbox import describe, run_limited
from lmic.ir.problem import Problem
from lmic.options import SolveOptions
from lmic.solution import Solution

__all__ = ["Backend", "in_turn", "KKT_ORDER"]

T = TypeVar("T")
R = TypeVar("R")

#: CVXOPT's KKT solvers in the order every CVXOPT-based backend tries them: 'chol' (CVXPY's
#: choice, 2.5x faster than CVXOPT's default 'qr' on qib.thm1 at n = 20: 0.53 s against 1.33 s)
#: needs rank [G; A] = n (the elimination of dependent entries provides it) and stops 'unknown'
#: on SDPLIB control1-3 and qap5, where 'qr' solves
KKT_ORDER: tuple[str, ...] = ("chol", "qr")


def in_turn(
    choices: Sequence[T],
    run: Callable[[T], R],
    again: Callable[[R], bool],
    errors: tuple[type[BaseException], ...] = (ValueError, ArithmeticError),
) -> tuple[R, T]:
    """``run`` each choice in turn until one neither raises ``errors`` nor asks to go ``again``.

    The last choice's answer (or exception) stands. Returns the answer and the choice that gave it.

    >>> in_turn(["chol", "qr"], lambda k: 1 / (k == "qr"), lambda r: False)
    (1.0, 'qr')
    >>> in_turn(["chol", "qr"], lambda k: k.upper(), lambda r: r == "CHOL")
    ('QR', 'qr')
    """
    for k, choice in enumerate(choices):
        last = k == len(choices) - 1
        try:
            answer = run(choice)
        except errors:
            if last:
                raise
            continue
        if last or not again(answer):
            return answer, choice
    raise ValueError("in_turn: no choices")


#: solver modules found by :meth:`Backend.missing_packages` in this process (a search of
#: ``sys.path`` per module and per call otherwise: ~0.5 ms of every default-route decision)
_FOUND: set[str] = set()


class Backend(ABC):  # noqa: B024 - a subclass implements call() or _solve(), either one
    """Base class of every backend plugin.

    Subclasses set the class attributes and implement :meth:`settings` and :meth:`call` (or,
    for a backend that does not fit that shape, :meth:`_solve`) for a *closed* problem (every
    LMI ``F(x) >= 0``, every row ``== 0`` or ``>= 0``), returning results in the same problem's
    variable space with ``solve_s`` set to the time spent inside the solver.
    """

    name: ClassVar[str] = ""
    #: the solver's name in messages ("Clarabel stopped with status ...")
    title: ClassVar[str] = ""
    #: importable module names the backend needs, and the pip package that provides each
    requires: ClassVar[dict[str, str]] = {}
    STATUS_MAP: ClassVar[dict[str, str]] = {}
    #: native words of an inexact infeasibility claim (kept only if the engine verifies its ray)
    INEXACT_INFEASIBLE: ClassVar[frozenset[str]] = frozenset()
    #: native words of an inexact unboundedness claim
    INEXACT_UNBOUNDED: ClassVar[frozenset[str]] = frozenset()
    #: native words of a solve stopped by the solver's own time limit
    TIME_LIMIT: ClassVar[frozenset[str]] = frozenset()
    #: constraint kinds the backend takes: subset of {"lmi", "eq", "ge"}
    capabilities: ClassVar[frozenset[str]] = frozenset({"lmi", "eq", "ge"})
    #: whether the solver enforces ``SolveOptions.time_limit`` itself
    native_time_limit: ClassVar[bool] = False
    #: interior-point (True) or first-order (False) method, for documentation and ``auto``
    interior_point: ClassVar[bool] = True
    #: whether the solver needs a constraint matrix of full column rank (CVXOPT, SDPA): linearly
    #: dependent entries of ``x`` are then eliminated first (:mod:`lmic.reductions.eliminate`)
    full_rank: ClassVar[bool] = False
    #: the smallest tolerance the solver is asked for (``SolveOptions.tol`` is raised to it)
    tol_floor: ClassVar[float] = 0.0
    #: one line shown by ``lmic backends``
    description: ClassVar[str] = ""
    #: accepted ``name:VARIANT`` suffixes (e.g. the sub-solvers of ``cvxpy``); empty: none
    variants: ClassVar[tuple[str, ...]] = ()

    def __init__(self, variant: str | None = None) -> None:
        if variant is not None and variant.upper() not in self.variants:
            from lmic.errors import BackendUnavailable

            raise BackendUnavailable(f"backend '{self.name}' has no variant '{variant}'")
        self.variant = variant

    @property
    def label(self) -> str:
        """The name shown in results (e.g. ``"cvxpy:SCS"`` for a configured backend)."""
        return self.name

    def missing_packages(self) -> list[str]:
        """The pip packages whose modules cannot be imported here."""
        missing = []
        for mod, pkg in self.requires.items():
            if mod in _FOUND:
                continue
            try:
                found = importlib.util.find_spec(mod) is not None
            except (ImportError, ValueError):
                found = False
            if found:
                _FOUND.add(mod)  # found stays found; a missing module is looked for again next time
            else:
                missing.append(pkg)
        return missing

    def is_available(self) -> bool:
        """True when every required module is importable."""
        return not self.missing_packages()

    def supports(self, problem: Problem, explain: bool = False) -> bool | tuple[bool, str]:
        """Whether this backend can take ``problem``; with ``explain``, also why not.

        The default compares the problem's constraint kinds with :attr:`capabilities` and
        requires at least one decision variable.
        """
        reason = ""
        extra = problem_kinds(problem) - set(self.capabilities)
        if extra:
            reason = (
                f"backend '{self.label}' cannot take {', '.join(sorted(extra))} constraints "
                f"(it takes {', '.join(sorted(self.capabilities))})"
            )
        elif problem.n == 0:
            reason = "the problem has no decision variables"
        ok = not reason
        return (ok, reason) if explain else ok

    def too_large(self, problem: Problem) -> str | None:
        """Why a solve of ``problem`` would exhaust this machine's memory, or ``None`` (the
        default: no estimate). The engine (:func:`lmic.reductions.pipeline.solve`) asks before
        every solve, so that no caller can start one that would end the process."""
        return None

    # -- the solve of a closed problem ----------------------------------------------------------
    def floor_options(self, options: SolveOptions | None) -> SolveOptions:
        """``options`` (default :class:`SolveOptions`) with ``tol`` raised to :attr:`tol_floor`.

        >>> from lmic.backends.registry import get_backend
        >>> get_backend("scs").floor_options(SolveOptions(tol=1e-9)).tol
        1e-06
        """
        options = options or SolveOptions()
        return replace(options, tol=self.tol_floor) if options.tol < self.tol_floor else options

    def import_native(self, *extra: str) -> Solution | None:
        """Import the solver's modules (and ``extra``) now, so that import time is not lmic's overhead.

        Returns the ``error`` solution naming the pip packages to install when one is missing.
        """
        try:
            for module in (*self.requires, *extra):
                importlib.import_module(module)
        except ImportError as err:
            return Solution(
                status="error",
                backend=self.label,
                message=f"{describe(err)}; pip install {' '.join(self.missing_packages())}",
            )
        return None

    def solve(self, problem: Problem, options: SolveOptions | None = None) -> Solution:
        """Solve the closed ``problem`` as given, with no reduction; every crash is a status.

        Strict constraints are solved as their closure (``>= 0``): the reductions that make a
        strict answer (and the elimination of unused entries, and the check of inexact
        infeasibility rays) are the engine's, :func:`lmic.reductions.pipeline.solve`. An
        inexact infeasibility claim stays ``inaccurate`` here, its ray in
        ``info["inexact_farkas"]``. ``solve_s`` is the time inside the solver, ``lower_s`` the
        rest (lowering and result mapping).

        >>> from lmic.backends.registry import get_backend
        >>> from lmic.testing.conformance import CASES
        >>> get_backend("clarabel").solve(CASES["max_sense"].build()).status
        'optimal'
        """
        options = self.floor_options(options)
        failed = self.import_native()
        if failed is not None:
            return failed
        t0 = time.perf_counter()
        deadline = None if options.time_limit is None else time.monotonic() + options.time_limit
        sol = self._run(problem, options, deadline)
        sol.backend = sol.backend or self.label
        sol.lower_s = max(0.0, time.perf_counter() - t0 - sol.solve_s)
        return sol

    def _run(self, problem: Problem, options: SolveOptions, deadline: float | None = None) -> Solution:
        """:meth:`_solve` within the time limit (:func:`lmic.backends.sandbox.run_limited`).

        ``deadline`` (``time.monotonic()`` seconds) is the end of the whole solve (all attempts
        of a reduction); each attempt gets the time left. A solve longer than 2 s shows
        ``lmic: <label> | <step> | <seconds>`` on a terminal.
        """
        from lmic.backends.progress import solve_progress

        with solve_progress(self.label):
            return run_limited(self._solve, self.label, problem, options, deadline, self.native_time_limit)

    def _solve(self, problem: Problem, options: SolveOptions) -> Solution:
        """Solve a closed ``problem`` with the native solver: settings, call, shared mapping."""
        return to_solution(self, problem, self.call(problem, self.settings(options)), options.time_limit)

    def settings(self, options: SolveOptions) -> dict[str, Any]:
        """The solver's settings from the uniform options (``options.extra`` last, verbatim)."""
        return dict(options.extra)

    def call(self, problem: Problem, settings: dict[str, Any]) -> NativeResult:
        """Lower ``problem``, run the solver with ``settings``, invert its answer."""
        raise TypeError(f"backend '{self.name}' implements neither call() nor _solve()")

    def map_status(self, native: str) -> str:
        """Map a native status into the shared vocabulary (unknown -> ``error``)."""
        return self.STATUS_MAP.get(str(native), "error")
