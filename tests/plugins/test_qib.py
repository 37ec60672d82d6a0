"""qib.thm1, cor1, thm2, cor2 (Wang, Song & Zhang 2015): examples, audits, random systems, bad input.

Reference values: seeds catalogue sections 3 and 6.
"""

from __future__ import annotations

import cvxpy as cp
import numpy as np
import pytest
from seeds_helpers import (
    BACKENDS,
    REF_SOLVERS,
    certify_point,
    compare_lmi,
    cvx_feasible,
    lmic_feasible,
    random_point,
    solve,
    system,
)

from lmic.certify import certify
from lmic.compile import compile_theorem
from lmic.errors import DataError
from lmic.solution import Solution

THM1 = "qib.thm1.flexible-joint"
THM2 = "qib.thm2.flexible-joint"
K_DEADBEAT = [[0.0, 0.4115], [0.0, 0.1656]]


# -- independent block matrices (catalogue 3.1-3.4), numpy or cvxpy ------------------------------


def lmi7(A, C, P, R, w, beta, gamma, bm):
    n = A.shape[0]
    I, Z = np.eye(n), np.zeros((n, n))
    X = A.T @ P - C.T @ R
    return bm([[-P + 2 * w * beta * I, X + w * gamma * I, X], [X.T + w * gamma * I, P - 2 * w * I, Z], [X.T, Z, -P]])


def lmi13(A, C, P, R, w, lam, bm):
    n = A.shape[0]
    I, Z = np.eye(n), np.zeros((n, n))
    X = A.T @ P - C.T @ R
    return bm([[-P + w * lam**2 * I, X, X], [X.T, P - w * I, Z], [X.T, Z, -P]])


def reduced(A, C, H):
    T_inv = np.linalg.inv(np.vstack([H, C]))
    k = H.shape[0]
    N, M = T_inv[:, :k], T_inv[:, k:]
    return N, M, H @ A @ N, C @ A @ N


def lmi21(A, C, H, K, P, w, beta, gamma, bm):
    """(21) (P a matrix) -- with P = alpha I it is (26)."""
    n = A.shape[0]
    N, _, AZ, CZ = reduced(A, C, H)
    F1 = (AZ - K @ CZ).T @ N.T @ P
    F2 = (H - K @ C).T @ N.T @ P
    return bm(
        [
            [-N.T @ P @ N + 2 * w * beta * N.T @ N, w * gamma * N.T, F1],
            [w * gamma * N, -2 * w * np.eye(n), F2],
            [F1.T, F2.T, -P],
        ]
    )


def lmi26(A, C, H, K, w, alpha, beta, gamma, bm):
    n = A.shape[0]
    N, _, AZ, CZ = reduced(A, C, H)
    F1 = alpha * (AZ - K @ CZ).T @ N.T
    F2 = alpha * (H - K @ C).T @ N.T
    return bm(
        [
            [(-alpha + 2 * w * beta) * N.T @ N, w * gamma * N.T, F1],
            [w * gamma * N, -2 * w * np.eye(n), F2],
            [F1.T, F2.T, -alpha * np.eye(n)],
        ]
    )


def random_plant(seed, n=3, p=1, rho=1.05):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    A *= rho / max(abs(np.linalg.eigvals(A)))
    return A, rng.standard_normal((p, n)), rng.standard_normal((n - p, n))


def arrays(name):
    return {k: np.array(v, dtype=float) for k, v in system(name)["data"].items()}


# -- published examples: full order ---------------------------------------------------------------


@pytest.mark.parametrize("backend", BACKENDS)
def test_thm1_example_feasible_gain_like_published(backend):
    r = solve("qib.thm1", system(THM1), backend=backend)
    assert r.verdict == "certified"
    L = np.array(r.derived["L"])
    # the published gain has the same structure (first column of A - L C zeroed) ...
    assert np.allclose(L[:, 0], [1.0, -4.86, 0.0, 0.195], atol=1e-4)
    # ... and is close (any certified L is acceptable; the reference solve is within 0.021)
    assert np.allclose(L, system(THM1)["published"]["L"], atol=0.05)


