"""Output details of issue #11 item 9: JSON params, LaTeX names, domains, help examples, ids."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from lmic.cli import COMMANDS, build_parser, main

ROOT = Path(__file__).resolve().parents[2]


def test_solve_json_params_hold_every_parameter_used(capsys):
    f = ROOT / "examples" / "qib.thm1.flexible-joint.yaml"
    assert main(["solve", "qib.thm1", str(f), "--json", "-p", "gamma=0"]) == 0
    params = json.loads(capsys.readouterr().out)["params"]
    assert params["beta"] == pytest.approx(0.00110889)  # from the file, not an override
    assert params["gamma"] == 0.0 and params["fixed_L"] == "0"  # override, and the option's default


def test_latex_keeps_eps1_as_epsilon_with_a_subscript(capsys):
    assert main(["show", "uncertain_dt.thm1", "--latex"]) == 0
    out = capsys.readouterr().out
    assert r"\varepsilon_{1}" in out and "eps_{1}" not in out


def test_domains_print_as_intervals(capsys):
    assert main(["show", "qib.cor1", "--json"]) == 0
    params = {p["name"]: p for p in json.loads(capsys.readouterr().out)["params"]}
    assert params["lambda"]["domain"] == "(0, inf)"
    assert main(["show", "qib.thm1", "--json"]) == 0
    params = {p["name"]: p for p in json.loads(capsys.readouterr().out)["params"]}
    assert params["beta"]["domain"] == "all reals" and "Interval" not in json.dumps(params)


def test_show_keeps_the_authors_term_order(capsys):
    assert main(["show", "qib.thm1"]) == 0
    out = capsys.readouterr().out
    assert "-P + (2*beta*omega)*I" in out  # (7) prints -P + 2 w beta I


def test_every_command_help_has_examples():
    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    assert set(sub.choices) >= {c.replace("_", "-") for c in COMMANDS} - {"audit-published"} | {"check"}
    for name, p in sub.choices.items():
        assert p.epilog and "examples:" in p.epilog and f"lmic {name}" in p.epilog, name


def test_theorem_ids_are_never_cut(capsys, monkeypatch):
    monkeypatch.setenv("COLUMNS", "60")
    assert main(["theorems"]) == 0
    out = capsys.readouterr().out
    for tid in ("obs_control.thm3_1", "thesis.thm4_1_2_linear", "uncertain_dt.lemma3"):
        assert tid in out
