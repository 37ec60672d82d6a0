"""``lmic batch STUDY.yaml -o DIR``: run a study; ``lmic batch --status DIR``: summarise one.

Forms::

    lmic batch STUDY.yaml -o DIR [--executor local|dask|tcp://HOST:PORT] [--workers N]
                                 [--export FILE.csv|FILE.parquet] [--map FILE.png] [--no-progress]
    lmic batch --status DIR [--json]

The study file is validated and expanded into jobs before any job runs (a bad study file is
one line and exit code 2). Results go to ``DIR/results.jsonl`` (one line per job), certificates
to ``DIR/certificates/``; a re-run skips the jobs already done. At the end: the table of
outcomes by theorem and backend, the region map ``DIR/map.png`` for a two-axis grid (or the
supremum curve of a ``maximize`` study over a one-axis grid), and the export if asked.

Exit codes: 0 every job has a result and none crashed (whatever the verdicts: a study reports
them, it does not fail on them); 1 some job ended in ``error``; 2 bad input; 130 interrupted.

Examples
--------
>>> import argparse
>>> parser = argparse.ArgumentParser(); sub = parser.add_subparsers()
>>> register(sub)
>>> args = parser.parse_args(["batch", "s.yaml", "-o", "out", "--executor", "dask", "--workers", "2"])
>>> args.executor, args.workers
('dask', 2)
"""

from __future__ import annotations

import argparse
import os
import sys
from typing import Any

__all__ = ["register", "run"]


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``batch`` sub-command."""
    from lmic.commands._common import add_executor_options

    p = sub.add_parser(
        "batch",
        help="run a study (many theorems x systems x parameters x backends) on local cores or a Dask cluster",
        description="lmic batch STUDY.yaml -o DIR [--executor local|dask|tcp://HOST:PORT] | lmic batch --status DIR",
    )
    p.add_argument("study", nargs="?", default=None, help="study file (YAML or JSON, schemas/study.schema.json)")
    p.add_argument("-o", "--output", default=None, metavar="DIR", help="output folder (results.jsonl, certificates/)")
    add_executor_options(p, "the jobs", default="local")
    p.add_argument("--export", default=None, metavar="FILE", help="also write the results as .csv or .parquet")
    p.add_argument("--map", default=None, metavar="PNG", help="region map file (default DIR/map.png when it applies)")
    p.add_argument("--status", default=None, metavar="DIR", help="summarise a running or finished study folder")
    p.add_argument("--json", action="store_true", help="print the summary as one JSON object")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def _status(args: argparse.Namespace) -> int:
    from lmic.commands._common import print_json
    from lmic.studies.report import print_table, status

    st = status(args.status)
    if args.json:
        print_json({k: v for k, v in st.items() if k not in ("records", "manifest")})
        return 0
    running = f"running (pid {st['running_pid']})" if st["running_pid"] else "not running"
    sys.stdout.write(
        f"{st['name']}: task {st['task']}, {st['done']} of {st['total']} jobs done, {running}"
        f"{'; last result ' + st['last_finished'] if st['last_finished'] else ''}\n"
    )
    print_table(st["records"], title=f"{st['name']}: outcomes", total=st["total"])
    return 0


def _draw_map(study: Any, records: list[dict[str, Any]], path: str) -> str | None:
    from lmic.studies.report import region_map

    if study.map_axes:
        return region_map(records, study.map_axes[0], study.map_axes[1], path, title=study.name)
    if study.task == "maximize" and len(study.grid_axes) == 1:
        return region_map(
            records,
            study.grid_axes[0],
            None,
            path,
            title=study.name,
            ylabel=f"sup {study.maximize['param']}",
        )
    return None


def run(args: argparse.Namespace) -> int:
    """Validate, run (or resume), report."""
    from lmic.errors import DataError

    if args.status:
        if args.study or args.output or args.export or args.map:
            raise DataError(
                "--status DIR takes no study file, -o, --export or --map (to export or map a finished study, "
                "run it again: lmic batch STUDY.yaml -o DIR --export FILE; nothing is solved twice)"
            )
        return _status(args)
    if not args.study:
        raise DataError("give a study file: lmic batch STUDY.yaml -o DIR (or lmic batch --status DIR)")
    if not args.output:
        raise DataError("give the output folder: lmic batch STUDY.yaml -o DIR")
    from lmic.commands._common import check_executor_args, print_json

    check_executor_args(args)
    if args.export and os.path.splitext(args.export)[1].lower() not in (".csv", ".parquet", ".pq"):
        raise DataError(f"--export {args.export}: use a .csv or .parquet file name")
    if args.map and os.path.splitext(args.map)[1].lower() != ".png":
        raise DataError(f"--map {args.map}: the map is a PNG image: use a .png file name")
    from lmic.output import check_output_path

    for path in (args.export, args.map):
        if path:
            check_output_path(path)  # a folder, a missing folder, ...: before any job runs
    from lmic.studies.driver import run_study
    from lmic.studies.report import export, print_table
    from lmic.studies.spec import load_study

    # The local pool's job runners start first: each imports lmic (about a second) while this
    # process loads and checks the study. They write nothing; a study that fails its checks
    # stops them again (bad input: exit 2, nothing written).
    executor: Any = args.executor
    if args.executor == "local":
        from lmic.studies.executors import LocalExecutor

        executor = LocalExecutor(args.workers)
    try:
        study = load_study(args.study)  # every check before any job runs
        if os.path.exists(args.output) and not os.path.isdir(args.output):
            raise DataError(f"-o {args.output}: exists and is not a folder")
    except BaseException:
        if not isinstance(executor, str):
            executor.close()
        raise
    try:
        summary = run_study(
            study,
            args.output,
            executor=executor,
            workers=args.workers,
            progress=not (args.no_progress or args.json),
        )
    except KeyboardInterrupt:
        sys.stderr.write("lmic: interrupted (finished results are kept; run again to resume)\n")
        return 130
    map_path = _draw_map(study, summary.records, args.map or os.path.join(args.output, "map.png"))
    if args.export:
        export(summary.records, args.export)
    if args.json:
        print_json(
            {
                "name": study.name,
                "total": summary.total,
                "skipped": summary.skipped,
                "ran": summary.ran,
                "counts": dict(summary.counts),
                "elapsed_s": summary.elapsed_s,
                "executor": summary.executor,
                "map": map_path,
                "export": args.export,
                "exit_code": summary.exit_code(),
            }
        )
        return summary.exit_code()
    rate = f", {summary.ran / summary.elapsed_s:.2f} jobs/s" if summary.ran and summary.elapsed_s else ""
    dup = f", {study.duplicates} duplicate jobs merged" if study.duplicates else ""
    sys.stdout.write(
        f"{study.name}: {summary.total} jobs, {summary.skipped} already done, {summary.ran} run in "
        f"{summary.elapsed_s:.1f} s on {summary.executor or 'no executor'}{rate}{dup}\n"
    )
    print_table(summary.records, title=f"{study.name}: outcomes", total=summary.total)
    sys.stdout.write(f"results: {os.path.join(args.output, 'results.jsonl')}\n")
    if map_path:
        sys.stdout.write(f"map: {map_path}\n")
    if args.export:
        sys.stdout.write(f"export: {args.export}\n")
    return summary.exit_code()
