"""The dual end proved exactly on the optimal face, for Lyapunov-type LMIs whose dual interior is
thinner than the floating-point resolution.

Why
---
The bounded-real lemma is the standard case. Its dual equalities for ``P`` read ``W = A X11 +
X11 A^T + B X21 + X12 B^T`` (``W``: the multiplier of ``P > 0``, ``X``: the main LMI's), so with
``W >= 0`` and ``A`` Hurwitz ``X11 <= gram(B X21 + X12 B^T)``, a Gramian driven by a term of
rank ``<= 2m`` whose eigenvalues decay geometrically: *every* dual feasible point has
``lambda_min(X11) / lambda_max(X11)`` about ``1e-11`` at 20 states and below ``1e-16`` at 40,
and ``W``'s eigenvalues are as small (``lambda_min(W) <= 2 ||A|| lambda_min(gram(...))``). No
dual point can be proved in floating point: ``W`` is the difference of terms of size
``||A|| ||X||`` that cancel to below the rounding of their evaluation.

What is proved instead
----------------------
The dual point is built on the face ``W = 0`` *exactly*, in rational arithmetic. When the
main LMI's coefficient of ``P`` has the Lyapunov (KYP) form ``E^T P Abar + Abar^T P E``
(``E`` selects the state rows, ``Abar = [A B ...]``; checked on the IR's coefficients,
:func:`lyapunov_structure`), a factored multiplier ``X = S S^T`` has

    ``sym(Abar X E^T) = sym((Abar S)(E S)^T) = 0``  whenever  ``Abar S = (E S) K``, ``K = -K^T``,

so ``W = 0``. Given ``K`` (``r x r`` skew; for the bounded-real lemma the rotation of the
worst frequency, ``r = 2``, or ``K = 0``, ``r = 1``, when the peak is at zero frequency) and the
non-state rows ``S_R`` of ``S``, the state rows ``S_E`` solve the Sylvester equation ``A_E S_E
- S_E K = -A_R S_R`` (``A_E``: ``Abar``'s state columns, Hurwitz in the bounded-real lemma, so
the solution is unique): an ``(n r) x (n r)`` rational solve (python-flint). ``X = S S^T / t``
(``t > 0`` so that the one remaining equality row, ``tr X22 + tr X33 = 1``, holds) is PSD by
construction, every other multiplier is zero, and the proof (:func:`prove_face`) checks every
dual equality *exactly*: the pivot block ``W`` is computed from its rows and must be PSD
(here: exactly zero), every other row must hold. The bound ``L = q_0 - g_0(u)`` is exact
(reported rounded down). Candidates ``(K, S_R)`` come from the solver's multiplier (its
rank-``r`` part: ``S_0 = V_r Lambda_r^(1/2)``, ``K`` the skew part of ``lstsq(E S_0, Abar
S_0)``) and from a frequency search that needs no dual point
(:mod:`lmic.certify.enclosure_face_kyp`: the best ``S_R`` for a given ``K`` is a generalised
eigenvector); they are ranked by their float bound and only the best are proved. Every
candidate is only a candidate: the exact checks decide. The coefficients checked are the
IR's own when they have the structure exactly, else the theorem's exact compilation
(:mod:`lmic.compile.exact`, :func:`structure_for`; the bound is then about that problem).

The discrete-time (Stein) form ``sigma (Abar^T P Abar - E^T P E)`` is the same with ``U``
exactly orthogonal in place of ``K`` (``Abar S = (E S) U``: :mod:`lmic.certify.enclosure_face_stein`).

The record (``dual`` of the result, ``form`` ``"face"``) holds ``K`` (or ``U`` as rationals,
``structure`` ``"stein"``), ``S_R``, the block and the pivot block; :func:`verify_face`
re-runs the exact proof from it alone.

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
>>> # the H-infinity norm of 1/(s + 1) (= 1): min t s.t. p > 0, [[2p, -p, -1], [-p, t, 0], [-1, 0, t]] > 0
>>> F = sp.csc_matrix(np.array([[0, 2, 0], [0, -1, 0], [-1, 0, 0], [0, 0, 1], [0, 0, 0], [0, 0, 1]], float))
>>> p = Problem([Variable("p", "scalar", (1, 1)), Variable("t", "scalar", (1, 1), offset=1)],
...             [LMI("p > 0", 1, sp.csc_matrix([[0.0, 1.0, 0.0]])), LMI("brl", 3, F)],
...             LinearConstraints.empty(2), Objective("min", [0.0, 0.0, 1.0]))
>>> st = lyapunov_structure(p)
>>> st["Abar"].tolist(), st["state"].tolist()
([[1.0, -1.0, 0.0]], [0])
>>> r = prove_face(p, st, np.zeros((1, 1)), np.array([[1.0], [1.0]]))  # w = 1, z = 1: |G(0)| = 1
>>> r["proven"], r["lower_exact"]
(True, '1')
"""

