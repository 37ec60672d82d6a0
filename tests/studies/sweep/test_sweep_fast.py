"""Fast sweeps and bisections: reused points, screened interior values, proven bracket ends.

The truth is independent of the code under test: the supremum of the decay rate ``a`` in
``A^T P + P A + 2 a P < 0, P > 0`` is ``-max Re eig(A)`` (closed form, numpy); every certified
point is certified again here, re-bound at its value; every infeasibility proof is the
certifier's verdict on the end's own solution.
"""

from __future__ import annotations

import numpy as np
import pytest

from lmic.certify import certify
from lmic.compile import bind, plan_for
from lmic.solution import Solution
from lmic.studies.sweep import maximize, minimize, points, sweep
from lmic.studies.sweep.results import PointResult, kind_of
from lmic.system import load_system
from lmic.template import block, theorem


@theorem(id="toy.decay_fast", title="decay rate", citation="test")
def decay(t):
    """``P > 0``, ``A^T P + P A + 2 a P < 0``: feasible iff ``a < -max Re eig(A)``."""
    (n,) = t.dims("n")
    A = t.data("A", n, n)
    a = t.param("a", default=0.0, domain="real")
    P = t.symmetric("P", n)
    t.lmi("P > 0", block(P) > 0)
    t.lmi("decay", block(A.T * P + P * A + 2 * a * P) < 0)


def _system(n: int, seed: int) -> tuple[dict, float]:
    """A random stable ``A`` (not small for the strict reduction: ``n(n+1)/2 > 200`` at n >= 20)."""
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n)) / np.sqrt(n)
    A -= (np.max(np.linalg.eigvals(A).real) + 1.0 + rng.random()) * np.eye(n)
    return {"lmic": 1, "data": {"A": A.tolist()}}, float(-np.max(np.linalg.eigvals(A).real))


def _problem(system: dict, value: float):
    sysobj = load_system(system)
    return bind(plan_for(decay, sysobj.params), sysobj, {"a": value})


def _certified(system: dict, value: float, x: np.ndarray) -> bool:
    cert = certify(_problem(system, value), Solution("feasible", x=np.asarray(x)))
    if cert.verdict != "certified":
        cert = certify(_problem(system, value), Solution("feasible", x=np.asarray(x)), exact=True)
    return cert.verdict == "certified"


def _end_is_bounded(system: dict, pt: PointResult) -> bool:
    """The non-certified end's solution, certified again on the problem re-bound at its value: a
    verified ray of this scale-free theorem bounds the relative margin (``infeasible-bounded``;
    the unstable mode of a random ``A`` is irrational, so no exact proof exists in rationals)."""
    cert = certify(_problem(system, pt.value), pt.solution)
    return cert.verdict == "infeasible-bounded" and cert.farkas["scope"]["basis"] == "homogeneous"


@pytest.mark.parametrize(("n", "seed"), [(3, 0), (20, 1)])
def test_maximize_brackets_the_closed_form_with_evidence_at_both_ends(n, seed):
    system, truth = _system(n, seed)
    res = maximize(decay, system, "a", lo=0.0, hi=2.0 * truth + 1.0, rtol=1e-4, xtol=0.0, backoff=0.0)
    assert res.converged and res.lower < truth <= res.upper
    assert res.upper - res.lower <= 1e-4 * res.upper * (1 + 1e-12)
    low = next(p for p in res.points if p.value == res.lower and p.outcome == "feasible")
    assert _certified(system, res.lower, low.x)
    assert res.end is not None and _certified(system, res.lower, res.end.solution.x)
    # the upper end carries a verified ray (bounded: scale-free, irrational unstable mode), verified
    # again here; the closed form says it is right; a screened point never carries one
    assert res.upper_kind == "infeasible-bounded"
    up = [p for p in res.points if p.value == res.upper and kind_of(p) == "infeasible-bounded"]
    assert up and not up[-1].screened and _end_is_bounded(system, up[-1])
    for p in res.points:
        if p.screened:
            assert p.outcome == "undecided" and kind_of(p) == "undecided"


@theorem(id="toy.growth_fast", title="growth bound", citation="test")
def growth(t):
    """``P > 0``, ``A^T P + P A - 2 b P < 0``: feasible iff ``b > max Re eig(A)``."""
    (n,) = t.dims("n")
    A = t.data("A", n, n)
    b = t.param("b", default=0.0, domain="real")
    P = t.symmetric("P", n)
    t.lmi("P > 0", block(P) > 0)
    t.lmi("growth", block(A.T * P + P * A - 2 * b * P) < 0)


@pytest.mark.parametrize(("n", "seed"), [(3, 2), (20, 7)])
def test_minimize_brackets_the_closed_form_with_evidence_at_both_ends(n, seed):
    system, truth = _system(n, seed)
    inf = -truth  # the spectral abscissa of A
    res = minimize(growth, system, "b", lo=2.0 * inf, hi=0.0, rtol=1e-4, xtol=0.0, backoff=0.0)
    assert res.sense == "min" and res.converged and res.lower <= inf < res.upper
    sysobj = load_system(system)
    at = bind(plan_for(growth, sysobj.params), sysobj, {"b": res.upper})
    end = next(p for p in res.points if p.value == res.upper and p.outcome == "feasible")
    assert certify(at, Solution("feasible", x=end.x)).verdict == "certified"
    assert res.upper_kind == "infeasible-bounded"  # for a minimum: the non-certified (lower) end
    low = [p for p in res.points if p.value == res.lower and kind_of(p) == "infeasible-bounded"][-1]
    at_low = bind(plan_for(growth, sysobj.params), sysobj, {"b": res.lower})
    assert not low.screened and certify(at_low, low.solution).verdict == "infeasible-bounded"


