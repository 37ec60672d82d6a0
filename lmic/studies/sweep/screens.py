"""A bisection's cheap steps: one certified solve (:func:`screen`) and a point's reach (:func:`reach`).

Split out of :mod:`lmic.studies.sweep.points` (which re-exports these names). A screen decides
an interior value of a bisection by one fixed-margin solve, certified; its "not certified" only
moves the bracket and is never reported as evidence (the bracket's final end is proven by the
full policy). :func:`reach` models how far a certified point stays feasible as the parameter
moves, so that the point can be certified again further up without a solve.

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
>>> P = lambda v: Problem([Variable("p", "scalar", (1, 1))],
...     [LMI("v - p > 0", 1, sp.csc_matrix([[v, -1.0]]))], LinearConstraints.empty(1),
...     Objective("feasibility", [0.0, 0.0]))
>>> round(reach(P(3.0), P(1.0), np.array([1.0])), 12)   # 2 - 2 s > 0 for s < 1
1.0
"""

from __future__ import annotations

import math
import time
from dataclasses import replace
from typing import Any

import numpy as np

from lmic.errors import LmicError
from lmic.ir.problem import Problem
from lmic.policy import feasibility_problem, min_rel_margin
from lmic.studies.sweep.results import PointResult

__all__ = [
    "screen",
    "reach",
    "scalar_derived",
    "SCREEN_RELATIVE_MARGIN",
    "SCREEN_FIRST_ORDER_ITERS",
    "SCREEN_FIRST_ORDER_TOL",
    "SCREEN_INTERIOR_POINT",
    "STRETCH_FRACTION",
]


def scalar_derived(cert: Any) -> dict[str, float]:
    """The finite scalar derived values of a certificate.

    >>> scalar_derived(None)
    {}
    """
    out: dict[str, float] = {}
    for item in getattr(cert, "derived", None) or []:
        v = item.get("value")
        if isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(float(v)):
            out[item["name"]] = float(v)
    return out


#: the relative margin a screen imposes (``SolveOptions.relative_margin`` for scale-free
#: problems, floored by the strict reduction at ten times the solver's tolerance): near a
#: supremum the best relative margin is about ``rtol`` (``qib.thm1``, n = 10: ``6e-7`` at
#: ``0.9999 sup``), so the default ``1e-4`` would call feasible values "not certified"
SCREEN_RELATIVE_MARGIN = 1e-7
#: iterations a first-order screen may take before the interior-point backend of the route
#: decides the value instead (near a supremum SCS needs seconds where Clarabel needs 0.1 s)
SCREEN_FIRST_ORDER_ITERS = 600
#: the interior-point backend a screen falls back to when the route has it
SCREEN_INTERIOR_POINT = "clarabel"
#: the tolerance of a first-order screen (its imposed margin is ten times this)
SCREEN_FIRST_ORDER_TOL = 1e-5


