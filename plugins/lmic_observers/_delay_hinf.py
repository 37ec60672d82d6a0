"""The delay H-infinity observer template shared by Papers A and B of the Delshad thesis.

Paper A (``delay_a``) and Paper B (``delay_b``) print the same LMIs except two entries that
carry the delayed-output matrices ``Cd`` and ``M4`` of Paper B:
``Omega(2,6) = Ad^T P1 - Cd^T Upsilon^T`` and ``Psi2(6,8) = P1 M2 - Upsilon M4``. With
``Cd = 0`` and ``M4 = 0`` the two papers coincide. This module builds both from one function,
so a typo resolution made here applies to both.

Setting: DT plant
``x+ = (A + dA) x + (Ad + dAd) x(k - tau(k)) + f(x) + B w``,
``y = (C + dC) x [+ (Cd + dCd) x(k - tau(k))] + D w``, ``tau1 <= tau(k) <= tau2``,
``tau0 = tau2 - tau1 + 1``; uncertainty ``[dA; dAd; dC; dCd] = [M1; M2; M3; M4] F N``,
``F^T F <= I``; performance output ``z = H e``; observer ``x^+ = A x^ + f(x^) + L (y - C x^)``,
``L = P1^-1 Upsilon``; ``gamma* = 1 / sqrt(alpha (1 + eps1))``.

Typo resolutions:

* ``Psi2(5,5)`` printed ``-eps I`` in Paper A is ``-eps2 I`` (Paper B prints ``-eps2 I``).
* ``Omega(2,1)`` printed ``*`` is ``0``; the ``< 0`` printed after ``Omega`` and ``Psi1`` are
  print artefacts (only the assembled block matrix is an LMI).
* ``eps3`` is used but not listed among the scalars; it is fixed with ``eps2`` (as the examples
  do) or, with ``eps_free: 1``, a decision variable like ``eps2``.
* ``Psi1``: the proof bounds ``|f~|^2 <= gamma^2 (|e|^2 + |x|^2)``, so ``alpha^-1 I`` belongs
  to both the ``e`` and ``x`` blocks, while the printed ``Psi1`` applies it to ``e`` only.
  ``psi1: printed`` (default, what the published numbers match best) keeps the 3 x 3 printed
  block; ``psi1: corrected`` uses the 4 x 4 block
  ``[-P1 + H^T H, 0, I, 0; *, (eps2 + tau0 eps3) N^T N - P2, 0, I; *, *, -alpha I, 0;
  *, *, *, -alpha I]`` (``Omega`` gets a fourth zero block row).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import sympy

from lmic.errors import DataError
from lmic.template import STAR, I, Template, block, schur_stable

__all__ = ["build_delay_hinf", "declare_tau0"]


def _is_integer(x: float) -> bool:
    return float(x).is_integer()


def declare_tau0(t: Template) -> sympy.Expr:
    """Parameters ``tau1``, ``tau2`` and ``tau0`` and the constant ``tau0_eff`` used by the LMIs.

    A system gives the delay bounds ``tau1 <= tau(k) <= tau2`` (then ``tau0 = tau2 - tau1 + 1``)
    or ``tau0`` directly (``tau0: 0``, the default, means "compute it from ``tau1``, ``tau2``").
    Given both, they must agree. Each must be a whole number.
    """
    tid = t.theorem_id
    t.param("tau1", default=0.0, domain="nonnegative", doc="lower delay bound tau1 (whole number)")
    t.param("tau2", default=0.0, domain="nonnegative", doc="upper delay bound tau2 (whole number)")
    t.param(
        "tau0",
        default=0.0,
        domain="nonnegative",
        doc="tau0 = tau2 - tau1 + 1 given directly (0: computed from tau1, tau2)",
    )

    def tau0_fn(v: Mapping[str, Any]) -> float:
        tau1, tau2, tau0 = v["tau1"], v["tau2"], v["tau0"]
        for key, val in (("tau1", tau1), ("tau2", tau2), ("tau0", tau0)):
            if not _is_integer(val):
                raise DataError(f"theorem {tid}: parameter {key} = {val:g} must be a whole number")
        if tau2 < tau1:
            raise DataError(f"theorem {tid}: parameters tau1 = {tau1:g}, tau2 = {tau2:g} need tau1 <= tau2")
        from_bounds = tau2 - tau1 + 1
        if tau0 == 0:
            return from_bounds
        if (tau1, tau2) != (0, 0) and tau0 != from_bounds:
            raise DataError(
                f"theorem {tid}: parameter tau0 = {tau0:g} disagrees with tau2 - tau1 + 1 = {from_bounds:g}"
            )
        return tau0

    return t.const("tau0_eff", tau0_fn, doc="tau0 = tau2 - tau1 + 1 (or tau0 as given)")


def build_delay_hinf(t: Template, *, paper: str, pareto: bool) -> None:
    """Declare the Paper A / Paper B delay H-infinity observer theorem on template ``t``.

    Parameters
    ----------
    t : Template
    paper : {"A", "B"}
        ``"B"`` adds the delayed-output data ``Cd`` and ``M4`` (default 0) and their entries.
    pareto : bool
        False: Theorem 3.1 (``eta`` given, ``min alpha + eps1``, ``Psi3`` with ``-eta^2 I``).
        True: Theorem 3.2 (A) / 4.1 (B) (``rho = eta^2`` a variable,
        ``min lambda (alpha + eps1) + (1 - lambda) rho``, ``eta* = sqrt(rho)``).
    """
    n, p, nw, r, s, nz = t.dims("n p nw r s nz")
    A = t.data("A", n, n, doc="state matrix")
    Ad = t.data("Ad", n, n, doc="delayed-state matrix")
    B = t.data("B", n, nw, doc="disturbance matrix of the state equation")
    C = t.data("C", p, n, doc="output matrix")
    D = t.data("D", p, nw, doc="disturbance matrix of the output")
    M1 = t.data("M1", n, r, doc="uncertainty dA = M1 F N")
    M2 = t.data("M2", n, r, doc="uncertainty dAd = M2 F N")
    M3 = t.data("M3", p, r, doc="uncertainty dC = M3 F N")
    N = t.data("N", s, n, doc="uncertainty right factor")
    H = t.data("H", nz, n, doc="performance output z = H e")
    if paper == "B":
        Cd = t.data("Cd", p, n, default=0, doc="delayed-output matrix (default 0)")
        M4 = t.data("M4", p, r, default=0, doc="uncertainty dCd = M4 F N (default 0)")
    tau0 = declare_tau0(t)
    psi1 = t.option(
        "psi1",
        ("printed", "corrected"),
        "printed",
        doc="Psi1 as printed (alpha^-1 on e only) or corrected (alpha^-1 on e and x)",
    )
    eps_free = t.flag("eps_free", doc="1: eps2, eps3 are decision variables instead of given")
    if pareto:
        lam = t.param("lambda", domain="unit", doc="Pareto weight lambda in [0, 1]")
    else:
        eta = t.param("eta", domain="positive", doc="H-infinity disturbance level eta (given)")
    if paper == "B":
        gamma0 = t.param("gamma0", default=0.0, domain="nonnegative", doc="known Lipschitz constant gamma0 of f0")

    P1 = t.symmetric("P1", n)
    P2 = t.symmetric("P2", n)
    Ups = t.full("Upsilon", n, p)
    eps1 = t.scalar("eps1", sign="positive")
    if eps_free:
        eps2 = t.scalar("eps2", sign="positive")
        eps3 = t.scalar("eps3", sign="positive")
    else:
        eps2 = t.param("eps2", domain="positive", doc="scalar eps2 (fixed; eps_free: 1 frees it)")
        eps3 = t.param("eps3", domain="positive", doc="scalar eps3 (fixed; eps_free: 1 frees it)")
    alpha = t.scalar("alpha", sign="positive")
    if pareto:
        rho = t.scalar("rho", sign="positive")

    third = sympy.Rational(1, 3)
    omega26 = Ad.T * P1 - Cd.T * Ups.T if paper == "B" else Ad.T * P1
    psi2_68 = P1 * M2 - Ups * M4 if paper == "B" else P1 * M2
    # Psi1 (rows e, x, alpha-e [, alpha-x]) and Omega (same rows, Psi2's columns)
    z8 = [0] * 8
    rows = [
        [-P1 + H.T * H, 0, I(n)] + ([0] if psi1 == "corrected" else []) + [A.T * P1 - C.T * Ups.T, 0, 0, 0, 0, 0, 0, 0],
        [STAR, (eps2 + tau0 * eps3) * N.T * N - P2, 0]
        + ([I(n)] if psi1 == "corrected" else [])
        + [0, A.T * P2, 0, 0, 0, omega26, Ad.T * P2, 0],
        [STAR, STAR, -alpha] + ([0] if psi1 == "corrected" else []) + z8,
    ]
    if psi1 == "corrected":
        rows.append([STAR, STAR, STAR, -alpha] + z8)
    k1 = len(rows)
    psi2 = [
        [-P1 * third, 0, P1 * third, 0, P1 * M1 - Ups * M3, 0, 0, 0],
        [0, -P2 * third, 0, P2 * third, P2 * M1, 0, 0, 0],
        [STAR, STAR, sympy.Rational(5, 3) * P1 - eps1 * I(n), 0, 0, 0, 0, 0],
        [STAR, STAR, STAR, sympy.Rational(5, 3) * P2 - eps1 * I(n), 0, 0, 0, 0],
        [STAR, STAR, STAR, STAR, -eps2, 0, 0, 0],
        [STAR, STAR, STAR, STAR, STAR, -P1 / (3 * tau0), 0, psi2_68],
        [STAR, STAR, STAR, STAR, STAR, STAR, -P2 / (3 * tau0), P2 * M2],
        [STAR, STAR, STAR, STAR, STAR, STAR, STAR, -eps3 * tau0],
    ]
    for prow in psi2:
        rows.append([STAR] * k1 + prow)

    w = "(43)" if paper == "A" else "(48)"
    t.lmi("P1 > 0", block(P1) > 0)
    t.lmi("P2 > 0", block(P2) > 0)
    big = "(15) [Psi1 Omega; * Psi2]" if paper == "A" else "(16) [Psi1 Omega; * Psi2]"
    t.lmi(big, block(rows) < 0)
    BP1 = B.T * P1 - D.T * Ups.T
    top = -rho if pareto else -(eta**2)
    psi3 = block(
        [
            [top, BP1, B.T * P2, BP1, B.T * P2],
            [STAR, -P1 * third, 0, 0, 0],
            [STAR, STAR, -P2 * third, 0, 0],
            [STAR, STAR, STAR, -1, 0],
            [STAR, STAR, STAR, STAR, -1],
        ]
    )
    if pareto:
        t.lmi(w, psi3 < 0)
        t.minimize(lam * (alpha + eps1) + (1 - lam) * rho)
    else:
        t.lmi("(16) Psi3" if paper == "A" else "(17) Psi3", psi3 < 0)
        t.minimize(alpha + eps1)

    L = t.derive("L", P1.inv() * Ups, doc="observer gain L = P1^-1 Upsilon")
    gstar = t.derive("gamma_star", 1 / sympy.sqrt(alpha * (1 + eps1)), doc="gamma* = 1/sqrt(alpha (1 + eps1))")
    if pareto:
        t.derive("eta_star", sympy.sqrt(rho), doc="eta* = sqrt(rho)")
    if paper == "B":
        t.derive(
            "delta_gamma_max",
            gstar - gamma0,
            doc="admissible Lipschitz uncertainty delta gamma_max = gamma* - gamma0 (Section 4)",
        )
    t.check("A - L C Schur stable", schur_stable(A - L * C), doc="nominal delay-free error dynamics")
    delayed = {"Cd": Cd, "MCd": M4} if paper == "B" else {}
    t.observer(
        "robust", "discrete", A=A, C=C, L=L, Ad=Ad, D1=B, D2=D, MA=M1, MAd=M2, MC=M3, NF=N, Hz=H,
        gamma="eta_star" if pareto else "eta", tau0="tau0_eff", tau1="tau1", tau2="tau2", **delayed,
    )  # fmt: skip
