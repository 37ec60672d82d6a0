"""The tutorial plugin: installed through its entry point, solved, certified, and checked
against an H-infinity norm computed independently (Hamiltonian bisection)."""

from __future__ import annotations

import numpy as np
import pytest

import lmic.api
from lmic.registry import get_theorem


def hinf_norm(A, B, C, D, tol=1e-9):
    """H-infinity norm by bisection on the imaginary-axis eigenvalues of the Hamiltonian."""
    lo = max(np.linalg.svd(D, compute_uv=False).max(initial=0.0), 1e-12)
    hi = 1.0

    def has_imag_eig(g):
        R = g * g * np.eye(D.shape[1]) - D.T @ D
        Ri = np.linalg.inv(R)
        H = np.block(
            [
                [A + B @ Ri @ D.T @ C, B @ Ri @ B.T],
                [-C.T @ (np.eye(C.shape[0]) + D @ Ri @ D.T) @ C, -(A + B @ Ri @ D.T @ C).T],
            ]
        )
        ev = np.linalg.eigvals(H)
        return np.any(np.abs(ev.real) < 1e-7 * max(1.0, np.abs(ev).max()))

    while has_imag_eig(hi):
        hi *= 2
    while hi - lo > tol * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if has_imag_eig(mid) else (lo, mid)
    return hi


def test_the_plugin_is_discovered_through_its_entry_point():
    thm = get_theorem("tutorial.bounded_real")
    assert thm.plugin.startswith("tutorial (lmic_tutorial")
    assert thm.provider.distribution == "lmic-tutorial"


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_minimal_gamma_is_the_hinf_norm_and_is_certified(seed):
    rng = np.random.default_rng(seed)
    n, m, q = 4, 2, 2
    A = rng.standard_normal((n, n))
    A -= (max(np.linalg.eigvals(A).real) + 0.5) * np.eye(n)  # make it Hurwitz
    B, C = rng.standard_normal((n, m)), rng.standard_normal((q, n))
    system = {"lmic": 1, "data": {"A": A.tolist(), "B": B.tolist(), "C": C.tolist()}}
    result = lmic.api.solve("tutorial.bounded_real", system, backend="clarabel")
    assert result.verdict == "certified"
    reference = hinf_norm(A, B, C, np.zeros((q, m)))
    assert result.objective == pytest.approx(reference, rel=1e-4)
    assert result.objective >= reference * (1 - 1e-6)  # every certified gamma is an upper bound
