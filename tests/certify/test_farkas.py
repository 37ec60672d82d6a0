"""Farkas certificates: closed and strict infeasibility, sign conventions, bad certificates."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.sparse as sp
from certify_helpers import lmi_from, lyapunov

from lmic.certify import certify
from lmic.certify.farkas import prove_farkas, verify_farkas
from lmic.errors import CertificateError
from lmic.ir.problem import LinearConstraints, Objective, Problem, Variable
from lmic.reductions.pipeline import solve as solve_with_reductions
from lmic.solution import Solution

UNSTABLE = np.array([[0.5, 1.0], [0.0, -1.0]])


def _lyapunov_certificate(A: np.ndarray) -> dict:
    """Z1 = v v^T, Z2 = 2 lambda v v^T for A v = lambda v, lambda > 0 (exact by construction)."""
    w, V = np.linalg.eig(A)
    k = int(np.argmax(w.real))
    v = V[:, k].real
    Z1 = np.outer(v, v)
    return {"lmis": [2 * w[k].real * Z1, Z1], "linear": []}


def _box_problem() -> Problem:
    # p >= 0, -1 - p >= 0: infeasible even when closed
    return Problem(
        [Variable("p", "scalar", (1, 1))],
        [
            lmi_from("p >= 0", [np.zeros((1, 1)), np.ones((1, 1))], strict=False),
            lmi_from("-1 - p >= 0", [-np.ones((1, 1)), -np.ones((1, 1))], strict=False),
        ],
        LinearConstraints.empty(1),
        Objective("feasibility", np.zeros(2)),
    )


def test_strict_homogeneous_lyapunov_infeasibility_is_verified():
    prob = lyapunov(UNSTABLE)
    r = verify_farkas(prob, _lyapunov_certificate(UNSTABLE))
    assert r["verified"] and r["kind"] == "strict"
    assert r["g0"] == 0.0 and r["tau"] == pytest.approx(1.0)
    assert r["margin_bound"] < 1e-12
    assert "strict problem" in r["reason"]


def test_the_same_certificate_does_not_prove_the_closed_problem_infeasible():
    # closed Lyapunov LMIs are feasible at P = 0: no certificate may claim otherwise
    prob = lyapunov(UNSTABLE, strict=False)
    r = verify_farkas(prob, _lyapunov_certificate(UNSTABLE))
    assert not r["verified"]
    assert "no separation" in r["reason"]


def test_closed_infeasibility_with_linear_rows():
    # x >= 1 (row) and x <= -1 (LMI): y = 1, Z = 1 gives g0 = -1 - 1 = -2, g1 = 1 - 1 = 0
    prob = Problem(
        [Variable("x", "scalar", (1, 1))],
        [lmi_from("-1 - x >= 0", [-np.ones((1, 1)), -np.ones((1, 1))], strict=False)],
        LinearConstraints(sp.csr_matrix(np.array([[-1.0, 1.0]])), ["ge"], [False], ["x >= 1"]),
        Objective("feasibility", np.zeros(2)),
    )
    r = verify_farkas(prob, {"lmis": [np.eye(1)], "linear": np.array([1.0])})
    assert r["verified"] and r["kind"] == "closed"
    assert r["g0"] == pytest.approx(-1.0)  # after normalisation to sum tr Z + |y| = 1
    # g_1 = 0 in float is not a proof of g_1 = 0: the radius stops at the check's own rounding
    # (never inf, never "no solution with ||x|| <= inf"); the exact proof is what makes it global
    assert np.isfinite(r["radius"]) and r["radius"] > 1e12
    # ... shrunk a little more for g_0's own rounding and the reconstructed Z's distance from PSD
    assert 0.5 * (-r["g0"] / r["residual_floor"]) < r["radius"] < -r["g0"] / r["residual_floor"]
    assert prove_farkas(prob, {"lmis": [np.eye(1)], "linear": np.array([1.0])})["proven"]


def test_opposite_sign_convention_is_recognised():
    r = verify_farkas(_box_problem(), {"lmis": [-np.eye(1), -np.eye(1)], "linear": []})
    assert r["verified"] and r["negated"]
    assert "opposite sign convention" in r["reason"]


def test_residual_in_the_trace_condition_is_named():
    r = verify_farkas(_box_problem(), {"lmis": [np.eye(1), 2 * np.eye(1)], "linear": []})
    assert not r["verified"]
    assert "trace condition fails for x[0] (p)" in r["reason"]
    assert r["rel_residual"] > 0.1


def test_non_psd_multiplier_is_rejected():
    prob = lyapunov(UNSTABLE)
    cert = _lyapunov_certificate(UNSTABLE)
    cert["lmis"][0] = cert["lmis"][0] - 0.5 * np.eye(2)
    r = verify_farkas(prob, cert)
    assert not r["verified"]
    assert "not PSD" in r["reason"]


def test_zero_certificate_and_bad_shapes():
    assert verify_farkas(_box_problem(), {"lmis": [np.zeros((1, 1)), None]})["reason"] == "the certificate is zero"
    with pytest.raises(CertificateError, match="shape"):
        verify_farkas(_box_problem(), {"lmis": [np.eye(2), np.eye(1)]})
    with pytest.raises(CertificateError, match="LMI multipliers"):
        verify_farkas(_box_problem(), {"lmis": [np.eye(1)] * 3})
    with pytest.raises(CertificateError, match="non-finite"):
        verify_farkas(_box_problem(), {"lmis": [np.full((1, 1), np.nan), np.eye(1)]})


def test_certify_turns_a_verified_certificate_into_infeasible_certified():
    prob = lyapunov(UNSTABLE)
    sol = Solution("infeasible", farkas=_lyapunov_certificate(UNSTABLE), backend="t")
    good = certify(prob, sol, exact=True)
    assert good.verdict == "infeasible-certified" and good.ok
    assert good.farkas["kind"] == "strict" and good.farkas["scope"]["basis"] == "exact"
    # the same certificate checked in floating point only: the relative margin is bounded
    float_only = certify(prob, sol)
    assert float_only.verdict == "infeasible-bounded" and float_only.farkas["scope"]["basis"] == "homogeneous"
    bogus = certify(prob, Solution("infeasible", farkas={"lmis": [np.eye(2), np.eye(2)], "linear": []}))
    assert bogus.verdict == "unverified"
    assert bogus.reason.startswith("infeasibility not verified: ")


def test_backends_infeasibility_certificates_verify():
    from lmic.backends.registry import available_backend_names, get_backend

    names = [b for b in ("clarabel", "scs", "cvxopt") if b in available_backend_names()]
    if not names:
        pytest.skip("no SDP backend installed")
    prob = lyapunov(UNSTABLE)
    for name in names:
        sol = solve_with_reductions(get_backend(name), prob)
        assert sol.status == "infeasible", name
        cert = certify(prob, sol)  # floating point: no point of relative margin above rho
        assert cert.verdict == "infeasible-bounded" and cert.farkas["verified"], (name, cert.reason)
        assert cert.farkas["scope"]["rho"] < 1e-6, (name, cert.reason)
        # the unstable mode e_1 is rational: the exact proof of the backend's ray is global
        assert certify(prob, sol, exact=True).verdict == "infeasible-certified", (name, cert.reason)


# ---- repair of inaccurate certificates -----------------------------------------------------


def _uir_sdpa():
    import json
    from pathlib import Path

    import yaml

    from lmic.compile import compile_theorem

    here = Path(__file__).parent
    case = json.loads((here / "data" / "uir_sdpa_farkas.json").read_text())
    system = yaml.safe_load((here.parents[1] / "examples" / case["system"]).read_text())
    prob = compile_theorem(case["theorem"], system, params=case["params"])
    assert prob.n == case["n"], "the recorded certificate no longer fits the compiled IR"
    farkas = {"lmis": [np.array(Z) for Z in case["farkas"]["lmis"]], "linear": np.array(case["farkas"]["linear"])}
    return prob, farkas


def test_sdpa_certificate_with_residual_3e_5_is_verified_after_repair():
    prob, farkas = _uir_sdpa()
    raw = verify_farkas(prob, farkas, repair=False)
    assert not raw["verified"] and raw["rel_residual"] == pytest.approx(2.76e-5, rel=1e-2)
    assert "x[53] (mubar)" in raw["reason"]
    r = verify_farkas(prob, farkas)
    assert r["verified"] and r["repaired"] and r["kind"] == "closed"
    assert r["original"]["rel_residual"] == pytest.approx(2.76e-5, rel=1e-2)
    assert r["rel_residual"] < 1e-12 and r["g0"] < -0.1
    # no feasible point with ||x||_inf below it (at the rounding level of the float check:
    # the residual 1e-14 is below it, so the radius is set by the check's own rounding)
    assert 1e9 < r["radius"] <= -r["g0"] / r["residual_floor"]
    assert r["repair"]["change"] < 0.1  # a cleaned-up version of the solver's certificate
    # the recorded repaired certificate verifies on its own, without another repair
    again = verify_farkas(prob, r["certificate"], repair=False)
    assert again["verified"] and again["rel_residual"] == pytest.approx(r["rel_residual"], abs=1e-15)
    cert = certify(prob, Solution("infeasible", farkas=farkas, backend="sdpa"))
    # the ray is a float certificate of an inhomogeneous problem: it proves "no solution with
    # ||x||_inf <= R" (R > 1e9), not infeasibility (lmic.certify.farkas.scope)
    assert cert.verdict == "infeasible-bounded" and cert.farkas["scope"]["radius"] > 1e9
    assert "after repair" in cert.farkas["reason"]


def test_perturbed_certificate_of_a_feasible_problem_stays_unverified():
    # A is stable (eigenvalues -1e-3, -1): the strict Lyapunov LMIs are feasible, so no
    # certificate exists. The certificate of the nearby unstable A (+1e-3) has a relative
    # residual ~1e-3 here: close enough to be repaired, and the repair must fail.
    eps = 1e-3
    stable = np.array([[-eps, 1.0], [0.0, -1.0]])
    near = _lyapunov_certificate(np.array([[eps, 1.0], [0.0, -1.0]]))
    prob = lyapunov(stable)
    raw = verify_farkas(prob, near, repair=False)
    assert not raw["verified"] and 1e-6 < raw["rel_residual"] < 1e-2
    r = verify_farkas(prob, near)
    assert not r["verified"] and not r["repaired"]
    assert r["repair"]["reason"].startswith("the repair shrank the certificate to zero")
    assert certify(prob, Solution("infeasible", farkas=near)).verdict == "unverified"


def test_perturbed_sdpa_certificate_does_not_pass_on_a_feasible_variant():
    # the same SDPA multipliers against a feasible problem (every constant term made slack)
    import dataclasses

    import scipy.sparse as sp

    prob, farkas = _uir_sdpa()
    lmis = []
    for lmi in prob.lmis:
        C = lmi.coeffs.tolil()
        from lmic.ir.svec import tril_rows_cols

        r, c = tril_rows_cols(lmi.dim)
        C[np.flatnonzero(r == c), 0] = 1e6  # F_i(0) = 1e6 I + ...: x = 0 is strictly feasible
        lmis.append(dataclasses.replace(lmi, coeffs=sp.csc_matrix(C)))
    A = prob.linear.A.tolil()
    A[:, 0] = 1e6
    feasible = dataclasses.replace(prob, lmis=lmis, linear=dataclasses.replace(prob.linear, A=sp.csr_matrix(A)))
    r = verify_farkas(feasible, farkas)
    assert not r["verified"]


def test_certificate_far_from_one_is_not_repaired():
    r = verify_farkas(_box_problem(), {"lmis": [np.eye(1), 2 * np.eye(1)], "linear": []})
    assert not r["verified"] and r["repair"]["reason"].startswith("not attempted")


def test_repair_keeps_the_multipliers_in_the_cone():
    from lmic.certify.farkas import repair_farkas

    prob, farkas = _uir_sdpa()
    rep = repair_farkas(prob, farkas)
    for Z in rep["certificate"]["lmis"]:
        assert np.linalg.eigvalsh(Z)[0] > -1e-15
    assert np.all(np.asarray(rep["certificate"]["linear"]) >= 0)  # ge rows
    total = sum(np.trace(Z) for Z in rep["certificate"]["lmis"]) + np.sum(rep["certificate"]["linear"])
    assert total == pytest.approx(1.0, rel=0.1)


# ---- exact Farkas certificates -------------------------------------------------------------


def _exact_g(prob, lmis, y):
    """g_k = sum_i <F_i^(k), Z_i> + a_k . y in Fractions, straight from the IR coefficients."""
    from fractions import Fraction

    from lmic.ir.svec import tril_rows_cols

    g = [Fraction(0)] * (1 + prob.n)
    for lmi, Z in zip(prob.lmis, lmis, strict=True):
        C = lmi.coeffs.tocoo()
        r, c = tril_rows_cols(lmi.dim)
        for t, k, v in zip(C.row, C.col, C.data, strict=True):
            i, j = int(r[t]), int(c[t])
            g[k] += Fraction(float(v)) * Z[i][j] * (1 if i == j else 2)
    A = prob.linear.A.tocoo()
    for row, k, v in zip(A.row, A.col, A.data, strict=True):
        g[k] += Fraction(float(v)) * y[row]
    return g


def test_exact_farkas_certificate_of_the_sdpa_answer_checks_independently():
    from fractions import Fraction

    from lmic.certify.exact import prove_psd
    from lmic.certify.farkas import prove_farkas

    prob, farkas = _uir_sdpa()
    assert not prove_farkas(prob, farkas)["proven"]  # the solver's own certificate is too rough
    rep = verify_farkas(prob, farkas)["certificate"]
    r = prove_farkas(prob, rep, keep_certificate=True)
    assert r["proven"] and r["kind"] == "closed", r["reason"]
    assert r["g0"] == pytest.approx(-0.195, abs=1e-3)
    ex = r["exact_certificate"]
    g = _exact_g(prob, ex["lmis"], ex["linear"])
    assert all(v == 0 for v in g[1:]) and g[0] < 0
    for Z in ex["lmis"]:
        den = 1
        for row in Z:
            for f in row:
                den = den * Fraction(f).denominator // math.gcd(den, Fraction(f).denominator)
        assert prove_psd([[int(Fraction(f) * den) for f in row] for row in Z])["proven"]
    assert all(v >= 0 for v in ex["linear"])  # every row is 'ge'


def test_certify_exact_labels_infeasibility_exact():
    prob, farkas = _uir_sdpa()
    cert = certify(prob, Solution("infeasible", farkas=farkas, backend="sdpa"), exact=True)
    assert cert.label == "infeasible-certified (exact)"
    assert cert.exact["source"] == "repaired" and cert.exact["kind"] == "closed"
    homogeneous = lyapunov(UNSTABLE)
    c2 = certify(homogeneous, Solution("infeasible", farkas=_lyapunov_certificate(UNSTABLE)), exact=True)
    assert c2.label == "infeasible-certified (exact)" and c2.exact["kind"] == "strict"


def test_exact_farkas_never_proves_a_feasible_problem_infeasible():
    from lmic.certify.farkas import prove_farkas

    eps = 1e-3
    prob = lyapunov(np.array([[-eps, 1.0], [0.0, -1.0]]))
    near = _lyapunov_certificate(np.array([[eps, 1.0], [0.0, -1.0]]))
    assert not prove_farkas(prob, near)["proven"]
    cert = certify(prob, Solution("infeasible", farkas=near), exact=True)
    assert cert.verdict == "unverified" and not cert.exact["proven"]
    # closed Lyapunov LMIs are feasible at P = 0: the strict certificate proves nothing there
    closed = lyapunov(UNSTABLE, strict=False)
    assert not prove_farkas(closed, _lyapunov_certificate(UNSTABLE))["proven"]


def test_round_off_on_a_zero_row_of_the_multiplier_does_not_block_the_exact_proof():
    # Block (41) of the repaired SDPA certificate has an exactly zero row: the face lies in a
    # coordinate subspace. LAPACK leaves ~1e-14 there in the eigenvectors (how much depends on
    # the build); rounded to 2^-50 that tilts the face out of the subspace and an equation that
    # vanishes identically on the true face binds. Inject such noise deterministically.
    from lmic.certify.farkas import prove_farkas

    prob, farkas = _uir_sdpa()
    rep = verify_farkas(prob, farkas)["certificate"]
    lmis = [np.array(Z) for Z in rep["lmis"]]
    i = next(k for k, Z in enumerate(lmis) if Z.shape[0] > 1 and np.min(np.diag(Z)) < 1e-20)
    j = int(np.argmin(np.diag(lmis[i])))
    e, v = np.eye(len(lmis[i]))[j], np.linalg.eigh(lmis[i])[1][:, -1]
    lmis[i] = lmis[i] + 5e-15 * (np.outer(e, v) + np.outer(v, e))
    assert np.max(np.abs(np.linalg.eigh(lmis[i])[1][j, -1])) > 2.0**-50  # survives the rounding
    r = prove_farkas(prob, {"lmis": lmis, "linear": rep["linear"]}, keep_certificate=True)
    assert r["proven"] and r["kind"] == "closed", r["reason"]
    ex = r["exact_certificate"]
    g = _exact_g(prob, ex["lmis"], ex["linear"])
    assert all(val == 0 for val in g[1:]) and g[0] < 0
    assert all(ex["lmis"][i][j][c] == 0 for c in range(len(lmis[i])))  # the zero row stays exactly zero


def test_exact_proof_moves_towards_the_centre_when_the_projection_leaves_the_cone():
    # p >= 1, p <= -1 twice: certificates are a = b + c (multipliers of the three LMIs), g0 < 0.
    # The rough (a, b, c) = (0.4, 0.5, 0.001) has residual -0.101; its least-norm projection
    # makes c = 0.001 - 0.101/3 < 0, and c is above every face threshold, so no face drops it.
    from fractions import Fraction

    from lmic.certify.farkas import prove_farkas

    prob = Problem(
        [Variable("p", "scalar", (1, 1))],
        [
            lmi_from("p - 1 >= 0", [-np.ones((1, 1)), np.ones((1, 1))], strict=False),
            lmi_from("-1 - p >= 0 (b)", [-np.ones((1, 1)), -np.ones((1, 1))], strict=False),
            lmi_from("-1 - p >= 0 (c)", [-np.ones((1, 1)), -np.ones((1, 1))], strict=False),
        ],
        LinearConstraints.empty(1),
        Objective("feasibility", np.zeros(2)),
    )
    rough = {"lmis": [0.4 * np.eye(1), 0.5 * np.eye(1), 0.001 * np.eye(1)], "linear": []}
    r = prove_farkas(prob, rough, keep_certificate=True)
    assert r["proven"] and r["kind"] == "closed" and r["face"]["centered"], r["reason"]
    ex = r["exact_certificate"]
    a, b, c = (Fraction(Z[0][0]) for Z in ex["lmis"])
    assert min(a, b, c) >= 0 and a - b - c == 0 and -(a + b + c) < 0  # g1 = a - b - c, g0 = -(a + b + c)
    assert all(v == 0 for v in _exact_g(prob, ex["lmis"], [])[1:])
