"""The repair's matrix-free least-norm step (lmic.certify.enclosure_gram) on large blocks with
sparse coefficients: the same numbers as the dense gradient, and the enclosure of an SDPLIB
max-cut-shaped problem (``min sum x_i`` s.t. ``Diag(x) - L / 4 >= 0``) against its closed form."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.sparse as sp

import lmic.api
from lmic.certify import certify
from lmic.certify import enclosure_repair as er
from lmic.certify.enclosure_dual import dual_bound
from lmic.certify.enclosure_gram import dense_cost, entries, free_cost, gram, step_matrix
from lmic.certify.enclosure_repair import _block_gradient, jacobian
from lmic.ir.sdpa import read_sdpa


def _mcp_cycle_text(n: int) -> str:
    """SDPLIB's mcp layout for the cycle ``C_n``, written here (not by lmic)."""
    lines = [str(n), "1", str(n), " ".join(["1"] * n)]
    for i in range(n):
        a, b = sorted((i, (i + 1) % n))
        lines.append(f"0 1 {i + 1} {i + 1} 0.5")  # L / 4: degree 2
        lines.append(f"0 1 {a + 1} {b + 1} -0.25")
    lines += [f"{i + 1} 1 {i + 1} {i + 1} 1.0" for i in range(n)]
    return "\n".join(lines) + "\n"


def _mcp_cycle_value(n: int) -> float:
    """``n / 4 lambda_max(L)`` of an odd cycle (tight: vertex- and edge-transitive graph)."""
    return n * (1.0 + math.cos(math.pi / n)) / 2.0


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_gram_and_step_match_the_dense_gradient(seed):
    rng = np.random.default_rng(seed)
    d, n = 7, 5
    Jb = sp.random(n, d * (d + 1) // 2, density=0.3, random_state=seed, format="csc")
    U = rng.standard_normal((d, 4 + seed))  # a rank-deficient factor too
    ia, ib = np.triu_indices(U.shape[1])
    G = _block_gradient(Jb, U, d, ia, ib)  # the dense form, built entry by entry
    ent = entries(Jb, d)
    assert np.allclose(gram(ent, U), G @ G.T, rtol=1e-12, atol=1e-12)
    lam = rng.standard_normal(n)
    E = step_matrix(ent, U, lam)
    assert np.allclose(E, E.T)
    assert np.allclose(E[ia, ib], G.T @ lam, rtol=1e-12, atol=1e-12)


def test_free_form_is_chosen_on_a_large_sparse_block_only():
    p = read_sdpa(_mcp_cycle_text(151))
    J, ranges = jacobian(p)
    ent = entries(J[1:, ranges[0][0] : ranges[0][1]], 151)
    assert p.n * 151 * 152 // 2 >= er.FREE_MIN_ENTRIES
    assert free_cost(ent, 151) < dense_cost(p.n, 151)
    # a dense coefficient block (every entry in every row) keeps the dense form
    dense = entries(sp.csc_matrix(np.ones((3, 6))), 3)
    assert free_cost(dense, 3) > dense_cost(3, 3)


def test_mcp_cycle_enclosure_holds_the_closed_form(monkeypatch):
    n = 151
    p = read_sdpa(_mcp_cycle_text(n))
    calls = []
    real = er.gram
    monkeypatch.setattr(er, "gram", lambda ent, U: calls.append(U.shape) or real(ent, U))
    r = lmic.api.solve(p, backend="sdpa", backoff=0)
    assert calls, "the repair did not take the matrix-free form"
    cert = certify(p, r.solution)
    assert cert.verdict == "certified", cert.reason
    enc = r.enclosure
    truth = _mcp_cycle_value(n)
    assert enc["lower"] <= truth <= enc["upper"], (enc["lower"], truth, enc["upper"])
    assert enc["rel_gap"] <= 1e-6, enc["reason"]
    # the same dual point repaired by the dense form proves the same bound (to round-off)
    free = dual_bound(p, r.solution.duals)
    monkeypatch.setattr(er, "free_cost", lambda ent, r: math.inf)
    dense = dual_bound(p, r.solution.duals)
    assert free["proven"] and dense["proven"]
    assert free["lower"] == pytest.approx(dense["lower"], rel=1e-12)
    assert free["lower"] <= truth
