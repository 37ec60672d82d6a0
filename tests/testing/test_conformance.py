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


def test_every_exclusion_names_a_known_backend_and_case_with_a_reason():
    from lmic.backends.registry import backend_classes

    known = set(backend_classes()) | set(LABELS)
    for (label, case), reason in EXCLUSIONS.items():
        assert label in known or label.split(":")[0] in known, f"exclusion of unknown backend {label!r}"
        assert case in CASES, f"exclusion of unknown case {case!r}"
        assert isinstance(reason, str) and len(reason) > 10, f"({label}, {case}): write the reason"


def test_an_exclusion_excuses_the_case_without_running_it(monkeypatch):
    class NeverRuns:
        name = label = "neverruns"

        def supports(self, *args, **kwargs):
            raise AssertionError("an excluded case must not be looked at")

        def solve(self, *args, **kwargs):
            raise AssertionError("an excluded case must not be solved")

    reason = "the solver cannot take this case (written reason)"
    monkeypatch.setitem(EXCLUSIONS, ("neverruns", "max_sense"), reason)
    result = run_case(NeverRuns(), CASES["max_sense"])  # type: ignore[arg-type]
    assert (result.excluded, result.passed, result.case, result.backend) == (reason, True, "max_sense", "neverruns")
    with pytest.raises(AssertionError, match="must not be looked at"):
        run_case(NeverRuns(), CASES["lyapunov_stable"])  # type: ignore[arg-type]


def test_hinf_norm_matches_frequency_sweep():
    A = np.array([[-0.2, 1.0], [-1.0, -0.2]])
    B = np.array([[0.0], [1.0]])
    C = np.array([[1.0, 0.0]])
    w = np.linspace(0.0, 3.0, 30001)
    sweep = max(abs((C @ np.linalg.solve(1j * f * np.eye(2) - A, B))[0, 0]) for f in w)
    assert abs(hinf_norm(A, B, C) - sweep) < 1e-4 * sweep
