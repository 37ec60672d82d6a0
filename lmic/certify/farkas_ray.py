"""Verification (and repair) of a float Farkas ray of infeasibility, from the IR alone.

:func:`verify_farkas` checks the sign conditions and the relative residuals of a dual
certificate (the conditions are in the docstring of :mod:`lmic.certify.farkas`);
:func:`repair_farkas` looks for an exact-enough certificate next to an inaccurate one, on its
face, and hands it back to the same verification; :func:`ray_report` turns a solver's (possibly
malformed) ray into such a report. Split out of :mod:`lmic.certify.farkas`, which re-exports
every public name.

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
>>> p = Problem([Variable("p", "scalar", (1, 1))],
...             [LMI("p >= 0", 1, sp.csc_matrix([[0., 1.]]), strict=False),
...              LMI("-1 - p >= 0", 1, sp.csc_matrix([[-1., -1.]]), strict=False)],
...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
>>> verify_farkas(p, {"lmis": [np.eye(1), np.eye(1)], "linear": []})["verified"]
True
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from lmic.certify.multipliers import parse_multipliers
from lmic.ir.problem import Problem
from lmic.ir.svec import tril_rows_cols

__all__ = ["verify_farkas", "ray_report", "repair_farkas", "REPAIR_MAX", "REPAIR_MAX_ENTRIES"]

#: a certificate is repaired only when its relative residual and violations are below this
REPAIR_MAX = 1e-2
#: largest Jacobian (rows x columns) a repair builds; larger certificates are not repaired
REPAIR_MAX_ENTRIES = 20_000_000


def _weights(d: int) -> np.ndarray:
    i, j = tril_rows_cols(d)
    return np.where(i == j, 1.0, 2.0)


def _parse(problem: Problem, record: dict[str, Any]) -> tuple[list[np.ndarray], np.ndarray]:
    return parse_multipliers(problem, record, "Farkas certificate", missing_is_zero=True)


def _evaluate(problem: Problem, mats: list[np.ndarray], y: np.ndarray, tol: float) -> dict:
    """Repair signs, then compute g, scales and the decision for one orientation."""
    ge = np.array([k == "ge" for k in problem.linear.kinds], dtype=bool)
    strict_rows = np.asarray(problem.linear.strict, dtype=bool) if len(y) else np.zeros(0, bool)
    eta_in = sum(float(np.sum(np.abs(np.linalg.eigvalsh(Z)))) for Z in mats if Z.size)
    eta_in += float(np.sum(np.abs(y)))
    if eta_in == 0:
        return {"verified": False, "reason": "the certificate is zero", "eta": 0.0}
    proj, removed, tops = [], 0.0, []
    for Z in mats:
        if not Z.size:
            proj.append(Z)
            tops.append(0.0)
            continue
        w, V = np.linalg.eigh(Z)
        removed += float(np.sum(-w[w < 0]))
        proj.append((V * np.maximum(w, 0.0)) @ V.T)
        tops.append(float(max(np.max(w), 0.0)))
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
    # a float residual at round-off (often exactly 0.0) does not prove g_k = 0: every g_k is
    # known only up to the rounding of its evaluation (the PSD projection and the rescaling,
    # ~ d eps per entry of Z, and the sum of its nonzero terms, ~ eps per term, each bounded
    # by c_k since |<F^(k), Z>| <= ||F^(k)||_F ||Z||_F <= c_k tr Z), so the radius is taken
    # with |g_k| + (that bound) in place of |g_k|
    terms = _terms(problem)
    res1_raw = res1
    res1_floor = float(np.sum(_ROUNDING_TERMS * np.finfo(float).eps * terms[1:] * sk))
    res1 = res1 + res1_floor
    # the statements below need Z_i PSD exactly: the reconstructed V diag(w+) V^T is PSD only
    # up to delta_i = 8 d eps max(w), so they are made for Z_i + delta_i I, which is: g_k grows
    # by at most delta_i |tr F_i^(k)|; g_0's own rounding is added as well
    shift = _psd_shift(problem, tops, eta)
    g0_safe = g0 + float(shift[0]) + _ROUNDING_TERMS * float(np.finfo(float).eps) * float(terms[0]) * s0
    res1_safe = res1 + float(np.sum(shift[1:]))
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
        "radius": (-g0_safe / res1_safe if res1_safe > 0 else math.inf) if g0_safe < 0 else 0.0,
        "residual_floor": res1_floor,
        "residual_raw": res1_raw,
        "margin_bound": (g0_safe + res1_safe) / tau if tau > 0 else None,
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
        elif g0 < 0:
            problems.append(
                f"separation too small: sum <F_i^(0), Z_i> + a0 . y = {g0:.3g} is not below "
                f"-{tol:g} x the constant-term scale {s0:.3g} (an exact proof may still decide)"
            )
        else:
            problems.append(
                f"no separation: sum <F_i^(0), Z_i> + a0 . y = {g0:.3g} >= 0 (constant-term scale {s0:.3g})"
            )
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


#: safety factor on the rounding level of a float ``g_k`` (:func:`_evaluate`)
_ROUNDING_TERMS = 2.0


def _psd_shift(problem: Problem, tops: list[float], eta: float) -> np.ndarray:
    """For ``k = 0 .. n``: ``sum_i delta_i |tr F_i^(k)|``, ``delta_i = 8 d_i eps max(w_i) / eta``
    the bound on how far the reconstructed (normalised) ``Z_i`` may be from PSD."""
    eps = float(np.finfo(float).eps)
    out = np.zeros(1 + problem.n)
    for lmi, top in zip(problem.lmis, tops, strict=True):
        if not top or not lmi.dim:
            continue
        r, c = tril_rows_cols(lmi.dim)
        trace = np.asarray(lmi.coeffs.tocsr()[np.flatnonzero(r == c), :].sum(axis=0)).ravel()
        out += 8.0 * lmi.dim * eps * (top / eta) * np.abs(trace)
    return out


def _terms(problem: Problem) -> np.ndarray:
    """For ``k = 0 .. n``: how many rounded operations enter a float ``g_k`` at most.

    The nonzero coefficients of ``x_k`` (every LMI and row), plus the largest LMI dimension
    (the reconstruction of a PSD-projected ``Z_i``), plus one (the rescaling).
    """
    nnz = np.zeros(1 + problem.n)
    dmax = 0
    for lmi in problem.lmis:
        C = lmi.coeffs.tocsc()
        nnz += np.diff(C.indptr)
        dmax = max(dmax, lmi.dim)
    if len(problem.linear):
        nnz += np.diff(problem.linear.A.tocsc().indptr)
    return nnz + dmax + 1


def _variable_of(problem: Problem, k: int) -> str:
    for v in problem.variables:
        if v.offset <= k < v.offset + v.size:
            return f" ({v.name})"
    return ""


def ray_report(problem: Problem, ray: dict[str, Any] | None) -> dict:
    """:func:`verify_farkas` for a ray a solver offered: a missing or malformed ray is "not verified".

    The backends' status maps and the strict reductions use it to decide whether an inexact
    infeasibility claim stands; a malformed ray is never an error there, just not a proof.

    >>> ray_report(None, None)["verified"]
    False
    """
    if ray is None or ray.get("lmis") is None:
        return {"verified": False, "reason": "the solver returned no ray"}
    try:
        return verify_farkas(problem, ray)
    except Exception as err:  # noqa: BLE001 - a malformed ray is just not a certificate
        return {"verified": False, "reason": f"{type(err).__name__}: {err}"}


def verify_farkas(problem: Problem, farkas: dict[str, Any], *, tol: float = 1e-6, repair: bool = True) -> dict:
    """Verify a dual certificate of infeasibility for ``problem`` (see the module docstring).

    Parameters
    ----------
    problem : Problem
    farkas : dict
        ``{"lmis": [Z_i], "linear": y}`` (extra keys such as ``strict`` are ignored: which
        conditions apply is decided from the IR).
    tol : float
        Relative tolerance of the sign, trace and separation conditions.
    repair : bool
        When the certificate fails only the tolerances and is within :data:`REPAIR_MAX` of one,
        verify the certificate :func:`repair_farkas` finds next to it instead.

    Returns
    -------
    dict
        ``verified`` (bool), ``kind`` (``"closed"``, ``"strict"`` or ``None``), ``reason`` (one
        line), ``negated`` (the certificate verified with the opposite sign convention),
        ``repaired`` (what verified is the repaired certificate, recorded in ``certificate``;
        the solver's own numbers are in ``original``, the repair's in ``repair``),
        ``psd_violation``, ``sign_violation``, ``rel_residual``, ``g0``, ``c0``, ``tau``,
        ``radius``, ``margin_bound``. An unverified certificate whose repair was tried or
        refused says why in ``repair``.

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
    >>> r["verified"], r["kind"], r["margin_bound"] < 1e-14  # 0 up to the check's rounding
    (True, 'strict', True)
    """
    mats, y = _parse(problem, farkas)
    first = _evaluate(problem, mats, y, tol)
    first.update(negated=False, repaired=False)
    if first["verified"]:
        return first
    flipped = _evaluate(problem, [-Z for Z in mats], -y, tol)
    if flipped["verified"]:
        flipped.update(negated=True, repaired=False)
        flipped["reason"] += " (with the opposite sign convention)"
        return flipped
    if not repair:
        return first
    why = "not attempted: the certificate is not within 1e-2 of one"
    for sign, base in ((1.0, first), (-1.0, flipped)):
        if not _repairable(base):
            continue
        rep = repair_farkas(problem, {"lmis": [sign * Z for Z in mats], "linear": sign * y}, tol=tol)
        if rep["certificate"] is None:
            why = rep["reason"]
            continue
        out = _evaluate(problem, rep["certificate"]["lmis"], np.asarray(rep["certificate"]["linear"]), tol)
        if not out["verified"]:
            why = f"the repaired certificate does not verify either ({out['reason']})"
            continue
        out.update(negated=sign < 0, repaired=True)
        out["original"] = {k: base.get(k) for k in ("rel_residual", "psd_violation", "sign_violation", "g0", "kind")}
        out["repair"] = {k: rep[k] for k in ("iterations", "change", "support", "reason")}
        out["certificate"] = {
            "lmis": [np.asarray(Z).tolist() for Z in rep["certificate"]["lmis"]],
            "linear": np.asarray(rep["certificate"]["linear"]).tolist(),
        }
        out["reason"] = (
            f"{out['reason']}, after repair: the solver's certificate had relative residual "
            f"{base['rel_residual']:.2g}; {rep['iterations']} damped least-squares steps on its support "
            f"(relative change {rep['change']:.2g}) give the recorded certificate"
        )
        if sign < 0:
            out["reason"] += " (with the opposite sign convention)"
        return out
    first["repair"] = {"reason": why}
    return first


def _repairable(r: dict[str, Any]) -> bool:
    keys = ("rel_residual", "psd_violation", "sign_violation")
    return all(k in r and r[k] <= REPAIR_MAX for k in keys)


def repair_farkas(
    problem: Problem,
    farkas: dict[str, Any],
    *,
    tol: float = 1e-6,
    max_iter: int = 200,
    step: float = 0.5,
) -> dict[str, Any]:
    """Look for a certificate next to ``farkas`` on its support (see the module docstring).

    The result is a candidate, not a verdict: :func:`verify_farkas` checks it like any other.

    Parameters
    ----------
    problem : Problem
    farkas : dict
        ``{"lmis": [Z_i], "linear": y}`` in the conic-dual convention (``Z_i >= 0``).
    tol : float
        The verifier's tolerance (unused by the search; accepted for a uniform call).
    max_iter : int
        Largest number of damped steps.
    step : float
        Largest ``||E_i||_2`` and ``|e_r|`` of a step (``< 1`` keeps the multipliers in the cone).

    Returns
    -------
    dict
        ``certificate`` (``{"lmis", "linear"}`` normalised to ``sum tr Z_i + sum |y_r| = 1``, or
        ``None`` when no repair was possible), ``iterations``, ``residual`` (the largest
        ``|g_k| / c_k`` at the end), ``change`` (Frobenius distance to the normalised input),
        ``support`` (rank of every ``Z_i`` and number of rows used) and ``reason``.

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
    >>> p = Problem([Variable("p", "scalar", (1, 1))],
    ...             [LMI("p >= 0", 1, sp.csc_matrix([[0., 1.]]), strict=False),
    ...              LMI("-1 - p >= 0", 1, sp.csc_matrix([[-1., -1.]]), strict=False)],
    ...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
    >>> r = repair_farkas(p, {"lmis": [np.eye(1), 1.001 * np.eye(1)], "linear": []})
    >>> r["residual"] < 1e-15, [round(float(Z[0][0]), 6) for Z in r["certificate"]["lmis"]]
    (True, [0.5, 0.5])
    """
    del tol
    mats, y = _parse(problem, farkas)
    n = problem.n
    kinds = list(problem.linear.kinds)
    ge = np.array([k == "ge" for k in kinds], dtype=bool)
    out: dict[str, Any] = {"certificate": None, "iterations": 0, "residual": math.inf, "change": 0.0}
    out["support"] = {"ranks": [], "rows": 0}
    # start from the sign-repaired, normalised certificate (as the verifier sees it)
    start = []
    for Z in mats:
        if Z.size:
            w, V = np.linalg.eigh(Z)
            Z = (V * np.maximum(w, 0.0)) @ V.T
        start.append(Z)
    y0 = np.where(ge, np.maximum(y, 0.0), y)
    eta = sum(float(np.trace(Z)) for Z in start) + float(np.sum(np.abs(y0)))
    if eta == 0:
        out["reason"] = "the certificate is zero"
        return out
    start = [Z / eta for Z in start]
    y0 = y0 / eta
    top = max([float(np.max(np.linalg.eigvalsh(Z))) for Z in start if Z.size] + [float(np.max(np.abs(y0), initial=0))])
    drop = 1e-12 * top
    Cs = [lmi.coeffs.tocsc() for lmi in problem.lmis]
    A = problem.linear.A.tocsc() if len(y0) else None
    scale = _coef_scale(problem)[1:]
    rows = [r for r in range(len(y0)) if (not ge[r]) or y0[r] > drop]
    cur, yc = [Z.copy() for Z in start], y0.copy()
    entries = n * (sum(lmi.dim * (lmi.dim + 1) // 2 for lmi in problem.lmis) + len(rows))
    if entries > REPAIR_MAX_ENTRIES:
        out["reason"] = f"too large to repair ({entries:.3g} Jacobian entries > {REPAIR_MAX_ENTRIES:.3g})"
        return out
    ranks: list[int] = []
    factors: list[np.ndarray | None] = []
    it = 0
    for it in range(1, max_iter + 1):
        g = _g_vector(problem, Cs, A, cur, yc)[1:]
        blocks, factors, ranks = [], [], []
        for lmi, C, Z in zip(problem.lmis, Cs, cur, strict=True):
            if not Z.size:
                factors.append(None)
                ranks.append(0)
                continue
            w, V = np.linalg.eigh(Z)
            keep = w > drop
            U = V[:, keep] * np.sqrt(w[keep])
            r = U.shape[1]
            ranks.append(r)
            factors.append(U if r else None)
            if not r:
                continue
            ri, ci = tril_rows_cols(lmi.dim)
            ia, ib = np.triu_indices(r)
            P, Q = U[ri], U[ci]
            T = P[:, ia] * Q[:, ib] + P[:, ib] * Q[:, ia]
            T[:, ia == ib] *= 0.5
            blocks.append(np.asarray(C[:, 1:].T @ (_weights(lmi.dim)[:, None] * T)))
        s_rows = np.array([max(abs(yc[r]), top * 1e-3) if not ge[r] else yc[r] for r in rows])
        if rows:
            assert A is not None  # rows index the linear rows, so there are some
            blocks.append(np.asarray(A[:, 1:][rows].T.toarray()) * s_rows[None, :])
        if not blocks:
            out["reason"] = (
                "the certificate has no support to repair"
                if it == 1
                else f"the repair shrank the certificate to zero after {it - 1} steps: there is none near it"
            )
            return out
        G = np.hstack(blocks)
        e = np.linalg.lstsq(G, -g, rcond=None)[0]
        Es: list[np.ndarray | None] = []
        k, norms = 0, [0.0]
        for U in factors:
            if U is None:
                Es.append(None)
                continue
            r = U.shape[1]
            ia, ib = np.triu_indices(r)
            E = np.zeros((r, r))
            E[ia, ib] = e[k : k + len(ia)]
            E[ib, ia] = e[k : k + len(ia)]
            k += len(ia)
            Es.append(E)
            norms.append(float(np.max(np.abs(np.linalg.eigvalsh(E)))))
        ey = e[k:]
        norms += [abs(float(v)) for r, v in zip(rows, ey, strict=True) if ge[r]]
        alpha = 1.0 if max(norms) <= step else step / max(norms)
        cur = [
            Z if U is None or E is None else U @ (np.eye(U.shape[1]) + alpha * E) @ U.T
            for Z, U, E in zip(cur, factors, Es, strict=True)
        ]
        for r, v, sr in zip(rows, ey, s_rows, strict=True):
            yc[r] += alpha * float(v) * sr
        if alpha == 1.0:  # the full correction fits in the cone: the residual is at round-off
            break
    g = _g_vector(problem, Cs, A, cur, yc)[1:]
    res = np.divide(np.abs(g), scale, out=np.zeros_like(g), where=scale > 0)
    change = math.sqrt(
        sum(float(np.sum((Z - Z0) ** 2)) for Z, Z0 in zip(cur, start, strict=True)) + float(np.sum((yc - y0) ** 2))
    )
    out.update(
        certificate={"lmis": [0.5 * (Z + Z.T) for Z in cur], "linear": yc},
        iterations=it,
        residual=float(np.max(res, initial=0.0)),
        change=change,
        support={"ranks": ranks, "rows": len(rows)},
        reason=f"{it} damped least-squares steps on the support (ranks {ranks}, {len(rows)} rows)",
    )
    return out


def _g_vector(problem: Problem, Cs: list, A: Any, mats: list[np.ndarray], y: np.ndarray) -> np.ndarray:
    """``g_k = sum_i <F_i^(k), Z_i> + sum_r a_rk y_r`` for ``k = 0 .. n``."""
    g = np.zeros(1 + problem.n)
    for lmi, C, Z in zip(problem.lmis, Cs, mats, strict=True):
        if Z.size:
            r, c = tril_rows_cols(lmi.dim)
            g += np.asarray(C.T @ (Z[r, c] * _weights(lmi.dim))).ravel()
    if A is not None and len(y):
        g += np.asarray(A.T @ y).ravel()
    return g


def _coef_scale(problem: Problem) -> np.ndarray:
    """``c_k = sum_i ||F_i^(k)||_F + sum_r |a_rk|`` for ``k = 0 .. n``."""
    s = np.zeros(1 + problem.n)
    for lmi in problem.lmis:
        C = lmi.coeffs.tocsc()
        s += np.sqrt(np.asarray(C.multiply(C).T @ _weights(lmi.dim)).ravel())
    if len(problem.linear):
        s += np.asarray(abs(problem.linear.A.tocsc()).sum(axis=0)).ravel()
    return s
