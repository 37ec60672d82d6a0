"""Exact zero tests of facial reduction (lmic.certify.enclosure_facial_int._is_zero_product)
where float partial sums exceed 2^53 (the exact integer product), against python fractions."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest

from lmic.certify.enclosure_facial_int import _is_zero_product


def _truth(M: np.ndarray, L: np.ndarray) -> bool:
    """``M @ L == 0`` in rationals, entry by entry (independent of the code under test)."""
    return all(
        sum((Fraction(float(M[r, k])) * int(L[k, c]) for k in range(M.shape[1])), Fraction(0)) == 0
        for r in range(M.shape[0])
        for c in range(L.shape[1])
    )


def test_cancellation_above_two_to_the_53():
    L = np.array([[2.0**60], [1.0]])
    zero = np.array([[1.0, -(2.0**60)]])
    off = np.array([[1.0, -(2.0**60 - 256.0)]])  # exact in floats; the product is 256
    assert _truth(zero, L) and not _truth(off, L)
    assert _is_zero_product(zero, L)
    assert not _is_zero_product(off, L)
    # a float sum would round 2^60 + 1 - 2^60 to 0; the exact product does not
    assert not _is_zero_product(np.array([[1.0, 1.0, -1.0]]), np.array([[2.0**60], [1.0], [2.0**60]]))


@pytest.mark.parametrize("seed", range(4))
def test_random_rows_against_fractions(seed):
    rng = np.random.default_rng(seed)
    for _ in range(50):
        n = int(rng.integers(2, 6))
        L = rng.integers(-3, 4, size=(n, 2)).astype(float) * 2.0 ** int(rng.integers(40, 60))
        M = rng.integers(-5, 6, size=(3, n)).astype(float) * 2.0 ** int(rng.integers(-20, 20))
        if rng.random() < 0.5:  # a row exactly orthogonal to L's columns: 2 x 2 cofactors
            L[:, 1] = 0.0
            M[0, :] = 0.0
            M[0, 0], M[0, 1] = L[1, 0], -L[0, 0]
            M = M[:1]
        assert _is_zero_product(M, L) == _truth(M, L)
