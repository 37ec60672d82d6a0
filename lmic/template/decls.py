"""The declaration core of a template: one dataclass per kind of declaration.

A :class:`~lmic.template.builder.Template` collects these (``t.data``, ``t.symmetric``, ``t.lmi``,
...); the compiler and the renderer read them. The names are re-exported by
:mod:`lmic.template.builder`.

Examples
--------
>>> normalise_option(1.0), sorted(DOMAINS)[:2]
('1', ['integer', 'natural'])
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import sympy

from lmic.template.blocks import LmiSpec
from lmic.template.checks import CheckSpec

__all__ = [
    "SIGNS",
    "DOMAINS",
    "in_domain",
    "normalise_option",
    "template_hash",
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

SIGNS = ("free", "positive", "nonnegative", "negative", "nonpositive")
DOMAINS = {
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


def in_domain(value: float, domain: sympy.Set) -> bool:
    """Whether ``value`` lies in ``domain`` (integer sets are decided on integral values).

    >>> in_domain(2.0, DOMAINS["natural"]), in_domain(-1, DOMAINS["positive"])
    (True, False)
    """
    verdict = domain.contains(sympy.Float(value))
    if verdict not in (sympy.true, sympy.false) and float(value).is_integer():
        verdict = domain.contains(sympy.Integer(int(value)))
    return verdict == sympy.true


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
    domain: sympy.Set = field(default_factory=lambda: DOMAINS["real"])
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


def template_hash(parts: Mapping[str, str]) -> str:
    """SHA-256 of a :meth:`Template.fingerprint` (the hash a certificate records).

    >>> len(template_hash({"LMI (1)": "0123456789abcdef"}))
    64
    """
    return hashlib.sha256(json.dumps(dict(sorted(parts.items()))).encode()).hexdigest()
