"""Thesis Part I plugins (``thesis.*``): published examples, independent CVXPY cross-checks, bad input.

Reference values and tolerances: ``thesis_catalogue.md`` sections 1.1-1.9, 10 and 11.
Every verdict goes through the certifier (:func:`lmic.api.solve` / :func:`lmic.certify.certify`).
"""

from __future__ import annotations

from pathlib import Path

import cvxpy as cp
import numpy as np
import pytest
import yaml

from lmic.api import solve
from lmic.certify import certify
from lmic.compile import compile_theorem
from lmic.errors import DataError
from lmic.solution import Solution

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
BACKENDS = ("clarabel", "sdpa")


def _system(name: str) -> tuple[dict, dict]:
    """The example file as a dict without ``published``, and the published values as arrays."""
    doc = yaml.safe_load((EXAMPLES / name).read_text())
    pub = doc.pop("published", {}) or {}
    arrays = {k: np.array(v, dtype=float) for k, v in pub.items() if not isinstance(v, str)}
    return doc, arrays


def _certify_point(tid: str, system, values: dict, params=None):
    """Compile, pack a given point and certify it (a published point is a claim too)."""
    prob = compile_theorem(tid, system, params)
    x = prob.pack(values)
    return prob, x, certify(prob, Solution("feasible", x=x))


def _lmi(cert, name: str) -> dict:
    return next(entry for entry in cert.lmis if entry["name"] == name)


def _outcome(result) -> str:
    """``feasible`` when certified, ``infeasible`` when the backend says so, else the verdict."""
    if result.verdict == "certified":
        return "feasible"
    if result.status == "infeasible":
        return "infeasible"
    return f"{result.status}/{result.verdict}"


# -- published examples ------------------------------------------------------------------------


def test_lyapunov_published_P_and_solve():
    system, pub = _system("thesis.lyapunov.ex2_3_2.yaml")
    prob, x, cert = _certify_point("thesis.lyapunov", system, {"P": pub["P"]})
    assert cert.verdict == "certified", cert.reason
    # catalogue 10: "certificate valid, exact": an exact rational proof of both LMIs
    exact = certify(prob, Solution("feasible", x=x), exact=True)
    assert exact.label == "certified (exact)", exact.exact
    # catalogue 1.1: eig(P) = {0.3552, 0.4237, 0.7607}, eig(A^T P + P A) = {-1.6706, -1.5606, -1.2290}
    assert _lmi(cert, "P > 0")["min_eig"] == pytest.approx(0.3552, abs=1e-4)
    assert -_lmi(cert, "(2.9)")["min_eig"] == pytest.approx(-1.2290, abs=1e-4)
    for params in ({}, {"nonstrict": 1}):
        r = solve("thesis.lyapunov", system, params=params)
        assert r.verdict == "certified", r.certificate.reason


def test_thm3_2_1_example_and_published_point():
    system, pub = _system("thesis.thm3_2_1.ex3_2_1.yaml")
    r = solve("thesis.thm3_2_1", system)
    assert (r.status, r.verdict) == ("feasible", "certified")
    checks = {c["name"]: c for c in r.certificate.checks}
    assert checks["A - L C Hurwitz"]["ok"] and checks["A - L C Hurwitz"]["value"] < 0
    # the published (P, Lbar) is a certificate of (3.11): eig {-13.61, -4.85, -1.0026}
    prob, x, cert = _certify_point("thesis.thm3_2_1", system, {"P": pub["P"], "Lbar": pub["Lbar"]})
    assert cert.verdict == "certified", cert.reason
    eig = np.linalg.eigvalsh(-prob.lmis[1].matrix(x))
    np.testing.assert_allclose(eig, [-13.61, -4.85, -1.0026], atol=1e-2)
    # L = P^-1 Lbar with the rounded printed P agrees with the printed L to about 2 %
    L = prob.environment(x)["L"]
    np.testing.assert_allclose(L, [[1.7513, 0.1448], [-2.11, 2.5], [-3.563, -1.477]], atol=2e-3)
    np.testing.assert_allclose(L, pub["L"], rtol=0.025, atol=0.03)
    # printed eigenvalues of A - L C (Example 1.1.1): -1.04, -6.10 +- 0.67i
    A, C = np.array(system["data"]["A"], float), np.array(system["data"]["C"], float)
    eig_pub = np.sort_complex(np.linalg.eigvals(A - pub["L"] @ C))
    expected = np.sort_complex(pub["eig_A_LC"][:, 0] + 1j * pub["eig_A_LC"][:, 1])
    np.testing.assert_allclose(eig_pub, expected, atol=1e-2)


