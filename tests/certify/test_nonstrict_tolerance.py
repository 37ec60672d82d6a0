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


@pytest.mark.xfail(strict=True, reason="documented equality-row tolerance rel = 1e-8 (lmic.certify.margins)")
def test_a_point_off_an_equality_row_does_not_certify_an_infeasible_strict_problem():
    """``x1 = x2`` (row), ``x1 - x2 - 1e-9 > 0`` and ``x1 - 1 > 0``: infeasible (the row forces
    ``x1 - x2 = 0``). At ``x = (1.5, 1.5 - 2e-9)`` both LMIs hold strictly with margin and the row
    is off by ``2e-9 <= 1e-8 * 3``: ``certified``, even with ``exact=True`` (the row "within
    tolerance"). SCS returns such a point (``decide(p, "scs")``: certified) where Clarabel and
    CVXOPT prove the problem infeasible exactly."""
    import numpy as np

    from lmic.certify import certify
    from lmic.solution import Solution

    lin = LinearConstraints(sp.csr_matrix(np.array([[0.0, 1.0, -1.0]])), ["eq"], [False], ["x1 = x2"])
    p = Problem(
        [Variable("x1", "scalar", (1, 1), 0), Variable("x2", "scalar", (1, 1), 1)],
        [
            LMI("x1 - x2 - 1e-9 > 0", 1, sp.csc_matrix([[-1e-9, 1.0, -1.0]])),
            LMI("x1 - 1 > 0", 1, sp.csc_matrix([[-1.0, 1.0, 0.0]])),
        ],
        lin,
        Objective("feasibility", [0.0, 0.0, 0.0]),
    )
    assert Fraction(-1e-9) < 0  # on the row x1 - x2 = 0 the first LMI is -1e-9 > 0: false
    x = np.array([1.5, 1.5 - 2e-9])
    assert certify(p, Solution("optimal", x=x), exact=True).verdict != "certified"
