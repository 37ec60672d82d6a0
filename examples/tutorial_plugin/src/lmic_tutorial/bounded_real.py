"""The bounded-real lemma: the H-infinity norm of a stable LTI system as an LMI.

Source: S. Boyd, L. El Ghaoui, E. Feron, V. Balakrishnan, *Linear Matrix Inequalities in
System and Control Theory*, SIAM 1994, section 6.3.2 (bounded-real lemma). For
``x' = A x + B w``, ``z = C x + D w``, the H-infinity norm is below ``gamma`` if and only if
there is ``P > 0`` with

    [ A^T P + P A , P B      , C^T      ;
      *           , -gamma I , D^T      ;
      *           , *        , -gamma I ] < 0.

Minimising ``gamma`` gives the norm (the infimum is not attained: the solver returns a value
just above it).
"""

from __future__ import annotations

from lmic.template import STAR, I, Template, block, hurwitz, theorem


@theorem(
    id="tutorial.bounded_real",
    title="Bounded-real lemma: minimal H-infinity norm bound",
    citation="Boyd, El Ghaoui, Feron & Balakrishnan (1994), LMIs in System and Control Theory, sec. 6.3.2",
    kind="analysis",
    objective="minimise gamma (the H-infinity norm of (A, B, C, D))",
    system_class="continuous time, linear, stable",
)
def bounded_real(t: Template) -> None:
    """Bounded-real lemma (Boyd et al. 1994, sec. 6.3.2); ``gamma`` = H-infinity norm bound."""
    n, m, q = t.dims("n m q")
    A = t.data("A", n, n, doc="state matrix (Hurwitz)")
    B = t.data("B", n, m, doc="disturbance input matrix")
    C = t.data("C", q, n, doc="performance output matrix")
    D = t.data("D", q, m, default=0.0, doc="feed-through (optional, zero by default)")
    P = t.symmetric("P", n, pd=True)
    gamma = t.scalar("gamma", sign="positive")
    t.lmi(
        "bounded real",
        block(
            [
                [A.T * P + P * A, P * B, C.T],
                [STAR, -gamma * I(m), D.T],
                [STAR, STAR, -gamma * I(q)],
            ]
        )
        < 0,
    )
    t.minimize(gamma)
    t.check("A Hurwitz", hurwitz(A))


THEOREMS = [bounded_real]