@pytest.mark.parametrize("backend", BACKENDS)
def test_thm3_2_2_infeasible_at_gamma_3_33(backend):
    # "there is no feasible solution for (3.14) with gamma = 3.33" (line 1241): infeasible, with
    # a Farkas certificate proven exactly (the solver's ray, on a small-denominator rational basis
    # of its face; the closed-form certificate is in tests/engine/test_engine.py)
    system, _ = _system("thesis.thm3_2_2.ex3_2_2.yaml")
    r = solve("thesis.thm3_2_2", system, backend=backend)
    assert r.status == "infeasible"
    assert r.verdict == "infeasible-certified", r.certificate.reason
    assert r.certificate.exact["proven"] and r.certificate.farkas["scope"]["basis"] == "exact"


def _sup(tid: str, system, key: str, lo: float, hi: float, tol: float, backend="clarabel") -> float:
    """Bisection on certified feasibility (the sup need not be attained)."""
    assert _outcome(solve(tid, system, params={key: lo}, backend=backend)) == "feasible"
    assert _outcome(solve(tid, system, params={key: hi}, backend=backend)) != "feasible"
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        if _outcome(solve(tid, system, params={key: mid}, backend=backend)) == "feasible":
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def test_thm3_2_2_sup_gamma_by_bisection():
    # catalogue 11.4: sup gamma of (3.14) on Example 3.2.2 = 0.9997 (margin 1e-7)
    system, _ = _system("thesis.thm3_2_2.ex3_2_2.yaml")
    assert _sup("thesis.thm3_2_2", system, "gamma", 0.5, 1.5, 2e-4) == pytest.approx(0.9997, abs=1e-3)


def test_cor3_19_example_and_published_point():
    system, pub = _system("thesis.cor3_19.ex3_2_2.yaml")
    for backend in BACKENDS:
        r = solve("thesis.cor3_19", system, backend=backend)
        assert r.verdict == "certified", (backend, r.certificate.reason)
    # published (P, L): Lbar = P L; (3.19) max eig = -0.2552 (catalogue 1.6, tolerance 1e-3)
    values = {"P": pub["P"], "Lbar": pub["P"] @ pub["L"]}
    prob, x, cert = _certify_point("thesis.cor3_19", system, values)
    assert cert.verdict == "certified", cert.reason
    assert -_lmi(cert, "(3.19)")["min_eig"] == pytest.approx(-0.2552, abs=1e-3)
    np.testing.assert_allclose(
        values["Lbar"],
        [[1.5384, -0.0014], [-40.4288, 0.4954], [7.3418, 40.9886], [0.5012, -0.1496]],
        atol=1e-3,
    )
    # the same (P, L) in (3.14) with gamma = 3.33 (gamma^2 I instead of G^T G): max eig +10.49,
    # so the certifier must reject it
    system2, _ = _system("thesis.thm3_2_2.ex3_2_2.yaml")
    _, _, cert2 = _certify_point("thesis.thm3_2_2", system2, values)
    assert cert2.verdict == "rejected"
    assert -_lmi(cert2, "(3.14)")["min_eig"] == pytest.approx(10.49, abs=1e-2)


def test_cor3_19_sup_g_by_bisection():
    # catalogue 1.6 / 11.9: sup g for G = [0 0 g 0] is 48.59 with Clarabel (SCS: 47.6); the
    # plugin takes G as data, so bisect on the data
    system, _ = _system("thesis.cor3_19.ex3_2_2.yaml")

    def feasible(g):
        data = {**system["data"], "G": [[0, 0, g, 0]]}
        return _outcome(solve("thesis.cor3_19", {**system, "data": data})) == "feasible"

    lo, hi = 40.0, 60.0
    assert feasible(lo) and not feasible(hi)
    while hi - lo > 0.02:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if feasible(mid) else (lo, mid)
    assert 0.5 * (lo + hi) == pytest.approx(48.59, abs=0.1)


