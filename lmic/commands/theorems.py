"""``lmic theorems [--json]``: the registered theorems; broken or conflicting plugins fail it.

Broken plugins (failed to load) and ambiguous ids (offered by two providers) are reported on
stderr, one line each, and make the command exit 2, so that CI catches them.
"""

from __future__ import annotations

import argparse
import sys

from lmic.commands._common import print_json

__all__ = ["register", "run"]


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``theorems`` sub-command."""
    p = sub.add_parser(
        "theorems",
        help="list the registered theorems",
        description="List the registered theorems. Exit 2 (with one line each on stderr) when a plugin "
        "failed to load or two plugins offer the same id.",
        epilog="examples:\n  lmic theorems\n  lmic theorems --json | jq '.theorems[].id'",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """List id, title, citation and objective of every theorem; report broken plugins.

    The list comes from :func:`lmic.plugin_index.theorem_index` (cached: no plugin is imported
    when nothing changed since the last run).
    """
    from lmic.plugin_index import theorem_index

    thms, broken, clashes = theorem_index()
    if args.json:
        print_json(
            {
                "theorems": [
                    {
                        "id": t.id,
                        "title": t.title,
                        "citation": t.citation,
                        "kind": t.kind,
                        "objective": t.objective,
                        "provider": t.provider,
                    }
                    for t in thms
                ],
                "broken_plugins": [{"name": b.name, "reason": b.reason} for b in broken],
                "conflicts": [
                    {"id": c.id, "providers": [p.to_dict() for p in c.providers], "message": c.message()}
                    for c in clashes
                ],
            }
        )
    else:
        from rich.console import Console
        from rich.table import Table

        console = Console(highlight=False, soft_wrap=True)
        table = Table(title=f"{len(thms)} theorems")
        # ids are never cut, whatever the terminal width (the other columns fold)
        table.add_column("id", no_wrap=True, min_width=max((len(t.id) for t in thms), default=2))
        table.add_column("kind", no_wrap=True, min_width=9)
        for col in ("title", "citation", "objective"):
            table.add_column(col, overflow="fold")
        for t in thms:
            table.add_row(t.id, t.kind_word, t.title, t.citation, t.objective)
        console.print(table)
    for b in broken:
        sys.stderr.write(f"lmic: error: plugin {b.name} failed to load: {b.reason}\n")
    for c in clashes:
        sys.stderr.write(f"lmic: error: {c.message()}\n")
    return 2 if broken or clashes else 0
