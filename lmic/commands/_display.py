"""Deprecated alias of :mod:`lmic.present.text` (the terminal output of a result moved there).

Examples
--------
>>> format_value(0.5)
'0.5'
"""

from __future__ import annotations

from lmic.present.text import format_value, print_result

__all__ = ["print_result", "format_value"]
