"""A job runner: one long-lived child Python process that runs jobs sent as JSON lines.

Every executor runs its jobs through a :class:`Runner`: the local executor keeps one per worker
thread, a Dask worker keeps one per worker thread too. The child imports lmic once and keeps the
analysed plans of the theorems it has seen (so only numbers travel); the parent can stop a job
that runs past its time limit by killing the child (a fresh one starts for the next job),
without harming itself. Jobs and results travel as one JSON line each (no pickle). The child
writes results on a private copy of its standard output and sends anything the solvers print to
standard error, so a chatty solver cannot corrupt the protocol.
A runner whose parent dies exits within a second, even in the middle of a job.

Examples
--------
>>> with Runner() as r:
...     rec = r.run({"hash": "h", "task": "solve", "theorem": "thesis.lyapunov",
...                  "system": {"data": {"A": [[-1.0]]}}, "params": {}, "backend": "clarabel"}, 60)
>>> rec["outcome"], rec["attempt_pid"] == r.last_pid
('certified', True)
"""

from __future__ import annotations

import json
import os
import select
import signal
import subprocess
import sys
import threading
import time
from typing import Any

from lmic.jsonable import to_jsonable

__all__ = [
    "Runner",
    "local_runner",
    "run_in_runner",
    "run_many_in_runner",
    "write_certificate_here",
    "TIME_LIMIT_GRACE",
]

#: seconds a job may overrun its limit (the solver's own limit comes first) before it is killed
TIME_LIMIT_GRACE = 2.0


def grace(time_limit: float) -> float:
    """How long past ``time_limit`` a job is killed: a quarter of the limit, 0.2 s to 2 s.

    >>> grace(0.4), grace(60)
    (0.2, 2.0)
    """
    return min(TIME_LIMIT_GRACE, max(0.2, 0.25 * float(time_limit)))


class JobCrashed(Exception):
    """The child died (killed, out of memory, segfault) while running a job."""


class Runner:
    """A child process running jobs (see the module docstring).

    Parameters
    ----------
    stderr : file or int, optional
        Where the child's standard error goes (default: discarded).
    """

    def __init__(self, stderr: Any = subprocess.DEVNULL) -> None:
        self._stderr = stderr
        self._proc: subprocess.Popen[bytes] | None = None
        self.last_pid: int | None = None

    def start(self) -> None:
        """Start the child now (it imports lmic while the caller does other work)."""
        self._start()

    def _start(self) -> subprocess.Popen[bytes]:
        if self._proc is None or self._proc.poll() is not None:
            self._proc = subprocess.Popen(
                [sys.executable, "-m", "lmic.studies.runner"],
                stdin=subprocess.PIPE,
                stdout=subprocess.PIPE,
                stderr=self._stderr,
                env={**os.environ, "PYTHONUNBUFFERED": "1", "OMP_NUM_THREADS": os.environ.get("OMP_NUM_THREADS", "1")},
                start_new_session=True,  # a Ctrl-C of the driver is the driver's to handle
            )
        return self._proc

    @property
    def pid(self) -> int | None:
        """The child's process id (``None`` before the first job)."""
        return None if self._proc is None else self._proc.pid

    def run(self, job: dict[str, Any], time_limit: float | None = None) -> dict[str, Any]:
        """Run ``job`` in the child; return its record.

        Past ``time_limit + grace(time_limit)`` seconds the child is killed and the record says
        ``undecided`` (``time limit``). Raises :class:`JobCrashed` if the child dies.
        """
        proc = self._start()
        self.last_pid = proc.pid
        assert proc.stdin is not None and proc.stdout is not None
        line = json.dumps({"job": job, "time_limit": time_limit}, allow_nan=False) + "\n"
        t0 = time.monotonic()
        try:
            proc.stdin.write(line.encode())
            proc.stdin.flush()
        except (BrokenPipeError, OSError):
            self.kill()
            raise JobCrashed(f"worker process {proc.pid} died before the job started") from None
        deadline = None if time_limit is None else t0 + float(time_limit) + grace(time_limit)
        fd = proc.stdout.fileno()
        while True:
            wait = None if deadline is None else max(0.0, deadline - time.monotonic())
            ready, _, _ = select.select([fd], [], [], wait)
            if ready:
                break
            if deadline is not None and time.monotonic() >= deadline:
                self.kill()
                return {
                    "hash": job["hash"],
                    "outcome": "undecided",
                    "status": "time limit",
                    "verdict": None,
                    "objective": None,
                    "message": f"time limit: stopped after {time.monotonic() - t0:.1f} s (limit {time_limit:g} s)",
                    "time_s": time.monotonic() - t0,
                    "worker": f"pid {proc.pid}",
                    "attempt_pid": proc.pid,
                }
        out = proc.stdout.readline()
        if not out.endswith(b"\n"):
            code = proc.wait()
            self._proc = None
            raise JobCrashed(f"worker process {proc.pid} died during the job (exit {code})")
        rec = json.loads(out)
        rec["attempt_pid"] = proc.pid
        return rec

    def kill(self) -> None:
        """Stop the child (its whole process group: solvers' helper processes too)."""
        proc, self._proc = self._proc, None
        if proc is None or proc.poll() is not None:
            return
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            proc.kill()
        proc.wait()

    def close(self) -> None:
        """Ask the child to stop (end of its input), then make sure it has."""
        proc = self._proc
        if proc is not None and proc.poll() is None:
            try:
                assert proc.stdin is not None
                proc.stdin.close()
                proc.wait(timeout=5)
            except (OSError, subprocess.TimeoutExpired):
                pass
        self.kill()

    def __enter__(self) -> Runner:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


