"""The exact dual end on the optimal face of a Lyapunov-type LMI (lmic.certify.enclosure_face):
the bounded-real lemma at 20 and 40 states, where the dual's interior is thinner than the
floating-point resolution, against the H-infinity norm from a Hamiltonian bisection (and a
frequency sweep); the audit re-proves the bound from the recorded point and rejects a tampered
one."""

from __future__ import annotations

import json
import os
from fractions import Fraction

import numpy as np
import pytest
import scipy.sparse as sp
from certify_helpers import hinf_norm, stable_system

import lmic.api
from lmic.certify import audit_certificate, write_certificate
from lmic.certify.enclosure import enclosure
from lmic.certify.enclosure_dual import verify_dual_bound
from lmic.certify.enclosure_face import face_bound, lyapunov_structure, prove_face
from lmic.certify.enclosure_float import primal_end
from lmic.compile.exact import cached_exact, exact_of, from_ir
from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable


def _system(n: int, seed: int, dyadic: bool):
    """A random stable system; with ``dyadic`` its diagonal is rounded to eighths, so the
    coefficients ``A_aa + A_bb`` of ``A^T P + P A`` are exact in floating point."""
    return stable_system(n, seed, eighths=dyadic)


def _brl(n: int, seed: int, dyadic: bool = True):
    A, B, C = _system(n, seed, dyadic)
    system = {"lmic": 1, "data": {"A": A.tolist(), "B": B.tolist(), "C": C.tolist()}}
    return (A, B, C), lmic.api.solve("tutorial.bounded_real", system, backend="clarabel", backoff=0)


def _sweep_lower(A, B, C) -> float:
    """max over a frequency grid of sigma_max(C (jw - A)^-1 B): a lower bound of the norm."""
    n = A.shape[0]
    return max(
        float(np.linalg.norm(C @ np.linalg.solve(1j * w * np.eye(n) - A, B), 2)) for w in np.logspace(-3, 3, 2000)
    )


@pytest.mark.parametrize(
    "n, seed",
    [
        (20, 0),
        (20, 3),
        (30, 0),
        pytest.param(
            40,
            0,
            marks=pytest.mark.skipif(
                not os.environ.get("LMIC_SLOW_TESTS"), reason="10 - 30 s: set LMIC_SLOW_TESTS=1 (in the benchmark)"
            ),
        ),
    ],
)
def test_bounded_real_lower_end_is_proved_exactly_on_the_face(n, seed, tmp_path):
    """20 to 40 states: the shifted, perturbed and centred duals cannot be proved (the
    conditional box bound was all lmic had); the face point is, exactly, and the enclosure
    contains the H-infinity norm."""
    (A, B, C), r = _brl(n, seed)
    lo, hi = hinf_norm(A, B, C)
    assert r.verdict == "certified"
    e = r.enclosure
    d = e["dual"]
    assert d["proven"] and d["route"] == "face" and d["method"] == "exact", e["reason"]
    assert e["lower"] <= hi and hi <= e["upper"]  # the norm is in [lo, hi] (bisection to 1e-12)
    assert _sweep_lower(A, B, C) <= e["upper"]
    assert e["rel_gap"] <= 1e-6
    # the exact value is a rational no larger than the reported (rounded-down) end
    num, _, den = d["lower_exact"].partition("/")
    assert Fraction(e["lower"]) <= Fraction(int(num), int(den or 1))
    # the audit re-proves it from the recorded K and S_R alone, and rejects tampering
    path = tmp_path / "brl.json"
    write_certificate(path, r.problem, r.solution, r.certificate, enclosure=r.enclosure)
    assert audit_certificate(path).ok
    good = json.loads(path.read_text())
    for tamper in ("lower", "S_rest", "K"):
        doc = json.loads(json.dumps(good))
        enc = doc["enclosure"]
        if tamper == "lower":
            enc["lower"] = enc["dual"]["lower"] = enc["lower"] + 1e-3 * abs(enc["lower"])
        elif tamper == "S_rest":
            enc["dual"]["dual"]["S_rest"][0][0] *= 1.5
        else:
            enc["dual"]["dual"]["K"] = (2.0 * np.asarray(enc["dual"]["dual"]["K"])).tolist()
        path.write_text(json.dumps(doc))
        bad = audit_certificate(path)
        assert not bad.ok, tamper
        assert bad.field in ("enclosure.dual", "enclosure.lower"), (tamper, bad.field, bad.message)


