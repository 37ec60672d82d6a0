"""The face route of :mod:`lmic.certify.enclosure_face` for the discrete-time (Stein) form.

The discrete bounded-real lemma ``[[A'PA - P, A'PB, C'], [*, B'PB - g I, D'], [*, *, -g I]] <
0`` has the coefficient ``sigma (Abar^T P Abar - E^T P E)`` of ``P`` (``Abar = [A B 0]``,
``E`` selecting the state rows, ``sigma = -1`` for an LMI ``< 0`` stored negated). A factored
multiplier ``X = S S^T`` then has

    ``Abar X Abar^T - E X E^T = 0``  whenever  ``Abar S = (E S) U``, ``U U^T = I``,

so the multiplier of ``P > 0`` is ``W = 0``, as with the continuous form. ``U`` is ``+-1``
(rank 1, a peak at ``theta = 0`` or ``pi``) or the rotation by the peak angle (rank 2), and
``S_E`` solves ``A_E S_E - S_E U = -A_R S_R`` (unique when ``A_E`` is Schur stable).
:func:`lmic.certify.enclosure_face.prove_face` decides exactly; ``U`` must be orthogonal in
rational arithmetic: a rotation ``c = (1 - t^2) / (1 + t^2)``, ``s = 2 t / (1 + t^2)`` with
``t`` a rational near ``tan(theta / 2)`` (:func:`rational_rotation`). The structure is found
in floating point (each diagonal coefficient of ``P`` is rank one plus ``-sigma e_s e_s^T``)
and checked on the exact coefficients (:mod:`lmic.compile.exact`), where every entry of
``Abar`` is an exact square root of a rational (declined otherwise). Candidates ``(U, S_R)``:
the solver's multiplier (the polar factor of ``lstsq(E S_0, Abar S_0)`` gives the angle) and
a search over ``theta`` in ``[0, pi]`` (the best ``S_R`` of each ``U`` a generalised
eigenvector, :mod:`lmic.certify.enclosure_face_kyp`).

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
>>> from lmic.certify.enclosure_face import prove_face
>>> # 1 / (z - 1/2), norm 2 at theta = 0: min g s.t. p > 0, -[[p/4 - p, p/2, 1], [*, p - g, 0], [*, *, -g]] > 0
>>> F = sp.csc_matrix(np.array([[0, .75, 0], [0, -.5, 0], [-1, 0, 0], [0, -1, 1], [0, 0, 0], [0, 0, 1]]))
>>> p = Problem([Variable("p", "scalar", (1, 1)), Variable("g", "scalar", (1, 1), offset=1)],
...             [LMI("p > 0", 1, sp.csc_matrix([[0.0, 1.0, 0.0]])), LMI("dbrl", 3, F)],
...             LinearConstraints.empty(2), Objective("min", [0.0, 0.0, 1.0]))
>>> st = stein_structure(p)
>>> st["form"], st["sigma"], st["Abar"].tolist()
('stein', -1, [[0.5, 1.0, 0.0]])
>>> prove_face(p, st, [[1]], np.array([[1.0], [1.0]]))["lower_exact"]
'2'
"""

from __future__ import annotations

import math
from fractions import Fraction
from typing import Any

import numpy as np
import scipy.sparse as sp

from lmic.certify.enclosure_about import structure_on_exact
from lmic.certify.enclosure_face_kyp import _best, _forms, _golden, estimate
from lmic.certify.enclosure_repair import jacobian, pivot_blocks
from lmic.compile.exact import ExactProblem, from_ir
from lmic.ir.problem import Problem
from lmic.ir.svec import tril_index, tril_rows_cols, tril_unvec

__all__ = [
    "stein_structure",
    "stein_structure_for",
    "exact_orthogonal",
    "rational_rotation",
    "stein_pivot_g",
    "stein_candidates",
    "THETA_GRID",
    "MAX_DEN",
]

#: angles of the search grid on ``[0, pi]`` (the angles of ``A_E``'s eigenvalues are added)
THETA_GRID = 721
#: largest denominator of the rational ``t ~ tan(theta / 2)`` of a rotation
MAX_DEN = 2**40
#: local maxima of the grid refined by a bounded scalar search
REFINE = 3
#: relative difference of the float bounds under which a rank-1 candidate is ranked first
TIE = 1e-13


