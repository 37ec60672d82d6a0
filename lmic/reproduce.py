"""Deprecated alias of :mod:`lmic.studies.reproduce` (and :mod:`lmic.present.reproduction` for the Markdown).

Examples
--------
>>> from lmic.reproduce import reproduce as a
>>> from lmic.studies.reproduce import reproduce as b
>>> a is b
True
"""

from __future__ import annotations

from lmic.present.reproduction import render_markdown
from lmic.studies.reproduce import (
    ReproductionReport,
    Row,
    RowResult,
    default_examples_dir,
    load_expectations,
    reproduce,
    theorem_of,
)

__all__ = [
    "Row",
    "RowResult",
    "ReproductionReport",
    "theorem_of",
    "load_expectations",
    "reproduce",
    "render_markdown",
    "default_examples_dir",
]
