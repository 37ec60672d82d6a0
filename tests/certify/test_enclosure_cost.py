"""The enclosure's cost is proportional (issue 13/14): the repair's Jacobian in the factor's
coordinates formed on the support only, the face centring's closed-form Hessian, the budget.

Every expected value is computed independently: the dense products the fast forms replace
(the full svec factor ``T`` of the repair, the ``E_k`` products of ``-log det``), and the
certifier's own enclosure of the SDPLIB optimum within its published rounding interval.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

from lmic.certify.enclosure import enclosure
from lmic.certify.enclosure_repair import _block_gradient
from lmic.ir.svec import tril_rows_cols

SDPLIB = Path("/work/shared/sdplib")


def _dense_gradient(Jb: np.ndarray, U: np.ndarray, dim: int) -> np.ndarray:
    """The full ``T`` of every svec row, by the definition ``d svec(U E U^T) / d E_ab``."""
    r = U.shape[1]
    ia, ib = np.triu_indices(r)
    ri, ci = tril_rows_cols(dim)
    T = np.zeros((ri.size, ia.size))
    for col, (a, b) in enumerate(zip(ia, ib, strict=True)):
        E = np.zeros((r, r))
        E[a, b] = E[b, a] = 1.0
        Z = U @ E @ U.T
        T[:, col] = Z[ri, ci]
    return Jb @ T


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_block_gradient_equals_the_dense_definition(seed: int) -> None:
    rng = np.random.default_rng(seed)
    dim, r = 7, 4
    t = dim * (dim + 1) // 2
    Jb = sp.random(5, t, density=0.2, random_state=seed, format="csc")
    U = rng.normal(size=(dim, r))
    ia, ib = np.triu_indices(r)
    fast = _block_gradient(Jb, U, dim, ia, ib)
    np.testing.assert_allclose(fast, _dense_gradient(Jb.toarray(), U, dim), rtol=1e-12, atol=1e-12)


def test_block_gradient_in_chunks_equals_one_chunk(monkeypatch: pytest.MonkeyPatch) -> None:
    import lmic.certify.enclosure_repair as rep

    rng = np.random.default_rng(3)
    dim, r = 9, 5
    Jb = sp.random(4, dim * (dim + 1) // 2, density=0.5, random_state=3, format="csc")
    U = rng.normal(size=(dim, r))
    ia, ib = np.triu_indices(r)
    whole = _block_gradient(Jb, U, dim, ia, ib)
    monkeypatch.setattr(rep, "CHUNK_ENTRIES", 20)  # one support row per chunk
    np.testing.assert_allclose(_block_gradient(Jb, U, dim, ia, ib), whole, rtol=1e-13, atol=1e-13)


@pytest.mark.parametrize("seed", [0, 1])
def test_the_congruence_form_equals_the_dense_definition(seed: int, monkeypatch: pytest.MonkeyPatch) -> None:
    """Row by row ``U' S_i U`` (chosen for a dense ``Jb`` on a large block), whole and in chunks
    of one row, against the full ``T``."""
    import lmic.certify.enclosure_repair as rep

    rng = np.random.default_rng(seed)
    dim, r = 24, 24
    t = dim * (dim + 1) // 2
    Jb = sp.random(6, t, density=0.9, random_state=seed, format="csc")
    Jb = sp.vstack([Jb, sp.csc_matrix((1, t))]).tocsc()  # a row without nonzeros stays zero
    U = rng.normal(size=(dim, r))
    ia, ib = np.triu_indices(r)
    reference = _dense_gradient(Jb.toarray(), U, dim)
    rows = np.unique(sp.csc_matrix(Jb).indices)
    direct = rep._congruence_gradient(sp.csc_matrix(Jb), U, dim, ia, ib, rows, np.zeros((7, ia.size)))
    np.testing.assert_array_equal(direct[6], 0.0)
    np.testing.assert_allclose(direct, reference, rtol=1e-12, atol=1e-12)
    calls: list[int] = []
    real = rep._congruence_gradient

    def spy(*args):
        calls.append(1)
        return real(*args)

    monkeypatch.setattr(rep, "_congruence_gradient", spy)
    chosen = _block_gradient(Jb, U, dim, ia, ib)
    assert calls, "the cost rule should pick the congruence form for a dense Jb on a large block"
    np.testing.assert_allclose(chosen, reference, rtol=1e-12, atol=1e-12)
    monkeypatch.setattr(rep, "CHUNK_ENTRIES", dim * dim)  # one row per chunk
    np.testing.assert_allclose(_block_gradient(Jb, U, dim, ia, ib), reference, rtol=1e-12, atol=1e-12)


def test_face_centre_newton_uses_the_hessian_of_minus_log_det() -> None:
    """The face centring on a slice whose centre is known: ``max log det S`` over ``tr S = 3``
    (no other equation) is ``S = I``, whatever the start inside the cone."""
    from lmic.certify.farkas_face import _center_on_face

    r = 3
    ia, ib = np.triu_indices(r)
    S0 = np.array([[2.0, 0.3, 0.0], [0.3, 0.5, 0.1], [0.0, 0.1, 0.5]])
    u0 = S0[ia, ib]
    J = np.zeros((1, u0.size))  # only g_0 (no separation: g_0 = 0)
    u = _center_on_face(J, u0, [r], np.zeros(0, dtype=bool), False)
    assert u is not None
    S = np.zeros((r, r))
    S[ia, ib] = S[ib, ia] = u
    np.testing.assert_allclose(S, np.eye(r), atol=1e-4)  # it stops at a Newton decrement of 1e-8


def _published_interval(text: str) -> tuple[float, float]:
    from decimal import Decimal

    d = Decimal(text)
    half = Decimal(5) * Decimal(10) ** (d.as_tuple().exponent - 1)
    return float(d - half), float(d + half)


@pytest.mark.skipif(not (SDPLIB / "control3.dat-s").exists(), reason="SDPLIB not available")
def test_control3_gap_below_1e_6_and_published_optimum_inside() -> None:
    from lmic.api import solve
    from lmic.ir.sdpa import read_sdpa

    problem = read_sdpa(SDPLIB / "control3.dat-s")
    res = solve(problem)
    enc = res.enclosure
    assert res.verdict == "certified"
    assert enc["rel_gap"] is not None and enc["rel_gap"] <= 1e-6
    lo, hi = _published_interval("1.363327e+01")
    assert enc["lower"] <= hi and enc["upper"] >= lo
    from lmic.certify.enclosure import verify_dual_bound

    assert verify_dual_bound(problem, enc["dual"])["ok"]  # the lower end re-proved from its dual point


def test_a_spent_budget_is_reported_and_never_a_bound() -> None:
    """With no time, the first shift alone is tried: on a slightly indefinite dual point
    (eigenvalues 0.5 +- 0.51) it does not prove, the budget is recorded as spent and no lower
    end is reported; with the default budget the same dual point is repaired and proves the
    closed-form optimum's lower end (min t s.t. [[t, 1], [1, t]] >= 0 is 1)."""
    from lmic.certify.enclosure_audit import audit_enclosure
    from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable

    C = sp.csc_matrix(np.array([[0.0, 1.0], [1.0, 0.0], [0.0, 1.0]]))
    p = Problem(
        [Variable("t", "scalar", (1, 1))],
        [LMI("M >= 0", 2, C, strict=False)],
        LinearConstraints.empty(1),
        Objective("min", [0.0, 1.0]),
    )
    duals = {"lmis": [np.array([[0.5, -0.51], [-0.51, 0.5]])], "linear": []}
    t0 = time.perf_counter()
    spent = enclosure(p, duals, None, budget_s=0.0)
    assert time.perf_counter() - t0 < 5.0
    assert spent["budget"]["spent"] is True
    assert spent["lower"] is None and spent["dual"]["proven"] is False
    assert "time budget" in spent["dual"]["reason"]
    full = enclosure(p, duals, None)
    assert full["lower"] is not None and 0.999 < full["lower"] <= 1.0
    assert audit_enclosure(p, full, None)["ok"]
