"""Paper B plugins (``delay_b.thm3_1``, ``delay_b.thm4_1``): Tables 1-4, published-point audits,
the paper's infeasibility claims, independent CVXPY cross-checks, bad input.

Reference values: ``thesis_catalogue.md`` section 3.2 and 11.8; tolerances of section 10/11:
2e-3 absolute on gamma*, eta* against the reference implementation, +-20 % against the
published tables, +-0.01 on the Table 1 audit at the published P's.
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
BACKENDS = ("clarabel", "sdpa")

_spec = importlib.util.spec_from_file_location("_delay_reference", Path(__file__).with_name("_delay_reference.py"))
ref = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(ref)


def _system(name: str) -> tuple[dict, dict]:
    doc = yaml.safe_load((EXAMPLES / name).read_text())
    pub = {k: np.array(v, dtype=float) for k, v in (doc.pop("published", {}) or {}).items()}
    return doc, pub


def _certified(tid, system, params=None, backend="clarabel"):
    r = solve(tid, system, params=params, backend=backend)
    assert (r.status, r.verdict) == ("optimal", "certified"), r.certificate.reason
    return r


#: example file -> reference (gamma*, eta*) of the printed theorem (catalogue 3.2, Clarabel)
REFERENCE = {
    "delay_b.thm4_1.ex1_lambda0_2.yaml": (0.264, 1.715),
    "delay_b.thm4_1.ex1_lambda0_5.yaml": (0.339, 2.070),
    "delay_b.thm4_1.ex1_lambda0_9.yaml": (0.428, 2.885),
    "delay_b.thm4_1.ex1_table2_tau0_2.yaml": (0.341, 1.921),
    "delay_b.thm4_1.ex1_table2_tau0_3.yaml": (0.339, 2.070),
    "delay_b.thm4_1.ex1_table2_tau0_4.yaml": (0.329, 2.246),
    "delay_b.thm4_1.ex1_table2_tau0_5.yaml": (0.290, 2.423),
    "delay_b.thm4_1.ex2_lambda0_2.yaml": (0.206, 1.902),
    "delay_b.thm4_1.ex2_lambda0_5.yaml": (0.257, 2.296),
    "delay_b.thm4_1.ex2_lambda0_9.yaml": (0.295, 2.894),
    "delay_b.thm4_1.ex2_table4_tau0_2.yaml": (0.374, 1.908),
    "delay_b.thm4_1.ex2_table4_tau0_3.yaml": (0.326, 2.090),
    "delay_b.thm4_1.ex2_table4_tau0_4.yaml": (0.257, 2.296),
}

#: published values that do not reproduce within +-20 % (Example 2 at tau0 = 4: the table
#: matches tau0 = 3, an off-by-one in tau0 the catalogue also sees in Table 2)
NOT_WITHIN_20 = {
    ("delay_b.thm4_1.ex2_lambda0_5.yaml", "gamma_star"),
    ("delay_b.thm4_1.ex2_lambda0_9.yaml", "gamma_star"),
}


@pytest.mark.parametrize("name", sorted(REFERENCE))
def test_tables_reference_values(name):
    system, pub = _system(name)
    r = _certified("delay_b.thm4_1", system)
    gamma, eta = REFERENCE[name]
    assert r.derived["gamma_star"] == pytest.approx(gamma, abs=2e-3)
    assert r.derived["eta_star"] == pytest.approx(eta, abs=2e-3)
    for key in ("gamma_star", "eta_star"):
        rel = abs(r.derived[key] - pub[key]) / pub[key]
        if (name, key) in NOT_WITHIN_20:
            assert rel > 0.2, (key, r.derived[key], pub[key])
        else:
            assert rel <= 0.2, (key, r.derived[key], pub[key])


@pytest.mark.parametrize("lam", ["0_5", "0_9"])
def test_example2_gamma_matches_published_at_tau0_3(lam):
    # the documented off-by-one: with tau0 = 3 instead of 4, Table 3's gamma* is within 20 %
    name = f"delay_b.thm4_1.ex2_lambda{lam}.yaml"
    system, pub = _system(name)
    r = _certified("delay_b.thm4_1", system, {"tau2": 2})
    assert abs(r.derived["gamma_star"] - pub["gamma_star"]) / pub["gamma_star"] <= 0.2


def test_trends_with_lambda_and_tau0():
    # gamma*, eta* increase with lambda; for lambda = 0.5, gamma decreases and eta increases
    # with tau0 (catalogue 3.2: gamma 0.342 ... 0.243, eta 1.787 ... 2.633 for tau0 = 1 ... 6)
    system, _ = _system("delay_b.thm4_1.ex1_lambda0_5.yaml")
    by_lambda = [_certified("delay_b.thm4_1", system, {"lambda": lam}).derived for lam in (0.2, 0.5, 0.9)]
    assert [d["gamma_star"] for d in by_lambda] == sorted(d["gamma_star"] for d in by_lambda)
    assert [d["eta_star"] for d in by_lambda] == sorted(d["eta_star"] for d in by_lambda)
    by_tau = [_certified("delay_b.thm4_1", system, {"tau2": tau0 - 1}).derived for tau0 in (1, 6)]
    assert by_tau[0]["gamma_star"] == pytest.approx(0.342, abs=2e-3)
    assert by_tau[0]["eta_star"] == pytest.approx(1.787, abs=2e-3)
    assert by_tau[1]["gamma_star"] < by_tau[0]["gamma_star"]
    assert by_tau[1]["eta_star"] > by_tau[0]["eta_star"]


@pytest.mark.parametrize(
    ("example", "tau0", "gamma"),
    [
        ("delay_b.thm4_1.ex1_table2_tau0_5.yaml", 6, 0.243),  # 'for tau0 >= 6 no feasible solution'
        ("delay_b.thm4_1.ex2_table4_tau0_4.yaml", 5, 0.187),  # 'tau0 >= 5 infeasible'
        ("delay_b.thm4_1.ex2_table4_tau0_4.yaml", 6, 0.107),
    ],
)
def test_published_infeasibility_claims_do_not_hold(example, tau0, gamma):
    # the printed LMIs stay feasible beyond the delay bound the paper states: certified points
    system, _ = _system(example)
    r = _certified("delay_b.thm4_1", system, {"tau0": tau0})
    assert r.derived["gamma_star"] == pytest.approx(gamma, abs=2e-3)
    if tau0 == 6 and "ex1" in example:
        assert r.derived["eta_star"] == pytest.approx(2.633, abs=2e-3)


def test_corrected_psi1_example1():
    # catalogue 3.2: corrected Psi1, Example 1, tau0 = 3
    expected = {"0_2": (0.200, 1.920), "0_5": (0.248, 2.382), "0_9": (0.288, 3.187)}
    for lam, (gamma, eta) in expected.items():
        system, _ = _system(f"delay_b.thm4_1.ex1_lambda{lam}.yaml")
        r = _certified("delay_b.thm4_1", system, {"psi1": "corrected"})
        assert r.derived["gamma_star"] == pytest.approx(gamma, abs=2e-3)
        assert r.derived["eta_star"] == pytest.approx(eta, abs=2e-3)


#: Table 1 / Table 3 audits at the published P1, P2, Upsilon (catalogue 3.2): gamma from
#: min alpha + eps1 with printed Psi1 and tau0 = 1, eta from (48), L = P1^-1 Upsilon
AUDIT = {
    "delay_b.thm4_1.ex1_lambda0_2.yaml": (0.261, 1.523, [0.667, 0.012]),
    "delay_b.thm4_1.ex1_lambda0_5.yaml": (0.326, 1.878, [0.549, -0.112]),
    "delay_b.thm4_1.ex1_lambda0_9.yaml": (0.408, 2.702, [0.307, -0.434]),
    "delay_b.thm4_1.ex2_lambda0_2.yaml": (0.281, 1.638, [0.101, -0.490]),
    "delay_b.thm4_1.ex2_lambda0_5.yaml": (0.356, 2.098, [0.081, -0.493]),
    "delay_b.thm4_1.ex2_lambda0_9.yaml": (0.431, 2.793, [-0.002, -0.515]),
}


@pytest.mark.parametrize("name", sorted(AUDIT))
def test_published_point_audit(name):
    system, pub = _system(name)
    gamma, eta, L = AUDIT[name]
    fixed = {"P1": pub["P1"], "P2": pub["P2"], "Upsilon": pub["Upsilon"]}
    prob = compile_theorem("delay_b.thm4_1", system, {"tau2": 0})  # tau0 = 1
    r = solve(ref.restrict(prob, fixed, {"alpha": 1.0, "eps1": 1.0}))
    assert (r.status, r.verdict) == ("optimal", "certified"), r.certificate.reason
    assert r.derived["gamma_star"] == pytest.approx(gamma, abs=2e-3)
    if "ex1" in name:  # Table 1's gamma* is met at tau0 = 1 (catalogue tolerance 0.01)
        assert r.derived["gamma_star"] == pytest.approx(pub["gamma_star"], abs=0.01)
    prob = compile_theorem("delay_b.thm4_1", system)
    # at the example's own delay bound (tau0 = 3 / 4) the published P's certify nothing: an exact
    # Farkas proof (the solver's ray on a rational basis of its face)
    r = solve(ref.restrict(prob, fixed, {"alpha": 1.0, "eps1": 1.0}))
    assert (r.status, r.verdict) == ("infeasible", "infeasible-certified"), r.certificate.reason
    assert r.certificate.exact["proven"]
    r = solve(ref.restrict(prob, {**fixed, "alpha": 1.0, "eps1": 1.0}, {"rho": 1.0}, lmis=["(48)"]))
    assert (r.status, r.verdict) == ("optimal", "certified"), r.certificate.reason
    assert r.derived["eta_star"] == pytest.approx(eta, abs=2e-3)
    np.testing.assert_allclose(np.ravel(r.derived["L"]), L, atol=2e-3)
    # the printed L agrees with P1^-1 Upsilon to rounding (Ex1 lambda = 0.2: 0.012 against -0.02)
    np.testing.assert_allclose(np.ravel(r.derived["L"]), np.ravel(pub["L"]), atol=0.035)


def test_thm3_1_with_eta_star_of_thm4_1():
    # catalogue 11.8: Thm 3.1 with eta fixed at eta* of Thm 4.1 (Ex 1, lambda = 0.5, tau0 = 3)
    # returns the same gamma* = 0.3389; delta_gamma_max = gamma* - gamma0 (Section 4)
    system, _ = _system("delay_b.thm4_1.ex1_lambda0_5.yaml")
    pareto = _certified("delay_b.thm4_1", system).derived
    params = {k: v for k, v in system["params"].items() if k != "lambda"}
    params.update(eta=pareto["eta_star"] * (1 + 1e-6), gamma0=0.1)
    r = _certified("delay_b.thm3_1", {**system, "params": params})
    assert r.derived["gamma_star"] == pytest.approx(0.3389, abs=1e-3)
    assert r.derived["gamma_star"] == pytest.approx(pareto["gamma_star"], abs=1e-3)
    assert r.derived["delta_gamma_max"] == pytest.approx(r.derived["gamma_star"] - 0.1, abs=1e-12)


def test_cd_m4_default_to_zero():
    system, _ = _system("delay_b.thm4_1.ex1_lambda0_5.yaml")
    without = {**system, "data": {k: v for k, v in system["data"].items() if k not in ("Cd", "M4")}}
    assert _certified("delay_b.thm4_1", without).objective == pytest.approx(
        _certified("delay_b.thm4_1", system).objective, rel=1e-6
    )


# -- independent CVXPY formulation on small random systems (Cd, M4 non-zero) --------------------


def _random_data(seed: int) -> dict:
    rng = np.random.default_rng(seed)
    data = {
        "A": 0.25 * rng.normal(size=(2, 2)),
        "Ad": 0.1 * rng.normal(size=(2, 2)),
        "B": rng.normal(size=(2, 1)),
        "C": 0.4 * rng.normal(size=(1, 2)),
        "D": 0.5 * rng.normal(size=(1, 1)),
        "M1": 0.1 * rng.normal(size=(2, 1)),
        "M2": 0.1 * rng.normal(size=(2, 1)),
        "M3": 0.1 * rng.normal(size=(1, 1)),
        "N": 0.1 * rng.normal(size=(1, 2)),
        "H": 0.2 * np.eye(2),
        "Cd": 0.2 * rng.normal(size=(1, 2)),
        "M4": 0.1 * rng.normal(size=(1, 1)),
    }
    return {k: v.tolist() for k, v in data.items()}


@pytest.mark.parametrize(("seed", "psi1"), [(0, "printed"), (1, "corrected")])
def test_thm4_1_matches_cvxpy(seed, psi1):
    data = _random_data(seed)
    params = {"tau1": 1, "tau2": 2, "eps2": 0.5, "eps3": 0.5, "lambda": 0.6, "psi1": psi1}
    expected = ref.reference(data, params, pareto=True)
    assert expected["status"] == "optimal"
    for backend in BACKENDS:
        r = _certified("delay_b.thm4_1", {"data": data, "params": params}, backend=backend)
        assert r.objective == pytest.approx(expected["value"], rel=2e-3), backend
        assert r.derived["gamma_star"] == pytest.approx(expected["gamma_star"], rel=2e-3)
        assert r.derived["eta_star"] == pytest.approx(expected["eta_star"], rel=2e-3)
        np.testing.assert_allclose(r.derived["L"], expected["L"], rtol=2e-2, atol=2e-3)


@pytest.mark.parametrize(("seed", "expected_status"), [(4, "optimal"), (2, "infeasible")])
def test_thm3_1_matches_cvxpy(seed, expected_status):
    data = _random_data(seed)
    params = {"tau0": 2, "eps2": 0.3, "eps3": 0.3, "eta": 3.0, "psi1": "printed"}
    expected = ref.reference(data, params, pareto=False)
    assert expected["status"] == expected_status
    for backend in BACKENDS:
        if expected_status == "infeasible":
            r = solve("delay_b.thm3_1", {"data": data, "params": params}, backend=backend)
            assert r.status == "infeasible" and r.verdict != "rejected", backend
            continue
        r = _certified("delay_b.thm3_1", {"data": data, "params": params}, backend=backend)
        assert r.objective == pytest.approx(expected["value"], rel=2e-3), backend
        assert r.derived["gamma_star"] == pytest.approx(expected["gamma_star"], rel=2e-3)


# -- bad input ---------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("params", "pattern"),
    [
        ({"lambda": 1.01}, r"delay_b\.thm4_1.*lambda = 1\.01 is outside its domain"),
        ({"tau0": 2}, r"delay_b\.thm4_1.*tau0 = 2 disagrees with tau2 - tau1 \+ 1 = 3"),
        ({"tau0": 1.5}, r"delay_b\.thm4_1.*tau0 = 1\.5 must be a whole number"),
        ({"tau1": -1}, r"delay_b\.thm4_1.*tau1 = -1 is outside its domain"),
        ({"eps3": -1}, r"delay_b\.thm4_1.*eps3 = -1 is outside its domain"),
        ({"gamma0": -0.1}, r"delay_b\.thm4_1.*gamma0 = -0\.1 is outside its domain"),
    ],
)
def test_bad_parameters(params, pattern):
    system, _ = _system("delay_b.thm4_1.ex1_lambda0_2.yaml")
    with pytest.raises(DataError, match=pattern):
        compile_theorem("delay_b.thm4_1", system, params)


def test_bad_data():
    system, _ = _system("delay_b.thm4_1.ex1_lambda0_2.yaml")
    with pytest.raises(DataError, match=r"delay_b\.thm4_1.*'Cd' has shape 2x2"):
        compile_theorem("delay_b.thm4_1", {**system, "data": {**system["data"], "Cd": np.eye(2).tolist()}})
    no_lambda = {**system, "params": {k: v for k, v in system["params"].items() if k != "lambda"}}
    with pytest.raises(DataError, match=r"delay_b\.thm4_1.*missing parameter 'lambda'"):
        compile_theorem("delay_b.thm4_1", no_lambda)
