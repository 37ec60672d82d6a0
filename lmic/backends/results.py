"""One mapping from a native solver answer to a :class:`~lmic.solution.Solution`, for every backend.

A backend's native call returns a :class:`NativeResult` (its status word, point, multipliers and
rays already inverted to the IR's space by the lowering); :func:`to_solution` applies the rules
of :mod:`lmic.backends.outcomes` through the backend's declared tables:

* ``STATUS_MAP`` (native -> lmic status; unlisted -> ``error``);
* ``INEXACT_INFEASIBLE``: inexact infeasibility claims, ``inaccurate`` without a point, their ray
  kept in ``info["inexact_farkas"]`` with ``info["claim"] = "infeasible"`` (the engine's
  :func:`lmic.reductions.pipeline.settle_inexact_infeasible` asks the certifier whether it
  verifies; a backend never decides that);
* ``INEXACT_UNBOUNDED``: inexact unboundedness claims, the direction in ``info["inexact_ray"]``;
* ``TIME_LIMIT``: native words of a solve stopped at its time limit (:func:`mark_time_limit`).

Examples
--------
>>> from lmic.testing.conformance import CASES
>>> class _B:
...     label, title = "x", "X"
...     STATUS_MAP = {"done": "optimal"}
...     INEXACT_INFEASIBLE = INEXACT_UNBOUNDED = TIME_LIMIT = frozenset()
...     def map_status(self, native): return self.STATUS_MAP.get(native, "error")
>>> p = CASES["max_sense"].build()
>>> to_solution(_B(), p, NativeResult("huh"), None).message
"X stopped with status 'huh'"
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from lmic.backends.outcomes import mark_time_limit
from lmic.ir.problem import Problem
from lmic.solution import Solution

__all__ = ["NativeResult", "to_solution"]


@dataclass
class NativeResult:
    """What one native call returned, in the IR's space.

    Attributes
    ----------
    native : str
        The solver's status word (the key of ``STATUS_MAP``).
    x : numpy.ndarray, optional
        The primal point (or, for an unbounded status, the primal ray).
    duals : dict, optional
        IR multipliers ``{"lmis", "linear"}``: the dual point, or the Farkas ray on infeasibility.
    shown : str
        The native status as reported (defaults to ``native``).
    """

    native: str
    x: np.ndarray | None = None
    duals: dict[str, Any] | None = None
    solve_s: float = 0.0
    iterations: int | None = None
    info: dict[str, Any] = field(default_factory=dict)
    message: str = ""
    shown: str = ""


def to_solution(backend: Any, problem: Problem, r: NativeResult, time_limit: float | None) -> Solution:
    """The :class:`Solution` of a native result, by the backend's tables (module docstring)."""
    status = backend.map_status(r.native)
    shown = r.shown or r.native
    sol = Solution(
        status=status,
        backend=backend.label,
        native_status=shown,
        solve_s=r.solve_s,
        iterations=r.iterations,
        info=dict(r.info),
        message=r.message,
    )
    if r.native in backend.TIME_LIMIT:
        mark_time_limit(sol, time_limit, r.solve_s)
        if shown != "time_limit":
            sol.message += f" ({shown})"
        return sol
    if r.native in backend.INEXACT_INFEASIBLE:
        sol.x = None
        sol.info["claim"] = "infeasible"
        if r.duals is not None and r.duals.get("lmis") is not None:
            sol.info["inexact_farkas"] = r.duals
            sol.message = (
                sol.message or f"{shown}: inexact infeasibility claim (its ray is checked by the solve policy)"
            )
        else:
            sol.message = sol.message or f"{shown}: inexact infeasibility claim without a ray"
    elif r.native in backend.INEXACT_UNBOUNDED:
        if r.x is not None:
            sol.info["inexact_ray"] = np.asarray(r.x, dtype=float)
        sol.message = sol.message or f"{backend.title} stopped with status {shown} (inexact unboundedness claim)"
    elif status in ("optimal", "inaccurate"):
        if r.x is None:
            sol.status = "error"
            sol.message = sol.message or f"{backend.title} stopped with status '{shown}' and no point"
            return sol
        sol.x = np.asarray(r.x, dtype=float).ravel()
        sol.objective = problem.objective.value(sol.x)
        sol.duals = r.duals or {}
    elif status == "infeasible":
        sol.farkas = r.duals
    elif status == "unbounded" and r.x is not None:
        sol.info["ray"] = np.asarray(r.x, dtype=float).ravel()
    if sol.status in ("error", "inaccurate") and not sol.message:
        sol.message = f"{backend.title} stopped with status '{shown}'"
    return sol
