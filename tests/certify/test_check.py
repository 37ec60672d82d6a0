"""The certifier: margins relative to the term scale, statuses, derived gains and checks."""

from __future__ import annotations

import json

import numpy as np
import pytest
import scipy.sparse as sp
from certify_helpers import lmi_from, lyapunov, observer

from lmic.certify import Certificate, Tolerances, certify
from lmic.errors import LmicError
from lmic.ir.problem import LMI, Check, LinearConstraints, Objective, Problem, Variable
from lmic.solution import Solution


def test_feasible_lyapunov_point_is_certified(lyapunov_point):
    prob, x = lyapunov_point
    cert = certify(prob, Solution("optimal", x=x, backend="test"))
    assert cert.verdict == "certified"
    assert cert.ok and cert.label == "certified"
    assert [e["ok"] for e in cert.lmis] == [True, True]
    # A'P + PA = -I exactly, so F = I: lambda_min = 1 up to round-off
    assert cert.lmis[1]["min_eig"] == pytest.approx(1.0, rel=1e-9)
    assert 0 < cert.lmis[1]["rel_margin"] <= 1
    assert cert.checks[0]["name"] == "A Hurwitz" and cert.checks[0]["ok"]
    assert cert.checks[0]["value"] < 0
    assert cert.derived[0]["name"] == "Pinv" and cert.derived[0]["ok"]
    assert "smallest margin" in cert.reason


def test_homogeneous_lmi_is_judged_at_its_own_scale(lyapunov_point):
    prob, x = lyapunov_point
    # a scaled-down certificate is still a certificate (the LMIs are homogeneous) ...
    tiny = certify(prob, Solution("optimal", x=1e-7 * x))
    assert tiny.verdict == "certified"
    assert tiny.lmis[1]["rel_margin"] == pytest.approx(certify(prob, Solution("optimal", x=x)).lmis[1]["rel_margin"])


def test_near_zero_point_with_tiny_absolute_violation_is_rejected(stable_A):
    # the SCS situation: omega ~ 1.7e-7, violations of ~1e-9 absolute that an absolute
    # tolerance would accept, but that are a percent of the point's own scale
    prob = lyapunov(stable_A)
    P = 1e-7 * np.diag([1.0, 1.0, 1e-3])
    P[0, 2] = P[2, 0] = 1e-7 * 0.05  # makes P indefinite by ~2.5e-10 absolute
    x = prob.pack({"P": P})
    cert = certify(prob, Solution("optimal", x=x, backend="scs"))
    assert abs(cert.lmis[0]["min_eig"]) < 1e-8  # absolutely "zero"
    assert cert.verdict == "rejected"
    assert cert.lmis[0]["rel_margin"] < -1e-4
    assert "violated" in cert.reason and "relative" in cert.reason
    assert not cert.lmis[0]["ok"] and cert.lmis[0]["min_eig"] > -1e-9


def test_zero_point_is_rejected_for_strict_homogeneous_lmis_only(stable_A):
    prob = lyapunov(stable_A, strict=False)
    prob.derived.clear()
    cert = certify(prob, Solution("optimal", x=np.zeros(prob.n)))
    # x = 0 satisfies the closed LMIs trivially; that certifies nothing for a strict theorem,
    # and for the closed problem it is a (trivial) valid point
    assert cert.verdict == "certified"
    strict = certify(lyapunov(stable_A), Solution("optimal", x=np.zeros(prob.n)))
    assert strict.verdict == "rejected"
    assert "~0" in strict.reason


