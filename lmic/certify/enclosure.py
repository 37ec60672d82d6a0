"""Certified enclosures of the optimal value: a proven dual (lower) bound next to the primal one.

For an optimisation problem the certifier proves an *upper* bound on a minimum: the objective
at a certified feasible point. This module proves the *lower* bound, from the solver's dual
point, with every floating-point error accounted for (the approach of VSDP: Jansen, Chaykin
and Keil, "Rigorous error bounds for the optimal value in semidefinite programming", SIAM J.
Numer. Anal. 46 (2007); adapted to lmic's LMI form, where the free variables are ``x``).

Setting (minimisation form)
---------------------------
With ``s = +1`` for ``minimize`` and ``s = -1`` for ``maximize``, write ``q = s c`` (``q_0``
the constant). The problem is ``p* = inf q_0 + q . x`` over ``F_i(x) >= 0`` (``> 0`` when
strict) and rows ``l_r(x) = a_r0 + a_r . x`` ``== 0`` (``eq``) or ``>= 0`` (``ge``). A dual
point is ``u = (Z_i, y)`` (the layout of :attr:`lmic.solution.Solution.duals`, paired with the
normalised ``F_i``). With ``g_k(u) = sum_i <F_i^(k), Z_i> + sum_r a_rk y_r`` (``k = 0 .. n``)
the identity

    ``q_0 + q . x = sum_i <F_i(x), Z_i> + sum_r y_r l_r(x) + (q_0 - g_0(u)) + (q - g(u))_{1:} . x``

holds for every ``x``. **Theorem (weak duality).** If ``Z_i >= 0``, ``y_r >= 0`` on ``ge``
rows and ``g_k(u) = q_k`` exactly for ``k >= 1``, then every feasible ``x`` (strict or not)
has objective ``>= L = q_0 - g_0(u)``. So ``L <= p*``; for a strict problem ``p*`` is an
infimum, possibly not attained, and ``L`` bounds it all the same.

Making the conditions hold exactly
----------------------------------
The solver's dual meets ``g_k = q_k`` only to its tolerance, and at an optimum ``Z_i`` is
singular (complementarity), so neither condition can be checked by floating point as it
stands. The steps, each checked rather than trusted:

1. *signs*: ``Z_i`` is projected onto the PSD cone, ``y`` clipped to ``>= 0`` on ``ge`` rows;
2. *shift*: ``Z_i += eps I`` and ``y_r += eps`` on ``ge`` rows, ``eps = eps_rel * max_i
   lambda_max(Z_i)`` (``eps_rel`` tried in :data:`SHIFTS`, smallest first): the dual moves
   into the interior of the cone, at a cost of about ``eps (sum_i tr F_i(x*) + sum_r
   l_r(x*))`` in the bound;
3. *repair*: damped least-squares steps ``Z_i -> eps/2 I + U_i (I + E_i) U_i^T`` (``Z_i -
   eps/2 I = U_i U_i^T``, ``||E_i||_2 <= 1/2``) and ``y_r -> eps/2 + (y_r - eps/2) (1 + e_r)``
   (``ge`` rows; ``eq`` rows are free), so that every eigenvalue stays above ``eps / 2``, drive
   the residual ``rho = q_{1:} - g_{1:}(u)`` down while keeping the cone; two plain
   least-norm steps over every entry then take it to round-off (they may leave the cone by
   their own size, which the shift must cover: the proof decides);
4. *rigorous bound*, in floating point with a priori error bounds (``u = 2^-53``,
   ``gamma_m = m u / (1 - m u)``, Higham, *Accuracy and Stability*, 2nd ed., ch. 3 and 10):

   * ``rho`` is enclosed: ``|rho_k| <= |fl(rho_k)| + gamma_{m+2} (|q_k| + sum_j |J_kj| |u_j|)``
     (``J`` is the matrix of the linear map ``u -> g(u)``; its entries are IR coefficients
     times 1 or 2, exact in floating point);
   * the exact point ``u* = u + J_S^T M^{-1} rho`` (``S``: the entries of every ``Z_i`` and
     the ``y_r``; ``M = J_S J_S^T``) satisfies ``g_k(u*) = q_k`` exactly, and
     ``||u* - u||_2 <= ||rho||_2 / sqrt(lambda_min(M))``; a rigorous lower bound of
     ``lambda_min(M)`` comes from ``fl(M)`` (error ``<= gamma_m || |J_S| |J_S|^T ||_F``) and
     :func:`lambda_min_lower`;
   * every ``Z_i* = Z_i + Delta_i`` with ``||Delta_i||_2 <= ||Delta_i||_F <= sqrt(2)
     ||u* - u||_2`` (an off-diagonal unknown appears twice), so ``lambda_min(Z_i*) >=
     lambda_min_lower(Z_i) - sqrt(2) ||u* - u||`` (Weyl) must be ``>= 0``, and
     ``y_r* >= y_r - ||u* - u|| >= 0`` on ``ge`` rows;
   * ``L = q_0 - g_0(u*) >= q_0 - fl(g_0(u)) - gamma_{m+2} sum_j |J_0j| |u_j| -
     ||J_{0,S}||_2 ||u* - u||_2``, the last subtraction rounded down.

   Every bound computed in floating point is inflated by ``(1 + 1e-9)`` (their own rounding
   is below ``(m + 4) u < 1e-9`` for ``m < 10^6`` unknowns).

:func:`lambda_min_lower` proves ``lambda_min(A) >= s - gamma_{2(d+1)} ||R||_F^2 - u max_i
|b_ii|`` for a float symmetric ``A`` from a successful Cholesky factorisation ``R`` of ``B =
fl(A - s I)``: ``R^T R = B + dB`` with ``|dB| <= gamma_{d+1} |R^T| |R|`` (Higham, Thm 10.3;
the constant is doubled to cover blocked LAPACK factorisations) and ``|| |R^T| |R| ||_2 <=
||R||_F^2``.

Exact mode (``exact=True``)
---------------------------
The same dual point ``u`` (after steps 1-3) is corrected in rational arithmetic
(python-flint): ``u* = u + J_S^T M^{-1} rho`` with ``rho``, ``M`` and the solve exact, every
``Z_i*`` proved PSD by an integer ``LDL^T`` / congruence (:func:`lmic.certify.exact.prove_psd`),
``y_r* >= 0`` checked exactly and ``L = q_0 - g_0(u*)`` computed exactly (reported rounded
down). Nothing is left to an error bound; it costs a rational solve of order ``n``
(:data:`EXACT_MAX_N`).

The primal end
--------------
The other end is the objective at a point proved feasible with rigorous rounding
(:func:`primal_end`: ``F_i(x)`` with an a-priori evaluation error bound, ``lambda_min`` bounded
by :func:`lambda_min_lower`, the objective rounded outwards). The certifier's ``certified``
tolerates a non-strict LMI violated by round-off; such a point gives no primal end here (the
caller may supply one from a point strictly inside, :func:`with_primal`).

What is recorded
----------------
:func:`dual_bound` returns the bound and the dual point ``u`` it was proved from (before the
exact correction, which is implicit): :func:`verify_dual_bound` re-proves the bound from the
recorded point alone, so ``lmic audit`` rejects a tampered bound (a recorded bound above the
re-proved one) or a tampered dual point (the bound no longer follows from it).

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
>>> # min t  s.t.  [[t, 1], [1, t]] >= 0  has optimum 1 (dual Z = [[.5, -.5], [-.5, .5]])
>>> C = sp.csc_matrix(np.array([[0.0, 1.0], [1.0, 0.0], [0.0, 1.0]]))
>>> p = Problem([Variable("t", "scalar", (1, 1))], [LMI("M >= 0", 2, C, strict=False)],
...             LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
>>> r = dual_bound(p, {"lmis": [np.array([[0.5, -0.5], [-0.5, 0.5]])], "linear": []})
>>> r["proven"], 0.999999 < r["lower"] <= 1.0
(True, True)
"""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Callable
from typing import Any