from __future__ import annotations

import math
from fractions import Fraction
from typing import Any

import numpy as np
import scipy.sparse as sp

from lmic.certify.enclosure_about import structure_on_exact
from lmic.certify.enclosure_float import down
from lmic.certify.enclosure_repair import jacobian, pivot_blocks
from lmic.compile.exact import ExactProblem, ExactUnavailable, exact_of, from_ir
from lmic.errors import CertificateError
from lmic.ir.problem import Problem
from lmic.ir.svec import tril_index, tril_rows_cols, tril_unvec

__all__ = [
    "MAX_RANK",
    "pivot_blocks",
    "lyapunov_structure",
    "structure_for",
    "face_bound",
    "prove_face",
    "verify_face",
]

#: largest rank ``r`` of the factored multiplier tried
MAX_RANK = 4
#: the frequency grid is searched when the best candidate's float bound is below the solver's
#: dual objective by more than this (relative)
GRID_SLACK = 1e-6


def _target(problem: Problem) -> np.ndarray:
    s = -1.0 if problem.objective.sense == "max" else 1.0
    return s * np.asarray(problem.objective.c, dtype=float)


def _float_structure(problem: Problem) -> dict[str, Any] | None:
    """The structure of :func:`lyapunov_structure` found in floating point, up to rounding
    (``exact_ir``: whether the IR's own coefficients have it exactly)."""
    J, ranges = jacobian(problem)
    pivots = pivot_blocks(problem, J, ranges)
    Jr = sp.csr_matrix(J)
    for pi, rows in pivots.items():
        touched = [
            i for i, (a, b) in enumerate(ranges) if i != pi and a < b and sp.csr_matrix(Jr[rows][:, a:b]).nnz > 0
        ]
        if len(touched) != 1:
            continue
        xi = touched[0]
        npv, d = problem.lmis[pi].dim, problem.lmis[xi].dim
        Fx = problem.lmis[xi].coeffs.tocsc()
        ri, ci = tril_rows_cols(npv)
        if np.any(sp.csr_matrix(Jr[rows][:, ranges[pi][0] : ranges[pi][1]]).diagonal() == 0):
            continue

        def H(t: int, Fx: sp.csc_matrix = Fx, rows: np.ndarray = rows, d: int = d) -> np.ndarray:
            k = int(rows[t])
            v = np.zeros(Fx.shape[0])
            v[Fx.indices[Fx.indptr[k] : Fx.indptr[k + 1]]] = Fx.data[Fx.indptr[k] : Fx.indptr[k + 1]]
            return tril_unvec(v, d)

        Abar = np.zeros((npv, d))
        state = np.zeros(npv, dtype=int)
        for t in range(ri.size):
            if ri[t] == ci[t]:
                h = H(t)
                r = int(np.argmax((h != 0).sum(axis=1)))
                state[ri[t]] = r
                Abar[ri[t]] = h[r]
                Abar[ri[t], r] = h[r, r] / 2.0
        if np.unique(state).size != npv:
            continue
        ok, exact_ir = True, True
        scale = float(np.max(np.abs(Abar), initial=0.0)) or 1.0
        for t in range(ri.size):
            a, b = ri[t], ci[t]
            G = np.zeros((d, d))
            G[state[a]] += Abar[b]
            if a != b:
                G[state[b]] += Abar[a]
            Gs = G + G.T
            Ht = H(t)
            if np.any(np.abs(Gs - Ht) > 1e-12 * scale):
                ok = False
                break
            if exact_ir:
                # a coefficient that is the rounded sum of two entries of Abar (A_aa + A_bb) is
                # not exact in floating point: the IR's own face W = 0 is then not this one
                both = np.argwhere((G != 0) & (G.T != 0))
                exact_ir = bool(np.all(Gs == Ht)) and all(
                    Fraction(float(Gs[i, j])) == Fraction(float(G[i, j])) + Fraction(float(G[j, i])) for i, j in both
                )
        if ok:
            return {"pivot": pi, "block": xi, "state": state, "Abar": Abar, "rows": rows, "exact_ir": exact_ir}
    return None


