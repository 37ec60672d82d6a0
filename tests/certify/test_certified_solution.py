"""The point lmic reports is the point it proves.

A newcomer's ``min s`` s.t. ``[[s I, C'], [C, I]] >= 0`` (optimum ``lambda_max(C'C)``, no
interior at the optimum) was reported ``certified (exact)`` with the objective and variables of
the solver's point, ``1.3e-7`` *below* the true minimum and infeasible, while the proof held at
the snapped point ``x_q``; ``lmic audit`` accepted the file. Now every caller reports the proven
point (:func:`lmic.certify.certified_solution`), and the audit rejects a file whose
``solution.x`` is not that point. The truth is computed with numpy and ``Fraction``, not lmic.
"""

from __future__ import annotations

import json
from fractions import Fraction

import numpy as np
import scipy.sparse as sp
import sympy
from certify_helpers import interval_problem

from lmic.certify import certified_solution, certify
from lmic.certify.audit import audit_certificate
from lmic.certify.certificate_write import write_certificate
from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
from lmic.solution import Solution


def _fixed_point(value: float) -> Problem:
    """``min x`` s.t. ``x - value >= 0`` and ``value - x >= 0``: the only point is ``value``."""
    return interval_problem(value, value, "min")


def test_a_snapped_point_replaces_the_solvers_point():
    p = _fixed_point(1.0)
    sol = Solution("optimal", x=np.array([1.0 - 1e-12]), objective=1.0 - 1e-12)
    cert = certify(p, sol)
    assert cert.verdict == "certified"
    moved, cert2 = certified_solution(p, sol, cert)
    assert moved is not sol and Fraction(moved.x[0]) == 1
    assert moved.objective == 1.0 and cert2 is cert
    assert np.array_equal(np.asarray(cert2.x), moved.x)


def test_a_point_proved_at_x_itself_is_returned_unchanged():
    p = _fixed_point(1.0)
    sol = Solution("optimal", x=np.array([1.0]), objective=1.0)
    moved, _ = certified_solution(p, sol, certify(p, sol))
    assert moved is sol


def test_the_audit_rejects_a_file_whose_point_is_not_the_proven_one(tmp_path):
    """The file the old code wrote: the solver's point with the certificate of the snapped one."""
    p = _fixed_point(1.0)
    sol = Solution("optimal", x=np.array([1.0 - 1e-12]), objective=1.0 - 1e-12)
    cert = certify(p, sol)
    good, _ = certified_solution(p, sol, cert)
    path = tmp_path / "good.json"
    write_certificate(path, p, good, cert)
    assert audit_certificate(path).ok
    doc = json.loads(path.read_text())
    doc["solution"]["x"] = [1.0 - 1e-12]
    doc["solution"]["objective"] = 1.0 - 1e-12
    doc["solution"]["variables"] = {"x": 1.0 - 1e-12}
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(doc))
    r = audit_certificate(bad)
    assert not r.ok and r.field == "solution.x"
    assert "not the proven point" in r.message


def test_the_reported_minimum_of_a_schur_lmi_is_never_below_the_optimum():
    """``min s`` s.t. ``[[s I, C'], [C, I]] >= 0``: the optimum is ``lambda_max(C'C)`` and the
    feasible set has no interior there. The reported ``s`` must be feasible: ``s I - C'C``
    positive semidefinite in exact arithmetic (checked here by a Fraction LDL)."""
    from lmic.api import solve
    from lmic.template import I, Template, block, theorem

    @theorem(id="test.schur_min", title="Schur", citation="test", kind="analysis")
    def schur(t: Template) -> None:
        n, q = t.dims("n q")
        C = t.data("C", q, n)
        s = t.scalar("s")
        t.lmi("schur", block([[s * I(n), C.T], [C, I(q)]]) >= 0)
        t.minimize(s)

    C = np.array(
        [
            [0.7572210447581504, -2.034167273443428, -0.9144945379945887],
            [0.7095799877420675, 1.156401048432157, -2.158005380126208],
        ]
    )
    truth = float(np.linalg.eigvalsh(C.T @ C).max())
    for backend in ("clarabel", "cvxopt"):
        r = solve(schur, {"lmic": 1, "data": {"C": C.tolist()}}, backend=backend)
        assert r.verdict == "certified", (backend, r.certificate.reason)
        s = float(r.variables["s"])
        assert s == r.objective and s >= truth * (1 - 1e-15), (backend, s, truth)
        # s I - C'C >= 0 exactly (the Schur complement of the identity block)
        M = [
            [Fraction(s) * (i == j) - sum(Fraction(C[k, i]) * Fraction(C[k, j]) for k in range(2)) for j in range(3)]
            for i in range(3)
        ]
        assert _psd_exact(M), backend
    assert sympy  # the template language is sympy's


