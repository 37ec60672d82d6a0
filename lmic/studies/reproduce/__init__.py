"""Run every shipped example and compare with what the papers print and the catalogues computed.

The expectations live in ``examples/reproduction.yaml``: for each example file, one row per
quantity with the published value, the catalogue's reference value and tolerance, the expected
verdict and, where they differ, the catalogue's explanation (with its line reference). Every row
says how lmic computes the quantity (``compute:``), one of::

    claim: KEY            the audit of the file's published: section (lmic.studies.published), the claim
                          covering KEY (of kind: K if given); with lmi: NAME (the paper's extreme
                          eigenvalue of that LMI), derived: NAME, check: NAME, or the computed
                          value of a value claim
    solve: {}             the theorem on the file (objective kept); with derived: NAME,
                          variable: NAME or objective: true (else the outcome only)
    at_published: NAME    a derived quantity computed from the printed numbers (not certified),
                          compared with the printed NAME (or published_key: KEY)
    maximize: PARAM       supremum by bisection (lmic.studies.sweep.maximize); rtol, lo, hi
    sweep: P=a:b:n        grid (lmic.studies.sweep.sweep): certified if some point is, else infeasible
    gain: KEY             the printed gain KEY through another theorem's fixed_KEY variant
                          (with theorem: and system:), e.g. a Theorem-4 gain as a Theorem-1 gain

Each ``compute:`` kind is a handler registered in :mod:`lmic.studies.reproduce.handlers`
(:func:`~lmic.studies.reproduce.rows.register`); rows and reports are in
:mod:`~lmic.studies.reproduce.rows`, the run in :mod:`~lmic.studies.reproduce.run`, and the
Markdown of ``docs/reproduction.md`` in :mod:`lmic.present.reproduction`.

Common keys: ``theorem:`` (default: the file's), ``params:`` (overrides), ``gain:`` with
``maximize`` (bisection on the fixed-gain variant).

A row agrees when lmic's finding equals the expected verdict and, when a numeric reference is
given, ``|computed - reference| <= tol`` (max over entries for matrices).

Examples
--------
>>> spec = {"quantity": "q", "compute": {"solve": {}}, "verdict": "certified"}
>>> Row.from_dict("thesis.lyapunov.ex2_3_2.yaml", spec).theorem
'thesis.lyapunov'
"""

from __future__ import annotations

from lmic.studies.reproduce import handlers as _handlers  # registers the shipped compute kinds
from lmic.studies.reproduce.rows import (
    HANDLERS,
    ReproductionReport,
    Row,
    RowResult,
    Selection,
    default_examples_dir,
    load_expectations,
    register,
    select_examples,
    theorem_of,
)
from lmic.studies.reproduce.run import judge, reproduce

__all__ = [
    "Row",
    "RowResult",
    "ReproductionReport",
    "theorem_of",
    "load_expectations",
    "select_examples",
    "Selection",
    "reproduce",
    "default_examples_dir",
    "register",
    "HANDLERS",
    "judge",
]

del _handlers