def test_thm1_published_point_is_a_certificate():
    d = system(THM1)
    prob = compile_theorem("qib.thm1", d)
    pub = d["published"]
    cert = certify_point(prob, {"P": pub["P"], "R": pub["R"], "omega": pub["omega"]})
    assert cert.verdict == "certified"
    x = prob.pack({"P": pub["P"], "R": pub["R"], "omega": pub["omega"]})
    lam_max = -np.linalg.eigvalsh(prob.lmis[1].matrix(x))[0]
    assert lam_max == pytest.approx(-0.05581, abs=1e-5)
    L_from_point = np.linalg.solve(np.array(pub["P"]), np.array(pub["R"]).T)
    assert np.allclose(L_from_point, pub["L"], atol=1e-3)  # printed to 4 decimals


@pytest.mark.parametrize("backend", BACKENDS)
def test_thm1_published_gain_is_certified(backend):
    d = system(THM1)
    d["data"]["L"] = d["published"]["L"]
    r = solve("qib.thm1", d, {"fixed_L": 1}, backend=backend)
    assert r.verdict == "certified"
    assert r.certificate.checks[0]["value"] == pytest.approx(0.335, abs=1e-3)  # rho(A - L_pub C)


def test_thm1_scs_near_zero_point_is_rejected():
    """Lesson 1: SCS at margin 1e-7 returns omega ~ 1.7e-7 and a garbage gain; never certified."""
    D = arrays(THM1)
    n, p = 4, 2
    P, R, w = cp.Variable((n, n), symmetric=True), cp.Variable((p, n)), cp.Variable()
    M = lmi7(D["A"], D["C"], P, R, w, 0.00110889, 0.0, cp.bmat)
    cons = [P >> 1e-7 * np.eye(n), M << -1e-7 * np.eye(3 * n), w >= 1e-7]
    cp.Problem(cp.Minimize(0), cons).solve(solver="SCS")
    prob = compile_theorem("qib.thm1", system(THM1))
    x = prob.pack({"P": P.value, "R": R.value, "omega": w.value})
    cert = certify(prob, Solution("optimal", x=x, backend="cvxpy:SCS"))
    assert cert.verdict == "rejected"


def test_cor1_example():
    r = solve("qib.cor1", system("qib.cor1.flexible-joint"))
    assert r.verdict == "certified"
    ref = [[1, 0.1], [-4.86, 2.5104], [0, 0.428], [0.195, 0.0255]]
    assert np.allclose(r.derived["L"], ref, atol=0.05)


def test_thm1_sup_beta():
    """Reference sup beta of (7) on this plant (gamma = 0): 0.01270."""
    assert solve("qib.thm1", system(THM1), {"beta": 0.0126}).verdict == "certified"
    assert solve("qib.thm1", system(THM1), {"beta": 0.0128}).status == "infeasible"


# -- published examples: reduced order ------------------------------------------------------------


@pytest.mark.parametrize("backend", BACKENDS)
def test_thm2_remark2_is_infeasible_and_published_k_is_least_infeasible(backend):
    r = solve("qib.thm2", system(THM2), backend=backend)
    assert r.status == "infeasible" and r.verdict == "infeasible-certified"
    if backend == "clarabel":
        # the max-margin point is the least-infeasible K: the published K (catalogue 3.3)
        assert np.allclose(r.variables["K"], system(THM2)["published"]["K"], atol=2e-3)


@pytest.mark.parametrize(
    "alpha",
    [
        1e-3,
        1.0,
        1e3,
    ],
)
def test_thm2_is_proven_infeasible_for_every_alpha(alpha):
    # (26) is homogeneous in (alpha, omega): scaling both scales the LMI, so (26) is infeasible
    # for every alpha when it is for one (the proof below). In the decision variables (K, omega)
    # it has constant blocks (alpha is given), so only an exact proof makes the ray global:
    # the one outcome is infeasible-certified on an exact proof.
    r = solve("qib.thm2", system(THM2), {"alpha": alpha})
    assert r.verdict == "infeasible-certified"
    assert r.outcome.evidence.kind == "exact-proof" and r.certificate.exact["proven"]


def test_thm2_infeasibility_proof():
    prob = compile_theorem("qib.thm2", system(THM2))
    # C_Z's second column is 0, A_Z's is [1; 1]: ||A_Z - K C_Z|| >= sqrt(2) for every K
    assert np.allclose(prob.data["C_Z"][:, 1], 0.0)
    assert np.allclose(prob.data["A_Z"][:, 1], [1.0, 1.0])
    assert solve("qib.cor2", system("qib.cor2.flexible-joint")).verdict == "infeasible-certified"


