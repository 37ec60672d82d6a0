"""The leaves of a frozen plan: dimensions, coefficients, factors, trees and domains, no sympy.

:mod:`lmic.compile.freeze` writes a plan's sympy expressions as IR expression trees
(:mod:`lmic.ir.expr`); these classes read them back and evaluate them with numpy, so that
:mod:`lmic.compile.bind` binds a frozen plan (:mod:`lmic.compile.warm`) exactly like an
analysed one. Sizes of identities and zeros inside a tree are ``{"dim": tree}`` placeholders,
replaced by integers at bind time.

Examples
--------
>>> Dim.of({"op": "add", "args": [{"name": "n"}, {"num": 1}]}).value({"n": 3})
4
>>> Domain.of(["interval", [0, 1], None, True, False], "Interval.open(0, oo)").contains_number(0.0)
False
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any, Self

from lmic.errors import IRError

__all__ = ["FORMAT", "Dim", "Coef", "Factor", "Tree", "Domain", "normalise_option"]

#: the layout written by :func:`lmic.compile.freeze.freeze`
FORMAT = "lmic-frozen-plan/1"


def normalise_option(value: Any) -> str:
    """The rule of :func:`lmic.template.decls.normalise_option` (without importing sympy).

    >>> normalise_option(1.0), normalise_option(True), normalise_option("printed")
    ('1', '1', 'printed')
    """
    if isinstance(value, bool):
        return "1" if value else "0"
    if isinstance(value, int | float):
        return str(int(value)) if float(value).is_integer() else repr(float(value))
    return str(value)


def _key(tree: Any) -> str:
    return json.dumps(tree, sort_keys=True, separators=(",", ":"), allow_nan=False)


def _check_tree(node: Any, depth: int = 0) -> None:
    """Reject anything outside the tree grammar (plus ``{"dim": tree}`` size placeholders)."""
    if depth > 200 or not isinstance(node, dict):
        raise ValueError("tree")
    if set(node) == {"dim"}:
        _check_tree(node["dim"], depth + 1)
        return
    from lmic.ir.expr import OPS

    if set(node) == {"name"} and isinstance(node["name"], str):
        return
    if set(node) == {"num"} and isinstance(node["num"], int | float) and not isinstance(node["num"], bool):
        if not math.isfinite(node["num"]):
            raise ValueError("number")
        return
    if set(node) == {"eye"}:
        _check_size(node["eye"], depth)
        return
    if set(node) == {"zeros"} and isinstance(node["zeros"], list) and len(node["zeros"]) == 2:
        for s in node["zeros"]:
            _check_size(s, depth)
        return
    if set(node) == {"block"} and isinstance(node["block"], list):
        for row in node["block"]:
            if not isinstance(row, list):
                raise ValueError("block")
            for e in row:
                _check_tree(e, depth + 1)
        return
    if set(node) <= {"op", "args"} and node.get("op") in OPS and isinstance(node.get("args", []), list):
        for a in node.get("args", []):
            _check_tree(a, depth + 1)
        return
    raise ValueError("tree node")


def _check_size(s: Any, depth: int) -> None:
    if isinstance(s, int) and not isinstance(s, bool) and s >= 0:
        return
    if isinstance(s, dict) and set(s) == {"dim"}:
        _check_tree(s["dim"], depth + 1)
        return
    raise ValueError("size")


def _evaluate(tree: Any, env: Mapping[str, Any]) -> Any:
    from lmic.ir.expr import evaluate

    return evaluate(tree, env)


def _text(tree: Any) -> str:
    """A short readable form of a dimension tree (error messages)."""
    if "name" in tree:
        return str(tree["name"])
    if "num" in tree:
        v = tree["num"]
        return str(int(v)) if float(v).is_integer() else str(v)
    sep = {"add": " + ", "mul": "*"}.get(tree.get("op", ""), ", ")
    return sep.join(_text(a) for a in tree.get("args", []))


@dataclass(frozen=True)
class _Keyed:
    """An expression tree with its canonical key: equal keys, equal expressions (the tree itself
    takes no part in comparisons or hashing)."""

    key: str
    tree: Any = field(compare=False, hash=False, repr=False)

    @classmethod
    def of(cls, tree: Any) -> Self:
        """The expression of ``tree`` (checked)."""
        _check_tree(tree)
        return cls(_key(tree), tree)


@dataclass(frozen=True)
class Dim(_Keyed):
    """A dimension expression (``n``, ``n + p``, ``4``) as a tree of dimension names.

    >>> Dim.of({"name": "n"}).symbol, str(Dim.of({"num": 2}))
    ('n', '2')
    """

    @property
    def symbol(self) -> str | None:
        """The dimension name when the expression is a bare name, else ``None``."""
        return self.tree["name"] if "name" in self.tree else None

    def names(self) -> set[str]:
        """The dimension names the expression uses."""
        from lmic.ir.expr import names

        return names(self.tree)

    def value(self, dims: Mapping[Any, int]) -> int | None:
        """The integer value under ``dims`` (names -> sizes), ``None`` when not fixed."""
        env = {str(k): int(v) for k, v in dims.items()}
        if not self.names() <= set(env):
            return None
        v = _evaluate(self.tree, env)
        if not isinstance(v, float) or not v.is_integer():
            return None
        return int(v)

    def __str__(self) -> str:
        return _text(self.tree)


def _bind_sizes(node: Any, dims: Mapping[Any, int]) -> Any:
    """``node`` with every ``{"dim": tree}`` placeholder replaced by its integer value."""
    if isinstance(node, dict):
        if set(node) == {"dim"}:
            v = Dim.of(node["dim"]).value(dims)
            if v is None:
                raise IRError(f"dimension {_text(node['dim'])} cannot be evaluated")
            return v
        return {k: _bind_sizes(v, dims) for k, v in node.items()}
    if isinstance(node, list):
        return [_bind_sizes(v, dims) for v in node]
    return node


@dataclass(frozen=True)
class Tree(_Keyed):
    """A matrix or scalar expression whose identity and zero sizes are bound per dimensions."""

    def bound(self, dims: Mapping[Any, int]) -> dict[str, Any]:
        """The IR expression tree at these dimensions."""
        return _bind_sizes(self.tree, dims)


@dataclass(frozen=True)
class Coef(_Keyed):
    """A scalar coefficient (a tree in parameters and scalar constants)."""

    @property
    def is_number(self) -> bool:
        """True when the coefficient uses no name."""
        from lmic.ir.expr import names

        return not names(self.tree)

    def __float__(self) -> float:
        return float(_evaluate(self.tree, {}))

    def function(self, names: list[str]) -> Callable[..., float]:
        """``f(*values)`` with values in the order of ``names`` (``ValueError`` if it fails)."""
        tree = self.tree

        def f(*args: float) -> float:
            try:
                v = _evaluate(tree, dict(zip(names, args, strict=True)))
            except IRError as err:
                raise ValueError(str(err)) from None
            if not isinstance(v, float):
                raise ValueError("not a scalar")
            return v

        return f

    def __str__(self) -> str:
        return _text(self.tree)


@dataclass(frozen=True)
class Factor:
    """A constant factor: ``eye`` (identity), ``name`` (a matrix), ``nameT`` (its transpose), ``tree``."""

    frozen_kind: str
    name: str = ""
    expr: Tree | None = None

    @classmethod
    def of(cls, rec: Any) -> Factor:
        """The factor of a record ``["eye"] | ["name", A] | ["nameT", A] | ["tree", tree]``."""
        kind = rec[0]
        if kind == "eye" and len(rec) == 1:
            return cls("eye")
        if kind in ("name", "nameT") and len(rec) == 2 and isinstance(rec[1], str):
            return cls(kind, rec[1])
        if kind == "tree" and len(rec) == 2:
            return cls("tree", expr=Tree.of(rec[1]))
        raise ValueError("factor")

    def value(self, env: Mapping[str, Any], dims: Mapping[Any, int]) -> Any:
        """Its numeric value (``None`` for an identity)."""
        if self.frozen_kind == "eye":
            return None
        if self.frozen_kind == "name":
            return env[self.name]
        if self.frozen_kind == "nameT":
            return env[self.name].T
        assert self.expr is not None
        return _evaluate(self.expr.bound(dims), env)

    def __str__(self) -> str:
        return {"eye": "I", "name": self.name, "nameT": f"{self.name}.T"}.get(self.frozen_kind, "expr")


@dataclass(frozen=True)
class Domain:
    """A parameter's domain: an interval with exact ends, or integers / naturals (``text``: sympy's)."""

    kind: str
    lo: Fraction | None = None
    hi: Fraction | None = None
    left_open: bool = False
    right_open: bool = False
    text: str = ""

    @classmethod
    def of(cls, rec: Any, text: str) -> Domain:
        """The domain of a record (:mod:`lmic.compile.freeze`)."""
        if rec[0] in ("integers", "naturals", "naturals0") and len(rec) == 1:
            return cls(rec[0], text=text)
        kind, lo, hi, lopen, ropen = rec
        if kind != "interval" or not (isinstance(lopen, bool) and isinstance(ropen, bool)):
            raise ValueError("domain")
        return cls("interval", _fraction(lo), _fraction(hi), lopen, ropen, str(text))

    def contains_number(self, value: float) -> bool:
        """Whether ``value`` lies in the domain (exact comparison with the ends)."""
        if not math.isfinite(value):
            return False
        if self.kind != "interval":
            if not float(value).is_integer():
                return False
            return {"integers": True, "naturals": value >= 1, "naturals0": value >= 0}[self.kind]
        x = Fraction(value)
        if self.lo is not None and (x < self.lo or (self.left_open and x == self.lo)):
            return False
        if self.hi is not None and (x > self.hi or (self.right_open and x == self.hi)):
            return False
        return True

    def __str__(self) -> str:
        return self.text


def _fraction(b: Any) -> Fraction | None:
    if b is None:
        return None
    p, q = b
    if not (isinstance(p, int) and isinstance(q, int) and q > 0 and abs(p) < 10**30 and q < 10**30):
        raise ValueError("bound")
    return Fraction(p, q)
