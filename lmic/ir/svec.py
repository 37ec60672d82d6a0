"""The one vectorisation convention of lmic, written down once.

Storage convention of the IR (``tril``)
    A symmetric ``d x d`` matrix ``M`` is stored as its **lower triangle in column-major
    order**, *unscaled*: entry ``k`` holds ``M[i, j]`` with ``i >= j``, in the order
    ``(0,0), (1,0), ..., (d-1,0), (1,1), (2,1), ..., (d-1,d-1)``. The vector has
    ``d (d + 1) / 2`` entries. :func:`tril_index` gives ``k`` for ``(i, j)``.

Isometric convention for conic solvers (``svec``)
    The same order with every off-diagonal entry multiplied by ``sqrt(2)`` so that
    ``svec(A) . svec(B) == trace(A B)``. SCS uses exactly this. Clarabel uses the *upper*
    triangle column-major with ``sqrt(2)`` scaling, which for a symmetric matrix is the lower
    triangle in *row-major* order: :func:`tril_to_triu_colmajor_perm` gives that permutation.

Backends convert from the storage convention with the helpers here and nowhere else.

Examples
--------
>>> import numpy as np
>>> M = np.array([[1.0, 2.0], [2.0, 3.0]])
>>> tril_vec(M)
array([1., 2., 3.])
>>> np.allclose(tril_unvec(tril_vec(M), 2), M)
True
"""

from __future__ import annotations

import functools
import math

import numpy as np

__all__ = [
    "tril_size",
    "tril_dim",
    "tril_index",
    "tril_rows_cols",
    "tril_vec",
    "tril_unvec",
    "svec_scale",
    "tril_to_triu_colmajor_perm",
]

SQRT2 = math.sqrt(2.0)


def tril_size(d: int) -> int:
    """Number of entries of the lower triangle of a ``d x d`` matrix.

    >>> tril_size(3)
    6
    """
    return d * (d + 1) // 2


def tril_dim(size: int) -> int:
    """Inverse of :func:`tril_size`; raises ``ValueError`` if ``size`` is not triangular.

    >>> tril_dim(6)
    3
    """
    d = int((math.isqrt(8 * size + 1) - 1) // 2)
    if tril_size(d) != size:
        raise ValueError(f"{size} is not a triangular number")
    return d


def tril_index(i, j, d: int):
    """Position of ``(i, j)`` (``i >= j``) in the column-major lower triangle of a ``d x d``.

    Works element-wise on integer arrays.

    >>> tril_index(1, 0, 3), tril_index(1, 1, 3), tril_index(2, 2, 3)
    (1, 3, 5)
    """
    return j * d - (j * (j - 1)) // 2 + (i - j)


@functools.lru_cache(maxsize=64)
def _tril_rows_cols(d: int) -> tuple[np.ndarray, np.ndarray]:
    """:func:`tril_rows_cols`, computed once per ``d`` (read-only arrays)."""
    cols, rows = np.triu_indices(d)  # (j, i) pairs with j <= i in row-major of the upper = colmajor lower
    order = np.lexsort((rows, cols))
    r, c = rows[order], cols[order]
    r.setflags(write=False)
    c.setflags(write=False)
    return r, c


def tril_rows_cols(d: int) -> tuple[np.ndarray, np.ndarray]:
    """Row and column indices ``(i, j)`` of every storage position, in storage order.

    >>> tril_rows_cols(2)
    (array([0, 1, 1]), array([0, 0, 1]))
    """
    r, c = _tril_rows_cols(d)
    return r.copy(), c.copy()


def tril_vec(M: np.ndarray) -> np.ndarray:
    """Lower triangle of a symmetric matrix in storage order (unscaled).

    >>> tril_vec(np.eye(2))
    array([1., 0., 1.])
    """
    M = np.asarray(M)
    r, c = _tril_rows_cols(M.shape[0])
    return M[r, c]


def tril_unvec(v, d: int) -> np.ndarray:
    """Symmetric ``d x d`` matrix from its storage vector.

    >>> tril_unvec([1.0, 2.0, 3.0], 2)
    array([[1., 2.],
           [2., 3.]])
    """
    v = np.asarray(v, dtype=float)
    M = np.empty((d, d))
    r, c = _tril_rows_cols(d)
    M[r, c] = v
    M[c, r] = v
    return M


def svec_scale(d: int) -> np.ndarray:
    """Per-entry factor turning a storage vector into the isometric ``svec`` (1 or sqrt 2).

    >>> svec_scale(2)
    array([1.        , 1.41421356, 1.        ])
    """
    r, c = _tril_rows_cols(d)
    return np.where(r == c, 1.0, SQRT2)


def tril_to_triu_colmajor_perm(d: int) -> np.ndarray:
    """Permutation ``p`` with ``triu_colmajor = tril_storage[p]`` (Clarabel's order).

    Clarabel stores the upper triangle column by column: ``(0,0), (0,1), (1,1), (0,2), ...``;
    entry ``(r, c)`` with ``r <= c`` equals the storage entry ``(c, r)``.

    >>> tril_to_triu_colmajor_perm(2)
    array([0, 1, 2])
    >>> tril_to_triu_colmajor_perm(3)
    array([0, 1, 3, 2, 4, 5])
    """
    rows, cols = [], []
    for c in range(d):
        for r in range(c + 1):
            rows.append(r)
            cols.append(c)
    return tril_index(np.array(cols), np.array(rows), d)
