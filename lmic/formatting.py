r"""Numbers and matrices as text, LaTeX and HTML: the formatting primitives every layer may use.

These are the low-level pieces of :mod:`lmic.present` (which builds the CLI tables, the report and
the Jupyter displays on them). They sit in the base layer because objects of lower layers render
themselves with them: a :class:`~lmic.template.theorem.Theorem` (template layer) and an
:class:`lmic.api.Result` (studies layer) in Jupyter, a reproduction row's value text.

Examples
--------
>>> format_value([[1.0, 2.0]]), value_text([[1.0, 0.5], [2.0, 3.0]]), number_text(None)
('[1 2]', '[1 0.5; 2 3]', '-')
>>> print(matrix_latex([[1.0, 0.5], [-2.0, 1.5e-7]]))
\begin{bmatrix}1 & 0.5 \\ -2 & 1.5 \cdot 10^{-7}\end{bmatrix}
"""

from __future__ import annotations

import html
import math
from typing import Any

import numpy as np

__all__ = [
    "bound_text",
    "interval_text",
    "domain_text",
    "esc",
    "number_html",
    "number_text",
    "number_latex",
    "matrix_latex",
    "format_value",
    "inline_matrix",
    "value_text",
    "result_html",
    "result_latex",
    "VERDICT_COLOURS",
]

#: verdict -> colour of its badge in HTML
VERDICT_COLOURS = {
    "certified": "#1a7f37",
    "infeasible-certified": "#0550ae",
    "rejected": "#cf222e",
    "unverified": "#9a6700",
}


def esc(value: Any) -> str:
    """``str(value)`` escaped for HTML (quotes too).

    >>> esc("<a & 'b'>")
    '&lt;a &amp; &#x27;b&#x27;&gt;'
    """
    return html.escape(str(value), quote=True)


def number_html(v: Any) -> str:
    """A table cell in HTML: ``—`` for none, floats to 6 significant digits, anything else escaped.

    >>> number_html(None), number_html(1 / 3), number_html("a<b")
    ('—', '0.333333', 'a&lt;b')
    """
    if v is None:
        return "—"
    if isinstance(v, float | np.floating):
        return f"{float(v):.6g}"
    return esc(v)


def number_text(v: Any, digits: int = 4) -> str:
    """A number as plain text: ``-`` for none, ``yes``/``no`` for booleans, ``digits`` significant digits.

    >>> number_text(2 / 3), number_text(True), number_text(float("inf")), number_text("x")
    ('0.6667', 'yes', 'inf', 'x')
    """
    if v is None:
        return "-"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, int | float | np.floating | np.integer):
        f = float(v)
        return f"{f:.{digits}g}" if math.isfinite(f) else str(f)
    return str(v)


def number_latex(v: float, digits: int = 4) -> str:
    """A number for LaTeX: ``digits`` significant digits, powers of ten as ``\\cdot 10^{k}``.

    >>> number_latex(0.0000123456), number_latex(12.0), number_latex(float("nan"))
    ('1.235 \\\\cdot 10^{-5}', '12', '\\\\text{NaN}')
    """
    if not math.isfinite(v):
        return r"\text{NaN}" if math.isnan(v) else (r"\infty" if v > 0 else r"-\infty")
    text = f"{v:.{digits}g}"
    if "e" in text:
        mant, exp = text.split("e")
        return f"{mant} \\cdot 10^{{{int(exp)}}}"
    return text


def matrix_latex(value: Any, digits: int = 4) -> str:
    """A scalar, vector or matrix as LaTeX (a ``bmatrix``; a scalar alone as a number).

    >>> matrix_latex(0.5), matrix_latex([[1.0, 2.0]])
    ('0.5', '\\\\begin{bmatrix}1 & 2\\\\end{bmatrix}')
    """
    arr = np.atleast_2d(np.asarray(value, dtype=float))
    if arr.size == 1:
        return number_latex(float(arr.reshape(-1)[0]), digits)
    rows = [" & ".join(number_latex(float(v), digits) for v in row) for row in arr]
    return r"\begin{bmatrix}" + r" \\ ".join(rows) + r"\end{bmatrix}"


