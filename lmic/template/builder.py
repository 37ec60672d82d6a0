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
>>> P = t.symmetric("P", n)
>>> t.lmi("Lyapunov", block(A.T * P + P * A) < 0)
>>> t.lmi("P > 0", block(P) > 0)
>>> [v.name for v in t.variables], [l.name for l in t.lmis]
(['P'], ['Lyapunov', 'P > 0'])
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import sympy

from lmic.errors import DataError, TemplateError
from lmic.template.blocks import Block, LmiSpec
from lmic.template.checks import CheckSpec
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

    def param(
        self, name: str, *, default: float | None = None, domain: Any = "real", doc: str = ""
    ) -> sympy.Symbol:
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
            raise DataError(
                f"theorem {self.theorem_id}: option {name} = {value!r} is not one of {', '.join(choices)}"
            )
        self.options.append(OptionDecl(name, choices, default, str(value), doc))
        return str(value)

    def flag(self, name: str, default: bool = False, doc: str = "") -> bool:
        """A structural on/off switch read from the parameters as 0 or 1 (e.g. ``nonstrict: 1``)."""
        return self.option(name, ("0", "1"), "1" if default else "0", doc) == "1"

    def const(
        self, name: str, fn: Callable[[Mapping[str, Any]], Any], shape: Any = None, doc: str = ""
    ) -> Any:
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

    def symmetric(self, name: str, n: Any, doc: str = "") -> sympy.MatrixSymbol:
        """A symmetric ``n x n`` decision matrix."""
        return self._var(name, "symmetric", (n, n), doc=doc)

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
        if isinstance(spec, Block):
            raise TemplateError(f"{self.theorem_id}: LMI '{name}' has no relation (write block(...) < 0)")
        if not isinstance(spec, LmiSpec):
            raise TemplateError(f"{self.theorem_id}: LMI '{name}' must be block(...) compared with 0")
        if any(d.name == name for d in self.lmis):
            raise TemplateError(f"{self.theorem_id}: two LMIs are called '{name}'")
        self.lmis.append(LmiDecl(name, spec, doc))

    def constraint(self, name: str, relation: Any, doc: str = "") -> None:
        """Add a scalar linear constraint, e.g. ``t.constraint("xi > 1", xi > 1)``."""
        if not isinstance(relation, sympy.core.relational.Relational) or isinstance(
            relation, sympy.core.relational.Ne
        ):
            raise TemplateError(f"{self.theorem_id}: constraint '{name}' is not a relation (<, <=, >, >=, Eq)")
        self.constraints.append(ConstraintDecl(name, relation, doc))

    def minimize(self, expr: Any) -> None:
        """Minimise a scalar expression linear in the decision variables."""
        self.objective = ("min", as_expr(expr))

    def maximize(self, expr: Any) -> None:
        """Maximise a scalar expression linear in the decision variables."""
        self.objective = ("max", as_expr(expr))

    def derive(self, name: str, expr: Any, doc: str = "") -> Any:
        """A derived quantity ``name = expr`` (e.g. ``L = P^-1 G``); returns a symbol for it."""
        self._claim(name)
        expr = as_expr(expr) if not isinstance(expr, sympy.MatrixExpr) else expr
        if isinstance(expr, sympy.MatrixExpr):
            sym = sympy.MatrixSymbol(name, *expr.shape)
        else:
            sym = sympy.Symbol(name, real=True)
        self.derived.append(DerivedDecl(name, expr, sym, doc))
        return sym

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