import numpy as np
import scipy.sparse as sp

from lmic.certify.multipliers import parse_multipliers
from lmic.errors import CertificateError
from lmic.ir.problem import Problem
from lmic.ir.svec import tril_rows_cols, tril_unvec

__all__ = [
    "SHIFTS",
    "EXACT_MAX_N",
    "lambda_min_lower",
    "dual_bound",
    "verify_dual_bound",
    "enclosure",
    "perturbed_problem",
    "PERTURBATIONS",
    "summary",
    "describe",
    "audit_enclosure",
    "with_primal",
    "primal_end",
]

#: relative shifts ``eps_rel`` tried, smallest first (step 2 of the module docstring)
SHIFTS = (1e-12, 1e-10, 1e-9, 1e-8, 3e-8, 1e-7, 3e-7, 1e-6)
#: relative perturbations ``eps_rel`` of :func:`perturbed_problem` tried when the solver's
#: own dual is degenerate
PERTURBATIONS = (1e-8, 1e-6)
#: a multiplier block below this times the largest multiplier is set to exactly zero (an
#: inactive constraint; it then needs no interior shift)
DROP = 1e-6
#: largest number of variables the exact (rational) correction is attempted for
EXACT_MAX_N = 400
_U = 2.0**-53
_SAFE = 1.0 + 1e-9


def _gamma(m: int) -> float:
    return m * _U / (1.0 - m * _U)


def _down(v: float) -> float:
    """A float ``<= v`` for a float ``v`` computed with one rounding."""
    return float(np.nextafter(np.nextafter(v, -np.inf), -np.inf))


def lambda_min_lower(A: np.ndarray) -> float:
    """A rigorous lower bound of ``lambda_min(A)`` for a float symmetric matrix ``A``.

    See the module docstring (Cholesky of ``A - s I`` with Higham's error bound). Returns
    ``-inf`` when no shift below the estimated smallest eigenvalue factorises.

    Examples
    --------
    >>> lb = lambda_min_lower(np.array([[2.0, 1.0], [1.0, 2.0]]))
    >>> 0.99 < lb <= 1.0
    True
    """
    A = np.asarray(A, dtype=float)
    d = A.shape[0]
    if d == 0:
        return math.inf
    if not np.all(np.isfinite(A)) or np.any(A != A.T):
        return -math.inf
    est = float(np.linalg.eigvalsh(A)[0])
    norm = float(np.max(np.abs(A)))
    g = _gamma(2 * (d + 1))
    best = -math.inf
    for f in (1e-9, 1e-6, 1e-3, 0.1, 0.5):
        s = est - max(f * abs(est), 4.0 * (d + 1) * (d + 1) * _U * norm)
        B = A - s * np.eye(d)
        try:
            R = np.linalg.cholesky(B)
        except np.linalg.LinAlgError:
            continue
        if not np.all(np.isfinite(R)):
            continue
        err = (g * float(np.sum(R * R)) + _U * float(np.max(np.abs(np.diag(B))))) * _SAFE
        lb = _down(s - err)
        best = max(best, lb)
        if lb > 0 or est <= 0:
            break
    return best


# -- the linear map u -> g(u) ----------------------------------------------------------------


def _weights(d: int) -> np.ndarray:
    i, j = tril_rows_cols(d)
    return np.where(i == j, 1.0, 2.0)


def _jacobian(problem: Problem) -> tuple[sp.csr_matrix, list[tuple[int, int]]]:
    """``J`` (``(1 + n) x m``, ``g = J u``) and the column range of every LMI's ``svec(Z_i)``."""
    cols, ranges, start = [], [], 0
    for lmi in problem.lmis:
        C = lmi.coeffs.tocsc()
        cols.append(sp.csr_matrix(C.T.multiply(_weights(lmi.dim)[None, :])))
        t = C.shape[0]
        ranges.append((start, start + t))
        start += t
    if len(problem.linear):
        cols.append(sp.csr_matrix(problem.linear.A.T))
    if not cols:
        return sp.csr_matrix((1 + problem.n, 0)), ranges
    return sp.csr_matrix(sp.hstack(cols)), ranges


def _pack(problem: Problem, mats: list[np.ndarray], y: np.ndarray) -> np.ndarray:
    parts = []
    for lmi, Z in zip(problem.lmis, mats, strict=True):
        r, c = tril_rows_cols(lmi.dim)
        parts.append(Z[r, c])
    parts.append(y)
    return np.concatenate(parts) if parts else np.zeros(0)


def _unpack(problem: Problem, u: np.ndarray, ranges: list[tuple[int, int]]) -> tuple[list[np.ndarray], np.ndarray]:
    mats = [tril_unvec(u[a:b], lmi.dim) for lmi, (a, b) in zip(problem.lmis, ranges, strict=True)]
    off = ranges[-1][1] if ranges else 0
    return mats, u[off:].copy()


def _parse(problem: Problem, record: dict[str, Any]) -> tuple[list[np.ndarray], np.ndarray]:
    return parse_multipliers(problem, record, "dual point", missing_is_zero=False)


