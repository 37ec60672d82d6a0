"""Plant matrices from python-control ``StateSpace`` objects (or anything with ``A, B, C, D``).

The Python API accepts, wherever a system is expected, a ``StateSpace``-like object or a dict
``{"plant": ss, "data": {...}, "params": {...}}``; the plant's ``A``, ``B``, ``C``, ``D`` become
the data keys of the same names that the theorem declares (others are ignored).

Examples
--------
>>> import numpy as np
>>> class SS:  # any object with A, B, C, D attributes works (python-control's StateSpace does)
...     A, B, C, D = -np.eye(2), np.ones((2, 1)), np.eye(1, 2), np.zeros((1, 1))
>>> sys = as_system("thesis.lyapunov", SS())
>>> sorted(sys["data"])
['A']
"""

from __future__ import annotations

from typing import Any

import numpy as np

from lmic.errors import DataError

__all__ = ["as_system", "is_statespace"]

_ROLES = ("A", "B", "C", "D")


def is_statespace(obj: Any) -> bool:
    """True for python-control ``StateSpace`` objects and look-alikes (``A, B, C, D`` arrays)."""
    return all(hasattr(obj, k) for k in _ROLES) and not isinstance(obj, dict | str)


def _declared(theorem: Any) -> set[str]:
    from lmic.registry import get_theorem
    from lmic.template.theorem import Theorem

    thm = theorem if isinstance(theorem, Theorem) else get_theorem(str(theorem))
    return {d.name for d in thm.template().data_decls}


def _plant_data(theorem: Any, ss: Any) -> dict[str, Any]:
    declared = _declared(theorem)
    out = {}
    for key in _ROLES:
        if key in declared:
            value = np.atleast_2d(np.asarray(getattr(ss, key), dtype=float))
            if value.size:
                out[key] = value
    if not out:
        raise DataError(f"the plant gives {', '.join(_ROLES)} but the theorem takes none of them: pass 'data'")
    return out


def as_system(theorem: Any, system: Any) -> Any:
    """Turn a ``StateSpace`` (or ``{"plant": ss, ...}``) into a system dict; pass anything else on."""
    if is_statespace(system):
        return {"lmic": 1, "name": "python-control plant", "data": _plant_data(theorem, system)}
    if isinstance(system, dict) and "plant" in system:
        rest = {k: v for k, v in system.items() if k != "plant"}
        data = dict(_plant_data(theorem, system["plant"]))
        data.update(rest.get("data") or {})
        rest["data"] = data
        rest.setdefault("lmic", 1)
        return rest
    return system
