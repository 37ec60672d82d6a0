"""Reading the IR from JSON: dict, text or file to a validated :class:`~lmic.ir.problem.Problem`.

Part of :mod:`lmic.ir.jsonio` (the format is described there). The schema is checked first
(:mod:`lmic.ir.jsonvalid`), then every index, size and number; each failure is one
:class:`~lmic.errors.IRError` line naming the source and the field.

Examples
--------
>>> problem_from_json('{"lmic_ir": 1}', "x.json")
Traceback (most recent call last):
...
lmic.errors.IRError: x.json: (top level): 'variables' is a required property
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import scipy.sparse as sp

from lmic.errors import IRError
from lmic.ir import expr as _expr
from lmic.ir.jsonvalid import IR_VERSION, first_nonfinite, validate_ir_dict
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

__all__ = ["problem_from_dict", "problem_from_json", "load_problem_json"]

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
    bad = first_nonfinite(dict(d), "")
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
