"""``lmic show THEOREM [--latex] [--json] [-p option=value]``: a theorem as the paper prints it.

After printing, runs the checks of ``lmic check`` (bilinear terms, asymmetric blocks, shape
mismatches; ``lmic check`` also lists unused declarations): a mistake is one line on stderr and
exit 2.
"""

from __future__ import annotations

import argparse
import sys
from typing import TYPE_CHECKING

from lmic.commands._common import parse_params, print_json

if TYPE_CHECKING:  # the template layer (sympy) is imported by run
    from lmic.template.theorem import Theorem

__all__ = ["register", "run"]


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``show`` sub-command."""
    p = sub.add_parser(
        "show",
        help="show a theorem: data, parameters, variables, LMIs (and check it)",
        epilog="examples:\n  lmic show qib.thm1\n  lmic show qib.thm1 -p fixed_L=1 --latex",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("theorem", help="theorem id (see 'lmic theorems')")
    p.add_argument("--latex", action="store_true", help="print the LMIs as LaTeX")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.add_argument(
        "-p",
        "--param",
        action="append",
        default=[],
        metavar="K=V",
        help="choose a structural option of the theorem (e.g. fixed_L=1, psi1=corrected)",
    )
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Print the theorem's declarations and LMIs."""
    from rich.console import Console

    from lmic.commands.check import check_option_names
    from lmic.registry import get_theorem
    from lmic.template.render import describe, theorem_latex

    thm = get_theorem(args.theorem)
    options = parse_params(args.param)
    t = thm.template(options)
    check_option_names(t, options)
    if args.json:
        print_json(describe(thm, t))
        return _validate(thm, options)
    if args.latex:
        print(theorem_latex(thm, t))
        return _validate(thm, options)
    d = describe(thm, t)
    c = Console(highlight=False, soft_wrap=True)
    c.print(f"[bold]{thm.id}[/bold] — {thm.title}")
    c.print(f"{thm.citation}  ({thm.kind_word}: {thm.objective})")
    if thm.notes:
        c.print(f"[dim]{thm.notes}[/dim]")
    c.print("\n[bold]data[/bold]")
    for x in d["data"]:
        tags = ", ".join(k for k in ("symmetric", "positive_definite", "optional") if x[k])
        extra = (f" ({tags})" if tags else "") + (f" — {x['doc']}" if x["doc"] else "")
        c.print(f"  {x['name']}: {x['shape']}{extra}")
    if d["params"] or d["options"]:
        c.print("[bold]parameters[/bold]")
        for x in d["params"]:
            default = "" if x["default"] is None else f", default {x['default']}"
            c.print(f"  {x['name']} in {x['domain']}{default}" + (f" — {x['doc']}" if x["doc"] else ""))
        for x in d["options"]:
            c.print(f"  {x['name']} in {{{', '.join(x['choices'])}}}, default {x['default']}")
    c.print("[bold]variables[/bold]")
    for x in d["variables"]:
        sign = "" if x["sign"] == "free" else f", {x['sign']}"
        c.print(f"  {x['name']}: {x['kind']} {x['shape']}{sign}")
    c.print("[bold]LMIs[/bold]")
    for x in d["lmis"]:
        c.print(f"  {x['name']}:")
        for line in x["text"].splitlines():
            c.print(f"    {line}")
    for x in d["constraints"]:
        c.print(f"  {x['name']}: {x['text']}")
    if d["objective_expr"]["sense"] != "feasibility":
        c.print(f"[bold]objective[/bold] {d['objective_expr']['sense']} {d['objective_expr']['expr']}")
    if d["derived"]:
        c.print("[bold]derived[/bold]")
        for x in d["derived"]:
            c.print(f"  {x['name']} = {x['expr']}")
    if d["checks"]:
        c.print("[bold]checks[/bold]")
        for x in d["checks"]:
            c.print(f"  {x['name']} ({x['kind']})")
    return _validate(thm, options)


def _validate(thm: Theorem, options: dict) -> int:
    """The checks of ``lmic check`` (one line each on stderr); 2 when a mistake is found."""
    from lmic.commands.check import check_theorem, report_lines

    report = check_theorem(thm, options)
    for line in report_lines(report, warnings=False):  # unused declarations: see lmic check
        sys.stderr.write(f"lmic check: {line}\n")
    return 2 if report.findings else 0
