"""``certified`` means proved: a non-strict LMI or row that holds only within the float tolerance
is proved exactly, or the point is rejected.

The counterexamples came from a soundness review: ``x - 1 >= 0`` and ``c - x >= 0`` with ``c``
the float nearest ``0.999999999`` is infeasible (exact rationals below), yet Clarabel's point
``x ~ 1 - 5e-10`` passed the non-strict rule ``lambda_min >= -1e-8 T`` as ``certified``; and a
point ``2e-9`` off an equality row certified an infeasible strict problem, even with
``exact=True`` (the row was accepted "within tolerance"). The truth of each problem is computed
here with :class:`fractions.Fraction`, not with lmic.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import scipy.sparse as sp
from certify_helpers import interval_problem

from lmic.certify import certify
from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
from lmic.solution import Solution

C = 0.999999999


def _interval(lo: float, hi: float) -> Problem:
    """``x - lo >= 0`` and ``hi - x >= 0``: feasible exactly when ``lo <= hi``."""
    return interval_problem(lo, hi)


def _on_row(shift: float, upper: float) -> Problem:
    """``x1 = x2`` (row), ``x1 - x2 - shift > 0``, ``x1 - 1 > 0`` and ``upper - x2 > 0``."""
    lin = LinearConstraints(sp.csr_matrix(np.array([[0.0, 1.0, -1.0]])), ["eq"], [False], ["x1 = x2"])
    return Problem(
        [Variable("x1", "scalar", (1, 1), 0), Variable("x2", "scalar", (1, 1), 1)],
        [
            LMI("x1 - x2 - shift > 0", 1, sp.csc_matrix([[-shift, 1.0, -1.0]])),
            LMI("x1 - 1 > 0", 1, sp.csc_matrix([[-1.0, 1.0, 0.0]])),
            LMI("upper - x2 > 0", 1, sp.csc_matrix([[upper, 0.0, -1.0]])),
        ],
        lin,
        Objective("feasibility", [0.0, 0.0, 0.0]),
    )


def test_a_point_within_the_tolerance_of_an_infeasible_problem_is_not_certified():
    """Clarabel's point ``x ~ 1 - 5e-10`` is rejected (exactly violated); its infeasibility
    certificate (separation ``-5e-10``, below the float rule) is then proved exactly."""
    from lmic.policy import decide

    assert Fraction(C) < 1  # x >= 1 and x <= C < 1: infeasible
    out = decide(_interval(1.0, C), "clarabel")
    assert out.verdict == "infeasible-certified", out.reason
    first = out.attempts[0]
    assert first.verdict == "rejected" and "not positive semidefinite" in first.note


def test_the_float_tolerance_alone_never_certifies():
    """At ``x = 1 - 5e-10`` the first LMI is ``-5e-10``: within ``1e-8``, and exactly violated."""
    c = certify(_interval(1.0, C), Solution("optimal", x=np.array([1.0 - 5e-10])))
    assert c.verdict == "rejected"
    assert c.lmis[0]["exact"] == "disproved" and not c.lmis[0]["ok"]


def test_a_boundary_point_of_a_feasible_problem_is_proved_exactly():
    """``x = 1`` is the only feasible point of ``1 <= x <= 1``; a float point next to it is
    within tolerance, and the exact proof (here: at the snapped point 1) certifies it."""
    for x in (1.0, 1.0 + 2e-16, 1.0 - 1e-12):
        c = certify(_interval(1.0, 1.0), Solution("optimal", x=np.array([x])))
        assert c.verdict == "certified", (x, c.reason)
        assert Fraction(c.x[0]) == 1  # the certified point is the exact one


def test_a_point_off_an_equality_row_does_not_certify_an_infeasible_problem():
    """On the row ``x1 - x2 = 0`` the first LMI reads ``-1e-9 > 0``: infeasible. The point is
    ``2e-9`` off the row, within ``1e-8 * 3``, and every LMI holds there with margin."""
    assert Fraction(-1e-9) < 0
    p = _on_row(1e-9, 3.0)
    x = np.array([1.5, 1.5 - 2e-9])
    for exact in (False, True):
        c = certify(p, Solution("optimal", x=x), exact=exact)
        assert c.verdict == "rejected", exact
        assert "equality 'x1 = x2' holds only within the tolerance" in c.reason


def test_a_point_near_an_equality_row_of_a_feasible_problem_is_projected_onto_it():
    """Without the shift the problem is feasible (``x1 = x2 = 1.7``); the float point is 1e-12
    off the row, and the exact projection onto it keeps every LMI."""
    p = _on_row(-1.0, 3.0)  # x1 - x2 + 1 > 0 holds on the row
    c = certify(p, Solution("optimal", x=np.array([1.7, 1.7 + 1e-12])))
    assert c.verdict == "certified"
    assert c.exact is not None and c.exact["proven"] and not c.exact["at_x"]
    num = [Fraction(int(v), int(c.exact["point"]["den"])) for v in c.exact["point"]["num"]]
    assert num[0] == num[1] and num[0] > 1 and 3 - num[1] > 0  # on the row, inside the LMIs


def test_a_separation_below_the_float_tolerance_is_decided_exactly():
    """``x >= 1`` and ``x <= 1 - 1e-6``: every interior point says infeasible, with a separation
    ``g0 = -5e-7`` below the float rule's ``1e-6 x scale 2``. The float check cannot verify it
    and used to say "-5e-07 > 0", and the route ended ``rejected``; the exact proof decides."""
    from lmic.api import solve
    from lmic.certify.farkas import verify_farkas

    hi = 1.0 - 1e-6
    assert Fraction(hi) < 1  # the truth: infeasible
    p = _interval(1.0, hi)
    r = solve(p)
    assert r.verdict == "infeasible-certified", r.certificate.reason
    assert r.certificate.exact is not None and r.certificate.exact["proven"]
    # the float verification's own words about such a certificate
    farkas = next(a for a in r.attempts if a["status"] == "infeasible")
    assert farkas["note"] == "exact proof of the ray"
    z = {"lmis": [[[0.5]], [[0.5]]], "y": []}
    f = verify_farkas(p, z, tol=1e-6)
    assert not f["verified"] and "separation too small" in f["reason"] and "> 0" not in f["reason"]
