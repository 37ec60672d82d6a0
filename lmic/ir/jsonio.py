"""The IR as JSON: an exact, schema-validated round trip.

Format (version 1, described by ``schemas/ir.schema.json``)::

    {"lmic_ir": 1,
     "meta": {...},
     "variables": [{"name", "kind", "shape", "offset", "blocks", "sign"}, ...],
     "lmis": [{"name", "dim", "strict", "relation", "block_sizes",
               "coeffs": {"row": [...], "col": [...], "val": [...]}}, ...],
     "linear": {"row": [...], "col": [...], "val": [...], "kinds", "strict", "names"},
     "objective": {"sense", "c": {"idx": [...], "val": [...]}},
     "data": {name: number or nested list},
     "derived": [{"name", "expr", "doc"}, ...],
     "checks": [{"name", "kind", "expr", "bound", "doc"}, ...]}

* LMI coefficients use the storage convention of :mod:`lmic.ir.svec`: ``row`` is the storage
  index of the lower triangle (column-major, unscaled), ``col`` is 0 for ``F0`` and ``1 + k``
  for ``F_k``. Linear rows use column 0 for the constant ``a0``.
* Sparse triplets are canonical: sorted by ``col`` then ``row``, no duplicates, no zeros. The
  objective vector keeps ``-0.0`` entries (only ``+0.0`` is left out) so that every float of the
  IR survives bitwise.
* Floats are written with ``repr`` (Python's shortest round-tripping form), so a load gives back
  bitwise equal numbers. NaN and infinities are rejected, on writing and on reading.
* Numpy arrays in ``data`` are written as nested lists and load as float arrays; scalars load
  as floats. ``meta`` is free-form JSON (strings allowed, e.g. ``meta["params"]``).

Every malformed input raises :class:`~lmic.errors.IRError` with one line naming the source and
the field, e.g. ``ir.json: lmis[2].coeffs: row index 17 out of range for dimension 5``.

Examples
--------
>>> import scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
>>> t = Variable("t", "scalar", (1, 1))
>>> lmi = LMI("t > 0", 1, sp.csc_matrix([[0.0, 1.0]]), strict=True)
>>> prob = Problem([t], [lmi], LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
>>> d = problem_to_dict(prob)
>>> d["lmis"][0]["coeffs"]
{'row': [0], 'col': [1], 'val': [1.0]}
>>> problem_hash(problem_from_dict(d)) == problem_hash(prob)
True
"""

from __future__ import annotations

import hashlib
import json
import math
import os
from collections.abc import Mapping
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np
import scipy.sparse as sp

from lmic.errors import IRError
from lmic.ir import expr as _expr
from lmic.ir.problem import (
    LMI,
    Check,
    LinearConstraints,
    NamedExpr,
    Objective,
    Problem,
    Variable,
)
from lmic.ir.svec import tril_size
from lmic.limits import (
    MAX_DIMENSION,
    MAX_INPUT_BYTES,
    MAX_INT_DIGITS,
    MAX_NONZEROS,
    MAX_VARIABLES,
    check_alloc,
    check_depth,
    check_size,
)

__all__ = [
    "IR_VERSION",
    "problem_to_dict",
    "problem_from_dict",
    "problem_to_json",
    "problem_from_json",
    "dump_problem",
    "load_problem_json",
    "problem_hash",
    "validate_ir_dict",
]

#: Version of the JSON format written (``"lmic_ir"``).
IR_VERSION = 1

_TOP_KEYS = ("lmic_ir", "meta", "variables", "lmis", "linear", "objective", "data", "derived", "checks")


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


def _fmt_path(parts: Any) -> str:
    out = ""
    for p in parts:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else str(p))
    return out or "(top level)"


def _first_nonfinite(obj: Any, path: str) -> str | None:
    """Path of the first NaN/Inf float inside a loaded JSON value, or None."""
    if isinstance(obj, float):
        return None if math.isfinite(obj) else path
    if isinstance(obj, dict):
        for k, v in obj.items():
            hit = _first_nonfinite(v, f"{path}.{k}" if path else k)
            if hit:
                return hit
    elif isinstance(obj, list) and obj:
        try:
            arr = np.asarray(obj)  # fast path: a (nested) list of numbers
        except (ValueError, TypeError, OverflowError):
            arr = None
        if arr is not None and arr.dtype.kind in "iub":
            return None
        if arr is not None and arr.dtype.kind == "f":
            bad = np.argwhere(~np.isfinite(arr))
            return f"{path}" + "".join(f"[{i}]" for i in bad[0]) if bad.size else None
        for i, v in enumerate(obj):
            hit = _first_nonfinite(v, f"{path}[{i}]")
            if hit:
                return hit
    return None


