"""Terminal output: a pipeline result as rich tables, numbers and matrices as text.

Examples
--------
>>> format_value(0.5), format_value([[1.0, 2.0]]), value_text([[1.0, 2.0], [3.0, 4.0]])
('0.5', '[1 2]', '[1 2; 3 4]')
"""

from __future__ import annotations

from typing import Any

from rich.console import Console
from rich.table import Table

from lmic.formatting import format_value, inline_matrix, number_text, value_text

__all__ = ["print_result", "format_value", "inline_matrix", "number_text", "value_text"]

_VERDICT_STYLE = {
    "certified": "bold green",
    "infeasible-certified": "bold blue",
    "rejected": "bold red",
    "unverified": "bold yellow",
    "undecided": "bold yellow",
    "infeasible-bounded": "bold cyan",
    "unbounded-certified": "bold magenta",
}


#: what the number of each check kind is (lmic.certify.derived)
_CHECK_VALUE = {
    "schur_stable": "spectral radius",
    "hurwitz": "spectral abscissa",
    "negative_definite": "lambda_max",
    "positive_definite": "lambda_min",
    "negative_semidefinite": "lambda_max",
    "positive_semidefinite": "lambda_min",
    "less_than": "value",
    "greater_than": "value",
    "finite": "max |entry|",
}


def print_result(
    result: Any, system: str | None = None, output: str | None = None, console: Console | None = None
) -> None:
    """Print target, status, verdict, LMI margins, checks, derived gains and timings."""
    c = console or Console(highlight=False, soft_wrap=False)
    sol = result.solution
    head = Table.grid(padding=(0, 2))
    head.add_column(style="bold")
    head.add_column()
    head.add_row("target", f"{result.target}" + (f" {system}" if system else ""))
    if result.theorem and result.problem.meta.get("citation"):
        title = result.problem.meta.get("title")
        head.add_row(
            "theorem", (f"{title} ({result.problem.meta['citation']})" if title else result.problem.meta["citation"])
        )
    head.add_row("backend", result.backend)
    head.add_row("status", result.status + (f" ({sol.native_status})" if sol.native_status else ""))
    if sol.message:
        head.add_row("message", sol.message)
    if result.objective is not None and not result.verdict.startswith("infeasible"):
        # the returned point's value: not an optimum for an unbounded problem, and not inside the
        # enclosure when its upper end comes from a restored point (the optimal value line below)
        at = " (at the certified point; no optimum)" if result.verdict == "unbounded-certified" else ""
        enc = result.enclosure or {}
        lo, hi = enc.get("lower"), enc.get("upper")
        if not at and (lo is not None and result.objective < lo or hi is not None and result.objective > hi):
            at = " (the returned point's; the optimal value is enclosed below)"
        elif not at and result.verdict != "certified":
            at = " (the solver's point, not certified)"
        head.add_row("objective", f"{result.objective:.10g}{at}")
    if sol.strategy != "none":
        head.add_row("strict", f"{sol.strategy}, margin {format_value(sol.margin)}")
    cert = result.certificate_dict()
    label = str(cert.get("label") or "")
    verdict = label if label.startswith(result.verdict) else result.verdict  # e.g. "certified (exact)"
    outcome = getattr(result, "outcome", None)
    reason = (outcome.reason if outcome is not None else "") or cert.get("reason") or ""
    style = _VERDICT_STYLE.get(result.verdict, "bold")
    head.add_row("verdict", f"[{style}]{verdict}[/{style}]" + (f": {reason}" if reason else ""))
    c.print(head)
    if cert.get("lmis") or cert.get("checks"):
        t = Table(show_edge=False, header_style="bold")
        for col in ("constraint", "kind", "min margin / value", "relative", "ok"):
            t.add_column(col, justify="right" if col in ("min margin / value", "relative") else "left")
        for lmi in cert.get("lmis", []):
            strict = "strict" if lmi.get("strict", True) else "non-strict"
            t.add_row(
                str(lmi.get("name")),
                f"LMI {lmi.get('dim', '')} {strict}".replace("  ", " "),
                format_value(lmi.get("min_margin")),
                format_value(lmi.get("rel_margin")),
                ("[green]ok (exact)[/green]" if lmi.get("decided_by") == "exact" else "[green]ok[/green]")
                if lmi.get("ok")
                else "[red]VIOLATED[/red]",
            )
        for chk in cert.get("checks", []):
            # a check's number is its own quantity, not a margin: say which
            what = _CHECK_VALUE.get(str(chk.get("kind", "")), "")
            t.add_row(
                str(chk.get("name")),
                f"check {chk.get('kind', '')}".strip() + (f" ({what})" if what else ""),
                format_value(chk.get("value")) + (" (float; holds exactly)" if chk.get("exact") == "holds" else ""),
                "",
                ("[green]ok (exact)[/green]" if chk.get("exact") == "holds" else "[green]ok[/green]")
                if chk.get("ok")
                else "[red]FAILED[/red]",
            )
        c.print(t)
    gains = {k: v for k, v in (result.derived or {}).items() if v is not None}
    if gains:
        g = Table(show_edge=False, header_style="bold")
        g.add_column("derived")
        g.add_column("value")
        for k, v in gains.items():
            g.add_row(k, format_value(v))
        c.print(g)
    if len(result.attempts) > 1:
        c.print("attempts (the solve policy, docs/backends.md):")
    for att in result.attempts if len(result.attempts) > 1 else []:
        native = f" ({att['native_status']})" if att.get("native_status") else ""
        note = f"; {att['note']}" if att.get("note") else ""
        c.print(
            f"  {att['backend']} / {att['reduction']}: {att['status']}{native} -> {att['verdict']} "
            f"({att['time_s']:.2f} s{note})",
            markup=False,
        )
    t = result.timings
    times = ", ".join(f"{k[:-2].replace('_', ' ')} {v:.3f} s" for k, v in t.items() if isinstance(v, float))
    c.print(f"[dim]timings  {times}[/dim]")
    if output and result.certificate is not None:
        c.print(f"wrote    {output}")
