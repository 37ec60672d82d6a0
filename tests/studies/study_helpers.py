"""Shared helpers for the batch-study tests (real processes, real Dask, only 127.0.0.1)."""

from __future__ import annotations

import json
import os
import shutil
import socket
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path

import numpy as np
import pytest
import yaml

REPO = Path(__file__).resolve().parents[2]


def env() -> dict[str, str]:
    """The environment of child processes: this checkout first on the path."""
    paths = [str(REPO), str(REPO / "plugins")]
    old = os.environ.get("PYTHONPATH")
    return {**os.environ, "PYTHONPATH": os.pathsep.join(paths + ([old] if old else []))}


def write_study(path: Path, study: dict) -> Path:
    path.write_text(yaml.safe_dump(study), encoding="utf-8")
    return path


def lines(out: Path) -> list[dict]:
    """Every line of results.jsonl, parsed (a torn line fails the test)."""
    p = out / "results.jsonl"
    if not p.exists():
        return []
    raw = p.read_bytes()
    assert not raw or raw.endswith(b"\n"), "results.jsonl ends with a torn line"
    return [json.loads(x) for x in raw.splitlines() if x.strip()]


def assert_exactly_once(out: Path, hashes: set[str]) -> list[dict]:
    """Every job of the study has exactly one line; no line of another job."""
    recs = lines(out)
    counts = Counter(r["hash"] for r in recs)
    assert set(counts) == hashes
    assert max(counts.values()) == 1, [h for h, c in counts.items() if c > 1]
    return recs


def lyapunov_truth(system: dict) -> str:
    """Closed-form truth for thesis.lyapunov (A^T P + P A < 0, P > 0): ``certified`` (feasible) iff
    A is Hurwitz, else ``infeasible``."""
    a = np.array(system["data"]["A"], dtype=float)
    return "certified" if max(np.linalg.eigvals(a).real) < 0 else "infeasible"


def decision(verdict: str) -> str:
    """A verdict's decision against a closed-form truth: ``infeasible`` for an infeasibility proof,
    global (exact) or bounded (a scale-free problem's float ray: no point of relative margin above
    rho); the verdict itself otherwise."""
    return "infeasible" if verdict in ("infeasible-certified", "infeasible-bounded") else verdict


def audit_certificates(out: Path, recs: list[dict]) -> None:
    """Re-check every certificate the study wrote with the certifier's audit (recomputed from the IR)."""
    from lmic.certify.certificate import audit_certificate

    for r in recs:
        if r.get("certificate"):
            res = audit_certificate(out / r["certificate"])
            assert res.ok, res.message
            assert res.verdict == r["verdict"]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def dask_cmd(*args: str) -> list[str]:
    exe = shutil.which("dask") or str(Path(sys.executable).parent / "dask")
    return [exe, *args]


def wait_for(pred, timeout: float, what: str, step: float = 0.1) -> None:
    t0 = time.monotonic()
    while not pred():
        if time.monotonic() - t0 > timeout:
            pytest.fail(f"timed out after {timeout:g} s waiting for {what}")
        time.sleep(step)


class DaskCluster:
    """A ``dask scheduler`` and ``dask worker`` processes on 127.0.0.1, stopped at the end."""

    def __init__(self, tmp: Path, workers: int) -> None:
        self.port = free_port()
        self.address = f"tcp://127.0.0.1:{self.port}"
        self.procs: list[subprocess.Popen] = []
        self.log = open(tmp / "dask.log", "wb")  # noqa: SIM115 - closed in stop()
        self.scheduler = self._spawn(
            dask_cmd("scheduler", "--host", "127.0.0.1", "--port", str(self.port), "--no-dashboard")
        )
        self.workers = [
            self._spawn(
                dask_cmd(
                    "worker",
                    self.address,
                    "--nthreads",
                    "1",
                    "--no-nanny",
                    "--no-dashboard",
                    "--host",
                    "127.0.0.1",
                    "--name",
                    f"w{k}",
                )
            )
            for k in range(workers)
        ]
        from distributed import Client

        with Client(self.address, timeout=60) as client:
            client.wait_for_workers(workers, timeout=90)

    def _spawn(self, cmd: list[str]) -> subprocess.Popen:
        p = subprocess.Popen(cmd, env=env(), stdout=self.log, stderr=subprocess.STDOUT, start_new_session=True)
        self.procs.append(p)
        return p

    def stop(self) -> None:
        for p in reversed(self.procs):
            if p.poll() is None:
                p.terminate()
        for p in self.procs:
            try:
                p.wait(timeout=15)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()
        self.log.close()


def runner_pids(parent: int | None = None) -> set[int]:
    """Process ids of the live job runners (``python -m lmic.studies.runner``) on this machine.

    ``parent``: only the runners whose parent process is ``parent`` (other test runs on the
    same machine have runners of their own).
    """
    out = set()
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                cmd = (d / "cmdline").read_bytes().split(b"\0")
                stat = (d / "stat").read_text()
            except OSError:
                continue
            if b"lmic.studies.runner" not in cmd:
                continue
            ppid = int(stat.rsplit(")", 1)[1].split()[1])  # field 4, after the command in parentheses
            if parent is None or ppid == parent:
                out.add(int(d.name))
    return out