def test_thm4_1_2_linear_example_and_published_gains():
    system, pub = _system("thesis.thm4_1_2_linear.ex4_1_3.yaml")
    r = solve("thesis.thm4_1_2_linear", system)
    assert r.verdict == "certified", r.certificate.reason
    assert np.abs(np.array(r.derived["M"]) @ np.array(system["data"]["D"])).max() < 1e-9
    # the published point: P = diag(1, 1, 0.22), Ybar = P Y, Kbar = P K
    P = pub["P"]
    prob, x, cert = _certify_point(
        "thesis.thm4_1_2_linear", system, {"P": P, "Ybar": P @ pub["Y"], "Kbar": P @ pub["K"]}
    )
    assert cert.verdict == "certified", cert.reason
    np.testing.assert_allclose(np.linalg.eigvalsh(-prob.lmis[1].matrix(x)), [-1.76, -1.0241, -0.9959], atol=1e-4)
    env = prob.environment(x)
    for key in ("U", "V", "E", "M", "G"):  # exact (catalogue 10: tolerance 1e-2; these are exact)
        np.testing.assert_allclose(env[key], pub[key], atol=1e-9, err_msg=key)
    for key in ("N", "L"):  # to print precision
        np.testing.assert_allclose(env[key], pub[key], atol=1.0001e-2, rtol=0, err_msg=key)
    assert np.abs(env["M"] @ np.array(system["data"]["D"], float)).max() < 1e-12


def test_thm4_1_2_sup_gamma_on_example_4_1_3_plant():
    # catalogue 1.8: the nonlinear LMI (4.24) on the Example 4.1.3 plant, sup gamma = 4.0
    system, _ = _system("thesis.thm4_1_2_linear.ex4_1_3.yaml")
    system["params"] = {"gamma": 1.0}
    assert _sup("thesis.thm4_1_2", system, "gamma", 3.0, 5.0, 1e-3) == pytest.approx(4.0, abs=2e-3)


def test_thm4_1_3_crane_feasible_for_every_gamma_and_published_gains():
    system, pub = _system("thesis.thm4_1_3.ex4_1_4_crane.yaml")
    for backend in BACKENDS:
        r = solve("thesis.thm4_1_3", system, backend=backend)
        assert r.verdict == "certified", (backend, r.certificate.reason)
    # D = D1 gives M D = 0: feasible for any gamma
    assert solve("thesis.thm4_1_3", system, params={"gamma": 50.0}).verdict == "certified"
    # the published Y, K (P = I recovers them) give the printed E, M, L, G (to 0.01) and N ~ 0
    prob, x, cert = _certify_point("thesis.thm4_1_3", system, {"P": np.eye(3), "Ybar": pub["Y"], "Kbar": pub["K"]})
    assert cert.verdict == "certified", cert.reason
    env = prob.environment(x)
    for key in ("U", "V", "E", "M", "G"):
        np.testing.assert_allclose(env[key], pub[key], atol=1e-9, err_msg=key)
    np.testing.assert_allclose(env["L"], pub["L"], atol=1.0001e-2, rtol=0)
    assert np.abs(env["N"]).max() <= 1.0001e-3


# -- independent CVXPY formulations on small random systems ------------------------------------

_M = 1e-7  # the catalogue's strict margin


def _cvx_status(constraints, objective=None):
    prob = cp.Problem(objective or cp.Minimize(0), constraints)
    prob.solve(solver="CLARABEL")
    return prob.status, prob.value


def _sym(X):
    return 0.5 * (X + X.T)


def _ref_luenberger(A, C, G2=None):
    """max s with [A'P + PA - C'Lb' - Lb C + s G2, P; P, -I] < 0 (thesis (3.14)/(3.19)), or the
    feasibility of (3.11) when ``G2`` is None. Written from the catalogue, not from the plugin."""
    n, p = A.shape[0], C.shape[0]
    P = cp.Variable((n, n), symmetric=True)
    Lb = cp.Variable((n, p))
    core = A.T @ P + P @ A - C.T @ Lb.T - Lb @ C
    if G2 is None:  # homogeneous: the margin may be normalised to I
        return _cvx_status([P >> np.eye(n), _sym(core) << -np.eye(n)])
    cons = [P >> _M * np.eye(n)]
    s = cp.Variable()
    big = cp.bmat([[core + s * G2, P], [P, -np.eye(n)]])
    cons += [_sym(big) << -_M * np.eye(2 * n), s >= 0]
    return _cvx_status(cons, cp.Maximize(s))


def _observable_pair(rng, n, p, unstable_hidden: bool):
    """(A, C); with ``unstable_hidden`` an unstable mode is unobservable (undetectable)."""
    A = rng.normal(size=(n, n))
    C = rng.normal(size=(p, n))
    if unstable_hidden:
        A[:, -1] = 0.0
        A[-1, :] = 0.0
        A[-1, -1] = 0.5
        C[:, -1] = 0.0
    return A, C


def _sys(**data):
    return {"lmic": 1, "data": {k: np.asarray(v, float).tolist() for k, v in data.items()}, "params": {}}


