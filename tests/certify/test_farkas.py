"""Farkas certificates: closed and strict infeasibility, sign conventions, bad certificates."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from certify_helpers import lmi_from, lyapunov

from lmic.certify import certify
from lmic.certify.farkas import verify_farkas
from lmic.errors import CertificateError
from lmic.ir.problem import LinearConstraints, Objective, Problem, Variable
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
    assert r["radius"] == float("inf")


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
    good = certify(prob, Solution("infeasible", farkas=_lyapunov_certificate(UNSTABLE), backend="t"))
    assert good.verdict == "infeasible-certified" and good.ok
    assert good.farkas["kind"] == "strict"
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
        sol = get_backend(name).solve(prob)
        assert sol.status == "infeasible", name
        cert = certify(prob, sol)
        assert cert.verdict == "infeasible-certified", (name, cert.reason)
