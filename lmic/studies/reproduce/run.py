"""``lmic reproduce``: every shipped example against its expectations, one row at a time.

Examples
--------
>>> judge(Row("f", "q", {"solve": {}}, "t", reference=1.0, tol=0.1), "certified", 1.05)
(True, True)
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from lmic.errors import LmicError
from lmic.studies.reproduce.handlers import Runner, compute_row, scalar
from lmic.studies.reproduce.rows import ReproductionReport, Row, RowResult, select_examples

__all__ = ["reproduce", "judge"]


def judge(row: Row, finding: str, value: Any) -> tuple[bool, bool | None]:
    """``(verdict_ok, value_ok)``: the expected verdict; the reference within ``tol`` (``None``: none numeric)."""
    verdict_ok = finding == row.verdict
    ref = row.reference
    if ref is None or isinstance(ref, str) or isinstance(ref, bool):
        return verdict_ok, None
    if value is None:
        return verdict_ok, False
    try:
        a = np.atleast_2d(np.asarray(value, dtype=float))
        b = np.atleast_2d(np.asarray(ref, dtype=float))
    except (TypeError, ValueError):
        return verdict_ok, False
    if a.shape != b.shape:
        return verdict_ok, False
    tol = row.tol if row.tol is not None else 1e-3
    return verdict_ok, bool(np.max(np.abs(a - b)) <= tol * (1 + 1e-9))


def reproduce(
    examples: str | os.PathLike[str] | None = None,
    expectations: str | os.PathLike[str] | None = None,
    *,
    only: Sequence[str] = (),
    backend: str = "auto",
    options: Any = None,
    progress: Callable[[dict[str, Any]], None] | None = None,
) -> ReproductionReport:
    """Run every example (or those matching ``only``) against its expectations.

    Parameters
    ----------
    examples : path, optional
        The examples folder (default :func:`default_examples_dir`).
    expectations : path, optional
        Default ``<examples>/reproduction.yaml``.
    only : sequence of str
        Glob patterns on file names (``qib.*``); empty = every example.
    backend : str
    options : SolveOptions, optional
    progress : callable, optional
        Called after each row with ``{"done", "total", "file", "row"}``.

    Returns
    -------
    ReproductionReport

    Examples
    --------
    >>> rep = reproduce(only=["thesis.lyapunov.*"])                       # doctest: +SKIP
    >>> [r.finding for r in rep.results]                                  # doctest: +SKIP
    ['certified', 'certified', 'certified']
    """
    t0 = time.perf_counter()
    sel = select_examples(examples, expectations, only)
    spec, files = sel.spec, sel.files
    rows = [row for f in files for row in spec.get(f, [])]
    runner = Runner(sel.folder, backend, options)
    results: list[RowResult] = []
    file_times: dict[str, float] = {}
    for k, row in enumerate(rows):
        t1 = time.perf_counter()
        try:
            finding, value, text, detail = compute_row(runner, row)
        except LmicError as err:
            finding, value, text, detail = "error", None, "error", " ".join(str(err).split())
        verdict_ok, value_ok = judge(row, finding, value)
        res = RowResult(row, finding, scalar(value), text, verdict_ok, value_ok, detail, time.perf_counter() - t1)
        results.append(res)
        file_times[row.file] = file_times.get(row.file, 0.0) + res.time_s
        if progress is not None:
            progress({"done": k + 1, "total": len(rows), "file": row.file, "row": res})
    return ReproductionReport(
        results=results,
        unlisted=sel.unlisted,
        missing=sel.missing,
        backend=backend,
        total_s=time.perf_counter() - t0,
        file_times=file_times,
    )
