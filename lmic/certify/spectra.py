"""One eigen-decomposition per LMI block and point, shared by every check of that point.

The fixed-margin point check of the strict reduction (:func:`lmic.reductions.strict.achieved_margin`
and :func:`~lmic.reductions.strict.verify_point`) and the certifier
(:func:`lmic.certify.check.lmi_report`) judge the same point on the same LMIs, one after the
other: :func:`block_spectrum` evaluates ``F(x)`` and its eigenvalues once and keeps the last few
results (keyed by the LMI object and the exact bytes of ``x``), so the later checks reuse them;
:func:`term_scale` (the certifier's ``T``) is kept with them.

What depends on the LMI's coefficients alone (the CSR copy, ``|C|``, the number of terms per
entry, the coefficient scale) is computed once per LMI object by :func:`prepared`. Both caches
hold the LMI object itself and check identity (``is``) on a hit, so an id reused by a new LMI
(a re-bind with other numbers) can never return another LMI's data; an LMI whose ``coeffs``
attribute was replaced is prepared again.

The term scale (the Perron root of ``|C| |x|``, an entrywise non-negative symmetric matrix) is
its largest eigenvalue: :func:`perron_root` takes it from ``eigvalsh`` (faster than a power
iteration, whose Collatz-Wielandt bracket closes slowly when ``-rho`` is nearly an eigenvalue
too: 100-200 matrix products at d = 60..150) and returns a value from above: the eigenvalue
raised by its backward-error bound, capped by the largest row sum (a rigorous upper bound).

Examples
--------
>>> import numpy as np
>>> round(perron_root(np.array([[2.0, 1.0], [1.0, 2.0]])), 12)
3.0
"""

from __future__ import annotations

import functools
from collections import OrderedDict
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp

from lmic.ir.svec import tril_unvec

__all__ = ["block_matrix", "block_spectrum", "term_scale", "perron_root", "prepared", "Prepared", "clear"]

#: unit round-off of float64
_U = float(np.finfo(float).eps) / 2.0

_CACHE: OrderedDict[tuple[int, bytes], list[Any]] = OrderedDict()
_CACHE_SIZE = 32
_PREPARED: OrderedDict[int, tuple[Any, Any, Prepared]] = OrderedDict()
_PREPARED_SIZE = 64


@dataclass(frozen=True)
class Prepared:
    """What the certifier needs of one LMI's coefficients (independent of the point).

    Attributes
    ----------
    C : scipy.sparse.csc_matrix
        The coefficients ``[F0 | F_1 ... F_n]`` (storage rows), canonical CSC (the IR's own
        format: no conversion).
    absC : scipy.sparse.csc_matrix
        ``|C|`` entrywise.
    k : int
        The largest number of terms of one entry (the float error bound's ``k``).
    dim : int
    """

    C: sp.csc_matrix
    absC: sp.csc_matrix
    k: int
    dim: int

    @functools.cached_property
    def coefficient_scale(self) -> tuple[float, np.ndarray]:
        """``(largest row sum, M)`` of ``M = sum_i |C_i|`` (the coefficient scale's matrix)."""
        M = tril_unvec(np.asarray(self.absC.sum(axis=1)).ravel(), self.dim)
        return float(M.sum(axis=1).max(initial=0.0)), M


def clear() -> None:
    """Forget the cached spectra and prepared coefficients."""
    _CACHE.clear()
    _PREPARED.clear()


def prepared(lmi: Any) -> Prepared:
    """The point-independent data of ``lmi`` (:class:`Prepared`), computed once per LMI object.

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI
    >>> L = LMI("p > 0", 1, sp.csc_matrix([[0., -2.]]))
    >>> prepared(L).k, prepared(L) is prepared(L)
    (1, True)
    """
    key = id(lmi)
    hit = _PREPARED.get(key)
    if hit is not None and hit[0] is lmi and hit[1] is lmi.coeffs:
        _PREPARED.move_to_end(key)
        return hit[2]
    C = sp.csc_matrix(lmi.coeffs, copy=False)
    if not C.has_canonical_format:
        C = C.copy()
        C.sum_duplicates()  # k counts the terms of an entry once
    k = int(np.bincount(C.indices, minlength=1).max()) if C.nnz else 0  # terms per entry (row)
    prep = Prepared(C=C, absC=abs(C), k=k, dim=lmi.dim)
    _PREPARED[key] = (lmi, lmi.coeffs, prep)
    if len(_PREPARED) > _PREPARED_SIZE:
        _PREPARED.popitem(last=False)
    return prep


