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

from lmic.certify.enclosure import GAP_TARGET, relative_gap
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


#: the rows' relative margin of :func:`restored_end`'s last restoration solve: a scalar row that
#: vanishes at the optimum (sampled_euler.thm3's ``epsilon > 0``) is met by the solver only to its
#: accuracy (random 12 states, seed 3, Clarabel: relative gap 1.9e-6 -> 4e-7)
RESTORE_ROW_MARGIN = 1e-7
#: the ``(tightening, rows' margin)`` of :func:`restored_end`'s restoration solves, in turn: the
#: smallest tightening that gives a provable point, then the rows at a larger margin
#: (:func:`lmic.backoff.restore`; ``None``: the rows as tightened)
RESTORE_RELS: tuple[tuple[float, float | None], ...] = (
    (1e-10, None),
    (1e-9, None),
    (1e-8, None),
    (1e-10, RESTORE_ROW_MARGIN),
)


def restored_end(problem: Problem, x: Any, backend: Any, options: Any, outer: tuple[Any, ...] = ()) -> dict[str, Any]:
    """A point proved feasible near the solver's point ``x`` (which gives no rigorous primal
    end): the restoration solve of :func:`lmic.backoff.restore` at the smallest tightening of
    :data:`RESTORE_RELS` that gives a provable point, then moved towards ``x`` and each of
    ``outer`` as far as the proof allows (:func:`lmic.certify.enclosure.polish_primal`).

    Returns
    -------
    dict
        ``proven``, ``x`` (a list), ``value`` (the rigorous objective), ``reason``.

    >>> from lmic.testing.conformance import CASES
    >>> p = CASES["max_sense"].build()
    >>> restored_end(p, None, "clarabel", None)["proven"]
    False
    """
    from lmic.backoff import restore
    from lmic.certify.enclosure import polish_primal, primal_end

    if x is None:
        return {"proven": False, "x": None, "value": None, "reason": "no solver point to restore"}
    minimise = problem.objective.sense == "min"
    for rel, row_rel in RESTORE_RELS:
        rest = restore(problem, x, backend, options, rel=rel, row_rel=row_rel)
        pe = primal_end(problem, np.asarray(rest["x"], dtype=float)) if rest["x"] is not None else {}
        if not pe.get("proven"):
            continue
        best = {"proven": True, "x": rest["x"], "value": pe["value"], "reason": f"restored point (tightening {rel:g})"}
        for out in (x, *outer):  # as close to the solver's point as the proof allows
            pol = polish_primal(problem, np.asarray(best["x"], dtype=float), np.asarray(out, dtype=float))
            if pol["proven"] and (pol["value"] < best["value"]) == minimise:
                best.update(x=pol["x"], value=pol["value"])
        return best
    return {"proven": False, "x": None, "value": None, "reason": "no restoration solve gave a provable point"}


def sgn_gap(problem: Problem, value: float, dual_end: float) -> float:
    """The relative gap of a primal end ``value`` to the dual end (VSDP's normalisation).

    >>> from lmic.testing.conformance import CASES
    >>> round(sgn_gap(CASES["max_sense"].build(), 1.0, 2.0), 6)
    0.666667
    """
    hi, lo = (value, dual_end) if problem.objective.sense == "min" else (dual_end, value)
    return relative_gap(lo, hi)