def test_a_wrong_screen_is_caught_by_the_end_proof_and_the_bracket_moves_up(monkeypatch):
    """A screen that calls feasible values infeasible: the end proof finds them certified."""
    system, truth = _system(20, 3)
    real = points.screen
    fooled: list[float] = []

    def faulty(problem, backend=None, options=None, *, value=float("nan"), **kw):
        if 0.6 * truth < value < truth:  # feasible values, screened as "solver: infeasible"
            fooled.append(value)
            pt = PointResult(value=value, outcome="undecided", proof="solver: infeasible (test)", verdict="undecided")
            pt.screened = True
            return pt
        return real(problem, backend, options, value=value, **kw)

    monkeypatch.setattr(points, "screen", faulty)
    res = maximize(decay, system, "a", lo=0.0, hi=2.0 * truth, rtol=1e-3, xtol=0.0, backoff=0.0)
    assert fooled  # the faulty screen was used
    assert res.converged and res.lower < truth <= res.upper
    assert res.upper - res.lower <= 1e-3 * res.upper * (1 + 1e-12)
    low = next(p for p in res.points if p.value == res.lower and p.outcome == "feasible")
    assert _certified(system, res.lower, low.x)
    up = [p for p in res.points if p.value == res.upper and not p.screened]
    assert up and _end_is_bounded(system, up[-1])


def test_a_screen_that_never_decides_leaves_the_end_honestly_labelled(monkeypatch):
    """No proof at the upper end: it is reported as what it is, never as infeasible-certified."""
    from lmic.studies.sweep import points as pts

    system, truth = _system(3, 4)
    monkeypatch.setattr(pts, "decide", _undecided_above(pts.decide, truth))
    real_screen = pts.screen

    def screen(problem, backend=None, options=None, *, value=float("nan"), **kw):
        if value >= truth:
            pt = PointResult(value=value, outcome="undecided", proof="not certified (test)", verdict="undecided")
            pt.screened = True
            return pt
        return real_screen(problem, backend, options, value=value, **kw)

    monkeypatch.setattr(pts, "screen", screen)
    res = maximize(decay, system, "a", lo=0.0, hi=2.0 * truth, rtol=1e-3, xtol=0.0, backoff=0.0)
    assert res.lower is not None and res.lower < truth
    assert res.upper_kind == "undecided" and res.upper_proven is None
    assert "not a proof" in res.message


def _undecided_above(real, truth):
    def decide(problem, backend=None, options=None, **kw):
        if kw.get("value", 0.0) >= truth:
            return PointResult(value=kw["value"], outcome="undecided", proof="no decision (test)", verdict="undecided")
        return real(problem, backend, options, **kw)

    return decide


def test_sweep_reuse_keeps_every_verdict_and_every_point_certifies(monkeypatch):
    system, truth = _system(6, 5)
    values = list(np.linspace(0.0, 1.3 * truth, 8))  # no value at the supremum itself
    fast = sweep(decay, system, "a", values)
    slow = sweep(decay, system, "a", values, reuse=False)
    assert [p.outcome for p in fast.points] == [p.outcome for p in slow.points]
    assert [p.outcome == "feasible" for p in fast.points] == [v < truth for v in values]
    assert any(p.reused for p in fast.points) and not any(p.reused for p in slow.points)
    for p in fast.points:
        if p.outcome == "feasible":
            assert _certified(system, p.value, p.x)
        else:
            assert _end_is_bounded(system, p)


def test_reuse_never_certifies_a_point_that_fails():
    system, truth = _system(4, 6)
    inside = points.decide(_problem(system, 0.5 * truth), "clarabel")
    assert inside.outcome == "feasible"
    assert points.reuse(_problem(system, 1.1 * truth), inside.x) is None
    near = points.reuse(_problem(system, 0.4 * truth), inside.x, value=0.4 * truth, source=0.5 * truth)
    assert near is not None and near.reused and _certified(system, 0.4 * truth, near.x)


def test_bisection_stops_at_floating_point_resolution():
    # tolerances far below the spacing of floats: the bracket ends as two adjacent numbers
    # around the closed form, with a message saying so, instead of bisecting forever
    system, truth = _system(3, 0)
    res = maximize(
        decay, system, "a", lo=0.0, hi=2.0 * truth + 1.0, rtol=1e-300, xtol=1e-300, max_evals=10**9, backoff=0.0
    )
    assert abs(res.lower - truth) <= 1e-6 * truth  # the certified end, to the certifier's accuracy
    assert np.nextafter(res.lower, np.inf) == res.upper
    assert "floating-point resolution" in res.message
    assert len(res.points) < 200
