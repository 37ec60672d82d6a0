"""Load and save IR problems by file suffix: ``.json`` (the IR) or ``.dat-s`` (SDPA sparse).

Examples
--------
>>> import tempfile, pathlib
>>> p = read_sdpa("1\\n1\\n1\\n1.0\\n0 1 1 1 2.0\\n1 1 1 1 1.0\\n")
>>> d = pathlib.Path(tempfile.mkdtemp())
>>> save_problem(p, d / "p.json")
>>> load_problem(d / "p.json").lmis[0].matrix([3.0])
array([[1.]])
"""

from __future__ import annotations

import os
from collections.abc import Callable

from lmic.errors import IRError
from lmic.ir.jsonio import dump_problem, load_problem_json
from lmic.ir.problem import Problem
from lmic.ir.sdpa import read_sdpa, write_sdpa

__all__ = ["SUFFIXES", "load_problem", "save_problem"]

#: suffix -> (reader, writer)
SUFFIXES: dict[str, tuple[Callable[..., Problem], Callable[..., None]]] = {
    ".json": (load_problem_json, dump_problem),
    ".dat-s": (read_sdpa, write_sdpa),
}


def _formats(path: str | os.PathLike[str]) -> tuple[Callable[..., Problem], Callable[..., None]]:
    name = os.fspath(path)
    for suffix, fns in SUFFIXES.items():
        if name.lower().endswith(suffix):
            return fns
    known = " or ".join(SUFFIXES)
    raise IRError(f"{name}: unknown problem file type (expected {known})")


def load_problem(path: str | os.PathLike[str]) -> Problem:
    """Read an IR (``.json``) or SDPA sparse (``.dat-s``) problem file.

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    Problem

    Raises
    ------
    IRError
        Unknown suffix, unreadable file, or a malformed file (naming the file and the field
        or line).

    Examples
    --------
    >>> load_problem("problem.txt")
    Traceback (most recent call last):
    ...
    lmic.errors.IRError: problem.txt: unknown problem file type (expected .json or .dat-s)
    """
    return _formats(path)[0](path)


def save_problem(problem: Problem, path: str | os.PathLike[str]) -> None:
    """Write a problem as an IR (``.json``) or SDPA sparse (``.dat-s``) file, by suffix.

    SDPA export is lossy in the ways :func:`lmic.ir.sdpa.write_sdpa` documents (one flat
    ``x``, strictness dropped, data/derived/checks not written).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = read_sdpa("1\\n1\\n1\\n1.0\\n1 1 1 1 1.0\\n")
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "p.dat-s"
    >>> save_problem(p, f)
    >>> load_problem(f).n
    1
    """
    _formats(path)[1](problem, path)
