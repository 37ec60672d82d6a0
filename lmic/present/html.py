"""HTML: escaping, table cells, a theorem's and a result's display (Jupyter and the report).

Examples
--------
>>> from lmic.registry import get_theorem
>>> "<table" in theorem_html(get_theorem("qib.thm1")), esc("a<b")
(True, 'a&lt;b')
"""

from __future__ import annotations

from lmic.formatting import VERDICT_COLOURS, esc, number_html, result_html
from lmic.template.render import theorem_html

__all__ = ["esc", "number_html", "theorem_html", "result_html", "VERDICT_COLOURS"]