def _exact_structure(problem: Problem, cand: dict[str, Any], ex: ExactProblem) -> dict[str, Any] | None:
    """``cand`` (:func:`_float_structure`) checked on the exact coefficients ``ex``: every pivot
    row's coefficients are those of ``E^T P Abar + Abar^T P E`` exactly, ``Abar`` exact
    (``AbarN / Abar_den``, python ints)."""
    pi, xi, state, rows = cand["pivot"], cand["block"], cand["state"], cand["rows"]
    Lp, Lx = ex.lmis[pi], ex.lmis[xi]
    npv, d = Lp.dim, Lx.dim
    ri, ci = tril_rows_cols(npv)
    if int(Lp.indptr[-1] - Lp.indptr[1]) != rows.size:  # no entry outside the pivot rows (but q_0's)
        return None
    for t, k in enumerate(rows.tolist()):  # the pivot block: one entry per column, in its own row
        pr, pn = Lp.column(int(k))
        if pr.size != 1 or int(pr[0]) != t or pn[0] == 0:
            return None
        if any(int(L.indptr[k + 1]) > int(L.indptr[k]) for i, L in enumerate(ex.lmis) if i not in (pi, xi)):
            return None

    def col(t: int) -> dict[int, int]:
        r, v = Lx.column(int(rows[t]))
        return {int(a): 2 * int(b) for a, b in zip(r.tolist(), v.tolist(), strict=True)}

    ii, jj = np.meshgrid(np.arange(d), np.arange(d), indexing="ij")
    slots = tril_index(np.maximum(ii, jj), np.minimum(ii, jj), d).tolist()  # slots[i][j]: (i, j)'s tril row

    def slot(i: int, j: int) -> int:
        return slots[i][j]

    AN = np.zeros((npv, d), dtype=object)  # Abar = AN / (2 den)
    for t in range(ri.size):
        if ri[t] == ci[t]:
            h, r = col(t), int(state[ri[t]])
            for c in range(d):
                AN[ri[t], c] = h.get(slot(r, c), 0) // (2 if c == r else 1)
    for t in range(ri.size):
        a, b = int(ri[t]), int(ci[t])
        want: dict[int, int] = {}
        for s_, row_ in ((int(state[a]), AN[b]), (int(state[b]), AN[a])) if a != b else ((int(state[a]), AN[a]),):
            for c in range(d):
                v = row_[c]
                if v:
                    k = slot(s_, c)
                    want[k] = want.get(k, 0) + (2 * v if c == s_ else v)
        if {k: v for k, v in want.items() if v} != {k: v for k, v in col(t).items() if v}:
            return None
    den = 2 * Lx.den
    Abar = np.array([[int(v) / den for v in row_] for row_ in AN], dtype=float)
    return dict(cand, Abar=Abar, AbarN=AN, Abar_den=den, exact=ex)


def lyapunov_structure(problem: Problem, exact: ExactProblem | None = None) -> dict[str, Any] | None:
    """The Lyapunov (KYP) structure of the module docstring, or ``None``.

    Returns ``pivot`` (the block of ``P > 0``), ``block`` (the main LMI, the only other block
    the pivot rows touch), ``state`` (``E``: the state row of each index of ``P``), ``Abar``
    (``n_P x d``; ``AbarN / Abar_den`` exactly), ``rows`` (the pivot row of each tril entry of
    ``P``'s block) and ``exact``, after checking that every pivot row's coefficients are those
    of ``E^T P Abar + Abar^T P E`` exactly on ``exact`` (default: the IR's own floats, where
    ``fl(A_aa + A_bb)`` of random data breaks it; :func:`lmic.compile.exact.exact_of`).

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("p", "scalar", (1, 1))], [LMI("p > 0", 1, sp.csc_matrix([[0.0, 1.0]]))],
    ...             LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
    >>> lyapunov_structure(p) is None
    True
    """
    cand = _float_structure(problem)
    if cand is None:
        return None
    if exact is None and not cand["exact_ir"]:
        return None
    return _exact_structure(problem, cand, exact if exact is not None else from_ir(problem))


