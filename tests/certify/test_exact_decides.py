"""With ``exact=True`` the exact proof decides strict LMIs below the float threshold.

``data/uio_dt_near_supremum.json`` holds two points Clarabel returned on ``uio_dt.thm3_2``
(flexible joint) near gamma_max = 51.5: at gamma = 51 the strict LMI (20) has a relative float
margin ~2.8e-13, below ``strict_rel = 1e-12``, and is positive definite exactly at the float
point; at gamma = 51.5 ('inaccurate') it is indefinite and no mode may certify it.
"""

from __future__ import annotations

import json
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp
import yaml

from lmic.certify import certify
from lmic.certify.certificate import audit_certificate, read_certificate, write_certificate
from lmic.compile import compile_theorem
from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
from lmic.solution import Solution

ROOT = Path(__file__).resolve().parents[2]
DATA = Path(__file__).parent / "data" / "uio_dt_near_supremum.json"
UIO = {c["params"]["gamma"]: c for c in json.loads(DATA.read_text())["cases"]}


def _uio(gamma: float) -> tuple[Problem, Solution]:
    case = UIO[gamma]
    system = yaml.safe_load((ROOT / "examples" / case["system"]).read_text())
    prob = compile_theorem(case["theorem"], system, params=case["params"])
    x = np.asarray(case["x"])
    assert x.shape == (prob.n,), "the recorded point no longer fits the compiled IR"
    sol = Solution(
        case["status"],
        x=x,
        backend=case["backend"],
        native_status=case["native_status"],
        margin=case["margin"],
        strategy=case["strategy"],
    )
    return prob, sol


def _big() -> Problem:
    """diag(1e6, 1e-7 + 0 p) > 0: lambda_min = 1e-7 at a scale 1e6, relative 1e-13."""
    return Problem(
        [Variable("p", "scalar", (1, 1))],
        [LMI("big", 2, sp.csc_matrix(np.array([[1e6, 0.0], [0.0, 0.0], [1e-7, 0.0]])), strict=True)],
        LinearConstraints.empty(1),
        Objective("feasibility", np.zeros(2)),
    )


def test_exact_proof_certifies_below_the_float_threshold():
    prob, sol = _big(), Solution("optimal", x=np.array([0.0]))
    float_only = certify(prob, sol)
    assert float_only.verdict == "rejected" and "relative 1e-12" in float_only.reason
    cert = certify(prob, sol, exact=True)
    assert cert.verdict == "certified" and cert.label == "certified (exact)"
    e = cert.lmis[0]
    # both results are reported: the float margin (and its failed threshold) and the proof
    assert e["rel_margin"] == pytest.approx(1e-13) and e["threshold"] == pytest.approx(1e-6)
    assert e["float_ok"] is False and e["ok"] is True
    assert e["exact"] == "proved" and e["decided_by"] == "exact"
    assert "below the float threshold" in e["note"]
    assert "below the float threshold but proved exactly: 'big'" in cert.reason
    assert cert.exact["at_x"] and cert.exact["point"] == {"den": "1", "num": ["0"]}


def test_exact_mode_never_certifies_a_point_that_is_not_positive_definite():
    # p - 1 > 0 at p = 1: float lambda_min = 0, the exact proof disproves it
    prob = Problem(
        [Variable("p", "scalar", (1, 1))],
        [LMI("p - 1 > 0", 1, sp.csc_matrix([[-1.0, 1.0]]))],
        LinearConstraints.empty(1),
        Objective("feasibility", np.zeros(2)),
    )
    cert = certify(prob, Solution("optimal", x=np.array([1.0])), exact=True)
    assert cert.verdict == "rejected"
    assert cert.lmis[0]["exact"] == "disproved" and not cert.lmis[0]["ok"]


def test_exact_proof_does_not_override_failed_checks():
    # the LMI is proved exactly, but a theorem check (here a failing bound) still rejects
    from lmic.ir.problem import Check

    base = _big()
    prob = Problem(
        base.variables,
        base.lmis,
        base.linear,
        base.objective,
        checks=[Check("p < -1", "less_than", {"name": "p"}, -1.0)],
    )
    cert = certify(prob, Solution("optimal", x=np.array([0.0])), exact=True)
    assert cert.lmis[0]["ok"] and cert.lmis[0]["decided_by"] == "exact"
    assert cert.verdict == "rejected" and cert.reason.startswith("check 'p < -1' failed")


def test_uio_dt_near_the_supremum_is_certified_by_the_exact_proof():
    prob, sol = _uio(51.0)
    float_only = certify(prob, sol)
    assert float_only.verdict == "rejected"
    worst = min(float_only.lmis, key=lambda e: e["rel_margin"])
    assert 0 < worst["rel_margin"] < 1e-12 and worst["min_eig"] > 0
    cert = certify(prob, sol, exact=True)  # default tolerances: no strict_rel workaround
    assert cert.label == "certified (exact)", cert.reason
    assert cert.exact["at_x"]  # the certified rational point is the solver's float point
    den = int(cert.exact["point"]["den"])
    assert [Fraction(int(v), den) for v in cert.exact["point"]["num"]] == [Fraction(v) for v in sol.x]
    rescued = [e for e in cert.lmis if e["decided_by"] == "exact"]
    assert rescued and all(not e["float_ok"] and e["exact"] == "proved" for e in rescued)
    assert all(c["ok"] for c in cert.checks)


def test_uio_dt_inaccurate_point_at_the_supremum_stays_rejected():
    prob, sol = _uio(51.5)
    cert = certify(prob, sol, exact=True)
    assert cert.verdict == "rejected" and not cert.exact["proven"]


def test_audit_reruns_the_recorded_exact_proof_and_catches_a_forged_point(tmp_path):
    prob, sol = _uio(51.0)
    path = tmp_path / "uio.json"
    write_certificate(path, prob, sol, certify(prob, sol, exact=True))
    doc = read_certificate(path)  # the schema accepts the exact block and its point
    assert doc["certificate"]["exact"]["point"]["den"] == str(2 ** doc["certificate"]["exact"]["bits"])
    r = audit_certificate(path)  # no --exact: the recorded verdict rests on the proof, re-run it
    assert r.ok and r.exact and r.label == "certified (exact)", r.message
    assert "exact proof re-run: holds" in r.message
    doc["certificate"]["exact"]["point"]["num"][0] = str(int(doc["certificate"]["exact"]["point"]["num"][0]) + 1)
    path.write_text(json.dumps(doc))
    bad = audit_certificate(path)
    assert not bad.ok and bad.field == "certificate.exact.point.num[0]"
    doc["certificate"]["exact"]["point"]["num"][0] = str(int(doc["certificate"]["exact"]["point"]["num"][0]) - 1)
    doc["certificate"]["exact"] = None  # dropping the proof leaves a verdict the floats reject
    path.write_text(json.dumps(doc))
    dropped = audit_certificate(path)
    assert not dropped.ok and dropped.field.startswith("certificate.lmis[")


def test_audit_exact_on_a_float_record_reports_without_upgrading(tmp_path):
    prob, sol = _big(), Solution("optimal", x=np.array([0.0]))
    path = tmp_path / "big.json"
    write_certificate(path, prob, sol, certify(prob, sol))
    r = audit_certificate(path, exact=True)
    assert r.ok and r.verdict == "rejected" and r.recorded_verdict == "rejected"
    assert "with it the verdict would be certified (exact); re-certify with --exact" in r.message
