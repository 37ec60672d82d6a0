"""``lmic simulate``: the four shipped examples decay, the figure is written atomically, and bad
input is one line with exit code 2 and nothing written."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import yaml

from lmic.cli import main

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"

SMALL = {
    "lmic": 1,
    "name": "two-state DT plant",
    "data": {"A": [[0.9, 0.2], [-0.1, 0.95]], "C": [[1.0, 0.0]]},
    "params": {"beta": 0.001},
    "simulation": {
        "nonlinearity": ["0", "0.03*sin(x1)"],
        "input": "sin(t)",
        "x0": [1.0, -1.0],
        "horizon": 20,
        "dt": 0.5,
    },
}


def write(tmp_path: Path, system: dict, name: str = "sys.yaml") -> Path:
    path = tmp_path / name
    path.write_text(yaml.safe_dump(system))
    return path


def test_simulate_prints_the_final_error_and_writes_the_figure(tmp_path, capsys):
    png = tmp_path / "fig.png"
    assert main(["simulate", "qib.thm1", str(write(tmp_path, SMALL)), "-o", str(png)]) == 0
    out = capsys.readouterr().out
    assert "luenberger (discrete time)" in out and "(decayed)" in out and f"wrote      {png}" in out
    assert png.read_bytes().startswith(b"\x89PNG")
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []  # no temporary left


def test_simulate_json(tmp_path, capsys):
    assert main(["simulate", "qib.thm1", str(write(tmp_path, SMALL)), "--json", "-p", "beta=0.002"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["verdict"] == "certified" and d["observer"]["model"] == "luenberger"
    sim = d["simulation"]
    assert sim["decayed"] and sim["final_error"] < 1e-3 * sim["initial_error"] and sim["points"] == 41
    assert d["plot"] is None


@pytest.mark.parametrize(
    ("theorem", "example", "model", "bound"),
    [
        ("qib.thm1", "qib.thm1.flexible-joint.yaml", "luenberger", 1e-4),
        ("thesis.cor3_19", "thesis.cor3_19.ex3_2_2.yaml", "luenberger", 1e-3),
        ("uio_dt.thm3_2", "uio_dt.thm3_2.flexible_joint.yaml", "uio", 1e-9),
        ("nonuniform.thm1", "nonuniform.thm1.flexible-arm.yaml", "sampled", 1e-3),
    ],
)
def test_shipped_examples_decay(theorem, example, model, bound, capsys):
    assert main(["simulate", theorem, str(EXAMPLES / example), "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["observer"]["model"] == model
    assert d["simulation"]["decayed"], d["simulation"]
    assert d["simulation"]["final_error"] < bound


def _expect_usage_error(args, capsys, *fragments):
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err.startswith("lmic: error: ") and err.count("\n") == 1, err
    for fragment in fragments:
        assert fragment in err, err
    return err


@pytest.mark.parametrize(
    ("change", "fragments"),
    [
        (lambda s: s.pop("simulation"), ["sys.yaml: has no 'simulation:' section"]),
        (lambda s: s["simulation"].update(seed=3), ["sys.yaml: simulation: unknown key 'seed'"]),
        (
            lambda s: s["simulation"].update(nonlinearity=["0", "__import__('os').system('x')"]),
            ["simulation.nonlinearity[2]: unknown function '__import__' at column 1"],
        ),
        (
            lambda s: s["simulation"].update(nonlinearity=["0", "1 + os"]),
            ["simulation.nonlinearity[2]: unknown name 'os' at column 5"],
        ),
        (lambda s: s["simulation"].update(x0=[1.0]), ["simulation.x0: has 1 entries, expected 2"]),
        (lambda s: s["simulation"].update(horizon="long"), ["simulation.horizon: 'long' is not of type 'number'"]),
        (
            lambda s: s["simulation"].update(nonlinearity=["0", "x2**3"], x0=[1.0, 10.0]),
            ["the plant state blew up at t = ", "sys.yaml: simulation"],
        ),
    ],
)
def test_bad_input_is_one_line_and_nothing_is_written(tmp_path, capsys, change, fragments):
    system = json.loads(json.dumps(SMALL))
    change(system)
    png = tmp_path / "fig.png"
    _expect_usage_error(["simulate", "qib.thm1", str(write(tmp_path, system)), "-o", str(png)], capsys, *fragments)
    assert not png.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sys.yaml"]


def test_other_bad_input(tmp_path, capsys):
    good = str(write(tmp_path, SMALL))
    _expect_usage_error(["simulate", "qib.thm1", str(tmp_path / "missing.yaml")], capsys, "missing.yaml: no such file")
    _expect_usage_error(["simulate", "qib.thm1", good, "-o", str(tmp_path / "no" / "f.png")], capsys, "does not exist")
    _expect_usage_error(["simulate", "no.such", good], capsys, "no.such")
    lyap = {"lmic": 1, "data": {"A": [[-1.0, 0.0], [0.0, -2.0]]}, "simulation": {"x0": [1, 1], "horizon": 1}}
    _expect_usage_error(
        ["simulate", "thesis.lyapunov", str(write(tmp_path, lyap, "l.yaml"))], capsys, "declares no observer"
    )
    bad = tmp_path / "bad.yaml"
    bad.write_text("lmic: 1\ndata: {A: [[1]]\n")
    _expect_usage_error(["simulate", "qib.thm1", str(bad)], capsys, "bad.yaml: malformed YAML")


def test_uncertified_gains_are_not_simulated(tmp_path, capsys):
    png = tmp_path / "fig.png"
    code = main(["simulate", "qib.thm1", str(write(tmp_path, SMALL)), "-p", "beta=50", "-o", str(png)])
    # LMI (7) with beta = 50 is infeasible whatever the data: its diagonal blocks need
    # P > 2 w beta I = 100 w I and P < 2 w I with w > 0. The LMI is homogeneous in (P, R, omega),
    # so the verified Farkas ray is a global proof: infeasible-certified, exit code 3.
    assert code == 3
    err = capsys.readouterr().err
    assert "verdict infeasible-certified" in err and "nothing simulated" in err
    assert not png.exists()
