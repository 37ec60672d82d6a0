"""sampled_euler.thm1..thm4 (Abbaszadeh & Marquez 2008): examples, audits, random systems, bad input.

Reference values: seeds catalogue sections 1 and 6 (Clarabel and SCS reference implementation).
"""

from __future__ import annotations

import cvxpy as cp
import numpy as np
import pytest
from seeds_helpers import (
    BACKENDS,
    REF_SOLVERS,
    compare_lmi,
    cvx_feasible,
    cvx_min,
    lmic_feasible,
    random_point,
    solve,
    system,
)

from lmic.compile import compile_theorem
from lmic.errors import DataError

L_PUB = [[1.0497], [0.3588]]  # Theorem 4's published gain


# -- independent formulas (from the catalogue) ----------------------------------------------------


def psi1(Q, gd):
    lmax, lmin = np.linalg.eigvalsh(Q)[-1], np.linalg.eigvalsh(Q)[0]
    return (-lmax + np.sqrt(lmax**2 + lmin**2 / gd**2)) / (gd + 2)


def lmi6(P, G, eps, Q, Ad, Cd):
    n = Ad.shape[0]
    return np.block([[P - Q - eps * np.eye(n), Ad.T @ P - Cd.T @ G.T], [P @ Ad - G @ Cd, P]])


def cvx_lmi6(P, G, eps, Q, Ad, Cd):
    n = Ad.shape[0]
    return cp.bmat([[P - Q - eps * np.eye(n), Ad.T @ P - Cd.T @ G.T], [P @ Ad - G @ Cd, P]])


def cvx_xi_star(Ad, Cd, Q, solver):
    """Theorem 2 written directly: min xi, (32), (33), xi > 1 (fixed margin 1e-7)."""
    n, p = Cd.shape[1], Cd.shape[0]
    P, G = cp.Variable((n, n), symmetric=True), cp.Variable((n, p))
    eps, xi = cp.Variable(), cp.Variable()
    lmin, lmax = np.linalg.eigvalsh(Q)[0], np.linalg.eigvalsh(Q)[-1]
    psi2 = (lmin * xi - lmax) / 3
    return cvx_min(
        xi,
        neg_strict=[],
        pos_strict=[P, cvx_lmi6(P, G, eps, Q, Ad, Cd), cp.bmat([[psi2 * np.eye(n), P], [P, psi2 * np.eye(n)]])],
        scalars=[eps, xi - 1],
        solver=solver,
    )


def random_system(rng, n=2, p=1, rho=0.9):
    A = rng.standard_normal((n, n))
    A *= rho / max(abs(np.linalg.eigvals(A)))
    C = rng.standard_normal((p, n))
    R = rng.standard_normal((n, n))
    Q = 0.1 * (R @ R.T + np.eye(n))
    return A, C, Q


# -- published examples ---------------------------------------------------------------------------


@pytest.mark.parametrize("backend", BACKENDS)
def test_thm2_example_reproduces_gamma_c_star(backend):
    r = solve("sampled_euler.thm2", system("sampled_euler.thm2.example"), backend=backend)
    assert r.verdict == "certified"
    assert r.variables["xi"] == pytest.approx(14.95596, rel=2e-6)
    assert r.derived["gamma_d_star"] == pytest.approx(0.066863, abs=1e-6)
    assert abs(r.derived["gamma_d_star"] - 0.067) < 2e-4  # published, rounded to 0.67 / T
    assert np.allclose(r.derived["L"], [[1.0384], [0.2454]], atol=2e-3)
    assert r.derived["delta_gamma_d"] == pytest.approx(0.066863 - 0.06109, abs=1e-6)


def test_thm2_xi_does_not_depend_on_q():
    r = solve("sampled_euler.thm2", system("sampled_euler.thm2.example", data={"Q": [[2.0, 0], [0, 2.0]]}))
    assert r.verdict == "certified"
    assert r.derived["gamma_d_star"] == pytest.approx(0.066863, abs=1e-6)


