"""uncertain_dt.lemma3, thm1, cor1 (Abbaszadeh & Marquez, ACC 2008): examples, audits, random systems.

Reference values: seeds catalogue sections 2 and 6 (Clarabel reference implementation).
"""

from __future__ import annotations

import cvxpy as cp
import numpy as np
import pytest
from seeds_helpers import (
    BACKENDS,
    REF_SOLVERS,
    compare_lmi,
    cvx_min,
    fix_variables,
    random_point,
    solve,
    system,
)

from lmic.api import solve as solve_problem
from lmic.compile import compile_theorem
from lmic.errors import DataError

THM1 = "uncertain_dt.thm1.example"
L_PUB = [[0.3220, 1.0764], [0.3426, 1.1104], [-0.1205, 1.5892]]


# -- independent block matrices (catalogue 2.1-2.3), for numpy and cvxpy alike --------------------


def _full(upper, bm):
    """Symmetric block matrix from its upper triangle (lower blocks = transposes)."""
    k = len(upper)
    rows = [[upper[i][j] if j >= i else upper[j][i].T for j in range(k)] for i in range(k)]
    return bm(rows)


def lemma3_lmis(D, P, alpha, e1, e2, mu, bm):
    A, B, H, M1, N = D["A"], D["B"], D["H"], D["M1"], D["N"]
    n, nw, r = A.shape[0], B.shape[1], M1.shape[1]
    Z, I = np.zeros, np.eye
    l15 = _full(
        [
            [H.T @ H - P + e2 * N.T @ N, I(n), A.T @ P, Z((n, n)), Z((n, r))],
            [None, -alpha * I(n), Z((n, n)), Z((n, n)), Z((n, r))],
            [None, None, -0.5 * P, P, P @ M1],
            [None, None, None, P - 2 * e1 * I(n), Z((n, r))],
            [None, None, None, None, -e2 * I(r)],
        ],
        bm,
    )
    l16 = _full(
        [
            [-(mu**2) * I(nw), B.T @ P, B.T @ P],
            [None, -0.5 * P, Z((n, n))],
            [None, None, -I(n)],
        ],
        bm,
    )
    return l15, l16


def thm1_lmis(D, P1, P2, G, alpha, e1, e2, mu, beta, bm, psi1="printed", Acal=None):
    """``[Psi1 Omega; * Psi2]`` and Xi1; ``Acal`` given: Corollary 1's Psi1."""
    A, B, C, Dm, H, M1, M2, N = (D[k] for k in ("A", "B", "C", "D", "H", "M1", "M2", "N"))
    n, nw, r = A.shape[0], B.shape[1], M1.shape[1]
    Z, I = np.zeros, np.eye
    Lam2 = B.T @ P1 - Dm.T @ G.T
    Lam3 = P1 @ M1 - G @ M2
    dec = np.exp(-2 * beta)
    if Acal is not None:
        psi = [[H.T @ H - dec * P1, Z((n, n)), Acal], [None, e2 * N.T @ N - P2, Z((n, n))], [None, None, -I(n)]]
    elif psi1 == "printed":
        psi = [[H.T @ H - dec * P1, Z((n, n)), I(n)], [None, e2 * N.T @ N - P2, Z((n, n))], [None, None, -alpha * I(n)]]
    else:
        psi = [
            [H.T @ H - dec * P1, Z((n, n)), I(n), Z((n, n))],
            [None, e2 * N.T @ N - P2, Z((n, n)), I(n)],
            [None, None, -alpha * I(n), Z((n, n))],
            [None, None, None, -alpha * I(n)],
        ]
    k = len(psi)
    omega = [
        [A.T @ P1 - C.T @ G.T, Z((n, n)), Z((n, n)), Z((n, n)), Z((n, r))],
        [Z((n, n)), A.T @ P2, Z((n, n)), Z((n, n)), Z((n, r))],
    ]
    omega += [[Z((n, n)), Z((n, n)), Z((n, n)), Z((n, n)), Z((n, r))] for _ in range(k - 2)]
    psi2 = [
        [-0.5 * P1, Z((n, n)), P1, Z((n, n)), Lam3],
        [None, -0.5 * P2, Z((n, n)), P2, P2 @ M1],
        [None, None, P1 - 2 * e1 * I(n), Z((n, n)), Z((n, r))],
        [None, None, None, P2 - 2 * e1 * I(n), Z((n, r))],
        [None, None, None, None, -e2 * I(r)],
    ]
    upper = [psi[i] + omega[i] for i in range(k)] + [[None] * k + psi2[i] for i in range(5)]
    big = _full(upper, bm)
    xi1 = _full(
        [
            [-(mu**2) * I(nw), Lam2, B.T @ P2, Lam2, B.T @ P2],
            [None, -0.5 * P1, Z((n, n)), Z((n, n)), Z((n, n))],
            [None, None, -0.5 * P2, Z((n, n)), Z((n, n))],
            [None, None, None, -I(n), Z((n, n))],
            [None, None, None, None, -I(n)],
        ],
        bm,
    )
    return big, xi1


