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


def test_uio_flexible_joint_backoff_gives_certified_gains_below_1e4():
    r = lmic.api.solve("uio_dt.thm4_1", str(EXAMPLES / "uio_dt.thm4_1.flexible_joint.yaml"), backend="clarabel")
    b = r.backoff
    assert b["verdict"] == "certified"
    for name in ("K", "L", "E", "N", "G"):
        assert np.linalg.norm(np.atleast_2d(np.asarray(b["derived"][name], dtype=float)), 2) < 1e4


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
