"""Deprecated alias of :mod:`lmic.studies.crosscheck` (the cross-check of backends moved there).

Examples
--------
>>> from lmic.crosscheck import crosscheck as a
>>> from lmic.studies.crosscheck import crosscheck as b
>>> a is b
True
"""

from __future__ import annotations

from lmic.studies.crosscheck import (
    DECISIONS,
    DEFAULT_RTOL,
    CrosscheckReport,
    Progress,
    assemble,
    backend_row,
    conflicts,
    crosscheck,
    error_row,
    status_class,
    target_label,
)

__all__ = [
    "CrosscheckReport",
    "crosscheck",
    "backend_row",
    "error_row",
    "assemble",
    "target_label",
    "status_class",
    "conflicts",
    "DEFAULT_RTOL",
    "DECISIONS",
    "Progress",
]
