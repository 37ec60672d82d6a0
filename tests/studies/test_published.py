"""lmic.studies.published: audits of what the papers print, checked against the catalogues' reference values."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp
import yaml

from lmic.certify import certify
from lmic.compile import compile_theorem
from lmic.errors import DataError
from lmic.ir.problem import LMI, LinearConstraints, NamedExpr, Objective, Problem, Variable
from lmic.solution import Solution
from lmic.studies.published import audit_published, fix_variables, recover_variables

ROOT = Path(__file__).resolve().parents[2]
EX = ROOT / "examples"


def _raw(name: str) -> dict:
    return yaml.safe_load((EX / name).read_text())


def _extreme(claim, lmi_name):
    return next(e["extreme"] for e in claim.lmis if e["name"] == lmi_name)


# -- IR helpers -----------------------------------------------------------------------------------


def test_fix_variables_substitutes_and_keeps_values_for_checks():
    p = Problem(
        [Variable("a", "scalar", (1, 1)), Variable("B", "symmetric", (2, 2), offset=1)],
        [LMI("B - a I > 0", 2, sp.csc_matrix(np.array([[0, -1, 1, 0, 0], [0, 0, 0, 1, 0], [0, -1, 0, 0, 1.0]])))],
        LinearConstraints(sp.csr_matrix([[0.0, 1.0, 0, 0, 0]]), ["ge"], [True], ["a > 0"]),
        Objective("min", [0.0, 2.0, 0, 0, 0]),
        derived=[NamedExpr("twice_a", {"op": "mul", "args": [{"num": 2.0}, {"name": "a"}]})],
    )
    q, x0, free = fix_variables(p, {"a": 0.5})
    assert [v.name for v in q.variables] == ["B"] and q.variables[0].offset == 0
    assert np.allclose(q.lmis[0].matrix([2.0, 0.0, 3.0]), [[1.5, 0], [0, 2.5]])
    assert q.linear.residuals([1, 2, 3]) == pytest.approx([0.5]) and q.objective.value([1, 2, 3]) == 1.0
    assert q.environment(np.array([1.0, 0, 1.0]))["twice_a"] == 1.0
    x = x0.copy()
    x[free] = [2.0, 0.0, 3.0]
    assert np.allclose(p.lmis[0].matrix(x), q.lmis[0].matrix([2.0, 0.0, 3.0]))


def test_recover_variables_from_printed_gains():
    p = compile_theorem("thesis.cor3_19", EX / "thesis.cor3_19.ex3_2_2.yaml")
    pub = _raw("thesis.cor3_19.ex3_2_2.yaml")["published"]
    found = recover_variables(p, {"P": pub["P"]}, pub)
    value, how, key = found["Lbar"]
    assert how == "Lbar = P L" and key == "L"
    assert np.allclose(value, np.array(pub["P"]) @ np.array(pub["L"]))
    # the catalogue's Lbar = P L (T1.6 line 146)
    assert np.allclose(value[:2], [[1.5384, -0.0014], [-40.4288, 0.4954]], atol=2e-4)
    qib = compile_theorem("qib.thm1", EX / "qib.thm1.flexible-joint.yaml")  # L = P^-1 R^T: R = (P L)^T
    pq = _raw("qib.thm1.flexible-joint.yaml")["published"]
    R, how, _ = recover_variables(qib, {"P": pq["P"]}, {"L": pq["L"]})["R"]
    assert how == "R = (P L)^T" and np.allclose(R, pq["R"], atol=0.02)


# -- route (a): the published point, certified as printed ----------------------------------------


def test_qib_thm1_published_point_and_gain():
    """S6 lines 486-487: (P, R, omega)_pub in (7): lambda_max = -0.05581; L_pub certified."""
    rep = audit_published("qib.thm1", EX / "qib.thm1.flexible-joint.yaml")
    point, gain = rep.claim("P"), rep.claim("L")
    assert point.kind == "point" and point.keys == ["P", "R", "omega"] and point.finding == "certified"
    assert _extreme(point, "(7)") == pytest.approx(-0.05581, abs=1e-5)
    assert gain.kind == "gain" and gain.finding == "certified" and gain.agrees
    assert _extreme(gain, "(7)") < 0
    assert rep.exit_code() == 0


def test_published_points_recovered_from_gains():
    """T1.6 line 144: (P, L) of Cor (3.19): -0.2552; T4.2 line 413: (P, Y, K) of Paper C: -0.2445, rho(N) 0.954."""
    cor = audit_published("thesis.cor3_19", EX / "thesis.cor3_19.ex3_2_2.yaml").claim("P")
    assert cor.kind == "point" and "Lbar = P L" in cor.route
    assert _extreme(cor, "(3.19)") == pytest.approx(-0.2552, abs=1e-3)
    uio = audit_published("uio_dt.thm3_2", EX / "uio_dt.thm3_2.flexible_joint.yaml")
    pt = uio.claim("P")
    assert pt.keys == ["P", "Y", "K"] and pt.finding == "certified"
    assert _extreme(pt, "(20)") == pytest.approx(-0.2445, abs=1e-3)
    rho = next(c["value"] for c in pt.checks if c["name"].startswith("N Schur"))
    assert rho == pytest.approx(0.954, abs=1e-3)
    # values recomputed from the printed Y, K (T4.2 lines 410-412)
    n = uio.claim("N")
    assert n.kind == "value" and n.finding == "matches"
    assert np.allclose(n.computed[3], [0.0227, -0.0665, -5.4227, 1], atol=1e-4)
    assert uio.claim("G").computed[2][0] == pytest.approx(-0.6475, abs=1e-4)
    assert uio.exit_code() == 0


def test_a_tampered_point_is_rejected_with_its_margin():
    raw = _raw("thesis.lyapunov.ex2_3_2.yaml")
    assert audit_published("thesis.lyapunov", raw).claim("P").finding == "certified"
    raw["published"]["P"] = (-np.array(raw["published"]["P"])).tolist()
    rep = audit_published("thesis.lyapunov", raw)
    c = rep.claim("P")
    assert c.finding == "rejected" and c.verdict == "rejected" and c.agrees is False
    assert _extreme(c, "P > 0") == pytest.approx(-0.7607, abs=1e-3)  # -lambda_max of the printed P
    assert "violated" in c.reason and rep.exit_code() == 1


# -- route (c): partial points completed by the solver ----------------------------------------------


def test_uncertain_dt_thm1_published_pair_is_infeasible_and_L_certifies_0_3428():
    """S6 lines 477-481: (eps1*, alpha*)_pub infeasible; L_pub certifies gamma = 0.3428; optimum 0.3405."""
    rep = audit_published("uncertain_dt.thm1", EX / "uncertain_dt.thm1.example.yaml")
    pair = rep.claim("eps1_star")
    assert pair.kind == "partial point" and pair.keys == ["eps1_star", "alpha_star"]
    assert pair.finding == "infeasible" and pair.verdict == "infeasible-certified" and pair.agrees is False
    gain = rep.claim("L")
    assert gain.finding == "certified" and gain.derived["gamma_star"] == pytest.approx(0.3428, abs=2e-3)
    gstar = rep.claim("gamma_star")
    assert gstar.finding == "differs" and gstar.computed == pytest.approx(0.3405, abs=2e-3)
    assert gstar.published == 0.4339
    assert rep.exit_code() == 3


def test_descriptor_published_point_completed_in_gamma():
    """T5.3 line 493: LMI (40) at the published P (Gamma free) is feasible; M from R exact (line 482)."""
    rep = audit_published("descriptor.thm3_3", EX / "descriptor.thm3_3.example.yaml")
    c = rep.claim("P")
    assert c.kind == "partial point" and "Ybar1 = P Y1" in c.route and c.finding == "certified"
    assert rep.claim("M").difference < 1e-9 and rep.claim("G").kind == "skipped"
    assert rep.exit_code() == 0


def test_delay_a_published_point_infeasible_and_L_consistent():
    """T2.2 lines 290-296: P1^-1 Upsilon = [0.9919; -1.0007]; published point infeasible; optimum L, gamma*."""
    rep = audit_published("delay_a.thm3_2", EX / "delay_a.thm3_2.example.yaml")
    assert rep.claim("P1").finding == "infeasible"  # an exact Farkas proof of the ray
    L = rep.claim("L")
    assert np.allclose(L.computed, [[1.229], [-1.473]], atol=2e-3)  # at the optimum (the point is refuted)
    assert "[0.9919; -1.001]" in L.reason
    assert rep.claim("gamma_star").computed == pytest.approx(0.2257, abs=2e-3)
    assert rep.claim("eta_star").computed == pytest.approx(1.8551, abs=2e-3)


# -- route (b): printed gains through fixed_<gain> ---------------------------------------------------


@pytest.mark.parametrize(
    ("theorem", "file", "finding"),
    [
        ("qib.thm2", "qib.thm2.flexible-joint.yaml", "infeasible"),  # S6 line 490
        # S6 line 499; the default route (SCS first at this size, issue 14) returns a ray whose
        # exact rational Farkas proof holds: a global proof, where Clarabel's ray gave none
        ("nonuniform.thm1", "nonuniform.thm1.chua.yaml", "infeasible"),
        ("nonuniform.thm1", "nonuniform.thm1.chua-gamma2.95.yaml", "certified"),  # S6 line 500
        ("nonuniform.thm1", "nonuniform.thm1.flexible-arm.yaml", "infeasible"),  # S6 line 495 (idem)
        ("sampled_euler.thm4", "sampled_euler.thm4.example.yaml", "infeasible"),  # S6 line 475
    ],
)
def test_printed_gains(theorem, file, finding):
    rep = audit_published(theorem, EX / file)
    gain = next(c for c in rep.claims if c.kind == "gain")
    assert gain.finding == finding
    if finding == "infeasible":
        assert gain.verdict == "infeasible-certified"
    elif finding == "infeasible-bounded":  # float ray of an inhomogeneous LMI: no global proof
        assert gain.verdict == "infeasible-bounded" and gain.agrees is False
    else:
        assert gain.verdict == "certified" and all(e["ok"] for e in gain.lmis)


def test_qib_thm2_published_K_in_both_forms():
    rep = audit_published("qib.thm2", EX / "qib.thm2.flexible-joint.yaml")
    assert [c.kind for c in rep.claims] == ["partial point", "gain"]
    assert all(c.finding == "infeasible" for c in rep.claims) and rep.exit_code() == 3


# -- status, values, bad input -------------------------------------------------------------------------


def test_status_claims():
    """T1.5 line 124: infeasible at gamma = 3.33; T11.6 line 702: uir (11). Both are Farkas rays of
    inhomogeneous LMIs that lmic proves exactly (global proofs)."""
    rep = audit_published("thesis.thm3_2_2", EX / "thesis.thm3_2_2.ex3_2_2.yaml")
    c = rep.claim("status")
    # the Farkas ray of an inhomogeneous LMI, proven exactly (a rational basis of its face; gamma =
    # 3.33 is above the closed-form bound sigma_min(A|ker C) = 1 of tests/engine/test_engine.py)
    assert (c.finding, c.verdict) == ("infeasible", "infeasible-certified")
    assert rep.exit_code() == 3
    uir = audit_published("uir.thm3_1", EX / "uir.thm3_1.rossler_published_gains.yaml").claim("status")
    # the claim "feasible" is refuted: the Farkas ray is proven exactly (a global proof)
    assert uir.finding == "infeasible" and uir.agrees is False


def test_value_claims_and_skipped_keys():
    rep = audit_published("thesis.thm3_2_1", EX / "thesis.thm3_2_1.ex3_2_1.yaml")
    L = rep.claim("L")
    # the generated audit variant (t.luenberger(..., fixes=Lbar) -> fixed_L) decides the printed
    # gain itself: the LMI (3.11) in P with L given is certified
    assert L.kind == "gain" and L.finding == "certified" and L.route.startswith("fixed_L = 1")
    assert rep.claim("eig_A_LC").kind == "skipped"
    crane = audit_published("thesis.thm4_1_3", EX / "thesis.thm4_1_3.ex4_1_4_crane.yaml")
    assert crane.claim("E").finding == "matches" and crane.claim("E").difference == 0  # from the printed Y
    assert crane.claim("N").finding == "differs"  # +-0.001 from the rounded Y, K (T1.9 line 205)


def test_bad_input():
    with pytest.raises(DataError, match="no 'published:' section"):
        audit_published("qib.cor1", EX / "qib.cor1.flexible-joint.yaml")
    raw = _raw("qib.thm1.flexible-joint.yaml")
    raw["published"]["P"] = [[1.0, 2.0], [2.0, 1.0]]
    with pytest.raises(DataError, match="published 'P'"):
        audit_published("qib.thm1", raw)


def test_point_certificate_is_the_certifiers():
    """The point route certifies exactly what lmic.certify says at the packed printed point."""
    raw = _raw("uio_dt.thm3_1.flexible_joint_published_gains.yaml")
    prob = compile_theorem("uio_dt.thm3_1", raw)
    cert = certify(prob, Solution("feasible", x=prob.pack({"P": raw["published"]["P"]})))
    claim = audit_published("uio_dt.thm3_1", raw).claim("P")
    assert cert.verdict == claim.verdict == "certified"
    assert claim.margin == pytest.approx(cert.min_margin) == pytest.approx(0.2445, abs=1e-3)


def test_published_text_or_matrix_where_a_number_belongs_is_skipped_with_the_reason():
    """A word in place of a variable, or a matrix in place of a parameter, is named as such."""
    raw = _raw("qib.thm1.flexible-joint.yaml")
    raw["published"] = {"omega": "see eq. (40)", "beta": [[1.0, 2.0]], "gamma": "zero"}
    rep = audit_published("qib.thm1", raw)
    omega, beta, gamma = rep.claim("omega"), rep.claim("beta"), rep.claim("gamma")
    assert omega.finding == "skipped" and omega.reason == "'see eq. (40)' is not a number"
    assert gamma.finding == "skipped" and gamma.reason == "'zero' is not a number"
    assert beta.finding == "skipped" and beta.reason == "parameter 'beta' is a number, not a (1, 2) matrix"
