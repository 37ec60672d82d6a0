"""The pipeline: compile or load, solve, certify, exit codes, the auto route."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from lmic.api import load_target, solve
from lmic.backends import auto
from lmic.errors import BackendUnavailable, LmicError
from lmic.ir.problem import Problem
from lmic.testing.conformance import CASES, lyapunov_problem

QIB = Path(__file__).resolve().parents[2] / "examples" / "qib.thm1.flexible-joint.yaml"


def test_problem_target_certified():
    r = solve(CASES["lyapunov_stable"].build(), backend="cvxopt")
    assert r.status == "feasible" and r.verdict == "certified" and r.exit_code() == 0
    assert r.min_margin is not None and r.min_margin > 0
    assert r.to_dict()["strict"]["strategy"] == "max-margin"


def test_infeasible_exit_code():
    # the truth, in closed form: A has the eigenvalue 0.5 > 0, so no P > 0 has A'P + PA < 0
    # (Lyapunov). The LMIs have no constant term (homogeneous): a float ray bounds the relative
    # margin only; its exact proof (the unstable mode e_1 is rational) makes it global: the
    # verdict is infeasible-certified, and its exit code is 3.
    A = np.array([[0.5, 1.0, 0.0], [0.0, -1.0, 1.0], [0.0, 0.0, -2.0]])
    assert max(np.linalg.eigvals(A).real) == pytest.approx(0.5)
    r = solve(lyapunov_problem(A))
    assert r.status == "infeasible"
    assert r.verdict == "infeasible-certified"
    assert r.outcome.evidence.kind == "exact-proof"
    assert r.exit_code() == 3


def test_a_proved_unbounded_problem_exits_5():
    # max x1 s.t. [[1 + x1, x2], [x2, 1]] >= 0: x1 -> +inf along (1, 0) (closed form)
    r = solve(CASES["unbounded"].build())
    assert r.verdict == "unbounded-certified" and r.exit_code() == 5
    assert r.to_dict()["unbounded"]["sense"] == "max" and r.to_dict()["exit_code"] == 5


def test_theorem_target_compiles_with_params():
    r = solve("qib.thm1", QIB, params={"beta": 0.0005}, backend="clarabel")
    assert r.theorem == "qib.thm1" and r.params == {"beta": 0.0005}
    assert r.verdict == "certified"
    L = np.asarray(r.derived["L"])
    assert L.shape == (4, 2)
    assert r.timings["compile_s"] > 0 and r.timings["solve_s"] > 0


def test_load_target_errors():
    with pytest.raises(LmicError, match="no such file"):
        load_target("nothing_here.dat-s")
    with pytest.raises(LmicError, match="not to an IR problem"):
        load_target(CASES["max_sense"].build(), system="x.yaml")
    with pytest.raises(BackendUnavailable):
        solve(CASES["max_sense"].build(), backend="nope")


def test_auto_route_by_size():
    assert auto.route(CASES["max_sense"].build()) == ["clarabel"]
    big = lyapunov_problem(-np.eye(60))
    assert isinstance(big, Problem) and auto.route(big) == ["scs", "cvxopt"]


def test_auto_falls_back_when_the_certificate_fails(monkeypatch):
    import lmic.policy

    # an optimisation problem: the default route's order is lmic.route_rule.optimisation_chain
    monkeypatch.setattr(lmic.policy, "optimisation_chain", lambda problem, first_order=None: ["scs", "clarabel"])
    from lmic.backends.base import SolveOptions

    # SCS stopped after 5 iterations cannot be certified; Clarabel then is
    r = solve(CASES["bounded_real"].build(), backend="auto", options=SolveOptions(max_iter=5))
    assert [a["backend"] for a in r.attempts][0] == "scs"
    assert all(a["verdict"] != "certified" for a in r.attempts if a["backend"] == "scs")
    backends = [a["backend"] for a in r.attempts]
    assert "clarabel" in backends and backends.index("clarabel") > 0  # escalated to the next backend
