"""Block matrices written like the paper: ``block([[a, b], [STAR, c]]) < 0``.

A single matrix needs no ``block``: importing :mod:`lmic.template` lets any sympy matrix
expression be compared with 0 (``A.T * P + P * A < 0``, ``P > 0``), which sympy itself refuses;
the result is the same :class:`LmiSpec` as ``block(M) < 0``.

Entries are sympy matrix expressions, ``0`` (a zero block sized by position), a scalar
expression on a diagonal block (meaning ``scalar * I`` sized by position, as papers write
``-alpha I``), or :data:`STAR` (the transpose of the mirror entry, filled by the compiler).

Examples
--------
>>> import sympy as sp
>>> n = sp.Symbol("n")
>>> P = sp.MatrixSymbol("P", n, n)
>>> spec = block([[-P, 0], [STAR, -P]]) < 0
>>> spec.relation, spec.strict, spec.block.shape
('<', True, (2, 2))
>>> (P > 0).block.shape
(1, 1)
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import sympy

from lmic.errors import TemplateError

__all__ = ["STAR", "Block", "LmiSpec", "block", "I"]


class _Star:
    """The ``*`` of a symmetric block matrix: the transpose of the mirror entry."""

    _instance: _Star | None = None

    def __new__(cls) -> _Star:
        if cls._instance is None:
            cls._instance = super().__new__(cls)
        return cls._instance

    def __repr__(self) -> str:
        return "STAR"


STAR = _Star()


def I(n: Any) -> sympy.Identity:  # noqa: E743 - reads like the paper
    """The ``n x n`` identity (``n`` a dimension symbol or an integer).

    >>> I(3).shape
    (3, 3)
    """
    return sympy.Identity(n)


@dataclass(frozen=True)
class LmiSpec:
    """A block matrix with a relation to zero: what ``block(...) < 0`` builds."""

    block: Block
    relation: str

    def __bool__(self) -> bool:
        raise TypeError("an LMI (matrix compared with 0) has no truth value; pass it to t.lmi(name, ...)")

    @property
    def strict(self) -> bool:
        """True for ``<`` and ``>``."""
        return self.relation in ("<", ">")

    @property
    def negated(self) -> bool:
        """True when the compiled form is ``-M >(=) 0`` (relations ``<``, ``<=``)."""
        return self.relation in ("<", "<=")


def _check_zero(other: Any, rel: str) -> None:
    if not (isinstance(other, int | float) and other == 0):
        raise TemplateError(
            f"an LMI is compared with 0 (write 'M - N {rel} 0' instead of 'M {rel} N', declared with t.lmi)"
        )


class Block:
    """A square block matrix of sympy expressions with ``STAR`` entries.

    Parameters
    ----------
    rows : list of list
        ``rows[i][j]`` is the block in block-row ``i``, block-column ``j``.
    """

    def __init__(self, rows: Any) -> None:
        if isinstance(rows, sympy.MatrixExpr | sympy.Expr):
            rows = [[rows]]
        if not isinstance(rows, list | tuple) or not rows or not all(isinstance(r, list | tuple) for r in rows):
            raise TemplateError("block() takes a list of rows, each a list of entries")
        k = len(rows)
        for i, r in enumerate(rows):
            if len(r) != k:
                raise TemplateError(f"block row {i + 1} has {len(r)} entries; a symmetric block matrix needs {k}")
        self.rows = [list(r) for r in rows]

    @property
    def shape(self) -> tuple[int, int]:
        """Number of block rows and block columns."""
        return (len(self.rows), len(self.rows))

    def entry(self, i: int, j: int) -> Any:
        """The entry as written (may be ``STAR`` or ``0``)."""
        return self.rows[i][j]

    def __lt__(self, other: Any) -> LmiSpec:
        _check_zero(other, "<")
        return LmiSpec(self, "<")

    def __le__(self, other: Any) -> LmiSpec:
        _check_zero(other, "<=")
        return LmiSpec(self, "<=")

    def __gt__(self, other: Any) -> LmiSpec:
        _check_zero(other, ">")
        return LmiSpec(self, ">")

    def __ge__(self, other: Any) -> LmiSpec:
        _check_zero(other, ">=")
        return LmiSpec(self, ">=")

    def __repr__(self) -> str:
        return f"block({self.rows!r})"


def block(rows: Any) -> Block:
    """Build a :class:`Block` (a single matrix expression is a 1 x 1 block).

    >>> import sympy as sp
    >>> P = sp.MatrixSymbol("P", 2, 2)
    >>> (block(P) > 0).relation
    '>'
    """
    return Block(rows)


def _matrix_compare(rel: str) -> Any:
    def compare(self: sympy.MatrixExpr, other: Any) -> LmiSpec:
        _check_zero(other, rel)
        return LmiSpec(Block([[self]]), rel)

    compare.__name__ = {"<": "__lt__", "<=": "__le__", ">": "__gt__", ">=": "__ge__"}[rel]
    return compare


# sympy raises "Invalid comparison of non-real" for a matrix compared with 0; make it an LMI
for _rel in ("<", "<=", ">", ">="):
    _f = _matrix_compare(_rel)
    setattr(sympy.MatrixExpr, _f.__name__, _f)
