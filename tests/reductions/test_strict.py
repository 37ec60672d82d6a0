"""lmic.reductions.strict: what the strict reduction returns and keeps for its caller."""

from __future__ import annotations


def test_a_ray_of_an_attempt_not_returned_is_kept_for_the_caller():
    """SCS's plan: fixed-margin first; its Farkas ray is not verified in floats (here a zero
    ray), so max-margin runs and its ``inaccurate`` answer is returned; the ray is kept in
    ``info["unchosen_rays"]``, for the policy's exact proof (tests/engine/test_policy.py)."""
    import numpy as np
    import scipy.sparse as sp

    from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
    from lmic.options import SolveOptions
    from lmic.reductions.strict import solve
    from lmic.solution import Solution

    p = Problem(
        [Variable("x", "scalar", (1, 1))],
        [LMI("x > 0", 1, sp.csc_matrix([[0.0, 1.0]])), LMI("1 - x > 0", 1, sp.csc_matrix([[1.0, -1.0]]))],
        LinearConstraints.empty(1),
        Objective("feasibility", [0.0, 0.0]),
    )

    def run(reduced, options):
        if reduced.objective.sense == "feasibility":  # fixed-margin
            return Solution("infeasible", farkas={"lmis": [[[0.0]], [[0.0]]], "y": []})
        return Solution("inaccurate", x=np.zeros(reduced.n), objective=0.0)

    sol = solve(p, SolveOptions(), run, first_order=True)
    assert sol.strategy == "max-margin" and sol.status == "inaccurate"
    rays = sol.info["unchosen_rays"]
    assert len(rays) == 1 and rays[0].strategy == "fixed-margin" and rays[0].status == "infeasible"