def _float_stein(problem: Problem) -> dict[str, Any] | None:
    """The Stein structure found in floating point (``Abar``, ``state``, ``sigma``, the
    reference column ``j0`` and sign of each row), up to rounding."""
    J, ranges = jacobian(problem)
    Jr = sp.csr_matrix(J)
    for pi, rows in pivot_blocks(problem, J, ranges).items():
        touched = [
            i for i, (a, b) in enumerate(ranges) if i != pi and a < b and sp.csr_matrix(Jr[rows][:, a:b]).nnz > 0
        ]
        if len(touched) != 1:
            continue
        xi = touched[0]
        npv, d = problem.lmis[pi].dim, problem.lmis[xi].dim
        Fx = problem.lmis[xi].coeffs.tocsc()
        ri, ci = tril_rows_cols(npv)

        def H(t: int, Fx: sp.csc_matrix = Fx, rows: np.ndarray = rows, d: int = d) -> np.ndarray:
            k = int(rows[t])
            v = np.zeros(Fx.shape[0])
            v[Fx.indices[Fx.indptr[k] : Fx.indptr[k + 1]]] = Fx.data[Fx.indptr[k] : Fx.indptr[k + 1]]
            return tril_unvec(v, d)

        tol = 1e-12 * max(float(np.max(np.abs(Fx.data), initial=0.0)), 1.0)
        Abar, state, j0s, sig = np.zeros((npv, d)), np.zeros(npv, dtype=int), np.zeros(npv, dtype=int), set()
        ok = True
        for t in np.flatnonzero(ri == ci).tolist():
            a, h = int(ri[t]), H(t)
            dg = np.diag(h)
            m = np.abs(np.outer(dg, dg) - h * h).sum(axis=1)  # row s: the rank-one part's defect
            found = False
            for s in np.flatnonzero(m >= (1 - 1e-9) * m.max()).tolist() if m.max() > 0 else []:
                j0 = int(np.argmax(np.where(np.arange(d) == s, 0.0, np.abs(dg))))
                if dg[j0] == 0:
                    continue
                sigma = 1 if dg[j0] > 0 else -1
                v = sigma * h[j0] / math.sqrt(abs(dg[j0]))
                E = np.zeros((d, d))
                E[s, s] = 1.0
                if np.all(np.abs(sigma * (np.outer(v, v) - E) - h) <= tol):
                    Abar[a], state[a], j0s[a], found = v, s, j0, True
                    sig.add(sigma)
                    break
            if not found:
                ok = False
                break
        if not ok or len(sig) != 1 or np.unique(state).size != npv:
            continue
        sigma = sig.pop()
        signs = np.ones(npv, dtype=int)
        for b in range(1, npv):  # each row's sign from P_0b's coefficient
            E = np.zeros((d, d))
            E[state[0], state[b]] += 1.0
            E[state[b], state[0]] += 1.0
            ab = np.outer(Abar[0], Abar[b])
            signs[b] = 1 if np.sum((H(int(tril_index(b, 0, npv))) + sigma * E) * sigma * (ab + ab.T)) >= 0 else -1
        Abar *= signs[:, None]
        for t in range(ri.size):  # every coefficient of P, to rounding
            a, b = int(ri[t]), int(ci[t])
            E = np.zeros((d, d))
            E[state[a], state[b]] += 1.0
            ab = np.outer(Abar[a], Abar[b])
            if a != b:
                E, ab = E + E.T, ab + ab.T
            if np.any(np.abs(sigma * (ab - E) - H(t)) > tol):
                ok = False
                break
        if ok:
            return {
                "form": "stein",
                "pivot": pi,
                "block": xi,
                "state": state,
                "Abar": Abar,
                "rows": rows,
                "sigma": sigma,
                "j0": j0s,
                "signs": signs,
            }
    return None


def _sqrt(f: Fraction) -> Fraction | None:
    """The exact square root of ``f >= 0``, else ``None``."""
    p, q = math.isqrt(f.numerator), math.isqrt(f.denominator)
    return Fraction(p, q) if f >= 0 and p * p == f.numerator and q * q == f.denominator else None


