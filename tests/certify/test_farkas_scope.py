"""lmic.certify.farkas_scope: a scale-free problem's float Farkas certificate is bounded, not global.

The counterexample that made it so: a Hurwitz ``A`` (eigenvalues -3.0e-8, about -0.6 and -1.5,
ill-conditioned eigenvectors). ``A^T P + P A < 0, P > 0`` is feasible: a Lyapunov solution is
proved below in rational arithmetic (Sylvester's criterion on the exact rationals of a float
``P``), sharing no code with lmic. Its relative margin is about 1e-10, and a float certificate
verified with ``rho = 4.5e-8``: lmic called the problem ``infeasible-certified`` (exit 3). Now the
answer is at most ``infeasible-bounded``, and says what is proved.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import scipy.linalg as sla

import lmic.api
from lmic.certify.farkas_ray import verify_farkas
from lmic.certify.farkas_scope import scope

A = np.array(
    [
        [-3.9333241716256833, 6.693832573433075, 0.44168907900946436],
        [-2.1586876262972656, 3.7357303047340076, 0.285031352329605],
        [3.0113725650032257, -6.051215819609048, -0.9748204197378534],
    ]
)


def _det(M: list[list[Fraction]]) -> Fraction:
    """Determinant by exact Gaussian elimination."""
    M = [row[:] for row in M]
    n, det = len(M), Fraction(1)
    for k in range(n):
        p = next((i for i in range(k, n) if M[i][k] != 0), None)
        if p is None:
            return Fraction(0)
        if p != k:
            M[k], M[p] = M[p], M[k]
            det = -det
        det *= M[k][k]
        for i in range(k + 1, n):
            f = M[i][k] / M[k][k]
            M[i] = [a - f * b for a, b in zip(M[i], M[k], strict=True)]
    return det


def _positive_definite(M: list[list[Fraction]]) -> bool:
    return all(_det([row[:k] for row in M[:k]]) > 0 for k in range(1, len(M) + 1))


def test_a_feasible_lyapunov_lmi_is_never_called_infeasible():
    # the truth, independently: a float P with P > 0 and -(A^T P + P A) > 0 exactly
    P = sla.solve_continuous_lyapunov(A.T, -np.eye(3))
    Pq = [[Fraction(float(v)) for v in row] for row in P]
    Aq = [[Fraction(float(v)) for v in row] for row in A]
    L = [[-sum(Aq[k][i] * Pq[k][j] + Pq[i][k] * Aq[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
    assert _positive_definite(Pq) and _positive_definite(L)
    r = lmic.api.solve("thesis.lyapunov", {"data": {"A": A.tolist()}})
    assert r.verdict != "infeasible-certified"
    if r.verdict == "infeasible-bounded":  # what it proves holds at the feasible point above
        rho = r.outcome.certificate.farkas["scope"]["rho"]
        margin = min(float(np.linalg.eigvalsh(P)[0]), float(np.linalg.eigvalsh(-(A.T @ P + P @ A))[0]))
        assert margin / np.max(np.abs(P)) <= rho


def test_a_scale_free_float_certificate_bounds_the_relative_margin_and_the_exact_one_is_global():
    """``p > 0`` and ``-p > 0``: the float certificate gives the radius ``1 / rho`` in the
    normalisation margin >= 1; the exact proof of the same certificate is global."""
    import scipy.sparse as sp

    from lmic.certify.farkas_exact import prove_infeasible
    from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable

    p = Problem(
        [Variable("p", "scalar", (1, 1))],
        [LMI("p > 0", 1, sp.csc_matrix([[0.0, 1.0]])), LMI("-p > 0", 1, sp.csc_matrix([[0.0, -1.0]]))],
        LinearConstraints.empty(1),
        Objective("feasibility", [0.0, 0.0]),
    )
    f = {"lmis": [np.eye(1), np.eye(1)]}
    v = verify_farkas(p, f)
    s = scope(p, v)
    assert s["scope"] == "bounded" and s["basis"] == "homogeneous"
    assert s["radius"] == 1.0 / s["rho"] and "relative margin above" in s["statement"]
    assert scope(p, v, prove_infeasible(p, f, v))["scope"] == "global"
