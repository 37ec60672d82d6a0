"""The answer an optimisation outcome becomes from its enclosure's proven point
(lmic.route_primal.decided_by_enclosure): a rejected solver point is replaced by the proven one,
``certified`` only when the enclosure proves the optimum to --gap, ``undecided`` (with the proven
point) otherwise; a point that fails the certifier is never adopted."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import scipy.sparse as sp

import lmic.api
from lmic.certify import certify
from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
from lmic.options import SolveOptions
from lmic.outcome import Outcome
from lmic.route_primal import decided_by_enclosure
from lmic.solution import Solution

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "plugins"))


def _min_t() -> Problem:
    """``min t`` subject to ``t >= 1`` (one non-strict 1x1 LMI): the optimum is 1."""
    lmi = LMI("t >= 1", 1, sp.csc_matrix([[-1.0, 1.0]]), strict=False)
    return Problem([Variable("t", "scalar", (1, 1))], [lmi], LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))


def _rejected(problem: Problem) -> Outcome:
    sol = Solution("optimal", x=np.array([0.9]), objective=0.9, backend="clarabel")
    cert = certify(problem, sol)
    assert cert.verdict == "rejected"  # t = 0.9 violates t >= 1
    return Outcome("rejected", reason=cert.reason, solution=sol, certificate=cert, backend="clarabel")


def _enc(lower: float | None, upper: float, x: float, primal: str = "restored point") -> dict:
    gap = None if lower is None else (upper - lower) / max(1.0, (abs(upper) + abs(lower)) / 2)
    enc = {"sense": "min", "kind": "minimum", "lower": lower, "upper": upper, "rel_gap": gap, "primal": primal}
    enc["reason"] = "test enclosure"
    if primal == "restored point":
        enc["restored_x"] = [x]
    return enc


def test_a_rejected_point_is_replaced_by_the_proven_one_undecided_without_a_lower_end():
    p = _min_t()
    out = decided_by_enclosure(p, _rejected(p), _enc(None, 1.5, 1.5), SolveOptions())
    assert out is not None and out.verdict == "undecided"
    assert out.solution.x.tolist() == [1.5] and out.certificate.verdict == "certified"
    assert out.evidence.kind == "point"
    assert "the solver's point: rejected" in out.reason and "not proven" in out.reason


def test_a_rejected_point_becomes_certified_when_the_enclosure_meets_the_gap():
    p = _min_t()
    out = decided_by_enclosure(p, _rejected(p), _enc(1.0, 1.0 + 1e-8, 1.0 + 1e-8), SolveOptions(gap=1e-4))
    assert out is not None and out.verdict == "certified" and out.solution.x.tolist() == [1.0 + 1e-8]
    # the same enclosure with a gap above --gap: the point is adopted, the optimum is not proven
    out = decided_by_enclosure(p, _rejected(p), _enc(1.0, 1.1, 1.1), SolveOptions(gap=1e-4))
    assert out is not None and out.verdict == "undecided" and out.solution.x.tolist() == [1.1]


def test_the_certified_backed_off_point_is_adopted_when_it_is_the_primal_end():
    p = _min_t()
    enc = _enc(None, 1.2, 1.2, primal="certified backed-off point")
    out = decided_by_enclosure(p, _rejected(p), enc, SolveOptions(), back={"x": [1.2]})
    assert out is not None and out.verdict == "undecided" and out.solution.x.tolist() == [1.2]
    assert "backed-off point" in out.reason
    # without the backed-off record there is nothing to adopt
    assert decided_by_enclosure(p, _rejected(p), enc, SolveOptions()) is None


def test_a_point_that_fails_the_certifier_is_never_adopted():
    p = _min_t()
    assert decided_by_enclosure(p, _rejected(p), _enc(None, 0.95, 0.95), SolveOptions()) is None


def test_an_answer_whose_own_point_holds_keeps_it_unless_the_optimum_is_proven():
    p = _min_t()
    sol = Solution("inaccurate", x=np.array([1.3]), objective=1.3, backend="sdpa")
    cert = certify(p, sol)
    holding = Outcome("undecided", reason="inexact", solution=sol, certificate=cert, backend="sdpa")
    assert decided_by_enclosure(p, holding, _enc(None, 1.2, 1.2), SolveOptions()) is None
    out = decided_by_enclosure(p, holding, _enc(1.0, 1.0 + 1e-8, 1.0 + 1e-8), SolveOptions())
    assert out is not None and out.verdict == "certified"


def test_uio_instance_with_a_rejected_solver_point_answers_with_the_proven_one():
    """Random uio_dt.thm4_1 (2 states, seed 100): Clarabel's point is rejected (lambda_min
    -6.5e-8 on a strict LMI), the others stop short ('inaccurate', or points rejected for margins
    below the threshold, which the exact rescue proves), and the dual is degenerate (no lower
    end): the optimum is not proven, so the answer is undecided, whatever route the solvers'
    rounding takes. The answer's point is the enclosure's proven primal end, whose gains the
    certifier certifies; it used to be the rejected point, with its gains. With AVX-512 OpenBLAS
    kernels the exact rescue of CVXOPT's 'inaccurate' point, 2.4e-3 above the infimum, made the
    answer 'certified' (the rescue now keeps verdict_of's rule: tests/engine/test_policy.py)."""
    import optimisation_instances as oi

    r = lmic.api.solve("uio_dt.thm4_1", oi.instance("uio_dt.thm4_1", 100, 2))
    enc = r.enclosure
    assert enc["lower"] is None and enc["upper"] is not None
    assert r.verdict == "undecided", r.outcome.reason
    # no attempt calls an inexact solve's point an optimum
    assert all(a["verdict"] != "certified" for a in r.attempts if a["status"] == "inaccurate"), r.attempts
    assert r.certificate.verdict == "certified"
    # the answer's objective is the enclosure's primal end, recomputed from the answer's point
    assert r.objective == r.problem.objective.value(r.solution.x)
    # a point that holds, never below the enclosure's upper end (the best point proven); it is
    # that end when the solvers' points were rejected, or an inexact solve's point that holds
    # (SDPA's pFEAS point, 43.65382 against the end 43.65360, with Haswell OpenBLAS kernels)
    assert r.objective >= enc["upper"] * (1 - 1e-9)
    # independent reference (bisection on Theorem 3.2's feasibility, resolution 2e-3)
    _, value, tol = oi.reference("uio_dt.thm4_1", oi.instance("uio_dt.thm4_1", 100, 2))
    assert abs(r.objective - value) <= tol


def test_a_backed_off_primal_end_that_meets_the_gap_certifies_the_answer():
    p = _min_t()
    enc = _enc(1.0, 1.0 + 1e-8, 1.0 + 1e-8, primal="certified backed-off point")
    out = decided_by_enclosure(p, _rejected(p), enc, SolveOptions(gap=1e-4), back={"x": [1.0 + 1e-8]})
    assert out is not None and out.verdict == "certified" and out.solution.x.tolist() == [1.0 + 1e-8]
