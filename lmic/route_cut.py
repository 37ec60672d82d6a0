"""The objective-cut search: a dual end where the dual route proves none, and a better primal
end on the way.

An optimisation answer whose enclosure has a primal end but no dual end (the dual has no
rational point near its optimum: an infimum that is not attained, ``uio_dt.thm4_1``, where the
solver also stops far above the infimum) is decided once more through feasibility problems:
the problem with the extra row "objective no better than ``r``"
(:func:`lmic.certify.enclosure_cut.cut_problem`), decided by the policy on the answer's
backend and on one more interior-point backend per cut (:data:`RAY_BACKENDS`).

* a **certified point** of the cut problem is a point of the problem: its rigorous objective
  (:func:`lmic.certify.enclosure_float.primal_end`, exactly when needed) is a new primal end
  when it is better (``restored point``, which ``lmic audit`` re-proves);
* a **global infeasibility proof** of the cut problem (an exact Farkas certificate,
  :func:`lmic.certify.enclosure_cut.prove_cut`) makes ``r`` the dual end;
* anything else (a bounded ray, a rejected point, a time-out) decides nothing at ``r``.

The search first steps away from the primal end ``U`` by ``CUT_FIRST * max(1, |U|)``, growing
the step :data:`CUT_GROWTH` times until a cut is proved infeasible, then bisects the largest
interval of ``[lower, U]`` not yet tried, until the relative gap meets
:data:`lmic.certify.enclosure.GAP_TARGET` (or ``--gap``, once :data:`RESOLUTION_UNDECIDED`
cuts decided nothing: the search has reached its resolution), :data:`MAX_CUT_STEPS` steps,
:data:`MAX_UNDECIDED` undecided steps (or :data:`WASTE_SHARE` of the budget spent on them),
or the budget (processor time, children's included). Every end it reports is a proof; the
record ``enclosure.cut`` says how many steps ran and what each decided.

Examples
--------
>>> cut_budget(0.2), cut_budget(30.0)
(10.0, 60.0)
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np

from lmic.certify.enclosure import GAP_TARGET, relative_gap
from lmic.formatting import interval_text
from lmic.ir.problem import Problem
from lmic.route_escalation import RouteClock

__all__ = [
    "proof_size",
    "CUT_MAX_ENTRIES",
    "cut_route",
    "cut_budget",
    "wants_cut",
    "MAX_CUT_STEPS",
    "MAX_UNDECIDED",
    "CUT_FIRST",
    "CUT_GROWTH",
    "RAY_BACKENDS",
]

#: the first cut's distance from the primal end, relative to ``max(1, |U|)``
CUT_FIRST = 1e-4
#: ... growing this many times a step until a cut is proved infeasible
CUT_GROWTH = 8.0
#: at most this many cut problems per search
MAX_CUT_STEPS = 40
#: ... of which at most this many decide nothing
MAX_UNDECIDED = 4
#: ... or this many inside the current interval once the gap meets ``--gap`` (cuts near the
#: optimum that neither a point nor a proof decides: the search has reached its resolution)
RESOLUTION_UNDECIDED = 2
#: the interior-point backends whose max-margin rays may prove a cut the route's backend did not
#: decide (uio_dt.thm4_1: CVXOPT's ray proves every cut below the infimum measured, Clarabel's
#: and SDPA's none: no exact separation, a multiplier not PSD), first tried first
RAY_BACKENDS = ("cvxopt", "clarabel", "sdpa")
#: the policy's exact proofs of bounded rays, per cut and backend, in processor seconds: a ray
#: that proves does so at once (uio_dt.thm4_1: 5 ms), failing ones took 7 s of an 11 s search
#: on a random 4-state instance whose cuts all fail
CUT_RAY_PROOF_S = 0.5
#: cuts that decided nothing may take this share of the budget (wall time): decided cuts are
#: progress, undecided ones near an optimum whose face is irrational are not (random 3-state
#: uio_dt.thm4_1 instances: 2-3 s each, four of them before)
WASTE_SHARE = 0.3
#: the search runs on problems whose :func:`proof_size` is at most this: an exact proof of a cut
#: costs 5 ms at 2.5e3 (uio_dt.thm4_1's example), 0.1-0.7 s at 5.7e3 (4 states) and 5-8 s at
#: 1.1e5 (the bounded-real lemma at 20 states), one or two a cut
CUT_MAX_ENTRIES = 30_000
#: the search's budget in processor seconds: ``max(FLOOR, FACTOR x)`` the route's solve time
CUT_BUDGET_FLOOR_S = 10.0
CUT_BUDGET_FACTOR = 2.0


def cut_budget(solve_s: float) -> float:
    """The search's processor-time budget after solves of ``solve_s`` seconds."""
    return max(CUT_BUDGET_FLOOR_S, CUT_BUDGET_FACTOR * float(solve_s))