def test_thm2_anisotropic_q_is_worse():
    d = system("sampled_euler.thm2.example", data={"Q": [[0.1, 0], [0, 0.2]]})
    r = solve("sampled_euler.thm2", d, {"gamma_d": 0.0})
    assert r.verdict == "certified"
    assert r.derived["gamma_d_star"] == pytest.approx(0.0340, abs=1e-4)
    # the actual constant 0.06109 exceeds this gamma_d*: Remark 2's check rejects the design
    r = solve("sampled_euler.thm2", d)
    assert r.verdict == "rejected" and "gamma_d < gamma_d*" in r.certificate.reason


def test_thm2_with_published_gain():
    r = solve("sampled_euler.thm2", system("sampled_euler.thm2.example", data={"L": L_PUB}), {"fixed_L": 1})
    assert r.verdict == "certified"
    assert r.derived["gamma_d_star"] == pytest.approx(0.066211, abs=1e-6)


def test_thm2_margin_check_rejects_too_large_gamma_d():
    r = solve("sampled_euler.thm2", system("sampled_euler.thm2.example"), {"gamma_d": 0.07})
    assert r.verdict == "rejected"
    assert "gamma_d < gamma_d*" in r.certificate.reason


@pytest.mark.parametrize("backend", BACKENDS)
def test_thm3_example_reproduces_gamma_c_star(backend):
    r = solve("sampled_euler.thm3", system("sampled_euler.thm3.example"), backend=backend)
    assert r.verdict == "certified"
    assert r.derived["gamma_c_star"] == pytest.approx(0.66863, abs=1e-5)
    assert abs(r.derived["gamma_c_star"] - 0.67) < 2e-3  # published
    assert r.derived["delta_gamma_c"] == pytest.approx(0.66863 - 0.6109, abs=1e-5)  # Remark 4: 0.0577
    assert np.allclose(r.derived["L"], [[1.0384], [0.2454]], atol=2e-3)


def test_thm3_default_q_is_t_identity():
    d = system("sampled_euler.thm3.example")
    del d["data"]["Q"]
    prob = compile_theorem("sampled_euler.thm3", d)
    assert np.allclose(prob.data["Q"], 0.1 * np.eye(2))
    assert np.allclose(prob.data["Ad"], [[1.0, 0.1], [-0.1, 0.9]])


def test_thm3_rejects_q_with_lambda_min_not_t():
    d = system("sampled_euler.thm3.example", data={"Q": [[0.2, 0], [0, 0.3]]})
    with pytest.raises(DataError, match=r"sampled_euler\.thm3.*'Q'.*lambda_min\(Q\) = T"):
        compile_theorem("sampled_euler.thm3", d)


def test_thm1_example_and_published_gain():
    for gd in (0.06109, 0.067):
        r = solve("sampled_euler.thm1", system("sampled_euler.thm1.example"), {"gamma_d": gd})
        assert r.verdict == "certified"
        r = solve(
            "sampled_euler.thm1", system("sampled_euler.thm1.example", data={"L": L_PUB}), {"gamma_d": gd, "fixed_L": 1}
        )
        assert r.verdict == "certified"


def test_thm1_sup_gamma_d():
    """Reference sup gamma_d = 0.09352 (bisection): feasible just below, infeasible just above."""
    d = system("sampled_euler.thm1.example")
    assert solve("sampled_euler.thm1", d, {"gamma_d": 0.0934}).verdict == "certified"
    above = solve("sampled_euler.thm1", d, {"gamma_d": 0.0937})
    assert above.status == "infeasible" and above.verdict == "infeasible-certified"


@pytest.mark.parametrize("backend", BACKENDS)
def test_thm4_example_is_infeasible(backend):
    r = solve("sampled_euler.thm4", system("sampled_euler.thm4.example"), backend=backend)
    assert r.status == "infeasible"
    assert r.verdict == "infeasible-certified" and r.certificate.exact["proven"]  # the ray, proven exactly
    assert r.exit_code() == 3
    lam2 = r.problem.data["Lambda2"]
    assert np.linalg.eigvalsh(lam2)[-1] == pytest.approx(0.1049, abs=1e-4)
    assert r.problem.data["Psi1"] == pytest.approx(0.6753, abs=1e-4)