def _target(problem: Problem) -> tuple[float, np.ndarray]:
    s = -1.0 if problem.objective.sense == "max" else 1.0
    q = s * problem.objective.c
    return s, q


# -- steps 1-3: a dual point inside the cone with round-off residual --------------------------


def _repair(
    problem: Problem,
    J: sp.csr_matrix,
    ranges: list,
    q: np.ndarray,
    mats: list,
    y: np.ndarray,
    floor: float = 0.0,
    steps: int = 40,
):
    import scipy.linalg

    ge = np.array([k == "ge" for k in problem.linear.kinds], dtype=bool)
    Jx = J[1:].tocsc()
    qn = q[1:]
    scale = float(np.max(np.abs(qn), initial=0.0)) + 1e-300
    history: list[float] = []
    for _ in range(steps):
        u = _pack(problem, mats, y)
        rho = qn - Jx @ u
        now = float(np.max(np.abs(rho), initial=0.0))
        if now <= 1e-15 * scale or (len(history) >= 6 and now > 0.9 * history[-6]):
            break  # converged, or stalled (no interior point near: the proof will say so)
        history.append(now)
        blocks: list[np.ndarray] = []
        factors: list[tuple[np.ndarray, np.ndarray, np.ndarray] | None] = []
        for lmi, Z, (a, b) in zip(problem.lmis, mats, ranges, strict=True):
            if not lmi.dim:
                factors.append(None)
                continue
            w, V = np.linalg.eigh(Z - floor * np.eye(lmi.dim))
            sel = w > 0
            U = V[:, sel] * np.sqrt(w[sel])
            r = U.shape[1]
            if not r:
                factors.append(None)
                continue
            ri, ci = tril_rows_cols(lmi.dim)
            ia, ib = np.triu_indices(r)
            P, Qm = U[ri], U[ci]
            T = P[:, ia] * Qm[:, ib] + P[:, ib] * Qm[:, ia]
            T[:, ia == ib] *= 0.5
            # d svec(Z) / d E_ab, mapped by J's columns of this LMI
            blocks.append(np.asarray(Jx[:, a:b] @ T))
            factors.append((U, ia, ib))
        off = ranges[-1][1] if ranges else 0
        rows = [r for r in range(len(y)) if (not ge[r]) or y[r] > floor]
        top = max([float(np.max(np.abs(y), initial=0.0))] + [float(np.max(np.abs(Z), initial=0.0)) for Z in mats])
        srow = np.array([y[r] - floor if ge[r] else max(abs(y[r]), 1e-3 * top, 1e-300) for r in rows])
        if rows:
            blocks.append(Jx[:, [off + r for r in rows]].toarray() * srow[None, :])
        if not blocks:
            break
        G = np.hstack(blocks)
        # least-norm step through the Gram matrix (n x n, cheap for the wide G of a face)
        Gm = G @ G.T
        Gm[np.diag_indices_from(Gm)] += 1e-14 * float(np.trace(Gm)) / max(1, Gm.shape[0]) + 1e-300
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", scipy.linalg.LinAlgWarning)
                e = G.T @ np.linalg.solve(Gm, rho)
        except (np.linalg.LinAlgError, ValueError):
            e = scipy.linalg.lstsq(G, rho, lapack_driver="gelsy", check_finite=False)[0]
        k, norms = 0, [0.0]
        Es: list[np.ndarray | None] = []
        for f in factors:
            if f is None:
                Es.append(None)
                continue
            U, ia, ib = f
            r = U.shape[1]
            E = np.zeros((r, r))
            E[ia, ib] = e[k : k + len(ia)]
            E[ib, ia] = e[k : k + len(ia)]
            k += len(ia)
            Es.append(E)
            norms.append(float(np.max(np.abs(np.linalg.eigvalsh(E)))))
        ey = e[k:]
        norms += [abs(float(v)) for r, v in zip(rows, ey, strict=True) if ge[r]]
        alpha = 1.0 if max(norms) <= 0.5 else 0.5 / max(norms)
        new = []
        for Z, f, Ef in zip(mats, factors, Es, strict=True):
            if f is None or Ef is None:
                new.append(Z)
            else:
                U = f[0]
                Zn = U @ (np.eye(U.shape[1]) + alpha * Ef) @ U.T + floor * np.eye(U.shape[0])
                new.append(0.5 * (Zn + Zn.T))
        mats = new
        y = y.copy()
        for r, v, sr in zip(rows, ey, srow, strict=True):
            y[r] += alpha * float(v) * sr
    return mats, y


def _scale(problem: Problem, mats: list, y: np.ndarray) -> float:
    ge = np.array([k == "ge" for k in problem.linear.kinds], dtype=bool)
    top = max(
        [float(np.max(np.abs(y[ge]), initial=0.0))]
        + [float(np.max(np.linalg.eigvalsh(Z), initial=0.0)) if Z.size else 0.0 for Z in mats]
    )
    return top if top > 0 else 1.0


def perturbed_problem(problem: Problem, eps: float) -> Problem:
    """The closed problem whose duals are ``eps`` inside the cone (VSDP's perturbation).

    Its objective is the minimisation form's ``q`` minus ``eps t`` with ``t_k = sum_i tr
    F_i^(k) + sum_{r ge} a_rk``: a dual point ``(Z_i', y')`` of it gives ``Z_i = Z_i' + eps I``,
    ``y_r = y_r' + eps`` (``ge`` rows), a dual point of ``problem`` whose every eigenvalue is at
    least ``eps``. Strict constraints are closed (the dual bound holds for the closure).

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("t", "scalar", (1, 1))], [LMI("t > 2", 1, sp.csc_matrix([[-2.0, 1.0]]))],
    ...             LinearConstraints.empty(1), Objective("max", [1.0, -1.0]))
    >>> q = perturbed_problem(p, 0.5)
    >>> q.objective.sense, q.objective.c.tolist(), q.lmis[0].strict
    ('min', [-1.0, 0.5], False)
    """
    import dataclasses

    from lmic.ir.problem import LinearConstraints, Objective

    _, q = _target(problem)
    t = np.zeros(1 + problem.n)
    for lmi in problem.lmis:
        i, j = tril_rows_cols(lmi.dim)
        t += np.asarray(lmi.coeffs.tocsr()[np.flatnonzero(i == j)].sum(axis=0)).ravel()
    ge = np.array([k == "ge" for k in problem.linear.kinds], dtype=bool)
    if np.any(ge):
        t += np.asarray(problem.linear.A.tocsr()[np.flatnonzero(ge)].sum(axis=0)).ravel()
    c = q - eps * t
    c[0] = q[0]
    lin = problem.linear
    return Problem(
        list(problem.variables),
        [dataclasses.replace(lmi, strict=False) for lmi in problem.lmis],
        LinearConstraints(lin.A, list(lin.kinds), [False] * len(lin), list(lin.names)),
        Objective("min", c),
        meta={"perturbed_from": problem.meta.get("theorem") if problem.meta else None},
    )


