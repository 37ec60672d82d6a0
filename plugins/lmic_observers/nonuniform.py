"""Observer for Lipschitz CT systems with nonuniformly sampled measurements.

Source: *Observer for Lipschitz nonlinear continuous-time systems with nonuniformly sampled
measurements* (conference paper; the authors are not in the text; the proof follows
Naghshtabrizi, Hespanha & Teel, reference [7] of the paper).

System ``x' = A x + rho(t, u) + G sigma(H x)``, ``y_k = C x(t_k)``, ``sigma`` Lipschitz with
constant gamma (2), sampling intervals ``delta_k <= delta_bar``. Observer (3):
``x^' = A x^ + rho + G sigma(H x^) + L (C x^(t_k) - y_k)`` on ``[t_k, t_{k+1})``; note the sign:
the error is ``e' = A e + G v + L C e(t_k)`` (5), so ``A + L C`` must be Hurwitz and the gains
are "negative". Dimensions: n states, q outputs, m = dim sigma (G: n x m, H: m x n).

Fixed gains (audits): with ``fixed_L: 1`` the gain ``L`` is data and ``L~ = P L`` is
substituted, so the LMIs are in ``(P, N1, N2, N3)`` only.
"""

from __future__ import annotations

from lmic.template import STAR, I, Template, block, hurwitz, theorem

__all__ = ["THEOREMS"]


@theorem(
    id="nonuniform.thm1",
    title="Observer with nonuniformly sampled measurements, LMIs (9a)-(9b)",
    citation="Observer for Lipschitz nonlinear continuous-time systems with nonuniformly "
    "sampled measurements (conference paper), Theorem 1 (Section II)",
    kind="synthesis",
    objective="feasibility; L = P^-1 L~",
    system_class="continuous time, Lipschitz sigma(H x), sampled output (intervals <= delta_bar)",
    notes="(9a) is extracted column-first; its printed (2,1) block lost a transpose (C^T L~^T). "
    "Every block re-derived from the proof. fixed_L: 1 audits a given gain (L~ = P L).",
)
def nonuniform_thm1(t: Template) -> None:
    """Theorem 1 (Section II, Main result): LMIs (9a) and (9b), with ``d = delta_bar``, ``P > 0``:

    ``(9a) [(1+d)(PA + A^T P) + g^2 H^T H - P - N1 - N1^T, (1+d) L~C + P - d A^T P + N1 - N2^T,
    (1+d) PG - N3^T, d A^T P; *, -d(L~C + C^T L~^T) - P + N2 + N2^T, -d PG + N3^T, d C^T L~^T;
    *, *, -I, d G^T P; *, *, *, -d P] < 0`` (block sizes n, n, m, n),

    ``(9b) [PA + A^T P + g^2 H^T H - P - N1 - N1^T, L~C + P + N1 - N2^T, PG - N3^T, d A^T P, d N1;
    *, -P + N2 + N2^T, N3^T, d C^T L~^T, d N2; *, *, -I, d G^T P, d N3; *, *, *, -d P, 0;
    *, *, *, *, -d P] < 0`` (block sizes n, n, m, n, n); the gain is ``L = P^-1 L~`` (stated
    with Theorem 1).

    Typo resolutions: (9a) is printed as a full 4 x 4 matrix whose text lists the first column
    first; (9b) is row-wise with split superscripts (``NT 1`` = N1^T). The printed (2,1)
    block of (9a), ``(1+d) C^T L~ + P - d P A + N1^T - N2``, lost the transpose on L~ (it is
    the transpose of (1,2)). Every block was re-derived from the proof of Theorem 1:
    ``xi = [e; eps; v]``, (9a) = ``R1 + d R3``, (9b) = ``R1 + d R2`` with ``d Q2`` and ``d R2``
    Schur-complemented, ``R2 = N P^-1 N^T`` (printed ``N^T P^-1 N``, a transposition slip).
    ``delta`` (the lower bound on the intervals) does not enter the LMIs. (9b) implies
    ``P (A + L C) + (A + L C)^T P + g^2 H^T H < 0`` (test vector ``[v; v; 0; 0; 0]``), hence the
    check ``A + L C`` Hurwitz.

    Reference (Section III, Examples; ``lmic reproduce``): A. flexible joint robotic arm
    (printed data) feasible; the published
    L fails (with the printed C, A + L_pub C has eigenvalue +62.7; with C = [I2 0] (9) is still
    infeasible; reading -52 as -5.2 it is certified up to gamma = 4.164). Chua (gamma = 5.9
    inferred; B. Chua's circuit) feasible; the published Chua L is certified only for
    gamma <= 3.227.
    """
    n, q, m = t.dims("n q m")
    A = t.data("A", n, n, doc="state matrix")
    C = t.data("C", q, n, doc="output matrix (sampled)")
    G = t.data("G", n, m, doc="nonlinearity input matrix, G sigma(H x)")
    H = t.data("H", m, n, doc="nonlinearity argument matrix, sigma(H x)")
    g = t.param("gamma", domain="nonnegative", doc="Lipschitz constant of sigma (2)")
    d = t.param("delta_bar", domain="positive", doc="upper bound on the sampling intervals")
    P = t.symmetric("P", n, pd=True)
    Lt = t.full("Lt", n, q, doc="L~ = P L")
    N1 = t.full("N1", n, n)
    N2 = t.full("N2", n, n)
    N3 = t.full("N3", m, n)
    PA = P * A
    LtC = Lt * C
    PG = P * G
    top = PA + A.T * P + g**2 * H.T * H - P - N1 - N1.T
    t.lmi(
        "(9a)",
        block(
            [
                [
                    top + d * (PA + A.T * P),
                    (1 + d) * LtC + P - d * A.T * P + N1 - N2.T,
                    (1 + d) * PG - N3.T,
                    d * A.T * P,
                ],
                [STAR, -d * (LtC + C.T * Lt.T) - P + N2 + N2.T, -d * PG + N3.T, d * C.T * Lt.T],
                [STAR, STAR, -I(m), d * G.T * P],
                [STAR, STAR, STAR, -d * P],
            ]
        )
        < 0,
    )
    t.lmi(
        "(9b)",
        block(
            [
                [top, LtC + P + N1 - N2.T, PG - N3.T, d * A.T * P, d * N1],
                [STAR, -P + N2 + N2.T, N3.T, d * C.T * Lt.T, d * N2],
                [STAR, STAR, -I(m), d * G.T * P, d * N3],
                [STAR, STAR, STAR, -d * P, 0],
                [STAR, STAR, STAR, STAR, -d * P],
            ]
        )
        < 0,
    )
    L = t.derive("L", P.inv() * Lt, doc="observer gain L = P^-1 L~", fixes=Lt)  # fixed_L: 1 -> L~ = P L
    t.check("A + L C Hurwitz", hurwitz(A + L * C))
    t.observer("sampled", "sampled", A=A, C=C, L=L)


THEOREMS = [nonuniform_thm1]
