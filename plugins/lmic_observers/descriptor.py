"""Delshad, Johansson, Darouach & Gustafsson (IFAC 2014), thesis Paper D: reduced-order H-inf filter.

Source: S. S. Delshad, A. Johansson, M. Darouach and T. Gustafsson, *H-inf filter design for
state estimation and unknown inputs reconstruction of a class of nonlinear systems*, IFAC 2014
(thesis Paper D).

System (1): ``x' = A x + B u + D f(x) + D1 w + sum F_i nu_i``, ``y = C x + D2 w + sum G_i nu_i``
(``f: R^n -> R^q`` Lipschitz ``gamma``, ``h`` unknown inputs ``nu``, ``w`` in L2). Augmented
descriptor form (4)-(5) with ``zeta = [x; nu]``: ``eta zeta' = Abar zeta + B u + D f + D1 w``,
``y = Cbar zeta + D2 w`` with ``eta = [I_n 0]``, ``Abar = [A F]``, ``Cbar = [C G]`` (the data
keys ``F`` and ``G`` are ``[F1 ... Fh]`` and ``[G1 ... Gh]``). Filter (7) of order ``q1``:
``z' = N z + L y + G u + M D f(zeta^)``, ``zeta^ = J z + E y``; error (13)
``eps' = N eps + M D df + (L D2 - M D1) w``, ``e = J eps + E D2 w``.

Pre-processing (data-derived constants, Section 3.3): ``[M K] = R [eta; Cbar]^+`` (35)-(36)
from a full-row-rank design matrix ``R`` (q1 x (n+h)); ``T = [M eta; Cbar]``;
``alpha1 = T^+ [I; 0]``, ``alpha2 = T^+ [0; I]``, ``beta1 = (I - T T^+)[I; 0]``,
``beta2 = (I - T T^+)[0; I]`` (38) with ``I - T T^+`` an exact orthogonal projector from an SVD
basis (the naive ``I - T pinv(T)`` leaves ~1e-16 entries that a solver exploits by driving
``Ybar1``, ``Y2`` to ~1e10). Gains (39): ``N = M Abar alpha1 + Y1 beta1``,
``L = M Abar alpha2 + Y1 beta2``, ``G = M B``, ``J = alpha1 + Y2 beta1``, ``E = alpha2 + Y2 beta2``.

The filter's input gain ``G = M B`` is the derived quantity ``Gf`` here, because the data key
``G`` is already the unknown-input output matrix ``[G1 ... Gh]``.

Reference values (checked by ``lmic reproduce``): on the example M from R is exact
(``[1 4 2; -2 4 0; -3 -2 3]``), ``T`` is invertible so ``beta = 0`` and Y1, Y2 have no effect;
N, L, G, J, E reproduce the print (to print precision); (40) is feasible at
(gamma, mu) = (0.45, 2.5); min mu at gamma = 0.45 is ``sqrt(2 (1 + gamma^2)) = 1.5508``; sup
gamma at mu = 2.5 is 1.4577; (20) at the printed gains (48) is feasible at (0.45, 2.5).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import sympy

from lmic.template import STAR, Block, I, Template, block, hurwitz, negative_definite, theorem
from lmic.template.numeric import null_projector, pinv, rank

CITATION = (
    "Delshad, Johansson, Darouach & Gustafsson, 'H-inf filter design for state estimation and "
    "unknown inputs reconstruction of a class of nonlinear systems', IFAC 2014 (Delshad PhD "
    "thesis, Lulea, Paper D)"
)
SYSTEM_CLASS = (
    "continuous time, Lipschitz nonlinearity D f(x), unknown inputs in state and output, "
    "L2 disturbance; reduced-order descriptor filter"
)


# -- the R -> M construction and the alpha, beta matrices (shared with Paper E, uir.py) -------


def _eta(values: Mapping[str, Any]) -> np.ndarray:
    n, h = values["A"].shape[0], values["F"].shape[1]
    return np.hstack([np.eye(n), np.zeros((n, h))])


def _abar(values: Mapping[str, Any]) -> np.ndarray:
    return np.hstack([values["A"], values["F"]])


def _cbar(values: Mapping[str, Any]) -> np.ndarray:
    return np.hstack([values["C"], values["G"]])


def _eta_cbar_pinv(values: Mapping[str, Any]) -> np.ndarray:
    """``[eta; Cbar]^+`` after checking Assumption 2 and the rank conditions (31)-(32) on R."""
    X = np.vstack([values["eta"], values["Cbar"]])
    nh = X.shape[1]
    if rank(X) != nh:
        raise ValueError(
            f"Assumption 2 fails: rank [eta; Cbar] = {rank(X)} < n + h = {nh} (zeta = [x; nu] is not observable)"
        )
    R = values["R"]
    if rank(R) != R.shape[0]:
        raise ValueError(f"R ({R.shape[0]}x{R.shape[1]}) must have full row rank (rank {rank(R)})")
    RC = np.vstack([R, values["Cbar"]])
    if rank(RC) != nh:
        raise ValueError(f"rank [R; Cbar] = {rank(RC)} must equal n + h = {nh} (31)")
    return pinv(X)


def _M(values: Mapping[str, Any]) -> np.ndarray:
    """``M = R [eta; Cbar]^+ [I; 0]`` (36)."""
    n = values["A"].shape[0]
    return (values["R"] @ _eta_cbar_pinv(values))[:, :n]


def _K(values: Mapping[str, Any]) -> np.ndarray:
    """``K = R [eta; Cbar]^+ [0; I]`` (36)."""
    n = values["A"].shape[0]
    return (values["R"] @ _eta_cbar_pinv(values))[:, n:]


def _T(values: Mapping[str, Any]) -> np.ndarray:
    return np.vstack([values["M"] @ values["eta"], values["Cbar"]])


def _alpha1(values: Mapping[str, Any]) -> np.ndarray:
    q1 = values["R"].shape[0]
    return pinv(values["T"])[:, :q1]


def _alpha2(values: Mapping[str, Any]) -> np.ndarray:
    q1 = values["R"].shape[0]
    return pinv(values["T"])[:, q1:]


def _beta1(values: Mapping[str, Any]) -> np.ndarray:
    q1 = values["R"].shape[0]
    return null_projector(values["T"])[:, :q1]


def _beta2(values: Mapping[str, Any]) -> np.ndarray:
    q1 = values["R"].shape[0]
    return null_projector(values["T"])[:, q1:]


def reduced_order_constants(
    t: Template, n: sympy.Symbol, h: sympy.Symbol, p: sympy.Symbol, q1: sympy.Symbol, with_D: bool = True
) -> dict[str, sympy.MatrixExpr]:
    """Declare the data of the R -> M construction and its constants; return them by name.

    Declares the dimensions' data ``A, B, C, F, G, D1, D2, R`` (and ``D`` when ``with_D``) and
    the constants ``eta, Abar, Cbar, M, K, T, alpha1, alpha2, beta1, beta2`` of (4)-(5), (36),
    (38) (Paper D) / (33)-(36) (Paper E).
    """
    m, nw = t.dims("m nw")
    s = {}
    s["A"] = t.data("A", n, n, doc="state matrix")
    s["B"] = t.data("B", n, m, doc="known-input matrix")
    s["C"] = t.data("C", p, n, doc="output matrix")
    if with_D:
        (q,) = t.dims("q")
        s["D"] = t.data("D", n, q, doc="nonlinearity input matrix (f: R^n -> R^q)")
    s["D1"] = t.data("D1", n, nw, doc="disturbance matrix of the state equation")
    s["D2"] = t.data("D2", p, nw, doc="disturbance matrix of the output")
    s["F"] = t.data("F", n, h, doc="unknown-input matrix of the state, [F1 ... Fh]")
    s["G"] = t.data("G", p, h, doc="unknown-input matrix of the output, [G1 ... Gh]")
    s["R"] = t.data("R", q1, n + h, doc="full-row-rank design matrix, rank [R; Cbar] = n + h")
    nh = n + h
    s["eta"] = t.const("eta", _eta, shape=(n, nh), doc="descriptor matrix [I_n 0]")
    s["Abar"] = t.const("Abar", _abar, shape=(n, nh), doc="Abar = [A F]")
    s["Cbar"] = t.const("Cbar", _cbar, shape=(p, nh), doc="Cbar = [C G]")
    s["M"] = t.const("M", _M, shape=(q1, n), doc="M = R [eta; Cbar]^+ [I; 0]")
    s["K"] = t.const("K", _K, shape=(q1, p), doc="K = R [eta; Cbar]^+ [0; I]")
    s["T"] = t.const("T", _T, shape=(q1 + p, nh), doc="T = [M eta; Cbar]")
    s["alpha1"] = t.const("alpha1", _alpha1, shape=(nh, q1), doc="alpha1 = T^+ [I; 0]")
    s["alpha2"] = t.const("alpha2", _alpha2, shape=(nh, p), doc="alpha2 = T^+ [0; I]")
    s["beta1"] = t.const("beta1", _beta1, shape=(q1 + p, q1), doc="(I - T T^+) [I; 0], exact")
    s["beta2"] = t.const("beta2", _beta2, shape=(q1 + p, p), doc="(I - T T^+) [0; I], exact")
    return s


def reduced_order_blocks(
    s: Mapping[str, sympy.MatrixExpr],
    P: sympy.MatrixExpr,
    Ybar1: sympy.MatrixExpr,
    Y2: sympy.MatrixExpr,
    nonlinear_gain: sympy.MatrixExpr,
) -> tuple[sympy.MatrixExpr, ...]:
    """The entries a11, a12, a13, a14, a34 of (40)/(38)/(41) in the variables P, Ybar1, Y2.

    ``nonlinear_gain`` is ``M D`` (Paper D) or ``M`` (Paper E).
    """
    M, Ab, a1, a2, b1, b2 = (s[k] for k in ("M", "Abar", "alpha1", "alpha2", "beta1", "beta2"))
    D1, D2 = s["D1"], s["D2"]
    a11 = a1.T * Ab.T * M.T * P + b1.T * Ybar1.T + P * M * Ab * a1 + Ybar1 * b1
    a12 = P * nonlinear_gain
    a13 = P * M * Ab * a2 * D2 + Ybar1 * b2 * D2 - P * M * D1
    a14 = a1.T + b1.T * Y2.T
    a34 = D2.T * a2.T + D2.T * b2.T * Y2.T
    return a11, a12, a13, a14, a34


def reduced_order_gains(
    t: Template, s: Mapping[str, sympy.MatrixExpr], P: sympy.MatrixExpr, Ybar1: sympy.MatrixExpr, Y2: sympy.MatrixExpr
) -> tuple[sympy.MatrixExpr, ...]:
    """Back-substitution (39)/(37): Y1, N, L, Gf (= M B), J, E; returns N, L, J, E."""
    M, Ab, a1, a2, b1, b2 = (s[k] for k in ("M", "Abar", "alpha1", "alpha2", "beta1", "beta2"))
    Y1 = t.derive("Y1", P.inv() * Ybar1, doc="Y1 = P^-1 Ybar1")
    N = t.derive("N", M * Ab * a1 + Y1 * b1, doc="N = M Abar alpha1 + Y1 beta1")
    L = t.derive("L", M * Ab * a2 + Y1 * b2, doc="L = M Abar alpha2 + Y1 beta2")
    t.derive("Gf", M * s["B"], doc="the filter's input gain G = M B (data G is [G1 ... Gh])")
    J = t.derive("J", a1 + Y2 * b1, doc="J = alpha1 + Y2 beta1")
    E = t.derive("E", a2 + Y2 * b2, doc="E = alpha2 + Y2 beta2")
    return N, L, J, E


def hinf_block(
    P: sympy.MatrixExpr,
    Gamma: sympy.MatrixExpr,
    N: sympy.MatrixExpr,
    L: sympy.MatrixExpr,
    J: sympy.MatrixExpr,
    E: sympy.MatrixExpr,
    nonlinear_gain: sympy.MatrixExpr,
    MD1: sympy.MatrixExpr,
    D2: sympy.MatrixExpr,
    c: sympy.Expr,
    mu_sq: sympy.Expr,
) -> Block:
    """Phi of (20)-(21) (Paper D) / (16)-(17) (Paper E) with ``c = 1 + gamma^2``."""
    return block(
        [
            [N.T * P + P * N + c * J.T * J, P * nonlinear_gain, P * (L * D2 - MD1) + c * J.T * E * D2],
            [STAR, -Gamma, 0],
            [STAR, STAR, c * D2.T * E.T * E * D2 - mu_sq * I(D2.shape[1])],
        ]
    )


# -- the theorems ------------------------------------------------------------------------------


@theorem(
    id="descriptor.thm3_1",
    title="Reduced-order filter stability analysis (14) in (P, Gamma) for given N, J, M",
    citation=CITATION + ", Theorem 3.1, inequalities (14)",
    kind="A",
    objective="feasibility (P, Gamma certify the given filter)",
    system_class=SYSTEM_CLASS,
    notes="Bilinear in (P, N); an LMI in (P, Gamma) for given gains.",
)
def descriptor_thm3_1(t: Template) -> None:
    """Theorem 3.1 (Section 3), inequalities (14).

    ``Gamma - I < 0``, ``[N^T P + P N + gamma^2 J^T J, P M D; *, -Gamma] < 0``, ``P > 0``: the
    error ``eps' = N eps + M D df`` (w = 0) is asymptotically stable and ``e = J eps -> 0``.
    """
    q1, nh, n, q = t.dims("q1 nh n q")
    N = t.data("N", q1, q1, doc="filter matrix N (given)")
    J = t.data("J", nh, q1, doc="filter output matrix J (given)")
    M = t.data("M", q1, n, doc="M (given; from R by (36))")
    D = t.data("D", n, q, doc="nonlinearity input matrix")
    gamma = t.param("gamma", domain="nonnegative", doc="Lipschitz constant of f")
    P = t.symmetric("P", q1, pd=True)
    Gamma = t.symmetric("Gamma", q)
    t.lmi("Gamma - I < 0", block(Gamma - I(q)) < 0)
    t.lmi("(14)", block([[N.T * P + P * N + gamma**2 * J.T * J, P * M * D], [STAR, -Gamma]]) < 0)
    t.check("N Hurwitz (error dynamics (13))", hurwitz(N))
    t.observer("filter_error", "continuous", N=N, J=J)


@theorem(
    id="descriptor.thm3_2",
    title="Reduced-order H-inf filter analysis (20)-(21) in (P, Gamma) for given gains",
    citation=CITATION + ", Theorem 3.2, inequalities (20)-(21)",
    kind="A",
    objective="feasibility (P, Gamma certify the given filter with ||e||_2 < mu ||w||_2)",
    system_class=SYSTEM_CLASS,
    notes="Nonlinear in the gains; an LMI in (P, Gamma) for fixed N, L, M, J, E. The proof's eq "
    "(25) prints the cross term as a product; it is a sum (no effect on (20)).",
)
def descriptor_thm3_2(t: Template) -> None:
    """Theorem 3.2 (Section 3), inequalities (20)-(21).

    ``Gamma - I < 0``, ``P > 0``, ``Phi = [a11, a12, a13; *, -Gamma, 0; *, 0, a33] < 0`` with
    ``a11 = N^T P + P N + (1+gamma^2) J^T J``, ``a12 = P M D``,
    ``a13 = P (L D2 - M D1) + (1+gamma^2) J^T E D2``,
    ``a33 = (1+gamma^2) D2^T E^T E D2 - mu^2 I``.

    Example: the printed (rounded) gains (48) at (gamma, mu) = (0.45, 2.5): feasible.
    """
    q1, nh, n, q, p, nw = t.dims("q1 nh n q p nw")
    N = t.data("N", q1, q1, doc="filter matrix N (given)")
    L = t.data("L", q1, p, doc="filter output-injection gain L (given)")
    M = t.data("M", q1, n, doc="M (given; from R by (36))")
    J = t.data("J", nh, q1, doc="filter output matrix J (given)")
    E = t.data("E", nh, p, doc="filter feed-through gain E (given)")
    D = t.data("D", n, q, doc="nonlinearity input matrix")
    D1 = t.data("D1", n, nw, doc="disturbance matrix of the state equation")
    D2 = t.data("D2", p, nw, doc="disturbance matrix of the output")
    gamma = t.param("gamma", domain="nonnegative", doc="Lipschitz constant of f")
    mu = t.param("mu", domain="positive", doc="disturbance attenuation level")
    P = t.symmetric("P", q1, pd=True)
    Gamma = t.symmetric("Gamma", q)
    t.lmi("Gamma - I < 0", block(Gamma - I(q)) < 0)
    t.lmi("(20)", hinf_block(P, Gamma, N, L, J, E, M * D, M * D1, D2, 1 + gamma**2, mu**2) < 0)
    t.check("N Hurwitz (error dynamics (13))", hurwitz(N))
    t.observer("filter_error", "continuous", N=N, J=J, L=L, M=M, E=E, D1=D1, D2=D2, gamma=mu)


@theorem(
    id="descriptor.thm3_3",
    title="Reduced-order H-inf filter synthesis LMI (40)-(41)",
    citation=CITATION + ", Theorem 3.3, LMI (40)-(41), gains (39)",
    kind="S",
    objective="feasibility (gamma, mu given); Y1 = P^-1 Ybar1, gains N, L, G, J, E by (39)",
    system_class=SYSTEM_CLASS,
    notes="Typos resolved (consistent with Thm 3.2, the derivation and the exact reproduction of "
    "the example): a12 = P M D (printed 'P M'), a13 = P M Abar alpha2 D2 + Ybar1 beta2 D2 - P M D1 "
    "(printed with a stray D: 'P M D Abar alpha2 D2'), a34 with beta2 (printed 'beta'); the rank "
    "conditions (31)-(32) read n + h (printed n). The filter gain G = M B is the derived 'Gf'.",
)
def descriptor_thm3_3(t: Template) -> None:
    """Theorem 3.3 (Section 3), LMI (40)-(41), gains (39).

    ``Gamma - I < 0``, ``P > 0`` and (block sizes q1, q, nw, n + h)
    ``[a11, a12, a13, a14; *, -Gamma, 0, 0; *, *, a33, a34; *, *, *, a44] < 0`` with
    ``a11 = alpha1^T Abar^T M^T P + beta1^T Ybar1^T + P M Abar alpha1 + Ybar1 beta1`` (``N^T P +
    P N``), ``a12 = P M D``, ``a13 = P M Abar alpha2 D2 + Ybar1 beta2 D2 - P M D1`` (``P (L D2 -
    M D1)``), ``a14 = alpha1^T + beta1^T Y2^T`` (``J^T``), ``a33 = -mu^2 I``,
    ``a34 = D2^T alpha2^T + D2^T beta2^T Y2^T`` (``(E D2)^T``), ``a44 = -(1/(1+gamma^2)) I``.
    The Schur complement of ``a44`` gives (20); the certificate also evaluates (20) at the
    recovered gains and the Hurwitz property of N.

    Example (43)-(48): n = 3, h = 2, p = 2, q1 = 3, gamma = 0.45 (printed; the true Lipschitz
    constant of f is 0.602), mu = 2.5: feasible; min mu at gamma = 0.45 is 1.5508.
    """
    n, h, p, q1 = t.dims("n h p q1")
    s = reduced_order_constants(t, n, h, p, q1, with_D=True)
    q = s["D"].shape[1]
    nw = s["D1"].shape[1]
    gamma = t.param("gamma", domain="nonnegative", doc="Lipschitz constant gamma0 of f")
    mu = t.param("mu", domain="positive", doc="disturbance attenuation level")
    P = t.symmetric("P", q1, pd=True)
    Gamma = t.symmetric("Gamma", q)
    Ybar1 = t.full("Ybar1", q1, q1 + p)
    Y2 = t.full("Y2", n + h, q1 + p)
    a11, a12, a13, a14, a34 = reduced_order_blocks(s, P, Ybar1, Y2, s["M"] * s["D"])
    t.lmi("Gamma - I < 0", block(Gamma - I(q)) < 0)
    t.lmi(
        "(40)",
        block(
            [
                [a11, a12, a13, a14],
                [STAR, -Gamma, 0, 0],
                [STAR, STAR, -(mu**2) * I(nw), a34],
                [STAR, STAR, STAR, -(1 / (1 + gamma**2)) * I(n + h)],
            ]
        )
        < 0,
    )
    N, L, J, E = reduced_order_gains(t, s, P, Ybar1, Y2)
    t.derive("MD", s["M"] * s["D"], doc="M D, the nonlinear injection gain")
    t.check("N Hurwitz (error dynamics (13))", hurwitz(N))
    t.observer(
        "ui_filter", "continuous", A=s["A"], B=s["B"], C=s["C"], F=s["F"], G=s["G"], N=N, L=L, M=s["M"], J=J, E=E,
        Gf="Gf", D1=s["D1"], D2=s["D2"], gamma=mu,
    )  # fmt: skip
    M, D, D1, D2 = s["M"], s["D"], s["D1"], s["D2"]
    t.check(
        "(20) at the recovered gains",
        negative_definite(hinf_block(P, Gamma, N, L, J, E, M * D, M * D1, D2, 1 + gamma**2, mu**2)),
    )


THEOREMS = [descriptor_thm3_1, descriptor_thm3_2, descriptor_thm3_3]