def screen(
    problem: Problem,
    backend: Any = None,
    options: Any = None,
    *,
    value: float = math.nan,
    first_order: bool = True,
) -> PointResult | None:
    """One solve, certified: the cheap decision of a bisection's interior value.

    The first backend of the route (:func:`lmic.policy.route`) solves the feasibility problem
    once, with the fixed-margin reduction alone on problems that are not small (no max-margin
    retry, no other backend) and a small imposed margin (:data:`SCREEN_RELATIVE_MARGIN`: near
    a supremum the margins are small). On the escalating route a first-order first backend
    gets at most :data:`SCREEN_FIRST_ORDER_ITERS` iterations; when it does not decide in them
    (or ``first_order`` is ``False``) the first interior-point backend of the route decides
    the value (``PointResult.fallback``). Returns

    * ``feasible`` when the certifier certifies the point (the same evidence as
      :func:`decide`);
    * ``infeasible`` when the point's certificate is a verified infeasibility proof;
    * ``undecided`` with ``screened = True`` otherwise (the solver says infeasible, fails, or
      returns a point the certifier rejects; a ray is not verified here, its verification can
      cost seconds): enough to move a bisection's
      upper end, never reported as evidence (the bracket's final end is decided by
      :func:`decide`, which escalates; if it is certified there, the bisection moves up);
    * ``None`` when the backend cannot take the problem, or the problem is small for an
      interior-point backend (solves of milliseconds): the caller runs :func:`decide`.

    Examples
    --------
    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("p", "scalar", (1, 1))], [LMI("p > 0", 1, sp.csc_matrix([[0., 1.]]))],
    ...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
    >>> screen(p, "clarabel") is None   # small: the full policy decides
    True
    """
    from lmic.backends.registry import get_backend
    from lmic.options import SolveOptions
    from lmic.policy import is_auto, route
    from lmic.reductions.strict import is_small

    judge = feasibility_problem(problem)
    options = options or SolveOptions()
    auto = is_auto(backend)
    try:
        names = route(judge, backend)
        backends = [b if not isinstance(b, str) else get_backend(b) for b in names]
    except LmicError:
        return None
    first = backends[0]
    if not first.supports(judge):
        return None
    tried: list[str] = []
    if auto and not first.interior_point:
        if first_order:
            res = _screen_on(first, judge, options, auto, value, max_iter=SCREEN_FIRST_ORDER_ITERS)
            if res.outcome in ("feasible", "infeasible") or res.status == "infeasible":
                return res
            tried = res.attempts
        # Clarabel first where the route has it: near a supremum its screens take a tenth of
        # a second at n = 10 where CVXOPT's take seconds (and a minute on infeasible values at
        # n = 20: CVXOPT ends 'inaccurate' after its iteration limit)
        ips = [b for b in backends[1:] if b.interior_point and b.supports(judge)]
        ip = next((b for b in ips if b.name == SCREEN_INTERIOR_POINT), ips[0] if ips else None)
        if ip is None:
            return None if not first_order else res
        first = ip
    if is_small(judge) and first.interior_point:
        return None  # solves of milliseconds: the full policy decides (max-margin first)
    res = _screen_on(first, judge, options, auto, value)
    res.attempts = tried + res.attempts
    res.fallback = bool(tried) or (auto and not first_order)
    return res


def _screen_on(
    be: Any, judge: Problem, options: Any, auto: bool, value: float, max_iter: int | None = None
) -> PointResult:
    """One fixed-margin solve of ``judge`` on ``be``, certified (:func:`screen`)."""
    from lmic.certify import certify
    from lmic.outcome import verdict_of
    from lmic.policy import step_options
    from lmic.reductions.pipeline import solve

    opts = step_options(be, options) if auto else options
    if options.strict == "auto":
        opts = replace(opts, strict="fixed-margin")
    opts = replace(opts, relative_margin=min(opts.relative_margin, SCREEN_RELATIVE_MARGIN))
    if max_iter is not None:
        opts = replace(opts, max_iter=max_iter if opts.max_iter is None else min(opts.max_iter, max_iter))
    if not be.interior_point:
        # SCS's margin is floored at ten times its tolerance: at 1e-3 a relative margin of 1e-2
        # would call values within a few per cent of the supremum infeasible
        opts = replace(opts, tol=min(opts.tol, SCREEN_FIRST_ORDER_TOL))
    t0 = time.perf_counter()
    sol = solve(be, judge, opts)
    t1 = time.perf_counter()
    if sol.status != "feasible" and sol.status != "optimal":
        # no point to certify; a ray's verification can cost seconds, and only the final end's
        # evidence is reported (proven there by the full policy)
        res = PointResult(value=value, outcome="undecided", proof="", status=sol.status, verdict="undecided")
        res.proof = f"not certified by one solve ({sol.status}); moves the bisection's bracket only"
        res.solve_s, res.screened, res.solution = float(sol.solve_s or (t1 - t0)), True, sol
        res.attempts = [f"{be.label} / screen/{sol.strategy}: {sol.status} -> not certified (screen, unproven)"]
        res.first_order = not be.interior_point
        return res
    cert = certify(judge, sol)
    verdict = verdict_of(judge, sol, cert)
    res = PointResult(value=value, outcome="undecided", proof=verdict, status=sol.status, verdict=verdict)
    res.solve_s, res.certify_s = float(sol.solve_s or (t1 - t0)), time.perf_counter() - t1
    res.certificate, res.solution = cert, sol
    res.rel_margin = min_rel_margin(cert)
    line = f"{be.label} / screen/{sol.strategy}: {sol.status} -> {{}} ({t1 - t0:.2f} s)"
    if verdict == "certified":
        res.outcome, res.proof, res.x = "feasible", "certified", sol.x
        res.derived = scalar_derived(cert)
    elif verdict == "infeasible-certified":
        res.outcome = "infeasible"
        res.proof = "infeasible-certified: " + str(getattr(cert, "reason", "") or "verified Farkas ray")
    else:
        # not certified here, nothing proven: the bisection's upper end may move to it (the
        # final end is decided by the full policy, which escalates)
        res.proof = f"not certified by one solve ({sol.status}, {verdict}); moves the bisection's bracket only"
        res.screened = True
        verdict = "not certified (screen, unproven)"
    res.attempts = [line.format(verdict)]
    res.first_order = not be.interior_point
    return res