_LOCAL = threading.local()


def local_runner() -> Runner:
    """The calling thread's :class:`Runner` (created at first use, kept for the process)."""
    runner = getattr(_LOCAL, "runner", None)
    if runner is None:
        runner = _LOCAL.runner = Runner()
    return runner


def run_in_runner(job: dict[str, Any], time_limit: float | None = None) -> dict[str, Any]:
    """Run ``job`` in this thread's runner (what a Dask task calls); a crash is an ``error`` record.

    The child's death is reported, not raised, so the scheduler does not retry a job that kills
    its process; the driver's retries decide.
    """
    runner = local_runner()
    try:
        return runner.run(job, time_limit)
    except JobCrashed as err:
        return {
            "hash": job["hash"],
            "outcome": "error",
            "status": "crashed",
            "verdict": None,
            "objective": None,
            "message": str(err),
            "crashed": True,
        }


def run_many_in_runner(jobs: list[dict[str, Any]], time_limit: float | None = None) -> list[dict[str, Any]]:
    """:func:`run_in_runner` for several jobs in turn (one Dask task for a group of short jobs)."""
    return [run_in_runner(job, time_limit) for job in jobs]


def _watch_parent(parent: int) -> None:
    """Exit as soon as the parent is gone (a killed driver or worker leaves no runner behind)."""
    while True:
        time.sleep(0.5)
        if os.getppid() != parent:
            os._exit(1)


#: what every job needs, imported when the child starts (often while the driver still loads the
#: study) instead of inside the first job; not the template layer (sympy): a theorem whose plan
#: an earlier process analysed binds its frozen plan without it (lmic.compile.warm)
PRELOAD = (
    "lmic.api",
    "lmic.studies.tasks",
    "lmic.certify.certificate",
    "lmic.compile.bind",
    "lmic.backends.clarabel",
    "lmic.backends.scs",
    "scipy.linalg",
)


def _preload() -> None:
    import importlib

    for name in PRELOAD:
        try:
            importlib.import_module(name)
        except ImportError:  # an optional solver missing: its jobs will say so themselves
            pass


#: how much a runner yields to its driver on a busy machine (``os.nice`` increment)
RUNNER_NICENESS = 5


def _lower_priority() -> None:
    """Let the driver win the cores when both want them (a runner is background compute).

    The runners start while the driver is still loading the study and import lmic at the same
    time; with as many runners as cores, the three processes shared two cores and the driver's
    load took 1.1 s instead of 0.7 s, on the critical path of every job. Niceness only matters
    under contention: an idle machine runs the jobs at full speed.
    """
    try:
        os.nice(RUNNER_NICENESS)
    except OSError:  # pragma: no cover - not permitted: run at the inherited priority
        pass


def _main() -> None:
    threading.Thread(target=_watch_parent, args=(os.getppid(),), daemon=True).start()
    proto = os.fdopen(os.dup(1), "w", encoding="utf-8")
    os.dup2(2, 1)  # anything printed by solvers goes to stderr
    sys.stdout = sys.stderr
    _lower_priority()
    _preload()
    from lmic.studies.tasks import run_job

    for line in sys.stdin:
        if not line.strip():
            continue
        msg = json.loads(line)
        rec = run_job(msg["job"], msg.get("time_limit"))
        write_certificate_here(msg["job"], rec)
        proto.write(json.dumps(to_jsonable(rec), allow_nan=False) + "\n")
        proto.flush()


def write_certificate_here(job: dict[str, Any], rec: dict[str, Any]) -> None:
    """Write ``rec``'s certificate to ``job["certificate_path"]`` when the driver gave one.

    A runner on the driver's machine (the local executor, a Dask ``LocalCluster``) writes the
    certificate file itself, atomically, before it answers; the record then carries
    ``_certificate_written`` instead of the document, so the (large) document is encoded once,
    here, in parallel across workers, instead of being sent to the driver and encoded again there.
    Without a path (a remote Dask worker) the document travels back in ``_certificate``.
    """
    path = job.get("certificate_path")
    doc = rec.get("_certificate")
    if not path or doc is None:
        return
    from lmic.studies.store import write_json_atomic

    write_json_atomic(path, to_jsonable(doc))
    del rec["_certificate"]
    rec["_certificate_written"] = True


if __name__ == "__main__":
    _main()
