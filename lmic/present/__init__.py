"""Presentation: one set of text, LaTeX and HTML formatters for the CLI, the report and Jupyter.

- :mod:`lmic.present.text`: terminal output (rich tables of a result, numbers and matrices);
- :mod:`lmic.present.latex`: numbers, matrices, theorems and results as LaTeX;
- :mod:`lmic.present.html`: theorems and results as HTML (Jupyter ``_repr_html_``, the report);
- :mod:`lmic.present.reproduction`: the Markdown of ``lmic reproduce`` (``docs/reproduction.md``).

The primitives shared with lower layers (a number, a matrix) live in :mod:`lmic.formatting`; a
theorem renders itself in :mod:`lmic.template.render`. This package builds on both; lower layers
(backends, certify, studies) never import it.

Examples
--------
>>> from lmic.present import matrix_latex, format_value
>>> matrix_latex([[1.0, 0.0]]), format_value(2.5)
('\\\\begin{bmatrix}1 & 0\\\\end{bmatrix}', '2.5')
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from lmic.present.html import result_html, theorem_html
    from lmic.present.latex import matrix_latex, number_latex, result_latex, theorem_latex_block
    from lmic.present.text import format_value, number_text, print_result, value_text

# imported on first use (PEP 562): ``lmic solve`` prints through lmic.present.text alone, and the
# theorem renderers (lmic.present.html, .latex) import the template layer (sympy)
_WHERE = {
    "result_html": "html",
    "theorem_html": "html",
    "matrix_latex": "latex",
    "number_latex": "latex",
    "result_latex": "latex",
    "theorem_latex_block": "latex",
    "format_value": "text",
    "number_text": "text",
    "print_result": "text",
    "value_text": "text",
}

__all__ = [
    "format_value",
    "matrix_latex",
    "number_latex",
    "number_text",
    "print_result",
    "result_html",
    "result_latex",
    "theorem_html",
    "theorem_latex_block",
    "value_text",
]


def __getattr__(name: str) -> Any:
    """The formatters above, imported from their module on first use."""
    if name in _WHERE:
        value = getattr(importlib.import_module(f"lmic.present.{_WHERE[name]}"), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'lmic.present' has no attribute {name!r}")
