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
  P > 0`` for an unstable ``A``) and of the max-margin reduction of :mod:`lmic.reductions.strict`.

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

Global or bounded: what a certificate proves about the ORIGINAL problem
-----------------------------------------------------------------------
Backends reduce strict constraints before solving (:mod:`lmic.reductions.strict`): the
``max-margin`` problem adds a margin ``t``, a cap ``t <= 1`` and, for scale-free problems, a
trace normalisation ``tr F_i(x) <= d_i``. The dual of such a problem carries multipliers of those
extra rows (the "box term"); :func:`verify_farkas` is always run on the ORIGINAL problem with
the multipliers of the original constraints only, so no box multiplier can enter ``g``. What
remains is the float residual ``g_k != 0`` (``k >= 1``), and that is what decides the scope
(:func:`scope`):

* **exact proof** (:func:`prove_farkas`): ``g_k = 0`` for ``k >= 1`` in rational arithmetic,
  ``Z_i >= 0`` and the separation exactly. Then (*) holds for every ``x`` with no ``x`` term,
  so no ``x`` at all is feasible: a **global** proof.
* **homogeneous problems** (every ``F_i^(0) = 0`` and ``a_r0 = 0``: the strict feasible set is
  an open cone, e.g. Lyapunov LMIs) with a verified *strict* certificate: ``g_0 = 0`` exactly
  (a sum of exact zeros), and (*) gives ``mu tau <= ||x||_inf ||g_{1:}||_1`` for every ``x``
  with margin ``mu``. Since ``x -> s x`` (``s > 0``) maps the feasible cone onto itself, the
  trace normalisation of the reduction loses nothing, and the bound is scale-free: no point
  *at any scale* has relative margin ``mu / ||x||_inf`` above ``rho = ||g_{1:}||_1 / tau``
  (recorded). lmic treats this as **global** (the coordinator's rule for scale-free cones);
  the recorded ``rho`` says how far that float statement goes.
* **everything else** (an inhomogeneous problem with a float certificate): (*) gives
  ``0 <= g_0 + ||x||_inf ||g_{1:}||_1`` at any feasible ``x``, so only points with
  ``||x||_inf < R = -g_0 / ||g_{1:}||_1`` are excluded: a **bounded** proof, "no solution with
  ``||x||_inf <= R``", never called infeasible. This is not a formality: the problem
  ``[[x, 1], [1, 1e-5]] > 0`` is feasible exactly for ``x > 1e5``, and SDPA and SCS return
  certificates that verify to ``1e-6`` with ``R ~ 4e4`` (``tests/engine/test_engine.py``). To go
  further: an exact proof (``--exact``), another backend (another ray), or a larger ``R``
  (a more accurate ray).

Repair of inaccurate certificates
---------------------------------
Interior-point solvers return the Farkas ray only to their own accuracy (SDPA on
``uir.thm5_1``: relative residual 2.8e-5, all of it in one variable whose every term has the
same sign, i.e. a genuine leak of the multiplier into directions that must carry no weight,
not a cancellation the measure misjudges). When the solver's certificate fails *only* the
tolerances and is within :data:`REPAIR_MAX` of one (relative residual, PSD and sign
violations), :func:`repair_farkas` looks for an exact-enough certificate next to it, on its
support: writing ``Z_i = U_i U_i^T`` (the eigenvectors of ``Z_i`` above ``1e-12`` of the
largest multiplier, scaled by the square roots of the eigenvalues) and ``y_r`` on the rows it
uses, it solves the least-norm correction ``Z_i -> U_i (I + E_i) U_i^T``, ``y_r -> y_r (1 +
e_r)`` of the linear conditions ``g_k = 0`` (``k >= 1``), and takes the step damped so that
``||E_i||_2, |e_r| <= 1/2``: the multipliers stay in the cone (this is the Dikin ellipsoid of
the certificate's face), the residual shrinks by the step each iteration, and a full step
ends the repair with the residual at round-off. The repaired certificate is then verified by
exactly the same conditions as any other certificate and recorded (``certificate``), next to
the solver's original numbers (``original``). A repair is a search for a certificate, and
its result is checked, not trusted: on a feasible problem nothing can pass (``tests``: a
perturbed certificate of a nearby unstable system stays unverified).

Exact certificates (:func:`prove_farkas`)
-----------------------------------------
A verified float certificate still has ``g_k ~ 1e-14`` instead of ``0``. :func:`prove_farkas`
turns it into an exact one: on the certificate's face (``Z_i = V_i S_i V_i^T``, ``V_i`` the
eigenvectors above ``1e-9`` of the largest multiplier, rounded to rationals ``2^-50``; ``y_r``
on the rows it uses) the conditions ``g_k = 0`` are linear in ``(S_i, y)`` with exact rational
coefficients. Entries of ``V_i`` below ``2^-40`` are LAPACK's round-off on coordinates the face
does not touch (a zero row of ``Z_i``) and are set to exact zeros before the rounding: kept,
they tilt the face out of its coordinate subspace, an equation that vanishes identically on the
true face binds in exact arithmetic, and the projection below has to cancel an O(1) part of the
multiplier (how much noise LAPACK leaves depends on its build: this decided the SDPA test case
on one machine and not on another). The rounded ``(S_i, y)`` is projected exactly onto their
solution space (over an independent subset of the equations, python-flint). When that leaves
the cone (an eigenvalue of ``S_i`` smaller than the projection's correction), a second attempt
first moves the float point towards the analytic centre of the face's certificates (log-det
barrier, Newton steps in the null space of the float equations): by the smallest step of a
grid that leaves every eigenvalue a float margin, so the certificate stays close to the
solver's. Either way the result is only a candidate; then, exactly: every ``S_i`` is
positive semidefinite (so is ``Z_i``), ``y_r >= 0`` on ``ge`` rows, ``g_k = 0`` for
``k >= 1`` by construction, and ``g_0 < 0`` (closed) or ``g_0 <= 0`` with ``tau > 0``
(strict). Nothing is left to tolerance: the problem is infeasible as stated by its IR.

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

from lmic.certify.multipliers import parse_multipliers
from lmic.ir.problem import Problem
from lmic.ir.svec import tril_rows_cols

__all__ = [
    "verify_farkas",
    "ray_report",
    "scope",
    "is_homogeneous",
    "repair_farkas",
    "prove_farkas",
    "prove_infeasible",
    "REPAIR_MAX",
    "REPAIR_MAX_ENTRIES",
    "EXACT_MAX_ENTRIES",
]

#: a certificate is repaired only when its relative residual and violations are below this
REPAIR_MAX = 1e-2
#: largest Jacobian (rows x columns) a repair builds; larger certificates are not repaired
REPAIR_MAX_ENTRIES = 20_000_000
#: largest exact Jacobian ((1 + n) x (tril entries) x (face unknowns)) an exact proof builds
EXACT_MAX_ENTRIES = 50_000_000
#: bits of the rational rounding of the face bases
_FACE_BITS = 50


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
    >>> r["verified"], r["kind"], r["margin_bound"]
    (True, 'strict', 0.0)
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
    it = 0
    for it in range(1, max_iter + 1):
        g = _g_vector(problem, Cs, A, cur, yc)[1:]
        blocks: list[np.ndarray] = []
        factors: list[np.ndarray | None] = []
        ranks = []
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
            assert A is not None  # rows index y0, so y0 is not empty and A was built
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
        k, norms = 0, [0.0]
        Es: list[np.ndarray | None] = []
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


def prove_farkas(
    problem: Problem,
    farkas: dict[str, Any],
    *,
    rel_face: tuple[float, ...] = (1e-9, 1e-7, 1e-5, 1e-3),
    keep_certificate: bool = False,
) -> dict[str, Any]:
    """Make a (float) Farkas certificate exact on its face and prove it (module docstring).

    Parameters
    ----------
    problem : Problem
    farkas : dict
        ``{"lmis": [Z_i], "linear": y}`` in the conic-dual convention (``Z_i >= 0``), e.g. the
        ``certificate`` :func:`verify_farkas` recorded after a repair.
    rel_face : tuple of float
        Eigenvalues of ``Z_i`` (and multipliers ``y_r``) above ``rel_face`` times the largest
        multiplier span the face; tried in order. A direction the solver left with a tiny
        weight where the exact conditions force none (a PSD coefficient that must be
        orthogonal to ``Z_i``) makes the face too large, and the next threshold drops it.
    keep_certificate : bool
        Also return the exact multipliers (``exact_certificate``: ``lmis`` as lists of
        :class:`fractions.Fraction` matrices, ``linear`` as Fractions). Large; not JSON.

    Returns
    -------
    dict
        ``proven`` (bool), ``kind`` (``"closed"``, ``"strict"`` or ``None``), ``reason``,
        ``face`` (rank of every ``Z_i``, the rows used and the threshold that worked),
        ``equations`` (independent ones),
        ``g0`` (exact, rounded to float, for ``sum tr Z_i + sum |y_r| = 1``), ``tau`` (likewise),
        ``denominator_bits`` (of the exact multipliers), ``time_s``.

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
    >>> p = Problem([Variable("p", "scalar", (1, 1))],
    ...             [LMI("p >= 0", 1, sp.csc_matrix([[0., 1.]]), strict=False),
    ...              LMI("-1 - p >= 0", 1, sp.csc_matrix([[-1., -1.]]), strict=False)],
    ...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
    >>> r = prove_farkas(p, {"lmis": [np.eye(1), (1 + 1e-12) * np.eye(1)], "linear": []})
    >>> r["proven"], r["kind"], r["g0"]
    (True, 'closed', -0.5)
    """
    import time

    t0 = time.perf_counter()
    out: dict[str, Any] = {}
    for rel in rel_face:
        for center in (False, True):
            attempt = _prove_farkas(problem, farkas, rel, keep_certificate, center)
            if attempt["face"] is not None:
                attempt["face"]["threshold"] = rel
                attempt["face"]["centered"] = center
            if not out or attempt["proven"]:
                out = attempt
            if attempt["proven"]:
                break
        if out.get("proven"):
            break
    out["time_s"] = time.perf_counter() - t0
    return out


def _prove_farkas(
    problem: Problem, farkas: dict[str, Any], rel_face: float, keep: bool, center: bool = False
) -> dict[str, Any]:
    from fractions import Fraction

    from lmic.certify.exact import _flint, prove_psd

    flint = _flint()
    mats, y = _parse(problem, farkas)
    fail: dict[str, Any] = {"proven": False, "kind": None, "face": None, "equations": 0, "g0": None, "tau": None}
    fail["denominator_bits"] = 0
    lin = problem.linear
    ge = np.array([k == "ge" for k in lin.kinds], dtype=bool)
    strict_rows = np.asarray(lin.strict, dtype=bool) if len(y) else np.zeros(0, bool)
    eigs = [np.linalg.eigh(Z) if Z.size else (np.zeros(0), np.zeros((0, 0))) for Z in mats]
    top = max([float(np.max(w)) for w, _ in eigs if w.size] + [float(np.max(np.where(ge, y, np.abs(y)), initial=0))])
    if not top > 0:
        return dict(fail, reason="the certificate has no positive multiplier")
    thr = rel_face * top
    n = problem.n

    def q(v: float) -> Any:
        f = Fraction(float(v))
        return flint.fmpq(f.numerator, f.denominator)

    # unknowns: svec(S_i) with Z_i = W_i S_i W_i^T on every face (W_i = round(V_i 2^50), an
    # integer matrix), then y on the rows used; one column of the exact Jacobian per unknown
    columns: list[list[Any]] = []  # 1 + n fmpq per unknown: d g_k / d unknown
    u0: list[Any] = []
    blocks: list[tuple[int, np.ndarray, int]] = []  # (lmi index, W_i as python ints, r)
    ranks: list[int] = []
    sels = [w > thr for w, _ in eigs]
    rows = [r for r in range(len(y)) if (not ge[r]) or y[r] > thr]
    # the float starting point: S_i = diag(w) on the face, y on the rows used
    parts = []
    for (w, _), sel in zip(eigs, sels, strict=True):
        ia, ib = np.triu_indices(int(np.sum(sel)))
        parts.append(np.where(ia == ib, w[sel][ia], 0.0))
    u0f = np.concatenate([*parts, y[rows]])
    if center and u0f.size:
        moved = _towards_center(problem, eigs, sels, rows, ge, u0f, top)
        if moved is None:
            return dict(fail, reason="no point inside the face's certificates was found (float centering)")
        u0f = moved
    k0 = 0
    for i, (lmi, (_w, V)) in enumerate(zip(problem.lmis, eigs, strict=True)):
        sel = sels[i]
        r = int(np.sum(sel))
        ranks.append(r)
        if not r:
            continue
        t = lmi.dim * (lmi.dim + 1) // 2
        if (1 + n) * t * r * (r + 1) // 2 > EXACT_MAX_ENTRIES:
            return dict(fail, reason=f"the face of LMI '{lmi.name}' is too large for an exact proof")
        W = np.rint(np.ldexp(_snap(V[:, sel]), _FACE_BITS)).astype(np.int64).astype(object)
        ri, ci = tril_rows_cols(lmi.dim)
        ia, ib = np.triu_indices(r)
        P, Q = W[ri], W[ci]
        # <F^(k), W E_ab W^T> over the tril storage: T[t, ab] = W[p,a] W[q,b] + W[p,b] W[q,a]
        # (halved when a == b), times the tril weight (2 off the diagonal)
        T = P[:, ia] * Q[:, ib] + P[:, ib] * Q[:, ia]
        T[:, ia == ib] //= 2
        T = T * _weights(lmi.dim).astype(np.int64).astype(object)[:, None]
        Cq = flint.fmpq_mat([[q(v) for v in row] for row in lmi.coeffs.tocsc().T.toarray()])
        Jl = (Cq * flint.fmpq_mat(T.tolist())).tolist()  # (1 + n) x r(r+1)/2
        for col in range(len(ia)):
            columns.append([Jl[k][col] for k in range(1 + n)])
        # V diag(w) V^T = W (diag(w) 2^-100) W^T
        scale = flint.fmpq(1, 1 << (2 * _FACE_BITS))
        u0 += [q(float(v)) * scale for v in u0f[k0 : k0 + len(ia)]]
        k0 += len(ia)
        blocks.append((i, W, r))
    if rows:
        A = lin.A.tocsc()
        Ad = A.toarray()
        for r in rows:
            columns.append([q(v) for v in Ad[r]])
            u0.append(q(float(u0f[k0])))
            k0 += 1
    if not columns:
        return dict(fail, reason="the certificate has an empty face")
    m = len(columns)
    Jall = flint.fmpq_mat([[columns[j][k] for j in range(m)] for k in range(1 + n)])
    Jx = flint.fmpq_mat([[columns[j][k] for j in range(m)] for k in range(1, 1 + n)])
    u = flint.fmpq_mat([[v] for v in u0])
    res = Jx * u
    R, rank = Jx.transpose().rref()
    if rank and any(v != 0 for v in res.entries()):
        width = R.ncols()
        flat = R.entries()
        piv = []
        for rr in range(rank):
            row = flat[rr * width : (rr + 1) * width]
            piv.append(next(c for c in range(width) if row[c] != 0))
        Ji = flint.fmpq_mat([[Jx[k, j] for j in range(m)] for k in piv])
        ri_ = flint.fmpq_mat([[res[k, 0]] for k in piv])
        u = u - Ji.transpose() * (Ji * Ji.transpose()).solve(ri_)
        if any(v != 0 for v in (Jx * u).entries()):
            return dict(
                fail,
                face={"ranks": ranks, "rows": len(rows)},
                equations=rank,
                reason="the trace conditions are inconsistent on the face in exact arithmetic",
            )
    uv = u.entries()
    face = {"ranks": ranks, "rows": len(rows)}
    # exact signs: every S_i PSD, y >= 0 on ge rows
    k = 0
    exact_lmis: list[Any] = [[[Fraction(0)] * lmi.dim for _ in range(lmi.dim)] for lmi in problem.lmis]
    trace_strict = Fraction(0)
    trace_all = Fraction(0)
    den_bits = 0
    for i, W, r in blocks:
        ia, ib = np.triu_indices(r)
        S = [[Fraction(0)] * r for _ in range(r)]
        for a, b in zip(ia, ib, strict=True):
            v = uv[k]
            S[a][b] = S[b][a] = Fraction(int(v.p), int(v.q))
            k += 1
        den = 1
        for row in S:
            for f in row:
                den = den * f.denominator // math.gcd(den, f.denominator)
        den_bits = max(den_bits, den.bit_length())
        Sint = [[int(f * den) for f in row] for row in S]
        pr = prove_psd(Sint)
        if not pr["proven"]:
            return dict(
                fail,
                face=face,
                equations=rank,
                reason=f"the exact multiplier of LMI '{problem.lmis[i].name}' is not proved PSD ({pr['detail']})",
            )
        if keep:
            Sm = np.array(S, dtype=object)
            exact_lmis[i] = (W @ Sm @ W.T).tolist()
        G = W.T @ W  # tr(Z_i) = tr(S W^T W)
        tr = sum((S[a][b] * int(G[b][a]) for a in range(r) for b in range(r)), Fraction(0))
        trace_all += tr
        if problem.lmis[i].strict:
            trace_strict += tr
    yv = {}
    for r in rows:
        v = uv[k]
        yv[r] = Fraction(int(v.p), int(v.q))
        den_bits = max(den_bits, int(v.q).bit_length())
        k += 1
        if ge[r] and yv[r] < 0:
            return dict(
                fail, face=face, equations=rank, reason=f"the exact multiplier of row '{lin.names[r]}' is negative"
            )
    g0v = (Jall * u)[0, 0]
    g0 = Fraction(int(g0v.p), int(g0v.q))
    tau = trace_strict + sum((yv[r] for r in rows if ge[r] and strict_rows[r]), Fraction(0))
    eta = trace_all + sum((abs(v) for v in yv.values()), Fraction(0))
    base: dict[str, Any] = {"face": face, "equations": rank, "denominator_bits": den_bits}
    if keep:
        base["exact_certificate"] = {
            "lmis": exact_lmis,
            "linear": [yv.get(r, Fraction(0)) for r in range(len(y))],
        }
    base["g0"] = float(g0 / eta) if eta else None
    base["tau"] = float(tau / eta) if eta else None
    exactly = "exact Farkas certificate: g_k = 0 exactly (k >= 1), multipliers proved PSD"
    if g0 < 0:
        reason = f"{exactly}, g_0 = {base['g0']:.3g} < 0 (even the closed problem is infeasible)"
        return dict(base, proven=True, kind="closed", reason=reason)
    if g0 <= 0 and tau > 0:
        reason = f"{exactly}, g_0 = 0 and tau = {base['tau']:.3g} > 0 (the strict problem is infeasible)"
        return dict(base, proven=True, kind="strict", reason=reason)
    return dict(base, proven=False, kind=None, reason=f"no exact separation: g_0 = {float(g0):.3g}")


def _snap(V: np.ndarray) -> np.ndarray:
    """Face basis with its round-off entries set to exact zeros.

    An entry below ``2^-(_FACE_BITS - 10)`` of a unit basis vector is LAPACK's noise on a
    coordinate the face does not touch (a zero row of ``Z_i``, a block of a block-diagonal
    ``Z_i``). Rounded to ``2^-_FACE_BITS`` it would survive as a few units and tilt the face out
    of that coordinate subspace: an equation ``<M, Z_i> = 0`` that holds identically on the
    true face (``M`` vanishing there) would then bind in exact arithmetic, and the exact
    projection would have to cancel an O(1) component of the multiplier along it.
    """
    return np.where(np.abs(V) < 2.0 ** -(_FACE_BITS - 10), 0.0, V)


def _face_jacobian(problem: Problem, eigs: list, sels: list, rows: list[int]) -> np.ndarray:
    """Float ``d g_k / d u`` (``k = 0 .. n``) for the face unknowns of :func:`_prove_farkas`.

    The unknowns are ``svec(S_i)`` (upper triangle, each off-diagonal entry once) with
    ``Z_i = V_i S_i V_i^T`` (``V_i`` the orthonormal face basis), then ``y`` on ``rows``.
    """
    cols = []
    for lmi, (_, V), sel in zip(problem.lmis, eigs, sels, strict=True):
        r = int(np.sum(sel))
        if not r:
            continue
        U = _snap(V[:, sel])
        ri, ci = tril_rows_cols(lmi.dim)
        ia, ib = np.triu_indices(r)
        P, Q = U[ri], U[ci]
        T = P[:, ia] * Q[:, ib] + P[:, ib] * Q[:, ia]
        T[:, ia == ib] *= 0.5
        cols.append(np.asarray(lmi.coeffs.tocsc().T @ (_weights(lmi.dim)[:, None] * T)))
    if rows:
        cols.append(np.asarray(problem.linear.A.tocsr()[rows].T.toarray()))
    return np.hstack(cols)


def _center_on_face(
    J: np.ndarray, u0: np.ndarray, sizes: list[int], ge_rows: np.ndarray, separate: bool, max_iter: int = 30
) -> np.ndarray | None:
    """A point deep inside the face's slice of the certificate cone, in floats.

    Maximises ``sum_i log det S_i + sum_{ge rows} log y_r (+ log(-g_0) when separate)`` subject
    to ``g_k = 0`` (``k >= 1``) and ``sum_i tr S_i + sum_{ge rows} y_r`` fixed, by infeasible-start
    Newton steps from ``u0`` (which must be strictly inside the cone). Returns ``None`` when no
    strictly interior point was reached (the face is larger than the certificates' face).
    """
    m = u0.size
    tri = [np.triu_indices(r) for r in sizes]
    nS = sum(len(a) for a, _ in tri)
    # trace row of the normalisation; svec -> S for every block
    N = np.zeros(m)
    k = 0
    for a, b in tri:
        N[k : k + len(a)] = (a == b).astype(float)
        k += len(a)
    N[nS:] = ge_rows.astype(float)
    A = np.vstack([J[1:], N[None, :]])
    c0 = J[0]
    scale = np.maximum(np.linalg.norm(A, axis=1), 1e-300)
    A = A / scale[:, None]  # rows of unit norm: the KKT system is better balanced
    b = np.zeros(A.shape[0])
    b[-1] = float(N @ u0) / scale[-1]

    def split(u: np.ndarray) -> list[np.ndarray]:
        out, k = [], 0
        for r, (a, bb) in zip(sizes, tri, strict=True):
            S = np.zeros((r, r))
            S[a, bb] = u[k : k + len(a)]
            S[bb, a] = u[k : k + len(a)]
            out.append(S)
            k += len(a)
        return out

    def inside(u: np.ndarray) -> bool:
        if separate and not float(c0 @ u) < 0:
            return False
        if np.any(u[nS:][ge_rows] <= 0):
            return False
        return all(np.linalg.eigvalsh(S)[0] > 0 for S in split(u) if S.size)

    def derivatives(u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        grad, H = np.zeros(m), np.zeros((m, m))
        k = 0
        for r, (a, bb), S in zip(sizes, tri, split(u), strict=True):
            t = len(a)
            E = np.zeros((t, r, r))
            E[np.arange(t), a, bb] = 1.0
            E[np.arange(t), bb, a] = 1.0
            Si = np.linalg.inv(S)
            M = Si @ E
            grad[k : k + t] = -np.einsum("kii->k", M)
            H[k : k + t, k : k + t] = np.einsum("kij,lji->kl", M, M)
            k += t
        yr = np.flatnonzero(ge_rows) + nS
        grad[yr] -= 1.0 / u[yr]
        H[yr, yr] += 1.0 / u[yr] ** 2
        if separate:
            h = -float(c0 @ u)
            grad += c0 / h
            H += np.outer(c0, c0) / h**2
        return grad, H

    # feasible-start Newton on the null space of the equality rows (orthonormal basis B)
    _, sv, Vt = np.linalg.svd(A)
    rank = int(np.sum(sv > 1e-10 * sv[0])) if sv.size else 0
    B = Vt[rank:].T
    dp = -np.linalg.lstsq(A, A @ u0 - b, rcond=1e-10)[0]  # least-norm move onto the slice
    if not inside(u0) or not B.shape[1]:
        return None
    # phase 1 (infeasible start): u = u0 + s dp + B z; each step takes the rest of dp and the
    # barrier's Newton correction in the null space, damped to stay inside the cone, until s = 1
    u, s = u0.copy(), 0.0
    for _ in range(max_iter):
        grad, H = derivatives(u)
        rest = (1.0 - s) * dp
        Hz = B.T @ H @ B
        dz = -np.linalg.solve(Hz + 1e-14 * np.trace(Hz) * np.eye(len(Hz)) / len(Hz), B.T @ (grad + H @ rest))
        t = 1.0
        while t > 1e-6 and not inside(u + t * (rest + B @ dz)):
            t *= 0.5
        if t <= 1e-6:
            return None
        u = u + t * (rest + B @ dz)
        s = 1.0 if t == 1.0 else s + t * (1.0 - s)
        if s == 1.0:
            break
    if s < 1.0:
        return None

    def value(u: np.ndarray) -> float:
        f = -sum(float(np.linalg.slogdet(S)[1]) for S in split(u) if S.size)
        f -= float(np.sum(np.log(u[nS:][ge_rows])))
        return f - (math.log(-float(c0 @ u)) if separate else 0.0)

    f = value(u)
    for _ in range(max_iter):
        grad, H = derivatives(u)
        gz, Hz = B.T @ grad, B.T @ H @ B
        dz = -np.linalg.solve(Hz + 1e-14 * np.trace(Hz) * np.eye(len(gz)) / len(gz), gz)
        dec = -float(gz @ dz)  # Newton decrement squared
        if not dec > 1e-8:  # near enough to the centre: only a margin is needed
            break
        du, t = B @ dz, 1.0
        while t > 1e-6:
            un = u + t * du
            if inside(un):
                fn = value(un)
                if fn <= f - 0.25 * t * dec:
                    break
            t *= 0.5
        if t <= 1e-6:
            break
        u, f = un, fn
    return u


def _towards_center(
    problem: Problem, eigs: list, sels: list, rows: list[int], ge: np.ndarray, u0: np.ndarray, top: float
) -> np.ndarray | None:
    """Move the face point ``u0`` towards the centre of the face's certificates, just enough.

    ``u0`` fails the exact test when an eigenvalue of some ``S_i`` (or a ``y_r``) is smaller
    than the correction the exact projection makes. The analytic centre ``u_c`` of the face's
    certificates (:func:`_center_on_face`) has every eigenvalue well inside; the returned point
    is ``(1 - theta) u_a + theta u_c`` with ``u_a`` the float projection of ``u0`` on
    ``g_k = 0`` and the smallest ``theta`` of a geometric grid whose float margin is at least
    ``1e-6 top`` and a quarter of the centre's (a convex combination: the separation and the
    trace conditions stay those of ``u0`` and ``u_c``).
    """
    sizes = [int(np.sum(sel)) for sel in sels]
    J = _face_jacobian(problem, eigs, sels, rows)
    ge_rows = np.array([bool(ge[r]) for r in rows], dtype=bool)
    separate = float(J[0] @ u0) < 0
    try:
        uc = _center_on_face(J, u0, sizes, ge_rows, separate)
    except np.linalg.LinAlgError:  # a singular block: the slice has no interior here
        uc = None
    if uc is None:
        return None
    ua = u0 - np.linalg.lstsq(J[1:], J[1:] @ u0, rcond=1e-13)[0]
    nS = sum(r * (r + 1) // 2 for r in sizes)

    def margin(u: np.ndarray) -> float:
        out, k = [], 0
        for r in sizes:
            ia, ib = np.triu_indices(r)
            S = np.zeros((r, r))
            S[ia, ib] = S[ib, ia] = u[k : k + len(ia)]
            k += len(ia)
            if r:
                out.append(float(np.linalg.eigvalsh(S)[0]))
        out += [float(v) for v in u[nS:][ge_rows]]
        return min(out, default=math.inf)

    if not margin(uc) > 1e-9 * top:  # the centre is on the boundary: the face is too large
        return None
    want = min(0.25 * margin(uc), 1e-6 * top)
    for theta in (0.0, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 0.03, 0.1, 0.3):
        u = (1 - theta) * ua + theta * uc
        if margin(u) >= want:
            return u
    return uc


def prove_infeasible(
    problem: Problem,
    farkas: dict[str, Any],
    verification: dict[str, Any],
    rel_face: tuple[float, ...] | None = None,
) -> dict[str, Any]:
    """The exact proof :func:`lmic.certify.certify` runs for an ``infeasible`` answer.

    Tries the repaired certificate (when :func:`verify_farkas` repaired one), then the
    solver's certificate in the orientation that verified (or both when none did). ``rel_face``
    (default: :func:`prove_farkas`'s) limits the face thresholds tried (each try costs seconds on
    problems with a few dozen variables).

    Returns
    -------
    dict
        :func:`prove_farkas`'s result (the first proof, or the first failure), with
        ``source`` (``"repaired"`` or ``"solver"``) and the ``denominator`` the certificate
        schema asks for.

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
    >>> p = Problem([Variable("p", "scalar", (1, 1))],
    ...             [LMI("p > 0", 1, sp.csc_matrix([[0., 1.]])),
    ...              LMI("-p > 0", 1, sp.csc_matrix([[0., -1.]]))],
    ...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
    >>> f = {"lmis": [np.eye(1), np.eye(1)]}
    >>> r = prove_infeasible(p, f, verify_farkas(p, f))
    >>> r["proven"], r["kind"], r["source"]
    (True, 'strict', 'solver')
    """
    mats, y = _parse(problem, farkas)
    candidates: list[tuple[str, dict[str, Any]]] = []
    if verification.get("repaired"):
        candidates.append(("repaired", verification["certificate"]))
    signs = [-1.0 if verification.get("negated") else 1.0] if verification.get("verified") else [1.0, -1.0]
    candidates += [("solver", {"lmis": [sg * Z for Z in mats], "linear": sg * y}) for sg in signs]
    out: dict[str, Any] = {}
    for source, cand in candidates:
        r = prove_farkas(problem, cand) if rel_face is None else prove_farkas(problem, cand, rel_face=rel_face)
        r["source"] = source
        if not out or r["proven"]:
            out = r
        if r["proven"]:
            break
    out["denominator"] = "rational" if out["proven"] else "-"  # sizes in denominator_bits
    return out


def is_homogeneous(problem: Problem) -> bool:
    """True when every LMI has ``F0 = 0`` and every linear row ``a0 = 0`` (a conic feasible set).

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("p", "scalar", (1, 1))], [LMI("p > 0", 1, sp.csc_matrix([[0., 1.]]))],
    ...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
    >>> is_homogeneous(p)
    True
    """
    for lmi in problem.lmis:
        col0 = lmi.coeffs.tocsc()[:, 0]
        if col0.nnz and np.any(col0.toarray()):
            return False
    if len(problem.linear):
        a0 = problem.linear.A.tocsc()[:, 0]
        if a0.nnz and np.any(a0.toarray()):
            return False
    return True


def scope(problem: Problem, verification: dict[str, Any] | None, exact: dict[str, Any] | None = None) -> dict[str, Any]:
    """What a Farkas certificate proves about the original problem: global, bounded or nothing.

    Rules in the module docstring ("Global or bounded").

    Parameters
    ----------
    problem : Problem
        The original problem (never a reduction of it).
    verification : dict or None
        :func:`verify_farkas`'s report.
    exact : dict or None
        :func:`prove_infeasible`'s report, when an exact proof was tried.

    Returns
    -------
    dict
        ``scope`` (``"global"``, ``"bounded"`` or ``None``), ``radius`` (bounded: no solution with
        ``||x||_inf <= radius``; ``inf`` for global), ``basis`` (``"exact"``, ``"homogeneous"``,
        ``"float"``), ``rho`` (homogeneous: relative-margin bound) and ``statement`` (one line).

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("p", "scalar", (1, 1))],
    ...             [LMI("p > 0", 1, sp.csc_matrix([[0., 1.]])), LMI("-p > 0", 1, sp.csc_matrix([[0., -1.]]))],
    ...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
    >>> f = {"lmis": [np.eye(1), np.eye(1)]}
    >>> scope(p, verify_farkas(p, f))["scope"]
    'global'
    >>> q = Problem([Variable("p", "scalar", (1, 1))],
    ...             [LMI("p >= 0", 1, sp.csc_matrix([[0., 1.]]), strict=False),
    ...              LMI("-1 - p >= 0", 1, sp.csc_matrix([[-1., -1.0000001]]), strict=False)],
    ...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
    >>> s = scope(q, verify_farkas(q, {"lmis": [np.eye(1), np.eye(1)]}, repair=False))
    >>> s["scope"], round(s["radius"])
    ('bounded', 10000000)
    """
    if exact is not None and exact.get("proven"):
        return {
            "scope": "global",
            "radius": math.inf,
            "basis": "exact",
            "rho": None,
            "statement": f"infeasible: exact rational Farkas certificate ({exact.get('kind')})",
        }
    v = verification or {}
    if not v.get("verified"):
        return {"scope": None, "radius": None, "basis": None, "rho": None, "statement": "no verified certificate"}
    g0, tau = float(v.get("g0") or 0.0), float(v.get("tau") or 0.0)
    radius = float(v.get("radius") or 0.0)
    if v.get("kind") == "strict" and tau > 0 and is_homogeneous(problem):
        mb = v.get("margin_bound")
        rho = float(mb) if mb is not None else None
        return {
            "scope": "global",
            "radius": math.inf,
            "basis": "homogeneous",
            "rho": rho,
            "statement": (
                "infeasible: homogeneous (scale-free) problem; at any scale no point has relative "
                f"margin above {rho:.3g} (strict Farkas certificate)"
            ),
        }
    if g0 < 0 and radius > 0:
        return {
            "scope": "bounded",
            "radius": radius,
            "basis": "float",
            "rho": None,
            "statement": (
                f"no solution with ||x||_inf <= {radius:.6g} (float Farkas certificate, residual "
                f"{float(v.get('rel_residual') or 0.0):.2g}); a larger solution is not excluded"
            ),
        }
    return {
        "scope": None,
        "radius": None,
        "basis": "float",
        "rho": None,
        "statement": "the certificate bounds the margin only (separation >= 0): no infeasibility shown",
    }
