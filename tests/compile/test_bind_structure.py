"""The CSC structure of an LMI is computed once per plan and dimensions and reused by re-binds:
a re-bind with other numbers must give exactly what a fresh plan (no cached structure) gives,
and both must equal ``F(x)`` evaluated with numpy directly."""

from __future__ import annotations

import numpy as np

from lmic.compile import analyse, bind
from lmic.template import STAR, I, block, theorem


@theorem(id="test.structure", title="structure reuse", citation="tests")
def structure(t):
    n, p = t.dims("n p")
    A = t.data("A", n, n)
    C = t.data("C", p, n)
    P = t.symmetric("P", n)
    R = t.full("R", p, n)
    w = t.scalar("w")
    X = A.T * P - C.T * R
    t.lmi("M", block([[-P + w * I(n), X, X], [STAR, P - w * I(n), 0], [STAR, STAR, -P]]) < 0)


def _system(n: int, p: int, seed: int) -> dict:
    rng = np.random.default_rng(seed)
    return {"data": {"A": rng.standard_normal((n, n)).tolist(), "C": rng.standard_normal((p, n)).tolist()}}


def _direct(system: dict, P: np.ndarray, R: np.ndarray, w: float) -> np.ndarray:
    A, C = np.asarray(system["data"]["A"]), np.asarray(system["data"]["C"])
    n = A.shape[0]
    X = A.T @ P - C.T @ R
    Z = np.zeros((n, n))
    M = np.block([[-P + w * np.eye(n), X, X], [X.T, P - w * np.eye(n), Z], [X.T, Z, -P]])
    return -M  # "M < 0" is stored as -M > 0


def test_rebind_reuses_the_structure_and_equals_a_fresh_plan():
    plan = analyse(structure)
    rng = np.random.default_rng(0)
    for seed in range(4):  # the first bind builds the structure, the others reuse it
        system = _system(5, 2, seed)
        cached = bind(plan, system).lmis[0].coeffs
        fresh = bind(analyse(structure), system).lmis[0].coeffs
        assert cached.has_sorted_indices and fresh.has_sorted_indices
        assert np.array_equal(cached.indptr, fresh.indptr) and np.array_equal(cached.indices, fresh.indices)
        assert np.array_equal(cached.data, fresh.data)
        # and against numpy at a random point
        prob = bind(plan, system)
        x = rng.standard_normal(prob.n)
        v = prob.unpack(x)
        assert np.allclose(prob.lmis[0].matrix(x), _direct(system, v["P"], v["R"], float(v["w"])), atol=1e-12)
    # other dimensions: another structure
    prob = bind(plan, _system(3, 1, 9))
    assert prob.lmis[0].dim == 9
    x = rng.standard_normal(prob.n)
    v = prob.unpack(x)
    assert np.allclose(prob.lmis[0].matrix(x), _direct(_system(3, 1, 9), v["P"], v["R"], float(v["w"])), atol=1e-12)


def test_sorted_indices_are_canonical():
    prob = bind(analyse(structure), _system(4, 2, 1))
    C = prob.lmis[0].coeffs
    check = C.copy()
    check.has_sorted_indices = False
    check.sort_indices()
    assert np.array_equal(check.indices, C.indices) and np.array_equal(check.data, C.data)
    assert C.has_canonical_format
