"""``lmic batch`` on real Dask: a LocalCluster, a scheduler and workers started as processes, a lost worker.

Only 127.0.0.1; every process started here is stopped by its id at the end.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading

import pytest
from study_helpers import (
    DaskCluster,
    assert_exactly_once,
    audit_certificates,
    decision,
    env,
    lines,
    lyapunov_truth,
    wait_for,
    write_study,
)

from lmic.studies.driver import run_study
from lmic.studies.spec import load_study

pytest.importorskip("distributed")


def _study(count: int, n: int, seed: int = 21) -> dict:
    """thesis.lyapunov on random 3x3 (mixed) or larger all-Hurwitz plants: truth from the eigenvalues."""
    plants = (
        {"count": count, "seed": seed, "dims": {"n": 3}, "scale": 0.5, "shift": {"A": -0.8}}
        if n == 3
        else {"count": count, "seed": seed, "dims": {"n": n}, "spectral_abscissa": {"A": -0.3}}
    )
    return {
        "lmic": 1,
        "name": "dask",
        "theorem": "thesis.lyapunov",
        "systems": {"random": plants},
        "backends": ["clarabel"],
        "time_limit": 120,
        "retries": 2,
    }


def _check_truth(study, recs) -> None:
    truth = {j.hash: lyapunov_truth(j.system) for j in study.jobs}
    assert all(decision(r["outcome"]) == truth[r["hash"]] for r in recs)


def test_local_cluster_with_two_worker_processes(tmp_path):
    study = load_study(_study(10, 3))
    summary = run_study(study, str(tmp_path / "o"), executor="dask", workers=2, progress=False)
    assert summary.executor == "dask LocalCluster (2 workers)"
    recs = assert_exactly_once(tmp_path / "o", {j.hash for j in study.jobs})
    assert summary.exit_code() == 0
    _check_truth(study, recs)
    audit_certificates(tmp_path / "o", recs)


def test_scheduler_and_worker_processes_run_a_20_job_study(tmp_path):
    cluster = DaskCluster(tmp_path, workers=1)
    try:
        study_file = write_study(tmp_path / "s.yaml", _study(20, 3, seed=22))
        proc = subprocess.run(
            [
                sys.executable,
                "-m",
                "lmic.cli",
                "batch",
                str(study_file),
                "-o",
                str(tmp_path / "o"),
                "--executor",
                cluster.address,
                "--json",
            ],
            env=env(),
            capture_output=True,
            text=True,
            timeout=600,
        )
        assert proc.returncode == 0, proc.stderr
        summary = json.loads(proc.stdout)
        assert summary["ran"] == 20 and summary["executor"].startswith(f"dask {cluster.address}")
        study = load_study(str(study_file))
        recs = assert_exactly_once(tmp_path / "o", {j.hash for j in study.jobs})
        _check_truth(study, recs)
        assert len({r["worker"] for r in recs}) == 1  # one worker, one runner: the plan analysed once
        # a job that hangs (a bisection to a zero tolerance: ~100 solves) is stopped by its 0.4 s limit,
        # and the worker goes on with the next study
        hang = load_study(
            {
                "theorem": "qib.thm1",
                "task": "maximize",
                "params": {"gamma": 0.0},
                "maximize": {"param": "beta", "xtol": 1e-300, "rtol": 0, "max_evals": 100},
                "systems": {"random": {"count": 1, "seed": 1, "dims": {"n": 4, "p": 1}, "spectral_radius": {"A": 0.9}}},
                "time_limit": 0.4,
                "retries": 0,
            }
        )
        run_study(hang, str(tmp_path / "h"), executor=cluster.address, progress=False)
        (rec,) = assert_exactly_once(tmp_path / "h", {hang.jobs[0].hash})
        assert rec["outcome"] == "undecided" and rec["status"] == "time limit" and rec["time_s"] < 2.0
        after = load_study(_study(3, 3, seed=24))
        run_study(after, str(tmp_path / "after"), executor=cluster.address, progress=False)
        _check_truth(after, assert_exactly_once(tmp_path / "after", {j.hash for j in after.jobs}))
    finally:
        cluster.stop()


def test_a_worker_killed_mid_study_loses_nothing_and_counts_nothing_twice(tmp_path):
    cluster = DaskCluster(tmp_path, workers=2)
    try:
        study = load_study(_study(30, 10, seed=23))
        out = tmp_path / "o"
        at_kill: list[int] = []

        def killer() -> None:
            wait_for(lambda: len(lines(out)) >= 3, 300, "three results")
            victim = cluster.workers[0]
            os.kill(victim.pid, signal.SIGKILL)
            victim.wait()
            at_kill.append(len(lines(out)))

        t = threading.Thread(target=killer)
        t.start()
        summary = run_study(study, str(out), executor=cluster.address, progress=False)
        t.join()
        assert at_kill and at_kill[0] < 30, "the worker was killed mid-study"
        recs = assert_exactly_once(out, {j.hash for j in study.jobs})
        assert summary.ran == 30 and summary.exit_code() == 0
        _check_truth(study, recs)
    finally:
        cluster.stop()
