"""Template features: requirements, element-wise signs, traces of expressions, integer domains,
absent optional data, constants that reject data."""

from __future__ import annotations

import numpy as np
import pytest
import sympy

from lmic.compile import analyse, bind
from lmic.errors import DataError, TemplateError
from lmic.template import block, theorem
from lmic.template.numeric import lambda_min


@theorem(id="test.features", title="features", citation="tests")
def features(t):
    n, m = t.dims("n m")
    A = t.data("A", n, n)
    W = t.data("W", n, n)
    t.data("B", n, m, default=0.0, doc="optional; its column count m is fixed by nothing else")
    t.param("k", default=2, domain="natural")

    def inverse_of_w(v):
        if abs(np.linalg.det(v["W"])) < 1e-12:
            raise DataError("W must be invertible")
        return np.linalg.inv(v["W"])

    t.const("Winv", inverse_of_w, shape=(n, n))
    P = t.symmetric("P", n)
    G = t.full("G", n, n, sign="positive")
    D = t.diagonal("D", n, sign="nonpositive")
    t.require("A + A^T < 0", lambda v: lambda_min(-v["A"] - v["A"].T) > 0, "the plant must be dissipative")
    t.lmi("P", block(P) > 0)
    t.minimize(sympy.Trace(W.T * G) + 2 * sympy.Trace(A * P * A.T) + sympy.Trace(W) - sympy.Trace(D))


PLAN = analyse(features)
A = [[-1.0, 0.5], [0.0, -2.0]]
W = [[1.0, 2.0], [3.0, 4.0]]


def test_trace_of_matrix_expressions_is_a_linear_objective():
    prob = bind(PLAN, {"data": {"A": A, "W": W}})
    x = np.random.default_rng(0).standard_normal(prob.n)
    v = prob.unpack(x)
    a, w = np.array(A), np.array(W)
    want = np.trace(w.T @ v["G"]) + 2 * np.trace(a @ v["P"] @ a.T) + np.trace(w) - np.trace(v["D"])
    assert prob.objective.value(x) == pytest.approx(want, rel=1e-12)


def test_elementwise_signs_of_matrix_variables_are_linear_rows():
    prob = bind(PLAN, {"data": {"A": A, "W": W}})
    names = prob.linear.names
    assert [n for n in names if n.startswith("G")] == [f"G[{k}] > 0" for k in range(4)]
    assert [n for n in names if n.startswith("D")] == [f"D[{k}] <= 0" for k in range(2)]
    x = np.zeros(prob.n)
    G = prob.variable("G")
    x[G.slice] = -1.0
    res = prob.linear.residuals(x)
    assert np.all(res[[i for i, n in enumerate(names) if n.startswith("G")]] == -1.0)


def test_absent_optional_data_binds_its_free_dimension_to_zero():
    prob = bind(PLAN, {"data": {"A": A, "W": W}})
    assert prob.meta["dims"] == {"n": 2, "m": 0}
    assert prob.data["B"].shape == (2, 0)


def test_integer_domains_are_checked():
    with pytest.raises(DataError, match=r"parameter k = 2.5 is outside its domain Naturals"):
        bind(PLAN, {"data": {"A": A, "W": W}, "params": {"k": 2.5}})
    with pytest.raises(DataError, match=r"parameter k = 0 is outside"):
        bind(PLAN, {"data": {"A": A, "W": W}, "params": {"k": 0}})
    assert bind(PLAN, {"data": {"A": A, "W": W}, "params": {"k": 3}}).meta["params"]["k"] == 3.0


def test_requirements_and_constants_reject_data_naming_theorem_and_file():
    with pytest.raises(DataError, match=r"theorem test.features, <system>: requirement 'A \+ A\^T < 0' fails"):
        bind(PLAN, {"data": {"A": [[1.0, 0.0], [0.0, -1.0]], "W": W}})
    with pytest.raises(DataError, match=r"theorem test.features, <system>: W must be invertible"):
        bind(PLAN, {"data": {"A": A, "W": [[1.0, 2.0], [2.0, 4.0]]}})


def test_trace_of_a_product_of_variables_is_rejected():
    @theorem(id="test.badtrace", title="t", citation="c")
    def bad(t):
        (n,) = t.dims("n")
        P = t.symmetric("P", n)
        Q = t.symmetric("Q", n)
        t.minimize(sympy.Trace(P * Q))

    with pytest.raises(TemplateError, match="product of decision variables P and Q"):
        analyse(bad)


def test_entries_of_a_variable_in_an_objective():
    @theorem(id="test.entries", title="t", citation="c")
    def entries(t):
        (n,) = t.dims("n")
        t.data("A", n, n)
        P = t.symmetric("P", n)
        R = t.full("R", n, n)
        t.minimize(P[0, 1] + 3 * R[1, 0] + sympy.Trace(P))

    prob = bind(analyse(entries), {"data": {"A": A}})
    x = np.random.default_rng(1).standard_normal(prob.n)
    v = prob.unpack(x)
    want = v["P"][0, 1] + 3 * v["R"][1, 0] + np.trace(v["P"])
    assert prob.objective.value(x) == pytest.approx(want, rel=1e-12)


def test_a_sign_typo_names_the_theorem_and_the_signs_there_are():
    from lmic.errors import TemplateError

    @theorem(id="test.sign_typo", title="t", citation="c")
    def typo(t):
        t.scalar("g", sign="postive")

    with pytest.raises(TemplateError) as info:
        typo.template({})
    assert str(info.value).startswith("theorem test.sign_typo: unknown sign 'postive' for variable 'g' (one of: free,")


def test_trace_from_lmic_template_is_sympys_trace_and_a_linear_objective():
    """``lmic.template.trace`` (what the docs tell a plugin author to use) compiles to the same
    objective as ``sympy.Trace``: ``trace(C P C')`` checked against numpy at a random point."""
    from lmic.template import trace

    @theorem(id="test.trace", title="trace", citation="tests")
    def traced(t):
        n, q = t.dims("n q")
        C = t.data("C", q, n)
        P = t.symmetric("P", n)
        t.lmi("P", P > 0)
        t.minimize(trace(C * P * C.T) + 3 * trace(P))

    C = np.arange(6.0).reshape(2, 3) - 2.5
    prob = bind(analyse(traced), {"data": {"C": C.tolist()}})
    x = np.random.default_rng(1).standard_normal(prob.n)
    P = prob.unpack(x)["P"]
    assert prob.objective.value(x) == pytest.approx(np.trace(C @ P @ C.T) + 3 * np.trace(P), rel=1e-12)
