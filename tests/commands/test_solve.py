"""``lmic solve``, ``lmic backends`` and ``lmic crosscheck`` from the command line."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from lmic.cli import main
from lmic.ir.io import save_problem
from lmic.testing.conformance import CASES

SDPLIB = Path(__file__).resolve().parents[3] / "shared" / "sdplib"
if not SDPLIB.is_dir():  # a checkout without shared/ beside it: the workplace copy, as elsewhere
    SDPLIB = Path("/work/shared/sdplib")
EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
QIB = EXAMPLES / "qib.thm1.flexible-joint.yaml"


@pytest.fixture
def ir_file(tmp_path):
    def make(case: str) -> str:
        path = tmp_path / f"{case}.json"
        save_problem(CASES[case].build(), path)
        return str(path)

    return make


def _json(capsys) -> dict:
    return json.loads(capsys.readouterr().out)


def test_backends_json_lists_every_builtin(capsys):
    assert main(["backends", "--json"]) == 0
    rows = {r["name"]: r for r in _json(capsys)["backends"]}
    assert {"clarabel", "scs", "cvxopt", "sdpa", "cvxpy", "picos", "auto"} <= set(rows)
    assert rows["clarabel"]["available"] and rows["clarabel"]["default"]
    assert "cvxpy:SCS" in rows["cvxpy"]["variants"]


def test_backends_table(capsys):
    assert main(["backends"]) == 0
    out = capsys.readouterr().out
    assert "clarabel (default)" in out and "sdpa" in out


def test_solve_ir_file_json_shape(ir_file, capsys):
    code = main(["solve", ir_file("linear_equalities"), "--json"])
    d = _json(capsys)
    assert code == 0
    for key in ("lmic", "theorem", "backend", "status", "objective", "variables", "derived", "certificate", "timings"):
        assert key in d
    assert d["status"] == "optimal" and d["certificate"]["verdict"] == "certified"
    assert abs(d["objective"] - 0.5857864376) < 1e-6
    assert set(d["timings"]) >= {"compile_s", "solve_s", "certify_s"}
    assert {"name", "min_margin", "ok"} <= set(d["certificate"]["lmis"][0])


def test_solve_infeasible_exits_3(ir_file, capsys):
    assert main(["solve", ir_file("lyapunov_unstable"), "--backend", "cvxopt", "--json"]) == 3
    assert _json(capsys)["status"] == "infeasible"


def test_solve_sdpa_file(capsys):
    code = main(["solve", str(SDPLIB / "truss1.dat-s"), "--backend", "sdpa"])
    out = capsys.readouterr().out
    assert code == 0 and "objective  -8.99999" in out and "verdict    certified" in out


def test_solve_sdplib_infeasible_is_certified(capsys):
    assert main(["solve", str(SDPLIB / "infp1.dat-s"), "--json"]) == 3
    assert _json(capsys)["certificate"]["verdict"] == "infeasible-certified"


def test_solve_theorem_and_system_writes_certificate(tmp_path, capsys):
    cert = tmp_path / "cert.json"
    code = main(["solve", "qib.thm1", str(QIB), "--backend", "scs", "--json", "-o", str(cert)])
    d = _json(capsys)
    assert code == 0 and d["theorem"] == "qib.thm1" and d["status"] == "feasible"
    # SCS (first order) takes the fixed-margin route; the margin its point achieves is recorded
    assert d["strict"]["strategy"] == "fixed-margin" and d["strict"]["margin"] > 1e-3
    assert "L" in d["derived"]
    assert json.loads(cert.read_text())["certificate"]["verdict"] == "certified"


@pytest.mark.parametrize(
    "argv, message",
    [
        (["solve", "CASE", "--backend", "nope"], "unknown backend 'nope'; available backends: auto"),
        (["solve", "missing.json"], "missing.json: no such file"),
        (["solve", "qib.thm1"], "give THEOREM SYSTEM"),
        (["solve", "CASE", "-p", "beta=1"], "-p parameters apply to a theorem"),
        (["crosscheck", "CASE", "--backends", "clarabel,nope"], "unknown backend 'nope'"),
    ],
)
def test_bad_input_exits_2_with_one_line(argv, message, ir_file, capsys):
    argv = [ir_file("max_sense") if a == "CASE" else a for a in argv]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1 and "Traceback" not in err


def test_missing_solver_package_exits_2(monkeypatch, ir_file, capsys):
    from lmic.backends.scs import SCSBackend

    monkeypatch.setattr(SCSBackend, "requires", {"scs_not_installed_here": "scs"})
    assert main(["solve", ir_file("max_sense"), "--backend", "scs"]) == 2
    assert "pip install scs" in capsys.readouterr().err


def test_backend_that_cannot_take_the_problem_exits_2(monkeypatch, ir_file, capsys):
    from lmic.backends.cvxopt import CVXOPTBackend

    monkeypatch.setattr(CVXOPTBackend, "capabilities", frozenset({"lmi"}))
    assert main(["solve", ir_file("linear_equalities"), "--backend", "cvxopt"]) == 2
    assert "cannot take eq constraints" in capsys.readouterr().err


def test_time_out_is_a_failed_solve(ir_file, capsys):
    code = main(["solve", ir_file("bounded_real"), "--backend", "scs", "--max-iter", "3", "--json"])
    d = _json(capsys)
    # SCS stopped by max_iters reports a '... inaccurate - reached max_iters' status, which
    # SCSBackend.STATUS_MAP maps to 'inaccurate' ('error' is for a failed SCS, not a stop)
    assert code == 1 and d["status"] == "inaccurate"
    assert "reached max_iters" in d["message"]


def test_crosscheck_table_and_json(ir_file, capsys):
    path = ir_file("bounded_real")
    assert main(["crosscheck", path, "--backends", "clarabel,cvxopt,sdpa"]) == 0
    out = capsys.readouterr().out
    assert "agree" in out and "cvxopt" in out and "certified" in out
    assert main(["crosscheck", path, "--backends", "clarabel,scs", "--json"]) == 0
    d = _json(capsys)
    assert d["agree"] is True and d["max_rel_objective_gap"] < 1e-3
    assert {"backend", "status", "objective", "verdict", "min_margin", "solve_s"} <= set(d["results"][0])


def test_crosscheck_theorem_with_system(capsys):
    code = main(["crosscheck", "qib.thm1", str(QIB), "--backends", "clarabel,scs,cvxopt", "--json"])
    d = _json(capsys)
    assert code == 0 and d["agree"] and all(r["verdict"] == "certified" for r in d["results"])


UIO32 = EXAMPLES / "uio_dt.thm3_2.flexible_joint.yaml"


def test_solve_strict_option(capsys):
    """uio_dt.thm3_2 at gamma = 45: max-margin alone is inaccurate, fixed-margin certifies."""
    base = ["solve", "uio_dt.thm3_2", str(UIO32), "-p", "gamma=45", "--json"]
    code = main([*base, "--strict", "max-margin", "--backend", "clarabel"])
    d = _json(capsys)
    first = d["attempts"][0]  # max-margin alone is inaccurate; the policy then rescales
    assert first["reduction"] == "default/max-margin" and first["status"] == "inaccurate"
    assert first["verdict"] == "rejected" and code == d["exit_code"]
    assert main([*base, "--strict", "fixed-margin"]) == 0
    d = _json(capsys)
    assert d["strict"]["strategy"] == "fixed-margin" and d["certificate"]["verdict"] == "certified"
    assert main(base) == 0  # auto: max-margin, then fixed-margin
    assert _json(capsys)["strict"]["strategy"] == "fixed-margin"


def test_solve_strict_option_rejects_unknown_values(capsys):
    with pytest.raises(SystemExit) as err:
        main(["solve", "qib.thm1", str(QIB), "--strict", "largest"])
    assert err.value.code == 2 and "invalid choice" in capsys.readouterr().err


def test_crosscheck_progress_and_margins(capsys):
    code = main(["crosscheck", "qib.thm1", str(QIB), "--backends", "clarabel,scs"])
    captured = capsys.readouterr()
    assert code == 0
    # off a terminal the progress bar is one line per backend on stderr
    assert "[1/2] clarabel: feasible, certified" in captured.err
    assert "[2/2] scs: feasible, certified" in captured.err
    assert "max-margin:" in captured.out and "fixed-margin:" in captured.out
    header = next(line for line in captured.out.splitlines() if "backend" in line)
    assert "objective" not in header  # a feasibility problem has none


def test_unbounded_problem_exits_5_and_its_certificate_audits(ir_file, tmp_path, capsys):
    """``max x1`` s.t. ``[[1 + x1, x2], [x2, 1]] >= 0`` (x1 -> +inf along (1, 0), closed form):
    ``lmic solve`` exits 5 with the ray in its JSON, ``-o`` records the ray, and ``lmic audit``
    re-proves it (exit 5, lmic solve's code for the same verdict); a file whose ray is edited is rejected (exit 1)."""
    cert = tmp_path / "unbounded.cert.json"
    code = main(["solve", ir_file("unbounded"), "--json", "-o", str(cert)])
    d = _json(capsys)
    assert code == 5 and d["verdict"] == "unbounded-certified" and d["exit_code"] == 5
    assert d["unbounded"]["sense"] == "max" and d["unbounded"]["slope"] < 0 and d["enclosure"] is None
    doc = json.loads(cert.read_text())
    assert doc["unbounded"]["ray"] == d["unbounded"]["ray"]
    assert main(["audit", str(cert)]) == 5
    assert "unbounded above" in capsys.readouterr().out
    doc["unbounded"]["ray"] = ["0", "1"]  # along x2 the objective does not improve (and the LMI is left)
    cert.write_text(json.dumps(doc))
    assert main(["audit", str(cert)]) == 1
    assert "unbounded.ray" in capsys.readouterr().out


def test_a_malformed_unbounded_section_is_bad_input(ir_file, tmp_path, capsys):
    """A certificate whose ``unbounded`` section is not what lmic writes (a ray of numbers, no
    ray): ``lmic audit`` exits 2 with one line naming the field."""
    cert = tmp_path / "unbounded.cert.json"
    main(["solve", ir_file("unbounded"), "-o", str(cert)])
    capsys.readouterr()
    doc = json.loads(cert.read_text())
    for section, needle in [
        ({"ray": [1, 0], "slope": -1.0, "sense": "max"}, "unbounded.ray[0]"),
        ({"slope": -1.0, "sense": "max"}, "'ray' is a required property"),
    ]:
        cert.write_text(json.dumps(dict(doc, unbounded=section)))
        assert main(["audit", str(cert)]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith("lmic: error:") and needle in err[0], err
