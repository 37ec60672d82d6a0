"""Differential property test: the compiled IR at a random x equals the block matrix
evaluated directly with numpy, for every kind of term the templates support."""

from __future__ import annotations

import numpy as np
import sympy
from hypothesis import given, settings
from hypothesis import strategies as st

from lmic.compile import analyse, bind
from lmic.template import STAR, I, block, theorem
from lmic.template.numeric import lambda_max, pinv


@theorem(id="test.kitchen_sink", title="every term kind", citation="tests")
def kitchen_sink(t):
    n, p = t.dims("n p")
    A = t.data("A", n, n)
    C = t.data("C", p, n)
    B = t.data("B", n, p)
    Q = t.data("Q", n, n, positive_definite=True)
    a = t.param("a")
    b = t.param("b", default=0.5)
    c = t.const("c", lambda v: lambda_max(v["Q"]))
    M = t.const("M", lambda v: pinv(v["C"]), shape=(n, p))
    P = t.symmetric("P", n)
    R = t.full("R", p, n)
    K = t.full("K", n, p)
    D = t.diagonal("D", n)
    S = t.blockdiag("S", (n, p))
    w = t.scalar("w", sign="positive")
    X = (A * P).T - a * C.T * R  # transpose of a product, scalar times a product
    t.lmi(
        "sink",
        block(
            [
                [A.T * P + P * A - a * C.T * R - a * R.T * C + b * w * I(n) + D, P * B + A.T * K - c * K + M],
                [STAR, -w * I(p) + B.T * P * B + sympy.exp(-2 * b) * I(p)],
            ]
        )
        < 0,
    )
    t.lmi("explicit lower", block([[Q * P + P * Q, X.T * 0 + A.T * K], [K.T * A, -w * I(p)]]) <= 0)
    t.lmi("blockdiag", block(S + a * I(n + p)) > 0)
    t.lmi("inverse data", block([[Q.inv() * P * Q.inv(), 0], [STAR, -w]]) >= 0)


PLAN = analyse(kitchen_sink)


def _expected(v, data, a, b):
    A, C, B, Q = data["A"], data["C"], data["B"], data["Q"]
    n, p = C.shape[1], C.shape[0]
    P, R, K, D, S, w = v["P"], v["R"], v["K"], v["D"], v["S"], v["w"]
    c = np.linalg.eigvalsh(Q)[-1]
    M = np.linalg.pinv(C)
    top = A.T @ P + P @ A - a * C.T @ R - a * R.T @ C + b * w * np.eye(n) + D
    off = P @ B + A.T @ K - c * K + M
    bot = -w * np.eye(p) + B.T @ P @ B + np.exp(-2 * b) * np.eye(p)
    sink = np.block([[top, off], [off.T, bot]])
    lower = np.block([[Q @ P + P @ Q, A.T @ K], [K.T @ A, -w * np.eye(p)]])
    Qi = np.linalg.inv(Q)
    inv = np.block([[Qi @ P @ Qi, np.zeros((n, 1))], [np.zeros((1, n)), -w * np.eye(1)]])
    return {"sink": -sink, "explicit lower": -lower, "blockdiag": S + a * np.eye(n + p), "inverse data": inv}


@settings(max_examples=40, deadline=None)
@given(
    n=st.integers(1, 4),
    p=st.integers(1, 3),
    seed=st.integers(0, 2**31 - 1),
    a=st.floats(-3, 3, allow_nan=False),
    b=st.floats(0, 2, allow_nan=False),
)
def test_compiled_lmis_equal_direct_numpy_evaluation(n, p, seed, a, b):
    rng = np.random.default_rng(seed)
    G = rng.standard_normal((n, n))
    data = {
        "A": rng.standard_normal((n, n)),
        "C": rng.standard_normal((p, n)),
        "B": rng.standard_normal((n, p)),
        "Q": G @ G.T + np.eye(n),
    }
    prob = bind(PLAN, {"data": {k: v.tolist() for k, v in data.items()}, "params": {"a": a, "b": b}})
    x = rng.standard_normal(prob.n)
    values = prob.unpack(x)
    expected = _expected(values, data, a, b)
    for lmi in prob.lmis:
        got = lmi.matrix(x)
        want = expected[lmi.name]
        assert got.shape == want.shape, lmi.name
        np.testing.assert_allclose(got, want, rtol=1e-10, atol=1e-10, err_msg=lmi.name)
    assert [lmi.strict for lmi in prob.lmis] == [True, False, True, False]
    # the scalar sign is a strict linear row w > 0
    assert prob.linear.names == ["w > 0"]
    assert prob.linear.residuals(x)[0] == values["w"]


def test_rebinding_reuses_the_plan_and_changes_only_numbers():
    data = {"A": [[1.0]], "C": [[1.0]], "B": [[1.0]], "Q": [[2.0]]}
    p1 = bind(PLAN, {"data": data, "params": {"a": 1.0}})
    p2 = bind(PLAN, {"data": data, "params": {"a": 2.0}})
    assert p1.n == p2.n
    x = np.ones(p1.n)
    assert not np.allclose(p1.lmis[0].matrix(x), p2.lmis[0].matrix(x))
