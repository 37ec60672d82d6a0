"""``lmic backends [--json]``: the discovered backends and whether each is available here."""

from __future__ import annotations

import argparse

__all__ = ["register", "run"]


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``backends`` sub-command."""
    p = sub.add_parser("backends", help="list solver backends and whether each is available")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Print the backend table (or JSON); exit 0."""
    from lmic.backends.registry import DISABLE_AUTOLOAD_ENV, backend_classes, backend_infos

    infos = backend_infos()
    classes = backend_classes()
    rows = []
    for info in infos:
        d = info.to_dict()
        cls = classes.get(info.name)
        d["variants"] = [f"{info.name}:{v}" for v in cls.variants] if cls is not None else []
        d["default"] = info.name == "clarabel"
        rows.append(d)
    if args.json:
        from lmic.commands._common import print_json

        print_json({"backends": rows, "autoload_env": DISABLE_AUTOLOAD_ENV})
        return 0
    from rich.console import Console
    from rich.table import Table

    table = Table(title="lmic backends")
    for col in ("name", "available", "description / problem"):
        table.add_column(col)
    for d in rows:
        if d["error"]:
            avail, text = "[red]broken[/red]", d["error"]
        elif d["available"]:
            avail, text = "[green]yes[/green]", d["description"]
            if d["variants"]:
                text += f" ({', '.join(d['variants'])})"
        else:
            avail = "[yellow]no[/yellow]"
            text = f"pip install {' '.join(d['missing_packages'])}"
        name = d["name"] + (" (default)" if d["default"] else "")
        table.add_row(name, avail, text)
    Console(soft_wrap=True).print(table)
    return 0
