"""The default route of optimisation problems (lmic.routes, lmic.policy.optimisation_chain):
the interior-point order by shape, escalation to the next interior-point method when the
enclosure does not meet --gap, and that every answer is certified with an enclosure that
contains an optimum computed independently (the H-infinity norm by a Hamiltonian bisection
written here; CVXPY + Clarabel on a theorem instance). No timing asserts."""

from __future__ import annotations

import numpy as np
import pytest
from certify_helpers import hinf_norm, stable_system

import lmic.api
import lmic.routes
from lmic import policy, route_rule
from lmic.certify import certify
from lmic.options import SolveOptions


def _brl(n: int, seed: int, eighths: bool = False) -> tuple[dict, tuple[float, float]]:
    """A random stable system; ``eighths``: the diagonal of ``A`` rounded to eighths (the IR's
    Lyapunov coefficients ``A_aa + A_bb`` are then exact: the exact face route proves the
    lower end, lmic.certify.enclosure_face)."""
    A, B, C = stable_system(n, 100 + seed, eighths=eighths)
    return {"lmic": 1, "data": {"A": A.tolist(), "B": B.tolist(), "C": C.tolist()}}, hinf_norm(A, B, C)


def _checked(r, lo: float, hi: float) -> dict:
    """Certified by the certifier again; both ends proven, and the enclosure contains the norm
    as far as the bisection resolves it: ``lower <= hi`` and ``upper >= lo`` (the exact face bound
    is within 1e-11 of the norm, so it may lie inside ``[lo, hi]``, never above it)."""
    assert r.verdict == "certified"
    assert certify(r.problem, r.solution).verdict == "certified"
    e = r.enclosure
    assert e["lower"] is not None and e["upper"] is not None
    assert e["lower"] <= hi and e["upper"] >= lo
    return e


def _steps(r) -> list[str]:
    return [s["backend"] for s in r.route["steps"]]


# -- the order by shape -----------------------------------------------------------------------


def test_the_bounded_real_lemma_goes_to_clarabel_and_a_few_variable_theorem_to_the_schur_complement():
    from lmic.api import load_target
    from lmic.registry import get_theorem
    from lmic.studies.plants import random_plants

    # the bounded-real lemma at 30 states: as many variables as the PSD blocks have entries
    system, _ = _brl(30, 0)
    brl = load_target("tutorial.bounded_real", system)[0]
    clarabel, schur = policy.ipm_costs(brl)
    assert policy.SCHUR_PENALTY * schur >= clarabel
    # its coefficients are crosses (A'P + PA), but Clarabel is still fast enough to keep it first
    structured = route_rule.structured_ipm_cost(brl)
    assert structured is not None and route_rule.STRUCTURED_PENALTY * structured < clarabel
    assert clarabel < route_rule.STRUCTURED_MIN_COST and policy.route(brl)[0] == "clarabel"
    # at 40 states CVXOPT's structured KKT solver goes first
    system, _ = _brl(40, 0)
    big = load_target("tutorial.bounded_real", system)[0]
    clarabel, _ = policy.ipm_costs(big)
    structured = route_rule.structured_ipm_cost(big)
    assert clarabel >= route_rule.STRUCTURED_MIN_COST
    assert structured is not None and route_rule.STRUCTURED_PENALTY * structured < clarabel
    assert policy.route(big)[:3] == ["cvxopt", "clarabel", "sdpa"]
    # uncertain_dt.thm1 at 8 states: 91 variables against blocks of 58 and 33
    spec = {"count": 1, "seed": 1, "dims": {"n": 8, "p": 2, "nw": 1, "nz": 8, "r": 2, "s": 2}}
    spec.update(spectral_radius={"A": 0.3}, scale=0.1)
    plant = random_plants(get_theorem("uncertain_dt.thm1").template(), spec, "test")[0]
    plant["params"] = {"mu": 1.25, "beta": 0.05}
    thm = load_target("uncertain_dt.thm1", plant)[0]
    clarabel, schur = policy.ipm_costs(thm)
    assert policy.SCHUR_PENALTY * schur < clarabel and policy.route(thm)[:2] == ["sdpa", "cvxopt"]


