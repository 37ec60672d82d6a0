"""The first backoff of the margin solve just inside the route's gap (lmic.upper_end's ``start``,
lmic.route_upper.START_WITHIN): a restored point then meets the gap instead of landing on it."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from lmic.certify import certify
from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
from lmic.solution import Solution
from lmic.upper_end import START_DELTAS, upper_from_lower


def _two_by_two() -> Problem:
    """``min t`` s.t. ``[[t, 1], [1, t]] >= 0``: optimum 1 (``t >= |1|``), closed form."""
    C = sp.csc_matrix(np.array([[0.0, 1.0], [1.0, 0.0], [0.0, 1.0]]))
    return Problem(
        [Variable("t", "scalar", (1, 1))],
        [LMI("M >= 0", 2, C, strict=False)],
        LinearConstraints.empty(1),
        Objective("min", [0.0, 1.0]),
    )


def test_start_backoff_is_tried_first_and_meets_it():
    p = _two_by_two()
    start = 0.9 * 1e-4
    assert start < START_DELTAS[0]
    r = upper_from_lower(p, 1.0, "clarabel", x_hint=np.array([1.0]), target=1e-3, start=start)
    assert r["proven"]
    assert r["steps"][0]["delta"] == start
    # the true optimum is 1: the point's objective lies in (1, 1 + start], rounding aside
    assert 1.0 <= r["value"] <= 1.0 + start * (1 + 1e-9)
    x = np.asarray(r["x"], dtype=float)
    sol = Solution(status="optimal", x=x, objective=float(x[0]), duals=None, backend="clarabel", message="")
    assert certify(p, sol).verdict == "certified"


def test_start_above_the_ladder_changes_nothing():
    p = _two_by_two()
    r = upper_from_lower(p, 1.0, "clarabel", x_hint=np.array([1.0]), target=1e-3, start=0.5)
    assert r["steps"][0]["delta"] == START_DELTAS[0]


def test_margin_solve_goes_to_the_alternatives_when_the_backend_gives_no_point():
    from lmic.backends.clarabel import ClarabelBackend
    from lmic.errors import BackendError

    class Broken(ClarabelBackend):
        """A backend that ends every solve without a point (as SDPA's noINFO on SDPLIB qap6's
        margin problem)."""

        def call(self, problem, settings):
            raise BackendError("broken on purpose")

    p = _two_by_two()
    r = upper_from_lower(p, 1.0, Broken(), x_hint=np.array([1.0]), target=1e-3, alternatives=("clarabel",))
    assert r["proven"]
    assert r["steps"][0].get("backend") == "clarabel"
    assert 1.0 <= r["value"] <= 1.0 + START_DELTAS[0] * (1 + 1e-9)
    x = np.asarray(r["x"], dtype=float)
    sol = Solution(status="optimal", x=x, objective=float(x[0]), duals=None, backend="clarabel", message="")
    assert certify(p, sol).verdict == "certified"
    # without the alternative, no point at all
    assert not upper_from_lower(p, 1.0, Broken(), x_hint=np.array([1.0]), target=1e-3)["proven"]
