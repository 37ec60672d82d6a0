"""The fixed-margin pass (lmic.reductions.strict_fixed) against dense evaluations: the shifted
LMI is ``F(x) - delta I``, strict rows lose ``delta``, and the normalisation rows are
``d - (trace F(x) - trace F0)`` per strict LMI and ``1 - a . x`` per strict row."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
from lmic.reductions.strict_fixed import _fixed_margin, _shift


def _random_lmi(d: int, n: int, seed: int, constant: bool) -> LMI:
    rng = np.random.default_rng(seed)
    C = sp.random(d * (d + 1) // 2, n + 1, density=0.6, random_state=seed, format="csc")
    C.data = rng.standard_normal(C.nnz)
    if not constant:
        C = sp.hstack([sp.csc_matrix((C.shape[0], 1)), C[:, 1:]], format="csc")
    return LMI("F", d, C, strict=True)


def test_shift_subtracts_the_margin_from_the_identity():
    rng = np.random.default_rng(0)
    for seed, constant in [(1, True), (2, False), (3, True)]:
        lmi = _random_lmi(5, 4, seed, constant)
        shifted = _shift(lmi, 0.25)
        assert not shifted.strict and shifted.coeffs.has_sorted_indices
        for _ in range(3):
            x = rng.standard_normal(4)
            assert np.allclose(shifted.matrix(x), lmi.matrix(x) - 0.25 * np.eye(5), atol=1e-14)
        # the variable columns are untouched
        assert np.array_equal(shifted.coeffs[:, 1:].toarray(), lmi.coeffs[:, 1:].toarray())


def test_fixed_margin_rows_and_normalisation():
    rng = np.random.default_rng(4)
    n = 3
    lmis = [_random_lmi(3, n, 5, False), _random_lmi(2, n, 6, False)]
    A = sp.csr_matrix(np.array([[0.0, 1.0, -2.0, 0.5], [0.0, 0.0, 1.0, 1.0], [0.0, 3.0, 0.0, -1.0]]))
    linear = LinearConstraints(A, ["ge", "eq", "ge"], [True, False, False], ["s", "e", "g"])
    prob = Problem([Variable("x", "full", (n, 1))], lmis, linear, Objective("feasibility", np.zeros(n + 1)))
    delta = 1e-2
    red = _fixed_margin(prob, delta, normalise=True)
    x = rng.standard_normal(n)
    xx = np.concatenate([[1.0], x])
    res = red.linear.A @ xx
    orig = A @ xx
    assert np.allclose(res[:3], orig - np.array([delta, 0.0, 0.0]))
    # one row per strict LMI (d - trace of the variable part), then one per strict row (1 - a.x)
    for k, lmi in enumerate(lmis):
        var_trace = np.trace(lmi.matrix(x)) - np.trace(lmi.matrix(np.zeros(n)))
        assert np.isclose(res[3 + k], lmi.dim - var_trace)
    assert np.isclose(res[5], 1.0 - (orig[0] - A[0, 0]))
    assert red.linear.kinds == ["ge", "eq", "ge", "ge", "ge", "ge"] and not any(red.linear.strict)
    assert red.linear.names[3:] == [f"scale normalisation {k}" for k in range(3)]
    for lmi, new in zip(lmis, red.lmis, strict=True):
        assert np.allclose(new.matrix(x), lmi.matrix(x) - delta * np.eye(lmi.dim))
