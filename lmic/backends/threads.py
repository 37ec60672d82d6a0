"""The number of threads of the BLAS libraries during a solve (:func:`blas_threads`).

lmic's own dense kernels inside a solver run (the structured KKT solver of
:mod:`lmic.backends.cvxopt_kkt`: products of ``n x d`` and ``d x n`` matrices, ``d`` about 40,
many times per iteration) lose to the thread start-up and synchronisation of a multi-threaded
BLAS: bounded-real lemma, 40 states, the whole CVXOPT solve with numpy's OpenBLAS on 2 threads
3.05-3.26 s, on 1 thread 1.72-1.85 s (two rounds each, measured on an idle 2-core machine).
The limit uses threadpoolctl (every BLAS library loaded: numpy's, SciPy's, CVXOPT's) and is
undone on exit; without threadpoolctl the solve runs unchanged.

Examples
--------
>>> import numpy as np
>>> with blas_threads(1):
...     float((np.eye(2) @ np.eye(2))[0, 0])
1.0
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

__all__ = ["blas_threads"]


@contextlib.contextmanager
def blas_threads(limit: int) -> Iterator[None]:
    """At most ``limit`` threads in every loaded BLAS library inside the ``with`` block."""
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:  # an optional speed-up: the solve is the same without it
        yield
        return
    with threadpool_limits(limits=int(limit), user_api="blas"):
        yield