def structure_for(problem: Problem) -> tuple[dict[str, Any] | None, str]:
    """The structure on the IR's own coefficients, else on the problem's exact compilation
    (:func:`lmic.compile.exact.exact_of`): ``(structure or None, reason)``; the structure's
    ``problem`` is ``"ir"`` or ``"exact"`` (what a bound proved on it is about)."""
    cand = _float_structure(problem)
    if cand is None:  # the discrete-time (Stein) form, else none
        from lmic.certify.enclosure_face_stein import stein_structure_for

        return stein_structure_for(problem)
    if cand["exact_ir"]:
        st = _exact_structure(problem, cand, from_ir(problem))
        if st is not None:
            return dict(st, problem="ir"), ""
    return structure_on_exact(problem, lambda ex: _exact_structure(problem, cand, ex), "Lyapunov")


def _fq(flint: Any, v: float) -> Any:
    f = Fraction(float(v))
    return flint.fmpq(f.numerator, f.denominator)


def prove_face(problem: Problem, structure: dict[str, Any], K: Any, S_rest: np.ndarray) -> dict[str, Any]:
    """The exact proof of the module docstring from ``K`` (``r x r``, skew) and ``S_rest``
    (the non-state rows of ``S``, ``(d - n_P) x r``), on the exact coefficients of
    ``structure`` (:func:`lyapunov_structure`; for a Stein structure ``K`` is ``U``, rationals
    exactly orthogonal). Returns ``proven``, ``lower`` (rounded down), ``lower_exact`` and
    ``reason``."""
    from lmic.certify.psd import load_flint, prove_psd

    flint = load_flint()
    P = problem
    ex: ExactProblem = structure["exact"]
    pi, xi, state = structure["pivot"], structure["block"], structure["state"]
    AN, Aden = structure["AbarN"], int(structure["Abar_den"])
    npv, d = P.lmis[pi].dim, P.lmis[xi].dim
    rest = np.setdiff1d(np.arange(d), state)
    stein = structure.get("form") == "stein"  # K is then U, exactly orthogonal (enclosure_face_stein)
    if stein:
        from lmic.certify.enclosure_face_stein import exact_orthogonal, stein_pivot_g

        Uq = exact_orthogonal(K)
        if Uq is None:
            return {"proven": False, "reason": "U is not an exactly orthogonal rational matrix"}
        Kq: list[list[Fraction]] = Uq
        K = np.array([[float(v) for v in row_] for row_ in Uq])
    K = np.asarray(K, dtype=float)
    S_rest = np.asarray(S_rest, dtype=float)
    r = K.shape[0] if K.ndim == 2 else -1
    if r < 1 or K.shape != (r, r) or S_rest.shape != (rest.size, r):
        return {"proven": False, "reason": "the face point's K or S_R has the wrong shape"}
    if not (np.all(np.isfinite(K)) and np.all(np.isfinite(S_rest))) or (not stein and np.any(K != -K.T)):
        return {"proven": False, "reason": "K is not a finite skew-symmetric matrix"}
    if not stein:
        Kq = [[Fraction(float(v)) for v in row_] for row_ in K]
    # A_E S_E - S_E K = -A_R S_R, as (I (x) A_E - K^T (x) I) vec(S_E) = vec(-A_R S_R)
    AE, AR = AN[:, state], AN[:, rest]
    nr = npv * r
    M = flint.fmpq_mat(nr, nr)
    for c in range(r):
        for i in range(npv):
            row = c * npv + i
            for j in range(npv):
                if AE[i, j] != 0:
                    M[row, c * npv + j] = flint.fmpq(int(AE[i, j]), Aden)
            for c2 in range(r):
                if Kq[c2][c] != 0:
                    M[row, c2 * npv + i] -= flint.fmpq(Kq[c2][c].numerator, Kq[c2][c].denominator)
    SRq = [[_fq(flint, S_rest[i, c]) for c in range(r)] for i in range(rest.size)]
    rhs = flint.fmpq_mat(nr, 1)
    for c in range(r):
        for i in range(npv):
            s = flint.fmpq(0)
            for j in range(rest.size):
                if AR[i, j] != 0:
                    s -= flint.fmpq(int(AR[i, j]), Aden) * SRq[j][c]
            rhs[c * npv + i, 0] = s
    try:
        sol = M.solve(rhs)
    except ZeroDivisionError:
        return {"proven": False, "reason": "the Sylvester equation of the face is singular"}
    # S = N / D with integers N and one common denominator D: the solve's own (flint), times the
    # power of two of the float S_R
    solN, solD = sol.numer_denom()
    solD = int(solD)
    SRf = [[Fraction(float(S_rest[j, c])) for c in range(r)] for j in range(rest.size)]
    two = max((f.denominator for row_ in SRf for f in row_), default=1)  # powers of two: the largest
    D = solD * two // math.gcd(solD, two)
    N = flint.fmpz_mat(d, r)
    for c in range(r):
        for i in range(npv):
            N[int(state[i]), c] = solN[c * npv + i, 0] * (D // solD)
        for j in range(rest.size):
            f = SRf[j][c]
            N[int(rest[j]), c] = f.numerator * (D // f.denominator)
    XN = N * N.transpose()  # X = XN / D^2, exactly
    sgn = -1 if P.objective.sense == "max" else 1
    q = list(ex.objective) if sgn == 1 else [-v for v in ex.objective]
    Lx, Lp = ex.lmis[xi], ex.lmis[pi]
    ti, tj = tril_rows_cols(d)
    # <F_k, X> over the main block: the weight 2 of an off-diagonal tril entry folded into xn
    xn = [int(XN[int(ti[k]), int(tj[k])]) * (1 if ti[k] == tj[k] else 2) for k in range(ti.size)]
    D2 = D * D

    def g(k: int) -> Fraction:
        """``g_k(X)`` over the main block, exactly."""
        rr, vv = Lx.column(k)
        return Fraction(sum(int(v) * xn[int(j)] for j, v in zip(rr.tolist(), vv.tolist(), strict=True)), Lx.den * D2)

    prow = {int(k): t for t, k in enumerate(structure["rows"])}
    # on a pivot row (P_ab) the coefficients are E^T E_ab Abar + Abar^T E_ab E (checked exactly
    # by lyapunov_structure): g = <F, X> = 2 (Abar X)[b, s_a] + 2 (Abar X)[a, s_b] (once if a = b)
    # Abar X = MN / (Aden D^2), MN = (AN N) N^T: two thin products (AN XN costs seconds at 50 states)
    pa_, pb_ = tril_rows_cols(npv)
    if stein:  # sigma tr(E_ab (Abar X Abar^T - E X E^T))
        g_pivot = stein_pivot_g(structure, N, D)
    else:
        MN = (flint.fmpz_mat([[int(v) for v in row_] for row_ in AN]) * N) * N.transpose()

        def g_pivot(t: int) -> Fraction:
            """``g`` of the pivot row of tril entry ``t``."""
            a_, b_ = int(pa_[t]), int(pb_[t])
            gn = int(MN[b_, int(state[a_])]) + (int(MN[a_, int(state[b_])]) if a_ != b_ else 0)
            return Fraction(2 * gn, Aden * D2) if gn else Fraction(0)

    others = [k for k in range(1, 1 + P.n) if k not in prow]
    gv = {k: g(k) for k in others}
    # X / t meets the rows without a pivot: one scale t > 0 for all of them
    t = None
    for k in others:
        if q[k] != 0:
            t = gv[k] / q[k]
            break
    if t is None or not t > 0:
        return {"proven": False, "reason": "no positive scale meets the equality rows without a pivot"}
    for k in others:
        if gv[k] != t * q[k]:
            return {"proven": False, "reason": f"equality row {k} does not hold on the face"}
    # the pivot block from its rows: W_j = (q_k - g_k(X) / t) / J_kj, exactly
    pr, pc = tril_rows_cols(npv)
    pw = np.where(pr == pc, 1, 2)
    w = [Fraction(0)] * pr.size
    for k, tt in prow.items():
        gn = g_pivot(tt)
        if gn or q[k]:  # on the face g = 0 (W = 0): no rational arithmetic unless needed
            w[tt] = (q[k] - gn / t) / (int(pw[tt]) * Lp.value(tt, k))
    if any(w):
        den = 1
        for f in w:
            den = den * f.denominator // math.gcd(den, f.denominator)
        Wm = [[0] * npv for _ in range(npv)]
        for f, r_, c_ in zip(w, pr, pc, strict=True):
            Wm[r_][c_] = Wm[c_][r_] = int(f * den)
        if not prove_psd(Wm)["proven"]:
            return {"proven": False, "reason": f"the pivot multiplier of '{P.lmis[pi].name}' is not PSD on the face"}
    Lf = q[0] - g(0) / t
    r0, v0 = Lp.column(0)
    for j, v in zip(r0.tolist(), v0.tolist(), strict=True):
        Lf -= int(pw[j]) * Fraction(int(v), Lp.den) * w[int(j)]
    lower = float(Lf)
    if Fraction(lower) > Lf:
        lower = down(lower)
    return {
        "proven": True,
        "lower": lower,
        "lower_exact": f"{Lf.numerator}/{Lf.denominator}" if Lf.denominator != 1 else str(Lf.numerator),
        "rank": r,
        "reason": "dual point on the face W = 0 proved feasible in exact rational arithmetic",
    }


def _candidates(structure: dict[str, Any], X0: np.ndarray) -> list[tuple[float, np.ndarray, np.ndarray]]:
    """``(float estimate of L's loss, K, S_R)`` for ranks ``1 .. MAX_RANK`` of the solver's
    multiplier, best first (the estimate: the relative change of ``S_E`` by the Sylvester
    solve)."""
    import scipy.linalg as sla

    state, Abar = structure["state"], structure["Abar"]
    d = X0.shape[0]
    rest = np.setdiff1d(np.arange(d), state)
    w, V = np.linalg.eigh(0.5 * (X0 + X0.T))
    out = []
    for r in range(1, min(MAX_RANK, d) + 1):
        if not w[-r] > 0:
            break
        S0 = V[:, -r:] * np.sqrt(w[-r:])
        S1 = S0[state]
        Kt = np.linalg.lstsq(S1, Abar @ S0, rcond=None)[0]
        K = (Kt - Kt.T) / 2.0
        try:
            S1n = sla.solve_sylvester(Abar[:, state], -K, -Abar[:, rest] @ S0[rest])
        except (np.linalg.LinAlgError, ValueError):
            continue
        change = float(np.linalg.norm(S1n - S1)) / max(float(np.linalg.norm(S1)), 1e-300)
        if np.isfinite(change):
            out.append((change, K, S0[rest]))
    out.sort(key=lambda c: c[0])
    return out


def _ranked(problem: Problem, st: dict[str, Any], mats: list[np.ndarray], y: np.ndarray) -> list[Any]:
    """Every candidate, best float bound first: the solver's (:func:`_candidates`) and the
    frequency search's (:mod:`lmic.certify.enclosure_face_kyp`: near the solver's frequency,
    and over a grid when the best is below the solver's dual objective by more than
    :data:`GRID_SLACK`, as when the solver stopped inaccurate)."""
    from lmic.certify.enclosure_face_kyp import estimate, kyp_candidates
    from lmic.certify.enclosure_repair import _pack

    own = _candidates(st, mats[st["block"]])
    out = [(estimate(problem, st, K, SR), K, SR) for _, K, SR in own]
    omega0 = next((float(K[1, 0]) for _, K, _ in own if K.shape[0] == 2 and K[1, 0] != 0), None)
    out += kyp_candidates(problem, st, omega0, grid=False)
    J, _ = jacobian(problem)
    L0 = float(_target(problem)[0] - (J[0] @ _pack(problem, mats, y))[0])
    top = max((c[0] for c in out if np.isfinite(c[0])), default=-np.inf)
    if not top >= L0 - GRID_SLACK * max(1.0, abs(L0)):
        out += kyp_candidates(problem, st, omega0, grid=True)
    return sorted((c for c in out if np.isfinite(c[0])), key=lambda c: -c[0])


def face_bound(problem: Problem, duals: dict[str, Any] | None, *, tries: int = 2) -> dict[str, Any]:
    """Prove a lower bound of the minimisation form's optimum on the face ``W = 0`` (module
    docstring), from the solver's multiplier of the main LMI and the frequency search
    (:func:`_ranked`; the search alone when ``duals`` has no multipliers): the candidates are
    tried best first (at most ``tries``), the first proven bound kept.

    Returns
    -------
    dict
        As :func:`lmic.certify.enclosure_dual.dual_bound`: ``proven``, ``lower``,
        ``lower_exact``, ``method`` (``"exact"``), ``route`` (``"face"``), ``reason``,
        ``problem`` (``"ir"``: the bound holds for the IR's own coefficients; ``"exact"``: for
        the theorem compiled exactly from the system's numbers, :mod:`lmic.compile.exact`),
        ``dual`` (``{"form": "face", "problem", "block", "pivot", "K", "S_rest"}``; the Stein
        form records ``U`` as rational strings and ``"structure": "stein"`` instead of ``K``).
    """
    from lmic.certify.multipliers import parse_multipliers

    if problem.objective.sense == "feasibility":
        raise CertificateError("a feasibility problem has no optimal value to bound")
    st, why = structure_for(problem)
    if st is None:
        return {"proven": False, "route": "face", "reason": why}
    stein, cands = st.get("form") == "stein", []  # type: tuple[bool, list[Any]]
    if stein:  # the discrete-time form: U exactly orthogonal (enclosure_face_stein)
        from lmic.certify.enclosure_face_stein import stein_candidates

        X0 = None
        if duals and duals.get("lmis") is not None:
            X0 = parse_multipliers(problem, duals, "dual point", missing_is_zero=False)[0][st["block"]]
        cands = stein_candidates(problem, st, X0)
    elif duals and duals.get("lmis") is not None:
        mats, y = parse_multipliers(problem, duals, "dual point", missing_is_zero=False)
        cands = _ranked(problem, st, mats, y)
    else:  # no dual point: the frequency search alone
        from lmic.certify.enclosure_face_kyp import kyp_candidates

        cands = kyp_candidates(problem, st)
    best: dict[str, Any] = {"proven": False, "route": "face", "reason": "no face candidate"}
    for _, K, SR in cands[:tries]:
        res = prove_face(problem, st, K, SR)
        res.update(route="face", method="exact", shift=0.0, problem=st["problem"])
        if res["proven"]:
            res["dual"] = {
                "form": "face",
                "problem": st["problem"],
                "block": int(st["block"]),
                "pivot": int(st["pivot"]),
                "S_rest": SR.tolist(),
            }
            if stein:
                res["dual"].update(structure="stein", U=[[str(v) for v in row_] for row_ in K])
            else:
                res["dual"]["K"] = np.asarray(K).tolist()
            return res
        best = res
    return best


def verify_face(problem: Problem, record: dict[str, Any]) -> dict[str, Any]:
    """Re-run :func:`prove_face` from a recorded point (``record["dual"]``, form ``"face"``)
    alone; the recorded ``lower`` must not exceed the re-proved bound. Returns ``ok``,
    ``lower`` and ``reason``."""
    d = record.get("dual")
    if not isinstance(d, dict) or d.get("form") != "face" or record.get("lower") is None:
        return {"ok": False, "lower": None, "reason": "no face dual point recorded"}
    about = d.get("problem", "ir")
    if about not in ("ir", "exact"):
        return {"ok": False, "lower": None, "reason": f"unknown problem {about!r} of the face point"}
    stein = d.get("structure", "kyp") == "stein"
    try:
        if stein:
            from lmic.certify.enclosure_face_stein import stein_structure

            st = stein_structure(problem, exact_of(problem) if about == "exact" else None)
        else:
            st = lyapunov_structure(problem, exact_of(problem) if about == "exact" else None)
    except ExactUnavailable as exc:
        return {"ok": False, "lower": None, "reason": f"the exact problem cannot be recompiled: {exc}"}
    if about == "exact" and st is not None and st["exact"].about != "theorem":
        return {"ok": False, "lower": None, "reason": "the face point is about the exact compilation of a theorem"}
    if st is None or d.get("block") != st["block"] or d.get("pivot") != st["pivot"]:
        return {"ok": False, "lower": None, "reason": "the recorded face does not match the problem's structure"}
    try:
        K: Any = d.get("U") if stein else np.asarray(d.get("K"), dtype=float)
        SR = np.asarray(d.get("S_rest"), dtype=float)
        if (not stein and np.ndim(K) != 2) or SR.ndim != 2:
            raise ValueError("K and S_rest must be matrices")
        res = prove_face(problem, st, K, SR)
    except (ValueError, TypeError) as exc:
        return {"ok": False, "lower": None, "reason": f"the recorded face point is unusable: {exc}"}
    if not res["proven"]:
        why = "the recorded dual point does not prove a bound: " + res["reason"]
        return {"ok": False, "lower": None, "reason": why}
    rec = float(record["lower"])
    if rec > res["lower"]:
        return {
            "ok": False,
            "lower": res["lower"],
            "reason": f"recorded lower bound {rec:.17g} exceeds the bound the dual point proves ({res['lower']:.17g})",
        }
    where = "the theorem's exact compilation" if about == "exact" else "the IR"
    return {
        "ok": True,
        "lower": res["lower"],
        "lower_exact": res["lower_exact"],
        "reason": f"lower bound re-proved exactly on the face ({where})",
    }