def _marginal_problem(strict: bool) -> tuple[Problem, np.ndarray]:
    """2x2 LMI [[p, 1], [1, q]] > 0 at a point with lambda_min = -1.6e-7, ||P|| ~ 7.5."""
    mats = [np.array([[0.0, 1.0], [1.0, 0.0]]), np.diag([1.0, 0.0]), np.diag([0.0, 1.0])]
    prob = Problem(
        [Variable("p", "scalar", (1, 1), offset=0), Variable("q", "scalar", (1, 1), offset=1)],
        [lmi_from("marginal", mats, strict)],
        LinearConstraints.empty(2),
        Objective("feasibility", np.zeros(3)),
    )
    q = 7.5
    # det = p q - 1; choose p so that lambda_min = -1.6e-7 exactly enough
    lam = -1.6e-7
    p = 1.0 / (q - lam) + lam
    return prob, np.array([p, q])


def test_inaccurate_status_with_small_violation_is_not_certified():
    prob, x = _marginal_problem(strict=True)
    cert = certify(prob, Solution("inaccurate", x=x, backend="clarabel", native_status="AlmostSolved"))
    assert cert.lmis[0]["min_eig"] == pytest.approx(-1.6e-7, rel=1e-3)
    assert cert.verdict == "rejected"
    assert "marginal" in cert.reason and "-1.6e-07" in cert.reason


def test_non_strict_tolerance_is_not_granted_to_inaccurate_solves():
    prob, x = _marginal_problem(strict=False)
    # relative violation ~2e-8: inside a 1e-7 tolerance when the solver claims success ...
    # ... but "within tolerance" proves nothing: the exact proof runs and disproves it, so the
    # point is rejected as holding only within the tolerance ...
    held = certify(prob, Solution("optimal", x=x), tol=1e-7)
    assert held.verdict == "rejected"
    assert held.lmis[0]["within_tolerance"] and held.lmis[0]["exact"] == "disproved"
    assert "LMI 'marginal' is not positive semidefinite at the solver's point" in held.reason
    # ... and when the solver itself says the answer is inaccurate, it is a plain violation
    bad = certify(prob, Solution("inaccurate", x=x), tol=1e-7)
    assert bad.verdict == "rejected" and "violated" in bad.reason
    assert "inaccurate" in bad.lmis[0]["note"]


def test_failed_check_rejects_even_when_every_lmi_holds():
    # a "theorem" whose only LMI is P > 0: nothing forces the gain to stabilise
    A = np.array([[1.1, 0.2], [0.0, 0.9]])
    C = np.array([[1.0, 0.0]])
    full = observer(A, C)
    prob = Problem(
        full.variables,
        [
            lmi_from(
                "P > 0",
                [np.zeros((2, 2))]
                + [
                    np.diag([1.0, 0.0]),
                    np.array([[0, 1.0], [1.0, 0]]),
                    np.diag([0.0, 1.0]),
                    np.zeros((2, 2)),
                    np.zeros((2, 2)),
                ],
            )
        ],
        full.linear,
        full.objective,
        data=full.data,
        derived=full.derived,
        checks=full.checks,
    )
    x = prob.pack({"P": np.eye(2), "G": np.array([[-1.0], [0.0]])})  # L = [-1, 0]: A - LC has 2.1
    cert = certify(prob, Solution("optimal", x=x, backend="scs"))
    assert all(e["ok"] for e in cert.lmis)
    assert cert.checks[0]["value"] == pytest.approx(2.1)
    assert not cert.checks[0]["ok"]
    assert cert.verdict == "rejected"
    assert cert.reason.startswith("check 'A - L C Schur stable' failed: spectral radius 2.1")


