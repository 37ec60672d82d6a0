"""lmic.route_unbounded: the search for an improving ray after a solver said ``unbounded``.

A solver's ``unbounded`` is a claim: on a bounded problem the ray problems are infeasible, and
an infeasibility answer from the first backend ends the search on each of them (a second
backend's proof of it proves nothing wanted; it cost 13 s of Clarabel on a 100-vertex graph
partitioning problem). The time of a search that proved nothing is reported on its own
(``ray_search_s``), not as lmic's overhead.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

import lmic.policy as policy
from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
from lmic.outcome import Attempt, Outcome
from lmic.route_unbounded import unbounded_outcome
from lmic.solution import Solution


def _bounded_problem() -> Problem:
    """``min t`` s.t. ``[[t, 1], [1, 1]] >= 0``: the optimum 1 (``t >= 1``), no improving ray."""
    C = sp.csc_matrix(np.array([[0.0, 1.0], [1.0, 0.0], [1.0, 0.0]]))
    return Problem(
        [Variable("t", "scalar", (1, 1))],
        [LMI("M", 2, C, strict=False)],
        LinearConstraints.empty(1),
        Objective("min", [0.0, 1.0]),
    )


def _every_infeasibility_bounded(monkeypatch: pytest.MonkeyPatch) -> None:
    """Every solve says ``infeasible`` with a bounded ray (as SDPA / CVXOPT / Clarabel do on
    the ray problems of graph partitioning)."""

    def infeasible(be, target, options, scales, judge):
        return Solution("infeasible", backend=be.label, message="stand-in")

    def bounded(problem, sol, cert):
        return "infeasible-bounded" if sol.status == "infeasible" else "undecided"

    monkeypatch.setattr(policy, "_solve_one", infeasible)
    monkeypatch.setattr(policy, "verdict_of", bounded)


def test_max_bounded_stops_the_route_at_the_first_bounded_answer(monkeypatch: pytest.MonkeyPatch) -> None:
    _every_infeasibility_bounded(monkeypatch)
    problem = _bounded_problem()
    default = policy.decide(problem, None)
    assert default.verdict == "infeasible-bounded"
    assert len({a.backend for a in default.attempts}) == policy.MAX_BOUNDED == 2
    once = policy.decide(problem, None, max_bounded=1)
    assert once.verdict == "infeasible-bounded"
    assert len({a.backend for a in once.attempts}) == 1


def test_a_ray_search_on_a_bounded_problem_asks_one_backend_per_ray_problem(monkeypatch: pytest.MonkeyPatch) -> None:
    _every_infeasibility_bounded(monkeypatch)
    real = policy.decide
    asked: list[tuple[str, set[str]]] = []  # (the problem decided, the backends it asked)

    def recording(problem, *args, **kwargs):
        out = real(problem, *args, **kwargs)
        asked.append((str(problem.meta.get("ray_of", problem.objective.sense)), {a.backend for a in out.attempts}))
        return out

    monkeypatch.setattr(policy, "decide", recording)
    problem = _bounded_problem()
    said = Outcome("undecided", reason="the solver said unbounded")
    said.attempts = [Attempt("sdpa", "rescaled", "unbounded", "pINF_dFEAS")]
    out = unbounded_outcome(problem, said)
    assert out is said and out.verdict == "undecided"
    assert "the solver reports unbounded, not proved: no improving ray found" in out.reason
    assert out.ray_search_s > 0
    # the two ray problems (strict, then closed): one backend each; then the original's
    # feasibility problem, on its own route (stopped by MAX_BOUNDED as any decision)
    assert [len(b) for _, b in asked] == [1, 1, policy.MAX_BOUNDED], asked


def test_the_route_reports_the_ray_search_apart_from_lmics_own_time(monkeypatch: pytest.MonkeyPatch) -> None:
    """The search for a ray a backend claimed (stood in by 0.4 s of sleep recorded on the
    outcome) reaches ``ray_search_s`` of the route's answer (the route sums it over its
    backends) and the timings, not ``lower_s`` (lmic's reduction and lowering)."""
    import time

    import lmic.api
    import lmic.routes as routes

    real = routes._unbounded_checked

    def searched(problem, out, options):
        out = real(problem, out, options)
        time.sleep(0.4)
        out.ray_search_s += 0.4
        return out

    monkeypatch.setattr(routes, "_unbounded_checked", searched)
    r = lmic.api.solve(_bounded_problem())
    assert r.verdict == "certified"
    assert r.enclosure["lower"] <= 1.0 <= r.enclosure["upper"]  # the optimum t = 1
    n_backends = len({a["backend"] for a in r.attempts})
    assert r.timings["ray_search_s"] == pytest.approx(0.4 * n_backends)
    assert r.timings["lower_s"] < 0.4
