"""System files: load, validate and hash the numbers a theorem is compiled with.

A system file is YAML or JSON holding numbers only (nothing is ever evaluated)::

    lmic: 1
    name: Flexible joint robot
    data:                      # row-major nested lists; a column vector is [[1], [1]]
      A: [[1, 0.1], [-4.86, 0.874]]
      C: [[1, 0]]
    params: {beta: 0.00110889, gamma: 0, psi1: printed}
    published: {L: [[1.0], [2.49]]}

Unknown top-level keys are kept (for tools such as ``simulation:``).

Examples
--------
>>> s = load_system({"lmic": 1, "data": {"A": [[-1.0]]}, "params": {"beta": 0.5}})
>>> s.data["A"].shape, s.params["beta"]
((1, 1), 0.5)
>>> len(s.data_hash())
64
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from lmic.errors import DataError
from lmic.limits import MAX_DIMENSION, MAX_INT_DIGITS, check_depth, load_json_text, load_yaml_text, read_text

__all__ = [
    "System",
    "load_system",
    "parse_matrix",
    "canonical_json",
    "Note",
    "UnusedDataNote",
    "RoundingNote",
    "edit_distance",
    "near_miss",
]


class Note(UserWarning):
    """Something the user should know that is not an error: the command line prints
    ``lmic: note: ...`` (:class:`UnusedDataNote`, :class:`RoundingNote`)."""


class UnusedDataNote(Note):
    """Data keys of a system file that the theorem does not take (shown as a note, not an error).

    One plant file may serve several theorems; the command line prints ``lmic: note: ...``.
    """


class RoundingNote(Note):
    """A data-derived constant that is singular only up to rounding (a projector or a kernel
    computed in floating point): the compiled problem reads it as regular."""


def edit_distance(a: str, b: str) -> int:
    """Levenshtein distance (insertions, deletions, substitutions).

    >>> edit_distance("gama", "gamma"), edit_distance("Cw", "Cv"), edit_distance("B", "D")
    (1, 1, 1)
    """
    prev = list(range(len(b) + 1))
    for i, ca in enumerate(a, 1):
        cur = [i]
        for j, cb in enumerate(b, 1):
            cur.append(min(prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (ca != cb)))
        prev = cur
    return prev[-1]


def near_miss(key: str, candidates: list[str]) -> str | None:
    """The candidate ``key`` is probably a typo of: edit distance <= 2, and at most half the
    longer name (so that one-letter plant keys such as ``B`` and ``D`` are not typos of each other).

    >>> near_miss("Cv", ["Cw", "L"]), near_miss("B", ["D"]), near_miss("gama", ["gamma"])
    ('Cw', None, 'gamma')
    """
    best = None
    for c in candidates:
        d = edit_distance(key, c)
        if d <= min(2, max(len(key), len(c)) // 2) and (best is None or d < best[0]):
            best = (d, c)
    return None if best is None else best[1]


SUPPORTED_VERSIONS = (1,)


@dataclass
class System:
    """The numbers of one system: ``data`` matrices, ``params`` and ``published`` values."""

    data: dict[str, np.ndarray]
    params: dict[str, float | str] = field(default_factory=dict)
    published: dict[str, Any] = field(default_factory=dict)
    name: str = ""
    source: str = ""
    path: str | None = None
    raw: dict[str, Any] = field(default_factory=dict)

    @property
    def label(self) -> str:
        """How error messages name this system (its file name, or ``<system>``)."""
        return os.path.basename(self.path) if self.path else "<system>"

    def data_hash(self) -> str:
        """SHA-256 of ``data`` (names, shapes, float64 bytes) and ``params`` (what a certificate pins)."""
        h = hashlib.sha256(b"lmic-system-v1")
        for key in sorted(self.data):
            arr = np.ascontiguousarray(self.data[key], dtype="<f8")
            h.update(canonical_json([key, list(arr.shape)]).encode())
            h.update(arr.tobytes())
        h.update(canonical_json(dict(sorted(self.params.items()))).encode())
        return h.hexdigest()

    def with_params(self, overrides: dict[str, Any]) -> System:
        """A copy with some parameters overridden."""
        params = dict(self.params)
        params.update(overrides)
        return System(dict(self.data), params, dict(self.published), self.name, self.source, self.path, self.raw)


def canonical_json(obj: Any) -> str:
    """Deterministic JSON (sorted keys, no spaces, floats by repr) used for hashing.

    >>> canonical_json({"b": 1.0, "a": [0.1]})
    '{"a":[0.1],"b":1.0}'
    """
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), allow_nan=False)


#: plain float literals, ASCII digits only (``\d`` would take Unicode digits such as "١٢")
_NUMBER = re.compile(r"[-+]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][-+]?[0-9]+)?", re.ASCII)


def _is_number(v: Any) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool)


def _number_literal(v: Any) -> Any:
    """YAML 1.1 reads ``1e-5`` (no dot) as a string: accept plain float literals, nothing else."""
    if isinstance(v, str) and len(v) <= 2 * MAX_INT_DIGITS and _NUMBER.fullmatch(v.strip()):
        return float(v)
    return v


def _float(v: Any, where: str) -> float:
    """``float(v)`` for a number, or one line (an integer too large for a float64)."""
    try:
        f = float(v)
    except (OverflowError, ValueError):
        raise DataError(f"{where}: the number {str(v)[:20]}... is too large for a float64") from None
    if not math.isfinite(f):
        raise DataError(f"{where}: is {f} (NaN and Inf are not allowed)")
    return f


def parse_matrix(value: Any, where: str) -> np.ndarray:
    """A 2-D float array from a number or a rectangular nested list of numbers.

    Raises :class:`DataError` naming ``where`` for anything else (strings, ragged rows,
    flat lists, NaN or Inf).

    >>> parse_matrix([[1, 2], [3, 4]], "A").shape
    (2, 2)
    >>> parse_matrix([1, 2], "B")
    Traceback (most recent call last):
    ...
    lmic.errors.DataError: B: is a flat list; write a column as [[1], [2]] or a row as [[1, 2]]
    """
    if isinstance(value, np.ndarray):  # from the Python API
        value = value.tolist() if value.ndim else float(value)
    if isinstance(value, np.generic):
        value = value.item()
    value = _number_literal(value)
    fast = _plain_rows(value)
    if fast is not None:  # a rectangular list of lists of floats (and ints): one conversion
        arr = fast
    elif _is_number(value):
        arr = np.array([[_float(value, where)]])
    elif isinstance(value, list):
        value = [[_number_literal(v) for v in r] if isinstance(r, list) else _number_literal(r) for r in value]
        if not value:
            raise DataError(f"{where}: is an empty list")
        if all(_is_number(v) for v in value):
            items = ", ".join(str(v) for v in value[:2])
            col = "], [".join(str(v) for v in value[:2])
            raise DataError(f"{where}: is a flat list; write a column as [[{col}]] or a row as [[{items}]]")
        if not all(isinstance(r, list) for r in value):
            raise DataError(f"{where}: mixes numbers and rows; use a nested list of rows")
        width = len(value[0])
        if len(value) > MAX_DIMENSION or width > MAX_DIMENSION:
            raise DataError(f"{where}: {len(value)} x {width} exceeds the size limit {MAX_DIMENSION}")
        for i, row in enumerate(value):
            if len(row) != width:
                raise DataError(f"{where}: row {i + 1} has {len(row)} entries, row 1 has {width}")
            for j, v in enumerate(row):
                if not _is_number(v):
                    raise DataError(f"{where}: entry ({i + 1},{j + 1}) is {_show(v)}, not a number")
                if isinstance(v, int) and abs(v) >= 10**308:
                    raise DataError(f"{where}: entry ({i + 1},{j + 1}) is too large for a float64")
        if width == 0:
            raise DataError(f"{where}: has empty rows")
        arr = np.array(value, dtype=float)
    else:
        raise DataError(f"{where}: is {type(value).__name__} {_show(value)}, not a number or a matrix")
    bad = ~np.isfinite(arr)
    if bad.any():
        i, j = np.argwhere(bad)[0]
        raise DataError(f"{where}: entry ({i + 1},{j + 1}) is {arr[i, j]} (NaN and Inf are not allowed)")
    return arr


def _plain_rows(value: Any) -> np.ndarray | None:
    """``value`` as a float array when it is a non-empty rectangular list of non-empty lists of
    Python floats and ints (no bools, strings or anything else) within the size limit; else
    ``None`` (the entry-by-entry checks of :func:`parse_matrix` then name what is wrong)."""
    if not isinstance(value, list) or not value or not all(type(r) is list for r in value):
        return None
    width = len(value[0])
    if not width or len(value) > MAX_DIMENSION or width > MAX_DIMENSION or any(len(r) != width for r in value):
        return None
    kinds: set[type] = set()
    for row in value:
        kinds.update(map(type, row))
    if not kinds <= {float, int}:
        return None
    try:
        return np.array(value, dtype=float)
    except OverflowError:  # an integer too large for a float64: the slow path says which
        return None


def _show(v: Any) -> str:
    """A short repr for an error message (never a 5000-character one)."""
    text = repr(v)
    return text if len(text) <= 40 else text[:37] + "..."


def _no_duplicate_keys(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for k, v in pairs:
        if k in out:
            raise DataError(f"key {k!r} appears twice")
        out[k] = v
    return out


def _read_file(path: Path) -> Any:
    """Parse a system file within :mod:`lmic.limits` (size, depth, aliases, integers, duplicate keys)."""
    if path.is_dir():
        raise DataError(f"{path}: is a directory, not a system file")
    if not path.exists():
        raise DataError(f"{path}: no such file")
    text = read_text(path, str(path))
    if path.suffix.lower() == ".json":
        try:
            return load_json_text(text, path.name, object_pairs_hook=_no_duplicate_keys)
        except DataError as err:
            msg = str(err)
            raise DataError(msg if msg.startswith(path.name) else f"{path.name}: {msg}") from None
    return load_yaml_text(text, path.name)


def load_system(src: str | os.PathLike[str] | dict[str, Any] | System, label: str | None = None) -> System:
    """Load and validate a system file (YAML or JSON), a dict with the same keys, or a System.

    Parameters
    ----------
    src : path, dict or System
    label : str, optional
        Name used in error messages for a dict (default ``<system>``).

    Raises
    ------
    DataError
        One line naming the file, key and what is wrong.
    """
    if isinstance(src, System):
        return src
    path: str | None = None
    if isinstance(src, dict):
        raw = src
        where = label or "<system>"
    else:
        p = Path(src)
        raw = _read_file(p)
        path = str(p)
        where = p.name
    if not isinstance(raw, dict):
        raise DataError(f"{where}: a system file is a mapping with keys lmic, data, params")
    check_depth(raw, where)
    version = raw.get("lmic", 1)
    if isinstance(version, bool) or version not in SUPPORTED_VERSIONS:
        raise DataError(f"{where}: lmic: {version!r} is not a supported system-file version (1)")
    data_raw = raw.get("data")
    if data_raw is None:
        raise DataError(f"{where}: has no 'data' section")
    if not isinstance(data_raw, dict):
        raise DataError(f"{where}: 'data' must be a mapping of names to matrices")
    data = {}
    for key, value in data_raw.items():
        if not isinstance(key, str):
            raise DataError(f"{where}: data key {key!r} is not a name")
        data[key] = parse_matrix(value, f"{where}: data '{key}'")
    params_raw = raw.get("params") or {}
    if not isinstance(params_raw, dict):
        raise DataError(f"{where}: 'params' must be a mapping of names to numbers")
    params: dict[str, float | str] = {}
    for key, value in params_raw.items():
        if not isinstance(key, str):
            raise DataError(f"{where}: parameter key {key!r} is not a name")
        value = _number_literal(value)
        if _is_number(value):
            params[key] = _float(value, f"{where}: parameter '{key}'")
        elif isinstance(value, str):
            params[key] = value
        else:
            raise DataError(f"{where}: parameter '{key}' is {_show(value)}, not a number or an option name")
    published_raw = raw.get("published") or {}
    if not isinstance(published_raw, dict):
        raise DataError(f"{where}: 'published' must be a mapping")
    published: dict[str, Any] = {}
    for key, value in published_raw.items():
        value = _number_literal(value)
        if isinstance(value, str):
            published[key] = value
        elif _is_number(value):
            published[key] = _float(value, f"{where}: published '{key}'")
        else:
            published[key] = parse_matrix(value, f"{where}: published '{key}'")
    return System(
        data=data,
        params=params,
        published=published,
        name=str(raw.get("name", "")),
        source=str(raw.get("source", "")),
        path=path,
        raw=raw,
    )
