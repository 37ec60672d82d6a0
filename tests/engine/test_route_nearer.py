"""The answer's point moved toward the enclosure's restored point (lmic.route_primal.nearer_point):
a newcomer's H2 norm by ``min trace(Z)``, whose certified point sat 9e-5 above the proven
enclosure, now answers within it; every candidate passes the certifier, and a problem with
derived gains keeps its interior point."""

from __future__ import annotations

import numpy as np
import scipy.linalg

import lmic.api
from lmic.route_primal import nearer_point
from lmic.template import STAR, I, block, theorem, trace

# a random stable 5-state system (a newcomer's instance, seed of their own)
A = [
    [-0.22246226907065503, -0.7584139806260218, -0.29323607424190806, 0.6321912601110062, 0.10339011015885671],
    [-0.10310075391382201, 0.06882717560154177, 0.11364092599773043, 0.36670185849216075, 0.04030636157346776],
    [0.48165116414053843, -0.19433971556516688, -0.019250657527004025, -0.20171410262764183, 0.023769336419386018],
    [0.755073236390706, -0.6154141222850084, -0.5655300313387682, -0.2494012177932125, 0.41415589601451647],
    [0.09741654111306958, -0.31607079161789986, 0.020702052586752135, -0.5210046249412046, -0.44614641778154723],
]
B = [[-0.7720558623744435], [0.5176441997474639], [-0.3149067090644009], [0.06816294250763563], [1.303884063415558]]
C = [
    [-0.4119211870803251, 1.3868748664034358, -0.9935963566029844, 2.2560505203638943, -1.4643795933435781],
    [-2.149965767956606, 0.21498990394222925, -0.21066989465960903, 0.7889379436273386, 0.8630338602364716],
    [-1.5180119682999633, -0.024972008944075582, 2.579801154009113, -0.36528262046028037, 1.7492341215440235],
]


@theorem(id="nb.dt_h2", title="discrete H2 norm squared", citation="Scherer & Weiland", kind="analysis")
def dt_h2(t):
    n, m, q = t.dims("n m q")
    Ad, Bd, Cd = t.data("A", n, n), t.data("B", n, m), t.data("C", q, n)
    P = t.symmetric("P", n)
    Z = t.symmetric("Z", q)
    t.lmi("Gramian", block([[P, Ad * P, Bd], [STAR, P, 0], [STAR, STAR, I(m)]]) > 0)
    t.lmi("output", block([[Z, Cd * P], [STAR, P]]) >= 0)
    t.minimize(trace(Z))


def _h2_squared() -> float:
    """trace(C W C') with W = A W A' + B B' (the controllability Gramian): no LMI solver."""
    a, b, c = (np.array(M) for M in (A, B, C))
    W = scipy.linalg.solve_discrete_lyapunov(a, b @ b.T)
    return float(np.trace(c @ W @ c.T))


def test_the_answer_lies_at_the_proven_primal_end():
    r = lmic.api.solve(dt_h2, {"data": {"A": A, "B": B, "C": C}})
    truth = _h2_squared()
    lo, hi = r.enclosure["lower"], r.enclosure["upper"]
    assert r.verdict == "certified" and lo <= truth <= hi and r.enclosure["rel_gap"] <= 1e-6
    # the returned objective: a feasible point's (above the infimum), and within 1e-7 of the
    # enclosure's primal end (it was 9e-5 above it, at the most interior point near the dual end)
    assert truth <= r.objective <= hi + 1e-7 * abs(hi)
    # its point, checked here with numpy: the strict LMI positive definite, the other PSD
    P, Z = np.array(r.values["P"]), np.array(r.values["Z"])
    a, b, c = (np.array(M) for M in (A, B, C))
    gram = np.block([[P, a @ P, b], [(a @ P).T, P, np.zeros((5, 1))], [b.T, np.zeros((1, 5)), np.eye(1)]])
    out = np.block([[Z, c @ P], [(c @ P).T, P]])
    assert np.linalg.eigvalsh(gram).min() > 0 and np.linalg.eigvalsh(out).min() > -1e-12
    assert abs(np.trace(Z) - r.objective) <= 1e-9 * abs(r.objective)
    # one enclosure in the answer: the verdict quotes the final one
    assert r.enclosure["reason"] in r.outcome.reason and "the answer's point before" in r.outcome.reason


def test_no_move_without_a_restored_point_with_exact_proofs_or_with_gains(monkeypatch):
    import dataclasses

    import lmic.route_primal

    monkeypatch.setattr(lmic.route_primal, "nearer_point", lambda *args, **kwargs: None)  # the answer as it was
    r = lmic.api.solve(dt_h2, {"data": {"A": A, "B": B, "C": C}})
    before = r.outcome
    assert before.solution.objective > r.enclosure["upper"] * (1 + 1e-6)  # the interior point, above the end
    moved = nearer_point(r.problem, before, r.enclosure)
    assert moved is not None and moved.certificate.verdict == "certified"
    assert moved.solution.objective < before.solution.objective
    assert nearer_point(r.problem, before, dict(r.enclosure, restored_x=None)) is None
    assert nearer_point(r.problem, before, r.enclosure, exact=True) is None
    with_gain = dataclasses.replace(r.problem, derived=[object()])
    assert nearer_point(with_gain, before, r.enclosure) is None
