"""The backed-off, well-scaled point near the optimum (lmic.backoff): certified by the certifier
against the original problem, within the relative backoff, recorded and re-certified by audit."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

import lmic.api
from lmic.backoff import backoff_problem
from lmic.certify import audit_certificate, write_certificate
from lmic.ir.problem import LinearConstraints, Objective, Problem, Variable

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def test_backoff_problem_keeps_the_objective_within_the_relative_room():
    p = Problem([Variable("a", "scalar", (1, 1))], [], LinearConstraints.empty(1), Objective("max", [0.0, 1.0]))
    q = backoff_problem(p, 4.0, 0.25)
    # max a, certified end 4: the row asks -(a) <= -4 + 1, i.e. a >= 3
    row = q.linear.A.toarray()[0]
    assert row.tolist() == [-3.0, 1.0, 0.0] and q.linear.kinds[0] == "ge"


def test_backed_off_gains_are_certified_and_near_the_optimum():
    r = lmic.api.solve("sampled_euler.thm2", str(EXAMPLES / "sampled_euler.thm2.example.yaml"), backend="clarabel")
    assert r.verdict == "certified"
    b = r.backoff
    assert b is not None and b["verdict"] == "certified"
    upper = r.enclosure["upper"]
    assert r.enclosure["lower"] <= b["objective"] <= upper * (1 + 1e-3) + 1e-12
    assert b["norm_inf"] <= float(np.max(np.abs(r.solution.x))) * (1 + 1e-6)


def _hyperbola():
    """``min t`` subject to ``[[x, 1], [1, t]] > 0`` (``t > 1 / x``: an infimum 0, not attained)."""
    import scipy.sparse as sp

    from lmic.ir.problem import LMI

    coeffs = sp.csc_matrix(np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]))
    variables = [Variable("x", "scalar", (1, 1)), Variable("t", "scalar", (1, 1), offset=1)]
    lmis = [LMI("h", 2, coeffs, strict=True)]
    return Problem(variables, lmis, LinearConstraints.empty(2), Objective("min", [0.0, 0.0, 1.0]))


def test_given_point_when_the_backed_off_solve_gives_none(monkeypatch):
    """Near an infimum that is not attained the backed-off slice can be too thin for the solver
    (uio_dt.thm4_1: "backoff solve ended infeasible without a point"): the given point (the
    objective cuts' one, lmic.route_cut) is used when it is certified and within the bound, with
    the status of its own solve (what lmic audit certifies it with); otherwise nothing is."""
    import lmic.backoff as bo
    from lmic.solution import Solution

    p = _hyperbola()
    monkeypatch.setattr(bo, "solve_with_reductions", lambda *a, **k: Solution(status="infeasible"))
    monkeypatch.setattr(bo, "_largest_margin", lambda *a, **k: None)
    # value 0.01, rel 0.5: the bound is t <= 0.015
    ok = bo.backoff(p, 0.01, "clarabel", rel=0.5, fallback=[100.0, 0.0125])
    assert ok["verdict"] == "certified" and ok["method"] == "given point" and ok["status"] == "optimal"
    assert ok["objective"] == 0.0125 and ok["x"] == [100.0, 0.0125]
    outside = bo.backoff(p, 0.01, "clarabel", rel=0.5, fallback=[100.0, 0.02])  # t above the bound
    infeasible = bo.backoff(p, 0.01, "clarabel", rel=0.5, fallback=[10.0, 0.0125])  # t < 1 / x
    none = bo.backoff(p, 0.01, "clarabel", rel=0.5)
    for b in (outside, infeasible, none):
        assert b["verdict"] == "undecided" and b["x"] is None and "without a point" in b["reason"]


def test_backoff_is_recorded_and_a_tampered_point_is_rejected(tmp_path):
    system = str(EXAMPLES / "sampled_euler.thm2.example.yaml")
    r = lmic.api.solve("sampled_euler.thm2", system, backend="clarabel")
    path = tmp_path / "c.json"
    from lmic.system import load_system

    write_certificate(
        path, r.problem, r.solution, r.certificate, system=load_system(system), enclosure=r.enclosure, backoff=r.backoff
    )
    ok = audit_certificate(path)
    assert ok.ok and "backoff" in ok.checked, ok.message
    doc = json.loads(path.read_text())
    doc["backoff"]["x"] = [v * 1e3 for v in doc["backoff"]["x"]]
    path.write_text(json.dumps(doc))
    bad = audit_certificate(path)
    assert not bad.ok and bad.field == "backoff"