def test_observer_certified_point_gives_a_stabilising_gain_and_garbage_point_does_not():
    A = np.array([[1.1, 0.3], [0.0, 0.7]])
    C = np.array([[1.0, 0.0]])
    prob = observer(A, C)
    L = np.array([[1.1], [0.0]])  # A - L C = [[0, .3], [0, .7]]
    from scipy.linalg import solve_discrete_lyapunov

    Acl = A - L @ C
    P = solve_discrete_lyapunov(Acl.T, np.eye(2))  # Acl' P Acl - P = -I
    good = prob.pack({"P": P, "G": P @ L})
    cert = certify(prob, Solution("optimal", x=good))
    assert cert.verdict == "certified"
    assert cert.checks[0]["value"] == pytest.approx(0.7)
    # a near-zero point with absolute noise: the gain is garbage and the LMI fails relatively
    garbage = prob.pack({"P": 1e-7 * np.eye(2), "G": 1e-7 * np.array([[-1.0], [0.0]])})
    bad = certify(prob, Solution("optimal", x=garbage, backend="scs"))
    assert bad.verdict == "rejected"
    assert -1e-6 < bad.lmis[0]["min_eig"] < 0  # tiny in absolute terms
    assert not bad.lmis[0]["ok"] and bad.lmis[0]["rel_margin"] < 0
    assert not bad.checks[0]["ok"]


def test_objective_is_recomputed_and_compared():
    prob = Problem(
        [Variable("t", "scalar", (1, 1))],
        [lmi_from("t >= 1", [np.array([[-1.0]]), np.array([[1.0]])], strict=False)],
        LinearConstraints.empty(1),
        Objective("min", np.array([0.5, 2.0])),
    )
    good = certify(prob, Solution("optimal", x=np.array([1.0]), objective=2.5))
    assert good.verdict == "certified"
    assert good.objective["value"] == 2.5 and good.objective["ok"]
    bad = certify(prob, Solution("optimal", x=np.array([1.0]), objective=2.0))
    assert bad.verdict == "rejected"
    assert bad.reason == "objective: the solver reports 2.0, the point gives 2.5"
    assert bad.objective["rel_diff"] == pytest.approx(0.2)


def test_linear_rows_eq_ge_and_strict():
    A = sp.csr_matrix(np.array([[-1.0, 1.0, 1.0], [0.0, 1.0, 0.0], [-0.5, 0.0, 1.0]]))
    lin = LinearConstraints(A, ["eq", "ge", "ge"], [False, False, True], ["x+y=1", "x>=0", "y>1/2"])
    prob = Problem(
        [Variable("x", "scalar", (1, 1), offset=0), Variable("y", "scalar", (1, 1), offset=1)],
        [],
        lin,
        Objective("feasibility", np.zeros(3)),
    )
    assert certify(prob, Solution("feasible", x=np.array([0.25, 0.75]))).verdict == "certified"
    eq = certify(prob, Solution("feasible", x=np.array([0.25, 0.76])))
    assert eq.verdict == "rejected" and eq.reason.startswith("equality 'x+y=1' violated: residual 0.01")
    strict = certify(prob, Solution("feasible", x=np.array([0.5, 0.5])))
    assert strict.verdict == "rejected" and "inequality 'y>1/2' violated" in strict.reason
    assert [r["ok"] for r in strict.linear] == [True, True, False]


@pytest.mark.parametrize(
    ("status", "x", "needle"),
    [
        ("infeasible", None, "no dual (Farkas) certificate"),
        ("error", None, "returned no point"),
        ("unbounded", None, "returned no point"),
    ],
)
def test_nothing_to_check_is_unverified(lyapunov_point, status, x, needle):
    prob, _ = lyapunov_point
    cert = certify(prob, Solution(status, x=x, message="time limit"))
    assert cert.verdict == "unverified"
    assert needle in cert.reason
    assert not cert.ok


def test_non_finite_point_is_rejected_and_wrong_length_is_an_error(lyapunov_point):
    prob, x = lyapunov_point
    y = x.copy()
    y[0] = np.nan
    assert certify(prob, Solution("optimal", x=y)).verdict == "rejected"
    with pytest.raises(LmicError, match="entries"):
        certify(prob, Solution("optimal", x=x[:-1]))


def test_singular_P_fails_the_derived_gain_and_its_checks(stable_A):
    prob = lyapunov(stable_A, strict=False)
    prob.checks.append(Check("Pinv finite", "finite", {"name": "Pinv"}))
    cert = certify(prob, Solution("optimal", x=np.zeros(prob.n)))
    assert cert.derived[0]["ok"] is False and cert.derived[0]["value"] is None
    assert cert.verdict == "rejected"
    assert cert.reason.startswith("derived 'Pinv' failed")
    assert cert.checks[1]["ok"] is False and "no value" in cert.checks[1]["error"]