def test_ipm_costs_grow_with_the_blocks_and_the_variables():
    from lmic.testing.conformance import lyapunov_problem

    small, large = lyapunov_problem(-np.eye(2)), lyapunov_problem(-np.eye(6))
    assert all(b > a for a, b in zip(policy.ipm_costs(small), policy.ipm_costs(large), strict=True))


# -- certified, with the optimum inside -------------------------------------------------------


@pytest.mark.parametrize("n,seed,eighths", [(4, 0, False), (8, 1, True), (12, 2, True)])
def test_default_route_brl_certified_and_encloses_the_hinf_norm(n, seed, eighths):
    system, (lo, hi) = _brl(n, seed, eighths)
    r = lmic.api.solve("tutorial.bounded_real", system, backoff=0)
    e = _checked(r, lo, hi)
    assert e["rel_gap"] <= SolveOptions().gap
    assert _steps(r) == [policy.route(r.problem)[0]]  # the gap was met: no escalation
    assert r.route["text"].startswith(f"route: {_steps(r)[0]} (interior point; ")


def test_default_route_on_a_theorem_instance_contains_cvxpy_s_optimum():
    cp = pytest.importorskip("cvxpy")
    from lmic.registry import get_theorem
    from lmic.studies.plants import random_plants

    spec = {"count": 1, "seed": 3, "dims": {"n": 3, "p": 1, "nw": 1, "nz": 3, "r": 1, "s": 1}}
    spec.update(spectral_radius={"A": 0.3}, scale=0.1)
    plant = random_plants(get_theorem("delay_b.thm4_1").template(), spec, "test")[0]
    plant["params"] = {"tau1": 0, "tau2": 2, "eps2": 1, "eps3": 1, "lambda": 0.5}
    r = lmic.api.solve("delay_b.thm4_1", plant, backoff=0)
    assert r.verdict == "certified" and certify(r.problem, r.solution).verdict == "certified"
    e = r.enclosure
    assert e["lower"] is not None and e["rel_gap"] <= SolveOptions().gap
    # the same LMIs in CVXPY + Clarabel (no lmic solver code): its optimum lies in the enclosure
    # up to CVXPY's own tolerance
    p = r.problem
    x = cp.Variable(p.n)
    cons = []
    for lmi in p.lmis:
        F = [lmi.coefficient(k) for k in range(p.n + 1)]
        M = F[0] + sum(F[k + 1] * x[k] for k in range(p.n) if np.any(F[k + 1]))
        cons.append(0.5 * (M + M.T) >> 0)
    A = p.linear.A.toarray()
    cons += [
        A[k, 1:] @ x + A[k, 0] >= 0 if kind == "ge" else A[k, 1:] @ x + A[k, 0] == 0
        for k, kind in enumerate(p.linear.kinds)
    ]
    c = p.objective.c
    value = cp.Problem(cp.Minimize(c[1:] @ x + c[0]), cons).solve(solver="CLARABEL")
    slack = 1e-6 * max(1.0, abs(value))
    assert e["lower"] - slack <= value <= e["upper"] + slack


# -- escalation when the gap is not met -------------------------------------------------------


def test_a_gap_that_is_not_met_escalates_through_the_interior_point_methods():
    system, (lo, hi) = _brl(5, 3)
    tight = SolveOptions(gap=1e-15)  # no solver meets it: every interior point of the route is tried
    r = lmic.api.solve("tutorial.bounded_real", system, options=tight, backoff=0)
    e = _checked(r, lo, hi)
    steps = r.route["steps"]
    assert len(steps) == 1 + lmic.routes.MAX_GAP_ESCALATIONS
    assert [s["backend"] for s in steps] == policy.route(r.problem)[: len(steps)]
    assert all(s.get("escalate") == "gap not met" for s in steps[:-1] if s["verdict"] == "certified")
    # the enclosure kept is the tightest certified one of the route
    gaps = [s["rel_gap"] for s in steps if s["verdict"] == "certified" and s.get("rel_gap") is not None]
    assert e["rel_gap"] == min(gaps)


