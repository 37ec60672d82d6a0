"""Verification of dual (Farkas) certificates of infeasibility, from the IR alone.

The problem is: find ``x`` with ``F_i(x) >= 0`` (``> 0`` when strict) for every LMI, and
linear rows ``l_r(x) = a_r0 + a_r . x`` that are ``== 0`` (``eq``) or ``>= 0`` / ``> 0``
(``ge``). A certificate is ``{"lmis": [Z_i], "linear": y}`` (the layout of
:attr:`lmic.solution.Solution.farkas`; ``Z_i`` dense symmetric, paired with the normalised
``F_i``, i.e. the conic-dual convention ``z in K*``). Write

    ``g_k = sum_i <F_i^(k), Z_i> + sum_r a_rk y_r``   for ``k = 0 .. n``

(``<A, B> = trace(A B)``; ``F_i^(0)`` and ``a_r0`` are the constant terms). For every ``x``

    ``sum_i <F_i(x), Z_i> + sum_r y_r l_r(x) = g_0 + sum_{k >= 1} x_k g_k``.        (*)

Conditions
----------
Signs: ``Z_i >= 0`` and ``y_r >= 0`` on ``ge`` rows (``y_r`` is free on ``eq`` rows). Then at a
feasible ``x`` the left side of (*) is ``>= 0``.

* **Closed infeasibility** (proves the non-strict problem, hence also the strict one,
  infeasible): ``g_k = 0`` for ``k >= 1`` and ``g_0 < 0``: (*) would give ``0 <= g_0 < 0``.
* **Strict infeasibility** (proves only the strict problem infeasible): ``g_k = 0`` for
  ``k >= 1``, ``g_0 <= 0`` and ``tau > 0``, where ``tau = sum_{i strict} tr Z_i +
  sum_{r strict} y_r``. If ``F_i(x) >= mu I`` on the strict LMIs and ``l_r(x) >= mu`` on the
  strict rows, the left side of (*) is ``>= mu tau``, so ``mu <= g_0 / tau <= 0``. This is the
  certificate of a homogeneous strict LMI (``F0 = 0``, ``g_0 = 0``, e.g. ``A^T P + P A < 0,
  P > 0`` for an unstable ``A``) and of the max-margin reduction of :mod:`lmic.backends.strict`.

With floating-point certificates the equalities hold only approximately. The verifier first
projects each ``Z_i`` onto the PSD cone and clips ``y`` on ``ge`` rows to ``>= 0`` (the part
removed must be below ``tol`` relative to ``eta = sum tr Z_i + sum |y_r|``; the certificate is
rescaled to ``eta = 1``), then recomputes ``g`` from the repaired certificate, so the sign
conditions hold by construction and only these tolerances remain, each relative:

``rel_residual = max_k |g_k| / c_k <= tol`` with ``c_k = sum_i ||F_i^(k)||_F + sum_r |a_rk|``
(how much ``x_k`` can move the constraints; with ``eta = 1`` this bounds the relative margin a
point could still have, since ``|<F_i^(k), Z_i>| <= ||F_i^(k)||_F``), and ``g_0 < -tol c_0``
(closed), or ``g_0 <= tol c_0`` and ``tau >= tol`` (strict).

What a verified float certificate proves, quantitatively, is reported: for the closed case
no feasible ``x`` with ``||x||_inf < radius = -g_0 / ||g_{1:}||_1``; for the strict case no
``x`` with margin ``mu > margin_bound = (g_0 + ||g_{1:}||_1 ||x||_inf) / tau`` (reported for
``||x||_inf = 1``; the margin bound scales with ``||x||`` for homogeneous problems, so it is a
bound on the *relative* margin).

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
>>> # p >= 0 and -1 - p >= 0 cannot both hold: Z = [[1]], [[1]] gives g0 = -1, g1 = 0
>>> p = Problem([Variable("p", "scalar", (1, 1))],
...             [LMI("p >= 0", 1, sp.csc_matrix([[0., 1.]]), strict=False),
...              LMI("-1 - p >= 0", 1, sp.csc_matrix([[-1., -1.]]), strict=False)],
...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
>>> r = verify_farkas(p, {"lmis": [np.eye(1), np.eye(1)], "linear": []})
>>> r["verified"], r["kind"]
(True, 'closed')
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from lmic.errors import CertificateError
from lmic.ir.problem import Problem
from lmic.ir.svec import tril_rows_cols

__all__ = ["verify_farkas"]


def _weights(d: int) -> np.ndarray:
    i, j = tril_rows_cols(d)
    return np.where(i == j, 1.0, 2.0)


def _parse(problem: Problem, farkas: dict[str, Any]) -> tuple[list[np.ndarray], np.ndarray]:
    if not isinstance(farkas, dict):
        raise CertificateError("a Farkas certificate is a dict {'lmis': [Z_i], 'linear': y}")
    mats_in = farkas.get("lmis") or []
    if len(mats_in) > len(problem.lmis):
        raise CertificateError(
            f"the Farkas certificate has {len(mats_in)} LMI multipliers, the problem {len(problem.lmis)} LMIs"
        )
    mats = []
    for i, lmi in enumerate(problem.lmis):
        Z = mats_in[i] if i < len(mats_in) else None
        if Z is None:
            mats.append(np.zeros((lmi.dim, lmi.dim)))
            continue
        Z = np.atleast_2d(np.asarray(Z, dtype=float))
        if Z.shape != (lmi.dim, lmi.dim):
            raise CertificateError(
                f"Farkas multiplier of LMI '{lmi.name}' has shape {Z.shape}, expected {(lmi.dim, lmi.dim)}"
            )
        mats.append(0.5 * (Z + Z.T))
    m = len(problem.linear)
    y_in = farkas.get("linear")
    y = np.zeros(m) if y_in is None or len(y_in) == 0 else np.asarray(y_in, dtype=float).ravel()
    if y.shape != (m,):
        raise CertificateError(f"Farkas multiplier y has {y.size} entries, the problem {m} rows")
    if not (all(np.all(np.isfinite(Z)) for Z in mats) and np.all(np.isfinite(y))):
        raise CertificateError("the Farkas certificate has non-finite entries")
    return mats, y


def _evaluate(problem: Problem, mats: list[np.ndarray], y: np.ndarray, tol: float) -> dict:
    """Repair signs, then compute g, scales and the decision for one orientation."""
    ge = np.array([k == "ge" for k in problem.linear.kinds], dtype=bool)
    strict_rows = np.asarray(problem.linear.strict, dtype=bool) if len(y) else np.zeros(0, bool)
    eta_in = sum(float(np.sum(np.abs(np.linalg.eigvalsh(Z)))) for Z in mats if Z.size)
    eta_in += float(np.sum(np.abs(y)))
    if eta_in == 0:
        return {"verified": False, "reason": "the certificate is zero", "eta": 0.0}
    proj, removed = [], 0.0
    for Z in mats:
        if not Z.size:
            proj.append(Z)
            continue
        w, V = np.linalg.eigh(Z)
        removed += float(np.sum(-w[w < 0]))
        proj.append((V * np.maximum(w, 0.0)) @ V.T)
    yy = y.copy()
    neg = ge & (yy < 0)
    y_removed = float(np.sum(-yy[neg]))
    yy[neg] = 0.0
    psd_violation = removed / eta_in
    sign_violation = y_removed / eta_in
    eta = sum(float(np.trace(Z)) for Z in proj) + float(np.sum(np.abs(yy)))
    if eta == 0:
        return {
            "verified": False,
            "reason": "the certificate is zero after sign repair",
            "psd_violation": psd_violation,
            "sign_violation": sign_violation,
            "eta": 0.0,
        }
    proj = [Z / eta for Z in proj]
    yy = yy / eta
    n = problem.n
    g = np.zeros(1 + n)
    s = np.zeros(1 + n)  # coefficient scale c_k
    tau = 0.0
    for lmi, Z in zip(problem.lmis, proj, strict=True):
        r, c = tril_rows_cols(lmi.dim)
        z = Z[r, c] * _weights(lmi.dim)
        C = lmi.coeffs.tocsc()
        g += np.asarray(C.T @ z).ravel()
        s += np.sqrt(np.asarray(C.multiply(C).T @ _weights(lmi.dim)).ravel())
        if lmi.strict:
            tau += float(np.trace(Z))
    if len(yy):
        A = problem.linear.A.tocsc()
        g += np.asarray(A.T @ yy).ravel()
        s += np.asarray(abs(A).sum(axis=0)).ravel()
        tau += float(np.sum(yy[ge & strict_rows]))
    g0, s0 = float(g[0]), float(s[0])
    res, sk = np.abs(g[1:]), s[1:]
    floor = 1e-12 * float(np.max(sk)) if sk.size and np.max(sk) > 0 else 0.0
    denom = np.maximum(sk, floor)
    rel = np.divide(res, denom, out=np.zeros_like(res), where=denom > 0)
    rel_residual = float(np.max(rel)) if rel.size else 0.0
    worst = int(np.argmax(rel)) if rel.size else -1
    res1 = float(np.sum(res))
    closed = g0 < -tol * s0 and g0 < 0
    strict_ok = tau >= tol and g0 <= tol * s0
    out: dict[str, Any] = {
        "psd_violation": psd_violation,
        "sign_violation": sign_violation,
        "rel_residual": rel_residual,
        "g0": g0,
        "c0": s0,
        "tau": tau,
        "eta": 1.0,
        "radius": (-g0 / res1 if res1 > 0 else math.inf) if g0 < 0 else 0.0,
        "margin_bound": (g0 + res1) / tau if tau > 0 else None,
        "kind": "closed" if closed else ("strict" if strict_ok else None),
    }
    problems = []
    if psd_violation > tol:
        problems.append(f"a multiplier Z_i is not PSD (negative part {psd_violation:.3g} of its size)")
    if sign_violation > tol:
        problems.append(f"y is negative on ge rows (part {sign_violation:.3g} of its size)")
    if rel_residual > tol:
        name = _variable_of(problem, worst)
        problems.append(
            f"the trace condition fails for x[{worst}]{name}: relative residual {rel_residual:.3g} > {tol:g}"
        )
    if not (closed or strict_ok):
        if tau < tol and g0 >= 0:
            problems.append(
                f"no separation: sum <F_i^(0), Z_i> + a0 . y = {g0:.3g} is not < 0 and the "
                "certificate does not weigh any strict constraint"
            )
        else:
            problems.append(f"no separation: sum <F_i^(0), Z_i> + a0 . y = {g0:.3g} > 0 (constant-term scale {s0:.3g})")
    out["verified"] = not problems
    if problems:
        out["reason"] = "; ".join(problems)
    elif closed:
        out["reason"] = (
            f"Farkas certificate verified: even the closed problem is infeasible "
            f"(separation {g0:.3g}, relative residual {rel_residual:.2g}, "
            f"no feasible x with ||x||_inf < {out['radius']:.3g})"
        )
    else:
        out["reason"] = (
            f"Farkas certificate verified for the strict problem: no x with margin above "
            f"{out['margin_bound']:.3g} per unit of ||x||_inf "
            f"(relative residual {rel_residual:.2g})"
        )
    return out


def _variable_of(problem: Problem, k: int) -> str:
    for v in problem.variables:
        if v.offset <= k < v.offset + v.size:
            return f" ({v.name})"
    return ""


def verify_farkas(problem: Problem, farkas: dict[str, Any], *, tol: float = 1e-6) -> dict:
    """Verify a dual certificate of infeasibility for ``problem`` (see the module docstring).

    Parameters
    ----------
    problem : Problem
    farkas : dict
        ``{"lmis": [Z_i], "linear": y}`` (extra keys such as ``strict`` are ignored: which
        conditions apply is decided from the IR).
    tol : float
        Relative tolerance of the sign, trace and separation conditions.

    Returns
    -------
    dict
        ``verified`` (bool), ``kind`` (``"closed"``, ``"strict"`` or ``None``), ``reason`` (one
        line), ``negated`` (the certificate verified with the opposite sign convention),
        ``psd_violation``, ``sign_violation``, ``rel_residual``, ``g0``, ``c0``, ``tau``,
        ``radius``, ``margin_bound``.

    Raises
    ------
    CertificateError
        When the certificate does not have the problem's shape.

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
    >>> # homogeneous strict LMI  -p > 0  and  p > 0: Z = 1, 1 gives g = 0 with tau = 2
    >>> p = Problem([Variable("p", "scalar", (1, 1))],
    ...             [LMI("p > 0", 1, sp.csc_matrix([[0., 1.]])),
    ...              LMI("-p > 0", 1, sp.csc_matrix([[0., -1.]]))],
    ...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
    >>> r = verify_farkas(p, {"lmis": [np.eye(1), np.eye(1)]})
    >>> r["verified"], r["kind"], r["margin_bound"]
    (True, 'strict', 0.0)
    """
    mats, y = _parse(problem, farkas)
    first = _evaluate(problem, mats, y, tol)
    first["negated"] = False
    if first["verified"]:
        return first
    flipped = _evaluate(problem, [-Z for Z in mats], -y, tol)
    if flipped["verified"]:
        flipped["negated"] = True
        flipped["reason"] += " (with the opposite sign convention)"
        return flipped
    return first
