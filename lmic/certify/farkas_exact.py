"""Exact (rational) Farkas certificates: a float ray made into a global proof of infeasibility.

:func:`prove_farkas` rounds a verified float certificate onto its face and projects it exactly
onto the conditions ``g_k = 0`` (the method is in the docstring of :mod:`lmic.certify.farkas`);
:func:`prove_infeasible` is the entry the certifier calls with ``exact=True``. Split out of
:mod:`lmic.certify.farkas`, which re-exports every public name.

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
>>> p = Problem([Variable("p", "scalar", (1, 1))],
...             [LMI("p >= 0", 1, sp.csc_matrix([[0., 1.]]), strict=False),
...              LMI("-1 - p >= 0", 1, sp.csc_matrix([[-1., -1.]]), strict=False)],
...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
>>> prove_farkas(p, {"lmis": [np.eye(1), np.eye(1)], "linear": []})["proven"]
True
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from lmic.certify.farkas_ray import _parse, _weights
from lmic.ir.problem import Problem
from lmic.ir.svec import tril_rows_cols

__all__ = ["prove_farkas", "prove_infeasible", "EXACT_MAX_ENTRIES"]

#: largest exact Jacobian ((1 + n) x (tril entries) x (face unknowns)) an exact proof builds
EXACT_MAX_ENTRIES = 50_000_000
#: bits of the rational rounding of the face bases
_FACE_BITS = 50


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
    for rel in _face_thresholds(problem, farkas, rel_face):
        for center, rational in ((False, False), (False, True), (True, False), (True, True)):
            attempt = _prove_farkas(problem, farkas, rel, keep_certificate, center, rational)
            if attempt["face"] is not None:
                attempt["face"]["threshold"] = rel
                attempt["face"]["centered"] = center
                attempt["face"]["rational_basis"] = rational
            if not out or attempt["proven"]:
                out = attempt
            if attempt["proven"]:
                break
        if out.get("proven"):
            break
    out["time_s"] = time.perf_counter() - t0
    return out


#: eigenvalue gaps (ratio of consecutive multipliers) that also define a face, at most this many
_GAP_FACES = 3
#: smallest ratio of consecutive multipliers that counts as a gap
_GAP_RATIO = 8.0


def _face_thresholds(problem: Problem, farkas: dict[str, Any], rel_face: tuple[float, ...]) -> list[float]:
    """The face thresholds to try: ``rel_face``, then the certificate's largest eigenvalue gaps.

    A fixed threshold depends on the solver's noise level relative to the certificate (the
    noise eigenvalues of a ray sit at ``1e-8`` of the largest on one instance and at ``1e-9``
    on the same instance scaled by ``1e3``): on one side of it the face is the true face of the
    certificates, on the other a tilted rank-deficient one on which the only exact solution is
    ``0``. The largest ratios between consecutive multipliers (every ``Z_i``'s eigenvalues and
    ``y_r``, each block on its own, relative to the largest multiplier) separate the certificate from the solver's noise
    whatever the scale; a threshold in the middle of each of the ``_GAP_FACES`` largest gaps
    (ratio above ``_GAP_RATIO``) is tried after ``rel_face`` when it gives another face.
    """
    mats, y = _parse(problem, farkas)
    ge = np.array([k == "ge" for k in problem.linear.kinds], dtype=bool)
    ws = [np.linalg.eigvalsh(Z) if Z.size else np.zeros(0) for Z in mats]
    ys = np.where(ge, y, np.abs(y)) if len(y) else np.zeros(0)
    top = float(max([float(np.max(w, initial=0.0)) for w in ws] + [float(np.max(ys, initial=0.0))]))
    if not top > 0:
        return list(rel_face)

    def face(rel: float) -> tuple[int, ...]:
        return (*[int(np.sum(w > rel * top)) for w in ws], int(np.sum(ys > rel * top)))

    gaps: list[tuple[float, float]] = []  # (ratio, threshold), every block on its own
    for w in [*ws, ys]:
        v = np.sort(w[w > 1e-15 * top] / top)[::-1]
        if v.size >= 2:
            ratio = v[:-1] / v[1:]
            gaps += [(float(ratio[j]), float(np.sqrt(v[j] * v[j + 1]))) for j in range(v.size - 1)]
    out, seen = list(rel_face), {face(rel) for rel in rel_face}
    for ratio, rel in sorted(gaps, reverse=True):
        if ratio < _GAP_RATIO or len(out) >= len(rel_face) + _GAP_FACES:
            break
        if face(rel) not in seen:
            seen.add(face(rel))
            out.append(rel)
    return out


def _prove_farkas(
    problem: Problem,
    farkas: dict[str, Any],
    rel_face: float,
    keep: bool,
    center: bool = False,
    rational: bool = False,
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
    bases: list[np.ndarray | None] = [None] * len(eigs)
    if rational:
        # the face spanned by small-denominator rationals (module docstring); a block whose
        # face has no such basis is dropped (its multiplier set to 0): the exact check decides
        for i, ((_w, V), sel) in enumerate(zip(eigs, sels, strict=True)):
            if np.any(sel):
                bases[i] = _rational_basis(_snap(V[:, sel]))
                if bases[i] is None:
                    sels[i] = np.zeros_like(sel)
        if not any(np.any(sel) for sel in sels) and not rows:
            return dict(fail, reason="no face block has a small-denominator rational basis")
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
        basis = bases[i]
        if basis is None:
            W = np.rint(np.ldexp(_snap(V[:, sel]), _FACE_BITS)).astype(np.int64).astype(object)
        else:
            W = basis
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
        seg = u0f[k0 : k0 + len(ia)]
        if basis is None:
            # V diag(w) V^T = W (diag(w) 2^-100) W^T
            scale = flint.fmpq(1, 1 << (2 * _FACE_BITS))
            u0 += [q(float(v)) * scale for v in seg]
        else:
            # the same face matrix V S V^T in the rational basis: S_W = W^+ V S V^T W^+T
            Sv = np.zeros((r, r))
            Sv[ia, ib] = Sv[ib, ia] = seg
            U = _snap(V[:, sel])
            Wp = np.linalg.pinv(W.astype(float))
            Sw = Wp @ (U @ Sv @ U.T) @ Wp.T
            u0 += [q(float(v)) for v in Sw[ia, ib]]
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


#: rational face bases: (tolerance on an entry, largest denominator), tried in order
_RATIONAL_GRID = ((1e-9, 1000), (1e-5, 30), (1e-3, 6))


def _rational_basis(U: np.ndarray) -> np.ndarray | None:
    """An integer basis of the span of ``U`` (``d x r``) whose entries are small-denominator rationals.

    A solver's ray is accurate only to its own tolerance: its face (the span of the top
    eigenvectors) is tilted by ``1e-6`` or so off the true face, and when the true face is
    spanned by rational vectors (structured data: ``e_4 - e_7``, ...) the tilt makes the exact
    conditions bind where they vanish identically on the true face (the only exact solution is
    then ``Z_i = 0``). The canonical basis ``B = U U[p]^-1`` (``p`` ``r`` pivot rows by QR with
    column pivoting, so ``B[p] = I``) is scale-free; its entries are replaced by the nearest
    fractions with denominators up to ``q_max`` when every entry is within ``tol`` of one
    (:data:`_RATIONAL_GRID`, tried in order), and ``B`` times the common denominator is
    returned. ``None`` when no grid entry fits. A candidate only: the exact proof checks it.

    Examples
    --------
    >>> U = np.array([[0.0], [1.0], [3e-7], [-1.0]]) / np.sqrt(2)
    >>> _rational_basis(U).ravel().tolist()
    [0, 1, 0, -1]
    """
    from fractions import Fraction

    import scipy.linalg

    d, r = U.shape
    if not r:
        return None
    _, _, piv = scipy.linalg.qr(U.T, pivoting=True, mode="economic")
    p = np.sort(piv[:r])
    try:
        B = U @ np.linalg.inv(U[p])
    except np.linalg.LinAlgError:
        return None
    B[p] = np.eye(r)
    for tol, qmax in _RATIONAL_GRID:
        fr = [[Fraction(float(b)).limit_denominator(qmax) for b in row] for row in B]
        if all(
            abs(float(f) - b) <= tol * max(1.0, abs(b))
            for row, brow in zip(fr, B, strict=True)
            for f, b in zip(row, brow, strict=True)
        ):
            den = 1
            for row in fr:
                for f in row:
                    den = den * f.denominator // math.gcd(den, f.denominator)
            return np.array([[int(f * den) for f in row] for row in fr], dtype=object).reshape(d, r)
    return None


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
    >>> from lmic.certify.farkas_ray import verify_farkas
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
