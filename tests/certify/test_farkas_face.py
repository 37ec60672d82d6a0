"""The exact proof of a solver's ray whose face is tilted off the true (rational) face."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from lmic.certify.farkas import prove_farkas, verify_farkas
from lmic.certify.farkas_exact import _prove_farkas
from lmic.compile import compile_theorem

THESIS_EX = Path(__file__).resolve().parents[2] / "examples" / "thesis.thm3_2_2.ex3_2_2.yaml"


def _tilted_ray(noise: float, seed: int = 0, gamma: float = 3.33) -> tuple[object, dict]:
    # z = (e4, -A e4) = e4 - e7 annihilates every P and Lbar term of LMI (3.14) (see
    # tests/engine/test_engine.py); a solver returns it only to its accuracy: z + noise,
    # a rank-1 Z whose face (span of z + noise) is tilted off the true face span(z)
    problem = compile_theorem("thesis.thm3_2_2", str(THESIS_EX), {"gamma": gamma})
    z = np.zeros(8)
    z[3], z[6] = 1.0, -1.0
    z += noise * np.random.default_rng(seed).standard_normal(8)
    lmis = [np.outer(z, z) if lmi.name == "(3.14)" else np.zeros((lmi.dim, lmi.dim)) for lmi in problem.lmis]
    return problem, {"lmis": lmis, "linear": []}


def test_tilted_rank_one_ray_is_proven_on_a_rational_face():
    problem, ray = _tilted_ray(3e-6)
    v = verify_farkas(problem, ray)
    assert v["verified"] and v["kind"] == "closed" and np.isfinite(v["radius"])
    # the cause of the old failure: on the tilted face the exact conditions force Z = 0
    tilted = _prove_farkas(problem, ray, 1e-9, False)
    assert not tilted["proven"] and "g_0 = 0" in tilted["reason"]
    r = prove_farkas(problem, ray, rel_face=(1e-9,))
    assert r["proven"] and r["kind"] == "closed" and r["face"]["rational_basis"]
    # g_0 of z z^T / |z|^2 with z = e4 - e7: (|A v|^2 - gamma^2) / 2 with |A v| = 1, gamma = 3.33
    assert r["g0"] == pytest.approx((1.0 - 3.33**2) / 2, rel=1e-12)


def test_rational_face_is_only_a_candidate():
    # gamma = 0.5: the same ray, found on the same rational face, has g_0 = (1 - gamma^2) / 2 > 0
    # (it separates nothing); the exact check says so instead of proving anything
    problem, ray = _tilted_ray(3e-6, gamma=0.5)
    assert not verify_farkas(problem, ray)["verified"]
    r = _prove_farkas(problem, ray, 1e-9, False, rational=True)
    assert not r["proven"] and "no exact separation" in r["reason"]
    assert r["g0"] == pytest.approx((1.0 - 0.5**2) / 2, rel=1e-12)
    assert not prove_farkas(problem, ray)["proven"]