def _exact_stein(cand: dict[str, Any], ex: ExactProblem) -> dict[str, Any] | None:
    """``cand`` checked on the exact coefficients ``ex``: ``Abar`` exact (``AbarN / Abar_den``)
    and every pivot row's coefficients ``sigma (Abar^T E_ab Abar - E^T E_ab E)`` exactly."""
    pi, xi, state, rows, sigma = cand["pivot"], cand["block"], cand["state"], cand["rows"], cand["sigma"]
    Lp, Lx = ex.lmis[pi], ex.lmis[xi]
    npv, d = Lp.dim, Lx.dim
    if int(Lp.indptr[-1] - Lp.indptr[1]) != rows.size:  # the pivot block: one entry per column
        return None
    for t, k in enumerate(rows.tolist()):
        pr, pn = Lp.column(int(k))
        if pr.size != 1 or int(pr[0]) != t or pn[0] == 0:
            return None
        if any(int(L.indptr[k + 1]) > int(L.indptr[k]) for i, L in enumerate(ex.lmis) if i not in (pi, xi)):
            return None
    ri, ci = tril_rows_cols(npv)
    ti, tj = tril_rows_cols(d)

    def col(t: int) -> np.ndarray:
        r, v = Lx.column(int(rows[t]))
        out = np.zeros(ti.size, dtype=object)
        out[r.astype(int)] = [int(x) for x in v]
        return out

    Aq: list[list[Fraction]] = []
    for a in range(npv):  # row a from the rank-one part of P_aa's coefficient, column j0
        h, j0 = col(int(tril_index(a, a, npv))), int(cand["j0"][a])
        root = _sqrt(Fraction(sigma * int(h[int(tril_index(j0, j0, d))]), Lx.den))
        if root is None or root == 0:
            return None
        sgn = sigma * int(cand["signs"][a])
        Aq.append([sgn * Fraction(int(h[int(tril_index(max(j0, j), min(j0, j), d))]), Lx.den) / root for j in range(d)])
    den = 1
    for row_ in Aq:
        for f in row_:
            den = den * f.denominator // math.gcd(den, f.denominator)
    AN = np.array([[int(f * den) for f in row_] for row_ in Aq], dtype=object)
    d2 = den * den
    for t in range(ri.size):
        a, b = int(ri[t]), int(ci[t])
        pred = AN[a][ti] * AN[b][tj]
        if a != b:
            pred = pred + AN[b][ti] * AN[a][tj]
        sa, sb = int(state[a]), int(state[b])
        pred[int(tril_index(max(sa, sb), min(sa, sb), d))] -= d2  # the states are distinct
        if np.any(col(t) * d2 != pred * (sigma * Lx.den)):
            return None
    Abar = np.array([[int(v) / den for v in row_] for row_ in AN], dtype=float)
    return dict(cand, Abar=Abar, AbarN=AN, Abar_den=den, exact=ex)


def stein_structure(problem: Problem, exact: ExactProblem | None = None) -> dict[str, Any] | None:
    """The Stein structure of the module docstring checked exactly on ``exact`` (default: the
    IR's own floats), or ``None``: as :func:`lmic.certify.enclosure_face.lyapunov_structure`,
    with ``form`` ``"stein"`` and ``sigma`` (the sign of the coefficient of ``P``).

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("p", "scalar", (1, 1))], [LMI("p > 0", 1, sp.csc_matrix([[0.0, 1.0]]))],
    ...             LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
    >>> stein_structure(p) is None
    True
    """
    cand = _float_stein(problem)
    if cand is None:
        return None
    return _exact_stein(cand, exact if exact is not None else from_ir(problem))


def stein_structure_for(problem: Problem) -> tuple[dict[str, Any] | None, str]:
    """The Stein structure on the problem's exact compilation (:func:`exact_of`: the IR's own
    floats when it has no theorem): ``(structure or None, reason)``, ``problem`` ``"ir"`` or
    ``"exact"`` as :func:`lmic.certify.enclosure_face.structure_for`.

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("p", "scalar", (1, 1))], [LMI("p > 0", 1, sp.csc_matrix([[0.0, 1.0]]))],
    ...             LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
    >>> stein_structure_for(p)
    (None, 'no Lyapunov or Stein structure for the face route')
    """
    cand = _float_stein(problem)
    if cand is None:
        return None, "no Lyapunov or Stein structure for the face route"
    return structure_on_exact(problem, lambda ex: _exact_stein(cand, ex), "Stein")


