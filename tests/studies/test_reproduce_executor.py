"""``lmic reproduce --executor``: the same rows as the sequential run, one job per example file."""

from __future__ import annotations

import json
import subprocess
import sys

from study_helpers import REPO, env

from lmic.reproduce import reproduce

ONLY = ["thesis.lyapunov.*", "qib.thm1.*", "qib.cor2.*"]


def test_parallel_reproduce_matches_the_sequential_run(tmp_path):
    seq = reproduce(REPO / "examples", only=ONLY)
    cmd = [
        sys.executable,
        "-m",
        "lmic.cli",
        "reproduce",
        "--examples",
        str(REPO / "examples"),
        "--json",
        "--executor",
        "local",
        "--workers",
        "2",
    ]
    for pat in ONLY:
        cmd += ["--only", pat]
    proc = subprocess.run(cmd, env=env(), capture_output=True, text=True, timeout=600, cwd=tmp_path)
    par = json.loads(proc.stdout)
    assert proc.returncode == seq.exit_code(), proc.stderr
    assert [(r["file"], r["quantity"]) for r in par["rows"]] == [(r.row.file, r.row.quantity) for r in seq.results]
    assert [(r["finding"], r["ok"]) for r in par["rows"]] == [(r.finding, r.ok) for r in seq.results]
    assert len({r["file"] for r in par["rows"]}) == 3


def test_bad_executor_or_workers_is_one_line_and_exit_2(tmp_path):
    out = tmp_path / "r.md"
    for extra, named in ((["--executor", "ssh://host"], "--executor ssh://host"), (["--workers", "0"], "--workers 0")):
        proc = subprocess.run(
            [sys.executable, "-m", "lmic.cli", "reproduce", "--only", "qib.thm1.*", "-o", str(out), *extra],
            cwd=REPO,
            env=env(),
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert proc.returncode == 2 and proc.stdout == ""
        assert proc.stderr.count("\n") == 1 and named in proc.stderr
        assert not out.exists()
