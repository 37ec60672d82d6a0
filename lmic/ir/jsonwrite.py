"""Writing the IR as JSON: the canonical dict, readable text, the file and the hash.

Part of :mod:`lmic.ir.jsonio` (the format is described there): floats are written with ``repr``
so a load gives them back bitwise; NaN and infinities are rejected.

Examples
--------
>>> import scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
>>> t = Variable("t", "scalar", (1, 1))
>>> lmi = LMI("t > 0", 1, sp.csc_matrix([[0.0, 1.0]]), strict=True)
>>> prob = Problem([t], [lmi], LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
>>> problem_to_dict(prob)["lmis"][0]["coeffs"]
{'row': [0], 'col': [1], 'val': [1.0]}
"""

from __future__ import annotations

import hashlib
import json
import math
import os
from collections.abc import Mapping
from typing import Any

import numpy as np
import scipy.sparse as sp

from lmic.errors import IRError
from lmic.ir import expr as _expr
from lmic.ir.jsonvalid import IR_VERSION
from lmic.ir.problem import (
    Problem,
)

__all__ = ["problem_to_dict", "problem_to_json", "dump_problem", "problem_hash"]

# --------------------------------------------------------------------------------------------
# helpers


def _canonical_triplets(M: sp.spmatrix) -> tuple[list[int], list[int], list[float]]:
    """``(row, col, val)`` of a sparse matrix: sorted by col then row, zeros dropped."""
    A = sp.csc_matrix(M, dtype=float, copy=True)
    A.sum_duplicates()
    A.eliminate_zeros()
    A.sort_indices()
    cols = np.repeat(np.arange(A.shape[1], dtype=np.int64), np.diff(A.indptr))
    return A.indices.astype(np.int64).tolist(), cols.tolist(), A.data.astype(float).tolist()


def _jsonable(value: Any, where: str) -> Any:
    """A JSON-ready copy of ``value`` (numpy scalars and arrays to Python, tuples to lists)."""
    if value is None or isinstance(value, bool | str):
        return value
    if isinstance(value, np.bool_):
        return bool(value)
    if isinstance(value, int | np.integer):
        return int(value)
    if isinstance(value, float | np.floating):
        f = float(value)
        if not math.isfinite(f):
            raise IRError(f"{where}: {f} is not a finite number")
        return f
    if isinstance(value, np.ndarray):
        if value.dtype.kind not in "biuf":
            raise IRError(f"{where}: array of dtype {value.dtype} is not allowed in an IR")
        return _jsonable(value.tolist(), where)
    if isinstance(value, Mapping):
        out = {}
        for k, v in value.items():
            if not isinstance(k, str):
                raise IRError(f"{where}: key {k!r} is not a string")
            out[k] = _jsonable(v, f"{where}.{k}")
        return out
    if isinstance(value, list | tuple):
        return [_jsonable(v, f"{where}[{i}]") for i, v in enumerate(value)]
    raise IRError(f"{where}: a {type(value).__name__} cannot be written to JSON")


def _data_to_json(name: str, value: Any) -> float | list:
    where = f"data.{name}"
    if isinstance(value, bool | np.bool_) or value is None or isinstance(value, str):
        raise IRError(f"{where}: {type(value).__name__} is not a number or an array")
    if isinstance(value, int | float | np.integer | np.floating):
        f = float(value)
        if not math.isfinite(f):
            raise IRError(f"{where}: {f} is not a finite number")
        return f
    try:
        arr = np.asarray(value)
    except ValueError:
        raise IRError(f"{where}: ragged nested list") from None
    if arr.dtype.kind not in "iuf" or arr.dtype == object:
        raise IRError(f"{where}: not a numeric array (dtype {arr.dtype})")
    arr = arr.astype(float)
    if not np.all(np.isfinite(arr)):
        raise IRError(f"{where}: has a non-finite entry")
    return arr.tolist()


# --------------------------------------------------------------------------------------------
# Problem -> dict


