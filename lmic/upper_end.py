"""A certified primal end from a proven dual end: points inside, closer and closer to it.

When the solver's point at an optimum gives no rigorous primal end (a strict problem whose
infimum is not attained, a near-singular optimum the solver resolves only to its tolerance:
the bounded-real lemma of a system with spectral abscissa ``-0.01``), any point proved
feasible whose objective is near the proven dual end ``L`` will do. This module finds one
without trusting the solver's point, in the minimisation form (``q`` the objective):

1. **margin solve**: ``max s`` subject to ``F_i(x) >= s I`` on every LMI, ``l_r(x) >= s`` on
   every ``ge`` row (``eq`` rows kept), ``q(x) <= L + delta_0 max(1, |L|)`` and ``|x_k| <= R``
   (``R`` ten times ``max(1, |L|)``, then ten times the solver's point): the most interior
   point of the slice, proved by :func:`lmic.certify.enclosure.primal_end` (``delta_0`` in
   :data:`START_DELTAS`);
2. **recentred solves**: from the last proved point ``x_0`` (``W_i = F_i(x_0) > 0``), with
   ``T_i`` the inverse Cholesky factor of ``W_i`` and the variables shifted and scaled,
   ``x = x_0 + diag(d) w`` (``1 / d_k`` the largest entry of the blocks ``T_i F_i^(k) T_i^T``:
   a unit ``w_k`` moves them by about one), the same problem is solved in the local metric:
   ``max s`` s.t. ``T_i F_i(x_0 + diag(d) w) T_i^T >= s I``, ``l_r(x) / l_r(x_0) >= s``,
   ``q(x) <= L + delta max(1, |L|)``, ``|w_k| <= RADIUS`` (above :data:`FULL_MAX` dense
   entries, a block whose ``W_i`` is well conditioned gets the diagonal congruence instead:
   sparse; a margin or recentred solve the backend ends without a point goes to the ``alternatives``).
   At ``w = 0`` every block is the identity (its diagonal), so the solver's error is relative
   to the current margins, not to the size of ``F_i``: where the slice at ``delta`` is ``1e-13`` thin relative to the
   entries (measured: ``n = 20`` near-unstable bounded-real lemma) a plain solve returns
   points violated by ``1e-8``, the recentred one points that hold. ``delta`` is divided by
   :data:`STEP` while the point is proved, by ``sqrt(STEP)`` once after a failure.

Nothing here is trusted: every point is proved by :func:`~lmic.certify.enclosure.primal_end`
on the ORIGINAL problem (the congruence and the scaling only shape the solve), and the caller
records it as a ``restored point`` that ``lmic audit`` re-proves. The solves share a deadline;
the search stops at the relative gap ``target`` (:data:`lmic.certify.enclosure.GAP_TARGET`).

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
>>> # inf t s.t. [[t, 1], [1, t]] > 0: infimum 1, not attained
>>> C = sp.csc_matrix(np.array([[0.0, 1.0], [1.0, 0.0], [0.0, 1.0]]))
>>> p = Problem([Variable("t", "scalar", (1, 1))], [LMI("M > 0", 2, C, strict=True)],
...             LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
>>> r = upper_from_lower(p, 1.0, "clarabel", x_hint=np.array([1.0]))
>>> r["proven"], 1.0 < r["value"] <= 1.0 + 1e-6
(True, True)
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np
import scipy.sparse as sp

from lmic.errors import LmicError
from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
from lmic.ir.svec import tril_rows_cols, tril_unvec
from lmic.reductions.pipeline import solve as solve_with_reductions

__all__ = [
    "BOX_GROWTH",
    "BOX_MAX",
    "BOX_START",
    "START_DELTAS",
    "STEP",
    "boxed_problem",
    "margin_problem",
    "recentred_problem",
    "upper_from_boxes",
    "upper_from_lower",
]

#: the relative backoffs of the first (margin) solve, tried in turn until one point is proved
START_DELTAS = (1e-4, 1e-3, 1e-2)
#: the backoffs of the margin solves for a point that passes ``check`` (:func:`upper_from_lower`)
CHECK_DELTAS = (1e-3, 1e-2, 1e-1)
#: the box ``|w_k| <= RADIUS`` of the recentred solves (a unit ``w_k`` moves the blocks by about their margin)
RADIUS = 10.0
#: above this many dense coefficient entries, an LMI whose ``F(x0)`` has condition number at
#: most :data:`DIAGONAL_COND` gets a diagonal congruence (sparse) instead of the full one (the
#: full one everywhere is better where affordable: 20 states, 5e-7 where the diagonal one on
#: ``P > 0`` stopped at 3.3e-6)
FULL_MAX = 1_000_000
DIAGONAL_COND = 1e4
#: the factor ``delta`` shrinks by after each proved recentred point
STEP = 30.0
#: the recentred problem is built with a dense congruence: above this many coefficient
#: entries (LMI storage rows times variables) only the margin solve runs
MAX_DENSE = 4_000_000


def _min_form(problem: Problem) -> tuple[float, np.ndarray]:
    s = -1.0 if problem.objective.sense == "max" else 1.0
    return s, s * np.asarray(problem.objective.c, dtype=float)


def _bound_row(q: np.ndarray, bound: float, x0: np.ndarray, d: np.ndarray) -> tuple[np.ndarray, float]:
    """The row ``bound - q(x_0 + diag(d) w) >= 0`` (coefficients of ``(1, w)``), normalised."""
    ob = bound - q[0] - float(q[1:] @ x0)
    row = np.concatenate([[ob], -q[1:] * d])
    return row / max(float(np.max(np.abs(row))), 1e-300), ob


def margin_problem(problem: Problem, bound: float, radius: float | np.ndarray) -> Problem:
    """Step 1 of the module docstring (variables ``x`` then ``s``; ``bound`` in the minimisation form).

    >>> import scipy.sparse as sp
    >>> p = Problem([Variable("t", "scalar", (1, 1))], [LMI("t > 0", 1, sp.csc_matrix([[0.0, 1.0]]))],
    ...             LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
    >>> margin_problem(p, 2.0, 10.0).lmis[0].coeffs.toarray().tolist()
    [[0.0, 1.0, -1.0]]
    """
    return recentred_problem(problem, np.zeros(problem.n), bound, radius, local=False)[0]


def recentred_problem(
    problem: Problem, x0: np.ndarray, bound: float, radius: float | np.ndarray = 10.0, *, local: bool = True
) -> tuple[Problem, np.ndarray]:
    """Step 2 of the module docstring: the problem in ``(w, s)`` and the scaling ``d``
    (``x = x0 + d * w``). ``local=False``: no congruence, no scaling (``d = 1``), step 1.

    >>> import scipy.sparse as sp
    >>> p = Problem([Variable("t", "scalar", (1, 1))], [LMI("t > 0", 1, sp.csc_matrix([[0.0, 1.0]]))],
    ...             LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
    >>> q, d = recentred_problem(p, np.array([4.0]), 3.0)
    >>> q.lmis[0].coeffs.toarray().round(6).tolist(), d.tolist()
    ([[1.0, 1.0, -1.0]], [4.0])
    """
    n = problem.n
    x0 = np.asarray(x0, dtype=float)
    xx0 = np.concatenate([[1.0], x0])
    d = np.ones(n)
    blocks: list[tuple[Any, Any]] = []
    big = _dense_size(problem) > FULL_MAX  # only then the sparse diagonal congruence where it may do
    for lmi in problem.lmis:
        C = lmi.coeffs.tocsc().astype(float)
        if not local:
            blocks.append((None, None))
            continue
        w0 = np.asarray(C @ xx0).ravel()
        W = tril_unvec(w0, lmi.dim)
        ev = np.linalg.eigvalsh(W)
        if big and ev[0] > 0 and ev[-1] <= DIAGONAL_COND * ev[0]:  # well conditioned: a diagonal congruence
            g = 1.0 / np.sqrt(np.diag(W))
            i, j = tril_rows_cols(lmi.dim)
            k = g[i] * g[j]
            blocks.append((k * w0, sp.csc_matrix(sp.diags(k) @ C[:, 1:])))
        else:
            K = _congruence(np.linalg.inv(np.linalg.cholesky(W)))
            blocks.append((K @ w0, sp.csc_matrix(K @ C[:, 1:].toarray())))
    if local:
        # every variable moves the congruent blocks by about one (the current margins are one)
        size = np.zeros(n)
        for _, Fk in blocks:
            size = np.maximum(size, np.asarray(abs(Fk).max(axis=0).todense()).ravel())
        d = np.where(size > 0, 1.0 / np.where(size > 0, size, 1.0), d)
    lmis = []
    for lmi, (F0, Fk) in zip(problem.lmis, blocks, strict=True):
        i, j = tril_rows_cols(lmi.dim)
        scol = sp.csc_matrix(np.where(i == j, -1.0, 0.0)[:, None])
        if local:
            coeffs = sp.hstack([sp.csc_matrix(F0[:, None]), Fk @ sp.diags(d), scol]).tocsc()
        else:
            coeffs = sp.hstack([lmi.coeffs.tocsc().astype(float), scol]).tocsc()
        lmis.append(LMI(lmi.name, lmi.dim, coeffs, False, lmi.relation, lmi.block_sizes))
    lin = problem.linear
    A = lin.A.tocsr().astype(float)
    val = np.asarray(A @ xx0).ravel() if len(lin) else np.zeros(0)
    ge = np.array([k == "ge" for k in lin.kinds], dtype=bool)
    w = np.where(ge & local, np.maximum(np.abs(val), 1e-300), 1.0) if len(lin) else np.zeros(0)
    if local:  # rows of (1, w): the value at x0 as the constant
        body = sp.hstack([sp.csr_matrix(val[:, None]), A[:, 1:] @ sp.diags(d)]) if len(lin) else None
    else:
        body = A if len(lin) else None
    parts = []
    if body is not None:
        parts.append(sp.hstack([sp.diags(1.0 / w) @ body, sp.csr_matrix(np.where(ge, -1.0, 0.0)[:, None])]))
    _, q = _min_form(problem)
    row, _ = _bound_row(q, bound, x0 if local else np.zeros(n), d)
    parts.append(sp.csr_matrix(np.concatenate([row, [0.0]])[None, :]))
    parts += _box_rows(n, radius, extra=1)
    kinds = list(lin.kinds) + ["ge"] * (1 + 2 * n)
    c = np.zeros(n + 2)
    c[-1] = 1.0
    out = Problem(
        [Variable("__w", "full", (n, 1)), Variable("__s", "scalar", (1, 1), offset=n)],
        lmis,
        LinearConstraints(sp.vstack(parts).tocsr(), kinds, [False] * len(kinds), [f"r{k}" for k in range(len(kinds))]),
        Objective("max", c),
        meta={"upper_end_of": (problem.meta or {}).get("theorem")},
    )
    return out, d


def _congruence(T: np.ndarray) -> np.ndarray:
    """The matrix of ``vec(M) -> vec(T M T^T)`` on the lower-triangle storage."""
    r, c = tril_rows_cols(T.shape[0])
    K = T[r[:, None], r[None, :]] * T[c[:, None], c[None, :]] + T[r[:, None], c[None, :]] * T[c[:, None], r[None, :]]
    K[:, r == c] *= 0.5
    return K


#: the time limit of one solve of the search without a deadline: a time limit runs a solver
#: without a native one in a forked child, so that a solver that ends the process (SDPA on
#: SDPLIB hinf1 boxed at ``|x| <= 1e4``: exit code 0, no output) only ends the child
SOLVE_LIMIT_S = 120.0


def _limited(options: Any, deadline: float | None) -> Any:
    """``options`` with a time limit: the time left before ``deadline`` (a
    :func:`time.perf_counter` value; at least 1 s), else :data:`SOLVE_LIMIT_S`, never above
    the given one.

    >>> _limited(None, None).time_limit
    120.0
    """
    from dataclasses import replace

    from lmic.options import SolveOptions

    left = SOLVE_LIMIT_S if deadline is None else max(1.0, deadline - time.perf_counter())
    given = options if options is not None else SolveOptions()
    return replace(given, time_limit=min(left, given.time_limit or left))


def _dense_size(problem: Problem) -> int:
    return sum(lmi.coeffs.shape[0] for lmi in problem.lmis) * (problem.n + 1)


def upper_from_lower(
    problem: Problem,
    lower: float,
    backend: Any,
    options: Any = None,
    *,
    x_hint: np.ndarray | None = None,
    target: float | None = None,
    deadline: float | None = None,
    check: Callable[[np.ndarray], bool] | None = None,
    alternatives: tuple[Any, ...] = (),
    radii: tuple[float | np.ndarray, ...] | None = None,
    start: float | None = None,
) -> dict[str, Any]:
    """A point proved feasible whose objective is near the proven dual end ``lower``.

    Parameters
    ----------
    problem : Problem
        An optimisation problem.
    lower : float
        The proven dual end in the problem's own sense (a lower bound of a minimum, an upper
        bound of a maximum).
    backend : str or Backend
    options : SolveOptions, optional
    x_hint : numpy.ndarray, optional
        The solver's point (certified or not): its size sets the box of the margin solve.
    target : float, optional
        The relative gap to stop at (default :data:`lmic.certify.enclosure.GAP_TARGET`).
    deadline : float, optional
        A :func:`time.perf_counter` value: no solve starts after it.
    check : callable, optional
        A second test of a proved point (the certifier's, whose relative threshold may ask for
        a larger margin than the proof): the best proved point that passes it is returned as
        ``checked_x`` / ``checked_value``, with margin solves at the larger backoffs of
        :data:`CHECK_DELTAS` when no point of the search passes.
    alternatives : tuple of str or Backend
        Backends for a margin or recentred solve that ``backend`` ends without a point (tried
        in turn; the first that gives one is used for the rest of the search).
    start : float, optional
        A first backoff of the margin solve, tried before :data:`START_DELTAS` when below them
        (the caller's gap: a point proved there meets it; SDPLIB qap6, whose recentred solves
        fail, stopped at 1.00005e-4 against the default ``--gap`` 1e-4 from ``1e-4``).
    radii : tuple of float, optional
        The boxes ``|x_k| <= R`` of the margin solves (default: ten times ``max(1, |lower|)``,
        then ten times the largest entry of ``x_hint``).

    Returns
    -------
    dict
        ``proven``, ``x`` (the best proved point, a list), ``value`` (its objective rounded
        outwards: the primal end), ``rel_gap`` (to ``lower``), ``checked_x``, ``checked_value``,
        ``steps`` (``delta``, the solve's status, whether its point was proved, seconds),
        ``reason``, ``time_s``.
    """
    from lmic.backends.registry import get_backend
    from lmic.certify.enclosure import GAP_TARGET, primal_end

    t0 = time.perf_counter()
    goal = GAP_TARGET if target is None else float(target)
    sgn, q = _min_form(problem)
    low = sgn * float(lower)  # the dual end in the minimisation form
    scale = max(1.0, abs(low))
    solvers = [b if not isinstance(b, str) else get_backend(b) for b in [backend, *alternatives]]
    hint = 0.0 if x_hint is None else float(np.max(np.abs(np.asarray(x_hint, dtype=float)), initial=0.0))
    # the box of the margin solve: ten times the objective's size, then the solver point's
    # (a loose box lets the solver drift to huge, less accurate points)
    if radii is None:
        radii = (10.0 * scale,) + ((10.0 * hint,) if np.isfinite(hint) and hint > 3.0 * scale else ())
    steps: list[dict[str, Any]] = []
    best: dict[str, Any] = {"proven": False}
    checked: dict[str, Any] = {}

    def late() -> bool:
        return deadline is not None and time.perf_counter() > deadline

    def attempt(delta: float, x0: np.ndarray | None, radius: float | np.ndarray = 1.0) -> bool:
        t1 = time.perf_counter()
        bound = low + delta * scale
        if x0 is None:
            target_problem, d, base = margin_problem(problem, bound, radius), np.ones(problem.n), np.zeros(problem.n)
        else:
            target_problem, d = recentred_problem(problem, x0, bound, RADIUS)
            base = x0
        step: dict[str, Any] = {"delta": delta, "recentred": x0 is not None}
        steps.append(step)
        opts = _limited(options, deadline)
        sol = None
        # a recentred problem is dense: where the backend fails on it (Clarabel, NumericalError at
        # 50 states), the alternatives in turn; the first that gives a point is kept for the rest.
        # So is a margin solve (SDPA ends SDPLIB qap6's with noINFO at once)
        for k, solver in enumerate(solvers):
            try:
                sol = solve_with_reductions(solver, target_problem, opts)
            except (LmicError, np.linalg.LinAlgError, ValueError, ArithmeticError) as exc:
                step.update(status="error", reason=str(exc)[:200])
                continue
            if sol.x is not None:
                if k:
                    solvers.insert(0, solvers.pop(k))
                    step["backend"] = str(getattr(solver, "name", solver))
                break
        if sol is None or sol.x is None:
            step.update(proven=False, status=getattr(sol, "status", "error"), time_s=time.perf_counter() - t1)
            return False
        step["status"] = sol.status
        x = base + d * np.asarray(sol.x, dtype=float)[: problem.n]
        pe = primal_end(problem, x)
        step.update(proven=bool(pe["proven"]), reason=pe["reason"], time_s=time.perf_counter() - t1)
        if pe["proven"] and (not best.get("proven") or sgn * pe["value"] < sgn * best["value"]):
            best.clear()
            best.update(proven=True, x=x, value=pe["value"])
        if pe["proven"] and check is not None and (not checked or sgn * pe["value"] < sgn * checked["value"]):
            if check(x):
                checked.update(x=x, value=pe["value"])
        return bool(pe["proven"])

    firsts = START_DELTAS if start is None or not 0.0 < start < START_DELTAS[0] else (float(start), *START_DELTAS)
    for delta in firsts:
        if late() or any(attempt(delta, None, radius) for radius in radii):
            break
    local = _dense_size(problem) <= MAX_DENSE
    failed = 0
    while best.get("proven") and local and not late():
        gap = (sgn * best["value"] - low) / scale
        if gap <= goal:
            break
        delta = max(gap / (STEP if failed == 0 else STEP**0.5), 0.5 * goal)
        if attempt(delta, best["x"]) and (sgn * best["value"] - low) / scale < 0.5 * gap:
            failed = 0
            continue
        failed += 1
        if failed >= 2:
            break
    for delta in CHECK_DELTAS if check is not None and best.get("proven") else ():
        if checked or late():
            break
        for radius in radii:
            if attempt(delta, None, radius) and checked:
                break
    out: dict[str, Any] = {"proven": bool(best.get("proven")), "steps": steps, "time_s": time.perf_counter() - t0}
    out["checked_x"] = np.asarray(checked["x"]).tolist() if checked else None
    out["checked_value"] = checked.get("value")
    if best.get("proven"):
        gap = max(0.0, (sgn * best["value"] - low) / scale)
        out.update(x=np.asarray(best["x"]).tolist(), value=best["value"], rel_gap=gap)
        out["reason"] = f"point proved feasible {gap:.2g} (relative) above the dual end after {len(steps)} solves"
    else:
        out.update(x=None, value=None, rel_gap=None)
        why = "time budget spent" if late() else "no solve gave a point proved feasible"
        out["reason"] = f"no primal end from the dual end: {why} ({len(steps)} solves)"
    return out


#: the boxes ``|x_k| <= R`` of :func:`upper_from_boxes`: from :data:`BOX_START`, times
#: :data:`BOX_GROWTH` each, up to :data:`BOX_MAX` (or ten times the solver's point, if smaller)
BOX_START = 100.0
BOX_GROWTH = 10.0
BOX_MAX = 1e10
#: the boxes stop growing once the boxed optimum improves by less than this (relative) and a
#: point is proved
BOX_STALL = 1e-4
#: the smallest half-width of a shaped box, relative to its largest (:func:`upper_from_boxes`)
SHAPE_FLOOR = 1e-3


def _radii(n: int, radius: float | np.ndarray) -> np.ndarray:
    """The half-widths of the box ``|x_k| <= radius_k`` of ``n`` variables (a scalar: all the same)."""
    return np.broadcast_to(np.asarray(radius, dtype=float), (n,))


def _box_rows(n: int, radius: float | np.ndarray, extra: int = 0) -> list[sp.csr_matrix]:
    """The rows ``radius_k - x_k >= 0`` and ``radius_k + x_k >= 0`` (constant column first),
    with ``extra`` zero columns after the ``n`` variables.

    >>> [m.toarray().tolist() for m in _box_rows(1, 2.0, extra=1)]
    [[[2.0, -1.0, 0.0]], [[2.0, 1.0, 0.0]]]
    """
    eye = sp.identity(n, format="csr")
    rad = sp.csr_matrix(_radii(n, radius).reshape(n, 1))
    z = sp.csr_matrix((n, extra))
    return [sp.hstack([rad, -eye, z]).tocsr(), sp.hstack([rad, eye, z]).tocsr()]


def boxed_problem(problem: Problem, radius: float | np.ndarray) -> Problem:
    """``problem`` with the rows ``radius - x_k >= 0`` and ``radius + x_k >= 0`` added.

    >>> import scipy.sparse as sp
    >>> p = Problem([Variable("t", "scalar", (1, 1))], [LMI("t > 0", 1, sp.csc_matrix([[0.0, 1.0]]))],
    ...             LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
    >>> boxed_problem(p, 5.0).linear.A.toarray().tolist()
    [[5.0, -1.0], [5.0, 1.0]]
    """
    n = problem.n
    lin = problem.linear
    parts = ([lin.A.tocsr().astype(float)] if len(lin) else []) + _box_rows(n, radius)
    kinds = list(lin.kinds) + ["ge"] * (2 * n)
    strict = list(lin.strict) + [False] * (2 * n)
    names = list(lin.names) + [f"|x[{k}]| <= {r:g}" for k, r in enumerate(_radii(n, radius))] * 2
    linear = LinearConstraints(sp.vstack(parts).tocsr(), kinds, strict, names)
    return Problem(problem.variables, problem.lmis, linear, problem.objective, meta=problem.meta)


def _boxed_values(
    problem: Problem, radius: float | np.ndarray, solvers: list[Any], options: Any, deadline: float | None = None
) -> list[tuple[float, int]]:
    """The boxed problem's optimum in the minimisation form (a solver's, unproved) from each of
    ``solvers`` that gives one, with the solver's index, lowest first (a solver stalled far
    inside the box reports a value far above the others': SDPLIB hinf13, SDPA 911 where CVXOPT
    has 55.6)."""
    sgn, _ = _min_form(problem)
    boxed = boxed_problem(problem, radius)
    found: list[tuple[float, int]] = []
    for k, solver in enumerate(solvers):
        try:
            sol = solve_with_reductions(solver, boxed, _limited(options, deadline))
        except (LmicError, np.linalg.LinAlgError, ValueError, ArithmeticError):
            continue
        if sol.x is not None and sol.status in ("optimal", "inaccurate"):
            val = problem.objective.value(np.asarray(sol.x, dtype=float))
            if val is not None and np.isfinite(val):
                found.append((sgn * float(val), k))
    return sorted(found)


def upper_from_boxes(
    problem: Problem,
    backend: Any,
    options: Any = None,
    *,
    x_hint: np.ndarray | None = None,
    target: float | None = None,
    deadline: float | None = None,
    check: Callable[[np.ndarray], bool] | None = None,
    alternatives: tuple[Any, ...] = (),
) -> dict[str, Any]:
    """A point proved feasible near the optimum when there is no proven dual end to aim at.

    An optimum approached only as ``|x|`` grows (SDPLIB hinf10: the solvers stop at
    ``|x| ~ 1e20`` with an objective far below the optimum, and no point of theirs holds) is
    found box by box: for ``R`` = :data:`BOX_START`, ``BOX_GROWTH * R``, ... the problem with
    ``|x_k| <= R`` is solved (a bounded problem; its value ``v_R``, not trusted, only the
    level to aim at), then :func:`upper_from_lower` looks for a point proved feasible near
    ``v_R`` inside that box (margin and recentred solves, every point proved by
    :func:`lmic.certify.enclosure.primal_end` on the original problem). The boxes grow while
    ``v_R`` improves by more than :data:`BOX_STALL` and the points keep being proved.

    Returns
    -------
    dict
        As :func:`upper_from_lower` (``rel_gap`` is to the boxed value, not to a proven end),
        with ``boxes``: one record per box (``radius``, ``value`` the boxed solve's, ``proven``,
        ``upper``).

    Examples
    --------
    >>> import scipy.sparse as sp
    >>> # inf t s.t. [[t, 1], [1, s]] >= 0, s <= 4: optimum 1/4
    >>> C = sp.csc_matrix(np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]))
    >>> p = Problem([Variable("t", "scalar", (1, 1)), Variable("s", "scalar", (1, 1), offset=1)],
    ...             [LMI("M >= 0", 2, C)],
    ...             LinearConstraints(sp.csr_matrix([[4.0, 0.0, -1.0]]), ["ge"], [False], ["s <= 4"]),
    ...             Objective("min", [0.0, 1.0, 0.0]))
    >>> r = upper_from_boxes(p, "clarabel")
    >>> r["proven"], 0.25 <= r["value"] <= 0.25 + 1e-5
    (True, True)
    """
    from lmic.backends.registry import get_backend
    from lmic.certify.enclosure import GAP_TARGET

    t0 = time.perf_counter()
    goal = GAP_TARGET if target is None else float(target)
    sgn, _ = _min_form(problem)
    solvers = [b if not isinstance(b, str) else get_backend(b) for b in [backend, *alternatives]]
    hint = np.inf if x_hint is None else float(np.max(np.abs(np.asarray(x_hint, dtype=float)), initial=0.0))
    top = BOX_MAX if not np.isfinite(hint) else min(BOX_MAX, max(BOX_START * BOX_GROWTH**2, 10.0 * hint))
    boxes: list[dict[str, Any]] = []
    best: dict[str, Any] = {"proven": False}
    checked: dict[str, Any] = {}

    # the boxes: |x_k| <= R, and first (after a solver's point far out) shaped like that point,
    # |x_k| <= R w_k with w = max(|x_hint|, SHAPE_FLOOR max|x_hint|) / max|x_hint| (SDPLIB hinf13:
    # the solvers' point has entries 4e6 .. 1e9; the round boxes lose their accuracy from
    # |x| <= 1e4, the shaped ones prove 44.56 where the round ones stop at 55.63)
    def late() -> bool:
        return deadline is not None and time.perf_counter() > deadline

    shapes: list[np.ndarray | None] = [None]
    if x_hint is not None and np.isfinite(hint) and hint > BOX_START:
        w = np.maximum(np.abs(np.asarray(x_hint, dtype=float)), SHAPE_FLOOR * hint) / hint
        shapes.insert(0, w)  # first: where the solver went is the likelier direction
    for shape in shapes:
        lowest: float | None = None
        misses = 0
        radius = BOX_START
        while radius <= top and not late():
            box: float | np.ndarray = radius if shape is None else radius * shape
            rec: dict[str, Any] = {"radius": radius, "shaped": shape is not None, "value": None, "proven": False}
            boxes.append(rec)
            v = None
            for v, k in _boxed_values(problem, box, solvers, options, deadline):
                # the boxed values, lowest first, until a point near one is proved (an inaccurate
                # boxed solve may report a value far below the box's optimum: nothing is proved there)
                others = tuple(b for j, b in enumerate(solvers) if j != k)
                r = upper_from_lower(
                    problem,
                    sgn * v,
                    solvers[k],
                    options,
                    target=goal,
                    deadline=deadline,
                    check=check,
                    alternatives=others,
                    radii=(box,),
                )
                rec.update(
                    value=sgn * v, proven=r["proven"], upper=r["value"], backend=str(getattr(solvers[k], "name", k))
                )
                if r["checked_x"] is not None and (not checked or sgn * r["checked_value"] < sgn * checked["value"]):
                    checked = {"x": r["checked_x"], "value": r["checked_value"]}
                if r["proven"]:
                    if not best.get("proven") or sgn * r["value"] < sgn * best["value"]:
                        best = {
                            "proven": True,
                            "x": r["x"],
                            "value": r["value"],
                            "radius": radius,
                            "shaped": rec["shaped"],
                        }
                    break
                if late():
                    break
            if rec["proven"] and v is not None:
                stalled = lowest is not None and lowest - v <= BOX_STALL * max(1.0, abs(v))
                lowest = v if lowest is None else min(lowest, v)
                if stalled:
                    break
            misses = 0 if rec["proven"] else misses + 1
            if lowest is not None and misses >= 2:
                break  # two boxes in a row without a proved point: the solves have lost their accuracy
            radius *= BOX_GROWTH
    out: dict[str, Any] = {"proven": bool(best.get("proven")), "boxes": boxes, "time_s": time.perf_counter() - t0}
    out["checked_x"] = checked.get("x")
    out["checked_value"] = checked.get("value")
    if best.get("proven"):
        out.update(x=best["x"], value=best["value"], rel_gap=None, radius=best["radius"])
        shaped = " (shaped like the solver's point)" if best["shaped"] else ""
        out["reason"] = f"point proved feasible in the box |x| <= {best['radius']:g}{shaped} ({len(boxes)} boxes)"
    else:
        out.update(x=None, value=None, rel_gap=None)
        out["reason"] = f"no point proved feasible in {len(boxes)} boxes (|x| <= {top:g})"
    return out