def test_escalation_only_when_another_solver_can_close_the_gap(monkeypatch):
    """A wide proven gap, or a missing primal end, escalates; a missing dual end does not (the
    dual search has tried its re-solves; its failure is the dual's structure)."""
    system, (lo, hi) = _brl(4, 5)
    real = lmic.routes.enclosure_of

    def without(end):
        def enclosure_of(problem, sol, cert, exact, backend, options, budget_s=None, target=None):
            enc, t = real(problem, sol, cert, exact, backend, options, budget_s, target)
            return dict(enc, **{end: None}, rel_gap=None, gap=None), t

        return enclosure_of

    monkeypatch.setattr(lmic.routes, "enclosure_of", without("lower"))
    r = lmic.api.solve("tutorial.bounded_real", system, backoff=0)
    assert r.verdict == "certified" and certify(r.problem, r.solution).verdict == "certified"
    assert len(r.route["steps"]) == 1 and r.enclosure["upper"] >= lo

    monkeypatch.setattr(lmic.routes, "enclosure_of", without("upper"))
    # the primal end from the dual end (lmic.route_upper) off: the missing end stays missing
    monkeypatch.setattr(lmic.routes, "upper_route", lambda problem, out, enc, *a, **k: (out, enc, 0.0))
    r = lmic.api.solve("tutorial.bounded_real", system, backoff=0)
    assert r.verdict == "certified" and certify(r.problem, r.solution).verdict == "certified"
    assert len(r.route["steps"]) == 1 + lmic.routes.MAX_GAP_ESCALATIONS
    assert r.enclosure["lower"] is None or r.enclosure["lower"] <= hi


def test_gap_escalates_rule():
    from lmic.testing.conformance import CASES

    p = CASES["max_sense"].build()  # a maximisation: the dual end is the upper one
    assert lmic.routes.gap_escalates(p, {"lower": 1.0, "upper": 1.5, "rel_gap": 0.4})
    assert lmic.routes.gap_escalates(p, {"lower": None, "upper": 1.5, "rel_gap": None})
    assert not lmic.routes.gap_escalates(p, {"lower": 1.0, "upper": None, "rel_gap": None})
    assert not lmic.routes.gap_escalates(p, None)


def test_the_route_shares_one_budget_for_exact_ray_proofs():
    """x >= 1 and x <= -1 as one 2x2 LMI: infeasible, with an inhomogeneous ray (bounded in
    float, global once proved exactly). With the ray-proof budget spent (what an earlier backend
    of the route used), no exact proof is tried and the verdict stays bounded."""
    import scipy.sparse as sp

    from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable

    F = sp.csc_matrix(np.array([[-1.0, 1.0], [0.0, 0.0], [-1.0, -1.0]]))  # diag(x - 1, -x - 1)
    p = Problem(
        [Variable("x", "scalar", (1, 1))],
        [LMI("x >= 1, x <= -1", 2, F, strict=False)],
        LinearConstraints.empty(1),
        Objective("min", np.array([0.0, 1.0])),
    )
    proved = policy.decide(p, "clarabel")
    assert proved.verdict == "infeasible-certified"
    assert certify(p, proved.solution, exact=True).verdict == "infeasible-certified"
    spent = policy.decide(p, "clarabel", ray_budget_s=0.0)
    assert spent.verdict == "infeasible-bounded"
    assert not any("exact proof of the ray" in a.note for a in spent.attempts)


def test_sdpa_skips_its_feasibility_error_recomputation_and_restores_it(monkeypatch):
    """SDPA first on the Schur-complement order: sdpa-python's ARPACK recomputation of its
    feasibility errors (half of its time, never read by lmic) is skipped during the solve only;
    the answer is certified by the certifier."""
    sdpaputils = pytest.importorskip("sdpap.sdpaputils")
    calls: list[str] = []

    def recorder(*args, **kwargs):
        calls.append("called")
        return 0.0

    monkeypatch.setattr(sdpaputils, "get_primalerror", recorder)
    monkeypatch.setattr(sdpaputils, "get_dualerror", recorder)
    system, (lo, hi) = _brl(4, 6, eighths=True)
    r = lmic.api.solve("tutorial.bounded_real", system, backend="sdpa", backoff=0)
    assert certify(r.problem, r.solution).verdict == "certified"
    assert r.enclosure["upper"] >= lo and r.enclosure["lower"] <= hi
    assert calls == []
    assert sdpaputils.get_primalerror is recorder and sdpaputils.get_dualerror is recorder


