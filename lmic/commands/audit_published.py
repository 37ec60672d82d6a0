"""``lmic audit-published THEOREM SYSTEM [-p k=v]... [--json]``: audit what the paper prints.

Every entry of the system file's ``published:`` section becomes a claim, decided with the
theorem's LMIs and the certifier (:mod:`lmic.published`): a full published point is certified as
it stands, a partial one is completed by the solver, a printed gain goes through the theorem's
``fixed_<gain>`` variant (the LMI in the remaining variables), a printed status is re-solved, and
printed values are compared with the computed ones.

Exit codes: 0 certified; 1 rejected (or not reproducible); 3 proven infeasible; 2 bad input (no
``published:`` section, a published matrix of the wrong shape, an unknown theorem).

Examples
--------
>>> import argparse
>>> parser = argparse.ArgumentParser(); sub = parser.add_subparsers()
>>> register(sub)
>>> parser.parse_args(["audit-published", "qib.thm1", "f.yaml", "--json"]).json
True
"""

from __future__ import annotations

import argparse

__all__ = ["register", "run"]


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``audit-published`` sub-command."""
    from lmic.commands._common import add_param_option
    from lmic.commands.solve import add_solver_options

    p = sub.add_parser(
        "audit-published",
        help="decide whether the result a paper prints (published:) is certified, rejected or not reproducible",
        description="lmic audit-published THEOREM SYSTEM [-p k=v]... [--json]",
    )
    p.add_argument("theorem", help="theorem id")
    p.add_argument("system", help="system file with a 'published:' section")
    add_param_option(p)
    p.add_argument("--backend", "-b", default=None, help="backend alone (default: the escalating policy)")
    p.add_argument(
        "--rtol",
        type=float,
        default=0.05,
        help="relative tolerance for printed values (default 0.05, or the print precision)",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object")
    add_solver_options(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Audit and report; the exit code follows the decisive claims."""
    from rich.console import Console
    from rich.table import Table

    from lmic.commands._common import parse_params, print_json, solve_options
    from lmic.formatting import value_text
    from lmic.studies.published import audit_published

    report = audit_published(
        args.theorem,
        args.system,
        parse_params(args.param) or None,
        backend=args.backend,
        options=solve_options(args),
        rtol=args.rtol,
    )
    if args.json:
        print_json(report.to_dict())
        return report.exit_code()
    out = Console(highlight=False, soft_wrap=True)
    if not out.is_terminal:
        out.width = 160
    out.print(f"theorem  {report.theorem}\nsystem   {report.system}")
    table = Table(show_lines=False)
    for col in ("published", "claim", "finding", "verdict", "margins / values", "how"):
        table.add_column(col)
    colour = {
        "certified": "green",
        "matches": "green",
        "rejected": "red",
        "infeasible": "red",
        "differs": "yellow",
        "not reproducible": "yellow",
        "skipped": "dim",
    }
    for c in report.claims:
        if c.kind == "value":
            info = f"printed {value_text(c.published, width=60)}, computed {value_text(c.computed, width=60)}"
            if c.difference is not None:
                info += f" (diff {value_text(c.difference, 3, width=60)})"
        else:
            parts = [
                f"{e['name']}: {e['which']} {value_text(e['extreme'], width=60)}"
                for e in c.lmis
                if e.get("extreme") is not None
            ]
            parts += [f"{k} {value_text(v, width=60)}" for k, v in c.derived.items()]
            if c.objective is not None:
                parts.append(f"objective {value_text(c.objective, width=60)}")
            info = "; ".join(parts)
        finding = f"[{colour.get(c.finding, 'white')}]{c.finding}[/]"
        if c.agrees is False:
            finding += " (paper claims otherwise)"
        how = c.route if c.kind != "skipped" else c.reason
        table.add_row(", ".join(c.keys), c.kind, finding, c.verdict, info, how)
    out.print(table)
    for c in report.claims:
        if c.kind in ("point", "partial point", "gain", "status", "param") and c.reason:
            out.print(f"  {', '.join(c.keys)}: {c.reason}")
    out.print(f"{len(report.claims)} claims, {report.time_s:.2f} s; exit {report.exit_code()}")
    return report.exit_code()