def format_value(value: Any, digits: int = 6) -> str:
    """A number or a matrix for a terminal table: one line per row (``-`` for none).

    >>> format_value(0.5), format_value([[1.0, 2.0], [3.0, 4.0]])
    ('0.5', '[1 2]\\n[3 4]')
    """
    if value is None:
        return "-"
    if isinstance(value, str):
        return value
    arr = np.atleast_2d(np.asarray(value, dtype=float))
    if arr.size == 1:
        return f"{arr.item():.{digits}g}"
    rows = ["[" + " ".join(f"{v:.{digits}g}" for v in row) + "]" for row in arr]
    return "\n".join(rows)


def inline_matrix(value: Any, digits: int = 4) -> str:
    """A matrix on one line, rows separated by ``;``.

    >>> inline_matrix([[1.0, 0.25], [2.0, 3.0]]), inline_matrix([1.0, 2.0])
    ('[1 0.25; 2 3]', '[1 2]')
    """
    arr = np.atleast_2d(np.asarray(value, dtype=float))
    return "[" + "; ".join(" ".join(f"{float(e):.{digits}g}" for e in row) for row in arr) + "]"


def value_text(
    value: Any,
    digits: int = 4,
    scalar_digits: int | None = None,
    *,
    spec: str | None = None,
    none: str = "-",
    width: int | None = None,
) -> str:
    """A short text for a value: the one number formatter of lmic's tables and messages.

    ``none`` for ``None``; a number with ``scalar_digits`` (default ``digits``) significant
    digits, or with the format ``spec`` (e.g. ``".3f"``, ``".2e"``); a list, tuple or array on one
    line (:func:`inline_matrix`, cut to ``width`` characters with ``...``); a boolean or anything
    else as ``str``.

    >>> value_text(None), value_text(True), value_text(1 / 3), value_text(1 / 3, scalar_digits=6)
    ('-', 'True', '0.3333', '0.333333')
    >>> value_text([[1.0, 0.5]]), value_text("n/a"), value_text(None, none="")
    ('[1 0.5]', 'n/a', '')
    >>> value_text(0.123456, spec=".3f"), value_text(list(range(30)), width=20)
    ('0.123', '[0 1 2 3 4 5 6 7 ...')
    """
    if value is None:
        return none
    if isinstance(value, bool):
        return str(value)
    if isinstance(value, int | float | np.floating | np.integer):
        return format(float(value), spec) if spec else f"{float(value):.{scalar_digits or digits}g}"
    if isinstance(value, list | tuple | np.ndarray):
        text = inline_matrix(value, digits)
        return text if width is None or len(text) <= width else text[: width - 3] + "..."
    return str(value)


# -- a result's own rendering (Jupyter reprs of lmic.api.Result) --------------------------------
def result_html(result: Any) -> str:
    """HTML of a solve result: verdict (coloured), status, objective, margins per LMI, checks, gains.

    ``result`` is any object with ``certificate_dict()``, ``derived``, ``target``, ``backend``,
    ``status`` and ``objective`` (an :class:`lmic.api.Result`).

    >>> from types import SimpleNamespace as NS
    >>> r = NS(certificate_dict=lambda: {"verdict": "certified"}, derived={"L": [[1.0]]},
    ...        target="t", backend="b", status="optimal", objective=None)
    >>> "certified" in result_html(r) and "L = $$1$$" in result_html(r)
    True
    """
    cert = result.certificate_dict()
    verdict = cert.get("label") or cert.get("verdict", "unverified")
    colour = VERDICT_COLOURS.get(cert.get("verdict", "unverified"), "#57606a")
    lmi_rows = "".join(
        f"<tr><td>{esc(m.get('name'))}</td><td>{number_html(m.get('min_margin'))}</td>"
        f"<td>{number_html(m.get('rel_margin'))}</td><td>{'✓' if m.get('ok') else '✗'}</td></tr>"
        for m in cert.get("lmis", [])
    )
    check_rows = "".join(
        f"<tr><td>{esc(c.get('name'))}</td><td>{number_html(c.get('value'))}</td>"
        f"<td>{'✓' if c.get('ok') else '✗'}</td></tr>"
        for c in cert.get("checks", [])
    )
    gains = "".join(
        f"<li>{esc(k)} = $${matrix_latex(v)}$$</li>"
        for k, v in (result.derived or {}).items()
        if v is not None and not isinstance(v, str)
    )
    objective = "" if result.objective is None else f", objective {number_html(result.objective)}"
    return (
        f"<div class='lmic-result'><p><b>{esc(result.target)}</b> on {esc(result.backend)}: "
        f"status {esc(result.status)}{objective} — "
        f"<span style='color:{colour};font-weight:bold'>{esc(verdict)}</span></p>"
        f"<table><tr><th>LMI</th><th>min margin</th><th>relative</th><th>ok</th></tr>{lmi_rows}</table>"
        + (f"<table><tr><th>check</th><th>value</th><th>ok</th></tr>{check_rows}</table>" if check_rows else "")
        + (f"<ul>{gains}</ul>" if gains else "")
        + "</div>"
    )


