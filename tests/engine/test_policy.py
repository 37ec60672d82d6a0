"""lmic.policy: the strategies of one backend after a failed optimisation solve."""

from __future__ import annotations

import numpy as np
import pytest

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
