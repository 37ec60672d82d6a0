r"""Render a theorem's template as the paper prints it: LaTeX and plain text.

Examples
--------
>>> from lmic.registry import get_theorem
>>> thm = get_theorem("thesis.lyapunov")
>>> latex = lmi_latex(thm.template().lmis[1])
>>> "A^{T} P" in latex and latex.endswith("\\prec 0")
True
"""

from __future__ import annotations

import re
from typing import TYPE_CHECKING, Any

import sympy

from lmic.formatting import esc
from lmic.template.blocks import STAR
from lmic.template.builder import LmiDecl, Template

if TYPE_CHECKING:
    from lmic.template.theorem import Theorem

__all__ = [
    "lmi_latex",
    "lmi_text",
    "theorem_latex",
    "describe",
    "entry_latex",
    "entry_text",
    "latex",
    "text",
    "domain_text",
    "theorem_html",
    "theorem_latex_block",
]

_LATEX_REL = {"<": r"\prec", "<=": r"\preceq", ">": r"\succ", ">=": r"\succeq"}


#: abbreviations authors use for Greek letters (``eps1`` is printed epsilon_1, not eps_1)
_GREEK = {"eps": r"\varepsilon", "lam": r"\lambda", "gam": r"\gamma", "om": r"\omega"}
_NAME = re.compile(r"^([A-Za-z]+?)_?(\d+)$")


def _symbol_names(e: Any) -> dict[Any, str]:
    r"""LaTeX names: ``eps1`` -> ``\varepsilon_{1}``; other names with digits keep them as a subscript.

    >>> import sympy
    >>> eps1 = sympy.Symbol("eps1")
    >>> sympy.latex(2 * eps1, symbol_names=_symbol_names(2 * eps1))
    '2 \\varepsilon_{1}'
    """
    out = {}
    for s in getattr(e, "free_symbols", set()):
        name = getattr(s, "name", "")
        if name in _GREEK:
            out[s] = _GREEK[name]
            continue
        m = _NAME.match(name)
        if m and m.group(1) in _GREEK:
            out[s] = f"{_GREEK[m.group(1)]}_{{{m.group(2)}}}"
    return out


def latex(e: Any) -> str:
    r"""LaTeX of an expression in the author's term order where sympy keeps it.

    >>> import sympy
    >>> P = sympy.MatrixSymbol("P", 2, 2); w = sympy.Symbol("omega")
    >>> latex(-P + 2 * w * sympy.Identity(2))
    '- P + 2 \\omega \\mathbb{I}'
    """
    return sympy.latex(e, order="none", symbol_names=_symbol_names(e))


def text(e: Any) -> str:
    """Plain text of an expression in the author's term order where sympy keeps it."""
    return sympy.sstr(e, order="none")


def domain_text(domain: Any) -> str:
    """A parameter domain as a reader writes it.

    >>> import sympy
    >>> domain_text(sympy.Interval(-sympy.oo, sympy.oo)), domain_text(sympy.Interval.Lopen(0, sympy.oo))
    ('all reals', '(0, inf)')
    >>> domain_text(sympy.Interval(0, 1)), domain_text(sympy.S.Naturals0)
    ('[0, 1]', '0, 1, 2, ...')
    """
    if domain == sympy.Interval(-sympy.oo, sympy.oo) or domain == sympy.S.Reals:
        return "all reals"
    if isinstance(domain, sympy.Interval):

        def num(x: Any) -> str:
            return "inf" if x == sympy.oo else "-inf" if x == -sympy.oo else sympy.sstr(x)

        left = "(" if domain.left_open else "["
        right = ")" if domain.right_open else "]"
        return f"{left}{num(domain.start)}, {num(domain.end)}{right}"
    named = {sympy.S.Integers: "integers", sympy.S.Naturals: "1, 2, 3, ...", sympy.S.Naturals0: "0, 1, 2, ..."}
    return named.get(domain, str(domain))


def entry_latex(e: Any) -> str:
    """LaTeX of one block entry (``STAR`` is ``\\star``)."""
    if e is STAR:
        return r"\star"
    if isinstance(e, int | float) and e == 0:
        return "0"
    return latex(e)