def result_latex(result: Any) -> str:
    r"""LaTeX of a solve result: the verdict and every derived quantity.

    >>> from types import SimpleNamespace as NS
    >>> r = NS(certificate_dict=lambda: {"verdict": "certified"}, derived={"L": 2.0}, target="t", status="optimal")
    >>> result_latex(r)
    '$\\text{t: optimal, certified},\\quad L = 2$'
    """
    cert = result.certificate_dict()
    parts = [rf"\text{{{result.target}: {result.status}, {cert.get('verdict', 'unverified')}}}"]
    for k, v in (result.derived or {}).items():
        if v is not None and not isinstance(v, str):
            parts.append(f"{k} = {matrix_latex(v)}")
    return "$" + r",\quad ".join(parts) + "$"


_INTERVAL_FORMS = {"Interval.open": "()", "Interval.Lopen": "(]", "Interval.Ropen": "[)", "Interval": "[]"}
_NAMED_DOMAINS = {
    "(0, inf)": "positive",
    "[0, inf)": "nonnegative",
    "(-inf, 0)": "negative",
    "(-inf, 0]": "nonpositive",
}


def domain_text(domain: Any) -> str:
    """A parameter's domain as a user reads it: ``positive (0, inf)`` for sympy's
    ``Interval.open(0, oo)`` (an analysed plan's domain, or a frozen plan's ``text`` of it).

    >>> domain_text("Interval.open(0, oo)"), domain_text("Interval(1/2, 1)"), domain_text("Naturals")
    ('positive (0, inf)', '[1/2, 1]', 'Naturals')
    """
    text = str(getattr(domain, "text", "") or domain)
    for name, brackets in sorted(_INTERVAL_FORMS.items(), key=lambda kv: -len(kv[0])):
        left, right = brackets[0], brackets[1]
        if text.startswith(name + "(") and text.endswith(")"):
            ends = [e.strip().replace("oo", "inf") for e in text[len(name) + 1 : -1].split(",")]
            if len(ends) == 2:
                text = f"{left}{ends[0]}, {ends[1]}{right}"
                return f"{_NAMED_DOMAINS[text]} {text}" if text in _NAMED_DOMAINS else text
    return text


def bound_text(value: float | None, side: str, digits: int = 10) -> str:
    """``value`` to ``digits`` significant digits, rounded *outward*: down for the ``"lower"``
    end of an interval, up for the ``"upper"`` one, so that a printed enclosure still contains
    what the proven one does (rounding to nearest printed a proven lower end 15.609311018437 as
    15.60931102, above it).

    >>> bound_text(15.609311018437344, "lower"), bound_text(15.609311018437344, "upper")
    ('15.60931101', '15.60931102')
    >>> bound_text(0.1, "lower", 3), bound_text(0.1, "upper", 3)  # the float 0.1 is 0.1000000000000000055...
    ('0.1', '0.101')
    >>> bound_text(-2.5, "lower", 3), bound_text(float("inf"), "lower")
    ('-2.5', 'inf')
    """
    from decimal import ROUND_CEILING, ROUND_FLOOR, Decimal

    if value is None:
        return "-"
    v = float(value)
    if not math.isfinite(v) or v == 0.0:
        return f"{v:.{digits}g}"
    exact = Decimal(v)  # the float's exact value
    quantum = Decimal(1).scaleb(exact.adjusted() - digits + 1)
    rounded = exact.quantize(quantum, rounding=ROUND_FLOOR if side == "lower" else ROUND_CEILING)
    return f"{float(rounded):.{digits}g}"  # at most `digits` significant digits: the same decimal


def interval_text(lo: float | None, hi: float | None, digits: int = 10) -> str:
    """``[lo, hi]`` with both ends rounded outward (:func:`bound_text`).

    >>> interval_text(15.609311018437344, 15.609316085)
    '[15.60931101, 15.60931609]'
    """
    return f"[{bound_text(lo, 'lower', digits)}, {bound_text(hi, 'upper', digits)}]"
