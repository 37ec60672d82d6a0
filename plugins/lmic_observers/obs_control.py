"""Delshad, Gustafsson, Karimi & Zemouche (ICCAS 2015), thesis Paper F: observer-based control.

Source: S. S. Delshad, T. Gustafsson, H. R. Karimi and A. Zemouche, *Observer-based control
design for a class of nonlinear systems subject to unknown inputs: LMI approach*, ICCAS 2015
(thesis Paper F).

System (1): ``x' = A x + B u + D f(x) + E mu``, ``y = C x``, ``||mu|| <= beta``, ``f``
Lipschitz ``gamma``. Observer-based controller (6): ``x^' = A x^ + B u + D f(x^) + L (y - C x^)``,
``u = -K x^``. Closed loop (8) in ``(x, e)``; goal: practical stability, ``x`` enters and stays
in ``||x|| < alpha``.

Theorem 3.1 is the BMI (9) in (P, K), (Q, L); for given K, L it is an LMI in (P, Q) after a
Schur complement of the ``P D D^T P``, ``P E E^T P``, ``Q D D^T Q``, ``Q E E^T Q`` terms.
Theorem 3.2 is its convexification with ``Gamma = P^-1``, ``Ktilde = K Gamma``,
``Ltilde = Q L`` and a Young inequality (with weight ``eps`` and ``N = Gamma``) on the coupling
``P B K``; it is linear once the scalars ``eps, epsc1, epsc2, epso1, epso2, gamma, alpha, beta``
are fixed (``eps Gamma`` would be bilinear: sweep ``eps``).

Typo resolved: Theorem 3.1 prints ``(epso2 + epsc1) beta^2/alpha^2`` in Omega11; the proof
((16) + (18)) and Theorem 3.2's delta33 give ``epso2 + epsc2``. Option
``c_variant = corrected | printed`` of ``obs_control.thm3_1`` selects it (default corrected).

Reference values (checked by ``lmic reproduce``), Rossler example with alpha = 0.05,
eps = 0.8, epsc1 = epsc2 = epso1 = epso2 = 0.5, gamma = 0.259, beta = 1: in the original
coordinates Theorem 3.2 is provably infeasible (delta11(3,3) needs
``400 G33^2 - 11.4 G33 + 2 < 0``); in the z-coordinates reconstruction (``Bz = B/100``,
``Dz = D/100``, ``Ez = E/100``, ``Cz = 100 C``) it is borderline infeasible at alpha = 0.05 (best
margin -1.6e-5, SCS's "optimal" must be rejected) and feasible at alpha = 0.06 with
``K ~ [123, 52, -19]``; Theorem 3.1 at the published K, L (z-coordinates) is feasible (max eig
-0.151).
"""

from __future__ import annotations

from typing import Any

import sympy

from lmic.template import STAR, Block, I, Template, block, hurwitz, negative_definite, theorem

CITATION = (
    "Delshad, Gustafsson, Karimi & Zemouche, 'Observer-based control design for a class of "
    "nonlinear systems subject to unknown inputs: LMI approach', ICCAS 2015 (Delshad PhD "
    "thesis, Lulea, Paper F)"
)
SYSTEM_CLASS = (
    "continuous time, Lipschitz nonlinearity D f(x), bounded unknown input E mu (||mu|| <= beta), "
    "observer-based state feedback; practical stability ||x|| < alpha"
)


def _plant(t: Template) -> tuple[tuple[sympy.Symbol, ...], tuple[sympy.MatrixExpr, ...]]:
    n, m, p, q, qE = t.dims("n m p q qE")
    A = t.data("A", n, n, doc="state matrix")
    B = t.data("B", n, m, doc="control input matrix")
    C = t.data("C", p, n, doc="output matrix")
    D = t.data("D", n, q, doc="nonlinearity input matrix")
    E = t.data("E", n, qE, doc="unknown-input matrix")
    return (n, m, p, q, qE), (A, B, C, D, E)


def _scalars(t: Template) -> tuple[sympy.Symbol, ...]:
    doc = "positive Young-inequality weight"
    epsc1 = t.param("epsc1", domain="positive", doc=doc + " (controller, f)")
    epsc2 = t.param("epsc2", domain="positive", doc=doc + " (controller, mu)")
    epso1 = t.param("epso1", domain="positive", doc=doc + " (observer, f)")
    epso2 = t.param("epso2", domain="positive", doc=doc + " (observer, mu)")
    gamma = t.param("gamma", domain="nonnegative", doc="Lipschitz constant of f")
    alpha = t.param("alpha", domain="positive", doc="radius of the target region ||x|| < alpha")
    beta = t.param("beta", domain="nonnegative", doc="bound of the unknown input ||mu|| <= beta")
    return epsc1, epsc2, epso1, epso2, gamma, alpha, beta


