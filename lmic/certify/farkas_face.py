"""The faces of a Farkas certificate for the exact proofs of :mod:`lmic.certify.farkas_exact`.

A solver's ray is exact only to the solver's tolerance: the exact proof needs the right face
(which eigenvectors of ``Z_i`` carry the certificate), the right basis of it (rational when the
true face is) and, when the float point sits on the boundary, a point inside. This module finds
them; every result is a candidate that the exact proof checks. Split out of
:mod:`lmic.certify.farkas_exact` (private helpers only).

* :func:`_face_thresholds`: the eigenvalue thresholds defining the faces to try (the given
  ones, then each block's largest eigenvalue gaps: scale-free).
* :func:`_snap` and :func:`_rational_basis`: the face basis without LAPACK's round-off, and a
  small-denominator rational basis of it.
* :func:`_towards_center`: a point moved towards the analytic centre of the face's
  certificates.

Examples
--------
>>> U = np.array([[0.0], [1.0], [3e-7], [-1.0]]) / np.sqrt(2)
>>> _rational_basis(U).ravel().tolist()
[0, 1, 0, -1]
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from lmic.certify.enclosure_repair import _congruence_gradient, _weights
from lmic.certify.farkas_ray import _parse
from lmic.ir.problem import Problem

#: bits of the rational rounding of the face bases
_FACE_BITS = 50

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
            ratios = v[:-1] / v[1:]
            gaps += [(float(ratios[j]), float(np.sqrt(v[j] * v[j + 1]))) for j in range(v.size - 1)]
    out, seen = list(rel_face), {face(rel) for rel in rel_face}
    for ratio, rel in sorted(gaps, reverse=True):
        if ratio < _GAP_RATIO or len(out) >= len(rel_face) + _GAP_FACES:
            break
        if face(rel) not in seen:
            seen.add(face(rel))
            out.append(rel)
    return out


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


def _congruence_columns(coeffs: Any, d: int, U: np.ndarray) -> np.ndarray:
    """``d <F_k, U S U^T> / d svec(S)`` for every column ``k`` of an LMI's coefficients (the
    lower triangles of ``F_k``): ``2 (U^T F_k U)[a, b]`` off the diagonal and ``(U^T F_k
    U)[a, a]`` on it, in the order of ``triu_indices(r)``: the enclosure repair's congruence
    gradient (:func:`lmic.certify.enclosure_repair._congruence_gradient`) of the weighted rows
    ``F_k``, ``O(d^2 r)`` a column (the products ``U E_ab U^T`` of every pair ``a <= b``, a
    ``d(d+1)/2 x r(r+1)/2`` matrix, took 0.2 s for a face of order 74 in an LMI of order 74).

    >>> import numpy as np, scipy.sparse as sp
    >>> F = sp.csc_matrix(np.array([[0.0, 1.0], [0.0, 2.0], [0.0, 3.0]]))  # [[1, 2], [2, 3]]
    >>> _congruence_columns(F, 2, np.eye(2)).tolist()
    [[0.0, 0.0, 0.0], [1.0, 4.0, 3.0]]
    """
    import scipy.sparse as sp

    rows = sp.csc_matrix(sp.csc_matrix(coeffs).T.multiply(_weights(d)[None, :]))
    ia, ib = np.triu_indices(U.shape[1])
    out = np.zeros((rows.shape[0], ia.size))
    return _congruence_gradient(rows, U, d, ia, ib, np.arange(rows.shape[0]), out)


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
        cols.append(_congruence_columns(lmi.coeffs, lmi.dim, U))
    if rows:
        cols.append(np.asarray(problem.linear.A.tocsr()[rows].T.toarray()))
    return np.hstack(cols)


@dataclass
class _FaceSetup:
    """What both centring methods share: the constraint rows (unit norm, the trace normalisation
    last), their right-hand side, and the split of ``u`` into the blocks ``S_i``."""

    nS: int
    A: np.ndarray
    b: np.ndarray
    c0: np.ndarray
    sizes: list[int]
    tri: list[tuple[np.ndarray, np.ndarray]]
    ge_rows: np.ndarray
    separate: bool

    def split(self, u: np.ndarray) -> list[np.ndarray]:
        out, k = [], 0
        for r, (a, bb) in zip(self.sizes, self.tri, strict=True):
            S = np.zeros((r, r))
            S[a, bb] = u[k : k + len(a)]
            S[bb, a] = u[k : k + len(a)]
            out.append(S)
            k += len(a)
        return out

    def inside(self, u: np.ndarray) -> bool:
        if self.separate and not float(self.c0 @ u) < 0:
            return False
        if np.any(u[self.nS :][self.ge_rows] <= 0):
            return False
        return all(np.linalg.eigvalsh(S)[0] > 0 for S in self.split(u) if S.size)

    def barrier(self, u: np.ndarray) -> float:
        """``-sum_i log det S_i - sum log y_r (- log(-g_0) when separate)`` at an interior ``u``."""
        f = -sum(float(np.linalg.slogdet(S)[1]) for S in self.split(u) if S.size)
        f -= float(np.sum(np.log(u[self.nS :][self.ge_rows])))
        return f - (math.log(-float(self.c0 @ u)) if self.separate else 0.0)


def _face_setup(J: np.ndarray, u0: np.ndarray, sizes: list[int], ge_rows: np.ndarray, separate: bool) -> _FaceSetup:
    """The rows ``g_k = 0`` (``k >= 1``) and the fixed trace ``sum_i tr S_i + sum y_r`` of the
    centring problems, each row of unit norm (a better balanced KKT system)."""
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
    scale = np.maximum(np.linalg.norm(A, axis=1), 1e-300)
    A = A / scale[:, None]
    rhs = np.zeros(A.shape[0])
    rhs[-1] = float(N @ u0) / scale[-1]
    return _FaceSetup(nS, A, rhs, J[0], sizes, tri, ge_rows, separate)


#: above this many unknowns the face centring factors its Hessian block by block
#: (:func:`_center_on_face_large`) instead of the dense null-space Newton steps (``O(m^3)`` a step)
DENSE_CENTRE_MAX = 1000


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
    if m > DENSE_CENTRE_MAX:
        return _center_on_face_large(J, u0, sizes, ge_rows, separate, max_iter)
    setup = _face_setup(J, u0, sizes, ge_rows, separate)
    nS, A, b, c0, tri, split, inside = setup.nS, setup.A, setup.b, setup.c0, setup.tri, setup.split, setup.inside

    def derivatives(u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        grad, H = np.zeros(m), np.zeros((m, m))
        k = 0
        for (a, bb), S in zip(tri, split(u), strict=True):
            t = len(a)
            # -log det S in svec coordinates (E_k = e_a e_b^T + e_b e_a^T, e_a e_a^T on the
            # diagonal): grad_k = -tr(S^-1 E_k), H_kl = tr(S^-1 E_k S^-1 E_l), in closed form
            # (O(t^2), not the O(t^2 r^2) of the products of the E_k)
            Si = np.linalg.inv(S)
            w = np.where(a == bb, 0.5, 1.0)
            grad[k : k + t] = -2.0 * w * Si[a, bb]
            H[k : k + t, k : k + t] = (
                2.0 * (Si[np.ix_(bb, a)] * Si[np.ix_(a, bb)] + Si[np.ix_(bb, bb)] * Si[np.ix_(a, a)]) * np.outer(w, w)
            )
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

    value = setup.barrier

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


def logdet_hessian_solve(S: np.ndarray, a: np.ndarray, b: np.ndarray, X: np.ndarray) -> np.ndarray:
    """``H^-1 X`` for the Hessian ``H`` of ``-log det S`` in the coordinates ``u_k = S[a_k, b_k]``
    of the upper triangle (``a = triu_indices(r)[0]``, ``b = ...[1]``), without forming ``H``.

    ``H = M' (S^-1 (x) S^-1) M`` with ``M`` the map from ``u`` to ``vec S``; its inverse is
    ``N (S (x) S) N'`` with ``N = (M'M)^-1 M'`` (``S (x) S`` commutes with the symmetrisation),
    so ``(H^-1 x)_k = (S G S)[a_k, b_k]`` with ``G`` the symmetric matrix of ``x_k / 2`` off the
    diagonal and ``x_k`` on it: ``O(r^3)`` a column against the ``O(r^6)`` of factoring ``H``
    (a face block of order 74: 2775 unknowns, 0.2 s a Cholesky). ``X`` is a vector or a matrix
    of columns; columns are taken in chunks of at most ``2e6 / r^2``.

    >>> import numpy as np
    >>> S = np.array([[2.0, 1.0], [1.0, 3.0]])
    >>> a, b = np.triu_indices(2)
    >>> x = np.array([1.0, 0.0, 0.0])           # the gradient direction of S[0, 0]
    >>> np.round(logdet_hessian_solve(S, a, b, x), 12).tolist()   # (S e_0 e_0' S) on the triangle
    [4.0, 2.0, 1.0]
    """
    r = S.shape[0]
    X2 = X[:, None] if X.ndim == 1 else X
    half = np.where(a == b, 1.0, 0.5)[:, None]
    out = np.empty_like(X2, dtype=float)
    step = max(1, int(2e6 // max(1, r * r)))
    for j in range(0, X2.shape[1], step):
        vals = (X2[:, j : j + step] * half).T
        G = np.zeros((vals.shape[0], r, r))
        G[:, a, b] = vals
        G[:, b, a] = vals
        Y = S @ G @ S
        out[:, j : j + step] = Y[:, a, b].T
    return out[:, 0] if X.ndim == 1 else out


def _center_on_face_large(
    J: np.ndarray, u0: np.ndarray, sizes: list[int], ge_rows: np.ndarray, separate: bool, max_iter: int = 30
) -> np.ndarray | None:
    """:func:`_center_on_face` for many unknowns (``m >`` :data:`DENSE_CENTRE_MAX`).

    Maximises ``sum_i log det S_i + sum_{ge rows} log y_r (+ log(-g_0) when separate)`` subject
    to ``g_k = 0`` (``k >= 1``) and ``sum_i tr S_i + sum_{ge rows} y_r`` fixed, by infeasible-start
    Newton steps from ``u0`` (which must be strictly inside the cone). Returns ``None`` when no
    strictly interior point was reached (the face is larger than the certificates' face).
    """
    m = u0.size
    setup = _face_setup(J, u0, sizes, ge_rows, separate)
    nS, A, b, c0, tri, split, inside = setup.nS, setup.A, setup.b, setup.c0, setup.tri, setup.split, setup.inside

    yr = np.flatnonzero(ge_rows) + nS

    def newton(u: np.ndarray, resid: np.ndarray) -> tuple[np.ndarray, float]:
        """The equality-constrained Newton step ``du`` (``A du = resid``) of the barrier at
        ``u`` and ``-grad . du``. The Hessian is block diagonal (one block per ``S_i``, a
        diagonal for the rows) plus rank one (the separation term): each block is factored
        alone and the constraints go through the small Schur complement ``A H^-1 A^T``, so a
        step costs ``O(sum t_i^3 + m p^2)``, not the ``O(m^3)`` of a dense null-space step."""
        import scipy.linalg

        grad = np.zeros(m)
        blocks: list[tuple[int, int, np.ndarray, np.ndarray, np.ndarray]] = []
        k = 0
        for (a, bb), S in zip(tri, split(u), strict=True):
            t = len(a)
            # -log det S in svec coordinates (E_k = e_a e_b^T + e_b e_a^T, e_a e_a^T on the
            # diagonal): grad_k = -tr(S^-1 E_k); the Hessian's inverse is applied in closed
            # form (logdet_hessian_solve), never formed
            Si = scipy.linalg.inv(S, check_finite=False)
            w = np.where(a == bb, 0.5, 1.0)
            grad[k : k + t] = -2.0 * w * Si[a, bb]
            blocks.append((k, t, S, a, bb))
            k += t
        dy = np.ones(m)
        grad[yr] -= 1.0 / u[yr]
        dy[yr] = u[yr] ** 2  # the inverse of the rows' diagonal Hessian 1 / y^2
        v = np.zeros(m)
        if separate:
            h = -float(c0 @ u)
            grad += c0 / h
            v = c0 / h

        def h0inv(X: np.ndarray) -> np.ndarray:
            out = X * (dy if X.ndim == 1 else dy[:, None])
            for k0, t, S, a, bb in blocks:
                out[k0 : k0 + t] = logdet_hessian_solve(S, a, bb, X[k0 : k0 + t])
            return out

        def hinv(X: np.ndarray) -> np.ndarray:
            Y = h0inv(X)
            if not separate:
                return Y
            hv = h0inv(v)
            den = 1.0 + float(v @ hv)
            return Y - np.outer(hv, v @ Y) / den if Y.ndim == 2 else Y - hv * float(v @ Y) / den

        HiAt = hinv(A.T.copy())
        Hig = hinv(grad.copy())
        K = A @ HiAt
        K[np.diag_indices_from(K)] += 1e-14 * float(np.trace(K)) / max(1, len(K))
        lam = np.linalg.lstsq(K, -(A @ Hig) - resid, rcond=1e-13)[0]
        du = -Hig - HiAt @ lam
        return du, -float(grad @ du)

    if not inside(u0):
        return None
    # phase 1 (infeasible start): Newton steps on the barrier that also take the rest of the
    # slice's equations, damped to stay inside the cone, until a full step lands on the slice
    u = u0.copy()
    reached = False
    for _ in range(max_iter):
        du, _dec = newton(u, b - A @ u)
        t = 1.0
        while t > 1e-6 and not inside(u + t * du):
            t *= 0.5
        if t <= 1e-6:
            return None
        u = u + t * du
        if t == 1.0:
            reached = True
            break
    if not reached:
        return None

    value = setup.barrier

    f = value(u)
    for _ in range(max_iter):
        du, dec = newton(u, b - A @ u)  # the slice's round-off is corrected as it goes
        if not dec > 1e-8:  # near enough to the centre: only a margin is needed
            break
        t = 1.0
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
    problem: Problem,
    eigs: list,
    sels: list,
    rows: list[int],
    ge: np.ndarray,
    u0: np.ndarray,
    top: float,
    method: str = "dense",
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
        if method == "schur":
            # the other centring (a different Newton path, a different centre): it proves
            # faces the dense one does not (obs_control original coordinates), and vice versa;
            # above DENSE_CENTRE_MAX it is what the dense call already ran
            if u0.size > DENSE_CENTRE_MAX:
                return None
            uc = _center_on_face_large(J, u0, sizes, ge_rows, separate)
        else:
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
