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
import yaml

from lmic.errors import DataError

__all__ = ["System", "load_system", "parse_matrix", "canonical_json", "UnusedDataNote", "edit_distance", "near_miss"]


class UnusedDataNote(UserWarning):
    """Data keys of a system file that the theorem does not take (shown as a note, not an error).

    One plant file may serve several theorems; the command line prints ``lmic: note: ...``.
    """


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


_NUMBER = re.compile(r"^[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$")


def _is_number(v: Any) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool)


def _number_literal(v: Any) -> Any:
    """YAML 1.1 reads ``1e-5`` (no dot) as a string: accept plain float literals, nothing else."""
    if isinstance(v, str) and _NUMBER.match(v.strip()):
        return float(v)
    return v


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
    if _is_number(value):
        arr = np.array([[float(value)]])
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
        for i, row in enumerate(value):
            if len(row) != width:
                raise DataError(f"{where}: row {i + 1} has {len(row)} entries, row 1 has {width}")
            for j, v in enumerate(row):
                if not _is_number(v):
                    raise DataError(f"{where}: entry ({i + 1},{j + 1}) is {v!r}, not a number")
        if width == 0:
            raise DataError(f"{where}: has empty rows")
        arr = np.array(value, dtype=float)
    else:
        raise DataError(f"{where}: is {type(value).__name__} {value!r}, not a number or a matrix")
    bad = ~np.isfinite(arr)
    if bad.any():
        i, j = np.argwhere(bad)[0]
        raise DataError(f"{where}: entry ({i + 1},{j + 1}) is {arr[i, j]} (NaN and Inf are not allowed)")
    return arr


def _read_file(path: Path) -> Any:
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise DataError(f"{path}: no such file") from None
    except IsADirectoryError:
        raise DataError(f"{path}: is a directory, not a system file") from None
    except (OSError, UnicodeDecodeError) as err:
        raise DataError(f"{path}: cannot be read ({err})") from None
    try:
        if path.suffix.lower() == ".json":
            return json.loads(text)
        return yaml.safe_load(text)
    except json.JSONDecodeError as err:
        raise DataError(f"{path.name}: malformed JSON at line {err.lineno}: {err.msg}") from None
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        line = f" at line {mark.line + 1}" if mark is not None else ""
        problem = getattr(err, "problem", None) or str(err).splitlines()[0]
        raise DataError(f"{path.name}: malformed YAML{line}: {problem}") from None


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
    version = raw.get("lmic", 1)
    if version not in SUPPORTED_VERSIONS:
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
            if not math.isfinite(float(value)):
                raise DataError(f"{where}: parameter '{key}' is {value} (NaN and Inf are not allowed)")
            params[key] = float(value)
        elif isinstance(value, str):
            params[key] = value
        else:
            raise DataError(f"{where}: parameter '{key}' is {value!r}, not a number or an option name")
    published_raw = raw.get("published") or {}
    if not isinstance(published_raw, dict):
        raise DataError(f"{where}: 'published' must be a mapping")
    published: dict[str, Any] = {}
    for key, value in published_raw.items():
        value = _number_literal(value)
        if isinstance(value, str):
            published[key] = value
        elif _is_number(value):
            published[key] = float(value)
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
