"""A variable that exposes a face of the dual on its own (lmic.certify.enclosure_facial.obvious_face):
SDPLIB's graph-partitioning layout (gpp: ``x_0 J + Diag(x) + L / 4 >= 0``, ``c_0 = 0``, so
every dual ``Y`` has ``<J, Y> = 0`` and no interior). The enclosure goes to the facial route
first; its bound is checked against the closed form of the cycle's bisection relaxation."""

from __future__ import annotations

import math

import pytest

import lmic.api
import lmic.certify.enclosure as enc_mod
from lmic.certify import certify
from lmic.certify.enclosure_facial import obvious_face
from lmic.ir.sdpa import read_sdpa


def _gpp_cycle_text(n: int, cost0: float = 0.0) -> str:
    """SDPLIB's gpp layout for the cycle ``C_n`` (written here, not by lmic): ``min sum_i
    x_i`` s.t. ``x_0 J + Diag(x) - F_0 >= 0``, ``F_0 = -L / 4``."""
    lines = [str(n + 1), "1", str(n), " ".join([repr(cost0)] + ["1"] * n)]
    for i in range(n):
        a, b = sorted((i, (i + 1) % n))
        lines.append(f"0 1 {i + 1} {i + 1} -0.5")
        lines.append(f"0 1 {a + 1} {b + 1} 0.25")
    lines += [f"1 1 {i + 1} {j + 1} 1.0" for i in range(n) for j in range(i, n)]
    lines += [f"{i + 2} 1 {i + 1} {i + 1} 1.0" for i in range(n)]
    return "\n".join(lines) + "\n"


def _gpp_cycle_value(n: int) -> float:
    """``-min <L/4, Y>`` over ``diag Y = 1``, ``Y e = 0``, ``Y >= 0``: ``-n lambda_2(L) / 4``
    (``<L, Y> >= lambda_2 tr Y`` on ``Y e = 0``, attained by ``Y_ij = cos(2 pi (i - j) / n)``)."""
    return -n * (2.0 - 2.0 * math.cos(2.0 * math.pi / n)) / 4.0


def test_obvious_face_detects_the_partition_constraint_only():
    assert obvious_face(read_sdpa(_gpp_cycle_text(8))) is not None
    # a cost on x_0: <J, Y> = c_0 != 0, the dual has an interior
    assert obvious_face(read_sdpa(_gpp_cycle_text(8, cost0=1.0))) is None
    # an indefinite coefficient of cost 0 (max-cut's L/4 as x_0's coefficient) is no exposing direction
    text = _gpp_cycle_text(4).splitlines()
    text = text[:4] + [ln for ln in text[4:] if not ln.startswith("1 ")]
    text += ["1 1 1 1 0.5", "1 1 1 2 -0.25"]
    assert obvious_face(read_sdpa("\n".join(text) + "\n")) is None


@pytest.mark.parametrize("n", [6, 9, 16])
def test_gpp_cycle_enclosure_by_the_facial_route_first(n, monkeypatch):
    p = read_sdpa(_gpp_cycle_text(n))
    shifted = []
    real = enc_mod.dual_bound
    monkeypatch.setattr(enc_mod, "dual_bound", lambda *a, **k: shifted.append(1) or real(*a, **k))
    r = lmic.api.solve(p, backend="sdpa", backoff=0)
    cert = certify(p, r.solution)
    assert cert.verdict == "certified", cert.reason
    enc = r.enclosure
    truth = _gpp_cycle_value(n)
    assert enc["lower"] <= truth <= enc["upper"], (enc["lower"], truth, enc["upper"])
    assert enc["rel_gap"] <= 1e-6, enc["reason"]
    assert enc["dual"]["route"] == "facial"
    assert not shifted, "the shifted repairs ran before the facial route"


