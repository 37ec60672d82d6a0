"""Exact proofs: rational points, exact F(x), congruence / LDL^T / charpoly, the benchmark."""

from __future__ import annotations

import importlib.util
import math
import time
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp
from certify_helpers import lmi_from

from lmic.certify import certify
from lmic.certify.exact import (
    FULL_BITS_MAX,
    _float_bits,
    exact_float,
    exact_matrix,
    prove,
    prove_pd,
    prove_psd,
    round_point,
)
from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
from lmic.ir.svec import tril_rows_cols
from lmic.solution import Solution

ROOT = Path(__file__).resolve().parents[2]


def _benchmark():
    spec = importlib.util.spec_from_file_location("lmic_bench_exact", ROOT / "benchmarks" / "exact.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.mark.parametrize("v", [0.1, -3.75, 1e-300, 5e-324, 1.7976931348623157e308, 2.0**-60 * 3])
def test_exact_float_is_exact(v):
    m, e = exact_float(v)
    assert Fraction(m) * Fraction(2) ** e == Fraction(v)
    assert m % 2 == 1


def test_round_point_rounds_to_the_dyadic_grid():
    pt = round_point(np.array([0.1, -0.3, 2.5, 0.0]), 4)
    assert pt.den == 16 and pt.describe() == "2^4"
    assert pt.num == [2, -5, 40, 0]
    for f, v in zip(pt.fractions(), [0.1, -0.3, 2.5, 0.0], strict=True):
        assert abs(f - Fraction(v)) <= Fraction(1, 32)


def test_exact_matrix_equals_the_rational_evaluation():
    rng = np.random.default_rng(0)
    d, n = 4, 3
    mats = []
    for _ in range(n + 1):
        M = rng.standard_normal((d, d)) * 10.0 ** rng.integers(-5, 5)
        mats.append(M + M.T)
    lmi = lmi_from("random", mats)
    pt = round_point(rng.standard_normal(n), 30)
    M = exact_matrix(lmi, pt)
    # reference: F(x_q) entry by entry in Fractions
    xs = [Fraction(1)] + pt.fractions()
    ref = [[sum(Fraction(float(mats[k][i, j])) * xs[k] for k in range(n + 1)) for j in range(d)] for i in range(d)]
    # M = c * ref for one positive c
    c = Fraction(M[0][0]) / ref[0][0]
    assert c > 0
    assert all(Fraction(M[i][j]) == c * ref[i][j] for i in range(d) for j in range(d))


def test_prove_pd_and_psd_small_and_by_every_method():
    assert prove_pd([[2, 1], [1, 2]])["proven"]
    r = prove_pd([[1, 2], [2, 1]])
    assert not r["proven"] and r["disproved"]
    # singular PSD: the congruence fails, LDL^T with a zero pivot proves PSD, disproves PD
    B = np.array([[1, 2, 3], [2, 4, 6], [0, 1, 1]])
    G = (B.T @ B).tolist()
    assert prove_psd(G)["proven"] and prove_psd(G)["method"] == "ldl"
    assert prove_pd(G)["disproved"]
    assert prove_psd([[0, 1], [1, 0]])["disproved"]


def test_charpoly_fallback_for_singular_psd_of_moderate_size():
    rng = np.random.default_rng(1)
    B = rng.integers(-3, 4, size=(45, 60))  # rank 45 < 60: singular PSD Gram matrix
    G = (B.T @ B).tolist()
    r = prove_psd(G)
    assert r["proven"] and r["method"] == "charpoly"
    G2 = (B.T @ B - np.eye(60, dtype=int)).tolist()  # has eigenvalue -1
    r2 = prove_psd(G2)
    assert r2["disproved"] and not r2["proven"]


def test_ill_conditioned_matrix_needs_more_rounds_but_is_proved():
    d = 30
    H = [[Fraction(1, i + j + 1) for j in range(d)] for i in range(d)]  # Hilbert: cond ~ 1e44
    den = 1
    for row in H:
        for f in row:
            den = den * f.denominator // math.gcd(den, f.denominator)
    M = [[int(f * den) for f in row] for row in H]
    r = prove_pd(M)
    assert r["proven"]  # by congruence rounds or by exact LDL^T


def test_prove_at_the_float_point_itself_first(lyapunov_point):
    prob, x = lyapunov_point
    r = prove(prob, x)
    assert r["proven"] and not r["disproved"]
    assert r["at_x"] and not r["rounded"] and r["distance"] == 0.0
    assert r["bits"] == _float_bits(x) and r["denominator"] == f"2^{r['bits']}"
    den = int(r["point"]["den"])
    assert [Fraction(int(v), den) for v in r["point"]["num"]] == [Fraction(float(v)) for v in x]
    assert r["attempts"] == [{"denominator": r["denominator"], "proven": True, "disproved": False}]
    assert "the returned float point x itself" in r["statement"]
    assert all(e["method"] == "congruence" for e in r["lmis"])


def test_forced_coarse_grid_records_the_rounded_point(lyapunov_point):
    prob, x = lyapunov_point
    r = prove(prob, x, bits=20)
    assert r["proven"] and r["rounded"] and not r["at_x"]
    assert r["denominator"] == "2^20" and r["point"]["den"] == str(2**20)
    assert 0 < r["distance"] <= 2.0**-21
    xq = np.array([int(v) / 2**20 for v in r["point"]["num"]])
    assert np.max(np.abs(xq - x)) == pytest.approx(r["distance"])
    assert "max |x_q - x| = " in r["statement"]


def test_huge_float_denominator_tries_a_coarse_grid_first():
    # an entry of 1e-100 needs 2^-385: beyond FULL_BITS_MAX, a margin-preserving grid goes first
    prob = Problem(
        [Variable("p", "scalar", (1, 1), offset=0), Variable("q", "scalar", (1, 1), offset=1)],
        [lmi_from("diag", [np.eye(2), np.diag([1.0, 0.0]), np.diag([0.0, 1.0])])],
        LinearConstraints.empty(2),
        Objective("min", np.array([0.0, 1.0, 1.0])),
    )
    x = np.array([0.5, 1e-100])
    assert _float_bits(x) > FULL_BITS_MAX
    r = prove(prob, x)
    assert r["proven"] and not r["at_x"] and r["bits"] < 20
    assert r["distance"] == pytest.approx(1e-100)
    assert r["objective"] == 0.5  # exact at x_q = (1/2, 0)


def test_tiny_margin_falls_back_to_the_float_point_itself():
    # [[p, 1], [1, q]] with p q - 1 = 1e-15: rounding x coarsely would break it
    prob = Problem(
        [Variable("p", "scalar", (1, 1), offset=0), Variable("q", "scalar", (1, 1), offset=1)],
        [lmi_from("tight", [np.array([[0.0, 1.0], [1.0, 0.0]]), np.diag([1.0, 0.0]), np.diag([0.0, 1.0])])],
        LinearConstraints.empty(2),
        Objective("feasibility", np.zeros(3)),
    )
    x = np.array([1.0 + 2.0**-40, 1.0])
    r = prove(prob, x)
    assert r["proven"] and r["at_x"] and r["bits"] >= 40
    # the recorded rational point is the float point itself, entry by entry
    den = Fraction(r["point"]["den"])
    assert [Fraction(int(v)) / den for v in r["point"]["num"]] == [Fraction(v) for v in x]
    p, q = (Fraction(v) for v in x)
    assert p * q - 1 == Fraction(1, 2**40)  # the margin the proof had to keep, exactly
    # a coarse grid rounds p to 1 and loses it: falling back to a rounding would not prove it
    assert not prove(prob, x, bits=20)["proven"]


def test_exact_disproof_of_a_tolerated_non_strict_violation():
    prob = Problem(
        [Variable("p", "scalar", (1, 1))],
        [LMI("p - 1 >= 0", 1, sp.csc_matrix([[-1.0, 1.0]]), strict=False)],
        LinearConstraints.empty(1),
        Objective("feasibility", np.zeros(2)),
    )
    x = np.array([1.0 - 2.0**-52])  # violation 2.2e-16: within every float tolerance
    plain = certify(prob, Solution("optimal", x=x, strategy="snapped"), exact=True)  # no snapping
    assert plain.verdict == "rejected"  # within tolerance only, and exactly violated
    assert plain.lmis[0]["decided_by"] == "exact" and not plain.lmis[0]["ok"]
    assert plain.exact["disproved"] and not plain.exact["proven"]
    # the exactly feasible point next to it (p = 1) is certified instead, and says so
    cert = certify(prob, Solution("optimal", x=x), exact=True)
    assert cert.verdict == "certified" and cert.x == [1.0] and "moved to x_q" in cert.reason
    assert plain.exact["reason"].startswith("LMI 'p - 1 >= 0' is not positive semidefinite at the solver's point")


def test_exact_disproof_of_a_strict_lmi_rejects(monkeypatch):
    # make the float test blind (a huge tolerance) to show the exact disproof decides
    prob = Problem(
        [Variable("p", "scalar", (1, 1))],
        [LMI("p - 1 > 0", 1, sp.csc_matrix([[-1.0, 1.0]]), strict=True)],
        LinearConstraints.empty(1),
        Objective("feasibility", np.zeros(2)),
    )
    import lmic.certify.margins as check

    monkeypatch.setattr(check, "_U", -1.0)  # pretend float64 had no round-off at all
    x = np.array([1.0 - 2.0**-52])
    cert = certify(prob, Solution("optimal", x=x), exact=True, tol={"strict_rel": -1.0})
    assert cert.verdict == "rejected"
    assert cert.reason.startswith("exact: LMI 'p - 1 > 0' is not positive definite at the solver's point")
    assert cert.lmis[0]["float_ok"] and not cert.lmis[0]["ok"] and cert.lmis[0]["decided_by"] == "exact"


def test_equality_rows_are_met_exactly_by_projection():
    # 0.1 x + y = 1 (the float 0.1 is not 1/10, rounding x, y cannot meet it), diag(x, y) > 0
    A = sp.csr_matrix(np.array([[-1.0, 0.1, 1.0]]))
    prob = Problem(
        [Variable("x", "scalar", (1, 1), offset=0), Variable("y", "scalar", (1, 1), offset=1)],
        [lmi_from("diag", [np.zeros((2, 2)), np.diag([1.0, 0.0]), np.diag([0.0, 1.0])])],
        LinearConstraints(A, ["eq"], [False], ["0.1 x + y = 1"]),
        Objective("feasibility", np.zeros(3)),
    )
    r = prove(prob, np.array([1.0, 0.9 + 1e-13]))
    assert r["proven"], r["reason"]
    assert r["linear"][0]["proven"] and r["linear"][0]["value"] == 0.0
    assert r["projection"] == "projected exactly onto the equality rows"
    assert not r["denominator"].startswith("2^")  # no longer a dyadic point


def test_benchmark_size_90_is_fast_and_proved():
    bench = _benchmark()
    prob = bench.qib_thm1_problem(30, 15)
    x = bench.feasible_point(prob)
    t0 = time.perf_counter()
    cert = certify(prob, Solution("feasible", x=x), exact=True)
    elapsed = time.perf_counter() - t0
    assert cert.label == "certified (exact)"
    assert cert.exact["lmis"][0]["method"] == "congruence"
    assert cert.exact["at_x"]  # proved at the float point itself, no rounding
    assert elapsed < 5.0
    # the float LMI agrees with a dense evaluation of the printed block matrix
    v = prob.unpack(x)
    A, C = np.array(prob.data["A"]), np.array(prob.data["C"])
    P, R, w, beta = v["P"], v["R"], v["omega"], prob.data["beta"]
    X = A.T @ P - C.T @ R
    n = P.shape[0]
    Z, I = np.zeros((n, n)), np.eye(n)
    M = np.block([[-P + 2 * w * beta * I, X, X], [X.T, P - 2 * w * I, Z], [X.T, Z, -P]])
    assert np.allclose(prob.lmis[0].matrix(x), -M, atol=1e-12)
    _ = tril_rows_cols  # the storage convention is what exact_matrix reads


def test_int64_limb_path_agrees_with_python_ints():
    # coefficients spread over 60 decades, some zeros; a small point takes the int64-limb path,
    # the same point with a 2^62 larger numerator and denominator the python-int path
    rng = np.random.default_rng(5)
    for _ in range(10):
        data = rng.standard_normal((21, 6)) * 10.0 ** rng.integers(-30, 30, size=(21, 6))
        data[rng.random((21, 6)) < 0.3] = 0.0
        lmi = LMI("r", 6, sp.csc_matrix(data))
        pt = round_point(rng.standard_normal(5) * 10.0 ** rng.integers(-3, 3, size=5), int(rng.integers(0, 40)))
        big = type(pt)([v << 62 for v in pt.num], pt.den << 62)
        assert max(map(abs, big.num + [big.den])) >= 2**62
        small = exact_matrix(lmi, pt)
        assert exact_matrix(lmi, big) == [[v << 62 for v in row] for row in small]  # same scale c


def _two_variable_problem(rows: np.ndarray, names: list[str]) -> Problem:
    return Problem(
        [Variable("x", "scalar", (1, 1), offset=0), Variable("y", "scalar", (1, 1), offset=1)],
        [lmi_from("diag", [np.zeros((2, 2)), np.diag([1.0, 0.0]), np.diag([0.0, 1.0])])],
        LinearConstraints(sp.csr_matrix(rows), ["eq"] * len(rows), [False] * len(rows), names),
        Objective("feasibility", np.zeros(3)),
    )


def test_rank_deficient_equality_rows_are_projected_on_an_independent_subset():
    # x + y = 1 twice (the second row exactly twice the first): 0.3 + 0.7 != 1 in exact rationals
    prob = _two_variable_problem(np.array([[-1.0, 1.0, 1.0], [-2.0, 2.0, 2.0]]), ["x+y=1", "2x+2y=2"])
    assert Fraction(0.3) + Fraction(0.7) != 1
    r = prove(prob, np.array([0.3, 0.7]))
    assert r["proven"], r["reason"]
    assert r["projection"] == "projected exactly onto the equality rows (1 independent of 2)"
    assert [e["value"] for e in r["linear"]] == [0.0, 0.0] and r["rows_within_tolerance"] == []
    assert not r["at_x"] and 0 < r["distance"] < 1e-16


def test_equality_rows_that_cannot_be_met_exactly_are_not_proven():
    # 0.1 x + y = 1 and 0.3 x + 3 y = 3: nearly but not exactly dependent in float, so the exact
    # projection lands on their intersection x = 0, where diag(x, y) > 0 fails; at the float
    # point itself both rows hold within the tolerance rel = 1e-8, which proves nothing: the
    # float problem is infeasible (its rows force x = 0)
    prob = _two_variable_problem(np.array([[-1.0, 0.1, 1.0], [-3.0, 0.3, 3.0]]), ["r1", "r2"])
    a, b = Fraction(0.1), Fraction(0.3)
    assert a * 3 != b  # the rows are independent in exact arithmetic: x = 0 on both
    x = np.array([1.0, 0.9])
    r = prove(prob, x)
    assert not r["proven"] and r["statement"] == ""
    cert = certify(prob, Solution("feasible", x=x), exact=True)
    assert cert.verdict == "rejected"
    assert cert.reason.startswith("equality 'r1' holds only within the tolerance")
