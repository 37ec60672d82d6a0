"""Index arithmetic of :mod:`lmic.compile.bind`: pure numpy, dimensions only (no values).

Where a coefficient of a term lands in an LMI's storage, and the integer types that hold it.

Examples
--------
>>> storage_map(0, 0, 2, 2, 2, False).tolist()
[0, 1, -1, 2]
"""

from __future__ import annotations

from typing import Any

import numpy as np

from lmic.ir.problem import Variable
from lmic.ir.svec import tril_index, tril_rows_cols

__all__ = ["basis_entries", "index_dtype", "storage_map", "column_major_order"]


def basis_entries(var: Variable) -> tuple[np.ndarray, np.ndarray]:
    """Rows and columns of the unit entries of ``var.basis()`` in its CSC order (column, then
    row), computed with numpy alone (no sparse matrix built) for the common kinds.

    >>> v = Variable("P", "symmetric", (2, 2))
    >>> [a.tolist() for a in basis_entries(v)]
    [[0, 1, 2, 3], [0, 1, 1, 2]]
    """
    r, c = var.shape
    if var.kind in ("scalar", "full"):
        k = np.arange(r * c, dtype=np.int64)
        return k, k
    if var.kind == "symmetric":
        i, j = (a.astype(np.int64) for a in tril_rows_cols(r))  # storage order: by column, then row
        k = np.arange(len(i), dtype=np.int64)
        off = i != j
        counts = 1 + off.astype(np.int64)  # an off-diagonal x_k sets (i, j) and (j, i)
        rows = np.empty(int(counts.sum()), dtype=np.int64)
        first = np.concatenate([[0], np.cumsum(counts)[:-1]])
        rows[first] = i + j * r  # (i, j) with i >= j comes first: i + j r < j + i r
        rows[first[off] + 1] = j[off] + i[off] * r
        return rows, np.repeat(k, counts)
    coo = var.basis().tocoo()  # diagonal, block-diagonal: the IR's own construction
    return coo.row.astype(np.int64), coo.col.astype(np.int64)


def index_dtype(top: int) -> type[np.signedinteger[Any]]:
    """``int32`` when indices up to ``top`` (and twice it) fit, else ``int64``.

    >>> index_dtype(10).__name__, index_dtype(2**31).__name__
    ('int32', 'int64')
    """
    return np.int32 if 2 * top < np.iinfo(np.int32).max else np.int64


def storage_map(row0: int, col0: int, ri: int, cj: int, d: int, mirrored: bool) -> np.ndarray:
    """Storage row of every position of a block entry's column-major vec (``-1``: upper triangle).

    The entry fills rows ``row0 ..`` and columns ``col0 ..`` (``ri x cj``) of a ``d x d`` LMI;
    ``mirrored``: the values are those of the ``cj x ri`` entry above it, transposed.

    >>> storage_map(0, 0, 2, 2, 2, False).tolist()
    [0, 1, -1, 2]
    >>> storage_map(1, 0, 1, 1, 2, True).tolist()
    [1]
    """
    gi = row0 + np.arange(ri, dtype=np.int64)[:, None]
    gj = col0 + np.arange(cj, dtype=np.int64)[None, :]
    grid = np.where(gi >= gj, tril_index(gi, gj, d), -1)  # (ri x cj), by global position
    return np.ascontiguousarray(grid.ravel(order="C" if mirrored else "F"))


def column_major_order(r: np.ndarray, c: np.ndarray, nrows: int, ncols: int) -> np.ndarray:
    """The permutation sorting entries ``(r, c)`` by column, then row (stable).

    Two stable passes (rows, then columns): radix sorts in linear time when both fit 16 bits.

    >>> column_major_order(np.array([2, 0, 1, 0]), np.array([0, 1, 0, 0]), 3, 2).tolist()
    [3, 2, 0, 1]
    """
    small = np.uint16 if max(nrows, ncols) <= np.iinfo(np.uint16).max else None
    if small is None:
        return np.lexsort((r, c))
    by_row = np.argsort(r.astype(small), kind="stable")
    return by_row[np.argsort(c[by_row].astype(small), kind="stable")]
