"""lmic.compile.probe: shape mistakes of derived quantities and checks are bad input at bind;
value-dependent failures at the random probe point are not (the certifier judges values at the
solver's point). delay_b.thm4_1 and uio_dt.thm4_1 derive quantities that are complex at a random
point: the first probe stopped every solve of them with a TypeError."""

from __future__ import annotations

import pytest
import sympy

from lmic.compile.bind import bind
from lmic.compile.plan import analyse
from lmic.errors import TemplateError
from lmic.template import I, block, hurwitz, theorem
from lmic.template.checks import less_than

SYSTEM = {"data": {"A": [[-1.0, 0.2], [0.0, -2.0]], "B": [[1.0], [0.5]]}}


@theorem(id="test.probe_values", title="t", citation="c")
def values(t):
    n, m = t.dims("n m")
    A = t.data("A", n, n)
    P = t.symmetric("P", n, pd=True)
    g = t.scalar("g")
    t.lmi("L", block(A.T * P + P * A + g * I(n)) < 0)
    r = t.derive("r", 1 / sympy.sqrt(-(g**2) - 1))  # a complex power at every point: a value, not a shape
    t.derive("r2", r * r)
    t.check("r below 10", less_than(r, 10.0))


@theorem(id="test.probe_square", title="t", citation="c")
def square(t):
    n, m = t.dims("n m")
    A, B = t.data("A", n, n), t.data("B", n, m)
    P = t.symmetric("P", n, pd=True)
    t.lmi("L", block(A.T * P + P * A) < 0)
    t.check("B Hurwitz", hurwitz(B))


def test_a_value_that_fails_only_at_the_probe_point_is_left_to_the_certifier():
    problem = bind(analyse(values), SYSTEM)
    assert [d.name for d in problem.derived] == ["r", "r2"]


def test_a_non_square_stability_check_is_a_template_error_at_bind():
    with pytest.raises(
        TemplateError, match=r"theorem test.probe_square: check 'B Hurwitz' \(hurwitz\) needs a square matrix, got 2x1"
    ):
        bind(analyse(square), SYSTEM)
