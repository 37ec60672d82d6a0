"""``lmic audit``: exit codes 0 / 1 / 2 / 3, the table and the JSON output."""

from __future__ import annotations

import json

import numpy as np
import pytest
import scipy.sparse as sp

from lmic.certify import certify, write_certificate
from lmic.cli import main
from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
from lmic.solution import Solution


def _problem() -> Problem:
    # p > 0 and 2 - p > 0
    return Problem(
        [Variable("p", "scalar", (1, 1))],
        [LMI("p > 0", 1, sp.csc_matrix([[0.0, 1.0]])), LMI("2 - p > 0", 1, sp.csc_matrix([[2.0, -1.0]]))],
        LinearConstraints.empty(1),
        Objective("feasibility", np.zeros(2)),
    )


def _write(tmp_path, sol: Solution, name: str = "c.json"):
    prob = _problem()
    path = tmp_path / name
    write_certificate(path, prob, sol, certify(prob, sol))
    return path


def test_consistent_certified_exits_0(tmp_path, capsys):
    path = _write(tmp_path, Solution("optimal", x=np.array([1.0]), backend="clarabel"))
    assert main(["audit", str(path), "--exact"]) == 0
    out = capsys.readouterr().out
    assert "consistent" in out and "certified (exact)" in out and "2 - p > 0" in out


def test_tampered_exits_1_and_names_the_field(tmp_path, capsys):
    path = _write(tmp_path, Solution("optimal", x=np.array([1.0])))
    doc = json.loads(path.read_text())
    doc["certificate"]["lmis"][0]["min_eig"] = 5.0
    path.write_text(json.dumps(doc))
    assert main(["audit", str(path), "--json"]) == 1
    out = json.loads(capsys.readouterr().out)
    assert out["ok"] is False and out["verdict"] == "rejected"
    assert out["field"] == "certificate.lmis[0].min_eig"
    assert out["exit_code"] == 1


def test_faithful_record_of_a_rejected_point_exits_1(tmp_path, capsys):
    path = _write(tmp_path, Solution("optimal", x=np.array([3.0])))
    assert main(["audit", str(path), "--json"]) == 1
    out = json.loads(capsys.readouterr().out)
    assert out["ok"] is True and out["recorded_verdict"] == "rejected"


def test_infeasible_certified_exits_3(tmp_path, capsys):
    # p > 0 and -p > 0: Z = (1, 1) is a strict Farkas certificate
    prob = Problem(
        [Variable("p", "scalar", (1, 1))],
        [LMI("p > 0", 1, sp.csc_matrix([[0.0, 1.0]])), LMI("-p > 0", 1, sp.csc_matrix([[0.0, -1.0]]))],
        LinearConstraints.empty(1),
        Objective("feasibility", np.zeros(2)),
    )
    sol = Solution("infeasible", farkas={"lmis": [np.eye(1), np.eye(1)], "linear": []})
    path = tmp_path / "inf.json"
    write_certificate(path, prob, sol, certify(prob, sol, exact=True))
    assert main(["audit", str(path)]) == 3
    assert "infeasible-certified" in capsys.readouterr().out
    # checked in floating point only: a scale-free problem's ray bounds the relative margin
    write_certificate(path, prob, sol, certify(prob, sol))
    assert main(["audit", str(path)]) == 4
    assert "infeasible-bounded" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("content", "needle"),
    [
        ('{"lmic_certificate": 1, "lm', "not valid JSON"),
        ('{"lmic_certificate": 7}', "unknown certificate schema version 7"),
    ],
)
def test_bad_files_exit_2_with_one_line(tmp_path, capsys, content, needle):
    path = tmp_path / "bad.json"
    path.write_text(content)
    assert main(["audit", str(path)]) == 2
    err = capsys.readouterr().err
    assert needle in err and err.count("\n") == 1 and err.startswith("lmic: error: ")


def test_missing_file_exits_2(tmp_path, capsys):
    assert main(["audit", str(tmp_path / "nope.json")]) == 2
    assert "no such certificate file" in capsys.readouterr().err


def test_exact_decision_is_shown(tmp_path, capsys):
    # diag(1e6, 1e-7) > 0: relative margin 1e-13, below the float threshold, proved exactly
    prob = Problem(
        [Variable("p", "scalar", (1, 1))],
        [LMI("M > 0", 2, sp.csc_matrix(np.array([[1e6, 0.0], [0.0, 0.0], [1e-7, 0.0]])))],
        LinearConstraints.empty(1),
        Objective("feasibility", np.zeros(2)),
    )
    sol = Solution("optimal", x=np.array([0.0]))
    path = tmp_path / "exact.json"
    write_certificate(path, prob, sol, certify(prob, sol, exact=True))
    assert main(["audit", str(path)]) == 0  # the recorded proof is re-run without --exact
    out = capsys.readouterr().out
    assert "consistent: certified (exact)" in out
    assert "below" in out and "proved" in out  # the table's float and exact columns (may wrap)
    assert main(["audit", str(path), "--json"]) == 0
    js = json.loads(capsys.readouterr().out)
    assert js["label"] == "certified (exact)" and js["certificate"]["lmis"][0]["decided_by"] == "exact"


def test_a_theorem_not_installed_names_the_distribution_to_install(tmp_path, capsys, monkeypatch):
    from pathlib import Path

    import lmic.registry
    from lmic.errors import LmicError

    example = Path(__file__).resolve().parents[2] / "examples" / "qib.thm1.flexible-joint.yaml"
    cert = tmp_path / "qib.json"
    assert main(["solve", "qib.thm1", str(example), "-o", str(cert)]) == 0
    capsys.readouterr()
    provider = json.loads(cert.read_text())["theorem"]["provider"]

    def missing(tid):
        raise LmicError(f"unknown theorem '{tid}'")

    monkeypatch.setattr(lmic.registry, "get_theorem", missing)  # as on a machine without the plugin
    assert main(["audit", str(cert)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "theorem 'qib.thm1' is not installed here" in err[0]
    assert f"pip install {provider['distribution']}=={provider['version']}" in err[0]
