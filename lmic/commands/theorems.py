"""``lmic theorems [--json]``: the registered theorems."""

from __future__ import annotations

import argparse

from rich.console import Console
from rich.table import Table

from lmic.commands._common import print_json
from lmic.registry import broken_plugins, list_theorems

__all__ = ["register", "run"]


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``theorems`` sub-command."""
    p = sub.add_parser("theorems", help="list the registered theorems")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """List id, title, citation and objective of every theorem (and broken plugins)."""
    thms = list_theorems()
    broken = broken_plugins()
    if args.json:
        print_json(
            {
                "theorems": [
                    {"id": t.id, "title": t.title, "citation": t.citation, "kind": t.kind, "objective": t.objective}
                    for t in thms
                ],
                "broken_plugins": [{"name": b.name, "reason": b.reason} for b in broken],
            }
        )
        return 0
    console = Console()
    table = Table(title=f"{len(thms)} theorems")
    for col in ("id", "kind", "title", "citation", "objective"):
        table.add_column(col, overflow="fold")
    for t in thms:
        table.add_row(t.id, t.kind, t.title, t.citation, t.objective)
    console.print(table)
    for b in broken:
        console.print(f"[yellow]plugin {b.name} failed to load: {b.reason}[/yellow]")
    return 0
