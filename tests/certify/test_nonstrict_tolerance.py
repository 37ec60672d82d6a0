"""A documented tolerance that yields a false ``certified`` (exit 0): NOT fixed, recorded here.

``x - 1 >= 0`` and ``c - x >= 0`` with ``c`` the float nearest ``0.999999999`` is infeasible (exact
rationals below). Clarabel returns ``x ~ 1 - 5e-10``; the certifier's non-strict rule
``lambda_min >= -1e-8 T`` accepts it, so lmic answers ``certified`` (exit 0). With ``--exact``
the same route even proves the problem infeasible exactly (CVXOPT's ray, ``infeasible-certified``)
and still returns ``certified``: the exact disproof of the row does not override the float
tolerance (``check._apply_exact``: "a non-strict LMI accepted within the float tolerance stays
accepted when exactly disproved"). Changing that rule is a policy decision, not a small fix.
"""

from __future__ import annotations

from fractions import Fraction

import pytest
import scipy.sparse as sp

from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable

C = 0.999999999


def _problem() -> Problem:
    return Problem(
        [Variable("x", "scalar", (1, 1))],
        [
            LMI("x - 1 >= 0", 1, sp.csc_matrix([[-1.0, 1.0]]), strict=False),
            LMI("c - x >= 0", 1, sp.csc_matrix([[C, -1.0]]), strict=False),
        ],
        LinearConstraints.empty(1),
        Objective("feasibility", [0.0, 0.0]),
    )


@pytest.mark.xfail(strict=True, reason="documented non-strict tolerance rel = 1e-8 (lmic.certify.check)")
def test_an_exactly_infeasible_problem_is_not_certified():
    from lmic.policy import decide

    assert Fraction(C) < 1  # x >= 1 and x <= C < 1: infeasible
    assert decide(_problem(), "clarabel").verdict != "certified"
