"""The authoring layer: a theorem's declarations, written like the paper.

A theorem's ``build(t)`` function receives a :class:`Template` ``t`` and declares, in order:
dimension symbols, data matrices with symbolic shapes, parameters, structural options,
data-derived constants, decision variables, LMIs, scalar constraints, an objective, derived
quantities (back-substitution) and checks.

Examples
--------
>>> from lmic.template import Template, block, STAR, I
>>> t = Template("demo")
>>> n, = t.dims("n")
>>> A = t.data("A", n, n)
>>> P = t.symmetric("P", n, pd=True)
>>> t.lmi("Lyapunov", A.T * P + P * A < 0)
>>> [v.name for v in t.variables], [l.name for l in t.lmis]
(['P'], ['P > 0', 'Lyapunov'])
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import sympy

from lmic.errors import DataError, TemplateError
from lmic.template.blocks import STAR, Block, LmiSpec
from lmic.template.checks import CheckSpec, hurwitz, schur_stable
from lmic.template.convert import as_expr

__all__ = [
    "Template",
    "normalise_option",
    "DataDecl",
    "ParamDecl",
    "OptionDecl",
    "ConstDecl",
    "VarDecl",
    "LmiDecl",
    "ConstraintDecl",
    "DerivedDecl",
    "CheckDecl",
    "ObserverDecl",
    "RequireDecl",
]

_SIGNS = ("free", "positive", "nonnegative", "negative", "nonpositive")
_DOMAINS = {
    "positive": sympy.Interval.open(0, sympy.oo),
    "nonnegative": sympy.Interval(0, sympy.oo),
    "negative": sympy.Interval.open(-sympy.oo, 0),
    "nonpositive": sympy.Interval(-sympy.oo, 0),
    "unit": sympy.Interval(0, 1),
    "real": sympy.Interval(-sympy.oo, sympy.oo),
    "integer": sympy.S.Integers,
    "natural": sympy.S.Naturals,
    "natural0": sympy.S.Naturals0,
}


@dataclass
class DataDecl:
    """A data matrix: name, sympy symbol, symbolic shape, tags, optional default."""

    name: str
    symbol: sympy.MatrixSymbol
    shape: tuple[Any, Any]
    symmetric: bool = False
    positive_definite: bool = False
    default: Any = None
    doc: str = ""


@dataclass
class ParamDecl:
    """A scalar user parameter with a default and a domain."""

    name: str
    symbol: sympy.Symbol
    default: float | None = None
    domain: sympy.Set = field(default_factory=lambda: _DOMAINS["real"])
    doc: str = ""


@dataclass
class OptionDecl:
    """A structural choice (e.g. ``psi1 = printed | corrected``) fixed before analysis."""

    name: str
    choices: tuple[str, ...]
    default: str
    value: str
    doc: str = ""


@dataclass
class ConstDecl:
    """A data-derived constant computed numerically before compiling."""

    name: str
    symbol: Any
    fn: Callable[[Mapping[str, Any]], Any]
    shape: tuple[Any, Any] | None = None
    doc: str = ""


@dataclass
class VarDecl:
    """A decision variable."""

    name: str
    kind: str
    shape: tuple[Any, Any]
    symbol: Any
    blocks: tuple[Any, ...] = ()
    sign: str = "free"
    doc: str = ""


@dataclass
class LmiDecl:
    """A block LMI with its name."""

    name: str
    spec: LmiSpec
    doc: str = ""


@dataclass
class ConstraintDecl:
    """A scalar linear constraint (a sympy relational)."""

    name: str
    relation: sympy.core.relational.Relational
    doc: str = ""


@dataclass
class DerivedDecl:
    """A derived quantity (back-substitution formula)."""

    name: str
    expr: Any
    symbol: Any
    doc: str = ""


@dataclass
class RequireDecl:
    """A hypothesis of the theorem on its data, checked before compiling."""

    name: str
    predicate: Callable[[Mapping[str, Any]], bool]
    doc: str = ""


@dataclass
class ObserverDecl:
    """How the designed observer runs, for simulation: a model name and role -> IR name."""

    model: str
    time: str
    roles: dict[str, str]
    doc: str = ""


@dataclass
class CheckDecl:
    """A check on derived quantities."""

    name: str
    spec: CheckSpec
    doc: str = ""


def normalise_option(value: Any) -> str:
    """Option values as strings; numbers written in a system file (``1``, ``1.0``) become ``"1"``.

    >>> normalise_option(1.0), normalise_option("printed"), normalise_option(0.5)
    ('1', 'printed', '0.5')
    """
    if isinstance(value, bool):
        return "1" if value else "0"
    if isinstance(value, int | float):
        return str(int(value)) if float(value).is_integer() else repr(float(value))
    return str(value)


class Template:
    """Collects a theorem's declarations (see the module docstring).

    Parameters
    ----------
    theorem_id : str
        Used in error messages.
    options : mapping, optional
        Values for structural options (strings), e.g. from the system file's ``params``.
    """

    def __init__(self, theorem_id: str, options: Mapping[str, Any] | None = None) -> None:
        self.theorem_id = theorem_id
        self._option_values = dict(options or {})
        self.dimensions: list[sympy.Symbol] = []
        self.data_decls: list[DataDecl] = []
        self.params: list[ParamDecl] = []
        self.options: list[OptionDecl] = []
        self.consts: list[ConstDecl] = []
        self.variables: list[VarDecl] = []
        self.lmis: list[LmiDecl] = []
        self.constraints: list[ConstraintDecl] = []
        self.objective: tuple[str, Any] = ("feasibility", sympy.Integer(0))
        self.derived: list[DerivedDecl] = []
        self.checks: list[CheckDecl] = []
        self.observer_decl: ObserverDecl | None = None
        self.requirements: list[RequireDecl] = []
        self._names: set[str] = set()

    # -- helpers ---------------------------------------------------------------------------
    def _claim(self, name: str) -> None:
        if not isinstance(name, str) or not name.isidentifier():
            raise TemplateError(f"{self.theorem_id}: '{name}' is not a valid name")
        if name in self._names:
            raise TemplateError(f"{self.theorem_id}: the name '{name}' is declared twice")
        self._names.add(name)

    # -- declarations ----------------------------------------------------------------------
    def dims(self, names: str) -> tuple[sympy.Symbol, ...]:
        """Dimension symbols, bound from the data's shapes at compile time.

        >>> Template("x").dims("n p")
        (n, p)
        """
        out = []
        for name in names.replace(",", " ").split():
            self._claim(name)
            s = sympy.Symbol(name, integer=True, positive=True)
            self.dimensions.append(s)
            out.append(s)
        return tuple(out)

    def data(
        self,
        name: str,
        rows: Any,
        cols: Any = 1,
        *,
        symmetric: bool = False,
        positive_definite: bool = False,
        default: Any = None,
        doc: str = "",
    ) -> sympy.MatrixSymbol:
        """A data matrix of symbolic shape ``rows x cols`` (a column vector when ``cols=1``).

        ``default`` makes the data optional: a number ``c`` means ``c`` times the (possibly
        rectangular) identity, a callable ``f(values, rows, cols) -> array`` computes it from the
        other inputs (``values`` maps data and parameter names to numbers / arrays).
        """
        self._claim(name)
        sym = sympy.MatrixSymbol(name, rows, cols)
        self.data_decls.append(
            DataDecl(name, sym, (rows, cols), symmetric or positive_definite, positive_definite, default, doc)
        )
        return sym

    def param(self, name: str, *, default: float | None = None, domain: Any = "real", doc: str = "") -> sympy.Symbol:
        """A scalar parameter; ``domain`` is a sympy set or one of ``positive``, ``nonnegative``,
        ``negative``, ``nonpositive``, ``unit`` ([0, 1]), ``real``, ``integer``, ``natural``
        (1, 2, ...), ``natural0`` (0, 1, ...)."""
        self._claim(name)
        if isinstance(domain, str):
            if domain not in _DOMAINS:
                raise TemplateError(f"{self.theorem_id}: unknown domain '{domain}' for parameter '{name}'")
            domain = _DOMAINS[domain]
        sym = sympy.Symbol(name, real=True)
        self.params.append(ParamDecl(name, sym, default, domain, doc))
        return sym

    def option(self, name: str, choices: Any, default: str, doc: str = "") -> str:
        """A structural option; returns the chosen value (a string) for this build."""
        self._claim(name)
        choices = tuple(choices)
        if default not in choices:
            raise TemplateError(f"{self.theorem_id}: default '{default}' of option '{name}' is not a choice")
        value = normalise_option(self._option_values.get(name, default))
        if value not in choices:
            raise DataError(f"theorem {self.theorem_id}: option {name} = {value!r} is not one of {', '.join(choices)}")
        self.options.append(OptionDecl(name, choices, default, str(value), doc))
        return str(value)

    def flag(self, name: str, default: bool = False, doc: str = "") -> bool:
        """A structural on/off switch read from the parameters as 0 or 1 (e.g. ``nonstrict: 1``)."""
        return self.option(name, ("0", "1"), "1" if default else "0", doc) == "1"

    def const(self, name: str, fn: Callable[[Mapping[str, Any]], Any], shape: Any = None, doc: str = "") -> Any:
        """A data-derived constant ``fn(values)`` (scalar, or a matrix of symbolic ``shape``).

        ``values`` maps data, parameter and earlier constant names to numbers / numpy arrays.
        """
        self._claim(name)
        sym = sympy.Symbol(name, real=True) if shape is None else sympy.MatrixSymbol(name, *shape)
        self.consts.append(ConstDecl(name, sym, fn, None if shape is None else tuple(shape), doc))
        return sym

    def _var(self, name: str, kind: str, shape: tuple[Any, Any], blocks=(), sign="free", doc=""):
        self._claim(name)
        if sign not in _SIGNS:
            raise TemplateError(f"{self.theorem_id}: unknown sign '{sign}' for variable '{name}'")
        sym = sympy.Symbol(name, real=True) if kind == "scalar" else sympy.MatrixSymbol(name, *shape)
        self.variables.append(VarDecl(name, kind, shape, sym, tuple(blocks), sign, doc))
        return sym

    def symmetric(self, name: str, n: Any, doc: str = "", *, pd: bool = False) -> sympy.MatrixSymbol:
        """A symmetric ``n x n`` decision matrix; ``pd=True`` adds the LMI ``"<name> > 0"``.

        >>> t = Template("x"); (n,) = t.dims("n")
        >>> P = t.symmetric("P", n, pd=True)
        >>> [l.name for l in t.lmis]
        ['P > 0']
        """
        sym = self._var(name, "symmetric", (n, n), doc=doc)
        if pd:
            self.lmi(f"{name} > 0", Block([[sym]]) > 0)
        return sym

    def full(self, name: str, rows: Any, cols: Any, sign: str = "free", doc: str = "") -> sympy.MatrixSymbol:
        """A full ``rows x cols`` decision matrix; ``sign`` constrains every entry (element-wise)."""
        return self._var(name, "full", (rows, cols), sign=sign, doc=doc)

    def diagonal(self, name: str, n: Any, sign: str = "free", doc: str = "") -> sympy.MatrixSymbol:
        """A diagonal ``n x n`` decision matrix; ``sign`` constrains every diagonal entry."""
        return self._var(name, "diagonal", (n, n), sign=sign, doc=doc)

    def blockdiag(self, name: str, sizes: Any, doc: str = "") -> sympy.MatrixSymbol:
        """A block-diagonal decision matrix with symmetric blocks of the given sizes."""
        sizes = tuple(sizes)
        total = sympy.Add(*sizes)
        return self._var(name, "blockdiag", (total, total), blocks=sizes, doc=doc)

    def scalar(self, name: str, sign: str = "free", doc: str = "") -> sympy.Symbol:
        """A scalar decision variable; ``sign`` in ``free, positive, nonnegative, negative,
        nonpositive`` (``positive`` is a strict constraint)."""
        return self._var(name, "scalar", (1, 1), sign=sign, doc=doc)

    def lmi(self, name: str, spec: LmiSpec | Block, doc: str = "") -> None:
        """Add an LMI ``block(...) < 0`` (or ``<=``, ``>``, ``>=``)."""
        if isinstance(spec, Block) or isinstance(spec, sympy.MatrixExpr):
            raise TemplateError(f"{self.theorem_id}: LMI '{name}' has no relation (write M < 0 or block(...) < 0)")
        if isinstance(spec, bool | sympy.logic.boolalg.Boolean):
            raise TemplateError(
                f"{self.theorem_id}: LMI '{name}' is a scalar comparison ({spec}); an LMI compares a matrix "
                "with 0 (use t.constraint for scalars)"
            )
        if not isinstance(spec, LmiSpec):
            raise TemplateError(f"{self.theorem_id}: LMI '{name}' must be a matrix or block(...) compared with 0")
        if any(d.name == name for d in self.lmis):
            raise TemplateError(f"{self.theorem_id}: two LMIs are called '{name}'")
        b = spec.block
        for i, row in enumerate(b.rows):
            for j, ent in enumerate(row):
                if isinstance(ent, np.ndarray | np.generic) and not isinstance(ent, np.floating | np.integer):
                    raise TemplateError(
                        f"{self.theorem_id}: LMI '{name}' block ({i + 1},{j + 1}) is a numpy array; "
                        "use I(n), 0, data or constants (t.const) inside blocks"
                    )
        self.lmis.append(LmiDecl(name, spec, doc))

    def constraint(self, name: str, relation: Any, doc: str = "") -> None:
        """Add a scalar linear constraint, e.g. ``t.constraint("xi > 1", xi > 1)``."""
        if not isinstance(relation, sympy.core.relational.Relational) or isinstance(relation, sympy.core.relational.Ne):
            raise TemplateError(f"{self.theorem_id}: constraint '{name}' is not a relation (<, <=, >, >=, Eq)")
        self.constraints.append(ConstraintDecl(name, relation, doc))

    def minimize(self, expr: Any) -> None:
        """Minimise a scalar expression linear in the decision variables."""
        self.objective = ("min", as_expr(expr))

    def maximize(self, expr: Any) -> None:
        """Maximise a scalar expression linear in the decision variables."""
        self.objective = ("max", as_expr(expr))

    def derive(self, name: str, expr: Any, doc: str = "", *, fixes: Any = None) -> Any:
        """A derived quantity ``name = expr`` (e.g. ``L = P^-1 G``); returns a symbol for it.

        ``fixes=V`` (a decision variable in ``expr``) generates the audit variant: the flag
        ``fixed_<name>`` (default 0); with ``fixed_<name>: 1`` the quantity is data (the printed
        gain to audit) and ``V`` is replaced everywhere by the expression solving
        ``name = expr`` for it (e.g. ``L = P^-1 R^T`` gives ``R = L^T P``). Declare it after the
        LMIs that use ``V``.

        >>> from lmic.template import block, STAR
        >>> t = Template("x", {"fixed_L": 1}); n, p = t.dims("n p")
        >>> A, C = t.data("A", n, n), t.data("C", p, n)
        >>> P = t.symmetric("P", n); R = t.full("R", p, n)
        >>> t.lmi("(7)", block([[-P, A.T * P - C.T * R], [STAR, -P]]) < 0)
        >>> L = t.derive("L", P.inv() * R.T, fixes=R)
        >>> [v.name for v in t.variables], t.role("L"), t.lmis[0].spec.block.entry(0, 1)
        (['P'], 'data', A.T*P - C.T*(L.T*P))
        """
        if fixes is not None:
            fixed = self._fixed_variant(name, expr, fixes)
            if fixed is not None:
                return fixed
        self._claim(name)
        expr = as_expr(expr) if not isinstance(expr, sympy.MatrixExpr) else expr
        if isinstance(expr, sympy.MatrixExpr):
            sym = sympy.MatrixSymbol(name, *expr.shape)
        else:
            sym = sympy.Symbol(name, real=True)
        self.derived.append(DerivedDecl(name, expr, sym, doc))
        return sym

    def _fixed_variant(self, name: str, expr: Any, var: Any) -> Any:
        vname = getattr(var, "name", None)
        decl = next((v for v in self.variables if v.name == vname and v.symbol == var), None)
        if decl is None or decl.kind == "scalar":
            raise TemplateError(f"{self.theorem_id}: derive '{name}': fixes= must be a matrix decision variable")
        if not isinstance(expr, sympy.MatrixExpr):
            raise TemplateError(f"{self.theorem_id}: derive '{name}': fixes= needs a matrix expression")
        flag = self.flag(f"fixed_{name}", doc=f"1: {name} is given as data (audit); {vname} is eliminated")
        if not flag:
            return None
        D = self.data(name, *expr.shape, doc=f"the {name} to audit (fixed_{name} = 1)")
        solved = _solve_for(expr, var, D, self._symmetric_names(), self.theorem_id, name)
        self._replace(var, solved)
        self.variables.remove(decl)
        return D

    def _symmetric_names(self) -> set[str]:
        out = {v.name for v in self.variables if v.kind in ("symmetric", "diagonal", "blockdiag")}
        return out | {d.name for d in self.data_decls if d.symmetric}

    def _replace(self, var: Any, value: Any) -> None:
        """Substitute ``var -> value`` in every declaration made so far."""
        sub = {var: value}

        def rep(e: Any) -> Any:
            return e.xreplace(sub) if isinstance(e, sympy.Basic) else e

        def rep_block(b: Block) -> Block:
            return Block([[e if e is STAR else rep(e) for e in row] for row in b.rows])

        self.lmis = [replace(d, spec=LmiSpec(rep_block(d.spec.block), d.spec.relation)) for d in self.lmis]
        self.constraints = [replace(c, relation=rep(c.relation)) for c in self.constraints]
        self.objective = (self.objective[0], rep(self.objective[1]))
        self.derived = [replace(d, expr=rep(d.expr)) for d in self.derived]
        self.checks = [
            replace(
                c,
                spec=replace(
                    c.spec, expr=rep_block(c.spec.expr) if isinstance(c.spec.expr, Block) else rep(c.spec.expr)
                ),
            )
            for c in self.checks
        ]

    def luenberger(
        self,
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

        >>> t = Template("x"); n, p = t.dims("n p")
        >>> A, C = t.data("A", n, n), t.data("C", p, n)
        >>> P = t.symmetric("P", n, pd=True); R = t.full("R", p, n)
        >>> L = t.luenberger(A, C, L=P.inv() * R.T, fixes=R)
        >>> t.derived[0].name, t.checks[0].name, t.observer_decl.model, t.options[0].name
        ('L', 'A - L C Schur stable', 'luenberger', 'fixed_L')
        """
        if time not in ("discrete", "continuous"):
            raise TemplateError(f"{self.theorem_id}: luenberger time must be discrete or continuous")
        if not (isinstance(L, sympy.MatrixSymbol) and self.role(L.name) in ("data", "derived")):
            L = self.derive(name, L, doc=doc or f"observer gain {name} = {L}", fixes=fixes)
        gain = getattr(L, "name", name)
        if time == "discrete":
            self.check(f"A - {gain} C Schur stable", schur_stable(A - L * C))
        else:
            self.check(f"A - {gain} C Hurwitz", hurwitz(A - L * C))
        self.observer("luenberger", time, A=A, C=C, L=L, **roles)
        return L

    def check(self, name: str, spec: CheckSpec, doc: str = "") -> None:
        """A check of the derived quantities (see :mod:`lmic.template.checks`)."""
        if not isinstance(spec, CheckSpec):
            raise TemplateError(f"{self.theorem_id}: check '{name}' must be built with schur_stable(...) etc.")
        self.checks.append(CheckDecl(name, spec, doc))

    def require(self, name: str, predicate: Callable[[Mapping[str, Any]], bool], doc: str = "") -> None:
        """A hypothesis on the data (e.g. ``lambda_min(Q) = T``), checked before compiling.

        ``predicate(values)`` gets data, parameters and constants by name and returns True when the
        hypothesis holds; otherwise compilation stops with one line naming the theorem, the
        system file and ``name`` (and ``doc``).
        """
        if not callable(predicate):
            raise TemplateError(f"{self.theorem_id}: requirement '{name}' needs a callable predicate")
        self.requirements.append(RequireDecl(name, predicate, doc))

    def observer(self, model: str, time: str, doc: str = "", **roles: Any) -> None:
        """Declare the observer the theorem designs, for ``lmic simulate``.

        Parameters
        ----------
        model : str
            The observer structure, e.g. ``"luenberger"`` (``x^+ = A x^ + f(x^) + L (y - C x^)``),
            ``"uio"`` (``z^+ = N z + G u + L y``, ``x^ = z - E y``), ``"sampled"``
            (continuous plant, output sampled at ``t_k``) — :mod:`lmic.simulate` lists them.
        time : {"discrete", "continuous", "sampled"}
        roles
            Role -> symbol (data, derived quantity or variable), e.g. ``A=A, C=C, L=L``.
        """
        if time not in ("discrete", "continuous", "sampled"):
            raise TemplateError(f"{self.theorem_id}: observer time must be discrete, continuous or sampled")
        names = {}
        for role, sym in roles.items():
            name = getattr(sym, "name", sym)
            if not isinstance(name, str):
                raise TemplateError(f"{self.theorem_id}: observer role '{role}' must name a symbol")
            names[role] = name
        self.observer_decl = ObserverDecl(model, time, names, doc)

    # -- validation ------------------------------------------------------------------------
    def _declared(self) -> dict[str, Any]:
        out: dict[str, Any] = {s.name: s for s in self.dimensions}
        for decls in (self.data_decls, self.params, self.consts, self.variables, self.derived):
            for d in decls:
                out[d.name] = d.symbol
        return out

    def _undeclared(self, exprs: list[Any], where: str, declared: dict[str, Any]) -> None:
        for e in exprs:
            for s in sorted(getattr(e, "free_symbols", set()), key=str):
                name = getattr(s, "name", str(s))
                if name not in declared:
                    what = "MatrixSymbol" if isinstance(s, sympy.MatrixSymbol) else "Symbol"
                    raise TemplateError(
                        f"theorem {self.theorem_id}: {where} uses {what} '{name}', which is not declared "
                        "(declare it with t.data, t.param, t.const, t.symmetric/t.full/t.scalar or t.dims)"
                    )
                if declared[name] != s and not (
                    isinstance(s, sympy.MatrixSymbol) and isinstance(declared[name], sympy.MatrixSymbol)
                ):
                    raise TemplateError(
                        f"theorem {self.theorem_id}: {where} uses a new sympy symbol '{name}', not the one "
                        f"t.{self.role(name) or 'dims'}(...) returned: use the returned symbol"
                    )
                if isinstance(s, sympy.MatrixSymbol) and isinstance(declared[name], sympy.MatrixSymbol):
                    if sympy.Tuple(*s.shape) != sympy.Tuple(*declared[name].shape):
                        raise TemplateError(
                            f"theorem {self.theorem_id}: {where} uses '{name}' as {s.shape[0]} x {s.shape[1]}, "
                            f"but it is declared {declared[name].shape[0]} x {declared[name].shape[1]}"
                        )

    def finish(self) -> None:
        """Validate after ``build``: every symbol used is declared (one line naming where).

        >>> import sympy as sp
        >>> t = Template("demo.x"); (n,) = t.dims("n")
        >>> P = t.symmetric("P", n)
        >>> t.lmi("(1)", P - sp.MatrixSymbol("B", n, n) < 0)
        >>> t.finish()  # doctest: +ELLIPSIS
        Traceback (most recent call last):
        ...
        lmic.errors.TemplateError: theorem demo.x: LMI '(1)' uses MatrixSymbol 'B', which is not declared ...
        """
        declared = self._declared()
        shaped: list[DataDecl | VarDecl] = [*self.data_decls, *self.variables]
        for sd in shaped:
            self._undeclared([as_expr(x) for x in sd.shape], f"the shape of '{sd.name}'", declared)
        for lmi in self.lmis:
            ents = [e for row in lmi.spec.block.rows for e in row if e is not STAR and isinstance(e, sympy.Basic)]
            self._undeclared(ents, f"LMI '{lmi.name}'", declared)
        for con in self.constraints:
            self._undeclared([con.relation], f"constraint '{con.name}'", declared)
        self._undeclared([self.objective[1]], "the objective", declared)
        for der in self.derived:
            self._undeclared([der.expr], f"derive '{der.name}'", declared)
        for chk in self.checks:
            e = chk.spec.expr
            ents = [x for row in e.rows for x in row if x is not STAR] if isinstance(e, Block) else [e]
            self._undeclared([x for x in ents if isinstance(x, sympy.Basic)], f"check '{chk.name}'", declared)

    def fingerprint(self) -> dict[str, str]:
        """Short hashes of every declaration (what a certificate's ``template_hash`` covers).

        Keys name the declaration (``LMI (7)``, ``derive L``, ...); the values are the first 16
        hex digits of a SHA-256 of its canonical sympy form. :func:`template_hash` combines them.

        >>> t = Template("x"); (n,) = t.dims("n")
        >>> P = t.symmetric("P", n, pd=True)
        >>> sorted(t.fingerprint())
        ['LMI P > 0', 'dimensions', 'variable P']
        """
        parts: dict[str, Any] = {"dimensions": [sympy.srepr(s) for s in self.dimensions]}

        def sr(e: Any) -> str:
            if e is STAR:
                return "STAR"
            if isinstance(e, Block):
                return "block" + json.dumps([[sr(x) for x in row] for row in e.rows])
            if isinstance(e, sympy.Basic):
                return sympy.srepr(e)
            if callable(e):
                return "<callable>"
            return repr(e)

        for d in self.data_decls:
            parts[f"data {d.name}"] = [sr(as_expr(x)) for x in d.shape] + [
                d.symmetric,
                d.positive_definite,
                sr(d.default),
            ]
        for p in self.params:
            parts[f"parameter {p.name}"] = [sr(p.domain), p.default]
        for o in self.options:
            parts[f"option {o.name}"] = [list(o.choices), o.default, o.value]
        for c in self.consts:
            parts[f"constant {c.name}"] = [sr(c.symbol)]
        for v in self.variables:
            parts[f"variable {v.name}"] = [
                v.kind,
                [sr(as_expr(x)) for x in v.shape],
                [sr(as_expr(b)) for b in v.blocks],
                v.sign,
            ]
        for lmi in self.lmis:
            parts[f"LMI {lmi.name}"] = [lmi.spec.relation, sr(lmi.spec.block)]
        for con in self.constraints:
            parts[f"constraint {con.name}"] = sr(con.relation)
        if self.objective[0] != "feasibility":
            parts["objective"] = [self.objective[0], sr(self.objective[1])]
        for der in self.derived:
            parts[f"derive {der.name}"] = sr(der.expr)
        for chk in self.checks:
            parts[f"check {chk.name}"] = [chk.spec.kind, sr(chk.spec.expr), chk.spec.bound]
        for r in self.requirements:
            parts[f"requirement {r.name}"] = r.doc
        if self.observer_decl is not None:
            ob = self.observer_decl
            parts["observer"] = [ob.model, ob.time, sorted(ob.roles.items())]
        return {
            k: hashlib.sha256(json.dumps(v, sort_keys=True, default=str).encode()).hexdigest()[:16]
            for k, v in parts.items()
        }

    # -- lookups ---------------------------------------------------------------------------
    def role(self, name: str) -> str | None:
        """``dim``, ``data``, ``param``, ``const``, ``var``, ``derived`` or ``None``."""
        for role, decls in (
            ("data", self.data_decls),
            ("param", self.params),
            ("const", self.consts),
            ("var", self.variables),
            ("derived", self.derived),
        ):
            if any(d.name == name for d in decls):
                return role
        if any(s.name == name for s in self.dimensions):
            return "dim"
        return None

    def option_values(self) -> dict[str, str]:
        """The option values this build used."""
        return {o.name: o.value for o in self.options}


def template_hash(parts: Mapping[str, str]) -> str:
    """SHA-256 of a :meth:`Template.fingerprint` (the hash a certificate records).

    >>> len(template_hash({"LMI (1)": "0123456789abcdef"}))
    64
    """
    return hashlib.sha256(json.dumps(dict(sorted(parts.items()))).encode()).hexdigest()


def _transpose(e: Any, symmetric: set[str]) -> Any:
    """``e^T`` with symmetric symbols left as they are (``(P D)^T = D^T P`` for symmetric P)."""
    if isinstance(e, sympy.MatMul):
        coeff, mats = e.as_coeff_matrices()
        out = [_transpose(m, symmetric) for m in reversed(mats)]
        prod = out[0]
        for m in out[1:]:
            prod = prod * m
        return coeff * prod if coeff != 1 else prod
    if isinstance(e, sympy.MatrixSymbol) and e.name in symmetric:
        return e
    if isinstance(e, sympy.Transpose):
        return e.arg
    if isinstance(e, sympy.Inverse):
        return _transpose(e.arg, symmetric).inv()
    return e.T


def _solve_for(expr: Any, var: Any, value: Any, symmetric: set[str], tid: str, name: str) -> Any:
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
        solved = _transpose(solved, symmetric)
    return solved
