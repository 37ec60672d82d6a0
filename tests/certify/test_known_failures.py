"""Points real solvers returned on the catalogues' known failure cases: none may be certified.

``data/known_failures.json`` holds the points (recorded once with SCS, Clarabel and SDPA, so
that this test needs no solver and runs in a second):

* ``uir.thm5_1`` (Rossler example) and ``obs_control.thm3_2`` in z-coordinates at alpha = 0.05:
  SCS reports success (``solved (inaccurate)``) on infeasible problems;
* ``qib.thm2`` with the published K, the closed LMI with a 1e-8 margin (the seeds catalogue's
  lesson 2): Clarabel returns ``AlmostSolved`` with a small violation, SCS an "optimal"
  near-zero point (||P|| ~ 2e-8) on the homogeneous LMI, SDPA an "optimal" point at
  ||P|| ~ 3e5 whose violation is at the level of float64 round-off.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml

from lmic.certify import certify
from lmic.compile import compile_theorem
from lmic.solution import Solution

ROOT = Path(__file__).resolve().parents[2]
CASES = json.loads((Path(__file__).parent / "data" / "known_failures.json").read_text())["cases"]


def _problem(case: dict):
    system = yaml.safe_load((ROOT / "examples" / case["system"]).read_text())
    if case["K"] is not None:
        system["data"]["K"] = case["K"]
    system.setdefault("params", {}).update(case["params"])
    return compile_theorem(case["theorem"], system)


@pytest.mark.parametrize("case", CASES, ids=[c["id"] for c in CASES])
def test_known_solver_failures_are_not_certified(case):
    prob = _problem(case)
    x = np.asarray(case["x"])
    assert x.shape == (prob.n,), "the recorded point no longer fits the compiled IR"
    sol = Solution(
        case["status"],
        x=x,
        objective=case["objective"],
        backend=case["backend"],
        native_status=case["native_status"],
        margin=case["margin"],
        strategy=case["strategy"],
    )
    cert = certify(prob, sol, exact=True)
    assert cert.verdict == "rejected", cert.reason
    assert not all(e["ok"] for e in cert.lmis)
    assert not cert.exact["proven"]


def test_scs_near_zero_point_is_caught_by_the_relative_margin():
    case = next(c for c in CASES if c["backend"] == "scs" and c["theorem"] == "qib.thm2")
    prob = _problem(case)
    cert = certify(prob, Solution(case["status"], x=np.asarray(case["x"])))
    worst = min(cert.lmis, key=lambda e: e["rel_margin"])
    assert case["status"] == "optimal"
    assert -1e-8 < worst["min_eig"] < 0  # absolutely tiny: an absolute 1e-8 tolerance would pass it
    assert worst["rel_margin"] < -1e-2  # a few percent of the point's own scale


def test_clarabel_almost_solved_violation_is_not_certified():
    case = next(c for c in CASES if c["backend"] == "clarabel")
    prob = _problem(case)
    cert = certify(prob, Solution(case["status"], x=np.asarray(case["x"])))
    assert case["status"] == "inaccurate"
    assert cert.verdict == "rejected"
    assert -1e-6 < cert.min_margin < 0


def test_round_off_level_violation_is_reported_as_such():
    case = next(c for c in CASES if c["backend"] == "sdpa")
    cert = certify(_problem(case), Solution(case["status"], x=np.asarray(case["x"])))
    assert cert.verdict == "rejected"
    # SDPA's point violates (21) by more than the float64 error of evaluating F(x) (so it is a
    # violation, not "zero to float64 accuracy"), but only at round-off level relative to the
    # term scale, and the reason says both
    r = next(e for e in cert.lmis if e["name"] == "(21)")
    assert r["min_eig"] < -r["float_err"] and abs(r["rel_margin"]) < 1e-12
    assert cert.reason.startswith(f"LMI '(21)' violated: lambda_min = {r['min_eig']:.3g} (relative ")
