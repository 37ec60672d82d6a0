"""JSON conversion shared by every layer: numpy arrays and scalars to plain JSON values.

Examples
--------
>>> import numpy as np
>>> to_jsonable({"x": np.array([1.0, np.inf]), "n": np.int64(3)})
{'x': [1.0, None], 'n': 3}
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["to_jsonable"]

#: element types that to_jsonable returns unchanged when finite
_PLAIN = {float, int}


def to_jsonable(obj: Any, *, nonfinite: str = "null") -> Any:
    """numpy arrays and scalars -> lists and floats, recursively.

    Parameters
    ----------
    obj : Any
    nonfinite : {"null", "string"}
        How a non-finite float is written: ``None`` (``"null"``, the default), or the strings
        ``"nan"``, ``"inf"``, ``"-inf"`` (``"string"``, the form of certificate files, which keeps
        the sign of an infinite margin).

    Examples
    --------
    >>> to_jsonable((np.float32(0.5), [np.nan], np.bool_(True)))
    [0.5, [None], True]
    >>> to_jsonable({"m": -np.inf, "v": [np.nan]}, nonfinite="string")
    {'m': '-inf', 'v': ['nan']}
    """
    if nonfinite not in ("null", "string"):
        raise ValueError(f"nonfinite must be 'null' or 'string', got {nonfinite!r}")
    if isinstance(obj, dict):
        return {str(k): to_jsonable(v, nonfinite=nonfinite) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        if set(map(type, obj)) <= _PLAIN and all(map(math.isfinite, obj)):
            return list(obj)  # plain finite ints and floats (a matrix row): nothing to convert
        return [to_jsonable(v, nonfinite=nonfinite) for v in obj]
    if isinstance(obj, np.ndarray):
        if obj.dtype.kind in "iub" or (obj.dtype.kind == "f" and np.all(np.isfinite(obj))):
            return obj.tolist()  # already plain ints, floats and bools: no walk over the entries
        return to_jsonable(obj.tolist(), nonfinite=nonfinite)
    if isinstance(obj, np.bool_):
        return bool(obj)
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, float | np.floating):
        f = float(obj)
        if math.isfinite(f):
            return f
        if nonfinite == "null":
            return None
        return "nan" if math.isnan(f) else ("inf" if f > 0 else "-inf")
    return obj
