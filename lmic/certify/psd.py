"""Exact positive (semi)definiteness of a symmetric integer matrix ``M``.

:func:`prove_pd` and :func:`prove_psd` prove or disprove, without floating-point doubt, that
``M`` (python ints, as :func:`lmic.certify.exact.exact_matrix` builds it) is positive definite or
semidefinite. They are the last step of the exact proofs of :mod:`lmic.certify.exact` and of the
exact Farkas proofs of :mod:`lmic.certify.farkas`.

How positive definiteness is proved (:func:`prove_pd`)
------------------------------------------------------
1. **Congruence + diagonal dominance** (fast, any size): a float Cholesky factor of the
   (diagonally scaled) matrix gives ``W ~ L^-1``; ``W`` is rounded to an integer *lower
   triangular* matrix with non-zero diagonal (so it is non-singular, which is checked exactly),
   and ``N = W M W^T`` is computed exactly with flint. By Sylvester's law of inertia ``M > 0``
   iff ``N > 0``, and ``N`` is close to the identity: if every row has
   ``N_ii > sum_{j != i} |N_ij|`` (exact integer comparisons), Gershgorin's theorem proves
   ``N > 0``. If ``N`` is not yet dominant (an ill-conditioned ``M``) the step is repeated on
   ``N`` (up to three rounds). For d = 180 this takes a few hundredths of a second.
2. **Exact LDL^T** (d <= 40): symmetric elimination in exact rationals. A strict LMI is proved
   when every pivot is ``> 0``; a non-strict one when every pivot is ``>= 0`` and a zero pivot
   has a zero column in the current Schur complement (then that row and column are dropped).
   A negative pivot, or a zero pivot with a non-zero column (the 2 x 2 minor
   ``[[0, b], [b, c]]`` has determinant ``-b^2 < 0``), *disproves* (semi)definiteness.
3. **Characteristic polynomial** (d <= 150): ``M`` is symmetric, so ``q(mu) = det(mu I + M)``
   has real roots ``-lambda_i``; all its coefficients are ``> 0`` iff ``M > 0`` and all are
   ``>= 0`` iff ``M >= 0``. The answer is exact either way (proved or disproved).
"""

from __future__ import annotations

import math
from fractions import Fraction
from types import ModuleType
from typing import Any

import numpy as np

from lmic.errors import LmicError

__all__ = ["prove_pd", "prove_psd", "bit_size", "load_flint", "LDL_MAX_DIM", "CHARPOLY_MAX_DIM"]

#: largest dimension proved by exact LDL^T in python rationals
LDL_MAX_DIM = 40
#: largest dimension proved through the characteristic polynomial
CHARPOLY_MAX_DIM = 150
#: rounds of the congruence step before the exact fallbacks
_ROUNDS = 3


def load_flint() -> ModuleType:
    """The python-flint module (an :class:`~lmic.errors.LmicError` naming the package if it is missing).

    >>> load_flint().fmpz(7) + 1
    8
    """
    try:
        import flint
    except ImportError as err:  # pragma: no cover - python-flint is a dependency
        raise LmicError("exact proofs need python-flint (pip install python-flint)") from err
    return flint


def bit_size(M: list[list[int]]) -> int:
    """Bits of the largest absolute entry of the integer matrix ``M``.

    >>> bit_size([[3, -4], [-4, 1]])
    3
    """
    return max((max(map(abs, row), default=0) for row in M), default=0).bit_length()


def _to_float(M: list[list[int]]) -> np.ndarray:
    try:
        return np.array(M, dtype=float)
    except OverflowError:
        s = bit_size(M) - 900
        return np.array([[float(v >> s) for v in row] for row in M])


def _dominant(N) -> tuple[bool, int]:
    """Is the fmpz_mat ``N`` strictly diagonally dominant with a positive diagonal?

    Returns ``(ok, first failing row or -1)``.
    """
    d = N.nrows()
    flat = [int(v) for v in N.entries()]
    for i in range(d):
        row = flat[i * d : (i + 1) * d]
        diag = row[i]
        if diag <= 0 or 2 * diag <= sum(abs(v) for v in row):
            return False, i
    return True, -1


def _inverse_cholesky(S: np.ndarray) -> np.ndarray | None:
    """``L^-1`` for the float Cholesky factor ``S = L L^T`` (``None`` if it breaks down).

    Up to d = 400 this runs as a numpy loop of vector operations: multithreaded LAPACK on
    these small matrices spends far more CPU on its thread pool (tens of milliseconds on a
    busy machine) than on the arithmetic.
    """
    d = S.shape[0]
    if d > 400:
        import scipy.linalg as sla  # here only: ~50 ms of import in every one-shot process otherwise

        L, info = sla.lapack.dpotrf(S, lower=1, clean=1)
        if info != 0:
            return None
        Linv, info = sla.lapack.dtrtri(L, lower=1)
        return None if info != 0 else np.tril(Linv)
    A = np.array(S, dtype=float)
    for j in range(d):
        piv = A[j, j]
        if not piv > 0:
            return None
        r = math.sqrt(piv)
        A[j, j] = r
        col = A[j + 1 :, j] / r
        A[j + 1 :, j] = col
        A[j + 1 :, j + 1 :] -= np.outer(col, col)
    L = np.tril(A)
    X = np.zeros_like(L)
    for i in range(d):
        X[i, i] = 1.0 / L[i, i]
        if i:
            X[i, :i] = -(L[i, :i] @ X[:i, :i]) / L[i, i]
    return X


