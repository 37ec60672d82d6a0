"""What a study shows: the outcome table, the region map, the export, ``--status``.

Examples
--------
>>> recs = [{"hash": "a", "theorem": "t", "backend": "clarabel", "outcome": "certified"},
...         {"hash": "b", "theorem": "t", "backend": "clarabel", "outcome": "error"}]
>>> outcome_table(recs)
{('t', 'clarabel'): Counter({'certified': 1, 'error': 1})}
>>> flat_rows([{"hash": "a", "params": {"eps": 0.5}, "outcome": "certified"}])[0]["param.eps"]
0.5
"""

from __future__ import annotations

import csv
import math
import os
from collections import Counter
from pathlib import Path
from typing import Any

from lmic.errors import DataError
from lmic.studies.tasks import OUTCOMES

__all__ = ["outcome_table", "print_table", "flat_rows", "export", "region_map", "status", "COLOURS"]

#: region-map colours by outcome
COLOURS = {
    "certified": "#2e9e44",
    "infeasible-certified": "#c0392b",
    "infeasible-bounded": "#f08a5d",
    "unbounded-certified": "#2874a6",
    "rejected": "#8e44ad",
    "undecided": "#bdbdbd",
    "error": "#222222",
}

_COLUMNS = [
    "hash",
    "task",
    "theorem",
    "system",
    "backend",
    "outcome",
    "status",
    "verdict",
    "objective",
    "min_margin",
    "sup_lower",
    "sup_upper",
    "sup_upper_kind",
    "time_s",
    "attempts",
    "worker",
    "finished_at",
    "certificate",
    "message",
]


def outcome_table(records: list[dict[str, Any]]) -> dict[tuple[str, str], Counter[str]]:
    """``(theorem, backend) -> Counter of outcomes``."""
    table: dict[tuple[str, str], Counter[str]] = {}
    for r in records:
        key = (str(r.get("theorem") or "-"), str(r.get("backend") or "default"))
        table.setdefault(key, Counter())[r.get("outcome", "error")] += 1
    return table


def print_table(records: list[dict[str, Any]], title: str = "outcomes", total: int | None = None) -> None:
    """The outcome table on stdout (rich)."""
    from rich.console import Console
    from rich.table import Table

    table = Table(title=title)
    table.add_column("theorem")
    table.add_column("backend")
    for o in OUTCOMES:
        table.add_column(o, justify="right")
    table.add_column("total", justify="right")
    rows = outcome_table(records)
    overall: Counter[str] = Counter()
    for (thm, be), counts in sorted(rows.items()):
        overall.update(counts)
        table.add_row(thm, be, *[str(counts.get(o, 0)) for o in OUTCOMES], str(sum(counts.values())))
    if len(rows) > 1:
        table.add_row("all", "", *[str(overall.get(o, 0)) for o in OUTCOMES], str(sum(overall.values())), style="bold")
    if total is not None and total > len(records):
        table.caption = f"{total - len(records)} of {total} jobs have no result yet"
    console = Console()
    if not console.is_terminal:  # a log file or a pipe: do not squeeze the columns to 80 characters
        console = Console(width=150)
    console.print(table)


