"""``lmic crosscheck THEOREM SYSTEM | FILE [--backends a,b,...] [--json]``.

Solves one problem on several backends, certifies each answer and says whether they agree.
Exit code: 0 when they agree and every answer is certified, 3 when they agree the problem is
infeasible, 1 otherwise, 2 for bad input.
"""

from __future__ import annotations

import argparse
import contextlib
from collections.abc import Iterator
from typing import Any

__all__ = ["register", "run"]


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``crosscheck`` sub-command."""
    from lmic.commands._common import add_param_option
    from lmic.commands.solve import add_solver_options

    p = sub.add_parser("crosscheck", help="solve one problem on several backends and compare")
    p.add_argument("target", help="theorem id, or an IR (.json) / SDPA (.dat-s) file")
    p.add_argument("system", nargs="?", default=None, help="system file (with a theorem)")
    add_param_option(p)
    p.add_argument("--backends", default=None, help="comma-separated backends (default: every available one)")
    p.add_argument("--rtol", type=float, default=None, help="objective agreement tolerance")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    add_solver_options(p)
    p.set_defaults(func=run)


def _fmt(v: Any, spec: str = ".6g") -> str:
    return "-" if v is None else format(v, spec)


@contextlib.contextmanager
def _progress_bar(enabled: bool) -> Iterator[Any]:
    """A rich progress bar on stderr (one step per backend, gone when done); ``None`` if off."""
    if not enabled:
        yield None
        return
    import sys

    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    console = Console(stderr=True)
    if not console.is_terminal:  # a log: one line per backend instead of a redrawn bar

        def log(done: int, total: int, name: str, row: dict | None) -> None:
            if row is not None:
                sys.stderr.write(f"[{done}/{total}] {name}: {row['status']}, {row['verdict']}\n")
                sys.stderr.flush()

        yield log
        return
    bar = Progress(
        TextColumn("{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        console=console,
        transient=True,
    )
    task = None

    def update(done: int, total: int, name: str, row: dict | None) -> None:
        nonlocal task
        if task is None:
            task = bar.add_task("crosscheck", total=total)
        if row is None:
            bar.update(task, completed=done, description=f"solving with {name}")
        else:
            bar.update(task, completed=done, description=f"{name}: {row['status']}, {row['verdict']}")

    with bar:
        yield update


def run(args: argparse.Namespace) -> int:
    """Cross-check and print the table (or JSON)."""
    from lmic.backends.registry import get_backend
    from lmic.commands._common import parse_params, print_json
    from lmic.commands.solve import solve_options
    from lmic.crosscheck import DEFAULT_RTOL, crosscheck

    names = [b.strip() for b in args.backends.split(",") if b.strip()] if args.backends else None
    for name in names or []:
        get_backend(name)  # an unknown or missing backend is bad input (exit 2)
    params = parse_params(args.param)
    with _progress_bar(enabled=not args.json) as progress:
        report = crosscheck(
            args.target,
            system=args.system,
            params=params or None,
            backends=names,
            options=solve_options(args),
            rtol=args.rtol if args.rtol is not None else DEFAULT_RTOL,
            progress=progress,
        )
    if args.json:
        print_json(report.to_dict())
        return report.exit_code()
    from rich.console import Console
    from rich.table import Table

    table = Table(title=f"crosscheck {report.target}")
    with_objective = any(r["objective"] is not None for r in report.results)
    table.add_column("backend", no_wrap=True)
    table.add_column("status", no_wrap=True)
    if with_objective:
        table.add_column("objective", justify="right", no_wrap=True)
    table.add_column("verdict", no_wrap=True)
    table.add_column("strict: margin", no_wrap=True)
    table.add_column("min margin", justify="right", no_wrap=True)
    table.add_column("time (s)", justify="right", no_wrap=True)
    for r in report.results:
        colour = {"certified": "green", "infeasible-certified": "green", "rejected": "red"}.get(r["verdict"], "yellow")
        strategy = r.get("strategy")
        strict = f"{strategy}: {_fmt(r.get('margin'), '.3g')}" if strategy not in (None, "none") else "-"
        cells = [r["backend"], r["status"]]
        if with_objective:
            cells.append(_fmt(r["objective"], ".8g"))
        cells += [
            f"[{colour}]{r['verdict']}[/{colour}]",
            strict,
            _fmt(r["min_margin"], ".3g"),
            _fmt(r["solve_s"], ".3f"),
        ]
        table.add_row(*cells)
    console = Console(soft_wrap=True)
    if not console.is_terminal:
        console.width = 160
    console.print(table)
    gap = report.max_rel_objective_gap
    verdict = "[green]agree[/green]" if report.agree else "[red]disagree[/red]"
    console.print(f"{verdict}; max relative objective gap {_fmt(gap, '.2e')} (rtol {report.rtol:g})")
    for r in report.results:
        if r.get("message") and r["status"] in ("error", "inaccurate"):
            console.print(f"  {r['backend']}: {r['message']}", markup=False)
    return report.exit_code()
