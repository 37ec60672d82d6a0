"""``lmic crosscheck THEOREM SYSTEM | FILE [--backends a,b,...] [--json]``.

Decides one problem on each backend alone (one row per backend with its decision) and says
whether the decisions agree (:mod:`lmic.crosscheck`). Failed or undecided backends are listed
and counted as failures, not as disagreement. Exit code: 0 when at least one backend decided
and no two decisions conflict, 1 on a conflict (or when no backend decided), 2 for bad input.

``--executor local|dask|tcp://HOST:PORT`` (``--workers N``) runs one job per backend on the
study executors (:func:`lmic.studies.parallel.crosscheck_parallel`), with the same rows and
decisions; without it the backends run one after the other in this process.
"""

from __future__ import annotations

import argparse
import contextlib
from collections.abc import Iterator
from typing import Any

__all__ = ["register", "run"]


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``crosscheck`` sub-command."""
    from lmic.commands._common import add_executor_options, add_param_option
    from lmic.commands.solve import add_solver_options

    p = sub.add_parser("crosscheck", help="solve one problem on several backends and compare")
    p.add_argument("target", help="theorem id, or an IR (.json) / SDPA (.dat-s) file")
    p.add_argument("system", nargs="?", default=None, help="system file (with a theorem)")
    add_param_option(p)
    p.add_argument("--backends", default=None, help="comma-separated backends (default: every available one)")
    p.add_argument("--rtol", type=float, default=None, help="objective agreement tolerance")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    add_executor_options(p, "the backends")
    add_solver_options(p)
    p.set_defaults(func=run)


@contextlib.contextmanager
def _progress_bar(enabled: bool) -> Iterator[Any]:
    """A progress bar on stderr (one step per backend, gone when done; a log line per backend when
    stderr is not a terminal); ``None`` if off."""
    if not enabled:
        yield None
        return
    from lmic.progressbar import ProgressBar

    with ProgressBar("crosscheck", transient=True, log=True) as bar:

        def update(done: int, total: int, name: str, row: dict | None) -> None:
            if row is None:
                bar.update(completed=done, total=total, description=f"solving with {name}")
            else:
                text = f"{name}: {row['status']}, {row['decision']}"
                bar.update(completed=done, total=total, description=text, line=f"[{done}/{total}] {text}")

        yield update


def run(args: argparse.Namespace) -> int:
    """Cross-check and print the table (or JSON)."""
    from lmic.commands._common import backend_names, check_executor_args, parse_params, print_json, solve_options
    from lmic.formatting import value_text
    from lmic.studies.crosscheck import DECISIONS, DEFAULT_RTOL, check_rtol, crosscheck

    names = backend_names(args.backends)
    if args.rtol is not None:
        check_rtol(args.rtol)
    params = parse_params(args.param)
    check_executor_args(args)
    with _progress_bar(enabled=not args.json) as progress:
        if args.executor:  # one job per backend (lmic.studies.parallel)
            from lmic.studies.parallel import crosscheck_parallel

            report = crosscheck_parallel(
                args.target,
                args.system,
                params=params or None,
                backends=names,
                options=solve_options(args),
                rtol=args.rtol,
                executor=args.executor,
                workers=args.workers,
                progress=progress,
            )
        else:
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
    table.add_column("decision", no_wrap=True)
    table.add_column("strict: margin", no_wrap=True)
    table.add_column("min margin", justify="right", no_wrap=True)
    if with_objective:
        table.add_column("proven optimum", justify="right", no_wrap=True)
    table.add_column("time (s)", justify="right", no_wrap=True)
    for r in report.results:
        colour = {
            "certified": "green",
            "infeasible-certified": "green",
            "infeasible-bounded": "cyan",
            "rejected": "red",
        }.get(r["decision"], "yellow")
        strategy = r.get("strategy")
        strict = f"{strategy}: {value_text(r.get('margin'), spec='.3g')}" if strategy not in (None, "none") else "-"
        cells = [r["backend"], r["status"]]
        if with_objective:
            cells.append(value_text(r["objective"], spec=".8g"))
        decision = r["decision"]
        if decision == "infeasible-bounded" and r.get("radius") is not None:
            decision += f" (R = {r['radius']:.3g})"
        cells += [
            f"[{colour}]{decision}[/{colour}]",
            strict,
            value_text(r["min_margin"], spec=".3g"),
        ]
        if with_objective:  # the backend's proven enclosure of the optimal value
            cells.append(_interval(r.get("lower"), r.get("upper")))
        cells.append(value_text(r.get("time_s", r["solve_s"]), spec=".3f"))
        table.add_row(*cells)
    console = Console(soft_wrap=True)
    if not console.is_terminal:
        console.width = 160
    console.print(table)
    gap = report.max_rel_objective_gap
    if report.agree:
        verdict = "[green]agree[/green]"
    elif report.conflicts:
        verdict = "[red]conflict[/red]"
    else:
        verdict = "[yellow]no decision[/yellow]"
    console.print(
        f"{verdict}: {report.decisions} decision(s), {report.failures} failure(s); "
        f"max relative gap of certified optima {value_text(gap, spec='.2e')} (rtol {report.rtol:g})"
    )
    lo, hi = report.enclosure
    if with_objective and (lo is not None or hi is not None):
        console.print(f"  every proven enclosure together: optimum in {_interval(lo, hi)}", markup=False)
    for c in report.conflicts:
        console.print(f"  conflict: {c}", markup=False)
    for r in report.results:
        if r["decision"] not in DECISIONS:
            console.print(f"  failure {r['backend']}: {r['decision']}: {r.get('message') or r['status']}", markup=False)
    return report.exit_code()


def _interval(lo: float | None, hi: float | None) -> str:
    """``[lo, hi]`` with 10 significant digits, ``-`` for a missing end, ``-`` for neither.

    >>> _interval(1.0, 2.5), _interval(None, 2.0), _interval(None, None)
    ('[1, 2.5]', '[-, 2]', '-')
    """
    if lo is None and hi is None:
        return "-"
    return "[" + ", ".join("-" if v is None else f"{v:.10g}" for v in (lo, hi)) + "]"
