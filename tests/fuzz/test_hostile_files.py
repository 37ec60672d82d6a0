"""Hostile input files: every reader answers one line on stderr, exit code 2, nothing written.

The cases are the findings of the adversarial campaign (#12 section 2, #17 item 7): numbers
too large for a float or with 5000 digits, NaN horizons, deep nesting, YAML alias bombs,
declared sizes far beyond the data or memory, regexes fed a long digit run and garbage,
duplicate keys, ``lmic: true`` and Unicode digits. Each runs through the real command line
(in-process for speed; the bombs also in a subprocess under a memory and time limit).
"""

from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
from pathlib import Path

import pytest

from lmic.cli import main

ROOT = Path(__file__).resolve().parents[2]
QIB = (ROOT / "examples" / "qib.thm1.flexible-joint.yaml").read_text()

GOOD_DATA = "data:\n  A: [[0.5, 0.1], [0.0, 0.4]]\n  C: [[1.0, 0.0]]\n"


def _bomb(levels: int = 9) -> str:
    text = "lmic: 1\na: &a [x, x, x, x, x, x, x, x, x, x]\n"
    names = "abcdefghijklmnop"
    for p, c in zip(names[: levels - 1], names[1:levels], strict=True):
        text += f"{c}: &{c} [" + ", ".join([f"*{p}"] * 10) + "]\n"
    return text + GOOD_DATA


SYSTEM_FILES = {
    "huge-int-in-data.yaml": "lmic: 1\ndata:\n  A: [[" + "9" * 400 + "]]\n",
    "int-beyond-float.yaml": "lmic: 1\ndata:\n  A: [[" + "9" * 308 + "9" + "]]\n",
    "huge-int-param.yaml": "lmic: 1\n" + GOOD_DATA + "params: {beta: " + "1" * 5000 + "}\n",
    "float-overflow.yaml": "lmic: 1\ndata:\n  A: [[1.0e999]]\n",
    "deep-flow.yaml": "lmic: 1\ndata:\n  A: " + "[" * 5000 + "1" + "]" * 5000 + "\n",
    "deep-block.yaml": "lmic: 1\nx:\n" + "".join("  " * i + "- \n" for i in range(1, 300)),
    "alias-bomb.yaml": _bomb(),
    "duplicate-key.yaml": "lmic: 1\n" + GOOD_DATA + "data:\n  A: [[1.0]]\n",
    "lmic-true.yaml": "lmic: true\n" + GOOD_DATA,
    "unicode-digits.yaml": "lmic: 1\ndata:\n  A: [['١٢']]\n  C: [[1.0, 0.0]]\n",
    "deep.json": '{"lmic": 1, "data": {"A": ' + "[" * 100000 + "]" * 100000 + "}}",
    "huge-int.json": '{"lmic": 1, "data": {"A": [[' + "7" * 5000 + "]]}}",
    "nan.json": '{"lmic": 1, "data": {"A": [[NaN]]}}',
    "dup.json": '{"lmic": 1, "lmic": 1, "data": {"A": [[1.0]]}}',
    "binary.yaml": "\udcff",
}

SIM_CASES = {
    "horizon-nan": "  horizon: .nan\n",
    "dt-nan": "  horizon: 2\n  dt: .nan\n",
    "horizon-huge": "  horizon: " + "9" * 300 + "\n",
    "horizon-5000": "  horizon: " + "9" * 5000 + "\n",
    "x0-huge": None,  # replaced below
    "sampling-nan": "  horizon: 2\n  sampling: {max: .nan}\n",
    "noise-inf": "  horizon: 2\n  noise: {std: .inf}\n",
    "bad-key": "  horizon: 2\n  nonlinearity: {1: x1}\n",
}


def _sim(case: str) -> str:
    head = "simulation:\n  nonlinearity: ['0', '2.16*u', '0', '-0.0333*sin(x3)']\n  input: 'sin(t)'\n"
    if case == "x0-huge":
        return QIB.split("simulation:")[0] + head + "  x0: [1e308, 1e308, 1e309, 0]\n  horizon: 2\n"
    if case == "bad-key":
        return QIB.split("simulation:")[0] + "simulation:\n  nonlinearity: {1: x1}\n  x0: [1, 0, 0, 0]\n  horizon: 2\n"
    return QIB.split("simulation:")[0] + head + "  x0: [1, 0.5, 1, -0.5]\n" + SIM_CASES[case]


SDPA_FILES = {
    "block-50000.dat-s": "1\n1\n50000\n1.0\n1 1 1 1 1.0\n",
    "block-negative.dat-s": "1\n1\n-1000000000\n1.0\n1 1 1 1 1.0\n",
    "block-2-63.dat-s": "1\n1\n9223372036854775808\n1.0\n1 1 1 1 1.0\n",
    "m-huge.dat-s": "1" * 5000 + "\n1\n1\n1.0\n",
    "value-5000.dat-s": "1\n1\n2\n1.0\n1 1 1 1 " + "1" * 5000 + "\n",
    "index-5000.dat-s": "1\n1\n2\n1.0\n1 1 " + "1" * 5000 + " 1 1.0\n",
    "digits-garbage.dat-s": "1\n1\n2\n1.0\n1 1 1 1 " + "1" * 200000 + "x\n",
    "comment-int.dat-s": '* lmic: {"c0": ' + "9" * 5000 + "}\n1\n1\n1\n1.0\n",
    "comment-deep.dat-s": "* lmic: " + "[" * 100000 + "\n1\n1\n1\n1.0\n",
}


