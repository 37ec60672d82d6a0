"""The strict-inequality reduction shared by every backend."""

from __future__ import annotations

import numpy as np
import pytest

from lmic.backends import strict
from lmic.backends.base import SolveOptions
from lmic.backends.registry import available_backend_names, get_backend
from lmic.solution import Solution
from lmic.testing.conformance import CASES, lyapunov_problem


def test_scale_free_feasibility_gets_margin_and_trace_normalisation():
    prob = lyapunov_problem(-np.eye(2))
    reduced, inv = strict.reduce(prob, SolveOptions())
    assert inv.strategy == "max-margin" and inv.scale_free
    assert reduced.n == prob.n + 1 and reduced.objective.sense == "max"
    assert all(not lmi.strict for lmi in reduced.lmis)
    # t <= 1 and one trace row per strict LMI
    assert len(reduced.linear) == 1 + 2
    assert reduced.linear.names[0] == "margin t <= 1"


def test_affine_problem_is_not_scale_free():
    prob = CASES["strict_affine"].build()
    reduced, inv = strict.reduce(prob, SolveOptions())
    assert not inv.scale_free
    # the strict row x + y < 3 carries -t
    assert reduced.linear.A[0, -1] == -1.0


def test_optimisation_uses_fixed_margin():
    prob = CASES["bounded_real"].build()
    reduced, inv = strict.reduce(prob, SolveOptions(margin=1e-3))
    assert inv.strategy == "fixed-margin" and reduced.n == prob.n
    d = prob.lmis[1].dim
    assert np.allclose(reduced.lmis[1].matrix(np.zeros(prob.n)), -1e-3 * np.eye(d))


def test_nonpositive_margin_means_infeasible():
    prob = lyapunov_problem(np.eye(1))
    _, inv = strict.reduce(prob, SolveOptions())
    raw = Solution(
        "optimal",
        x=np.array([0.0, 1e-12]),
        duals={"lmis": [np.eye(1), np.eye(1)], "linear": np.zeros(3)},
    )
    sol = strict.invert(raw, inv, SolveOptions())
    assert sol.status == "infeasible" and sol.farkas["strict"] is True
    assert sol.x.shape == (1,) and len(sol.farkas["linear"]) == 0


@pytest.mark.parametrize("backend", available_backend_names())
def test_homogeneous_lmi_stays_bounded_on_every_backend(backend):
    """P stays O(1): the normalisation, not the solver, fixes the scale (SDPA gave P ~ 1e17)."""
    A = np.array([[-1.0, 5.0], [0.0, -2.0]])
    sol = get_backend(backend).solve(lyapunov_problem(A))
    assert sol.status == "feasible" and sol.strategy == "max-margin"
    assert np.max(np.abs(sol.x)) < 10 and sol.margin > 1e-3
