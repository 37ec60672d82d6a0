"""nonuniform.thm1 (CT Lipschitz observer, nonuniform sampling): examples, audits, random systems.

Reference values: seeds catalogue sections 4 and 6.
"""

from __future__ import annotations

import cvxpy as cp
import numpy as np
import pytest
from seeds_helpers import (
    BACKENDS,
    compare_lmi,
    cvx_feasible,
    lmic_feasible,
    random_point,
    solve,
    system,
)

from lmic.compile import compile_theorem
from lmic.errors import DataError

ARM = "nonuniform.thm1.flexible-arm"
ARM_STD_C = "nonuniform.thm1.flexible-arm-stdC"
CHUA = "nonuniform.thm1.chua"
L_ARM_PUB = [[-52.0, -0.5], [20.7, -6.4], [-1.2, -0.3], [-9.7, 2.0]]
L_ARM_DECIMAL = [[-5.2, -0.5], [20.7, -6.4], [-1.2, -0.3], [-9.7, 2.0]]
L_CHUA_PUB = [[-0.9], [-1.3], [1.2]]


# -- independent block matrices (catalogue 4.1), numpy or cvxpy -----------------------------------


def _full(upper, bm):
    k = len(upper)
    return bm([[upper[i][j] if j >= i else upper[j][i].T for j in range(k)] for i in range(k)])


def lmi9(A, C, G, H, g, d, P, Lt, N1, N2, N3, bm):
    n, m = A.shape[0], G.shape[1]
    Z = np.zeros
    top = P @ A + A.T @ P + g**2 * H.T @ H - P - N1 - N1.T
    a = _full(
        [
            [
                top + d * (P @ A + A.T @ P),
                (1 + d) * Lt @ C + P - d * A.T @ P + N1 - N2.T,
                (1 + d) * P @ G - N3.T,
                d * A.T @ P,
            ],
            [None, -d * (Lt @ C + C.T @ Lt.T) - P + N2 + N2.T, -d * P @ G + N3.T, d * C.T @ Lt.T],
            [None, None, -np.eye(m), d * G.T @ P],
            [None, None, None, -d * P],
        ],
        bm,
    )
    b = _full(
        [
            [top, Lt @ C + P + N1 - N2.T, P @ G - N3.T, d * A.T @ P, d * N1],
            [None, -P + N2 + N2.T, N3.T, d * C.T @ Lt.T, d * N2],
            [None, None, -np.eye(m), d * G.T @ P, d * N3],
            [None, None, None, -d * P, Z((n, n))],
            [None, None, None, None, -d * P],
        ],
        bm,
    )
    return a, b


def arrays(name):
    return {k: np.array(v, dtype=float) for k, v in system(name)["data"].items()}


def random_system(seed, n=3, q=1, m=1):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    return {
        "A": A,
        "C": rng.standard_normal((q, n)),
        "G": rng.standard_normal((n, m)),
        "H": rng.standard_normal((m, n)),
    }


def sysdict(D, **params):
    return {"lmic": 1, "data": {k: v.tolist() for k, v in D.items()}, "params": params}


# -- published examples ---------------------------------------------------------------------------


@pytest.mark.parametrize("backend", BACKENDS)
def test_flexible_arm_design_is_feasible(backend):
    r = solve("nonuniform.thm1", system(ARM), backend=backend)
    assert r.verdict == "certified"
    D = arrays(ARM)
    assert max(np.linalg.eigvals(D["A"] + np.array(r.derived["L"]) @ D["C"]).real) < 0


def test_flexible_arm_published_gain_fails():
    D = arrays(ARM)
    # with the printed C, A + L_pub C has the unstable eigenvalue +62.7
    eig = np.linalg.eigvals(D["A"] + np.array(L_ARM_PUB) @ D["C"])
    assert max(eig.real) == pytest.approx(62.7, abs=0.1)
    for backend in BACKENDS:
        r = solve("nonuniform.thm1", system(ARM, data={"L": L_ARM_PUB}), {"fixed_L": 1}, backend=backend)
        assert r.verdict == "infeasible-certified" and r.certificate.exact["proven"]  # exact Farkas proof
    # with C = [I2 0] A + L_pub C is Hurwitz, but (9) is still infeasible
    Dstd = arrays(ARM_STD_C)
    assert max(np.linalg.eigvals(Dstd["A"] + np.array(L_ARM_PUB) @ Dstd["C"]).real) < 0
    r = solve("nonuniform.thm1", system(ARM_STD_C, data={"L": L_ARM_PUB}), {"fixed_L": 1})
    # an exact rational Farkas certificate (the policy proves up to MAX_RAY_PROOFS rays exactly)
    assert r.verdict == "infeasible-certified" and "exact rational Farkas" in r.certificate.reason


def test_flexible_arm_decimal_corrected_gain_is_certified():
    d = system(ARM_STD_C, data={"L": L_ARM_DECIMAL})
    for backend in BACKENDS:
        assert solve("nonuniform.thm1", d, {"fixed_L": 1}, backend=backend).verdict == "certified"
    # certified up to gamma = 4.164 (delta_bar = 0.1)
    assert solve("nonuniform.thm1", d, {"fixed_L": 1, "gamma": 4.15}).verdict == "certified"
    # Clarabel (the helpers' backend): its rays are not proven exactly here
    assert solve("nonuniform.thm1", d, {"fixed_L": 1, "gamma": 4.18}).verdict == "infeasible-bounded"


