"""``lmic batch`` on the local executor: truth, certificates, resume, crashes, time limits, outputs."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from study_helpers import (
    assert_exactly_once,
    audit_certificates,
    decision,
    env,
    lines,
    lyapunov_truth,
    runner_pids,
    wait_for,
    write_study,
)

from lmic.studies.driver import run_study
from lmic.studies.executors import LocalExecutor
from lmic.studies.spec import load_study

#: A^T P + P A < 0 for random 3x3 plants, some stable, some not (truth: the eigenvalues of A)
LYAP = {
    "lmic": 1,
    "name": "lyapunov",
    "theorem": "thesis.lyapunov",
    "systems": {"random": {"count": 12, "seed": 5, "dims": {"n": 3}, "scale": 0.5, "shift": {"A": -0.8}}},
    "backends": ["clarabel"],
    "time_limit": 60,
}


def STABLE(count: int, n: int) -> dict:  # noqa: N802 - a constant-like factory
    """Larger plants, all Hurwitz (max Re eig = -0.3): each job's truth is certified."""
    return {"count": count, "seed": 11, "dims": {"n": n}, "spectral_abscissa": {"A": -0.3}}


def _truths(study) -> dict[str, str]:
    return {j.hash: lyapunov_truth(j.system) for j in study.jobs}


def test_local_pool_matches_the_eigenvalue_truth_and_certificates_audit(tmp_path):
    study = load_study(LYAP)
    truth = _truths(study)
    assert set(truth.values()) == {"certified", "infeasible"}  # the seed gives both kinds
    summary = run_study(study, str(tmp_path / "out"), workers=2, progress=False)
    recs = assert_exactly_once(tmp_path / "out", set(truth))
    assert summary.exit_code() == 0 and summary.ran == 12
    for r in recs:
        assert decision(r["outcome"]) == truth[r["hash"]], r
    assert len({r["worker"] for r in recs}) == 2  # both workers took jobs
    audit_certificates(tmp_path / "out", recs)
    assert all((tmp_path / "out" / r["certificate"]).is_file() for r in recs)


def test_each_worker_analyses_a_theorem_once(tmp_path):
    """The runner child keeps the plan: the first job of a worker pays the analysis, later ones bind."""
    study = load_study({**LYAP, "systems": {"random": {**LYAP["systems"]["random"], "count": 8}}})
    run_study(study, str(tmp_path / "o"), workers=1, progress=False)
    recs = sorted(lines(tmp_path / "o"), key=lambda r: r["finished_at"] + r["hash"])
    compile_s = [r["timings"]["compile_s"] for r in recs]
    first = max(compile_s)
    assert len({r["worker"] for r in recs}) == 1
    later = sorted(compile_s)[:-1]  # every job but the slowest (the one that analysed the template)
    assert len(later) == 7 and float(np.median(later)) < first / 3


def test_killed_runner_is_retried_and_counted_once(tmp_path):
    study = load_study({**LYAP, "systems": {"random": STABLE(16, 12)}, "retries": 2})
    ex = LocalExecutor(2)
    out = tmp_path / "out"
    killed: list[int] = []

    import threading

    def killer() -> None:
        wait_for(lambda: len(lines(out)) >= 2, 120, "two results")
        pid = ex.runner_pids[0]
        os.kill(pid, signal.SIGKILL)
        killed.append(len(lines(out)))

    t = threading.Thread(target=killer)
    t.start()
    summary = run_study(study, str(out), executor=ex, progress=False)
    t.join()
    assert killed and killed[0] < 16  # the kill happened mid-study
    recs = assert_exactly_once(out, {j.hash for j in study.jobs})
    truth = _truths(study)
    assert all(decision(r["outcome"]) == truth[r["hash"]] for r in recs)
    assert summary.retried >= 1 and any(r["attempts"] == 2 for r in recs)


def test_a_job_past_its_time_limit_is_stopped(tmp_path):
    """A bisection with a zero tolerance runs ~100 solves (seconds); its limit is 0.4 s."""
    spec = {
        "lmic": 1,
        "theorem": "qib.thm1",
        "task": "maximize",
        "maximize": {"param": "beta", "xtol": 1e-300, "rtol": 0, "max_evals": 100},
        "params": {"gamma": 0.0},
        "systems": {"random": {"count": 1, "seed": 1, "dims": {"n": 4, "p": 1}, "spectral_radius": {"A": 0.9}}},
        "time_limit": 0.4,
        "retries": 0,
    }
    study = load_study(spec)
    t0 = time.monotonic()
    run_study(study, str(tmp_path / "o"), workers=1, progress=False)
    elapsed = time.monotonic() - t0
    (rec,) = assert_exactly_once(tmp_path / "o", {study.jobs[0].hash})
    assert rec["outcome"] == "undecided" and rec["status"] == "time limit"
    assert 0.4 <= rec["time_s"] < 2.0
    assert elapsed < 30


