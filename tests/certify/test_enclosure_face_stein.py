"""The exact dual end on the optimal face for the discrete-time (Stein) form
(lmic.certify.enclosure_face_stein): the discrete bounded-real lemma as a newcomer writes it, on
random Schur-stable plants, against the H-infinity norm from a frequency sweep; the audit
re-proves the bound from the recorded rational U and S_R and rejects a tampered one; the
continuous form still takes the KYP path."""

from __future__ import annotations

import json
from fractions import Fraction

import numpy as np
import pytest
import scipy.sparse as sp
from certify_helpers import inline_brl, inline_dbrl, stable_system

import lmic.api
from lmic.certify import audit_certificate, write_certificate
from lmic.certify.enclosure_dual import verify_dual_bound
from lmic.certify.enclosure_face import face_bound, lyapunov_structure, prove_face, verify_face
from lmic.certify.enclosure_face_stein import exact_orthogonal, rational_rotation, stein_structure
from lmic.compile.exact import exact_of
from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable


def _plant(n: int, seed: int):
    """A random plant with A scaled to spectral radius 0.9, B n x 2, C 2 x n."""
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    A *= 0.9 / max(abs(np.linalg.eigvals(A)))
    return A, rng.standard_normal((n, 2)), rng.standard_normal((2, n))


def _hinf_dt(A, B, C) -> float:
    """The peak of sigma_max(C (e^{j theta} I - A)^-1 B) over [0, pi]: a dense grid, then a bounded
    scalar refinement around the best grid points (no LMI involved)."""
    from scipy.optimize import minimize_scalar

    n = A.shape[0]

    def sig(th: float) -> float:
        return float(np.linalg.norm(C @ np.linalg.solve(np.exp(1j * th) * np.eye(n) - A, B), 2))

    grid = np.linspace(0.0, np.pi, 4001)
    vals = np.array([sig(th) for th in grid])
    best = float(vals.max())
    for i in np.argsort(-vals)[:5]:
        lo, hi = grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]
        res = minimize_scalar(lambda th: -sig(th), bounds=(lo, hi), method="bounded", options={"xatol": 1e-14})
        best = max(best, -float(res.fun))
    return best


def _solve(n: int, seed: int):
    A, B, C = _plant(n, seed)
    system = {"lmic": 1, "data": {"A": A.tolist(), "B": B.tolist(), "C": C.tolist()}}
    return (A, B, C), lmic.api.solve(inline_dbrl, system)


@pytest.mark.parametrize("n, seed", [(4, 0), (10, 0), (20, 0)])
def test_discrete_bounded_real_lower_end_is_proved_on_the_face(n, seed):
    (A, B, C), r = _solve(n, seed)
    assert r.verdict == "certified"
    e = r.enclosure
    d = e["dual"]
    assert d["proven"] and d["route"] == "face" and d["method"] == "exact", e["reason"]
    assert d["dual"]["structure"] == "stein" and d["problem"] == "exact"
    U = exact_orthogonal(d["dual"]["U"])
    assert U is not None  # exactly orthogonal, as rationals
    h = _hinf_dt(A, B, C)
    assert e["lower"] <= h * (1 + 1e-13)  # float evaluation of the peak
    assert h <= e["upper"]
    assert e["rel_gap"] <= 1e-6
    assert (h - e["lower"]) / h <= 1e-9  # the face point is at the peak
    num, _, den = d["lower_exact"].partition("/")
    assert Fraction(e["lower"]) <= Fraction(int(num), int(den or 1))


def test_audit_reproves_the_stein_face_and_rejects_tampering(tmp_path):
    """The audit recompiles the theorem exactly (registered for it, as a notebook would) and
    re-proves the bound from the recorded rational U and S_R alone."""
    from lmic.registry import REGISTRY, register

    try:
        register(inline_dbrl)
        _audit(tmp_path)
    finally:
        REGISTRY._theorems.pop("test.inline_discrete_bounded_real", None)