def entry_text(e: Any) -> str:
    """Plain text of one block entry (``STAR`` is ``*``)."""
    if e is STAR:
        return "*"
    if isinstance(e, int | float) and e == 0:
        return "0"
    return text(e)


def lmi_latex(decl: LmiDecl) -> str:
    """The LMI as LaTeX: a ``bmatrix`` with ``\\star`` entries and the relation."""
    b = decl.spec.block
    rel = _LATEX_REL[decl.spec.relation]
    if b.shape == (1, 1):
        return f"{entry_latex(b.entry(0, 0))} {rel} 0"
    rows = [" & ".join(entry_latex(e) for e in row) for row in b.rows]
    body = r" \\ ".join(rows)
    return rf"\begin{{bmatrix}} {body} \end{{bmatrix}} {rel} 0"


def lmi_text(decl: LmiDecl) -> str:
    """The LMI as plain text, one block row per line."""
    b = decl.spec.block
    rel = decl.spec.relation
    if b.shape == (1, 1):
        return f"{entry_text(b.entry(0, 0))} {rel} 0"
    cells = [[entry_text(e) for e in row] for row in b.rows]
    widths = [max(len(cells[i][j]) for i in range(len(cells))) for j in range(len(cells))]
    lines = []
    for i, row in enumerate(cells):
        inner = " , ".join(c.ljust(widths[j]) for j, c in enumerate(row))
        end = f" ]  {rel} 0" if i == len(cells) - 1 else " ;"
        lines.append(("[ " if i == 0 else "  ") + inner + end)
    return "\n".join(lines)


def _text(name: str) -> str:
    """A name inside ``\\text{}`` with LaTeX's special characters escaped."""
    out = name
    for ch in "\\&%$#_{}":
        out = out.replace(ch, "\\" + ch)
    out = out.replace("~", r"\textasciitilde{}").replace("^", r"\textasciicircum{}")
    # plain LaTeX's text font has no < or > (OT1 prints them as inverted marks: "P ¿ 0"): math
    # mode inside the text, which LaTeX and KaTeX (the HTML report) both read
    return out.replace("<", r"\(<\)").replace(">", r"\(>\)")


#: a check as LaTeX, from the LaTeX of its expression (and bound)
_CHECK_LATEX = {
    "schur_stable": r"\rho\left({e}\right) < 1",
    "hurwitz": r"\max \operatorname{{Re}} \lambda\left({e}\right) < 0",
    "negative_definite": r"{e} \prec 0",
    "positive_definite": r"{e} \succ 0",
    "negative_semidefinite": r"{e} \preceq 0",
    "positive_semidefinite": r"{e} \succeq 0",
    "less_than": r"{e} < {b}",
    "greater_than": r"{e} > {b}",
    "finite": r"{e} \text{{ finite}}",
}


def check_latex(spec: Any) -> str:
    """A check (``t.check``) as LaTeX: its condition on the expression.

    >>> import sympy
    >>> from lmic.template.checks import schur_stable
    >>> print(check_latex(schur_stable(sympy.MatrixSymbol("M", 2, 2))))
    \\rho\\left(M\\right) < 1
    """
    e = spec.expr
    if hasattr(e, "rows") and hasattr(e, "shape") and not hasattr(e, "is_Matrix"):  # a block of entries
        body = r" \\ ".join(" & ".join(entry_latex(x) for x in row) for row in e.rows)
        body = rf"\begin{{bmatrix}} {body} \end{{bmatrix}}"
    else:
        body = latex(e)
    bound = 0.0 if spec.bound is None else spec.bound
    return _CHECK_LATEX.get(spec.kind, r"\text{{{e}}}").format(e=body, b=f"{bound:g}")


