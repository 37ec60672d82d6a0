"""Unbounded problems (a dual infeasible): an exact improving ray and what it proves.

The truth is known independently: ``min -t`` over ``[[t, 1], [1, t]] >= 0`` is unbounded (the
feasible set is ``t >= 1``, closed form), and SDPLIB's infd1 is published as dual infeasible.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

from lmic.certify.farkas_unbounded import prove_improving_ray, ray_problem
from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable

SDPLIB = Path("/work/shared/sdplib")


def _unbounded_problem(sense: str = "min") -> Problem:
    C = sp.csc_matrix(np.array([[0.0, 1.0], [1.0, 0.0], [0.0, 1.0]]))  # [[t, 1], [1, t]]
    c = [0.0, -1.0] if sense == "min" else [0.0, 1.0]
    return Problem(
        [Variable("t", "scalar", (1, 1))],
        [LMI("M >= 0", 2, C, strict=False)],
        LinearConstraints.empty(1),
        Objective(sense, c),
    )


@pytest.mark.parametrize("sense", ["min", "max"])
def test_the_improving_ray_is_proved_and_a_wrong_one_is_not(sense: str) -> None:
    p = _unbounded_problem(sense)
    assert prove_improving_ray(p, np.array([2.5]))["proven"]
    bad = prove_improving_ray(p, np.array([-1.0]))  # the objective increases along it
    assert not bad["proven"] and "does not decrease" in bad["reason"]


def test_a_ray_that_leaves_an_lmi_is_not_proved() -> None:
    # min -t - s over diag(t - s, s - t) >= 0 ... along d = (1, 0): t - s grows, s - t falls
    C = sp.csc_matrix(np.array([[0.0, 1.0, -1.0], [0.0, 0.0, 0.0], [0.0, -1.0, 1.0]]))
    p = Problem(
        [Variable("t", "scalar", (1, 1), 0), Variable("s", "scalar", (1, 1), 1)],
        [LMI("D >= 0", 2, C, strict=False)],
        LinearConstraints.empty(2),
        Objective("min", [0.0, -1.0, -1.0]),
    )
    res = prove_improving_ray(p, np.array([1.0, 0.0]))
    assert not res["proven"] and "not proved PSD" in res["reason"]
    assert prove_improving_ray(p, np.array([1.0, 1.0]))["proven"]  # t = s grows: feasible forever


def test_ray_problem_points_are_rays() -> None:
    from lmic.policy import decide

    p = _unbounded_problem()
    out = decide(ray_problem(p))
    assert out.verdict == "certified"
    assert prove_improving_ray(p, out.solution.x)["proven"]


@pytest.mark.parametrize("sense", ["min", "max"])
def test_an_unbounded_problem_is_decided_with_a_point_and_an_exact_ray(sense: str) -> None:
    from lmic.certify import certify
    from lmic.routes import decide_route

    p = _unbounded_problem(sense)
    out = decide_route(p, "clarabel").outcome
    assert out.verdict == "unbounded-certified" and out.exit_code() == 5  # a decision: no optimum exists
    assert out.evidence.kind == "exact-proof"
    word = "below" if sense == "min" else "above"
    assert out.reason.startswith(f"unbounded {word}: a certified feasible point and an exact improving ray")
    # both halves, independently: the point meets t >= 1 (the closed-form feasible set) and is
    # certified on the problem itself; the recorded ray is a positive multiple of the true one
    assert out.solution.x[0] >= 1.0 and certify(p, out.solution).verdict == "certified"
    assert out.unbounded["sense"] == sense and out.unbounded["ray"] == ["1"]
    assert out.unbounded["slope"] == -1.0  # q.d with q = s c (s = -1 for max): -1 for both senses


def test_a_ray_without_a_feasible_point_is_not_called_unbounded() -> None:
    """min -t s.t. [[t, 1], [1, t]] >= 0 and t <= -2: the ray t -> +inf is improving for the
    cone, but the problem is infeasible (t >= 1 and t <= -2): never unbounded-certified."""
    from lmic.routes import decide_route

    base = _unbounded_problem()
    rows = LinearConstraints(sp.csr_matrix(np.array([[-2.0, -1.0]])), ["ge"], [False], ["t <= -2"])
    p = Problem(base.variables, base.lmis, rows, base.objective)
    out = decide_route(p, "clarabel").outcome
    assert out.verdict != "unbounded-certified"
    assert out.verdict in ("infeasible-certified", "infeasible-bounded"), out.reason


def _write_unbounded_certificate(tmp_path: Path) -> tuple[Path, dict]:
    import json

    from lmic.api import solve
    from lmic.certify.certificate_write import write_certificate

    r = solve(_unbounded_problem(), backend="clarabel")
    assert r.verdict == "unbounded-certified" and r.exit_code() == 5
    assert r.enclosure is None and r.to_dict()["unbounded"]["ray"] == ["1"]
    path = tmp_path / "unbounded.json"
    write_certificate(path, r.problem, r.solution, r.certificate, unbounded=r.outcome.unbounded)
    return path, json.loads(path.read_text())


def test_the_certificate_of_an_unbounded_problem_audits_and_tampering_is_named(tmp_path: Path) -> None:
    import json

    from lmic.certify.certificate import audit_certificate

    path, doc = _write_unbounded_certificate(tmp_path)
    good = audit_certificate(path)
    assert good.ok and "unbounded (exact ray)" in good.checked and "unbounded below" in good.message
    # the audit's verdict and exit code are lmic solve's (a newcomer saw "consistent: certified", exit 0)
    from lmic.commands.audit import exit_code

    assert good.verdict == "unbounded-certified" and exit_code(good) == 5
    assert good.label.startswith("unbounded-certified")
    for edit, field in [
        (lambda d: d["unbounded"].__setitem__("ray", ["-1"]), "unbounded.ray"),  # objective increases
        (lambda d: d["unbounded"].__setitem__("ray", ["0"]), "unbounded.ray"),
        (lambda d: d["unbounded"].__setitem__("slope", -2.0), "unbounded.slope"),
        (lambda d: d["unbounded"].__setitem__("sense", "max"), "unbounded.sense"),
    ]:
        bad = json.loads(json.dumps(doc))
        edit(bad)
        path.write_text(json.dumps(bad))
        r = audit_certificate(path)
        assert not r.ok and r.field == field, (field, r.field, r.message)


def test_audit_unbounded_reads_fractions_only() -> None:
    from lmic.certify.farkas_unbounded import audit_unbounded

    p = _unbounded_problem()
    assert audit_unbounded(p, {"ray": ["3/8"], "slope": -3 / 8, "sense": "min"})["ok"]
    # not what lmic writes: scientific notation, code, a zero or non-dyadic denominator, a
    # number, the wrong length, an entry of 65 characters (a forged file's huge integers)
    for ray in (["1e3"], ["__import__('os')"], ["1/0"], ["3/7"], [1], ["1", "2"], ["1" * 65]):
        res = audit_unbounded(p, {"ray": ray, "slope": -1.0, "sense": "min"})
        assert not res["ok"] and res["field"] == "unbounded.ray", ray


@pytest.mark.skipif(not (SDPLIB / "infd1.dat-s").exists(), reason="SDPLIB not available")
def test_sdplib_infd1_is_reported_dual_infeasible_and_unbounded() -> None:
    from lmic.ir.sdpa import read_sdpa
    from lmic.policy import feasibility_problem
    from lmic.routes import decide_route

    problem = read_sdpa(SDPLIB / "infd1.dat-s")
    r = decide_route(problem)
    assert r.outcome.verdict == "unbounded-certified" and r.outcome.exit_code() == 5
    assert "unbounded below" in r.outcome.reason and "the dual is infeasible" in r.outcome.reason
    # the point behind "a certified feasible point" is certified against the feasibility problem
    from lmic.certify import certify
    from lmic.certify.farkas_unbounded import audit_unbounded

    assert r.outcome.certificate is not None
    assert certify(feasibility_problem(problem), _solution(r.outcome.certificate.x)).verdict == "certified"
    assert audit_unbounded(problem, r.outcome.unbounded)["ok"]


def _solution(x: np.ndarray):
    from lmic.solution import Solution

    return Solution("optimal", x=np.asarray(x, dtype=float))
