"""Abbaszadeh & Marquez (2008): robust H-infinity filtering for DT nonlinear uncertain systems.

Source: M. Abbaszadeh, H. J. Marquez, *LMI optimization approach to robust H-infinity filtering
for discrete-time nonlinear uncertain systems*, ACC 2008 (version of IJRNC 2009).

System ``x(k+1) = (A + dA) x + Phi(x, u) + B w``, ``y = (C + dC) x + D w``, ``Phi`` Lipschitz
(constant gamma), ``[dA; dC] = [M1; M2] F N`` with ``F^T F <= I``; observer
``x^(k+1) = A x^ + Phi(x^, u) + L (y - C x^)``, ``z = H e``, ``||z|| <= mu ||w||``, decay rate
beta. Dimensions: n states, p outputs, nw disturbances, F is r x s (M1: n x r, M2: p x r,
N: s x n), H is nz x n. Every inequality of the paper is strict.

Fixed gains (audits): with ``fixed_L: 1`` the gain ``L`` is data and ``G = P1 L`` is
substituted, so the LMIs are in ``(P1, P2, alpha, eps1, eps2)`` only.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import sympy

from lmic.errors import DataError
from lmic.template import STAR, I, Template, block, schur_stable, theorem

__all__ = ["THEOREMS", "vec_embedding"]

CITATION = (
    "Abbaszadeh & Marquez (2008), LMI optimization approach to robust H-infinity filtering for "
    "discrete-time nonlinear uncertain systems, ACC 2008"
)


@theorem(
    id="uncertain_dt.lemma3",
    title="Robust stability and L2 gain of a DT Lipschitz uncertain system, LMIs (15)-(16)",
    citation=CITATION + ", Lemma 3",
    kind="A",
    objective="min alpha + eps1; gamma* = 1/sqrt(alpha (1 + eps1))",
    system_class="discrete time, Lipschitz, norm-bounded uncertainty (analysis of a plant)",
    notes="Block sizes (15): n, n, n, n, r; (16): nw, n, n. Checked against the proof.",
)
def uncertain_dt_lemma3(t: Template) -> None:
    """Lemma 3 (Section III, H-infinity synthesis): for ``x(k+1) = (A + M1 F N) x + Phi + B w``, ``z = H x``,

    ``(15) [Lambda1, I, A^T P, 0, 0; *, -alpha I, 0, 0, 0; *, *, -P/2, P, P M1;
    *, *, *, P - 2 eps1 I, 0; *, *, *, *, -eps2 I] < 0``, ``Lambda1 = H^T H - P + eps2 N^T N``,

    ``(16) [-mu^2 I, B^T P, B^T P; *, -P/2, 0; *, *, -I] < 0``, ``P > 0``, scalars > 0;
    ``min alpha + eps1``, ``gamma* = 1/sqrt(alpha* (1 + eps1*))`` (22).

    Checked against the proof: the Schur complement of rows 3-5 of (15) is the last
    inequality of the proof; (16) gives ``-mu^2 + 2 B^T P B + B^T P P B < 0``.
    Reference (Sec. V plant, mu = 1.25, Clarabel): alpha = 65.57, eps1 = 12.68, gamma* = 0.0334.
    """
    n, nw, nz, r, s = t.dims("n nw nz r s")
    A = t.data("A", n, n, doc="state matrix")
    B = t.data("B", n, nw, doc="disturbance matrix")
    H = t.data("H", nz, n, doc="performance output z = H x")
    M1 = t.data("M1", n, r, doc="uncertainty dA = M1 F N")
    N = t.data("N", s, n, doc="uncertainty dA = M1 F N")
    mu = t.param("mu", domain="positive", doc="L2 gain bound mu")
    P = t.symmetric("P", n, pd=True)
    alpha = t.scalar("alpha", sign="positive")
    eps1 = t.scalar("eps1", sign="positive")
    eps2 = t.scalar("eps2", sign="positive")
    Lambda1 = H.T * H - P + eps2 * N.T * N
    t.lmi(
        "(15)",
        block(
            [
                [Lambda1, I(n), A.T * P, 0, 0],
                [STAR, -alpha, 0, 0, 0],
                [STAR, STAR, -P / 2, P, P * M1],
                [STAR, STAR, STAR, P - 2 * eps1 * I(n), 0],
                [STAR, STAR, STAR, STAR, -eps2 * I(r)],
            ]
        )
        < 0,
    )
    t.lmi("(16)", block([[-(mu**2) * I(nw), B.T * P, B.T * P], [STAR, -P / 2, 0], [STAR, STAR, -1]]) < 0)
    t.minimize(alpha + eps1)
    t.derive("gamma_star", 1 / sympy.sqrt(alpha * (1 + eps1)), doc="gamma* = 1/sqrt(alpha (1 + eps1)) (22)")


def _filter_data(t: Template) -> dict[str, Any]:
    """Data, parameters and gain variables shared by Theorem 1 and Corollary 1."""
    n, p, nw, nz, r, s = t.dims("n p nw nz r s")
    d = {
        "n": n,
        "p": p,
        "nw": nw,
        "r": r,
        "A": t.data("A", n, n, doc="state matrix"),
        "B": t.data("B", n, nw, doc="disturbance matrix (state)"),
        "C": t.data("C", p, n, doc="output matrix"),
        "D": t.data("D", p, nw, doc="disturbance matrix (output)"),
        "H": t.data("H", nz, n, doc="performance output z = H e"),
        "M1": t.data("M1", n, r, doc="uncertainty dA = M1 F N"),
        "M2": t.data("M2", p, r, doc="uncertainty dC = M2 F N"),
        "N": t.data("N", s, n, doc="uncertainty [dA; dC] = [M1; M2] F N"),
        "mu": t.param("mu", domain="positive", doc="L2 gain bound mu"),
        "beta": t.param("beta", domain="nonnegative", doc="decay rate beta"),
    }
    fixed = t.flag("fixed_L", doc="1: L is given as data (audit), G = P1 L")
    P1 = t.symmetric("P1", n)
    P2 = t.symmetric("P2", n)
    if fixed:
        L = t.data("L", n, p, doc="the observer gain to audit (fixed_L = 1)")
        G = P1 * L
    else:
        L = None
        G = t.full("G", n, p, doc="G = P1 L")
    d.update(P1=P1, P2=P2, G=G, L=L)
    return d


def _filter_lmis(t: Template, d: dict[str, Any], psi1_rows: list[Any], eps1: sympy.Expr, eps2: sympy.Expr) -> None:
    """``[Psi1 Omega; * Psi2] < 0`` and Xi1 (24) of Theorem 1, given Psi1's block rows.

    ``psi1_rows`` is the k x k upper triangle of Psi1 (k = 3 printed, 4 corrected) with the
    e-row first and the x-row second; Omega gets zero rows below its first two.
    """
    A, B, C, D, M1, M2 = d["A"], d["B"], d["C"], d["D"], d["M1"], d["M2"]
    P1, P2, G, n = d["P1"], d["P2"], d["G"], d["n"]
    Lambda2 = B.T * P1 - D.T * G.T
    Lambda3 = P1 * M1 - G * M2
    k = len(psi1_rows)
    omega = [[A.T * P1 - C.T * G.T, 0, 0, 0, 0], [0, A.T * P2, 0, 0, 0]] + [[0] * 5 for _ in range(k - 2)]
    psi2 = [
        [-P1 / 2, 0, P1, 0, Lambda3],
        [STAR, -P2 / 2, 0, P2, P2 * M1],
        [STAR, STAR, P1 - 2 * eps1 * I(n), 0, 0],
        [STAR, STAR, STAR, P2 - 2 * eps1 * I(n), 0],
        [STAR, STAR, STAR, STAR, -eps2 * I(d["r"])],
    ]
    rows = [list(psi1_rows[i]) + omega[i] for i in range(k)]
    rows += [[STAR] * k + psi2[i] for i in range(5)]
    t.lmi("P1 > 0", block(P1) > 0)
    t.lmi("P2 > 0", block(P2) > 0)
    t.lmi("[Psi1 Omega; * Psi2]", block(rows) < 0)
    t.lmi(
        "Xi1 (24)",
        block(
            [
                [-(d["mu"] ** 2) * I(d["nw"]), Lambda2, B.T * P2, Lambda2, B.T * P2],
                [STAR, -P1 / 2, 0, 0, 0],
                [STAR, STAR, -P2 / 2, 0, 0],
                [STAR, STAR, STAR, -1, 0],
                [STAR, STAR, STAR, STAR, -1],
            ]
        )
        < 0,
    )


def _gain_and_check(t: Template, d: dict[str, Any]) -> None:
    L = d["L"] if d["L"] is not None else t.derive("L", d["P1"].inv() * d["G"], doc="L = P1^-1 G (26)")
    t.check("A - L C Schur stable", schur_stable(d["A"] - L * d["C"]))
    t.observer(
        "robust", "discrete", A=d["A"], C=d["C"], L=L, D1=d["B"], D2=d["D"], MA=d["M1"], MC=d["M2"], NF=d["N"],
        Hz=d["H"], gamma="mu", decay="beta",
    )  # fmt: skip


@theorem(
    id="uncertain_dt.thm1",
    title="Robust H-infinity observer with decay rate and max Lipschitz constant, LMIs (23)-(24)",
    citation=CITATION + ", Theorem 1",
    kind="S",
    objective="min alpha + eps1; L = P1^-1 G, gamma* = 1/sqrt(alpha (1 + eps1))",
    system_class="discrete time, Lipschitz, norm-bounded uncertainty, disturbance",
    notes="psi1: printed (default) | corrected (alpha^-1 I on both e and x, see docstring). "
    "The published (eps1, alpha) = (0.7715, 2.9982) is infeasible; the optimum is gamma* = 0.3405.",
)
def uncertain_dt_thm1(t: Template) -> None:
    """Theorem 1 (Section III): ``min alpha + eps1`` subject to
    ``[Psi1, Omega; *, Psi2] < 0`` and ``Xi1 < 0`` (24), ``P1, P2 > 0``, scalars > 0:

    ``Psi1 = [H^T H - e^{-2 beta} P1, 0, I; *, eps2 N^T N - P2, 0; *, *, -alpha I]``,
    ``Omega = [A^T P1 - C^T G^T, 0, 0, 0, 0; 0, A^T P2, 0, 0, 0; 0, 0, 0, 0, 0]``,
    ``Psi2 = [-P1/2, 0, P1, 0, Lambda3; *, -P2/2, 0, P2, P2 M1; *, *, P1 - 2 eps1 I, 0, 0;
    *, *, *, P2 - 2 eps1 I, 0; *, *, *, *, -eps2 I]``,
    ``Xi1 = [-mu^2 I, Lambda2, B^T P2, Lambda2, B^T P2; *, -P1/2, 0, 0, 0; *, *, -P2/2, 0, 0;
    *, *, *, -I, 0; *, *, *, *, -I]``, ``Lambda2 = B^T P1 - D^T G^T``, ``Lambda3 = P1 M1 - G M2``;
    ``L = P1^-1 G`` (26), ``gamma* = 1/sqrt(alpha* (1 + eps1*))`` (28).

    Typo resolutions: the second rows of Psi1, Psi2 and Omega carry a leading alignment ``&``
    in the extraction; the star pattern fixes the positions. Every block was re-derived from
    Lemma 3 with the augmented matrices.

    ``psi1: corrected``: on the augmented state the bound ``||Phi~|| <= gamma ||xi||`` needs
    ``alpha^-1 I_2n`` (both the e and the x blocks); the printed Psi1 applies it to e only.
    The corrected Psi1 is ``[H^T H - e^{-2 beta} P1, 0, I, 0; *, eps2 N^T N - P2, 0, I;
    *, *, -alpha I, 0; *, *, *, -alpha I]`` and Omega gets a fourth zero row. The default is
    ``printed`` (the published gain supports that reading).

    Reference (``lmic reproduce``; Sec. V example, Clarabel): printed: alpha = 4.0625,
    eps1 = 1.1226, eps2 = 0.1620, gamma* = 0.3405 (published 0.4339, whose (eps1, alpha) is
    infeasible), L = [0.3522 1.0213; 0.3051 1.1676; -0.1104 1.5616]; corrected: alpha = 19.635,
    eps1 = 2.835, gamma* = 0.1152. Published L (``fixed_L: 1``): alpha = 4.150, eps1 = 1.051,
    gamma = 0.3428.
    """
    d = _filter_data(t)
    psi1 = t.option(
        "psi1", ("printed", "corrected"), "printed", doc="printed Psi1, or alpha^-1 I on both e and x (corrected)"
    )
    alpha = t.scalar("alpha", sign="positive")
    eps1 = t.scalar("eps1", sign="positive")
    eps2 = t.scalar("eps2", sign="positive")
    n, P1, P2, H, N = d["n"], d["P1"], d["P2"], d["H"], d["N"]
    decay = sympy.exp(-2 * d["beta"])
    if psi1 == "printed":
        rows = [
            [H.T * H - decay * P1, 0, I(n)],
            [STAR, eps2 * N.T * N - P2, 0],
            [STAR, STAR, -alpha * I(n)],
        ]
    else:
        rows = [
            [H.T * H - decay * P1, 0, I(n), 0],
            [STAR, eps2 * N.T * N - P2, 0, I(n)],
            [STAR, STAR, -alpha * I(n), 0],
            [STAR, STAR, STAR, -alpha * I(n)],
        ]
    _filter_lmis(t, d, rows, eps1, eps2)
    t.minimize(alpha + eps1)
    _gain_and_check(t, d)
    t.derive("gamma_star", 1 / sympy.sqrt(alpha * (1 + eps1)), doc="gamma* = 1/sqrt(alpha (1 + eps1)) (28)")


def vec_embedding(Cw: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Constant factors ``E, F`` with ``E diag(w) F = [w_(i n + j) / c_ij]`` (row-major ``w``).

    Corollary 1 needs a matrix variable with element-wise sign constraints and the weighted
    objective ``sum c_ij alpha_ij``. Both are linear in a *diagonal* ``n^2 x n^2`` variable
    ``W = diag(c_ij alpha_ij)``: ``trace(W)`` is the weighted sum, ``W > 0`` is ``alpha_ij > 0``,
    and ``Acal = E W F`` recovers ``[alpha_ij]`` with ``E = (I_n kron 1_n^T) diag(1 / vec_r(C))``
    and ``F = 1_n kron I_n``.

    Examples
    --------
    >>> E, F = vec_embedding(np.array([[1.0, 2.0], [4.0, 1.0]]))
    >>> E @ np.diag([1.0, 2.0, 4.0, 3.0]) @ F
    array([[1., 1.],
           [1., 3.]])
    """
    Cw = np.atleast_2d(np.asarray(Cw, dtype=float))
    n = Cw.shape[0]
    E = np.kron(np.eye(n), np.ones((1, n))) / Cw.reshape(1, -1)
    F = np.kron(np.ones((n, 1)), np.eye(n))
    return E, F


