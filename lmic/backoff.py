"""A well-scaled point near the optimum: back off the objective, then minimise the size of ``x``.

At an optimum the LMIs are singular and interior-point solvers return points at the edge of
what they can represent: gains of ``1e6`` to ``1e9``, eigenvalue margins below the
certification threshold. Once the optimal value is enclosed, a second solve keeps the
objective within a relative ``backoff`` of the certified end and minimises ``t = ||x||_inf``
over the same constraints:

    ``min t``  s.t.  every LMI and row of the problem,  ``-t <= x_k <= t``,
    ``q_0 + q . x <= v + backoff * |v|``  (``backoff`` itself when ``v = 0``),
    ``F_i(x) >= MARGIN t I`` on strict LMIs (and strict rows ``>= MARGIN t``)

(``q`` the minimisation form of the objective, ``v`` the certified primal end). The point it
returns is certified against the *original* problem by the certifier, like any other point:
a backed-off answer is a feasible point whose objective is within the backoff of the optimum
(and, with the dual end of :mod:`lmic.certify.enclosure`, provably within ``backoff`` plus the
enclosure's gap of the optimal value).

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
>>> # min t s.t. t >= 1 and a free s with  [[t, s], [s, 1]] >= 0 (any |s| <= sqrt(t) works)
>>> C = sp.csc_matrix(np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]))
>>> p = Problem([Variable("t", "scalar", (1, 1)), Variable("s", "scalar", (1, 1), offset=1)],
...             [LMI("M >= 0", 2, C, strict=False)],
...             LinearConstraints(sp.csr_matrix([[-1.0, 1.0, 0.0]]), ["ge"], [False], ["t >= 1"]),
...             Objective("min", [0.0, 1.0, 0.0]))
>>> r = backoff(p, 1.0, "clarabel", rel=1e-3)
>>> r["verdict"], r["objective"] <= 1.001 + 1e-9, r["norm_inf"] <= 1.0011
('certified', True, True)
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
import scipy.sparse as sp

from lmic.errors import LmicError
from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
from lmic.ir.svec import tril_rows_cols
from lmic.reductions.pipeline import solve as solve_with_reductions

__all__ = [
    "DEFAULT_BACKOFF",
    "RESTORE",
    "RESTORE_MARGIN",
    "MARGIN",
    "backoff_problem",
    "backoff",
    "describe",
    "restore_problem",
    "restore",
]

#: default relative backoff for problems with derived gains
DEFAULT_BACKOFF = 1e-3
#: relative backoff of the restoration solve that supplies a rigorous primal end when the
#: solver's point meets a non-strict constraint only to the certifier's tolerance
RESTORE = 5e-7
#: the margin (relative to ||x||_inf) of the restoration solve: above the solvers' accuracy
RESTORE_MARGIN = 1e-8
#: strict constraints of the backed-off problem hold with margin ``MARGIN * ||x||_inf``, far
#: above the certifier's relative threshold (``1e-12`` of the scale)
MARGIN = 1e-10
_T = "__backoff_t"


def _room(value: float, rel: float) -> float:
    return rel * (abs(value) if value != 0 else 1.0)


def backoff_problem(
    problem: Problem, value: float, rel: float, all_margins: bool = False, margin: float | None = None
) -> Problem:
    """The second problem of the module docstring (``x`` first, then ``t``).

    >>> import scipy.sparse as sp
    >>> p = Problem([Variable("a", "scalar", (1, 1))], [], LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
    >>> q = backoff_problem(p, 2.0, 0.5)
    >>> q.n, q.objective.c.tolist(), len(q.linear)
    (2, [0.0, 0.0, 1.0], 3)
    """
    if problem.objective.sense == "feasibility":
        raise LmicError("a feasibility problem has no objective to back off")
    n = problem.n
    m = MARGIN if margin is None else margin
    s = -1.0 if problem.objective.sense == "max" else 1.0
    q = s * problem.objective.c
    bound = s * value + _room(value, rel)
    lmis = []
    for lmi in problem.lmis:
        col = np.zeros((lmi.coeffs.shape[0], 1))
        if lmi.strict or all_margins:  # F(x) >= margin * t I: a margin that scales with the point
            i, j = tril_rows_cols(lmi.dim)
            col[i == j, 0] = -m
        coeffs = sp.hstack([lmi.coeffs, sp.csc_matrix(col)]).tocsc()
        lmis.append(LMI(lmi.name, lmi.dim, coeffs, lmi.strict, lmi.relation, lmi.block_sizes))
    lin = problem.linear
    marked = np.asarray(lin.strict, dtype=bool) | (all_margins & np.array([k == "ge" for k in lin.kinds], dtype=bool))
    tcol = np.where(marked, -m, 0.0)[:, None] if len(lin) else np.zeros((0, 1))
    old = sp.hstack([lin.A, sp.csr_matrix(tcol)]).tocsr()
    eye = sp.identity(n, format="csr")
    ones = sp.csr_matrix(np.ones((n, 1)))
    zeros = sp.csr_matrix((n, 1))
    upper = sp.hstack([zeros, -eye, ones])  # t - x_k >= 0
    lower = sp.hstack([zeros, eye, ones])  # t + x_k >= 0
    obj_row = sp.csr_matrix(np.concatenate([[bound - q[0]], -q[1:], [0.0]])[None, :])
    A = sp.vstack([old, obj_row, upper, lower]).tocsr()
    kinds = list(lin.kinds) + ["ge"] * (1 + 2 * n)
    strict = list(lin.strict) + [False] * (1 + 2 * n)
    names = list(lin.names) + ["objective within the backoff"] + [f"|x[{k}]| <= t" for k in range(n)] * 2
    variables = list(problem.variables) + [Variable(_T, "scalar", (1, 1), offset=n)]
    c = np.zeros(n + 2)
    c[-1] = 1.0
    return Problem(
        variables,
        lmis,
        LinearConstraints(A, kinds, strict, names),
        Objective("min", c),
        meta={"backoff_of": (problem.meta or {}).get("theorem")},
    )


def backoff(
    problem: Problem,
    value: float,
    backend: Any,
    options: Any = None,
    *,
    rel: float = DEFAULT_BACKOFF,
    all_margins: bool = False,
    margin: float | None = None,
    fallback: Any = None,
) -> dict[str, Any]:
    """Solve the backed-off problem and certify its point against ``problem``.

    Parameters
    ----------
    problem : Problem
        An optimisation problem.
    value : float
        The certified primal end of the enclosure (objective at a certified point).
    backend : str or Backend
    options : SolveOptions, optional
    rel : float
        Relative backoff of the objective.
    all_margins : bool
        Impose the margin ``MARGIN t`` on the non-strict constraints too (a point strictly
        inside, which :func:`lmic.certify.enclosure.primal_end` can prove feasible).
    margin : float, optional
        The relative margin (default :data:`MARGIN`).
    fallback : array_like, optional
        A point to use when neither the backed-off solve nor the largest-margin one gives a
        certified point (``method`` ``"given point"``): it must be certified here and within the
        bound (the objective-cut search's point, :mod:`lmic.route_cut`, near an infimum that is
        not attained, where the slice is too thin for the solvers).

    Returns
    -------
    dict
        ``rel``, ``bound`` (the objective limit), ``status`` (the second solve's),
        ``verdict`` (the certifier's on the original problem), ``reason``, ``objective``,
        ``norm_inf`` (of the backed-off ``x``), ``x``, ``variables`` and ``derived`` (at the
        backed-off point), ``time_s``.
    """
    from lmic.backends.registry import get_backend

    t0 = time.perf_counter()
    s = -1.0 if problem.objective.sense == "max" else 1.0
    out: dict[str, Any] = {"rel": rel, "bound": s * (s * value + _room(value, rel)), "x": None}
    bp = backoff_problem(problem, value, rel, all_margins, margin)
    be = backend if not isinstance(backend, str) else get_backend(backend)
    try:
        sol = solve_with_reductions(be, bp, options)
    except LmicError as exc:
        out.update(status="error", verdict="undecided", reason=f"backoff solve failed: {exc}")
        out["time_s"] = time.perf_counter() - t0
        return out
    out["status"] = sol.status
    other = None
    if sol.x is None:
        other = _other_point(problem, out["bound"], be, options, fallback)
        if other is None:
            out.update(verdict="undecided", reason=f"backoff solve ended {sol.status} without a point ({sol.message})")
            out["time_s"] = time.perf_counter() - t0
            return out
    else:
        x, mine, cert = _certified(problem, sol)
        # a slice too thin for the solver's accuracy (a near-singular optimum): another point
        other = _other_point(problem, out["bound"], be, options, fallback) if cert.verdict != "certified" else None
    if other is not None:
        x, mine, cert, out["method"] = other
        out["status"] = mine.status  # the point's own solve ("status" is what lmic audit certifies with)
    d = cert.to_dict()
    out.update(
        verdict=cert.verdict,
        reason=cert.reason,
        objective=problem.objective.value(x),
        norm_inf=float(np.max(np.abs(x), initial=0.0)),
        x=x.tolist(),
        variables={k: np.asarray(v).tolist() for k, v in problem.unpack(x).items()},
        derived={r["name"]: r.get("value") for r in d.get("derived", [])},
        min_margin=min((r["min_margin"] for r in d.get("lmis", []) if r.get("min_margin") is not None), default=None),
    )
    out["time_s"] = time.perf_counter() - t0
    return out


def describe(record: dict[str, Any] | None, original_norm: float | None = None) -> list[str]:
    """Human lines for a backoff record (``lmic solve`` output).

    >>> describe({"rel": 1e-3, "verdict": "certified", "objective": 1.0, "norm_inf": 2.0,
    ...           "derived": {}, "reason": "ok", "x": [2.0]}, 1e6)[0]
    'backed-off point (objective within 0.001 relative): certified, objective 1, ||x||_inf 2 (optimum point: 1e+06)'
    """
    if not record:
        return []
    if record.get("x") is None:
        return [f"backed-off point (objective within {record['rel']:g} relative): {record['reason']}"]
    was = "" if original_norm is None else f" (optimum point: {original_norm:.3g})"
    lines = [
        f"backed-off point (objective within {record['rel']:g} relative): {record['verdict']}, "
        f"objective {record['objective']:.10g}, ||x||_inf {record['norm_inf']:.3g}{was}"
    ]
    if record["verdict"] != "certified":
        lines.append(f"  {record['reason']}")
    for name, v in (record.get("derived") or {}).items():
        arr = np.asarray(v, dtype=float) if v is not None and not isinstance(v, str) else None
        if arr is not None and arr.size:
            lines.append(f"  {name}: norm {float(np.linalg.norm(np.atleast_2d(arr), 2)):.4g}")
    return lines


def restore_problem(
    problem: Problem, x: np.ndarray, rel: float = RESTORE_MARGIN, row_rel: float | None = None
) -> Problem:
    """The problem with every constraint tightened by a margin, for a point strictly inside.

    Every LMI becomes ``F_i(x) >= delta_i I`` and every ``ge`` row ``>= delta_r`` (closed), with
    ``delta = rel * max(1, scale at x)`` (the largest entry of ``|F_i|`` at ``x``; the size of
    the row's terms): the solver's optimum of it, within its accuracy, is then strictly
    feasible for ``problem`` and :func:`lmic.certify.enclosure.primal_end` can prove it.
    ``row_rel`` (default ``rel``) is the rows' own relative margin: a scalar row ``epsilon > 0``
    whose value vanishes at the optimum needs more than the solver's accuracy.

    >>> import scipy.sparse as sp
    >>> p = Problem([Variable("t", "scalar", (1, 1))], [LMI("t >= 0", 1, sp.csc_matrix([[0.0, 1.0]]), strict=False)],
    ...             LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
    >>> restore_problem(p, np.array([0.0]), 0.5).lmis[0].coeffs.toarray().tolist()
    [[-0.5, 1.0]]
    """
    import dataclasses

    x = np.asarray(x, dtype=float)
    xx = np.concatenate([[1.0], x])
    lmis = []
    for lmi in problem.lmis:
        C = lmi.coeffs.tocsc().astype(float).tolil()
        i, j = tril_rows_cols(lmi.dim)
        scale = float(np.max(np.abs(abs(lmi.coeffs) @ np.abs(xx)), initial=0.0))
        delta = rel * max(1.0, scale)
        for k in np.flatnonzero(i == j):
            C[k, 0] = C[k, 0] - delta
        lmis.append(dataclasses.replace(lmi, coeffs=C.tocsc(), strict=False))
    lin = problem.linear
    A = lin.A.tocsr().astype(float).tolil()
    if len(lin):
        sizes = np.asarray(abs(lin.A) @ np.abs(xx)).ravel()
        for r, kind in enumerate(lin.kinds):
            if kind == "ge":
                A[r, 0] = A[r, 0] - (rel if row_rel is None else row_rel) * max(1.0, float(sizes[r]))
    return Problem(
        list(problem.variables),
        lmis,
        LinearConstraints(A.tocsr(), list(lin.kinds), [False] * len(lin), list(lin.names)),
        Objective(problem.objective.sense, problem.objective.c.copy()),
        meta={"restored_from": (problem.meta or {}).get("theorem")},
    )


def restore(
    problem: Problem,
    x: np.ndarray,
    backend: Any,
    options: Any = None,
    rel: float = RESTORE_MARGIN,
    row_rel: float | None = None,
) -> dict[str, Any]:
    """Solve :func:`restore_problem` and return ``x`` (``None`` without a point), ``status``,
    ``objective`` and ``time_s``; the caller proves the point (nothing here is trusted)."""
    from lmic.backends.registry import get_backend

    t0 = time.perf_counter()
    be = backend if not isinstance(backend, str) else get_backend(backend)
    try:
        sol = solve_with_reductions(be, restore_problem(problem, x, rel, row_rel), options)
    except LmicError as exc:
        return {"x": None, "status": "error", "reason": str(exc), "time_s": time.perf_counter() - t0}
    xr = None if sol.x is None else np.asarray(sol.x, dtype=float)
    return {
        "x": None if xr is None else xr.tolist(),
        "status": sol.status,
        "objective": None if xr is None else problem.objective.value(xr),
        "time_s": time.perf_counter() - t0,
    }


def _largest_margin(problem: Problem, bound: float, backend: Any, options: Any) -> tuple[np.ndarray, Any, Any] | None:
    """``(x, solution, certificate)`` of the most interior point with objective within ``bound``
    (:func:`lmic.upper_end.margin_problem`), when the certifier certifies it; else ``None``."""
    from lmic.upper_end import margin_problem

    s = -1.0 if problem.objective.sense == "max" else 1.0
    try:
        sol = solve_with_reductions(backend, margin_problem(problem, s * bound, 10.0 * max(1.0, abs(bound))), options)
    except LmicError:
        return None
    if sol.x is None:
        return None
    x, mine, cert = _certified(problem, sol)
    return (x, mine, cert) if cert.verdict == "certified" else None


def _other_point(
    problem: Problem, bound: float, backend: Any, options: Any, given: Any
) -> tuple[np.ndarray, Any, Any, str] | None:
    """When the backed-off solve gives no certified point: the most interior point within
    ``bound`` (:func:`_largest_margin`, method ``"largest margin"``), else the ``given`` point
    (:func:`_given`, method ``"given point"``); ``(x, solution, certificate, method)`` or ``None``."""
    found = _largest_margin(problem, bound, backend, options)
    if found is not None:
        return (*found, "largest margin")
    found = _given(problem, given, bound)
    return None if found is None else (*found, "given point")


def _given(problem: Problem, x: Any, bound: float) -> tuple[np.ndarray, Any, Any] | None:
    """``(x, solution, certificate)`` of a given point when the certifier certifies it (in exact
    arithmetic where its margins are below the float threshold) and its objective is within
    ``bound``; else ``None``.

    >>> _given(None, None, 1.0) is None
    True
    """
    from lmic.certify import certified_solution
    from lmic.rescue import exact_rescue_point
    from lmic.solution import Solution

    if x is None:
        return None
    s = -1.0 if problem.objective.sense == "max" else 1.0
    given = Solution(status="optimal", x=np.asarray(x, dtype=float), backend="given point")
    xs, mine, cert = _certified(problem, given)
    if cert.verdict == "rejected":  # margins below the float threshold: the exact proof decides
        cert = exact_rescue_point(problem, mine, cert) or cert
        mine, cert = certified_solution(problem, mine, cert)  # the point proved, if it moved
        xs = np.asarray(mine.x, dtype=float)
    value = problem.objective.value(xs)
    if cert.verdict != "certified" or value is None or not s * float(value) <= s * bound:
        return None
    return xs, mine, cert


def _certified(problem: Problem, sol: Any) -> tuple[np.ndarray, Any, Any]:
    """``(x, solution, certificate)``: a solve's point (its first ``problem.n`` entries: the
    backed-off and margin problems append variables) certified against ``problem``."""
    from lmic.certify import certified_solution, certify
    from lmic.solution import Solution

    x = np.asarray(sol.x, dtype=float)[: problem.n]
    mine = Solution(status=sol.status, x=x, objective=problem.objective.value(x), backend=sol.backend)
    mine, cert = certified_solution(problem, mine, certify(problem, mine))
    return np.asarray(mine.x, dtype=float), mine, cert
