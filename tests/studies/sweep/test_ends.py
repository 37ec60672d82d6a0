"""lmic.studies.sweep.ends: the certified end reports, and writes, the point its proof holds at."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
from certify_helpers import interval_problem

from lmic.certify import certify
from lmic.solution import Solution
from lmic.studies.sweep.ends import certified_end
from lmic.studies.sweep.results import PointResult


def test_the_end_point_is_the_snapped_point_the_proof_holds_at():
    """``p - 1 >= 0`` and ``1 - p >= 0``: the only point is ``p = 1`` (closed form). A bisection
    point ``1 - 1e-12`` is certified at the certifier's snap onto ``p = 1``; the end reports
    that point, not the bisection's (whose certificate file ``lmic audit`` would reject)."""
    p = interval_problem(1.0, 1.0, name="p")
    x = np.array([1.0 - 1e-12])
    assert not Fraction(x[0]) == 1  # the bisection point itself is infeasible
    cert = certify(p, Solution("optimal", x=x))
    assert cert.verdict == "certified" and not np.array_equal(np.asarray(cert.x), x)  # the snap
    pt = PointResult(value=0.5, outcome="feasible", proof="certified", status="optimal")
    pt.problem, pt.x = p, x
    end = certified_end(pt, backoff=0.0)
    assert end is not None and end.verdict == "certified"
    assert Fraction(end.solution.x[0]) == 1 and end.norm_inf == 1.0
    assert certify(p, end.solution).verdict == "certified"