@pytest.mark.filterwarnings("ignore:Solution may be inaccurate")
def test_thm2_published_k_with_p_free_is_not_certified():
    d = system(THM2, data={"K": system(THM2)["published"]["K"]})
    for backend in BACKENDS:
        r = solve("qib.thm2", d, {"fixed_K": 1}, backend=backend)
        assert r.verdict != "certified"
        assert r.status == "infeasible"
    # Lesson 2: CVXPY-Clarabel at margin 1e-7 says optimal_inaccurate with a +1.6e-7 violation
    D = arrays(THM2)
    K = np.array(d["data"]["K"])
    P, w = cp.Variable((4, 4), symmetric=True), cp.Variable()
    M = lmi21(D["A"], D["C"], D["H"], K, P, w, 0.00110889, 0.0, cp.bmat)
    pb = cp.Problem(cp.Minimize(0), [P >> 1e-7 * np.eye(4), M << -1e-7 * np.eye(10), w >= 1e-7])
    pb.solve(solver="CLARABEL")
    prob = compile_theorem("qib.thm2", d, {"fixed_K": 1})
    x = prob.pack({"P": P.value, "omega": w.value})
    for status in ("inaccurate", "optimal"):
        cert = certify(prob, Solution(status, x=x, backend="cvxpy:CLARABEL"))
        assert cert.verdict == "rejected", (pb.status, cert.reason)


def test_thm2_deadbeat_k_is_feasible():
    d = system(THM2, data={"K": K_DEADBEAT})
    for backend in BACKENDS:
        r = solve("qib.thm2", d, {"fixed_K": 1}, backend=backend)
        assert r.verdict == "certified"
        # rho(A_Z - K C_Z) = 0 for the exact dead-beat gain; ~0.009 with K rounded to 4 decimals
        assert r.certificate.checks[0]["value"] < 0.02


def test_thm2_n_m_computed_when_omitted():
    d = system(THM2)
    del d["data"]["N"], d["data"]["M"]
    prob = compile_theorem("qib.thm2", d)
    assert np.allclose(prob.data["N"], system(THM2)["data"]["N"])
    assert np.allclose(prob.data["M"], system(THM2)["data"]["M"])


# -- random systems -------------------------------------------------------------------------------


def test_random_lmis_match_catalogue():
    rng = np.random.default_rng(3)
    A, C, H = random_plant(0, n=4, p=2)
    base = {"lmic": 1, "data": {"A": A.tolist(), "C": C.tolist()}}
    prob = compile_theorem("qib.thm1", {**base, "params": {"beta": 0.3, "gamma": -0.7}})
    x, v = random_point(prob, rng)
    compare_lmi(prob, "(7)", x, lmi7(A, C, v["P"], v["R"], v["omega"], 0.3, -0.7, np.block))
    prob = compile_theorem("qib.cor1", {**base, "params": {"lambda": 0.4}})
    x, v = random_point(prob, rng)
    compare_lmi(prob, "(13)", x, lmi13(A, C, v["P"], v["R"], v["omega"], 0.4, np.block))
    red = {"lmic": 1, "data": {"A": A.tolist(), "C": C.tolist(), "H": H.tolist()}}
    prob = compile_theorem("qib.thm2", {**red, "params": {"beta": 0.3, "gamma": 0.5, "alpha": 2.0}})
    x, v = random_point(prob, rng)
    compare_lmi(prob, "(26)", x, lmi26(A, C, H, v["K"], v["omega"], 2.0, 0.3, 0.5, np.block))
    K = rng.standard_normal((2, 2))
    fixed = {"lmic": 1, "data": {**red["data"], "K": K.tolist()}}
    prob = compile_theorem("qib.thm2", {**fixed, "params": {"beta": 0.3, "gamma": 0.5, "fixed_K": 1}})
    x, v = random_point(prob, rng)
    compare_lmi(prob, "(21)", x, lmi21(A, C, H, K, v["P"], v["omega"], 0.3, 0.5, np.block))
    prob = compile_theorem("qib.cor2", {**fixed, "params": {"lambda": 0.4, "fixed_K": 1}})
    x, v = random_point(prob, rng)
    compare_lmi(prob, "(27)", x, lmi21(A, C, H, K, v["P"], v["omega"], 0.16, 0.0, np.block))
    prob = compile_theorem("qib.cor2", {**red, "params": {"lambda": 0.4, "alpha": 2.0}})
    x, v = random_point(prob, rng)
    compare_lmi(prob, "(27) with P = alpha I", x, lmi26(A, C, H, v["K"], v["omega"], 2.0, 0.16, 0.0, np.block))


