"""Deprecated alias module: the backend interface now lives in one module per job.

``lmic.backends.base`` did six jobs; they moved (old -> new):

==========================================  ==============================================
``SolveOptions``                            :mod:`lmic.options`
``Backend``                                 :mod:`lmic.backends.backend`
``ConicData``, ``conic_data``,              :mod:`lmic.backends.lowering` (:class:`SForm`,
``full_vec_map``, ``full_vec_coo``,         :class:`LMIForm`, apply/invert)
``problem_kinds``
``quiet_native``                            :mod:`lmic.backends.quiet`
the fork-based time limit (``_sandboxed``)  :mod:`lmic.backends.sandbox`
``eliminate_unused``,                       :mod:`lmic.reductions.eliminate` (engine layer;
``independent_columns``,                    loaded here on first use only, so the backends
``restore_eliminated``                      layer never imports the engine)
==========================================  ==============================================

Import from the new modules; this one re-exports the old names.

Examples
--------
>>> SolveOptions(tol=1e-9).tol
1e-09
>>> from lmic.backends.base import eliminate_unused
>>> eliminate_unused.__module__
'lmic.reductions.eliminate'
"""

from __future__ import annotations

import importlib
from typing import Any

from lmic.backends.backend import Backend
from lmic.backends.lowering import ConicData, conic_data, full_vec_coo, full_vec_map, problem_kinds
from lmic.backends.quiet import quiet_native
from lmic.options import SolveOptions

__all__ = [
    "SolveOptions",
    "Backend",
    "ConicData",
    "conic_data",
    "problem_kinds",
    "full_vec_map",
    "full_vec_coo",
    "quiet_native",
]

_MOVED_UP = {"eliminate_unused", "independent_columns", "restore_eliminated"}


def __getattr__(name: str) -> Any:
    """The names that moved to the engine layer, loaded on first use (PEP 562)."""
    if name in _MOVED_UP:
        module = importlib.import_module(".".join(("lmic", "reductions", "eliminate")))
        return getattr(module, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
