"""``lmic report``: one self-contained HTML page per theorem and system.

:mod:`~lmic.report.builder` runs the pipeline (solve, certify, cross-check, simulate) and
writes the page; :mod:`~lmic.report.assets` inlines the vendored KaTeX (scripts, styles and
woff2 fonts as data URIs) so the report needs no network.

Examples
--------
>>> from lmic.report import KATEX_VERSION
>>> KATEX_VERSION
'0.19.1'
"""

from __future__ import annotations

from lmic.report.assets import KATEX_VERSION
from lmic.report.builder import Report, build_report, render_html

__all__ = ["KATEX_VERSION", "Report", "build_report", "render_html"]
