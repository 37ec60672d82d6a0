"""The tight re-solves of an enclosure whose gap misses the target, and the cross re-solves.

:func:`tighten` runs after the first enclosure of an optimisation answer
(:func:`lmic.routes.enclosure_of`) when its relative gap is above the target
(:data:`lmic.certify.enclosure.GAP_TARGET`) on an interior-point backend:

1. **tight re-solves** on the same backend at each of :data:`TIGHT_TOLS` below the solve's
   tolerance, loosest first, until the gap meets the target; each re-solve's enclosure is
   proved on its own and the better proven end of each is kept
   (:func:`lmic.certify.enclosure.best_of`); a re-solve that did not halve the gap ends the
   ladder (the gap is then not the tolerance's);
2. **cross re-solves** on the other interior-point backends (:data:`CROSS_BACKENDS`, in
   order, until the gap meets the target) when the gap still misses the target *because the
   backend could not go tighter*: a tight re-solve ended without reaching its tolerance
   (SDPA's ``pdFEAS``: status ``inaccurate``) or with no point. A cross re-solve runs at the
   first tight tolerance, and its enclosure's own
   re-solves (perturbed and centring problems) run on that backend too. Its point and dual are
   candidates like any other: lmic proves both ends (the primal end at the point, the dual end
   by the rigorous bound), and the record names the backends (``cross``). The answer's point,
   status and gains stay the chosen backend's.

Every step runs only when the enclosure's budget has about twice the first solve's time left,
and a cross re-solve only on a backend whose estimated time is affordable
(:func:`lmic.route_rule.affordable`: not Clarabel's dense KKT of order 13041 after SDPA's 3 s
on SDPLIB arch8).

Examples
--------
>>> _cross_candidates("sdpa"), _cross_candidates("cvxpy:CLARABEL")
(('clarabel', 'cvxopt'), ('cvxopt', 'sdpa'))
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np

from lmic.ir.problem import Problem
from lmic.route_escalation import seconds_left
from lmic.route_rule import affordable

__all__ = ["TIGHT_TOLS", "CROSS_BACKENDS", "tighten"]

#: the tolerances of :func:`tighten`'s re-solves, loosest first: Clarabel stops at
#: ``AlmostSolved`` at 1e-10 on SDPLIB control3 where 1e-9 closes the gap (2.1e-6 -> 3e-7)
TIGHT_TOLS = (1e-9, 1e-10)
#: the interior-point backends the cross re-solves may use, in this order (not the answer's
#: backend, nor the solver a modelling-layer backend wraps)
CROSS_BACKENDS = ("clarabel", "cvxopt", "sdpa")


def tighten(
    problem: Problem,
    enc: dict[str, Any],
    x: Any,
    exact: bool,
    backend: Any,
    options: Any,
    resolve: Any,
    solve_point: Any,
    deadline: Any = None,
    solve_s: float = 0.0,
    target: float | None = None,
    closures: Callable[[str], tuple[Any, Any]] | None = None,
) -> dict[str, Any]:
    """A gap above ``target`` (default :data:`lmic.certify.enclosure.GAP_TARGET`) on an
    interior-point backend: the tight re-solves, then the cross re-solves (module docstring).

    When the tight point's primal end is met only to round-off, the end comes from a point
    polished toward it (``restored point``); without any proven end there, ``tight_x`` records
    the tight point for the restoration of :func:`lmic.api.solve`. With ``deadline`` (a
    :func:`time.perf_counter` value, or a callable giving the seconds left), a re-solve runs
    only when about twice ``solve_s`` (the first solve's time) is left, and its enclosure gets
    what is left. ``closures(name)`` gives ``(resolve, solve_point)`` on backend ``name`` for
    the cross re-solves' enclosures; without it there is none.

    >>> tighten(None, {"rel_gap": 1e-8}, None, False, "clarabel", None, None, None)
    {'rel_gap': 1e-08}
    """
    from lmic.certify.enclosure import GAP_TARGET
    from lmic.options import SolveOptions

    goal = GAP_TARGET if target is None else float(target)
    gap = enc.get("rel_gap")
    label = str(getattr(backend, "name", backend) or "")
    if (gap is not None and gap <= goal) or "scs" in label.lower():
        return enc
    key = "upper" if problem.objective.sense == "min" else "lower"
    if gap is None and enc.get(key) is not None:
        # the primal end is proven, the dual end not (the dual search tried its perturbed and centred routes): a
        # tighter solve puts the dual nearer its cone's boundary (BRL n = 20: twice the time, nothing proved)
        return enc
    base = options if options is not None else SolveOptions()

    def fits() -> bool:  # a re-solve (typically slower than the first) fits the budget
        return deadline is None or seconds_left(deadline) >= 2.0 * solve_s

    out = enc
    stuck = False  # whether a tight re-solve ended short of its tolerance
    for tol in [t for t in TIGHT_TOLS if t < base.tol]:
        if not fits():
            break
        tight = _tight(base, tol)
        before = out
        out, status = _tighten_once(problem, out, x, exact, backend, tight, resolve, solve_point, deadline, key)
        stuck = stuck or status != "optimal"
        if _met(out, goal):
            return out
        if out is not before and _no_progress(before, out):
            # a tight solve that ran and did not halve the gap: the gap is not the solver's
            # tolerance (SDPLIB qap: a primal end limited by the problem), a tighter one will not
            break
    if not stuck or closures is None:
        return out
    pre = out.get("rel_gap")  # the gap the backend itself reached
    for other in _cross_candidates(label):
        if not fits():
            break
        left = None if deadline is None else seconds_left(deadline)
        if not affordable(problem, label, solve_s, other, left):
            continue  # its estimated time is far beyond the solve it would narrow (route_rule)
        # at the first tight tolerance (a dual near the optimum is what the proof needs); the
        # user's solver-specific settings (``extra``) are not the other backend's
        cross = replace(_tight(base, min(base.tol, TIGHT_TOLS[0])), extra={})
        res, pts = closures(other)
        before = out
        out, _ = _tighten_once(problem, out, x, exact, other, cross, res, pts, deadline, key)
        if out is not before and _narrowed(before, out):
            by = [*out.get("cross", {}).get("backends", []), other]
            out = dict(out, cross={"backend": other, "backends": by, "rel_gap_before": pre})
            was = f" from {pre:.2g}" if pre is not None else ""
            out["reason"] = f"{out.get('reason')}; narrowed{was} by re-solves on {', '.join(by)}"
        if _met(out, goal):
            break  # else the next other backend (sampled_euler.thm2 n = 12 seed 2 on SDPA:
            # Clarabel's cross re-solve narrowed 4.3e-5 to 1.2e-6)
    return out


def _tight(base: Any, tol: float) -> Any:
    """``base`` at tolerance ``tol``. The strict margin shrinks with it (strict.py keeps
    ``delta >= 10 tol``): at the default 1e-7 the primal end of a problem whose multipliers have
    trace ~300 stays 3e-5 above the optimum."""
    return replace(base, tol=tol, margin=min(base.margin, 10.0 * tol))


def _narrowed(before: dict[str, Any], after: dict[str, Any]) -> bool:
    """Whether ``after`` proves both ends where ``before`` did not, or a relative gap at least 10 %
    smaller.

    >>> _narrowed({"rel_gap": 1e-5}, {"rel_gap": 0.99e-5}), _narrowed({"rel_gap": None}, {"rel_gap": 1e-5})
    (False, True)
    """
    g0, g1 = before.get("rel_gap"), after.get("rel_gap")
    return g1 is not None and (g0 is None or g1 < 0.9 * g0)


def _met(enc: dict[str, Any], goal: float) -> bool:
    return enc.get("rel_gap") is not None and enc["rel_gap"] <= goal


def _cross_candidates(label: str) -> tuple[str, ...]:
    """The backends a cross re-solve may use after ``label``'s (module docstring)."""
    inner = label.lower().split(":")[-1]
    return tuple(b for b in CROSS_BACKENDS if b != inner)


def _no_progress(before: dict[str, Any], after: dict[str, Any]) -> bool:
    """Whether a re-solve's enclosure ``after`` failed to halve the relative gap of ``before``
    (both gaps known).

    >>> _no_progress({"rel_gap": 1e-4}, {"rel_gap": 0.9e-4}), _no_progress({"rel_gap": 1e-4}, {"rel_gap": 1e-6})
    (True, False)
    """
    g0, g1 = before.get("rel_gap"), after.get("rel_gap")
    return g0 is not None and g1 is not None and g1 > 0.5 * g0


def _tighten_once(
    problem: Problem,
    enc: dict[str, Any],
    x: Any,
    exact: bool,
    backend: Any,
    tight: Any,
    resolve: Any,
    solve_point: Any,
    deadline: Any,
    key: str,
) -> tuple[dict[str, Any], str]:
    """One re-solve on ``backend`` with ``tight`` options and the better proven end of each:
    ``(enclosure, the re-solve's status)`` (``"error"`` when it gave no point and dual)."""
    from lmic.certify.enclosure import best_of, enclosure, polish_primal, with_primal
    from lmic.errors import LmicError
    from lmic.policy import decide

    try:
        # the policy's strategies on this backend (an AlmostSolved solve is re-tried preconditioned
        # at its point: Clarabel at 1e-9 on SDPLIB control3)
        left = None if deadline is None else max(0.0, seconds_left(deadline))
        sol2 = decide(problem, backend, tight, rescue=False, budget_s=left).solution  # strategies within the budget
    except LmicError:
        return enc, "error"
    if sol2 is None or sol2.status not in ("optimal", "inaccurate") or sol2.x is None or not sol2.duals:
        return enc, "error"
    left = None if deadline is None else max(0.0, seconds_left(deadline))
    enc2 = enclosure(
        problem,
        sol2.duals,
        sol2.x,
        exact=exact,
        resolve=resolve,
        solve_point=solve_point,
        solve_s=float(getattr(sol2, "solve_s", 0.0) or 0.0),
        budget_s=left,
    )
    inner = enc.get("restored_x") if enc.get("primal") == "restored point" else x
    if enc2.get(key) is None and enc.get(key) is not None and inner is not None:
        # the tight point is met only to round-off: as close to it as the proof allows
        pol = polish_primal(problem, np.asarray(inner, dtype=float), np.asarray(sol2.x, dtype=float))
        if pol["proven"]:
            enc2 = dict(with_primal(enc2, pol["value"], "restored point"), restored_x=pol["x"])
            return best_of(enc, enc2, pol["x"]), sol2.status
    out = best_of(enc, enc2, sol2.x)
    if out.get(key) is None:
        out["tight_x"] = np.asarray(sol2.x, dtype=float).tolist()  # the restoration's target (solve())
    return out, sol2.status