def _nine(P: Any, Q: Any, K: Any, L: Any, mats: tuple[Any, ...], scalars: tuple[Any, ...], c: Any) -> Block:
    """The BMI (9) ``[Omega11, P B K; *, Omega22]`` (for checks: P, Q, K, L are numbers)."""
    A, B, C, D, E = mats
    epsc1, epsc2, epso1, epso2, gamma, _, _ = scalars
    n = A.shape[0]
    Acl = A - B * K
    Aob = A - L * C
    om11 = P * Acl + Acl.T * P + (1 / epsc1) * P * D * D.T * P + (1 / epsc2) * P * E * E.T * P + c * I(n)
    om22 = Q * Aob + Aob.T * Q + (1 / epso1) * Q * D * D.T * Q + epso1 * gamma**2 * I(n) + (1 / epso2) * Q * E * E.T * Q
    return block([[om11, P * B * K], [STAR, om22]])


@theorem(
    id="obs_control.thm3_1",
    title="Observer-based control with unknown inputs: inequality (9) in (P, Q) for given K, L",
    citation=CITATION + ", Theorem 3.1, inequalities (9)-(11)",
    kind="A",
    objective="feasibility (P, Q certify the given gains K, L)",
    system_class=SYSTEM_CLASS,
    notes="A BMI in (P, K), (Q, L); an LMI in (P, Q) for given K, L after Schur complements. "
    "Omega11's constant is printed eps_c1 gamma^2 + (eps_o2 + eps_c1) beta^2/alpha^2; the proof "
    "gives eps_o2 + eps_c2 (option c_variant = corrected, default, or printed). (10)-(11) "
    "(Omega11 < 0, Omega22 < 0) are implied by (9).",
)
def obs_control_thm3_1(t: Template) -> None:
    """Theorem 3.1 (Section 3), inequalities (9)-(11), in Schur form.

    ``[He(P(A - B K)) + c I, P B K, P D, P E, 0, 0; *, He(Q(A - L C)) + epso1 gamma^2 I, 0, 0,
    Q D, Q E; *, *, -epsc1 I, 0, 0, 0; *, *, *, -epsc2 I, 0, 0; *, *, *, *, -epso1 I, 0;
    *, *, *, *, *, -epso2 I] < 0`` with ``P > 0``, ``Q > 0`` and
    ``c = epsc1 gamma^2 + (epso2 + epsc2) beta^2/alpha^2`` (corrected; printed: epso2 + epsc1).
    The certificate also evaluates (9) in its Omega11, Omega22 form at the solution.

    Example: the published K, L in the z-coordinates of the paper's example: feasible (max eig -0.151).
    """
    (n, m, p, q, qE), mats = _plant(t)
    A, B, C, D, E = mats
    K = t.data("K", m, n, doc="state-feedback gain (given), u = -K x^")
    L = t.data("L", n, p, doc="observer gain (given)")
    scalars = _scalars(t)
    epsc1, epsc2, epso1, epso2, gamma, alpha, beta = scalars
    variant = t.option(
        "c_variant",
        ("corrected", "printed"),
        "corrected",
        doc="Omega11 constant: (epso2 + epsc2) beta^2/alpha^2 (corrected) or epso2 + epsc1 (printed)",
    )
    second = epsc2 if variant == "corrected" else epsc1
    c = epsc1 * gamma**2 + (epso2 + second) * beta**2 / alpha**2
    P = t.symmetric("P", n, pd=True)
    Q = t.symmetric("Q", n)
    Acl = A - B * K
    Aob = A - L * C
    t.lmi("Q > 0", block(Q) > 0)
    t.lmi(
        "(9) (Schur form)",
        block(
            [
                [P * Acl + Acl.T * P + c * I(n), P * B * K, P * D, P * E, 0, 0],
                [STAR, Q * Aob + Aob.T * Q + epso1 * gamma**2 * I(n), 0, 0, Q * D, Q * E],
                [STAR, STAR, -epsc1 * I(q), 0, 0, 0],
                [STAR, STAR, STAR, -epsc2 * I(qE), 0, 0],
                [STAR, STAR, STAR, STAR, -epso1 * I(q), 0],
                [STAR, STAR, STAR, STAR, STAR, -epso2 * I(qE)],
            ]
        )
        < 0,
    )
    t.check("A - B K Hurwitz", hurwitz(Acl))
    t.check("A - L C Hurwitz", hurwitz(Aob))
    t.check("(9) in the Omega form", negative_definite(_nine(P, Q, K, L, mats, scalars, c)))
    t.observer("obs_control", "continuous", A=A, B=B, C=C, K=K, L=L, E=E, alpha=alpha)


