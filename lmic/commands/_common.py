"""Helpers shared by the sub-commands: parameter overrides, JSON output, atomic writes.

Examples
--------
>>> parse_params(["beta=0.5", "psi1=corrected"])
{'beta': 0.5, 'psi1': 'corrected'}
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from lmic.errors import DataError

if TYPE_CHECKING:  # lmic.jsonable imports numpy: re-exported lazily by __getattr__ below
    from lmic.jsonable import to_jsonable

__all__ = [
    "parse_params",
    "print_json",
    "to_jsonable",
    "write_atomic",
    "add_param_option",
    "solve_options",
    "add_executor_options",
    "check_executor_args",
    "backend_names",
]


def parse_params(items: list[str] | None) -> dict[str, float | str]:
    """``k=v`` strings -> dict; numbers become floats (parsed with ``float``, nothing evaluated)."""
    out: dict[str, float | str] = {}
    for item in items or []:
        if "=" not in item:
            raise DataError(f"-p {item!r}: write parameters as name=value")
        key, value = item.split("=", 1)
        key, value = key.strip(), value.strip()
        if not key.isidentifier():
            raise DataError(f"-p {item!r}: '{key}' is not a parameter name")
        try:
            num = float(value)
        except ValueError:
            out[key] = value
            continue
        if not math.isfinite(num):
            raise DataError(f"-p {item!r}: {value} is not a finite number")
        out[key] = num
    return out


def backend_names(text: str | None) -> list[str] | None:
    """The backends of ``--backends a,b,...``, each checked (``None``: the option was not given).

    An unknown or unavailable backend, or a list naming none, is bad input (:class:`DataError`).

    >>> backend_names("clarabel, scs"), backend_names(None)
    (['clarabel', 'scs'], None)
    >>> backend_names(",")
    Traceback (most recent call last):
    ...
    lmic.errors.DataError: --backends ',': name at least one backend (or leave the option out)
    """
    if text is None:
        return None
    names = [b.strip() for b in text.split(",") if b.strip()]
    if not names:
        raise DataError(f"--backends {text!r}: name at least one backend (or leave the option out)")
    from lmic.backends.registry import get_backend

    for name in names:
        get_backend(name)  # an unknown or missing backend is bad input (exit 2)
    return names


def add_param_option(parser: Any) -> None:
    """Add the ``-p k=v`` option (repeatable)."""
    parser.add_argument(
        "-p", "--param", action="append", default=[], metavar="K=V", help="override a parameter of the system file"
    )


def print_json(obj: Any) -> None:
    """Print one JSON object on stdout."""
    from lmic.jsonable import to_jsonable
    from lmic.output import json_text  # json.dumps(indent=2, allow_nan=False), faster on matrices

    sys.stdout.write(json_text(to_jsonable(obj)) + "\n")


def write_atomic(path: str | os.PathLike[str], write: Callable[[Any], None], mode: str = "w") -> None:
    """Write through :func:`lmic.output.write_output` (atomic, output-path rules, one-line errors).

    Examples
    --------
    >>> import tempfile, os
    >>> f = os.path.join(tempfile.mkdtemp(), "t.txt")
    >>> write_atomic(f, lambda fh: fh.write("ok"))
    >>> open(f).read()
    'ok'
    """
    from lmic.output import write_output

    write_output(path, write, binary="b" in mode)


def solve_options(args: argparse.Namespace) -> Any:
    """A :class:`~lmic.options.SolveOptions` from the parsed arguments."""
    from lmic.options import SolveOptions

    opts = SolveOptions(verbose=bool(getattr(args, "verbose", False)))
    if getattr(args, "tol", None) is not None:
        opts.tol = args.tol
    if getattr(args, "max_iter", None) is not None:
        opts.max_iter = args.max_iter
    if getattr(args, "time_limit", None) is not None:
        opts.time_limit = args.time_limit
    if getattr(args, "margin", None) is not None:
        opts.margin = args.margin
    if getattr(args, "strict", None) is not None:
        opts.strict = args.strict
    if getattr(args, "gap", None) is not None:
        opts.gap = args.gap  # lmic.routes: the relative gap the default route stops at
    return opts


def add_executor_options(parser: Any, runs: str, default: str | None = None) -> None:
    """``--executor`` and ``--workers`` (:mod:`lmic.studies.executors`), shared by batch,
    crosscheck and reproduce; ``runs`` says what runs in parallel."""
    parser.add_argument(
        "--executor",
        default=default,
        help=f"run {runs} in parallel: local (worker processes), dask (a LocalCluster) or "
        "tcp://HOST:PORT (a Dask scheduler)" + ("" if default else "; default: one after the other in this process"),
    )
    parser.add_argument("--workers", type=int, default=None, help="workers for --executor (default: cores)")


def check_executor_args(args: argparse.Namespace) -> None:
    """Bad ``--executor`` / ``--workers`` values are bad input (one line, exit 2), before any work.

    >>> check_executor_args(argparse.Namespace(executor="ssh://h", workers=None))
    Traceback (most recent call last):
    ...
    lmic.errors.DataError: --executor ssh://h: use local, dask or tcp://HOST:PORT
    >>> check_executor_args(argparse.Namespace(executor="local", workers=10**5))  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    lmic.errors.DataError: --workers 100000: at most ... on this machine (... cores; each worker is a process)
    """
    from lmic.studies.executors import check_workers

    spec = args.executor
    if spec is not None and not (spec in ("local", "dask") or spec.startswith("tcp://")):
        raise DataError(f"--executor {spec}: use local, dask or tcp://HOST:PORT")
    check_workers(spec, args.workers)


def __getattr__(name: str) -> Any:
    """``to_jsonable`` (re-exported from :mod:`lmic.jsonable`) is imported on first use: numpy."""
    if name == "to_jsonable":
        from lmic.jsonable import to_jsonable

        return to_jsonable
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