def _prepare(
    problem: Problem, J, ranges, q, mats, y, eps_rel: float, top: float | None = None, drop: bool = True
) -> tuple[list, np.ndarray, np.ndarray]:
    """Steps 1-3 of the module docstring; returns ``(Z_i, y, active)`` (``active``: the
    entries of ``u`` the proof may correct; the others are exactly zero)."""
    ge = np.array([k == "ge" for k in problem.linear.kinds], dtype=bool)
    proj = []
    for Z in mats:
        if not Z.size:
            proj.append(Z)
            continue
        w, V = np.linalg.eigh(Z)
        proj.append((V * np.maximum(w, 0.0)) @ V.T)
    y = np.where(ge, np.maximum(y, 0.0), y)
    if top is None:
        top = _scale(problem, proj, y)
    eps = eps_rel * top
    active = np.ones(_pack(problem, proj, y).size, dtype=bool)
    keep = []
    for Z, (a, b) in zip(proj, ranges, strict=True):
        on = not drop or (Z.size and float(np.max(np.linalg.eigvalsh(Z))) > DROP * top)
        keep.append(on)
        active[a:b] = on
    off = ranges[-1][1] if ranges else 0
    rows_on = ~ge | (y > DROP * top) | (not drop)
    active[off:] = rows_on
    proj = [Z + eps * np.eye(Z.shape[0]) if on else np.zeros_like(Z) for Z, on in zip(proj, keep, strict=True)]
    y = np.where(ge & rows_on, y + eps, np.where(ge, 0.0, y))
    mats, y = _repair(problem, J, ranges, q, [0.5 * (Z + Z.T) for Z in proj], y, floor=0.5 * eps)
    # what the damped steps left: a plain least-norm step over the active entries (it may
    # leave the cone by its own size, which the shift pays for; the proof decides)
    u = _pack(problem, mats, y)
    Js = J[1:][:, np.flatnonzero(active)]
    for _ in range(2):
        rho = q[1:] - J[1:] @ u
        if not np.any(rho):
            break
        M = (Js @ Js.T).toarray()
        w = np.linalg.lstsq(M, rho, rcond=None)[0]
        u[active] += Js.T @ w
    mats, y = _unpack(problem, u, ranges)
    return mats, y, active


# -- step 4: the rigorous bound -----------------------------------------------------------------


def _prove_float(problem: Problem, J, ranges, q, mats, y, active: np.ndarray | None = None) -> dict[str, Any]:
    ge = np.array([k == "ge" for k in problem.linear.kinds], dtype=bool)
    u = _pack(problem, mats, y)
    if active is None:  # every nonzero entry may be corrected
        active = np.ones(u.size, dtype=bool)
        for a, b in ranges:
            active[a:b] = bool(np.any(u[a:b]))
        off = ranges[-1][1] if ranges else 0
        active[off:] = ~ge | (u[off:] != 0)
    if np.any(u[~active] != 0):
        return {"proven": False, "reason": "an inactive multiplier is not exactly zero"}
    m = u.size
    gm = _gamma(m + 2)
    Ja = abs(J)
    absu = np.abs(u)
    g = J @ u
    rho = q[1:] - g[1:]
    rho_bar = (np.abs(rho) + gm * (np.abs(q[1:]) + (Ja @ absu)[1:])) * _SAFE
    rho_norm = float(np.linalg.norm(rho_bar)) * _SAFE
    Js = J[1:][:, np.flatnonzero(active)]
    # a variable no active multiplier can move needs an exactly zero residual
    nz = np.asarray(abs(Js).sum(axis=1)).ravel() > 0
    if np.any(~nz & (rho_bar != 0)):
        k = int(np.flatnonzero(~nz & (rho_bar != 0))[0])
        return {"proven": False, "reason": f"x[{k}] has a residual no active multiplier can absorb"}
    Js = Js[nz]
    if Js.shape[0]:
        M = (Js @ Js.T).toarray()
        Jsa = abs(Js)
        E = (Jsa @ Jsa.T).toarray()
        err_M = _gamma(m + 1) * float(np.linalg.norm(E)) * _SAFE
        lamM = lambda_min_lower(0.5 * (M + M.T)) - err_M - _U * float(np.max(np.abs(M - M.T), initial=0.0))
        if not lamM > 0:
            return {
                "proven": False,
                "reason": "the dual equality system is singular (no lower bound on sigma_min of the constraint map)",
            }
        dn = rho_norm / math.sqrt(_down(lamM)) * _SAFE
    else:
        dn = 0.0
    margins = []
    for lmi, Z, (a, b) in zip(problem.lmis, mats, ranges, strict=True):
        if not np.any(active[a:b]):
            continue  # exactly zero, not corrected: PSD
        lb = lambda_min_lower(Z) if lmi.dim else math.inf
        margins.append(lb)
        if lmi.dim and not lb - math.sqrt(2.0) * dn * _SAFE >= 0:
            return {
                "proven": False,
                "reason": f"multiplier of LMI '{lmi.name}' not proved PSD: lambda_min >= {lb:.3g}, "
                f"correction up to {math.sqrt(2.0) * dn:.3g}",
            }
    off = ranges[-1][1] if ranges else 0
    gea = ge & active[off:]
    if np.any(gea) and not float(np.min(y[gea])) - dn * _SAFE >= 0:
        return {"proven": False, "reason": "a row multiplier is not proved nonnegative after the correction"}
    j0 = J[0].toarray().ravel()
    g0 = float(g[0])
    g0_err = gm * float(np.abs(j0) @ absu) * _SAFE
    corr = float(np.linalg.norm(j0[active])) * dn * _SAFE
    lower = _down(_down(q[0] - g0) - (g0_err + corr) * _SAFE)
    return {
        "proven": True,
        "lower": lower,
        "residual_bound": rho_norm,
        "correction_bound": dn,
        "min_eig_lower": min(margins, default=math.inf),
        "reason": "dual point proved feasible with rigorous floating-point error bounds",
    }


