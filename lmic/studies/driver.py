"""Run a study: skip the jobs already done, run the rest on an executor, record each once.

The driver is the only writer of ``DIR/results.jsonl`` (:class:`~lmic.studies.store.Store`).
A result is written once per job hash: a record arriving for a job already recorded (a Dask
task re-run after its worker was lost, for instance) is dropped. A job whose runner crashed is
resubmitted up to ``retries`` times, then recorded as ``error``.

Examples
--------
>>> import tempfile
>>> from lmic.studies.spec import load_study
>>> study = load_study({"theorem": "thesis.lyapunov", "backend": "clarabel",
...                     "systems": {"random": {"count": 2, "dims": {"n": 2},
...                                            "spectral_abscissa": {"A": -1.0}}}})
>>> d = tempfile.mkdtemp()
>>> run_study(study, d, workers=1, progress=False).counts["certified"]
2
>>> run_study(study, d, workers=1, progress=False).skipped  # resumed: nothing left to do
2
"""

from __future__ import annotations

import os
import sys
import time
from collections import Counter
from dataclasses import dataclass, field
from typing import Any

from lmic.studies.executors import Executor, make_executor
from lmic.studies.spec import Study
from lmic.studies.store import Store, read_results
from lmic.studies.tasks import OUTCOMES

__all__ = ["RunSummary", "run_study", "manifest_of"]


@dataclass
class RunSummary:
    """What one ``lmic batch`` run did."""

    total: int
    skipped: int
    ran: int
    counts: Counter[str] = field(default_factory=Counter)
    records: list[dict[str, Any]] = field(default_factory=list)
    elapsed_s: float = 0.0
    executor: str = ""
    workers: int = 1
    dropped_duplicates: int = 0
    retried: int = 0

    @property
    def complete(self) -> bool:
        """Every job of the study has a result."""
        return len(self.records) == self.total

    def exit_code(self) -> int:
        """0 every job has a result and none is ``error``; 1 otherwise."""
        return 0 if self.complete and not self.counts.get("error") else 1


def manifest_of(study: Study) -> dict[str, Any]:
    """The ``study.json`` content for ``study``.

    >>> from lmic.studies.spec import load_study
    >>> m = manifest_of(load_study({"theorem": "thesis.lyapunov",
    ...                             "systems": {"random": {"count": 2, "dims": {"n": 2}}}}))
    >>> m["total"], m["task"], sorted(m["jobs"][0])[:3]
    (2, 'solve', ['backend', 'backends', 'certificate_file'])
    """
    return {
        "name": study.name,
        "study": study.path,
        "task": study.task,
        "total": len(study.jobs),
        "grid_axes": study.grid_axes,
        "map_axes": list(study.map_axes) if study.map_axes else None,
        "maximize": study.maximize,
        "time_limit": study.time_limit,
        "retries": study.retries,
        "jobs": [j.meta() for j in study.jobs],
    }


class _Bar:
    """A progress bar on stderr with rate, ETA and the outcome counts so far (:mod:`lmic.progressbar`)."""

    def __init__(self, total: int, done: int, label: str) -> None:
        from lmic.progressbar import ProgressBar

        self._bar = ProgressBar(label, total, completed=done, rate="jobs", eta=True, summary=True).__enter__()

    def advance(self, counts: Counter[str]) -> None:
        short = {
            "certified": "ok",
            "infeasible-certified": "inf",
            "infeasible-bounded": "bnd",
            "unbounded-certified": "unb",
            "rejected": "rej",
            "undecided": "?",
            "error": "err",
        }
        text = " ".join(f"{short[k]} {counts[k]}" for k in OUTCOMES if counts.get(k))
        self._bar.update(advance=1, info=text)

    def close(self) -> None:
        self._bar.__exit__(None, None, None)


def run_study(
    study: Study,
    out_dir: str,
    *,
    executor: str | Executor = "local",
    workers: int | None = None,
    progress: bool = True,
) -> RunSummary:
    """Run the jobs of ``study`` not yet in ``out_dir``; return what happened.

    Parameters
    ----------
    study : Study
        From :func:`lmic.studies.spec.load_study`.
    out_dir : str
        The output folder (created; resumed if it holds results).
    executor : str or Executor
        ``local`` (default), ``dask``, ``tcp://HOST:PORT``, or an executor instance (already
        started, e.g. to overlap its start-up with loading the study; closed when the run ends).
    workers : int, optional
        Local workers / LocalCluster processes (default: every core).
    progress : bool
        Draw a progress bar on stderr.
    """
    t0 = time.perf_counter()
    ex: Executor | None = None if isinstance(executor, str) else executor
    if ex is None:  # start the executor first: an unreachable scheduler leaves nothing written
        finished = {r["hash"] for r in read_results(os.path.join(out_dir, "results.jsonl"))}
        if any(j.hash not in finished for j in study.jobs):
            ex = make_executor(str(executor), workers)
    try:
        store = Store(out_dir)
        store.lock()
    except BaseException:
        if ex is not None:
            ex.close()
        raise
    try:
        done = store.done()
        wanted = {j.hash for j in study.jobs}
        pending = [j for j in study.jobs if j.hash not in done]
        store.write_manifest(manifest_of(study))
        summary = RunSummary(total=len(study.jobs), skipped=len(study.jobs) - len(pending), ran=0)
        for rec in done.values():
            if rec["hash"] in wanted:
                summary.counts[rec.get("outcome", "error")] += 1
        if not pending or ex is None:
            if ex is not None:
                ex.close()
            summary.records = [done[j.hash] for j in study.jobs if j.hash in done]
            summary.elapsed_s = time.perf_counter() - t0
            return summary
        summary.executor, summary.workers = ex.label, ex.workers
        bar = _Bar(len(study.jobs), summary.skipped, study.name) if progress else None
        by_hash = {j.hash: j for j in pending}
        attempts: Counter[str] = Counter()
        try:
            payload = {job.hash: job.to_dict() for job in pending}
            if ex.shared_filesystem:  # runners write certificates themselves (see runner.write_certificate_here)
                for key, d in payload.items():
                    d["certificate_path"] = store.certificate_path(key)
            for job in pending:
                attempts[job.hash] += 1
            ex.submit_many(list(payload.values()), study.time_limit)
            for rec in ex.results():
                h = rec.get("hash")
                if h not in by_hash or h in done:
                    summary.dropped_duplicates += 1
                    continue
                job = by_hash[h]
                if rec.get("crashed") and attempts[h] <= study.retries:
                    attempts[h] += 1
                    summary.retried += 1
                    ex.submit(payload[h], study.time_limit)
                    continue
                cert = rec.pop("_certificate", None)
                rec.pop("crashed", None)
                rec.pop("attempt_pid", None)
                if rec.pop("_certificate_written", False):
                    rec["certificate"] = f"certificates/{h}.json"
                elif cert is not None:
                    rec["certificate"] = store.write_certificate(h, cert)
                rec.update(
                    task=job.task,
                    theorem=job.theorem,
                    system=job.system_label,
                    backend=job.backend or "default",
                    params=job.params,
                    point=job.point,
                    attempts=attempts[h],
                    finished_at=time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
                )
                store.append(rec)
                done[h] = rec
                summary.ran += 1
                summary.counts[rec["outcome"]] += 1
                if bar is not None:
                    bar.advance(summary.counts)
        finally:
            if bar is not None:
                bar.close()
            ex.close()
        summary.records = [done[j.hash] for j in study.jobs if j.hash in done]
        summary.elapsed_s = time.perf_counter() - t0
        return summary
    finally:
        store.close()
        sys.stderr.flush()
