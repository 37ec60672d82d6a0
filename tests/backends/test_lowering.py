"""The lowering (lmic/backends/lowering.py): apply and invert of the s-form and the LMI form on
random problems, against a dense construction written here entry by entry (the native
vectorisations spelled out as loops, as each solver's documentation states them)."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from lmic.backends.clarabel import clarabel_unvec, clarabel_vec
from lmic.backends.lowering import (
    LMIForm,
    SForm,
    conic_data,
    full_vec_coo,
    full_vec_map,
    has_strict,
    problem_kinds,
    split_rows,
)
from lmic.backends.scs import scs_unvec, scs_vec
from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
from lmic.ir.svec import tril_vec
from lmic.testing.conformance import CASES, dense_lmi

SQRT2 = np.sqrt(2.0)


# -- the independent construction -----------------------------------------------------------------
def _storage(M: np.ndarray) -> list[float]:
    """The IR's storage: the lower triangle, column by column."""
    d = len(M)
    return [M[i, j] for j in range(d) for i in range(j, d)]


def _scs_native(M: np.ndarray) -> list[float]:
    """SCS: lower triangle column by column, off-diagonal entries times sqrt(2)."""
    d = len(M)
    return [M[i, j] * (1.0 if i == j else SQRT2) for j in range(d) for i in range(j, d)]


def _clarabel_native(M: np.ndarray) -> list[float]:
    """Clarabel: upper triangle column by column, off-diagonal entries times sqrt(2)."""
    d = len(M)
    return [M[i, j] * (1.0 if i == j else SQRT2) for j in range(d) for i in range(j + 1)]


NATIVE = {"scs": (scs_vec, _scs_native), "clarabel": (clarabel_vec, _clarabel_native)}


def _sym(rng: np.random.Generator, d: int, density: float) -> np.ndarray:
    M = rng.standard_normal((d, d)) * (rng.random((d, d)) < density)
    return M + M.T


def _random_problem(seed: int, dims: list[int], n: int, kinds: list[str], sense: str, density: float):
    """A random problem with its dense LMI matrices ``[F0, F1, ..., Fn]`` and rows ``[a0 | a]``."""
    rng = np.random.default_rng(seed)
    mats = [[_sym(rng, d, density) for _ in range(n + 1)] for d in dims]
    lmis = []
    for k, (d, Fs) in enumerate(zip(dims, mats, strict=True)):
        cols = np.array([_storage(F) for F in Fs]).T  # storage rows x (n + 1)
        lmis.append(LMI(f"F{k}", d, sp.csc_matrix(cols), strict=bool(k % 2)))
    rows = rng.standard_normal((len(kinds), n + 1)) * (rng.random((len(kinds), n + 1)) < 0.7)
    linear = LinearConstraints(
        sp.csr_matrix(rows.reshape(len(kinds), n + 1)),
        list(kinds),
        [False] * len(kinds),
        [f"r{i}" for i in range(len(kinds))],
    )
    c = rng.standard_normal(n + 1)
    problem = Problem(
        [Variable("x", "full", (n, 1))],
        lmis,
        linear,
        Objective(sense, c if sense != "feasibility" else np.zeros(n + 1)),
    )
    return problem, mats, rows


problems = st.builds(
    _random_problem,
    seed=st.integers(0, 2**32 - 1),
    dims=st.lists(st.integers(1, 6), min_size=0, max_size=3),
    n=st.integers(1, 7),
    kinds=st.lists(st.sampled_from(["eq", "ge"]), min_size=0, max_size=5),
    sense=st.sampled_from(["min", "max", "feasibility"]),
    density=st.sampled_from([0.2, 0.6, 1.0]),
)

FAST = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])


