"""The time-limit sandbox (lmic/backends/sandbox.py): a forked child stopped at the limit, a
deadline already passed, a crash in the child."""

from __future__ import annotations

import os
import time

import numpy as np

from lmic.backends.backend import Backend
from lmic.backends.outcomes import is_time_limit
from lmic.backends.sandbox import call_safely, describe, run_in_child, run_limited
from lmic.options import SolveOptions
from lmic.solution import Solution
from lmic.testing.conformance import CASES


class _Sleepy(Backend):
    name = "sleepy"
    STATUS_MAP = {"done": "optimal"}

    def _solve(self, problem, options):
        time.sleep(30)
        return Solution("optimal", x=np.zeros(problem.n))


def test_time_limit_without_native_support_stops_the_child():
    t0 = time.perf_counter()
    sol = _Sleepy().solve(CASES["max_sense"].build(), SolveOptions(time_limit=0.5))
    assert time.perf_counter() - t0 < 10
    assert sol.status == "error" and is_time_limit(sol) and "time limit" in sol.message


def test_a_deadline_already_passed_returns_at_once():
    sol = run_limited(lambda p, o: Solution("optimal"), "x", None, SolveOptions(time_limit=5.0), time.monotonic() - 1)
    assert is_time_limit(sol) and "used up before this solve started" in sol.message


def test_the_child_answers_and_its_death_is_an_error():
    ok = run_in_child(lambda p, o: Solution("optimal", native_status=str(os.getpid())), "x", None, SolveOptions(), 20)
    assert ok is not None and ok.status == "optimal" and ok.native_status != str(os.getpid())
    died = run_in_child(lambda p, o: os._exit(3), "x", None, SolveOptions(), 20)
    assert died is not None and died.status == "error" and "exit code 3" in died.message


def test_a_crash_is_described_in_one_line():
    sol = call_safely(lambda p, o: int("not\n a number"), "x", None, SolveOptions())
    assert sol.status == "error" and "\n" not in sol.message and sol.message.startswith("ValueError: ")
    assert describe(KeyError("")) == "KeyError: ''"