def _psd_exact(M: list[list[Fraction]]) -> bool:
    """Positive semidefinite by exact symmetric elimination (a zero pivot needs a zero row)."""
    n = len(M)
    M = [row[:] for row in M]
    for k in range(n):
        if M[k][k] < 0:
            return False
        if M[k][k] == 0:
            if any(M[k][j] != 0 for j in range(k, n)):
                return False
            continue
        for i in range(k + 1, n):
            f = M[i][k] / M[k][k]
            for j in range(k + 1, n):
                M[i][j] -= f * M[k][j]
    return True


def _on_row_problem() -> Problem:
    """``min x1`` s.t. ``x1 - 3 x2 = 0`` (a row) and ``x1 + x2 - 1 >= 0``: the minimum is 3/4."""
    lin = LinearConstraints(sp.csr_matrix(np.array([[0.0, 1.0, -3.0]])), ["eq"], [False], ["x1 - 3 x2 = 0"])
    return Problem(
        [Variable("x1", "scalar", (1, 1), 0), Variable("x2", "scalar", (1, 1), 1)],
        [LMI("x1 + x2 - 1 >= 0", 1, sp.csc_matrix([[-1.0, 1.0, 1.0]]), strict=False)],
        lin,
        Objective("min", [0.0, 1.0, 0.0]),
    )


def test_a_point_proved_at_its_projection_onto_the_rows_is_reported_at_that_projection(tmp_path):
    """The solver's point misses the row by ~4e-9 and its objective is below 3/4; the proof holds
    at its projection onto the row, a rational point no float represents. The point reported is
    the nearest floats to it, proved again: on the row and above the minimum up to rounding
    (checked with ``Fraction``), and the file audits (a reviewer found the solver's point
    reported, ``certified (exact)``, 9e-9 off the row)."""
    p = _on_row_problem()
    x = np.array([0.7499999992837606, 0.25000000283553425])
    assert Fraction(x[0]) < Fraction(3, 4)  # the solver's objective is below the minimum
    sol = Solution("optimal", x=x, objective=float(x[0]))
    cert = certify(p, sol)
    assert cert.verdict == "certified" and not cert.exact["at_x"]
    moved, cert2 = certified_solution(p, sol, cert)
    assert moved is not sol and cert2.verdict == "certified"
    X = [Fraction(v) for v in moved.x]
    ulp = Fraction(2) ** -52
    assert abs(X[0] - 3 * X[1]) <= 4 * ulp  # on the row up to rounding
    assert X[0] >= Fraction(3, 4) - ulp and moved.objective == float(moved.x[0])
    path = tmp_path / "row.json"
    write_certificate(path, p, moved, cert2)
    assert audit_certificate(path).ok


def test_an_exact_rescue_reports_the_point_its_proof_holds_at(tmp_path):
    """The rescue of a point rejected for its tiny margins (a constant block ``diag(1e6, 1e-7)``)
    whose proof holds at a rounding on the row ``x1 = x2``, not at the solver's point (which
    misses it by 2^-50): the rescued answer is that rounding, exactly on the row, and its file
    audits (it used to report the solver's point, and the audit rejected the honest file)."""
    from lmic.outcome import Outcome
    from lmic.rescue import rescue_rejected

    lin = LinearConstraints(sp.csr_matrix(np.array([[0.0, 1.0, -1.0]])), ["eq"], [False], ["x1 = x2"])
    p = Problem(
        [Variable("x1", "scalar", (1, 1), 0), Variable("x2", "scalar", (1, 1), 1)],
        [
            LMI("x1 - 1 >= 0", 1, sp.csc_matrix([[-1.0, 1.0, 0.0]]), strict=False),
            LMI("M > 0", 2, sp.csc_matrix([[1e6, 0.0, 0.0], [0.0, 0.0, 0.0], [1e-7, 0.0, 0.0]])),
        ],
        lin,
        Objective("min", [0.0, 1.0, 1.0]),
    )
    x = np.array([1.0 + 2.0**-30, 1.0 + 2.0**-30 + 2.0**-50])
    sol = Solution("optimal", x=x, objective=float(x.sum()))
    cert = certify(p, sol)
    assert cert.verdict == "rejected"  # the constant block's margin is below the float threshold
    out = rescue_rejected(p, Outcome("rejected"), [(sol, cert, "clarabel")], [], key=lambda c: 0.0)
    assert out.verdict == "certified" and out.solution is not sol
    X = [Fraction(v) for v in out.solution.x]
    assert X[0] == X[1] and X[0] >= 1  # on the row, in the LMI: exactly
    path = tmp_path / "rescued.json"
    write_certificate(path, p, out.solution, out.certificate)
    assert audit_certificate(path).ok
