"""Enclosure instead of bisection: a parameter that enters affinely is solved for once.

The truth comes from elsewhere: the H-infinity norm of the bounded-real lemma from
python-control (a Hamiltonian-based algorithm, no LMI), and the bisection of the same parameter
(the older path, each point certified on its own).
"""

from __future__ import annotations

import pytest
from brl_helpers import brl, hinf, peak_gain, plant

from lmic.certify import certify
from lmic.studies.sweep import maximize, minimize
from lmic.studies.sweep.enclosed import affine_parameter
from lmic.studies.sweep.points import setup
from lmic.template import STAR, I, block, theorem


@theorem(
    id="test.brl_gamma_squared",
    title="Bounded-real lemma through a constant computed from gamma (not affine)",
    citation="Boyd et al. (1994), sec. 6.3.2",
    kind="analysis",
    objective="feasibility",
    system_class="continuous time, linear, stable",
)
def brl_const(t):
    n, m, q = t.dims("n m q")
    A, B, C = t.data("A", n, n), t.data("B", n, m), t.data("C", q, n)
    P = t.symmetric("P", n, pd=True)
    t.param("gamma", default=1.0, domain="positive", doc="H-infinity bound")
    g2 = t.const("g2", lambda d: float(d["gamma"]) ** 2, doc="gamma^2 (hidden from the template)")
    t.lmi("brl", block([[A.T * P + P * A, P * B, C.T], [STAR, -g2 * I(m), 0], [STAR, STAR, -I(q)]]) < 0)


@pytest.mark.parametrize(("n", "seed"), [(4, 0), (6, 1), (8, 2), (10, 3)])
def test_minimize_encloses_the_hinf_norm(n, seed):
    A, B, C, system = plant(n, seed)
    r = minimize(brl, system, "gamma")
    assert r.method == "enclosure" and r.upper_kind == "dual-bound" and r.iterations == 0
    ref, peak = hinf(A, B, C), peak_gain(A, B, C)
    # the lower end can be within 1e-15 of the norm (the exact face route): against the peak
    # gain, which is below the norm up to its own rounding (1e-13 relative is far above it)
    assert r.lower <= peak * (1 + 1e-13) and max(ref, peak) <= r.upper
    assert abs(peak - ref) <= 1e-9 * ref  # the two references agree
    # converged exactly when the enclosure is within the tolerance (else said in the message)
    assert r.converged == (r.upper - r.lower <= max(r.xtol, r.rtol * r.upper))
    assert r.converged or "gap" in r.message
    # the certified end: the theorem's own problem at gamma = upper, certified again here
    assert r.end is not None and r.end.value == r.upper
    assert certify(r.end.problem, r.end.solution).verdict == "certified"
    d = r.to_dict()
    ends = d["ends"]
    assert ends["lower"]["is_bound"] is True and "dual point" in ends["lower"]["proof"]
    assert ends["upper"]["evidence"] == "certified point"
    # each side's kind under its own name (upper_kind once named the lower end of an infimum)
    assert (d["lower_kind"], d["upper_kind"]) == ("dual-bound", "certified point")


@pytest.mark.parametrize(("n", "seed"), [(4, 0), (6, 1)])
def test_minimize_enclosure_is_tight_on_clarabel(n, seed):
    A, B, C, system = plant(n, seed)
    r = minimize(brl, system, "gamma", backend="clarabel", rtol=1e-4)
    assert r.converged and r.upper - r.lower <= 1e-4 * hinf(A, B, C)


def test_enclosure_agrees_with_the_bisection():
    A, B, C, system = plant(5, 3)
    enc = minimize(brl, system, "gamma", rtol=1e-6)
    bis = minimize(brl, system, "gamma", method="bisection", lo=1e-2, hi=1e3, rtol=1e-6)
    assert bis.method == "bisection"
    # the bisection's certified value is feasible: the proven dual bound lies below it
    assert enc.lower <= bis.upper
    # and the enclosure's certified value lies above the bisection's last non-certified value
    assert bis.lower is None or bis.lower <= enc.upper
    assert abs(enc.upper - bis.upper) <= 1e-4 * bis.upper


