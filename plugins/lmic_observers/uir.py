"""Delshad, Johansson, Darouach & Gustafsson (Automatica 2015), thesis Paper E: robust UIO.

Source: S. S. Delshad, A. Johansson, M. Darouach and T. Gustafsson, *Robust state estimation
and unknown inputs reconstruction for a class of nonlinear systems: multiobjective approach*,
Automatica 2015 (thesis Paper E).

System (1): ``x' = A x + B u + f(x) + F nu + D1 w``, ``y = C x + G nu + D2 w`` with
``f: R^n -> R^n`` Lipschitz ``gamma`` (no ``D`` matrix: Paper D with ``D = I``). Augmented
descriptor form with ``zeta = [x; nu]``, descriptor matrix ``[I_n 0]`` (called ``E`` in the
paper, ``eta`` here because ``E`` is also the observer's output gain), ``Abar = [A F]``,
``Cbar = [C G]``. Observer (4) of order ``q1``: ``z' = N z + L y + G u + M f(E zeta^)``,
``zeta^ = J z + E y``; error (10) ``eps' = N eps + M df + (L D2 - M D1) w``, ``e = J eps + E D2 w``.

Pre-processing as Paper D (see :mod:`lmic_observers.descriptor`): ``[M K] = R [E; Cbar]^+``
(33)-(34), ``T = [M E; Cbar]``, ``alpha1, alpha2 = T^+ [I; 0], T^+ [0; I]``, exact projectors
``beta1, beta2 = (I - T T^+)[I; 0], (I - T T^+)[0; I]`` (36); gains (37) (``G = M B`` is the
derived ``Gf``, the data key ``G`` being the unknown-input output matrix).

Uncertainty (Section 4): ``A = A0 + dA``, ``f = f0 + df``; the lumped nonlinearity has
Lipschitz constant ``gamma0 + dgamma + ||dA||``. Theorem 4.1 maximises ``gamma`` through
``rho = 1/(1 + gamma^2)`` with the side condition (40) ``0 < rho < 1/(1 + gamma0^2)``
(``gamma > gamma0``); ``(dgamma + ||dA||)_max = sqrt(1/rho - 1) - gamma0``.

Reference values (checked by ``lmic reproduce``): on the Rossler example (kappa
coordinates) M from R is exact, ``T`` is invertible (``beta = 0``), J and E reproduce exactly;
with the printed F the structural N is unstable, with ``F(1,:) = [1 0]`` N and L match the
print. Theorem 5.1 is **infeasible** for both F (``||J (sI - N)^-1 M||_inf ~ 30.2`` forces
``rho >~ 913``): with (40) imposed (default) no point exists, and without it the optimum
``rho ~ 916`` has no real ``gamma``; SCS's "solutions" there must be rejected. The stability
LMI (11) at the printed observer (51) is feasible only for ``gamma < 0.0401``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import sympy

from lmic.template import STAR, I, Template, block, hurwitz, less_than, negative_definite, theorem
from lmic.template.numeric import left_null_basis
from lmic_observers.descriptor import (
    hinf_block,
    reduced_order_blocks,
    reduced_order_constants,
    reduced_order_gains,
)

CITATION = (
    "Delshad, Johansson, Darouach & Gustafsson, 'Robust state estimation and unknown inputs "
    "reconstruction for a class of nonlinear systems: multiobjective approach', Automatica 2015 "
    "(Delshad PhD thesis, Lulea, Paper E)"
)
SYSTEM_CLASS = (
    "continuous time, Lipschitz nonlinearity f(x) in R^n, unknown inputs in state and output, "
    "L2 disturbance, norm-bounded uncertainty; reduced-order descriptor observer"
)


@theorem(
    id="uir.thm3_1",
    title="Reduced-order UIO stability analysis (11) in (P, Gamma) for given N, J, M",
    citation=CITATION + ", Theorem 3.1, inequalities (11)",
    kind="A",
    objective="feasibility (P, Gamma certify the given observer)",
    system_class=SYSTEM_CLASS,
    notes="Bilinear in (P, N); an LMI in (P, Gamma) for given gains. Paper D Thm 3.1 with D = I.",
)
def uir_thm3_1(t: Template) -> None:
    """Theorem 3.1 (Section 3), inequalities (11).

    ``Gamma - I < 0``, ``[N^T P + P N + gamma^2 J^T J, P M; *, -Gamma] < 0``, ``P > 0``.

    Example: the printed observer (51) at gamma0 = 0.259 (the paper claims feasibility):
    infeasible; by the bounded-real lemma (11) holds at these gains only for gamma < 0.0401.
    """
    q1, nh, n = t.dims("q1 nh n")
    N = t.data("N", q1, q1, doc="observer matrix N (given)")
    J = t.data("J", nh, q1, doc="observer output matrix J (given)")
    M = t.data("M", q1, n, doc="M (given; from R by (34))")
    gamma = t.param("gamma", domain="nonnegative", doc="Lipschitz constant of f")
    P = t.symmetric("P", q1, pd=True)
    Gamma = t.symmetric("Gamma", n)
    t.lmi("Gamma - I < 0", block(Gamma - I(n)) < 0)
    t.lmi("(11)", block([[N.T * P + P * N + gamma**2 * J.T * J, P * M], [STAR, -Gamma]]) < 0)
    t.check("N Hurwitz (error dynamics (10))", hurwitz(N))
    t.observer("filter_error", "continuous", N=N, J=J)


@theorem(
    id="uir.thm3_2",
    title="Reduced-order UIO H-inf analysis (16)-(17) in (P, Gamma) for given gains",
    citation=CITATION + ", Theorem 3.2, inequalities (16)-(17)",
    kind="A",
    objective="feasibility (P, Gamma certify the given observer with ||e||_2 < mu ||w||_2)",
    system_class=SYSTEM_CLASS,
    notes="Paper D Thm 3.2 with D = I (a12 = P M).",
)
def uir_thm3_2(t: Template) -> None:
    """Theorem 3.2 (Section 3), inequalities (16)-(17).

    ``Gamma - I < 0``, ``P > 0``, ``[a11, P M, a13; *, -Gamma, 0; *, 0, a33] < 0`` with
    ``a11 = N^T P + P N + (1+gamma^2) J^T J``, ``a13 = P (L D2 - M D1) + (1+gamma^2) J^T E D2``,
    ``a33 = (1+gamma^2) D2^T E^T E D2 - mu^2 I``.
    """
    q1, nh, n, p, nw = t.dims("q1 nh n p nw")
    N = t.data("N", q1, q1, doc="observer matrix N (given)")
    L = t.data("L", q1, p, doc="observer output-injection gain L (given)")
    M = t.data("M", q1, n, doc="M (given; from R by (34))")
    J = t.data("J", nh, q1, doc="observer output matrix J (given)")
    E = t.data("E", nh, p, doc="observer feed-through gain E (given)")
    D1 = t.data("D1", n, nw, doc="disturbance matrix of the state equation")
    D2 = t.data("D2", p, nw, doc="disturbance matrix of the output")
    gamma = t.param("gamma", domain="nonnegative", doc="Lipschitz constant of f")
    mu = t.param("mu", domain="positive", doc="disturbance attenuation level")
    P = t.symmetric("P", q1, pd=True)
    Gamma = t.symmetric("Gamma", n)
    t.lmi("Gamma - I < 0", block(Gamma - I(n)) < 0)
    t.lmi("(16)", hinf_block(P, Gamma, N, L, J, E, M, M * D1, D2, 1 + gamma**2, mu**2) < 0)
    t.check("N Hurwitz (error dynamics (10))", hurwitz(N))
    t.observer("filter_error", "continuous", N=N, J=J, L=L, M=M, E=E, D1=D1, D2=D2, gamma=mu)


def _range_basis_t(values: Mapping[str, Any]) -> np.ndarray:
    """``W^T`` for ``I - T T^+ = W W^T``: ``W`` an orthonormal basis of the left null space of
    ``T`` in its first columns, zero columns after it."""
    T = np.atleast_2d(values["T"])
    B = left_null_basis(T)
    W = np.zeros((T.shape[0], T.shape[0]))
    W[:, : B.shape[1]] = B
    return W.T


def _beta1_w(values: Mapping[str, Any]) -> np.ndarray:
    return _range_basis_t(values)[:, : values["R"].shape[0]]


def _beta2_w(values: Mapping[str, Any]) -> np.ndarray:
    return _range_basis_t(values)[:, values["R"].shape[0] :]


def _robust(t: Template, multiobjective: bool) -> None:
    """Theorems 4.1 (``multiobjective=False``) and 5.1: the LMI (38)/(41), objective, checks."""
    n, h, p, q1 = t.dims("n h p q1")
    s = reduced_order_constants(t, n, h, p, q1, with_D=False)
    nw = s["D1"].shape[1]
    # Ybar1 and Y2 enter only through Ybar1 Pi and Y2 Pi (Pi = I - T T^+ = [beta1 beta2]):
    # written Ybar1 W^T, Y2 W^T (Pi = W W^T, W's columns past rank Pi exactly zero), the
    # directions Pi annihilates get exactly zero coefficients instead of round-off ones (with a
    # float Pi they make the compiled problem a different one, with spurious free directions,
    # which no dual bound can then enclose); Y1 and Y2 below are the paper's Y1 W, Y2 W
    s = dict(s)
    s["beta1"] = t.const("beta1_W", _beta1_w, shape=(q1 + p, q1), doc="W^T [I; 0], I - T T^+ = W W^T")
    s["beta2"] = t.const("beta2_W", _beta2_w, shape=(q1 + p, p), doc="W^T [0; I], I - T T^+ = W W^T")
    gamma0 = t.param("gamma0", domain="nonnegative", doc="Lipschitz constant of the nominal f0")
    if multiobjective:
        lam = t.param("lambda", domain="unit", doc="weight of rho in lambda rho + (1-lambda) mubar")
    else:
        mu = t.param("mu", domain="positive", doc="disturbance attenuation level")
    rho_bound = t.flag(
        "rho_bound",
        default=True,
        doc="impose the side condition (40) rho < 1/(1 + gamma0^2) (1, default) or not (0)",
    )
    P = t.symmetric("P", q1, pd=True)
    Gamma = t.symmetric("Gamma", n)
    Ybar1 = t.full("Ybar1", q1, q1 + p)
    Y2 = t.full("Y2", n + h, q1 + p)
    rho = t.scalar("rho", sign="positive", doc="rho = 1/(1 + gamma^2)")
    if multiobjective:
        mubar = t.scalar("mubar", sign="positive", doc="mubar = mu^2")
        mu_sq = mubar
    else:
        mu_sq = mu**2
    a11, a12, a13, a14, a34 = reduced_order_blocks(s, P, Ybar1, Y2, s["M"])
    t.lmi("Gamma - I < 0", block(Gamma - I(n)) < 0)
    name = "(41)" if multiobjective else "(38)"
    t.lmi(
        name,
        block(
            [
                [a11, a12, a13, a14],
                [STAR, -Gamma, 0, 0],
                [STAR, STAR, -mu_sq * I(nw), a34],
                [STAR, STAR, STAR, -rho * I(n + h)],
            ]
        )
        < 0,
    )
    if rho_bound:
        t.constraint("(40) rho < 1/(1 + gamma0^2)", (1 + gamma0**2) * rho < 1)
    if multiobjective:
        t.minimize(lam * rho + (1 - lam) * mubar)
    else:
        t.minimize(rho)
    g = t.derive("gamma", sympy.sqrt(1 / rho - 1), doc="gamma = sqrt(1/rho - 1)")
    t.derive(
        "delta_max",
        g - gamma0,
        doc="(dgamma + ||dA||)_max = sqrt(1/rho - 1) - gamma0",
    )
    if multiobjective:
        t.derive("mu_min", sympy.sqrt(mubar), doc="mu_min = sqrt(mubar)")
    N, L, J, E = reduced_order_gains(t, s, P, Ybar1, Y2)
    t.check("(40) rho < 1/(1 + gamma0^2) (gamma > gamma0)", less_than(rho * (1 + gamma0**2), 1))
    t.check("N Hurwitz (error dynamics (10))", hurwitz(N))
    M, D1, D2 = s["M"], s["D1"], s["D2"]
    t.check(
        "(16) at the recovered gains with 1 + gamma^2 = 1/rho",
        negative_definite(hinf_block(P, Gamma, N, L, J, E, M, M * D1, D2, 1 / rho, mu_sq)),
    )
    t.observer(
        "ui_filter", "continuous", A=s["A"], B=s["B"], C=s["C"], F=s["F"], G=s["G"], N=N, L=L, M=M, J=J, E=E,
        Gf="Gf", D1=D1, D2=D2, gamma="mu_min" if multiobjective else "mu",
    )  # fmt: skip


@theorem(
    id="uir.thm4_1",
    title="Robust reduced-order UIO with maximal uncertainty bound, LMI (38)-(40)",
    citation=CITATION + ", Theorem 4.1, LMI (38)-(39), side condition (40)",
    kind="S",
    objective="min rho (mu given); gamma = sqrt(1/rho - 1), (dgamma + ||dA||)_max = gamma - gamma0",
    system_class=SYSTEM_CLASS,
    notes="Same block as Paper D (40) with a12 = P M (correct here), a44 = -rho I. The side "
    "condition (40) 0 < rho < 1/(1+gamma0^2) is imposed by default (rho_bound = 1); with "
    "rho_bound = 0 it is only checked on the result.",
)
def uir_thm4_1(t: Template) -> None:
    """Theorem 4.1 (Section 4), LMI (38)-(39), side condition (40).

    ``min rho`` subject to ``Gamma - I < 0``, ``P > 0``, ``(1 + gamma0^2) rho < 1`` (40) and
    ``[a11, P M, a13, a14; *, -Gamma, 0, 0; *, *, -mu^2 I, a34; *, *, *, -rho I] < 0`` (block
    sizes q1, n, nw, n + h) with a11, a13, a14, a34 as in Paper D (40). The Schur complement of
    ``-rho I`` gives (16) with ``1 + gamma^2 = 1/rho``.
    """
    _robust(t, multiobjective=False)


@theorem(
    id="uir.thm5_1",
    title="Multiobjective robust reduced-order UIO, LMI (41)-(42)",
    citation=CITATION + ", Theorem 5.1, LMI (41)-(42), Section 6 example",
    kind="S",
    objective="min lambda rho + (1 - lambda) mubar; gamma = sqrt(1/rho - 1), mu_min = sqrt(mubar)",
    system_class=SYSTEM_CLASS,
    notes="The statement calls rho a given scalar; it is a decision variable (it is minimised). "
    "mubar = mu^2 is a variable. Side condition (40) imposed by default (rho_bound = 1). The "
    "published example is infeasible: with the printed F(1,:) = [0 1] the "
    "structural N is unstable; F(1,:) = [1 0] reproduces the printed N, L but (41) still needs "
    "rho >~ 913.",
)
def uir_thm5_1(t: Template) -> None:
    """Theorem 5.1 (Section 5), LMI (41)-(42).

    As Theorem 4.1 with ``a33 = -mubar I`` (``mubar = mu^2`` a decision variable) and objective
    ``min lambda rho + (1 - lambda) mubar``, ``lambda`` in [0, 1];
    ``(dgamma + ||dA||)_max = sqrt(1/rho - 1) - gamma0``, ``mu_min = sqrt(mubar)``.

    Example (43)-(51), Rossler in kappa coordinates (T = diag(1, 1, 100)), gamma0 = 0.259,
    lambda = 0.5, R as printed: M = [-1 0 0; 0 2 -1; -2 -1 0] exactly; the LMI is infeasible
    with both F variants (the paper claims feasibility).
    """
    _robust(t, multiobjective=True)


THEOREMS = [uir_thm3_1, uir_thm3_2, uir_thm4_1, uir_thm5_1]
