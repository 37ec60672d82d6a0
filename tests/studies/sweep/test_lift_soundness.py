"""A parameter is lifted into one convex problem only where the template shows it affine.

The bound data at three sample values cannot show affinity: a constant (``t.const``) or a
coefficient that agrees with an affine function at the sample values (0, 1 and 1/2 for a
parameter whose default is 0) and not elsewhere passed that check, and the lifted problem's
dual bound was then reported as a proven end of a bracket that excludes feasible values.
The truth here is arithmetic: ``x = 0`` satisfies the constraints at ``p = 10``.
"""

from __future__ import annotations

from lmic.studies.sweep import maximize
from lmic.studies.sweep.enclosed import affine_parameter
from lmic.studies.sweep.points import setup
from lmic.template import theorem


def _c(p: float) -> float:
    # p at p = 0, 1/2, 1 (the sample values); -75.5 at p = 10
    return p - 0.1 * p * (p - 1.0) * (p - 0.5)


@theorem(
    id="test.lift_cubic_const",
    title="a constant affine at three values only",
    citation="-",
    kind="analysis",
    objective="feasibility",
)
def cubic_const(t):
    t.param("p", default=0.0, domain="real")
    c = t.const("c", lambda v: _c(float(v["p"])))
    x = t.scalar("x")
    t.constraint("x >= 0", x >= 0)
    t.constraint("x <= 2 - c", x <= 2 - c)


@theorem(
    id="test.lift_cubic_coef",
    title="a scale-free coefficient affine at three values only",
    citation="-",
    kind="analysis",
    objective="feasibility",
)
def cubic_coef(t):
    p = t.param("p", default=0.0, domain="real")
    w = t.scalar("w", sign="positive")
    x = t.scalar("x")
    t.constraint("w > 0", w > 0)
    t.constraint("x > 0", x > 0)
    t.constraint("(2 - c(p)) w - x > 0", (2 - p + p * (p - 1) * (p - 0.5) / 10) * w - x > 0)


def test_truth():
    assert _c(10.0) == -75.5 and 0.0 <= 2.0 - _c(10.0)  # x = 0 is feasible at p = 10


def test_a_constant_that_reads_the_parameter_is_not_lifted():
    s, plan, overrides, decl = setup(cubic_const, {"data": {}}, "p", None)
    ok, why, _ = affine_parameter(plan, s, overrides, decl)
    assert ok is False and "t.const" in why


def test_a_coefficient_not_affine_is_not_lifted_on_the_scale_free_route():
    s, plan, overrides, decl = setup(cubic_coef, {"data": {}}, "p", None)
    ok, why, _ = affine_parameter(plan, s, overrides, decl)
    assert ok is False and "non-affinely" in why


def test_no_proven_bracket_excludes_a_feasible_value():
    """``c(p) <= 2`` for every ``p >= 0`` (its maximum is 1.76 at p = 2.35): the supremum is
    infinite, so no proof may bound it; the search doubles up to its evaluation budget."""
    r = maximize(cubic_const, {"data": {}}, "p", max_evals=12)
    d = r.to_dict()
    assert r.method == "bisection" and r.upper_proven is None and not d["bracket_proven"]
    assert r.lower is not None and r.lower >= 10.0 and _c(r.lower) <= 2.0


@theorem(
    id="test.non_monotone",
    title="feasible for p <= 1.1 and for p >= 3",
    citation="-",
    kind="analysis",
    objective="feasibility",
)
def non_monotone(t):
    t.param("p", default=0.0, domain="real")
    c = t.const("c", lambda v: (float(v["p"]) - 1.1) * (float(v["p"]) - 3.0))
    x = t.scalar("x")
    t.constraint("x >= 0", x >= 0)
    t.constraint("x <= c", x <= c)


def test_a_bisection_bracket_is_not_called_proven_where_feasibility_is_not_monotone(capsys):
    assert (10.0 - 1.1) * (10.0 - 3.0) >= 0.0  # x = 0 is feasible at p = 10: sup p = +inf
    r = maximize(non_monotone, {"data": {}}, "p", rtol=1e-3, max_evals=20)
    d = r.to_dict()
    # both ends are proven (a certified point near 1.1, exact infeasibility just above it) ...
    assert d["ends_proven"] and r.upper_proven is not None and 1.1 <= r.upper_proven < 3.0
    # ... but the supremum is not bracketed: p enters non-affinely, and is feasible again from 3
    assert not d["interval_proven"] and not d["bracket_proven"]
    assert "assumes that the feasible values of 'p' form an interval" in r.message
    from lmic.commands.sweep_cli import _print_sup

    _print_sup(r)  # what `lmic solve --maximize` prints
    out = " ".join(capsys.readouterr().out.split())
    assert "(xtol 1e-06, rtol 0.001) (if the feasible values form an interval: see the note)" in out
    assert "the bracket assumes that the feasible values of 'p' form an interval" in out
