"""The feasible values of a parameter form an interval when the theorem is affine in a power
``p^k`` that multiplies no decision variable (``gamma^2`` in an H-infinity bound): the bracket of
``--maximize`` is then a proven supremum (``bracket_proven``). Where the power multiplies a
variable, or two powers mix, lmic does not claim it.

The truth of the toy theorem is arithmetic: ``x >= gamma^2`` and ``x <= 2`` is feasible exactly
for ``gamma <= sqrt(2)``.
"""

from __future__ import annotations

import math

from lmic.studies.sweep import maximize
from lmic.studies.sweep.enclosed import affine_parameter, monotone_affine
from lmic.studies.sweep.points import setup
from lmic.template import theorem


@theorem(id="test.mono_square", title="x >= gamma^2, x <= 2", citation="-", kind="analysis", objective="feasibility")
def square(t):
    g = t.param("gamma", default=1.0, domain="nonnegative")
    x = t.scalar("x")
    t.constraint("x >= gamma^2", x - g**2 >= 0)
    t.constraint("x <= 2", 2 - x >= 0)


@theorem(id="test.mono_mixed", title="x >= gamma^2 - gamma", citation="-", kind="analysis", objective="feasibility")
def mixed(t):
    g = t.param("gamma", default=1.0, domain="nonnegative")
    x = t.scalar("x")
    t.constraint("x >= gamma^2 - gamma", x - g**2 + g >= 0)
    t.constraint("x <= 2", 2 - x >= 0)


@theorem(id="test.mono_times_var", title="gamma^2 x <= 1", citation="-", kind="analysis", objective="feasibility")
def times_var(t):
    g = t.param("gamma", default=1.0, domain="nonnegative")
    x = t.scalar("x")
    t.constraint("x >= 1", x - 1 >= 0)
    t.constraint("gamma^2 x <= 1", 1 - g**2 * x >= 0)


def _check(thm) -> tuple[bool, str]:
    s, plan, o, d = setup(thm, {"data": {}}, "gamma", None)
    return affine_parameter(plan, s, o, d)[0], monotone_affine(plan, s, o, d)


def test_a_square_is_recognised_and_a_mixture_or_a_product_is_not():
    assert _check(square) == (False, "gamma**2")
    assert _check(mixed) == (False, "")  # gamma^2 - gamma is affine in no single power
    assert _check(times_var) == (False, "")  # gamma^2 multiplies x: not jointly affine


def test_the_bracket_of_a_square_is_a_proven_supremum(capsys):
    r = maximize(square, {"data": {}}, "gamma", rtol=1e-4)
    d = r.to_dict()
    assert d["interval_proven"] and d["ends_proven"] and d["bracket_proven"]
    assert r.lower <= math.sqrt(2.0) <= r.upper and "assumes" not in r.message
    from lmic.commands.sweep_cli import _print_sup

    _print_sup(r)  # what `lmic solve --maximize` prints: the bracket, without the caveat
    out = " ".join(capsys.readouterr().out.split())
    assert "sup gamma in [" in out and "if the feasible values form an interval" not in out