def test_every_check_kind():
    from lmic.certify.check import evaluate_checks

    env = {"S": np.array([[-2.0, 0.5], [0.5, -1.0]]), "s": 0.3, "M": np.array([[0.2, 5.0], [0.0, 0.3]])}
    cases = [
        ("schur_stable", "M", None, 0.3, True),
        ("hurwitz", "S", None, None, True),
        ("negative_definite", "S", None, None, True),
        ("positive_definite", "S", None, None, False),
        ("negative_semidefinite", "S", None, None, True),
        ("positive_semidefinite", "S", None, None, False),
        ("less_than", "s", 0.5, 0.3, True),
        ("greater_than", "s", 0.5, 0.3, False),
        ("finite", "M", None, 5.0, True),
    ]
    checks = [Check(f"c{i}", kind, {"name": name}, bound) for i, (kind, name, bound, _, _) in enumerate(cases)]
    out = evaluate_checks(checks, env, Tolerances())
    for (kind, _, _, value, ok), r in zip(cases, out, strict=True):
        assert r["ok"] is ok, kind
        if value is not None:
            assert r["value"] == pytest.approx(value), kind
    bad = evaluate_checks([Check("c", "less_than", {"name": "M"}, 1.0)], env, Tolerances())[0]
    assert not bad["ok"] and "needs a scalar" in bad["error"]


def test_margin_claim_is_reported(lyapunov_point):
    prob, x = lyapunov_point
    cert = certify(prob, Solution("optimal", x=x, margin=0.5, strategy="max-margin"))
    assert cert.margin["claimed"] == 0.5 and cert.margin["strategy"] == "max-margin"
    assert cert.margin["achieved"] == pytest.approx(min(e["min_eig"] for e in cert.lmis))


def test_to_dict_is_json(lyapunov_point):
    prob, x = lyapunov_point
    d = certify(prob, Solution("optimal", x=x), exact=True).to_dict()
    text = json.dumps(d, allow_nan=False)
    back = json.loads(text)
    assert back["verdict"] == "certified" and back["exact"]["proven"] is True
    assert set(back["lmis"][0]) >= {"name", "dim", "strict", "min_eig", "max_abs", "min_margin", "rel_margin", "ok"}
    nan = Certificate("rejected", lmis=[{"min_eig": float("nan"), "scale": float("inf")}]).to_dict()
    assert nan["lmis"][0] == {"min_eig": "nan", "scale": "inf"}


def test_tolerances_coerce_rejects_garbage():
    assert Tolerances.coerce(None) == Tolerances()
    with pytest.raises(LmicError, match="unknown tolerance"):
        Tolerances.coerce({"nope": 1})
    with pytest.raises(LmicError):
        Tolerances.coerce(-1.0)
    with pytest.raises(LmicError):
        Tolerances.coerce("1e-3")


def test_strict_threshold_is_relative_not_absolute():
    # lambda_min = 1e-7 absolute on a matrix of scale 1e6: relative 1e-13, below strict_rel
    prob = Problem(
        [Variable("p", "scalar", (1, 1))],
        [LMI("big", 2, sp.csc_matrix(np.array([[1e6, 0.0], [0.0, 0.0], [1e-7, 0.0]])), strict=True)],
        LinearConstraints.empty(1),
        Objective("feasibility", np.zeros(2)),
    )
    cert = certify(prob, Solution("optimal", x=np.array([0.0])))
    assert cert.lmis[0]["min_eig"] == pytest.approx(1e-7)
    assert cert.verdict == "rejected"
    loose = certify(prob, Solution("optimal", x=np.array([0.0])), tol={"strict_rel": 1e-15})
    assert loose.verdict == "certified"
