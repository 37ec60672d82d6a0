"""Solver options on the command line: negative, zero, NaN or infinite values are bad input (exit 2)."""

from __future__ import annotations

from pathlib import Path

import pytest

from lmic.cli import main

SYSTEM = str(Path(__file__).resolve().parents[2] / "examples" / "qib.thm1.flexible-joint.yaml")


@pytest.mark.parametrize(
    ("option", "value"),
    [
        ("--time-limit", "-1"),
        ("--time-limit", "0"),
        ("--time-limit", "nan"),
        ("--time-limit", "inf"),
        ("--tol", "-1e-8"),
        ("--tol", "nan"),
        ("--max-iter", "-3"),
        ("--max-iter", "0"),
        ("--margin", "-0.5"),
        ("--margin", "nan"),
    ],
)
def test_bad_solver_option_is_one_line_exit_2(option, value, capsys):
    assert main(["solve", "qib.thm1", SYSTEM, f"{option}={value}"]) == 2  # SolveOptions (lmic.options)
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("lmic: error:")


def test_bad_audit_tolerance_is_exit_2(capsys, tmp_path):
    for bad in ("rel=-1", "rel=nan", "nope=1", "rel"):
        assert main(["audit", str(tmp_path / "c.json"), "--tol", bad]) == 2
        assert capsys.readouterr().err.startswith("lmic: error: --tol")
