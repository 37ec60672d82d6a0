"""The default route's primal end from the dual end: a certified point when the solver's is not.

On an optimisation problem whose optimum the solvers resolve only to their tolerance (the
bounded-real lemma of a near-unstable system: Clarabel stops at ``AlmostSolved``, its point
is rejected or gives no rigorous primal end), the dual end is often proven all the same (the
repaired dual, the face route). :func:`upper_route` then asks
:func:`lmic.upper_end.upper_from_lower` for a point proved feasible near that end, certifies
it with the certifier against the original problem, and records it in the enclosure as a
``restored point`` (``restored_x``, re-proved by ``lmic audit``). When the enclosure then meets
the route's gap, the step's outcome is ``certified`` with that point (its evidence: the
certifier's and the enclosure's, both proofs); otherwise the step is left as it was, with the
better enclosure.

Examples
--------
>>> upper_budget(0.5), upper_budget(5.0), upper_budget(60.0)
(20.0, 100.0, 150.0)
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from lmic.certify.enclosure import GAP_TARGET
from lmic.ir.problem import Problem
from lmic.outcome import Outcome

__all__ = ["UPPER_FACTOR", "UPPER_MIN_S", "upper_budget", "upper_route"]

#: the search of :func:`upper_route` may take this many times the step's solve ...
UPPER_FACTOR = 20.0
#: ... and at least this many seconds (n = 20 near-unstable bounded-real lemma: 1.5 to 3 s)
UPPER_MIN_S = 20.0
#: ... and at most this many, over all the steps of one route (every solve of the search is
#: stopped at the deadline)
UPPER_MAX_S = 150.0
#: the first backoff of the margin solve, as a fraction of the route's gap
#: (:func:`lmic.upper_end.upper_from_lower`'s ``start``)
START_WITHIN = 0.9
#: backends whose points are first-order accurate, and the interior point used in their place
FIRST_ORDER = ("scs", "cosmo")
INTERIOR_FALLBACK = "clarabel"
#: the backends for a recentred (dense) solve the step's backend fails: SDPA solves the
#: 50-state bounded-real lemma's where Clarabel stops at NumericalError (CVXOPT: over 10 min)
ALTERNATIVES = ("sdpa", "clarabel")


def upper_budget(solve_s: float) -> float:
    """Seconds for :func:`upper_route` after a solve of ``solve_s`` seconds (at most :data:`UPPER_MAX_S`)."""
    return min(UPPER_MAX_S, max(UPPER_MIN_S, UPPER_FACTOR * float(solve_s)))


def _ends(problem: Problem, enc: dict[str, Any]) -> tuple[float | None, float | None]:
    """``(dual end, primal end)`` of an enclosure in the problem's own sense."""
    if problem.objective.sense == "min":
        return enc.get("lower"), enc.get("upper")
    return enc.get("upper"), enc.get("lower")


def _solution(problem: Problem, sol: Any, x: np.ndarray, message: str) -> Any:
    from lmic.solution import Solution

    return Solution(
        status=sol.status,
        x=x,
        objective=problem.objective.value(x),
        duals=sol.duals,
        backend=sol.backend,
        message=message,
    )


