"""The clock of the default route's escalation decisions, robust to the machine's load.

:mod:`lmic.routes` escalates an optimisation answer whose enclosure meets ``--gap`` but not
:data:`lmic.certify.enclosure.GAP_TARGET` to the next interior-point solver while the route
has cost less than :data:`lmic.route_rule.CHEAP_ESCALATION_S`. Measured on the wall clock,
that decision depended on what else the machine ran: random ``delay_b.thm4_1`` n = 10 stopped
at SDPA's gap 1.2e-6 after 13.1 s on a loaded machine and escalated on a quiet one.
:class:`RouteClock` measures the route's *cost* instead: the processor time of this process
and of its reaped children (solves run in forked children under a time limit,
:mod:`lmic.backends.sandbox`), capped by the wall clock (a multi-threaded solver spends more
processor than wall time, and the wall clock is then the better measure of the cost).

Also the route's two small judgements of enclosures: :func:`tighter` (which certified answer
the route keeps) and :func:`gap_note` (the route line's note on a missing end).

Examples
--------
>>> clock = RouteClock()
>>> 0.0 <= clock.elapsed() <= clock.wall()
True
"""

from __future__ import annotations

import os
import time
from typing import Any

__all__ = ["RouteClock", "cpu_seconds", "gap_note", "seconds_left", "tighter"]


def cpu_seconds() -> float:
    """Processor seconds (user and system) of this process and of its reaped children.

    >>> cpu_seconds() > 0.0
    True
    """
    t = os.times()
    return float(t.user + t.system + t.children_user + t.children_system)


class RouteClock:
    """The cost of a route since its start: processor time, capped by wall time.

    Under load the wall clock runs ahead of the processor time the route used (other
    processes share the cores); with a multi-threaded solver the processor time runs ahead of
    the wall clock. ``min`` of the two is the route's cost in both cases.
    """

    def __init__(self) -> None:
        self.wall0 = time.perf_counter()
        self.cpu0 = cpu_seconds()

    def wall(self) -> float:
        """Wall-clock seconds since the start."""
        return time.perf_counter() - self.wall0

    def elapsed(self) -> float:
        """The route's cost in seconds: ``min(processor, wall)`` since the start."""
        return min(cpu_seconds() - self.cpu0, self.wall())


def seconds_left(deadline: Any) -> float:
    """Seconds left before ``deadline``: a :func:`time.perf_counter` value, or a callable that
    returns the seconds left (a budget of processor time, :class:`RouteClock`).

    >>> seconds_left(lambda: 2.5), seconds_left(time.perf_counter() + 60.0) > 59.0
    (2.5, True)
    """
    return float(deadline()) if callable(deadline) else float(deadline) - time.perf_counter()


def tighter(enc: dict[str, Any] | None, best_enc: dict[str, Any] | None, out: Any, best: Any) -> bool:
    """A later certified answer (a polish) replaces an earlier one unless the earlier one's
    enclosure has a smaller relative gap."""
    if out.verdict != "certified" or best.verdict != "certified":
        return False
    new, old = (enc or {}).get("rel_gap"), (best_enc or {}).get("rel_gap")
    return old is None or (new is not None and new <= old)


def gap_note(enc: dict[str, Any] | None) -> str:
    """Which end of an enclosure without a relative gap is missing (the route line).

    >>> gap_note(None), gap_note({"lower": 1.0, "upper": None})
    ('no enclosure', 'no certified upper end')
    """
    if enc is None:
        return "no enclosure"
    lo, hi = enc.get("lower"), enc.get("upper")
    if lo is None and hi is None:
        return "no certified end"
    return "no certified lower end" if lo is None else "no certified upper end"
