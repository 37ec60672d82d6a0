"""uir plugins (thesis Paper E): published example, reference values, random cross-checks, bad input.

Reference values: thesis catalogue sections 6.1-6.3, 10 (Paper E row) and 11.6, 11.9.
"""

from __future__ import annotations

import cvxpy as cp
import numpy as np
import pytest
import yaml
from delshad_helpers import (
    MARGIN,
    bisect,
    cvx_max_margin,
    cvx_min,
    exact_projector,
    example,
    pinv,
    point,
    uir_big_block,
)

from lmic.api import solve
from lmic.backends.base import SolveOptions
from lmic.compile import compile_theorem
from lmic.errors import DataError
from lmic.system import UnusedDataNote

EX31 = "uir.thm3_1.rossler_published_gains.yaml"
EX51 = "uir.thm5_1.rossler.yaml"
EX51C = "uir.thm5_1.rossler_F_row1_corrected.yaml"
N_PRINTED = np.array([[401, -100, -201], [19.6, -5.7, -9.8], [803.6, -200, -402.8]])
SCS_FAST = SolveOptions(tol=1e-6, max_iter=5000)


# -- Theorem 3.1 at the printed observer (51) ---------------------------------------------------


def test_thm3_1_published_gains_infeasible_at_claimed_gamma():
    """The paper claims feasibility at gamma0 = 0.259; (11) at the printed gains is infeasible."""
    r = solve("uir.thm3_1", example(EX31), backend="clarabel")
    assert r.status == "infeasible"
    assert r.certificate.verdict == "infeasible-certified", r.certificate.reason
    assert r.certificate.exact["proven"]  # global: the Farkas ray is proven in rational arithmetic


def _hinf_norm(N, M, J):
    """sup_w sigma_max(J (jw I - N)^-1 M) on a dense frequency grid (N Hurwitz)."""
    ws = np.concatenate([[0.0], np.logspace(-3, 4, 4000)])
    eye = np.eye(N.shape[0])
    return max(np.linalg.norm(J @ np.linalg.solve(1j * w * eye - N, M), 2) for w in ws)


def test_thm3_1_threshold_is_the_bounded_real_lemma():
    """(11) at the printed gains holds iff gamma < 1/||J (sI - N)^-1 M||_inf = 0.0401 (11.6)."""
    data = yaml.safe_load(open(example(EX31)))["data"]
    N, J, M = (np.array(data[k], dtype=float) for k in ("N", "J", "M"))
    bound = 1 / _hinf_norm(N, M, J)
    assert bound == pytest.approx(0.0401, abs=2e-4)

    def feasible(g):
        return solve("uir.thm3_1", example(EX31), {"gamma": g}).certificate.verdict == "certified"

    lo, hi = bisect(feasible, 0.03, 0.05, 2e-4)
    assert lo == pytest.approx(bound, abs=5e-4)
    assert solve("uir.thm3_1", example(EX31), {"gamma": 0.041}).certificate.verdict == "infeasible-certified"


# -- Theorem 5.1 on the Rossler example --------------------------------------------------------------


def test_thm5_1_structural_gains():
    """M exact from R; J, E exact; printed F gives an unstable N, F(1,:) = [1 0] the printed N, L."""
    for name, corrected in ((EX51, False), (EX51C, True)):
        prob = compile_theorem("uir.thm5_1", example(name))
        assert np.allclose(prob.data["M"], [[-1, 0, 0], [0, 2, -1], [-2, -1, 0]], atol=1e-9)
        assert not np.any(prob.data["beta1"]) and not np.any(prob.data["beta2"])
        env = prob.environment(point(prob, P=np.eye(3), rho=1.0, mubar=1.0))
        J_pub = [[-1, 0, 0], [2, 0, -1], [4, -1, -2], [1, 0, 0], [-2, 0, 1]]
        assert np.allclose(env["J"], J_pub, atol=1e-9)
        assert np.allclose(env["E"], [[0, 0], [0, 0], [0, 0], [0, 1], [1, 0]], atol=1e-9)
        if corrected:
            assert np.allclose(env["N"], N_PRINTED, atol=0.011)
            assert np.allclose(env["L"], [[0, -1], [2, 2], [-1, -3]], atol=0.011)
            assert max(np.linalg.eigvals(env["N"]).real) < 0
        else:
            assert max(np.linalg.eigvals(env["N"]).real) == pytest.approx(0.17, abs=0.01)
            assert np.allclose(env["L"], [[-1, 0], [2, 1.99], [-3, -1]], atol=0.011)


