"""Paper A plugins (``delay_a.thm3_1``, ``delay_a.thm3_2``): example, published-point audits,
independent CVXPY cross-checks, bad input.

Reference values: ``thesis_catalogue.md`` section 2 and 11.2 (tolerances of section 10/11:
2e-3 absolute on gamma*, eta*; 2 % on the other solved quantities; 1e-3 on audits of the
published point). Every number is read from a certified (or infeasible-certified) answer.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest
import yaml

from lmic.api import solve
from lmic.compile import compile_theorem
from lmic.errors import DataError

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
EXAMPLE = "delay_a.thm3_2.example.yaml"
BACKENDS = ("clarabel", "sdpa")

_spec = importlib.util.spec_from_file_location("_delay_reference", Path(__file__).with_name("_delay_reference.py"))
ref = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(ref)


def _system(name: str = EXAMPLE) -> tuple[dict, dict]:
    doc = yaml.safe_load((EXAMPLES / name).read_text())
    pub = {k: np.array(v, dtype=float) for k, v in (doc.pop("published", {}) or {}).items()}
    return doc, pub


def _certified(tid, system, params=None, backend="clarabel"):
    r = solve(tid, system, params=params, backend=backend)
    assert (r.status, r.verdict) == ("optimal", "certified"), r.certificate.reason
    return r


def _thm3_1_system() -> dict:
    """The Paper A example for Theorem 3.1: eta instead of lambda."""
    system, _ = _system()
    params = {k: v for k, v in system["params"].items() if k != "lambda"}
    return {**system, "params": {**params, "eta": 2.379}}


def test_example_full_solve_reference_values():
    # catalogue 2.2: printed Psi1, eps2 = eps3 = 0.1, lambda = 0.9, tau0 = 3
    system, pub = _system()
    r = _certified("delay_a.thm3_2", system)
    d, v = r.derived, r.variables
    assert d["gamma_star"] == pytest.approx(0.2257, abs=2e-3)
    assert d["eta_star"] == pytest.approx(1.8551, abs=2e-3)
    np.testing.assert_allclose(np.ravel(d["L"]), [1.229, -1.473], rtol=0.02)
    assert v["alpha"] == pytest.approx(8.4137, rel=0.02)
    assert v["eps1"] == pytest.approx(1.3323, rel=0.02)
    checks = {c["name"]: c for c in r.certificate.checks}
    assert checks["A - L C Schur stable"]["ok"]
    # the published gamma* = 0.335 and eta* = 2.379 are not optimal for the printed problem
    # (catalogue 2.2: gamma* not reproducible; eta* is reproduced only at the published P's)
    assert abs(d["gamma_star"] - pub["gamma_star"]) / pub["gamma_star"] > 0.2
    assert d["eta_star"] < pub["eta_star"]


@pytest.mark.parametrize(
    ("tau2", "psi1", "gamma", "eta"),
    [
        (1, "printed", 0.3088, 1.9603),  # tau0 = 2
        (0, "printed", 0.3832, 2.1640),  # tau0 = 1
        (2, "corrected", 0.1296, 1.7704),
        (0, "corrected", 0.2283, 1.9761),
    ],
)
def test_tau0_and_psi1_variants(tau2, psi1, gamma, eta):
    system, _ = _system()
    r = _certified("delay_a.thm3_2", system, {"tau2": tau2, "psi1": psi1})
    assert r.derived["gamma_star"] == pytest.approx(gamma, abs=2e-3)
    assert r.derived["eta_star"] == pytest.approx(eta, abs=2e-3)
    if (tau2, psi1) == (0, "printed"):
        np.testing.assert_allclose(np.ravel(r.derived["L"]), [1.0, -1.0], atol=2e-3)


def test_tau0_given_directly_equals_tau1_tau2():
    system, _ = _system()
    params = {k: v for k, v in system["params"].items() if k not in ("tau1", "tau2")}
    a = _certified("delay_a.thm3_2", {**system, "params": {**params, "tau0": 3}})
    b = _certified("delay_a.thm3_2", system)
    assert a.objective == pytest.approx(b.objective, rel=1e-6)


@pytest.mark.parametrize(("tau2", "gamma"), [(2, 0.2249), (0, 0.388)])
def test_thm3_1_with_eta_given(tau2, gamma):
    # catalogue 2.1: eta = 2.379 fixed, printed Psi1, eps2 = eps3 = 0.1
    r = _certified("delay_a.thm3_1", _thm3_1_system(), {"tau2": tau2})
    assert r.derived["gamma_star"] == pytest.approx(gamma, abs=2e-3)


def _published_values(pub):
    return {"P1": pub["P1"], "P2": pub["P2"], "Upsilon": pub["Upsilon"]}


def test_published_point_L_and_eta_reproduce():
    system, pub = _system()
    prob = compile_theorem("delay_a.thm3_2", system)
    # min rho in (43) alone at the published P1, P2, Upsilon: eta = sqrt(rho) = 2.3787
    audit = ref.restrict(prob, {**_published_values(pub), "eps1": 1.0, "alpha": 1.0}, {"rho": 1.0}, lmis=["(43)"])
    r = solve(audit)
    assert (r.status, r.verdict) == ("optimal", "certified"), r.certificate.reason
    assert r.derived["eta_star"] == pytest.approx(2.3787, abs=1e-3)
    assert r.derived["eta_star"] == pytest.approx(pub["eta_star"], abs=1e-3)
    # L = P1^-1 Upsilon = [0.9919, -1.0007] (published L = [1, -1], structural M1 / M3)
    np.testing.assert_allclose(np.ravel(r.derived["L"]), [0.9919, -1.0007], atol=1e-3)
    np.testing.assert_allclose(np.ravel(r.derived["L"]), np.ravel(pub["L"]), atol=1e-2)


@pytest.mark.parametrize("tau2", [0, 1, 2])
def test_published_point_infeasible_for_big_lmi(tau2):
    # catalogue 2.2: with eps2 = eps3 = 0.1, the published P's leave (15) infeasible for every
    # tau0 in {1, 2, 3} (alpha, eps1, rho free): the published gamma* = 0.335 has no certificate
    system, pub = _system()
    prob = compile_theorem("delay_a.thm3_2", system, {"tau2": tau2})
    audit = ref.restrict(prob, _published_values(pub), {"alpha": 1.0, "eps1": 1.0})
    r = solve(audit)
    assert r.status == "infeasible"
    assert r.verdict != "rejected"


@pytest.mark.parametrize("tau2", [0, 1])
def test_published_point_with_eps_free(tau2):
    # catalogue 2.2 / 11.2: eps2, eps3 free, min alpha + eps1 at the published P's gives
    # gamma = 0.3549 for tau0 = 1 and 2 (the tau0 = 3 value is numerically unreliable)
    system, pub = _system()
    params = {k: v for k, v in system["params"].items() if k not in ("eps2", "eps3")}
    prob = compile_theorem("delay_a.thm3_2", {**system, "params": params}, {"eps_free": 1, "tau2": tau2})
    audit = ref.restrict(prob, _published_values(pub), {"alpha": 1.0, "eps1": 1.0})
    r = solve(audit)
    assert (r.status, r.verdict) == ("optimal", "certified"), r.certificate.reason
    assert r.derived["gamma_star"] == pytest.approx(0.3549, abs=2e-3)


def test_eps_free_relaxes_the_fixed_problem():
    # eps2, eps3 as decision variables: the fixed eps2 = eps3 = 0.1 point stays admissible
    system, _ = _system()
    fixed = _certified("delay_a.thm3_2", system)
    params = {k: v for k, v in system["params"].items() if k not in ("eps2", "eps3")}
    free = _certified("delay_a.thm3_2", {**system, "params": {**params, "eps_free": 1}})
    assert free.objective <= fixed.objective * (1 + 1e-6)
    assert free.variables["eps2"] > 0 and free.variables["eps3"] > 0


def test_lambda_trend():
    # gamma* and eta* increase with lambda (catalogue 3.2, same structure in Paper A)
    system, _ = _system()
    out = [_certified("delay_a.thm3_2", system, {"lambda": lam}).derived for lam in (0.2, 0.5, 0.9)]
    gammas = [d["gamma_star"] for d in out]
    etas = [d["eta_star"] for d in out]
    assert gammas == sorted(gammas) and etas == sorted(etas)


# -- independent CVXPY formulation on small random systems -------------------------------------


def _random_data(seed: int, rho_a: float | None = None) -> dict:
    rng = np.random.default_rng(seed)
    A = 0.25 * rng.normal(size=(2, 2))
    if rho_a is not None:
        A *= rho_a / max(abs(np.linalg.eigvals(A)))
    data = {
        "A": A,
        "Ad": 0.1 * rng.normal(size=(2, 2)),
        "B": rng.normal(size=(2, 1)),
        "C": 0.4 * rng.normal(size=(1, 2)),
        "D": 0.5 * rng.normal(size=(1, 1)),
        "M1": 0.1 * rng.normal(size=(2, 1)),
        "M2": 0.1 * rng.normal(size=(2, 1)),
        "M3": 0.1 * rng.normal(size=(1, 1)),
        "N": 0.1 * rng.normal(size=(1, 2)),
        "H": 0.2 * np.eye(2),
    }
    return {k: v.tolist() for k, v in data.items()}


@pytest.mark.parametrize(("seed", "psi1"), [(0, "printed"), (1, "corrected")])
def test_thm3_2_matches_cvxpy(seed, psi1):
    data = _random_data(seed)
    params = {"tau1": 1, "tau2": 2, "eps2": 0.5, "eps3": 0.5, "lambda": 0.6, "psi1": psi1}
    expected = ref.reference(data, params, pareto=True)
    assert expected["status"] == "optimal"
    for backend in BACKENDS:
        r = _certified("delay_a.thm3_2", {"data": data, "params": params}, backend=backend)
        assert r.objective == pytest.approx(expected["value"], rel=2e-3), backend
        assert r.derived["gamma_star"] == pytest.approx(expected["gamma_star"], rel=2e-3)
        assert r.derived["eta_star"] == pytest.approx(expected["eta_star"], rel=2e-3)


def test_thm3_1_matches_cvxpy():
    data = _random_data(3)
    params = {"tau1": 0, "tau2": 1, "eps2": 0.3, "eps3": 0.3, "eta": 3.0, "psi1": "printed"}
    expected = ref.reference(data, params, pareto=False)
    assert expected["status"] == "optimal"
    for backend in BACKENDS:
        r = _certified("delay_a.thm3_1", {"data": data, "params": params}, backend=backend)
        assert r.objective == pytest.approx(expected["value"], rel=2e-3), backend
        assert r.derived["gamma_star"] == pytest.approx(expected["gamma_star"], rel=2e-3)


def test_infeasible_when_plant_too_fast():
    # independent necessary condition: the principal block on rows (x, Psi2) gives
    # 3 A^T P2 A < P2, i.e. spectral radius(A) < 1/sqrt(3); at 0.6 both theorems are infeasible
    data = _random_data(0, rho_a=0.6)
    params = {"tau1": 1, "tau2": 2, "eps2": 0.5, "eps3": 0.5, "lambda": 0.6}
    for backend in BACKENDS:
        r = solve("delay_a.thm3_2", {"data": data, "params": params}, backend=backend)
        assert r.status == "infeasible" and r.verdict != "rejected", backend
    r = solve("delay_a.thm3_2", {"data": _random_data(0, rho_a=0.5), "params": params})
    assert r.verdict == "certified"  # just below the bound it can be feasible


# -- bad input ---------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("params", "pattern"),
    [
        ({"lambda": 1.5}, r"delay_a\.thm3_2.*lambda = 1\.5 is outside its domain"),
        ({"lambda": -0.1}, r"delay_a\.thm3_2.*lambda = -0\.1 is outside its domain"),
        ({"tau1": 3}, r"delay_a\.thm3_2.*tau1 = 3, tau2 = 2 need tau1 <= tau2"),
        ({"tau0": 5}, r"delay_a\.thm3_2.*tau0 = 5 disagrees with tau2 - tau1 \+ 1 = 3"),
        ({"tau2": 2.5}, r"delay_a\.thm3_2.*tau2 = 2\.5 must be a whole number"),
        ({"eps2": 0}, r"delay_a\.thm3_2.*eps2 = 0 is outside its domain"),
        ({"psi1": "fixed"}, r"delay_a\.thm3_2.*psi1 = 'fixed' is not one of printed, corrected"),
        ({"eta": 2.0}, r"delay_a\.thm3_2.*unknown parameter 'eta'"),
    ],
)
def test_bad_parameters(params, pattern):
    system, _ = _system()
    with pytest.raises(DataError, match=pattern):
        compile_theorem("delay_a.thm3_2", system, params)


def test_bad_data():
    system, _ = _system()
    no_h = {**system, "data": {k: v for k, v in system["data"].items() if k != "H"}}
    with pytest.raises(DataError, match=r"delay_a\.thm3_2.*missing data 'H'"):
        compile_theorem("delay_a.thm3_2", no_h)
    bad_m3 = {**system, "data": {**system["data"], "M3": [[0.1, 0.2]]}}
    with pytest.raises(DataError, match=r"delay_a\.thm3_2.*'M3' has shape 1x2"):
        compile_theorem("delay_a.thm3_2", bad_m3)
    with pytest.raises(DataError, match=r"delay_a\.thm3_1.*missing parameter 'eta'"):
        compile_theorem("delay_a.thm3_1", {**_thm3_1_system(), "params": {"eps2": 0.1, "eps3": 0.1}})
