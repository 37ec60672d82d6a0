"""The default route (lmic.routes, lmic.backends.auto.route): which route for which shape, that
it certifies on random instances with the enclosure containing an independently computed
optimum (the H-infinity norm by a Hamiltonian bisection), --gap validation, and escalation when
the first-order step fails. Every solver answer is re-checked through the certifier."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
import scipy.sparse as sp
from certify_helpers import hinf_norm

import lmic.api
from lmic import policy
from lmic.backends import auto
from lmic.certify import certify
from lmic.errors import BackendError, LmicError
from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
from lmic.options import SolveOptions
from lmic.policy import route


def _shape(dims: list[int], n: int, sense: str = "feasibility", strict: bool = True) -> Problem:
    """A problem with LMI blocks of the given sizes and ``n`` scalar variables (only the shape
    matters to the route rule)."""
    rng = np.random.default_rng(0)
    lmis = []
    for k, d in enumerate(dims):
        rows = d * (d + 1) // 2
        lmis.append(LMI(f"F{k}", d, sp.random(rows, n + 1, density=0.2, random_state=rng, format="csc"), strict=strict))
    variables = [Variable(f"x{i}", "scalar", (1, 1), offset=i) for i in range(n)]
    c = np.r_[0.0, np.ones(n)] if sense != "feasibility" else np.zeros(n + 1)
    return Problem(variables, lmis, LinearConstraints.empty(n), Objective(sense, c))


def test_tiny_strict_feasibility_takes_clarabel_larger_takes_the_first_order_route():
    assert route(_shape([4, 12], 10))[0] == "clarabel"  # sum d^2 = 160 <= SMALL_FEASIBILITY
    r = route(_shape([40, 120], 100))
    assert r[:2] == ["scs", "cvxopt"]


def test_optimisation_route_picks_the_interior_point_method_by_shape():
    # tiny: Clarabel, the embedded default solver
    tiny = _shape([10, 14], 20, "min", strict=False)
    assert policy.ipm_costs(tiny)[0] <= policy.TINY_IPM_COST and route(tiny)[0] == "clarabel"
    # few variables against large PSD blocks: the Schur complement is far cheaper (SDPA, CVXOPT)
    few = _shape([60], 100, "min", strict=False)
    clarabel, schur = policy.ipm_costs(few)
    assert policy.SCHUR_PENALTY * schur < clarabel
    r = route(few)
    assert r[:3] == ["sdpa", "cvxopt", "clarabel"]
    # many variables against the blocks: Clarabel first, then the Schur-complement methods
    many = _shape([10], 300, "min", strict=False)
    clarabel, schur = policy.ipm_costs(many)
    assert policy.SCHUR_PENALTY * schur >= clarabel and route(many)[:3] == ["clarabel", "cvxopt", "sdpa"]
    # the first-order variant starts with SCS; the interior-point variant never does
    assert route(few, "auto:first-order")[:2] == ["scs", "sdpa"]
    assert route(few, "auto:interior-point")[0] == "sdpa"
    # feasibility problems keep their own rule (lmic.backends.auto.route)
    assert route(_shape([60], 100))[0] == auto.route(_shape([60], 100))[0]


def test_unknown_auto_variant_and_explicit_backend():
    with pytest.raises(BackendError, match="unknown auto variant"):
        route(_shape([4], 3), "auto:fastest")
    assert route(_shape([40, 120], 100), "clarabel") == ["clarabel"]


# -- the default route on random instances, against the H-infinity norm -----------------------


def _brl(n: int, seed: int):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    A -= (max(np.linalg.eigvals(A).real) + 0.5) * np.eye(n)
    B, C = rng.standard_normal((n, 2)), rng.standard_normal((2, n))
    system = {"lmic": 1, "data": {"A": A.tolist(), "B": B.tolist(), "C": C.tolist()}}
    return system, hinf_norm(A, B, C)


def _check_enclosure(r, lo, hi):
    assert r.verdict == "certified"
    assert certify(r.problem, r.solution).verdict == "certified"  # re-checked independently of the route
    e = r.enclosure
    assert e["upper"] is not None and e["upper"] >= hi
    if e["lower"] is not None:  # the norm is in [lo, hi] (bisection to 1e-12); the exact face
        assert e["lower"] <= hi  # bound can be within 1e-13 of it, above lo
    return e


@pytest.mark.parametrize("seed", range(2))
def test_default_route_small_brl_certifies_and_encloses_the_hinf_norm(seed):
    system, (lo, hi) = _brl(4, seed)
    r = lmic.api.solve("tutorial.bounded_real", system)
    e = _check_enclosure(r, lo, hi)
    assert e["lower"] is not None and e["rel_gap"] <= SolveOptions().gap
    assert r.route["steps"][-1]["backend"] == "clarabel" and "clarabel (interior point" in r.route["text"]


@pytest.mark.parametrize("variant", ["auto", "auto:first-order"])
def test_default_route_with_the_schur_complement_order(monkeypatch, variant):
    # the crossover is a measured parameter: no penalty puts the Schur-complement methods first
    # on an instance that solves in well under a second
    import lmic.route_rule

    monkeypatch.setattr(lmic.route_rule, "TINY_IPM_COST", 0.0)
    monkeypatch.setattr(lmic.route_rule, "SCHUR_PENALTY", 0.0)
    system, (lo, hi) = _brl(5, 3)
    r = lmic.api.solve("tutorial.bounded_real", system, backend=variant)
    _check_enclosure(r, lo, hi)
    steps = [s["backend"] for s in r.route["steps"]]
    assert steps[0] == ("scs" if variant == "auto:first-order" else "sdpa")
    if variant == "auto:first-order":
        gap = r.route["steps"][0].get("rel_gap")
        # the first-order step stops the route only when its proven gap meets --gap
        assert (gap is not None and gap <= r.route["gap"]) == (steps == ["scs"])


def test_first_order_optimisation_step_that_fails_escalates(monkeypatch):
    import lmic.routes

    monkeypatch.setattr(lmic.routes, "OPTIMISATION_FIRST_ORDER_ITERS", 1)  # SCS cannot converge
    system, (lo, hi) = _brl(5, 4)
    r = lmic.api.solve("tutorial.bounded_real", system, backend="auto:first-order")
    _check_enclosure(r, lo, hi)
    assert r.route["steps"][0]["backend"] == "scs" and r.route["steps"][0]["verdict"] != "certified"
    chain = policy.optimisation_chain(r.problem, False)
    assert r.route["steps"][1]["backend"] == chain[0] and r.backend in chain


def test_feasibility_first_order_failure_escalates_to_an_interior_point_method():
    sys.path.insert(0, str(__import__("pathlib").Path(__file__).resolve().parents[2] / "benchmarks"))
    from backends import random_qib_system

    # one SCS iteration (extra settings reach SCS only): its point is not certified
    r = lmic.api.solve("qib.thm1", random_qib_system(8), options=SolveOptions(extra={"max_iters": 1}))
    assert r.verdict == "certified" and certify(r.problem, r.solution).verdict == "certified"
    steps = r.route["steps"]
    assert steps[0] == {"backend": "scs", "verdict": "rejected"} and steps[-1]["verdict"] == "certified"
    assert r.backend != "scs" and "=> " in r.route["text"]
    assert r.to_dict()["route"]["steps"] == steps


# -- --gap ----------------------------------------------------------------------------------------


@pytest.mark.parametrize("bad", [0, 1, -1e-3, float("nan"), float("inf"), "1e-4", True])
def test_gap_validation(bad):
    with pytest.raises(LmicError, match="gap must be"):
        SolveOptions(gap=bad)


@pytest.mark.parametrize("bad", ["0", "2", "nan", "-1", "abc"])
def test_cli_bad_gap_is_one_line_exit_2(tmp_path, bad):
    system, _ = _brl(3, 0)
    path = tmp_path / "s.json"
    path.write_text(__import__("json").dumps(system))
    out = subprocess.run(
        [sys.executable, "-m", "lmic.cli", "solve", "tutorial.bounded_real", str(path), "--gap", bad],
        capture_output=True,
        text=True,
    )
    assert out.returncode == 2
    lines = [ln for ln in out.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and "gap" in lines[0], out.stderr
    assert out.stdout == ""


def test_cli_prints_the_route(tmp_path):
    system, (lo, hi) = _brl(3, 1)
    path = tmp_path / "s.json"
    path.write_text(__import__("json").dumps(system))
    out = subprocess.run(
        [sys.executable, "-m", "lmic.cli", "solve", "tutorial.bounded_real", str(path), "--gap", "1e-3"],
        capture_output=True,
        text=True,
    )
    assert out.returncode == 0, out.stderr
    assert "route: clarabel (interior point; " in out.stdout and "-> certified" in out.stdout


def test_a_backend_cut_by_its_budget_gives_way_and_is_retried_without_one(monkeypatch) -> None:
    """Every budgeted solve stops at its time limit (a stand-in for a slow solver); solves
    without a limit run. The escalating route tries each backend under its budget, then
    retries the first one cut without a budget, and ends with a decision the certifier checks."""
    import numpy as np

    import lmic.policy as policy
    from lmic.backends.outcomes import time_limit_solution
    from lmic.certify import certify
    from lmic.solution import Solution
    from lmic.testing.conformance import lyapunov_problem

    real = policy._solve_one

    problem = lyapunov_problem(-np.eye(3))
    names = policy.route(problem)
    last = policy._instance(names[-1]).label

    def slow(be, target, options, scales, judge):
        if options.time_limit is not None:
            return time_limit_solution(be.label, options.time_limit, elapsed=options.time_limit)
        if be.label == last:  # the route's last backend (unbudgeted) fails too
            return Solution("error", message="stand-in failure")
        return real(be, target, options, scales, judge)

    monkeypatch.setattr(policy, "_solve_one", slow)
    out = policy.decide(problem)
    assert out.verdict == "certified"
    assert certify(problem, out.solution).verdict == "certified"
    budgeted = [a for a in out.attempts if a.status == "error"]
    assert {a.backend for a in budgeted} >= {policy._instance(n).label for n in names[:-1]}
    assert out.attempts[-1].backend == policy._instance(names[0]).label  # the retry, unbudgeted
    # an explicit budget is the caller's: never exceeded, no retry
    explicit = policy.decide(problem, None, budget_s=5.0)
    assert explicit.verdict == "undecided" and all(a.status == "error" for a in explicit.attempts)


def test_the_enclosure_re_solves_on_a_first_order_backend_start_at_its_answer_and_are_capped(monkeypatch):
    """SCS's re-solves in the enclosure (the polish towards the closed problem, the perturbed and
    centring problems) start from the answer they certify and stop at twice its solve time: cold,
    each ran to SCS's iteration limit (delay_a.thm3_1, 6 states: two 47 s re-solves, the same
    enclosure as warm in 0.6 s). Interior-point re-solves are left alone. The enclosure still
    contains the H-infinity norm (Hamiltonian bisection)."""
    import lmic.routes as routes

    calls: list[tuple[str, SolveOptions]] = []
    solve_on = routes._solve_on
    monkeypatch.setattr(
        routes, "_solve_on", lambda name, p, opts: calls.append((name, opts)) or solve_on(name, p, opts)
    )
    rng = np.random.default_rng(0)
    A = rng.standard_normal((4, 4))
    A -= (max(np.linalg.eigvals(A).real) + 0.5) * np.eye(4)
    B, C = rng.standard_normal((4, 2)), rng.standard_normal((2, 4))
    system = {"lmic": 1, "data": {"A": A.tolist(), "B": B.tolist(), "C": C.tolist()}}
    prob = lmic.api.load_target("tutorial.bounded_real", system)[0]
    sol = lmic.api.solve_problem(prob, "scs")
    enc, _ = routes.enclosure_of(prob, sol, certify(prob, sol), False, "scs", None)
    assert calls and all(name == "scs" for name, _ in calls)
    cap = max(routes.FIRST_ORDER_RESOLVE_MIN_S, routes.FIRST_ORDER_RESOLVE_FACTOR * sol.solve_s)
    assert all(opts.warm_start is sol and opts.time_limit == cap for _, opts in calls)
    lo, hi = hinf_norm(A, B, C)
    assert enc["lower"] <= hi and lo <= enc["upper"]
    assert routes.first_order_capped("cvxopt", None, 5.0, sol) is None