def test_resume_after_killing_the_batch_process(tmp_path):
    study_file = write_study(tmp_path / "s.yaml", {**LYAP, "systems": {"random": STABLE(40, 8)}})
    out = tmp_path / "out"
    cmd = [
        sys.executable,
        "-m",
        "lmic.cli",
        "batch",
        str(study_file),
        "-o",
        str(out),
        "--workers",
        "2",
        "--no-progress",
    ]
    old_runners = runner_pids()
    proc = subprocess.Popen(cmd, env=env(), stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    wait_for(lambda: len(lines(out)) >= 3 or proc.poll() is not None, 120, "three results")
    ours = runner_pids(parent=proc.pid) - old_runners
    assert len(ours) == 2  # the two workers of the killed run
    from lmic.studies.report import status

    st_running = status(str(out))  # while it runs
    proc.kill()
    proc.wait()
    wait_for(lambda: not (runner_pids() & ours), 10, "the runners of the killed driver to exit")
    before = {r["hash"]: r for r in lines(out)}
    assert 3 <= len(before) < 40, "the run was killed mid-study"
    assert st_running["running_pid"] == proc.pid and st_running["total"] == 40
    assert 3 <= st_running["done"] <= len(before)
    again = subprocess.run([*cmd, "--json"], env=env(), capture_output=True, text=True, timeout=300)
    assert again.returncode == 0, again.stderr
    summary = json.loads(again.stdout)
    assert summary["skipped"] == len(before) and summary["ran"] == 40 - len(before)
    study = load_study(str(study_file))
    recs = assert_exactly_once(out, {j.hash for j in study.jobs})
    after = {r["hash"]: r for r in recs}
    assert all(after[h] == r for h, r in before.items())  # finished results kept as they were
    truth = _truths(study)
    assert all(decision(r["outcome"]) == truth[r["hash"]] for r in recs)
    status = subprocess.run(
        [sys.executable, "-m", "lmic.cli", "batch", "--status", str(out), "--json"],
        env=env(),
        capture_output=True,
        text=True,
        timeout=120,
    )
    st = json.loads(status.stdout)
    assert st["done"] == st["total"] == 40 and st["running_pid"] is None
    assert st["counts"]["certified"] == sum(v == "certified" for v in truth.values())


def test_torn_last_line_is_fenced_off(tmp_path):
    study = load_study(LYAP)
    out = tmp_path / "o"
    out.mkdir()
    (out / "results.jsonl").write_bytes(b'{"hash": "' + study.jobs[0].hash.encode() + b'", "outc')
    run_study(study, str(out), workers=2, progress=False)
    raw = (out / "results.jsonl").read_bytes().splitlines()
    assert raw[0].endswith(b'"outc')  # the torn line stays, fenced, and is not counted
    assert_lines = [json.loads(x) for x in raw[1:]]
    assert sorted(r["hash"] for r in assert_lines) == sorted(j.hash for j in study.jobs)


def test_grid_map_export_and_status(tmp_path):
    pytest.importorskip("pyarrow")
    import pyarrow.parquet as pq

    spec = {
        "lmic": 1,
        "name": "qib grid",
        "theorem": "qib.thm1",
        "params": {"gamma": 0.0},
        "systems": {"random": {"count": 1, "seed": 4, "dims": {"n": 2, "p": 1}, "spectral_radius": {"A": 1.2}}},
        "grid": {"beta": {"logspace": [1e-4, 1.0, 4]}, "gamma": [-0.2, 0.2]},
    }
    spec.pop("params")
    study_file = write_study(tmp_path / "g.yaml", spec)
    out = tmp_path / "out"
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "lmic.cli",
            "batch",
            str(study_file),
            "-o",
            str(out),
            "--workers",
            "1",
            "--export",
            str(tmp_path / "r.parquet"),
            "--no-progress",
        ],
        env=env(),
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    assert "qib.thm1" in proc.stdout and "certified" in proc.stdout
    png = (out / "map.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    table = pq.read_table(tmp_path / "r.parquet").to_pylist()
    recs = lines(out)
    assert sorted((r["param.beta"], r["param.gamma"], r["outcome"]) for r in table) == sorted(
        (r["params"]["beta"], r["params"]["gamma"], r["outcome"]) for r in recs
    )
    assert sorted({r["param.beta"] for r in table}) == pytest.approx(list(np.geomspace(1e-4, 1.0, 4)))
    audit_certificates(out, recs)
    csv_out = subprocess.run(
        [
            sys.executable,
            "-m",
            "lmic.cli",
            "batch",
            str(study_file),
            "-o",
            str(out),
            "--export",
            str(tmp_path / "r.csv"),
            "--json",
        ],
        env=env(),
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert json.loads(csv_out.stdout)["ran"] == 0  # resumed: nothing left
    header = (tmp_path / "r.csv").read_text(encoding="utf-8").splitlines()[0].split(",")
    assert {"hash", "outcome", "param.beta", "param.gamma"} <= set(header)


def test_ctrl_c_keeps_finished_results(tmp_path):
    study_file = write_study(tmp_path / "s.yaml", {**LYAP, "systems": {"random": STABLE(40, 8)}})
    out = tmp_path / "out"
    proc = subprocess.Popen(
        [sys.executable, "-m", "lmic.cli", "batch", str(study_file), "-o", str(out), "--workers", "1", "--no-progress"],
        env=env(),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    wait_for(lambda: len(lines(out)) >= 2 or proc.poll() is not None, 120, "two results")
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130
    assert err.strip().splitlines() == ["lmic: interrupted (finished results are kept; run again to resume)"]
    recs = lines(out)
    assert 2 <= len(recs) < 40 and len({r["hash"] for r in recs}) == len(recs)
    assert all(r["outcome"] == "certified" for r in recs)  # all-Hurwitz plants


def test_crosscheck_audit_published_and_audit_tasks(tmp_path):
    """The other tasks: crosscheck against the eigenvalue truth, audit-published against the direct
    API call, and an audit study over the certificates a solve study wrote."""
    from study_helpers import REPO

    from lmic.published import audit_published
    from lmic.studies.tasks import outcome

    xc = load_study(
        {
            **LYAP,
            "task": "crosscheck",
            "backends": ["clarabel", "cvxopt"],
            "systems": {"random": {**LYAP["systems"]["random"], "count": 4}},
        }
    )
    assert len(xc.jobs) == 4 and all(j.backends == ["clarabel", "cvxopt"] for j in xc.jobs)
    run_study(xc, str(tmp_path / "xc"), workers=2, progress=False)
    truth = _truths(xc)
    for r in assert_exactly_once(tmp_path / "xc", set(truth)):
        assert decision(r["outcome"]) == truth[r["hash"]] and [row["backend"] for row in r["rows"]] == [
            "clarabel",
            "cvxopt",
        ]

    sysfile = REPO / "examples" / "qib.thm2.flexible-joint.yaml"
    ap = load_study({"theorem": "qib.thm2", "task": "audit-published", "systems": {"files": [str(sysfile)]}})
    run_study(ap, str(tmp_path / "ap"), workers=1, progress=False)
    (rec,) = assert_exactly_once(tmp_path / "ap", {ap.jobs[0].hash})
    assert rec["outcome"] == outcome("audit-published", audit_published("qib.thm2", str(sysfile)))

    solve = load_study({**LYAP, "systems": {"random": {**LYAP["systems"]["random"], "count": 3}}})
    run_study(solve, str(tmp_path / "s"), workers=1, progress=False)
    solved = {r["certificate"]: r for r in lines(tmp_path / "s")}
    audit = load_study({"task": "audit", "systems": {"files": [str(tmp_path / "s" / "certificates" / "*.json")]}})
    assert len(audit.jobs) == 3
    run_study(audit, str(tmp_path / "a"), workers=1, progress=False)
    audited = assert_exactly_once(tmp_path / "a", {j.hash for j in audit.jobs})
    by_file = {j.hash: os.path.relpath(j.certificate_file, tmp_path / "s") for j in audit.jobs}
    for r in audited:
        assert r["outcome"] == solved[by_file[r["hash"]]]["outcome"] and r["status"] == "consistent"
    # a tampered certificate is rejected by the audit study
    path = next(iter((tmp_path / "s" / "certificates").glob("*.json")))
    doc = json.loads(path.read_text(encoding="utf-8"))
    doc["certificate"]["verdict"] = (
        "infeasible-certified" if doc["certificate"]["verdict"] == "certified" else "certified"
    )
    path.write_text(json.dumps(doc), encoding="utf-8")
    again = load_study({"task": "audit", "systems": {"files": [str(path)]}})
    run_study(again, str(tmp_path / "a2"), workers=1, progress=False)
    (bad,) = lines(tmp_path / "a2")
    assert bad["outcome"] == "rejected"


def _runner_children() -> list[int]:
    """Live (non-zombie) ``lmic.studies.runner`` children of this test process."""
    me, out = os.getpid(), []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat", encoding="utf-8") as fh:
                fields = fh.read().rsplit(")", 1)[1].split()
            with open(f"/proc/{entry}/cmdline", "rb") as fh:
                cmd = fh.read()
        except OSError:
            continue
        if int(fields[1]) == me and fields[0] != "Z" and b"lmic.studies.runner" in cmd:
            out.append(int(entry))
    return out


def test_local_runners_write_the_certificate_files_themselves(tmp_path):
    """With a path from the driver the runner writes the certificate; without one it sends it back."""
    study = load_study({**LYAP, "systems": {"random": {**STABLE(2, 3)}}})
    with_path, without = (j.to_dict() for j in study.jobs)
    target = tmp_path / "cert.json"
    with_path["certificate_path"] = str(target)
    ex = LocalExecutor(1)
    try:
        ex.submit(with_path, 60)
        ex.submit(without, 60)
        recs = {r["hash"]: r for r in ex.results()}
    finally:
        ex.close()
    written, sent = recs[with_path["hash"]], recs[without["hash"]]
    assert written["outcome"] == sent["outcome"] == lyapunov_truth(with_path["system"]) == "certified"
    assert written.get("_certificate_written") is True and "_certificate" not in written
    assert "_certificate_written" not in sent
    (tmp_path / "sent.json").write_text(json.dumps(sent["_certificate"]), encoding="utf-8")
    from lmic.certify.certificate import audit_certificate

    for path in (target, tmp_path / "sent.json"):  # both documents are whole, valid certificates
        res = audit_certificate(path)
        assert res.ok and res.verdict == "certified", res.message
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # no temporary file left


def test_results_are_fsynced_in_groups_and_at_close(tmp_path, monkeypatch):
    """One fsync per interval (not per line), always one at close; sync_interval=0 syncs each line."""
    import lmic.studies.store as store_mod

    calls: list[int] = []
    real = os.fsync
    monkeypatch.setattr(store_mod.os, "fsync", lambda fd: (calls.append(fd), real(fd))[1])
    grouped = store_mod.Store(tmp_path / "a", sync_interval=3600)
    for k in range(10):
        grouped.append({"hash": f"h{k}", "outcome": "certified"})
    assert calls == []  # the lines are written (a killed process keeps them) ...
    assert len(store_mod.read_results(tmp_path / "a" / "results.jsonl")) == 10
    grouped.close()
    assert len(calls) == 1  # ... and made durable once, at close
    calls.clear()
    each = store_mod.Store(tmp_path / "b", sync_interval=0)
    for k in range(5):
        each.append({"hash": f"h{k}", "outcome": "certified"})
    each.close()
    assert len(calls) == 5  # the close finds nothing left to sync


def test_a_bad_study_stops_the_runners_started_early(tmp_path):
    """`lmic batch` starts the local runners before it reads the study; bad input stops them again."""
    from lmic.cli import main

    assert _runner_children() == []
    bad = write_study(tmp_path / "bad.yaml", {"lmic": 1, "theorem": "no.such.theorem", "systems": []})
    assert main(["batch", str(bad), "-o", str(tmp_path / "out"), "--workers", "2"]) == 2
    assert not (tmp_path / "out").exists()
    assert _runner_children() == []


def test_runners_yield_the_cores_to_the_driver():
    """A runner child runs RUNNER_NICENESS steps nicer than its driver (it starts while the driver loads)."""
    from lmic.studies.runner import RUNNER_NICENESS

    mine = os.getpriority(os.PRIO_PROCESS, 0)
    if mine + RUNNER_NICENESS > 19:
        pytest.skip(f"this process already runs at niceness {mine}: no room to lower a child's priority")
    ex = LocalExecutor(1)
    try:
        pid = ex.runner_pids[0]
        deadline = time.monotonic() + 30
        while os.getpriority(os.PRIO_PROCESS, pid) == mine and time.monotonic() < deadline:
            time.sleep(0.05)  # the child lowers its own priority first thing after it starts
        assert os.getpriority(os.PRIO_PROCESS, pid) == mine + RUNNER_NICENESS
    finally:
        ex.close()


def test_make_executor_refuses_more_workers_than_the_machine_can_run():
    # the Python API has the CLI's limit: a huge count is bad input, before any process starts
    import os

    from lmic.errors import DataError
    from lmic.studies.executors import make_executor

    most = max(16, 8 * (os.cpu_count() or 1))
    with pytest.raises(DataError, match=f"--workers {most + 1}: at most {most}"):
        make_executor("local", most + 1)
    with pytest.raises(DataError, match="--workers 0: give at least 1"):
        make_executor("dask", 0)
