"""lmic theorems / show / compile: output, JSON and exit codes."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from lmic.cli import main

ROOT = Path(__file__).resolve().parents[2]
QIB = {"lmic": 1, "data": {"A": [[0.5, 0.1], [0.0, 0.4]], "C": [[1.0, 0.0]]}, "params": {"beta": 0.01}}


@pytest.fixture
def qib_file(tmp_path):
    f = tmp_path / "qib.json"
    f.write_text(json.dumps(QIB))
    return f


def test_theorems_json_lists_ids_and_citations(capsys):
    assert main(["theorems", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    ids = {t["id"]: t for t in out["theorems"]}
    assert "Wang, Song & Zhang" in ids["qib.thm1"]["citation"]
    assert out["broken_plugins"] == []


def test_show_prints_lmis_like_the_paper(capsys):
    assert main(["show", "qib.thm1"]) == 0
    out = capsys.readouterr().out
    assert "A.T*P - C.T*R" in out and "*" in out and "L = P**(-1)*R.T" in out


def test_show_latex_and_json(capsys):
    assert main(["show", "qib.thm1", "--latex"]) == 0
    latex = capsys.readouterr().out
    assert r"\begin{bmatrix}" in latex and r"\star" in latex and r"\prec 0" in latex
    assert main(["show", "thesis.lyapunov", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["variables"] == [{"name": "P", "kind": "symmetric", "shape": "n x n", "sign": "free"}]
    assert [o["name"] for o in d["options"]] == ["nonstrict"]


def test_compile_writes_an_ir_file(qib_file, tmp_path):
    out = tmp_path / "ir.json"
    assert main(["compile", "qib.thm1", str(qib_file), "-p", "beta=0.02", "-o", str(out)]) == 0
    ir = json.loads(out.read_text())
    assert ir["meta"]["theorem"] == "qib.thm1"
    assert ir["meta"]["params"]["beta"] == 0.02
    assert [lmi["name"] for lmi in ir["lmis"]] == ["P > 0", "(7)"]


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["show", "nope.thm"], "unknown theorem 'nope.thm'"),
        (["compile", "qib.thm1", "missing.yaml", "-o", "x.json"], "missing.yaml: no such file"),
        (["compile", "qib.thm1", "{sys}", "-p", "beta", "-o", "{out}"], "write parameters as name=value"),
        (["compile", "qib.thm1", "{sys}", "-p", "gamma=nan", "-o", "{out}"], "not a finite number"),
        (["compile", "qib.thm1", "{sys}", "-p", "zeta=1", "-o", "{out}"], "unknown parameter 'zeta'"),
        (["frobnicate"], "invalid choice"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(args, message, qib_file, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "ir.json"
    args = [a.format(sys=qib_file, out=out) for a in args]
    try:
        rc = main(args)
    except SystemExit as exc:  # argparse usage errors
        rc = exc.code
    assert rc == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], lines
    assert not out.exists()  # nothing half-written


def test_errors_in_a_real_process_have_no_traceback(tmp_path):
    proc = subprocess.run(
        [sys.executable, "-m", "lmic.cli", "compile", "qib.thm1", "nope.yaml", "-o", "x.json"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    assert proc.returncode == 2
    assert proc.stderr.strip() == "lmic: error: nope.yaml: no such file"
    assert not (tmp_path / "x.json").exists()


def test_version_flag(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    assert capsys.readouterr().out.startswith("lmic ")
