"""What a backend returns: one status vocabulary and a :class:`Solution`.

A solver's ``optimal`` is a claim, not a fact: the certifier (:mod:`lmic.certify`) decides.

Examples
--------
>>> s = Solution(status="optimal", x=np.array([1.0]), backend="clarabel")
>>> s.ok
True
>>> Solution(status="infeasible").ok
False
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["STATUSES", "Solution"]

#: The one status vocabulary every backend maps its native statuses into.
#: An unknown native status is ``error``, never success.
STATUSES = ("optimal", "feasible", "infeasible", "unbounded", "inaccurate", "error")


@dataclass
class Solution:
    """A backend's answer for an IR :class:`~lmic.ir.problem.Problem`.

    Parameters
    ----------
    status : str
        One of :data:`STATUSES`.
    x : numpy.ndarray or None
        The point in the IR's variable space (length ``problem.n``), when there is one.
    objective : float or None
        The objective *as reported by the solver*, in the IR's sense (the certifier recomputes it).
    backend : str
        Backend name (e.g. ``"clarabel"``, ``"cvxpy:SCS"``).
    native_status : str
        The solver's own status word.
    message : str
        Solver message (errors, time-outs).
    duals : dict
        ``{"lmis": [Z_i dense symmetric, ...], "linear": y}`` where the solver provides them.
    farkas : dict or None
        A dual certificate of infeasibility (same layout as ``duals``) for ``infeasible``.
    margin : float or None
        The margin ``t`` the strict-inequality strategy achieved or imposed (``F(x) >= t I``).
    strategy : str
        How strict inequalities were handled (``"max-margin"``, ``"fixed-margin"``, ``"none"``).
    solve_s, lower_s : float
        Solver time, and lmic's lowering + result mapping time (seconds).
    iterations : int or None
    info : dict
        Anything else worth reporting (versions, solver options).
    """

    status: str
    x: np.ndarray | None = None
    objective: float | None = None
    backend: str = ""
    native_status: str = ""
    message: str = ""
    duals: dict[str, Any] = field(default_factory=dict)
    farkas: dict[str, Any] | None = None
    margin: float | None = None
    strategy: str = "none"
    solve_s: float = 0.0
    lower_s: float = 0.0
    iterations: int | None = None
    info: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.status not in STATUSES:
            self.message = f"unknown status '{self.status}'; {self.message}".strip("; ")
            self.status = "error"
        if self.x is not None:
            self.x = np.asarray(self.x, dtype=float).ravel()

    @property
    def ok(self) -> bool:
        """True when the solver *claims* a solution (``optimal`` or ``feasible``)."""
        return self.status in ("optimal", "feasible") and self.x is not None
