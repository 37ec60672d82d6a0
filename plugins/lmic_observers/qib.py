"""Wang, Song & Zhang (2015): DT observers for generalised Lipschitz (QIB) nonlinearities.

Source: Y. Wang, Y. Song, W. Zhang, *State estimation for discrete-time systems with
generalized Lipschitz nonlinear dynamics*, Advances in Difference Equations 2015:307.
System ``x(k+1) = A x + B u + f(x, y)``, ``y = C x``, with the quadratic inner-boundedness
(QIB) condition ``|f(x) - f(x^)|^2 <= beta |x - x^|^2 + gamma <x - x^, f(x) - f(x^)>``
(Assumption 1; beta, gamma any reals); a Lipschitz f (constant lambda, Assumption 2) is QIB
with ``beta = lambda^2``, ``gamma = 0``.

Every LMI of the paper is homogeneous (no constant blocks): the margin of a strict solve is
scale-free, and a near-zero point says nothing (the certifier judges margins relative to
the term scale).

Fixed gains (audits): ``fixed_L: 1`` (full order, ``R = L^T P`` substituted) and
``fixed_K: 1`` (reduced order, (21) in ``(P, omega)`` with ``K`` given).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
import sympy

from lmic.errors import DataError
from lmic.template import STAR, I, Template, block, schur_stable, theorem

__all__ = ["THEOREMS", "reduced_coordinates"]

CITATION = "Wang, Song & Zhang (2015), Adv. Difference Equ. 2015:307"


def _full_order(t: Template) -> tuple[Any, ...]:
    """Data, ``P > 0``, ``R``, ``omega`` and ``X = A^T P - C^T R`` of LMIs (7) and (13)."""
    n, p = t.dims("n p")
    A = t.data("A", n, n, doc="state matrix")
    C = t.data("C", p, n, doc="output matrix")
    P = t.symmetric("P", n, pd=True)
    R = t.full("R", p, n, doc="R = L^T P")
    w = t.scalar("omega", sign="positive")
    return n, A, C, P, R, w, A.T * P - C.T * R


@theorem(
    id="qib.thm1",
    title="Full-order observer for QIB nonlinear DT systems, LMI (7)",
    citation=CITATION + ", Theorem 1",
    kind="synthesis",
    objective="feasibility; L = P^-1 R^T",
    system_class="discrete time, QIB (beta, gamma) nonlinearity",
    notes="Checked against the proof of Theorem 1 (Section 3); L = P^-1 R^T (R = L^T P). "
    "The LMI is homogeneous in (P, R, omega). fixed_L: 1 audits a given gain.",
)
def qib_thm1(t: Template) -> None:
    """Theorem 1 (Section 3, Full-order observer design), LMI (7).

    ``[-P + 2 w beta I, A^T P - C^T R + w gamma I, A^T P - C^T R; *, P - 2 w I, 0; *, *, -P] < 0``
    with ``P > 0``, ``w > 0``; the observer gain is ``L = P^-1 R^T``.

    Reference (Section 5, the flexible-joint example, Euler step Te = 0.1, beta = 0.00110889,
    gamma = 0): the printed (P, R, omega) is a certificate (lambda_max of (7) = -0.05581);
    a fresh solve gives L = [1 0.1; -4.86 2.5134; 0 0.4295; 0.195 0.0264] (rho = 0.3525),
    essentially the printed L; the printed L is certified with ``fixed_L: 1``.
    """
    n, A, C, P, R, w, X = _full_order(t)
    beta = t.param("beta", domain="real", doc="QIB constant beta")
    gamma = t.param("gamma", default=0.0, domain="real", doc="QIB constant gamma")
    t.lmi(
        "(7)",
        block(
            [
                [-P + 2 * w * beta * I(n), X + w * gamma * I(n), X],
                [STAR, P - 2 * w * I(n), 0],
                [STAR, STAR, -P],
            ]
        )
        < 0,
    )
    t.luenberger(A, C, L=P.inv() * R.T, fixes=R, doc="observer gain L = P^-1 R^T")


@theorem(
    id="qib.cor1",
    title="Full-order observer for Lipschitz DT systems, LMI (13)",
    citation=CITATION + ", Corollary 1",
    kind="synthesis",
    objective="feasibility; L = P^-1 R^T",
    system_class="discrete time, Lipschitz (constant lambda)",
    notes="Theorem 1 with beta = lambda^2, gamma = 0 and omega renamed (2 omega -> omega). "
    "Homogeneous. fixed_L: 1 audits a given gain.",
)
def qib_cor1(t: Template) -> None:
    """Corollary 1 (Section 3), LMI (13).

    ``[-P + w lambda^2 I, A^T P - C^T R, A^T P - C^T R; *, P - w I, 0; *, *, -P] < 0``,
    ``P > 0``, ``w > 0``; ``L = P^-1 R^T``. This is Theorem 1 with ``beta = lambda^2``,
    ``gamma = 0`` and ``2 w`` renamed ``w``.

    Reference (Section 5, flexible joint, lambda = 0.0333): feasible,
    L = [1 0.1; -4.86 2.5104; 0 0.428; 0.195 0.0255].
    """
    n, A, C, P, R, w, X = _full_order(t)
    lam = t.param("lambda", domain="positive", doc="Lipschitz constant lambda of f")
    t.lmi("(13)", block([[-P + w * lam**2 * I(n), X, X], [STAR, P - w * I(n), 0], [STAR, STAR, -P]]) < 0)
    t.luenberger(A, C, L=P.inv() * R.T, fixes=R, doc="observer gain L = P^-1 R^T")


def reduced_coordinates(H: np.ndarray, C: np.ndarray, where: str = "") -> tuple[np.ndarray, np.ndarray]:
    """``[N M] = [H; C]^-1`` of (15), split after the first ``n - p`` columns.

    Raises :class:`DataError` (prefixed by ``where``) when ``[H; C]`` is singular.

    Examples
    --------
    >>> N, M = reduced_coordinates(np.array([[0.0, 1.0]]), np.array([[1.0, 0.0]]))
    >>> N.ravel().tolist(), M.ravel().tolist()
    ([0.0, 1.0], [1.0, 0.0])
    """
    T = np.vstack([np.atleast_2d(H), np.atleast_2d(C)])
    if T.shape[0] != T.shape[1] or np.linalg.cond(T) > 1e12:
        raise DataError(f"{where}data 'H': [H; C] must be square and nonsingular (15)")
    Tinv = np.linalg.inv(T)
    k = np.atleast_2d(H).shape[0]
    return Tinv[:, :k], Tinv[:, k:]


def _check_nm(tid: str) -> Callable[[Mapping[str, Any]], float]:
    def rule(v: Mapping[str, Any]) -> float:
        reduced_coordinates(v["H"], v["C"], f"theorem {tid}: ")  # [H; C] nonsingular
        T = np.vstack([v["H"], v["C"]])
        NM = np.hstack([v["N"], v["M"]])
        err = float(np.max(np.abs(T @ NM - np.eye(T.shape[0]))))
        if err > 1e-9 * max(1.0, float(np.max(np.abs(T))) * float(np.max(np.abs(NM)))):
            raise DataError(
                f"theorem {tid}: data 'N', 'M' must satisfy [N M] = [H; C]^-1 (15) "
                f"(max |[H; C][N M] - I| = {err:.3g}); omit N and M to have them computed"
            )
        return err

    return rule


def _reduced_order(t: Template, beta: sympy.Symbol, gamma: sympy.Symbol | None) -> None:
    """Theorem 2 / Corollary 2: (26) with P = alpha I, or (21) with K fixed (``fixed_K: 1``).

    ``gamma`` is ``None`` for Corollary 2 (the (1,2) block is 0).
    """
    tid = t.theorem_id
    n, p = t.dims("n p")
    t.data("A", n, n, doc="state matrix (enters through A_Z, C_Z)")
    C = t.data("C", p, n, doc="output matrix")
    H = t.data("H", n - p, n, doc="z = H x, [H; C] nonsingular (14)-(15)")
    where = f"theorem {tid}: "
    N = t.data(
        "N",
        n,
        n - p,
        default=lambda v, r, c: reduced_coordinates(v["H"], v["C"], where)[0],
        doc="[N M] = [H; C]^-1 (15); computed when omitted",
    )
    t.data(
        "M",
        n,
        p,
        default=lambda v, r, c: reduced_coordinates(v["H"], v["C"], where)[1],
        doc="[N M] = [H; C]^-1 (15), enters the observer (18) only; computed when omitted",
    )
    alpha = t.param(
        "alpha", default=1.0, domain="positive", doc="P = alpha I (Remark 2); (26) is homogeneous in (alpha, omega)"
    )
    fixed = t.flag("fixed_K", doc="1: K is given as data and P is free (LMI (21) in P, omega)")
    t.const("NM_check", _check_nm(tid), doc="checks [N M] = [H; C]^-1 (15)")
    AZ = t.const("A_Z", lambda v: v["H"] @ v["A"] @ v["N"], shape=(n - p, n - p), doc="A_Z = H A N")
    CZ = t.const("C_Z", lambda v: v["C"] @ v["A"] @ v["N"], shape=(p, n - p), doc="C_Z = C A N")
    w = t.scalar("omega", sign="positive")
    if fixed:
        K = t.data("K", n - p, p, doc="the reduced-order gain to audit (fixed_K = 1)")
        P = t.symmetric("P", n, pd=True)
        a11 = -N.T * P * N + 2 * w * beta * N.T * N
        a13 = (AZ - K * CZ).T * N.T * P
        a23 = (H - K * C).T * N.T * P
        a33 = -P
        name = "(21)" if gamma is not None else "(27)"
    else:
        K = t.full("K", n - p, p, doc="reduced-order observer gain")
        a11 = (-alpha + 2 * w * beta) * N.T * N
        a13 = alpha * (AZ - K * CZ).T * N.T
        a23 = alpha * (H - K * C).T * N.T
        a33 = -alpha * I(n)
        name = "(26)" if gamma is not None else "(27) with P = alpha I"
    a12 = 0 if gamma is None else w * gamma * N.T
    t.lmi(name, block([[a11, a12, a13], [STAR, -2 * w * I(n), a23], [STAR, STAR, a33]]) < 0)
    t.check("A_Z - K C_Z Schur stable", schur_stable(AZ - K * CZ))
    t.observer("reduced", "discrete", A="A", C=C, H=H, N=N, M="M", K=K)


@theorem(
    id="qib.thm2",
    title="Reduced-order observer for QIB nonlinear DT systems, LMI (26) (Remark 2, P = alpha I)",
    citation=CITATION + ", Theorem 2 and Remark 2",
    kind="synthesis",
    objective="feasibility; gain K",
    system_class="discrete time, QIB (beta, gamma) nonlinearity, reduced-order observer",
    notes="(21) is bilinear (P K); Remark 2's P = alpha I gives the LMI (26) in (K, omega). "
    "fixed_K: 1 gives (21) in (P, omega) for a given K. The published K is infeasible.",
)
def qib_thm2(t: Template) -> None:
    """Theorem 2 (Section 4, Reduced-order observer design), LMI (21), and Remark 2, LMI (26).

    Reduced coordinates (14)-(15): ``z = H x``, ``[H; C]^-1 = [N M]``, ``A_Z = H A N``,
    ``C_Z = C A N``; error ``eps(k+1) = (A_Z - K C_Z) eps + (H - K C) dg`` (20).

    ``(21) [-N^T P N + 2 w beta N^T N, w gamma N^T, (A_Z - K C_Z)^T N^T P;
    *, -2 w I, (H - K C)^T N^T P; *, *, -P] < 0`` is bilinear in (P, K) (the paper says so).
    Default form: Remark 2, ``P = alpha I`` with alpha given,
    ``(26) [(-alpha + 2 w beta) N^T N, w gamma N^T, alpha (A_Z - K C_Z)^T N^T;
    *, -2 w I, alpha (H - K C)^T N^T; *, *, -alpha I] < 0`` in (K, w). (26) is homogeneous in
    (alpha, w): its feasibility does not depend on alpha. With ``fixed_K: 1`` the gain K is
    data and (21) is an LMI in (P, w), ``P > 0``.

    The text says "by solving the LMI (21)" with alpha given: it must mean (26). N and M may be
    given (the example prints them; they must equal [H; C]^-1) or are computed.

    Result (Section 5): on the flexible-joint example (26) is infeasible for every
    alpha and K (C_Z's second column is 0, so ||A_Z - K C_Z|| >= sqrt(2)); the published
    K = [0 0.2057; 0 -0.0401] is the least-infeasible point of (26). With K_pub fixed, (21) is
    marginally infeasible (phase-1 t* = 5.9e-11): solvers may return an 'inaccurate' point with
    a tiny violation, which must not be certified. The dead-beat K = [0 0.4115; 0 0.1656] is
    feasible in (21).
    """
    beta = t.param("beta", domain="real", doc="QIB constant beta")
    gamma = t.param("gamma", default=0.0, domain="real", doc="QIB constant gamma")
    _reduced_order(t, beta, gamma)


@theorem(
    id="qib.cor2",
    title="Reduced-order observer for Lipschitz DT systems, LMI (27) with P = alpha I",
    citation=CITATION + ", Corollary 2",
    kind="synthesis",
    objective="feasibility; gain K",
    system_class="discrete time, Lipschitz (constant lambda), reduced-order observer",
    notes="Theorem 2 with beta = lambda^2, gamma = 0 (the factor 2 of 2 omega stays). "
    "P = alpha I as in Remark 2; fixed_K: 1 gives (27) in (P, omega).",
)
def qib_cor2(t: Template) -> None:
    """Corollary 2 (Section 4), LMI (27):

    ``[-N^T P N + 2 w lambda^2 N^T N, 0, (A_Z - K C_Z)^T N^T P; *, -2 w I, (H - K C)^T N^T P;
    *, *, -P] < 0``: Theorem 2 with ``beta = lambda^2``, ``gamma = 0`` (unlike Corollary 1,
    omega is not rescaled). As for Theorem 2 the default form sets ``P = alpha I`` (Remark 2),
    an LMI in (K, w); ``fixed_K: 1`` gives (27) in (P, w) for a given K.

    Reference (Section 5, flexible joint, lambda = 0.0333): infeasible (same proof as
    Theorem 2).
    """
    lam = t.param("lambda", domain="positive", doc="Lipschitz constant lambda of f")
    _reduced_order(t, lam**2, None)


THEOREMS = [qib_thm1, qib_cor1, qib_thm2, qib_cor2]
