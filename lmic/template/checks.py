"""Checks a theorem states on its derived quantities (certified numerically).

Each helper returns a :class:`CheckSpec`; the compiler turns it into an IR
:class:`~lmic.ir.problem.Check` whose meaning is fixed in :data:`lmic.ir.problem.CHECK_KINDS`.

Examples
--------
>>> import sympy as sp
>>> M = sp.MatrixSymbol("M", 2, 2)
>>> schur_stable(M).kind
'schur_stable'
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

__all__ = [
    "CheckSpec",
    "schur_stable",
    "hurwitz",
    "negative_definite",
    "positive_definite",
    "negative_semidefinite",
    "positive_semidefinite",
    "less_than",
    "greater_than",
    "finite",
]


@dataclass(frozen=True)
class CheckSpec:
    """A check before compilation: kind, a sympy expression (or a block), optional bound."""

    kind: str
    expr: Any
    bound: float | None = None


def schur_stable(M: Any) -> CheckSpec:
    """``M`` is Schur stable: spectral radius < 1 (discrete time)."""
    return CheckSpec("schur_stable", M)


def hurwitz(M: Any) -> CheckSpec:
    """``M`` is Hurwitz: every eigenvalue has negative real part (continuous time)."""
    return CheckSpec("hurwitz", M)


def negative_definite(M: Any) -> CheckSpec:
    """The symmetric matrix (or :class:`~lmic.template.blocks.Block`) ``M`` is < 0."""
    return CheckSpec("negative_definite", M)


def positive_definite(M: Any) -> CheckSpec:
    """The symmetric matrix (or block) ``M`` is > 0."""
    return CheckSpec("positive_definite", M)


def negative_semidefinite(M: Any) -> CheckSpec:
    """The symmetric matrix (or block) ``M`` is <= 0 (within tolerance)."""
    return CheckSpec("negative_semidefinite", M)


def positive_semidefinite(M: Any) -> CheckSpec:
    """The symmetric matrix (or block) ``M`` is >= 0 (within tolerance)."""
    return CheckSpec("positive_semidefinite", M)


def less_than(expr: Any, bound: float) -> CheckSpec:
    """A scalar expression is < ``bound``."""
    return CheckSpec("less_than", expr, float(bound))


def greater_than(expr: Any, bound: float) -> CheckSpec:
    """A scalar expression is > ``bound``."""
    return CheckSpec("greater_than", expr, float(bound))


def finite(expr: Any) -> CheckSpec:
    """Every entry of the expression is finite (e.g. a back-substituted gain exists)."""
    return CheckSpec("finite", expr)