def _audit(tmp_path):
    (A, B, C), r = _solve(10, 1)
    e = r.enclosure
    assert e["dual"]["route"] == "face" and e["dual"]["dual"]["structure"] == "stein"
    assert verify_dual_bound(r.problem, e["dual"])["ok"]
    path = tmp_path / "dbrl.json"
    write_certificate(path, r.problem, r.solution, r.certificate, enclosure=e)
    assert audit_certificate(path).ok
    good = json.loads(path.read_text())
    for tamper in ("lower", "S_rest", "U", "U rotation", "structure"):
        doc = json.loads(json.dumps(good))
        enc = doc["enclosure"]
        point = enc["dual"]["dual"]
        if tamper == "lower":
            enc["lower"] = enc["dual"]["lower"] = enc["lower"] + 1e-7 * abs(enc["lower"])
        elif tamper == "S_rest":
            point["S_rest"][0][0] *= 1.5
        elif tamper == "U":  # no longer exactly orthogonal
            point["U"][0][0] = str(float(Fraction(point["U"][0][0])))
        elif tamper == "U rotation":  # exactly orthogonal, another angle: a smaller bound
            point["U"] = [[str(v) for v in row] for row in rational_rotation(0.3)]
        else:
            del point["structure"]
        path.write_text(json.dumps(doc))
        bad = audit_certificate(path)
        assert not bad.ok, tamper
        assert bad.field in ("enclosure.dual", "enclosure.lower"), (tamper, bad.field, bad.message)


def _first_order(a: float) -> Problem:
    """min g s.t. p > 0, -[[a^2 p - p, a p, 1], [*, p - g, 0], [*, *, -g]] > 0: the norm of
    1 / (z - a), 1 / (1 - |a|), at theta = 0 (a > 0) or pi (a < 0)."""
    F = np.array([[0, 1 - a * a, 0], [0, -a, 0], [-1, 0, 0], [0, -1, 1], [0, 0, 0], [0, 0, 1]], float)
    return Problem(
        [Variable("p", "scalar", (1, 1)), Variable("g", "scalar", (1, 1), offset=1)],
        [LMI("p > 0", 1, sp.csc_matrix([[0.0, 1.0, 0.0]])), LMI("dbrl", 3, sp.csc_matrix(F))],
        LinearConstraints.empty(2),
        Objective("min", [0.0, 0.0, 1.0]),
    )


@pytest.mark.parametrize("a, U, z, value", [(0.5, [[1]], 1.0, "2"), (-0.75, [[-1]], -1.0, "4")])
def test_first_order_norm_exactly(a, U, z, value):
    """S_E = w / (U - a) (U = +-1), the objective 2 S_E z / (w^2 + z^2): the norm at w = |z| = 1."""
    p = _first_order(a)
    st = stein_structure(p)
    assert st is not None and st["form"] == "stein" and st["state"].tolist() == [0]
    assert lyapunov_structure(p) is None  # not the continuous form
    r = prove_face(p, st, U, np.array([[1.0], [z]]))
    assert r["proven"] and r["lower_exact"] == value
    res = face_bound(p, None)  # the search alone finds the peak and proves it
    assert res["proven"] and Fraction(res["lower_exact"]) == Fraction(value)
    rec = {"lower": res["lower"], "dual": res["dual"]}
    assert verify_face(p, rec)["ok"]
    assert not verify_face(p, dict(rec, lower=res["lower"] * (1 + 1e-9)))["ok"]
    # the wrong sign of U: the Sylvester solve is another point, a smaller bound
    flip = [[-v for v in row] for row in U]
    r2 = prove_face(p, st, flip, np.array([[1.0], [z]]))
    assert not r2["proven"] or Fraction(r2["lower_exact"]) < Fraction(value)


def test_prove_face_rejects_a_u_that_is_not_exactly_orthogonal():
    p = _first_order(0.5)
    st = stein_structure(p)
    r = prove_face(p, st, [[0.5]], np.array([[1.0], [1.0]]))
    assert not r["proven"] and "orthogonal" in r["reason"]
    assert exact_orthogonal([[0.6, -0.8], [0.8, 0.6]]) is None  # floats: not exactly orthogonal
    assert exact_orthogonal([["3/5", "-4/5"], ["4/5", "3/5"]]) is not None
    assert exact_orthogonal([[True]]) is None


def test_continuous_bounded_real_still_takes_the_kyp_path():
    A, B, C = stable_system(6, 0)
    system = {"lmic": 1, "data": {"A": A.tolist(), "B": B.tolist(), "C": C.tolist()}}
    r = lmic.api.solve(inline_brl, system)
    assert stein_structure(r.problem, exact_of(r.problem)) is None
    d = r.enclosure["dual"]
    if d.get("route") == "face":
        assert "K" in d["dual"] and "structure" not in d["dual"]
    res = face_bound(r.problem, None)
    assert res["proven"] and "K" in res["dual"] and "structure" not in res["dual"]
