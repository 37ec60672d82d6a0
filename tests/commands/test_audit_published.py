"""lmic audit-published: output, JSON and exit codes 0 / 1 / 3 / 2."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml

from lmic.cli import main

ROOT = Path(__file__).resolve().parents[2]
EX = ROOT / "examples"


def test_certified_point_and_gain_exit_0(capsys):
    assert main(["audit-published", "qib.thm1", str(EX / "qib.thm1.flexible-joint.yaml")]) == 0
    out = capsys.readouterr().out
    assert "P, R, omega" in out and "certified" in out and "lambda_max -0.05581" in out
    assert "fixed_L = 1" in out and "exit 0" in out


def test_json_infeasible_published_point_exit_3(capsys):
    f = str(EX / "uncertain_dt.thm1.example.yaml")
    assert main(["audit-published", "uncertain_dt.thm1", f, "--json"]) == 3
    d = json.loads(capsys.readouterr().out)
    assert d["theorem"] == "uncertain_dt.thm1" and d["exit_code"] == 3
    kinds = {c["kind"]: c for c in d["claims"]}
    assert kinds["partial point"]["finding"] == "infeasible" and kinds["partial point"]["agrees"] is False
    assert kinds["gain"]["derived"]["gamma_star"] == pytest.approx(0.3428, abs=2e-3)  # S6 line 480
    assert kinds["value"]["published"] == 0.4339 and kinds["value"]["computed"] == pytest.approx(0.3405, abs=2e-3)


def test_rejected_point_exit_1(tmp_path, capsys):
    raw = yaml.safe_load((EX / "thesis.cor3_19.ex3_2_2.yaml").read_text())
    raw["published"]["L"] = (np.array(raw["published"]["L"]) * 0.2).tolist()  # a wrong gain
    f = tmp_path / "cor.yaml"
    f.write_text(yaml.safe_dump(raw))
    assert main(["audit-published", "thesis.cor3_19", str(f), "--json"]) == 1
    claim = json.loads(capsys.readouterr().out)["claims"][0]
    assert claim["kind"] == "point" and claim["finding"] == "rejected" and claim["margin"] < 0


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["qib.cor1", "qib.cor1.flexible-joint.yaml"], "no 'published:' section"),
        (["qib.nope", "qib.thm1.flexible-joint.yaml"], "qib.nope"),
        (["qib.thm1", "missing.yaml"], "no such file"),
        (["qib.thm1", "qib.thm1.flexible-joint.yaml", "-p", "beta=-"], "beta"),
    ],
)
def test_bad_input_exit_2(args, message, capsys):
    theorem, file, *rest = args
    assert main(["audit-published", theorem, str(EX / file), *rest]) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
