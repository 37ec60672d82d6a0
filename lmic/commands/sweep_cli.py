"""``lmic solve --maximize`` / ``--sweep``: options, progress bar and printing (:mod:`lmic.sweep` computes).

Examples
--------
>>> import argparse
>>> p = argparse.ArgumentParser()
>>> add_cli_options(p)
>>> p.parse_args(["--maximize", "gamma"]).maximize
'gamma'
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

from lmic.errors import LmicError
from lmic.sweep import PointResult, SupResult, SweepResult, maximize, parse_grid, sweep

__all__ = ["add_cli_options", "run_cli"]


def add_cli_options(p: argparse.ArgumentParser) -> None:
    """``--maximize PARAM [--lo a --hi b --xtol t --rtol r --max-evals k]`` and ``--sweep P=a:b:n``."""
    g = p.add_argument_group("supremum and sweep (a theorem's scalar parameter)")
    g.add_argument(
        "--maximize", metavar="PARAM", default=None, help="supremum of PARAM by bisection on certified feasibility"
    )
    g.add_argument("--lo", type=float, default=None, help="lower end of the bracket (certified)")
    g.add_argument("--hi", type=float, default=None, help="upper end of the bracket (not certified)")
    g.add_argument("--xtol", type=float, default=1e-6, help="absolute tolerance on PARAM (default 1e-6)")
    g.add_argument("--rtol", type=float, default=1e-5, help="relative tolerance on PARAM (default 1e-5)")
    g.add_argument("--max-evals", type=int, default=100, help="at most this many points (default 100)")
    g.add_argument(
        "--sweep",
        metavar="PARAM=a:b:n",
        default=None,
        help="grid over PARAM (linear, or log:a:b:n geometric); best certified point",
    )
    g.add_argument("--no-progress", action="store_true", help="no progress bar")


def _fmt(v: Any, digits: int = 7) -> str:
    if v is None:
        return "-"
    if isinstance(v, float):
        return f"{v:.{digits}g}"
    return str(v)


class _Bar:
    """A rich progress bar on stderr (silent when stderr is not a terminal)."""

    def __init__(self, title: str, enabled: bool) -> None:
        from rich.console import Console
        from rich.progress import BarColumn, MofNCompleteColumn, Progress, SpinnerColumn, TextColumn, TimeElapsedColumn

        console = Console(stderr=True)
        self.progress = Progress(
            SpinnerColumn(),
            TextColumn("[bold]{task.description}"),
            BarColumn(),
            MofNCompleteColumn(),
            TimeElapsedColumn(),
            TextColumn("{task.fields[info]}"),
            console=console,
            transient=False,
            disable=not (enabled and console.is_terminal),
        )
        self.task = self.progress.add_task(title, total=None, info="")

    def __enter__(self) -> _Bar:
        self.progress.__enter__()
        return self

    def __exit__(self, *exc: Any) -> None:
        self.progress.__exit__(*exc)

    def __call__(self, ev: dict[str, Any]) -> None:
        pt: PointResult = ev["point"]
        mark = {"feasible": "[green]certified", "infeasible": "[red]infeasible"}.get(pt.outcome, "[yellow]undecided")
        if ev["phase"] == "sweep":
            info = f"{_fmt(pt.value)}: {mark}[/]"
            self.progress.update(self.task, total=ev.get("total"), completed=ev.get("iteration", 0), info=info)
            return
        lo, hi = ev.get("lower"), ev.get("upper")
        info = f"[{_fmt(lo)}, {_fmt(hi)}]  last {_fmt(pt.value)}: {mark}[/]"
        desc = "bracketing" if ev["phase"] == "bracket" else "bisection"
        self.progress.update(
            self.task, description=desc, total=ev.get("total"), completed=ev.get("iteration", 0), info=info
        )


def run_cli(args: argparse.Namespace) -> int:
    """Run ``lmic solve THEOREM SYSTEM --maximize P`` or ``--sweep P=a:b:n``; return the exit code."""
    from lmic.commands._common import parse_params, print_json, solve_options

    if args.maximize and args.sweep:
        raise LmicError("give --maximize or --sweep, not both")
    if args.system is None:
        raise LmicError("--maximize and --sweep need THEOREM SYSTEM (a theorem and its system file)")
    if getattr(args, "output", None):
        raise LmicError("-o is not available with --maximize / --sweep (use --json for the full record)")
    if getattr(args, "exact", False):
        sys.stderr.write("lmic: note: exact proofs are used automatically where float margins are too small\n")
    params = parse_params(args.param)
    opts = solve_options(args)
    show = not args.json and not args.no_progress
    if args.maximize:
        with _Bar(f"sup {args.maximize}", show) as bar:
            res = maximize(
                args.target,
                args.system,
                args.maximize,
                lo=args.lo,
                hi=args.hi,
                xtol=args.xtol,
                rtol=args.rtol,
                params=params,
                backend=args.backend,
                options=opts,
                max_evals=args.max_evals,
                progress=bar,
            )
        if args.json:
            print_json(res.to_dict())
        else:
            _print_sup(res)
        return res.exit_code()
    name, values = parse_grid(args.sweep)
    with _Bar(f"sweep {name}", show) as bar:
        sw = sweep(
            args.target,
            args.system,
            name,
            values,
            params=params,
            backend=args.backend,
            options=opts,
            progress=bar,
        )
    if args.json:
        print_json(sw.to_dict())
    else:
        _print_sweep(sw)
    return sw.exit_code()


def _print_sup(r: SupResult) -> None:
    from rich.console import Console

    out = Console(highlight=False, soft_wrap=True)
    if not out.is_terminal:
        out.width = 160
    out.print(f"theorem    {r.theorem}   sup {r.param} (bisection on certified feasibility, backend {r.backend})")
    tol = f"xtol {r.xtol:g}, rtol {r.rtol:g}"
    if r.lower is None:
        out.print(f"[red]no certified value of {r.param}[/]: {r.message}")
    else:
        if r.upper_kind == "infeasible-certified":
            out.print(f"[bold]sup {r.param} in [{_fmt(r.lower, 10)}, {_fmt(r.upper, 10)}][/]   ({tol})")
        elif r.upper_proven is not None:
            out.print(f"[bold]sup {r.param} in [{_fmt(r.lower, 10)}, {_fmt(r.upper_proven, 10)}][/]   (proven ends)")
        else:
            out.print(
                f"[bold]sup {r.param} >= {_fmt(r.lower, 10)}[/]   (no proven upper end: may be larger, even infinite)"
            )
        lower_pt = next((p for p in r.points if p.value == r.lower and p.outcome == "feasible"), None)
        how = lower_pt.proof if lower_pt else "certified"
        out.print(f"  lower    {_fmt(r.lower, 10)}  {how}")
        if r.upper is not None:
            kind = {
                "undecided": "not certified (neither certified nor proven infeasible): not an upper bound",
                "infeasible-bounded": "infeasible-bounded (no solution with ||x||_inf <= R only): not an upper bound",
                "infeasible-certified": "infeasible-certified (global proof)",
            }.get(r.upper_kind, r.upper_kind)
            out.print(f"  bisection upper {_fmt(r.upper, 10)}  {kind}")
        if r.upper_proven is not None and r.upper_proven != r.upper:
            out.print(f"  proven infeasible (global) from {_fmt(r.upper_proven, 10)}")
    if r.message:
        out.print(f"  note     {r.message}")
    binds = [p.bind_s for p in r.points]
    out.print(
        f"  {r.iterations} bisection steps, {len(r.points)} points, {r.total_s:.2f} s "
        f"(analysis once {r.plan_s * 1e3:.0f} ms, re-bind {1e3 * sum(binds) / max(len(binds), 1):.1f} ms a point, "
        f"solve {sum(p.solve_s for p in r.points):.2f} s, certify {sum(p.certify_s for p in r.points):.2f} s)"
    )


def _print_sweep(r: SweepResult) -> None:
    from rich.console import Console
    from rich.table import Table

    out = Console(highlight=False, soft_wrap=True)
    if not out.is_terminal:
        out.width = 160
    table = Table(title=f"{r.theorem}: sweep of {r.param} (backend {r.backend})")
    for col in (r.param, "outcome", "status", "verdict", "objective", "rel. margin", "how", "bind ms", "solve s"):
        table.add_column(col)
    for p in r.points:
        star = " *" if p is r.best else ""
        table.add_row(
            _fmt(p.value) + star,
            p.outcome,
            p.status,
            p.verdict,
            _fmt(p.objective),
            _fmt(p.rel_margin, 3),
            p.proof[:60],
            f"{1e3 * p.bind_s:.1f}",
            f"{p.solve_s:.3f}",
        )
    out.print(table)
    if r.best is None:
        out.print(f"no certified point on the grid of {r.param}")
    else:
        what = (
            "objective " + _fmt(r.best.objective)
            if r.sense in ("min", "max")
            else "relative margin " + _fmt(r.best.rel_margin, 3)
        )
        if r.best_rule == "edge of the certified range":
            what = f"the edge of the certified range; {what}"
        out.print(f"best certified point: {r.param} = {_fmt(r.best.value)} ({what})")
    binds = [p.bind_s for p in r.points]
    out.print(
        f"{len(r.points)} points, {r.total_s:.2f} s (analysis once {r.plan_s * 1e3:.0f} ms, "
        f"re-bind {1e3 * sum(binds) / max(len(binds), 1):.1f} ms a point)"
    )
