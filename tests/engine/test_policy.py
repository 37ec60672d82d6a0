"""lmic.policy: the strategies of one backend after a failed optimisation solve."""

from __future__ import annotations

import numpy as np
import pytest
from certify_helpers import interval_problem

from lmic.certify import certify
from lmic.solution import Solution


def test_failed_optimisation_solve_is_rescaled_at_the_feasibility_point(monkeypatch) -> None:
    """The optimisation solve fails without a point (a stand-in for CVXOPT's ZeroDivisionError
    on random sampled_euler.thm2 at 9 states); its feasibility problem has a point, which decides
    nothing on its own. The optimisation problem preconditioned at that point (``rescaled``) is
    solved next and gives the optimum: certified by the certifier, ``max t`` s.t. ``C - t I >= 0``
    equal to ``lambda_min(C)`` (numpy), never the feasibility point's objective."""
    import lmic.policy as policy
    from lmic.testing.conformance import _C, CASES

    real = policy._solve_one

    def failing(be, target, options, scales, judge):
        if scales is None and target.objective.sense != "feasibility":
            return Solution("error", message="stand-in failure")
        return real(be, target, options, scales, judge)

    monkeypatch.setattr(policy, "_solve_one", failing)
    problem = CASES["max_sense"].build()
    out = policy.decide(problem, "clarabel")
    assert [a.reduction.split("/")[0] for a in out.attempts] == ["default", "feasibility", "rescaled"]
    assert out.solution.objective == pytest.approx(float(np.linalg.eigvalsh(_C)[0]), abs=1e-6)
    # the optimum is on the boundary of the non-strict LMI: Clarabel's point there is outside by
    # ~1e-9, within the float tolerance, and the exact proof disproves it; never "certified" on
    # the tolerance (the enclosure's restored point is what lmic.api.solve certifies)
    assert out.verdict == "rejected" and "not positive semidefinite at the solver's point" in out.reason
    assert certify(problem, out.solution).verdict == "rejected"


@pytest.mark.parametrize(("status", "verdict"), [("inaccurate", "undecided"), ("optimal", "certified")])
def test_an_exact_rescue_keeps_the_solvers_word_on_optimality(monkeypatch, status, verdict) -> None:
    """``min t`` s.t. ``t - 1 > 0``: a point ``t = 1 + 2^-46`` holds with a margin below the float
    certifier's threshold, so it is rejected, and the exact rescue proves it (``t - 1 > 0`` in
    rational arithmetic, checked here with ``Fraction``). That makes the point hold; it is the
    optimum only as far as the solver says: an ``inaccurate`` solve's point stays ``undecided``
    (uio_dt.thm4_1 got ``certified`` at a point 2.4e-3 above its infimum), an ``optimal`` one is
    ``certified``."""
    from fractions import Fraction

    import scipy.sparse as sp

    import lmic.policy as policy
    from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable

    problem = Problem(
        [Variable("t", "scalar", (1, 1))],
        [LMI("t - 1 > 0", 1, sp.csc_matrix([[-1.0, 1.0]]))],
        LinearConstraints.empty(1),
        Objective("min", [0.0, 1.0]),
    )
    t = 1.0 + 2.0**-46
    assert Fraction(t) - 1 > 0  # the truth: the point holds

    def answer(be, target, options, scales, judge):
        return Solution(status, x=np.array([t]), objective=t, backend="clarabel")

    monkeypatch.setattr(policy, "_solve_one", answer)
    assert certify(problem, Solution(status, x=np.array([t]), objective=t)).verdict == "rejected"
    out = policy.decide(problem, "clarabel")
    rescue = [a for a in out.attempts if a.reduction == "exact rescue"]
    assert rescue and rescue[0].verdict == verdict
    assert out.verdict == verdict and out.certificate.verdict == "certified"
    assert out.solution.x.tolist() == [t]


def test_a_ray_the_strict_reduction_did_not_return_is_still_proved(monkeypatch) -> None:
    """``x >= 1`` and ``-x >= 0``: infeasible (closed form). The strict reduction returned its
    max-margin answer (undecided, ``inaccurate``) and kept fixed-margin's Farkas ray aside
    (``info["unchosen_rays"]``); the policy certifies that ray too: ``Z = (1, 1)`` gives
    ``sum_i <F_i^(k), Z_i> = 1 - 1 = 0`` for ``x`` and ``-1 < 0`` for the constants."""
    import lmic.policy as policy

    problem = interval_problem(1.0, 0.0)
    ray = Solution("infeasible", farkas={"lmis": [[[1.0]], [[1.0]]], "y": []}, strategy="fixed-margin")

    def answer(be, target, options, scales, judge):
        sol = Solution("inaccurate", x=np.array([0.5]), objective=0.0, strategy="max-margin", backend="clarabel")
        sol.info["unchosen_rays"] = [ray]
        return sol

    monkeypatch.setattr(policy, "_solve_one", answer)
    out = policy.decide(problem, "clarabel")
    assert out.verdict == "infeasible-certified", out.reason
    assert [a.reduction for a in out.attempts][:2] == ["default/max-margin", "default/fixed-margin"]

    def without(be, target, options, scales, judge):
        return Solution("inaccurate", x=np.array([0.5]), objective=0.0, strategy="max-margin", backend="clarabel")

    monkeypatch.setattr(policy, "_solve_one", without)
    assert policy.decide(problem, "clarabel").verdict != "infeasible-certified"  # nothing else proves it