def test_a_gap_within_gap_but_above_1e_6_escalates_once_when_cheap(monkeypatch):
    """An enclosure inside --gap but above GAP_TARGET (1e-6): while the route is cheap, one more
    interior point runs and the tighter enclosure is kept; once the route is not cheap, none."""
    from lmic.certify.enclosure import GAP_TARGET

    system, (lo, hi) = _brl(4, 7)
    real = lmic.routes.enclosure_of
    calls: list[str] = []

    def loose_first(problem, sol, cert, exact, backend, options, budget_s=None, target=None):
        enc, t = real(problem, sol, cert, exact, backend, options, budget_s, target)
        calls.append(str(backend))
        if len(calls) == 1 and enc["lower"] is not None:  # the first solver's lower end, loosened
            lower = enc["lower"] - 5e-6 * abs(enc["lower"])
            enc = dict(enc, lower=lower, gap=enc["upper"] - lower)
            enc["rel_gap"] = enc["gap"] / max(1.0, 0.5 * (abs(enc["upper"]) + abs(lower)))
        return enc, t

    monkeypatch.setattr(lmic.routes, "enclosure_of", loose_first)
    r = lmic.api.solve("tutorial.bounded_real", system, backoff=0)
    steps = r.route["steps"]
    assert [s.get("escalate") for s in steps[:1]] == ["gap above 1e-6, cheap"] and len(steps) == 2
    assert steps[0]["rel_gap"] > GAP_TARGET >= r.enclosure["rel_gap"]
    assert _checked(r, lo, hi)["rel_gap"] <= GAP_TARGET

    calls.clear()
    monkeypatch.setattr(lmic.routes, "CHEAP_ESCALATION_S", 0.0)
    r = lmic.api.solve("tutorial.bounded_real", system, backoff=0)
    assert len(r.route["steps"]) == 1 and r.enclosure["rel_gap"] > GAP_TARGET
    assert r.enclosure["lower"] <= hi and r.enclosure["upper"] >= lo


def test_a_restored_point_gets_the_whole_dual_search_when_its_gap_is_above_the_target():
    """A newcomer's theorem (max t s.t. A'P + PA + t I <= 0, I <= P <= 10 I, a random 7-state
    A): Clarabel's point is rejected, upper_route restores a certified one, and its dual end had
    been proved from the solver's degenerate dual with a shift (relative gap 1.0e-6). The
    route now runs the step's whole dual search (its centred re-solves) from the certified point:
    the gap meets 1e-6 and the enclosure contains the optimum of a tight CVXPY solve."""
    import cvxpy as cp

    from lmic.compile import analyse, bind
    from lmic.template import I, theorem

    @theorem(id="test.margin", title="margin", citation="tests", objective="max t")
    def margin(t):
        (n,) = t.dims("n")
        A = t.data("A", n, n)
        P = t.symmetric("P", n)
        s = t.scalar("t")
        t.lmi("Lyapunov", A.T * P + P * A + s * I(n) <= 0)
        t.lmi("P lower", P - I(n) >= 0)
        t.lmi("P upper", 10 * I(n) - P >= 0)
        t.maximize(s)

    rng = np.random.default_rng(0)
    n = 7
    rng.integers(3, 8)  # the draw of the instance the docstring quotes
    A = rng.standard_normal((n, n))
    A -= (max(np.linalg.eigvals(A).real) + 0.2) * np.eye(n)
    problem = bind(analyse(margin), {"data": {"A": A.tolist()}})
    r = lmic.api.solve(problem, backoff=0)
    assert r.verdict == "certified"
    e = r.enclosure
    assert e["lower"] is not None and e["upper"] is not None and e["rel_gap"] <= 1e-6, e["reason"]
    P, tv = cp.Variable((n, n), symmetric=True), cp.Variable()
    ref = cp.Problem(
        cp.Maximize(tv), [A.T @ P + P @ A + tv * np.eye(n) << 0, P >> np.eye(n), P << 10 * np.eye(n)]
    ).solve(solver=cp.CLARABEL, tol_gap_abs=1e-12, tol_gap_rel=1e-12, tol_feas=1e-12)
    assert e["lower"] <= ref <= e["upper"]
    assert certify(problem, r.solution).verdict == "certified"
