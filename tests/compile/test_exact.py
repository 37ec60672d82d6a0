"""lmic.compile.exact: the IR's coefficients in exact rational arithmetic, against a hand
computation in Fractions (products of data factors, a rational parameter coefficient, sums of
duplicate entries), the declines (an irrational coefficient, a computed factor), and the
rigour of the perturbation bound |G_exact(x) - G(x)| against the difference computed exactly."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest
import sympy
from certify_helpers import inline_brl

from lmic.compile.bind import bind
from lmic.compile.exact import ExactUnavailable, exact_bind, from_ir
from lmic.compile.plan import analyse
from lmic.ir.svec import tril_rows_cols
from lmic.template import block, theorem


@theorem(id="test.exact_products", title="t", citation="c")
def _products(t):
    (n,) = t.dims("n")
    A = t.data("A", n, n)
    B = t.data("B", n, n)
    alpha = t.param("alpha", domain="positive")
    P = t.symmetric("P", n)
    t.lmi("main", block(A.T * P * B + B.T * P * A + alpha / 3 * P) < 0)


@theorem(id="test.exact_sqrt", title="t", citation="c")
def _irrational(t):
    (n,) = t.dims("n")
    A = t.data("A", n, n)
    alpha = t.param("alpha", domain="positive")
    P = t.symmetric("P", n)
    t.lmi("main", block(A.T * P + P * A + sympy.sqrt(alpha) * P) < 0)


@theorem(id="test.exact_inverse", title="t", citation="c")
def _computed(t):
    (n,) = t.dims("n")
    A = t.data("A", n, n)
    P = t.symmetric("P", n)
    t.lmi("main", block(A.inv().T * P + P * A.inv()) < 0)


def _fmat(M) -> list[list[Fraction]]:
    return [[Fraction(float(v)) for v in row] for row in np.asarray(M)]


def _mul(X, Y):
    return [
        [sum((X[i][k] * Y[k][j] for k in range(len(Y))), Fraction(0)) for j in range(len(Y[0]))] for i in range(len(X))
    ]


def _t(X):
    return [list(r) for r in zip(*X, strict=True)]


def test_exact_coefficients_equal_a_hand_computation_in_fractions():
    rng = np.random.default_rng(5)
    A, B = rng.standard_normal((3, 3)), rng.standard_normal((3, 3))
    alpha = 0.7
    system = {"data": {"A": A.tolist(), "B": B.tolist()}, "params": {"alpha": alpha}}
    plan = analyse(_products)
    ex = exact_bind(plan, system)
    prob = bind(plan, system)
    (P,) = prob.variables
    basis = P.basis().toarray()  # vec(P) (column-major) = basis @ x_P
    Aq, Bq, aq = _fmat(A), _fmat(B), Fraction(alpha) / 3
    ti, tj = tril_rows_cols(3)
    lmi = ex.lmis[0]
    differ = 0
    for k in range(P.size):
        E = [[Fraction(int(basis[i + 3 * j, k])) for j in range(3)] for i in range(3)]
        M = [
            [a + b + aq * e for a, b, e in zip(r1, r2, r3, strict=True)]
            for r1, r2, r3 in zip(_mul(_mul(_t(Aq), E), Bq), _mul(_mul(_t(Bq), E), Aq), E, strict=True)
        ]
        for t in range(ti.size):
            want = -M[ti[t]][tj[t]]  # "< 0" is stored as -(...) >= 0
            assert lmi.value(t, 1 + k) == want
            differ += Fraction(float(prob.lmis[0].coeffs[t, 1 + k])) != want
    assert differ > 0  # the float IR rounds some of them: the exact values are not its floats
    # rounded to nearest, the exact coefficients are the IR's up to its rounding
    assert abs(lmi.rounded() - prob.lmis[0].coeffs).max() <= 1e-14 * abs(prob.lmis[0].coeffs).max()


def test_irrational_coefficient_and_computed_factor_decline():
    A = [[-1.0, 0.5], [0.0, -2.0]]
    with pytest.raises(ExactUnavailable, match="sqrt|exact rational"):
        exact_bind(analyse(_irrational), {"data": {"A": A}, "params": {"alpha": 2.0}})
    with pytest.raises(ExactUnavailable, match="computed"):
        exact_bind(analyse(_computed), {"data": {"A": A}})


def test_perturbation_bound_covers_the_exact_difference():
    rng = np.random.default_rng(2)
    A = rng.standard_normal((4, 4)) - 3 * np.eye(4)
    B = rng.standard_normal((4, 4))
    system = {"data": {"A": A.tolist(), "B": B.tolist()}, "params": {"alpha": 0.1}}
    plan = analyse(_products)
    ex, prob = exact_bind(plan, system), bind(plan, system)
    x = rng.standard_normal(prob.n) * 10.0
    lmi_b, lin_b, obj_b = ex.perturbation(prob, x)
    xq = [Fraction(1)] + [Fraction(float(v)) for v in x]
    C = prob.lmis[0].coeffs.tocsc()
    ti, tj = tril_rows_cols(prob.lmis[0].dim)
    diff = [Fraction(0)] * ti.size
    for k in range(1 + prob.n):
        for t in range(ti.size):
            diff[t] += (ex.lmis[0].value(t, k) - Fraction(float(C[t, k]))) * xq[k]
    fro2 = sum((d * d * (1 if ti[t] == tj[t] else 2) for t, d in enumerate(diff)), Fraction(0))
    assert fro2 > 0
    assert Fraction(lmi_b[0]) ** 2 >= fro2  # rigorous
    assert lmi_b[0] <= 1e-12 * float(np.abs(x).max() + 1)  # and of the order of the rounding
    assert obj_b == 0.0 and lin_b == []
    # the IR's own floats are exact: no difference at all
    assert from_ir(prob).perturbation(prob, x)[0][0] <= 1e-300


def test_exact_of_recompiles_a_theorem_and_declines_an_unknown_one():
    """A compiled problem's counterpart is its theorem compiled exactly (cached); an IR naming a
    theorem that cannot be compiled declines with the reason (never a crash); an IR with no
    theorem is its own exact data."""
    from lmic.api import load_target
    from lmic.compile.exact import cached_exact, exact_of

    A = [[-0.3, 0.1], [0.2, -0.7]]
    prob = load_target("tutorial.bounded_real", {"data": {"A": A, "B": [[1.0], [0.5]], "C": [[1.0, 0.1]]}})[0]
    assert cached_exact(prob) is None
    ex = exact_of(prob)
    assert ex.about == "theorem" and cached_exact(prob) is ex and exact_of(prob) is ex
    # the coefficient of P_01 at entry (0, 1) of -(A^T P + P A): -(A_00 + A_11), exactly
    a = Fraction(-0.3) + Fraction(-0.7)
    P01 = 1 + prob.variables[0].offset + 1
    assert ex.lmis[1].value(1, P01) == -a and Fraction(float(prob.lmis[1].coeffs[1, P01])) != -a
    bad = load_target("tutorial.bounded_real", {"data": {"A": A, "B": [[1.0], [0.5]], "C": [[1.0, 0.1]]}})[0]
    bad.meta["theorem"] = "no.such_theorem"
    with pytest.raises(ExactUnavailable, match="no.such_theorem"):
        exact_of(bad)
    with pytest.raises(ExactUnavailable):  # the failure is cached too
        exact_of(bad)
    bare = load_target("tutorial.bounded_real", {"data": {"A": A, "B": [[1.0], [0.5]], "C": [[1.0, 0.1]]}})[0]
    bare.meta.pop("theorem")
    assert exact_of(bare).about == "ir"


def test_exact_of_an_unregistered_theorem_uses_the_plan_it_was_bound_from():
    """A theorem passed as an object (a notebook's, a newcomer's) is in no registry: its id
    alone cannot recompile it. The problem keeps the plan it was bound from, and its exact
    counterpart is that plan compiled exactly (the sum A_00 + A_11 of P_01's coefficient, in
    Fractions, where the float IR rounded it). A copy of the IR without the plan declines by
    name, as before."""
    import dataclasses

    from lmic.compile.exact import exact_of
    from lmic.registry import get_theorem

    with pytest.raises(Exception, match="test.inline_bounded_real"):
        get_theorem("test.inline_bounded_real")  # not registered: nothing finds it by id
    A = [[-0.3, 0.1], [0.2, -0.7]]
    system = {"data": {"A": A, "B": [[1.0], [0.5]], "C": [[1.0, 0.1]]}}
    prob = bind(analyse(inline_brl), system)
    ex = exact_of(prob)
    assert ex.about == "theorem"
    P01 = 1 + prob.variables[0].offset + 1
    brl = [lmi.name for lmi in prob.lmis].index("brl")
    a = Fraction(-0.3) + Fraction(-0.7)
    assert ex.lmis[brl].value(1, P01) == -a and Fraction(float(prob.lmis[brl].coeffs[1, P01])) != -a
    copy = dataclasses.replace(prob)
    with pytest.raises(ExactUnavailable, match="test.inline_bounded_real"):
        exact_of(copy)


def test_a_derived_problem_with_another_objective_or_row_has_no_exact_counterpart():
    """A problem derived from a compiled one (a cut, a lifted or backed-off problem) keeps the
    theorem's metadata; if its objective or a row changed, the theorem compiled exactly is another
    problem, and a bound proved on it would not be this one's: it declines by name."""
    import dataclasses

    import scipy.sparse as sp

    from lmic.api import load_target
    from lmic.compile.exact import exact_of
    from lmic.ir.problem import LinearConstraints, Objective

    system = {"data": {"A": [[-0.3, 0.1], [0.2, -0.7]], "B": [[1.0], [0.5]], "C": [[1.0, 0.1]]}}
    prob = load_target("tutorial.bounded_real", system)[0]
    assert exact_of(prob).about == "theorem"
    c = np.asarray(prob.objective.c, dtype=float).copy()
    c[-1] *= 2.0
    other = dataclasses.replace(prob, objective=Objective(prob.objective.sense, c))
    with pytest.raises(ExactUnavailable, match="objective differs"):
        exact_of(other)
    lin = prob.linear
    A = sp.csr_matrix(lin.A).toarray()
    assert lin.names == ["gamma > 0"]
    A[0, 0] += 1.0  # gamma > 0 becomes gamma + 1 > 0
    moved = dataclasses.replace(prob, linear=LinearConstraints(sp.csr_matrix(A), lin.kinds, lin.strict, lin.names))
    with pytest.raises(ExactUnavailable, match="row 'gamma > 0'"):
        exact_of(moved)