def _reference_face_variable(problem) -> int | None:
    """The first variable whose coefficient is semidefinite of one sign in every LMI (checked
    on the whole matrix by eigenvalues, not by obvious_face's support and minor tests), not
    zero in all of them, of cost 0, zero on equality rows and of that sign on ``ge`` rows."""
    import numpy as np

    from lmic.ir.svec import tril_unvec

    c = np.asarray(problem.objective.c, dtype=float)[1:]
    A = problem.linear.A.toarray() if len(problem.linear) else np.zeros((0, problem.n + 1))
    ge = np.array([k == "ge" for k in problem.linear.kinds], dtype=bool)
    for k in range(problem.n):
        if c[k] != 0.0 or np.any(A[~ge, 1 + k] != 0.0):
            continue
        signs = set(np.sign(A[ge, 1 + k][A[ge, 1 + k] != 0.0]).astype(int).tolist())
        mats = [tril_unvec(lmi.coeffs[:, 1 + k].toarray().ravel(), lmi.dim) for lmi in problem.lmis]
        mats = [M for M in mats if np.any(M != 0.0)]
        if not mats:
            continue
        for M in mats:
            w = np.linalg.eigvalsh(M)
            scale = max(1.0, float(np.max(np.abs(w))))
            signs |= {1} if w[0] >= -1e-12 * scale else {-1} if w[-1] <= 1e-12 * scale else {0}
        if len(signs) == 1 and 0 not in signs:
            return k
    return None


@pytest.mark.parametrize("seed", range(40))
def test_obvious_face_agrees_with_a_whole_matrix_eigenvalue_test(seed):
    """Random LMIs whose variables' coefficients are semidefinite (of either sign, on a random
    support), indefinite, or a lone off-diagonal pair: the vectorised pre-filter and the
    per-variable test together find a face variable exactly when the eigenvalue test does, and
    the same one."""
    import numpy as np
    import scipy.sparse as sp

    from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
    from lmic.ir.svec import tril_rows_cols

    rng = np.random.default_rng(seed)
    n, dims = int(rng.integers(2, 7)), [int(d) for d in rng.integers(2, 6, size=int(rng.integers(1, 3)))]
    face_sign = int(rng.choice([1, -1]))
    lmis = []
    for d in dims:
        i, j = tril_rows_cols(d)
        cols = [rng.standard_normal(len(i)) * (rng.random(len(i)) < 0.5)]
        for _ in range(n):
            kind = rng.choice(["psd", "indef", "pair", "zero"], p=[0.4, 0.3, 0.2, 0.1])
            M = np.zeros((d, d))
            if kind == "psd":
                sup = rng.choice(d, size=int(rng.integers(1, d + 1)), replace=False)
                B = rng.standard_normal((len(sup), int(rng.integers(1, len(sup) + 1))))
                M[np.ix_(sup, sup)] = face_sign * (B @ B.T)
            elif kind == "indef":
                M = rng.standard_normal((d, d))
                M = M + M.T
            elif kind == "pair":
                a, b = rng.choice(d, size=2, replace=False)
                M[a, b] = M[b, a] = 1.0
            cols.append(M[i, j])
        lmis.append(LMI(f"L{d}", d, sp.csc_matrix(np.column_stack(cols)), strict=False))
    cost = np.concatenate([[0.0], rng.choice([0.0, 1.0], size=n, p=[0.7, 0.3])])
    rows = rng.standard_normal((int(rng.integers(0, 3)), n + 1)) * (rng.random((1, n + 1)) < 0.3)
    linear = (
        LinearConstraints(sp.csc_matrix(rows), ["ge"] * len(rows), [False] * len(rows), [""] * len(rows))
        if len(rows)
        else LinearConstraints.empty(n)
    )
    p = Problem([Variable("x", "full", (n, 1))], lmis, linear, Objective("min", cost))
    ref = _reference_face_variable(p)
    got = obvious_face(p)
    assert (got is None) == (ref is None), (got, ref)
    if ref is not None:
        assert got == f"variable {ref + 1}: a semidefinite coefficient of cost 0"