def _ir(**change) -> str:
    d = {
        "lmic_ir": 1,
        "variables": [{"name": "t", "kind": "scalar", "shape": [1, 1], "offset": 0}],
        "lmis": [{"name": "t > 0", "dim": 1, "strict": True, "coeffs": {"row": [0], "col": [1], "val": [1.0]}}],
        "linear": {"row": [], "col": [], "val": [], "kinds": [], "strict": [], "names": []},
        "objective": {"sense": "feasibility", "c": {"idx": [], "val": []}},
    }
    for key, value in change.items():
        d[key] = value
    return json.dumps(d)


IR_FILES = {
    "dim-huge.json": _ir(
        lmis=[{"name": "big", "dim": 10**9, "strict": True, "coeffs": {"row": [0], "col": [1], "val": [1.0]}}]
    ),
    "dim-50000.json": _ir(
        lmis=[{"name": "big", "dim": 50000, "strict": True, "coeffs": {"row": [0], "col": [1], "val": [1.0]}}]
    ),
    "shape-huge.json": _ir(variables=[{"name": "X", "kind": "full", "shape": [10**6, 10**6], "offset": 0}]),
    "shape-negative.json": _ir(variables=[{"name": "X", "kind": "full", "shape": [-5, 1], "offset": 0}]),
    "int-5000.json": _ir().replace('"offset": 0', '"offset": ' + "1" * 5000),
    "deep.json": _ir().replace('"lmic_ir": 1', '"x": ' + "[" * 100000 + "]" * 100000 + ', "lmic_ir": 1'),
}


def _check_one_line(code: int, err: str, out_dir: Path, before: set[str]) -> None:
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert code == 2, err
    assert len(lines) == 1 and lines[0].startswith("lmic: error:"), err
    assert "Traceback" not in err
    assert len(lines[0]) < 400
    assert set(os.listdir(out_dir)) == before  # nothing written


def _run(tmp_path: Path, name: str, text: str, argv_of, capsys) -> None:
    path = tmp_path / name
    if text == "\udcff":
        path.write_bytes(b"lmic: 1\n\xff\xfe\n")
    else:
        path.write_text(text, encoding="utf-8")
    before = set(os.listdir(tmp_path))
    out = tmp_path / "out.json"
    code = main(argv_of(path, out))
    _check_one_line(code, capsys.readouterr().err, tmp_path, before)


@pytest.mark.parametrize("name", sorted(SYSTEM_FILES))
def test_hostile_system_file(name, tmp_path, capsys):
    _run(tmp_path, name, SYSTEM_FILES[name], lambda p, o: ["solve", "qib.thm1", str(p), "-o", str(o)], capsys)


@pytest.mark.parametrize("case", sorted(SIM_CASES))
def test_hostile_simulation_section(case, tmp_path, capsys):
    _run(tmp_path, "sim.yaml", _sim(case), lambda p, o: ["simulate", "qib.thm1", str(p), "-o", str(o) + ".png"], capsys)


@pytest.mark.parametrize("name", sorted(SDPA_FILES))
def test_hostile_sdpa_file(name, tmp_path, capsys):
    _run(tmp_path, name, SDPA_FILES[name], lambda p, o: ["solve", str(p), "-o", str(o)], capsys)


@pytest.mark.parametrize("name", sorted(IR_FILES))
def test_hostile_ir_file(name, tmp_path, capsys):
    _run(tmp_path, name, IR_FILES[name], lambda p, o: ["solve", str(p), "-o", str(o)], capsys)


CERT_FILES = {
    "deep.json": '{"lmic_certificate": 1, "x": ' + "[" * 100000 + "]" * 100000 + "}",
    "huge-int.json": '{"lmic_certificate": ' + "1" * 5000 + "}",
    "nan.json": '{"lmic_certificate": 1, "created": NaN}',
    "overflow.json": '{"lmic_certificate": 1, "created": 1e999}',  # found by benchmarks/fuzz.py
    "not-utf8.json": "\udcff",
}


@pytest.mark.parametrize("name", sorted(CERT_FILES))
def test_hostile_certificate_file(name, tmp_path, capsys):
    _run(tmp_path, name, CERT_FILES[name], lambda p, o: ["audit", str(p)], capsys)


def _limited() -> None:  # in the child: 4 GB of address space, 60 s of CPU
    resource.setrlimit(resource.RLIMIT_AS, (4 * 2**30, 4 * 2**30))
    resource.setrlimit(resource.RLIMIT_CPU, (60, 60))


@pytest.mark.parametrize(
    ("name", "text", "args"),
    [
        ("bomb.yaml", _bomb(12), ["solve", "qib.thm1"]),
        ("block.dat-s", SDPA_FILES["block-50000.dat-s"], ["solve"]),
        ("neg.dat-s", SDPA_FILES["block-negative.dat-s"], ["solve"]),
    ],
)
def test_bombs_in_a_subprocess_under_limits(name, text, args, tmp_path):
    path = tmp_path / name
    path.write_text(text)
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), str(ROOT / "plugins")]))
    proc = subprocess.run(
        [sys.executable, "-m", "lmic.cli", *args, str(path)],
        capture_output=True,
        text=True,
        timeout=120,
        preexec_fn=_limited,
        env=env,
    )
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.count("\n") == 1 and "Traceback" not in proc.stderr
