"""Delshad, PhD thesis (Lulea), Part I: Lyapunov, Lipschitz and unknown-input observer LMIs.

Source: S. S. Delshad, *Observer design for Lipschitz nonlinear systems*, PhD thesis, Lulea
University of Technology, Part I chapters 2-4 (eq. (2.9), Sections 3.2 and 4.1.2).

Families of results here:

* ``thesis.lyapunov`` -- Lyapunov LMI (2.9)/(2.14);
* ``thesis.thm3_2_1``, ``thesis.thm3_2_2``, ``thesis.cor3_19`` -- Luenberger observers for
  linear / Lipschitz / matrix-Lipschitz continuous-time plants, ``L = P^-1 Lbar``;
* ``thesis.thm4_1_2``, ``thesis.thm4_1_2_linear``, ``thesis.thm4_1_3`` -- full-order
  unknown-input observers with the ``U, V`` parametrisation ``E = U + Y V``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import sympy

from lmic.errors import DataError
from lmic.template import STAR, I, Template, block, hurwitz, negative_definite, schur_stable, theorem
from lmic.template.checks import less_than
from lmic.template.numeric import null_projector, pinv, rank
from lmic.template.totree import norm2

__all__ = [
    "thesis_lyapunov",
    "thesis_thm3_2_1",
    "thesis_thm3_2_2",
    "thesis_cor3_19",
    "thesis_thm4_1_2",
    "thesis_thm4_1_2_linear",
    "thesis_thm4_1_3",
    "THEOREMS",
]

#: relative bound of the structural check ``M D = 0`` (exact in exact arithmetic)
_DECOUPLING_TOL = 1e-8


@theorem(
    id="thesis.lyapunov",
    title="Lyapunov stability LMI (2.9)",
    citation="Delshad, PhD thesis (Lulea), Part I, eq. (2.9)/(2.14), Example 2.3.2",
    kind="A",
    objective="feasibility (P certifies stability of A)",
    system_class="continuous time, linear",
    notes="The example (2.14) uses the non-strict A^T P + P A <= 0; choose it with nonstrict: 1.",
)
def thesis_lyapunov(t: Template) -> None:
    """Thesis eq. (2.9): ``P > 0``, ``A^T P + P A < 0`` (or ``<= 0`` with ``nonstrict = 1``)."""
    (n,) = t.dims("n")
    A = t.data("A", n, n, doc="state matrix")
    nonstrict = t.flag("nonstrict", doc="1 for the non-strict A^T P + P A <= 0 of (2.14)")
    P = t.symmetric("P", n, pd=True)
    lyap = A.T * P + P * A
    if nonstrict:
        t.lmi("(2.14)", lyap <= 0)
    else:
        t.lmi("(2.9)", lyap < 0)
    t.check("A Hurwitz", hurwitz(A))


# -- chapter 3: Luenberger observers, L = P^-1 Lbar ----------------------------------------


def _luenberger_data(t: Template) -> tuple[sympy.Symbol, sympy.Symbol, sympy.MatrixExpr, sympy.MatrixExpr]:
    """Dimensions and data shared by Theorem 3.2.1, Theorem 3.2.2 and Corollary (3.19)."""
    n, m, p = t.dims("n m p")
    A = t.data("A", n, n, doc="state matrix")
    t.data("B", n, m, doc="input matrix (enters the observer, not the LMI)")
    C = t.data("C", p, n, doc="output matrix")
    return n, p, A, C


@theorem(
    id="thesis.thm3_2_1",
    title="Luenberger observer LMI (3.11)",
    citation="Delshad, PhD thesis (Lulea), Part I, Theorem 3.2.1, LMI (3.11), Example 3.2.1",
    kind="S",
    objective="feasibility; L = P^-1 Lbar",
    system_class="continuous time, linear",
    notes="The example's plant is that of Example 1.1.1 (the text says 'Example 1.2.1'). "
    "The statement says 'matrices L and P'; the LMI variable is Lbar = P L.",
)
def thesis_thm3_2_1(t: Template) -> None:
    """Thesis Theorem 3.2.1 (Section 3.2.1, linear case), LMI (3.11).

    ``P > 0``, ``A^T P + P A - C^T Lbar^T - Lbar C < 0``; the observer gain is
    ``L = P^-1 Lbar``. The check restates the original inequality (3.9),
    ``(A - L C)^T P + P (A - L C) < 0``, with the back-substituted gain.
    """
    n, p, A, C = _luenberger_data(t)
    P = t.symmetric("P", n, pd=True)
    Lbar = t.full("Lbar", n, p)
    t.lmi("(3.11)", A.T * P + P * A - C.T * Lbar.T - Lbar * C < 0)
    L = t.luenberger(A, C, L=P.inv() * Lbar, time="continuous", fixes=Lbar, B="B", doc="L = P^-1 Lbar")
    Acl = A - L * C
    t.check("(3.9)", negative_definite(Acl.T * P + P * Acl), doc="original inequality")


@theorem(
    id="thesis.thm3_2_2",
    title="Lipschitz observer LMI (3.14), scalar Lipschitz constant gamma",
    citation="Delshad, PhD thesis (Lulea), Part I, Theorem 3.2.2, LMI (3.14), Example 3.2.2",
    kind="S",
    objective="feasibility for a given gamma; L = P^-1 Lbar (sup gamma by bisection)",
    system_class="continuous time, globally Lipschitz f: R^n -> R^n (constant gamma)",
    notes="The statement says 'matrices L and P'; the LMI variable is Lbar = P L. "
    "Example 3.2.2: infeasible at gamma = 3.33 (as the thesis says); sup gamma = 0.9997.",
)
def thesis_thm3_2_2(t: Template) -> None:
    """Thesis Theorem 3.2.2 (Section 3.2.2, nonlinear case), LMI (3.14).

    ``[A^T P + P A - C^T Lbar^T - Lbar C + gamma^2 I, P; *, -I] < 0`` with ``P > 0``;
    ``L = P^-1 Lbar``. The check restates (3.17),
    ``(A - L C)^T P + P (A - L C) + P P + gamma^2 I < 0``.
    """
    n, p, A, C = _luenberger_data(t)
    gamma = t.param("gamma", domain="nonnegative", doc="Lipschitz constant of f")
    P = t.symmetric("P", n, pd=True)
    Lbar = t.full("Lbar", n, p)
    t.lmi(
        "(3.14)",
        block(
            [
                [A.T * P + P * A - C.T * Lbar.T - Lbar * C + gamma**2 * I(n), P],
                [STAR, -1],
            ]
        )
        < 0,
    )
    L = t.luenberger(A, C, L=P.inv() * Lbar, time="continuous", fixes=Lbar, B="B", doc="L = P^-1 Lbar")
    Acl = A - L * C
    t.check(
        "(3.17)",
        negative_definite(Acl.T * P + P * Acl + P * P + gamma**2 * I(n)),
        doc="original inequality",
    )


@theorem(
    id="thesis.cor3_19",
    title="Matrix-Lipschitz observer LMI (3.19)",
    citation="Delshad, PhD thesis (Lulea), Part I, Corollary [69], LMI (3.19), Example 3.2.2",
    kind="S",
    objective="feasibility; L = P^-1 Lbar",
    system_class="continuous time, |f(x1) - f(x2)| <= |G (x1 - x2)|",
    notes="Example 3.2.2 does not print G; G = [0 0 3.33 0] is forced by f = [0,0,0,-3.33 sin x3].",
)
def thesis_cor3_19(t: Template) -> None:
    """Thesis Corollary [69] (Section 3.2.2), LMI (3.19).

    ``[A^T P + P A - C^T Lbar^T - Lbar C + G^T G, P; *, -I] < 0`` with ``P > 0``;
    ``L = P^-1 Lbar``. The check restates the pre-Schur inequality
    ``(A - L C)^T P + P (A - L C) + P P + G^T G < 0``.
    """
    n, p, A, C = _luenberger_data(t)
    (q,) = t.dims("q")
    G = t.data("G", q, n, doc="matrix Lipschitz bound |f(x1) - f(x2)| <= |G (x1 - x2)|")
    P = t.symmetric("P", n, pd=True)
    Lbar = t.full("Lbar", n, p)
    t.lmi("(3.19)", block([[A.T * P + P * A - C.T * Lbar.T - Lbar * C + G.T * G, P], [STAR, -1]]) < 0)
    L = t.luenberger(A, C, L=P.inv() * Lbar, time="continuous", fixes=Lbar, B="B", doc="L = P^-1 Lbar")
    Acl = A - L * C
    t.check(
        "(3.19) before the Schur complement",
        negative_definite(Acl.T * P + P * Acl + P * P + G.T * G),
        doc="original inequality",
    )


# -- chapter 4: unknown-input observers, E = U + Y V ----------------------------------------


def _uio_constants(
    t: Template, n: sympy.Symbol, p: sympy.Symbol, C: sympy.MatrixExpr, Dui: sympy.MatrixExpr, key: str
) -> tuple[sympy.MatrixExpr, sympy.MatrixExpr]:
    """``U = -Dui (C Dui)^+`` and the exact projector ``V = I - (C Dui)(C Dui)^+`` (4.23).

    ``Dui`` is the unknown-input matrix (``key`` its data name). ``C Dui`` must have full column
    rank: otherwise no ``E`` gives ``M Dui = 0`` and the unknown input is not decoupled.
    """
    tid = t.theorem_id

    def u_fn(v: Mapping[str, Any]) -> np.ndarray:
        CD = v["C"] @ v[key]
        h = CD.shape[1]
        if rank(CD) < h:
            raise DataError(
                f"theorem {tid}: data '{key}': C {key} must have full column rank {h} "
                f"(rank {rank(CD)}), else M {key} = 0 has no solution"
            )
        return -v[key] @ pinv(CD)

    U = t.const("U", u_fn, shape=(n, p), doc=f"U = -{key} (C {key})^+ (4.23)")
    V = t.const(
        "V",
        lambda v: null_projector(v["C"] @ v[key]),
        shape=(p, p),
        doc=f"V = I - (C {key})(C {key})^+ (4.23), exact projector from an SVD basis",
    )
    return U, V


def _uio_gains(
    t: Template,
    n: sympy.Symbol,
    p: sympy.Symbol,
    A: sympy.MatrixExpr,
    B: sympy.MatrixExpr,
    C: sympy.MatrixExpr,
    P: sympy.MatrixExpr,
    Ybar: sympy.MatrixExpr,
    Kbar: sympy.MatrixExpr,
    U: sympy.MatrixExpr,
    V: sympy.MatrixExpr,
) -> tuple[sympy.MatrixExpr, sympy.MatrixExpr]:
    """Back-substitution (4.26)/(4.36): ``Y, K, E, M, N, L, G``."""
    # fixes=: the audit variants fixed_Y / fixed_K take printed Y, K as data (Ybar = P Y, Kbar = P K)
    Y = t.derive("Y", P.inv() * Ybar, doc="Y = P^-1 Ybar", fixes=Ybar)
    K = t.derive("K", P.inv() * Kbar, doc="K = P^-1 Kbar", fixes=Kbar)
    E = t.derive("E", U + Y * V, doc="E = U + Y V")
    M = t.derive("M", I(n) + E * C, doc="M = I + E C")
    N = t.derive("N", M * A - K * C, doc="N = M A - K C")
    t.derive("L", K * (I(p) + C * E) - M * A * E, doc="L = K (I + C E) - M A E")
    t.derive("G", M * B, doc="G = M B")
    return M, N


def _decoupling_check(t: Template, M: sympy.MatrixExpr, Dui: sympy.MatrixExpr, key: str) -> None:
    """``M Dui = 0`` (structural: holds exactly when ``C Dui`` has full column rank)."""
    t.check(
        f"M {key} = 0",
        less_than(norm2(M * Dui) / norm2(Dui), _DECOUPLING_TOL),
        doc="the unknown input is decoupled (relative to |{key}|)",
    )


def _ct_uio(t: Template, nonlinear: bool) -> None:
    n, m, p, h = t.dims("n m p h")
    A = t.data("A", n, n, doc="state matrix")
    B = t.data("B", n, m, doc="known-input matrix (G = M B)")
    C = t.data("C", p, n, doc="output matrix")
    D = t.data("D", n, h, doc="unknown-input matrix (x' = A x + B u + f(x) + D nu)")
    gamma = t.param("gamma", domain="nonnegative", doc="Lipschitz constant of f") if nonlinear else 0
    U, V = _uio_constants(t, n, p, C, D, "D")
    P = t.symmetric("P", n, pd=True)
    Ybar = t.full("Ybar", n, p)
    Kbar = t.full("Kbar", n, p)
    UCA = (I(n) + U * C) * A
    d11 = UCA.T * P + P * UCA + (V * C * A).T * Ybar.T + Ybar * (V * C * A) - C.T * Kbar.T - Kbar * C
    if nonlinear:
        d12 = P * (I(n) + U * C) + Ybar * (V * C)
        t.lmi("(4.24)", block([[d11 + gamma**2 * I(n), d12], [STAR, -1]]) < 0)
    else:
        t.lmi("(4.28)", block(d11) < 0)
    M, N = _uio_gains(t, n, p, A, B, C, P, Ybar, Kbar, U, V)
    t.observer("uio", "continuous", A=A, B=B, C=C, D1=D, N=N, M=M, E="E", L="L", G="G")
    if nonlinear:
        t.check(
            "(4.18)",
            negative_definite(N.T * P + P * N + P * M * M.T * P + gamma**2 * I(n)),
            doc="original inequality N^T P + P N + P M M^T P + gamma^2 I < 0",
        )
    else:
        t.check("N^T P + P N < 0", negative_definite(N.T * P + P * N), doc="original inequality")
    t.check("N Hurwitz", hurwitz(N))
    _decoupling_check(t, M, D, "D")


@theorem(
    id="thesis.thm4_1_2",
    title="Continuous-time unknown-input observer LMI (4.24)",
    citation="Delshad, PhD thesis (Lulea), Part I, Theorem 4.1.2, LMI (4.24)-(4.26)",
    kind="S",
    objective="feasibility for a given gamma; gains E, M, N, L, G from Y = P^-1 Ybar, K = P^-1 Kbar",
    system_class="continuous time, Lipschitz f: R^n -> R^n, unknown input D nu",
    notes="The statement lists Ybar and P only; Kbar is a decision variable too. P > 0 is added "
    "explicitly. U, V of (4.23) use the Moore-Penrose inverse and an exact SVD projector.",
)
def thesis_thm4_1_2(t: Template) -> None:
    """Thesis Theorem 4.1.2 (Section 4.1.2, unknown inputs issue), LMI (4.24)-(4.25).

    ``[d11, d12; *, -I] < 0`` with
    ``d11 = ((I+UC)A)^T P + P (I+UC)A + (VCA)^T Ybar^T + Ybar (VCA) - C^T Kbar^T - Kbar C + gamma^2 I``,
    ``d12 = P (I+UC) + Ybar (VC)``, ``U = -D (CD)^+``, ``V = I - (CD)(CD)^+`` (4.23).
    Gains (4.26): ``Y = P^-1 Ybar``, ``K = P^-1 Kbar``, ``E = U + Y V``, ``M = I + E C``,
    ``N = M A - K C``, ``L = K (I + C E) - M A E``, ``G = M B``. Checks: the original (4.18)
    ``N^T P + P N + P M M^T P + gamma^2 I < 0``, ``N`` Hurwitz, ``M D = 0``.
    """
    _ct_uio(t, nonlinear=True)


@theorem(
    id="thesis.thm4_1_2_linear",
    title="Continuous-time unknown-input observer, linear case LMI (4.28)",
    citation="Delshad, PhD thesis (Lulea), Part I, Theorem 4.1.2 / Remark eq. (4.28), Example 4.1.3",
    kind="S",
    objective="feasibility; gains E, M, N, L, G from Y = P^-1 Ybar, K = P^-1 Kbar",
    system_class="continuous time, linear, unknown input D nu",
    notes="Typo: (4.28) prints (VCA)^T Ybar and C^T Kbar; dimensions force Ybar^T and Kbar^T "
    "(the transposes are restored). Example 4.1.3 does not print D; D = e1 is forced by U, V.",
)
def thesis_thm4_1_2_linear(t: Template) -> None:
    """Thesis Remark after Theorem 4.1.2 (Section 4.1.2), LMI (4.28), f = 0.

    ``((I+UC)A)^T P + P (I+UC)A + (VCA)^T Ybar^T + Ybar (VCA) - C^T Kbar^T - Kbar C < 0`` and
    ``P > 0``; gains as (4.26). Typo resolution: the printed ``(VCA)^T Ybar`` and ``C^T Kbar``
    are dimensionally impossible (``Ybar``, ``Kbar`` are ``n x p``) and read ``(VCA)^T Ybar^T``,
    ``C^T Kbar^T``, the symmetric counterparts of ``Ybar (VCA)`` and ``Kbar C``. Checks: the
    original ``N^T P + P N < 0``, ``N`` Hurwitz, ``M D = 0``.
    """
    _ct_uio(t, nonlinear=False)


@theorem(
    id="thesis.thm4_1_3",
    title="Discrete-time unknown-input observer LMI (4.34)",
    citation="Delshad, PhD thesis (Lulea), Part I, Theorem 4.1.3, LMI (4.34)-(4.36), Example 4.1.4",
    kind="S",
    objective="feasibility for a given gamma; gains E, M, N, L, G from Y = P^-1 Ybar, K = P^-1 Kbar",
    system_class="discrete time, Lipschitz f: R^n -> R^q entering through D, unknown input D1 nu",
    notes="Same as Paper C Theorem 3.2. U, V are built from D1 (the unknown-input matrix). "
    "Example 4.1.4 prints U with a spurious transpose. With D = D1 the LMI is feasible for every gamma.",
)
def thesis_thm4_1_3(t: Template) -> None:
    """Thesis Theorem 4.1.3 (Section 4.1.2), LMI (4.34)-(4.35) (= Paper C Theorem 3.2).

    ``[-P + gamma^2 I, 0, d13; *, -I_q, d23; *, *, -P] < 0`` with
    ``d13 = A^T P + (UCA)^T P + (VCA)^T Ybar^T - C^T Kbar^T`` (``= N^T P``) and
    ``d23 = D^T P + (UCD)^T P + (VCD)^T Ybar^T`` (``= (M D)^T P``), ``U = -D1 (C D1)^+``,
    ``V = I - (C D1)(C D1)^+``. Gains (4.36) as in Theorem 4.1.2. Checks: the original
    inequality (Paper C (14)) ``[N^T P N - P + gamma^2 I, N^T P M D; *, -I + (MD)^T P M D] < 0``,
    ``N`` Schur stable, ``M D1 = 0``.
    """
    n, m, p, q, h = t.dims("n m p q h")
    A = t.data("A", n, n, doc="state matrix")
    B = t.data("B", n, m, doc="known-input matrix (G = M B)")
    C = t.data("C", p, n, doc="output matrix")
    D = t.data("D", n, q, doc="nonlinearity input matrix (x+ = A x + B u + D f(x) + D1 nu)")
    D1 = t.data("D1", n, h, doc="unknown-input matrix")
    gamma = t.param("gamma", domain="nonnegative", doc="Lipschitz constant of f")
    U, V = _uio_constants(t, n, p, C, D1, "D1")
    P = t.symmetric("P", n)
    Ybar = t.full("Ybar", n, p)
    Kbar = t.full("Kbar", n, p)
    d13 = A.T * P + (U * C * A).T * P + (V * C * A).T * Ybar.T - C.T * Kbar.T
    d23 = D.T * P + (U * C * D).T * P + (V * C * D).T * Ybar.T
    t.lmi(
        "(4.34)",
        block(
            [
                [-P + gamma**2 * I(n), 0, d13],
                [STAR, -1, d23],
                [STAR, STAR, -P],
            ]
        )
        < 0,
    )
    M, N = _uio_gains(t, n, p, A, B, C, P, Ybar, Kbar, U, V)
    t.observer("uio", "discrete", A=A, B=B, C=C, D1=D1, N=N, M=M, E="E", L="L", G="G")
    MD = M * D
    t.check(
        "Paper C (14)",
        negative_definite(
            block(
                [
                    [N.T * P * N - P + gamma**2 * I(n), N.T * P * MD],
                    [STAR, -I(q) + MD.T * P * MD],
                ]
            )
        ),
        doc="original inequality",
    )
    t.check("N Schur stable", schur_stable(N))
    _decoupling_check(t, M, D1, "D1")


THEOREMS = [
    thesis_lyapunov,
    thesis_thm3_2_1,
    thesis_thm3_2_2,
    thesis_cor3_19,
    thesis_thm4_1_2,
    thesis_thm4_1_2_linear,
    thesis_thm4_1_3,
]
