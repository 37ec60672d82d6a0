"""One eigen-decomposition per LMI block and point, shared by every check of that point.

The fixed-margin point check of the strict reduction (:func:`lmic.reductions.strict.achieved_margin`
and :func:`~lmic.reductions.strict.verify_point`) and the certifier
(:func:`lmic.certify.check.lmi_report`) judge the same point on the same LMIs, one after the
other: :func:`block_spectrum` evaluates ``F(x)`` and its eigenvalues once and keeps the last few
results (keyed by the LMI object and the exact bytes of ``x``), so the later checks reuse them.

The term scale of the certifier (the Perron root of ``|C| |x|``, an entrywise non-negative
symmetric matrix) needs no second decomposition: :func:`perron_root` brackets it by power
iteration with the Collatz-Wielandt bounds ``min_i (M v)_i / v_i <= rho <= max_i (M v)_i / v_i``
and returns the upper end once the bracket is within ``rtol`` (an upper bound is the safe side
for an error bound); it falls back to ``eigvalsh`` when the bracket does not close.

Examples
--------
>>> import numpy as np
>>> round(perron_root(np.array([[2.0, 1.0], [1.0, 2.0]])), 12)
3.0
"""

from __future__ import annotations

import math
from collections import OrderedDict
from typing import Any

import numpy as np

from lmic.ir.svec import tril_unvec

__all__ = ["block_spectrum", "perron_root", "clear"]

_CACHE: OrderedDict[tuple[int, bytes], tuple[Any, np.ndarray, np.ndarray]] = OrderedDict()
_CACHE_SIZE = 32


def clear() -> None:
    """Forget the cached spectra."""
    _CACHE.clear()


def block_spectrum(lmi: Any, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``F(x)`` of one LMI (dense, symmetric) and its eigenvalues (ascending), computed once.

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI
    >>> F, eig = block_spectrum(LMI("p > 0", 1, sp.csc_matrix([[0., 1.]])), np.array([3.0]))
    >>> float(F[0, 0]), eig.tolist()
    (3.0, [3.0])
    """
    xx = np.ascontiguousarray(x, dtype=float)
    key = (id(lmi), xx.tobytes())
    hit = _CACHE.get(key)
    if hit is not None and hit[0] is lmi:
        _CACHE.move_to_end(key)
        return hit[1], hit[2]
    C = lmi.coeffs.tocsr()
    F = tril_unvec(C @ np.concatenate([[1.0], xx]), lmi.dim)
    eig = np.linalg.eigvalsh(F) if lmi.dim and np.all(np.isfinite(F)) else np.full(lmi.dim, np.nan)
    _CACHE[key] = (lmi, F, eig)
    if len(_CACHE) > _CACHE_SIZE:
        _CACHE.popitem(last=False)
    return F, eig


def perron_root(M: np.ndarray, rtol: float = 1e-10, max_iter: int = 200) -> float:
    """The Perron root (spectral norm) of a symmetric entrywise non-negative matrix, from above.

    Power iteration from the all-ones vector with the Collatz-Wielandt bracket; the upper end
    once ``hi - lo <= rtol * hi``, else ``eigvalsh``'s largest eigenvalue.

    >>> perron_root(np.zeros((3, 3))), perron_root(np.array([[5.0]]))
    (0.0, 5.0)
    """
    d = M.shape[0]
    if d == 0:
        return 0.0
    if d == 1:
        return float(M[0, 0])
    v = np.ones(d)
    for _ in range(max_iter):
        w = M @ v
        if not np.all(w > 0):
            break  # a zero row (reducible matrix): the bracket does not apply
        q = w / v
        lo, hi = float(q.min()), float(q.max())
        if not math.isfinite(hi):
            break  # overflow or an entry of v that underflowed to 0: no bracket, decompose
        if hi - lo <= rtol * hi:
            return hi
        v = w / float(w.max())
        if not np.all(v > 0):
            break  # an entry underflowed (a component with a much smaller root): decompose
    return float(max(np.linalg.eigvalsh(M)[-1], 0.0))
