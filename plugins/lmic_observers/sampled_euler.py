"""Abbaszadeh & Marquez (2008): sampled-data Lipschitz observers, exact and Euler models.

Source: M. Abbaszadeh, H. J. Marquez, *Robust H-infinity observer design for sampled-data
Lipschitz nonlinear systems with exact and Euler approximate models*, Automatica 44 (2008)
799-806 (the text followed is the later arXiv version).

Discrete-time plant ``x(k+1) = Ad x + F(x, u)``, ``y = Cd x`` with ``F`` Lipschitz (constant
``gamma_d``), observer ``x^(k+1) = Ad x^ + F(x^, u) + L (y - Cd x^)``, gain ``L = P^-1 G``.
``Q > 0`` is a fixed design matrix (Remark 1). Every inequality of the paper is strict.

Fixed gains (audits of published gains): with ``fixed_L: 1`` the gain ``L`` is data and the
change of variables ``G = P L`` is substituted, so the LMIs are in ``P`` (and the scalars) only.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import sympy

from lmic.errors import DataError
from lmic.template import STAR, I, Template, block, greater_than, schur_stable, theorem
from lmic.template.numeric import lambda_max, lambda_min

__all__ = ["THEOREMS", "psi1_value"]

CITATION = (
    "Abbaszadeh & Marquez (2008), Robust H-infinity observer design for sampled-data Lipschitz "
    "nonlinear systems with exact and Euler approximate models, Automatica 44:799-806"
)


def psi1_value(Q: np.ndarray, gamma_d: float) -> float:
    """Psi1 of (8): the positive root of ``(g + 2) p^2 + 2 lmax(Q) p - lmin(Q)^2 / (g^2 (g + 2))``.

    Parameters
    ----------
    Q : array (n, n)
        The fixed design matrix, ``Q > 0``.
    gamma_d : float
        The Lipschitz constant, ``> 0``.

    Examples
    --------
    >>> round(psi1_value(0.1 * np.eye(2), 0.067), 4)
    0.6753
    """
    lmax, lmin = lambda_max(Q), lambda_min(Q)
    return float((-lmax + np.sqrt(lmax**2 + lmin**2 / gamma_d**2)) / (gamma_d + 2.0))


def _gain(
    t: Template, n: sympy.Symbol, p: sympy.Symbol, P: sympy.MatrixExpr, fixed: bool
) -> tuple[sympy.MatrixExpr, sympy.MatrixExpr | None]:
    """``G`` as a decision variable, or ``P L`` with ``L`` given (``fixed_L = 1``)."""
    if fixed:
        L = t.data("L", n, p, doc="the observer gain to audit (fixed_L = 1)")
        return P * L, L
    return t.full("G", n, p, doc="G = P L"), None


def _observer(t: Template) -> tuple[sympy.Symbol, sympy.Symbol, sympy.MatrixExpr, sympy.MatrixExpr]:
    """Dimensions and the discrete-time data ``Ad``, ``Cd`` of Theorems 1, 2 and 4."""
    n, p = t.dims("n p")
    Ad = t.data("Ad", n, n, doc="discrete-time state matrix")
    Cd = t.data("Cd", p, n, doc="discrete-time output matrix")
    return n, p, Ad, Cd


def _lmi6(
    t: Template,
    n: sympy.Symbol,
    P: sympy.MatrixExpr,
    Q: sympy.MatrixExpr,
    Ad: sympy.MatrixExpr,
    Cd: sympy.MatrixExpr,
    G: sympy.MatrixExpr,
    eps: sympy.Expr,
    name: str,
) -> None:
    """LMI (6) = (32) = (71): ``[P - Q - eps I, Ad^T P - Cd^T G^T; *, P] > 0``."""
    t.lmi(name, block([[P - Q - eps * I(n), Ad.T * P - Cd.T * G.T], [STAR, P]]) > 0)


def _finish_gain(
    t: Template,
    P: sympy.MatrixExpr,
    G: sympy.MatrixExpr,
    L_data: sympy.MatrixExpr | None,
    Ad: sympy.MatrixExpr,
    Cd: sympy.MatrixExpr,
) -> sympy.MatrixExpr:
    """``L = P^-1 G`` (or the given L) and the check ``Ad - L Cd`` Schur stable."""
    L = L_data if L_data is not None else t.derive("L", P.inv() * G, doc="observer gain L = P^-1 G (9)")
    t.check("Ad - L Cd Schur stable", schur_stable(Ad - L * Cd))
    t.observer("luenberger", "discrete", A=Ad, C=Cd, L=L)
    return L


@theorem(
    id="sampled_euler.thm1",
    title="Lipschitz DT observer for a given Lipschitz constant, LMIs (6)-(8)",
    citation=CITATION + ", Theorem 1",
    kind="S",
    objective="feasibility; L = P^-1 G",
    system_class="discrete time, Lipschitz (gamma_d given)",
    notes="Psi1 (8) is printed as a stacked fraction: it is the positive root of (30). "
    "Q is a fixed design matrix; fixed_L: 1 audits a given gain (G = P L).",
)
def sampled_euler_thm1(t: Template) -> None:
    """Theorem 1 (Section 3, discrete-time systems): LMIs (6), (7), Psi1 (8).

    ``(6) [P - Q - eps I, Ad^T P - Cd^T G^T; *, P] > 0``, ``(7) [Psi1 I, P; *, Psi1 I] > 0``
    (i.e. ``lambda_max(P) < Psi1``), with the constant
    ``Psi1 = (-lmax(Q) + sqrt(lmax(Q)^2 + lmin(Q)^2 / gamma_d^2)) / (gamma_d + 2)`` and
    ``P > 0``, ``eps > 0``; the gain is ``L = P^-1 G`` (9).

    Typo resolution: (8) is garbled in the text (stacked fraction); it is the positive root of
    the quadratic (30) ``(gd + 2) p^2 + 2 lmax(Q) p - lmin(Q)^2 / (gd^2 (gd + 2)) = 0``
    (checked algebraically). The (2,1) block of (6), printed ``P Ad - G Cd``, is the transpose
    of (1,2): consistent.

    Reference (``lmic reproduce``): example data, Q = 0.1 I, gamma_d = 0.06109 is feasible;
    sup gamma_d = 0.0935 by bisection. The published Theorem-4 gain L = [1.0497; 0.3588] is a
    valid Theorem-1 certificate (``fixed_L: 1``).
    """
    n, p, Ad, Cd = _observer(t)
    Q = t.data("Q", n, n, positive_definite=True, doc="fixed design matrix Q > 0")
    t.param("gamma_d", domain="positive", doc="Lipschitz constant gamma_d of F")
    fixed = t.flag("fixed_L", doc="1: L is given as data (audit), G = P L")
    psi1 = t.const("Psi1", lambda v: psi1_value(v["Q"], v["gamma_d"]), doc="Psi1 of (8)")
    P = t.symmetric("P", n, pd=True)
    G, L_data = _gain(t, n, p, P, fixed)
    eps = t.scalar("epsilon", sign="positive")
    _lmi6(t, n, P, Q, Ad, Cd, G, eps, "(6)")
    t.lmi("(7)", block([[psi1, P], [STAR, psi1]]) > 0)
    _finish_gain(t, P, G, L_data, Ad, Cd)


def _thm2_body(
    t: Template,
    n: sympy.Symbol,
    Ad: sympy.MatrixExpr,
    Cd: sympy.MatrixExpr,
    Q: sympy.MatrixExpr,
    P: sympy.MatrixExpr,
    G: sympy.MatrixExpr,
    L_data: sympy.MatrixExpr | None,
) -> sympy.Symbol:
    """LMIs (32)-(34) and ``min xi``; returns xi."""
    lmin_q = t.const("lambda_min_Q", lambda v: lambda_min(v["Q"]), doc="lambda_min(Q)")
    lmax_q = t.const("lambda_max_Q", lambda v: lambda_max(v["Q"]), doc="lambda_max(Q)")
    eps = t.scalar("epsilon", sign="positive")
    xi = t.scalar("xi", doc="xi = 1 / gamma_d*")
    t.constraint("xi > 1", xi > 1)
    psi2 = (lmin_q * xi - lmax_q) / 3
    t.lmi("P > 0", block(P) > 0)
    _lmi6(t, n, P, Q, Ad, Cd, G, eps, "(32)")
    t.lmi("(33)", block([[psi2, P], [STAR, psi2]]) > 0)
    t.minimize(xi)
    _finish_gain(t, P, G, L_data, Ad, Cd)
    return xi


@theorem(
    id="sampled_euler.thm2",
    title="Maximum admissible Lipschitz constant, LMIs (32)-(34)",
    citation=CITATION + ", Theorem 2",
    kind="S",
    objective="min xi; gamma_d* = 1/xi, L = P^-1 G",
    system_class="discrete time, Lipschitz (gamma_d < 1)",
    notes="For Q = q I the LMIs are homogeneous in (P, G, eps, q): xi* does not depend on q. "
    "gamma_d (optional) is the actual Lipschitz constant, for Remark 2's margin.",
)
def sampled_euler_thm2(t: Template) -> None:
    """Theorem 2 (Section 3): ``min xi`` subject to (32) = (6) and
    ``(33) [Psi2 I, P; *, Psi2 I] > 0`` with ``Psi2 = (lmin(Q) xi - lmax(Q)) / 3`` (34),
    ``xi > 1``, ``P > 0``, ``eps > 0``; ``gamma_d* = 1/xi*`` (36), ``L = P^-1 G`` (35).

    Remark 2: the observer tolerates any additive Lipschitz uncertainty up to
    ``gamma_d* - gamma_d`` (derived ``delta_gamma_d``; the check ``gamma_d < gamma_d*``
    states that the design covers the actual constant).

    Reference (``lmic reproduce``): example (Ad = I + 0.1 A, Q = q I, any q):
    xi* = 14.95596, gamma_d* = 0.066863 (paper: 0.067), L = [1.0384; 0.2454].
    """
    n, p, Ad, Cd = _observer(t)
    Q = t.data("Q", n, n, positive_definite=True, doc="fixed design matrix Q > 0")
    gamma_d = t.param(
        "gamma_d", default=0.0, domain="nonnegative", doc="actual Lipschitz constant (Remark 2 margin; 0 if unknown)"
    )
    fixed = t.flag("fixed_L", doc="1: L is given as data (audit), G = P L")
    P = t.symmetric("P", n)
    G, L_data = _gain(t, n, p, P, fixed)
    xi = _thm2_body(t, n, Ad, Cd, Q, P, G, L_data)
    gd_star = t.derive("gamma_d_star", 1 / xi, doc="maximum admissible Lipschitz constant (36)")
    delta = t.derive("delta_gamma_d", gd_star - gamma_d, doc="Remark 2 margin gamma_d* - gamma_d")
    t.check("gamma_d < gamma_d* (Remark 2)", greater_than(delta, 0.0))


def _theorem3_q_rule(v: Mapping[str, Any]) -> float:
    """``lambda_min(Q) = T`` is part of Theorem 3's statement."""
    lmin_q, T = lambda_min(v["Q"]), v["T"]
    if abs(lmin_q - T) > 1e-9 * max(1.0, T):
        raise DataError(
            f"theorem sampled_euler.thm3: data 'Q' must satisfy lambda_min(Q) = T "
            f"(lambda_min(Q) = {lmin_q:g}, T = {T:g}); use sampled_euler.thm2 on the Euler model "
            "for another Q"
        )
    return lmin_q