@pytest.mark.parametrize("name", [EX51, EX51C])
def test_thm5_1_example_infeasible_and_scs_success_rejected(name):
    """The claimed feasibility does not reproduce: Clarabel proves infeasibility; SCS returns a
    point (status inaccurate) that the certifier must reject (catalogue 6.3, 11.9)."""
    r = solve("uir.thm5_1", example(name), backend="clarabel")
    assert r.status == "infeasible"
    assert r.certificate.verdict == "infeasible-certified", r.certificate.reason  # the ray, proven exactly
    s = solve("uir.thm5_1", example(name), backend="scs", options=SCS_FAST)
    first = s.attempts[0]  # SCS's own point is rejected; its policy then finds a bounded ray
    assert first["status"] in ("optimal", "feasible", "inaccurate") and first["verdict"] == "rejected"
    assert s.verdict != "certified" and s.exit_code() != 0  # nothing certifies an infeasible problem


def test_thm5_1_without_side_condition_gives_no_real_gamma():
    """Without (40) the optimum has rho ~ 916 > 1: no real gamma; the certificate rejects it."""
    r = solve("uir.thm5_1", example(EX51C), {"rho_bound": 0}, backend="clarabel")
    assert r.variables["rho"] == pytest.approx(916.0, rel=5e-3)
    assert r.certificate.verdict == "rejected"
    failed = [c["name"] for c in r.certificate.checks if not c["ok"]]
    assert any(name.startswith("(40)") for name in failed)


def test_thm4_1_example_infeasible():
    """Theorem 4.1 with (40) is infeasible on the example too (catalogue 11.6), whatever mu."""
    system = yaml.safe_load(open(example(EX51C)))
    system["params"] = {"gamma0": 0.259, "mu": 10.0}
    r = solve("uir.thm4_1", system, backend="clarabel")
    assert r.status == "infeasible" and r.certificate.verdict == "infeasible-certified"


# -- random systems against the LMIs written directly in CVXPY -------------------------------------


def _system(data, **params):
    return {"lmic": 1, "data": {k: np.asarray(v).tolist() for k, v in data.items()}, "params": params}


def _hurwitz(rng, k):
    X = rng.normal(size=(k, k))
    return X - (max(np.linalg.eigvals(X).real) + 1.0) * np.eye(k)


#: the random-plant tests compare lmic's max-margin optimum with CVXPY's: the max-margin reduction
#: named explicitly (by default the policy may prove infeasibility from another reduction's ray,
#: whose margin is its fixed one)
MAX_MARGIN = SolveOptions(strict="max-margin")


def _agree(r, t_ref):
    assert t_ref is not None
    # the max-margin optimum can be a supremum (variables unbounded): 1 % on the margin
    assert r.solution.margin == pytest.approx(t_ref, rel=1e-2, abs=1e-5)
    if t_ref > 1e-5:
        assert r.verdict == "certified" and r.certificate.verdict == "certified"
    else:
        assert t_ref < -1e-5 and r.status == "infeasible"


def _random_gains(seed):
    rng = np.random.default_rng(seed)
    q1, nh, n, p = 2, 3, 2, 2
    return {
        "N": _hurwitz(rng, q1),
        "L": rng.normal(size=(q1, p)),
        "M": 0.3 * rng.normal(size=(q1, n)),
        "J": 0.3 * rng.normal(size=(nh, q1)),
        "E": 0.3 * rng.normal(size=(nh, p)),
        "D1": rng.normal(size=(n, 1)),
        "D2": rng.normal(size=(p, 1)),
    }


def _cvx_thm3_1(g, gamma):
    N, J, M = g["N"], g["J"], g["M"]
    q1, n = M.shape
    P = cp.Variable((q1, q1), symmetric=True)
    Gam = cp.Variable((n, n), symmetric=True)
    F11 = cp.bmat([[N.T @ P + P @ N + gamma**2 * J.T @ J, P @ M], [(P @ M).T, -Gam]])
    return cvx_max_margin([-P, Gam - np.eye(n), F11])


