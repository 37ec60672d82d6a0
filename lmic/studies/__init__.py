"""Batch studies (``lmic batch``): many jobs on every core or on a Dask cluster, crash-safe.

Modules: :mod:`~lmic.studies.spec` (study files -> jobs), :mod:`~lmic.studies.plants` (random
plants), :mod:`~lmic.studies.tasks` (one job through the public API, the verdict mapping),
:mod:`~lmic.studies.runner` (the child process that runs jobs), :mod:`~lmic.studies.executors`
(local pool, Dask), :mod:`~lmic.studies.store` (results.jsonl, certificates, lock),
:mod:`~lmic.studies.driver` (run / resume), :mod:`~lmic.studies.report` (table, map, export,
status), :mod:`~lmic.studies.parallel` (``lmic reproduce --executor``). See docs/batch.md.

The names below are loaded on first use, so that a Dask worker unpickling a task imports only
the small runner module.

Examples
--------
>>> import tempfile
>>> from lmic.studies import load_study, run_study
>>> study = load_study({"theorem": "thesis.lyapunov",
...                     "systems": {"random": {"count": 2, "dims": {"n": 2}, "spectral_abscissa": {"A": -1.0}}}})
>>> run_study(study, tempfile.mkdtemp(), workers=1, progress=False).counts["certified"]
2
"""

from __future__ import annotations

import importlib
from typing import Any

__all__ = ["load_study", "run_study", "Study", "Job", "RunSummary", "OUTCOMES", "outcome"]

_WHERE = {
    "load_study": "spec",
    "Study": "spec",
    "Job": "spec",
    "run_study": "driver",
    "RunSummary": "driver",
    "OUTCOMES": "tasks",
    "outcome": "tasks",
}


def __getattr__(name: str) -> Any:
    if name in _WHERE:
        return getattr(importlib.import_module(f"lmic.studies.{_WHERE[name]}"), name)
    raise AttributeError(f"module 'lmic.studies' has no attribute {name!r}")
