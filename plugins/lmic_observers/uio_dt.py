"""Delshad & Gustafsson (ECC 2014), thesis Paper C: unknown-input observers for DT Lipschitz systems.

Source: S. S. Delshad and T. Gustafsson, *Observer design for a class of nonlinear systems
subject to unknown inputs*, ECC 2014 (thesis Paper C).

System (1): ``x(k+1) = A x + B u + D f(x) + D1 mu``, ``y = C x``, ``f`` Lipschitz with constant
``gamma`` (``f: R^n -> R^q``, ``mu`` the unknown input, ``h`` columns of ``D1``). Observer (3):
``z(k+1) = N z + G u + L y + M D f(x^)``, ``x^ = z - E y`` with ``M = I + E C``; under (6)
``G = M B``, ``M D1 = 0``, ``N M = M A - L C`` the error obeys ``e(k+1) = N e + M D df`` (7).

Pre-processing (19), computed as data-derived constants: ``U = -D1 (C D1)^+`` and the exact
orthogonal projector ``V = I - (C D1)(C D1)^+`` (SVD basis of the left null space of ``C D1``,
not ``I - X pinv(X)``), so that ``E = U + Y V`` solves ``E C D1 = -D1`` (16) for every ``Y``.
This requires ``rank(C D1) = rank(D1)`` (checked when the constants are computed).

Gains (22)/(27): ``Y = P^-1 Ybar``, ``K = P^-1 Kbar``, ``E = U + Y V``, ``M = I + E C``,
``N = M A - K C``, ``L = K (I + C E) - M A E``, ``G = M B``.

Reference values (checked by ``lmic reproduce``): Thm 3.2 on the flexible-joint robot with
gamma = 1 is feasible; the published (P, Y, K) certify (9)/(20) with max eig -0.2445; the
spectral radius of the recovered N is 0.954; Thm 4.1 gamma_max = 51.5 is a supremum that is not
attained (P unbounded): it is found by bisection on Thm 3.2 feasibility (or on the ``gamma``
parameter of Thm 4.1), while a direct ``min rho`` stops early in a solver-dependent place.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import sympy

from lmic.template import (
    STAR,
    Block,
    I,
    Template,
    block,
    lambda_max,
    less_than,
    negative_definite,
    norm2,
    schur_stable,
    theorem,
)
from lmic.template.numeric import null_projector, pinv, rank

CITATION = (
    "Delshad & Gustafsson, 'Observer design for a class of nonlinear systems subject to unknown "
    "inputs', ECC 2014 (Delshad PhD thesis, Lulea, Paper C)"
)
SYSTEM_CLASS = "discrete time, Lipschitz nonlinearity D f(x), unknown input D1 mu, y = C x"


def _cd1(values: Mapping[str, Any]) -> np.ndarray:
    C, D1 = values["C"], values["D1"]
    CD1 = C @ D1
    r_cd1, r_d1 = rank(CD1), rank(D1)
    if r_cd1 != r_d1:
        raise ValueError(
            f"rank(C D1) = {r_cd1} differs from rank(D1) = {r_d1}: E C D1 = -D1 (16) has no "
            "solution (the unknown input cannot be decoupled)"
        )
    return CD1


def _U(values: Mapping[str, Any]) -> np.ndarray:
    """``U = -D1 (C D1)^+`` (19)."""
    return -values["D1"] @ pinv(_cd1(values))


def _V(values: Mapping[str, Any]) -> np.ndarray:
    """``V = I - (C D1)(C D1)^+`` (19), an exact orthogonal projector."""
    return null_projector(_cd1(values))


def _uio_data(t: Template) -> tuple[tuple[sympy.Symbol, ...], tuple[sympy.MatrixExpr, ...], tuple[Any, Any]]:
    """Dimensions, data and the constants U, V shared by Theorems 3.2 and 4.1."""
    n, m, p, q, h = t.dims("n m p q h")
    A = t.data("A", n, n, doc="state matrix")
    B = t.data("B", n, m, doc="known-input matrix")
    C = t.data("C", p, n, doc="output matrix")
    D = t.data("D", n, q, doc="nonlinearity input matrix (f: R^n -> R^q)")
    D1 = t.data("D1", n, h, doc="unknown-input matrix")
    U = t.const("U", _U, shape=(n, p), doc="U = -D1 (C D1)^+ (19)")
    V = t.const("V", _V, shape=(p, p), doc="V = I - (C D1)(C D1)^+ (19), exact projector")
    return (n, p, q), (A, B, C, D, D1), (U, V)


def _deltas(
    A: Any, C: Any, D: Any, U: Any, V: Any, P: Any, Ybar: Any, Kbar: Any
) -> tuple[sympy.MatrixExpr, sympy.MatrixExpr]:
    """``delta13 = N^T P`` and ``delta23 = (M D)^T P`` in the new variables (21)/(26)."""
    d13 = A.T * P + (U * C * A).T * P + (V * C * A).T * Ybar.T - C.T * Kbar.T
    d23 = D.T * P + (U * C * D).T * P + (V * C * D).T * Ybar.T
    return d13, d23


def _gains(
    t: Template,
    n: sympy.Symbol,
    p: sympy.Symbol,
    mats: tuple[Any, ...],
    consts: tuple[Any, Any],
    P: sympy.MatrixExpr,
    Ybar: sympy.MatrixExpr,
    Kbar: sympy.MatrixExpr,
) -> tuple[sympy.MatrixExpr, sympy.MatrixExpr]:
    """Back-substitution (22)/(27); returns the symbols of N and M."""
    A, B, C, D, D1 = mats
    U, V = consts
    # fixes=: the audit variants fixed_Y / fixed_K take printed Y, K as data (Ybar = P Y, Kbar = P K)
    Y = t.derive("Y", P.inv() * Ybar, doc="Y = P^-1 Ybar", fixes=Ybar)
    K = t.derive("K", P.inv() * Kbar, doc="K = P^-1 Kbar", fixes=Kbar)
    E = t.derive("E", U + Y * V, doc="E = U + Y V (18)")
    M = t.derive("M", I(n) + E * C, doc="M = I + E C")
    N = t.derive("N", M * A - K * C, doc="N = M A - K C")
    t.derive("L", K * (I(p) + C * E) - M * A * E, doc="L = K (I + C E) - M A E")
    t.derive("G", M * B, doc="G = M B")
    t.derive("lambda_max_P", lambda_max(P), doc="largest eigenvalue of P (grows without bound near a sup)")
    t.observer("uio", "discrete", A=A, B=B, C=C, D1=D1, N=N, M=M, E=E, L="L", G="G")
    t.check("N Schur stable (error dynamics (7))", schur_stable(N))
    t.check("M D1 = 0 (6)", less_than(norm2(M * D1), 1e-6))
    return N, M


def _nine(n: Any, q: Any, P: Any, N: Any, M: Any, D: Any, gamma_sq: Any) -> Block:
    """Inequality (9) written with N, M, P: ``[-P + g^2 I, 0, N^T P; *, -I, D^T M^T P; *, *, -P]``."""
    return block(
        [
            [-P + gamma_sq * I(n), 0, N.T * P],
            [STAR, -I(q), D.T * M.T * P],
            [STAR, STAR, -P],
        ]
    )


@theorem(
    id="uio_dt.thm3_1",
    title="DT unknown-input observer: analysis inequality (9) in P for given N, M",
    citation=CITATION + ", Theorem 3.1, inequality (9)",
    kind="A",
    objective="feasibility (P certifies the given observer N, M)",
    system_class=SYSTEM_CLASS,
    notes="Bilinear in (N, M, P); an LMI in P once N and M are given. The proof's eq (15) has a "
    "sign typo (-P^-1) that does not affect (9).",
)
def uio_dt_thm3_1(t: Template) -> None:
    """Theorem 3.1 (Section 3), inequality (9).

    ``[-P + gamma^2 I, 0, N^T P; *, -I_q, D^T M^T P; *, *, -P] < 0`` with ``P > 0`` (the
    ``-P`` diagonal blocks already imply it). It is ``N^T P N - P + gamma^2 I + ... < 0`` of
    (14) after a Schur complement: the error ``e(k+1) = N e + M D df`` is then asymptotically
    stable. Printed with ``P N``, ``P M D`` in the last block row; the upper triangle written
    here is their transpose.

    Example: the flexible-joint robot of Paper C with N, M recomputed by (22) from the printed
    Y, K, gamma = 1: feasible (the published P certifies it, max eig -0.2445); largest gamma
    with P free 3.72.
    """
    n, q = t.dims("n q")
    N = t.data("N", n, n, doc="observer matrix N (given)")
    M = t.data("M", n, n, doc="M = I + E C (given)")
    D = t.data("D", n, q, doc="nonlinearity input matrix")
    gamma = t.param("gamma", domain="nonnegative", doc="Lipschitz constant of f")
    P = t.symmetric("P", n, pd=True)
    t.lmi("(9)", _nine(n, q, P, N, M, D, gamma**2) < 0)
    t.check("N Schur stable (error dynamics (7))", schur_stable(N))
    t.observer("filter_error", "discrete", N=N)


@theorem(
    id="uio_dt.thm3_2",
    title="DT unknown-input observer synthesis LMI (20)-(21)",
    citation=CITATION + ", Theorem 3.2, LMI (20)-(21), gains (22)",
    kind="S",
    objective="feasibility; Y = P^-1 Ybar, K = P^-1 Kbar, gains E, M, N, L, G by (22)",
    system_class=SYSTEM_CLASS,
    notes="U, V of (19) are exact (SVD) projectors. The printed text calls the variables "
    "'Ybar and P'; Kbar is a decision variable too (it appears in delta13 and K = P^-1 Kbar). "
    "Thesis Thm 4.1.3 is the same LMI.",
)
def uio_dt_thm3_2(t: Template) -> None:
    """Theorem 3.2 (Section 3), LMI (20)-(21), gains (22).

    ``[-P + gamma^2 I, 0, d13; *, -I_q, d23; *, *, -P] < 0`` with
    ``d13 = A^T P + (U C A)^T P + (V C A)^T Ybar^T - C^T Kbar^T`` (``= N^T P``) and
    ``d23 = D^T P + (U C D)^T P + (V C D)^T Ybar^T`` (``= (M D)^T P``); ``-P`` on the diagonal
    implies ``P > 0``. The certificate also evaluates (9) at the recovered N, M and P (what
    Theorem 3.1 claims), the Schur stability of N and ``M D1 = 0``.

    Example (31)-(33): flexible-joint robot, Euler ts = 12 ms, f = sin(x3), gamma = 1 (not
    printed; the Lipschitz constant of sin). Feasible; published P, Y, K give max eig -0.2445.
    """
    (n, p, q), mats, consts = _uio_data(t)
    A, B, C, D, D1 = mats
    U, V = consts
    gamma = t.param("gamma", domain="nonnegative", doc="Lipschitz constant of f")
    P = t.symmetric("P", n)
    Ybar = t.full("Ybar", n, p)
    Kbar = t.full("Kbar", n, p)
    d13, d23 = _deltas(A, C, D, U, V, P, Ybar, Kbar)
    t.lmi(
        "(20)",
        block([[-P + gamma**2 * I(n), 0, d13], [STAR, -I(q), d23], [STAR, STAR, -P]]) < 0,
    )
    N, M = _gains(t, n, p, mats, consts, P, Ybar, Kbar)
    t.check("(9) at the recovered N, M, P", negative_definite(_nine(n, q, P, N, M, D, gamma**2)))


@theorem(
    id="uio_dt.thm4_1",
    title="DT unknown-input observer with maximal Lipschitz constant, LMI (25)",
    citation=CITATION + ", Theorem 4.1, LMI (25)-(28), Table 2",
    kind="S",
    objective="min rho; gamma_max = 1/sqrt(rho) (28); gains by (27)",
    system_class=SYSTEM_CLASS,
    notes="The infimum of rho is in general not attained (P unbounded): a direct min rho stops "
    "early at a solver-dependent point (Clarabel ~11, SCS ~5-7 on the example, against the "
    "supremum 51.5). Get the supremum by bisection on feasibility: the optional parameter gamma "
    "adds rho <= 1/gamma^2 (gamma_max >= gamma), so 'feasible at gamma' is exactly Theorem 3.2 "
    "at gamma; gamma = 0 (default) leaves rho free.",
)
def uio_dt_thm4_1(t: Template) -> None:
    """Theorem 4.1 (Section 4), LMI (25)-(26), gamma_max (28), gains (27).

    ``min rho`` subject to ``[-P, 0, d13, I; *, -I_q, d23, 0; *, *, -P, 0; *, *, *, -rho I] < 0``
    (block sizes n, q, n, n) with ``d13``, ``d23`` as in Theorem 3.2. The Schur complement of
    the ``-rho I`` block gives (20) with ``gamma^2 = 1/rho`` (29), so ``gamma_max = 1/sqrt(rho)``.

    Addition for bisection (not in the paper): parameter ``gamma`` (default 0) adds the linear
    constraint ``gamma^2 rho <= 1``; the problem is feasible at ``gamma > 0`` exactly when
    Theorem 3.2 is. Table 2 (flexible-joint robot): gamma_max = 51.5, reproduced by bisection
    (51.499); other entries of Table 2 (0.99, 48.5) are other authors' methods.
    """
    (n, p, q), mats, consts = _uio_data(t)
    A, B, C, D, D1 = mats
    U, V = consts
    gamma = t.param(
        "gamma",
        default=0.0,
        domain="nonnegative",
        doc="required Lipschitz constant: adds rho <= 1/gamma^2 (0 = none); for bisection",
    )
    P = t.symmetric("P", n)
    Ybar = t.full("Ybar", n, p)
    Kbar = t.full("Kbar", n, p)
    rho = t.scalar("rho", sign="positive", doc="rho = 1/gamma^2 (29)")
    d13, d23 = _deltas(A, C, D, U, V, P, Ybar, Kbar)
    t.lmi(
        "(25)",
        block(
            [
                [-P, 0, d13, I(n)],
                [STAR, -I(q), d23, 0],
                [STAR, STAR, -P, 0],
                [STAR, STAR, STAR, -rho * I(n)],
            ]
        )
        < 0,
    )
    t.constraint("gamma^2 rho <= 1", gamma**2 * rho <= 1)
    t.minimize(rho)
    g = t.derive("gamma_max", 1 / sympy.sqrt(rho), doc="gamma_max = sqrt(1/rho) (28)")
    N, M = _gains(t, n, p, mats, consts, P, Ybar, Kbar)
    t.check(
        "(9) at the recovered N, M, P with gamma = gamma_max",
        negative_definite(_nine(n, q, P, N, M, D, g**2)),
    )


THEOREMS = [uio_dt_thm3_1, uio_dt_thm3_2, uio_dt_thm4_1]
