"""The strict-inequality strategies shared by every backend (``SolveOptions.strict``)."""

from __future__ import annotations

import numpy as np
import pytest

from lmic.backends import strict
from lmic.backends.base import SolveOptions
from lmic.backends.registry import available_backend_names, get_backend
from lmic.errors import LmicError
from lmic.reductions.pipeline import solve as solve_with_reductions
from lmic.solution import Solution
from lmic.testing.conformance import CASES, lyapunov_problem


def test_scale_free_feasibility_gets_margin_and_trace_normalisation():
    prob = lyapunov_problem(-np.eye(2))
    reduced, inv = strict.reduce(prob, SolveOptions(), "max-margin")
    assert inv.strategy == "max-margin" and inv.scale_free
    assert reduced.n == prob.n + 1 and reduced.objective.sense == "max"
    assert all(not lmi.strict for lmi in reduced.lmis)
    # t <= 1 and one trace row per strict LMI
    assert len(reduced.linear) == 1 + 2
    assert reduced.linear.names[0] == "margin t <= 1"


def test_fixed_margin_feasibility_is_relative_under_the_trace_normalisation():
    prob = lyapunov_problem(-np.eye(2))
    reduced, inv = strict.reduce(prob, SolveOptions(), "fixed-margin")
    assert inv.strategy == "fixed-margin" and inv.scale_free and inv.margin == strict.RELATIVE_MARGIN
    assert reduced.n == prob.n and reduced.objective.sense == "feasibility"
    assert reduced.linear.names == ["scale normalisation 0", "scale normalisation 1"]
    # F(x) - delta I >= 0 for both LMIs; the margin never drops below 10 tol
    assert np.allclose(reduced.lmis[1].matrix(np.zeros(prob.n)), -1e-4 * np.eye(2))
    _, loose = strict.reduce(prob, SolveOptions(tol=1e-3), "fixed-margin")
    assert loose.margin == pytest.approx(1e-2)


def test_affine_problem_is_not_scale_free():
    prob = CASES["strict_affine"].build()
    reduced, inv = strict.reduce(prob, SolveOptions(), "max-margin")
    assert not inv.scale_free
    # the strict row x + y < 3 carries -t
    assert reduced.linear.A[0, -1] == -1.0
    _, fixed = strict.reduce(prob, SolveOptions(margin=1e-6), "fixed-margin")
    assert not fixed.scale_free and fixed.margin == 1e-6


def test_optimisation_uses_fixed_margin():
    prob = CASES["bounded_real"].build()
    reduced, inv = strict.reduce(prob, SolveOptions(margin=1e-3))
    assert inv.strategy == "fixed-margin" and reduced.n == prob.n
    d = prob.lmis[1].dim
    assert np.allclose(reduced.lmis[1].matrix(np.zeros(prob.n)), -1e-3 * np.eye(d))
    assert strict.plan(prob, SolveOptions(strict="max-margin")) == ["fixed-margin"]
    with pytest.raises(ValueError, match="feasibility problems only"):
        strict.reduce(prob, SolveOptions(), "max-margin")


def test_plan_by_size_solver_and_choice():
    small, large = lyapunov_problem(-np.eye(3)), lyapunov_problem(-np.eye(40))
    assert strict.plan(small, SolveOptions()) == ["max-margin", "fixed-margin"]
    assert strict.plan(small, SolveOptions(), first_order=True) == ["fixed-margin", "max-margin"]
    assert strict.plan(large, SolveOptions()) == ["fixed-margin", "max-margin"]
    assert strict.plan(large, SolveOptions(strict="max-margin")) == ["max-margin"]
    assert strict.plan(small, SolveOptions(strict="fixed-margin")) == ["fixed-margin"]
    assert strict.plan(CASES["max_sense"].build(), SolveOptions()) == []
    with pytest.raises(LmicError, match="unknown"):
        SolveOptions(strict="biggest")
    with pytest.raises(LmicError, match="relative_margin"):
        SolveOptions(relative_margin=1.5)


