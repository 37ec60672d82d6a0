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

from lmic.certify import certified_solution, certify
from lmic.certify.audit import audit_certificate
from lmic.certify.certificate_write import write_certificate
from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
from lmic.solution import Solution


def _fixed_point(value: float) -> Problem:
    """``min x`` s.t. ``x - value >= 0`` and ``value - x >= 0``: the only point is ``value``."""
    return Problem(
        [Variable("x", "scalar", (1, 1))],
        [
            LMI("x - v >= 0", 1, sp.csc_matrix([[-value, 1.0]]), strict=False),
            LMI("v - x >= 0", 1, sp.csc_matrix([[value, -1.0]]), strict=False),
        ],
        LinearConstraints.empty(1),
        Objective("min", [0.0, 1.0]),
    )


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
