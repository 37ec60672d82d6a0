"""Deprecated alias of :mod:`lmic.studies.sweep` (suprema, infima and grids over one parameter).

.. deprecated::
    Import from :mod:`lmic.studies.sweep` (or its modules ``results``, ``points``, ``ends``,
    ``bisect``, ``enclosed``, ``grid``). This module only re-exports their names, so that code
    written against ``lmic.sweep`` keeps working.

Examples
--------
>>> from lmic.sweep import parse_grid
>>> parse_grid("alpha=log:1e-3:1:4")
('alpha', [0.001, 0.01, 0.1, 1.0])
"""

from __future__ import annotations

from lmic.policy import exact_rescue_point as _exact_rescue
from lmic.studies.sweep import (
    OUTCOMES,
    EndPoint,
    PointResult,
    SupResult,
    SweepResult,
    certified_end,
    decide,
    maximize,
    minimize,
    parse_grid,
    precondition,
    sweep,
    write_end_certificate,
)
from lmic.studies.sweep.points import scalar_derived as _scalar_derived

__all__ = [
    "OUTCOMES",
    "PointResult",
    "SupResult",
    "EndPoint",
    "certified_end",
    "write_end_certificate",
    "SweepResult",
    "decide",
    "precondition",
    "maximize",
    "minimize",
    "sweep",
    "parse_grid",
    "_exact_rescue",
    "_scalar_derived",
]
