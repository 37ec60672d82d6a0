"""The primal end from the proven dual end (lmic.upper_end, lmic.route_upper).

The near-unstable bounded-real lemma (spectral abscissa -0.01, n = 8, seed 6): Clarabel alone
stops with a rejected point and no upper end; the default route must give a certified point, an
enclosure within 1e-6 that ``lmic audit`` re-verifies, and the H-infinity norm computed
independently (Hamiltonian bisection, ``certify_helpers.hinf_norm``) inside it.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import scipy.sparse as sp

sys.path.insert(0, str(Path(__file__).parents[1] / "certify"))
from certify_helpers import hinf_norm, stable_system  # noqa: E402

from lmic.api import solve  # noqa: E402
from lmic.certify import audit_certificate, certify, write_certificate  # noqa: E402
from lmic.certify.enclosure import primal_end  # noqa: E402
from lmic.certify.enclosure_audit import audit_enclosure  # noqa: E402
from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable  # noqa: E402
from lmic.solution import Solution  # noqa: E402
from lmic.upper_end import recentred_problem, upper_from_lower  # noqa: E402


def _near_unstable(n: int, seed: int) -> tuple[dict, tuple[float, float]]:
    A, B, C = stable_system(n, seed, margin=0.01)
    system = {"lmic": 1, "data": {"A": A.tolist(), "B": B.tolist(), "C": C.tolist()}}
    return system, hinf_norm(A, B, C)


def test_near_unstable_brl_default_route_certified_with_gap_below_1e_6(tmp_path: Path) -> None:
    system, (a, b) = _near_unstable(8, 6)
    alone = solve("tutorial.bounded_real", system, backend="clarabel", backoff=0)
    assert alone.verdict != "certified"  # the case the route must rescue
    r = solve("tutorial.bounded_real", system, backoff=0)
    assert r.verdict == "certified" and r.certificate.verdict == "certified", r.certificate.reason
    enc = r.enclosure
    assert enc["consistent"] and enc["rel_gap"] <= 1e-6, enc["reason"]
    assert enc["lower"] <= b and a <= enc["upper"], (enc["lower"], a, b, enc["upper"])
    audit = audit_enclosure(r.problem, enc, r.certificate, r.backoff)
    assert audit["ok"], audit["message"]
    # the certifier on the original problem at the recorded primal point
    x = np.asarray(enc["restored_x"], dtype=float)
    assert primal_end(r.problem, x)["proven"]
    # the outcome's point (the most interior point the certifier accepts) through the certifier
    xo = np.asarray(r.solution.x, dtype=float)
    cert = certify(r.problem, Solution(status="optimal", x=xo, objective=r.problem.objective.value(xo)))
    assert cert.verdict == "certified", cert.reason
    # the certificate file and `lmic audit` (audit_certificate), then a tampered restored point
    from lmic.system import load_system

    sys_path = tmp_path / "system.json"
    sys_path.write_text(json.dumps(system))
    path = tmp_path / "brl.json"
    write_certificate(
        path, r.problem, r.solution, r.certificate, system=load_system(str(sys_path)), enclosure=enc, backoff=r.backoff
    )
    ok = audit_certificate(path)
    assert ok.ok and "enclosure" in ok.checked, ok.message
    doc = json.loads(path.read_text())
    doc["enclosure"]["restored_x"] = [v * (1 + 1e-3) for v in doc["enclosure"]["restored_x"]]
    path.write_text(json.dumps(doc))
    assert not audit_certificate(path).ok
    # a tampered upper end (below the point's objective), or a tampered point, is rejected
    lowered = dict(enc, upper=enc["upper"] - 1e-9 * abs(enc["upper"]))
    assert not audit_enclosure(r.problem, lowered, r.certificate)["ok"]
    moved = dict(enc, restored_x=(x * (1 - 1e-3)).tolist())
    assert not audit_enclosure(r.problem, moved, r.certificate)["ok"]


def _strict_pair() -> Problem:
    # inf t s.t. [[t, 1], [1, t]] > 0: infimum 1, not attained
    C = sp.csc_matrix(np.array([[0.0, 1.0], [1.0, 0.0], [0.0, 1.0]]))
    return Problem(
        [Variable("t", "scalar", (1, 1))],
        [LMI("M > 0", 2, C, strict=True)],
        LinearConstraints.empty(1),
        Objective("min", [0.0, 1.0]),
    )


def test_upper_from_lower_on_an_unattained_infimum() -> None:
    p = _strict_pair()
    r = upper_from_lower(p, 1.0, "clarabel", x_hint=np.array([2.0]))
    assert r["proven"] and 1.0 < r["value"] <= 1.0 + 1e-6 and r["rel_gap"] <= 1e-6
    assert primal_end(p, np.asarray(r["x"]))["proven"]


def test_upper_from_lower_with_a_wrong_dual_end_proves_nothing() -> None:
    # a "lower end" of 0.5, below the infimum 1: every slice it tries is empty, nothing is proved
    p = _strict_pair()
    r = upper_from_lower(p, 0.5, "clarabel", x_hint=np.array([2.0]))
    assert not r["proven"] and r["value"] is None and r["x"] is None
    assert "no solve gave a point proved feasible" in r["reason"]


def test_recentred_problem_is_the_identity_at_the_centre(monkeypatch) -> None:
    import lmic.upper_end

    p = _strict_pair()
    # F(x0) = [[t, 1], [1, t]]: the full congruence, T F(x0) T^T = I
    for t in (3.0, 1.0 + 1e-6):
        q, d = recentred_problem(p, np.array([t]), 1.0)
        assert np.allclose(q.lmis[0].coeffs.toarray()[:, 0], [1.0, 0.0, 1.0], atol=1e-9)
        assert d.shape == (1,) and d[0] > 0
    # a "large" problem: the well-conditioned block (t = 3) gets the diagonal congruence, unit
    # diagonal, the ill-conditioned one (t = 1 + 1e-6) still the full one
    monkeypatch.setattr(lmic.upper_end, "FULL_MAX", 0)
    q, d = recentred_problem(p, np.array([3.0]), 2.0)
    assert np.allclose(q.lmis[0].coeffs.toarray()[:, 0], [1.0, 1.0 / 3.0, 1.0])
    q, d = recentred_problem(p, np.array([1.0 + 1e-6]), 1.0)
    assert np.allclose(q.lmis[0].coeffs.toarray()[:, 0], [1.0, 0.0, 1.0], atol=1e-9)


def test_near_unstable_brl_undecided_alone_gets_an_upper_end() -> None:
    # n = 8, seed 2: Clarabel alone ends undecided (NumericalError) without an upper end
    system, (a, b) = _near_unstable(8, 2)
    assert solve("tutorial.bounded_real", system, backend="clarabel", backoff=0).verdict != "certified"
    r = solve("tutorial.bounded_real", system, backoff=0)
    assert r.verdict == "certified" and r.certificate.verdict == "certified", r.certificate.reason
    enc = r.enclosure
    assert enc["upper"] is not None and enc["rel_gap"] <= 1e-6
    assert enc["lower"] <= b and a <= enc["upper"]
    assert audit_enclosure(r.problem, enc, r.certificate, r.backoff)["ok"]


def test_near_unstable_brl_backed_off_point_is_certified() -> None:
    # n = 8, seed 0: the backed-off solve's own point is rejected (main: 'rejected'); the most
    # interior point within the bound replaces it
    system, (a, b) = _near_unstable(8, 0)
    r = solve("tutorial.bounded_real", system, backoff=1e-3)
    back = r.backoff
    assert back["verdict"] == "certified", back["reason"]
    x = np.asarray(back["x"], dtype=float)
    cert = certify(r.problem, Solution(status="optimal", x=x, objective=r.problem.objective.value(x)))
    assert cert.verdict == "certified", cert.reason
    assert a <= back["objective"] <= back["bound"] <= b * (1 + 1e-3) * (1 + 1e-6)
    assert audit_enclosure(r.problem, r.enclosure, r.certificate, back)["ok"]


def test_a_missing_primal_end_is_found_from_the_dual_end_without_escalating(monkeypatch) -> None:
    import lmic.routes

    system, (a, b) = _near_unstable(6, 1)
    real = lmic.routes.enclosure_of

    def without_upper(problem, sol, cert, exact, backend, options, budget_s=None, target=None):
        enc, t = real(problem, sol, cert, exact, backend, options, budget_s, target)
        return dict(enc, upper=None, rel_gap=None, gap=None, primal="no certified point"), t

    monkeypatch.setattr(lmic.routes, "enclosure_of", without_upper)
    r = solve("tutorial.bounded_real", system, backoff=0)
    assert r.verdict == "certified" and r.certificate.verdict == "certified", r.certificate.reason
    assert len(r.route["steps"]) == 1 and r.route["steps"][0]["upper"]["proven"]
    enc = r.enclosure
    assert enc["primal"] == "restored point" and enc["rel_gap"] <= 1e-6
    assert enc["lower"] <= b and a <= enc["upper"]
    assert audit_enclosure(r.problem, enc, r.certificate)["ok"]


def test_upper_from_lower_on_a_maximisation_stays_below_the_dual_end() -> None:
    from lmic.testing.conformance import CASES

    p = CASES["max_sense"].build()
    enc = solve(p, backend="clarabel", backoff=0).enclosure
    r = upper_from_lower(p, enc["upper"], "clarabel")
    assert r["proven"] and r["value"] <= enc["upper"] and r["rel_gap"] <= 1e-6
    pe = primal_end(p, np.asarray(r["x"]))
    assert pe["proven"] and pe["value"] == r["value"]
