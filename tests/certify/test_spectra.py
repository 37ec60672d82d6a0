"""lmic.certify.spectra: the Perron root without a second decomposition, and the shared
per-block spectrum (the truth from numpy's eigvalsh, a different algorithm)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

from lmic.certify.spectra import block_spectrum, clear, perron_root
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
