"""The default route: the fastest route that can *prove* the answer, chosen by shape and size.

With no backend (or ``"auto"``) :func:`decide_route` runs:

* **feasibility problems**: the escalating policy of :mod:`lmic.policy` on the route of
  :func:`lmic.backends.auto.route`: above a tiny size, strict feasibility problems take the
  certified first-order route (SCS under the trace normalisation, a fixed-margin point, checked
  by the certifier), escalating to CVXOPT and the rest of :data:`lmic.policy.ORDER` when it
  fails; tiny ones take Clarabel, the embedded default solver;
* **optimisation problems**: each backend of the route alone (:func:`lmic.policy.decide`), in
  the interior-point order of :func:`lmic.route_rule.optimisation_chain` (Clarabel first when
  the problem is tiny or its Schur complement is not clearly cheaper, else SDPA then CVXOPT: a
  per-iteration cost model, :func:`lmic.route_rule.ipm_costs`), until one gives a certified
  point, then the certified enclosure of the optimal value
  (:func:`lmic.certify.enclosure.enclosure`, from the primal point and the repaired dual).
  When the enclosure misses :attr:`lmic.options.SolveOptions.gap`, the route escalates to the
  next interior point (:func:`lmic.route_rule.gap_escalates`: a gap too wide or a primal end
  missing; at most :data:`MAX_GAP_ESCALATIONS`, within a time cap) and keeps the tightest
  certified enclosure. An enclosure within the gap but above
  :data:`lmic.certify.enclosure.GAP_TARGET` escalates once more while the route has run less
  than :data:`lmic.route_rule.CHEAP_ESCALATION_S` (processor time: :mod:`lmic.route_escalation`).
  A first-order step (``auto:first-order``) whose enclosure does not meet the gap is polished by
  the interior points. The exact proofs of bounded rays share one budget over the route's backends.

An explicit backend is that backend alone, as before. :func:`describe` gives the one line the
CLI prints (``route: scs (first-order, n=40) -> certified``), also in the JSON (``route``).

Examples
--------
>>> from lmic.testing.conformance import lyapunov_problem
>>> import numpy as np
>>> r = decide_route(lyapunov_problem(-np.eye(2)))
>>> r.outcome.verdict, r.route["text"]
('certified', 'route: clarabel (interior point; 3 variables, PSD 2+2) -> certified')
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from lmic.certify.enclosure import GAP_TARGET
from lmic.formatting import interval_text
from lmic.ir.problem import Problem
from lmic.outcome import Outcome, rank
from lmic.route_escalation import RouteClock, gap_note, tighter
from lmic.route_rule import (
    CHEAP_ESCALATION_S,
    GAP_ESCALATION_FACTOR,
    GAP_ESCALATION_FLOOR_S,
    MAX_GAP_ESCALATIONS,
    affordable,
    gap_escalates,
    ray_proof_s,
)
from lmic.route_tighten import tighten
from lmic.route_unbounded import unbounded_checked as _unbounded_checked
from lmic.route_unbounded import unbounded_outcome
from lmic.route_upper import upper_route

__all__ = [
    "RouteResult",
    "decide_route",
    "describe",
    "enclosure_of",
    "method_of",
    "OPTIMISATION_FIRST_ORDER_TOL",
    "OPTIMISATION_FIRST_ORDER_ITERS",
    "ENCLOSURE_BUDGET_FACTOR",
    "ENCLOSURE_BUDGET_FLOOR_S",
    "enclosure_budget",
    "gap_escalates",
    "MAX_GAP_ESCALATIONS",
    "GAP_ESCALATION_FACTOR",
    "GAP_ESCALATION_FLOOR_S",
    "unbounded_outcome",
]

#: tolerance of the first-order step of an optimisation route ("moderate accuracy": the
#: enclosure, not the solver, says how close the point is)
OPTIMISATION_FIRST_ORDER_TOL = 1e-6
#: iteration cap of that step (each strategy of it): a first-order solve that has not met the
#: tolerance by then is polished by the interior-point step instead (SCS without a cap took
#: 200 s on a 30-state bounded-real lemma where CVXOPT takes 2 s)
OPTIMISATION_FIRST_ORDER_ITERS = 2000

#: the enclosure of an optimisation answer (dual repair and proof, perturbed and centred
#: re-solves, the tight re-solve of :func:`tighten`) may take this many times the solve it
#: certifies (the dual search's own share: ``enclosure.BUDGET_FACTOR``) ...
ENCLOSURE_BUDGET_FACTOR = 20.0
#: ... and at least this many seconds of processor time (two enclosures with the centred route
#: and a tight re-solve: uir.thm4_1 n = 12 seed 2 on Clarabel needs 10-13 s; 10 gave 1.4e-6 or 1.4e-7)
ENCLOSURE_BUDGET_FLOOR_S = 20.0


def enclosure_budget(solve_s: float | None) -> float:
    """The time budget of an enclosure: ``max(FLOOR, FACTOR * solve_s)`` seconds.

    >>> enclosure_budget(0.1), enclosure_budget(10.0)
    (20.0, 200.0)
    """
    s = float(solve_s or 0.0)
    return max(ENCLOSURE_BUDGET_FLOOR_S, ENCLOSURE_BUDGET_FACTOR * (s if s > 0 else 0.0))


@dataclass
class RouteResult:
    """What :func:`decide_route` concluded: the outcome, the enclosure (optimisation problems
    on the default route; ``None`` otherwise: the caller computes it), and the route taken."""

    outcome: Outcome
    enclosure: dict[str, Any] | None = None
    enclosure_s: float = 0.0
    route: dict[str, Any] = field(default_factory=dict)


def method_of(backend: str) -> str:
    """``"first-order"`` or ``"interior point"``.

    >>> method_of("scs"), method_of("cvxopt")
    ('first-order', 'interior point')
    """
    from lmic.policy import _instance

    try:
        return "interior point" if _instance(backend).interior_point else "first-order"
    except Exception:  # noqa: BLE001 - a label only (an unknown backend was refused earlier)
        return "interior point"


def describe(route: list[dict[str, Any]], problem: Problem) -> str:
    """The one-line route: each backend tried with its method and verdict.

    >>> from lmic.testing.conformance import lyapunov_problem
    >>> import numpy as np
    >>> describe([{"backend": "scs", "verdict": "certified"}], lyapunov_problem(-np.eye(2)))
    'route: scs (first-order; 3 variables, PSD 2+2) -> certified'
    """
    parts = []
    blocks = "+".join(str(lmi.dim) for lmi in problem.lmis) or "0"
    for step in route:
        shape = f"{problem.n} variables, PSD {blocks}"
        text = f"{step['backend']} ({method_of(step['backend'])}; {shape}) -> {step['verdict']}"
        if step.get("rel_gap") is not None:
            text += f", relative gap {step['rel_gap']:.1e}"
        elif step.get("gap_note"):
            text += f", {step['gap_note']}"
        parts.append(text)
    return "route: " + " => ".join(parts)


def _steps(outcome: Outcome) -> list[dict[str, Any]]:
    """One step per backend of the attempts, with the verdict of its last attempt."""
    steps: list[dict[str, Any]] = []
    for a in outcome.attempts:
        if steps and steps[-1]["backend"] == a.backend:
            steps[-1]["verdict"] = a.verdict if rank(a.verdict) >= rank(steps[-1]["verdict"]) else steps[-1]["verdict"]
        else:
            steps.append({"backend": a.backend, "verdict": a.verdict})
    return steps


def _solve_on(backend: Any, problem: Problem, options: Any) -> Any:
    """``problem`` solved on ``backend`` with the reductions (``None`` if it cannot take it or fails)."""
    from lmic.errors import LmicError
    from lmic.policy import _instance
    from lmic.reductions.pipeline import solve

    try:
        be = _instance(backend)
        if not be.supports(problem):
            return None  # as lmic.api.solve_problem: a backend that cannot take it is no answer
        return solve(be, problem, options)
    except LmicError:
        return None


#: a re-solve of the enclosure on a first-order backend may take this many times the solve it
#: certifies (and at least FIRST_ORDER_RESOLVE_MIN_S): without a cap each one runs to the
#: backend's iteration limit (SCS alone on delay_a.thm3_1, 6 states: two polish re-solves of
#: 47 s each after a 20 s solve, for no tighter end)
FIRST_ORDER_RESOLVE_FACTOR = 2.0
FIRST_ORDER_RESOLVE_MIN_S = 2.0


def first_order_capped(backend: Any, options: Any, solve_s: float, warm: Any = None) -> Any:
    """``options`` with a time limit of ``max(MIN, FACTOR x solve_s)`` for a first-order
    ``backend`` (its re-solves stop at their iteration limit otherwise, which on a hard problem is
    minutes); unchanged for an interior-point one (whose re-solves converge).

    >>> first_order_capped("scs", None, 10.0).time_limit, first_order_capped("clarabel", None, 10.0)
    (20.0, None)
    """
    if method_of(backend) != "first-order":
        return options
    from lmic.options import SolveOptions

    base = options or SolveOptions()
    cap = max(FIRST_ORDER_RESOLVE_MIN_S, FIRST_ORDER_RESOLVE_FACTOR * float(solve_s))
    return dataclasses.replace(
        base,
        time_limit=min(cap, base.time_limit) if base.time_limit is not None else cap,
        # the re-solves are the same problem, nearly: start at its answer
        warm_start=base.warm_start if base.warm_start is not None else warm,
    )


def enclosure_of(
    problem: Problem,
    sol: Any,
    cert: Any,
    exact: bool,
    backend: Any,
    options: Any,
    budget_s: float | None = None,
    target: float | None = None,
) -> tuple[dict[str, Any] | None, float]:
    """The certified enclosure of ``problem``'s optimal value from a solution's point and dual.

    ``None`` for a feasibility problem, or without a certificate or a solution to work from. A
    degenerate dual is retried on a perturbed problem, then on a centred dual point (the dual
    problem solved for the largest interior margin), both on ``backend``; a gap above
    :data:`lmic.certify.enclosure.GAP_TARGET` on an interior-point backend gets re-solves at
    :data:`lmic.route_tighten.TIGHT_TOLS`, then cross re-solves on the other interior points
    when the backend could not go tighter (:func:`lmic.route_tighten.tighten`). The whole
    enclosure has ``budget_s`` seconds (default :func:`enclosure_budget` of the solve's time): no step starts
    after it, the tight re-solve only when the rest of the budget can pay for it, and a budget
    spent is recorded (``budget``), never turned into a bound. The budget counts processor time
    (:class:`lmic.route_escalation.RouteClock`): a loaded machine does not spend it.

    >>> from lmic.testing.conformance import lyapunov_problem
    >>> import numpy as np
    >>> enclosure_of(lyapunov_problem(-np.eye(1)), None, None, False, "clarabel", None)
    (None, 0.0)
    """
    if problem.objective.sense == "feasibility" or cert is None or sol is None:
        return None, 0.0
    if sol.status in ("infeasible", "unbounded"):
        return None, 0.0
    from lmic.certify.enclosure import enclosure

    clock = RouteClock()  # the budget counts processor time: a loaded machine does not spend it
    solve_s = float(getattr(sol, "solve_s", 0.0) or 0.0)
    budget = enclosure_budget(solve_s) if budget_s is None else float(budget_s)

    def deadline() -> float:
        return budget - clock.elapsed()  # seconds left

    # the certified point (the certifier may have moved the solver's onto a face: lmic.certify.snap)
    x = None
    if getattr(cert, "verdict", None) == "certified":
        x = np.asarray(cert.x, dtype=float) if getattr(cert, "x", None) is not None else sol.x

    def closures(name: Any, opts: Any) -> tuple[Any, Any]:
        """The enclosure's re-solves (perturbed problems, centring problems) on ``name``."""
        opts = first_order_capped(name, opts, solve_s, sol if name == backend else None)

        def resolve(perturbed: Problem) -> dict[str, Any] | None:
            if deadline() < solve_s:
                return None  # the re-solve would not fit in the budget
            other = _solve_on(name, perturbed, opts)
            return other.duals if other is not None and other.status in ("optimal", "inaccurate") else None

        def solve_point(other_problem: Problem) -> np.ndarray | None:
            if deadline() < solve_s:
                return None
            other = _solve_on(name, other_problem, opts)
            return other.x if other is not None and other.status in ("optimal", "inaccurate") else None

        return resolve, solve_point

    resolve, solve_point = closures(backend, options)

    enc = enclosure(
        problem,
        sol.duals,
        x,
        exact=exact,
        resolve=resolve,
        solve_point=solve_point,
        solve_s=solve_s,
        budget_s=budget,
    )
    enc = tighten(
        problem,
        enc,
        x,
        exact,
        backend,
        options,
        resolve,
        solve_point,
        deadline=deadline,
        solve_s=solve_s,
        target=target,
        closures=lambda name: closures(name, None),
    )
    spent = clock.elapsed()
    enc["budget"] = {"seconds": budget, "used": spent, "spent": spent > budget}
    if enc["budget"]["spent"] and enc.get("rel_gap") is None:
        enc["reason"] = f"{enc.get('reason')}; enclosure time budget {budget:.3g} s spent"
    return enc, spent


def _narrowing(problem: Problem, done: str, done_s: float, rest: list[str]) -> list[str]:
    """The backends of ``rest`` that may narrow a certified answer's gap: interior points whose
    estimated time is affordable after ``done_s`` seconds on ``done`` (:func:`affordable`)."""
    return [nm for nm in rest if method_of(nm) != "first-order" and affordable(problem, done, done_s, nm)]


def decide_route(problem: Problem, backend: Any = None, options: Any = None, *, exact: bool = False) -> RouteResult:
    """Decide ``problem`` on the route of the module docstring.

    Parameters
    ----------
    problem : Problem
    backend : str, Backend or None
        ``None`` / ``"auto"`` / ``"auto:first-order"`` / ``"auto:interior-point"``: the default
        route; anything else: that backend alone (:func:`lmic.policy.decide`).
    options : SolveOptions, optional
        ``options.gap`` is the relative gap an optimisation route stops at.
    exact : bool

    Returns
    -------
    RouteResult
    """
    from lmic.reductions.memo import remembered_solves

    with remembered_solves():  # a closed problem solved twice on the route is solved once
        return _decide_route(problem, backend, options, exact)


def _decide_route(problem: Problem, backend: Any, options: Any, exact: bool) -> RouteResult:
    """:func:`decide_route`'s work, its solves remembered."""
    from lmic.options import SolveOptions
    from lmic.policy import RAY_PROOF_BUDGET_S, backend_budget, decide, is_auto, route

    options = options or SolveOptions()
    if not is_auto(backend) or problem.objective.sense == "feasibility":
        out = _unbounded_checked(problem, decide(problem, backend, options, exact=exact), options)
        done, enc, enc_s = _steps(out), None, 0.0
        if out.verdict == "undecided" and getattr(out.certificate, "verdict", None) == "certified":
            # a point that holds from a solve the solver called inexact (SDPA's pFEAS): as on
            # the default route, an enclosure that meets the gap proves the optimum
            used = out.backend or str(getattr(backend, "label", backend))
            enc, enc_s = enclosure_of(problem, out.solution, out.certificate, exact, used, options)
            if enc is not None and enc.get("rel_gap") is not None and enc["rel_gap"] <= options.gap:
                out = _upgrade(out, enc)
                done[-1]["verdict"] = out.verdict
        return RouteResult(out, enc, enc_s, {"steps": done, "text": describe(done, problem)})
    names = list(route(problem, backend))
    budgeted = options.time_limit is None
    last = len(names) - 1
    cut: list[Any] = []
    best: Outcome | None = None
    best_enc: dict[str, Any] | None = None
    enc_s = 0.0
    attempts: list[Any] = []
    steps: list[dict[str, Any]] = []
    bounded = 0
    escalated = 0
    ray_search_s = 0.0
    clock, first_s = RouteClock(), 0.0  # the route's cost, robust to load (route_escalation)
    k = -1
    while k + 1 < len(names):
        k += 1
        name = names[k]
        first_order = method_of(name) == "first-order"
        opts = options
        if first_order:
            from dataclasses import replace

            opts = replace(
                options,
                tol=max(options.tol, OPTIMISATION_FIRST_ORDER_TOL),
                max_iter=options.max_iter or OPTIMISATION_FIRST_ORDER_ITERS,
            )
        budget = backend_budget(problem) if budgeted and k < last else None
        t_b = time.perf_counter()
        # the exact proofs of bounded rays share one budget over the route, as in one decide()
        rays = None if k == 0 else max(0.0, RAY_PROOF_BUDGET_S - ray_proof_s(attempts))
        out = _unbounded_checked(
            problem, decide(problem, name, opts, exact=exact, budget_s=budget, ray_budget_s=rays), options
        )
        step_s = time.perf_counter() - t_b  # this backend's solve, for the cost of the next
        if budget is not None and not out.decided and step_s >= budget:
            cut.append(name)  # stopped by its budget: the next backend now; retried at the end
        attempts.extend(out.attempts)
        ray_search_s += out.ray_search_s  # each backend's search for a ray it said exists
        step: dict[str, Any] = {"backend": name, "verdict": out.verdict}
        steps.append(step)
        enc = None
        holds = out.verdict == "undecided" and getattr(out.certificate, "verdict", None) == "certified"
        # the tight re-solve aims at GAP_TARGET (1e-6) whatever the looser --gap of escalation
        aim = min(float(options.gap), GAP_TARGET)
        if out.verdict == "certified" or holds:
            enc, t_enc = enclosure_of(problem, out.solution, out.certificate, exact, name, opts, target=aim)
            enc_s += t_enc
            rel = None if enc is None else enc.get("rel_gap")
            step["rel_gap"] = rel
            if rel is None:
                step["gap_note"] = gap_note(enc)
        restored = enc is None and out.verdict != "certified"  # upper_route's dual end has no re-solves
        out, enc, t_up = upper_route(problem, out, enc, name, opts, exact, options.gap, steps)  # lmic.route_upper
        enc_s += t_up
        now = None if enc is None else enc.get("rel_gap")
        if restored and out.verdict == "certified" and now is not None and now > GAP_TARGET:
            # the point upper_route restored is certified, its dual end proved without this
            # step's re-solves (the solver's degenerate dual, with a shift): the whole dual search
            # from the certified point (a random 7-state margin problem, max t with A'P + PA + t I
            # <= 0, I <= P <= 10 I: relative gap 1.0e-6 to 1.1e-8, the centred dual)
            again, t_again = enclosure_of(problem, out.solution, out.certificate, exact, name, opts, target=aim)
            enc_s += t_again
            if again is not None and again.get("rel_gap") is not None and again["rel_gap"] <= now:
                enc = again
                step["rel_gap"] = enc["rel_gap"]
        if holds and enc is not None and enc.get("rel_gap") is not None and enc["rel_gap"] <= options.gap:
            out = _upgrade(out, enc)  # the enclosure proves the optimum whatever the solver's status
            step["verdict"] = out.verdict
        even = best is not None and _score(out) == _score(best) and out.verdict != "certified"
        if (
            best is None
            or _score(out) > _score(best)
            or tighter(enc, best_enc, out, best)
            or (even and _ends_key(problem, enc) > _ends_key(problem, best_enc))
        ):
            best, best_enc = out, enc
        if out.verdict == "certified":
            rel = step.get("rel_gap")
            if rel is not None and rel <= options.gap:
                cheap = clock.elapsed() < CHEAP_ESCALATION_S
                if first_order or rel <= GAP_TARGET or escalated > 0 or not cheap or k == len(names) - 1:
                    break  # the enclosure proves the optimum to the requested gap
                # within --gap but above GAP_TARGET, and cheap: one more interior point may close it
                escalated += 1
                step["escalate"] = "gap above 1e-6, cheap"
                names = names[: k + 1] + _narrowing(problem, name, step_s, names[k + 1 :])
                continue
            if not first_order:
                first_s = first_s or clock.elapsed()
                late = clock.elapsed() > max(GAP_ESCALATION_FLOOR_S, GAP_ESCALATION_FACTOR * first_s)
                if escalated >= MAX_GAP_ESCALATIONS or late or not gap_escalates(problem, enc):
                    break  # a certified interior-point answer: its enclosure is what can be proved
                # the gap is not met and another interior-point solver may close it (its point
                # or its dual is more accurate): the next one of the route, first-order ones skipped
                escalated += 1
                step["escalate"] = "gap not met"
                names = names[: k + 1] + _narrowing(problem, name, step_s, names[k + 1 :])
            continue  # a first-order point whose gap is too wide: polish
        if out.verdict in ("infeasible-certified", "unbounded-certified"):
            break
        if out.verdict == "undecided" and getattr(out.evidence, "kind", "") == "exact-proof":
            break  # proved dual infeasible, feasibility not decided: lmic.route_unbounded
        if out.verdict == "infeasible-bounded":
            bounded += 1
            if bounded >= 2:
                break
        if k == len(names) - 1 and cut and budgeted:
            names.append(cut[0])  # nothing decided within the budgets: the first one cut, unbudgeted
            budgeted = False
    assert best is not None
    best, best_enc, t_box = _boxed_upper(problem, best, best_enc, steps, options, exact)
    enc_s += t_box
    best.attempts = attempts
    best.ray_search_s = ray_search_s
    if best.solution is not None:
        best.solution.info["attempts"] = [a.to_dict() for a in attempts]
    return RouteResult(best, best_enc, enc_s, {"steps": steps, "text": describe(steps, problem), "gap": options.gap})


def _boxed_upper(
    problem: Problem,
    best: Outcome,
    enc: dict[str, Any] | None,
    steps: list[dict[str, Any]],
    options: Any,
    exact: bool,
) -> tuple[Outcome, dict[str, Any] | None, float]:
    """The route's last resort for a missing primal end: the boxed search of
    :func:`lmic.upper_end.upper_from_boxes` on the best step's backend (an optimum approached
    only as ``|x|`` grows: the solvers' points are far out and none holds, SDPLIB hinf10), once,
    within the route's budget of :mod:`lmic.route_upper`. A point that holds from an inexact
    solve whose enclosure then meets the gap is upgraded, as in the route."""
    if problem.objective.sense == "feasibility" or best.solution is None or best.backend is None:
        return best, enc, 0.0
    key = "upper" if problem.objective.sense == "min" else "lower"
    if enc is not None and enc.get(key) is not None:
        return best, enc, 0.0
    mine = [i for i, st in enumerate(steps) if st["backend"] == best.backend]
    if not mine:
        return best, enc, 0.0
    i = mine[-1]
    order = steps[:i] + steps[i + 1 :] + [steps[i]]  # upper_route writes into the last one
    out, enc2, t = upper_route(problem, best, enc, best.backend, options, exact, options.gap, order, boxes=True)
    holds = out.verdict == "undecided" and getattr(out.certificate, "verdict", None) == "certified"
    if holds and enc2 is not None and enc2.get("rel_gap") is not None and enc2["rel_gap"] <= options.gap:
        out = _upgrade(out, enc2)
        steps[i]["verdict"] = out.verdict
    return out, enc2, t


def _ends_key(problem: Problem, enc: dict[str, Any] | None) -> tuple[int, float]:
    """How much an enclosure proves, to choose between two steps of the same rank: its number
    of proven ends, then its dual end in the minimisation form (higher is better; SDPLIB hinf9:
    CVXOPT's perturbed dual proves 225.5, SDPA's own 236.249, where the optimum is 236.249).

    >>> from lmic.testing.conformance import CASES
    >>> p = CASES["max_sense"].build()
    >>> _ends_key(p, {"lower": 1.0, "upper": 3.0}) > _ends_key(p, {"lower": 1.0, "upper": 2.0}), _ends_key(p, None)
    (False, (0, -inf))
    """
    if enc is None:
        return 0, -np.inf
    lo, hi = enc.get("lower"), enc.get("upper")
    count = int(lo is not None) + int(hi is not None)
    dual = lo if problem.objective.sense == "min" else (None if hi is None else -hi)
    return count, -np.inf if dual is None else float(dual)


def _score(out: Outcome) -> float:
    """:func:`lmic.outcome.rank`, with a point that holds from an inexact solve (undecided)
    above a rejected point: its objective is a proven end of the enclosure.

    >>> _score(Outcome("rejected")) < _score(Outcome("infeasible-bounded"))
    True
    """
    if out.verdict == "undecided" and getattr(out.certificate, "verdict", None) == "certified":
        return rank("rejected") + 0.5
    return float(rank(out.verdict))


def _upgrade(out: Outcome, enc: dict[str, Any]) -> Outcome:
    """A point that holds from a solve the solver called inexact, whose enclosure meets the gap:
    the optimum is proven to that gap by the enclosure alone (both ends are proofs)."""
    from lmic.outcome import evidence_of

    out.verdict = "certified"
    out.evidence = evidence_of("certified", out.certificate)
    out.reason = (
        f"{out.reason}; the enclosure proves the optimum: {enc.get('kind')} in "
        f"{interval_text(enc['lower'], enc['upper'])} (relative gap {enc['rel_gap']:.2g})"
    )
    return out
