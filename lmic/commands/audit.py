"""``lmic audit CERT.json [--exact] [--json] [--tol NAME=VALUE]``: recompute a certificate and compare.

The audit decides with lmic's default tolerances, or stricter ones given with ``--tol``; a file
recording looser ones is rejected, naming the tolerance. ``--json`` lists the informational
fields (the only ones a certificate may change freely).

Exit codes, as ``lmic solve``'s: 0 the certificate is consistent and certifies a solution; 3 it
is consistent and certifies infeasibility; 4 it is consistent and records a bounded
infeasibility certificate; 5 it is consistent and certifies unboundedness (a certified point and
the improving ray, both re-proved); 1 it was tampered with, no longer matches its system file or theorem,
or records a verdict that certifies nothing (``rejected``/``unverified``); 2 the file is
malformed, truncated, of an unknown schema version, or its theorem or system file is missing
(one line on stderr).

Examples
--------
>>> import argparse
>>> parser = argparse.ArgumentParser(); sub = parser.add_subparsers()
>>> register(sub)
>>> parser.parse_args(["audit", "c.json", "--exact"]).exact
True
"""

from __future__ import annotations

import argparse
import math
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # imported by the functions that use them (lmic's start-up stays light)
    from lmic.certify.certificate import AuditResult

__all__ = ["register", "run", "exit_code"]


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``audit`` sub-command."""
    p = sub.add_parser("audit", help="recompute a certificate file and reject it if anything differs")
    p.add_argument("certificate", metavar="CERT.json", help="a certificate written by 'lmic solve -o'")
    p.add_argument("--exact", action="store_true", help="also prove every LMI in exact rational arithmetic")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.add_argument(
        "--tol",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="a stricter tolerance to decide with (rel, strict_rel, zero_rel, objective_rel, farkas_rel); "
        "the file's own tolerances are never used when looser than lmic's defaults",
    )
    p.set_defaults(func=run)


def _tolerances(items: list[str]) -> dict[str, float]:
    """``NAME=VALUE`` strings -> dict of finite non-negative floats (bad input otherwise).

    >>> _tolerances(["rel=1e-10"])
    {'rel': 1e-10}
    """
    from lmic.certify.check import Tolerances
    from lmic.errors import DataError

    known = Tolerances().to_dict()
    out: dict[str, float] = {}
    for item in items:
        name, sep, value = item.partition("=")
        name = name.strip()
        if not sep or name not in known:
            raise DataError(f"--tol {item!r}: write NAME=VALUE with NAME one of {', '.join(known)}")
        try:
            num = float(value)
        except ValueError:
            raise DataError(f"--tol {item!r}: {value!r} is not a number") from None
        if not (math.isfinite(num) and num >= 0):
            raise DataError(f"--tol {item!r}: must be a finite non-negative number")
        out[name] = num
    return out


def exit_code(result: AuditResult) -> int:
    """0 consistent and certified, 3 consistent and infeasible-certified, 4 consistent and
    infeasible-bounded, 5 consistent and unbounded-certified (``lmic solve``'s codes), 1
    otherwise.

    >>> from lmic.certify.certificate import AuditResult
    >>> exit_code(AuditResult(ok=False, verdict="rejected", recorded_verdict="certified"))
    1
    """
    if not result.ok:
        return 1
    if result.verdict == "certified":
        return 0
    if result.verdict == "infeasible-certified":
        return 3
    if result.verdict == "infeasible-bounded":
        return 4
    if result.verdict == "unbounded-certified":
        return 5
    return 1


def run(args: argparse.Namespace) -> int:
    """Audit the certificate; print a table (or JSON); return the exit code."""
    from rich.console import Console
    from rich.table import Table

    from lmic.certify.certificate import audit_certificate
    from lmic.formatting import value_text

    result = audit_certificate(args.certificate, exact=args.exact, tol=_tolerances(args.tol) or None)
    code = exit_code(result)
    if args.json:
        from lmic.commands._common import print_json

        print_json(dict(result.to_dict(), exit_code=code))
        return code
    console = Console()
    head = Table(title=f"audit of {args.certificate}", show_header=False)
    head.add_column("field")
    head.add_column("value", overflow="fold")
    head.add_row("theorem", result.theorem or "(raw IR)")
    head.add_row("checked", ", ".join(result.checked))
    head.add_row("recorded verdict", result.recorded_verdict)
    colour = "green" if code in (0, 3) else "red"
    label = result.label if result.ok else result.verdict
    head.add_row("audit", f"[{colour}]{'consistent' if result.ok else 'REJECTED'}: {label}[/{colour}]")
    if result.field:
        head.add_row("first difference", result.field)
    head.add_row("message", result.message)
    console.print(head)
    cert = result.certificate
    if cert is not None and cert.lmis:
        t = Table(title="LMIs (recomputed)")
        for col in ("name", "dim", "strict", "lambda_min", "relative", "float", "exact", "ok"):
            t.add_column(col)
        for e in cert.lmis:
            t.add_row(
                e["name"],
                str(e["dim"]),
                str(e["strict"]),
                value_text(e["min_eig"], none=""),
                value_text(e["rel_margin"], none=""),
                "ok" if e.get("float_ok", e["ok"]) else "below threshold",
                e.get("exact") or "-",
                ("[green]yes[/green]" if e["ok"] else "[red]no[/red]")
                + (" (exact)" if e.get("decided_by") == "exact" else ""),
            )
        console.print(t)
    if cert is not None and cert.checks:
        t = Table(title="checks (recomputed)")
        for col in ("name", "kind", "value", "ok"):
            t.add_column(col)
        for e in cert.checks:
            t.add_row(
                e["name"],
                e["kind"],
                value_text(e["value"], none=""),
                "[green]yes[/green]" if e["ok"] else "[red]no[/red]",
            )
        console.print(t)
    if cert is not None and cert.exact is not None:
        e = cert.exact
        console.print(
            f"exact: {'proven' if e['proven'] else 'not proven'} (denominator {e['denominator']}, "
            f"{e['time_s']:.3f} s) {e.get('statement') or e['reason']}"
        )
    return code
