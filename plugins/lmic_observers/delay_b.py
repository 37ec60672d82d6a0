"""Paper B of the Delshad thesis: H-infinity observers with state and output delays.

Source: S. S. Delshad & T. Gustafsson, *Robust H-infinity observer design for uncertain
nonlinear discrete-time systems with state and output delays*, IJRNC 2015 (thesis Paper B).

Identical to Paper A except ``Omega(2,6) = Ad^T P1 - Cd^T Upsilon^T`` and
``Psi2(6,8) = P1 M2 - Upsilon M4`` (delayed output ``Cd x(k - tau)``, uncertainty
``dCd = M4 F N``); the examples give neither ``Cd`` nor ``M4``, which default to 0. Shared
blocks, typo resolutions and the ``psi1 = printed | corrected`` option:
:mod:`lmic_observers._delay_hinf`.
"""

from __future__ import annotations

from lmic.template import Template, theorem
from lmic_observers._delay_hinf import build_delay_hinf

__all__ = ["delay_b_thm3_1", "delay_b_thm4_1", "THEOREMS"]

_NOTES = (
    "Cd and M4 default to 0 (the examples give neither). eps3 is used but not listed: fixed with "
    "eps2 (eps_free: 1 makes both decision variables). psi1: printed | corrected (the printed Psi1 "
    "applies alpha^-1 to the e block only). tau0 = tau2 - tau1 + 1, or tau0 given. "
    "delta_gamma_max = gamma* - gamma0 (Section 4; gamma0 defaults to 0)."
)


@theorem(
    id="delay_b.thm3_1",
    title="Delay H-infinity observer with delayed output, LMI (16)-(17), eta given",
    citation="Delshad & Gustafsson, IJRNC 2015 (thesis Paper B), Theorem 3.1",
    kind="S",
    objective="min alpha + eps1 (eta given); L = P1^-1 Upsilon, gamma* = 1/sqrt(alpha (1+eps1))",
    system_class="discrete time, Lipschitz f, state and output delays, norm-bounded uncertainty",
    notes=_NOTES + " The statement omits eta and eps3 from its scalars: eta is given.",
)
def delay_b_thm3_1(t: Template) -> None:
    """Paper B, Theorem 3.1 (Section 3), LMIs (16)-(17).

    As Paper A Theorem 3.1 with ``Omega(2,6) = Ad^T P1 - Cd^T Upsilon^T`` and
    ``Psi2(6,8) = P1 M2 - Upsilon M4``; ``min alpha + eps1`` for a given ``eta``. Outputs (18)
    ``L = P1^-1 Upsilon``, ``gamma* = 1/sqrt(alpha (1 + eps1))`` and the admissible Lipschitz
    uncertainty ``delta_gamma_max = gamma* - gamma0`` of Section 4.
    """
    build_delay_hinf(t, paper="B", pareto=False)


@theorem(
    id="delay_b.thm4_1",
    title="Delay H-infinity observer with delayed output, Pareto LMI (16), (48)",
    citation="Delshad & Gustafsson, IJRNC 2015 (thesis Paper B), Theorem 4.1, Examples 1-2, Tables 1-4",
    kind="S",
    objective="min lambda (alpha + eps1) + (1 - lambda) rho; L, gamma* = 1/sqrt(alpha (1+eps1)), eta* = sqrt(rho)",
    system_class="discrete time, Lipschitz f, state and output delays, norm-bounded uncertainty",
    notes=_NOTES + " Tables 1-4 reproduce only approximately (about 10-20 %); the "
    "claims 'tau0 >= 6 (Ex 1) / >= 5 (Ex 2) infeasible' do not hold for the printed LMIs.",
)
def delay_b_thm4_1(t: Template) -> None:
    """Paper B, Theorem 4.1 (Section 4), LMIs (16) and (48).

    ``[Psi1, Omega; *, Psi2] < 0`` (Theorem 3.1 blocks) and (48) (``Psi3`` with ``-rho I``);
    ``min lambda (alpha + eps1) + (1 - lambda) rho``, ``lambda`` in ``[0, 1]`` given. Outputs
    (49) ``L = P1^-1 Upsilon``, ``gamma* = 1/sqrt(alpha* (1 + eps1*))``, ``eta* = sqrt(rho)``,
    and ``delta_gamma_max = gamma* - gamma0``.
    """
    build_delay_hinf(t, paper="B", pareto=True)


THEOREMS = [delay_b_thm3_1, delay_b_thm4_1]