#: how far along the modelled reach of a certified point :meth:`Evaluator.stretch` tries it
STRETCH_FRACTION = 0.95


def reach(pa: Problem, pb: Problem, x: np.ndarray) -> float | None:
    """The largest ``s`` keeping ``x`` strictly feasible on the segment from ``pa`` to ``pb``.

    Every LMI and row at ``x`` is modelled as affine along the segment, ``M(s) = M_a + s (M_b -
    M_a)``; ``M(s)`` stays positive definite for ``s < -1 / lambda_min(L^-1 (M_b - M_a) L^-T)``
    (``M_a = L L^T``), ``inf`` when nothing decreases. ``None`` when ``x`` is not strictly
    feasible at ``pa`` or the problems differ in structure. Only a guess of where to look: the
    caller certifies ``x`` at the value it picks.

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> P = lambda v: Problem([Variable("p", "scalar", (1, 1))],
    ...     [LMI("v - p > 0", 1, sp.csc_matrix([[v, -1.0]]))], LinearConstraints.empty(1),
    ...     Objective("feasibility", [0.0, 0.0]))
    >>> reach(P(2.0), P(0.0), np.array([1.0]))   # 2 - 2 s - 1 > 0 for s < 1/2
    0.5
    """
    if pa.n != pb.n or len(pa.lmis) != len(pb.lmis) or len(pa.linear) != len(pb.linear) or len(x) != pa.n:
        return None
    s = math.inf
    for la, lb in zip(pa.lmis, pb.lmis, strict=True):
        if la.dim != lb.dim:
            return None
        Ma, Mb = la.matrix(x), lb.matrix(x)
        try:
            L = np.linalg.cholesky(Ma)
        except np.linalg.LinAlgError:
            return None
        Li = np.linalg.inv(L)
        D = Li @ (Mb - Ma) @ Li.T
        lam = float(np.linalg.eigvalsh(0.5 * (D + D.T))[0])
        if lam < 0:
            s = min(s, -1.0 / lam)
    if len(pa.linear):
        ra, rb = pa.linear.residuals(x), pb.linear.residuals(x)
        for k, kind in enumerate(pa.linear.kinds):
            if kind == "eq":
                if rb[k] != ra[k]:
                    return None
            elif ra[k] <= 0:
                return None
            elif rb[k] < ra[k]:
                s = min(s, ra[k] / (ra[k] - rb[k]))
    return s
