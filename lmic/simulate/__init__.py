"""Simulate a plant and its certified observer: ``lmic simulate``.

:mod:`~lmic.simulate.parser` parses the expressions of a system file's ``simulation:`` section
(safely: nothing is evaluated as code), :mod:`~lmic.simulate.models` holds the observer models
a theorem can declare, :mod:`~lmic.simulate.run` simulates, :mod:`~lmic.simulate.plot` draws
the figure.

Examples
--------
>>> from lmic.simulate import MODELS
>>> sorted(MODELS)
['euler', 'filter_error', 'luenberger', 'obs_control', 'reduced', 'robust', 'sampled', 'ui_filter', 'uio']
"""

from __future__ import annotations

from lmic.simulate.models import MODELS, Observer, make_observer
from lmic.simulate.parser import Expression, parse
from lmic.simulate.run import SimulationDiverged, SimulationSpec, Trajectory, read_spec, run, simulate

__all__ = [
    "MODELS",
    "Observer",
    "make_observer",
    "Expression",
    "parse",
    "SimulationDiverged",
    "SimulationSpec",
    "Trajectory",
    "read_spec",
    "run",
    "simulate",
]
