"""Shared rules for turning a native solver answer into a :class:`~lmic.solution.Solution`.

Every backend declares its native statuses in a ``STATUS_MAP`` table; the rules the tables
follow are stated here once:

* the solver's own "solved" status is ``optimal`` (a claim the certifier checks);
* an inexact claim (Clarabel's ``Almost*``, SCS's and CVXPY's ``*_inaccurate``, SDPA's
  ``pdFEAS``/``pFEAS``/``dFEAS``, CVXOPT's ``unknown`` with an iterate) is ``inaccurate``;
* a status the table does not list is ``error``, never success
  (:meth:`lmic.backends.backend.Backend.map_status`).

An *inexact infeasibility* claim (``AlmostPrimalInfeasible``, ``infeasible_inaccurate``) is
``inaccurate`` without a point, but its ray is kept (``info["inexact_farkas"]``, a backend's
``INEXACT_INFEASIBLE`` table, :mod:`lmic.backends.results`). The engine, not the status map,
asks the certifier: :func:`lmic.reductions.pipeline.settle_inexact_infeasible` promotes the
claim to ``infeasible`` only when the ray verifies as a Farkas certificate of the (closed)
problem the solver was given, so a decision is not thrown away and the solver's inexact word is
never taken. (``settle_inexact_infeasible`` is still importable from here: deprecated alias.)

A stopped solve (time limit) is an ``error`` with ``info["time_limit"] = True``,
``native_status`` ``"time_limit"`` (or the solver's own word) and a message starting
``time limit of ...``: callers report it as ``undecided (time limit)``
(:func:`time_limit_solution`, :func:`is_time_limit`).

Examples
--------
>>> sol = time_limit_solution("clarabel", 0.5, elapsed=0.51)
>>> sol.status, is_time_limit(sol), sol.message
('error', True, 'time limit of 0.5 s exceeded (stopped after 0.51 s)')
"""

from __future__ import annotations

import importlib
from typing import Any

from lmic.solution import Solution

__all__ = ["time_limit_solution", "mark_time_limit", "is_time_limit"]


def time_limit_solution(backend: str, limit: float, elapsed: float, native: str = "time_limit") -> Solution:
    """The ``error`` solution of a solve stopped at its time limit.

    >>> time_limit_solution("sdpa", 2.0, 2.1).info
    {'time_limit': True, 'time_limit_s': 2.0}
    """
    sol = Solution(status="error", backend=backend, native_status=native, solve_s=elapsed)
    return mark_time_limit(sol, limit, elapsed)


def mark_time_limit(sol: Solution, limit: float | None, elapsed: float | None = None) -> Solution:
    """Mark ``sol`` as stopped by the time limit (status ``error``, flag, message); returns it.

    >>> mark_time_limit(Solution("inaccurate", native_status="MaxTime"), 1.0).status
    'error'
    """
    sol.status = "error"
    sol.x = None
    sol.info["time_limit"] = True
    sol.info["time_limit_s"] = limit
    after = ""
    if elapsed is not None:
        after = f" (stopped after {elapsed:.3g} s)" if elapsed > 0 else " (used up before this solve started)"
    sol.message = f"time limit of {limit:g} s exceeded{after}" if limit is not None else "time limit exceeded"
    return sol


def is_time_limit(sol: Solution) -> bool:
    """Whether ``sol`` is a solve stopped by its time limit (report ``undecided (time limit)``).

    >>> is_time_limit(Solution("error", message="NumericalError"))
    False
    """
    return bool(sol.info.get("time_limit"))


def __getattr__(name: str) -> Any:
    """``settle_inexact_infeasible`` moved to the engine (:mod:`lmic.reductions.pipeline`); deprecated here."""
    if name == "settle_inexact_infeasible":
        return getattr(importlib.import_module(".".join(("lmic", "reductions", "pipeline"))), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
