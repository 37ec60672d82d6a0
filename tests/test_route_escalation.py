"""The route's escalation clock (lmic.route_escalation) measures processor time, not the wall clock.

The cheap escalation towards 1e-6 (lmic.routes) used to measure the route's wall-clock time: on
a loaded machine a route that had cost 3 s of processor time looked like 13 s and did not
escalate. A sleeping route (the wall clock runs, the processor does not: what other processes
on the machine look like to it) must not count; a solve in a forked child (the time-limited
solves of lmic.backends.sandbox) must.
"""

from __future__ import annotations

import multiprocessing
import time

from lmic.route_escalation import RouteClock, cpu_seconds


def _burn(seconds: float) -> None:
    """Spend ``seconds`` of this process's processor time (however loaded the machine is)."""
    end = time.process_time() + seconds
    x = 0
    while time.process_time() < end:
        x += 1


def test_waiting_is_not_cost():
    clock = RouteClock()
    time.sleep(0.5)
    assert clock.wall() >= 0.5
    assert clock.elapsed() < 0.1


def test_work_here_and_in_a_reaped_child_is_cost():
    clock = RouteClock()
    _burn(0.3)
    here = clock.elapsed()
    assert here >= 0.25
    proc = multiprocessing.get_context("fork").Process(target=_burn, args=(0.5,))
    proc.start()
    proc.join()
    assert cpu_seconds() >= clock.cpu0 + here + 0.45
    assert clock.elapsed() >= here + 0.45 or clock.elapsed() == clock.wall()  # capped by the wall clock
