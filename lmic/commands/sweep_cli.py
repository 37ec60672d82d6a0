"""``lmic solve --maximize`` / ``--sweep``: options, progress bar and printing (:mod:`lmic.studies.sweep` computes).

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
import math
import sys
from typing import TYPE_CHECKING, Any

from lmic.errors import LmicError

if TYPE_CHECKING:  # lmic.studies.sweep (numpy, solvers) is imported by run_cli: the parser stays light
    from lmic.studies.sweep import PointResult, SupResult, SweepResult

__all__ = ["add_cli_options", "run_cli"]


def add_cli_options(p: argparse.ArgumentParser) -> None:
    """``--maximize|--minimize PARAM [--lo a --hi b --xtol t --rtol r --max-evals k]``, ``--sweep P=a:b:n``."""
    g = p.add_argument_group("supremum and sweep (a theorem's scalar parameter)")
    g.add_argument(
        "--maximize", metavar="PARAM", default=None, help="supremum of PARAM by bisection on certified feasibility"
    )
    g.add_argument(
        "--minimize", metavar="PARAM", default=None, help="infimum of PARAM by bisection on certified feasibility"
    )
    g.add_argument(
        "--lo",
        type=float,
        default=None,
        help="lower end of the bracket (certified with --maximize, not with --minimize)",
    )
    g.add_argument(
        "--hi",
        type=float,
        default=None,
        help="upper end of the bracket (certified with --minimize, not with --maximize)",
    )
    g.add_argument("--xtol", type=float, default=1e-6, help="absolute tolerance on PARAM (default 1e-6)")
    g.add_argument("--rtol", type=float, default=1e-5, help="relative tolerance on PARAM (default 1e-5)")
    g.add_argument("--max-evals", type=int, default=100, help="at most this many points (default 100)")
    g.add_argument(
        "--method",
        choices=("auto", "enclosure", "bisection"),
        default="auto",
        help="auto (default): where PARAM enters the LMIs affinely, one convex solve and the enclosure of its "
        "optimum; else bisection",
    )
    g.add_argument(
        "--sweep",
        metavar="PARAM=a:b:n",
        default=None,
        help="grid over PARAM (linear, or log:a:b:n geometric); best certified point",
    )
    g.add_argument("--no-progress", action="store_true", help="no progress bar")


class _Bar:
    """The progress of a bisection or a sweep (:class:`lmic.progressbar.ProgressBar`, with a spinner)."""

    def __init__(self, title: str, enabled: bool) -> None:
        from lmic.progressbar import ProgressBar

        self.bar = ProgressBar(title, enabled=enabled, spinner=True)

    def __enter__(self) -> _Bar:
        self.bar.__enter__()
        return self

    def __exit__(self, *exc: Any) -> None:
        self.bar.__exit__(*exc)

    def __call__(self, ev: dict[str, Any]) -> None:
        from lmic.formatting import value_text

        pt: PointResult = ev["point"]
        mark = {"feasible": "[green]certified", "infeasible": "[red]infeasible"}.get(pt.outcome, "[yellow]undecided")
        if ev["phase"] == "sweep":
            info = f"{value_text(pt.value, 7)}: {mark}[/]"
            self.bar.update(total=ev.get("total"), completed=ev.get("iteration", 0), info=info)
            return
        lo, hi = ev.get("lower"), ev.get("upper")
        info = f"[{value_text(lo, 7)}, {value_text(hi, 7)}]  last {value_text(pt.value, 7)}: {mark}[/]"
        desc = "bracketing" if ev["phase"] == "bracket" else "bisection"
        self.bar.update(description=desc, total=ev.get("total"), completed=ev.get("iteration", 0), info=info)


def run_cli(args: argparse.Namespace) -> int:
    """Run ``lmic solve THEOREM SYSTEM --maximize P`` or ``--sweep P=a:b:n``; return the exit code."""
    from lmic.commands._common import parse_params, print_json, solve_options
    from lmic.studies.sweep import maximize, minimize, parse_grid, sweep, write_end_certificate

    if sum(bool(a) for a in (args.maximize, args.minimize, args.sweep)) > 1:
        raise LmicError("give one of --maximize, --minimize, --sweep")
    if args.system is None:
        raise LmicError("--maximize, --minimize and --sweep need THEOREM SYSTEM (a theorem and its system file)")
    if getattr(args, "output", None) and args.sweep:
        raise LmicError("-o is not available with --sweep (use --json for the full record)")
    for flag, value in (("--xtol", args.xtol), ("--rtol", args.rtol)):
        if not (math.isfinite(value) and value >= 0):
            raise LmicError(f"{flag} {value}: give a non-negative number")
    if args.max_evals < 1:
        raise LmicError(f"--max-evals {args.max_evals}: give at least 1")
    if getattr(args, "exact", False):
        sys.stderr.write("lmic: note: exact proofs are used automatically where float margins are too small\n")
    params = parse_params(args.param)
    opts = solve_options(args)
    show = not args.json and not args.no_progress
    if args.maximize or args.minimize:
        name = args.maximize or args.minimize
        run = maximize if args.maximize else minimize
        with _Bar(f"{'sup' if args.maximize else 'inf'} {name}", show) as bar:
            res = run(
                args.target,
                args.system,
                name,
                lo=args.lo,
                hi=args.hi,
                xtol=args.xtol,
                rtol=args.rtol,
                params=params,
                backend=args.backend,
                options=opts,
                max_evals=args.max_evals,
                progress=bar,
                backoff=getattr(args, "backoff", None),
                method=getattr(args, "method", "auto"),
            )
        written = None
        if getattr(args, "output", None):
            if res.end is not None:
                write_end_certificate(res, args.output)
                written = args.output
            else:
                sys.stderr.write(f"lmic: no certified point of '{name}': no certificate written\n")
        if args.json:
            doc = res.to_dict()
            doc["certificate_file"] = written
            print_json(doc)
        else:
            _print_sup(res, written)
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


def _print_sup(r: SupResult, written: str | None = None) -> None:
    from rich.console import Console

    from lmic.formatting import bound_text, interval_text, value_text

    out = Console(highlight=False, soft_wrap=True)
    if not out.is_terminal:
        out.width = 160
    is_max = r.sense == "max"
    op = "sup" if is_max else "inf"
    how_found = (
        "one convex solve, enclosure of its optimum"
        if r.method == "enclosure"
        else "bisection on certified feasibility"
    )
    out.print(f"theorem    {r.theorem}   {op} {r.param} ({how_found}, backend {r.backend})")
    if r.method_note and r.method != "enclosure" and r.method_note != "bisection asked for":
        out.print(f"  method   bisection ({r.method_note})")
    elif r.method_note and r.method == "enclosure":
        out.print(f"  method   enclosure ({r.method_note})")
    tol = f"xtol {r.xtol:g}, rtol {r.rtol:g}"
    c, o = r.certified, r.other
    if c is None:
        out.print(f"[red]no certified value of {r.param}[/]: {r.message}")
    else:
        lo_hi = (c, o) if is_max else (o, c)
        assumed = "" if r.interval_proven else "   (if the feasible values form an interval: see the note)"
        if r.upper_kind in ("infeasible-certified", "dual-bound"):
            out.print(f"[bold]{op} {r.param} in {interval_text(lo_hi[0], lo_hi[1])}[/]   ({tol}){assumed}")
        elif r.upper_proven is not None:
            ends = (c, r.upper_proven) if is_max else (r.upper_proven, c)
            out.print(f"[bold]{op} {r.param} in {interval_text(ends[0], ends[1])}[/]   (proven ends){assumed}")
        else:
            rel, more = (">=", "larger, even infinite") if is_max else ("<=", "smaller")
            out.print(
                f"[bold]{op} {r.param} {rel} {bound_text(c, 'lower' if is_max else 'upper')}[/]   "
                f"(no proven {'upper' if is_max else 'lower'} end: may be {more})"
            )
        cert_pt = next((p for p in r.points if p.value == c and p.outcome == "feasible"), None)
        how = cert_pt.proof if cert_pt else "certified"
        side, other_side = ("lower", "upper") if is_max else ("upper", "lower")
        article = "an" if other_side == "upper" else "a"
        out.print(f"  {side:<8} {value_text(c, 10)}  {how} (evidence: a certified point)")
        if o is not None:
            kind = {
                "undecided": "not certified (neither certified nor proven infeasible): "
                f"not {article} {other_side} bound",
                "infeasible-bounded": "infeasible-bounded (no solution with ||x||_inf <= R only): "
                f"not {article} {other_side} bound",
                "infeasible-certified": "infeasible-certified (global proof)",
                "dual-bound": "proven dual bound (dual point proved feasible: no value beyond it)",
            }.get(r.upper_kind, r.upper_kind)
            label = "dual" if r.upper_kind == "dual-bound" else "bisection" if r.method != "enclosure" else "proof"
            out.print(f"  {label} {other_side} {value_text(o, 10)}  {kind}")
        if r.upper_proven is not None and r.upper_proven != o:
            out.print(f"  proven infeasible (global) from {value_text(r.upper_proven, 10)}")
        _print_end(out, r)
    if written:
        out.print(
            f"  certificate of the point at {r.param} = {value_text(c, 10)} written to {written} "
            f"(check: lmic audit {written})"
        )
    if r.message:
        out.print(f"  note     {r.message}")
    binds = [p.bind_s for p in r.points]
    steps = "one convex solve" if r.method == "enclosure" else f"{r.iterations} bisection steps"
    out.print(
        f"  {steps}, {len(r.points)} points, {r.total_s:.2f} s "
        f"(analysis once {r.plan_s * 1e3:.0f} ms, re-bind {1e3 * sum(binds) / max(len(binds), 1):.1f} ms a point, "
        f"solve {sum(p.solve_s for p in r.points):.2f} s, certify {sum(p.certify_s for p in r.points):.2f} s)"
    )


def _print_end(out: Any, r: SupResult) -> None:
    """The certified end's point: how it was certified, its derived scalars and gain norms."""
    import numpy as np

    from lmic.formatting import value_text

    end = r.end
    if end is None:
        out.print("  [yellow]the certified end's point could not be re-certified on the theorem's problem: no gains[/]")
        return
    extra = f", objective within {end.backoff:g} relative" if end.backoff else ""
    out.print(
        f"  point at {r.param} = {value_text(end.value, 10)}: {end.source}{extra}, {end.proof}, "
        f"||x||_inf {end.norm_inf:.3g}"
    )
    for note in end.notes:
        out.print(f"    note: {note}")
    norms = end.gain_norms()
    for name, v in end.derived.items():
        if name in norms:
            shape = "x".join(str(d) for d in np.atleast_2d(np.asarray(v, dtype=float)).shape)
            out.print(f"    {name:<12} {shape} matrix, ||.||_2 = {norms[name]:.4g}")
        elif isinstance(v, float):
            out.print(f"    {name:<12} {value_text(v, 10)}")
    if norms:
        out.print("    (the matrices in full: --json, or the certificate file with -o)")


