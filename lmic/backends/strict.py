"""Deprecated alias of :mod:`lmic.reductions.strict` (the strict reductions left ``backends/``).

The reductions are the engine's (a layer above the backends), so this module loads them on first
attribute access (PEP 562 ``__getattr__``, module name computed) instead of importing them: the
backends layer's import graph stays free of the engine. Import :mod:`lmic.reductions.strict`.

>>> from lmic.backends.strict import plan
>>> plan.__module__
'lmic.reductions.strict'
"""

from __future__ import annotations

import importlib
from typing import Any


def _target() -> Any:
    return importlib.import_module(".".join(("lmic", "reductions", "strict")))


def __getattr__(name: str) -> Any:
    """Every name of :mod:`lmic.reductions.strict` (private ones included), on first use."""
    try:
        return getattr(_target(), name)
    except AttributeError:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None


def __dir__() -> list[str]:
    return sorted(dir(_target()))
