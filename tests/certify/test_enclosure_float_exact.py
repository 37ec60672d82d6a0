"""The last resorts of ``primal_end`` (lmic.certify.enclosure_float): the exactly rounded
evaluation, the exact positive-definiteness proof, the shifts below the Cholesky floor."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import scipy.sparse as sp

from lmic.certify.enclosure_float import exact_lmi, lambda_min_lower, rounded_products
from lmic.ir.svec import tril_vec


def test_rounded_products_are_the_exact_sums_rounded_once() -> None:
    rng = np.random.default_rng(3)
    C = sp.random(40, 30, density=0.4, random_state=4, format="csr") * 1e3
    x = rng.standard_normal(30) * 10.0 ** rng.integers(-5, 5, 30)
    got = rounded_products(C, x)
    for r in range(C.shape[0]):
        lo, hi = C.indptr[r], C.indptr[r + 1]
        exact = sum(
            (Fraction(float(v)) * Fraction(float(x[j])) for j, v in zip(C.indices[lo:hi], C.data[lo:hi], strict=True)),
            Fraction(0),
        )
        assert got[r] == float(exact)  # Fraction -> float rounds to nearest


def _storage(M: np.ndarray) -> sp.csr_matrix:
    """Storage of the constant LMI ``M`` (one column, no variable)."""
    return sp.csr_matrix(tril_vec(M)[:, None])


def test_exact_lmi_decides_what_floating_point_cannot() -> None:
    eps = 2.0**-45
    # [[1, 1], [1, 1 + eps]] is positive definite (lambda_min ~ eps / 2); with 1 - eps indefinite
    assert exact_lmi(_storage(np.array([[1.0, 1.0], [1.0, 1.0 + eps]])), np.array([1.0]), 2)
    assert not exact_lmi(_storage(np.array([[1.0, 1.0], [1.0, 1.0 - eps]])), np.array([1.0]), 2)
    # exactly singular: not positive definite
    assert not exact_lmi(_storage(np.array([[1.0, 1.0], [1.0, 1.0]])), np.array([1.0]), 2)
    # the shift is honoured: lambda_min ~ eps / 2 is not above eps
    assert not exact_lmi(_storage(np.array([[1.0, 1.0], [1.0, 1.0 + eps]])), np.array([1.0]), 2, shift=eps)


def test_lambda_min_lower_below_the_floor_is_still_a_lower_bound() -> None:
    # a large matrix with a margin far below 4 (d + 1)^2 u ||A||: Q diag(...) Q^T, eigenvalues known
    rng = np.random.default_rng(0)
    d = 20
    Q, _ = np.linalg.qr(rng.standard_normal((d, d)))
    eig = np.concatenate([[3e-9], np.linspace(1.0, 4e4, d - 1)])
    A = (Q * eig) @ Q.T
    A = 0.5 * (A + A.T)
    lb = lambda_min_lower(A)
    true = float(np.linalg.eigvalsh(A)[0])  # accurate to ~1e-11 here: the bound must stay below it
    assert 0 < lb <= true + 1e-11
