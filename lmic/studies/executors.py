"""Where jobs run: a local pool of job runners, a Dask ``LocalCluster``, or a Dask scheduler.

Every executor runs each job in a :class:`~lmic.studies.runner.Runner` (a long-lived child that
caches the analysed plans and can be killed at the time limit) and yields records as jobs
finish, in any order. ``--executor local`` (the default) needs no service: one runner per worker
thread of the driver. ``--executor dask`` starts a ``LocalCluster`` of worker processes (one
thread each); ``--executor tcp://HOST:PORT`` uses an existing scheduler. Dask is optional
(``pip install "lmic[dask]"``).

Examples
--------
>>> ex = make_executor("local", workers=1)
>>> job = {"hash": "h", "task": "solve", "theorem": "thesis.lyapunov",
...        "system": {"data": {"A": [[-2.0]]}}, "params": {}, "backend": "clarabel"}
>>> ex.submit(job, 60)
>>> [rec["outcome"] for rec in ex.results()]
['certified']
>>> ex.close()
"""

from __future__ import annotations

import os
import queue
import threading
from abc import ABC, abstractmethod
from collections.abc import Iterator
from typing import Any

from lmic.errors import DataError
from lmic.studies.runner import JobCrashed, Runner

__all__ = ["Executor", "LocalExecutor", "DaskExecutor", "make_executor", "default_workers"]


def default_workers() -> int:
    """The number of usable cores.

    >>> default_workers() >= 1
    True
    """
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


def _crash_record(job: dict[str, Any], message: str) -> dict[str, Any]:
    return {
        "hash": job["hash"],
        "outcome": "error",
        "status": "crashed",
        "verdict": None,
        "objective": None,
        "message": message,
        "crashed": True,
    }


class Executor(ABC):
    """Submit jobs, then iterate over :meth:`results` (records in completion order)."""

    label = "executor"
    workers = 1
    #: the workers see the driver's file system (they may write certificate files themselves)
    shared_filesystem = False

    @abstractmethod
    def submit(self, job: dict[str, Any], time_limit: float | None) -> None:
        """Queue one job."""

    def submit_many(self, jobs: list[dict[str, Any]], time_limit: float | None) -> None:
        """Queue several jobs (an executor may group them to save per-task overhead)."""
        for job in jobs:
            self.submit(job, time_limit)

    @abstractmethod
    def results(self) -> Iterator[dict[str, Any]]:
        """Records of the submitted jobs as they finish (until none is outstanding)."""

    @abstractmethod
    def close(self) -> None:
        """Stop the workers."""


class LocalExecutor(Executor):
    """``workers`` threads of the driver, each driving its own :class:`Runner` child."""

    shared_filesystem = True

    def __init__(self, workers: int | None = None, stderr: Any = None) -> None:
        import subprocess

        self.workers = int(workers or default_workers())
        self.label = f"local ({self.workers} worker{'s' if self.workers != 1 else ''})"
        self._jobs: queue.Queue[tuple[dict[str, Any], float | None] | None] = queue.Queue()
        self._done: queue.Queue[dict[str, Any]] = queue.Queue()
        self._outstanding = 0
        self._runners = [Runner(stderr if stderr is not None else subprocess.DEVNULL) for _ in range(self.workers)]
        for r in self._runners:  # the children import lmic while the driver loads the study
            r.start()
        self._threads = [threading.Thread(target=self._loop, args=(r,), daemon=True) for r in self._runners]
        for t in self._threads:
            t.start()

    @property
    def runner_pids(self) -> list[int]:
        """Process ids of the live runner children (for tests that kill one)."""
        return [r.pid for r in self._runners if r.pid is not None]

    def _loop(self, runner: Runner) -> None:
        while True:
            item = self._jobs.get()
            if item is None:
                return
            job, limit = item
            try:
                rec = runner.run(job, limit)
            except JobCrashed as err:
                rec = _crash_record(job, str(err))
            except Exception as err:  # noqa: BLE001 - the driver must hear about every job
                rec = _crash_record(job, f"{type(err).__name__}: {err}")
            self._done.put(rec)

    def submit(self, job: dict[str, Any], time_limit: float | None) -> None:
        self._outstanding += 1
        self._jobs.put((job, time_limit))

    def results(self) -> Iterator[dict[str, Any]]:
        while self._outstanding:
            rec = self._done.get()
            self._outstanding -= 1
            yield rec

    def close(self) -> None:
        for _ in self._threads:
            self._jobs.put(None)
        for r in self._runners:
            r.kill()