@pytest.mark.parametrize("n, seed", [(5, 1), (12, 2), (20, 0)])
def test_random_diagonal_is_proved_on_the_exact_compilation(n, seed, tmp_path):
    """With a random diagonal the IR's coefficients fl(A_aa + A_bb) are rounded sums: the IR's
    own face W = 0 is not the Lyapunov one, but the theorem compiled exactly from the system's
    numbers (lmic.compile.exact) has it. The lower end is proved there, the certified point is
    proved for that problem too (its margin covers the rounding), and the enclosure says so."""
    (A, B, C), r = _brl(n, seed, dyadic=False)
    assert r.verdict == "certified"
    assert lyapunov_structure(r.problem) is None  # the IR's own floats
    assert lyapunov_structure(r.problem, exact_of(r.problem)) is not None
    e = r.enclosure
    d = e["dual"]
    assert d["proven"] and d["route"] == "face" and d["problem"] == "exact", e["reason"]
    assert e["problem"] == "exact" and d["dual"]["problem"] == "exact"
    lo, hi = hinf_norm(A, B, C)  # the norm is in [lo, hi] (bisection to 1e-12)
    assert e["lower"] <= hi and hi <= e["upper"]
    assert e["rel_gap"] <= 1e-6
    # python-control's norm (another algorithm) is inside as well
    control = pytest.importorskip("control")
    norm = float(control.norm(control.ss(A, B, C, np.zeros((2, 2))), "inf", tol=1e-10, method="scipy"))
    assert e["lower"] <= norm * (1 + 1e-9) and norm * (1 - 1e-9) <= e["upper"]
    # the audit recompiles the exact problem from the theorem and the system, re-proves both
    # ends for it, and rejects tampering (the bound, K, S_R, or the problem it is about)
    path = tmp_path / "brl.json"
    write_certificate(path, r.problem, r.solution, r.certificate, enclosure=r.enclosure)
    assert audit_certificate(path).ok
    good = json.loads(path.read_text())
    for tamper in ("lower", "S_rest", "K", "problem", "point problem"):
        doc = json.loads(json.dumps(good))
        enc = doc["enclosure"]
        if tamper == "lower":
            enc["lower"] = enc["dual"]["lower"] = enc["lower"] + 1e-7 * abs(enc["lower"])
        elif tamper == "S_rest":
            enc["dual"]["dual"]["S_rest"][0][0] *= 1.5
        elif tamper == "K":
            enc["dual"]["dual"]["K"] = (np.asarray(enc["dual"]["dual"]["K"]) + 1e-3).tolist()
        elif tamper == "problem":
            enc["problem"] = "ir"
        else:
            enc["dual"]["dual"]["problem"] = "ir"
        path.write_text(json.dumps(doc))
        bad = audit_certificate(path)
        assert not bad.ok, tamper
        assert bad.field in ("enclosure.dual", "enclosure.lower", "enclosure.problem"), (tamper, bad.field)


def test_primal_end_covers_the_exact_counterpart_once_it_exists():
    """A point proved for the IR whose margin is below |G_exact(x) - G(x)| gives no primal end
    once the problem has an exact counterpart (a counterpart built by hand here, with one
    coefficient 1e-3 away from the IR's)."""
    p = _first_order(-2.0, 1.0, 3.0)
    x = np.array([3.0, 1.5 + 1e-4])  # G = 3/(s+2): p = 3, t just above the norm 3/2
    assert primal_end(p, x)["proven"] and primal_end(p, x)["problem"] == "ir"
    ex = from_ir(p)
    brl = ex.lmis[1]
    k = int(brl.indptr[2])  # the coefficient of t at entry (1, 1)
    brl.num[k] -= brl.den // 1000 + 1  # the exact problem: t's coefficient just below 1 - 1e-3
    ex.about = "theorem"
    p._lmic_exact = ex  # what lmic.compile.exact.exact_of caches
    assert cached_exact(p) is ex
    res = primal_end(p, x)
    assert not res["proven"], res
    assert primal_end(p, np.array([3.0, 1.6]))["proven"]  # a margin 0.1 covers it
    assert primal_end(p, np.array([3.0, 1.6]))["problem"] == "exact"