def as_arrays(d):
    return {k: np.array(v, dtype=float) for k, v in d["data"].items()}


def random_data(seed, n=2, p=1, nw=1, r=1, s=1):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    A *= 0.4 / max(abs(np.linalg.eigvals(A)))
    return {
        "A": A,
        "B": rng.standard_normal((n, nw)),
        "C": rng.standard_normal((p, n)),
        "D": 0.2 * rng.standard_normal((p, nw)),
        "H": 0.25 * np.eye(n),
        "M1": 0.1 * rng.standard_normal((n, r)),
        "M2": 0.1 * rng.standard_normal((p, r)),
        "N": 0.2 * rng.standard_normal((s, n)),
        "Cw": 1 + rng.random((n, n)),
    }


def sysdict(D, keys, **params):
    return {"lmic": 1, "data": {k: D[k].tolist() for k in keys}, "params": params}


# -- published examples ---------------------------------------------------------------------------


@pytest.mark.parametrize("backend", BACKENDS)
def test_thm1_example_reference_optimum(backend):
    r = solve("uncertain_dt.thm1", system(THM1), backend=backend)
    assert r.verdict == "certified"
    v = r.variables
    assert v["alpha"] == pytest.approx(4.0625, abs=2e-4)
    assert v["eps1"] == pytest.approx(1.1226, abs=2e-4)
    assert v["eps2"] == pytest.approx(0.1620, abs=2e-4)
    assert r.derived["gamma_star"] == pytest.approx(0.3405, abs=1e-4)
    assert np.allclose(r.derived["L"], [[0.3522, 1.0213], [0.3051, 1.1676], [-0.1104, 1.5616]], atol=1e-3)
    # the published gamma* = 0.4339 is not what the printed LMIs give
    assert r.derived["gamma_star"] < 0.4339 - 0.09


def test_thm1_published_point_is_infeasible():
    prob = compile_theorem("uncertain_dt.thm1", system(THM1))
    r = solve_problem(fix_variables(prob, eps1=0.7715, alpha=2.9982))
    assert r.status == "infeasible" and r.verdict == "infeasible-certified"
    # with eps1 = 0.7715 fixed, the least alpha is 4.790 (catalogue 2.2)
    r = solve_problem(fix_variables(prob, eps1=0.7715))
    assert r.verdict == "certified"
    assert r.variables["alpha"] == pytest.approx(4.790, abs=1e-3)


def test_thm1_published_gain_is_certified():
    r = solve("uncertain_dt.thm1", system(THM1, data={"L": L_PUB}), {"fixed_L": 1})
    assert r.verdict == "certified"
    assert r.objective == pytest.approx(5.2006, abs=2e-4)
    assert r.variables["alpha"] == pytest.approx(4.150, abs=1e-3)
    assert r.variables["eps1"] == pytest.approx(1.051, abs=1e-3)
    assert r.derived["gamma_star"] == pytest.approx(0.3428, abs=1e-4)


def test_thm1_corrected_psi1():
    r = solve("uncertain_dt.thm1", system(THM1), {"psi1": "corrected"})
    assert r.verdict == "certified"
    assert r.variables["alpha"] == pytest.approx(19.635, abs=2e-3)
    assert r.variables["eps1"] == pytest.approx(2.835, abs=1e-3)
    assert r.derived["gamma_star"] == pytest.approx(0.1152, abs=1e-4)
    assert np.allclose(r.derived["L"], [[0.514, 0.789], [0.207, 1.202], [0.024, 1.275]], atol=2e-3)