class DaskExecutor(Executor):
    """Jobs as Dask tasks (``run_in_runner``) on a ``LocalCluster`` or an existing scheduler."""

    #: most jobs in one Dask task (:meth:`submit_many`)
    MAX_CHUNK = 8

    def __init__(self, address: str | None = None, workers: int | None = None) -> None:
        try:
            from distributed import Client, LocalCluster
        except ImportError:
            raise DataError('--executor dask needs Dask: pip install "lmic[dask]"') from None
        self._cluster = None
        if address is None:
            self.workers = int(workers or default_workers())
            self._cluster = LocalCluster(
                n_workers=self.workers,
                threads_per_worker=1,
                processes=True,
                dashboard_address=None,
                host="127.0.0.1",
            )
            self._client = Client(self._cluster)
            self.label = f"dask LocalCluster ({self.workers} workers)"
            self.shared_filesystem = True
        else:
            try:
                self._client = Client(address, timeout=10)
            except (OSError, TimeoutError) as err:
                raise DataError(f"--executor {address}: cannot reach the Dask scheduler ({err})") from None
            self.workers = max(1, sum(w.get("nthreads", 1) for w in self._client.scheduler_info()["workers"].values()))
            self.label = f"dask {address} ({self.workers} threads)"
        self._futures: dict[Any, Any] = {}
        from distributed import as_completed

        self._ac = as_completed([], with_results=False)
        self._count = 0

    @property
    def client(self) -> Any:
        """The ``distributed.Client``."""
        return self._client

    def submit(self, job: dict[str, Any], time_limit: float | None) -> None:
        from lmic.studies.runner import run_in_runner

        self._count += 1
        fut = self._client.submit(
            run_in_runner, job, time_limit, key=f"lmic-job-{job['hash'][:16]}-{self._count}", pure=False
        )
        self._futures[fut.key] = job
        self._ac.add(fut)

    def submit_many(self, jobs: list[dict[str, Any]], time_limit: float | None) -> None:
        """Group jobs into tasks of up to ``MAX_CHUNK`` (about four tasks per worker at least).

        A Dask task costs some milliseconds of scheduling and messages; grouping short jobs keeps
        that off each job. Results of a group arrive together; a group lost with its worker is
        re-run by Dask and the driver keeps the first result of each job.
        """
        from lmic.studies.runner import run_many_in_runner

        size = max(1, min(self.MAX_CHUNK, len(jobs) // (4 * self.workers)))
        for k in range(0, len(jobs), size):
            chunk = jobs[k : k + size]
            if len(chunk) == 1:
                self.submit(chunk[0], time_limit)
                continue
            self._count += 1
            fut = self._client.submit(
                run_many_in_runner,
                chunk,
                time_limit,
                key=f"lmic-jobs-{chunk[0]['hash'][:16]}-{self._count}",
                pure=False,
            )
            self._futures[fut.key] = chunk
            self._ac.add(fut)

    def results(self) -> Iterator[dict[str, Any]]:
        for fut in self._ac:
            item = self._futures.pop(fut.key)
            jobs = item if isinstance(item, list) else [item]
            try:
                out = fut.result()
                recs = out if isinstance(out, list) else [out]
            except Exception as err:  # noqa: BLE001 - KilledWorker, a lost scheduler ...
                msg = f"{type(err).__name__}: {' '.join(str(err).split())}"[:300]
                recs = [_crash_record(job, msg) for job in jobs]
            fut.release()
            yield from recs

    def close(self) -> None:
        try:
            self._client.close()
        finally:
            if self._cluster is not None:
                self._cluster.close()


def check_workers(spec: str | None, workers: int | None) -> None:
    """Refuse a worker count that would fork more processes than this machine can run.

    A remote scheduler (``tcp://``) is not limited here: its workers are elsewhere.

    >>> check_workers("local", 10**5)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    lmic.errors.DataError: --workers 100000: at most ... on this machine (... cores; each worker is a process)
    """
    if workers is not None and workers < 1:
        raise DataError(f"--workers {workers}: give at least 1")
    cores = os.cpu_count() or 1
    most = max(16, 8 * cores)
    if workers is not None and workers > most and not (spec or "").startswith("tcp://"):
        raise DataError(
            f"--workers {workers}: at most {most} on this machine ({cores} cores; each worker is a process)"
        )


def make_executor(spec: str, workers: int | None = None) -> Executor:
    """``local``, ``dask`` or ``tcp://HOST:PORT`` -> an executor.

    >>> make_executor("ssh://x")
    Traceback (most recent call last):
    ...
    lmic.errors.DataError: --executor ssh://x: use local, dask or tcp://HOST:PORT
    """
    check_workers(spec, workers)
    if spec == "local":
        return LocalExecutor(workers)
    if spec == "dask":
        return DaskExecutor(None, workers)
    if spec.startswith("tcp://"):
        return DaskExecutor(spec, workers)
    raise DataError(f"--executor {spec}: use local, dask or tcp://HOST:PORT")