@theorem(
    id="obs_control.thm3_2",
    title="Observer-based control with unknown inputs: synthesis LMI (21)-(22)",
    citation=CITATION + ", Theorem 3.2, LMI (21)-(22)",
    kind="S",
    objective="feasibility (all scalars given); K = Ktilde Gamma^-1, L = Q^-1 Ltilde",
    system_class=SYSTEM_CLASS,
    notes="Linear for fixed eps, epsc1, epsc2, epso1, epso2, gamma, alpha, beta (eps Gamma would "
    "be bilinear: sweep eps). (31) prints -epso1, -epso2 without I; the proof writes L = Q^-1 "
    "Lbar. The certificate evaluates the BMI (9) of Theorem 3.1 at P = Gamma^-1 and the "
    "recovered K, L.",
)
def obs_control_thm3_2(t: Template) -> None:
    """Theorem 3.2 (Section 3), LMI (21)-(22).

    Block sizes n, n, n, q, qE, n, n:
    ``[d11, 0, Gamma, 0, 0, B Kt, 0; *, d22, 0, Q D, Q E, 0, I; *, *, -d33, 0, 0, 0, 0;
    *, *, *, -epso1 I, 0, 0, 0; *, *, *, *, -epso2 I, 0, 0; *, *, *, *, *, -(1/eps) Gamma, 0;
    *, *, *, *, *, *, -eps Gamma] < 0`` with ``Gamma > 0``, ``Q > 0``,
    ``d11 = He(A Gamma - B Kt) + (1/epsc1) D D^T + (1/epsc2) E E^T``,
    ``d22 = He(Q A - Lt C) + epso1 gamma^2 I``,
    ``d33 = I / (epsc1 gamma^2 + (epso2 + epsc2) beta^2/alpha^2)``.
    Gains ``K = Kt Gamma^-1``, ``L = Q^-1 Lt``.

    Example (32)-(37), Rossler: original coordinates infeasible; z-coordinates borderline at
    alpha = 0.05, feasible at alpha = 0.06 (K ~ [123, 52, -19]).
    """
    (n, m, p, q, qE), mats = _plant(t)
    A, B, C, D, E = mats
    eps = t.param("eps", domain="positive", doc="Young-inequality weight of the coupling B K")
    scalars = _scalars(t)
    epsc1, epsc2, epso1, epso2, gamma, alpha, beta = scalars
    c = epsc1 * gamma**2 + (epso2 + epsc2) * beta**2 / alpha**2
    Gamma = t.symmetric("Gamma", n, doc="Gamma = P^-1")
    Q = t.symmetric("Q", n)
    Kt = t.full("Kt", m, n, doc="Ktilde = K Gamma")
    Lt = t.full("Lt", n, p, doc="Ltilde = Q L")
    d11 = A * Gamma + Gamma * A.T - B * Kt - Kt.T * B.T + (1 / epsc1) * D * D.T
    d11 = d11 + (1 / epsc2) * E * E.T
    d22 = Q * A + A.T * Q - Lt * C - C.T * Lt.T + epso1 * gamma**2 * I(n)
    t.lmi("Gamma > 0", block(Gamma) > 0)
    t.lmi("Q > 0", block(Q) > 0)
    t.lmi(
        "(21)",
        block(
            [
                [d11, 0, Gamma, 0, 0, B * Kt, 0],
                [STAR, d22, 0, Q * D, Q * E, 0, I(n)],
                [STAR, STAR, -(1 / c) * I(n), 0, 0, 0, 0],
                [STAR, STAR, STAR, -epso1 * I(q), 0, 0, 0],
                [STAR, STAR, STAR, STAR, -epso2 * I(qE), 0, 0],
                [STAR, STAR, STAR, STAR, STAR, -(1 / eps) * Gamma, 0],
                [STAR, STAR, STAR, STAR, STAR, STAR, -eps * Gamma],
            ]
        )
        < 0,
    )
    P = t.derive("P", Gamma.inv(), doc="P = Gamma^-1")
    K = t.derive("K", Kt * Gamma.inv(), doc="K = Ktilde Gamma^-1")
    L = t.derive("L", Q.inv() * Lt, doc="L = Q^-1 Ltilde")
    t.check("A - B K Hurwitz", hurwitz(A - B * K))
    t.check("A - L C Hurwitz", hurwitz(A - L * C))
    t.check("(9) of Theorem 3.1 at P = Gamma^-1, K, L", negative_definite(_nine(P, Q, K, L, mats, scalars, c)))
    t.observer("obs_control", "continuous", A=A, B=B, C=C, K=K, L=L, E=E, alpha=alpha)


THEOREMS = [obs_control_thm3_1, obs_control_thm3_2]