def exact_orthogonal(U: Any) -> list[list[Fraction]] | None:
    """``U`` (rationals: ``Fraction``, ``int``, ``"p/q"`` strings or floats, read exactly) when
    it is square and ``U U^T = I`` exactly, else ``None``.

    >>> exact_orthogonal([["3/5", "-4/5"], ["4/5", "3/5"]]) is not None, exact_orthogonal([[0.6, -0.8], [0.8, 0.6]])
    (True, None)
    """
    try:
        rows = [list(r) for r in U]
        Q = [[v if isinstance(v, Fraction) else Fraction(v) for v in r] for r in rows]
    except (TypeError, ValueError, ZeroDivisionError, OverflowError):
        return None
    r = len(Q)
    if r < 1 or any(len(row_) != r for row_ in Q) or any(isinstance(v, bool) for row_ in rows for v in row_):
        return None
    for i in range(r):
        for j in range(r):
            if sum(Q[i][k] * Q[j][k] for k in range(r)) != (1 if i == j else 0):
                return None
    return Q


def rational_rotation(theta: float, max_den: int = MAX_DEN) -> list[list[Fraction]]:
    """The rotation ``[[c, -s], [s, c]]`` by about ``theta`` (in ``[0, pi]``), exactly orthogonal:
    ``c = (1 - t^2) / (1 + t^2)``, ``s = 2 t / (1 + t^2)``, ``t ~ tan(theta / 2)`` rational.

    >>> [[str(v) for v in r] for r in rational_rotation(math.pi / 2)]
    [['0', '-1'], ['1', '0']]
    """
    if theta >= math.pi * (1 - 1e-15):
        return [[Fraction(-1), Fraction(0)], [Fraction(0), Fraction(-1)]]
    t = Fraction(math.tan(theta / 2.0)).limit_denominator(max_den)
    c, s = (1 - t * t) / (1 + t * t), 2 * t / (1 + t * t)
    return [[c, -s], [s, c]]


def stein_pivot_g(structure: dict[str, Any], N: Any, D: int) -> Any:
    """``g`` of each pivot row (by tril entry of ``P``), exactly, for ``S = N / D`` (python-flint
    ``fmpz_mat``): ``sigma tr(E_ab (Abar X Abar^T - E X E^T))``, ``X = S S^T``.

    >>> import numpy as np, scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> F = sp.csc_matrix(np.array([[0, .75, 0], [0, -.5, 0], [-1, 0, 0], [0, -1, 1], [0, 0, 0], [0, 0, 1]]))
    >>> p = Problem([Variable("p", "scalar", (1, 1)), Variable("g", "scalar", (1, 1), offset=1)],
    ...             [LMI("p > 0", 1, sp.csc_matrix([[0.0, 1.0, 0.0]])), LMI("dbrl", 3, F)],
    ...             LinearConstraints.empty(2), Objective("min", [0.0, 0.0, 1.0]))  # 1 / (z - 1/2)
    >>> from lmic.certify.psd import load_flint
    >>> g = stein_pivot_g(stein_structure(p), load_flint().fmpz_mat([[2], [1], [1]]), 1)
    >>> g(0)  # Abar S = 2 / 2 + 1 = 2 = (E S) U with U = 1: on the face
    Fraction(0, 1)
    """
    from lmic.certify.psd import load_flint

    flint = load_flint()
    AN, Ad, sigma = structure["AbarN"], int(structure["Abar_den"]), int(structure["sigma"])
    state = [int(s) for s in structure["state"]]
    G = flint.fmpz_mat([[int(v) for v in row_] for row_ in AN]) * N
    NE = flint.fmpz_mat([[int(N[s, c]) for c in range(N.ncols())] for s in state])
    M = G * G.transpose() - (NE * NE.transpose()) * (Ad * Ad)
    pa, pb = tril_rows_cols(len(state))
    den = Ad * Ad * D * D

    def g(t: int) -> Fraction:
        a, b = int(pa[t]), int(pb[t])
        v = int(M[a, b])
        return Fraction(sigma * (2 if a != b else 1) * v, den) if v else Fraction(0)

    return g


def _dual_angles(structure: dict[str, Any], X0: np.ndarray) -> tuple[list[float], list[np.ndarray]]:
    """The solver's angle (rank 2: the polar factor of ``lstsq(E S_0, Abar S_0)``, a rotation)
    and its rank-1 ``S_R``."""
    state, Abar = structure["state"], structure["Abar"]
    rest = np.setdiff1d(np.arange(X0.shape[0]), state)
    w, V = np.linalg.eigh(0.5 * (X0 + X0.T))
    thetas, srs = [], []
    for r in (1, 2):
        if X0.shape[0] < r or not w[-r] > 0:
            break
        S0 = V[:, -r:] * np.sqrt(w[-r:])
        Ut = np.linalg.lstsq(S0[state], Abar @ S0, rcond=None)[0]
        W_, _, Zt = np.linalg.svd(Ut)
        U = W_ @ Zt
        if r == 1:
            srs.append(S0[rest])
        elif np.linalg.det(U) > 0:
            thetas.append(abs(math.atan2(U[1, 0], U[0, 0])))
    return thetas, srs