def test_nonpositive_margin_means_infeasible():
    prob = lyapunov_problem(np.eye(1))
    _, inv = strict.reduce(prob, SolveOptions(), "max-margin")
    raw = Solution(
        "optimal",
        x=np.array([0.0, 1e-12]),
        duals={"lmis": [np.eye(1), np.eye(1)], "linear": np.zeros(3)},
    )
    sol = strict.invert(raw, inv, SolveOptions())
    assert sol.status == "infeasible" and sol.farkas["strict"] is True
    assert sol.x.shape == (1,) and len(sol.farkas["linear"]) == 0


def test_small_positive_margin_is_undecided_unless_something_verifies():
    """SCS at 1e-3 found t* = 1.4e-3 <= 10 tol on a feasible problem: not 'infeasible'."""
    prob = lyapunov_problem(-np.eye(1))  # -2p > 0, p > 0: feasible
    _, inv = strict.reduce(prob, SolveOptions(), "max-margin")
    opts = SolveOptions(tol=1e-3)
    wrong_dual = {"lmis": [np.eye(1), np.zeros((1, 1))], "linear": np.zeros(3)}
    # a point that does not verify (p < 0) and a dual that is no Farkas ray: undecided
    raw = Solution("optimal", x=np.array([-1e-3, 2e-3]), duals=dict(wrong_dual))
    sol = strict.invert(raw, inv, opts, prob)
    assert sol.status == "inaccurate" and "within" in sol.message
    # the same t* at a point that verifies: feasible
    raw = Solution("optimal", x=np.array([0.5, 2e-3]), duals=dict(wrong_dual))
    assert strict.invert(raw, inv, opts, prob).status == "feasible"


def test_inaccurate_negative_margin_stays_inaccurate_without_a_verified_dual():
    prob = lyapunov_problem(np.eye(1))
    _, inv = strict.reduce(prob, SolveOptions(), "max-margin")
    raw = Solution(
        "inaccurate",
        native_status="AlmostSolved",
        x=np.array([1.0, -0.5]),
        duals={"lmis": [np.zeros((1, 1)), np.zeros((1, 1))], "linear": np.zeros(3)},
    )
    sol = strict.invert(raw, inv, SolveOptions(), prob)
    assert sol.status == "inaccurate" and sol.farkas is None
    assert "not a verified Farkas certificate" in sol.message


def test_unbounded_answer_to_a_feasibility_reduction_is_a_solver_failure():
    prob = lyapunov_problem(-np.eye(1))
    for strategy in ("max-margin", "fixed-margin"):
        _, inv = strict.reduce(prob, SolveOptions(), strategy)
        sol = strict.invert(Solution("unbounded", native_status="pINF_dFEAS"), inv, SolveOptions(), prob)
        assert sol.status == "error" and "bounded" in sol.message


def test_verify_point_follows_the_certifier():
    prob = lyapunov_problem(-np.eye(2))
    assert strict.verify_point(prob, np.array([1.0, 0.0, 1.0])) == (True, "")
    ok, why = strict.verify_point(prob, np.array([1.0, 0.0, 0.0]))
    assert not ok and "lambda_min 0" in why
    assert strict.verify_point(prob, None)[0] is False


@pytest.mark.parametrize("backend", available_backend_names())
def test_homogeneous_lmi_stays_bounded_on_every_backend(backend):
    """P stays O(1): the normalisation, not the solver, fixes the scale (SDPA gave P ~ 1e17)."""
    A = np.array([[-1.0, 5.0], [0.0, -2.0]])
    for choice in ("max-margin", "fixed-margin"):
        sol = solve_with_reductions(get_backend(backend), lyapunov_problem(A), SolveOptions(strict=choice))
        assert sol.status == "feasible" and sol.strategy == choice
        assert np.max(np.abs(sol.x)) < 10 and sol.margin > 1e-3
        assert [a["strategy"] for a in sol.info["strict_attempts"]] == [choice]


def test_large_scale_free_problem_takes_the_fixed_margin_route():
    """40x40 Lyapunov LMIs: one fixed-margin solve, verified; its margin is relative."""
    A = -np.eye(40) + np.diag(np.full(39, 0.5), 1)
    sol = solve_with_reductions(get_backend("scs"), lyapunov_problem(A))
    assert sol.status == "feasible" and sol.strategy == "fixed-margin"
    assert [a["strategy"] for a in sol.info["strict_attempts"]] == ["fixed-margin"]
    assert sol.info["imposed_margin"] == pytest.approx(strict.RELATIVE_MARGIN)  # SCS tol floor 1e-6: 10 tol < 1e-4
    assert 0 < sol.margin <= 1.0