def _entry(lmi: Any, x: np.ndarray, spectrum: bool = True) -> list[Any]:
    """The cache entry ``[lmi, coeffs, xx, F, eig or None, T or None]`` of ``lmi`` at ``x``
    (``spectrum``: with the eigenvalues, computed now if the entry has none yet)."""
    xx = np.concatenate([[1.0], np.asarray(x, dtype=float).ravel()])
    key = (id(lmi), xx.tobytes())
    entry = _CACHE.get(key)
    if entry is not None and entry[0] is lmi and entry[1] is lmi.coeffs:
        _CACHE.move_to_end(key)
    else:
        entry = [lmi, lmi.coeffs, xx, tril_unvec(prepared(lmi).C @ xx, lmi.dim), None, None]
        _CACHE[key] = entry
        if len(_CACHE) > _CACHE_SIZE:
            _CACHE.popitem(last=False)
    if spectrum and entry[4] is None:
        F = entry[3]
        entry[4] = np.linalg.eigvalsh(F) if lmi.dim and np.all(np.isfinite(F)) else np.full(lmi.dim, np.nan)
    return entry


def block_matrix(lmi: Any, x: np.ndarray) -> np.ndarray:
    """``F(x)`` of one LMI (dense, symmetric), kept for :func:`block_spectrum` at the same point
    (a test of a solver's iterate factorises it first, the certifier then needs its spectrum).

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI
    >>> block_matrix(LMI("p > 0", 1, sp.csc_matrix([[1., 2.]])), np.array([3.0])).tolist()
    [[7.0]]
    """
    return _entry(lmi, x, spectrum=False)[3]


def block_spectrum(lmi: Any, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``F(x)`` of one LMI (dense, symmetric) and its eigenvalues (ascending), computed once.

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI
    >>> F, eig = block_spectrum(LMI("p > 0", 1, sp.csc_matrix([[0., 1.]])), np.array([3.0]))
    >>> float(F[0, 0]), eig.tolist()
    (3.0, [3.0])
    """
    entry = _entry(lmi, x)
    return entry[3], entry[4]


def term_scale(lmi: Any, x: np.ndarray) -> float:
    """The certifier's term scale ``T = || |F0| + sum_k |x_k| |F_k| ||_2`` at ``x``, from above.

    Computed once per LMI and point (kept with :func:`block_spectrum`'s entry).

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI
    >>> term_scale(LMI("p > 0", 1, sp.csc_matrix([[1., -2.]])), np.array([3.0]))
    7.0
    """
    entry = _entry(lmi, x)
    if entry[5] is None:
        entry[5] = perron_root(tril_unvec(prepared(lmi).absC @ np.abs(entry[2]), lmi.dim))
    return float(entry[5])


def perron_root(M: np.ndarray) -> float:
    """The Perron root (spectral norm) of a symmetric entrywise non-negative matrix, from above.

    ``eigvalsh``'s largest eigenvalue raised by ``10 (d + 1) u`` of itself (its backward error
    is a small multiple of ``d u ||M||``), never above the largest row sum (which bounds the
    root of a non-negative matrix); a non-finite matrix gives ``inf``.

    >>> perron_root(np.zeros((3, 3))), perron_root(np.array([[5.0]]))
    (0.0, 5.0)
    """
    d = M.shape[0]
    if d == 0:
        return 0.0
    if d == 1:
        return float(M[0, 0])
    if not np.all(np.isfinite(M)):
        return float("inf")
    top = float(np.linalg.eigvalsh(M)[-1])
    rows = float(M.sum(axis=1).max())
    return float(min(max(top, 0.0) * (1.0 + 10.0 * (d + 1) * _U), rows))