@pytest.mark.parametrize("seed", range(4))
def test_thm3_2_1_matches_cvxpy(seed):
    rng = np.random.default_rng(seed)
    A, C = _observable_pair(rng, 3, 1, unstable_hidden=seed % 2 == 1)
    status, _ = _ref_luenberger(A, C)
    expected = "feasible" if status == "optimal" else "infeasible"
    assert expected == ("infeasible" if seed % 2 else "feasible")  # the reference decides both ways
    system = _sys(A=A, B=np.ones((3, 1)), C=C)
    for backend in BACKENDS:
        assert _outcome(solve("thesis.thm3_2_1", system, backend=backend)) == expected, backend


@pytest.mark.parametrize("seed", range(2))
def test_lyapunov_matches_cvxpy(seed):
    rng = np.random.default_rng(100 + seed)
    A = rng.normal(size=(3, 3)) - (3.0 if seed == 0 else -1.0) * np.eye(3)
    P = cp.Variable((3, 3), symmetric=True)
    status, _ = _cvx_status([P >> np.eye(3), _sym(A.T @ P + P @ A) << -np.eye(3)])
    expected = "feasible" if status == "optimal" else "infeasible"
    assert expected == ("feasible" if np.linalg.eigvals(A).real.max() < 0 else "infeasible")
    assert expected == ("feasible", "infeasible")[seed]
    for backend in BACKENDS:
        assert _outcome(solve("thesis.lyapunov", _sys(A=A), backend=backend)) == expected


def _check_threshold(tid, system, key, sup_ref, scale=1.0):
    """Certified at 0.9 of the reference supremum, infeasible at 1.1 of it, on both backends."""
    for backend in BACKENDS:
        below = solve(tid, system, params={key: 0.9 * sup_ref * scale}, backend=backend)
        above = solve(tid, system, params={key: 1.1 * sup_ref * scale}, backend=backend)
        assert _outcome(below) == "feasible", (backend, below.certificate.reason)
        assert _outcome(above) == "infeasible", (backend, above.status)


@pytest.mark.parametrize("seed", range(2))
def test_thm3_2_2_and_cor3_19_match_cvxpy(seed):
    rng = np.random.default_rng(200 + seed)
    A = rng.normal(size=(3, 3)) - 2.0 * np.eye(3)
    C = rng.normal(size=(2, 3))
    status, s = _ref_luenberger(A, C, np.eye(3))
    assert status == "optimal" and s > 0
    system = _sys(A=A, B=np.ones((3, 1)), C=C)
    _check_threshold("thesis.thm3_2_2", {**system, "params": {"gamma": 1.0}}, "gamma", np.sqrt(s))
    G0 = rng.normal(size=(1, 3))
    status, s = _ref_luenberger(A, C, G0.T @ G0)
    assert status == "optimal" and s > 0
    # G = g G0: the threshold on g; the plugin takes G as data, so scale the matrix
    for factor, expected in ((0.9, "feasible"), (1.1, "infeasible")):
        sysg = _sys(A=A, B=np.ones((3, 1)), C=C, G=factor * np.sqrt(s) * G0)
        for backend in BACKENDS:
            assert _outcome(solve("thesis.cor3_19", sysg, backend=backend)) == expected, backend


def _uio_uv(C, Dui):
    CD = C @ Dui
    pinv = np.linalg.pinv(CD)
    return -Dui @ pinv, np.eye(C.shape[0]) - CD @ pinv


def _ref_ct_uio(A, C, D, nonlinear: bool):
    """Thesis (4.24) (max s = gamma^2) or (4.28) (feasibility), from the catalogue."""
    n, p = A.shape[0], C.shape[0]
    U, V = _uio_uv(C, D)
    P = cp.Variable((n, n), symmetric=True)
    Yb = cp.Variable((n, p))
    Kb = cp.Variable((n, p))
    W = (np.eye(n) + U @ C) @ A
    d11 = W.T @ P + P @ W + (V @ C @ A).T @ Yb.T + Yb @ (V @ C @ A) - C.T @ Kb.T - Kb @ C
    if not nonlinear:  # homogeneous: the margin may be normalised to I
        return _cvx_status([P >> np.eye(n), _sym(d11) << -np.eye(n)])
    cons = [P >> _M * np.eye(n)]
    s = cp.Variable()
    d12 = P @ (np.eye(n) + U @ C) + Yb @ (V @ C)
    big = cp.bmat([[d11 + s * np.eye(n), d12], [d12.T, -np.eye(n)]])
    return _cvx_status(cons + [_sym(big) << -_M * np.eye(2 * n), s >= 0], cp.Maximize(s))


#: one output, one unknown input: the unknown-input observer exists iff the two invariant zeros
#: of (A, D, C) are stable; seeds 300, 301 have a zero in the right half-plane, 302, 306 do not
UIO_SEEDS = (300, 301, 302, 306)


