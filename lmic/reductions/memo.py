"""Solves remembered within one route: the same closed problem is never solved twice.

A route (:func:`lmic.routes.decide_route`) may hand a backend the very problem it solved
before: the enclosure's strict polish re-solves the strict problem at the route's options (the
route's own first solve when that was the backend's plain strategy), and the tight re-solve's
enclosure re-solves the closed problem its first enclosure already solved. The interior-point
solvers are deterministic, so the second solve returns the first's answer, bit for bit
(random ``delay_a.thm3_1``, 7 states: one SDPA solve of seven, 0.24 of 2.4 s).

Inside :func:`remembered_solves`, :func:`lmic.reductions.pipeline.solve` looks each closed
solve up by the backend, a fingerprint of the problem's numbers (:func:`problem_key`) and the
options that change the answer (:func:`options_key`: not the time limit; a warm start or an
``accept`` predicate is never remembered). A solve that ended in an error or at its time limit
is not remembered. Each lookup returns a deep copy (a caller may change what it gets), marked
``info["remembered"]``, with no solver time (``solve_s = 0``).

Examples
--------
>>> from lmic.testing.conformance import CASES
>>> problem_key(CASES["max_sense"].build()) == problem_key(CASES["max_sense"].build())
True
>>> with remembered_solves():
...     active()
True
>>> active()
False
"""

from __future__ import annotations

import copy
import hashlib
from collections import OrderedDict
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from typing import Any

import numpy as np
import scipy.sparse as sp

from lmic.ir.problem import Problem
from lmic.options import SolveOptions
from lmic.solution import Solution

__all__ = ["MAX_ENTRIES", "active", "options_key", "problem_key", "recall", "remember", "remembered_solves"]

#: solutions kept per route, oldest dropped first (a route makes a handful of solves; a large
#: problem's dual is megabytes)
MAX_ENTRIES = 16

_MEMO: ContextVar[OrderedDict[tuple[Any, ...], Solution] | None] = ContextVar("lmic_solve_memo", default=None)


@contextmanager
def remembered_solves() -> Iterator[None]:
    """Remember the closed solves made inside (nested uses share the outermost memory)."""
    if _MEMO.get() is not None:
        yield
        return
    token = _MEMO.set(OrderedDict())
    try:
        yield
    finally:
        _MEMO.reset(token)


def active() -> bool:
    """Whether solves are being remembered here."""
    return _MEMO.get() is not None


def _sparse_digest(h: Any, M: Any) -> None:
    A = sp.csr_matrix(M, copy=True)
    A.sum_duplicates()
    A.sort_indices()
    h.update(np.asarray(A.shape, dtype=np.int64).tobytes())
    h.update(np.ascontiguousarray(A.indptr, dtype=np.int64).tobytes())
    h.update(np.ascontiguousarray(A.indices, dtype=np.int64).tobytes())
    h.update(np.ascontiguousarray(A.data, dtype=float).tobytes())


def problem_key(problem: Problem) -> str:
    """A digest of everything a backend reads of ``problem``: the variables' layout, every LMI's
    size, relation, strictness, blocks and coefficients, the linear rows and the objective (not
    the names, the data or the derived values).

    >>> from lmic.testing.conformance import lyapunov_problem
    >>> problem_key(lyapunov_problem(-np.eye(2))) != problem_key(lyapunov_problem(-2 * np.eye(2)))
    True
    """
    h = hashlib.blake2b(digest_size=20)
    h.update(repr([(v.kind, v.shape, v.offset, v.blocks, v.sign) for v in problem.variables]).encode())
    for lmi in problem.lmis:
        h.update(repr((lmi.dim, lmi.strict, lmi.relation, tuple(lmi.block_sizes))).encode())
        _sparse_digest(h, lmi.coeffs)
    lin = problem.linear
    h.update(repr((list(lin.kinds), [bool(s) for s in lin.strict])).encode())
    _sparse_digest(h, lin.A)
    h.update(problem.objective.sense.encode())
    h.update(np.ascontiguousarray(problem.objective.c, dtype=float).tobytes())
    return h.hexdigest()


def options_key(options: SolveOptions) -> tuple[Any, ...] | None:
    """The options that change a solve's answer, or ``None`` when the solve is not to be
    remembered (a warm start, an ``accept`` predicate, or ``extra`` settings that are not plain
    values).

    >>> options_key(SolveOptions(time_limit=5.0)) == options_key(SolveOptions())
    True
    >>> options_key(SolveOptions(tol=1e-9)) == options_key(SolveOptions())
    False
    """
    if options.warm_start is not None or options.accept is not None:
        return None
    extra = []
    for name, value in sorted(options.extra.items()):
        if not isinstance(value, (str, int, float, bool, type(None))):
            return None
        extra.append((name, value))
    return (
        options.tol,
        options.max_iter,
        options.verbose,
        options.margin,
        options.strict,
        options.relative_margin,
        options.gap,
        tuple(extra),
    )


def _key(label: str, problem: Problem, options: SolveOptions) -> tuple[Any, ...] | None:
    if _MEMO.get() is None:
        return None
    opts = options_key(options)
    return None if opts is None else (label, problem_key(problem), opts)


def recall(label: str, problem: Problem, options: SolveOptions) -> tuple[tuple[Any, ...] | None, Solution | None]:
    """``(key, a copy of the remembered solution or None)``; the key is ``None`` outside
    :func:`remembered_solves` or for options that are not remembered."""
    key = _key(label, problem, options)
    memo = _MEMO.get()
    if key is None or memo is None or key not in memo:
        return key, None
    memo.move_to_end(key)
    sol = copy.deepcopy(memo[key])
    sol.info["remembered"] = True
    sol.solve_s = 0.0  # no solver time spent on it here
    return key, sol


def remember(key: tuple[Any, ...] | None, sol: Solution) -> None:
    """Keep a copy of ``sol`` under ``key`` (from :func:`recall`) unless it is an error or was
    stopped at its time limit."""
    memo = _MEMO.get()
    if key is None or memo is None or sol.status == "error" or sol.info.get("time_limit"):
        return
    try:
        memo[key] = copy.deepcopy(sol)
    except Exception:  # noqa: BLE001 - a solution that cannot be copied is simply not remembered
        return
    while len(memo) > MAX_ENTRIES:
        memo.popitem(last=False)
