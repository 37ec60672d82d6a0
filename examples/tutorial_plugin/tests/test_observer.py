"""The tutorial observer: a synthesised gain, and its generated audit variant (``fixed_L: 1``).

The theorem object is solved directly (the notebook route), so the test also runs where an
older install of the plugin does not list it yet. Gains are checked independently: the
spectral radius of ``A - L C`` by numpy, a pole-placement gain from scipy.
"""

from __future__ import annotations

import numpy as np
import scipy.signal
from lmic_tutorial.observer import observer

import lmic
from lmic.commands.check import check_theorem

A = np.array([[1.0, 0.1, 0.0], [0.0, 1.0, 0.1], [-0.2, -0.3, 0.9]])
C = np.array([[1.0, 0.0, 0.0]])


def test_the_template_passes_lmic_check():
    report = check_theorem(observer)
    assert report.findings == [] and report.warnings == []


def test_synthesised_gain_is_certified_and_stabilises():
    r = lmic.solve(observer, {"data": {"A": A, "C": C}})
    assert r.verdict == "certified"
    L = r.gains["L"]
    assert L.shape == (3, 1)
    assert np.abs(np.linalg.eigvals(A - L @ C)).max() < 1


def test_audit_variant_certifies_a_given_gain_and_refuses_a_bad_one():
    # a gain from pole placement (scipy), not from lmic: the dual problem places A^T - C^T L^T
    poles = [0.5, 0.4, 0.3]
    L = scipy.signal.place_poles(A.T, C.T, poles).gain_matrix.T
    assert np.allclose(np.sort(np.linalg.eigvals(A - L @ C).real), np.sort(poles))
    good = lmic.solve(observer, {"data": {"A": A, "C": C, "L": L}}, {"fixed_L": 1})
    assert good.verdict == "certified"
    assert [v.name for v in good.problem.variables] == ["P"]  # R was eliminated: R = L^T P
    # a gain placing one pole at 1.5: A - L C is not Schur, so no P can satisfy the LMI
    bad_L = scipy.signal.place_poles(A.T, C.T, [1.5, 0.4, 0.3]).gain_matrix.T
    assert np.abs(np.linalg.eigvals(A - bad_L @ C)).max() > 1.4
    bad = lmic.solve(observer, {"data": {"A": A, "C": C, "L": bad_L}}, {"fixed_L": 1})
    assert bad.verdict != "certified"
