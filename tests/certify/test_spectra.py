"""lmic.certify.spectra: the Perron root from above, the shared per-block spectrum and term
scale, and the per-LMI prepared coefficients (the truth from dense numpy: ``numpy.linalg.norm(.,
2)`` (an SVD) and ``eigvalsh``, computed without the module's caches)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

from lmic.certify.margins import lmi_report
from lmic.certify.result import Tolerances
from lmic.certify.spectra import block_spectrum, clear, perron_root, prepared, term_scale
from lmic.ir.problem import LMI


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("d", [2, 7, 60])
def test_perron_root_is_an_upper_bound_close_to_the_largest_eigenvalue(seed, d):
    rng = np.random.default_rng(seed)
    G = np.abs(rng.standard_normal((d, d))) * (rng.random((d, d)) < 0.5)
    M = G + G.T
    truth = float(np.linalg.eigvalsh(M)[-1])
    got = perron_root(M)
    assert got >= truth * (1 - 1e-12) and got <= truth * (1 + 1e-9)


def test_perron_root_of_a_reducible_matrix_falls_back():
    M = np.diag([0.0, 3.0, 1.0])  # zero row: no Collatz-Wielandt bracket
    assert perron_root(M) == pytest.approx(3.0, rel=1e-14)


def test_block_spectrum_is_keyed_by_the_point_and_the_lmi():
    clear()
    rng = np.random.default_rng(1)
    lmi = LMI("F", 3, sp.csc_matrix(rng.standard_normal((6, 3))))
    x1, x2 = np.array([0.3, -1.0]), np.array([0.3, -1.0 + 1e-15])
    F1, e1 = block_spectrum(lmi, x1)
    assert np.array_equal(e1, np.linalg.eigvalsh(lmi.matrix(x1)))
    assert block_spectrum(lmi, x1.copy())[1] is e1  # reused
    F2, e2 = block_spectrum(lmi, x2)
    assert e2 is not e1 and np.allclose(e2, np.linalg.eigvalsh(lmi.matrix(x2)), rtol=0, atol=1e-12)
    other = LMI("G", 3, sp.csc_matrix(rng.standard_normal((6, 3))))
    assert np.array_equal(block_spectrum(other, x1)[1], np.linalg.eigvalsh(other.matrix(x1)))


def test_perron_root_of_two_components_far_apart_is_the_largest_eigenvalue():
    """Regression: |F| of an obs_control.thm3_2 LMI has two components with roots ~1e3 and ~4e5.

    The power iteration's vector underflows to 0 on the small component; the old bracket then
    divided by 0 and returned inf, so the certifier saw T = inf and rejected a point with margin
    0.039 as "zero to float64 accuracy". The truth here is numpy's symmetric eigensolver.
    """
    M = np.load(Path(__file__).parent / "data" / "perron_underflow.npy", allow_pickle=False)
    truth = float(np.linalg.eigvalsh(M)[-1])
    root = perron_root(M)
    assert np.isfinite(root)
    assert truth <= root <= truth * (1 + 1e-9)  # an upper bound, tight


def _dense_term_scale(lmi: LMI, x: np.ndarray) -> float:
    """``|| |F0| + sum_k |x_k| |F_k| ||_2`` from dense coefficient matrices (an SVD)."""
    T = np.abs(lmi.coefficient(0))
    for k, xk in enumerate(x):
        T = T + abs(xk) * np.abs(lmi.coefficient(k + 1))
    return float(np.linalg.norm(T, 2))


@pytest.mark.parametrize("seed", range(4))
def test_term_scale_is_the_norm_of_the_absolute_terms_from_above(seed):
    clear()
    rng = np.random.default_rng(seed)
    d, n = 6, 4
    C = sp.random(d * (d + 1) // 2, n + 1, density=0.5, random_state=seed, format="csc")
    C.data = rng.standard_normal(C.nnz)
    lmi = LMI("F", d, C)
    x = rng.standard_normal(n)
    truth = _dense_term_scale(lmi, x)
    got = term_scale(lmi, x)
    assert truth * (1 - 1e-14) <= got <= truth * (1 + 1e-12)
    assert term_scale(lmi, x.copy()) == got  # kept with the spectrum


def test_a_rebind_with_other_numbers_never_reuses_prepared_or_spectral_data():
    """Two LMIs with the same shape and sparsity but other numbers (a re-bind): each is judged on
    its own coefficients, even when the first is gone and its id is reused."""
    clear()
    rng = np.random.default_rng(7)
    pattern = sp.random(6, 3, density=0.7, random_state=1, format="csc")
    x = np.array([0.4, -0.9])
    seen = []
    for _ in range(30):  # ids of dropped objects are reused by CPython: exercise that
        C = pattern.copy()
        C.data = rng.standard_normal(C.nnz)
        lmi = LMI("F", 3, C)
        F, eig = block_spectrum(lmi, x)
        assert np.array_equal(F, lmi.matrix(x))
        assert np.allclose(eig, np.linalg.eigvalsh(lmi.matrix(x)), rtol=0, atol=1e-13)
        assert prepared(lmi).C.toarray() == pytest.approx(C.toarray(), abs=0)
        assert term_scale(lmi, x) == pytest.approx(_dense_term_scale(lmi, x), rel=1e-12)
        seen.append(id(lmi))
        del lmi
    # the replaced coefficients of one LMI object are prepared again
    lmi = LMI("F", 3, pattern.copy())
    first = prepared(lmi)
    lmi.coeffs = sp.csc_matrix(2.0 * pattern)
    assert prepared(lmi) is not first
    assert np.allclose(block_spectrum(lmi, x)[0], lmi.matrix(x))


def test_cached_lmi_report_equals_the_uncached_one():
    rng = np.random.default_rng(3)
    C = sp.random(10, 5, density=0.6, random_state=3, format="csc")
    C.data = rng.standard_normal(C.nnz)
    lmi = LMI("F", 4, C)
    x = rng.standard_normal(4)
    clear()
    cold = lmi_report(lmi, x, Tolerances())
    warm = lmi_report(lmi, x, Tolerances())  # every cache hit
    assert cold == warm
    clear()
    assert lmi_report(lmi, x, Tolerances()) == cold
