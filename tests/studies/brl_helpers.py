"""The bounded-real lemma with ``gamma`` a parameter, random stable plants, and two independent
references for its infimum (the H-infinity norm): python-control's norm and the peak gain."""

from __future__ import annotations

import numpy as np
import pytest

from lmic.template import STAR, I, block, theorem


@theorem(
    id="test.brl_gamma_param",
    title="Bounded-real lemma, gamma a parameter",
    citation="Boyd et al. (1994), sec. 6.3.2",
    kind="analysis",
    objective="feasibility",
    system_class="continuous time, linear, stable",
)
def brl(t):
    n, m, q = t.dims("n m q")
    A, B, C = t.data("A", n, n), t.data("B", n, m), t.data("C", q, n)
    P = t.symmetric("P", n, pd=True)
    g = t.param("gamma", default=1.0, domain="positive", doc="H-infinity bound")
    t.lmi("brl", block([[A.T * P + P * A, P * B, C.T], [STAR, -g * I(m), 0], [STAR, STAR, -g * I(q)]]) < 0)


def plant(n: int, seed: int):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    A -= (max(np.linalg.eigvals(A).real) + 0.5) * np.eye(n)
    B, C = rng.standard_normal((n, 2)), rng.standard_normal((2, n))
    return A, B, C, {"lmic": 1, "data": {"A": A.tolist(), "B": B.tolist(), "C": C.tolist()}}


def hinf(A, B, C) -> float:
    control = pytest.importorskip("control")
    return float(control.norm(control.ss(A, B, C, np.zeros((C.shape[0], B.shape[1]))), p="inf", tol=1e-12))


def peak_gain(A, B, C) -> float:
    """The H-infinity norm from below, to rounding: the largest singular value of ``G(jw)`` at
    its peak frequencies. python-control's norm is only good to about 1e-12 relative (1.3e-12
    below the peak at n = 10, seed 3), and the exact face route's lower end is tighter than that.
    The peaks are where the Hamiltonian just below that norm has imaginary eigenvalues; a
    bounded scalar search refines each."""
    from scipy.optimize import minimize_scalar

    n = A.shape[0]

    def gain(w: float) -> float:
        return float(np.linalg.svd(C @ np.linalg.solve(1j * w * np.eye(n) - A, B), compute_uv=False)[0])

    g = hinf(A, B, C) * (1 - 1e-6)
    ev = np.linalg.eigvals(np.block([[A, B @ B.T / g], [-C.T @ C / g, -A.T]]))
    peaks = {0.0} | {abs(e.imag) for e in ev if abs(e.real) < 1e-8 * max(1.0, abs(e))}
    best = 0.0
    for w in peaks:
        found = minimize_scalar(
            lambda x: -gain(x), bounds=(0.99 * w, 1.01 * w + 1e-9), method="bounded", options={"xatol": 1e-14}
        )
        best = max(best, gain(w), -float(found.fun))
    return best
