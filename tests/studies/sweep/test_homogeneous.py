"""A parameter multiplying a positive scalar of a scale-free theorem, and the bisection's cheap steps.

The truth is a closed form: for a symmetric ``A`` with ``A < 0`` the supremum of ``beta`` such
that ``P > 0``, ``w I - P > 0`` and ``-(A^T P + P A) - 2 beta w I > 0`` hold for some ``P`` and
``w > 0`` is ``lambda_min(-A)`` (``P -> w I``; no ``P < w I`` does better: ``e^T (-(A^T P + P
A)) e = 2 a_i P_ii < 2 a_i w`` on the eigenvectors of ``A``). Every answer is checked by the
certifier on the theorem bound at the reported value, never by the code under test.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from lmic.certify import certify
from lmic.compile import bind, plan_for
from lmic.solution import Solution
from lmic.studies.sweep import maximize
from lmic.studies.sweep.enclosed import affine_parameter, fix_scalar
from lmic.studies.sweep.points import decide, setup
from lmic.studies.sweep.results import PROVEN_KINDS
from lmic.studies.sweep.screens import reach, screen
from lmic.template import I, block, theorem


@theorem(id="test.gevp_w", title="decay bound through a positive scalar", citation="test")
def gevp(t):
    (n,) = t.dims("n")
    A = t.data("A", n, n)
    P = t.symmetric("P", n)
    w = t.scalar("w", sign="positive")
    b = t.param("beta", default=0.1, domain="positive")
    t.lmi("P > 0", block(P) > 0)
    t.lmi("P < w I", block(w * I(n) - P) > 0)
    t.lmi("decay", block(-(A.T * P + P * A) - 2 * b * w * I(n)) > 0)


@theorem(id="test.gevp_free_w", title="the same with w free in sign", citation="test")
def gevp_free(t):
    (n,) = t.dims("n")
    A = t.data("A", n, n)
    P = t.symmetric("P", n)
    w = t.scalar("w")
    b = t.param("beta", default=0.1, domain="positive")
    t.lmi("P > 0", block(P) > 0)
    t.lmi("P < w I", block(w * I(n) - P) > 0)
    t.lmi("decay", block(-(A.T * P + P * A) - 2 * b * w * I(n)) > 0)


@theorem(id="test.gevp_offset", title="the same with a constant term (not scale-free)", citation="test")
def gevp_offset(t):
    (n,) = t.dims("n")
    A = t.data("A", n, n)
    P = t.symmetric("P", n)
    w = t.scalar("w", sign="positive")
    b = t.param("beta", default=0.1, domain="positive")
    t.lmi("P > I", block(P - I(n)) > 0)
    t.lmi("P < w I", block(w * I(n) - P) > 0)
    t.lmi("decay", block(-(A.T * P + P * A) - 2 * b * w * I(n)) > 0)


def _system(n: int, seed: int) -> tuple[dict, float]:
    rng = np.random.default_rng(seed)
    Q, _ = np.linalg.qr(rng.standard_normal((n, n)))
    a = rng.uniform(0.5, 3.0, n)
    A = -(Q * a) @ Q.T
    A = 0.5 * (A + A.T)
    return {"lmic": 1, "data": {"A": A.tolist()}}, float(np.linalg.eigvalsh(-A)[0])


def _problem(theorem_obj, system: dict, value: float):
    return bind(plan_for(theorem_obj, {}), _load(system), {"beta": value})


def _load(system: dict):
    from lmic.system import load_system

    return load_system(system)


def _certified(theorem_obj, system: dict, value: float, x) -> bool:
    cert = certify(_problem(theorem_obj, system, value), Solution("feasible", x=np.asarray(x, dtype=float)))
    if cert.verdict != "certified":
        cert = certify(_problem(theorem_obj, system, value), Solution("feasible", x=np.asarray(x)), exact=True)
    return cert.verdict == "certified"


def test_the_positive_scalar_is_detected_and_fixed():
    system, _ = _system(3, 0)
    s, plan, overrides, decl = setup(gevp, system, "beta", None)
    ok, name, bound = affine_parameter(plan, s, overrides, decl)
    assert ok and name == "w"
    probs, values, k = bound
    original = bind(plan, s, {"beta": values[0]})
    assert k == original.variable("w").offset
    # the fixed problem has one variable fewer and no row 'w > 0'
    assert probs[0].n == original.n - 1 and len(probs[0].linear) == len(original.linear) - 1
    # x of the fixed problem, with w = 1 put back, gives the same LMI values as the original
    rng = np.random.default_rng(1)
    xf = rng.standard_normal(probs[0].n)
    xo = np.insert(xf, k, 1.0)
    for a, b in zip(probs[0].lmis, original.lmis, strict=True):
        assert np.allclose(a.matrix(xf), b.matrix(xo))
    assert fix_scalar(original, k).n == original.n - 1


@pytest.mark.parametrize(
    ("theo", "why"),
    [(gevp_free, "not constrained positive"), (gevp_offset, "not scale-free")],
)
def test_no_fixing_without_a_positive_scalar_of_a_scale_free_problem(theo, why):
    system, _ = _system(3, 0)
    s, plan, overrides, decl = setup(theo, system, "beta", None)
    ok, reason, _ = affine_parameter(plan, s, overrides, decl)
    assert not ok and why in reason


@pytest.mark.parametrize(("n", "seed"), [(3, 0), (6, 1)])
def test_maximize_encloses_the_closed_form_with_a_proof_at_each_end(n, seed):
    system, truth = _system(n, seed)
    res = maximize(gevp, system, "beta", rtol=1e-4, xtol=0.0, backoff=0.0)
    assert res.method == "enclosure" and "w = 1" in res.method_note
    assert res.lower < truth <= res.upper and res.converged
    assert res.upper - res.lower <= 1e-4 * res.upper * (1 + 1e-12)
    # the certified end, checked on the theorem bound at that value (w = 1 put back)
    assert res.end is not None and _certified(gevp, system, res.lower, res.end.solution.x)
    # the other end: a global infeasibility proof at that value, verified again here
    assert res.upper_kind in PROVEN_KINDS and res.upper_proven == res.upper
    up = next(p for p in res.points if p.value == res.upper)
    cert = certify(_problem(gevp, system, res.upper), up.solution, exact=True)  # the exact proof is global
    assert cert.verdict == "infeasible-certified"


def test_bisection_agrees_with_the_closed_form_and_its_stretched_points_are_certified():
    system, truth = _system(5, 2)
    res = maximize(gevp, system, "beta", lo=1e-3, hi=4.0 * truth, rtol=1e-4, xtol=0.0, backoff=0.0, method="bisection")
    assert res.method == "bisection"
    assert res.lower < truth <= res.upper and res.converged
    assert res.upper_kind == "infeasible-certified"
    stretched = [p for p in res.points if p.stretched]
    for p in stretched:
        assert p.outcome == "feasible" and _certified(gevp, system, p.value, p.x)


def test_reach_is_exact_for_a_parameter_entering_affinely_at_a_fixed_point():
    """At a fixed point the LMIs are affine in beta: the modelled reach is where lambda_min hits 0."""
    system, truth = _system(4, 3)
    s, plan, _, _ = setup(gevp, system, "beta", None)
    p0 = bind(plan, s, {"beta": 0.5 * truth})
    sol = decide(p0, "clarabel")
    assert sol.outcome == "feasible"
    x = sol.x
    b0, b1 = 0.5 * truth, 2.0 * truth
    r = reach(p0, bind(plan, s, {"beta": b1}), x)
    edge = b0 + r * (b1 - b0)
    assert b0 < edge < truth  # a point's reach never passes the supremum
    # numpy alone: the smallest eigenvalue of each LMI at x, just inside and just beyond the edge
    for beta, sign in ((b0 + 0.999 * (edge - b0), 1.0), (edge + 1e-3 * (edge - b0), -1.0)):
        mins = [np.linalg.eigvalsh(lmi.matrix(x))[0] for lmi in bind(plan, s, {"beta": beta}).lmis]
        assert sign * min(mins) > 0


def test_a_screen_near_the_supremum_certifies():
    """Within 1e-5 of the supremum the relative margins are far below the default 1e-4: a screen
    imposes a smaller one and its point is certified."""
    system, truth = _system(14, 4)  # not small: a screen solves (small problems go to the policy)
    problem = _problem(gevp, system, truth * (1 - 1e-5))
    res = screen(problem, "clarabel")
    assert res is not None and res.outcome == "feasible"
    assert _certified(gevp, system, truth * (1 - 1e-5), res.x)


SHARED = Path("/work/shared/theorems/examples/uio_dt.thm4_1.flexible_joint.yaml")


@pytest.mark.skipif(not SHARED.exists(), reason="the shared theorem catalogue is not on this machine")
def test_uio_maximize_on_the_shared_example_gives_usable_gains_and_a_certificate(tmp_path, capsys):
    """Issue 13: ``--maximize`` on uio_dt.thm4_1 (flexible joint) returns the bracket, the gains
    and a certificate at the lower end, with gains below 1e4 in norm."""
    from lmic.cli import main

    cert = tmp_path / "end.json"
    argv = ["solve", "uio_dt.thm4_1", str(SHARED), "--maximize", "gamma", "--lo", "50", "--hi", "52"]
    code = main([*argv, "--rtol", "1e-2", "--no-progress", "-o", str(cert), "--json"])
    d = json.loads(capsys.readouterr().out)
    assert code == 0 and d["certificate_file"] == str(cert)
    assert 50.0 <= d["lower"] < d["upper"] <= 52.0
    lower = d["ends"]["lower"]
    assert lower["evidence"] == "certified point"
    assert max(lower["derived_norms"][k] for k in ("L", "K", "N", "M", "G")) < 1e4
    assert main(["audit", str(cert), "--json"]) == 0
