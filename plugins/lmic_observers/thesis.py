"""Delshad, PhD thesis (Lulea), Part I: Lyapunov and Lipschitz observer LMIs.

Source: S. S. Delshad, *Observer design for Lipschitz nonlinear systems*, PhD thesis, Lulea
University of Technology (source file 002), Part I chapters 2-4.
"""

from __future__ import annotations

from lmic.template import block, hurwitz, theorem


@theorem(
    id="thesis.lyapunov",
    title="Lyapunov stability LMI (2.9)",
    citation="Delshad, PhD thesis (Lulea), Part I, eq. (2.9)/(2.14), Example 2.3.2",
    kind="A",
    objective="feasibility (P certifies stability of A)",
    system_class="continuous time, linear",
    notes="The example (2.14) uses the non-strict A^T P + P A <= 0; choose it with nonstrict: 1.",
)
def thesis_lyapunov(t):
    """Thesis eq. (2.9): ``P > 0``, ``A^T P + P A < 0`` (or ``<= 0`` with ``nonstrict = 1``)."""
    (n,) = t.dims("n")
    A = t.data("A", n, n, doc="state matrix")
    nonstrict = t.flag("nonstrict", doc="1 for the non-strict A^T P + P A <= 0 of (2.14)")
    P = t.symmetric("P", n)
    t.lmi("P > 0", block(P) > 0)
    lyap = block(A.T * P + P * A)
    if nonstrict:
        t.lmi("(2.14)", lyap <= 0)
    else:
        t.lmi("(2.9)", lyap < 0)
    t.check("A Hurwitz", hurwitz(A))


THEOREMS = [thesis_lyapunov]