@FAST
@given(problem=problems, solver=st.sampled_from(sorted(NATIVE)), seed=st.integers(0, 1000))
def test_sform_apply_is_the_stacked_slack_and_invert_reads_back_the_multipliers(problem, solver, seed):
    p, mats, rows = problem
    vec, native = NATIVE[solver]
    rng = np.random.default_rng(seed)
    x = rng.standard_normal(p.n)
    data = SForm(vec).apply(p)
    eq = [i for i, k in enumerate(p.linear.kinds) if k == "eq"]
    ge = [i for i, k in enumerate(p.linear.kinds) if k == "ge"]
    # s = b - A x is [eq rows; ge rows; native(F_i(x)) ...]
    expected = [rows[i, 0] + rows[i, 1:] @ x for i in eq + ge]
    for Fs in mats:
        expected += native(Fs[0] + sum(xk * Fk for xk, Fk in zip(x, Fs[1:], strict=True)))
    assert data.A.shape == (len(expected), p.n)
    np.testing.assert_allclose(data.b - data.A @ x, expected, atol=1e-12)
    assert (data.n_eq, data.n_ge, data.psd) == (len(eq), len(ge), [len(Fs[0]) for Fs in mats])
    sign = -1.0 if p.objective.sense == "max" else 1.0
    if p.objective.sense == "feasibility":
        assert not data.c.any() and data.c0 == 0.0
    else:
        assert np.allclose(data.c, sign * p.objective.c[1:]) and data.c0 == sign * p.objective.c[0]
    # solvers need canonical CSC (Clarabel checks sorted row indices)
    check = data.A.copy()
    check.has_sorted_indices = False
    check.sort_indices()
    assert np.array_equal(check.indices, data.A.indices)
    # invert: a native dual vector [y_eq; y_ge; native(Z_i)] back to the IR's multipliers
    y = rng.standard_normal(len(p.linear))
    Zs = [_sym(rng, len(Fs[0]), 1.0) for Fs in mats]
    z = np.array([*y[eq], *y[ge], *[v for Z in Zs for v in native(Z)]])
    back = SForm(vec).invert(data, z, len(p.linear))
    np.testing.assert_allclose(back["linear"], y, atol=1e-14)
    assert len(back["lmis"]) == len(Zs)
    for got, Z in zip(back["lmis"], Zs, strict=True):
        np.testing.assert_allclose(got, Z, atol=1e-12)
    # the pairing is the IR's: <s, z> = y . rows(x) + sum <F_i(x), Z_i>
    Fx = [Fs[0] + sum(xk * Fk for xk, Fk in zip(x, Fs[1:], strict=True)) for Fs in mats]
    pairing = y[eq + ge] @ np.array(expected[: len(eq + ge)]) + sum(np.sum(F * Z) for F, Z in zip(Fx, Zs, strict=True))
    assert np.isclose((data.b - data.A @ x) @ z, pairing, rtol=1e-10, atol=1e-10)


@FAST
@given(problem=problems, seed=st.integers(0, 1000))
def test_lmi_form_apply_gives_the_dense_blocks_and_invert_reads_back_the_multipliers(problem, seed):
    p, mats, rows = problem
    rng = np.random.default_rng(seed)
    x = rng.standard_normal(p.n)
    data = LMIForm.apply(p)
    for F0, G, Fs in zip(data.F0, data.G, mats, strict=True):
        d = len(Fs[0])
        np.testing.assert_allclose(F0, Fs[0], atol=0)
        dense_x = sum(xk * Fk for xk, Fk in zip(x, Fs[1:], strict=True))
        np.testing.assert_allclose((G @ x).reshape(d, d, order="F"), dense_x, atol=1e-12)
    eq = [i for i, k in enumerate(p.linear.kinds) if k == "eq"]
    ge = [i for i, k in enumerate(p.linear.kinds) if k == "ge"]
    np.testing.assert_allclose(data.A_eq.toarray(), rows[eq].reshape(len(eq), p.n + 1))
    np.testing.assert_allclose(data.A_ge.toarray(), rows[ge].reshape(len(ge), p.n + 1))
    y = rng.standard_normal(len(p.linear))
    Zs = [rng.standard_normal((len(Fs[0]),) * 2) for Fs in mats]  # not symmetric: invert symmetrises
    back = LMIForm.invert(data, Zs, y[eq], y[ge])
    np.testing.assert_allclose(back["linear"], y)
    for got, Z in zip(back["lmis"], Zs, strict=True):
        np.testing.assert_allclose(got, (Z + Z.T) / 2)
    xi = np.concatenate([y[eq], y[ge], *[Z.reshape(-1, order="F") for Z in Zs]])
    stacked = LMIForm.invert_stacked(data, xi)
    np.testing.assert_allclose(stacked["linear"], y)
    for got, Z in zip(stacked["lmis"], Zs, strict=True):
        np.testing.assert_allclose(got, (Z + Z.T) / 2)