def _cvx_thm3_2(g, gamma, mu):
    N, L, M, J, E, D1, D2 = (g[k] for k in ("N", "L", "M", "J", "E", "D1", "D2"))
    q1, n = M.shape
    nw = D1.shape[1]
    c = 1 + gamma**2
    P = cp.Variable((q1, q1), symmetric=True)
    Gam = cp.Variable((n, n), symmetric=True)
    a11 = N.T @ P + P @ N + c * J.T @ J
    a13 = P @ (L @ D2 - M @ D1) + c * J.T @ E @ D2
    a33 = c * D2.T @ E.T @ E @ D2 - mu**2 * np.eye(nw)
    Phi = cp.bmat([[a11, P @ M, a13], [(P @ M).T, -Gam, np.zeros((n, nw))], [a13.T, np.zeros((nw, n)), a33]])
    return cvx_max_margin([-P, Gam - np.eye(n), Phi])


@pytest.mark.parametrize("backend", ["clarabel", "sdpa"])
@pytest.mark.parametrize("seed,gamma", [(1, 0.1), (2, 20.0)])
def test_thm3_1_random_matches_cvxpy(seed, gamma, backend):
    g = _random_gains(seed)
    data = {k: g[k] for k in ("N", "J", "M")}
    _agree(solve("uir.thm3_1", _system(data, gamma=gamma), backend=backend, options=MAX_MARGIN), _cvx_thm3_1(g, gamma))


@pytest.mark.parametrize("backend", ["clarabel", "sdpa"])
@pytest.mark.parametrize("seed,gamma,mu", [(3, 0.1, 20.0), (4, 0.1, 0.05)])
def test_thm3_2_random_matches_cvxpy(seed, gamma, mu, backend):
    g = _random_gains(seed)
    _agree(
        solve("uir.thm3_2", _system(g, gamma=gamma, mu=mu), backend=backend, options=MAX_MARGIN),
        _cvx_thm3_2(g, gamma, mu),
    )


def _random_plant(seed):
    rng = np.random.default_rng(seed)
    n, h, p, q1 = 2, 1, 2, 2
    return {
        "A": _hurwitz(rng, n),
        "B": rng.normal(size=(n, 1)),
        "C": rng.normal(size=(p, n)),
        "F": rng.normal(size=(n, h)),
        "G": rng.normal(size=(p, h)),
        "D1": rng.normal(size=(n, 1)),
        "D2": rng.normal(size=(p, 1)),
        "R": rng.normal(size=(q1, n + h)),
    }


def _cvx_robust(d, gamma0, mu=None, lam=None):
    """Theorem 4.1 (mu given) or 5.1 (lam given), written from catalogue 6.2-6.3."""
    A, C, F, G, R, D1, D2 = (d[k] for k in ("A", "C", "F", "G", "R", "D1", "D2"))
    n, h, p, q1, nw = A.shape[0], F.shape[1], C.shape[0], R.shape[0], D1.shape[1]
    nh = n + h
    eta = np.hstack([np.eye(n), np.zeros((n, h))])
    Abar, Cbar = np.hstack([A, F]), np.hstack([C, G])
    M = (R @ pinv(np.vstack([eta, Cbar])))[:, :n]
    T = np.vstack([M @ eta, Cbar])
    Tp, Pi = pinv(T), exact_projector(T)
    a1, a2, b1, b2 = Tp[:, :q1], Tp[:, q1:], Pi[:, :q1], Pi[:, q1:]
    P = cp.Variable((q1, q1), symmetric=True)
    Gam = cp.Variable((n, n), symmetric=True)
    Yb1, Y2 = cp.Variable((q1, q1 + p)), cp.Variable((nh, q1 + p))
    rho = cp.Variable()
    PN = P @ M @ Abar @ a1 + Yb1 @ b1
    a13 = P @ M @ Abar @ a2 @ D2 + Yb1 @ b2 @ D2 - P @ M @ D1
    a14 = a1.T + b1.T @ Y2.T
    a34 = D2.T @ a2.T + D2.T @ b2.T @ Y2.T
    if lam is None:
        a33, objective, scalars = -(mu**2) * np.eye(nw), rho, [rho]
    else:
        mubar = cp.Variable()
        a33, objective, scalars = -mubar * np.eye(nw), lam * rho + (1 - lam) * mubar, [rho, mubar]
    big = uir_big_block(PN, P, M, Gam, a13, a14, a33, a34, rho, n, nw, nh)
    side = [1 - (1 + gamma0**2) * rho >= MARGIN]  # (40), strict
    return cvx_min(objective, [-P, Gam - np.eye(n), big], scalars, side)


