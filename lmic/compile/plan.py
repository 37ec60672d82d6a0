"""Analyse a template once into a reusable :class:`Plan` (no numbers involved).

Every block entry is expanded into *terms* ``coef * L * V * R`` (or ``coef * L * V^T * R``):
``coef`` a scalar expression of parameters and constants, ``L`` and ``R`` products of constant
factors (data, constants, identities), ``V`` one decision variable (matrix or scalar) or none.
A product of two decision variables, or a decision variable inside a non-linear function, is a
:class:`~lmic.errors.TemplateError` naming the LMI, the block and the term.

Binding numbers to a plan (:mod:`lmic.compile.bind`) is then pure numerics: a parameter sweep
re-binds the same plan.

Examples
--------
>>> from lmic.template import theorem, block, STAR, I
>>> @theorem(id="demo.x", title="t", citation="c")
... def demo(t):
...     n, = t.dims("n")
...     A = t.data("A", n, n)
...     P = t.symmetric("P", n)
...     w = t.scalar("w", sign="positive")
...     t.lmi("L1", block([[A.T * P + P * A, P], [STAR, -w * I(n)]]) < 0)
>>> plan = analyse(demo)
>>> [len(e.terms) for e in plan.lmis[0].entries.values()]
[2, 1, 1]
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import sympy
from sympy.matrices.expressions import (
    Identity,
    Inverse,
    MatAdd,
    MatMul,
    MatPow,
    MatrixSymbol,
    Trace,
    Transpose,
    ZeroMatrix,
)
from sympy.matrices.expressions.matexpr import MatrixElement

from lmic.errors import TemplateError
from lmic.template.blocks import STAR
from lmic.template.builder import Template
from lmic.template.convert import as_expr
from lmic.template.theorem import Theorem

__all__ = ["Term", "EntryPlan", "LmiPlan", "LinearForm", "Plan", "analyse", "analyse_template"]


@dataclass(frozen=True)
class Term:
    """``coef * L V R`` with ``L = prod(left)``, ``R = prod(right)`` constant factors.

    ``var`` is a decision variable name (``None`` for a constant term); for a scalar variable,
    every matrix factor is in ``left``. ``transposed`` means ``V^T``.
    """

    coef: sympy.Expr
    var: str | None
    transposed: bool
    left: tuple[Any, ...]
    right: tuple[Any, ...]
    text: str = ""


@dataclass
class EntryPlan:
    """The terms of one explicit block entry; ``scalar`` when written as a scalar (``s I``)."""

    terms: list[Term]
    scalar: bool = False
    text: str = ""


@dataclass
class LmiPlan:
    """One LMI: its explicit entries ``(i, j) -> EntryPlan`` and mirrored ``(i, j)`` pairs."""

    name: str
    relation: str
    k: int
    entries: dict[tuple[int, int], EntryPlan]
    zeros: set[tuple[int, int]]
    stars: set[tuple[int, int]]
    sizes: list[Any]
    written: Any = None  # the Block as written, for display

    @property
    def strict(self) -> bool:
        return self.relation in ("<", ">")

    @property
    def negated(self) -> bool:
        return self.relation in ("<", "<=")


@dataclass
class LinearForm:
    """A scalar expression linear in the decision variables: ``const + sum coef * atom``.

    Atoms are ``(var, kind, i, j)`` with kind ``scalar``, ``entry`` (``V[i, j]``) or ``trace``.
    """

    const: sympy.Expr
    terms: list[tuple[sympy.Expr, tuple[str, str, int, int]]] = field(default_factory=list)
    #: ``coef * trace(expression)`` parts: the expression expanded into terms
    traces: list[tuple[sympy.Expr, list[Term]]] = field(default_factory=list)


@dataclass
class Plan:
    """A theorem analysed once: template declarations plus expanded LMIs and linear forms."""

    theorem: Theorem
    template: Template
    options: dict[str, str]
    lmis: list[LmiPlan]
    constraints: list[tuple[str, str, bool, LinearForm]]  # (name, "eq"|"ge", strict, lhs - rhs (>=))
    objective: tuple[str, LinearForm]
    coef_symbols: list[sympy.Symbol]
    #: numeric structures that depend only on the dimensions (filled by bind, reused by sweeps)
    cache: dict[Any, Any] = field(default_factory=dict, repr=False)

    @property
    def id(self) -> str:
        return self.theorem.id


def analyse(theorem: Theorem, options: Mapping[str, Any] | None = None) -> Plan:
    """Build the template of ``theorem`` and expand it into a :class:`Plan`.

    :func:`lmic.compile.cache.cached_analyse` is the same with the expansion cached on disk.
    """
    return analyse_template(theorem, theorem.template(options))


def analyse_template(theorem: Theorem, t: Template) -> Plan:
    """Expand the built template ``t`` of ``theorem`` into a :class:`Plan` (see :func:`analyse`)."""
    an = _Analyser(t)
    lmis = [an.lmi(d.name, d.spec) for d in t.lmis]
    constraints = []
    for v in t.variables:
        if v.kind == "scalar" and v.sign != "free":
            s = v.symbol
            rel = {"positive": s > 0, "nonnegative": s >= 0, "negative": s < 0, "nonpositive": s <= 0}[v.sign]
            constraints.append(an.relation(f"{v.name} {rel.rel_op} 0", rel))
    for c in t.constraints:
        constraints.append(an.relation(c.name, c.relation))
    sense, expr = t.objective
    objective = (sense, an.linear(expr, "objective"))
    coef_symbols = [p.symbol for p in t.params] + [c.symbol for c in t.consts if c.shape is None]
    return Plan(theorem, t, t.option_values(), lmis, constraints, objective, coef_symbols)


class _Analyser:
    def __init__(self, t: Template) -> None:
        self.t = t
        self.matrix_vars = {v.name for v in t.variables if v.kind != "scalar"}
        self.scalar_vars = {v.symbol: v.name for v in t.variables if v.kind == "scalar"}
        self.derived = {d.name for d in t.derived}
        self.where = ""

    # -- matrix expressions ---------------------------------------------------------------
    def _has_var(self, e: Any) -> bool:
        if isinstance(e, MatrixSymbol):
            return e.name in self.matrix_vars
        syms: set[Any] = getattr(e, "free_symbols", set())
        return any((isinstance(s, MatrixSymbol) and s.name in self.matrix_vars) or s in self.scalar_vars for s in syms)

    def _check_names(self, e: Any) -> None:
        for s in getattr(e, "free_symbols", set()):
            name = getattr(s, "name", None)
            if name in self.derived:
                raise TemplateError(
                    f"{self.t.theorem_id}: {self.where} uses the derived quantity '{name}'; "
                    "LMIs may use data, parameters, constants and decision variables only"
                )

    def expand(self, e: Any) -> list[tuple[sympy.Expr, list[Any]]]:
        """Sum of (scalar coefficient, list of matrix factors)."""
        if isinstance(e, ZeroMatrix):
            return []
        if isinstance(e, MatAdd):
            out = []
            for a in e.args:
                out += self.expand(a)
            return out
        if isinstance(e, MatMul):
            coeff, mats = e.as_coeff_matrices()
            result: list[tuple[sympy.Expr, list[Any]]] = [(as_expr(coeff), [])]
            for m in mats:
                sub = self.expand(m)
                result = [(c1 * c2, f1 + f2) for c1, f1 in result for c2, f2 in sub]
            return result
        if isinstance(e, Transpose):
            return [(c, [_transpose_atom(f) for f in reversed(fs)]) for c, fs in self.expand(e.arg)]
        if isinstance(e, MatrixSymbol | Identity):
            return [(sympy.Integer(1), [e])]
        if isinstance(e, Inverse | MatPow) or not self._has_var(e):
            if self._has_var(e):
                raise TemplateError(f"{self.t.theorem_id}: {self.where}: '{e}' is not linear in the decision variables")
            return [(sympy.Integer(1), [e])]
        raise TemplateError(f"{self.t.theorem_id}: {self.where}: unsupported expression '{e}' ({type(e).__name__})")

    def split_scalar(self, coef: sympy.Expr, text: str) -> list[tuple[sympy.Expr, str | None]]:
        """Split a scalar coefficient into (parameter part, scalar variable or None)."""
        out: list[tuple[sympy.Expr, str | None]] = []
        for mono in sympy.Add.make_args(sympy.expand(coef)):
            vs = [s for s in mono.free_symbols if s in self.scalar_vars]
            if not vs:
                out.append((mono, None))
                continue
            if len(vs) > 1:
                raise TemplateError(
                    f"{self.t.theorem_id}: {self.where}: product of decision variables "
                    f"{' and '.join(sorted(self.scalar_vars[v] for v in vs))} in term '{text}'"
                )
            v = vs[0]
            indep, dep = mono.as_independent(v, as_Add=False)
            if dep != v:
                raise TemplateError(
                    f"{self.t.theorem_id}: {self.where}: '{dep}' is not linear in the decision "
                    f"variable {self.scalar_vars[v]} (term '{text}')"
                )
            out.append((indep, self.scalar_vars[v]))
        return out

    def terms(self, e: Any) -> list[Term]:
        self._check_names(e)
        out: list[Term] = []
        for coef, factors in self.expand(e):
            text = str(sympy.MatMul(coef, *factors)) if factors else str(coef)
            var_atoms = [(k, name) for k, f in enumerate(factors) if (name := _atom_var(f)) in self.matrix_vars]
            var_pos = [k for k, _ in var_atoms]
            for part, svar in self.split_scalar(coef, text):
                if part == 0:
                    continue
                if svar is not None and var_pos:
                    names = [svar] + [name for _, name in var_atoms if name is not None]
                    raise TemplateError(
                        f"{self.t.theorem_id}: {self.where}: product of decision variables "
                        f"{' and '.join(names)} in term '{text}'"
                    )
                if len(var_pos) > 1:
                    names = [name for _, name in var_atoms if name is not None]
                    raise TemplateError(
                        f"{self.t.theorem_id}: {self.where}: product of decision variables "
                        f"{' and '.join(names)} in term '{text}'"
                    )
                if var_pos:
                    k = var_pos[0]
                    f = factors[k]
                    left, right = tuple(factors[:k]), tuple(factors[k + 1 :])
                    out.append(Term(part, _atom_var(f), isinstance(f, Transpose), left, right, text))
                else:
                    out.append(Term(part, svar, False, tuple(factors), (), text))
        return out

    def lmi(self, name: str, spec: Any) -> LmiPlan:
        b = spec.block
        k = b.shape[0]
        entries: dict[tuple[int, int], EntryPlan] = {}
        zeros: set[tuple[int, int]] = set()
        stars: set[tuple[int, int]] = set()
        sizes: list[Any] = [None] * k
        for i in range(k):
            for j in range(k):
                ent = b.entry(i, j)
                self.where = f"LMI '{name}' block ({i + 1},{j + 1})"
                if ent is STAR:
                    if b.entry(j, i) is STAR:
                        raise TemplateError(f"{self.t.theorem_id}: {self.where} and its mirror are both '*'")
                    stars.add((i, j))
                elif isinstance(ent, int | float) and not isinstance(ent, bool) and ent == 0:
                    zeros.add((i, j))
                elif isinstance(ent, sympy.MatrixExpr):
                    r, c = ent.shape
                    for idx, s in ((i, r), (j, c)):
                        if sizes[idx] is None:
                            sizes[idx] = s
                        elif sympy.simplify(as_expr(sizes[idx]) - as_expr(s)) != 0:
                            raise TemplateError(
                                f"{self.t.theorem_id}: {self.where} has size {r}x{c}, which does not "
                                f"fit block size {sizes[idx]} of its row/column"
                            )
                    if isinstance(ent, ZeroMatrix):
                        zeros.add((i, j))
                    else:
                        entries[(i, j)] = EntryPlan(self.terms(ent), False, str(ent))
                elif isinstance(ent, sympy.Expr | int | float) and not isinstance(ent, bool):
                    if i != j:
                        raise TemplateError(
                            f"{self.t.theorem_id}: {self.where}: scalar entry '{ent}' off the diagonal "
                            "(write a matrix, or 0)"
                        )
                    expr = as_expr(ent)
                    self._check_names(expr)
                    terms = []
                    for part, svar in self.split_scalar(expr, str(expr)):
                        if part != 0:
                            terms.append(Term(part, svar, False, (), (), str(expr)))
                    entries[(i, j)] = EntryPlan(terms, True, str(expr))
                else:
                    raise TemplateError(
                        f"{self.t.theorem_id}: {self.where}: entry '{ent}' is not a matrix expression, "
                        "a scalar, 0 or STAR"
                    )
        for i in range(k):
            if sizes[i] is None and (i, i) in entries and entries[(i, i)].scalar:
                sizes[i] = sympy.Integer(1)  # a row holding only a scalar is a 1 x 1 block
            if sizes[i] is None:
                raise TemplateError(
                    f"{self.t.theorem_id}: LMI '{name}': block row {i + 1} has no matrix entry to fix its size"
                )
        return LmiPlan(name, spec.relation, k, entries, zeros, stars, sizes, b)

    # -- scalar linear forms --------------------------------------------------------------
    def linear(self, expr: Any, where: str) -> LinearForm:
        self.where = where
        expr = sympy.expand(as_expr(expr))
        self._check_names(expr)
        form = LinearForm(sympy.Integer(0))
        for mono in sympy.Add.make_args(expr):
            if mono.atoms(sympy.Sum) and self._has_var(mono):  # (A.T*P)[0, 0]: sympy's sum over an index
                raise TemplateError(
                    f"{self.t.theorem_id}: {where}: '{mono}' is an entry of a matrix product; write entries "
                    "of a variable (P[0, 1]), or the product's entry as trace(E * M) with a selector E (t.const)"
                )
            traces = [a for a in mono.atoms(Trace) if not isinstance(a.arg, MatrixSymbol) or not self._has_var(a)]
            if traces:
                scalar_var = any(s in self.scalar_vars for s in mono.free_symbols)
                if len(traces) > 1 or mono.atoms(MatrixElement) or scalar_var:
                    raise TemplateError(f"{self.t.theorem_id}: {where}: '{mono}' is not linear")
                indep, dep = mono.as_independent(traces[0], as_Add=False)
                if dep != traces[0]:
                    raise TemplateError(f"{self.t.theorem_id}: {where}: '{mono}' is not linear")
                self.where = f"{where}, trace({traces[0].arg})"
                form.traces.append((indep, self.terms(traces[0].arg)))
                continue
            atoms = [a for a in mono.atoms(MatrixElement, Trace) if self._has_var(a)]
            svars = [s for s in mono.free_symbols if s in self.scalar_vars]
            if len(atoms) + len(svars) == 0:
                form.const += mono
                continue
            if len(atoms) + len(svars) > 1:
                raise TemplateError(f"{self.t.theorem_id}: {where}: '{mono}' is not linear")
            target = atoms[0] if atoms else svars[0]
            indep, dep = mono.as_independent(target, as_Add=False)
            if dep != target:
                raise TemplateError(f"{self.t.theorem_id}: {where}: '{mono}' is not linear")
            if isinstance(target, MatrixElement):
                if not isinstance(target.parent, MatrixSymbol):
                    raise TemplateError(
                        f"{self.t.theorem_id}: {where}: write entries of a variable, not of '{target.parent}'"
                    )
                atom = (target.parent.name, "entry", int(target.i), int(target.j))
            elif isinstance(target, Trace):
                if not isinstance(target.arg, MatrixSymbol):
                    raise TemplateError(
                        f"{self.t.theorem_id}: {where}: write the trace of a variable, not of '{target.arg}'"
                    )
                atom = (target.arg.name, "trace", 0, 0)
            else:
                atom = (self.scalar_vars[target], "scalar", 0, 0)
            form.terms.append((indep, atom))
        return form

    def relation(self, name: str, rel: Any) -> tuple[str, str, bool, LinearForm]:
        diff = rel.lhs - rel.rhs
        op = rel.rel_op
        if op in ("<", "<="):
            diff = -diff
        kind = "eq" if op == "==" else "ge"
        return (name, kind, op in ("<", ">"), self.linear(diff, f"constraint '{name}'"))


def _atom_var(f: Any) -> str | None:
    if isinstance(f, MatrixSymbol):
        return f.name
    if isinstance(f, Transpose) and isinstance(f.arg, MatrixSymbol):
        return f.arg.name
    return None


def _transpose_atom(f: Any) -> Any:
    if isinstance(f, Identity):
        return f
    if isinstance(f, Transpose):
        return f.arg
    return Transpose(f)
