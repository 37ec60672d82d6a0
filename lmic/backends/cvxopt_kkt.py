"""A structure-exploiting KKT solver for CVXOPT's ``conelp``: the Schur complement from low-rank
"cross" coefficient matrices.

CVXOPT's interior-point method solves, at every iteration, the KKT system of its Nesterov-Todd
scaling ``W``; with its ``chol`` solver the work is the Schur complement

    H[i, j] = sum over PSD blocks of tr(F_i Q F_j Q),  Q = rti rti',

formed by scaling every column of ``G`` (``n`` products of order ``d``) and one ``syrk`` of
order ``n`` over ``d (d + 1) / 2`` rows: ``n^2 d^2 / 2`` flops per block. The coefficient
matrices of LMIs written from system matrices are "crosses": ``A' P + P A`` with ``P = E_ab``
is non-zero only in rows and columns ``a`` and ``b``. A symmetric ``F`` whose non-zeros all lie
in rows or columns of a set ``S`` (a vertex cover of its sparsity graph) is

    F = E C' + C E',  E = I[:, S],  C = F[:, S] - E F[S, S] / 2,

and, with the one-sided scaling ``L = rti`` (``W^{-T} F = L' F L``), ``L' F L = U V' + V U'``
with ``U = L[S]'`` and ``V = L' C``: ``s`` columns each. So, summing over the columns ``a`` of
``i`` and ``b`` of ``j``,

    H[i, j] = 2 sum_{a, b} ( (U_a . V_b)(U_b . V_a) + (V_a . V_b)(U_a . U_b) ),

four products of order ``T = sum |S_j|`` over ``d`` per block instead of ``n^2 d^2 / 2``
(bounded-real lemma, 40 states: ``T = 1.6e3`` against ``n = 821``, ``d = 44``). As in
CVXOPT's own solver, nothing uses ``Q = L L'`` explicitly: that would square the scaling's
condition number (1e12 and more near the optimum) and lose the last iterations. Variables whose
cover is wide (``gamma I``, a dense coefficient) are handled as whole matrices (``L' F_j L``,
one column of ``H`` each). :func:`structured_cost` estimates the work, so the backend uses this
solver only where it wins (:func:`lmic.backends.cvxopt`).

The solver follows CVXOPT's contract for a user ``kktsolver`` (``coneprog.conelp``): ``f =
kktsolver(W)``, and ``f(x, y, z)`` overwrites the right-hand side ``(bx, by, bz)`` with ``(ux,
uy, W uz)``. Equality constraints are eliminated by a QR factorisation of ``A'``, as CVXOPT's
``chol`` does. Every solve is refined (at most :data:`REFINEMENT_STEPS`) against the true
operator, applied from the scaled data without the formed ``H``. When the Schur complement is
numerically indefinite, or a refined solve stays inaccurate (:data:`INACCURATE`), CVXOPT's
QR-based solver takes over for the rest of the run (:meth:`StructuredKKT.__call__`).

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> G = sp.csc_matrix(np.array([[1.0], [0.0], [0.0], [1.0]]))  # the identity of order 2
>>> kkt = StructuredKKT([G], sp.csc_matrix((0, 1)), sp.csc_matrix((0, 1)), [2])
>>> kkt.T, kkt.wide_count
(2, 0)
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

__all__ = [
    "StructuredKKT",
    "structured_cost",
    "cover_sizes",
    "analyse",
    "STRUCTURED_MARGIN",
    "MAX_STRUCTURED_ITERATIONS",
    "STRUCTURED_MIN_WORK",
    "worth_it",
]


def _lower_entries(G: sp.spmatrix, d: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(var, row, col, value)`` of the lower-triangle non-zeros (``row >= col``) of every
    column of ``G`` (column-major ``d x d`` blocks; CVXOPT reads only the lower triangle)."""
    C = sp.coo_matrix(G)
    keep = C.data != 0
    idx, var, val = C.row[keep], C.col[keep], C.data[keep]
    row, col = idx % d, idx // d
    low = row >= col
    return var[low], row[low], col[low], val[low]