@pytest.mark.parametrize("backend", BACKENDS)
def test_lemma3_example_plant(backend):
    r = solve("uncertain_dt.lemma3", system("uncertain_dt.lemma3.example-plant"), backend=backend)
    assert r.verdict == "certified"
    assert r.variables["alpha"] == pytest.approx(65.57, abs=1e-2)
    assert r.variables["eps1"] == pytest.approx(12.68, abs=1e-2)
    assert r.variables["eps2"] == pytest.approx(0.1539, abs=2e-4)
    assert r.derived["gamma_star"] == pytest.approx(0.0334, abs=1e-4)


@pytest.mark.parametrize("backend", BACKENDS)
def test_cor1_example_plant(backend):
    r = solve("uncertain_dt.cor1", system("uncertain_dt.cor1.example-plant"), backend=backend)
    assert r.verdict == "certified"
    assert r.objective == pytest.approx(-0.77198, abs=2e-5)
    assert r.variables["eps1"] == pytest.approx(0.5731, abs=2e-4)
    gstar = np.array(r.derived["Gamma_star"])
    assert np.allclose(gstar, np.array([[0.113], [0.1376], [0.1069]]) @ np.ones((1, 3)), atol=2e-4)
    assert np.allclose(r.derived["Gamma_star_T"], gstar.T)
    assert np.all(np.array(r.derived["Acal"]) > 0)


# -- random systems -------------------------------------------------------------------------------


def test_random_lmis_match_catalogue():
    rng = np.random.default_rng(5)
    D = random_data(1, n=3, p=2, nw=2, r=2, s=2)
    keys_l3 = ("A", "B", "H", "M1", "N")
    prob = compile_theorem("uncertain_dt.lemma3", sysdict(D, keys_l3, mu=1.3))
    x, v = random_point(prob, rng)
    l15, l16 = lemma3_lmis(D, v["P"], v["alpha"], v["eps1"], v["eps2"], 1.3, np.block)
    compare_lmi(prob, "(15)", x, l15)
    compare_lmi(prob, "(16)", x, l16)
    keys = ("A", "B", "C", "D", "H", "M1", "M2", "N")
    for psi1 in ("printed", "corrected"):
        prob = compile_theorem("uncertain_dt.thm1", sysdict(D, keys, mu=1.3, beta=0.07, psi1=psi1))
        x, v = random_point(prob, rng)
        big, xi1 = thm1_lmis(D, v["P1"], v["P2"], v["G"], v["alpha"], v["eps1"], v["eps2"], 1.3, 0.07, np.block, psi1)
        compare_lmi(prob, "[Psi1 Omega; * Psi2]", x, big)
        compare_lmi(prob, "Xi1 (24)", x, xi1)
    prob = compile_theorem("uncertain_dt.cor1", sysdict(D, keys + ("Cw",), mu=1.3, beta=0.07))
    x, v = random_point(prob, rng)
    env = prob.environment(x)
    acal = env["Acal"]
    w = np.diag(v["W"]).reshape(3, 3)  # row-major c_ij alpha_ij
    assert np.allclose(acal, w / D["Cw"])
    big, xi1 = thm1_lmis(D, v["P1"], v["P2"], v["G"], 0.0, v["eps1"], v["eps2"], 1.3, 0.07, np.block, Acal=acal)
    compare_lmi(prob, "[Psi1 Omega; * Psi2]", x, big)
    compare_lmi(prob, "Xi1 (24)", x, xi1)
    assert prob.objective.value(x) == pytest.approx(v["eps1"] - np.sum(D["Cw"] * acal))


def _cvx_thm1(D, mu, beta, solver, kind):
    n, p = D["A"].shape[0], D["C"].shape[0]
    P1, P2 = cp.Variable((n, n), symmetric=True), cp.Variable((n, n), symmetric=True)
    G = cp.Variable((n, p))
    alpha, e1, e2 = cp.Variable(), cp.Variable(), cp.Variable()
    if kind == "cor1":
        Acal = cp.Variable((n, n))
        big, xi1 = thm1_lmis(D, P1, P2, G, alpha, e1, e2, mu, beta, cp.bmat, Acal=Acal)
        scalars = [e1, e2] + [Acal[i, j] for i in range(n) for j in range(n)]
        return cvx_min(e1 - cp.sum(cp.multiply(D["Cw"], Acal)), [big, xi1], [P1, P2], scalars, solver=solver)
    big, xi1 = thm1_lmis(D, P1, P2, G, alpha, e1, e2, mu, beta, cp.bmat, kind)
    return cvx_min(alpha + e1, [big, xi1], [P1, P2], [alpha, e1, e2], solver=solver)