def test_an_unbounded_supremum_falls_back_to_the_bisection():
    """``sup gamma`` of the bounded-real lemma is infinite (any larger gamma works): the convex
    problem is unbounded, the route gives no certified end and the bisection takes over."""
    A, B, C, system = plant(3, 4)
    ref = hinf(A, B, C)
    r = maximize(brl, system, "gamma", lo=2.0 * ref, hi=50.0, max_evals=8)
    assert r.method == "bisection" and r.method_note.startswith("no enclosure")
    assert r.lower == 50.0  # certified at the top of the bracket


@pytest.mark.parametrize(
    ("theorem_id", "system", "param", "affine", "why"),
    [
        # beta multiplies only omega > 0 in a scale-free problem: omega = 1 makes it affine
        ("qib.thm1", "examples/qib.thm1.flexible-joint.yaml", "beta", True, "omega"),
        ("uncertain_dt.lemma3", "examples/uncertain_dt.lemma3.example-plant.yaml", "mu", False, "non-affinely"),
        ("nonuniform.thm1", "examples/nonuniform.thm1.chua.yaml", "delta_bar", False, "multiplies"),
        ("delay_b.thm4_1", "examples/delay_b.thm4_1.ex1_lambda0_2.yaml", "lambda", True, ""),
    ],
)
def test_affine_parameter_detection_on_shipped_theorems(theorem_id, system, param, affine, why):
    from pathlib import Path

    root = Path(__file__).resolve().parents[3]
    s, plan, overrides, decl = setup(theorem_id, str(root / system), param, None)
    ok, reason, _ = affine_parameter(plan, s, overrides, decl)
    assert ok is affine
    assert why in reason


def test_affine_parameter_detection_sees_through_constants():
    _, _, _, system = plant(3, 5)
    s, plan, overrides, decl = setup(brl_const, system, "gamma", None)
    ok, reason, _ = affine_parameter(plan, s, overrides, decl)
    assert ok is False and "not affine" in reason
    s, plan, overrides, decl = setup(brl, system, "gamma", None)
    assert affine_parameter(plan, s, overrides, decl)[0] is True


def test_cli_method_option_selects_the_route_and_both_routes_agree(capsys):
    """`--method enclosure` and `--method bisection` on delay_b's affine lambda: two algorithms,
    one supremum (lambda's domain ends at 1, where both certify); a bad --method is bad input."""
    import json
    from pathlib import Path

    from lmic.cli import main

    f = str(Path(__file__).resolve().parents[3] / "examples" / "delay_b.thm4_1.ex1_lambda0_2.yaml")
    found = {}
    for method in ("enclosure", "bisection"):
        assert main(["solve", "delay_b.thm4_1", f, "--maximize", "lambda", "--method", method, "--json"]) == 0
        d = json.loads(capsys.readouterr().out)
        assert d["method"] == method
        found[method] = d["lower"]
    assert abs(found["enclosure"] - found["bisection"]) <= 1e-6
    with pytest.raises(SystemExit) as exc:
        main(["solve", "delay_b.thm4_1", f, "--maximize", "lambda", "--method", "nonsense"])
    assert exc.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--method" in err[0] and "nonsense" in err[0]


def test_the_bisection_without_a_bracket_goes_below_half_its_start():
    """--minimize gamma --method bisection with no bracket, from a start well above the norm
    (gamma = 4 times it, an open domain end at 0): the expansion stepped from a fixed base, met
    the same clamped midpoint twice and stopped at half the start, saying gamma was certified
    'down to the end of its domain'. It now halves from the latest certified value."""
    A, B, C, system = plant(4, 5)
    ref = hinf(A, B, C)
    system = dict(system, params={**system.get("params", {}), "gamma": 4.0 * ref})
    r = minimize(brl, system, "gamma", method="bisection", rtol=1e-4)
    assert r.method == "bisection" and "end of its domain" not in r.message
    assert r.upper is not None and r.lower is not None
    assert r.lower <= ref * (1 + 1e-9) and ref <= r.upper <= ref * (1 + 2e-4)
    assert certify(r.end.problem, r.end.solution).verdict == "certified"
