"""Fixtures of the certifier tests (the builders live in ``certify_helpers``)."""

from __future__ import annotations

import numpy as np
import pytest
from certify_helpers import lyapunov


@pytest.fixture
def stable_A() -> np.ndarray:
    return np.array([[-1.0, 2.0, -1.0], [-4.0, -2.0, 0.0], [1.0, 1.0, -2.0]])


@pytest.fixture
def lyapunov_point(stable_A):
    """The Lyapunov problem of ``stable_A`` and a strictly feasible x (P solves A'P + PA = -I)."""
    from scipy.linalg import solve_continuous_lyapunov

    prob = lyapunov(stable_A)
    P = solve_continuous_lyapunov(stable_A.T, -np.eye(3))
    return prob, prob.pack({"P": P})
