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
>>> p = read_sdpa("1\\n1\\n1\\n1.0\\n0 1 1 1 2.0\\n1 1 1 1 1.0\\n")
>>> problem_from_dict(problem_to_dict(p)).lmis[0].name
'block 1'
"""

from __future__ import annotations

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
