"""The repair's least-norm step without its dense gradient, for large blocks with sparse coefficients.

A damped step of the dual repair (:func:`lmic.certify.enclosure_repair._repair`) moves a block
``Z = U U^T`` (plus a floor) to ``U (I + E) U^T``; ``E`` symmetric of order ``r`` (the rank of
``U``), parametrised by its upper triangle ``e``. The dual equalities are linear in ``e``: ``g =
G e`` with ``G_k,(a,b) = 2 B_k[a, b]`` (``a < b``) and ``B_k[a, a]``, ``B_k = U^T C_k U`` and
``C_k`` the symmetric coefficient matrix of row ``k`` (``g_k(Z) = <C_k, Z>``). The least-norm
step is ``e = G^T lambda`` with ``(G G^T) lambda = rho``.

Forming ``G`` costs ``n r (r + 1) / 2`` entries (SDPLIB maxG11: ``n = 800``, ``r = 800``: 2 GB,
and ``G G^T`` 2e11 flops per step). This module gives ``G G^T`` and ``G^T lambda`` without it:

* ``(G G^T)_kl = 2 <B_k, B_l> - sum_a B_k[a, a] B_l[a, a]`` and ``<B_k, B_l> = tr(C_k W C_l W)``
  (``W = U U^T``) ``= sum_{e in C_k, f in C_l} c_e c_f W[i_e, i_f] W[j_e, j_f]`` over the
  entries of ``C_k`` and ``C_l`` (both triangles): ``O(N^2)`` work for ``N`` coefficient
  entries (:func:`gram`), in chunks of bounded memory;
* ``G^T lambda`` is the upper triangle of ``2 B(lambda) - Diag(B(lambda))`` with ``B(lambda) =
  U^T (sum_k lambda_k C_k) U`` (:func:`step_matrix`), a sparse-dense product.

Both are the same numbers as the dense form's up to rounding; nothing here is a proof (the
proof of :mod:`lmic.certify.enclosure_float` decides on the repaired point).

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> from lmic.certify.enclosure_repair import _block_gradient
>>> rng = np.random.default_rng(0)
>>> d, n = 4, 3
>>> Jb = sp.random(n, d * (d + 1) // 2, density=0.5, random_state=1, format="csc")
>>> U = rng.standard_normal((d, d))
>>> ia, ib = np.triu_indices(d)
>>> G = _block_gradient(Jb, U, d, ia, ib)
>>> ent = entries(Jb, d)
>>> bool(np.allclose(gram(ent, U), G @ G.T))
True
>>> lam = rng.standard_normal(n)
>>> bool(np.allclose(step_matrix(ent, U, lam)[ia, ib], G.T @ lam))
True
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import scipy.sparse as sp

from lmic.ir.svec import tril_rows_cols

__all__ = ["Entries", "entries", "gram", "step_matrix", "dense_cost", "free_cost", "CHUNK_ENTRIES", "GATHER_RATE"]

#: the cost of a gathered pair product of :func:`gram` against a BLAS flop of the dense form's
#: ``G G^T`` (SDPLIB ss30, 11562 entries on a 294 x 294 block, 132 rows: the free form 3.5 s a
#: step for 5.3e8 pair products, the dense ``G G^T`` 7.5e8 flops in about 0.4 s; the support
#: form's measured ratio in :mod:`lmic.certify.enclosure_repair`, ``CONGRUENCE_RATE``, is 20 too)
GATHER_RATE = 20.0

#: entries of one chunk of :func:`gram`'s pair products (bounds its memory: 32 MB)
CHUNK_ENTRIES = 4_000_000


class Entries(NamedTuple):
    """The coefficient entries of one block's rows, both triangles: row ``k``, position
    ``(i, j)``, value ``c`` (``C_k[i, j]``), and the indicator ``S`` (``n x N``, ``S[k, e] = 1``
    when entry ``e`` belongs to row ``k``)."""

    k: np.ndarray
    i: np.ndarray
    j: np.ndarray
    c: np.ndarray
    S: sp.csr_matrix
    dim: int


def entries(Jb: sp.spmatrix, dim: int) -> Entries:
    """The entries of the symmetric ``C_k`` of a block's Jacobian columns ``Jb`` (``n x
    dim (dim + 1) / 2``, tril storage order; an off-diagonal column holds twice the entry).

    >>> import scipy.sparse as sp
    >>> e = entries(sp.csc_matrix([[1.0, 4.0, 3.0]]), 2)
    >>> e.i.tolist(), e.j.tolist(), e.c.tolist()
    ([0, 1, 0, 1], [0, 0, 1, 1], [1.0, 2.0, 2.0, 3.0])
    """
    coo = sp.coo_matrix(Jb)
    ri, ci = tril_rows_cols(dim)
    i, j = ri[coo.col], ci[coo.col]
    off = i != j
    val = np.where(off, 0.5 * coo.data, coo.data)
    k = np.concatenate([coo.row, coo.row[off]])
    ii = np.concatenate([i, j[off]])
    jj = np.concatenate([j, i[off]])
    c = np.concatenate([val, val[off]])
    order = np.lexsort((ii, jj, k))
    k, ii, jj, c = k[order], ii[order], jj[order], c[order]
    S = sp.csr_matrix((np.ones(k.size), (k, np.arange(k.size))), shape=(Jb.shape[0], k.size))
    return Entries(k, ii, jj, c, S, dim)


def dense_cost(n: int, r: int) -> float:
    """Flops of the dense form's ``G G^T`` (``n`` rows, ``r (r + 1) / 2`` columns).

    >>> dense_cost(800, 800)
    205056000000.0
    """
    return float(n) * float(n) * r * (r + 1) / 2.0


def free_cost(ent: Entries, r: int) -> float:
    """Flops of :func:`gram` and :func:`step_matrix` (the pair products, the diagonal term,
    the sparse-dense products).

    >>> import scipy.sparse as sp
    >>> free_cost(entries(sp.csc_matrix([[1.0, 0.0, 1.0]]), 2), 2)
    346.0
    """
    N, n = float(ent.c.size), float(ent.S.shape[0])
    return GATHER_RATE * 4.0 * N * N + n * n * r + 2.0 * N * r + 2.0 * ent.dim * r * r


def gram(ent: Entries, U: np.ndarray) -> np.ndarray:
    """``G G^T`` of the module docstring (``n x n``) from the entries and the factor ``U``.

    >>> import numpy as np, scipy.sparse as sp
    >>> gram(entries(sp.csc_matrix([[1.0, 0.0, 1.0]]), 2), np.eye(2)).tolist()
    [[2.0]]
    """
    n = ent.S.shape[0]
    out = np.zeros((n, n))
    N = ent.c.size
    if not N or not U.shape[1]:
        return out
    W = U @ U.T
    step = max(1, CHUNK_ENTRIES // max(1, N))
    for s0 in range(0, N, step):
        sl = slice(s0, s0 + step)
        # <B_k, B_l> summed over entry pairs: c_e c_f W[i_e, i_f] W[j_e, j_f]
        P = W[np.ix_(ent.i[sl], ent.i)] * W[np.ix_(ent.j[sl], ent.j)]
        P *= ent.c[sl, None]
        P *= ent.c[None, :]
        out += ent.S[:, sl] @ np.asarray(ent.S @ P.T).T
    # the diagonal term: D[k, a] = B_k[a, a] = sum_{e in k} c_e U[i_e, a] U[j_e, a]
    D = ent.S @ (ent.c[:, None] * U[ent.i] * U[ent.j])
    return 2.0 * out - D @ D.T


def step_matrix(ent: Entries, U: np.ndarray, lam: np.ndarray) -> np.ndarray:
    """The symmetric ``E`` whose upper triangle is ``G^T lambda``: ``2 B - Diag(B)``, ``B =
    U^T C(lambda) U``.

    >>> import numpy as np, scipy.sparse as sp
    >>> step_matrix(entries(sp.csc_matrix([[1.0, 4.0, 3.0]]), 2), np.eye(2), np.array([1.0])).tolist()
    [[1.0, 4.0], [4.0, 3.0]]
    """
    d = ent.dim
    C = sp.csr_matrix((ent.c * lam[ent.k], (ent.i, ent.j)), shape=(d, d))
    B = U.T @ np.asarray(C @ U)
    B = 0.5 * (B + B.T)
    E = 2.0 * B
    E[np.diag_indices_from(E)] = np.diag(B)
    return E