def _print_sweep(r: SweepResult) -> None:
    from rich.console import Console
    from rich.table import Table

    from lmic.formatting import interval_text, value_text

    out = Console(highlight=False, soft_wrap=True)
    if not out.is_terminal:
        out.width = 160
    table = Table(title=f"{r.theorem}: sweep of {r.param} (backend {r.backend})")
    optimisation = r.sense in ("min", "max")
    cols = (r.param, "outcome", "status", "verdict", "objective") + (("optimum in",) if optimisation else ())
    for col in cols + ("rel. margin", "how", "bind ms", "solve s"):
        table.add_column(col)
    for p in r.points:
        star = " *" if p is r.best else ""
        enc = p.enclosure or {}
        table.add_row(
            value_text(p.value, 7) + star,
            p.outcome,
            p.status,
            p.verdict,
            value_text(p.objective, 7),
            *((interval_text(enc.get("lower"), enc.get("upper"), 7) if enc else "-",) if optimisation else ()),
            value_text(p.rel_margin, 3),
            p.proof[:60],
            f"{1e3 * p.bind_s:.1f}",
            f"{p.solve_s:.3f}",
        )
    out.print(table)
    if r.best is None:
        out.print(f"no certified point on the grid of {r.param}")
    else:
        what = (
            "objective " + value_text(r.best.objective, 7)
            if r.sense in ("min", "max")
            else "relative margin " + value_text(r.best.rel_margin, 3)
        )
        if r.best.enclosure:
            best_enc = r.best.enclosure
            what += f"; optimum in {interval_text(best_enc.get('lower'), best_enc.get('upper'), 7)}"
        if r.best_rule == "edge of the certified range":
            what = f"the edge of the certified range; {what}"
        out.print(f"best certified point: {r.param} = {value_text(r.best.value, 7)} ({what})")
    binds = [p.bind_s for p in r.points]
    out.print(
        f"{len(r.points)} points, {r.total_s:.2f} s (analysis once {r.plan_s * 1e3:.0f} ms, "
        f"re-bind {1e3 * sum(binds) / max(len(binds), 1):.1f} ms a point)"
    )