def upper_route(
    problem: Problem,
    out: Outcome,
    enc: dict[str, Any] | None,
    backend: Any,
    options: Any,
    exact: bool,
    gap: float,
    steps: list[dict[str, Any]],
    *,
    boxes: bool = False,
) -> tuple[Outcome, dict[str, Any] | None, float]:
    """The step ``out`` (its enclosure ``enc``) with a primal end from its dual end, when it lacks one.

    Runs only for an optimisation problem whose step has a solution with a dual point and whose
    enclosure has no primal end or a relative gap above
    :data:`lmic.certify.enclosure.GAP_TARGET`. Returns the (possibly new) outcome, enclosure
    and the seconds spent; ``steps`` are the route's records so far, the last one this step's: it
    gets ``upper`` (what was tried) and the new ``rel_gap`` / ``verdict``. The searches of one
    route share :data:`UPPER_MAX_S` seconds (the earlier steps' ``upper.time_s``).

    ``boxes=True`` (the route's last resort, once, on its best step): when the search from the
    dual end proves nothing or there is no dual end, the boxed search of
    :func:`lmic.upper_end.upper_from_boxes` (recorded as ``upper_boxed``).
    """
    step = steps[-1]
    key = "upper_boxed" if boxes else "upper"
    spent = sum(float((s.get(k) or {}).get("time_s", 0.0)) for s in steps[:-1] for k in ("upper", "upper_boxed"))
    sol = out.solution
    if problem.objective.sense == "feasibility" or sol is None:
        return out, enc, 0.0
    if out.verdict not in ("certified", "undecided", "rejected"):
        return out, enc, 0.0
    if enc is not None and enc.get("rel_gap") is not None and enc["rel_gap"] <= GAP_TARGET:
        return out, enc, 0.0
    from lmic.certify import certified_solution, certify
    from lmic.certify.enclosure import enclosure, with_primal
    from lmic.upper_end import upper_from_boxes, upper_from_lower

    t0 = time.perf_counter()
    solve_s = float(getattr(sol, "solve_s", 0.0) or 0.0)
    left = UPPER_MAX_S - spent
    if left <= 0.0:
        step[key] = {"proven": False, "reason": f"the route's {UPPER_MAX_S:g} s for the primal end are spent"}
        return out, enc, 0.0
    deadline = t0 + min(upper_budget(solve_s), left)
    if enc is None:  # no certified point: the dual end alone (the face route needs no dual point)
        enc = enclosure(problem, sol.duals or None, None, exact=exact, budget_s=upper_budget(solve_s))
    dual_end, primal = _ends(problem, enc)
    if dual_end is None and not boxes:
        return out, enc, time.perf_counter() - t0
    # the solves want an interior point: a first-order step's backend gives points violated by
    # its tolerance, far above the margins of a near-singular slice
    label = str(getattr(backend, "name", backend) or "").lower()
    solver = INTERIOR_FALLBACK if any(k in label for k in FIRST_ORDER) else backend

    def passes(x: np.ndarray) -> bool:  # the certifier's verdict, for the step's outcome
        return certify(problem, _solution(problem, sol, x, "")).verdict == "certified"

    others = tuple(b for b in ALTERNATIVES if b not in str(getattr(solver, "name", solver)).lower())
    r: dict[str, Any] = {"proven": False}
    if dual_end is not None and not boxes:
        r = upper_from_lower(
            problem,
            dual_end,
            solver,
            options,
            x_hint=sol.x,
            deadline=deadline,
            check=passes,
            alternatives=others,
            start=START_WITHIN * gap,  # the first margin solve just inside the route's gap
        )
    if boxes and sol.x is not None:  # first a point restored near the solver's (cheap: one or three solves)
        tight = () if enc.get("tight_x") is None else (enc["tight_x"],)  # the tight re-solve's point (tighten)
        r = dict(restored_end(problem, sol.x, solver, options, outer=tight), what="point restored near the solver's")
        r["checked_x"] = r["x"] if r["proven"] and passes(np.asarray(r["x"], dtype=float)) else None
        r["checked_value"] = r["value"] if r["checked_x"] is not None else None
    if boxes and not r["proven"]:  # no dual end to aim at (or the search from it failed): box by box
        r = upper_from_boxes(
            problem, solver, options, x_hint=sol.x, deadline=deadline, check=passes, alternatives=others
        )
        r["what"] = "point proved in a box |x| <= R (lmic.upper_end.upper_from_boxes)"
    if boxes and r["proven"] and dual_end is not None:  # either search's gap is to the proven dual end
        r["rel_gap"] = max(0.0, sgn_gap(problem, r["value"], dual_end))
    step[key] = {k: r.get(k) for k in ("proven", "rel_gap", "reason")}
    step[key]["time_s"] = time.perf_counter() - t0
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
    if step["rel_gap"] is None:
        step["gap_note"] = "no certified lower end" if problem.objective.sense == "min" else "no certified upper end"
    else:
        step.pop("gap_note", None)
    holds = getattr(out.certificate, "verdict", None) == "certified"
    if enc2.get("rel_gap") is None or enc2["rel_gap"] > gap or (holds and not boxes):
        # a better enclosure; the step's point stands (a point that holds from an inexact solve
        # is upgraded by the route when the enclosure meets the gap)
        return out, enc2, time.perf_counter() - t0
    if r["checked_x"] is None:  # the rigorous proof holds; no point met the certifier's threshold
        step[key]["certifier"] = "no point of the search met the certifier's threshold"
        return out, enc2, time.perf_counter() - t0
    from lmic.outcome import evidence_of

    xc = np.asarray(r["checked_x"], dtype=float)
    what = r.get("what", "most interior point near the proven dual end")
    sol2 = _solution(problem, sol, xc, f"the {what} at objective {r['checked_value']:.10g} (lmic.upper_end)")
    sol2, cert2 = certified_solution(problem, sol2, certify(problem, sol2))
    new = Outcome(
        "certified",
        evidence_of("certified", cert2),
        f"{cert2.reason} (the {what}; the solver's point: "
        f"{out.verdict}); the enclosure proves the optimum: {enc2['reason']}",
        list(out.attempts),
        sol2,
        cert2,
        out.backend,
    )
    step["verdict"] = "certified"
    return new, enc2, time.perf_counter() - t0
