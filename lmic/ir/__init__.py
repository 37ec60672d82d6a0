"""The IR: the contract between the front end and every backend, and its file formats.

* :mod:`lmic.ir.problem`: :class:`Problem`, :class:`Variable`, :class:`LMI`,
  :class:`LinearConstraints`, :class:`Objective`, :class:`NamedExpr`, :class:`Check`;
* :mod:`lmic.ir.svec`: the one vectorisation convention;
* :mod:`lmic.ir.expr`: expression trees for derived quantities and checks;
* :mod:`lmic.ir.jsonio`: the exact JSON round trip (``schemas/ir.schema.json``) and hashing;
* :mod:`lmic.ir.sdpa`: SDPA sparse (``.dat-s``) import and export;
* :mod:`lmic.ir.io`: :func:`load_problem` / :func:`save_problem` by file suffix.

Examples
--------
>>> from lmic.ir import problem_from_dict, problem_to_dict, read_sdpa
>>> p = read_sdpa("1\\n1\\n1\\n1.0\\n0 1 1 1 2.0\\n1 1 1 1 1.0\\n")
>>> problem_from_dict(problem_to_dict(p)).lmis[0].name
'block 1'
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from lmic.ir.io import load_problem, save_problem
    from lmic.ir.jsonio import problem_from_dict, problem_hash, problem_to_dict
    from lmic.ir.problem import (
        LMI,
        Check,
        LinearConstraints,
        NamedExpr,
        Objective,
        Problem,
        Variable,
    )
    from lmic.ir.sdpa import read_sdpa, write_sdpa

# imported on first use (PEP 562): a process that needs lmic.ir.expr or lmic.ir.problem alone
# does not load the file formats (JSON reader and writer, SDPA)
_WHERE = {
    "load_problem": "io",
    "save_problem": "io",
    "problem_from_dict": "jsonio",
    "problem_hash": "jsonio",
    "problem_to_dict": "jsonio",
    "LMI": "problem",
    "Check": "problem",
    "LinearConstraints": "problem",
    "NamedExpr": "problem",
    "Objective": "problem",
    "Problem": "problem",
    "Variable": "problem",
    "read_sdpa": "sdpa",
    "write_sdpa": "sdpa",
}

__all__ = [
    "Problem",
    "Variable",
    "LMI",
    "LinearConstraints",
    "Objective",
    "NamedExpr",
    "Check",
    "load_problem",
    "save_problem",
    "problem_to_dict",
    "problem_from_dict",
    "problem_hash",
    "read_sdpa",
    "write_sdpa",
]


def __getattr__(name: str) -> Any:
    """The names above, imported from their module on first use."""
    if name in _WHERE:
        value = getattr(importlib.import_module(f"lmic.ir.{_WHERE[name]}"), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'lmic.ir' has no attribute {name!r}")