def stein_candidates(
    problem: Problem, structure: dict[str, Any], X0: np.ndarray | None = None
) -> list[tuple[float, list[list[Fraction]], np.ndarray]]:
    """``(float bound, U, S_R)`` (``U`` exactly orthogonal), best first: ``U = +-1`` and the
    best rotations of a search over ``theta`` in ``[0, pi]`` (a grid with the angles of
    ``A_E``'s eigenvalues and the solver's, refined by golden section), each with its best
    ``S_R``, plus the solver's own rank-1 point (``X0``, the main block's multiplier).

    >>> import numpy as np, scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> F = sp.csc_matrix(np.array([[0, .75, 0], [0, -.5, 0], [-1, 0, 0], [0, -1, 1], [0, 0, 0], [0, 0, 1]]))
    >>> p = Problem([Variable("p", "scalar", (1, 1)), Variable("g", "scalar", (1, 1), offset=1)],
    ...             [LMI("p > 0", 1, sp.csc_matrix([[0.0, 1.0, 0.0]])), LMI("dbrl", 3, F)],
    ...             LinearConstraints.empty(2), Objective("min", [0.0, 0.0, 1.0]))  # 1 / (z - 1/2)
    >>> best = stein_candidates(p, stein_structure(p))[0]
    >>> round(best[0], 12), best[1]  # the norm 2, at theta = 0
    (2.0, [[Fraction(1, 1)]])
    """
    forms = _forms(problem, structure)
    if forms is None:
        return []
    state = np.asarray(structure["state"])
    rest = np.setdiff1d(np.arange(problem.lmis[structure["block"]].dim), state)
    Abar = np.asarray(structure["Abar"], dtype=float)
    AE, AR = Abar[:, state], Abar[:, rest]
    out: list[tuple[float, list[list[Fraction]], np.ndarray]] = []

    def fl(U: list[list[Fraction]]) -> np.ndarray:
        return np.array([[float(v) for v in r] for r in U])

    for sgn in (1, -1):
        one = _best(AE, AR, state, rest, forms, np.array([[float(sgn)]]))
        if one is not None:
            out.append((one[0], [[Fraction(sgn)]], one[1]))
    thetas0, srs = _dual_angles(structure, X0) if X0 is not None else ([], [])
    for SR in srs:
        for sgn in (1, -1):
            out.append((estimate(problem, structure, np.array([[float(sgn)]]), SR), [[Fraction(sgn)]], SR))

    def neg(th: float) -> float:
        b = _best(AE, AR, state, rest, forms, fl(rational_rotation(th, 2**20)))
        return -b[0] if b is not None and np.isfinite(b[0]) else np.inf

    ev = np.abs(np.angle(np.linalg.eigvals(AE))) if AE.size else np.zeros(0)
    grid = np.unique(np.concatenate([np.linspace(0.0, math.pi, THETA_GRID), ev, thetas0]))
    vals = np.array([neg(th) for th in grid])
    peaks = [
        i
        for i in range(grid.size)
        if np.isfinite(vals[i]) and vals[i] <= vals[max(i - 1, 0)] and vals[i] <= vals[min(i + 1, grid.size - 1)]
    ]
    for i in sorted(peaks, key=lambda i: vals[i])[:REFINE]:
        lo, hi = float(grid[max(i - 1, 0)]), float(grid[min(i + 1, grid.size - 1)])
        th, v = float(grid[i]), float(vals[i])
        if hi > lo:
            tg, vg = _golden(neg, lo, hi)
            if vg < v:
                th = tg
        U = rational_rotation(th)
        b = _best(AE, AR, state, rest, forms, fl(U))
        if b is not None and np.isfinite(b[0]):
            out.append((b[0], U, b[1]))
    out = [c for c in out if np.isfinite(c[0])]
    # rank 1 first within TIE (a peak at 0 or pi: exactly there, with smaller numbers)
    out.sort(key=lambda c: -c[0] - (TIE * abs(c[0]) if len(c[1]) == 1 else 0.0))
    return out
