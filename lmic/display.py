"""Rich display of theorems and results in Jupyter (``_repr_html_`` / ``_repr_latex_``).

Examples
--------
>>> from lmic.registry import get_theorem
>>> "<table" in theorem_html(get_theorem("qib.thm1"))
True
"""

from __future__ import annotations

import html
from typing import Any

import numpy as np

__all__ = ["theorem_html", "theorem_latex_block", "result_html", "result_latex", "matrix_latex"]

_VERDICT_COLOURS = {
    "certified": "#1a7f37",
    "infeasible-certified": "#0550ae",
    "rejected": "#cf222e",
    "unverified": "#9a6700",
}


def _esc(x: Any) -> str:
    return html.escape(str(x))


def _fmt(v: Any) -> str:
    if v is None:
        return "—"
    if isinstance(v, float | np.floating):
        return f"{float(v):.6g}"
    return _esc(v)


def matrix_latex(value: Any, digits: int = 4) -> str:
    """A number or a matrix as LaTeX (``bmatrix``).

    >>> matrix_latex([[1.0, 0.5]])
    '\\\\begin{bmatrix} 1 & 0.5 \\\\end{bmatrix}'
    """
    arr = np.atleast_2d(np.asarray(value, dtype=float))
    if arr.size == 1:
        return f"{arr.item():.{digits}g}"
    rows = [" & ".join(f"{v:.{digits}g}" for v in row) for row in arr]
    return r"\begin{bmatrix} " + r" \\ ".join(rows) + r" \end{bmatrix}"


def theorem_latex_block(theorem: Any, options: dict | None = None) -> str:
    """The theorem's LMIs as a display-math LaTeX string."""
    from lmic.template.render import theorem_latex

    return "$$" + theorem_latex(theorem, theorem.template(options)) + "$$"


def theorem_html(theorem: Any, options: dict | None = None) -> str:
    """HTML: id, title, citation, declarations, and the LMIs (as MathJax-ready LaTeX)."""
    from lmic.template.render import describe

    d = describe(theorem, theorem.template(options))
    rows = "".join(
        f"<tr><td>{_esc(v['name'])}</td><td>{_esc(v['kind'])}</td><td>{_esc(v['shape'])}</td></tr>"
        for v in d["variables"]
    )
    data = ", ".join(f"{_esc(x['name'])} ({_esc(x['shape'])})" for x in d["data"])
    params = ", ".join(_esc(p["name"]) for p in d["params"]) or "none"
    lmis = "".join(f"<li><b>{_esc(x['name'])}</b>: $${_esc(x['latex'])}$$</li>" for x in d["lmis"])
    return (
        f"<div class='lmic-theorem'><h4>{_esc(theorem.id)} — {_esc(theorem.title)}</h4>"
        f"<p><i>{_esc(theorem.citation)}</i></p><p>data: {data}; parameters: {params}</p>"
        f"<table><tr><th>variable</th><th>kind</th><th>shape</th></tr>{rows}</table>"
        f"<ul>{lmis}</ul></div>"
    )


def result_html(result: Any) -> str:
    """HTML: verdict (coloured), status, objective, margins per LMI, checks, gains."""
    cert = result.certificate_dict()
    verdict = cert.get("label") or cert.get("verdict", "unverified")
    colour = _VERDICT_COLOURS.get(cert.get("verdict", "unverified"), "#57606a")
    lmi_rows = "".join(
        f"<tr><td>{_esc(m.get('name'))}</td><td>{_fmt(m.get('min_margin'))}</td>"
        f"<td>{_fmt(m.get('rel_margin'))}</td><td>{'✓' if m.get('ok') else '✗'}</td></tr>"
        for m in cert.get("lmis", [])
    )
    check_rows = "".join(
        f"<tr><td>{_esc(c.get('name'))}</td><td>{_fmt(c.get('value'))}</td><td>{'✓' if c.get('ok') else '✗'}</td></tr>"
        for c in cert.get("checks", [])
    )
    gains = "".join(
        f"<li>{_esc(k)} = $${matrix_latex(v)}$$</li>"
        for k, v in (result.derived or {}).items()
        if v is not None and not isinstance(v, str)
    )
    objective = "" if result.objective is None else f", objective {_fmt(result.objective)}"
    return (
        f"<div class='lmic-result'><p><b>{_esc(result.target)}</b> on {_esc(result.backend)}: "
        f"status {_esc(result.status)}{objective} — "
        f"<span style='color:{colour};font-weight:bold'>{_esc(verdict)}</span></p>"
        f"<table><tr><th>LMI</th><th>min margin</th><th>relative</th><th>ok</th></tr>{lmi_rows}</table>"
        + (f"<table><tr><th>check</th><th>value</th><th>ok</th></tr>{check_rows}</table>" if check_rows else "")
        + (f"<ul>{gains}</ul>" if gains else "")
        + "</div>"
    )


def result_latex(result: Any) -> str:
    """LaTeX: the verdict and every derived quantity."""
    cert = result.certificate_dict()
    parts = [rf"\text{{{result.target}: {result.status}, {cert.get('verdict', 'unverified')}}}"]
    for k, v in (result.derived or {}).items():
        if v is not None and not isinstance(v, str):
            parts.append(f"{k} = {matrix_latex(v)}")
    return "$" + r",\quad ".join(parts) + "$"