def upper_route(
    problem: Problem,
    out: Outcome,
    enc: dict[str, Any] | None,
    backend: Any,
    options: Any,
    exact: bool,
    gap: float,
    steps: list[dict[str, Any]],
) -> tuple[Outcome, dict[str, Any] | None, float]:
    """The step ``out`` (its enclosure ``enc``) with a primal end from its dual end, when it lacks one.

    Runs only for an optimisation problem whose step has a solution with a dual point and whose
    enclosure has no primal end or a relative gap above
    :data:`lmic.certify.enclosure.GAP_TARGET`. Returns the (possibly new) outcome, enclosure
    and the seconds spent; ``steps`` are the route's records so far, the last one this step's: it
    gets ``upper`` (what was tried) and the new ``rel_gap`` / ``verdict``. The searches of one
    route share :data:`UPPER_MAX_S` seconds (the earlier steps' ``upper.time_s``).
    """
    step = steps[-1]
    spent = sum(float((s.get("upper") or {}).get("time_s", 0.0)) for s in steps[:-1])
    sol = out.solution
    if problem.objective.sense == "feasibility" or sol is None:
        return out, enc, 0.0
    if out.verdict not in ("certified", "undecided", "rejected"):
        return out, enc, 0.0
    if enc is not None and enc.get("rel_gap") is not None and enc["rel_gap"] <= GAP_TARGET:
        return out, enc, 0.0
    from lmic.certify import certify
    from lmic.certify.enclosure import enclosure, with_primal
    from lmic.upper_end import upper_from_lower

    t0 = time.perf_counter()
    solve_s = float(getattr(sol, "solve_s", 0.0) or 0.0)
    left = UPPER_MAX_S - spent
    if left <= 0.0:
        step["upper"] = {"proven": False, "reason": f"the route's {UPPER_MAX_S:g} s for the primal end are spent"}
        return out, enc, 0.0
    deadline = t0 + min(upper_budget(solve_s), left)
    if enc is None:  # no certified point: the dual end alone (the face route needs no dual point)
        enc = enclosure(problem, sol.duals or None, None, exact=exact, budget_s=upper_budget(solve_s))
    dual_end, primal = _ends(problem, enc)
    if dual_end is None:
        return out, enc, time.perf_counter() - t0
    # the solves want an interior point: a first-order step's backend gives points violated by
    # its tolerance, far above the margins of a near-singular slice
    label = str(getattr(backend, "name", backend) or "").lower()
    solver = INTERIOR_FALLBACK if any(k in label for k in FIRST_ORDER) else backend

    def passes(x: np.ndarray) -> bool:  # the certifier's verdict, for the step's outcome
        return certify(problem, _solution(problem, sol, x, "")).verdict == "certified"

    others = tuple(b for b in ALTERNATIVES if b not in str(getattr(solver, "name", solver)).lower())
    # the first margin solve just inside the route's gap: a point proved there meets it
    r = upper_from_lower(
        problem,
        dual_end,
        solver,
        options,
        x_hint=sol.x,
        deadline=deadline,
        check=passes,
        alternatives=others,
        start=START_WITHIN * gap,
    )
    step["upper"] = {k: r[k] for k in ("proven", "rel_gap", "reason")}
    step["upper"]["time_s"] = time.perf_counter() - t0
    sgn = -1.0 if problem.objective.sense == "max" else 1.0
    if not r["proven"] or (primal is not None and sgn * r["value"] >= sgn * primal):
        return out, enc, time.perf_counter() - t0
    x = np.asarray(r["x"], dtype=float)
    base = dict(enc)
    base["upper" if problem.objective.sense == "min" else "lower"] = None
    enc2 = dict(with_primal(base, r["value"], "restored point"), restored_x=x.tolist())
    enc2.pop("polish", None)
    enc2["consistent"] = enc2.get("consistent", True)
    step["rel_gap"] = enc2.get("rel_gap")
    step.pop("gap_note", None)
    if enc2.get("rel_gap") is None or enc2["rel_gap"] > gap or getattr(out.certificate, "verdict", None) == "certified":
        # a better enclosure; the step's point stands (a point that holds from an inexact solve
        # is upgraded by the route when the enclosure meets the gap)
        return out, enc2, time.perf_counter() - t0
    if r["checked_x"] is None:  # the rigorous proof holds; no point met the certifier's threshold
        step["upper"]["certifier"] = "no point of the search met the certifier's threshold"
        return out, enc2, time.perf_counter() - t0
    from lmic.outcome import evidence_of

    xc = np.asarray(r["checked_x"], dtype=float)
    sol2 = _solution(
        problem, sol, xc, f"the most interior point at objective {r['checked_value']:.10g} (lmic.upper_end)"
    )
    cert2 = certify(problem, sol2)
    new = Outcome(
        "certified",
        evidence_of("certified", cert2),
        f"{cert2.reason} (the most interior point near the proven dual end; the solver's point: "
        f"{out.verdict}); the enclosure proves the optimum: {enc2['reason']}",
        list(out.attempts),
        sol2,
        cert2,
        out.backend,
    )
    step["verdict"] = "certified"
    return new, enc2, time.perf_counter() - t0
