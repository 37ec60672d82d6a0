"""A discrete-time Luenberger observer by a Lyapunov LMI, with a generated audit variant.

For ``x(k+1) = A x(k)``, ``y = C x`` and the observer ``x^(k+1) = A x^ + L (y - C x^)``, the
error ``e(k+1) = (A - L C) e`` converges if some ``P > 0`` satisfies
``(A - L C)^T P (A - L C) - P < 0``; by a Schur complement and ``R = L^T P`` this is the LMI

    [ -P , A^T P - C^T R ;
       * ,      -P       ] < 0,

and the gain is ``L = P^-1 R^T`` (e.g. Boyd et al. 1994, section 5.1, discrete-time Lyapunov
inequality, with the classical change of variables).

``fixes=R`` generates the audit variant: with ``fixed_L: 1`` the gain ``L`` is data (a printed
or hand-tuned gain) and ``R = L^T P`` is substituted, so the same theorem certifies a given gain.
"""

from __future__ import annotations

from lmic.template import STAR, Template, block, theorem


@theorem(
    id="tutorial.observer",
    title="Discrete-time Luenberger observer by a Lyapunov LMI",
    citation="Boyd, El Ghaoui, Feron & Balakrishnan (1994), LMIs in System and Control Theory, sec. 5.1",
    kind="synthesis",
    objective="feasibility; L = P^-1 R^T",
    system_class="discrete time, linear",
)
def observer(t: Template) -> None:
    """Lyapunov LMI for ``A - L C``; ``L = P^-1 R^T`` (``fixed_L: 1`` audits a given L)."""
    n, p = t.dims("n p")
    A = t.data("A", n, n, doc="state matrix")
    C = t.data("C", p, n, doc="output matrix")
    P = t.symmetric("P", n, pd=True)
    R = t.full("R", p, n, doc="R = L^T P")
    t.lmi("Lyapunov", block([[-P, A.T * P - C.T * R], [STAR, -P]]) < 0)
    t.luenberger(A, C, L=P.inv() * R.T, time="discrete", fixes=R)


THEOREMS = [observer]