def test_thm4_infeasible_for_large_gamma_d_and_printed_coupling():
    r = solve("sampled_euler.thm4", system("sampled_euler.thm4.example"), {"gamma_d": 0.5})
    assert r.verdict == "infeasible-certified" and r.outcome.evidence.kind == "exact-proof"
    d = system("sampled_euler.thm4.example", data={"Bd": [[1.0, 0.0], [0.0, 1.0]]})
    r = solve("sampled_euler.thm4", d, {"coupling": "I"})
    assert r.verdict == "infeasible-certified" and r.outcome.evidence.kind == "exact-proof"


# -- random systems: the compiled LMIs are the catalogue's, and solvers agree with CVXPY ----------


def test_random_lmis_match_catalogue():
    rng = np.random.default_rng(1)
    for seed in range(3):
        A, C, Q = random_system(np.random.default_rng(seed), n=3, p=2)
        gd = 0.05 + 0.1 * seed
        base = {"lmic": 1, "data": {"Ad": A.tolist(), "Cd": C.tolist(), "Q": Q.tolist()}, "params": {"gamma_d": gd}}
        prob = compile_theorem("sampled_euler.thm1", base)
        x, v = random_point(prob, rng)
        s = psi1(Q, gd)
        compare_lmi(prob, "(6)", x, lmi6(v["P"], v["G"], v["epsilon"], Q, A, C))
        compare_lmi(prob, "(7)", x, np.block([[s * np.eye(3), v["P"]], [v["P"], s * np.eye(3)]]))
        prob = compile_theorem("sampled_euler.thm2", base)
        x, v = random_point(prob, rng)
        psi2 = (np.linalg.eigvalsh(Q)[0] * v["xi"] - np.linalg.eigvalsh(Q)[-1]) / 3
        compare_lmi(prob, "(33)", x, np.block([[psi2 * np.eye(3), v["P"]], [v["P"], psi2 * np.eye(3)]]))
        compare_lmi(prob, "(32)", x, lmi6(v["P"], v["G"], v["epsilon"], Q, A, C))
        Bd = rng.standard_normal((3, 1))
        H = rng.standard_normal((2, 3))
        d4 = {"lmic": 1, "data": {**base["data"], "Bd": Bd.tolist(), "H": H.tolist()}, "params": {"gamma_d": gd}}
        prob = compile_theorem("sampled_euler.thm4", d4)
        x, v = random_point(prob, rng)
        lmax = np.linalg.eigvalsh(Q)[-1]
        lam2 = H.T @ H - Q + gd * (3 * s + lmax) * np.eye(3)
        c = 2 * (gd + 1) * s + lmax
        expected = np.block([[lam2, c / 2 * Bd], [c / 2 * Bd.T, Bd.T @ v["P"] @ Bd - v["zeta"]]])
        compare_lmi(prob, "(73)", x, expected)
        # the proof of catalogue 1.4: Lambda2 always has a positive eigenvalue
        assert np.linalg.eigvalsh(prob.data["Lambda2"])[-1] > 0


def test_random_thm1_status_matches_cvxpy():
    seen = set()
    for seed in range(4):
        A, C, Q = random_system(np.random.default_rng(10 + seed))
        for gd in (0.01, 0.3):
            d = {"lmic": 1, "data": {"Ad": A.tolist(), "Cd": C.tolist(), "Q": Q.tolist()}, "params": {"gamma_d": gd}}
            n = 2
            P, G, eps = cp.Variable((n, n), symmetric=True), cp.Variable((n, 1)), cp.Variable()
            s = psi1(Q, gd)
            ref = {
                solver: cvx_feasible(
                    [],
                    [P, cvx_lmi6(P, G, eps, Q, A, C), cp.bmat([[s * np.eye(n), P], [P, s * np.eye(n)]])],
                    [eps],
                    solver=solver,
                )
                for solver in REF_SOLVERS
            }
            assert ref["CLARABEL"] is not None
            assert ref["SCS"] in (None, ref["CLARABEL"])
            for backend in BACKENDS:
                assert lmic_feasible(solve("sampled_euler.thm1", d, backend=backend)) == ref["CLARABEL"]
            seen.add(ref["CLARABEL"])
    assert seen == {True, False}


