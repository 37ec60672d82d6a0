"""Validation of the IR's JSON form: the schema (``schemas/ir.schema.json``) and non-finite numbers.

Part of :mod:`lmic.ir.jsonio` (the format is described there). Every failure is an
:class:`~lmic.errors.IRError` of one line naming the source and the field.

Examples
--------
>>> validate_ir_dict({"lmic_ir": 1}, "x.json")
Traceback (most recent call last):
...
lmic.errors.IRError: x.json: (top level): 'variables' is a required property
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Any

import numpy as np

from lmic.errors import IRError

__all__ = ["IR_VERSION", "validate_ir_dict", "first_nonfinite"]

#: Version of the JSON format written (``"lmic_ir"``).
IR_VERSION = 1

_TOP_KEYS = ("lmic_ir", "meta", "variables", "lmis", "linear", "objective", "data", "derived", "checks")


def _fmt_path(parts: Any) -> str:
    out = ""
    for p in parts:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else str(p))
    return out or "(top level)"


def first_nonfinite(obj: Any, path: str) -> str | None:
    """Path of the first NaN/Inf float inside a loaded JSON value, or None."""
    if isinstance(obj, float):
        return None if math.isfinite(obj) else path
    if isinstance(obj, dict):
        for k, v in obj.items():
            hit = first_nonfinite(v, f"{path}.{k}" if path else k)
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
            hit = first_nonfinite(v, f"{path}[{i}]")
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
