"""The Backend interface (lmic/backends/backend.py): the backend-level solve runs no reduction,
crashes and unknown statuses are ``error`` solutions, ``supports`` explains a refusal."""

from __future__ import annotations

import numpy as np
import pytest

from lmic.api import certify_solution
from lmic.backends.backend import Backend
from lmic.backends.registry import get_backend
from lmic.options import SolveOptions
from lmic.reductions.pipeline import solve as solve_with_reductions
from lmic.solution import Solution
from lmic.testing.conformance import CASES, lyapunov_problem


class _Crash(Backend):
    name = "crash"
    STATUS_MAP = {"done": "optimal"}

    def _solve(self, problem, options):
        raise RuntimeError("segment the fault")


class _Weird(Backend):
    name = "weird"
    STATUS_MAP = {"done": "optimal"}

    def _solve(self, problem, options):
        return Solution(self.map_status("SOMETHING_NEW"), native_status="SOMETHING_NEW")


class _Neither(Backend):
    name = "neither"


def test_crash_is_an_error_status_not_a_traceback():
    for solve in (lambda p: _Crash().solve(p), lambda p: solve_with_reductions(_Crash(), p)):
        sol = solve(CASES["max_sense"].build())
        assert sol.status == "error" and "RuntimeError: segment the fault" in sol.message


def test_unknown_native_status_is_error():
    assert _Weird().solve(CASES["max_sense"].build()).status == "error"


def test_a_backend_without_call_or_solve_is_an_error_status():
    sol = _Neither().solve(CASES["max_sense"].build())
    assert sol.status == "error" and "implements neither" in sol.message


def test_supports_explains_missing_capability():
    class _LmiOnly(_Crash):
        capabilities = frozenset({"lmi"})

    ok, why = _LmiOnly().supports(CASES["linear_equalities"].build(), explain=True)
    assert not ok and "cannot take eq constraints" in why


def test_tolerance_floor_is_applied():
    assert get_backend("scs").floor_options(SolveOptions(tol=1e-9)).tol == get_backend("scs").tol_floor
    assert get_backend("clarabel").floor_options(None).tol == SolveOptions().tol


@pytest.mark.parametrize("name", ["clarabel", "cvxopt"])
def test_backend_solve_runs_no_reduction_and_the_pipeline_does(name):
    # a stable A: P > 0 with A'P + PA < 0 exists; the closure also admits P = 0 (margin 0)
    problem = lyapunov_problem(np.array([[-1.0, 2.0], [0.0, -3.0]]))
    closed = get_backend(name).solve(problem)
    assert closed.strategy in (None, "", "none") and "strict_attempts" not in closed.info
    reduced = solve_with_reductions(get_backend(name), problem)
    assert reduced.strategy in ("max-margin", "fixed-margin")
    assert certify_solution(problem, reduced).verdict == "certified"