def _default_active(problem: Problem, ranges: list, u: np.ndarray) -> np.ndarray:
    """Entries a proof may correct: every nonzero block, ``eq`` rows, nonzero ``ge`` rows."""
    ge = np.array([k == "ge" for k in problem.linear.kinds], dtype=bool)
    active = np.ones(u.size, dtype=bool)
    for a, b in ranges:
        active[a:b] = bool(np.any(u[a:b]))
    off = ranges[-1][1] if ranges else 0
    active[off:] = ~ge | (u[off:] != 0)
    return active


def _prove_exact(problem: Problem, J, ranges, q, mats, y) -> dict[str, Any]:
    from fractions import Fraction

    from lmic.certify.exact import _flint, prove_psd

    flint = _flint()
    n = problem.n
    if n > EXACT_MAX_N:
        return {"proven": False, "reason": f"{n} variables: above the exact limit {EXACT_MAX_N}"}
    ge = np.array([k == "ge" for k in problem.linear.kinds], dtype=bool)
    u = _pack(problem, mats, y)

    def fq(v: float) -> Any:
        f = Fraction(float(v))
        return flint.fmpq(f.numerator, f.denominator)

    Jc = J.tocsr()
    active = _default_active(problem, ranges, u)
    uq = [fq(v) for v in u]

    def row(k: int) -> dict[int, Any]:
        a, b = Jc.indptr[k], Jc.indptr[k + 1]
        return {int(j): fq(v) for j, v in zip(Jc.indices[a:b], Jc.data[a:b], strict=True)}

    # exact residual over every entry; the correction moves only the active ones
    rows, rho = [], []
    for k in range(1, 1 + n):
        full = row(k)
        res = fq(q[k]) - sum((v * uq[j] for j, v in full.items()), flint.fmpq(0))
        act = {j: v for j, v in full.items() if active[j]}
        if not act:
            if res != 0:
                return {"proven": False, "reason": f"x[{k - 1}] has a residual no active multiplier can absorb"}
            continue
        rows.append(act)
        rho.append(res)
    p = len(rows)
    if p:
        Mq = flint.fmpq_mat(p, p)
        for a in range(p):
            ra = rows[a]
            for b in range(a, p):
                rb = rows[b]
                s = flint.fmpq(0)
                small, big = (ra, rb) if len(ra) <= len(rb) else (rb, ra)
                for j, v in small.items():
                    w = big.get(j)
                    if w is not None:
                        s += v * w
                Mq[a, b] = s
                Mq[b, a] = s
        try:
            w = Mq.solve(flint.fmpq_mat([[r] for r in rho]))
        except ZeroDivisionError:
            return {"proven": False, "reason": "the dual equality system is singular in exact arithmetic"}
        ustar = list(uq)
        for a in range(p):
            wa = w[a, 0]
            if wa != 0:
                for j, v in rows[a].items():
                    ustar[j] += v * wa
    else:
        ustar = list(uq)
    # exact checks: Z_i* PSD, y* >= 0 on ge rows
    for lmi, (a, b) in zip(problem.lmis, ranges, strict=True):
        if not lmi.dim:
            continue
        vals = [Fraction(int(v.p), int(v.q)) for v in ustar[a:b]]
        den = 1
        for f in vals:
            den = den * f.denominator // math.gcd(den, f.denominator)
        ri, ci = tril_rows_cols(lmi.dim)
        Mi = [[0] * lmi.dim for _ in range(lmi.dim)]
        for f, r_, c_ in zip(vals, ri, ci, strict=True):
            Mi[r_][c_] = Mi[c_][r_] = int(f * den)
        pr = prove_psd(Mi)
        if not pr["proven"]:
            return {"proven": False, "reason": f"exact multiplier of LMI '{lmi.name}' not proved PSD ({pr['detail']})"}
    off = ranges[-1][1] if ranges else 0
    for r in range(len(y)):
        if ge[r] and ustar[off + r] < 0:
            return {"proven": False, "reason": f"exact multiplier of row '{problem.linear.names[r]}' is negative"}
    r0 = row(0)
    g0 = sum((v * ustar[j] for j, v in r0.items()), flint.fmpq(0))
    L = fq(q[0]) - g0
    Lf = Fraction(int(L.p), int(L.q))
    lower = float(Lf)
    if Fraction(lower) > Lf:
        lower = _down(lower)
    return {
        "proven": True,
        "lower": lower,
        "lower_exact": f"{Lf.numerator}/{Lf.denominator}" if Lf.denominator != 1 else str(Lf.numerator),
        "reason": "dual point corrected and proved feasible in exact rational arithmetic",
    }


