"""The objective-cut search (lmic.route_cut) on a closed-form infimum that is not attained:
both ends it reports are proofs, the truth (0) lies between them, and the audit re-proves them."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from lmic.certify.enclosure_audit import audit_enclosure
from lmic.certify.enclosure_float import primal_end
from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
from lmic.options import SolveOptions
from lmic.route_cut import cut_route, wants_cut


def _hyperbola() -> Problem:
    """``inf t`` subject to ``[[x, 1], [1, t]] > 0``: ``t > 1 / x``, so the infimum is 0, approached
    only as ``x`` grows (closed form)."""
    # tril order (0,0), (1,0), (1,1); columns: constant, x, t
    coeffs = sp.csc_matrix(np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]))
    lmi = LMI("hyperbola", 2, coeffs, strict=True)
    variables = [Variable("x", "scalar", (1, 1)), Variable("t", "scalar", (1, 1), offset=1)]
    return Problem(variables, [lmi], LinearConstraints.empty(2), Objective("min", [0.0, 0.0, 1.0]))


def _upper_only(problem: Problem, x: np.ndarray) -> dict:
    pe = primal_end(problem, x)
    assert pe["proven"]
    return {
        "sense": "min",
        "kind": "infimum",
        "lower": None,
        "upper": pe["value"],
        "primal": "restored point",
        "restored_x": x.tolist(),
        "dual": {"proven": False, "reason": "not attempted"},
        "problem": "ir",
        "reason": "infimum: only the upper end is certified",
    }


def test_cuts_bracket_an_infimum_that_is_not_attained():
    p = _hyperbola()
    enc = _upper_only(p, np.array([5.0, 0.5]))  # t = 0.5 > 1 / 5
    assert wants_cut(p, enc)
    out = cut_route(p, enc, "clarabel", SolveOptions(), False, 20.0)
    lo, hi = out["lower"], out["upper"]
    assert lo is not None and hi is not None
    assert lo <= 0.0 <= hi  # the infimum, 0
    assert hi - lo < 0.05 * 0.5  # narrowed from [none, 0.5]
    assert out["dual"]["route"] == "objective cut" and out["dual"]["proven"]
    assert out["primal"] == "restored point" and out["restored_x"] != enc["restored_x"]
    assert out["cut"]["steps"] == len(out["cut"]["log"]) >= 2
    assert out["rel_gap"] == hi - lo  # |ends| < 1: the relative gap is absolute
    audit = audit_enclosure(p, out, None)
    assert audit["ok"], audit["message"]
    # tampered ends are rejected: a lower end moved above the infimum, an upper end below it
    assert not audit_enclosure(p, dict(out, lower=1e-3, dual=dict(out["dual"], lower=1e-3)), None)["ok"]
    assert not audit_enclosure(p, dict(out, upper=hi / 2), None)["ok"]


def test_no_budget_no_cut_and_the_record_says_so():
    p = _hyperbola()
    enc = _upper_only(p, np.array([5.0, 0.5]))
    out = cut_route(p, enc, "clarabel", SolveOptions(), False, 0.0)
    assert out["lower"] is None and out["upper"] == enc["upper"] and out["cut"]["steps"] == 0
    assert "none proved" in out["reason"]


def test_maximisation_cuts_give_the_upper_end():
    """``sup -t`` of the same set: 0, the cut's record in the minimisation form."""
    p = _hyperbola()
    p = Problem(p.variables, p.lmis, p.linear, Objective("max", [0.0, 0.0, -1.0]))
    x = np.array([4.0, 0.5])
    enc = {
        "sense": "max",
        "kind": "supremum",
        "lower": primal_end(p, x)["value"],
        "upper": None,
        "primal": "restored point",
        "restored_x": x.tolist(),
        "dual": {"proven": False},
        "problem": "ir",
        "reason": "supremum: only the lower end is certified",
    }
    out = cut_route(p, enc, "cvxopt", SolveOptions(), False, 20.0)
    assert out["lower"] <= 0.0 <= out["upper"]
    assert out["dual"]["lower"] == -out["upper"]
    assert audit_enclosure(p, out, None)["ok"]
