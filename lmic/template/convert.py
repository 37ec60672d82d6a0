"""Strict conversion of template values to sympy: sympy objects and numbers only.

Strings are never parsed (no ``sympify`` of text anywhere in lmic).

Examples
--------
>>> as_expr(2), as_expr(0.5)
(2, 0.500000000000000)
>>> as_expr("x + 1")
Traceback (most recent call last):
...
lmic.errors.TemplateError: expression: 'x + 1' is not a sympy expression or a number (text is never parsed)
"""

from __future__ import annotations

from fractions import Fraction
from typing import Any

import sympy

from lmic.errors import TemplateError

__all__ = ["as_expr"]


def as_expr(value: Any, what: str = "expression") -> sympy.Basic:
    """``value`` as a sympy object: sympy objects pass, Python numbers convert, nothing else."""
    if isinstance(value, sympy.Basic):
        return value
    if isinstance(value, bool):
        raise TemplateError(f"{what}: {value!r} is a bool, not a number")
    if isinstance(value, int):
        return sympy.Integer(value)
    if isinstance(value, float):
        return sympy.Float(value)
    if isinstance(value, Fraction):
        return sympy.Rational(value.numerator, value.denominator)
    hint = " (t.dims returns a tuple: write n, = t.dims('n'))" if isinstance(value, tuple) else ""
    raise TemplateError(f"{what}: {value!r} is not a sympy expression or a number (text is never parsed){hint}")
