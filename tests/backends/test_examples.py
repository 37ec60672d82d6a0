"""Backend regressions found on the shipped examples and the observer theorems.

Each test names the problem report it guards: the cost of strict feasibility, the fixed-margin
option, Clarabel's inaccurate max-margin answers, CVXOPT/PICOS failures on problems with
redundant decision variables, and SCS's tolerance.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

from lmic.api import solve
from lmic.backends.base import SolveOptions, eliminate_unused, independent_columns
from lmic.backends.registry import get_backend
from lmic.compile import compile_theorem
from lmic.reductions.pipeline import solve as solve_with_reductions

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
UIO32 = EXAMPLES / "uio_dt.thm3_2.flexible_joint.yaml"
UIO41 = EXAMPLES / "uio_dt.thm4_1.flexible_joint.yaml"
THESIS = EXAMPLES / "thesis.thm3_2_2.ex3_2_2.yaml"
DESCRIPTOR = EXAMPLES / "descriptor.thm3_3.example.yaml"


def _qib_system(n: int, seed: int = 0) -> dict:
    rng = np.random.default_rng(seed + 1000 * n)
    A = rng.standard_normal((n, n))
    A *= 0.9 / max(abs(np.linalg.eigvals(A)))
    C = rng.standard_normal((max(1, n // 2), n))
    return {"lmic": 1, "data": {"A": A.tolist(), "C": C.tolist()}, "params": {"beta": 1e-3, "gamma": 0.0}}


# -- 1. strict feasibility: a fixed-margin solve costs a third of the max-margin iterations ----


def test_fixed_margin_feasibility_needs_far_fewer_iterations_than_max_margin():
    problem = compile_theorem("qib.thm1", _qib_system(8))
    fixed = solve(problem, backend="clarabel", options=SolveOptions(strict="fixed-margin"))
    best = solve(problem, backend="clarabel", options=SolveOptions(strict="max-margin"))
    assert fixed.verdict == best.verdict == "certified"
    assert fixed.solution.iterations * 2 <= best.solution.iterations
    # the point's own relative margin is recorded, far above the 1e-4 that was imposed
    assert fixed.solution.info["imposed_margin"] == pytest.approx(1e-4)
    assert 1e-3 < fixed.solution.margin <= best.solution.margin + 1e-9


# -- 2. uio_dt.thm3_2 at gamma = 45: max-margin is inaccurate (P ~ 1e8), fixed-margin is clean --


def test_uio_gamma_45_default_retries_fixed_margin():
    worst = solve("uio_dt.thm3_2", UIO32, {"gamma": 45}, backend="clarabel", options=SolveOptions(strict="max-margin"))
    first = worst.attempts[0]  # max-margin alone; the policy then escalates (other reductions)
    assert first["reduction"] == "default/max-margin" and first["status"] == "inaccurate"
    assert first["verdict"] == "rejected"
    r = solve("uio_dt.thm3_2", UIO32, {"gamma": 45})
    assert r.status == "feasible" and r.verdict == "certified" and r.solution.strategy == "fixed-margin"
    steps = [(a["strategy"], a["status"]) for a in r.solution.info["strict_attempts"]]
    assert steps == [("max-margin", "inaccurate"), ("fixed-margin", "feasible")]
    chosen = solve("uio_dt.thm3_2", UIO32, {"gamma": 45}, options=SolveOptions(strict="fixed-margin"))
    assert chosen.verdict == "certified" and len(chosen.solution.info["strict_attempts"]) == 1


# -- 3. Clarabel AlmostSolved on a max-margin problem whose t* is clearly negative ------------


def test_inaccurate_negative_max_margin_is_infeasible_on_a_verified_dual():
    """obs_control.thm3_2, a random plant that CVXPY finds infeasible: Clarabel stops
    AlmostSolved at t* = -0.0217 with |x| ~ 1e5; its dual is a closed Farkas certificate."""
    rng = np.random.default_rng(4)
    A, B, C = rng.normal(size=(2, 2)), rng.normal(size=(2, 1)), rng.normal(size=(1, 2))
    data = {"A": A, "B": B, "C": C, "D": rng.normal(size=(2, 1)), "E": rng.normal(size=(2, 1))}
    params = {"gamma": 0.1, "alpha": 2.0, "eps": 0.5, "epsc1": 1.0, "epsc2": 0.5, "epso1": 1.0, "epso2": 2.0}
    system = {"lmic": 1, "data": {k: v.tolist() for k, v in data.items()}, "params": dict(params, beta=0.1)}
    r = solve("obs_control.thm3_2", system, backend="clarabel", options=SolveOptions(strict="max-margin"))
    assert r.solution.native_status == "AlmostSolved"
    assert r.status == "infeasible" and r.solution.margin == pytest.approx(-0.0217, abs=1e-3)
    assert "verifies" in r.solution.message
    # the verified float ray of this inhomogeneous problem proves "no solution with ||x||_inf <= R"
    assert r.verdict == "infeasible-bounded" and r.outcome.evidence.radius > 1.0
    assert r.exit_code() == 4


# -- 4. CVXOPT / PICOS: redundant decision variables, diverging iterates ----------------------


@pytest.mark.parametrize("target", [(("uio_dt.thm3_2", UIO32)), ("descriptor.thm3_3", DESCRIPTOR)])
def test_cvxopt_takes_problems_with_unused_variables(target):
    """Ybar (uio_dt) and Ybar1, Y2 (descriptor) appear in no LMI: CVXOPT said Rank(A) < p."""
    r = solve(*target, backend="cvxopt")
    assert r.status == "feasible" and r.verdict == "certified"
    eliminated = r.solution.info["eliminated"]
    assert eliminated["count"] > 0 and eliminated["variables"]
    assert not np.any(r.solution.x[eliminated["indices"]])  # reported as 0
    assert set(eliminated["variables"]) <= set(r.variables)


def test_cvxopt_on_uio_thm4_1_no_longer_refuses():
    r = solve("uio_dt.thm4_1", UIO41, backend="cvxopt")
    assert "Rank" not in r.solution.message and r.status != "error"


@pytest.mark.parametrize("backend", ["cvxopt", "picos"])
def test_thesis_lipschitz_example_on_cvxopt_and_picos(backend):
    """Only Lbar C + C^T Lbar^T appears with C = [I 0]: the skew part of Lbar[:2, :2] is a
    direction that changes nothing. CVXOPT followed it to |x| ~ 1e26 ('unknown' at gamma 0.5,
    ZeroDivisionError at 3.33; PICOS ran ~100 s into the same error)."""
    ok = solve("thesis.thm3_2_2", THESIS, {"gamma": 0.5}, backend=backend)
    assert ok.status == "feasible" and ok.verdict == "certified"
    assert ok.solution.info["eliminated"]["variables"] == ["Lbar"]
    bad = solve("thesis.thm3_2_2", THESIS, {"gamma": 3.33}, backend=backend)
    # the float ray of an inhomogeneous LMI, proven exactly on a rational basis of its face (the
    # closed-form certificate z = (e4, -e3) of tests/engine/test_engine.py): global, exit 3
    assert bad.status == "infeasible" and bad.verdict == "infeasible-certified" and bad.exit_code() == 3
    assert bad.certificate.exact["proven"]
    assert ok.timings["solve_s"] + bad.timings["solve_s"] < 20


def test_independent_columns_matches_the_numerical_rank():
    rng = np.random.default_rng(0)
    base = sp.random(60, 12, density=0.3, random_state=1, format="csc")
    mix = sp.csc_matrix(base.toarray() @ rng.standard_normal((12, 6)))
    M = sp.hstack([base, mix, sp.csc_matrix((60, 2))], format="csc")
    keep = independent_columns(M)
    assert keep.sum() == np.linalg.matrix_rank(M.toarray()) == np.linalg.matrix_rank(M.toarray()[:, keep])
    assert not keep[-2:].any()


def test_elimination_keeps_objective_directions():
    problem = compile_theorem("thesis.thm3_2_2", THESIS, {"gamma": 0.5})
    kept, keep = eliminate_unused(problem, dependent=True)
    assert kept.n == problem.n - 1 and len(keep) == kept.n
    assert eliminate_unused(problem)[1] is None  # no entry is unused on its own


def test_a_genuine_solver_crash_is_an_error_with_its_message(monkeypatch):
    import cvxopt.solvers

    def crash(*args, **kwargs):
        raise ZeroDivisionError("float division by zero")

    monkeypatch.setattr(cvxopt.solvers, "sdp", crash)
    sol = solve_with_reductions(get_backend("cvxopt"), compile_theorem("thesis.thm3_2_2", THESIS, {"gamma": 0.5}))
    assert sol.status == "error" and "ZeroDivisionError: float division by zero" in sol.message


# -- 5. SCS: tolerance floor and a margin above its accuracy ---------------------------------


def test_scs_runs_at_its_floor_tolerance_and_certifies():
    """At tol 1e-8 SCS used its 1e5 iterations (uncertain_dt 36 s, rejected); at the 1e-6 floor
    with the margin floor 10 tol it certifies in a few thousand."""
    r = solve("delay_b.thm4_1", EXAMPLES / "delay_b.thm4_1.ex1_lambda0_5.yaml", backend="scs")
    assert r.verdict == "certified" and r.solution.iterations < 20000
    assert r.solution.margin == pytest.approx(1e-5)
