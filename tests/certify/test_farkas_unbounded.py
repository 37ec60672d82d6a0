"""Unbounded problems (a dual infeasible): an exact improving ray and what it proves.

The truth is known independently: ``min -t`` over ``[[t, 1], [1, t]] >= 0`` is unbounded (the
feasible set is ``t >= 1``, closed form), and SDPLIB's infd1 is published as dual infeasible.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

from lmic.certify.farkas_unbounded import prove_improving_ray, ray_problem
from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable

SDPLIB = Path("/work/shared/sdplib")


def _unbounded_problem(sense: str = "min") -> Problem:
    C = sp.csc_matrix(np.array([[0.0, 1.0], [1.0, 0.0], [0.0, 1.0]]))  # [[t, 1], [1, t]]
    c = [0.0, -1.0] if sense == "min" else [0.0, 1.0]
    return Problem(
        [Variable("t", "scalar", (1, 1))],
        [LMI("M >= 0", 2, C, strict=False)],
        LinearConstraints.empty(1),
        Objective(sense, c),
    )


@pytest.mark.parametrize("sense", ["min", "max"])
def test_the_improving_ray_is_proved_and_a_wrong_one_is_not(sense: str) -> None:
    p = _unbounded_problem(sense)
    assert prove_improving_ray(p, np.array([2.5]))["proven"]
    bad = prove_improving_ray(p, np.array([-1.0]))  # the objective increases along it
    assert not bad["proven"] and "does not decrease" in bad["reason"]


def test_a_ray_that_leaves_an_lmi_is_not_proved() -> None:
    # min -t - s over diag(t - s, s - t) >= 0 ... along d = (1, 0): t - s grows, s - t falls
    C = sp.csc_matrix(np.array([[0.0, 1.0, -1.0], [0.0, 0.0, 0.0], [0.0, -1.0, 1.0]]))
    p = Problem(
        [Variable("t", "scalar", (1, 1), 0), Variable("s", "scalar", (1, 1), 1)],
        [LMI("D >= 0", 2, C, strict=False)],
        LinearConstraints.empty(2),
        Objective("min", [0.0, -1.0, -1.0]),
    )
    res = prove_improving_ray(p, np.array([1.0, 0.0]))
    assert not res["proven"] and "not proved PSD" in res["reason"]
    assert prove_improving_ray(p, np.array([1.0, 1.0]))["proven"]  # t = s grows: feasible forever


def test_ray_problem_points_are_rays() -> None:
    from lmic.policy import decide

    p = _unbounded_problem()
    out = decide(ray_problem(p))
    assert out.verdict == "certified"
    assert prove_improving_ray(p, out.solution.x)["proven"]


def test_route_says_exactly_what_is_proved_for_an_unbounded_problem() -> None:
    from lmic.routes import decide_route

    out = decide_route(_unbounded_problem(), "clarabel").outcome
    assert out.verdict == "undecided" and out.exit_code() == 1  # no optimum exists to certify
    assert out.evidence.kind == "exact-proof"
    assert out.reason.startswith("unbounded below: a certified feasible point and an exact improving ray")


@pytest.mark.skipif(not (SDPLIB / "infd1.dat-s").exists(), reason="SDPLIB not available")
def test_sdplib_infd1_is_reported_dual_infeasible_and_unbounded() -> None:
    from lmic.ir.sdpa import read_sdpa
    from lmic.policy import feasibility_problem
    from lmic.routes import decide_route

    problem = read_sdpa(SDPLIB / "infd1.dat-s")
    r = decide_route(problem)
    assert r.outcome.verdict == "undecided"
    assert "unbounded below" in r.outcome.reason and "the dual is infeasible" in r.outcome.reason
    # the point behind "a certified feasible point" is certified against the feasibility problem
    from lmic.certify import certify

    assert r.outcome.certificate is not None
    assert certify(feasibility_problem(problem), _solution(r.outcome.certificate.x)).verdict == "certified"


def _solution(x: np.ndarray):
    from lmic.solution import Solution

    return Solution("optimal", x=np.asarray(x, dtype=float))
