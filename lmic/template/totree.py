"""Turn sympy expressions of a template into IR expression trees (:mod:`lmic.ir.expr`).

Dimension symbols are replaced by their bound integer values, so the tree is concrete.

Examples
--------
>>> import sympy as sp
>>> P, G = sp.MatrixSymbol("P", 2, 2), sp.MatrixSymbol("G", 2, 1)
>>> to_tree(P.inv() * G, {})
{'op': 'mul', 'args': [{'op': 'inv', 'args': [{'name': 'P'}]}, {'name': 'G'}]}
"""

from __future__ import annotations

from collections.abc import Mapping
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

from lmic.errors import TemplateError
from lmic.template.blocks import STAR, Block
from lmic.template.convert import as_expr

__all__ = ["to_tree", "FUNCTIONS", "lambda_max", "lambda_min", "spectral_radius", "norm2", "trace"]

lambda_max = sympy.Function("lambda_max")
lambda_min = sympy.Function("lambda_min")
spectral_radius = sympy.Function("spectral_radius")
norm2 = sympy.Function("norm2")
pinv = sympy.Function("pinv")


def trace(M: Any) -> Any:
    """The trace of a square matrix expression: a scalar, linear in the decision variables
    when ``M`` is (``t.minimize(trace(Z))``, ``trace(C * P * C.T)``).

    >>> import sympy
    >>> n, q = sympy.symbols("n q")
    >>> Z = sympy.MatrixSymbol("Z", q, q)
    >>> trace(Z + Z)
    2*Trace(Z)
    >>> trace(sympy.MatrixSymbol("Y", q, n))
    Traceback (most recent call last):
    ...
    lmic.errors.TemplateError: trace of a matrix that is not square: Y is q x n
    """
    e = as_expr(M)
    if not (getattr(e, "is_Matrix", False) or isinstance(e, sympy.MatrixExpr)):
        raise TemplateError(f"trace of '{e}', which is not a matrix")
    rows, cols = e.shape
    if rows - cols != 0:  # dimension symbols: a difference that is not identically zero
        raise TemplateError(f"trace of a matrix that is not square: {e} is {rows} x {cols}")
    return sympy.trace(e)


#: sympy function name -> expression-tree operator
FUNCTIONS = {
    "exp": "exp",
    "log": "log",
    "Abs": "abs",
    "Max": "max",
    "Min": "min",
    "lambda_max": "lambda_max",
    "lambda_min": "lambda_min",
    "spectral_radius": "spectral_radius",
    "spectral_abscissa": "spectral_abscissa",
    "norm2": "norm2",
    "pinv": "pinv",
}


def _dim(v: Any, dims: Mapping[sympy.Symbol, int]) -> Any:
    symbolic = getattr(dims, "symbolic_dim", None)
    if symbolic is not None:  # lmic.compile.freeze: a size left symbolic, bound at bind time
        return symbolic(v)
    val = as_expr(as_expr(v).xreplace(dict(dims)))
    if not val.is_Integer:
        raise TemplateError(f"dimension {v} cannot be evaluated (unbound symbol)")
    return int(val)


def _op(op: str, *args: dict) -> dict:
    return {"op": op, "args": list(args)}


def to_tree(e: Any, dims: Mapping[sympy.Symbol, int]) -> dict:
    """Convert a sympy scalar or matrix expression (or a :class:`Block`) to a tree."""
    if isinstance(e, Block):
        return _block_tree(e, dims)
    if isinstance(e, int | float):
        return {"num": float(e)}
    if isinstance(e, MatrixSymbol):
        return {"name": e.name}
    if isinstance(e, Identity):
        return {"eye": _dim(e.shape[0], dims)}
    if isinstance(e, ZeroMatrix):
        return {"zeros": [_dim(e.shape[0], dims), _dim(e.shape[1], dims)]}
    if isinstance(e, MatAdd | sympy.Add):
        return _op("add", *[to_tree(a, dims) for a in e.args])
    if isinstance(e, MatMul):
        coeff, mats = e.as_coeff_matrices()
        args = [] if coeff == 1 else [to_tree(coeff, dims)]
        return _op("mul", *args, *[to_tree(m, dims) for m in mats])
    if isinstance(e, sympy.Mul):
        return _op("mul", *[to_tree(a, dims) for a in e.args])
    if isinstance(e, Transpose):
        return _op("transpose", to_tree(e.arg, dims))
    if isinstance(e, Inverse):
        return _op("inv", to_tree(e.arg, dims))
    if isinstance(e, MatPow):
        return _op("pow", to_tree(e.base, dims), to_tree(e.exp, dims))
    if isinstance(e, sympy.Pow):
        if e.exp == sympy.Rational(1, 2):
            return _op("sqrt", to_tree(e.base, dims))
        if e.exp == -1:
            return _op("inv", to_tree(e.base, dims))
        return _op("pow", to_tree(e.base, dims), to_tree(e.exp, dims))
    if isinstance(e, Trace):
        return _op("trace", to_tree(e.arg, dims))
    if isinstance(e, sympy.Symbol):
        return {"name": e.name}
    if isinstance(e, sympy.Number) or (isinstance(e, sympy.Expr) and e.is_number):
        return {"num": float(e)}
    if isinstance(e, sympy.Function) or isinstance(e, sympy.core.function.AppliedUndef):
        name = type(e).__name__
        if name in FUNCTIONS:
            return _op(FUNCTIONS[name], *[to_tree(a, dims) for a in e.args])
    raise TemplateError(f"cannot express '{e}' ({type(e).__name__}) as an expression tree")


def _block_tree(b: Block, dims: Mapping[sympy.Symbol, int]) -> dict:
    k = b.shape[0]
    rows_n: list[int | None] = [None] * k
    for i in range(k):
        for j in range(k):
            for ent, axis, idx in ((b.entry(i, j), 0, i), (b.entry(j, i), 1, i)):
                if isinstance(ent, sympy.MatrixExpr) and rows_n[idx] is None:
                    rows_n[idx] = _dim(ent.shape[axis], dims)
    sizes = [r for r in rows_n if r is not None]
    if len(sizes) != k:
        raise TemplateError("a block row has no matrix entry to size it")
    out = []
    for i in range(k):
        row = []
        for j in range(k):
            ent = b.entry(i, j)
            if ent is STAR:
                mirror = b.entry(j, i)
                if mirror is STAR:
                    raise TemplateError(f"block ({i + 1},{j + 1}) and its mirror are both '*'")
                row.append(_op("transpose", _entry_tree(mirror, sizes[j], sizes[i], j == i, dims)))
            else:
                row.append(_entry_tree(ent, sizes[i], sizes[j], i == j, dims))
        out.append(row)
    return {"block": out}


def _entry_tree(ent: Any, r: int, c: int, diagonal: bool, dims: Mapping[sympy.Symbol, int]) -> dict:
    if isinstance(ent, int | float) and ent == 0:
        return {"zeros": [r, c]}
    if isinstance(ent, sympy.MatrixExpr):
        return to_tree(ent, dims)
    if diagonal:  # a scalar on a diagonal block means scalar * I
        return _op("mul", to_tree(as_expr(ent), dims), {"eye": r})
    raise TemplateError(f"scalar entry '{ent}' off the diagonal of a block matrix")