def flat_rows(records: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """One flat dict per record: the fixed columns plus ``param.<name>`` columns."""
    names = sorted({k for r in records for k in (r.get("params") or {})})
    rows = []
    for r in records:
        row = {c: r.get(c) for c in _COLUMNS}
        for n in names:
            v = (r.get("params") or {}).get(n)
            row[f"param.{n}"] = v
        rows.append(row)
    return rows


def export(records: list[dict[str, Any]], path: str) -> str:
    """Write the records to ``path`` (``.csv`` or ``.parquet``), atomically; return the format.

    >>> import os, tempfile
    >>> p = os.path.join(tempfile.mkdtemp(), "r.csv")
    >>> export([{"hash": "a", "outcome": "certified", "params": {"eps": 0.5}}], p)
    'csv'
    >>> open(p).readline().strip().split(",")[-1]
    'param.eps'
    """
    from lmic.studies.store import write_atomic

    rows = flat_rows(records)
    suffix = Path(path).suffix.lower()
    if suffix == ".csv":
        columns = list(rows[0]) if rows else list(_COLUMNS)

        def write(fh: Any) -> None:
            w = csv.DictWriter(fh, fieldnames=columns)
            w.writeheader()
            w.writerows(rows)

        write_atomic(path, write)
        return "csv"
    if suffix in (".parquet", ".pq"):
        try:
            import pyarrow as pa  # type: ignore[import-untyped]
            import pyarrow.parquet as pq  # type: ignore[import-untyped]
        except ImportError:
            raise DataError(f'--export {path}: Parquet needs pyarrow (pip install "lmic[dask]")') from None
        for row in rows:  # one type per column: mixed numbers / option names become strings
            for k, v in row.items():
                if k.startswith("param.") and isinstance(v, str):
                    for other in rows:
                        if other.get(k) is not None:
                            other[k] = str(other[k])
        table = pa.Table.from_pylist(rows)
        write_atomic(path, lambda fh: pq.write_table(table, fh), mode="wb")
        return "parquet"
    raise DataError(f"--export {path}: use a .csv or .parquet file name")


def _axis_values(records: list[dict[str, Any]], name: str) -> list[Any]:
    vals = {(r.get("point") or {}).get(name) for r in records}
    vals.discard(None)
    try:
        return sorted(vals)
    except TypeError:
        return sorted(vals, key=str)


def region_map(
    records: list[dict[str, Any]], x: str, y: str | None, path: str, title: str = "", ylabel: str = ""
) -> str:
    """A PNG of the outcome over the grid: cells coloured by outcome (2-D), or the supremum curve.

    With ``y`` a grid axis, each cell is coloured by its most frequent outcome (cells with several
    systems or backends show the share of certified jobs in the cell). With ``y`` ``None`` and
    task ``maximize``, the largest value certified (a lower bound of the supremum) and the smallest
    value found not certified are drawn against ``x``.
    """
    import matplotlib

    from lmic.formatting import value_text

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    xs = _axis_values(records, x)
    fig, ax = plt.subplots(figsize=(7, 5), dpi=100)
    if y is not None:
        ys = _axis_values(records, y)
        cells: dict[tuple[int, int], Counter[str]] = {}
        xi, yi = {v: i for i, v in enumerate(xs)}, {v: i for i, v in enumerate(ys)}
        for r in records:
            pt = r.get("point") or {}
            if pt.get(x) in xi and pt.get(y) in yi:
                cells.setdefault((xi[pt[x]], yi[pt[y]]), Counter())[r.get("outcome", "error")] += 1
        import numpy as np

        grid = np.full((len(ys), len(xs)), np.nan)
        for (i, j), counts in cells.items():
            grid[j, i] = OUTCOMES.index(counts.most_common(1)[0][0])
        cmap = ListedColormap([COLOURS[o] for o in OUTCOMES])
        ax.imshow(
            grid, cmap=cmap, vmin=-0.5, vmax=len(OUTCOMES) - 0.5, origin="lower", aspect="auto", interpolation="nearest"
        )
        if any(sum(c.values()) > 1 for c in cells.values()) and len(cells) <= 400:
            for (i, j), counts in cells.items():
                share = counts.get("certified", 0) / sum(counts.values())
                ax.text(i, j, f"{share:.0%}", ha="center", va="center", fontsize=7, color="white")
        step_x, step_y = max(1, math.ceil(len(xs) / 8)), max(1, math.ceil(len(ys) / 12))
        ax.set_xticks(range(0, len(xs), step_x), [value_text(v, 3) for v in xs[::step_x]], rotation=45)
        ax.set_yticks(range(0, len(ys), step_y), [value_text(v, 3) for v in ys[::step_y]])
        ax.set_xlabel(x)
        ax.set_ylabel(y)
        present = [o for o in OUTCOMES if any(o in c for c in cells.values())]
        ax.legend(
            handles=[Patch(color=COLOURS[o], label=o) for o in present],
            loc="upper left",
            bbox_to_anchor=(1.01, 1.0),
            fontsize=8,
        )
    else:
        pts = sorted(
            ((r["point"][x], r.get("sup_lower"), r.get("sup_upper")) for r in records if x in (r.get("point") or {})),
            key=lambda t: t[0],
        )
        xv = [p[0] for p in pts]
        lo = [math.nan if p[1] is None else p[1] for p in pts]
        hi = [math.nan if p[2] is None else p[2] for p in pts]
        ax.plot(xv, lo, "o-", color=COLOURS["certified"], label="largest value certified (lower bound of the supremum)")
        ax.plot(xv, hi, "x--", color=COLOURS["infeasible-certified"], label="smallest value not certified")
        ax.set_xlabel(x)
        ax.set_ylabel(ylabel or "supremum")
        ax.legend(fontsize=8)
    ax.set_title(title or "lmic batch")
    fig.tight_layout()
    from lmic.studies.store import write_atomic

    write_atomic(path, lambda fh: fig.savefig(fh, format="png"), mode="wb")
    plt.close(fig)
    return path


def status(out_dir: str) -> dict[str, Any]:
    """Summary of a running or finished study folder (``lmic batch --status DIR``).

    >>> status("/nonexistent-study-dir")
    Traceback (most recent call last):
    ...
    lmic.errors.DataError: /nonexistent-study-dir: no such study folder
    """
    from lmic.studies.store import Store, read_results

    if not os.path.isdir(out_dir):
        raise DataError(f"{out_dir}: no such study folder")
    store = Store.__new__(Store)
    store.root = Path(out_dir)
    manifest = store.manifest()
    if manifest is None:
        raise DataError(f"{out_dir}: not a study folder (no study.json)")
    jobs = manifest.get("jobs", []) if isinstance(manifest, dict) else None
    if not isinstance(jobs, list) or not all(isinstance(j, dict) and isinstance(j.get("hash"), str) for j in jobs):
        raise DataError(f"{out_dir}: study.json is not a study manifest (edited or damaged?)")
    wanted = {j["hash"] for j in jobs}
    records = [r for r in read_results(Path(out_dir) / "results.jsonl") if r["hash"] in wanted]
    counts = Counter(r.get("outcome", "error") for r in records)
    return {
        "name": manifest.get("name"),
        "task": manifest.get("task"),
        "total": manifest["total"] if isinstance(manifest.get("total"), int) else len(wanted),
        "done": len(records),
        "counts": {o: counts.get(o, 0) for o in OUTCOMES},
        "running_pid": store.running_pid(),
        "last_finished": max((r.get("finished_at", "") for r in records), default=None),
        "records": records,
        "manifest": manifest,
    }