@theorem(
    id="sampled_euler.thm3",
    title="Observer on the Euler model of a CT Lipschitz system (Theorem 2 with lambda_min(Q) = T)",
    citation=CITATION + ", Theorem 3",
    kind="S",
    objective="min xi; gamma_c* = 1/(T xi), L = P^-1 G",
    system_class="continuous time Lipschitz (gamma_c), Euler model Ad = I + T A",
    notes="Q defaults to T I (Remark 3, the best choice); lambda_min(Q) = T is enforced.",
)
def sampled_euler_thm3(t: Template) -> None:
    """Theorem 3 (Section 4, sampled-data systems): Theorem 2 applied to the Euler model (47)-(49),
    ``Ad = I + T A`` (48), ``Cd = C``, ``F_T = T f`` so ``gamma_d = T gamma_c``, with the
    extra requirement ``lambda_min(Q) = T``. Derived ``gamma_c* = gamma_d*/T``;
    Remark 4 margin ``gamma_c* - gamma_c``.

    The system file gives the continuous-time ``A``, ``C`` and the sampling time ``T``; ``Q``
    is optional (default ``T I``, Remark 3 (66)); a ``Q`` with ``lambda_min(Q) != T`` is
    rejected (the statement requires it).

    Reference (``lmic reproduce``): example T = 0.1, Q = 0.1 I: gamma_c* = 0.66863
    (paper: 0.67), L = [1.0384; 0.2454].
    """
    n, p = t.dims("n p")
    t.data("A", n, n, doc="continuous-time state matrix (enters through Ad)")
    C = t.data("C", p, n, doc="output matrix (Cd = C)")
    T = t.param("T", domain="positive", doc="sampling time")
    gamma_c = t.param(
        "gamma_c", default=0.0, domain="nonnegative", doc="actual CT Lipschitz constant (Remark 4 margin; 0 if unknown)"
    )
    Q = t.data(
        "Q",
        n,
        n,
        positive_definite=True,
        default=lambda v, r, c: v["T"] * np.eye(r),
        doc="fixed design matrix with lambda_min(Q) = T (default T I)",
    )
    fixed = t.flag("fixed_L", doc="1: L is given as data (audit), G = P L")
    t.const("lambda_min_Q_is_T", _theorem3_q_rule, doc="checks lambda_min(Q) = T")
    Ad = t.const(
        "Ad", lambda v: np.eye(v["A"].shape[0]) + v["T"] * v["A"], shape=(n, n), doc="Euler model Ad = I + T A (48)"
    )
    P = t.symmetric("P", n)
    G, L_data = _gain(t, n, p, P, fixed)
    xi = _thm2_body(t, n, Ad, C, Q, P, G, L_data)
    t.derive("gamma_d_star", 1 / xi, doc="maximum admissible DT Lipschitz constant")
    gc_star = t.derive("gamma_c_star", 1 / (T * xi), doc="gamma_c* = gamma_d* / T")
    delta = t.derive("delta_gamma_c", gc_star - gamma_c, doc="Remark 4 margin gamma_c* - gamma_c")
    t.check("gamma_c < gamma_c* (Remark 4)", greater_than(delta, 0.0))
    t.observer("euler", "discrete", A="A", C=C, L="L", T=T)