def proof_size(problem: Problem) -> int:
    """``(1 + n)`` times the LMIs' lower-triangle entries: the scale of a cut's exact proof
    (:data:`CUT_MAX_ENTRIES`).

    >>> from lmic.testing.conformance import CASES
    >>> proof_size(CASES["max_sense"].build())  # one variable, one 3 x 3 LMI
    12
    """
    return (1 + problem.n) * sum(lmi.dim * (lmi.dim + 1) // 2 for lmi in problem.lmis)


def wants_cut(problem: Problem, enc: dict[str, Any] | None) -> bool:
    """Whether the search applies: an optimisation problem whose enclosure (of the IR's own
    problem) has its primal end and no dual end, small enough for exact proofs of its cuts
    (:func:`proof_size` at most :data:`CUT_MAX_ENTRIES`).

    >>> from lmic.testing.conformance import CASES
    >>> p = CASES["max_sense"].build()
    >>> wants_cut(p, {"lower": 1.0, "upper": None}), wants_cut(p, {"lower": 1.0, "upper": 2.0}), wants_cut(p, None)
    (True, False, False)
    """
    if enc is None or problem.objective.sense not in ("min", "max"):
        return False
    if proof_size(problem) > CUT_MAX_ENTRIES:
        return False
    if enc.get("problem", "ir") != "ir" or enc.get("consistent") is False:
        return False
    primal, dual = ("upper", "lower") if problem.objective.sense == "min" else ("lower", "upper")
    return enc.get(primal) is not None and enc.get(dual) is None


def cut_route(
    problem: Problem,
    enc: dict[str, Any],
    backend: Any,
    options: Any,
    exact: bool,
    budget_s: float,
) -> dict[str, Any]:
    """The objective-cut search (module docstring) from the enclosure ``enc``; returns the
    enclosure, narrowed where a step proved something (``cut``: the search's record).

    No cut is tried when the rows of the dual equality system are dependent up to rounding
    but independent exactly (:func:`lmic.certify.enclosure_cut.near_dependent_rows`: no cut's
    Farkas certificate can be made exact); ``cut.skipped`` then says why.

    Parameters
    ----------
    problem : Problem
        An optimisation problem; ``enc`` must pass :func:`wants_cut`.
    enc : dict
        Its enclosure (:func:`lmic.certify.enclosure.enclosure`).
    backend : str or None
        The answer's backend (``None``: the policy's default route for each cut problem).
    options : SolveOptions
    exact : bool
    budget_s : float
        Processor seconds; no step starts after them, and each step's solves are limited to
        what is left.

    Examples
    --------
    >>> enc = cut_route(problem, enc, "clarabel", SolveOptions(), False, 10.0)   # doctest: +SKIP
    >>> enc["dual"]["route"], enc["cut"]["steps"]                                # doctest: +SKIP
    ('objective cut', 17)

    (``tests/engine/test_route_cut.py`` runs it on ``inf t`` subject to ``[[x, 1], [1, t]] > 0``.)
    """
    from lmic.certify.enclosure_cut import near_dependent_rows
    from lmic.certify.enclosure_float import primal_end
    from lmic.certify.snap import exact_primal_end

    t0 = time.perf_counter()
    why = near_dependent_rows(problem)
    if why is not None:  # no cut can be proved: not one solve (random uio_dt.thm4_1: 1-9 s saved)
        out = dict(enc, cut={"steps": 0, "log": [], "time_s": time.perf_counter() - t0, "skipped": why})
        out["reason"] = f"{enc.get('reason')}; objective cuts not tried: {why}"
        return out
    sign = 1.0 if problem.objective.sense == "min" else -1.0
    pkey = "upper" if sign > 0 else "lower"
    U = sign * float(enc[pkey])  # the primal end, minimisation form
    lo: float | None = None
    lo_rec: dict[str, Any] | None = None
    best_x: np.ndarray | None = None
    tried: list[float] = []  # cuts that decided nothing
    log: list[dict[str, Any]] = []
    clock = RouteClock()  # processor time of this process and its solver children, capped by wall time
    step = CUT_FIRST * max(1.0, abs(U))
    wasted = 0.0  # the seconds of the cuts that decided nothing
    order = list(RAY_BACKENDS)  # the backends whose rays proved a cut move to the front

    def left() -> float:
        return budget_s - clock.elapsed()

    for _ in range(MAX_CUT_STEPS):
        if left() <= 0.0 or len(tried) >= MAX_UNDECIDED or wasted >= WASTE_SHARE * budget_s:
            break
        if lo is None:
            r = U - step
        else:
            rel = relative_gap(lo, U)
            inside = sum(1 for t in tried if lo < t < U)  # undecided cuts still inside the interval
            # the resolution stop also asks the gap relative to the ends themselves: VSDP's gap is
            # absolute below 1, and an objective of 4e-4 (uio_dt.thm4_1's rho) is then 25 % open
            own = (U - lo) / max(abs(U), abs(lo), 1e-300)
            if rel <= GAP_TARGET or (inside >= RESOLUTION_UNDECIDED and max(rel, own) <= float(options.gap)):
                break  # the target met, or --gap met and the cuts have reached their resolution
            r = _next_cut(lo, U, tried)
        t_step = clock.wall()
        found = _decide_cut(problem, r, backend, options, exact, left, order, proved=lo_rec is not None)
        decided = found["decided"]
        settled = found.get("record") is not None or found.get("x") is not None  # a proof or a point
        if found.get("record") is not None:
            lo_rec = found["record"]
            lo = float(lo_rec["lower"])  # r, or just below it when the objective has a constant
        else:
            x = found.get("x")
            pe = exact_primal_end(problem, x, primal_end(problem, x)) if x is not None else {}
            if pe.get("proven") and sign * float(pe["value"]) < U:
                U, best_x = sign * float(pe["value"]), x
            else:
                decided = f"{decided}, no better end" if x is not None else decided
                tried.append(r)
                wasted += clock.wall() - t_step
            if lo is None:
                step *= CUT_GROWTH  # further from the primal end: a cut easier to prove
        log.append({"cut": sign * r, "decided": decided, "settled": settled, "time_s": round(clock.wall() - t_step, 3)})
    return _narrowed(problem, enc, lo, lo_rec, U, best_x, log, clock.wall())


def _decide_cut(
    problem: Problem,
    r: float,
    backend: Any,
    options: Any,
    exact: bool,
    left: Callable[[], float],
    order: list[str],
    proved: bool = False,
) -> dict[str, Any]:
    """One cut at ``r`` (minimisation form): the policy on the route's backend and on the first
    of ``order`` (with the max-margin reduction where the problem is strict); their points are
    certified by the policy, their rays proved by :func:`lmic.certify.enclosure_cut.prove_cut`.

    Returns ``decided`` (what happened), and ``x`` (a certified point of the cut problem) or
    ``record`` (the proven cut), or neither. ``left()`` is the budget's seconds left; the
    backend whose ray proved moves to the front of ``order``, and once one has (``proved``) it
    goes first.
    """
    from lmic.certify.enclosure_cut import cut_problem, prove_cut
    from lmic.errors import LmicError
    from lmic.policy import decide
    from lmic.reductions.strict import has_strict

    cut = cut_problem(problem, r)
    # the other backend's ray: its max-margin reduction where the problem is strict, else its
    # own. One a cut, from the first of ``order``: the backend whose ray proved the last cut
    # first (its max-margin point, when the cut is feasible, is certified as well;
    # uio_dt.thm4_1: 16 cuts in 15 s the other way round); before any proof, after the
    # route's backend, each cut on the next backend (every ray at every cut cost 3 s a cut on
    # uio_dt.thm4_1 near its infimum, and 30 s an instance where nothing proves)
    strict = options.strict == "auto" and has_strict(cut)
    ray = (order[0], replace(options, strict="max-margin") if strict else options)
    tries: list[tuple[Any, Any]] = [ray, (backend, options)] if proved else [(backend, options), ray]
    if ray[0] == backend and ray[1] is options:
        tries = tries[:1]  # the same decision twice
    if not proved:
        order.append(order.pop(0))
    notes = []
    for name, opts in tries:
        rest = left()
        if rest <= 0.0:
            notes.append("budget spent")
            break
        try:
            # the user's time limit, if any, as on the route (a time limit puts every solve in a
            # forked child: 90 ms of a 0.2 s cut on uio_dt.thm4_1); the budget is checked between
            out = decide(cut, name, opts, exact=exact, ray_budget_s=CUT_RAY_PROOF_S)
        except (LmicError, ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:
            notes.append(f"{name or 'auto'}: {exc}")
            continue
        label = name or "auto"
        if (
            out.solution is not None
            and out.solution.x is not None
            and (out.verdict == "certified" or _only_the_cut_unproved(out.certificate))
        ):
            # the point is the original problem's; its primal end is proved on that problem
            return {"decided": f"point ({label})", "x": np.asarray(out.solution.x, dtype=float)}
        sol = out.solution
        # the policy proves a bounded ray at one face threshold, as prove_cut does: a ray it
        # failed on is not tried again (5 s an exact proof on a 20-state bounded-real lemma)
        failed = out.verdict == "infeasible-bounded" and any(
            "exact proof of the ray failed" in a.note for a in out.attempts
        )
        if (
            sol is not None
            and sol.farkas
            and out.verdict in ("infeasible-certified", "infeasible-bounded")
            and not failed
        ):
            rec = prove_cut(problem, r, sol.farkas, getattr(out.certificate, "farkas", None) or {})
            if rec["proven"]:
                if name in order and (name, opts) == ray:
                    order.remove(name)
                    order.insert(0, name)
                how = ", max-margin" if opts is not options else ""
                return {"decided": f"infeasible ({label}{how})", "record": rec}
        notes.append(f"{label}: {out.verdict}")
    return {"decided": "; ".join(notes) or "nothing"}


def _only_the_cut_unproved(cert: Any) -> bool:
    """The cut problem's point was rejected only because the cut row holds within tolerance, not
    provably: the solver stops on the cut (``f(x) = r`` to ``1e-13``). The point is still one of
    the original problem when everything else holds; the rigorous primal end then decides."""
    from lmic.certify.enclosure_cut import CUT_NAME

    if cert is None or getattr(cert, "verdict", None) != "rejected":
        return False
    bad_rows = [r for r in cert.linear if not r["ok"]]
    return (
        all(r["ok"] for r in cert.lmis)
        and [r["name"] for r in bad_rows] == [CUT_NAME]
        and bool(bad_rows[0].get("within_tolerance"))
        and all(r["ok"] for r in cert.derived)
        and all(r["ok"] for r in cert.checks)
    )


def _next_cut(lo: float, hi: float, tried: list[float]) -> float:
    """The midpoint of the largest interval of ``[lo, hi]`` between cuts already tried.

    >>> _next_cut(0.0, 1.0, []), _next_cut(0.0, 1.0, [0.5]), _next_cut(0.0, 1.0, [0.5, 0.25])
    (0.5, 0.25, 0.75)
    """
    cuts = sorted([lo, hi, *[t for t in tried if lo < t < hi]])
    widths = np.diff(cuts)
    k = int(np.argmax(widths))
    return 0.5 * (cuts[k] + cuts[k + 1])


def _narrowed(
    problem: Problem,
    enc: dict[str, Any],
    lo: float | None,
    lo_rec: dict[str, Any] | None,
    U: float,
    best_x: np.ndarray | None,
    log: list[dict[str, Any]],
    seconds: float,
) -> dict[str, Any]:
    """``enc`` with the search's proven ends (minimisation form ``lo``, ``U``) in the problem's
    own sense, its gap and reason, and the ``cut`` record."""
    out = dict(enc)
    sense = problem.objective.sense
    sign = 1.0 if sense == "min" else -1.0
    pkey, dkey = ("upper", "lower") if sense == "min" else ("lower", "upper")
    notes = []
    if best_x is not None:
        out[pkey] = sign * U
        out["primal"] = "restored point"
        out["restored_x"] = best_x.tolist()
        notes.append("primal end from a point of a cut problem")
    if lo is not None and lo_rec is not None:
        out[dkey] = sign * lo
        out["dual"] = lo_rec
        out.pop("conditional", None)  # a proven end replaces the box-conditional one (as best_of)
        notes.append("dual end by an objective cut proved infeasible")
    out["cut"] = {"steps": len(log), "log": log, "time_s": seconds}
    a, b = out.get("lower"), out.get("upper")
    if a is not None and b is not None:
        out["gap"] = b - a
        out["rel_gap"] = relative_gap(a, b) if b >= a else 0.0
        if b < a:  # both ends are proofs: never hide an inconsistency
            out["reason"] = f"inconsistent ends: lower {a:.10g} > upper {b:.10g}"
            out["consistent"] = False
            return out
        why = "; ".join(notes)
        out["reason"] = f"{out['kind']} in {interval_text(a, b)} (relative gap {out['rel_gap']:.2g}; {why})"
    elif notes:
        out["reason"] = f"{out.get('reason')}; {'; '.join(notes)}"
    else:
        out["reason"] = f"{out.get('reason')}; objective cuts: {len(log)} tried, none proved"
    return out