def test_random_thm1_status_matches_cvxpy():
    seen = set()
    for seed in range(3):
        A, C, _ = random_plant(60 + seed)
        for beta, gamma in ((0.01, 0.1), (0.5, 0.0)):
            n = 3
            P, R, w = cp.Variable((n, n), symmetric=True), cp.Variable((1, n)), cp.Variable()
            ref = {
                s: cvx_feasible([lmi7(A, C, P, R, w, beta, gamma, cp.bmat)], [P], [w], solver=s, box=[P, R, w])
                for s in REF_SOLVERS
            }
            assert ref["CLARABEL"] is not None
            assert ref["SCS"] in (None, ref["CLARABEL"])
            d = {"lmic": 1, "data": {"A": A.tolist(), "C": C.tolist()}, "params": {"beta": beta, "gamma": gamma}}
            for backend in BACKENDS:
                assert lmic_feasible(solve("qib.thm1", d, backend=backend)) == ref["CLARABEL"]
            seen.add(ref["CLARABEL"])
    assert seen == {True, False}


def test_random_thm2_status_matches_cvxpy():
    seen = set()
    for seed in range(4):
        A, C, H = random_plant(70 + seed, n=3, p=1, rho=0.9)
        for beta in (0.001, 0.2):
            K = cp.Variable((2, 1))
            w = cp.Variable()
            ref = {
                s: cvx_feasible([lmi26(A, C, H, K, w, 1.0, beta, 0.0, cp.bmat)], [], [w], solver=s, box=[K, w])
                for s in REF_SOLVERS
            }
            assert ref["CLARABEL"] is not None
            assert ref["SCS"] in (None, ref["CLARABEL"])
            d = {"lmic": 1, "data": {"A": A.tolist(), "C": C.tolist(), "H": H.tolist()}, "params": {"beta": beta}}
            for backend in BACKENDS:
                assert lmic_feasible(solve("qib.thm2", d, backend=backend)) == ref["CLARABEL"]
            seen.add(ref["CLARABEL"])
    assert seen == {True, False}


# -- bad input ------------------------------------------------------------------------------------


def test_bad_input_messages():
    with pytest.raises(DataError, match=r"qib\.cor1.*lambda = -0\.1.*outside its domain"):
        compile_theorem("qib.cor1", system("qib.cor1.flexible-joint"), {"lambda": -0.1})
    with pytest.raises(DataError, match=r"qib\.thm2.*alpha = 0.*outside its domain"):
        compile_theorem("qib.thm2", system(THM2), {"alpha": 0})
    with pytest.raises(DataError, match=r"qib\.thm2.*'N', 'M' must satisfy \[N M\] = \[H; C\]\^-1"):
        compile_theorem("qib.thm2", system(THM2, data={"N": [[0, 0], [0, 0], [0, 1], [1, 0]]}))
    with pytest.raises(DataError, match=r"qib\.thm2.*'H'.*nonsingular"):
        compile_theorem("qib.thm2", system(THM2, data={"H": [[1, 0, 0, 0], [0, 0, 0, 1]]}))
    with pytest.raises(DataError, match=r"qib\.thm2.*missing data 'K'"):
        compile_theorem("qib.thm2", system(THM2), {"fixed_K": 1})
    with pytest.raises(DataError, match=r"qib\.thm1.*'C'.*shape 2x3"):
        compile_theorem("qib.thm1", system(THM1, data={"C": [[1, 0, 0], [0, 1, 0]]}))
    with pytest.raises(DataError, match=r"qib\.thm1.*unknown parameter 'lambda'"):
        compile_theorem("qib.thm1", system(THM1), {"lambda": 0.1})