def dual_bound(
    problem: Problem,
    duals: dict[str, Any],
    *,
    exact: bool = False,
    resolve: Callable[[Problem], dict[str, Any] | None] | None = None,
    budget_s: float = 20.0,
) -> dict[str, Any]:
    """Prove a lower bound of the minimisation form's optimal value from a dual point.

    Parameters
    ----------
    problem : Problem
        An optimisation problem (``min`` or ``max``).
    duals : dict
        ``{"lmis": [Z_i], "linear": y}`` (:attr:`lmic.solution.Solution.duals`).
    exact : bool
        Prove in rational arithmetic (module docstring, *Exact mode*) after the float proof.
    resolve : callable, optional
        ``resolve(problem) -> duals`` (a solve on the caller's backend). When the solver's own
        dual cannot be proved (a degenerate dual: no strictly feasible point near it), the
        dual of :func:`perturbed_problem` is tried (``route`` ``"perturbed"``).
    budget_s : float
        No new attempt (shift or perturbation) starts after this many seconds.

    Returns
    -------
    dict
        ``proven`` (bool), ``route`` (``"solver dual"`` or ``"perturbed"``), ``lower`` (a
        bound ``<= inf q_0 + q . x``, the minimisation form:
        for ``max`` problems ``-lower`` bounds the maximum from above), ``method``
        (``"rigorous-float"`` or ``"exact"``), ``shift`` (the ``eps_rel`` used), ``reason``,
        ``dual`` (the dual point the bound was proved from, JSON-ready), ``time_s``; the float
        proof's ``residual_bound``, ``correction_bound``, ``min_eig_lower``.

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
    >>> p = Problem([Variable("t", "scalar", (1, 1))],
    ...             [LMI("t - 2 >= 0", 1, sp.csc_matrix([[-2.0, 1.0]]), strict=False)],
    ...             LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
    >>> r = dual_bound(p, {"lmis": [np.eye(1)], "linear": []})
    >>> r["proven"], 1.9999999 < r["lower"] <= 2.0
    (True, True)
    """
    t0 = time.perf_counter()
    if problem.objective.sense == "feasibility":
        raise CertificateError("a feasibility problem has no optimal value to bound")
    mats0, y0 = _parse(problem, duals)
    _, q = _target(problem)
    J, ranges = _jacobian(problem)
    out: dict[str, Any] = {"proven": False, "reason": "no shift gave a provable dual point"}
    top = _scale(problem, mats0, y0)
    attempts: list[tuple[str, float, list | None, np.ndarray | None]] = [("solver dual", e, mats0, y0) for e in SHIFTS]
    for k, (route, eps_rel, mz, yz) in enumerate(attempts):
        if k and time.perf_counter() - t0 > budget_s:
            out["reason"] = f"{out.get('reason')}; time budget {budget_s:g} s spent after {k} attempts"
            break
        if route == "perturbed" and mz is None:
            try:
                d2 = resolve(perturbed_problem(problem, eps_rel * top)) if resolve is not None else None
                mz, yz = _parse(problem, d2) if d2 else (None, None)
            except CertificateError:
                mz = None
            if mz is None:
                continue
            # Z = Z' + eps I: the perturbed dual shifted back (the shift of _prepare)
        try:
            mats, y, active = _prepare(problem, J, ranges, q, mz, yz, eps_rel, top)
            res = _prove_float(problem, J, ranges, q, mats, y, active)
            if not res["proven"] and ("singular" in res["reason"] or "absorb" in res["reason"]):
                mats, y, active = _prepare(problem, J, ranges, q, mz, yz, eps_rel, top, drop=False)
                res = _prove_float(problem, J, ranges, q, mats, y, active)
        except (np.linalg.LinAlgError, ValueError, FloatingPointError) as exc:
            res = {"proven": False, "reason": f"numerical failure in the repair: {exc}"}
        res.update(method="rigorous-float", shift=eps_rel, route=route)
        if res["proven"] or not out.get("proven"):
            res["dual"] = {"lmis": [Z.tolist() for Z in mats], "linear": y.tolist()} if res["proven"] else None
            out = res
        if res["proven"]:
            break
        if k == len(SHIFTS) - 1 and resolve is not None:
            attempts += [("perturbed", e, None, None) for e in PERTURBATIONS]
    if exact and out.get("proven"):
        mats, y = _parse(problem, out["dual"])
        ex = _prove_exact(problem, J, ranges, q, mats, y)
        out["exact"] = ex
        if ex["proven"]:
            out.update(method="exact", lower=ex["lower"], lower_exact=ex["lower_exact"])
    out["time_s"] = time.perf_counter() - t0
    return out


def verify_dual_bound(problem: Problem, record: dict[str, Any], *, exact: bool = False) -> dict[str, Any]:
    """Re-prove a recorded dual bound from its recorded dual point alone (for ``lmic audit``).

    The recorded point is used as it stands (no shift, no repair): its rigorous bound must be
    at least the recorded ``lower`` (minimisation form).

    Returns
    -------
    dict
        ``ok`` (bool), ``lower`` (re-proved), ``reason``.

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
    >>> p = Problem([Variable("t", "scalar", (1, 1))],
    ...             [LMI("t - 2 >= 0", 1, sp.csc_matrix([[-2.0, 1.0]]), strict=False)],
    ...             LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
    >>> r = dual_bound(p, {"lmis": [np.eye(1)], "linear": []})
    >>> verify_dual_bound(p, r)["ok"], verify_dual_bound(p, dict(r, lower=2.5))["ok"]
    (True, False)
    """
    if not record.get("dual") or record.get("lower") is None:
        return {"ok": False, "lower": None, "reason": "no dual point recorded"}
    try:
        mats, y = _parse(problem, record["dual"])
    except CertificateError as exc:
        return {"ok": False, "lower": None, "reason": str(exc)}
    _, q = _target(problem)
    J, ranges = _jacobian(problem)
    if exact or record.get("method") == "exact":
        res = _prove_exact(problem, J, ranges, q, mats, y)
    else:
        res = _prove_float(problem, J, ranges, q, mats, y)
    if not res["proven"]:
        return {
            "ok": False,
            "lower": None,
            "reason": "the recorded dual point does not prove a bound: " + res["reason"],
        }
    rec = float(record["lower"])
    if rec > res["lower"]:
        return {
            "ok": False,
            "lower": res["lower"],
            "reason": f"recorded lower bound {rec:.17g} exceeds the bound the dual point proves ({res['lower']:.17g})",
        }
    return {"ok": True, "lower": res["lower"], "reason": "lower bound re-proved from the recorded dual point"}


def primal_end(problem: Problem, x: np.ndarray) -> dict[str, Any]:
    """Prove ``x`` feasible with rigorous rounding, and bound its objective outwards.

    Every ``F_i(x)`` is evaluated in floating point with the entrywise error bound
    ``gamma_{k+1} (|F_i^(0)| + sum_k |x_k| |F_i^(k)|)`` (``k`` terms); ``lambda_min(F_i(x)) >=
    lambda_min_lower(fl(F_i(x))) - ||E_i||_F`` must be ``>= 0`` (``> 0`` when strict). Rows
    ``ge`` likewise; ``eq`` rows are evaluated exactly (rationals) and must vanish. The
    certifier's tolerances play no part: a point it certifies with a non-strict constraint
    violated by round-off gives no primal end here.

    Returns
    -------
    dict
        ``proven`` (bool), ``value`` (the objective, rounded up for ``min`` and down for
        ``max``: a rigorous end), ``reason``.

    Examples
    --------
    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("t", "scalar", (1, 1))],
    ...             [LMI("t - 2 >= 0", 1, sp.csc_matrix([[-2.0, 1.0]]), strict=False)],
    ...             LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
    >>> primal_end(p, np.array([2.5]))["value"] >= 2.5, primal_end(p, np.array([1.9]))["proven"]
    (True, False)
    """
    from fractions import Fraction

    x = np.asarray(x, dtype=float).ravel()
    if x.shape != (problem.n,) or not np.all(np.isfinite(x)):
        return {"proven": False, "value": None, "reason": "no finite point of the right length"}
    xx = np.concatenate([[1.0], x])
    ax = np.abs(xx)
    for lmi in problem.lmis:
        C = lmi.coeffs.tocsr()
        f = np.asarray(C @ xx).ravel()
        k = int(np.max(np.diff(C.indptr), initial=0))
        err = _gamma(k + 2) * np.asarray(abs(C) @ ax).ravel() * _SAFE
        F = tril_unvec(f, lmi.dim)
        E = tril_unvec(err, lmi.dim)
        lb = lambda_min_lower(0.5 * (F + F.T)) - float(np.linalg.norm(E)) * _SAFE
        if not (lb > 0 if lmi.strict else lb >= 0):
            return {
                "proven": False,
                "value": None,
                "reason": f"LMI '{lmi.name}' is not proved {'> 0' if lmi.strict else '>= 0'} at the point "
                f"with rigorous rounding (lambda_min >= {lb:.3g})",
            }
    lin = problem.linear
    if len(lin):
        A = lin.A.tocsr()
        r = np.asarray(A @ xx).ravel()
        k = int(np.max(np.diff(A.indptr), initial=0))
        err = _gamma(k + 2) * np.asarray(abs(A) @ ax).ravel() * _SAFE
        for i, (kind, strict) in enumerate(zip(lin.kinds, lin.strict, strict=True)):
            if kind == "eq":
                a, b = A.indptr[i], A.indptr[i + 1]
                exact = sum(
                    (
                        Fraction(float(v)) * Fraction(float(xx[j]))
                        for j, v in zip(A.indices[a:b], A.data[a:b], strict=True)
                    ),
                    Fraction(0),
                )
                ok = exact == 0
            else:
                ok = (r[i] - err[i] > 0) if strict else (r[i] - err[i] >= 0)
            if not ok:
                return {
                    "proven": False,
                    "value": None,
                    "reason": f"row '{lin.names[i]}' is not proved at the point with rigorous rounding",
                }
    c = problem.objective.c
    v = float(c @ xx)
    e = _gamma(problem.n + 2) * float(np.abs(c) @ ax) * _SAFE
    up = problem.objective.sense != "max"
    value = float(np.nextafter(v + e, np.inf)) if up else float(np.nextafter(v - e, -np.inf))
    return {"proven": True, "value": value, "reason": "point proved feasible with rigorous rounding"}


