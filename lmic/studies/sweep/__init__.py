"""Studies over one scalar parameter of a theorem: suprema, infima and grids.

``lmic solve ... --maximize P`` / ``--minimize P`` / ``--sweep P=a:b:n``. Modules, by job:

- :mod:`~lmic.studies.sweep.results`: the result types (:class:`PointResult`,
  :class:`EndPoint`, :class:`SupResult`, :class:`SweepResult`);
- :mod:`~lmic.studies.sweep.points`: one value bound, decided by the solve policy, recorded
  (warm-started from the neighbouring point); for feasibility questions the last certified
  point is first certified again at the new value (``reuse``: no solve where it holds), and a
  bisection's interior values are decided by one certified solve (``screen``), the full policy
  deciding the bracket's final ends;
- :mod:`~lmic.studies.sweep.screens`: a bisection's cheap steps (one certified solve with a small
  margin, SCS first on the default route; the reach of a certified point, certified again
  further up without a solve);
- :mod:`~lmic.studies.sweep.ends`: the certified end of a bracket, its gains and certificate;
- :mod:`~lmic.studies.sweep.bisect`: suprema and infima by bisection;
- :mod:`~lmic.studies.sweep.enclosed`: suprema and infima of a parameter that enters affinely,
  solved once as a convex problem and enclosed (instead of bisected);
- :mod:`~lmic.studies.sweep.homogeneous`: a parameter multiplying one positive scalar of a
  scale-free theorem (fixed to 1, it enters affinely);
- :mod:`~lmic.studies.sweep.grid`: grids.

Examples
--------
>>> from lmic.studies.sweep import parse_grid
>>> parse_grid("eps=0.5:1.5:3")
('eps', [0.5, 1.0, 1.5])
"""

from __future__ import annotations

from lmic.reductions.precondition import precondition
from lmic.studies.sweep.bisect import maximize, minimize
from lmic.studies.sweep.ends import certified_end, write_end_certificate
from lmic.studies.sweep.grid import parse_grid, sweep
from lmic.studies.sweep.points import decide
from lmic.studies.sweep.results import OUTCOMES, EndPoint, PointResult, SupResult, SweepResult

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
]