def _check_min(r, ref):
    status, value = ref
    if status == "infeasible":
        assert r.status == "infeasible"
        return
    assert status == "optimal"
    assert r.status in ("optimal", "inaccurate") and r.certificate.verdict == "certified", r.certificate.reason
    assert r.objective == pytest.approx(value, rel=1e-3, abs=1e-6)


@pytest.mark.parametrize("backend", ["clarabel", "sdpa"])
@pytest.mark.parametrize("seed,gamma0", [(5, 0.1), (8, 0.1), (8, 3.0)])
def test_thm4_1_random_matches_cvxpy(seed, gamma0, backend):
    d = _random_plant(seed)
    r = solve("uir.thm4_1", _system(d, gamma0=gamma0, mu=5.0), backend=backend)
    _check_min(r, _cvx_robust(d, gamma0, mu=5.0))
    if r.status == "optimal":
        assert r.derived["gamma"] == pytest.approx(np.sqrt(1 / r.objective - 1))


@pytest.mark.parametrize("backend", ["clarabel", "sdpa"])
@pytest.mark.parametrize("seed,lam,gamma0", [(5, 0.5, 0.1), (10, 0.9, 0.1), (5, 0.5, 3.0)])
def test_thm5_1_random_matches_cvxpy(seed, lam, gamma0, backend):
    d = _random_plant(seed)
    r = solve("uir.thm5_1", _system(d, gamma0=gamma0, **{"lambda": lam}), backend=backend)
    _check_min(r, _cvx_robust(d, gamma0, lam=lam))


# -- bad input -------------------------------------------------------------------------------------


def test_bad_input():
    d = _random_plant(5)
    with pytest.raises(DataError, match=r"uir\.thm5_1.*parameter lambda = 1.5 is outside its domain \[0, 1\]"):
        compile_theorem("uir.thm5_1", _system(d, gamma0=0.1, **{"lambda": 1.5}))
    with pytest.raises(DataError, match=r"uir\.thm5_1.*parameter gamma0 = -0.1 is outside"):
        compile_theorem("uir.thm5_1", _system(d, gamma0=-0.1, **{"lambda": 0.5}))
    # a parameter of another theorem (uir.thm5_1's lambda) in the plant file: a note, as extra data
    with pytest.warns(UnusedDataNote, match=r"uir\.thm4_1.*parameter 'lambda' not used by the theorem"):
        compile_theorem("uir.thm4_1", _system(d, gamma0=0.1, mu=1.0, **{"lambda": 0.5}))
    with pytest.raises(DataError, match=r"uir\.thm4_1.*unknown parameter 'lambda' \(the theorem takes"):
        compile_theorem("uir.thm4_1", _system(d, gamma0=0.1, mu=1.0), {"lambda": 0.5})  # asked for by the caller
    with pytest.raises(DataError, match=r"uir\.thm4_1.*unknown parameter 'gama0' \(did you mean 'gamma0'"):
        compile_theorem("uir.thm4_1", _system(d, gama0=0.1, mu=1.0))  # a typo
    with pytest.raises(DataError, match=r"uir\.thm4_1.*missing data 'R'"):
        compile_theorem("uir.thm4_1", _system({k: v for k, v in d.items() if k != "R"}, gamma0=0.1, mu=1.0))
    with pytest.raises(DataError, match=r"uir\.thm5_1.*rho_bound = '2' is not one of 0, 1"):
        compile_theorem("uir.thm5_1", _system(d, gamma0=0.1, rho_bound=2, **{"lambda": 0.5}))