def _positive_weights(v: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    Cw = v["Cw"]
    if not np.all(Cw > 0):
        raise DataError("theorem uncertain_dt.cor1: data 'Cw' (the weights c_ij) must be element-wise > 0")
    return vec_embedding(Cw)


@theorem(
    id="uncertain_dt.cor1",
    title="Matrix-type Lipschitz constant (element-wise robustness), Corollary 1",
    citation=CITATION + ", Corollary 1",
    kind="S",
    objective="min eps1 - sum c_ij alpha_ij; L = P1^-1 G, Gamma* = Acal / sqrt(1 + eps1)",
    system_class="discrete time, matrix-Lipschitz ||Phi(x1) - Phi(x2)|| <= ||Gamma (x1 - x2)||",
    notes="Acal > 0 read element-wise (the paper's notation II-A); positivity: elementwise | none. "
    "As printed, the certified matrix is Gamma*^T (Gamma_star_T).",
)
def uncertain_dt_cor1(t: Template) -> None:
    """Corollary 1 (Section IV.B, element-wise robustness): Theorem 1 with
    ``Psi1 = [H^T H - e^{-2 beta} P1, 0, Acal; *, eps2 N^T N - P2, 0; *, *, -I]`` (Xi1, Psi2,
    Omega unchanged), ``Acal = [alpha_ij] > 0``, objective ``min eps1 - sum_ij c_ij alpha_ij``
    with fixed weights ``c_ij > 0`` (data ``Cw``, all ones when omitted); ``L = P1^-1 G``,
    ``Gamma* = Acal* / sqrt(1 + eps1*)``.

    Readings: ``Acal > 0`` is element-wise (the paper defines its order element-wise,
    Section II-A); ``positivity: none`` drops it. Transposition: ``[X, Acal; Acal^T, -I] < 0``
    yields ``X + Acal Acal^T`` while the proof's change of variables is
    ``(1 + eps1) Gamma^T Gamma = Acal^T Acal``: as printed the certified
    matrix-type constant is ``Gamma*^T`` (derived ``Gamma_star_T``); identical when Acal* is
    symmetric.

    Formulation: the weighted sum and the element-wise signs are linear in the diagonal
    ``n^2 x n^2`` variable ``W = diag(c_ij alpha_ij)`` (row-major), with ``Acal = E W F`` for the
    constant factors of :func:`vec_embedding`; the objective is ``eps1 - trace(W)``.

    Reference (``lmic reproduce``; Sec. V data, c_ij = 1, Clarabel = SCS): objective
    -0.77198, eps1 = 0.5731.
    """
    d = _filter_data(t)
    n = d["n"]
    t.data(
        "Cw",
        n,
        n,
        default=lambda v, r, c: np.ones((r, c)),
        doc="weights c_ij > 0 of the objective (default: all ones, as in the shipped example)",
    )
    positivity = t.option(
        "positivity", ("elementwise", "none"), "elementwise", doc="Acal > 0 element-wise, or no sign constraint"
    )
    E = t.const("E", lambda v: _positive_weights(v)[0], shape=(n, n**2), doc="Acal = E W F")
    F = t.const("F", lambda v: _positive_weights(v)[1], shape=(n**2, n), doc="Acal = E W F")
    W = t.diagonal("W", n**2, doc="diag(c_ij alpha_ij), row-major")
    eps1 = t.scalar("eps1", sign="positive")
    eps2 = t.scalar("eps2", sign="positive")
    Acal = E * W * F
    P1, P2, H, N = d["P1"], d["P2"], d["H"], d["N"]
    decay = sympy.exp(-2 * d["beta"])
    rows = [
        [H.T * H - decay * P1, 0, Acal],
        [STAR, eps2 * N.T * N - P2, 0],
        [STAR, STAR, -I(n)],
    ]
    if positivity == "elementwise":
        t.lmi("Acal > 0 (element-wise)", block(W) > 0)
    _filter_lmis(t, d, rows, eps1, eps2)
    t.minimize(eps1 - sympy.Trace(W))
    _gain_and_check(t, d)
    acal = t.derive("Acal", Acal, doc="Acal = [alpha_ij]")
    gstar = t.derive("Gamma_star", acal / sympy.sqrt(1 + eps1), doc="Gamma* = Acal / sqrt(1 + eps1)")
    t.derive("Gamma_star_T", gstar.T, doc="the matrix certified as printed (see docstring)")


THEOREMS = [uncertain_dt_lemma3, uncertain_dt_thm1, uncertain_dt_cor1]