def test_random_lemma3_matches_cvxpy():
    for seed in range(3):
        D = random_data(40 + seed)
        mu = 3.0
        n = 2
        P = cp.Variable((n, n), symmetric=True)
        alpha, e1, e2 = cp.Variable(), cp.Variable(), cp.Variable()
        l15, l16 = lemma3_lmis(D, P, alpha, e1, e2, mu, cp.bmat)
        ref = {s: cvx_min(alpha + e1, [l15, l16], [P], [alpha, e1, e2], solver=s) for s in REF_SOLVERS}
        assert ref["CLARABEL"][0] == "optimal"
        assert ref["SCS"][1] == pytest.approx(ref["CLARABEL"][1], rel=2e-2)
        for backend in BACKENDS:
            r = solve("uncertain_dt.lemma3", sysdict(D, ("A", "B", "H", "M1", "N"), mu=mu), backend=backend)
            assert r.verdict == "certified"
            assert r.objective == pytest.approx(ref["CLARABEL"][1], rel=1e-4)


@pytest.mark.parametrize("kind", ["printed", "corrected", "cor1"])
def test_random_thm1_cor1_match_cvxpy(kind):
    keys = ("A", "B", "C", "D", "H", "M1", "M2", "N")
    for seed in range(2):
        D = random_data(50 + seed)
        mu, beta = 3.0, 0.05
        ref = {s: _cvx_thm1(D, mu, beta, s, kind) for s in REF_SOLVERS}
        assert ref["CLARABEL"][0] == "optimal"
        assert ref["SCS"][1] == pytest.approx(ref["CLARABEL"][1], rel=2e-2, abs=1e-3)
        if kind == "cor1":
            tid, d = "uncertain_dt.cor1", sysdict(D, keys + ("Cw",), mu=mu, beta=beta)
        else:
            tid, d = "uncertain_dt.thm1", sysdict(D, keys, mu=mu, beta=beta, psi1=kind)
        for backend in BACKENDS:
            r = solve(tid, d, backend=backend)
            assert r.verdict == "certified"
            assert r.objective == pytest.approx(ref["CLARABEL"][1], rel=1e-4, abs=1e-6)


# -- bad input ------------------------------------------------------------------------------------


def test_bad_input_messages():
    with pytest.raises(DataError, match=r"uncertain_dt\.thm1.*beta = -0\.05.*outside its domain"):
        compile_theorem("uncertain_dt.thm1", system(THM1), {"beta": -0.05})
    with pytest.raises(DataError, match=r"uncertain_dt\.thm1.*option psi1 = 'fixed' is not one of printed, corrected"):
        compile_theorem("uncertain_dt.thm1", system(THM1), {"psi1": "fixed"})
    bad = system(THM1)
    del bad["data"]["M2"]
    with pytest.raises(DataError, match=r"uncertain_dt\.thm1.*missing data 'M2'"):
        compile_theorem("uncertain_dt.thm1", bad)
    with pytest.raises(DataError, match=r"uncertain_dt\.thm1.*'D'.*shape 3x1"):
        compile_theorem("uncertain_dt.thm1", system(THM1, data={"D": [[0.2], [0.2], [0.1]]}))
    with pytest.raises(DataError, match=r"uncertain_dt\.lemma3.*mu = 0.*outside its domain"):
        compile_theorem("uncertain_dt.lemma3", system("uncertain_dt.lemma3.example-plant"), {"mu": 0})
    cw = system("uncertain_dt.cor1.example-plant", data={"Cw": [[1.0, 1.0, 1.0], [1.0, 0.0, 1.0], [1.0, 1.0, 1.0]]})
    with pytest.raises(DataError, match=r"uncertain_dt\.cor1.*'Cw'.*element-wise > 0"):
        compile_theorem("uncertain_dt.cor1", cw)