def enclosure(
    problem: Problem,
    duals: dict[str, Any] | None,
    x: np.ndarray | None,
    *,
    exact: bool = False,
    resolve: Callable[[Problem], dict[str, Any] | None] | None = None,
) -> dict[str, Any]:
    """The certified enclosure of the optimal value, in the problem's own sense.

    Parameters
    ----------
    problem : Problem
    duals : dict or None
        The solver's dual point (``Solution.duals``).
    x : numpy.ndarray or None
        A (certified) point: when :func:`primal_end` proves it feasible, its objective
        (rounded outwards) is the primal end (an upper bound of a minimum, a lower bound of a
        maximum).
    exact : bool
    resolve : callable, optional
        A solve of a perturbed problem on the caller's backend (:func:`dual_bound`).

    Returns
    -------
    dict
        ``sense``, ``kind`` (``"infimum"`` / ``"supremum"`` for problems with a strict
        constraint, whose optimum need not be attained, else ``"minimum"`` / ``"maximum"``),
        ``lower``, ``upper`` (``None`` at an end without proof), ``gap``, ``rel_gap`` (VSDP's
        ``(upper - lower) / max(1, (|upper| + |lower|) / 2)``),
        ``primal`` (``"certified point"`` or why not), ``dual`` (the :func:`dual_bound` record
        or why not), ``reason`` (one line).

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
    >>> p = Problem([Variable("t", "scalar", (1, 1))],
    ...             [LMI("t - 2 >= 0", 1, sp.csc_matrix([[-2.0, 1.0]]), strict=False)],
    ...             LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
    >>> e = enclosure(p, {"lmis": [np.eye(1)], "linear": []}, np.array([2.0 + 1e-9]))
    >>> e["kind"], 2.0 < e["upper"] < 2.0 + 2e-9, e["rel_gap"] < 1e-8
    ('minimum', True, True)
    """
    sense = problem.objective.sense
    strict = any(lmi.strict for lmi in problem.lmis) or any(problem.linear.strict)
    kind = ("infimum" if sense == "min" else "supremum") if strict else ("minimum" if sense == "min" else "maximum")
    out: dict[str, Any] = {"sense": sense, "kind": kind, "lower": None, "upper": None, "gap": None, "rel_gap": None}
    dual: dict[str, Any]
    if not duals or duals.get("lmis") is None:
        dual = {"proven": False, "reason": "the solver returned no dual point"}
    else:
        try:
            dual = dual_bound(problem, duals, exact=exact, resolve=resolve)
        except CertificateError as exc:
            dual = {"proven": False, "reason": str(exc)}
    out["dual"] = dual
    upper_value = None
    if x is None:
        out["primal"] = "no certified point"
    else:
        pe = primal_end(problem, x)
        upper_value = pe["value"] if pe["proven"] else None
        out["primal"] = "certified point" if pe["proven"] else "no rigorous primal end: " + pe["reason"]
    bound = None
    if dual.get("proven"):
        bound = dual["lower"] if sense == "min" else -dual["lower"]
    if sense == "min":
        out["lower"], out["upper"] = bound, upper_value
    else:
        out["lower"], out["upper"] = upper_value, bound
    lo, hi = out["lower"], out["upper"]
    if lo is not None and hi is not None:
        out["gap"] = hi - lo
        out["rel_gap"] = (hi - lo) / max(1.0, 0.5 * (abs(hi) + abs(lo))) if hi >= lo else 0.0
        if hi < lo:
            # both ends proven: cannot happen unless a proof is wrong; never hide it
            out["reason"] = f"inconsistent ends: lower {lo:.10g} > upper {hi:.10g}"
            out["consistent"] = False
            return out
        out["reason"] = f"{kind} in [{lo:.10g}, {hi:.10g}] (relative gap {out['rel_gap']:.2g})"
    elif lo is None and hi is None:
        out["reason"] = f"no certified bound: no certified point, and {dual.get('reason')}"
    else:
        missing = "dual bound" if dual.get("proven") is not True else "primal point"
        why = dual.get("reason") if missing == "dual bound" else "no certified point"
        side = "lower" if lo is None else "upper"
        out["reason"] = (
            f"{kind}: only the {'upper' if side == 'lower' else 'lower'} end is certified; "
            f"no certified {side} end ({why})"
        )
    out["consistent"] = True
    return out


def summary(record: dict[str, Any] | None) -> dict[str, Any] | None:
    """The enclosure without the dual point's matrices (for ``--json`` output).

    >>> summary({"lower": 1.0, "upper": 2.0, "dual": {"proven": True, "dual": {"lmis": []}}})
    {'lower': 1.0, 'upper': 2.0, 'dual': {'proven': True}}
    """
    if record is None:
        return None
    out = {k: v for k, v in record.items() if k != "restored_x"}
    if isinstance(out.get("dual"), dict):
        out["dual"] = {k: v for k, v in out["dual"].items() if k != "dual"}
    return out