def _first_order(a: float, b: float, c: float) -> Problem:
    """min t s.t. p > 0, -[[2 a p, p b, c], [p b, -t, 0], [c, 0, -t]] > 0: the H-infinity norm
    of c b / (s - a), which is |c b / a| (the peak at zero frequency)."""
    F = np.array(
        [
            [0.0, -2.0 * a, 0.0],  # (0, 0)
            [0.0, -b, 0.0],  # (1, 0)
            [-c, 0.0, 0.0],  # (2, 0)
            [0.0, 0.0, 1.0],  # (1, 1)
            [0.0, 0.0, 0.0],  # (2, 1)
            [0.0, 0.0, 1.0],  # (2, 2)
        ]
    )
    return Problem(
        [Variable("p", "scalar", (1, 1)), Variable("t", "scalar", (1, 1), offset=1)],
        [LMI("p > 0", 1, sp.csc_matrix([[0.0, 1.0, 0.0]])), LMI("brl", 3, sp.csc_matrix(F))],
        LinearConstraints.empty(2),
        Objective("min", [0.0, 0.0, 1.0]),
    )


def test_face_point_of_a_first_order_system_gives_its_norm_exactly():
    # G(s) = 3 / (s + 2): norm 3/2. Rank 1, K = 0: S_E = -A^-1 B w = w / 2; the dual objective
    # of X = S S^T / t is 2 c S_E z / (w^2 + z^2) = 3 w z / (w^2 + z^2), exactly 3/2 at z = w
    p = _first_order(-2.0, 1.0, 3.0)
    st = lyapunov_structure(p)
    assert st is not None and st["state"].tolist() == [0]
    r = prove_face(p, st, np.zeros((1, 1)), np.array([[1.0], [1.0]]))
    assert r["proven"] and r["lower_exact"] == "3/2"
    # any other point of the face proves less, never more
    r2 = prove_face(p, st, np.zeros((1, 1)), np.array([[1.0], [0.5]]))
    assert r2["proven"] and Fraction(r2["lower_exact"]) == Fraction(6, 5)
    # and the recorded form is re-proved; a raised bound is rejected
    point = {"form": "face", "block": 1, "pivot": 0, "K": [[0.0]], "S_rest": [[1.0], [1.0]]}
    rec = {"lower": r["lower"], "dual": point}
    assert verify_dual_bound(p, rec)["ok"]
    assert not verify_dual_bound(p, dict(rec, lower=1.5 + 1e-9))["ok"]


def test_face_rejects_a_non_skew_rotation():
    p = _first_order(-2.0, 1.0, 3.0)
    st = lyapunov_structure(p)
    r = prove_face(p, st, np.array([[0.5]]), np.array([[1.0], [1.0]]))
    assert not r["proven"] and "skew" in r["reason"]


