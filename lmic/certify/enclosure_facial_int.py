"""Exact integer helpers of facial reduction (:mod:`lmic.certify.enclosure_facial_exact`).

The IR's coefficients are floats, hence dyadic rationals: a matrix times a power of two is an
integer matrix, exactly (``ldexp``). Products of integer matrices held in floats are exact when
every partial sum stays below ``2^53`` (:func:`_exact_product` checks it on the product of the
absolute values); elsewhere python-flint integers or python fractions are used. Nothing here
decides anything: the callers' exact checks do.

Examples
--------
>>> import numpy as np
>>> N, e = _int_scaled(np.array([[0.5, 0.25], [0.25, 1.0]]))
>>> N.tolist(), e
([[2.0, 1.0], [1.0, 4.0]], 2)
>>> _exact_int_rows(np.array([[0.5, 1.5, 0.0]]))
[[1, 3, 0]]
"""

from __future__ import annotations

import math
from fractions import Fraction
from typing import Any

import numpy as np
import scipy.sparse as sp

from lmic.ir.problem import LMI
from lmic.ir.svec import tril_rows_cols, tril_unvec

__all__ = ["EXACT_INT"]


def _fr(v: float) -> Fraction:
    return Fraction(float(v))


def _dyadic(tril: np.ndarray, dim: int) -> tuple[Any, int]:
    """The symmetric matrix of the tril vector ``tril`` (floats) as ``(N, e)``: ``N / 2^e``
    exactly, ``N`` a flint integer matrix."""
    from lmic.certify.psd import load_flint

    flint = load_flint()
    N, e = _int_scaled(tril_unvec(np.asarray(tril, dtype=float), dim))
    return flint.fmpz_mat(dim, dim, [int(v) for v in N.ravel().tolist()]), e


#: below this, sums of products of integers held in floats are exact
EXACT_INT = float(2**53)


def _int_scaled(F: np.ndarray) -> tuple[np.ndarray, int]:
    """``(N, e)`` with ``F = N / 2^e`` exactly and ``N`` integer-valued floats (or Python ints
    in an object array when they exceed :data:`EXACT_INT`)."""
    nz = np.abs(F[F != 0])
    if not nz.size:
        return np.zeros_like(F), 0
    # the largest power of two in any denominator: 2^-(exponent of the lowest set bit)
    e = max(int(abs(x).as_integer_ratio()[1]).bit_length() - 1 for x in np.unique(nz).tolist())
    N = np.ldexp(F, e)
    if float(np.max(np.abs(N))) < EXACT_INT:
        return N, e
    return np.array([[int(Fraction(float(v)) * (1 << e)) for v in row] for row in np.atleast_2d(F)], dtype=object), e


def _exact_product(*mats: np.ndarray) -> np.ndarray | None:
    """The product of integer-valued float matrices when it is exact in floating point (every
    partial sum below :data:`EXACT_INT`, checked on the product of the absolute values), else
    ``None``."""
    if any(m.dtype == object for m in mats):
        return None
    out, bound = mats[0], np.abs(mats[0])
    for m in mats[1:]:
        out, bound = out @ m, bound @ np.abs(m)
    return out if float(np.max(bound, initial=0.0)) < EXACT_INT else None


