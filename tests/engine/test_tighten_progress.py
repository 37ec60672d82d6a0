"""The tight re-solves of lmic.route_tighten.tighten stop when one ran without halving the gap: an
infimum that is not attained (``inf 1e4 x1`` s.t. ``[[x1, 1], [1, x2]] >= 0``, value 0, the
points go to infinity) has a gap limited by the problem, not by the solver's tolerance."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

import lmic.api
import lmic.route_tighten as route_tighten
from lmic.certify import certify
from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable


def _unattained() -> Problem:
    C = sp.csc_matrix(np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]))
    return Problem(
        [Variable("x", "full", (2, 1))],
        [LMI("M >= 0", 2, C, strict=False)],
        LinearConstraints.empty(2),
        Objective("min", [0.0, 1e4, 0.0]),
    )


def test_no_second_tight_solve_without_progress(monkeypatch):
    p = _unattained()
    seen = []
    real = route_tighten._tighten_once

    def spy(*args, **kwargs):
        before = args[1]
        out, status = real(*args, **kwargs)
        seen.append((before.get("rel_gap"), out.get("rel_gap"), out is before))
        return out, status

    monkeypatch.setattr(route_tighten, "_tighten_once", spy)
    r = lmic.api.solve(p, backend="clarabel", backoff=0)
    assert certify(p, r.solution).verdict == "certified"
    enc = r.enclosure
    # the infimum is 0: x1 x2 >= 1 with x1 > 0 makes 1e4 x1 as small as wanted, never 0 or less
    assert enc["lower"] <= 0.0 <= enc["upper"]
    assert len(seen) == 1, seen
    g0, g1, same = seen[0]
    assert not same and g1 > 0.5 * g0  # the one tight solve ran and did not halve the gap


def test_no_progress_rule():
    assert route_tighten._no_progress({"rel_gap": 2e-6}, {"rel_gap": 1.5e-6})
    assert not route_tighten._no_progress({"rel_gap": 2e-6}, {"rel_gap": 0.5e-6})
    assert not route_tighten._no_progress({"rel_gap": None}, {"rel_gap": 1e-6})
