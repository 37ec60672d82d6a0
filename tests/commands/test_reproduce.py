"""lmic reproduce: a subset run, the Markdown file, JSON and exit codes."""

from __future__ import annotations

import json
from pathlib import Path

import yaml

from lmic.cli import main

ROOT = Path(__file__).resolve().parents[2]
EX = ROOT / "examples"


def test_subset_writes_markdown_and_exits_0(tmp_path, capsys):
    out = tmp_path / "reproduction.md"
    args = ["reproduce", "--examples", str(EX), "--only", "thesis.cor3_19.*", "--only", "qib.cor2.*", "-o", str(out)]
    assert main(args) == 0
    text = capsys.readouterr().out
    assert "rows agree" in text and f"wrote {out}" in text
    md = out.read_text()
    assert "### `thesis.cor3_19.ex3_2_2.yaml`" in md and "### `qib.cor2.flexible-joint.yaml`" in md
    assert "lambda_max -0.255165" in md and "| yes |" in md and "| **no** |" not in md


def test_json_and_a_failing_expectation_exit_1(tmp_path, capsys):
    spec = {
        "examples": {
            "qib.cor2.flexible-joint.yaml": [
                {
                    "quantity": "feasibility",
                    "compute": {"solve": {}},
                    "verdict": "certified",
                    "catalogue": "S6 line 493",
                }
            ]
        }
    }
    f = tmp_path / "r.yaml"
    f.write_text(yaml.safe_dump(spec))
    assert main(["reproduce", "--examples", str(EX), "--expectations", str(f), "--only", "qib.cor2.*", "--json"]) == 1
    d = json.loads(capsys.readouterr().out)
    row = d["rows"][0]
    assert row["finding"] == "infeasible" and row["expected_verdict"] == "certified" and not row["ok"]
    assert d["agree"] == 0 and d["disagree"] == 1 and d["exit_code"] == 1


def test_bad_expectations_exit_2(tmp_path, capsys):
    f = tmp_path / "r.yaml"
    f.write_text("examples: [1, 2]\n")
    assert main(["reproduce", "--examples", str(EX), "--expectations", str(f)]) == 2
    assert "'examples' section" in capsys.readouterr().err
    assert main(["reproduce", "--examples", str(tmp_path / "none")]) == 2
