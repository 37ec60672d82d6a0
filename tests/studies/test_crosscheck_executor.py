"""``lmic crosscheck --executor``: one job per backend, the same rows and decisions as the sequential run.

The sequential run (:func:`lmic.crosscheck.crosscheck`, in this process) is the reference for
the parallel ones (``--executor local`` as a command, a Dask ``LocalCluster`` of 2 worker
processes through :func:`lmic.studies.parallel.crosscheck_parallel`). Independently of lmic, the
certified optima of control1 are checked against SDPLIB's published optimum (read from
``../shared/sdplib/README.md``), and no backend may call the flexible-joint example of qib.thm1
infeasible: the paper's own matrices certify it (``examples/reproduction.yaml``).
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest
from study_helpers import REPO, decision, env, lyapunov_truth

from lmic.crosscheck import DECISIONS, crosscheck
from lmic.options import SolveOptions
from lmic.reproduce import load_expectations
from lmic.studies.parallel import crosscheck_parallel

SDPLIB = REPO.parent / "shared" / "sdplib"
if not SDPLIB.is_dir():  # a checkout without shared/ beside it: the workplace copy, as elsewhere
    SDPLIB = Path("/work/shared/sdplib")
CONTROL1 = SDPLIB / "control1.dat-s"
THM1 = REPO / "examples" / "qib.thm1.flexible-joint.yaml"

#: (name, target, system, backends): scs is rejected on control1 (a failure row next to decisions)
CASES = [
    ("control1", str(CONTROL1), None, ["clarabel", "cvxopt", "scs", "sdpa"]),
    ("qib.thm1", "qib.thm1", str(THM1), ["clarabel", "cvxopt", "scs", "sdpa"]),
]
TIME_LIMIT = 120.0  # per backend job: a hung solve is stopped, the test stays bounded


def _untimed(obj):
    """``obj`` without wall-clock fields (``solve_s``, ``time_s`` ..., which differ run to run)."""
    if isinstance(obj, dict):
        return {k: _untimed(v) for k, v in obj.items() if not k.endswith("_s")}
    if isinstance(obj, list):
        return [_untimed(v) for v in obj]
    return obj


def _json(report) -> dict:
    """The ``--json`` object of a report, as the command prints it (a JSON round trip)."""
    from lmic.jsonable import to_jsonable

    return json.loads(json.dumps(to_jsonable(report.to_dict())))


def _sdplib_optimum(name: str) -> float:
    text = (SDPLIB / "README.md").read_text(encoding="utf-8")
    m = re.search(rf"^\| {re.escape(name)} \|[^|]*\|[^|]*\| ([-+0-9.eE]+) \|", text, re.M)
    assert m, f"{name} not in the SDPLIB table"
    return float(m.group(1))


def _published_verdict(example: str) -> str:
    rows = load_expectations(REPO / "examples" / "reproduction.yaml")[example]
    return rows[0].verdict


def _check_truth(name: str, out: dict) -> None:
    """What is known about each case without lmic."""
    rows = out["results"]
    assert any(r["decision"] in DECISIONS for r in rows)
    if name == "control1":
        best = _sdplib_optimum("control1")
        certified = [r for r in rows if r["decision"] == "certified"]
        assert certified
        for r in certified:  # certified optima of a minimisation are within rtol of SDPLIB's
            assert abs(r["objective"] - best) <= 1e-3 * max(1.0, abs(best)), r
        assert not any(r["decision"].startswith("infeasible") for r in rows)
    else:
        assert _published_verdict("qib.thm1.flexible-joint.yaml") == "certified"
        assert not any(r["decision"].startswith("infeasible") for r in rows)  # the paper's point is feasible


@pytest.fixture(scope="module")
def sequential() -> dict[str, dict]:
    """The sequential reports (the reference), one per case."""
    opts = SolveOptions(time_limit=TIME_LIMIT)
    return {name: _json(crosscheck(t, s, backends=b, options=opts)) for name, t, s, b in CASES}


def _assert_same(seq: dict, par: dict) -> None:
    assert [(r["backend"], r["decision"], r["status"]) for r in par["results"]] == [
        (r["backend"], r["decision"], r["status"]) for r in seq["results"]
    ]
    assert _untimed(par) == _untimed(seq)  # every row field, conflicts, counts, gap, exit code


@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_local_executor_gives_the_sequential_rows(case, sequential, tmp_path):
    name, target, system, backends = case
    cmd = [sys.executable, "-m", "lmic.cli", "crosscheck", target]
    cmd += [system] if system else []
    cmd += ["--backends", ",".join(backends), "--time-limit", str(TIME_LIMIT)]
    cmd += ["--json", "--executor", "local", "--workers", "2"]
    proc = subprocess.run(cmd, env=env(), capture_output=True, text=True, timeout=600, cwd=tmp_path)
    par = json.loads(proc.stdout)
    seq = sequential[name]
    assert proc.returncode == seq["exit_code"], proc.stderr
    _assert_same(seq, par)
    _check_truth(name, par)
    if name == "control1":  # a failure next to the decisions, counted apart, not a conflict
        assert par["failures"] >= 1 and par["decisions"] >= 1 and par["agree"] and not par["conflicts"]


def test_dask_local_cluster_of_two_processes_gives_the_sequential_rows(sequential):
    pytest.importorskip("distributed")
    opts = SolveOptions(time_limit=TIME_LIMIT)
    for name, target, system, backends in CASES:
        rep = crosscheck_parallel(target, system, backends=backends, options=opts, executor="dask", workers=2)
        par = _json(rep)
        _assert_same(sequential[name], par)
        _check_truth(name, par)


@pytest.mark.parametrize(
    ("extra", "needle"),
    [(["--executor", "ssh://host"], "--executor ssh://host"), (["--executor", "local", "--workers", "0"], "--workers")],
)
def test_bad_executor_spec_is_one_line_and_exit_2(extra, needle, tmp_path):
    cmd = [sys.executable, "-m", "lmic.cli", "crosscheck", str(CONTROL1), "--backends", "clarabel", *extra]
    proc = subprocess.run(cmd, env=env(), capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert proc.returncode == 2
    assert proc.stdout == ""
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and needle in lines[0], proc.stderr


def test_help_shows_the_executor_examples():
    proc = subprocess.run(
        [sys.executable, "-m", "lmic.cli", "crosscheck", "--help"],
        env=env(),
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert proc.returncode == 0
    assert "--executor" in proc.stdout and "--workers" in proc.stdout
    assert "lmic crosscheck qib.thm1 examples/qib.thm1.flexible-joint.yaml --executor dask" in proc.stdout


def test_a_backend_that_cannot_run_is_the_same_failure_row_in_a_worker():
    """An unknown backend: an ``undecided`` row with the same message, a failure, not a conflict."""
    system = {"data": {"A": [[-1.0, 2.0], [0.0, -3.0]]}}
    seq = _json(crosscheck("thesis.lyapunov", system, backends=["clarabel", "no-such-backend"]))
    rep = crosscheck_parallel(
        "thesis.lyapunov", system, backends=["clarabel", "no-such-backend"], executor="local", workers=1
    )
    par = _json(rep)
    _assert_same(seq, par)
    assert [decision(r["decision"]) for r in par["results"]] == [lyapunov_truth(system), "undecided"]
    assert par["failures"] == 1 and par["agree"] and par["exit_code"] == 0
    assert "no-such-backend" in par["results"][1]["message"]
