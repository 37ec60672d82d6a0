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


def to_jsonable(obj: Any) -> Any:
    """numpy arrays and scalars -> lists and floats, recursively (non-finite floats -> None).

    Examples
    --------
    >>> to_jsonable((np.float32(0.5), [np.nan], np.bool_(True)))
    [0.5, [None], True]
    """
    if isinstance(obj, dict):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist())
    if isinstance(obj, np.bool_):
        return bool(obj)
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, float | np.floating):
        f = float(obj)
        return f if math.isfinite(f) else None
    return obj
