"""Paper A of the Delshad thesis: H-infinity observers for uncertain nonlinear DT delay systems.

Source: S. S. Delshad & T. Gustafsson, *H-infinity observer design for uncertain nonlinear
discrete-time systems with time-delay: LMI optimization approach*, MED 2012 (thesis Paper A).

The LMIs, their typo resolutions and the ``psi1 = printed | corrected`` option are shared with
Paper B and documented in :mod:`lmic_observers._delay_hinf`.
"""

from __future__ import annotations

from lmic.template import Template, theorem
from lmic_observers._delay_hinf import build_delay_hinf

__all__ = ["delay_a_thm3_1", "delay_a_thm3_2", "THEOREMS"]

_NOTES = (
    "Psi2(5,5) printed -eps I is -eps2 I; Omega(2,1) printed * is 0. eps3 is used but not listed: "
    "fixed with eps2 (eps_free: 1 makes both decision variables). psi1: printed | corrected "
    "(the printed Psi1 applies alpha^-1 to the e block only). tau0 = tau2 - tau1 + 1, or tau0 given."
)


@theorem(
    id="delay_a.thm3_1",
    title="Delay H-infinity observer LMI (15)-(16), eta given",
    citation="Delshad & Gustafsson, MED 2012 (thesis Paper A), Theorem 3.1",
    kind="S",
    objective="min alpha + eps1 (eta given); L = P1^-1 Upsilon, gamma* = 1/sqrt(alpha (1+eps1))",
    system_class="discrete time, Lipschitz f, time-varying state delay, norm-bounded uncertainty",
    notes=_NOTES + " eta is listed among the scalars but the objective is min alpha + eps1: eta is given.",
)
def delay_a_thm3_1(t: Template) -> None:
    """Paper A, Theorem 3.1 (Section 3), LMIs (15)-(16).

    ``[Psi1, Omega; *, Psi2] < 0`` and ``Psi3 < 0`` (``-eta^2 I`` in its (1,1) block), with
    ``P1 > 0``, ``P2 > 0``, ``eps1, eps2, eps3, alpha > 0``; ``min alpha + eps1``.
    Outputs ``L = P1^-1 Upsilon`` and ``gamma* = 1/sqrt(alpha (1 + eps1))``; the check
    ``A - L C`` Schur stable is implied by the LMI (principal block ``3 (A-LC)^T P1 (A-LC) < P1``).
    Blocks and typo resolutions: :mod:`lmic_observers._delay_hinf`.
    """
    build_delay_hinf(t, paper="A", pareto=False)


@theorem(
    id="delay_a.thm3_2",
    title="Delay H-infinity observer, Pareto LMI (15), (43)",
    citation="Delshad & Gustafsson, MED 2012 (thesis Paper A), Theorem 3.2, example (44)-(46)",
    kind="S",
    objective="min lambda (alpha + eps1) + (1 - lambda) rho; L, gamma* = 1/sqrt(alpha (1+eps1)), eta* = sqrt(rho)",
    system_class="discrete time, Lipschitz f, time-varying state delay, norm-bounded uncertainty",
    notes=_NOTES + " lambda in [0, 1] is user-chosen. The published gamma* = 0.335 is not reproducible "
    "eta* = 2.3787 at the published P1, P2, Upsilon is.",
)
def delay_a_thm3_2(t: Template) -> None:
    """Paper A, Theorem 3.2 (Section 3), LMIs (15) and (43).

    ``[Psi1, Omega; *, Psi2] < 0`` and (43) (``Psi3`` with ``-rho I``, ``rho = eta^2``);
    ``min lambda (alpha + eps1) + (1 - lambda) rho`` for a given ``lambda`` in ``[0, 1]``.
    Outputs ``L = P1^-1 Upsilon``, ``gamma* = 1/sqrt(alpha (1 + eps1))``, ``eta* = sqrt(rho)``.
    Blocks and typo resolutions: :mod:`lmic_observers._delay_hinf`.
    """
    build_delay_hinf(t, paper="A", pareto=True)


THEOREMS = [delay_a_thm3_1, delay_a_thm3_2]