def describe(record: dict[str, Any] | None) -> list[str]:
    """Human lines for an enclosure record (``lmic solve`` output).

    >>> describe({"kind": "minimum", "lower": 1.0, "upper": 1.5, "gap": 0.5, "rel_gap": 0.4,
    ...           "dual": {"proven": True, "method": "rigorous-float", "shift": 1e-12}})[0]
    'optimal value (minimum) in [1, 1.5]  gap 0.5 (relative 0.4)'
    """
    if not record:
        return []
    lo, hi = record.get("lower"), record.get("upper")
    dual = record.get("dual") or {}
    kind = record.get("kind", "optimum")
    if lo is not None and hi is not None:
        lines = [
            f"optimal value ({kind}) in [{lo:.10g}, {hi:.10g}]  "
            f"gap {record['gap']:.3g} (relative {record['rel_gap']:.3g})"
        ]
    else:
        lines = [f"optimal value ({kind}): " + record.get("reason", "no certified bound")]
    dual_end = "lower" if record.get("sense") != "max" else "upper"
    primal_end = "upper" if dual_end == "lower" else "lower"
    if dual.get("proven"):
        how = "exact rational arithmetic" if dual.get("method") == "exact" else "rigorous floating-point error bounds"
        lines.append(f"  {dual_end} end: dual point proved feasible ({how}; interior shift {dual.get('shift'):g})")
    else:
        lines.append(f"  {dual_end} end: no certified dual bound ({dual.get('reason', 'not attempted')})")
    lines.append(f"  {primal_end} end: {record.get('primal', 'no certified point')}")
    if kind in ("infimum", "supremum"):
        lines.append(f"  strict constraints: the optimum is an {kind}, which no feasible point need attain")
    return lines


def with_primal(record: dict[str, Any], value: float, label: str) -> dict[str, Any]:
    """The enclosure with a primal end from another certified point (e.g. the backed-off one).

    Used only when the record has no primal end: ``value`` must be the objective at a point
    the certifier certified against the same problem.

    >>> e = {"sense": "min", "kind": "minimum", "lower": 1.0, "upper": None, "dual": {"proven": True}}
    >>> with_primal(e, 1.5, "certified backed-off point")["gap"]
    0.5
    """
    out = dict(record)
    key = "upper" if out.get("sense") == "min" else "lower"
    if out.get(key) is not None:
        return out
    out[key] = float(value)
    out["primal"] = label
    lo, hi = out.get("lower"), out.get("upper")
    if lo is not None and hi is not None and hi >= lo:
        out["gap"] = hi - lo
        out["rel_gap"] = (hi - lo) / max(1.0, 0.5 * (abs(hi) + abs(lo)))
        out["reason"] = f"{out['kind']} in [{lo:.10g}, {hi:.10g}] (relative gap {out['rel_gap']:.2g}; {label})"
    elif lo is not None and hi is not None:
        out["reason"] = f"inconsistent ends: lower {lo:.10g} > upper {hi:.10g}"
        out["consistent"] = False
    else:
        out["reason"] = f"{out['kind']}: only the {key} end is certified ({label})"
    return out


def audit_enclosure(
    problem: Problem, record: dict[str, Any], certificate: Any, backoff: dict[str, Any] | None = None
) -> dict[str, Any]:
    """Re-verify both ends of a recorded enclosure (``lmic audit``).

    The primal end must be the objective the certifier recomputes at the recorded point, and
    only when that point is certified; the dual end must be re-proved from the recorded dual
    point (:func:`verify_dual_bound`). A primal end taken from the backed-off point
    (:func:`with_primal`) must be the objective at ``backoff["x"]``, re-certified here.
    Returns ``ok``, ``field`` (the first failing one) and ``message``.

    >>> import numpy as np, scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
    >>> p = Problem([Variable("t", "scalar", (1, 1))],
    ...             [LMI("t - 2 >= 0", 1, sp.csc_matrix([[-2.0, 1.0]]), strict=False)],
    ...             LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
    >>> e = enclosure(p, {"lmis": [np.eye(1)], "linear": []}, None)
    >>> audit_enclosure(p, e, None)["ok"], audit_enclosure(p, dict(e, lower=2.1), None)["ok"]
    (True, False)
    """
    sense = problem.objective.sense
    if record.get("sense") != sense:
        return {"ok": False, "field": "enclosure.sense", "message": "enclosure.sense differs from the IR's objective"}
    primal_key, dual_key = ("upper", "lower") if sense == "min" else ("lower", "upper")
    pv = record.get(primal_key)
    if pv is not None:
        if record.get("primal") == "certified backed-off point":
            xs = None if not backoff else backoff.get("x")
        elif record.get("primal") == "restored point":
            xs = record.get("restored_x")
        else:
            xs = getattr(certificate, "x", None)
        pe = primal_end(problem, np.asarray(xs, dtype=float)) if xs is not None else {"proven": False}
        if not pe["proven"] or float(pv) != pe["value"]:
            return {
                "ok": False,
                "field": f"enclosure.{primal_key}",
                "message": f"enclosure.{primal_key} {pv!r} is not the rigorous objective at the recorded point "
                f"({pe.get('value')!r}; {pe.get('reason', 'no point recorded')})",
            }
    dv = record.get(dual_key)
    dual = record.get("dual") or {}
    if dv is not None:
        if not dual.get("proven"):
            return {
                "ok": False,
                "field": f"enclosure.{dual_key}",
                "message": f"enclosure.{dual_key} has no proof recorded",
            }
        lower = -float(dv) if sense == "max" else float(dv)
        if float(dual.get("lower", math.nan)) != lower:
            return {
                "ok": False,
                "field": f"enclosure.{dual_key}",
                "message": f"enclosure.{dual_key} differs from the recorded dual bound",
            }
        v = verify_dual_bound(problem, dual)
        if not v["ok"]:
            return {"ok": False, "field": "enclosure.dual", "message": "enclosure.dual: " + v["reason"]}
    lo, hi = record.get("lower"), record.get("upper")
    if lo is not None and hi is not None:
        if float(lo) > float(hi):
            return {"ok": False, "field": "enclosure", "message": "enclosure: lower end above upper end"}
        if record.get("gap") is not None and float(record["gap"]) != float(hi) - float(lo):
            return {"ok": False, "field": "enclosure.gap", "message": "enclosure.gap differs from upper - lower"}
    return {"ok": True, "field": None, "message": "enclosure re-verified (both recorded ends)"}
