"""The storage convention (lower triangle, column-major, unscaled) and its conversions."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from lmic.ir.svec import (
    svec_scale,
    tril_dim,
    tril_index,
    tril_rows_cols,
    tril_size,
    tril_to_triu_colmajor_perm,
    tril_unvec,
    tril_vec,
)

dims = st.integers(min_value=1, max_value=9)


def _sym(d: int, seed: int) -> np.ndarray:
    M = np.random.default_rng(seed).standard_normal((d, d))
    return M + M.T


def test_storage_order_is_lower_triangle_column_major():
    d = 4
    r, c = tril_rows_cols(d)
    expected = [(i, j) for j in range(d) for i in range(j, d)]
    assert list(zip(r.tolist(), c.tolist(), strict=True)) == expected
    M = np.arange(16.0).reshape(4, 4)
    M = M + M.T
    assert tril_vec(M).tolist() == [M[i, j] for i, j in expected]


@given(dims)
def test_size_and_dim_are_inverse(d):
    assert tril_size(d) == d * (d + 1) // 2 == len(tril_rows_cols(d)[0])
    assert tril_dim(tril_size(d)) == d


@pytest.mark.parametrize("size", [2, 4, 5, 7, 8, 9, 11])
def test_tril_dim_rejects_non_triangular(size):
    with pytest.raises(ValueError, match="not a triangular number"):
        tril_dim(size)


@given(dims)
def test_tril_index_matches_storage_order(d):
    r, c = tril_rows_cols(d)
    assert np.array_equal(tril_index(r, c, d), np.arange(tril_size(d)))
    # scalar form agrees with the vectorised one
    assert [tril_index(int(i), int(j), d) for i, j in zip(r, c, strict=True)] == list(range(tril_size(d)))


@given(dims, st.integers(0, 2**31))
def test_vec_unvec_round_trip(d, seed):
    M = _sym(d, seed)
    v = tril_vec(M)
    assert v.shape == (tril_size(d),)
    assert np.array_equal(tril_unvec(v, d), M)  # exact: entries are copied, not computed
    assert np.array_equal(tril_vec(tril_unvec(v, d)), v)


def test_unvec_is_symmetric_and_unscaled():
    M = tril_unvec([1.0, 2.0, 3.0, 4.0, 5.0, 6.0], 3)
    assert np.array_equal(M, [[1, 2, 3], [2, 4, 5], [3, 5, 6]])


@given(dims, st.integers(0, 2**31))
def test_svec_scaling_makes_the_inner_product_the_trace(d, seed):
    A, B = _sym(d, seed), _sym(d, seed + 1)
    s = svec_scale(d)
    r, c = tril_rows_cols(d)
    assert np.all(s[r == c] == 1.0) and np.allclose(s[r != c], np.sqrt(2.0))
    assert np.isclose((s * tril_vec(A)) @ (s * tril_vec(B)), np.trace(A @ B))


@given(dims, st.integers(0, 2**31))
def test_triu_colmajor_permutation(d, seed):
    M = _sym(d, seed)
    p = tril_to_triu_colmajor_perm(d)
    assert sorted(p.tolist()) == list(range(tril_size(d)))
    expected = [M[r, c] for c in range(d) for r in range(c + 1)]  # Clarabel's order
    assert np.array_equal(tril_vec(M)[p], expected)
