"""Rigorous floating-point bounds of the enclosure (step 4 of :mod:`lmic.certify.enclosure`).

* :func:`lambda_min_lower`: a rigorous lower bound of ``lambda_min`` of a float symmetric matrix
  from a Cholesky factorisation of a shifted copy (Higham, *Accuracy and Stability of Numerical
  Algorithms*, 2nd ed., Thm 10.3, with the constant doubled for blocked factorisations);
* :func:`prove_float`: a repaired dual point proved feasible with a-priori error bounds on the
  residual of the dual equalities, on the exact correction ``u* = u + J_S^T M^{-1} rho`` and on
  the dual objective (the derivation is in the docstring of :mod:`lmic.certify.enclosure`);
* :func:`primal_end`: a primal point proved feasible with rigorous rounding, its objective
  rounded outwards.

Examples
--------
>>> import numpy as np
>>> 0.99 < lambda_min_lower(np.array([[2.0, 1.0], [1.0, 2.0]])) <= 1.0
True
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import scipy.sparse as sp

from lmic.certify.enclosure_repair import _pack
from lmic.ir.problem import Problem
from lmic.ir.svec import tril_rows_cols, tril_unvec

__all__ = [
    "lambda_min_lower",
    "prove_float",
    "primal_end",
    "polish_primal",
    "POLISH_WEIGHTS",
    "gamma",
    "down",
    "UNIT",
    "SAFE",
]

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
        lb = _shifted_lower(A, est - max(f * abs(est), 4.0 * (d + 1) * (d + 1) * _U * norm), g)
        if lb == -math.inf:  # A - s I did not factorise
            continue
        best = max(best, lb)
        if lb > 0 or est <= 0:
            break
    if best <= 0 < est:
        # a margin below the floor 4 (d + 1)^2 u ||A|| of the shifts above (a point near a
        # singular optimum: 8e-9 on entries 4.5e4): shifts between 0 and the estimate, whose
        # Cholesky may still succeed; the error bound is the same, whatever the shift
        for f in (0.5, 0.8, 0.2, 0.95):
            best = max(best, _shifted_lower(A, est * f, g))
            if best > 0:
                break
    return best


def _shifted_lower(A: np.ndarray, s: float, g: float) -> float:
    """``s`` minus Higham's bound on the Cholesky of ``A - s I`` (rounded down): a rigorous
    lower bound of ``lambda_min(A)``; ``-inf`` when ``A - s I`` does not factorise."""
    B = A - s * np.eye(A.shape[0])
    try:
        R = np.linalg.cholesky(B)
    except np.linalg.LinAlgError:
        return -math.inf
    if not np.all(np.isfinite(R)):
        return -math.inf
    err = (g * float(np.sum(R * R)) + _U * float(np.max(np.abs(np.diag(B))))) * _SAFE
    return _down(s - err)


#: smallest positive subnormal: the absolute error a product may add by underflow
_ETA = 2.0**-1074


def residuals(J: sp.spmatrix, u: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``fl(q_k - (J u)_k)`` for every row, with a rigorous bound of its error.

    Every row is summed by :func:`math.fsum`, which returns the correctly rounded sum of its
    float terms: the terms ``q_k`` and ``-fl(J_kj u_j)`` carry one rounding each (``<= u
    |J_kj u_j| + eta``), the sum one more (``<= u |result|``). The bound is about ``m`` times
    tighter than the a-priori ``gamma_m`` bound of a plain dot product (Higham ch. 3), which
    lets a smaller interior shift be proved.

    >>> import scipy.sparse as sp
    >>> r, e = residuals(sp.csr_matrix([[1.0, 1.0]]), np.array([0.1, 0.2]), np.array([0.3]))
    >>> bool(abs(r[0]) <= 1e-16 and e[0] < 1e-16)
    True

    A row no nonzero multiplier touches (a variable the constraints do not involve) has the
    exact residual ``q_k`` and no error:

    >>> residuals(sp.csr_matrix([[0.0, 0.0], [0.0, 2.0]]), np.array([1.0, 0.0]), np.zeros(2))
    (array([0., 0.]), array([0., 0.]))
    """
    Jc = sp.csr_matrix(J)
    out = np.empty(Jc.shape[0])
    err = np.empty(Jc.shape[0])
    for k in range(Jc.shape[0]):
        a, b = Jc.indptr[k], Jc.indptr[k + 1]
        prods = Jc.data[a:b] * u[Jc.indices[a:b]]
        out[k] = math.fsum([float(q[k]), *(-prods).tolist()])
        terms = float(np.sum(np.abs(prods))) * (1.0 + _gamma(b - a + 1))
        # a product with a zero factor is exactly zero (no rounding, no underflow): a row no
        # nonzero multiplier touches has the exact residual q_k (a variable that appears in
        # no constraint, e.g. a part of a gain the projector V annihilates)
        nnz = int(np.count_nonzero((Jc.data[a:b] != 0) & (u[Jc.indices[a:b]] != 0)))
        err[k] = (_U * terms + _U * abs(out[k]) + (nnz + 1) * _ETA * (nnz > 0)) * _SAFE
    return out, err


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
    res, res_err = residuals(J, u, q)
    rho_bar = (np.abs(res[1:]) + res_err[1:]) * _SAFE
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
                # what a larger interior shift must cover (lmic.certify.enclosure_dual.needed_shift)
                "psd_deficit": float(math.sqrt(2.0) * dn - lb) if math.isfinite(lb) else math.inf,
            }
    off = ranges[-1][1] if ranges else 0
    gea = ge & active[off:]
    if np.any(gea) and not float(np.min(y[gea])) - dn * _SAFE >= 0:
        return {"proven": False, "reason": "a row multiplier is not proved nonnegative after the correction"}
    j0 = J[0].toarray().ravel()
    corr = float(np.linalg.norm(j0[active])) * dn * _SAFE
    # res[0] = fl(q_0 - g_0(u)) within res_err[0]
    lower = _down(_down(float(res[0])) - (float(res_err[0]) + corr) * _SAFE)
    return {
        "proven": True,
        "lower": lower,
        "residual_bound": rho_norm,
        "correction_bound": dn,
        "min_eig_lower": min(margins, default=math.inf),
        "reason": "dual point proved feasible with rigorous floating-point error bounds",
    }


