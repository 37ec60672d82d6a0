"""The LTI integrator of the simulator against independent references (solve_ivp, closed forms)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from lmic.simulate.lti import TimeSignal, constant_signal, expression_signal, propagate
from lmic.simulate.parser import parse_vector


def _random_stable(rng: np.random.Generator, n: int) -> np.ndarray:
    A = rng.standard_normal((n, n))
    return A - (np.max(np.real(np.linalg.eigvals(A))) + 0.5) * np.eye(n)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_matches_solve_ivp_at_tight_tolerances_on_a_random_stable_system_with_a_sinusoid(seed):
    rng = np.random.default_rng(seed)
    n, q = 4, 2
    A, B = _random_stable(rng, n), rng.standard_normal((n, q))
    s0 = rng.standard_normal(n)
    om = np.array([3.0, 40.0])
    ph = rng.uniform(0, np.pi, q)
    grid = np.linspace(0.0, 5.0, 251)
    sig = TimeSignal(q, lambda ts: np.sin(np.outer(ts, om) + ph))
    S = propagate(A, B, s0, grid, sig)
    ref = solve_ivp(lambda t, s: A @ s + B @ np.sin(om * t + ph), (0.0, 5.0), s0, t_eval=grid,
                    method="DOP853", rtol=1e-12, atol=1e-13)  # fmt: skip
    np.testing.assert_allclose(S, ref.y.T, atol=1e-9 * max(1.0, float(np.abs(ref.y).max())))


def test_constant_input_is_the_closed_form():
    A = np.array([[-1.0, 2.0], [0.0, -3.0]])
    B = np.array([[1.0], [1.0]])
    grid = np.linspace(0.0, 2.0, 3)  # two steps only: the short-grid path
    S = propagate(A, B, np.array([1.0, -1.0]), grid, constant_signal(np.ones(1)))
    from scipy.linalg import expm

    xs = -np.linalg.solve(A, B[:, 0])  # equilibrium
    for k, t in enumerate(grid):
        np.testing.assert_allclose(S[k], xs + expm(A * t) @ (np.array([1.0, -1.0]) - xs), atol=1e-12)


def test_parsed_expressions_are_evaluated_on_the_grid():
    sig = expression_signal(parse_vector(["sin(5*t)", "0.5"], {"t"}, "w"), 2)
    ts = np.linspace(0, 1, 7)
    np.testing.assert_allclose(sig.on(ts), np.c_[np.sin(5 * ts), 0.5 * np.ones(7)])
    np.testing.assert_allclose(sig(0.3), [np.sin(1.5), 0.5])