def problem_to_dict(problem: Problem) -> dict[str, Any]:
    """The IR as a JSON-ready dict (canonical: equal problems give equal dicts).

    Parameters
    ----------
    problem : Problem

    Returns
    -------
    dict
        Plain Python values only (lists, dicts, floats, ints, strings, bools, None).

    Raises
    ------
    IRError
        If a value cannot be written exactly (NaN/Inf, a non-numeric data entry, an object in
        ``meta`` that is not JSON).

    Examples
    --------
    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LinearConstraints, Objective, Problem, Variable
    >>> x = Variable("x", "full", (2, 1))
    >>> lin = LinearConstraints(sp.csr_matrix([[1.0, -1.0, 0.0]]), ["ge"], [False], ["x0 <= 1"])
    >>> p = Problem([x], [], lin, Objective("max", [0.0, 1.0, 2.0]), data={"a": 0.5})
    >>> d = problem_to_dict(p)
    >>> d["linear"]["row"], d["linear"]["col"], d["linear"]["val"]
    ([0, 0], [0, 1], [1.0, -1.0])
    >>> d["objective"]
    {'sense': 'max', 'c': {'idx': [1, 2], 'val': [1.0, 2.0]}}
    """
    problem.validate()
    variables = [
        {
            "name": v.name,
            "kind": v.kind,
            "shape": [int(v.shape[0]), int(v.shape[1])],
            "offset": int(v.offset),
            "blocks": [int(b) for b in v.blocks],
            "sign": v.sign,
        }
        for v in problem.variables
    ]
    lmis = []
    for lmi in problem.lmis:
        row, col, val = _canonical_triplets(lmi.coeffs)
        lmis.append(
            {
                "name": lmi.name,
                "dim": int(lmi.dim),
                "strict": bool(lmi.strict),
                "relation": lmi.relation,
                "block_sizes": [int(b) for b in lmi.block_sizes],
                "coeffs": {"row": row, "col": col, "val": val},
            }
        )
    row, col, val = _canonical_triplets(problem.linear.A)
    linear = {
        "row": row,
        "col": col,
        "val": val,
        "kinds": list(problem.linear.kinds),
        "strict": [bool(s) for s in problem.linear.strict],
        "names": [str(s) for s in problem.linear.names],
    }
    c = np.asarray(problem.objective.c, dtype=float)
    keep = np.flatnonzero((c != 0) | np.signbit(c))  # +0.0 is implicit, -0.0 is kept
    objective = {
        "sense": problem.objective.sense,
        "c": {"idx": keep.tolist(), "val": c[keep].tolist()},
    }
    data = {str(k): _data_to_json(str(k), v) for k, v in problem.data.items()}
    derived = []
    for i, d in enumerate(problem.derived):
        _expr.validate(d.expr, f"derived[{i}].expr")
        derived.append({"name": d.name, "expr": _jsonable(d.expr, f"derived[{i}].expr"), "doc": d.doc})
    checks = []
    for i, ch in enumerate(problem.checks):
        _expr.validate(ch.expr, f"checks[{i}].expr")
        checks.append(
            {
                "name": ch.name,
                "kind": ch.kind,
                "expr": _jsonable(ch.expr, f"checks[{i}].expr"),
                "bound": None if ch.bound is None else _jsonable(float(ch.bound), f"checks[{i}]"),
                "doc": ch.doc,
            }
        )
    return {
        "lmic_ir": IR_VERSION,
        "meta": _jsonable(dict(problem.meta), "meta"),
        "variables": variables,
        "lmis": lmis,
        "linear": linear,
        "objective": objective,
        "data": data,
        "derived": derived,
        "checks": checks,
    }


# --------------------------------------------------------------------------------------------
# text and files


def _pretty(obj: Any, indent: int = 0) -> str:
    """Readable JSON: short values inline, lists of numbers on one line, matrices by row.

    Every value is serialised once (children first), so the cost is linear in the output.
    """
    if not isinstance(obj, dict | list) or not obj:
        return json.dumps(obj, allow_nan=False)
    if isinstance(obj, list) and not isinstance(obj[0], dict | list):
        return json.dumps(obj, separators=(", ", ": "), allow_nan=False)  # a vector: one line
    pad, inner = " " * indent, " " * (indent + 1)
    if isinstance(obj, dict):
        parts = [f"{json.dumps(k)}: {_pretty(v, indent + 1)}" for k, v in obj.items()]
        open_, close = "{", "}"
    else:
        parts = [_pretty(v, indent + 1) for v in obj]
        open_, close = "[", "]"
    if sum(len(p) + 2 for p in parts) + indent <= 100 and not any("\n" in p for p in parts):
        return open_ + ", ".join(parts) + close
    return open_ + "\n" + ",\n".join(inner + p for p in parts) + "\n" + pad + close


def problem_to_json(problem: Problem, *, indent: bool = True) -> str:
    """The IR as JSON text (readable when ``indent``, else compact).

    Examples
    --------
    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LinearConstraints, Objective, Problem, Variable
    >>> p = Problem([Variable("t", "scalar", (1, 1))], [], LinearConstraints.empty(1),
    ...             Objective("feasibility", [0.0, 0.0]))
    >>> problem_to_json(p, indent=False)[:22]
    '{"lmic_ir":1,"meta":{}'
    """
    d = problem_to_dict(problem)
    if indent:
        return _pretty(d) + "\n"
    return json.dumps(d, separators=(",", ":"), allow_nan=False)


def dump_problem(problem: Problem, path: str | os.PathLike[str]) -> None:
    """Write the IR to a JSON file (nothing is written if the problem cannot be serialised).

    Examples
    --------
    >>> import tempfile, pathlib, scipy.sparse as sp
    >>> from lmic.ir.problem import LinearConstraints, Objective, Problem, Variable
    >>> p = Problem([Variable("t", "scalar", (1, 1))], [], LinearConstraints.empty(1),
    ...             Objective("min", [0.0, 1.0]))
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "ir.json"
    >>> dump_problem(p, f)
    >>> '"lmic_ir": 1' in f.read_text()
    True
    """
    from lmic.output import write_output

    write_output(path, problem_to_json(problem))  # atomic: nothing half-written


def problem_hash(problem: Problem) -> str:
    """SHA-256 (hex) of the canonical JSON of the IR.

    Canonical: :func:`problem_to_dict`, keys sorted, no whitespace, floats via ``repr``. Two
    problems have the same hash iff they serialise identically (``meta`` included).

    Examples
    --------
    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LinearConstraints, Objective, Problem, Variable
    >>> p = Problem([Variable("t", "scalar", (1, 1))], [], LinearConstraints.empty(1),
    ...             Objective("min", [0.0, 1.0]))
    >>> len(problem_hash(p))
    64
    """
    text = json.dumps(
        problem_to_dict(problem),
        sort_keys=True,
        separators=(",", ":"),
        allow_nan=False,
        ensure_ascii=True,
    )
    return hashlib.sha256(text.encode("utf-8")).hexdigest()
