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

Examples
--------
>>> clock = RouteClock()
>>> 0.0 <= clock.elapsed() <= clock.wall()
True
"""

from __future__ import annotations

import os
import time

__all__ = ["RouteClock", "cpu_seconds"]


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
