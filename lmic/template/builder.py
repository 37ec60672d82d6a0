"""The authoring layer: a theorem's declarations, written like the paper.

A theorem's ``build(t)`` function receives a :class:`Template` ``t`` and declares, in order:
dimension symbols, data matrices with symbolic shapes, parameters, structural options,
data-derived constants, decision variables, LMIs, scalar constraints, an objective, derived
quantities (back-substitution) and checks.

The declaration dataclasses live in :mod:`lmic.template.decls`, the authoring sugar (the
``fixes=`` audit variant, the one-call Luenberger observer) in :mod:`lmic.template.sugar`;
this module keeps :class:`Template` and re-exports the declarations.

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
from typing import Any

import numpy as np
import sympy

from lmic.errors import DataError, TemplateError
from lmic.template import sugar as _sugar
from lmic.template.blocks import STAR, Block, LmiSpec
from lmic.template.checks import CheckSpec
from lmic.template.convert import as_expr
from lmic.template.decls import (
    DOMAINS as _DOMAINS,
)
from lmic.template.decls import (
    SIGNS as _SIGNS,
)
from lmic.template.decls import (
    CheckDecl,
    ConstDecl,
    ConstraintDecl,
    DataDecl,
    DerivedDecl,
    LmiDecl,
    ObserverDecl,
    OptionDecl,
    ParamDecl,
    RequireDecl,
    VarDecl,
    in_domain,
    normalise_option,
    template_hash,
)

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
    "template_hash",
]


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
        if default is not None:
            ok = isinstance(default, int | float | np.integer | np.floating) and not isinstance(default, bool)
            if not ok or not np.isfinite(default) or not in_domain(float(default), domain):
                raise TemplateError(
                    f"{self.theorem_id}: the default {default!r} of parameter '{name}' is not a number "
                    f"in its domain {domain}"
                )
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
            raise TemplateError(
                f"theorem {self.theorem_id}: unknown sign '{sign}' for variable '{name}' (one of: {', '.join(_SIGNS)})"
            )
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
        """Add a scalar linear constraint, e.g. ``t.constraint("xi > 1", xi > 1)``.

        A matrix inequality is an LMI (``t.lmi``); a matrix equality is refused by name (write
        its entries, e.g. ``sympy.Eq(P[0, 1], 0)``, one constraint each).
        """
        if isinstance(relation, LmiSpec):
            raise TemplateError(
                f"{self.theorem_id}: constraint '{name}' is a matrix inequality: declare it with "
                f"t.lmi('{name}', ...); t.constraint takes scalar relations"
            )
        if not isinstance(relation, sympy.core.relational.Relational) or isinstance(relation, sympy.core.relational.Ne):
            raise TemplateError(f"{self.theorem_id}: constraint '{name}' is not a relation (<, <=, >, >=, Eq)")
        if any(getattr(side, "is_Matrix", False) or isinstance(side, sympy.MatrixExpr) for side in relation.args):
            raise TemplateError(
                f"{self.theorem_id}: constraint '{name}' relates matrices; t.constraint takes scalar "
                "relations: write the entries (e.g. sympy.Eq(P[0, 1], 0)), one constraint each, or a "
                "matrix inequality with t.lmi"
            )
        self.constraints.append(ConstraintDecl(name, relation, doc))

    def minimize(self, expr: Any) -> None:
        """Minimise a scalar expression linear in the decision variables."""
        self.objective = ("min", self._scalar_objective(expr))

    def maximize(self, expr: Any) -> None:
        """Maximise a scalar expression linear in the decision variables."""
        self.objective = ("max", self._scalar_objective(expr))

    def _scalar_objective(self, expr: Any) -> Any:
        e = as_expr(expr)
        if getattr(e, "is_Matrix", False) or isinstance(e, sympy.MatrixExpr):
            raise TemplateError(
                f"{self.theorem_id}: the objective '{e}' is a matrix; minimise or maximise a scalar "
                "(a t.scalar variable, a sum of them, or trace(Z) with trace from lmic.template)"
            )
        return e

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
        return _sugar.fixed_variant(self, name, expr, var)

    #: ``t.luenberger(A, C, L, ...)``: the observer in one call (:func:`lmic.template.sugar.luenberger`)
    luenberger = _sugar.luenberger

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
            what = f"theorem {self.theorem_id}: the shape of '{sd.name}'"
            self._undeclared([as_expr(x, what) for x in sd.shape], f"the shape of '{sd.name}'", declared)
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
