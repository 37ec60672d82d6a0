"""Wang, Song & Zhang (2015): DT observers for generalised Lipschitz (QIB) nonlinearities.

Source: Y. Wang, Y. Song, W. Zhang, *State estimation for discrete-time systems with
generalized Lipschitz nonlinear dynamics*, Advances in Difference Equations 2015:307.
System ``x(k+1) = A x + B u + f(x, y)``, ``y = C x``, with the quadratic inner-boundedness
(QIB) condition ``|f(x) - f(x^)|^2 <= beta |x - x^|^2 + gamma <x - x^, f(x) - f(x^)>``.
"""

from __future__ import annotations

from lmic.template import STAR, I, block, schur_stable, theorem


@theorem(
    id="qib.thm1",
    title="Full-order observer for QIB nonlinear DT systems, LMI (7)",
    citation="Wang, Song & Zhang (2015), Adv. Difference Equ. 2015:307, Theorem 1",
    kind="S",
    objective="feasibility; L = P^-1 R^T",
    system_class="discrete time, QIB (beta, gamma) nonlinearity",
    notes="Checked against the proof (lines 102-132 of the source); L = P^-1 R^T (R = L^T P). "
    "The LMI is homogeneous in (P, R, omega).",
)
def qib_thm1(t):
    """Theorem 1 (source 003, line 95), LMI (7).

    ``[-P + 2 w beta I, A^T P - C^T R + w gamma I, A^T P - C^T R; *, P - 2 w I, 0; *, *, -P] < 0``
    with ``P > 0``, ``w > 0``; the observer gain is ``L = P^-1 R^T``.
    """
    n, p = t.dims("n p")
    A = t.data("A", n, n, doc="state matrix")
    C = t.data("C", p, n, doc="output matrix")
    beta = t.param("beta", domain="real", doc="QIB constant beta")
    gamma = t.param("gamma", default=0.0, domain="real", doc="QIB constant gamma")
    P = t.symmetric("P", n)
    R = t.full("R", p, n)
    w = t.scalar("omega", sign="positive")
    X = A.T * P - C.T * R
    t.lmi("P > 0", block(P) > 0)
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
    L = t.derive("L", P.inv() * R.T, doc="observer gain L = P^-1 R^T")
    t.check("A - L C Schur stable", schur_stable(A - L * C))


THEOREMS = [qib_thm1]
