"""Deprecated alias: the Jupyter displays moved to :mod:`lmic.present` (html, latex).

A theorem renders itself in :mod:`lmic.template.render`, a result with :mod:`lmic.formatting`;
:mod:`lmic.present.html` and :mod:`lmic.present.latex` gather them.

Examples
--------
>>> from lmic.registry import get_theorem
>>> "<table" in theorem_html(get_theorem("qib.thm1"))
True
"""

from __future__ import annotations

from lmic.present.html import result_html, theorem_html
from lmic.present.latex import matrix_latex, result_latex, theorem_latex_block

__all__ = ["theorem_html", "theorem_latex_block", "result_html", "result_latex", "matrix_latex"]
