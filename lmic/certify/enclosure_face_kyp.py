"""Face points computed from the problem, not read off the solver: the best ``(K, S_R)`` of
:mod:`lmic.certify.enclosure_face` by a frequency search (KYP).

On the face ``W = 0`` the dual point is fixed by ``K`` and ``S_R`` (module docstring of
:mod:`lmic.certify.enclosure_face`): ``S_E`` solves ``A_E S_E - S_E K = -A_R S_R``, linear in
``S_R``, so every dual equality row and the dual objective are quadratic forms in ``s =
vec(S_R)``: ``g_k(X) = s^T Q_k s``. With ``t = g_k(X) / q_k`` (``k`` the normalising row) the
bound is ``L = q_0 - q_k (s^T Q_0 s) / (s^T Q_k s)``: for a fixed ``K`` its best ``S_R`` is a
generalised symmetric eigenvector (the smallest eigenvalue of ``(q_k Q_0, Q_k)``). ``K`` is
``0`` (rank 1, a peak at zero frequency) or the rotation ``[[0, -w], [w, 0]]`` (rank 2),
``w`` searched on a logarithmic grid and refined by a bounded scalar search; the solver's own
``w`` (when it gave one) is a starting point, never needed. The search is in floating point:
the exact proof (:func:`lmic.certify.enclosure_face.prove_face`) decides, so a poor or
inaccurate solver dual (an ``AlmostSolved`` or ``NumericalError`` stop) still gives a tight
bound.

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
>>> from lmic.certify.enclosure_face import lyapunov_structure, prove_face
>>> F = sp.csc_matrix(np.array([[0, 4, 0], [0, -1, 0], [-3, 0, 0], [0, 0, 1], [0, 0, 0], [0, 0, 1]], float))
>>> p = Problem([Variable("p", "scalar", (1, 1)), Variable("t", "scalar", (1, 1), offset=1)],
...             [LMI("p > 0", 1, sp.csc_matrix([[0.0, 1.0, 0.0]])), LMI("brl", 3, F)],
...             LinearConstraints.empty(2), Objective("min", [0.0, 0.0, 1.0]))
>>> st = lyapunov_structure(p)  # 3 / (s + 2): norm 3/2 at zero frequency
>>> best = kyp_candidates(p, st)[0]
>>> round(best[0], 12), prove_face(p, st, best[1], best[2])["proven"]
(1.5, True)
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.linalg as sla

from lmic.ir.problem import Problem
from lmic.ir.svec import tril_unvec

__all__ = ["kyp_candidates", "estimate", "GRID", "REFINE"]

#: frequencies of the grid, relative to ``||A_E||_2`` (40 a decade: a lightly damped peak is
#: found near its grid point, then refined)
GRID = np.logspace(-5, 1, 241)
#: local maxima of the grid refined by a bounded scalar search
REFINE = 3


def _forms(problem: Problem, structure: dict[str, Any]) -> tuple[np.ndarray, np.ndarray, float, float] | None:
    """``F_0``, ``F_k`` (dense, the main block's constant and normalising columns), ``q_0`` and
    ``q_k``; ``None`` when no row normalises."""
    xi = structure["block"]
    sgn = -1.0 if problem.objective.sense == "max" else 1.0
    q = sgn * np.asarray(problem.objective.c, dtype=float)
    prow = {int(k) for k in structure["rows"]}
    C = problem.lmis[xi].coeffs.tocsc()
    d = problem.lmis[xi].dim
    ks = [k for k in range(1, 1 + problem.n) if k not in prow and q[k] != 0]
    if len(ks) != 1:
        return None
    k = ks[0]

    def dense(j: int) -> np.ndarray:
        v = np.zeros(C.shape[0])
        v[C.indices[C.indptr[j] : C.indptr[j + 1]]] = C.data[C.indptr[j] : C.indptr[j + 1]]
        return tril_unvec(v, d)

    return dense(0), dense(k), float(q[0]), float(q[k])


def _state_rows(AE: np.ndarray, AR: np.ndarray, K: np.ndarray) -> np.ndarray | None:
    """``S_E`` of each unit ``S_R = E_(i, c)`` (columns ``c m + i``), stacked per column ``c``."""
    n, m, r = AE.shape[0], AR.shape[1], K.shape[0]
    op = np.kron(np.eye(r), AE) - np.kron(K.T, np.eye(n))
    rhs = np.zeros((n * r, m * r))
    for c in range(r):  # unit S_R = E_(i, c): -A_R S_R has column c = -A_R[:, i]
        rhs[c * n : (c + 1) * n, c * m : (c + 1) * m] = -AR
    try:
        return np.linalg.solve(op, rhs)
    except np.linalg.LinAlgError:
        return None


def _quadratic(
    AE: np.ndarray, AR: np.ndarray, state: np.ndarray, rest: np.ndarray, forms: Any, K: np.ndarray
) -> tuple[np.ndarray, np.ndarray] | None:
    """``Q_0``, ``Q_k`` (``g(X) = s^T Q s``, ``s = vec(S_R)`` column-major)."""
    F0, Fk = forms[0], forms[1]
    n, m, r = AE.shape[0], AR.shape[1], K.shape[0]
    sol = _state_rows(AE, AR, K)
    if sol is None:
        return None
    Q0, Qk = np.zeros((m * r, m * r)), np.zeros((m * r, m * r))
    for c in range(r):
        Sc = np.zeros((m * r, n + m))  # row j: column c of S for the unit S_R number j
        Sc[:, state] = sol[c * n : (c + 1) * n, :].T
        Sc[c * m + np.arange(m), rest] = 1.0
        Q0 += Sc @ F0 @ Sc.T
        Qk += Sc @ Fk @ Sc.T
    return 0.5 * (Q0 + Q0.T), 0.5 * (Qk + Qk.T)


def _best(
    AE: np.ndarray, AR: np.ndarray, state: np.ndarray, rest: np.ndarray, forms: Any, K: np.ndarray
) -> tuple[float, np.ndarray] | None:
    """The best bound and ``S_R`` for this ``K`` (module docstring)."""
    Q = _quadratic(AE, AR, state, rest, forms, K)
    if Q is None:
        return None
    q0, qk = forms[2], forms[3]
    try:
        w, V = sla.eigh(qk * Q[0], Q[1])
    except (np.linalg.LinAlgError, ValueError):
        return None
    if w.size == 0 or not np.isfinite(w[0]):  # no S_R entry to choose (an equality row took them all)
        return None
    s = V[:, 0] / max(float(np.max(np.abs(V[:, 0]))), 1e-300)
    return q0 - float(w[0]), s.reshape(K.shape[0], AR.shape[1]).T


def estimate(problem: Problem, structure: dict[str, Any], K: np.ndarray, S_rest: np.ndarray) -> float:
    """The float value of the bound of the face point ``(K, S_R)`` (``-inf`` when it has none)."""
    forms = _forms(problem, structure)
    state = np.asarray(structure["state"])
    rest = np.setdiff1d(np.arange(problem.lmis[structure["block"]].dim), state)
    Abar = np.asarray(structure["Abar"], dtype=float)
    Q = None if forms is None else _quadratic(Abar[:, state], Abar[:, rest], state, rest, forms, K)
    if Q is None or forms is None:
        return -np.inf
    s = np.asarray(S_rest, dtype=float).T.ravel()
    den = float(s @ Q[1] @ s)
    return forms[2] - forms[3] * float(s @ Q[0] @ s) / den if den > 0 else -np.inf


def _golden(f: Any, lo: float, hi: float, rtol: float = 1e-13) -> tuple[float, float]:
    """A minimum of ``f`` on ``[lo, hi]`` by golden-section search (``f`` unimodal there; no
    scipy.optimize: its import costs a second)."""
    g = (np.sqrt(5.0) - 1.0) / 2.0
    a, b = lo, hi
    c, d = b - g * (b - a), a + g * (b - a)
    fc, fd = f(c), f(d)
    for _ in range(200):
        if b - a <= rtol * max(abs(b), 1e-300):
            break
        if fc < fd:
            b, d, fd = d, c, fc
            c = b - g * (b - a)
            fc = f(c)
        else:
            a, c, fc = c, d, fd
            d = a + g * (b - a)
            fd = f(d)
    return (c, fc) if fc < fd else (d, fd)


def kyp_candidates(
    problem: Problem, structure: dict[str, Any], omega0: float | None = None, *, grid: bool = True
) -> list[tuple[float, np.ndarray, np.ndarray]]:
    """``(float bound, K, S_R)`` for ``K = 0`` and the best rotation found, best first (empty when
    the problem has no single normalising row); ``omega0``: a frequency to start from (with
    ``grid=False`` only its neighbourhood, ``omega0 (1 +- 1/4)``, is searched)."""
    forms = _forms(problem, structure)
    if forms is None:
        return []
    state = np.asarray(structure["state"])
    d = problem.lmis[structure["block"]].dim
    rest = np.setdiff1d(np.arange(d), state)
    Abar = np.asarray(structure["Abar"], dtype=float)
    AE, AR = Abar[:, state], Abar[:, rest]
    out = []
    one = _best(AE, AR, state, rest, forms, np.zeros((1, 1)))
    if one is not None:
        out.append((one[0], np.zeros((1, 1)), one[1]))

    def rot(w: float) -> np.ndarray:
        return np.array([[0.0, -w], [w, 0.0]])

    def neg(w: float) -> float:
        b = _best(AE, AR, state, rest, forms, rot(w))
        return -b[0] if b is not None and np.isfinite(b[0]) else np.inf

    scale = float(np.linalg.norm(AE, 2)) or 1.0
    if grid:
        grid_w = np.sort(np.concatenate([GRID * scale, [abs(omega0)] if omega0 else []]))
    elif omega0:
        grid_w = abs(omega0) * np.array([0.8, 1.0, 1.25])
    else:
        grid_w = np.zeros(0)
    vals = np.array([neg(w) for w in grid_w])
    # refine around the best local maxima of the grid (and the solver's frequency)
    peaks = [
        i
        for i in range(grid_w.size)
        if np.isfinite(vals[i]) and vals[i] <= vals[max(i - 1, 0)] and vals[i] <= vals[min(i + 1, grid_w.size - 1)]
    ]
    peaks = sorted(peaks, key=lambda i: vals[i])[:REFINE]
    best_w, best_v = None, np.inf
    for i in peaks:
        lo, hi = grid_w[max(i - 1, 0)], grid_w[min(i + 1, grid_w.size - 1)]
        w, v = float(grid_w[i]), float(vals[i])
        if hi > lo:
            wg, vg = _golden(neg, float(lo), float(hi))
            if vg < v:
                w, v = wg, vg
        if v < best_v:
            best_w, best_v = w, v
    if best_w is not None:
        b = _best(AE, AR, state, rest, forms, rot(best_w))
        if b is not None:
            out.append((b[0], rot(best_w), b[1]))
    out.sort(key=lambda c: -c[0])
    return out