def cover_sizes(G: sp.spmatrix, d: int, n: int, max_rounds: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """A vertex cover of each variable's sparsity graph in one block (greedy, all variables at
    once): ``(cover, size)``, ``cover`` an ``(n, d)`` boolean array. After ``max_rounds``
    picks, a variable still uncovered gets every row.

    >>> import numpy as np, scipy.sparse as sp
    >>> F = np.zeros((3, 3)); F[0, :] = F[:, 0] = 1.0   # a cross on row 0
    >>> cover, size = cover_sizes(sp.csc_matrix(F.reshape(-1, 1, order="F")), 3, 1)
    >>> cover[0].nonzero()[0].tolist(), size.tolist()
    ([0], [1])
    """
    var, row, col, _ = _lower_entries(G, d)
    cover = np.zeros((n, d), dtype=bool)
    alive = np.ones(len(var), dtype=bool)
    rounds = 0
    while alive.any():
        rounds += 1
        if max_rounds is not None and rounds > max_rounds:  # the rest are wide: every row
            cover[np.unique(var[alive])] = True
            break
        v, r, c = var[alive], row[alive], col[alive]
        deg = np.zeros((n, d))
        np.add.at(deg, (v, r), 1.0)
        off = r != c
        np.add.at(deg, (v[off], c[off]), 1.0)
        has = np.zeros(n, dtype=bool)
        has[v] = True
        pick = np.argmax(deg, axis=1)
        cover[np.nonzero(has)[0], pick[has]] = True
        alive &= ~(cover[var, row] | cover[var, col])
    return cover, cover.sum(axis=1)


class _Block:
    """One PSD block: the cover of every variable and the split into narrow variables (the
    cross formula, padded to ``s`` slots) and wide ones (whole matrices); :meth:`build` makes
    the per-iteration data."""

    def __init__(self, G: sp.spmatrix, d: int, n: int) -> None:
        self.d, self.n = d, n
        self.G = sp.csc_matrix(G)
        self.entries = _lower_entries(self.G, d)
        self.cover, size = cover_sizes(self.G, d, n, max_rounds=max(2, d // 4))
        wide = size > _narrow_limit(size, d, len(self.entries[0]))
        self.wide = np.nonzero(wide)[0]
        self.narrow = np.nonzero(~wide & (size > 0))[0]
        self.s = int(size[self.narrow].max()) if len(self.narrow) else 0
        self.T = len(self.narrow) * self.s
        self.cost = float(self.T**2 * d + d**2 * self.T + len(self.wide) * (2 * d**3 + len(self.entries[0])))

    def build(self) -> None:
        """``C`` (``d x T``) and ``R`` of the narrow variables, by slot (once)."""
        if hasattr(self, "C"):
            return
        d, n, s, cover = self.d, self.n, self.s, self.cover
        var, row, col, val = self.entries
        narrow = self.narrow
        # position of every cover row within its variable's (padded) group of slots
        pos = np.cumsum(cover, axis=1) - 1
        slot = np.full(n, -1)
        slot[narrow] = np.arange(len(narrow))
        Cbig = np.zeros((d, self.T))
        R = np.zeros(self.T, dtype=np.int64)
        vs, ks = np.nonzero(cover[narrow])
        R[vs * s + pos[narrow][vs, ks]] = ks
        # C[:, (j, k)] = F_j[:, S_j[k]] - E_j F_j[S_j, S_j[k]] / 2, from both orientations
        for u, w, once in ((row, col, True), (col, row, False)):
            # the entry F[u, w] of column w (the diagonal only once)
            keep = (slot[var] >= 0) & cover[var, w] & (once | (u != w))
            j, uu, ww, vv = var[keep], u[keep], w[keep], val[keep]
            half = np.where(cover[j, uu], 0.5, 1.0)
            np.add.at(Cbig, (uu, slot[j] * s + pos[j, ww]), vv * half)
        self.C, self.R = Cbig, R
        # the columns and rows of each slot, contiguous (one product per pair of slots)
        self.slot_C = [np.ascontiguousarray(Cbig[:, k::s]) for k in range(s)]
        self.slot_R = [R[k::s] for k in range(s)]
        lo = int(narrow[0]) if len(narrow) else 0
        #: the narrow variables as a slice when they are consecutive (no fancy-indexed update)
        self.narrow_slice = slice(lo, lo + len(narrow)) if len(narrow) and narrow[-1] - lo + 1 == len(narrow) else None
        #: the wide variables' coefficients as symmetric matrices
        cols = self.G[:, self.wide].toarray()
        self.wide_F = [_sym_lower(cols[:, k], d) for k in range(len(self.wide))]

    def scaled(self, L: np.ndarray) -> dict[str, Any]:
        """The iteration's scaled data for ``L = rti`` (``W^{-T} F = L' F L``): ``V_k = L' C_k``,
        ``U_k = L[R_k]`` per slot and ``M_j = L' F_j L`` per wide variable."""
        return {
            "V": [L.T @ C for C in self.slot_C],
            "U": [L[R] for R in self.slot_R],
            "M": [L.T @ F @ L for F in self.wide_F],
        }

    def schur(self, sc: dict[str, Any], H: np.ndarray, work: list[np.ndarray] | None = None) -> None:
        """Add this block's ``tr(F_i Q F_j Q) = <L' F_i L, L' F_j L>`` to ``H`` (``sc`` from
        :meth:`scaled`, ``work`` the caller's buffers)."""
        if self.T:
            part = self._narrow_part(sc, [] if work is None else work)
            if self.narrow_slice is not None:
                H[self.narrow_slice, self.narrow_slice] += part
            else:
                H[np.ix_(self.narrow, self.narrow)] += part
        for k, (j, M) in enumerate(zip(self.wide, sc["M"], strict=True)):
            col = np.zeros(H.shape[0])
            if self.T:
                col[self.narrow] = self._narrow_trace(sc, M)
            col[self.wide] = [float(np.sum(M * Mw)) for Mw in sc["M"]]
            col[self.wide[:k]] = 0.0  # the pairs of wide variables once
            H[:, j] += col
            col[j] = 0.0
            H[j, :] += col

    def _narrow_trace(self, sc: dict[str, Any], N: np.ndarray) -> np.ndarray:
        """``<L' F_i L, N>`` for every narrow ``i`` and a symmetric ``N``:
        ``L' F_i L = U_i V_i' + V_i U_i'``, so ``2 sum_k U_k[i] . (N V_k)[:, i]``."""
        total = np.zeros(len(self.narrow))
        for U, V in zip(sc["U"], sc["V"], strict=True):
            total += np.einsum("ir,ri->i", U, N @ V)
        return 2.0 * total

    def rhs(self, sc: dict[str, Any], N: np.ndarray, out: np.ndarray) -> None:
        """Add ``<L' F_i L, N>`` for every variable to ``out``."""
        if self.T:
            out[self.narrow] += self._narrow_trace(sc, N)
        for j, M in zip(self.wide, sc["M"], strict=True):
            out[j] += float(np.sum(M * N))

    def _narrow_part(self, sc: dict[str, Any], work: list[np.ndarray]) -> np.ndarray:
        """``<L' F_i L, L' F_j L>`` for the narrow variables, by pairs of slots ``(k, l)``: with
        ``P_kl = U_k V_l`` (``= (Q C_l)[R_k]``), ``M_kl = V_k' V_l`` and ``Q_kl = U_k U_l'``,

            2 sum_{k, l} ( P_lk' o P_kl + M_kl o Q_kl ),

        each pair's term the transpose of the ``(l, k)`` one: ``s (s + 1) / 2`` pairs of order
        ``m`` (the narrow variables), four products each, all from the one-sided scaling (the
        explicit ``Q = L L'`` would square its condition number)."""
        s, m = self.s, len(self.narrow)
        Us, Vs = sc["U"], sc["V"]
        if not work:  # allocated once per solve: fresh pages cost as much as the arithmetic
            work.extend(np.empty((m, m)) for _ in range(5 if s > 1 else 4))
        acc, buf, prod, other = work[:4]
        off = work[4] if s > 1 else None
        if off is not None:
            off[:] = 0.0
        for k in range(s):
            for l in range(k, s):
                target = acc if k == l == 0 else buf
                np.matmul(Us[k], Vs[l], out=prod)  # P_kl
                if k == l:
                    np.multiply(prod.T, prod, out=target)
                else:
                    np.matmul(Us[l], Vs[k], out=other)  # P_lk
                    np.multiply(other.T, prod, out=target)
                np.matmul(Vs[k].T, Vs[l], out=prod)
                np.matmul(Us[k], Us[l].T, out=other)
                prod *= other
                target += prod
                if target is buf:
                    if k == l:
                        acc += buf
                    else:
                        off += buf
        if off is not None:
            acc += off
            acc += off.T
        acc *= 2.0
        return acc  # a work buffer: valid until the next call

    def apply_scaled(self, sc: dict[str, Any], u: np.ndarray) -> np.ndarray:
        """``L' (sum_j u_j F_j) L`` from the scaled data, as CVXOPT's solvers form ``W^{-T} G u``
        (scaling before the sum: the unscaled sum's rounding, amplified by ``L``, would cost
        the last digits the final iterations need)."""
        S = np.zeros((self.d, self.d))
        if self.T:
            un = u[self.narrow]
            for U, V in zip(sc["U"], sc["V"], strict=True):
                S += (U.T * un) @ V.T
            S += S.T
        for j, M in zip(self.wide, sc["M"], strict=True):
            S += u[j] * M
        return S


def _narrow_limit(size: np.ndarray, d: int, nnz: int) -> int:
    """The largest cover size handled by the cross formula: the one that minimises the
    estimated work ``(count * s)^2 d`` of the narrow variables plus ``2 d^3 + nnz / n`` per wide
    one (a few wide variables, e.g. ``gamma I``, would pad every narrow one)."""
    sizes = np.unique(size[size > 0])
    if not len(sizes):
        return 0
    per_wide = 2.0 * d**3 + nnz / max(len(size), 1)
    best, limit = np.inf, 0
    for s in sizes:
        count = int(np.count_nonzero((size > 0) & (size <= s)))
        work = float(count * s) ** 2 * d + (np.count_nonzero(size > s)) * per_wide
        if work < best:
            best, limit = work, int(s)
    return limit


def _sym_lower(v: np.ndarray, d: int) -> np.ndarray:
    """The symmetric matrix whose lower triangle is that of the column-major vector ``v``."""
    M = v.reshape(d, d, order="F")
    L = np.tril(M)
    return L + np.tril(M, -1).T


def structured_cost(G: list[sp.spmatrix], dims: list[int], n: int) -> tuple[float, float, list[_Block]]:
    """Per-iteration flop estimates ``(structured, chol)`` of the Schur complement, and the
    analysed blocks: ``T^2 d + d^2 T`` plus ``2 d^3`` and a trace product per wide variable,
    against CVXOPT's ``n^2 d^2 / 2 + n d^3``, summed over blocks; ``(inf, chol, [])`` when a
    lower bound of the first already loses by :data:`STRUCTURED_MARGIN` (no cover searched).

    >>> import numpy as np, scipy.sparse as sp
    >>> G = sp.csc_matrix(np.array([[1.0], [0.0], [0.0], [1.0]]))
    >>> s, c, _ = structured_cost([G], [2], 1)
    >>> s > 0 and c > 0
    True
    """
    theirs = float(sum(n**2 * d**2 / 2 + n * d**3 for d in dims))
    # a cover row covers at most 2 d stored entries, so T >= nnz / (2 d) whatever the cover: when
    # even that bound loses, no cover is searched (the greedy costs a pass over the entries per
    # round; dense coefficients would take up to d / 4 rounds)
    bound = sum((g.nnz / (2.0 * d)) ** 2 * d for g, d in zip(G, dims, strict=True) if d)
    if STRUCTURED_MARGIN * bound >= theirs:
        return float("inf"), theirs, []
    blocks = [_Block(g, d, n) for g, d in zip(G, dims, strict=True)]
    return float(sum(b.cost for b in blocks)), theirs, blocks


#: the structured solver replaces CVXOPT's 'chol' when its per-iteration estimate times this
#: is below 'chol''s (bounded-real lemma, 40 states: 1.5e8 against 1.3e9; 39 ms against 93 ms
#: per factorisation)
STRUCTURED_MARGIN = 2.0


def worth_it(problem: Any, data: Any = None) -> bool:
    """Whether CVXOPT should use the structured solver on ``problem`` (:data:`STRUCTURED_MARGIN`,
    :data:`STRUCTURED_MIN_WORK`).

    >>> from lmic.testing.conformance import bounded_real_problem
    >>> import numpy as np
    >>> A = lambda n: -np.eye(n) + np.diag(np.ones(n - 1), 1)
    >>> [worth_it(bounded_real_problem(A(n), np.ones((n, 1)), np.ones((1, n)))) for n in (3, 24)]
    [False, True]
    """
    if not problem.lmis:
        return False
    ours, theirs, _ = analyse(problem, data)
    return theirs >= STRUCTURED_MIN_WORK and STRUCTURED_MARGIN * ours < theirs


#: factorisations after which the QR-based solver takes over (CVXOPT converges in 15 to 30
#: iterations on the bounded-real lemma and the shipped theorems; near 1e-8 the normal
#: equations' rounding can stall it: ``uncertain_dt.thm1`` n = 8 stalled at gap 2e-8 for 80
#: iterations before this limit)
MAX_STRUCTURED_ITERATIONS = 35


#: refinement steps of each KKT solve against the true operator (:meth:`StructuredKKT._structured`)
REFINEMENT_STEPS = 2
#: ... none needed below this relative residual
REFINED = 1e-11
#: a solve left above this relative residual after its refinement hands the next
#: factorisations to CVXOPT's QR solver (``uncertain_dt.thm1`` n = 6: the directions lost
#: accuracy from iteration 21, and the run stalled at gap 4e-8 until the iteration cap).
#: Measured: 1e-6 and above let that run stall again; 1e-7 hands over later (bounded-real
#: lemma n = 40: after 15 factorisations, 1.27 s, against 13 and 1.41 s at 1e-9); 1e-8 keeps a
#: factor of 100 from the stall
INACCURATE = 1e-8


#: ... and only where 'chol''s estimate is at least this (a few ms per iteration): below it the
#: per-iteration overhead of the structured solver (and its refinement) is not repaid. Measured
#: whole CVXOPT solves, structured against 'chol' then 'qr' (lmic's previous default): SDPLIB
#: control2 (1.7e6) 0.108 against 0.096 s, hinf1 (1e4) 0.101 against 0.043 s, a 16-state
#: bounded-real lemma (7.8e6) 0.049 against 0.035 s; 20 states (2.6e7) 0.101 against 0.215 s,
#: 30 states (2.5e8) 0.317 against 1.00 s, uir.thm4_1 n = 12 (2e8) 0.158 against 0.345 s
STRUCTURED_MIN_WORK = 2e7


_ANALYSES: dict[int, tuple[Any, tuple[float, float, list[_Block]]]] = {}


def analyse(problem: Any, data: Any = None) -> tuple[float, float, list[_Block]]:
    """:func:`structured_cost` of a problem's LMI-form data (:class:`~lmic.backends.lowering.LMIForm`,
    CVXOPT's sign), computed once per problem object (the route rule and the backend share it;
    ``data``: the backend's lowering of it, not made again).

    >>> from lmic.testing.conformance import bounded_real_problem
    >>> import numpy as np
    >>> ours, theirs, _ = analyse(bounded_real_problem(-np.eye(3), np.ones((3, 1)), np.ones((1, 3))))
    >>> ours < theirs
    True
    """
    import weakref

    from lmic.backends.lowering import LMIForm

    key = id(problem)
    hit = _ANALYSES.get(key)
    if hit is not None and hit[0]() is problem:
        return hit[1]
    data = LMIForm.apply(problem) if data is None else data
    result = structured_cost([-g for g in data.G], data.dims, problem.n)

    def forget(_ref: Any, key: int = key) -> None:
        _ANALYSES.pop(key, None)

    _ANALYSES[key] = (weakref.ref(problem, forget), result)
    return result


class StructuredKKT:
    """CVXOPT ``kktsolver`` from the cross structure (module docstring) of ``conelp``'s data.

    Parameters
    ----------
    G : list of scipy sparse ``(d_k^2, n)``
        The 's' blocks of CVXOPT's ``G`` (column-major, only the lower triangle is read).
    Gl : scipy sparse ``(ml, n)``
        The 'l' rows of ``G``.
    A : scipy sparse ``(p, n)``
        The equality rows.
    dims : list of int
        The orders of the PSD blocks.
    blocks : list, optional
        Blocks prepared by :func:`structured_cost` (not prepared again).

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> G = sp.csc_matrix(np.array([[1.0], [0.0], [0.0], [1.0]]))
    >>> StructuredKKT([G], sp.csc_matrix((0, 1)), sp.csc_matrix((0, 1)), [2]).n
    1
    """

    def __init__(
        self,
        G: list[sp.spmatrix],
        Gl: sp.spmatrix,
        A: sp.spmatrix,
        dims: list[int],
        blocks: list[_Block] | None = None,
    ) -> None:
        self.n = int(Gl.shape[1])
        self.blocks = blocks if blocks is not None else [_Block(g, d, self.n) for g, d in zip(G, dims, strict=True)]
        for b in self.blocks:
            b.build()
        self.Gl = sp.csr_matrix(Gl)
        self.A = np.asarray(sp.csr_matrix(A).toarray())
        self.ml, self.p = int(Gl.shape[0]), int(self.A.shape[0])
        if self.p:
            self.QA, RA = np.linalg.qr(self.A.T, mode="complete")
            self.RA = RA[: self.p]
        self.T = sum(b.T for b in self.blocks)
        self.wide_count = sum(len(b.wide) for b in self.blocks)
        #: factorisations so far, and the one from which CVXOPT's QR solver took over (or None)
        self.iterations = 0
        self.fallback_from: int | None = None
        self._work: list[list[np.ndarray]] = [[] for _ in self.blocks]
        self._qr: Any = None

    @property
    def qr_tail(self) -> int:
        """Factorisations made by CVXOPT's QR solver after the hand-over (0 without one)."""
        return 0 if self.fallback_from is None else self.iterations - self.fallback_from

    def __call__(self, W: dict[str, Any]) -> Any:
        """Factor the KKT system of the scaling ``W``; return the solve ``f(x, y, z)``.

        Once the Schur complement is numerically indefinite (near the optimum of a degenerate
        problem: the scaling's condition number passes 1e12), or after
        :data:`MAX_STRUCTURED_ITERATIONS` (an interior-point run that has not converged by then
        is stalling on the normal equations' rounding), this and every later iteration use
        CVXOPT's own QR-based solver on the same data (``misc.kkt_qr``, which never forms the
        Schur complement): the fast iterations first, the stable ones at the end.
        """
        if self.fallback_from is None and self.iterations >= MAX_STRUCTURED_ITERATIONS:
            self.fallback_from = self.iterations  # stalled: the last digits need the stable solver
        if self.fallback_from is None:
            try:
                return self._structured(W)
            except ArithmeticError:
                self.fallback_from = self.iterations
        self.iterations += 1
        if self._qr is None:
            self._qr = self._qr_factory()
        return self._qr(W)

    def _qr_factory(self) -> Any:
        """CVXOPT's ``misc.kkt_qr`` on the dense ``G = [Gl; G_s ...]`` and ``A``."""
        import cvxopt
        from cvxopt import misc

        rows = [self.Gl.toarray()] + [b.G.toarray() for b in self.blocks]
        G = cvxopt.matrix(np.vstack(rows) if rows else np.zeros((0, self.n)))
        A = cvxopt.matrix(self.A if self.p else np.zeros((0, self.n)))
        dims = {"l": self.ml, "q": [], "s": [b.d for b in self.blocks]}
        return misc.kkt_qr(G, dims, A)

    def _structured(self, W: dict[str, Any]) -> Any:
        """The structured factorisation (``ArithmeticError`` when the Cholesky fails)."""
        n, p, ml = self.n, self.p, self.ml
        di = np.array(W["di"], dtype=float).ravel() if ml else np.zeros(0)
        rti = [np.array(r, dtype=float) for r in W["rti"]]
        scs = [b.scaled(L) for b, L in zip(self.blocks, rti, strict=True)]
        H = np.zeros((n, n))
        for b, sc, work in zip(self.blocks, scs, self._work, strict=True):
            b.schur(sc, H, work)
        if ml:
            Gd = sp.diags(di) @ self.Gl
            H += np.asarray((Gd.T @ Gd).toarray())
        if p:
            K = self.QA.T @ H @ self.QA
            K22 = K[p:, p:]
        else:
            K = H
            K22 = H
        factor = _cholesky(K22) if len(K22) else None
        self.iterations += 1
        offsets = np.cumsum([0] + [b.d**2 for b in self.blocks])

        def reduced(rx: np.ndarray, ry: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            """``[[H, A'], [A, 0]] [ux; uy] = [rx; ry]`` by the factorisation (QR of ``A'``)."""
            if p:
                xq = self.QA.T @ rx
                v = sla.solve_triangular(self.RA, ry, trans="T")
                w = sla.cho_solve(factor, xq[p:] - K[p:, :p] @ v) if factor is not None else np.zeros(0)
                uy = sla.solve_triangular(self.RA, xq[:p] - K[:p, :p] @ v - K[:p, p:] @ w)
                return self.QA @ np.concatenate([v, w]), uy
            return (sla.cho_solve(factor, rx) if factor is not None else rx.copy()), np.zeros(0)

        def schur_times(u: np.ndarray) -> np.ndarray:
            """``H u`` from the scaled data, without the formed ``H``."""
            out = np.zeros(n)
            for b, sc in zip(self.blocks, scs, strict=True):
                b.rhs(sc, b.apply_scaled(sc, u), out)
            if ml:
                out += self.Gl.T @ (di * di * (self.Gl @ u))
            return out

        def solve(x: Any, y: Any, z: Any) -> None:
            bx = np.array(x, dtype=float).ravel()
            bz = np.array(z, dtype=float).ravel()
            rhs = bx.copy()
            Bs = []  # W^{-T} bz, block by block
            for k, (b, L, sc) in enumerate(zip(self.blocks, rti, scs, strict=True)):
                B = L.T @ _sym_lower(bz[ml + offsets[k] : ml + offsets[k + 1]], b.d) @ L
                Bs.append(B)
                b.rhs(sc, B, rhs)  # G' W^{-1} W^{-T} bz
            if ml:
                rhs += self.Gl.T @ (di * di * bz[:ml])
            by = np.array(y, dtype=float).ravel() if p else np.zeros(0)
            ux, uy = reduced(rhs, by)
            # iterative refinement against the true operator (from the scaled data: H is
            # formed with rounding that grows with the scaling's condition number)
            for step in range(REFINEMENT_STEPS + 1):
                Hu = schur_times(ux)
                rx = rhs - Hu - (self.A.T @ uy if p else 0.0)
                ry = by - self.A @ ux if p else np.zeros(0)
                size = float(np.linalg.norm(rhs) + np.linalg.norm(Hu) + np.linalg.norm(by)) or 1.0
                err = float(max(np.linalg.norm(rx), np.linalg.norm(ry) if p else 0.0)) / size
                if err <= REFINED or step == REFINEMENT_STEPS:
                    break
                dx, dy = reduced(rx, ry)
                ux, uy = ux + dx, uy + dy
            if err > INACCURATE and self.fallback_from is None:
                self.fallback_from = self.iterations  # the next factorisations: CVXOPT's QR
            if p:
                y[:] = _cvx(uy)
            out = np.empty_like(bz)
            if ml:
                out[:ml] = di * (self.Gl @ ux - bz[:ml])
            for k, (b, B, sc) in enumerate(zip(self.blocks, Bs, scs, strict=True)):
                out[ml + offsets[k] : ml + offsets[k + 1]] = (b.apply_scaled(sc, ux) - B).ravel(order="F")
            x[:] = _cvx(ux)
            z[:] = _cvx(out)

        return solve


def _cholesky(K: np.ndarray) -> Any:
    """``cho_factor`` of ``K``; ``ArithmeticError`` when it is not numerically positive definite."""
    if not np.all(np.isfinite(K)):
        raise ArithmeticError("Schur complement is not finite")
    try:
        return sla.cho_factor(K, lower=True, check_finite=False)
    except np.linalg.LinAlgError as exc:
        raise ArithmeticError("Schur complement not positive definite") from exc


def _cvx(v: np.ndarray) -> Any:
    """A CVXOPT column matrix of ``v``."""
    import cvxopt

    return cvxopt.matrix(np.ascontiguousarray(v, dtype=float).reshape(-1, 1))