def test_infeasible_problem_is_decided_by_a_verified_ray_or_by_max_margin():
    """Unstable A: a fixed-margin Farkas ray that proves the original problem infeasible ends the
    plan; otherwise (or on a small problem) max-margin decides."""
    unstable = lyapunov_problem(np.diag([0.5, -1.0]))
    sol = solve_with_reductions(get_backend("clarabel"), unstable)
    assert sol.status == "infeasible" and sol.strategy == "max-margin" and sol.margin <= 0
    assert [a["strategy"] for a in sol.info["strict_attempts"]] == ["max-margin"]
    sol = solve_with_reductions(get_backend("scs"), unstable)
    assert [a["strategy"] for a in sol.info["strict_attempts"]] == ["fixed-margin"]
    assert sol.status == "infeasible" and "meets the original problem's conditions in floating point" in sol.message
    from lmic.certify.farkas import verify_farkas

    assert verify_farkas(unstable, {k: sol.farkas[k] for k in ("lmis", "linear")})["verified"]


def test_fixed_margin_point_that_misses_the_strict_constraints_is_not_feasible():
    prob = lyapunov_problem(-np.eye(1))
    _, inv = strict.reduce(prob, SolveOptions(), "fixed-margin")
    sol = strict.invert(Solution("optimal", x=np.array([-1e-3])), inv, SolveOptions(), prob)
    assert sol.status == "inaccurate" and sol.margin < 0 and "misses" in sol.message
    sol = strict.invert(Solution("optimal", x=np.array([0.5])), inv, SolveOptions(), prob)
    assert sol.status == "feasible" and sol.margin == pytest.approx(1.0)


# ---- an optimisation solve without a decision: the constraints alone decide ----------------


def _infeasible_optimisation():
    import scipy.sparse as sp

    from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable

    # p > 1 and p < -1 (strict): no p at all, whatever the objective min p
    return Problem(
        [Variable("p", "scalar", (1, 1))],
        [LMI("p - 1 > 0", 1, sp.csc_matrix([[-1.0, 1.0]])), LMI("-1 - p > 0", 1, sp.csc_matrix([[-1.0, -1.0]]))],
        LinearConstraints.empty(1),
        Objective("min", np.array([0.0, 1.0])),
    )


def _failing_on(senses, calls, native="NumericalError", message="Clarabel stopped with status NumericalError"):
    real = get_backend("clarabel")._run

    def run(problem, options, deadline=None):
        calls.append(problem.objective.sense)
        if problem.objective.sense in senses:
            return Solution("error", backend="clarabel", native_status=native, message=message, solve_s=0.5)
        return real(problem, options, deadline=deadline)

    return run


@pytest.mark.skipif("clarabel" not in available_backend_names(), reason="needs Clarabel")
def test_optimisation_error_is_decided_by_the_constraints_alone():
    """The policy's ``feasibility`` step: a failed optimisation solve, then the constraints alone."""
    from lmic.policy import decide

    prob, calls = _infeasible_optimisation(), []
    be = get_backend("clarabel")
    be._run = _failing_on({"min"}, calls)
    out = decide(prob, be, SolveOptions(), exact=False)
    assert calls[0] == "min" and len(calls) >= 2 and "min" not in calls[1:]  # then the constraints alone
    # the certifier decides: the ray is proven exactly, so the proof is global (p > 1 and p < -1)
    assert out.verdict == "infeasible-certified", out.reason
    assert out.certificate.verdict == "infeasible-certified"
    assert [a.native_status for a in out.attempts][0] == "NumericalError"


@pytest.mark.skipif("clarabel" not in available_backend_names(), reason="needs Clarabel")
def test_constraints_route_that_decides_nothing_keeps_the_failure():
    from lmic.policy import decide

    prob, calls = _infeasible_optimisation(), []
    be = get_backend("clarabel")
    be._run = _failing_on({"min", "max", "feasibility"}, calls)
    out = decide(prob, be, SolveOptions(), exact=False)
    assert out.verdict == "undecided" and out.exit_code() == 1
    assert all(a.native_status == "NumericalError" for a in out.attempts)