def test_frequency_search_gives_the_norm_even_from_a_useless_dual():
    """The face point from the frequency search (lmic.certify.enclosure_face_kyp) does not need
    the solver's multiplier: from a dual point that is pure noise the proven bound is still
    within 1e-9 of the H-infinity norm (the grid runs: the noise's dual objective is far off),
    and with Clarabel's dual the bound is as tight."""
    (A, B, C), r = _brl(12, 4, dyadic=False)
    lo, hi = hinf_norm(A, B, C)
    rng = np.random.default_rng(0)
    noise = {
        "lmis": [(lambda M: M @ M.T)(rng.standard_normal((lmi.dim, lmi.dim))) for lmi in r.problem.lmis],
        "linear": np.abs(rng.standard_normal(len(r.problem.linear))),
    }
    res = face_bound(r.problem, noise)
    assert res["proven"] and res["problem"] == "exact", res["reason"]
    assert res["lower"] <= hi and (hi - res["lower"]) / hi <= 1e-9
    e = r.enclosure
    assert e["dual"]["route"] == "face" and (hi - e["lower"]) / hi <= 1e-9
    # with no dual point and no certified point at all (a solver that failed): the lower end alone
    e0 = enclosure(r.problem, None, None)
    assert e0["upper"] is None and e0["problem"] == "exact" and e0["lower"] <= hi
    assert (hi - e0["lower"]) / hi <= 1e-9


def test_best_of_never_pairs_ends_of_two_problems():
    """An exact-problem lower end (the face route) is not combined with a primal end proved for
    the IR only; the better ends of one problem are kept instead."""
    from lmic.certify.enclosure import best_of

    ir = {"sense": "min", "kind": "infimum", "lower": 1.0, "upper": 2.0, "problem": "ir", "primal": "certified point"}
    ir["dual"] = {"proven": True, "problem": "ir"}
    ex = {
        "sense": "min",
        "kind": "infimum",
        "lower": 1.5,
        "upper": 3.0,
        "problem": "exact",
        "primal": "certified point",
    }
    ex["dual"] = {"proven": True, "problem": "exact"}
    out = best_of(ir, ex, [3.0])  # mixing would give [1.5, 2.0]: the IR's own ends are kept
    assert (out["lower"], out["upper"], out["problem"], out["dual"]["problem"]) == (1.0, 2.0, "ir", "ir")
    both = dict(ex, upper=2.5)
    out = best_of(both, dict(ex, lower=1.4, upper=2.2), [2.2])  # one problem: the better of each
    assert (out["lower"], out["upper"], out["problem"]) == (1.5, 2.2, "exact")


def test_an_equality_row_on_the_lyapunov_variable_does_not_break_the_face_route():
    """A newcomer's min s with P >= 0, A'P + PA <= s I and trace(P) == 1: the face route's KYP
    step had no S_R entry left to choose (an empty eigenproblem) and raised IndexError, which
    ended every solve. The optimum min over trace-one P >= 0 of lambda_max(A'P + PA) comes
    here from CVXPY + Clarabel (a tight, independent solve) and lies in lmic's enclosure."""
    import cvxpy as cp
    import sympy

    import lmic
    from lmic.template import I, theorem, trace

    A = np.array(
        [
            [-1.9639527445352074, 0.2463123418909185, -0.2931716774803635],
            [-0.26931252027041225, -0.1171975395721152, 0.6513744981394683],
            [1.045995814244609, -0.3793338889429307, -1.2132830811152708],
        ]
    )

    @theorem(id="nb.trace_one", title="t", citation="c", kind="analysis")
    def trace_one(t):
        (n,) = t.dims("n")
        Ad = t.data("A", n, n)
        P = t.symmetric("P", n)
        s = t.scalar("s", sign="negative")
        t.lmi("P >= 0", P >= 0)
        t.lmi("Lyapunov", Ad.T * P + P * Ad - s * I(n) <= 0)
        t.constraint("trP", sympy.Eq(trace(P), 1))
        t.minimize(s)

    r = lmic.solve(trace_one, {"data": {"A": A.tolist()}})
    P = cp.Variable((3, 3), symmetric=True)
    ref = cp.Problem(cp.Minimize(cp.lambda_max(A.T @ P + P @ A)), [P >> 0, cp.trace(P) == 1])
    ref.solve(solver=cp.CLARABEL, tol_gap_abs=1e-10, tol_gap_rel=1e-10, tol_feas=1e-10)
    assert r.verdict == "certified" and r.enclosure["rel_gap"] <= 1e-6
    assert r.enclosure["lower"] - 1e-8 <= ref.value <= r.enclosure["upper"] + 1e-8
