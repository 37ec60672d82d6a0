"""lmic.studies.sweep.exact_lift: the lifted problem's exact counterpart.

Checked against a hand computation in Fractions (the coefficient of ``P_01`` is ``-(A_00 +
A_11)`` exactly where the float IR rounded the sum; the parameter's column is ``-1`` on the
``gamma`` diagonal; the constant column keeps ``C`` exactly), against the decline when the
parameter multiplies a decision variable, and end to end: ``minimize`` of a 20-state
bounded-real lemma proves its lower end by the exact face route (before, it had none: the
lifted problem had no exact counterpart), below the H-infinity norm.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest
import scipy.sparse as sp
from brl_helpers import brl, peak_gain, plant

from lmic.compile.exact import ExactUnavailable, exact_of
from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
from lmic.ir.svec import tril_rows_cols
from lmic.studies.sweep import minimize
from lmic.studies.sweep.enclosed import affine_parameter, lift
from lmic.studies.sweep.exact_lift import exact_lift
from lmic.studies.sweep.points import setup


def test_the_lifted_exact_problem_equals_a_hand_computation():
    A, _, C, system = plant(3, 7)
    A[0, 0], A[1, 1] = -0.1, -0.2  # a sum A_00 + A_11 that rounds in floating point
    system["data"]["A"] = A.tolist()
    s, plan, overrides, decl = setup(brl, system, "gamma", None)
    ok, _, (probs, values, k) = affine_parameter(plan, s, overrides, decl)
    assert ok and k is None
    lifted = lift(probs, values, "gamma", "min", (0.0, np.inf, False, False))
    ex = exact_of(lifted)
    assert ex.about == "theorem" and "lifted in 'gamma'" in ex.source
    (lm,) = [i for i, lmi in enumerate(lifted.lmis) if lmi.name == "brl"]
    rows = list(zip(*tril_rows_cols(lifted.lmis[lm].dim), strict=True))
    P01 = 1 + lifted.variables[0].offset + 1  # svec order of P: P_00, P_01, ...
    exact_sum = Fraction(float(A[0, 0])) + Fraction(float(A[1, 1]))
    assert ex.lmis[lm].value(rows.index((1, 0)), P01) == -exact_sum  # the LMI is -(...) > 0
    assert Fraction(float(lifted.lmis[lm].coeffs[rows.index((1, 0)), P01])) != -exact_sum
    g = lifted.n  # the parameter's column: gamma on the diagonal of the last 4 rows (m = q = 2)
    for d in range(3, 7):
        assert ex.lmis[lm].value(rows.index((d, d)), g) == 1  # -(-gamma) I
        assert ex.lmis[lm].value(rows.index((d, d)), 0) == 0  # no constant left at gamma = 0
    assert ex.lmis[lm].value(rows.index((5, 0)), 0) == -Fraction(float(C[0, 0]))  # -C
    assert ex.objective[-1] == 1 and not any(ex.objective[:-1])


def _problem(v: float, w: float) -> Problem:
    """``[[v + w q]] > 0``: the parameter's value ``v`` enters the constant; ``w`` the variable's
    coefficient."""
    return Problem(
        [Variable("q", "scalar", (1, 1))],
        [LMI("c", 1, sp.csc_matrix([[v, w]]))],
        LinearConstraints.empty(1),
        Objective("feasibility", [0.0, 0.0]),
    )


def test_a_parameter_in_a_variables_coefficient_declines_exactly():
    dom = (0.0, 1.0, True, True)
    p0, p1 = _problem(0.1, 1.0), _problem(0.3, 1.0)
    good = exact_lift(p0, p1, 0.1, 0.3, lift([p0, p1], [0.1, 0.3], "v", "min", dom), "v")
    assert [good.lmis[0].value(0, k) for k in range(3)] == [0, 1, 1]
    # the bound problems differ in q's coefficient by one unit in the last place: float lifting
    # would not notice, the exact check does
    p0, p1 = _problem(0.1, 1.0), _problem(0.3, float(np.nextafter(1.0, 2.0)))
    with pytest.raises(ExactUnavailable, match="decision variable"):
        exact_lift(p0, p1, 0.1, 0.3, lift([p0, p1], [0.1, 0.3], "v", "min", dom), "v")


def test_minimize_at_20_states_proves_its_lower_end_on_the_exact_face():
    A, B, C, system = plant(20, 0)
    r = minimize(brl, system, "gamma")
    lower = r.to_dict()["ends"]["lower"]
    assert r.method == "enclosure" and r.upper_kind == "dual-bound"
    assert "exact rational arithmetic" in lower["proof"], lower
    peak = peak_gain(A, B, C)
    assert r.lower <= peak * (1 + 1e-13) and peak <= r.upper
    assert r.upper - r.lower <= 1e-5 * r.upper