def rounded_products(C: sp.csr_matrix, xx: np.ndarray) -> np.ndarray | None:
    """``C @ xx`` with every entry the exact value rounded to nearest (error ``<= u |f| + 2^-1074``),
    or ``None`` where the error-free products do not apply (overflow, underflow).

    Each product is split exactly, ``a b = p + e`` (Dekker's TwoProduct with Veltkamp's
    splitting; exact without overflow or underflow), and :func:`math.fsum` rounds the exact sum
    of the pieces once.

    >>> C = sp.csr_matrix(np.array([[1.0, 1e-16, -1.0]]))
    >>> rounded_products(C, np.ones(3)).tolist(), (C @ np.ones(3)).tolist()
    ([1e-16], [0.0])
    """
    C = C.tocsr()
    a = C.data.astype(float)
    b = np.asarray(xx, dtype=float)[C.indices]
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))):
        return None
    # Veltkamp's split and Dekker's product are exact when no piece over- or underflows: every
    # non-zero factor in [2^-400, 2^500] (the pieces' products are then above 2^-860)
    p = a * b
    for v in (a, b):
        m = np.abs(v[v != 0])
        if m.size and (float(m.max()) > 2.0**500 or float(m.min()) < 2.0**-400):
            return None

    def split(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        c = 134217729.0 * v  # 2^27 + 1
        h = c - (c - v)
        return h, v - h

    ah, al = split(a)
    bh, bl = split(b)
    e = al * bl - (((p - ah * bh) - al * bh) - ah * bl)
    out = np.empty(C.shape[0])
    for r in range(C.shape[0]):
        lo, hi = C.indptr[r], C.indptr[r + 1]
        out[r] = math.fsum(np.concatenate([p[lo:hi], e[lo:hi]]).tolist())
    return out


#: the largest LMI :func:`exact_lmi` evaluates in rationals
EXACT_LMI_MAX_DIM = 200
#: ... with at most this many coefficients (rational products: about a second at the limit)
EXACT_LMI_MAX_TERMS = 400_000


def exact_lmi(C: sp.csr_matrix, xx: np.ndarray, dim: int, shift: float = 0.0) -> bool:
    """Whether ``F(x) - shift I`` is proved positive definite in exact arithmetic.

    ``F(x)`` (storage ``C``, ``xx = (1, x)``) is evaluated exactly (the floats are dyadic
    rationals) and :func:`lmic.certify.psd.prove_pd` decides, without floating-point doubt:
    the last resort of :func:`primal_end` for a margin below the floating-point bounds (a
    point near a singular optimum). Only tried where the float estimate of ``lambda_min`` is
    above ``shift`` and ``dim <= EXACT_LMI_MAX_DIM``.

    >>> C = sp.csr_matrix(np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 1e-10]]))
    >>> exact_lmi(C, np.array([1.0, 1.0]), 2), exact_lmi(C, np.array([1.0, -1.0]), 2)
    (True, False)
    """
    from fractions import Fraction

    from lmic.certify.psd import prove_pd

    C = C.tocsr()
    if dim > EXACT_LMI_MAX_DIM or C.nnz > EXACT_LMI_MAX_TERMS or not np.all(np.isfinite(xx)):
        return False
    f = np.asarray(C @ xx).ravel()
    if float(np.linalg.eigvalsh(tril_unvec(f, dim))[0]) <= shift:
        return False
    xq = [Fraction(float(v)) for v in xx]
    vals = []
    for r in range(C.shape[0]):
        lo, hi = C.indptr[r], C.indptr[r + 1]
        vals.append(
            sum((Fraction(float(v)) * xq[k] for k, v in zip(C.indices[lo:hi], C.data[lo:hi], strict=True)), Fraction(0))
        )
    i, j = tril_rows_cols(dim)
    t = Fraction(float(shift))
    for p in np.flatnonzero(i == j).tolist():
        vals[p] -= t
    den = max((v.denominator for v in vals), default=1)  # powers of two: the largest is a multiple of all
    M = [[0] * dim for _ in range(dim)]
    for r, v in enumerate(vals):
        a, b = int(i[r]), int(j[r])
        M[a][b] = M[b][a] = int(v * den)
    return bool(prove_pd(M)["proven"])


def primal_end(problem: Problem, x: np.ndarray) -> dict[str, Any]:
    """Prove ``x`` feasible with rigorous rounding, and bound its objective outwards.

    Every ``F_i(x)`` is evaluated in floating point with the entrywise error bound
    ``gamma_{k+1} (|F_i^(0)| + sum_k |x_k| |F_i^(k)|)`` (``k`` terms); ``lambda_min(F_i(x)) >=
    lambda_min_lower(fl(F_i(x))) - ||E_i||_F`` must be ``>= 0`` (``> 0`` when strict). Rows
    ``ge`` likewise; ``eq`` rows are evaluated exactly (rationals) and must vanish. The
    certifier's tolerances play no part: a point it certifies with a non-strict constraint
    violated by round-off gives no primal end here. Once the problem has an exact counterpart
    (:func:`lmic.compile.exact.exact_of`, the face route's), every margin must also cover the
    rigorous bound of ``|G_exact(x) - G(x)|`` (:meth:`~lmic.compile.exact.ExactProblem.perturbation`)
    and the objective's bound covers ``|c_exact . x - c . x|``: the point is proved for both.

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
    # once the problem has an exact counterpart (lmic.compile.exact, built by the face route),
    # the point is proved for it too: every margin must also cover |G_exact(x) - G(x)|
    from lmic.compile.exact import cached_exact

    ex = cached_exact(problem)
    pl, pr, po = ex.perturbation(problem, x) if ex is not None and ex.about == "theorem" else ([], [], 0.0)
    for i_lmi, lmi in enumerate(problem.lmis):
        C = lmi.coeffs.tocsr()
        f = np.asarray(C @ xx).ravel()
        k = int(np.max(np.diff(C.indptr), initial=0))
        err = _gamma(k + 2) * np.asarray(abs(C) @ ax).ravel() * _SAFE
        F = tril_unvec(f, lmi.dim)
        E = tril_unvec(err, lmi.dim)
        lb = lambda_min_lower(0.5 * (F + F.T)) - float(np.linalg.norm(E)) * _SAFE
        if not lb > 0:  # the evaluation's a priori bound may be what fails: evaluate exactly rounded
            fe = rounded_products(C, xx)
            if fe is not None:
                Ee = tril_unvec(_U * np.abs(fe) + _ETA, lmi.dim)
                lb = max(lb, _down(lambda_min_lower(tril_unvec(fe, lmi.dim)) - float(np.linalg.norm(Ee)) * _SAFE))
        if pl:  # the exact counterpart's difference, subtracted rounding down
            lb = _down(_down(lb) - pl[i_lmi])
        if not (lb > 0 if lmi.strict else lb >= 0) and exact_lmi(C, xx, lmi.dim, pl[i_lmi] if pl else 0.0):
            lb = 0.0 if not lmi.strict else math.ulp(0.0)  # proved exactly: F(x) - pl I > 0
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
                ok = exact == 0 and not (pr and pr[i] > 0)
            else:
                m = _down(_down(r[i] - err[i]) - pr[i]) if pr else r[i] - err[i]
                ok = (m > 0) if strict else (m >= 0)
            if not ok:
                return {
                    "proven": False,
                    "value": None,
                    "reason": f"row '{lin.names[i]}' is not proved at the point with rigorous rounding",
                }
    c = problem.objective.c
    v = float(c @ xx)
    e = _gamma(problem.n + 2) * float(np.abs(c) @ ax) * _SAFE + po * _SAFE
    up = problem.objective.sense != "max"
    value = float(np.nextafter(v + e, np.inf)) if up else float(np.nextafter(v - e, -np.inf))
    about = "exact" if pl else "ir"  # the problems the point is proved for: the IR (and its exact counterpart)
    return {"proven": True, "value": value, "reason": "point proved feasible with rigorous rounding", "problem": about}


#: public names of the helpers (used by the other enclosure modules)
UNIT = _U
SAFE = _SAFE
gamma = _gamma
down = _down
prove_float = _prove_float


#: weights of the inner point tried by :func:`polish_primal`, smallest first
POLISH_WEIGHTS = tuple(float(f"{m}e{e}") for e in range(-9, 0) for m in (1, 3)) + (0.5, 0.7, 0.9, 1.0)


def polish_primal(problem: Problem, inner: np.ndarray, outer: np.ndarray) -> dict[str, Any]:
    """The best provable point on the segment from ``outer`` (near the optimum, possibly just
    outside) to ``inner`` (a point :func:`primal_end` proves), and its rigorous objective.

    ``x(theta) = outer + theta (inner - outer)`` for ``theta`` in :data:`POLISH_WEIGHTS`,
    smallest first: the first point :func:`primal_end` proves is returned (``theta = 1`` is
    ``inner`` itself). Nothing is trusted: every candidate is proved as it stands.

    Returns
    -------
    dict
        ``proven``, ``x`` (list), ``value`` (rigorous objective), ``theta``, ``reason``.

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("t", "scalar", (1, 1))],
    ...             [LMI("t - 2 > 0", 1, sp.csc_matrix([[-2.0, 1.0]]), strict=True)],
    ...             LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
    >>> r = polish_primal(p, np.array([3.0]), np.array([2.0]))
    >>> r["proven"], 2.0 < r["value"] < 2.0 + 1e-8
    (True, True)
    """
    inner = np.asarray(inner, dtype=float).ravel()
    outer = np.asarray(outer, dtype=float).ravel()
    if inner.shape != outer.shape or not np.all(np.isfinite(outer)):
        return {"proven": False, "x": None, "value": None, "reason": "no finite outer point of the right length"}
    for theta in POLISH_WEIGHTS:
        x = outer + theta * (inner - outer) if theta < 1.0 else inner
        pe = primal_end(problem, x)
        if pe["proven"]:
            return {"proven": True, "x": x.tolist(), "value": pe["value"], "theta": theta, "reason": pe["reason"]}
    return {"proven": False, "x": None, "value": None, "reason": "no point of the segment is proved feasible"}
