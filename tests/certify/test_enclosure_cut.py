"""The objective cut's dual end (lmic.certify.enclosure_cut): a cut proved infeasible in exact
arithmetic bounds the optimal value; the record is re-proved by the audit and a tampered one is
rejected. Closed forms throughout."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from lmic.certify.enclosure_audit import audit_enclosure
from lmic.certify.enclosure_cut import CUT_NAME, cut_problem, prove_cut, verify_cut
from lmic.certify.farkas_ray import verify_farkas
from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable


def _interval(sense: str, strict: bool) -> Problem:
    """``t`` in ``[2, 3]`` (``t > 2``, ``t < 3`` when strict): the optimum is 2 (min) or 3 (max)."""
    lmis = [
        LMI("t - 2", 1, sp.csc_matrix([[-2.0, 1.0]]), strict=strict),
        LMI("3 - t", 1, sp.csc_matrix([[3.0, -1.0]]), strict=strict),
    ]
    return Problem([Variable("t", "scalar", (1, 1))], lmis, LinearConstraints.empty(1), Objective(sense, [0.0, 1.0]))


def test_cut_problem_adds_one_non_strict_row_in_the_minimisation_form():
    p = _interval("max", False)
    cut = cut_problem(p, -2.5)  # max t: "-t <= -2.5", i.e. t >= 2.5
    assert cut.objective.sense == "feasibility"
    assert cut.linear.names == [CUT_NAME] and cut.linear.kinds == ["ge"] and cut.linear.strict == [False]
    assert cut.linear.residuals(np.array([2.5]))[0] == 0.0 and cut.linear.residuals(np.array([2.4]))[0] < 0
    with pytest.raises(ValueError, match="optimisation"):
        cut_problem(Problem(p.variables, p.lmis, p.linear, Objective("feasibility", [0.0, 0.0])), 1.0)


@pytest.mark.parametrize(("sense", "r", "bound"), [("min", 1.5, 1.5), ("max", -3.25, 3.25)])
def test_a_cut_beyond_the_optimum_is_a_proven_end_and_audited(sense, r, bound):
    p = _interval(sense, False)
    cut = cut_problem(p, r)
    # the ray: the constraint active at the optimum plus the cut row (closed form)
    ray = {"lmis": [np.eye(1), np.zeros((1, 1))] if sense == "min" else [np.zeros((1, 1)), np.eye(1)], "linear": [1.0]}
    rec = prove_cut(p, r, ray, verify_farkas(cut, ray))
    assert rec["proven"] and rec["route"] == "objective cut" and rec["lower"] == r and rec["kind"] == "closed"
    assert verify_cut(p, rec)["ok"]
    # the enclosure with it: the optimum (2 or 3) is inside, and the audit re-proves the end
    enc = {
        "sense": sense,
        "kind": "minimum" if sense == "min" else "maximum",
        "lower": r if sense == "min" else None,
        "upper": None if sense == "min" else bound,
        "dual": rec,
        "problem": "ir",
    }
    assert audit_enclosure(p, enc, None)["ok"]
    # tampered: the cut moved past the optimum, the ray changed, the threshold made invalid
    moved = 2.5 if sense == "min" else -2.5
    assert "above the cut's bound" in verify_cut(p, dict(rec, lower=moved))["reason"]
    assert not verify_cut(p, dict(rec, lower=moved, cut={**rec["cut"], "r": moved}))["ok"]
    forged = {**rec["cut"], "farkas": {"lmis": [[[1.0]], [[1.0]]], "linear": [0.0]}}
    assert not verify_cut(p, dict(rec, cut=forged))["ok"]
    assert not verify_cut(p, dict(rec, cut={**rec["cut"], "threshold": 2.0}))["ok"]
    bad = dict(enc, lower=moved) if sense == "min" else dict(enc, upper=-moved)
    assert not audit_enclosure(p, dict(bad, dual=dict(rec, lower=moved)), None)["ok"]


def test_a_cut_at_a_strict_infimum_is_proved_for_the_strict_problem():
    """``inf t`` over ``t > 2`` is 2, not attained: the cut ``t <= 2`` is infeasible for the strict
    problem (a strict proof), and 2 is the exact lower end."""
    p = _interval("min", True)
    ray = {"lmis": [np.eye(1), np.zeros((1, 1))], "linear": [1.0]}
    rec = prove_cut(p, 2.0, ray, verify_farkas(cut_problem(p, 2.0), ray))
    assert rec["proven"] and rec["lower"] == 2.0 and rec["kind"] == "strict"
    assert verify_cut(p, rec)["ok"]
    # ... while for the closed problem t = 2 is feasible: no proof
    closed = _interval("min", False)
    assert not prove_cut(closed, 2.0, ray, verify_farkas(cut_problem(closed, 2.0), ray))["proven"]


def test_a_feasible_cut_is_never_proved():
    p = _interval("min", False)
    rays = ({"lmis": [np.eye(1), np.zeros((1, 1))], "linear": [1.0]}, {"lmis": [np.eye(1), np.eye(1)], "linear": [0.0]})
    for ray in rays:
        rec = prove_cut(p, 2.5, ray, verify_farkas(cut_problem(p, 2.5), ray))
        assert not rec["proven"] and rec["lower"] is None


def test_a_malformed_record_is_rejected_with_a_reason():
    p = _interval("min", False)
    assert "missing" in verify_cut(p, {"route": "objective cut", "lower": float("nan"), "cut": {}})["reason"]
    bad = {"route": "objective cut", "lower": 1.5, "cut": {"r": 1.5, "farkas": {"lmis": "x"}, "threshold": 1e-9}}
    assert "malformed" in verify_cut(p, bad)["reason"]
    shape = {"r": 1.5, "farkas": {"lmis": [[[1.0, 2.0]], [[0.0]]], "linear": [1.0]}, "threshold": 1e-9}
    out = verify_cut(p, {"route": "objective cut", "lower": 1.5, "cut": shape})
    assert not out["ok"] and "malformed" in out["reason"] and "shape" in out["reason"]


def test_an_objective_constant_is_summed_exactly_and_rounded_down():
    """``min 0.1 + t`` over ``t >= 2`` (optimum 2.1): the cut row's constant is ``fl(r - 0.1)``,
    so the end the proof gives is ``0.1 + fl(r - 0.1)`` in exact arithmetic, rounded down."""
    from fractions import Fraction

    from lmic.certify.enclosure_cut import cut_bound

    p = _interval("min", False)
    p = Problem(p.variables, p.lmis, p.linear, Objective("min", [0.1, 1.0]))
    r = 2.05
    ray = {"lmis": [np.eye(1), np.zeros((1, 1))], "linear": [1.0]}
    rec = prove_cut(p, r, ray, verify_farkas(cut_problem(p, r), ray))
    assert rec["proven"] and rec["cut"]["r"] == r
    exact = Fraction(0.1) + Fraction(r - 0.1)
    assert Fraction(rec["lower"]) <= exact and rec["lower"] == cut_bound(p, r)
    assert Fraction(float(np.nextafter(rec["lower"], np.inf))) > exact  # the largest float below
    assert verify_cut(p, rec)["ok"]
    assert not verify_cut(p, dict(rec, lower=np.nextafter(float(exact), np.inf)))["ok"]
