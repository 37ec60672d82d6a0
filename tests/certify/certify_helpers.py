"""Small hand-built IR problems for the certifier tests (no compiler, no backend needed).

A uniquely named module (not ``conftest``) so that test modules can import it unambiguously.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from lmic.ir.problem import LMI, Check, LinearConstraints, NamedExpr, Objective, Problem, Variable
from lmic.ir.svec import tril_size, tril_vec
from lmic.template import STAR, I, block, theorem


def lmi_from(name: str, mats: list[np.ndarray], strict: bool = True, relation: str = ">") -> LMI:
    """LMI ``mats[0] + sum_k x_k mats[1 + k]`` (dense symmetric matrices)."""
    d = mats[0].shape[0]
    coeffs = sp.csc_matrix(np.column_stack([tril_vec(M) for M in mats]))
    assert coeffs.shape == (tril_size(d), len(mats))
    return LMI(name, d, coeffs, strict=strict, relation=relation)


def interval_problem(lo: float, hi: float, sense: str = "feasibility", name: str = "x") -> Problem:
    """``name - lo >= 0`` and ``hi - name >= 0`` (non-strict) in one scalar variable: feasible
    exactly when ``lo <= hi`` (the single point ``lo`` when equal); ``sense`` ``min`` / ``max``
    optimises the variable itself."""
    c = [0.0, 0.0] if sense == "feasibility" else [0.0, 1.0]
    return Problem(
        [Variable(name, "scalar", (1, 1))],
        [
            LMI(f"{name} - lo >= 0", 1, sp.csc_matrix([[-lo, 1.0]]), strict=False),
            LMI(f"hi - {name} >= 0", 1, sp.csc_matrix([[hi, -1.0]]), strict=False),
        ],
        LinearConstraints.empty(1),
        Objective(sense, c),
    )


def lyapunov(A: np.ndarray, strict: bool = True, checks: bool = True) -> Problem:
    """``P > 0`` and ``A^T P + P A < 0`` (homogeneous); derived ``Pinv``; check ``A`` Hurwitz."""
    n = A.shape[0]
    P = Variable("P", "symmetric", (n, n))
    B = P.basis().toarray()
    basis = [B[:, k].reshape(n, n, order="F") for k in range(P.size)]
    zero = np.zeros((n, n))
    lmi_p = lmi_from("P > 0", [zero] + basis, strict)
    lmi_a = lmi_from("A'P + PA < 0", [zero] + [-(A.T @ E + E @ A) for E in basis], strict, "<")
    return Problem(
        [P],
        [lmi_p, lmi_a],
        LinearConstraints.empty(P.size),
        Objective("feasibility", np.zeros(1 + P.size)),
        data={"A": A.tolist()},
        derived=[NamedExpr("Pinv", {"op": "inv", "args": [{"name": "P"}]})],
        checks=[Check("A Hurwitz", "hurwitz", {"name": "A"})] if checks else [],
    )


def observer(A: np.ndarray, C: np.ndarray) -> Problem:
    """A discrete-time observer LMI in (P, G): [[P, A^T P - C^T G^T], [*, P]] > 0 (homogeneous).

    Derived ``L = P^-1 G``; check ``A - L C`` Schur stable.
    """
    n, p = A.shape[0], C.shape[0]
    P = Variable("P", "symmetric", (n, n), offset=0)
    G = Variable("G", "full", (n, p), offset=P.size)
    N = P.size + G.size
    mats = [np.zeros((2 * n, 2 * n))]
    BP = P.basis().toarray()
    for k in range(P.size):
        E = BP[:, k].reshape(n, n, order="F")
        mats.append(np.block([[E, A.T @ E], [E @ A, E]]))
    BG = G.basis().toarray()
    for k in range(G.size):
        E = BG[:, k].reshape(n, p, order="F")
        X = -C.T @ E.T
        mats.append(np.block([[np.zeros((n, n)), X], [X.T, np.zeros((n, n))]]))
    lmi = lmi_from("observer", mats, True)
    L = {"op": "mul", "args": [{"op": "inv", "args": [{"name": "P"}]}, {"name": "G"}]}
    closed = {
        "op": "add",
        "args": [{"name": "A"}, {"op": "neg", "args": [{"op": "mul", "args": [{"name": "L"}, {"name": "C"}]}]}],
    }
    return Problem(
        [P, G],
        [lmi],
        LinearConstraints.empty(N),
        Objective("feasibility", np.zeros(1 + N)),
        data={"A": A.tolist(), "C": C.tolist()},
        derived=[NamedExpr("L", L)],
        checks=[Check("A - L C Schur stable", "schur_stable", closed)],
    )


def stable_system(n, seed, margin=0.5, eighths=False):
    """A random ``(A, B, C)`` (2 inputs, 2 outputs) with spectral abscissa ``-margin``, drawn
    from ``default_rng(seed)`` in that order; ``eighths``: the diagonal of ``A`` rounded to
    eighths (the coefficients ``A_aa + A_bb`` of ``A^T P + P A`` are then exact in floating
    point), shifted by eighths until the abscissa is at most ``-0.1``."""
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    A -= (max(np.linalg.eigvals(A).real) + margin) * np.eye(n)
    if eighths:
        A[np.diag_indices(n)] = np.round(A[np.diag_indices(n)] * 8) / 8
        while max(np.linalg.eigvals(A).real) >= -0.1:
            A -= 0.125 * np.eye(n)
    return A, rng.standard_normal((n, 2)), rng.standard_normal((2, n))


def hinf_norm(A, B, C, tol=1e-12):
    """Bracket ``(lo, hi)`` of the H-infinity norm of (A, B, C, 0) by bisection on the
    imaginary-axis eigenvalues of the Hamiltonian (independent of any LMI solver)."""

    def crosses(g):
        H = np.block([[A, B @ B.T / g], [-C.T @ C / g, -A.T]])
        ev = np.linalg.eigvals(H)
        return np.any(np.abs(ev.real) < 1e-8 * max(1.0, np.abs(ev).max()))

    lo, hi = 0.0, 1.0
    while crosses(hi):
        lo, hi = hi, 2 * hi
    while hi - lo > tol * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if crosses(mid) else (lo, mid)
    return lo, hi


@theorem(id="test.inline_bounded_real", title="t", citation="c")
def inline_brl(t):
    """The bounded-real lemma as a notebook writes it: a theorem object in no registry."""
    n, m, q = t.dims("n m q")
    A, B, C = t.data("A", n, n), t.data("B", n, m), t.data("C", q, n)
    P = t.symmetric("P", n, pd=True)
    gamma = t.scalar("gamma", sign="positive")
    t.lmi("brl", block([[A.T * P + P * A, P * B, C.T], [STAR, -gamma * I(m), 0], [STAR, STAR, -gamma * I(q)]]) < 0)
    t.minimize(gamma)


@theorem(
    id="test.inline_discrete_bounded_real", title="Discrete-time bounded-real lemma", citation="de Souza & Xie (1992)"
)
def inline_dbrl(t):
    """The discrete-time bounded-real lemma as a newcomer writes it (D = 0), in no registry."""
    n, m, q = t.dims("n m q")
    A, B, C = t.data("A", n, n), t.data("B", n, m), t.data("C", q, n)
    P = t.symmetric("P", n, pd=True)
    gamma = t.scalar("gamma", sign="positive")
    t.lmi(
        "dbrl",
        block([[A.T * P * A - P, A.T * P * B, C.T], [STAR, B.T * P * B - gamma * I(m), 0], [STAR, STAR, -gamma * I(q)]])
        < 0,
    )
    t.minimize(gamma)
