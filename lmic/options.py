"""Options every backend understands (:class:`SolveOptions`), below backends and reductions.

>>> SolveOptions(tol=1e-9).tol
1e-09
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

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
        Seconds. Solvers without a native time limit run in a child process that is stopped
        when the limit is reached (status ``error``, message ``time limit ... exceeded``).
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
    extra : dict
        Solver-specific settings passed through unchanged.

    Examples
    --------
    >>> SolveOptions(max_iter=50).max_iter
    50
    >>> SolveOptions(strict="fixed-margin").strict
    'fixed-margin'
    """

    tol: float = 1e-8
    max_iter: int | None = None
    time_limit: float | None = None
    verbose: bool = False
    margin: float = 1e-7
    strict: str = "auto"
    relative_margin: float = 1e-4
    extra: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        from lmic.errors import LmicError

        if self.strict not in ("auto", "max-margin", "fixed-margin"):
            raise LmicError(f"strict strategy '{self.strict}' unknown; choose auto, max-margin or fixed-margin")
        if not 0.0 < self.relative_margin < 1.0:
            raise LmicError(f"relative_margin must be in (0, 1), got {self.relative_margin}")
