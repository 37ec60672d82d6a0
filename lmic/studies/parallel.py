"""``lmic reproduce --executor`` and ``lmic crosscheck --executor``: their jobs on the study executors.

``lmic crosscheck --executor`` (:func:`crosscheck_parallel`) runs one job per backend (task
``crosscheck-backend``, :func:`lmic.studies.tasks.run_crosscheck_backend`) and joins the rows,
in backend order, into the report the sequential :func:`lmic.crosscheck.crosscheck` builds.

``lmic reproduce --executor`` (:func:`reproduce_parallel`) runs one job per example file.

Each example file becomes a job of task ``reproduce-file`` that runs
:func:`lmic.reproduce.reproduce` restricted to that file in a job runner
(:func:`lmic.studies.tasks.run_reproduce_file`) (local worker or Dask
task); the rows come back as JSON and are joined, in the order of the expectations file, into
the same :class:`~lmic.reproduce.ReproductionReport` the sequential command builds.

Examples
--------
>>> rep = reproduce_parallel(only=["thesis.lyapunov.*"], executor="local", workers=1)
>>> [r.finding for r in rep.results], rep.exit_code()
(['certified', 'certified', 'certified'], 0)
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

__all__ = ["reproduce_parallel", "crosscheck_parallel"]


def reproduce_parallel(
    examples: str | os.PathLike[str] | None = None,
    expectations: str | os.PathLike[str] | None = None,
    *,
    only: Sequence[str] = (),
    backend: str | None = None,
    options: dict[str, Any] | None = None,
    executor: str = "local",
    workers: int | None = None,
    time_limit: float | None = None,
    progress: Callable[[dict[str, Any]], None] | None = None,
) -> Any:
    """:func:`lmic.reproduce.reproduce` with one job per example file on an executor.

    Parameters
    ----------
    examples, expectations, only
        As :func:`lmic.reproduce.reproduce`.
    backend : str, optional
        Default: :func:`lmic.reproduce.reproduce`'s own default.
    options : dict, optional
        ``SolveOptions`` fields to set (``tol``, ``time_limit`` ...), sent as numbers.
    executor : str
        ``local``, ``dask`` or ``tcp://HOST:PORT``.
    workers : int, optional
    time_limit : float, optional
        Per example file; a file past it gets ``error`` rows saying so.
    progress : callable, optional
        Called after each row with ``{"done", "total", "file", "row"}``.

    Returns
    -------
    ReproductionReport
    """
    from lmic.studies.executors import make_executor
    from lmic.studies.reproduce import ReproductionReport, RowResult, select_examples

    t0 = time.perf_counter()
    sel = select_examples(examples, expectations, only)
    spec, files, folder, exp_path = sel.spec, sel.files, sel.folder, sel.expectations
    listed = [f for f in files if f in spec]
    total = sum(len(spec[f]) for f in listed)
    jobs = [
        {
            "hash": f,
            "task": "reproduce-file",
            "file": f,
            "examples": str(folder.resolve()),
            "expectations": str(exp_path.resolve()),
            "backend": backend,
            "options": options or {},
        }
        for f in listed
    ]
    by_file: dict[str, list[Any]] = {}
    file_times: dict[str, float] = {}
    done = 0
    used = backend or ""
    ex = make_executor(executor, workers)
    try:
        ex.submit_many(jobs, time_limit)
        for rec in ex.results():
            f = rec["hash"]
            rows = spec[f]
            got = rec.get("rows")
            results = []
            for k, row in enumerate(rows):
                if got is not None and k < len(got):
                    d = got[k]
                    res = RowResult(
                        row,
                        d["finding"],
                        d["computed"],
                        d["computed_text"],
                        d["verdict_ok"],
                        d["value_ok"],
                        d["detail"],
                        d["time_s"],
                    )
                else:
                    res = RowResult(
                        row, "error", None, "error", False, None, f"{rec.get('status')}: {rec.get('message')}", 0.0
                    )
                results.append(res)
                done += 1
                if progress is not None:
                    progress({"done": done, "total": total, "file": f, "row": res})
            by_file[f] = results
            file_times[f] = (rec.get("file_times") or {}).get(f, rec.get("time_s", 0.0))
            used = rec.get("backend") or used
    finally:
        ex.close()
    return ReproductionReport(
        results=[r for f in listed for r in by_file.get(f, [])],
        unlisted=sel.unlisted,
        missing=sel.missing,
        backend=used,
        total_s=time.perf_counter() - t0,
        file_times=file_times,
    )


def _portable(value: Any) -> Any:
    """A target or system as a worker can load it: an existing file as an absolute path."""
    if isinstance(value, str | os.PathLike) and Path(value).is_file():
        return str(Path(value).resolve())
    return value


def crosscheck_parallel(
    target: str | os.PathLike[str],
    system: str | os.PathLike[str] | dict[str, Any] | None = None,
    params: dict[str, Any] | None = None,
    backends: list[str] | None = None,
    options: Any = None,
    rtol: float | None = None,
    *,
    executor: str = "local",
    workers: int | None = None,
    progress: Callable[[int, int, str, dict[str, Any] | None], None] | None = None,
) -> Any:
    """:func:`lmic.crosscheck.crosscheck` with one job per backend on an executor.

    The problem is loaded here once (bad input fails before any job starts); each job loads it
    again in its worker and decides it with one backend (:func:`lmic.crosscheck.backend_row`).
    The rows are joined in the order of ``backends`` into the report the sequential run builds
    (same rows, same decisions; ``runs`` stays empty: results do not travel). A job that crashes
    or passes its time limit is an ``undecided`` row saying so (a failure, not a conflict).

    Parameters
    ----------
    target, system, params, backends, rtol
        As :func:`lmic.crosscheck.crosscheck` (a theorem id or an IR/SDPA file; a system file
        or dict).
    options : SolveOptions, optional
        Sent to the workers field by field; its ``time_limit`` (plus a grace) also bounds each job.
    executor : str
        ``local``, ``dask`` or ``tcp://HOST:PORT``.
    workers : int, optional
    progress : callable, optional
        ``progress(done, total, backend, row)`` after each backend's row arrives.

    Returns
    -------
    CrosscheckReport

    Examples
    --------
    >>> rep = crosscheck_parallel("thesis.lyapunov", {"data": {"A": [[-2.0]]}},
    ...                           backends=["clarabel", "scs"], executor="local", workers=1)
    >>> [(r["backend"], r["decision"]) for r in rep.results], rep.exit_code()
    ([('clarabel', 'certified'), ('scs', 'certified')], 0)
    """
    import dataclasses
    import json

    from lmic.api import load_target
    from lmic.backends.registry import available_backend_names
    from lmic.errors import LmicError
    from lmic.studies.crosscheck import DEFAULT_RTOL, assemble, check_rtol, error_row, target_label
    from lmic.studies.executors import make_executor

    check_rtol(DEFAULT_RTOL if rtol is None else rtol)
    problem, _theorem, _ = load_target(target, system, params)
    names = backends or available_backend_names()
    if not names:
        raise LmicError("no backend to cross-check with")
    fields: dict[str, Any] = {}
    limit = None
    if options is not None:
        default = type(options)()
        for f in dataclasses.fields(options):
            value = getattr(options, f.name)
            if value != getattr(default, f.name):
                try:
                    json.dumps(value, allow_nan=False)
                except (TypeError, ValueError):
                    raise LmicError(f"solve option {f.name}={value!r} cannot be sent to a worker") from None
                fields[f.name] = value
        limit = options.time_limit
    jobs = [
        {
            "hash": f"{k}:{name}",
            "task": "crosscheck-backend",
            "target": _portable(target),
            "system": _portable(system),
            "params": params or {},
            "backend": name,
            "options": fields,
        }
        for k, name in enumerate(names)
    ]
    rows: dict[str, dict[str, Any]] = {}
    ex = make_executor(executor, workers)
    try:
        ex.submit_many(jobs, limit)
        for rec in ex.results():
            key = rec["hash"]
            if key in rows:  # a re-run of a lost Dask task: keep the first result
                continue
            name = key.split(":", 1)[1]
            row = rec.get("row")
            if row is None:  # crashed, stopped at the time limit, or raised in the worker
                row = error_row(name, str(rec.get("message") or rec.get("status")), status=str(rec.get("status")))
            rows[key] = row
            if progress is not None:
                progress(len(rows), len(jobs), name, row)
    finally:
        ex.close()
    ordered = [rows[job["hash"]] for job in jobs]
    return assemble(
        target_label(target, system),
        ordered,
        problem.objective.sense,
        DEFAULT_RTOL if rtol is None else rtol,
    )
