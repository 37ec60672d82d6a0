"""Options every backend understands (:class:`SolveOptions`), below backends and reductions.

>>> SolveOptions(tol=1e-9).tol
1e-09
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from lmic.errors import LmicError
from lmic.solution import Solution

__all__ = ["SolveOptions"]


@dataclass
class SolveOptions:
    """Options every backend understands (each maps them onto its solver's own names).

    Parameters
    ----------
    tol : float
        Relative accuracy (gap and feasibility) asked of the solver.
    max_iter : int or None
    time_limit : float or None
        Seconds for the whole solve of one backend (:func:`lmic.reductions.pipeline.solve`,
        every strict-reduction attempt included). Solvers with a native limit (Clarabel, SCS,
        CVXPY with either) are given the time left; the others solve in a forked child process
        that is stopped at the limit.
        A stopped solve is status ``error`` with ``info["time_limit"] = True`` and a message
        ``time limit of ... s exceeded`` (:mod:`lmic.backends.outcomes`): report it as
        ``undecided (time limit)``.
    verbose : bool
    margin : float
        Absolute margin imposed on strict inequalities (``F(x) >= margin I``) by the
        ``fixed-margin`` reduction of optimisation problems and of feasibility problems that are
        not scale-free (:mod:`lmic.reductions.strict`).
    strict : {"auto", "max-margin", "fixed-margin"}
        How strict inequalities of a feasibility problem are reduced (:mod:`lmic.reductions.strict`):
        ``max-margin`` maximises the margin ``t`` (decides feasibility and infeasibility in one
        solve, ~3x the interior-point iterations), ``fixed-margin`` asks for a point with a
        fixed margin (fast; an infeasible answer only says that margin is out of reach),
        ``auto`` combines them.
    relative_margin : float
        Margin of the ``fixed-margin`` feasibility solve of a scale-free problem, relative to
        the mean eigenvalue under the trace normalisation (default ``1e-4``).
    gap : float
        Optimisation problems on the default route (:mod:`lmic.routes`): the relative gap of the
        certified enclosure of the optimal value at which the route stops (default ``1e-4``);
        a larger gap is polished by an interior-point method. In ``(0, 1)``.
    extra : dict
        Solver-specific settings passed through unchanged.
    warm_start : Solution or None
        A previous :class:`~lmic.solution.Solution` of a problem with the same shape (e.g. the
        neighbouring point of a sweep, the same plan re-bound): its native iterates are the
        solver's initial guess. Backends that can (SCS: ``x``, ``y``, ``s``; CVXOPT: primal
        and dual starting points) use it when the shapes match and ignore it otherwise, as do
        backends that cannot warm-start. It changes where the solver starts, never what is
        certified.
    accept : callable or None
        Set by the engine, not by users: ``accept(x) -> bool`` tests a point of the problem given
        to the solver against the *original* problem (:func:`lmic.reductions.strict.verify_point`
        on a fixed-margin feasibility solve). A first-order solver that can pause (SCS) tests its
        iterates every few iterations and stops at the first one that passes, instead of waiting
        for its own convergence test (every 25 iterations); the certifier still judges the
        answer. Other backends ignore it.

    Every field is checked when it is set (at construction and on assignment): a tolerance in
    ``(0, 1)``, a positive finite time limit and margin, a positive integer ``max_iter``;
    anything else (negative, zero, NaN, infinite, not a number) raises
    :class:`lmic.errors.LmicError` (bad input: one line, exit code 2).

    Examples
    --------
    >>> SolveOptions(max_iter=50).max_iter
    50
    >>> SolveOptions(strict="fixed-margin").strict
    'fixed-margin'
    >>> SolveOptions(gap=0)
    Traceback (most recent call last):
    ...
    lmic.errors.LmicError: gap must be a relative gap in (0, 1), got 0
    >>> SolveOptions(time_limit=float("nan"))
    Traceback (most recent call last):
    ...
    lmic.errors.LmicError: time_limit must be a finite number, got nan
    """

    tol: float = 1e-8
    max_iter: int | None = None
    time_limit: float | None = None
    verbose: bool = False
    margin: float = 1e-7
    strict: str = "auto"
    relative_margin: float = 1e-4
    gap: float = 1e-4
    extra: dict[str, Any] = field(default_factory=dict)
    warm_start: Solution | None = None
    accept: Callable[[np.ndarray], bool] | None = None

    def __setattr__(self, name: str, value: Any) -> None:
        # every assignment is checked, at construction and later (the CLI sets fields one by one)
        check = _OPTION_CHECKS.get(name)
        if check is not None:
            value = check(value)
        object.__setattr__(self, name, value)


def _finite_number(name: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise LmicError(f"{name} must be a number, got {value!r}")
    value = float(value)
    if not np.isfinite(value):
        raise LmicError(f"{name} must be a finite number, got {value}")
    return value


def _check_tol(value: Any) -> float:
    value = _finite_number("tol", value)
    if not 0.0 < value < 1.0:
        raise LmicError(f"tol must be in (0, 1), got {value:g}")
    return value


def _check_time_limit(value: Any) -> float | None:
    if value is None:
        return None
    value = _finite_number("time_limit", value)
    if value <= 0.0:
        raise LmicError(f"time_limit must be a positive number of seconds, got {value:g}")
    return value


def _check_max_iter(value: Any) -> int | None:
    if value is None:
        return None
    number = _finite_number("max_iter", value)
    if number != int(number) or number < 1:
        raise LmicError(f"max_iter must be a positive integer, got {value!r}")
    return int(number)


def _check_margin(value: Any) -> float:
    value = _finite_number("margin", value)
    if value <= 0.0:
        raise LmicError(f"margin must be positive, got {value:g}")
    return value


def _check_strict(value: Any) -> str:
    if value not in ("auto", "max-margin", "fixed-margin"):
        raise LmicError(f"strict strategy '{value}' unknown; choose auto, max-margin or fixed-margin")
    return str(value)


def _check_relative_margin(value: Any) -> float:
    value = _finite_number("relative_margin", value)
    if not 0.0 < value < 1.0:
        raise LmicError(f"relative_margin must be in (0, 1), got {value:g}")
    return value


def _check_warm_start(value: Any) -> Solution | None:
    if value is not None and not isinstance(value, Solution):
        raise LmicError(f"warm_start must be a Solution or None, got {type(value).__name__}")
    return value


def _check_gap(value: Any) -> float:
    value = _finite_number("gap", value)
    if not 0.0 < value < 1.0:
        raise LmicError(f"gap must be a relative gap in (0, 1), got {value:g}")
    return value


def _check_accept(value: Any) -> Callable[[np.ndarray], bool] | None:
    if value is not None and not callable(value):
        raise LmicError(f"accept must be a callable or None, got {type(value).__name__}")
    return value


_OPTION_CHECKS: dict[str, Callable[[Any], Any]] = {
    "accept": _check_accept,
    "warm_start": _check_warm_start,
    "tol": _check_tol,
    "time_limit": _check_time_limit,
    "max_iter": _check_max_iter,
    "margin": _check_margin,
    "strict": _check_strict,
    "relative_margin": _check_relative_margin,
    "gap": _check_gap,
}
