"""SCS paused to test its iterates (``SolveOptions.accept``): the fixed-margin feasibility solve
stops at the first iterate that verifies on the original problem; the certifier judges the answer.
"""

from __future__ import annotations

import numpy as np
import pytest

from lmic.backends.registry import get_backend
from lmic.backends.scs import CHECK_EVERY
from lmic.certify import certify
from lmic.options import SolveOptions
from lmic.reductions import strict
from lmic.reductions.pipeline import solve as solve_with_reductions
from lmic.testing.conformance import lyapunov_problem

pytest.importorskip("scs")


def _stable(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    return A - (max(np.linalg.eigvals(A).real) + 0.5) * np.eye(n)


def _lyapunov_holds(A: np.ndarray, P: np.ndarray) -> bool:
    """Independent of lmic's certifier: P > 0 and A'P + PA < 0 by Cholesky factorisations."""
    try:
        np.linalg.cholesky(P)
        np.linalg.cholesky(-(A.T @ P + P @ A))
    except np.linalg.LinAlgError:
        return False
    return True


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_first_order_feasibility_stops_at_a_verified_iterate(seed):
    A = _stable(8, seed)
    prob = lyapunov_problem(A)
    sol = solve_with_reductions(get_backend("scs"), prob, SolveOptions(tol=1e-3))
    assert sol.status == "feasible" and sol.strategy == "fixed-margin"
    # SCS tests its own convergence every 25 iterations; the iterate test stops earlier
    assert sol.native_status.startswith("point verified at iteration")
    assert sol.iterations < 25
    assert sol.info["accept_tests"] >= 1 and sol.info["accept_s"] >= 0.0
    assert certify(prob, sol).verdict == "certified"
    assert _lyapunov_holds(A, prob.variables[0].value(sol.x))


def test_an_iterate_that_never_passes_leaves_scs_its_own_answer():
    prob = lyapunov_problem(_stable(6, 3))
    reduced, _ = strict.reduce(prob, SolveOptions(tol=1e-3), "fixed-margin")
    calls: list[int] = []

    def never(x: np.ndarray) -> bool:
        calls.append(len(x))
        return False

    be = get_backend("scs")
    own = be._run(reduced, SolveOptions(tol=1e-3))
    checked = be._run(reduced, SolveOptions(tol=1e-3, accept=never))
    assert calls and all(k == prob.n for k in calls)
    assert checked.native_status == own.native_status == "solved"
    assert checked.status == own.status == "optimal"
    assert checked.info["accept_tests"] == len(calls)
    # each test follows a full stretch of CHECK_EVERY iterations; SCS's own convergence test
    # (run at the start of every resumed stretch too) ended the solve
    assert checked.iterations >= CHECK_EVERY * len(calls)
    # the reduced problem's constraints hold at both points, to SCS's tolerance
    for sol in (own, checked):
        assert min(np.linalg.eigvalsh(lmi.matrix(sol.x))[0] for lmi in reduced.lmis) > -1e-2


def test_infeasible_problem_is_not_accepted():
    A = np.diag([0.5, -1.0])  # unstable: A'P + PA < 0, P > 0 has no solution
    prob = lyapunov_problem(A)
    sol = solve_with_reductions(get_backend("scs"), prob, SolveOptions(tol=1e-3))
    assert sol.status != "feasible"
    assert certify(prob, sol).verdict != "certified"


def test_point_test_agrees_with_verify_point():
    prob = lyapunov_problem(_stable(4, 5))
    test = strict.point_test(prob)
    rng = np.random.default_rng(0)
    for _ in range(20):
        x = rng.standard_normal(prob.n)
        assert test(x) == strict.verify_point(prob, x)[0]
    assert not test(np.full(prob.n, np.nan)) and not test(np.zeros(prob.n + 1))
