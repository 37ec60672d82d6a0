"""SolveOptions.warm_start: SCS and CVXOPT start from a neighbouring point's iterates.

A warm start changes where the solver starts, never what is certified: the verdicts warm and
cold must agree (every answer checked by the certifier), and the solver's own iteration count
(read from the solution, not timed) must drop.
"""

from __future__ import annotations

import numpy as np
import pytest

from lmic.certify import certify
from lmic.compile import bind, plan_for
from lmic.errors import LmicError
from lmic.options import SolveOptions
from lmic.reductions.pipeline import solve
from lmic.studies.sweep import points, sweep


def qib_system(n: int, seed: int = 0) -> dict:
    rng = np.random.default_rng(seed + 1000 * n)
    A = rng.standard_normal((n, n))
    A *= 0.9 / max(abs(np.linalg.eigvals(A)))
    C = rng.standard_normal((max(1, n // 2), n))
    return {"lmic": 1, "data": {"A": A.tolist(), "C": C.tolist()}, "params": {"beta": 1e-3, "gamma": 0.0}}


def _bound(system: dict, beta: float):
    plan = plan_for("qib.thm1", system["params"])
    return bind(plan, system, {**system["params"], "beta": beta})


@pytest.mark.parametrize(
    ("backend", "extra"),
    [("scs", {"eps_abs": 1e-9, "eps_rel": 1e-9}), ("cvxopt", {})],
)
@pytest.mark.parametrize(("b0", "b1"), [(0.01, 0.0105), (0.05, 0.051)])
def test_warm_start_same_verdict_fewer_iterations(backend, extra, b0, b1):
    pytest.importorskip(backend)
    from lmic.backends.registry import get_backend

    be = get_backend(backend)
    system = qib_system(8)
    p0, p1 = _bound(system, b0), _bound(system, b1)
    first = solve(be, p0, SolveOptions(tol=1e-6, extra=dict(extra)))
    cold = solve(be, p1, SolveOptions(tol=1e-6, extra=dict(extra)))
    warm = solve(be, p1, SolveOptions(tol=1e-6, extra=dict(extra), warm_start=first))
    assert warm.info["warm_started"] is True and cold.info["warm_started"] is False
    v_cold, v_warm = certify(p1, cold).verdict, certify(p1, warm).verdict
    assert v_cold == v_warm == "certified"
    assert warm.iterations < cold.iterations


def test_a_warm_start_of_another_shape_is_ignored():
    pytest.importorskip("scs")
    from lmic.backends.registry import get_backend

    be = get_backend("scs")
    other = solve(be, _bound(qib_system(6), 0.01), SolveOptions(tol=1e-6))
    p = _bound(qib_system(8), 0.01)
    sol = solve(be, p, SolveOptions(tol=1e-6, warm_start=other))
    assert sol.info["warm_started"] is False
    assert certify(p, sol).verdict == "certified"


@pytest.mark.parametrize("bad", [3, "x", {"x": [1.0]}])
def test_warm_start_must_be_a_solution(bad):
    with pytest.raises(LmicError, match="warm_start must be a Solution"):
        SolveOptions(warm_start=bad)


def test_sweep_outcomes_are_the_same_warm_and_cold(monkeypatch):
    pytest.importorskip("cvxopt")
    system = qib_system(6)
    values = [0.001, 0.01, 0.02, 0.03]
    # reuse=False: every value solved (a reused point would need no solve, hence no warm start)
    warm = sweep("qib.thm1", system, "beta", values, backend="cvxopt", reuse=False)
    monkeypatch.setattr(points, "warm_options", lambda options, warm: options or SolveOptions())
    cold = sweep("qib.thm1", system, "beta", values, backend="cvxopt", reuse=False)
    assert [p.outcome for p in warm.points] == [p.outcome for p in cold.points]
    assert any(p.outcome == "feasible" for p in warm.points)
    for p in warm.points:  # every certified point certified again, independently of the sweep
        if p.outcome == "feasible":
            assert certify(p.problem, p.solution).verdict == "certified"
    it_warm = sum(p.solution.iterations for p in warm.points[1:])
    it_cold = sum(p.solution.iterations for p in cold.points[1:])
    assert it_warm < it_cold