@theorem(
    id="sampled_euler.thm4",
    title="Robust H-infinity observer (min mu), LMIs (71)-(73)",
    citation=CITATION + ", Theorem 4",
    kind="S",
    objective="min zeta; mu* = sqrt(zeta), L = P^-1 G",
    system_class="discrete time, Lipschitz (gamma_d given), disturbance Bd w, z = H e",
    notes="(73) as printed is infeasible for every instance: its constant (1,1) block Lambda2 "
    "always has a positive eigenvalue. coupling: Bd (default) | I.",
)
def sampled_euler_thm4(t: Template) -> None:
    """Theorem 4 (Section 5, H-infinity synthesis): ``min zeta`` subject to (71) = (6), (72) = (7) with
    Psi1 from (8), and

    ``(73) [Lambda2, c/2 Bd; *, Bd^T P Bd - zeta I] < 0``,
    ``Lambda2 = H^T H - Q + gamma_d (3 Psi1 + lmax(Q)) I``, ``c = 2 (gamma_d + 1) Psi1 + lmax(Q)``;
    ``mu* = sqrt(zeta*)``, ``L = P^-1 G``.

    Typo resolution (73): the printed (1,1) entry is ``Lambda2 I``; Lambda2 is already a
    matrix (the ``I`` multiplies the scalar part only). The printed (1,2) entry is ``c/2 I``;
    it must be n x nw, and the proof ((74), (77): cross term ``w^T Bd^T [2 lmax(P)(gd + 1) +
    lmax(Q)] e``) gives ``c/2 Bd`` (option ``coupling: Bd``, the default). ``coupling: I``
    keeps the printed identity, possible only when nw = n (Bd must then be n x n).

    Result: only ``zeta`` and ``P`` enter (73) and its (1,1) block is the constant Lambda2,
    which has a positive eigenvalue for every Q > 0, gamma_d > 0, H (with v the unit
    eigenvector of Q for s = lambda_min(Q), r = lambda_max(Q), u = s / (gamma_d r):
    ``v^T Lambda2 v / (gamma_d r) >= 1 - u + 3 (sqrt(1 + u^2) - 1) / (gamma_d + 2) > 0``).
    The theorem as printed is infeasible on every instance; the published
    mu* = 0.1308 cannot be reproduced (example: lambda_max(Lambda2) = +0.1049).
    """
    n, p, Ad, Cd = _observer(t)
    nw, nz = t.dims("nw nz")
    coupling = t.option("coupling", ("Bd", "I"), "Bd", doc="(1,2) block of (73): c/2 Bd or c/2 I")
    if coupling == "I":
        Bd = t.data("Bd", n, n, doc="disturbance matrix (coupling: I needs nw = n)")
    else:
        Bd = t.data("Bd", n, nw, doc="disturbance matrix")
    t.data("H", nz, n, doc="performance output z = H e (enters through Lambda2)")
    Q = t.data("Q", n, n, positive_definite=True, doc="fixed design matrix Q > 0")
    gamma_d = t.param("gamma_d", domain="positive", doc="Lipschitz constant gamma_d of F")
    fixed = t.flag("fixed_L", doc="1: L is given as data (audit), G = P L")
    psi1 = t.const("Psi1", lambda v: psi1_value(v["Q"], v["gamma_d"]), doc="Psi1 of (8)")
    lmax_q = t.const("lambda_max_Q", lambda v: lambda_max(v["Q"]), doc="lambda_max(Q)")
    Lambda2 = t.const(
        "Lambda2",
        lambda v: (
            v["H"].T @ v["H"] - v["Q"] + v["gamma_d"] * (3 * v["Psi1"] + v["lambda_max_Q"]) * np.eye(v["Q"].shape[0])
        ),
        shape=(n, n),
        doc="Lambda2 = H^T H - Q + gamma_d (3 Psi1 + lmax(Q)) I",
    )
    half_c = (2 * (gamma_d + 1) * psi1 + lmax_q) / 2
    P = t.symmetric("P", n, pd=True)
    G, L_data = _gain(t, n, p, P, fixed)
    eps = t.scalar("epsilon", sign="positive")
    zeta = t.scalar("zeta", sign="positive", doc="zeta = mu^2")
    coupling_block = half_c * (I(n) if coupling == "I" else Bd)
    _lmi6(t, n, P, Q, Ad, Cd, G, eps, "(71)")
    t.lmi("(72)", block([[psi1, P], [STAR, psi1]]) > 0)
    t.lmi("(73)", block([[Lambda2, coupling_block], [STAR, Bd.T * P * Bd - zeta * I(Bd.shape[1])]]) < 0)
    t.minimize(zeta)
    t.derive("mu_star", sympy.sqrt(zeta), doc="mu* = sqrt(zeta*)")
    _finish_gain(t, P, G, L_data, Ad, Cd)
    t.observer("robust", "discrete", A=Ad, C=Cd, L="L", D1=Bd, Hz="H", gamma="mu_star")


THEOREMS = [sampled_euler_thm1, sampled_euler_thm2, sampled_euler_thm3, sampled_euler_thm4]
