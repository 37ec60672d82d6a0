"""Authoring sugar on top of the declaration core: the ``fixes=`` audit variant of a derived gain
(the ``fixed_<gain>`` convention) and the one-call Luenberger observer.

:class:`~lmic.template.builder.Template` exposes them as ``t.derive(..., fixes=V)`` and
``t.luenberger(...)``; here they are functions of the template.

Examples
--------
>>> import sympy
>>> P, D = sympy.MatrixSymbol("P", 2, 2), sympy.MatrixSymbol("D", 2, 2)
>>> R = sympy.MatrixSymbol("R", 2, 2)
>>> solve_for(P.inv() * R.T, R, D, {"P"}, "thm", "L")
D.T*P
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING, Any

import sympy

from lmic.errors import TemplateError
from lmic.template.blocks import STAR, Block, LmiSpec
from lmic.template.checks import hurwitz, schur_stable

if TYPE_CHECKING:
    from lmic.template.builder import Template

__all__ = ["fixed_variant", "replace_everywhere", "symmetric_names", "luenberger", "solve_for", "transpose"]


def fixed_variant(t: Template, name: str, expr: Any, var: Any) -> Any:
    """The audit variant of ``t.derive(name, expr, fixes=var)``: with ``fixed_<name>: 1`` the gain is data.

    Declares the flag ``fixed_<name>``; when it is set, declares ``name`` as data, replaces ``var``
    everywhere by the solution of ``name = expr`` for it and drops the variable. Returns the data
    symbol, or ``None`` when the flag is off (the caller then derives ``name`` as usual).
    """
    vname = getattr(var, "name", None)
    decl = next((v for v in t.variables if v.name == vname and v.symbol == var), None)
    if decl is None or decl.kind == "scalar":
        raise TemplateError(f"{t.theorem_id}: derive '{name}': fixes= must be a matrix decision variable")
    if not isinstance(expr, sympy.MatrixExpr):
        raise TemplateError(f"{t.theorem_id}: derive '{name}': fixes= needs a matrix expression")
    flag = t.flag(f"fixed_{name}", doc=f"1: {name} is given as data (audit); {vname} is eliminated")
    if not flag:
        return None
    D = t.data(name, *expr.shape, doc=f"the {name} to audit (fixed_{name} = 1)")
    solved = solve_for(expr, var, D, symmetric_names(t), t.theorem_id, name)
    replace_everywhere(t, var, solved)
    t.variables.remove(decl)
    return D


def symmetric_names(t: Template) -> set[str]:
    """Names of the symmetric variables and data of ``t`` (left as they are when transposed)."""
    out = {v.name for v in t.variables if v.kind in ("symmetric", "diagonal", "blockdiag")}
    return out | {d.name for d in t.data_decls if d.symmetric}


def replace_everywhere(t: Template, var: Any, value: Any) -> None:
    """Substitute ``var -> value`` in every declaration made so far."""
    sub = {var: value}

    def rep(e: Any) -> Any:
        return e.xreplace(sub) if isinstance(e, sympy.Basic) else e

    def rep_block(b: Block) -> Block:
        return Block([[e if e is STAR else rep(e) for e in row] for row in b.rows])

    t.lmis = [replace(d, spec=LmiSpec(rep_block(d.spec.block), d.spec.relation)) for d in t.lmis]
    t.constraints = [replace(c, relation=rep(c.relation)) for c in t.constraints]
    t.objective = (t.objective[0], rep(t.objective[1]))
    t.derived = [replace(d, expr=rep(d.expr)) for d in t.derived]
    t.checks = [
        replace(
            c,
            spec=replace(c.spec, expr=rep_block(c.spec.expr) if isinstance(c.spec.expr, Block) else rep(c.spec.expr)),
        )
        for c in t.checks
    ]


def luenberger(
    t: Template,
    A: Any,
    C: Any,
    L: Any,
    time: str = "discrete",
    *,
    name: str = "L",
    fixes: Any = None,
    doc: str = "",
    **roles: Any,
) -> Any:
    """The observer ``x^+ = A x^ + f + L (y - C x^)`` in one call: derive, check, observer.

    ``L`` is an expression (derived as ``name``, with the audit variant ``fixed_<name>`` when
    ``fixes`` names the eliminated variable) or an existing data / derived symbol. Adds the
    check ``A - L C Schur stable`` (``time="discrete"``) or ``A - L C Hurwitz``
    (``"continuous"``) and declares the Luenberger observer for ``lmic simulate``. Returns
    the gain symbol. Extra keyword ``roles`` go to :meth:`observer` (e.g. ``B="B"``).

    >>> from lmic.template.builder import Template
    >>> t = Template("x"); n, p = t.dims("n p")
    >>> A, C = t.data("A", n, n), t.data("C", p, n)
    >>> P = t.symmetric("P", n, pd=True); R = t.full("R", p, n)
    >>> L = t.luenberger(A, C, L=P.inv() * R.T, fixes=R)
    >>> t.derived[0].name, t.checks[0].name, t.observer_decl.model, t.options[0].name
    ('L', 'A - L C Schur stable', 'luenberger', 'fixed_L')
    """
    if time not in ("discrete", "continuous"):
        raise TemplateError(f"{t.theorem_id}: luenberger time must be discrete or continuous")
    if not (isinstance(L, sympy.MatrixSymbol) and t.role(L.name) in ("data", "derived")):
        L = t.derive(name, L, doc=doc or f"observer gain {name} = {L}", fixes=fixes)
    gain = getattr(L, "name", name)
    if time == "discrete":
        t.check(f"A - {gain} C Schur stable", schur_stable(A - L * C))
    else:
        t.check(f"A - {gain} C Hurwitz", hurwitz(A - L * C))
    t.observer("luenberger", time, A=A, C=C, L=L, **roles)
    return L


def transpose(e: Any, symmetric: set[str]) -> Any:
    """``e^T`` with symmetric symbols left as they are (``(P D)^T = D^T P`` for symmetric P)."""
    if isinstance(e, sympy.MatMul):
        coeff, mats = e.as_coeff_matrices()
        out = [transpose(m, symmetric) for m in reversed(mats)]
        prod = out[0]
        for m in out[1:]:
            prod = prod * m
        return coeff * prod if coeff != 1 else prod
    if isinstance(e, sympy.MatrixSymbol) and e.name in symmetric:
        return e
    if isinstance(e, sympy.Transpose):
        return e.arg
    if isinstance(e, sympy.Inverse):
        return transpose(e.arg, symmetric).inv()
    return e.T


def solve_for(expr: Any, var: Any, value: Any, symmetric: set[str], tid: str, name: str) -> Any:
    """Solve ``value = expr`` for the matrix variable ``var`` (expr a product with one ``var``)."""
    fail = f"{tid}: derive '{name}': cannot solve {name} = {expr} for {var.name} (fixes=)"
    coeff, mats = expr.as_coeff_matrices() if isinstance(expr, sympy.MatMul) else (sympy.Integer(1), [expr])
    where = [k for k, f in enumerate(mats) if var in f.free_symbols]
    if len(where) != 1 or not (mats[where[0]] == var or mats[where[0]] == var.T):
        raise TemplateError(fail + f": it must appear once, as {var.name} or {var.name}^T, in a product")
    k = where[0]

    def inv(f: Any) -> Any:
        if isinstance(f, sympy.Inverse):
            return f.arg
        if not f.is_square:
            raise TemplateError(fail + f": the factor {f} is not square")
        return f.inv()

    factors = [inv(f) for f in reversed(mats[:k])] + [value] + [inv(f) for f in reversed(mats[k + 1 :])]
    solved = factors[0]
    for f in factors[1:]:
        solved = solved * f
    if coeff != 1:
        solved = (1 / coeff) * solved
    if mats[k] != var:
        solved = transpose(solved, symmetric)
    return solved
