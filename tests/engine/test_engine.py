"""The decision engine (issue 9): no false certificates, one outcome, one exit-code rule.

Instances are built here with their truth in closed form:

* ``big(eps)``: ``[[x, 1], [1, eps]] > 0``, feasible exactly for ``x > 1/eps`` (Schur
  complement): its only solutions are large. SDPA and SCS return Farkas rays that verify in
  float with radius ~4e4 < 1/eps: before the engine they were printed ``infeasible-certified``.
* ``thesis.thm3_2_2`` with ``C = I``: ``P = I``, ``Lbar = A + k I`` with ``k = gamma^2 + 1`` is
  feasible for every ``gamma`` (``(A - L C) = -k I`` gives ``-2k + gamma^2 + 1 < 0``): the
  supremum of ``gamma`` is infinite.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp
import yaml

from lmic.api import solve
from lmic.certify import certify
from lmic.crosscheck import assemble, conflicts, crosscheck
from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
from lmic.outcome import EXIT_CODES, exit_code, verdict_of
from lmic.solution import Solution

ROOT = Path(__file__).resolve().parents[2]
EPS = 1e-5


def big(eps: float = EPS) -> Problem:
    """``[[x, 1], [1, eps]] > 0``: feasible exactly for ``x > 1/eps``."""
    coeffs = sp.csc_matrix(np.array([[0.0, 1.0], [1.0, 0.0], [eps, 0.0]]))  # tril (0,0), (1,0), (1,1)
    return Problem(
        [Variable("x", "scalar", (1, 1))],
        [LMI("big", 2, coeffs, strict=True)],
        LinearConstraints.empty(1),
        Objective("feasibility", [0, 0]),
    )


def _truly_feasible(x: float, eps: float = EPS) -> bool:
    # closed form, no solver: x > 0 and eps - 1/x > 0
    return x > 1.0 / eps


@pytest.mark.parametrize("backend", ["clarabel", "cvxopt", "sdpa", "scs", None])
def test_feasible_problem_with_only_large_solutions_is_never_called_infeasible(backend):
    r = solve(big(), backend=backend)
    assert r.verdict != "infeasible-certified" and r.exit_code() != 3
    if r.verdict == "certified":
        x = float(r.solution.x[0])
        assert _truly_feasible(x)
        exact = bool(r.certificate.exact and r.certificate.exact.get("proven"))  # exact rescue
        assert certify(big(), Solution("feasible", x=np.array([x])), exact=exact).verdict == "certified"
    if r.verdict == "infeasible-bounded":
        # what is claimed must be true: no solution with |x| <= R, and every solution is > 1/eps
        assert r.exit_code() == 4
        assert r.outcome.evidence.radius <= 1.0 / EPS
        assert "no solution with ||x||_inf <=" in r.outcome.reason


def test_default_policy_certifies_the_large_solution():
    r = solve(big())
    assert r.verdict == "certified" and _truly_feasible(float(r.solution.x[0]))


def test_a_float_ray_of_an_inhomogeneous_problem_is_bounded_and_its_radius_is_true():
    # a Farkas ray that passes the float tests for [[x,1],[1,eps]] > 0 (which is feasible):
    # Z = [[d, -s], [-s, 1]], s = sqrt(d): <F_x, Z> = d ~ 0, <F_0, Z> = eps - 2 s < 0
    d = 1e-8
    s = np.sqrt(d) * (1 - 1e-9)
    Z = np.array([[d, -s], [-s, 1.0]])
    cert = certify(big(), Solution("infeasible", farkas={"lmis": [Z], "linear": []}))
    assert cert.farkas["verified"]  # the float verification alone would have said "infeasible"
    assert cert.verdict == "infeasible-bounded"
    radius = cert.farkas["scope"]["radius"]
    # independent check of the claim: every solution has x > 1/eps, so none has |x| <= radius
    assert radius < 1.0 / EPS
    assert exit_code(verdict_of(big(), Solution("infeasible"), cert)) == 4


def test_homogeneous_ray_is_proved_exactly():
    # -p > 0 and p > 0 (homogeneous): the float ray bounds the relative margin only; the policy
    # proves the bounded ray exactly (Z = 1, 1 is rational), and that is global
    p = Problem(
        [Variable("p", "scalar", (1, 1))],
        [LMI("p > 0", 1, sp.csc_matrix([[0.0, 1.0]])), LMI("-p > 0", 1, sp.csc_matrix([[0.0, -1.0]]))],
        LinearConstraints.empty(1),
        Objective("feasibility", [0, 0]),
    )
    r = solve(p)
    assert r.verdict == "infeasible-certified" and r.exit_code() == 3
    assert r.outcome.evidence.kind == "exact-proof"


def test_unverified_infeasible_status_does_not_exit_3():
    p = big()
    bad = Solution("infeasible", farkas={"lmis": [np.eye(2)], "linear": []})  # not a Farkas ray
    cert = certify(p, bad)
    assert cert.verdict == "unverified"
    v = verdict_of(p, bad, cert)
    assert v == "undecided" and exit_code(v) == 1


def test_exit_code_table_is_the_documented_one():
    # the table in README.md and docs/backends.md is the one lmic uses
    for doc in (ROOT / "README.md", ROOT / "docs" / "backends.md"):
        text = doc.read_text()
        found = dict(re.findall(r"^\|\s*`([a-z -]+)`\s*\|[^|\n]*\|\s*(\d+)\s*\|", text, flags=re.M))
        assert found, f"{doc.name}: no verdict table"
        assert {k: int(v) for k, v in found.items()} == EXIT_CODES, doc.name
    assert [exit_code(v) for v in ("certified", "rejected", "undecided")] == [0, 1, 1]


def test_crosscheck_semantics_failures_are_not_conflicts():
    rows = [
        {"backend": "a", "decision": "certified", "objective": 1.0, "x_norm": 2.0},
        {"backend": "b", "decision": "certified", "objective": 1.0 + 1e-6, "x_norm": 2.0},
        {"backend": "c", "decision": "rejected", "objective": None},
        {"backend": "d", "decision": "undecided", "objective": None},
    ]
    found, gap = conflicts(rows, "min", 1e-3)
    assert found == [] and gap is not None and gap < 1e-3
    rows.append({"backend": "e", "decision": "certified", "objective": 1.5, "x_norm": 2.0})
    assert any("optima differ" in c for c in conflicts(rows, "min", 1e-3)[0])
    rows = [
        {"backend": "a", "decision": "certified", "objective": None, "x_norm": 2.0},
        {"backend": "b", "decision": "infeasible-certified", "objective": None},
    ]
    assert conflicts(rows, "feasibility", 1e-3)[0]
    # a bounded ray conflicts with a certified point only inside its radius
    rows[1] = {"backend": "b", "decision": "infeasible-bounded", "radius": 1.0, "objective": None}
    assert conflicts(rows, "feasibility", 1e-3)[0] == []
    rows[1]["radius"] = 3.0
    assert conflicts(rows, "feasibility", 1e-3)[0]


def test_crosscheck_unbounded_conflicts_with_an_optimum_and_with_infeasibility():
    unb = {"backend": "u", "decision": "unbounded-certified", "objective": None, "x_norm": 1.0}
    opt = {"backend": "a", "decision": "certified", "objective": 1.0, "x_norm": 2.0}
    inf = {"backend": "b", "decision": "infeasible-certified", "objective": None}
    assert conflicts([unb, dict(unb, backend="v")], "min", 1e-3)[0] == []
    assert "proves the problem unbounded" in conflicts([unb, opt], "min", 1e-3)[0][0]
    assert "proves it infeasible" in conflicts([unb, inf], "min", 1e-3)[0][0]
    assert assemble("p", [unb, {"backend": "c", "decision": "undecided", "objective": None}], "min").agree


def test_batch_counts_unbounded_as_its_own_outcome():
    from lmic.api import solve
    from lmic.studies.tasks import OUTCOMES, outcome
    from lmic.testing.conformance import CASES

    r = solve(CASES["unbounded"].build())
    assert outcome("solve", r) == "unbounded-certified" and "unbounded-certified" in OUTCOMES


def test_crosscheck_control1_agrees_with_failures_listed():
    from lmic.backends.base import SolveOptions

    path = ROOT.parent / "shared" / "sdplib" / "control1.dat-s"
    if not path.is_file():
        pytest.skip("SDPLIB not available")
    # SCS capped at 50 iterations cannot reach a certified optimum: a failure, not a disagreement
    rep = crosscheck(str(path), backends=["clarabel", "cvxopt", "scs"], options=SolveOptions(max_iter=50))
    decisions = {r["backend"]: r["decision"] for r in rep.results}
    assert decisions["clarabel"] == decisions["cvxopt"] == "certified"
    assert decisions["scs"] != "certified"
    assert rep.agree and rep.exit_code() == 0 and rep.failures == 1 and rep.conflicts == []


def _lmic(*args: str) -> subprocess.CompletedProcess:
    import os

    env = dict(os.environ)
    env["PYTHONPATH"] = f"{ROOT}{os.pathsep}{ROOT / 'plugins'}"
    return subprocess.run(
        [sys.executable, "-m", "lmic.cli", *args], capture_output=True, text=True, env=env, cwd=ROOT, timeout=600
    )


THESIS_EX = ROOT / "examples" / "thesis.thm3_2_2.ex3_2_2.yaml"


def _thesis_gamma_bound() -> tuple[float, float]:
    """(gamma of Example 3.2.2, a closed-form upper bound on the sup of gamma in LMI (3.14)).

    On ``ker C`` the ``Lbar`` terms of (3.14) vanish; with ``z = (v, u)``, ``v`` in ``ker C``,
    ``z' (3.14) z = 2 v'P(Av + u) + gamma^2 |v|^2 - |u|^2``, and ``u = -A v`` removes ``P``:
    (3.14) < 0 needs ``gamma |v| < |A v|`` for every ``v`` in ``ker C``, so
    ``gamma < sigma_min(A N)`` (``N`` an orthonormal basis of ``ker C``). No solver involved.
    """
    import scipy.linalg

    sysfile = yaml.safe_load(THESIS_EX.read_text())
    A, C = np.array(sysfile["data"]["A"], dtype=float), np.array(sysfile["data"]["C"], dtype=float)
    N = scipy.linalg.null_space(C)
    return float(sysfile["params"]["gamma"]), float(np.linalg.svd(A @ N, compute_uv=False).min())


def test_same_verdict_from_solve_api_and_audit_published(tmp_path):
    from lmic.published import audit_published

    gamma, bound = _thesis_gamma_bound()
    assert gamma == 3.33 and bound == pytest.approx(1.0)  # infeasible: gamma is above the bound
    api = solve("thesis.thm3_2_2", str(THESIS_EX))
    cli = _lmic("solve", "thesis.thm3_2_2", str(THESIS_EX), "--json")
    assert cli.returncode == api.exit_code(), cli.stderr
    assert json.loads(cli.stdout)["verdict"] == api.verdict
    audit = audit_published("thesis.thm3_2_2", str(THESIS_EX))
    status = next(c for c in audit.claims if c.kind == "status")
    assert status.verdict == api.verdict
    # infeasible, so never certified; what lmic does prove rests on a Farkas ray the certifier verified
    assert api.verdict != "certified"
    assert api.certificate.farkas["verified"]


def test_closed_form_farkas_certificate_of_thesis_example_is_proven_exactly():
    # z = (v, -A v) with v = e4 in ker C (A e4 = e3): z z' annihilates every P and Lbar term of
    # (3.14) and leaves gamma^2 - |A v|^2 = 3.33^2 - 1 > 0 on the constants: a global proof
    from lmic.compile import compile_theorem

    problem = compile_theorem("thesis.thm3_2_2", str(THESIS_EX))
    z = np.zeros(8)
    z[3], z[4 + 2] = 1.0, -1.0
    lmis = [np.outer(z, z) if lmi.name == "(3.14)" else np.zeros((lmi.dim, lmi.dim)) for lmi in problem.lmis]
    farkas = {"lmis": lmis, "linear": [0.0] * len(problem.linear)}
    cert = certify(problem, Solution("infeasible", farkas=farkas), exact=True)
    assert cert.verdict == "infeasible-certified" and cert.exact["proven"]


def test_exact_certificate_checked_in_float_only_claims_a_finite_radius():
    # the closed-form certificate above has g_k = 0.0 exactly in float, but a float check does
    # not prove g_k = 0 (its own rounding): it once said "no solution with ||x||_inf <= inf ...
    # a larger solution is not excluded". It must claim a finite radius, set by that rounding.
    from lmic.compile import compile_theorem

    problem = compile_theorem("thesis.thm3_2_2", str(THESIS_EX))
    z = np.zeros(8)
    z[3], z[4 + 2] = 1.0, -1.0
    lmis = [np.outer(z, z) if lmi.name == "(3.14)" else np.zeros((lmi.dim, lmi.dim)) for lmi in problem.lmis]
    cert = certify(problem, Solution("infeasible", farkas={"lmis": lmis, "linear": []}), exact=False)
    assert cert.verdict == "infeasible-bounded" and not cert.exact
    sc = cert.farkas["scope"]
    assert sc["scope"] == "bounded" and np.isfinite(sc["radius"])
    assert cert.farkas["rel_residual"] == 0.0 and sc["radius"] <= -cert.farkas["g0"] / cert.farkas["residual_floor"]
    assert "<= inf" not in sc["statement"] and "rounding" in sc["statement"]
    assert "<= inf" not in cert.reason


def test_thesis_example_3_2_2_is_decided_infeasible():
    gamma, bound = _thesis_gamma_bound()
    assert gamma > bound  # infeasible, and a global proof exists (previous test): a decision exists
    assert solve("thesis.thm3_2_2", str(THESIS_EX)).verdict == "infeasible-certified"


def test_infinite_supremum_has_no_proven_upper_end(tmp_path):
    from lmic.compile import compile_theorem
    from lmic.studies.sweep import maximize

    rng = np.random.default_rng(3)
    A = rng.standard_normal((2, 2))
    system = {"lmic": 1, "data": {"A": A.tolist(), "B": [[1.0], [0.0]], "C": np.eye(2).tolist()}, "params": {}}
    path = tmp_path / "sys.yaml"
    path.write_text(yaml.safe_dump(system))
    r = maximize("thesis.thm3_2_2", str(path), "gamma", max_evals=10)
    assert r.lower is not None
    assert r.upper_proven is None and r.upper_kind != "infeasible-certified"
    assert not r.to_dict()["bracket_proven"]
    for pt in r.points:
        # closed form: P = I, Lbar = A + k I (k = gamma^2 + 1) is feasible at every gamma
        g = pt.value
        prob = compile_theorem("thesis.thm3_2_2", str(path), {"gamma": g})
        x = prob.pack({"P": np.eye(2), "Lbar": A + (g * g + 1.0) * np.eye(2)})
        assert certify(prob, Solution("feasible", x=x)).verdict == "certified"
        assert pt.outcome != "infeasible"
