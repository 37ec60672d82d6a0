"""Every available backend (and every CVXPY sub-solver) runs the conformance suite."""

from __future__ import annotations

import numpy as np
import pytest

from lmic.backends.registry import available_backend_names, get_backend
from lmic.testing.conformance import CASES, EXCLUSIONS, hinf_norm, run_case

LABELS = available_backend_names(expand_variants=True)


@pytest.mark.parametrize("case", list(CASES))
@pytest.mark.parametrize("label", LABELS)
def test_conformance(label, case):
    result = run_case(get_backend(label), CASES[case])
    if result.excluded:
        pytest.skip(f"excluded: {result.excluded}")
    if result.skipped:
        pytest.skip(f"not supported: {result.skipped}")
    assert result.passed, f"{label} / {case}: {result.message}"


def test_every_exclusion_has_a_reason():
    assert all(isinstance(r, str) and len(r) > 10 for r in EXCLUSIONS.values())


def test_hinf_norm_matches_frequency_sweep():
    A = np.array([[-0.2, 1.0], [-1.0, -0.2]])
    B = np.array([[0.0], [1.0]])
    C = np.array([[1.0, 0.0]])
    w = np.linspace(0.0, 3.0, 30001)
    sweep = max(abs((C @ np.linalg.solve(1j * f * np.eye(2) - A, B))[0, 0]) for f in w)
    assert abs(hinf_norm(A, B, C) - sweep) < 1e-4 * sweep
