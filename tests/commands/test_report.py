"""``lmic report``: writes one self-contained page atomically; exit code follows the certificate;
bad input is one line, exit 2, nothing written."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from lmic.cli import main

ROOT = Path(__file__).resolve().parents[2]

SMALL = {
    "lmic": 1,
    "data": {"A": [[0.9, 0.2], [-0.1, 0.95]], "C": [[1.0, 0.0]]},
    "params": {"beta": 0.001},
    "simulation": {"x0": [1.0, -1.0], "horizon": 10, "input": "sin(t)", "nonlinearity": ["0", "0.02*sin(x1)"]},
}


def write(tmp_path: Path, system: dict) -> Path:
    path = tmp_path / "sys.yaml"
    path.write_text(yaml.safe_dump(system))
    return path


def test_report_writes_the_page(tmp_path, capsys):
    out = tmp_path / "r.html"
    code = main(["report", "qib.thm1", str(write(tmp_path, SMALL)), "-o", str(out), "--backends", "clarabel"])
    assert code == 0
    text = capsys.readouterr().out
    assert "crosscheck 1 backends, agree" in text and "(decayed)" in text and f"wrote      {out}" in text
    page = out.read_text()
    assert page.startswith("<!DOCTYPE html>") and 'id="simulation-plot"' in page
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.html", "sys.yaml"]


def test_report_of_an_uncertified_result_is_written_with_its_exit_code(tmp_path, capsys):
    out = tmp_path / "r.html"
    args = ["report", "qib.thm1", str(write(tmp_path, SMALL)), "-o", str(out), "-p", "beta=50", "--no-crosscheck"]
    # beta = 50: LMI (7)'s diagonal blocks need P > 100 w I and P < 2 w I (w > 0), infeasible for
    # any data; the LMI is homogeneous, so the Farkas ray proves it globally: exit code 3
    assert main(args) == 3
    assert "No certified gains" in capsys.readouterr().out
    page = out.read_text()
    assert "No certified gains" in page and "verdict infeasible-certified" in page


def test_report_of_a_shipped_example(tmp_path):
    out = tmp_path / "r.html"
    example = ROOT / "examples" / "thesis.cor3_19.ex3_2_2.yaml"
    assert main(["report", "thesis.cor3_19", str(example), "-o", str(out), "--no-crosscheck"]) == 0
    page = out.read_text()
    assert "Matrix-Lipschitz observer" in page and 'id="simulation-plot"' in page


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (["--backends", "nosuch"], "nosuch"),
        (["--backend", "nosuch"], "nosuch"),
        (["-p", "beta"], "write parameters as name=value"),
    ],
)
def test_bad_options(tmp_path, capsys, args, fragment):
    out = tmp_path / "r.html"
    assert main(["report", "qib.thm1", str(write(tmp_path, SMALL)), "-o", str(out), *args]) == 2
    err = capsys.readouterr().err
    assert err.startswith("lmic: error: ") and fragment in err and err.count("\n") == 1
    assert not out.exists()


def test_bad_input_writes_nothing(tmp_path, capsys):
    out = tmp_path / "r.html"
    bad = dict(SMALL, simulation={"x0": [1, 0], "horizon": 1, "nonlinearity": ["0", "exec(1)"]})
    assert main(["report", "qib.thm1", str(write(tmp_path, bad)), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "simulation.nonlinearity[2]: unknown function 'exec' at column 1" in err
    assert not out.exists()
    assert main(["report", "qib.thm1", str(tmp_path / "none.yaml"), "-o", str(out)]) == 2
    assert "none.yaml: no such file" in capsys.readouterr().err
    assert main(["report", "qib.thm1", str(write(tmp_path, SMALL)), "-o", str(tmp_path / "x" / "r.html")]) == 2
    assert "does not exist" in capsys.readouterr().err
    with pytest.raises(SystemExit) as info:
        main(["report", "qib.thm1", str(write(tmp_path, SMALL))])  # -o is required
    assert info.value.code == 2
