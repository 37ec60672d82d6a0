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


def _one_error_line(capsys, *fragments: str) -> None:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("lmic: error:"), err
    for fragment in fragments:
        assert fragment in err, err


@pytest.mark.parametrize("command", ["show", "check"])
def test_unknown_option_name_of_show_and_check_is_exit_2(command, capsys):
    assert main([command, "qib.thm1", "-p", "zzz=1"]) == 2
    _one_error_line(capsys, "unknown parameter 'zzz'", "beta, fixed_L, gamma")


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (["--backends", ""], "--backends '': name at least one backend"),
        (["--backends", " , "], "name at least one backend"),
        (["--rtol", "-1"], "rtol must be a non-negative number"),
        (["--rtol", "nan"], "rtol must be a non-negative number"),
        (["--rtol", "-1", "--executor", "local"], "rtol must be a non-negative number"),
    ],
)
def test_bad_crosscheck_arguments_are_exit_2_before_any_solve(args, fragment, capsys, monkeypatch):
    import lmic.studies.crosscheck as cc

    monkeypatch.setattr(cc, "backend_row", lambda *a, **k: pytest.fail("a backend ran"))
    assert main(["crosscheck", "qib.thm1", SYSTEM, *args]) == 2
    _one_error_line(capsys, fragment)


def test_report_with_an_empty_backend_list_is_exit_2(tmp_path, capsys):
    out = tmp_path / "r.html"
    assert main(["report", "qib.thm1", SYSTEM, "-o", str(out), "--backends", ","]) == 2
    _one_error_line(capsys, "name at least one backend")
    assert not out.exists()


@pytest.mark.parametrize("value", ["-1", "nan", "inf"])
def test_bad_backoff_is_exit_2_before_solving(value, capsys, monkeypatch):
    import lmic.routes

    monkeypatch.setattr(lmic.routes, "decide_route", lambda *a, **k: pytest.fail("solved"))
    assert main(["solve", "qib.thm1", SYSTEM, f"--backoff={value}"]) == 2
    _one_error_line(capsys, "backoff must be a non-negative number")


def test_reproduce_pattern_matching_nothing_is_exit_2(tmp_path, capsys):
    out = tmp_path / "r.md"
    assert main(["reproduce", "--only", "nope.*", "--no-progress", "-o", str(out)]) == 2
    _one_error_line(capsys, "--only 'nope.*': no example file matches")
    assert not out.exists()
    assert main(["reproduce", "--only", "nope.*", "--no-progress", "--executor", "local"]) == 2
    _one_error_line(capsys, "no example file matches")


STUDY = str(Path(__file__).resolve().parents[2] / "examples" / "studies" / "qib_sup_beta.yaml")


@pytest.mark.parametrize(
    ("extra", "fragment"),
    [
        (["--map", "m.txt"], "--map m.txt: the map is a PNG image"),
        (["--map", "{tmp}/dir.png"], "dir.png: is a directory"),
        (["--export", "{tmp}/no/x.csv"], "folder {tmp}/no does not exist"),
    ],
)
def test_bad_batch_output_files_are_refused_before_any_job(tmp_path, capsys, extra, fragment):
    (tmp_path / "dir.png").mkdir()
    out = tmp_path / "study"
    args = [a.format(tmp=tmp_path) for a in extra]
    assert main(["batch", STUDY, "-o", str(out), "--no-progress", *args]) == 2
    _one_error_line(capsys, fragment.format(tmp=tmp_path))
    assert not out.exists()


@pytest.mark.parametrize("extra", [["--export", "x.csv"], ["--map", "m.png"]])
def test_batch_status_refuses_export_and_map_instead_of_ignoring_them(tmp_path, capsys, extra):
    assert main(["batch", "--status", str(tmp_path), *extra]) == 2
    _one_error_line(capsys, "--status DIR takes no study file, -o, --export or --map")


@pytest.mark.parametrize(
    "argv",
    [
        ["crosscheck", "qib.thm1", SYSTEM, "--executor", "local"],
        ["reproduce", "--only", "qib.thm1*", "--executor", "dask"],
        ["batch", STUDY, "-o", "{tmp}/out"],
    ],
)
def test_a_worker_count_far_above_the_cores_is_refused_before_any_process_starts(argv, tmp_path, capsys, monkeypatch):
    import lmic.studies.executors as executors

    monkeypatch.setattr(executors.LocalExecutor, "__init__", lambda *a, **k: pytest.fail("workers started"))
    args = [a.format(tmp=tmp_path) for a in argv]
    assert main([*args, "--workers", "100000"]) == 2
    _one_error_line(capsys, "--workers 100000: at most", "each worker is a process")


@pytest.mark.parametrize(
    ("option", "value", "fragment"),
    [
        ("--rtol", "nan", "--rtol nan: give a non-negative number"),
        ("--xtol", "inf", "--xtol inf: give a non-negative number"),
        ("--xtol", "-1", "--xtol -1.0: give a non-negative number"),
        ("--max-evals", "0", "--max-evals 0: give at least 1"),
    ],
)
def test_bad_bisection_tolerances_are_exit_2_before_solving(option, value, fragment, capsys, monkeypatch):
    import lmic.studies.sweep as sweep

    monkeypatch.setattr(sweep, "maximize", lambda *a, **k: pytest.fail("solved"))
    assert main(["solve", "qib.thm1", SYSTEM, "--maximize", "beta", f"{option}={value}"]) == 2
    _one_error_line(capsys, fragment)


def test_simulate_with_an_ir_file_names_the_system_file_not_its_contents(tmp_path, capsys):
    ir = tmp_path / "p.json"
    assert main(["compile", "qib.thm1", SYSTEM, "-o", str(ir)]) == 0
    capsys.readouterr()
    assert main(["simulate", str(ir), SYSTEM]) == 2
    _one_error_line(capsys, "p.json: an IR or SDPA file takes no system file (got 'qib.thm1.flexible-joint.yaml')")


def test_system_and_theorem_swapped_say_the_order(capsys):
    example = Path(__file__).resolve().parents[2] / "examples" / "qib.thm1.flexible-joint.yaml"
    assert main(["solve", str(example), "qib.thm1"]) == 2
    order = f"the arguments are THEOREM SYSTEM (lmic solve qib.thm1 {example}?)"
    _one_error_line(capsys, "qib.thm1: no such file", order)


def test_maximize_of_a_decision_variable_says_how_to_optimise_it(tmp_path, capsys):
    system = tmp_path / "plant.yaml"
    system.write_text("data:\n  A: [[-1.0]]\n  B: [[1.0]]\n  C: [[1.0]]\n")
    assert main(["solve", "tutorial.bounded_real", str(system), "--maximize", "gamma"]) == 2
    _one_error_line(capsys, "'gamma' is a decision variable, not a parameter", "t.maximize(gamma) or t.minimize(gamma)")
