"""Lowering: a closed IR problem to a solver's data, and the solver's answer back (apply/invert).

Two forms, each with an ``apply`` (problem -> data) and an ``invert`` (native dual vector or
blocks -> the IR's multipliers ``{"lmis": [Z_i], "linear": y}``):

* :class:`SForm`: the stacked form ``A x + s = b``, ``s`` in ``{0}^eq x R+^ge x PSD_1 x ...``
  shared by Clarabel and SCS (:func:`conic_data`); each backend passes its own PSD
  vectorisation ``(perm, scale)`` (:mod:`lmic.ir.svec`), the one conversion place.
* :class:`LMIForm`: the LMI form ``F0 + sum x_k F_k >= 0`` with full column-major ``d*d``
  blocks (:func:`full_vec_map`, :func:`full_vec_coo`) and the linear rows split into equalities
  and inequalities: CVXOPT, SDPA, CVXPY and PICOS.

Everything is built with numpy/scipy.sparse index arithmetic: there is no loop over entries,
only over blocks (``benchmarks/lowering.py`` measures it). Both forms share one split of the
linear rows (:func:`split_rows`).

Examples
--------
>>> from lmic.testing.conformance import CASES
>>> p = CASES["max_sense"].build()
>>> data = SForm(lambda d: (np.arange(d * (d + 1) // 2), np.ones(d * (d + 1) // 2))).apply(p)
>>> data.A.shape[1] == p.n
True
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.sparse as sp

from lmic.ir.problem import LinearConstraints, Problem
from lmic.ir.svec import tril_rows_cols, tril_size

__all__ = [
    "problem_kinds",
    "has_strict",
    "split_rows",
    "objective_vector",
    "ConicData",
    "conic_data",
    "SForm",
    "LMIData",
    "LMIForm",
    "full_vec_map",
    "full_vec_coo",
    "psd_unvec",
]

#: ``psd_vec(d) -> (perm, scale)``: a solver's vectorisation of a ``d x d`` block,
#: ``native = scale * tril_storage[perm]``
PsdVec = Callable[[int], tuple[np.ndarray, np.ndarray]]


def problem_kinds(problem: Problem) -> set[str]:
    """The constraint kinds a problem uses: a subset of ``{"lmi", "eq", "ge"}``.

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("t", "scalar", (1, 1))], [LMI("t>0", 1, sp.csc_matrix([[0., 1.]]))],
    ...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
    >>> sorted(problem_kinds(p))
    ['lmi']
    """
    kinds = {"lmi"} if problem.lmis else set()
    kinds.update(problem.linear.kinds)
    return kinds


def has_strict(problem: Problem) -> bool:
    """True when some LMI or linear row is strict.

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("p", "scalar", (1, 1))], [LMI("p>=0", 1, sp.csc_matrix([[0., 1.]]),
    ...             strict=False)], LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
    >>> has_strict(p)
    False
    """
    return any(lmi.strict for lmi in problem.lmis) or any(problem.linear.strict)


def split_rows(linear: LinearConstraints) -> tuple[np.ndarray, np.ndarray]:
    """Indices of the equality and the inequality rows (the one eq/ge split of every backend).

    >>> split_rows(LinearConstraints(sp.csr_matrix(np.ones((3, 2))), ["ge", "eq", "ge"], [False] * 3, list("abc")))
    (array([1]), array([0, 2]))
    """
    if not len(linear):
        return np.zeros(0, dtype=int), np.zeros(0, dtype=int)
    kinds = np.asarray(linear.kinds, dtype=object)
    return np.flatnonzero(kinds == "eq"), np.flatnonzero(kinds == "ge")


def objective_vector(problem: Problem) -> tuple[np.ndarray, float, float]:
    """``(c, c0, sign)`` of the objective in the minimisation sense (zeros for feasibility).

    >>> from lmic.testing.conformance import CASES
    >>> c, c0, sign = objective_vector(CASES["max_sense"].build())
    >>> sign
    -1.0
    """
    obj = problem.objective
    sign = -1.0 if obj.sense == "max" else 1.0
    if obj.sense == "feasibility":
        return np.zeros(problem.n), 0.0, sign
    return np.asarray(sign * obj.c[1:], dtype=float), sign * float(obj.c[0]), sign


@functools.lru_cache(maxsize=64)
def _tril_rows_cols(d: int) -> tuple[np.ndarray, np.ndarray]:
    i, j = tril_rows_cols(d)
    i.setflags(write=False)
    j.setflags(write=False)
    return i, j


def _row_mults(z: np.ndarray, eq: np.ndarray, ge: np.ndarray, n_rows: int) -> np.ndarray:
    y = np.zeros(n_rows)
    y[eq] = z[: len(eq)]
    y[ge] = z[len(eq) : len(eq) + len(ge)]
    return y


# -- the s-form: A x + s = b ----------------------------------------------------------------------
@dataclass
class ConicData:
    """``min c . x`` (plus ``c0``) subject to ``A x + s = b``, ``s`` in the cone ``dims``.

    Attributes
    ----------
    A : scipy.sparse.csc_matrix
    b, c : numpy.ndarray
    c0 : float
        Constant of the objective (in the minimisation sense).
    sign : float
        ``+1`` when the IR minimises (or is a feasibility problem), ``-1`` when it maximises.
    n_eq, n_ge : int
        Numbers of equality and inequality rows (first ``n_eq`` rows, then ``n_ge``).
    psd : list of int
        LMI dimensions, in IR order.
    eq_rows, ge_rows : numpy.ndarray
        Indices of the IR's linear rows placed in each block.
    """

    A: sp.csc_matrix
    b: np.ndarray
    c: np.ndarray
    c0: float
    sign: float
    n_eq: int
    n_ge: int
    psd: list[int]
    eq_rows: np.ndarray
    ge_rows: np.ndarray

    @property
    def psd_offsets(self) -> list[int]:
        """Row where each PSD block starts."""
        off, out = self.n_eq + self.n_ge, []
        for d in self.psd:
            out.append(off)
            off += tril_size(d)
        return out


#: one block's variable columns in CSC layout: ``(indptr, rows, values)`` (``indptr`` from 0)
_Part = tuple[np.ndarray, np.ndarray, np.ndarray]


def _split_const(
    M: sp.spmatrix, row_of: np.ndarray | None = None, scale: np.ndarray | None = None, keep: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray, _Part]:
    """A CSC block ``[m0 | M_x]``: its constant column as ``(rows, values)`` and its variable columns.

    Rows are moved to ``row_of`` and scaled by ``scale`` (both indexed by the block's own rows);
    with ``keep`` (a mask over the block's rows), only those entries are taken.
    """
    M = M if M.format == "csc" else M.tocsc()
    if not M.has_sorted_indices:
        M = M.sorted_indices()
    ip, rows, vals = M.indptr, M.indices, M.data
    if keep is not None:
        mask = keep[rows]
        ip = np.concatenate([[0], np.cumsum(mask)])[ip]
        rows, vals = rows[mask], vals[mask]
    moved = rows if row_of is None else row_of[rows]
    if scale is not None:
        scaled = scale[rows]  # one new array, scaled in place (not a gather and a product)
        vals = np.multiply(scaled, vals, out=scaled)
    s0, s1 = int(ip[0]), int(ip[1])
    return moved[s0:s1], vals[s0:s1], (ip[1:] - s1, moved[s1:], vals[s1:])


def _assemble(parts: list[_Part], n_rows: int, n_cols: int, sign: float = 1.0, order: str = "sort") -> sp.csc_matrix:
    """The CSC matrix whose column ``j`` is the concatenation of every part's column ``j``.

    Placed by index arithmetic on the ``indptr`` arrays (no COO round trip). ``order``: ``"sort"``
    sorts the rows within each column (Clarabel requires it); ``"sorted"`` when the caller knows
    they already are (parts in increasing disjoint row ranges, each sorted); ``"any"`` leaves
    them unsorted (marked so) where it does not matter.
    """
    nnz = sum(len(rows) for _, rows, _ in parts)
    # scipy's own index type (int32 where it fits): no conversion copy in the constructor
    idx: type[np.signedinteger[Any]] = np.int32 if max(n_rows, nnz) < np.iinfo(np.int32).max else np.int64
    filled = [part for part in parts if len(part[1])]
    if len(filled) == 1:  # one block holds every entry: it is the matrix
        ip, rows, vals = filled[0]
        indptr, indices, data = ip.astype(idx), rows.astype(idx), sign * vals
    else:
        counts: np.ndarray = np.array([np.diff(ip) for ip, _, _ in parts], dtype=idx).reshape(len(parts), n_cols)
        indptr = np.concatenate([[0], np.cumsum(counts.sum(axis=0))]).astype(idx)
        indices = np.empty(nnz, dtype=idx)
        data = np.empty(nnz)
        before: np.ndarray = np.cumsum(counts, axis=0, dtype=idx) - counts  # entries of earlier parts in each column
        for k, (ip, rows, vals) in enumerate(parts):
            if not len(rows):
                continue
            start = indptr[:-1] + before[k] - ip[:-1].astype(idx)  # destination minus source, per column
            dest = np.repeat(start, counts[k]) + np.arange(len(rows), dtype=idx)
            indices[dest] = rows
            data[dest] = sign * vals
    if not filled:
        indptr, indices, data = np.zeros(n_cols + 1, dtype=idx), np.zeros(0, dtype=idx), np.zeros(0)
    A = sp.csc_matrix((data, indices, indptr), shape=(n_rows, n_cols))
    A.has_sorted_indices = order == "sorted"
    if order == "sort":
        A.sort_indices()
    return A


def _stack_sorted(parts: list[_Part], heights: list[int], n_cols: int, sign: float = 1.0) -> sp.csc_matrix:
    """The CSC matrix of the parts stacked vertically, each with its own (sorted) rows.

    scipy's stacking of CSC blocks along rows (one compiled pass, :func:`scipy.sparse.vstack`)
    instead of index arithmetic; ``sign`` is applied in place on the result.

    >>> p = (np.array([0, 1, 1]), np.array([0]), np.array([2.0]))
    >>> _stack_sorted([p, p], [1, 2], 2, -1.0).toarray()
    array([[-2.,  0.],
           [-2.,  0.],
           [ 0.,  0.]])
    """
    n_rows = int(sum(heights))
    idx: type[np.signedinteger[Any]] = (
        np.int32 if max(n_rows, sum(len(p[1]) for p in parts)) < np.iinfo(np.int32).max else np.int64
    )
    blocks = []
    for (ip, rows, vals), h in zip(parts, heights, strict=True):
        M = sp.csc_matrix((vals, rows.astype(idx, copy=False), ip.astype(idx, copy=False)), shape=(h, n_cols))
        M.has_sorted_indices = True
        blocks.append(M)
    if not blocks:
        return sp.csc_matrix((0, n_cols))
    A = sp.csc_matrix(sp.vstack(blocks, format="csc")) if len(blocks) > 1 else blocks[0].copy()
    if sign != 1.0:
        np.multiply(A.data, sign, out=A.data)
    A.has_sorted_indices = True
    return A


def conic_data(problem: Problem, psd_vec: PsdVec) -> ConicData:
    """Stack a closed problem as ``A x + s = b`` with ``s`` in ``{0} x R+ x PSD...``.

    Parameters
    ----------
    problem : Problem
        A problem without strict constraints (strictness is ignored here).
    psd_vec : callable
        ``psd_vec(d) -> (perm, scale)``: the solver's vectorisation of a ``d x d`` block,
        ``native = scale * tril_storage[perm]`` (from :mod:`lmic.ir.svec`).

    Each LMI ``F0 + sum x_k F_k >= 0`` becomes ``s = F(x)``: ``b = vec(F0)``, ``A = -vec(F_k)``.

    Examples
    --------
    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("t", "scalar", (1, 1))], [LMI("t>=1", 1, sp.csc_matrix([[-1., 1.]]))],
    ...             LinearConstraints.empty(1), Objective("min", [0, 1]))
    >>> data = conic_data(p, lambda d: (np.arange(d * (d + 1) // 2), np.ones(d * (d + 1) // 2)))
    >>> data.A.toarray(), data.b
    (array([[-1.]]), array([-1.]))
    """
    lin = problem.linear
    eq_rows, ge_rows = split_rows(lin)
    b_rows, b_vals, parts, heights = [], [], [], []
    offset = 0
    ordered_rows = True  # each part's rows increase within a column (then parts stack in order)
    if len(lin):
        ordered = lin.A if not len(eq_rows) or not len(ge_rows) else lin.A[np.concatenate([eq_rows, ge_rows])]
        r, v, part = _split_const(ordered)
        b_rows.append(r)
        b_vals.append(v)
        parts.append(part)
        heights.append(len(lin))
        offset = len(lin)
    for lmi in problem.lmis:
        native, scale = _native_rows(psd_vec, lmi.dim)
        ordered_rows &= _increasing(native)
        same = bool(len(native) == 0 or (native[0] == 0 and native[-1] == len(native) - 1 and _increasing(native)))
        r, v, part = _split_const(lmi.coeffs, None if same else native, scale)  # the block's own rows
        b_rows.append(r + offset)
        b_vals.append(v)
        parts.append(part)
        heights.append(len(native))
        offset += len(native)
    b = np.zeros(offset)
    if b_rows:
        np.add.at(b, np.concatenate(b_rows), np.concatenate(b_vals))
    if ordered_rows:
        A = _stack_sorted(parts, heights, problem.n, sign=-1.0)
    else:
        starts = np.concatenate([[0], np.cumsum(heights)]).astype(np.int64)
        moved = [(ip, rows + int(off), vals) for (ip, rows, vals), off in zip(parts, starts, strict=False)]
        A = _assemble(moved, offset, problem.n, sign=-1.0, order="sort")
    c, c0, sign = objective_vector(problem)
    return ConicData(
        A=A,
        b=b,
        c=c,
        c0=c0,
        sign=sign,
        n_eq=len(eq_rows),
        n_ge=len(ge_rows),
        psd=[lmi.dim for lmi in problem.lmis],
        eq_rows=eq_rows,
        ge_rows=ge_rows,
    )


def _increasing(a: np.ndarray) -> bool:
    return bool(np.all(a[1:] > a[:-1]))


def _native_rows(psd_vec: PsdVec, d: int) -> tuple[np.ndarray, np.ndarray]:
    """Native row of each storage row (``perm``'s inverse) and its scale, for one ``d x d`` block."""
    perm, scale = psd_vec(d)
    native = np.empty(len(perm), dtype=np.int32 if len(perm) < np.iinfo(np.int32).max else np.int64)
    native[perm] = np.arange(len(perm))
    return native, np.asarray(scale)[native]


def psd_unvec(psd_vec: PsdVec, v: np.ndarray, d: int) -> np.ndarray:
    """Dense symmetric matrix from one native PSD block (the inverse of ``psd_vec``).

    >>> psd_unvec(lambda d: (np.arange(3), np.array([1.0, 2.0, 1.0])), np.array([1.0, 4.0, 3.0]), 2)
    array([[1., 2.],
           [2., 3.]])
    """
    perm, scale = psd_vec(d)
    storage = np.empty(len(perm))
    storage[perm] = np.asarray(v, dtype=float) / scale
    i, j = _tril_rows_cols(d)
    M = np.empty((d, d))
    M[i, j] = storage
    M[j, i] = storage
    return M


@dataclass(frozen=True)
class SForm:
    """The s-form lowering of one solver: ``apply`` builds :class:`ConicData`, ``invert`` reads duals.

    >>> from lmic.testing.conformance import CASES
    >>> p = CASES["max_sense"].build()
    >>> form = SForm(lambda d: (np.arange(d * (d + 1) // 2), np.ones(d * (d + 1) // 2)))
    >>> data = form.apply(p)
    >>> form.invert(data, np.zeros(data.A.shape[0]), len(p.linear))["linear"].shape == (len(p.linear),)
    True
    """

    psd_vec: PsdVec

    def apply(self, problem: Problem) -> ConicData:
        """:func:`conic_data` with this solver's vectorisation."""
        return conic_data(problem, self.psd_vec)

    def invert(self, data: ConicData, z: np.ndarray, n_rows: int) -> dict[str, Any]:
        """IR-shaped ``{"lmis": [Z_i], "linear": y}`` from a stacked dual (or ray) vector ``z``."""
        z = np.asarray(z, dtype=float).ravel()
        y = _row_mults(z, data.eq_rows, data.ge_rows, n_rows)
        mats = [
            psd_unvec(self.psd_vec, z[off : off + tril_size(d)], d)
            for off, d in zip(data.psd_offsets, data.psd, strict=True)
        ]
        return {"lmis": mats, "linear": y}


# -- the LMI form: F0 + sum x_k F_k >= 0, full column-major blocks -------------------------------
def full_vec_map(d: int) -> sp.csr_matrix:
    """Sparse ``E`` (``d*d x tril_size(d)``) with ``vec(M) = E @ tril_storage(M)`` (column-major).

    >>> full_vec_map(2).toarray()
    array([[1., 0., 0.],
           [0., 1., 0.],
           [0., 1., 0.],
           [0., 0., 1.]])
    """
    i, j = _tril_rows_cols(d)
    k = np.arange(len(i))
    off = i != j
    rows = np.concatenate([i + j * d, (j + i * d)[off]])
    cols = np.concatenate([k, k[off]])
    return sp.csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(d * d, len(i)))


def full_vec_coo(lmi: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(row, col, value)`` of ``full_vec_map(d) @ lmi.coeffs`` without a sparse product.

    Storage entry ``(i, j)`` of column ``k`` goes to rows ``i + j d`` and, off the diagonal,
    ``j + i d`` of the column-major ``d*d`` vectorisation (CVXOPT's and SDPA's form).

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI
    >>> row, col, val = full_vec_coo(LMI("F", 2, sp.csc_matrix([[1.0], [2.0], [3.0]])))
    >>> row.tolist(), col.tolist(), val.tolist()
    ([0, 1, 3, 2], [0, 0, 0, 0], [1.0, 2.0, 3.0, 2.0])
    """
    d = lmi.dim
    i, j = _tril_rows_cols(d)
    C = lmi.coeffs.tocoo()
    ii, jj = i[C.row], j[C.row]
    off = ii != jj
    row = np.concatenate([ii + jj * d, (jj + ii * d)[off]])
    col = np.concatenate([C.col, C.col[off]])
    val = np.concatenate([C.data, C.data[off]])
    return row, col, val


@functools.lru_cache(maxsize=64)
def _full_vec_rows(d: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per storage entry ``(i, j)``: its rows ``i + j d`` and ``j + i d``, and whether it is off the diagonal."""
    i, j = _tril_rows_cols(d)
    out = (i + j * d, j + i * d, i != j)
    for a in out:
        a.setflags(write=False)
    return out


def _full_vec_csc(lmi: Any, sort: bool = False) -> tuple[np.ndarray, sp.csc_matrix]:
    """``full_vec_map(d) @ lmi.coeffs`` split: the dense constant ``d*d`` vector and the ``d*d x n`` block.

    Built from the CSC coefficients by index arithmetic (each off-diagonal entry twice), no
    sparse product and no COO round trip.
    """
    d = lmi.dim
    lower, upper, off = _full_vec_rows(d)
    r1, v1, p1 = _split_const(lmi.coeffs, lower)
    r2, v2, p2 = _split_const(lmi.coeffs, upper, keep=off)
    F0 = np.zeros(d * d)
    np.add.at(F0, np.concatenate([r1, r2]), np.concatenate([v1, v2]))
    return F0, _assemble([p1, p2], d * d, lmi.coeffs.shape[1] - 1, order="sort" if sort else "any")


@dataclass
class LMIData:
    """A closed problem in LMI form: per LMI ``vec F(x) = F0 + G x`` (full column-major ``d*d``).

    Attributes
    ----------
    F0 : list of numpy.ndarray
        Constant blocks as dense ``d x d`` matrices.
    G : list of scipy.sparse.csc_matrix
        ``d*d x n`` coefficient blocks: ``vec F(x) = vec F0 + G x``.
    eq, ge : numpy.ndarray
        IR row indices of the equality and inequality rows.
    A_eq, A_ge : scipy.sparse.csc_matrix
        Their rows ``[a0 | a]`` (``a0 + a x == 0`` / ``>= 0``).
    c, c0, sign
        The objective in the minimisation sense (:func:`objective_vector`).
    """

    F0: list[np.ndarray]
    G: list[sp.csc_matrix]
    eq: np.ndarray
    ge: np.ndarray
    A_eq: sp.csc_matrix
    A_ge: sp.csc_matrix
    c: np.ndarray
    c0: float
    sign: float
    n_rows: int
    dims: list[int] = field(default_factory=list)


class LMIForm:
    """The LMI-form lowering (CVXOPT, SDPA, CVXPY, PICOS): ``apply`` and ``invert``.

    >>> from lmic.testing.conformance import CASES
    >>> p = CASES["max_sense"].build()
    >>> data = LMIForm.apply(p)
    >>> [G.shape[0] for G in data.G] == [lmi.dim ** 2 for lmi in p.lmis]
    True
    """

    @staticmethod
    def apply(problem: Problem) -> LMIData:
        """The blocks ``F0``, ``G`` of every LMI and the split linear rows."""
        F0, G = [], []
        for lmi in problem.lmis:
            f0, g = _full_vec_csc(lmi)
            F0.append(f0.reshape(lmi.dim, lmi.dim, order="F"))
            G.append(g)
        lin = problem.linear
        eq, ge = split_rows(lin)
        A = lin.A.tocsr()
        A_eq = A if len(eq) == len(lin) else A[eq]
        A_ge = A if len(ge) == len(lin) else A[ge]
        c, c0, sign = objective_vector(problem)
        return LMIData(
            F0=F0,
            G=G,
            eq=eq,
            ge=ge,
            A_eq=A_eq.tocsc(),
            A_ge=A_ge.tocsc(),
            c=c,
            c0=c0,
            sign=sign,
            n_rows=len(lin),
            dims=[lmi.dim for lmi in problem.lmis],
        )

    @staticmethod
    def invert(data: LMIData, blocks: list[Any] | None, y_eq: Any = None, y_ge: Any = None) -> dict[str, Any]:
        """IR multipliers from native dense dual blocks and row multipliers (IR sign convention).

        ``blocks`` are symmetrised (``(Z + Z') / 2``); missing row multipliers are zeros.
        """
        y = np.zeros(data.n_rows)
        if y_eq is not None and len(data.eq):
            y[data.eq] = np.asarray(y_eq, dtype=float).ravel()
        if y_ge is not None and len(data.ge):
            y[data.ge] = np.asarray(y_ge, dtype=float).ravel()
        mats = [np.asarray(Z, dtype=float) for Z in (blocks or [])]
        return {"lmis": [0.5 * (Z + Z.T) for Z in mats], "linear": y}

    @staticmethod
    def invert_stacked(data: LMIData, xi: np.ndarray) -> dict[str, Any]:
        """IR multipliers from one stacked vector ``[y_eq; y_ge; vec Z_1; ...]`` (SDPA's primal)."""
        xi = np.asarray(xi, dtype=float).ravel()
        y = _row_mults(xi, data.eq, data.ge, data.n_rows)
        off = len(data.eq) + len(data.ge)
        mats = []
        for d in data.dims:
            Z = xi[off : off + d * d].reshape(d, d, order="F")
            mats.append(0.5 * (Z + Z.T))
            off += d * d
        return {"lmis": mats, "linear": y}
