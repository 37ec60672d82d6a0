"""A grid over a parameter of an optimisation theorem gives each value's proven optimum (the
route and its enclosure, as a single solve), and picks the best value by it. A newcomer's sweep
reported the policy's first certified point at each value, 11-14 % above the optimum, and so
named the wrong best value."""

from __future__ import annotations

from brl_helpers import hinf, plant

from lmic.studies.sweep import sweep
from lmic.template import STAR, I, block, theorem


@theorem(id="test.scaled_brl", title="min gamma for (A, B, c C)", citation="Boyd et al. (1994)", kind="analysis")
def scaled_brl(t):
    n, m, q = t.dims("n m q")
    A, B, C = t.data("A", n, n), t.data("B", n, m), t.data("C", q, n)
    c = t.param("c", default=1.0, domain="positive", doc="output scaling")
    P = t.symmetric("P", n, pd=True)
    g = t.scalar("gamma")
    t.lmi("brl", block([[A.T * P + P * A, P * B, c * C.T], [STAR, -g * I(m), 0], [STAR, STAR, -g * I(q)]]) < 0)
    t.minimize(g)


def test_each_value_gets_its_proven_optimum_and_the_best_is_chosen_by_it():
    A, B, C, system = plant(4, 7)
    norm = hinf(A, B, C)  # python-control: min gamma at c is c times the H-infinity norm
    values = [2.0, 0.5, 1.0]
    r = sweep(scaled_brl, system, "c", values)
    assert r.best_rule == "proven optimum" and r.best.value == 0.5
    for p in r.points:
        truth = p.value * norm
        enc = p.enclosure
        assert p.outcome == "feasible" and enc is not None
        assert enc["lower"] <= truth * (1 + 1e-9) and truth <= enc["upper"] * (1 + 1e-12)
        assert enc["rel_gap"] <= 1e-6 and p.objective >= truth * (1 - 1e-9)
    assert r.to_dict()["points"][0]["enclosure"]["upper"] == r.points[0].enclosure["upper"]
