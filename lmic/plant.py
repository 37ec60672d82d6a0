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

__all__ = ["as_system", "is_statespace", "TimebaseNote"]

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


class TimebaseNote(UserWarning):
    """A python-control plant whose time base (``dt``) contradicts the theorem's system class."""


def _check_timebase(theorem: Any, ss: Any) -> None:
    """Warn (:class:`TimebaseNote`) when a plant's ``dt`` says continuous time (``dt = 0``) and the
    theorem's ``system_class`` says discrete time, or the other way round (``dt > 0`` or
    ``True``). The matrices are taken as they are either way: the theorem decides what they mean.

    >>> import warnings, numpy as np
    >>> class SS:
    ...     A, B, C, D, dt = -np.eye(2), np.ones((2, 1)), np.eye(1, 2), np.zeros((1, 1)), 0
    >>> with warnings.catch_warnings(record=True) as w:
    ...     warnings.simplefilter("always")
    ...     _ = as_system("uio_dt.thm3_1", SS())
    >>> print(w[0].message)
    the plant is continuous-time (dt = 0) but theorem uio_dt.thm3_1 is for discrete time systems (its system class: ...)
    """
    import warnings

    from lmic.registry import get_theorem
    from lmic.template.theorem import Theorem

    dt = getattr(ss, "dt", None)
    if dt is None or isinstance(dt, str):
        return
    thm = theorem if isinstance(theorem, Theorem) else get_theorem(str(theorem))
    cls = str(getattr(thm, "system_class", "") or "").lower()
    discrete_plant = dt is True or (not isinstance(dt, bool) and float(dt) > 0)
    continuous_plant = not discrete_plant and dt is not False and float(dt) == 0
    has_d, has_c = "discrete" in cls, "continuous" in cls  # a class naming both (sampled data) fits either
    said = (has_d and not has_c and continuous_plant) or (has_c and not has_d and discrete_plant)
    if said:
        kind = "continuous-time (dt = 0)" if continuous_plant else f"discrete-time (dt = {dt})"
        other = "discrete" if continuous_plant else "continuous"
        warnings.warn(
            TimebaseNote(
                f"the plant is {kind} but theorem {thm.id} is for {other} time systems "
                f"(its system class: {thm.system_class})"
            ),
            stacklevel=3,
        )


def as_system(theorem: Any, system: Any) -> Any:
    """Turn a ``StateSpace`` (or ``{"plant": ss, ...}``) into a system dict; pass anything else on."""
    if is_statespace(system):
        _check_timebase(theorem, system)
        return {"lmic": 1, "name": "python-control plant", "data": _plant_data(theorem, system)}
    if isinstance(system, dict) and "plant" in system:
        _check_timebase(theorem, system["plant"])
        rest = {k: v for k, v in system.items() if k != "plant"}
        data = dict(_plant_data(theorem, system["plant"]))
        data.update(rest.get("data") or {})
        rest["data"] = data
        rest.setdefault("lmic", 1)
        return rest
    return system