def test_random_thm2_thm3_optimum_matches_cvxpy():
    for seed in range(3):
        A, C, Q = random_system(np.random.default_rng(20 + seed), rho=1.5)
        T = 0.1
        Ad = np.eye(2) + T * A
        ref = {solver: cvx_xi_star(Ad, C, Q, solver) for solver in REF_SOLVERS}
        assert ref["CLARABEL"][0] == "optimal"
        xi = ref["CLARABEL"][1]
        assert ref["SCS"][1] == pytest.approx(xi, rel=1e-3)
        d2 = {"lmic": 1, "data": {"Ad": Ad.tolist(), "Cd": C.tolist(), "Q": Q.tolist()}}
        for backend in BACKENDS:
            r = solve("sampled_euler.thm2", d2, backend=backend)
            assert r.verdict == "certified"
            assert r.objective == pytest.approx(xi, rel=1e-5)
        # Theorem 3 on the same Euler model (Q scaled so that lambda_min(Q) = T)
        Q3 = Q * (T / np.linalg.eigvalsh(Q)[0])
        xi3 = cvx_xi_star(Ad, C, Q3, "CLARABEL")[1]
        d3 = {"lmic": 1, "data": {"A": A.tolist(), "C": C.tolist(), "Q": Q3.tolist()}, "params": {"T": T}}
        r = solve("sampled_euler.thm3", d3)
        assert r.verdict == "certified"
        assert r.derived["gamma_c_star"] == pytest.approx(1 / (T * xi3), rel=1e-5)


def test_random_thm4_infeasible_like_cvxpy():
    for seed in range(2):
        rng = np.random.default_rng(30 + seed)
        A, C, Q = random_system(rng)
        Bd, H, gd = rng.standard_normal((2, 1)), rng.standard_normal((2, 2)), 0.05
        d = {
            "lmic": 1,
            "data": {"Ad": A.tolist(), "Cd": C.tolist(), "Q": Q.tolist(), "Bd": Bd.tolist(), "H": H.tolist()},
            "params": {"gamma_d": gd},
        }
        P, zeta = cp.Variable((2, 2), symmetric=True), cp.Variable()
        s, lmax = psi1(Q, gd), np.linalg.eigvalsh(Q)[-1]
        lam2 = H.T @ H - Q + gd * (3 * s + lmax) * np.eye(2)
        c = 2 * (gd + 1) * s + lmax
        m73 = cp.bmat([[lam2, c / 2 * Bd], [c / 2 * Bd.T, Bd.T @ P @ Bd - zeta * np.eye(1)]])
        for solver in REF_SOLVERS:
            status, _ = cvx_min(zeta, [m73], [P], [zeta], solver=solver)
            assert status == "infeasible"
        for backend in BACKENDS:
            assert solve("sampled_euler.thm4", d, backend=backend).verdict == "infeasible-certified"


# -- bad input ------------------------------------------------------------------------------------


def test_bad_input_messages():
    d = system("sampled_euler.thm1.example")
    with pytest.raises(DataError, match=r"sampled_euler\.thm1.*gamma_d = -0\.1.*outside its domain"):
        compile_theorem("sampled_euler.thm1", d, {"gamma_d": -0.1})
    bad = system("sampled_euler.thm2.example")
    del bad["data"]["Q"]
    with pytest.raises(DataError, match=r"sampled_euler\.thm2.*missing data 'Q'"):
        compile_theorem("sampled_euler.thm2", bad)
    bad = system("sampled_euler.thm2.example", data={"Cd": [[1.0, 0.0, 0.0]]})
    with pytest.raises(DataError, match=r"sampled_euler\.thm2.*'Cd'.*shape 1x3"):
        compile_theorem("sampled_euler.thm2", bad)
    bad = system("sampled_euler.thm3.example", data={"Q": [[0.1, 0.0], [0.0, -0.1]]})
    with pytest.raises(DataError, match=r"sampled_euler\.thm3.*'Q' must be positive definite"):
        compile_theorem("sampled_euler.thm3", bad)
    with pytest.raises(DataError, match=r"sampled_euler\.thm4.*'Bd'.*expected n x n"):
        compile_theorem("sampled_euler.thm4", system("sampled_euler.thm4.example"), {"coupling": "I"})
    with pytest.raises(DataError, match=r"sampled_euler\.thm3.*T = 0.*outside its domain"):
        compile_theorem("sampled_euler.thm3", system("sampled_euler.thm3.example"), {"T": 0.0})