@FAST
@given(problem=problems)
def test_full_vec_coo_and_map_are_the_column_major_matrices(problem):
    p, mats, _ = problem
    for lmi, Fs in zip(p.lmis, mats, strict=True):
        d = lmi.dim
        row, col, val = full_vec_coo(lmi)
        M = sp.csc_matrix((val, (row, col)), shape=(d * d, p.n + 1)).toarray()
        for k, F in enumerate(Fs):
            np.testing.assert_allclose(M[:, k], F.reshape(-1, order="F"))
        np.testing.assert_allclose((full_vec_map(d) @ lmi.coeffs).toarray(), M)


def test_kinds_strictness_and_row_split():
    p = CASES["linear_equalities"].build()
    assert problem_kinds(p) == {"lmi", "eq"}
    assert has_strict(CASES["lyapunov_stable"].build())
    lin = LinearConstraints(sp.csr_matrix(np.ones((4, 2))), ["ge", "eq", "ge", "eq"], [False] * 4, list("abcd"))
    eq, ge = split_rows(lin)
    assert eq.tolist() == [1, 3] and ge.tolist() == [0, 2]


@pytest.mark.parametrize("vec,unvec", [(clarabel_vec, clarabel_unvec), (scs_vec, scs_unvec)])
def test_psd_vectorisations_are_isometric_and_invertible(vec, unvec):
    rng = np.random.default_rng(1)
    d = 4
    A, B = rng.standard_normal((d, d)), rng.standard_normal((d, d))
    A, B = A + A.T, B + B.T
    perm, scale = vec(d)
    va, vb = scale * tril_vec(A)[perm], scale * tril_vec(B)[perm]
    assert np.isclose(va @ vb, np.trace(A @ B))
    assert np.allclose(unvec(va, d), A)


def test_cached_vectorisations_are_read_only():
    perm, scale = clarabel_vec(3)
    with pytest.raises(ValueError):
        perm[0] = 5
    with pytest.raises(ValueError):
        scs_vec(3)[1][0] = 2.0


def test_clarabel_order_is_upper_triangle_by_columns():
    M = np.arange(9.0).reshape(3, 3)
    M = M + M.T
    perm, _ = clarabel_vec(3)
    assert np.allclose(tril_vec(M)[perm], [M[0, 0], M[0, 1], M[1, 1], M[0, 2], M[1, 2], M[2, 2]])


def test_conic_data_stacks_rows_then_lmis():
    prob = CASES["linear_equalities"].build()
    data = conic_data(prob, scs_vec)
    assert (data.n_eq, data.n_ge, data.psd) == (1, 0, [3])
    x = np.random.default_rng(0).standard_normal(prob.n)
    s = data.b - data.A @ x
    assert np.isclose(s[0], prob.linear.residuals(x)[0])
    assert np.allclose(scs_unvec(s[1:], 3), prob.lmis[0].matrix(x))


def test_max_objective_is_minimised_with_sign():
    t = Variable("t", "scalar", (1, 1))
    lmi = dense_lmi("1 - t >= 0", np.eye(1), [-np.eye(1)], False)
    prob = Problem([t], [lmi], LinearConstraints.empty(1), Objective("max", np.array([0.5, 2.0])))
    data = conic_data(prob, scs_vec)
    assert data.sign == -1.0 and np.allclose(data.c, [-2.0]) and data.c0 == -0.5
    assert isinstance(data.A, sp.csc_matrix)