def _uio_case(seed):
    rng = np.random.default_rng(seed)
    return rng.normal(size=(3, 3)), rng.normal(size=(1, 3)), rng.normal(size=(3, 1))


@pytest.mark.parametrize("seed", UIO_SEEDS)
def test_thm4_1_2_linear_matches_cvxpy(seed):
    A, C, D = _uio_case(seed)
    status, _ = _ref_ct_uio(A, C, D, nonlinear=False)
    expected = "feasible" if status == "optimal" else "infeasible"
    system = _sys(A=A, B=np.ones((3, 1)), C=C, D=D)
    for backend in BACKENDS:
        assert _outcome(solve("thesis.thm4_1_2_linear", system, backend=backend)) == expected, backend


def test_thm4_1_2_linear_cases_cover_both_outcomes():
    outcomes = [_ref_ct_uio(*_uio_case(seed), nonlinear=False)[0] for seed in UIO_SEEDS]
    assert outcomes == ["infeasible", "infeasible", "optimal", "optimal"]


def test_thm4_1_2_matches_cvxpy():
    rng = np.random.default_rng(400)
    A = rng.normal(size=(3, 3)) - 2.0 * np.eye(3)
    C, D = rng.normal(size=(2, 3)), rng.normal(size=(3, 1))
    status, s = _ref_ct_uio(A, C, D, nonlinear=True)
    assert status == "optimal" and s > 0
    system = {**_sys(A=A, B=np.ones((3, 1)), C=C, D=D), "params": {"gamma": 1.0}}
    _check_threshold("thesis.thm4_1_2", system, "gamma", np.sqrt(s))


def test_thm4_1_3_matches_cvxpy():
    rng = np.random.default_rng(500)
    n, p = 3, 2
    A = rng.normal(size=(n, n))
    A *= 0.8 / max(abs(np.linalg.eigvals(A)))
    C, D, D1 = rng.normal(size=(p, n)), rng.normal(size=(n, 1)), rng.normal(size=(n, 1))
    U, V = _uio_uv(C, D1)
    P = cp.Variable((n, n), symmetric=True)
    Yb, Kb, s = cp.Variable((n, p)), cp.Variable((n, p)), cp.Variable()
    d13 = A.T @ P + (U @ C @ A).T @ P + (V @ C @ A).T @ Yb.T - C.T @ Kb.T
    d23 = D.T @ P + (U @ C @ D).T @ P + (V @ C @ D).T @ Yb.T
    big = cp.bmat(
        [
            [-P + s * np.eye(n), np.zeros((n, 1)), d13],
            [np.zeros((1, n)), -np.eye(1), d23],
            [d13.T, d23.T, -P],
        ]
    )
    status, s_val = _cvx_status([_sym(big) << -_M * np.eye(2 * n + 1), s >= 0], cp.Maximize(s))
    assert status == "optimal" and s_val > 0
    system = {**_sys(A=A, B=np.ones((n, 1)), C=C, D=D, D1=D1), "params": {"gamma": 1.0}}
    _check_threshold("thesis.thm4_1_3", system, "gamma", np.sqrt(s_val))


# -- bad input ---------------------------------------------------------------------------------


def test_bad_input_names_theorem_key_and_rule():
    system, _ = _system("thesis.thm3_2_2.ex3_2_2.yaml")
    with pytest.raises(DataError, match=r"thesis\.thm3_2_2.*gamma = -1 .*outside its domain"):
        compile_theorem("thesis.thm3_2_2", system, {"gamma": -1})
    uio, _ = _system("thesis.thm4_1_2_linear.ex4_1_3.yaml")
    no_c = {**uio, "data": {k: v for k, v in uio["data"].items() if k != "C"}}
    with pytest.raises(DataError, match=r"thesis\.thm4_1_2_linear.*missing data 'C'"):
        compile_theorem("thesis.thm4_1_2_linear", no_c)
    hidden = {**uio, "data": {**uio["data"], "D": [[0], [0], [1]]}}  # C D = 0: not decoupled
    with pytest.raises(DataError, match=r"thesis\.thm4_1_2_linear.*'D'.*full column rank"):
        compile_theorem("thesis.thm4_1_2_linear", hidden)
    cor, _ = _system("thesis.cor3_19.ex3_2_2.yaml")
    bad_g = {**cor, "data": {**cor["data"], "G": [[0, 0, 3.33]]}}
    with pytest.raises(DataError, match=r"thesis\.cor3_19.*'G' has shape 1x3"):
        compile_theorem("thesis.cor3_19", bad_g)