def _exact_int_rows(M: np.ndarray) -> list[list[int]]:
    """Every row of the float matrix ``M`` times a power of two that makes it integer (exact:
    ``ldexp`` scaling, and a float that is an integer converts exactly), as Python ints."""
    if not M.size:
        return []
    _, p = np.frexp(M)
    s_r = np.where(M != 0, 53 - p, -(10**6)).max(axis=1)
    s_r = np.where(s_r < -(10**5), 0, s_r)
    N = np.ldexp(M, s_r[:, None])
    if not np.all(np.isfinite(N)):
        return _int_rows([[_fr(v) for v in row] for row in M])
    if float(np.max(np.abs(N))) < 2.0**62:
        Ni = N.astype(np.int64)
        g = np.gcd.reduce(np.abs(Ni), axis=1)
        return (Ni // np.where(g > 0, g, 1)[:, None]).tolist()
    return [_primitive([int(v) for v in row]) for row in N.tolist()]


def _primitive(v: list[int]) -> list[int]:
    """``v`` divided by the gcd of its entries."""
    g = 0
    for a in v:
        g = math.gcd(g, a)
    return [a // g for a in v] if g > 1 else v


def _exact_rows_block(C: sp.spmatrix, Bf: np.ndarray, dim: int, n: int) -> list[list[int]] | None:
    """The rows ``(a, c)`` of ``d -> (sum_k d_k F^(k) B)[a, c]`` (``C``: an LMI's coefficients,
    ``Bf``: an integer basis as floats) as primitive integer rows, when every product is exact
    in floating point (:func:`_exact_product`); else ``None``."""
    C = sp.csc_matrix(C)
    cols = np.zeros((dim * Bf.shape[1], n))
    for k in range(n):
        if not C[:, 1 + k].nnz:
            continue
        N, e = _int_scaled(tril_unvec(C[:, 1 + k].toarray().ravel(), dim))
        P = _exact_product(N, Bf)
        if P is None:
            return None
        v = np.ldexp(P.ravel(), -e)
        if np.any(np.ldexp(v, e) != P.ravel()):
            return None
        cols[:, k] = v
    return _exact_int_rows(cols[np.any(cols != 0, axis=1)])


def _is_zero_product(M: np.ndarray, L: np.ndarray) -> bool:
    """Whether ``M @ L == 0`` exactly (``M`` floats, ``L`` integer-valued floats): each row of
    ``M`` scaled by a power of two to integers, the product in floats where every partial sum
    stays below :data:`EXACT_INT`, in rationals elsewhere."""
    if not M.size or not L.size:
        return True
    _, p = np.frexp(M)
    s_r = np.where(M != 0, 53 - p, -(10**6)).max(axis=1)
    s_r = np.where(s_r < -(10**5), 0, s_r)
    N = np.ldexp(M, s_r[:, None])
    fast = np.all(np.isfinite(N), axis=1)
    fast &= (np.abs(np.where(np.isfinite(N), N, 0.0)) @ np.abs(L)).max(axis=1, initial=0.0) < EXACT_INT
    if np.any((N[fast] @ L) != 0):
        return False
    slow = np.flatnonzero(~fast)
    whole = slow[np.all(np.isfinite(N[slow]), axis=1)]
    if whole.size:
        # the scaled rows are integers held exactly in floats: one exact integer product (flint)
        from lmic.certify.psd import load_flint

        flint = load_flint()
        A = flint.fmpz_mat(int(whole.size), int(M.shape[1]), [int(v) for v in N[whole].ravel().tolist()])
        B = flint.fmpz_mat(int(L.shape[0]), int(L.shape[1]), [int(v) for v in np.asarray(L).ravel().tolist()])
        if not (A * B).is_zero():
            return False
    for r in np.setdiff1d(slow, whole):
        for c in range(L.shape[1]):
            if sum((_fr(v) * int(L[k, c]) for k, v in enumerate(M[r]) if v and L[k, c]), Fraction(0)):
                return False
    return True


def _block_exact(lmi: LMI, d: list[int]) -> list[list[Fraction]]:
    """``W = sum_k d_k F^(k)`` of one LMI, exactly (``d`` integers)."""
    C = sp.csr_matrix(lmi.coeffs)
    i, j = tril_rows_cols(lmi.dim)
    W = [[Fraction(0)] * lmi.dim for _ in range(lmi.dim)]
    for t in range(C.shape[0]):
        s = Fraction(0)
        for col, v in zip(C.indices[C.indptr[t] : C.indptr[t + 1]], C.data[C.indptr[t] : C.indptr[t + 1]], strict=True):
            if col and d[col - 1]:
                s += _fr(v) * d[col - 1]
        W[i[t]][j[t]] = W[j[t]][i[t]] = s
    return W


def _int_rows(rows: list[list[Fraction]]) -> list[list[int]]:
    """Each row times the lcm of its denominators (same null space)."""
    out = []
    for r in rows:
        den = 1
        for f in r:
            den = den * f.denominator // math.gcd(den, f.denominator)
        out.append([int(f * den) for f in r])
    return out


def _short(rows: list[list[int]]) -> list[list[int]]:
    """An LLL-reduced basis of the lattice of the integer ``rows`` (same rational span, short
    entries: the reduced problem's coefficients ``V^T F V`` stay small and well scaled)."""
    from lmic.certify.psd import load_flint

    flint = load_flint()
    if not rows:
        return rows
    M = flint.fmpz_mat(len(rows), len(rows[0]), [v for r in rows for v in r]).lll()
    return [[int(M[i, j]) for j in range(M.ncols())] for i in range(M.nrows())]


def _pivots(V: list[list[int]]) -> list[int] | None:
    """Rows ``P`` of the integer matrix ``V`` (``d x r``) with ``V[P]`` invertible, or ``None``
    when ``V`` has rank below ``r``."""
    from lmic.certify.psd import load_flint

    flint = load_flint()
    d = len(V)
    r = len(V[0]) if d else 0
    if r == 0:
        return []
    R, rank = flint.fmpq_mat(r, d, [V[a][b] for b in range(r) for a in range(d)]).rref()
    if rank != r:
        return None
    piv = []
    for row in range(r):
        for col in range(d):
            if R[row, col] != 0:
                piv.append(col)
                break
    return piv


def _nullspace_int(rows: list[list[int]], n: int) -> list[list[int]]:
    """An integer basis (columns, as a list of column vectors) of ``{d : rows d = 0}``."""
    from lmic.certify.psd import load_flint

    flint = load_flint()
    if not rows:
        return [[int(i == j) for i in range(n)] for j in range(n)]
    X, nullity = flint.fmpz_mat(len(rows), n, [v for r in rows for v in r]).nullspace()
    return [_primitive([int(X[i, j]) for i in range(n)]) for j in range(int(nullity))]
