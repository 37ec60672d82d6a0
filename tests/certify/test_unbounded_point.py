"""lmic.route_unbounded: ``unbounded-certified`` needs a point that IS feasible, not one the
certifier's non-strict tolerance lets through.

The counterexample: ``min x1`` s.t. ``x2 - 1 >= 0`` and ``c - x2 >= 0`` with ``c`` the float
nearest ``0.999999999``; ``x1`` appears in no constraint. The problem is infeasible (``x2 >= 1 >
c >= x2``, checked below in exact rationals). Clarabel calls it unbounded; the exact improving
ray ``(-1, 0)`` is a true recession direction, and the feasibility solve returns ``x2 ~ 1 -
5e-10``, violating both rows by ``5e-10``, which the certifier's ``rel = 1e-8`` accepts. lmic
answered ``unbounded-certified`` (exit 5, "a certified feasible point and an exact improving
ray; the optimal value is -inf") for an infeasible problem, and ``lmic audit`` accepted the file.
"""

from __future__ import annotations

import json
from fractions import Fraction
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
from lmic.solution import Solution

C = 0.999999999


def _problem() -> Problem:
    # columns: [1, x1, x2]; two 1x1 LMIs x2 - 1 >= 0 and C - x2 >= 0 (x1 in none)
    return Problem(
        [Variable("x1", "scalar", (1, 1), 0), Variable("x2", "scalar", (1, 1), 1)],
        [
            LMI("x2 - 1 >= 0", 1, sp.csc_matrix([[-1.0, 0.0, 1.0]]), strict=False),
            LMI("c - x2 >= 0", 1, sp.csc_matrix([[C, 0.0, -1.0]]), strict=False),
        ],
        LinearConstraints.empty(2),
        Objective("min", [0.0, 1.0, 0.0]),
    )


def test_the_problem_is_infeasible_in_exact_arithmetic():
    # x2 >= 1 and x2 <= C need C >= 1: the float C is below 1 exactly
    assert Fraction(C) < 1


def test_an_infeasible_problem_is_never_unbounded_certified():
    from lmic.routes import decide_route

    out = decide_route(_problem(), "clarabel").outcome
    assert out.verdict != "unbounded-certified", out.reason
    assert out.exit_code() != 5


def test_the_audit_rejects_an_unbounded_certificate_whose_point_is_feasible_only_within_tolerance(tmp_path: Path):
    from lmic.certify import certify
    from lmic.certify.certificate import audit_certificate
    from lmic.certify.certificate_write import write_certificate

    p = _problem()
    x = np.array([0.0, 1.0 - 5e-10])  # both rows violated by 5e-10 (exactly: x2 < 1)
    assert Fraction(float(x[1])) < 1
    sol = Solution("feasible", x=x, objective=0.0, backend="clarabel")
    cert = certify(p, sol)
    assert cert.verdict == "rejected"  # within tolerance only: the certifier proves nothing
    cert.verdict = "certified"  # a forger's certificate claims it anyway
    unb = {"ray": ["-1", "0"], "slope": -1.0, "sense": "min", "statement": "unbounded below"}
    path = tmp_path / "forged.json"
    write_certificate(path, p, sol, cert, unbounded=unb)
    json.loads(path.read_text())  # a well-formed file
    r = audit_certificate(path)
    assert not r.ok and r.field == "certificate.verdict", r.message  # recomputed: rejected
