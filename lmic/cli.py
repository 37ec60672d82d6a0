"""The ``lmic`` command line.

Every sub-command lives in its own module under :mod:`lmic.commands`, exposing
``register(subparsers)`` (which adds its parser and sets ``func``) and a ``run(args) -> int``.
Exit codes (DESIGN section 7): 0 certified, 3 infeasible, 1 rejected / inaccurate / failed
solve, 2 bad usage or bad input (one line on stderr, no traceback).

Examples
--------
>>> main(["--version"])  # doctest: +SKIP
lmic 0.1.0
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from lmic import __version__
from lmic.errors import LmicError

__all__ = ["main", "COMMANDS", "EXIT_OK", "EXIT_FAILED", "EXIT_USAGE", "EXIT_INFEASIBLE", "EXIT_INTERRUPTED"]

EXIT_OK = 0
EXIT_FAILED = 1
EXIT_USAGE = 2
EXIT_INFEASIBLE = 3
#: Ctrl-C (128 + SIGINT, the shell convention)
EXIT_INTERRUPTED = 130

#: sub-command modules, in the order ``lmic --help`` lists them
COMMANDS = [
    "theorems",
    "backends",
    "show",
    "compile",
    "solve",
    "crosscheck",
    "audit",
    "audit_published",
    "reproduce",
    "simulate",
    "report",
]


class _Parser(argparse.ArgumentParser):
    """argparse that reports usage errors as one line and exit code 2."""

    def error(self, message: str) -> None:  # type: ignore[override]
        sys.stderr.write(f"lmic: error: {message}\n")
        raise SystemExit(EXIT_USAGE)


def build_parser() -> argparse.ArgumentParser:
    """The full argument parser (every available sub-command)."""
    parser = _Parser(prog="lmic", description="Compile, solve and certify linear matrix inequalities.")
    parser.add_argument("--version", action="version", version=f"lmic {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    for name in COMMANDS:
        try:
            module = importlib.import_module(f"lmic.commands.{name}")
        except ModuleNotFoundError as err:
            if err.name == f"lmic.commands.{name}":
                continue  # command not built yet
            raise
        module.register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; return the exit code."""
    try:
        parser = build_parser()
        args = parser.parse_args(argv)
        if not getattr(args, "func", None):
            parser.print_help()
            return EXIT_USAGE
        return int(args.func(args))
    except LmicError as err:
        msg = " ".join(str(err).split())
        sys.stderr.write(f"lmic: error: {msg}\n")
        return EXIT_USAGE
    except KeyboardInterrupt:
        sys.stderr.write("lmic: interrupted\n")
        return EXIT_INTERRUPTED


def _entry() -> None:
    raise SystemExit(main())


if __name__ == "__main__":
    _entry()