def theorem_latex(thm: Theorem, t: Template) -> str:
    """Every LMI and scalar constraint of a theorem as a LaTeX ``align*`` body."""
    lines = [rf"\text{{{_text(d.name)}}}:\quad & {lmi_latex(d)}" for d in t.lmis]
    lines += [rf"\text{{{_text(c.name)}}}:\quad & {latex(c.relation)}" for c in t.constraints]
    sense, expr = t.objective
    if sense != "feasibility":
        lines.append(rf"\text{{{'minimise' if sense == 'min' else 'maximise'}}}:\quad & {latex(expr)}")
    for d in t.derived:
        lines.append(rf"{latex(d.symbol)} &= {latex(d.expr)}")
    lines += [rf"\text{{check {_text(c.name)}}}:\quad & {check_latex(c.spec)}" for c in t.checks]
    return "\\begin{align*}\n" + " \\\\\n".join(lines) + "\n\\end{align*}"


def _shape(shape: Any) -> str:
    return " x ".join(str(s) for s in shape)


def describe(thm: Theorem, t: Template) -> dict[str, Any]:
    """A JSON-able description of a theorem (``lmic show --json``)."""
    return {
        "id": thm.id,
        "title": thm.title,
        "citation": thm.citation,
        "kind": thm.kind,
        "objective": thm.objective,
        "system_class": thm.system_class,
        "notes": thm.notes,
        "doc": thm.doc,
        "dimensions": [str(s) for s in t.dimensions],
        "data": [
            {
                "name": d.name,
                "shape": _shape(d.shape),
                "symmetric": d.symmetric,
                "positive_definite": d.positive_definite,
                "optional": d.default is not None,
                "doc": d.doc,
            }
            for d in t.data_decls
        ],
        "params": [
            {"name": p.name, "default": p.default, "domain": domain_text(p.domain), "doc": p.doc} for p in t.params
        ],
        "options": [
            {"name": o.name, "choices": list(o.choices), "default": o.default, "doc": o.doc} for o in t.options
        ],
        "constants": [{"name": c.name, "doc": c.doc} for c in t.consts],
        "variables": [{"name": v.name, "kind": v.kind, "shape": _shape(v.shape), "sign": v.sign} for v in t.variables],
        "lmis": [
            {"name": d.name, "relation": d.spec.relation, "text": lmi_text(d), "latex": lmi_latex(d)} for d in t.lmis
        ],
        "constraints": [{"name": c.name, "text": text(c.relation)} for c in t.constraints],
        "objective_expr": {"sense": t.objective[0], "expr": text(t.objective[1])},
        "derived": [{"name": d.name, "expr": text(d.expr), "doc": d.doc} for d in t.derived],
        "checks": [{"name": c.name, "kind": c.spec.kind} for c in t.checks],
    }


def theorem_latex_block(thm: Theorem, options: dict[str, Any] | None = None) -> str:
    r"""The theorem's LMIs as a display-math LaTeX string (its Jupyter ``_repr_latex_``).

    >>> from lmic.registry import get_theorem
    >>> theorem_latex_block(get_theorem("thesis.lyapunov")).startswith("$$\\begin{align*}")
    True
    """
    return "$$" + theorem_latex(thm, thm.template(options)) + "$$"


def theorem_html(thm: Theorem, options: dict[str, Any] | None = None) -> str:
    """HTML: id, title, citation, declarations, and the LMIs as MathJax-ready LaTeX (its ``_repr_html_``).

    >>> from lmic.registry import get_theorem
    >>> "<table" in theorem_html(get_theorem("qib.thm1"))
    True
    """
    d = describe(thm, thm.template(options))
    rows = "".join(
        f"<tr><td>{esc(v['name'])}</td><td>{esc(v['kind'])}</td><td>{esc(v['shape'])}</td></tr>" for v in d["variables"]
    )
    data = ", ".join(f"{esc(x['name'])} ({esc(x['shape'])})" for x in d["data"])
    params = ", ".join(esc(p["name"]) for p in d["params"]) or "none"
    lmis = "".join(f"<li><b>{esc(x['name'])}</b>: $${esc(x['latex'])}$$</li>" for x in d["lmis"])
    return (
        f"<div class='lmic-theorem'><h4>{esc(thm.id)} — {esc(thm.title)}</h4>"
        f"<p><i>{esc(thm.citation)}</i></p><p>data: {data}; parameters: {params}</p>"
        f"<table><tr><th>variable</th><th>kind</th><th>shape</th></tr>{rows}</table>"
        f"<ul>{lmis}</ul></div>"
    )