def _congruence(M: list[list[int]]) -> tuple[bool, str]:
    """Step 1 of :func:`prove_pd`: ``W M W^T`` diagonally dominant for a triangular ``W``."""
    flint = load_flint()
    d = len(M)
    cur = flint.fmpz_mat(M)
    Mf = _to_float(M)
    for rnd in range(1, _ROUNDS + 1):
        diag = np.diag(Mf).copy()
        if np.any(~np.isfinite(Mf)) or np.any(diag <= 0):
            return False, "a diagonal entry is not positive"
        s = 1.0 / np.sqrt(diag)
        Linv = _inverse_cholesky(Mf * s[:, None] * s[None, :])
        if Linv is None:
            return False, "float Cholesky failed (not numerically positive definite)"
        W = Linv * s[None, :]
        # scale every row to ~2^50 and round to integers (row scaling keeps the congruence)
        rmax = np.max(np.abs(W), axis=1)
        expo = 50 - np.ceil(np.log2(rmax)).astype(int)
        Wi = np.rint(np.ldexp(W, expo[:, None]))
        Wint = Wi.astype(np.int64).tolist()
        for i in range(d):
            if Wint[i][i] == 0:  # keep W non-singular
                Wint[i][i] = 1
        Wm = flint.fmpz_mat(Wint)
        N = Wm * cur * Wm.transpose()
        ok, _ = _dominant(N)
        if ok:
            return (
                True,
                f"congruence W M W^T diagonally dominant ({rnd} round{'s' if rnd > 1 else ''})",
            )
        cur = N
        Mf = _to_float([[int(v) for v in row] for row in N.tolist()])
    return False, f"W M W^T not diagonally dominant after {_ROUNDS} rounds (ill-conditioned)"


def _ldl(M: list[list[int]], strict: bool) -> tuple[bool | None, str]:
    """Exact symmetric elimination; ``True`` proved, ``False`` disproved."""
    d = len(M)
    A = [[Fraction(v) for v in row] for row in M]
    active = list(range(d))
    npiv = 0
    while active:
        k = active[0]
        p = A[k][k]
        rest = active[1:]
        if p < 0:
            return False, f"pivot {npiv + 1} is negative"
        if p == 0:
            if strict:
                return False, f"pivot {npiv + 1} is zero (singular)"
            if any(A[i][k] != 0 for i in rest):
                return False, f"zero pivot {npiv + 1} with a non-zero column"
            active = rest
            npiv += 1
            continue
        for i in rest:
            f = A[i][k] / p
            if f:
                Ai, Ak = A[i], A[k]
                for j in rest:
                    if j >= i:
                        Ai[j] -= f * Ak[j]
                        if j != i:
                            A[j][i] = Ai[j]
        active = rest
        npiv += 1
    return True, f"exact LDL^T: {npiv} pivots {'> 0' if strict else '>= 0'}"


def _charpoly(M: list[list[int]], strict: bool) -> tuple[bool, str]:
    flint = load_flint()
    d = len(M)
    coeffs = [int(c) for c in flint.fmpz_mat(M).charpoly().coeffs()]  # low to high, det(lI - M)
    coeffs += [0] * (d + 1 - len(coeffs))
    signed = [c * (-1) ** (d + j) for j, c in enumerate(coeffs)]  # det(mu I + M)
    if strict:
        ok = all(c > 0 for c in signed)
        return ok, "charpoly: every coefficient of det(mu I + M) " + ("> 0" if ok else "is not > 0")
    ok = all(c >= 0 for c in signed)
    return ok, "charpoly: every coefficient of det(mu I + M) " + (">= 0" if ok else "is not >= 0")


def prove_pd(M: list[list[int]]) -> dict[str, Any]:
    """Prove (or disprove) that the symmetric integer matrix ``M`` is positive definite.

    Returns
    -------
    dict
        ``proven`` (bool), ``disproved`` (bool: exactly shown not to be positive definite),
        ``method`` and ``detail``.

    Examples
    --------
    >>> prove_pd([[2, 1], [1, 2]])["proven"], prove_pd([[1, 2], [2, 1]])["disproved"]
    (True, True)
    """
    return _prove(M, strict=True)


def prove_psd(M: list[list[int]]) -> dict[str, Any]:
    """Prove (or disprove) that the symmetric integer matrix ``M`` is positive semidefinite.

    >>> prove_psd([[1, 1], [1, 1]])["proven"], prove_psd([[0, 1], [1, 0]])["disproved"]
    (True, True)
    """
    return _prove(M, strict=False)


def _prove(M: list[list[int]], strict: bool) -> dict[str, Any]:
    d = len(M)
    if d == 0:
        return {"proven": True, "disproved": False, "method": "empty", "detail": ""}
    ok, detail = _congruence(M)
    if ok:
        return {"proven": True, "disproved": False, "method": "congruence", "detail": detail}
    if d <= LDL_MAX_DIM:
        res, why = _ldl(M, strict)
        return {"proven": bool(res), "disproved": res is False, "method": "ldl", "detail": why}
    if d <= CHARPOLY_MAX_DIM:
        res, why = _charpoly(M, strict)
        return {"proven": res, "disproved": not res, "method": "charpoly", "detail": why}
    return {
        "proven": False,
        "disproved": False,
        "method": "congruence",
        "detail": detail + f"; dimension {d} too large for the exact fallbacks",
    }