@pytest.mark.parametrize("backend", BACKENDS)
def test_chua_design_feasible_published_gain_not(backend):
    r = solve("nonuniform.thm1", system(CHUA), backend=backend)
    assert r.verdict == "certified"
    r = solve("nonuniform.thm1", system(CHUA, data={"L": L_CHUA_PUB}), {"fixed_L": 1}, backend=backend)
    # every backend's answer is proven exactly (a rational basis of a ray's face; with Clarabel
    # the ray of its fixed-margin reduction, after the max-margin one's proof fails)
    assert r.verdict == "infeasible-certified" and "exact rational Farkas" in r.certificate.reason
    d = system("nonuniform.thm1.chua-gamma2.95", data={"L": L_CHUA_PUB})
    assert solve("nonuniform.thm1", d, {"fixed_L": 1}, backend=backend).verdict == "certified"


def test_chua_published_gain_certified_only_up_to_gamma_3_227():
    d = system(CHUA, data={"L": L_CHUA_PUB})
    assert solve("nonuniform.thm1", d, {"fixed_L": 1, "gamma": 3.22}).verdict == "certified"
    assert solve("nonuniform.thm1", d, {"fixed_L": 1, "gamma": 3.235}).verdict == "infeasible-certified"
    D = arrays(CHUA)
    assert max(np.linalg.eigvals(D["A"] + np.array(L_CHUA_PUB) @ D["C"]).real) < 0  # Hurwitz anyway


def test_sup_gamma_of_the_designs():
    """Reference sup gamma: 4.521 (arm, delta_bar = 0.1), 9.748 (Chua, delta_bar = 0.05)."""
    assert solve("nonuniform.thm1", system(ARM), {"gamma": 4.5}).verdict == "certified"
    assert solve("nonuniform.thm1", system(ARM), {"gamma": 4.55}).status == "infeasible"
    assert solve("nonuniform.thm1", system(CHUA), {"gamma": 9.7}).verdict == "certified"
    assert solve("nonuniform.thm1", system(CHUA), {"gamma": 9.8}).status == "infeasible"


# -- random systems -------------------------------------------------------------------------------


def test_random_lmis_match_catalogue():
    rng = np.random.default_rng(7)
    D = random_system(1, n=3, q=2, m=2)
    prob = compile_theorem("nonuniform.thm1", sysdict(D, gamma=1.3, delta_bar=0.2))
    x, v = random_point(prob, rng)
    a, b = lmi9(D["A"], D["C"], D["G"], D["H"], 1.3, 0.2, v["P"], v["Lt"], v["N1"], v["N2"], v["N3"], np.block)
    compare_lmi(prob, "(9a)", x, a)
    compare_lmi(prob, "(9b)", x, b)
    L = rng.standard_normal((3, 2))
    prob = compile_theorem("nonuniform.thm1", {**sysdict({**D, "L": L}, gamma=1.3, delta_bar=0.2, fixed_L=1)})
    x, v = random_point(prob, rng)
    a, b = lmi9(D["A"], D["C"], D["G"], D["H"], 1.3, 0.2, v["P"], v["P"] @ L, v["N1"], v["N2"], v["N3"], np.block)
    compare_lmi(prob, "(9a)", x, a)
    compare_lmi(prob, "(9b)", x, b)


def test_random_status_matches_cvxpy():
    """(9) is not homogeneous (-I blocks): no box needed. CVXPY's SCS needs 1-4 s a solve on
    these 16 x 16 LMIs, so the references are CVXPY's Clarabel and CVXOPT (interior point)."""
    seen = set()
    for seed in range(2):
        D = random_system(80 + seed)
        for gamma, delta in ((0.2, 0.05), (3.0, 0.5)):
            n, q, m = 3, 1, 1
            P, Lt = cp.Variable((n, n), symmetric=True), cp.Variable((n, q))
            N1, N2, N3 = cp.Variable((n, n)), cp.Variable((n, n)), cp.Variable((m, n))
            a, b = lmi9(D["A"], D["C"], D["G"], D["H"], gamma, delta, P, Lt, N1, N2, N3, cp.bmat)
            ref = {s: cvx_feasible([a, b], [P], solver=s) for s in ("CLARABEL", "CVXOPT")}
            assert ref["CLARABEL"] is not None
            assert ref["CVXOPT"] == ref["CLARABEL"]
            d = sysdict(D, gamma=gamma, delta_bar=delta)
            for backend in BACKENDS:
                assert lmic_feasible(solve("nonuniform.thm1", d, backend=backend)) == ref["CLARABEL"]
            seen.add(ref["CLARABEL"])
    assert seen == {True, False}


# -- bad input ------------------------------------------------------------------------------------


def test_bad_input_messages():
    with pytest.raises(DataError, match=r"nonuniform\.thm1.*gamma = -3\.3.*outside its domain"):
        compile_theorem("nonuniform.thm1", system(ARM), {"gamma": -3.3})
    with pytest.raises(DataError, match=r"nonuniform\.thm1.*delta_bar = 0.*outside its domain"):
        compile_theorem("nonuniform.thm1", system(ARM), {"delta_bar": 0})
    with pytest.raises(DataError, match=r"nonuniform\.thm1.*'H'.*shape 1x3"):
        compile_theorem("nonuniform.thm1", system(ARM, data={"H": [[0.0, 0.0, 1.0]]}))
    bad = system(CHUA)
    del bad["data"]["G"]
    with pytest.raises(DataError, match=r"nonuniform\.thm1.*missing data 'G'"):
        compile_theorem("nonuniform.thm1", bad)
    with pytest.raises(DataError, match=r"nonuniform\.thm1.*missing parameter 'delta_bar'"):
        d = system(CHUA)
        del d["params"]["delta_bar"]
        compile_theorem("nonuniform.thm1", d)