@lru_cache(maxsize=1)
def _validator() -> Any:
    import jsonschema

    from lmic.schemas import load_schema

    schema = load_schema("ir")
    cls = jsonschema.validators.validator_for(schema)
    return cls(schema)


def _one_line(text: str, limit: int = 160) -> str:
    text = " ".join(str(text).split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


# jsonschema spends microseconds per array item, so the schema sees only a prefix of the
# potentially long homogeneous arrays (coefficient triplets, the linear rows' kinds / strict /
# names, numeric data); problem_from_dict checks those completely with numpy.
_PREFIX = 8
_LONG_KEYS = ("row", "col", "val", "idx", "kinds", "strict", "names")


def _prefix(v: Any) -> Any:
    if isinstance(v, list):
        return [_prefix(e) for e in v[:_PREFIX]]
    return v


def _skeleton(d: Any, key: str = "") -> Any:
    """``d`` with the long homogeneous arrays cut to a prefix (see above)."""
    if isinstance(d, dict):
        if key == "data":
            return {k: _prefix(v) for k, v in d.items()}
        return {k: (v[:_PREFIX] if k in _LONG_KEYS and isinstance(v, list) else _skeleton(v, k)) for k, v in d.items()}
    if isinstance(d, list):
        return [_skeleton(v) for v in d]
    return d


def validate_ir_dict(d: Any, source: str = "<dict>") -> None:
    """Validate a loaded IR dict against ``schemas/ir.schema.json``.

    Only the schema: the semantic checks (index ranges, shapes, offsets) happen in
    :func:`problem_from_dict`.

    Parameters
    ----------
    d : object
        The decoded JSON.
    source : str
        Names the input in error messages.

    Raises
    ------
    IRError
        On the first (most relevant) violation, naming ``source`` and the field.

    Examples
    --------
    >>> validate_ir_dict({"lmic_ir": 1}, "ir.json")
    Traceback (most recent call last):
    ...
    lmic.errors.IRError: ir.json: (top level): 'variables' is a required property
    """
    import jsonschema

    errors = list(_validator().iter_errors(_skeleton(d)))
    if not errors:
        return
    err = jsonschema.exceptions.best_match(errors)
    # for oneOf failures inside a field, the deepest context is the useful one
    while err.context:
        err = jsonschema.exceptions.best_match(err.context)
    raise IRError(f"{source}: {_fmt_path(err.absolute_path)}: {_one_line(err.message)}")


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
# dict -> Problem


def _index_array(values: list, where: str) -> np.ndarray:
    """A flat int64 array from a list of non-negative integers (checked with numpy)."""
    try:
        arr = np.asarray(values)
    except (TypeError, ValueError, OverflowError):
        raise IRError(f"{where}: expected a list of integers") from None
    if arr.size == 0:
        return np.zeros(0, dtype=np.int64)
    if arr.ndim != 1 or arr.dtype.kind not in "iu":
        raise IRError(f"{where}: expected a list of integers")
    arr = arr.astype(np.int64)
    if arr.min() < 0:
        raise IRError(f"{where}[{int(np.argmin(arr))}]: negative index {int(arr.min())}")
    return arr


def _value_array(values: list, where: str) -> np.ndarray:
    """A flat float array from a list of finite numbers (checked with numpy)."""
    try:
        arr = np.asarray(values)
    except (TypeError, ValueError, OverflowError):
        raise IRError(f"{where}: expected a list of numbers") from None
    if arr.size == 0:
        return np.zeros(0)
    if arr.ndim != 1 or arr.dtype.kind not in "iuf":
        raise IRError(f"{where}: expected a list of numbers")
    arr = arr.astype(float)
    bad = np.flatnonzero(~np.isfinite(arr))
    if bad.size:
        raise IRError(f"{where}[{bad[0]}]: {arr[bad[0]]} is not a finite number")
    return arr


def _sparse(t: Mapping[str, Any], shape: tuple[int, int], where: str, what: str) -> sp.csc_matrix:
    """A sparse matrix from ``{"row", "col", "val"}`` with range and duplicate checks."""
    row = _index_array(t["row"], f"{where}.row")
    col = _index_array(t["col"], f"{where}.col")
    val = _value_array(t["val"], f"{where}.val")
    if not (len(row) == len(col) == len(val)):
        raise IRError(f"{where}: row, col and val have different lengths ({len(row)}, {len(col)}, {len(val)})")
    nr, nc = shape
    if row.size and row.max() >= nr:
        raise IRError(f"{where}: row index {int(row.max())} out of range for {what}")
    if col.size and col.max() >= nc:
        raise IRError(f"{where}: col index {int(col.max())} out of range for 1 + n = {nc} columns")
    if row.size:
        key = col * nr + row
        uniq, first, counts = np.unique(key, return_index=True, return_counts=True)
        if uniq.size != key.size:
            k = int(uniq[np.argmax(counts > 1)])
            raise IRError(f"{where}: duplicate entry (row {k % nr}, col {k // nr})")
    return sp.csc_matrix((val, (row, col)), shape=shape)


def _wrap(source: str, where: str, fn: Any, *args: Any, **kwargs: Any) -> Any:
    try:
        return fn(*args, **kwargs)
    except IRError as err:
        raise IRError(f"{source}: {where}: {err}") from None


def _load_data(value: Any, where: str) -> float | np.ndarray:
    if isinstance(value, bool) or not isinstance(value, int | float | list):
        raise IRError(f"{where}: {type(value).__name__} is not a number or a nested list")
    if not isinstance(value, list):
        return float(value)
    try:
        arr = np.array(value)
    except (ValueError, TypeError, OverflowError):
        raise IRError(f"{where}: ragged or non-numeric nested list") from None
    if arr.size and arr.dtype.kind not in "iuf":
        raise IRError(f"{where}: ragged or non-numeric nested list")
    arr = arr.astype(float)
    if not np.all(np.isfinite(arr)):
        raise IRError(f"{where}: has a non-finite entry")
    return arr


def _check_declared_sizes(d: Mapping[str, Any], source: str) -> None:
    """Declared sizes against :mod:`lmic.limits` and the data present, before any allocation."""
    for i, v in enumerate(d["variables"]):
        for k, s in enumerate(v["shape"]):
            check_size(s, MAX_VARIABLES, f"variables[{i}].shape[{k}]", source, IRError)
        check_size(v["offset"], MAX_VARIABLES, f"variables[{i}].offset", source, IRError)
        for k, b in enumerate(v.get("blocks", [])):
            check_size(b, MAX_DIMENSION, f"variables[{i}].blocks[{k}]", source, IRError)
    dense = 0
    entries = 0
    for i, m in enumerate(d["lmis"]):
        dim = check_size(m["dim"], MAX_DIMENSION, f"lmis[{i}].dim", source, IRError)
        for k, b in enumerate(m.get("block_sizes", [])):
            check_size(b, MAX_DIMENSION, f"lmis[{i}].block_sizes[{k}]", source, IRError)
        dense += 8 * dim * dim
        coeffs = m["coeffs"]
        entries += max(len(coeffs.get("row", [])), len(coeffs.get("val", [])))
    check_alloc(dense, "the LMIs (dense)", source, IRError)
    lin = d["linear"]
    check_size(len(lin["kinds"]), MAX_NONZEROS, "linear rows", source, IRError)
    entries += len(lin.get("row", []))
    check_size(entries, MAX_NONZEROS, "coefficient entries", source, IRError)


def problem_from_dict(d: Any, source: str = "<dict>") -> Problem:
    """Build a :class:`Problem` from a decoded IR dict, validating it fully.

    Parameters
    ----------
    d : dict
        As produced by :func:`problem_to_dict` or decoded from an IR file.
    source : str
        Names the input in error messages (a file name).

    Returns
    -------
    Problem

    Raises
    ------
    IRError
        One line naming ``source`` and the field at fault: schema violations, unsupported
        version, index out of range, duplicate entries, inconsistent offsets or shapes,
        non-finite numbers, expressions that use unknown names.

    Examples
    --------
    >>> d = {"lmic_ir": 1, "variables": [{"name": "t", "kind": "scalar", "shape": [1, 1],
    ...      "offset": 0}], "lmis": [{"name": "t > 0", "dim": 1, "strict": True,
    ...      "coeffs": {"row": [0], "col": [1], "val": [1.0]}}],
    ...      "linear": {"row": [], "col": [], "val": [], "kinds": [], "strict": [], "names": []},
    ...      "objective": {"sense": "feasibility", "c": {"idx": [], "val": []}}}
    >>> problem_from_dict(d).lmis[0].matrix([2.0])
    array([[2.]])
    >>> d["lmis"][0]["coeffs"]["row"] = [3]
    >>> problem_from_dict(d, "ir.json")
    Traceback (most recent call last):
    ...
    lmic.errors.IRError: ir.json: lmis[0].coeffs: row index 3 out of range for dimension 1
    """
    if not isinstance(d, Mapping):
        raise IRError(f"{source}: an IR must be a JSON object, not {type(d).__name__}")
    if "lmic_ir" not in d:
        raise IRError(f"{source}: lmic_ir: missing format version (not an lmic IR file?)")
    if d["lmic_ir"] != IR_VERSION or isinstance(d["lmic_ir"], bool):
        raise IRError(f"{source}: lmic_ir: unsupported IR version {d['lmic_ir']!r} (this lmic reads {IR_VERSION})")
    bad = _first_nonfinite(dict(d), "")
    if bad:
        raise IRError(f"{source}: {bad}: NaN or infinite number")
    validate_ir_dict(dict(d), source)
    _check_declared_sizes(d, source)

    # variables
    variables: list[Variable] = []
    offset = 0
    seen: set[str] = set()
    for i, v in enumerate(d["variables"]):
        where = f"variables[{i}]"
        if v["name"] in seen:
            raise IRError(f"{source}: {where}.name: duplicate variable name '{v['name']}'")
        seen.add(v["name"])
        var = _wrap(
            source,
            where,
            Variable,
            v["name"],
            v["kind"],
            (int(v["shape"][0]), int(v["shape"][1])),
            offset=int(v["offset"]),
            blocks=tuple(int(b) for b in v.get("blocks", [])),
            sign=v.get("sign", "free"),
        )
        if var.kind != "blockdiag" and var.blocks:
            raise IRError(f"{source}: {where}.blocks: only a blockdiag variable has blocks")
        if var.offset != offset:
            raise IRError(f"{source}: {where}.offset: {var.offset}, expected {offset}")
        offset += var.size
        if offset > MAX_VARIABLES:
            raise IRError(f"{source}: {where}: more than {MAX_VARIABLES} variables in all")
        variables.append(var)
    n = offset

    # LMIs
    lmis: list[LMI] = []
    for i, m in enumerate(d["lmis"]):
        where = f"lmis[{i}]"
        dim = int(m["dim"])
        sizes = tuple(int(b) for b in m.get("block_sizes", [])) or (dim,)
        if sum(sizes) != dim:
            raise IRError(f"{source}: {where}.block_sizes: {list(sizes)} do not add up to dimension {dim}")
        try:
            coeffs = _sparse(m["coeffs"], (tril_size(dim), 1 + n), f"{where}.coeffs", f"dimension {dim}")
        except IRError as err:
            raise IRError(f"{source}: {err}") from None
        lmis.append(
            _wrap(
                source,
                where,
                LMI,
                m["name"],
                dim,
                coeffs,
                strict=bool(m.get("strict", True)),
                relation=m.get("relation", ">" if m.get("strict", True) else ">="),
                block_sizes=sizes,
            )
        )

    # linear constraints
    lin = d["linear"]
    rows = len(lin["kinds"])
    if not (len(lin["strict"]) == len(lin["names"]) == rows):
        raise IRError(
            f"{source}: linear: kinds, strict and names have different lengths "
            f"({rows}, {len(lin['strict'])}, {len(lin['names'])})"
        )
    for i, (kind, strict, name) in enumerate(zip(lin["kinds"], lin["strict"], lin["names"], strict=True)):
        if kind not in ("eq", "ge"):
            raise IRError(f"{source}: linear.kinds[{i}]: {kind!r} is not 'eq' or 'ge'")
        if type(strict) is not bool:
            raise IRError(f"{source}: linear.strict[{i}]: {strict!r} is not a boolean")
        if not isinstance(name, str):
            raise IRError(f"{source}: linear.names[{i}]: {name!r} is not a string")
    try:
        A = _sparse(lin, (rows, 1 + n), "linear", f"{rows} rows")
    except IRError as err:
        raise IRError(f"{source}: {err}") from None
    linear = _wrap(
        source,
        "linear",
        LinearConstraints,
        A.tocsr(),
        list(lin["kinds"]),
        [bool(s) for s in lin["strict"]],
        [str(s) for s in lin["names"]],
    )

    # objective
    obj = d["objective"]
    try:
        idx = _index_array(obj["c"]["idx"], "objective.c.idx")
        val = _value_array(obj["c"]["val"], "objective.c.val")
    except IRError as err:
        raise IRError(f"{source}: {err}") from None
    if len(idx) != len(val):
        raise IRError(f"{source}: objective.c: idx and val have different lengths ({len(idx)}, {len(val)})")
    if idx.size and idx.max() >= 1 + n:
        raise IRError(f"{source}: objective.c: index {int(idx.max())} out of range for 1 + n = {1 + n} entries")
    if np.unique(idx).size != idx.size:
        raise IRError(f"{source}: objective.c: duplicate index")
    c = np.zeros(1 + n)
    c[idx] = val
    objective = _wrap(source, "objective", Objective, obj["sense"], c)

    # data, derived quantities, checks
    data: dict[str, Any] = {}
    for k, v in d.get("data", {}).items():
        try:
            data[k] = _load_data(v, f"data.{k}")
        except IRError as err:
            raise IRError(f"{source}: {err}") from None
    known = set(data) | {v.name for v in variables}
    derived: list[NamedExpr] = []
    for i, item in enumerate(d.get("derived", [])):
        where = f"derived[{i}].expr"
        _wrap(source, where, _expr.validate, item["expr"], "expression")
        unknown = sorted(_expr.names(item["expr"]) - known)
        if unknown:
            raise IRError(
                f"{source}: {where}: uses '{unknown[0]}', which is not data, a variable or an earlier derived quantity"
            )
        derived.append(NamedExpr(item["name"], item["expr"], item.get("doc", "")))
        known.add(item["name"])
    checks: list[Check] = []
    for i, item in enumerate(d.get("checks", [])):
        where = f"checks[{i}]"
        _wrap(source, f"{where}.expr", _expr.validate, item["expr"], "expression")
        unknown = sorted(_expr.names(item["expr"]) - known)
        if unknown:
            raise IRError(
                f"{source}: {where}.expr: uses '{unknown[0]}', which is not data, a variable or a derived quantity"
            )
        bound = item.get("bound")
        if item["kind"] in ("less_than", "greater_than") and bound is None:
            raise IRError(f"{source}: {where}.bound: a '{item['kind']}' check needs a bound")
        checks.append(
            _wrap(
                source,
                where,
                Check,
                item["name"],
                item["kind"],
                item["expr"],
                None if bound is None else float(bound),
                item.get("doc", ""),
            )
        )

    return _wrap(
        source,
        "problem",
        Problem,
        variables,
        lmis,
        linear,
        objective,
        data=data,
        derived=derived,
        checks=checks,
        meta=dict(d.get("meta", {})),
    )


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


def _reject_constant(name: str) -> float:
    # NaN / Infinity literals load as NaN so that the field check can name where they are
    return float("nan")


def _no_duplicate_keys(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for k, v in pairs:
        if k in out:
            raise _DuplicateKey(k)
        out[k] = v
    return out


class _DuplicateKey(ValueError):
    pass


def problem_from_json(text: str, source: str = "<string>") -> Problem:
    """Parse IR JSON text (see :func:`problem_from_dict` for the checks).

    Examples
    --------
    >>> problem_from_json('{"lmic_ir": 1, "variables": [', "ir.json")
    Traceback (most recent call last):
    ...
    lmic.errors.IRError: ir.json: not valid JSON (line 1, column 30): Expecting value
    """
    try:
        d = json.loads(
            text,
            parse_constant=_reject_constant,
            object_pairs_hook=_no_duplicate_keys,
            parse_int=lambda t: _parse_int(t, source),
        )
    except _DuplicateKey as err:
        raise IRError(f"{source}: duplicate key '{err.args[0]}'") from None
    except json.JSONDecodeError as err:
        raise IRError(f"{source}: not valid JSON (line {err.lineno}, column {err.colno}): {err.msg}") from None
    except RecursionError:
        raise IRError(f"{source}: not valid JSON (nested too deeply)") from None
    check_depth(d, source, IRError)
    return problem_from_dict(d, source)


def _parse_int(text: str, source: str) -> int:
    digits = len(text.lstrip("-"))
    if digits > MAX_INT_DIGITS:
        raise IRError(f"{source}: an integer of {digits} digits (at most {MAX_INT_DIGITS})")
    return int(text)


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
    >>> load_problem_json(f).objective.c
    array([0., 1.])
    """
    from lmic.output import write_output

    write_output(path, problem_to_json(problem))  # atomic: nothing half-written


def load_problem_json(path: str | os.PathLike[str]) -> Problem:
    """Read and validate an IR JSON file.

    Errors name the file as given (``path``) and the field.

    Examples
    --------
    >>> load_problem_json("/nonexistent/ir.json")
    Traceback (most recent call last):
    ...
    lmic.errors.IRError: /nonexistent/ir.json: cannot read: No such file or directory
    """
    source = os.fspath(path)
    try:
        size = os.stat(path).st_size
        if size > MAX_INPUT_BYTES:
            raise IRError(f"{source}: file of {size} bytes exceeds the input limit of {MAX_INPUT_BYTES}")
        raw = Path(path).read_bytes()
    except OSError as err:
        raise IRError(f"{source}: cannot read: {err.strerror or err}") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as err:
        raise IRError(f"{source}: not UTF-8 text (byte {err.start})") from None
    return problem_from_json(text, source)


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
