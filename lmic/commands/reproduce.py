"""``lmic reproduce [--json] [-o docs/reproduction.md] [--only PATTERN]...``: run the shipped examples.

Every example file ``examples/<family>.<item>.<name>.yaml`` is run against its expectations in
``examples/reproduction.yaml`` (:mod:`lmic.reproduce`): published value, computed value, verdict,
the catalogue's reference value and, where they differ, its explanation. ``-o`` writes the
Markdown table (``docs/reproduction.md`` is generated this way).

Exit codes: 0 every row agrees with its expectation; 1 some row does not; 2 bad input (no
examples folder, a malformed expectations file).

Examples
--------
>>> import argparse
>>> parser = argparse.ArgumentParser(); sub = parser.add_subparsers()
>>> register(sub)
>>> parser.parse_args(["reproduce", "--only", "qib.*", "--only", "thesis.*"]).only
['qib.*', 'thesis.*']
"""

from __future__ import annotations

import argparse
from typing import Any

__all__ = ["register", "run"]


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``reproduce`` sub-command."""
    from lmic.commands._common import add_executor_options
    from lmic.commands.solve import add_solver_options

    p = sub.add_parser(
        "reproduce",
        help="run every shipped example against the papers and the catalogues; write docs/reproduction.md",
        description="lmic reproduce [--json] [-o docs/reproduction.md] [--only PATTERN]...",
    )
    p.add_argument("--examples", default=None, help="examples folder (default ./examples)")
    p.add_argument("--expectations", default=None, help="expectations file (default EXAMPLES/reproduction.yaml)")
    p.add_argument(
        "--only",
        action="append",
        default=[],
        metavar="PATTERN",
        help="only example files matching this glob (repeatable)",
    )
    p.add_argument("--backend", "-b", default="auto", help="backend alone (default auto: the escalating policy)")
    p.add_argument("-o", "--output", default=None, help="write the Markdown table here")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_executor_options(p, "the example files")
    add_solver_options(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run, report, optionally write the Markdown file."""
    from rich.console import Console
    from rich.table import Table

    from lmic.commands._common import check_executor_args, print_json, solve_options, write_atomic

    check_executor_args(args)
    from lmic.present.reproduction import render_markdown
    from lmic.progressbar import ProgressBar
    from lmic.studies.reproduce import reproduce

    if args.output:
        from lmic.output import check_output_path

        check_output_path(args.output)  # before any work
    with ProgressBar("reproduce", enabled=not (args.json or args.no_progress)) as bar:

        def progress(ev: dict[str, Any]) -> None:
            row = ev["row"]
            mark = "[green]ok[/]" if row.ok else "[red]differs[/]"
            bar.update(total=ev["total"], completed=ev["done"], info=f"{ev['file']}: {row.row.quantity[:40]} {mark}")

        if args.executor:  # one job per example file (lmic.studies.parallel)
            from lmic.studies.parallel import reproduce_parallel

            keys = ("tol", "max_iter", "time_limit", "margin", "strict", "verbose")
            report = reproduce_parallel(
                args.examples,
                args.expectations,
                only=args.only,
                backend=args.backend,
                options={k: getattr(args, k) for k in keys if getattr(args, k, None) not in (None, False)},
                executor=args.executor,
                workers=args.workers,
                progress=progress,
            )
        else:
            report = reproduce(
                args.examples,
                args.expectations,
                only=args.only,
                backend=args.backend,
                options=solve_options(args),
                progress=progress,
            )
    if args.output:
        command = "lmic reproduce -o " + args.output + "".join(f" --only '{p}'" for p in args.only)
        text = render_markdown(report, command=command)
        write_atomic(args.output, lambda fh: fh.write(text))
    if args.json:
        print_json(report.to_dict())
        return report.exit_code()
    out = Console(highlight=False, soft_wrap=True)
    if not out.is_terminal:
        out.width = 160
    table = Table(title=f"reproduction ({report.backend})")
    for col in ("example", "quantity", "published", "computed", "verdict", "reference", "ok"):
        table.add_column(col)
    for r in report.results:
        verdict = r.finding if r.finding == r.row.verdict else f"{r.finding} (expected {r.row.verdict})"
        ref = "-" if r.row.reference is None else str(r.row.reference)
        table.add_row(
            r.row.file,
            r.row.quantity,
            str(r.row.published if r.row.published is not None else "-"),
            r.text,
            verdict,
            ref,
            "[green]yes[/]" if r.ok else "[red]no[/]",
        )
    out.print(table)
    agree = sum(r.ok for r in report.results)
    out.print(f"{agree} of {len(report.results)} rows agree; {report.total_s:.1f} s")
    if report.missing:
        out.print(f"[red]missing example files[/]: {', '.join(report.missing)}")
    if report.unlisted:
        out.print(f"examples without expectations: {', '.join(report.unlisted)}")
    if args.output:
        out.print(f"wrote {args.output}")
    return report.exit_code()
