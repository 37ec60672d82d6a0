"""The one solve policy: reductions x backends until the certifier decides.

Every entry point uses :func:`decide`: ``lmic solve`` and :func:`lmic.api.solve`, each
``lmic crosscheck`` column (with one backend), ``--maximize`` / ``--sweep``
(:func:`lmic.studies.sweep.decide`), ``audit-published``, ``reproduce`` and ``report``.

What it does
------------
For each backend of the route (:func:`route`), it tries strategies until one *decides* (a
certified point, or a GLOBAL infeasibility proof, :mod:`lmic.outcome`):

1. ``scaled``: the problem preconditioned at a reference point (when the caller has one, e.g.
   the last certified point of a bisection; :mod:`lmic.reductions.precondition`);
2. ``default``: the backend's own strict reduction plan (:mod:`lmic.reductions.strict`);
3. on ``error``, ``inaccurate``, a rejected point or a bounded ray: the other strict reduction
   (``max-margin`` <-> ``fixed-margin``) when the problem is a feasibility problem with strict
   constraints (unless ``SolveOptions.strict`` names one: that choice is honoured), and the
   problem preconditioned at the point the solver returned (``rescaled``); for an optimisation
   problem whose solve failed, its feasibility problem (``feasibility``: only an infeasibility
   proof counts from it, a point is no optimum);
4. the first ``infeasible-bounded`` answer ("no solution with ``||x||_inf <= R``") is
   immediately tried for an exact rational proof (:func:`lmic.certify.farkas.prove_infeasible`),
   which makes it global when it holds (up to :data:`MAX_RAY_PROOFS` rays per backend, one
   face threshold each, within :data:`RAY_PROOF_BUDGET_S` CPU seconds per decision: a proof
   attempt costs seconds; another strategy's or backend's ray, e.g. the fixed-margin one, is
   often the one that proves).

Then the next backend of the route. After the route: the exact rescue of the best rejected
point whose float eigenvalues are all positive (margins below the float error bound, e.g. near a
supremum that is not attained). The best outcome found is returned (certified or
infeasible-certified > infeasible-bounded > rejected > undecided), with every attempt.

Escalation order: the shape- and size-based first choice of :func:`lmic.backends.auto.route`
(strict feasibility problems above a tiny size: the certified first-order route, SCS then
CVXOPT; small problems: Clarabel; optimisation problems: the interior-point order of
:func:`lmic.route_rule.optimisation_chain`, by a per-iteration cost model; :mod:`lmic.routes`
adds the ``--gap`` test of the optimal-value enclosure and the escalation), then the rest of
:data:`ORDER` (Clarabel -> CVXOPT -> SDPA -> SCS), skipping backends that are not installed or
cannot take the problem (Clarabel's memory
guard on large PSD blocks). SCS, a first-order method, runs at tolerance
:data:`FIRST_ORDER_TOL` in the route (its answers are certified, not trusted; alone it runs at
its own floor). ``backend="X"`` means X alone (strategies and exact rescue still apply, no other
backend); no backend (or ``"auto"``) means the escalating route. Once :data:`MAX_BOUNDED`
backends have given bounded rays that no exact proof upgrades, the route stops there.

Examples
--------
>>> import scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
>>> p = Problem([Variable("p", "scalar", (1, 1))], [LMI("p > 0", 1, sp.csc_matrix([[0., 1.]]))],
...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
>>> out = decide(p)
>>> out.verdict, out.exit_code(), out.attempts[0].backend
('certified', 0, 'clarabel')
"""

from __future__ import annotations

import time
from dataclasses import replace
from typing import Any

import numpy as np

from lmic.errors import BackendError, LmicError
from lmic.ir.problem import Problem
from lmic.outcome import Attempt, Evidence, Outcome, evidence_of, rank, verdict_of
from lmic.rescue import exact_rescue_point, rescue_rejected
from lmic.route_rule import SCHUR_PENALTY, TINY_IPM_COST, ipm_costs, optimisation_chain
from lmic.solution import Solution

__all__ = [
    "ORDER",
    "FIRST_ORDER_TOL",
    "MAX_BOUNDED",
    "BACKEND_BUDGET_S",
    "MAX_RAY_PROOFS",
    "backend_budget",
    "AUTO_VARIANTS",
    "route",
    "ipm_costs",
    "optimisation_chain",
    "TINY_IPM_COST",
    "SCHUR_PENALTY",
    "decide",
    "step_options",
    "is_auto",
    "exact_rescue_point",
]

#: default escalation order of backends
ORDER = ("clarabel", "cvxopt", "sdpa", "scs")
#: tolerance of a first-order backend's solve (certified, not trusted)
FIRST_ORDER_TOL = 1e-3
#: stop escalating once this many backends gave bounded rays that no exact proof upgraded
MAX_BOUNDED = 2

#: bounded rays per backend of a decision tried for an exact (global) proof: on obs_control.thm3_2
#: in z-coordinates (eps = 0.8) CVXOPT's max-margin ray fails and its fixed-margin ray proves; on
#: random obs_control.thm3_2 instances Clarabel's three rays fail and CVXOPT's rescaled one proves
MAX_RAY_PROOFS = 3
#: ... while the proofs so far took less than this many CPU seconds (the first is always tried)
RAY_PROOF_BUDGET_S = 15.0
#: ... and one proof stops trying further faces after this many seconds (a 20-state scale-free
#: bisection point spent 12 s a proof on an irrational face, 48 s in all, before it was bounded;
#: tests/studies/sweep/test_sweep_fast.py 285 s -> 120 s)
RAY_PROOF_ATTEMPT_S = 2.0

#: per-backend time budget of an escalating route (seconds, for a problem of size 1e6 or less;
#: see :func:`backend_budget`): a backend that has not decided by then gives way to the next one
BACKEND_BUDGET_S = 60.0


def backend_budget(problem: Problem) -> float:
    """Seconds one backend of an escalating route may take before the next one is tried.

    ``BACKEND_BUDGET_S * max(1, n * cone / 1e6)`` with ``n`` the variables and ``cone`` the
    dimension of the PSD cone (``sum d (d + 1) / 2``): about the growth of an interior-point
    solve. On a random 8-state ``delay_b.thm4_1`` (infeasible) Clarabel ran 200 s where CVXOPT
    decides in 2 s. Only routes with another backend after this one are budgeted; a backend cut
    by its budget is tried again without one when no other backend decided (a decision wherever
    one exists).

    >>> from lmic.testing.conformance import lyapunov_problem
    >>> backend_budget(lyapunov_problem(-np.eye(2)))
    60.0
    """
    cone = sum(lmi.dim * (lmi.dim + 1) // 2 for lmi in problem.lmis) + len(problem.linear)
    return BACKEND_BUDGET_S * max(1.0, problem.n * cone / 1e6)


#: ``auto:VARIANT``: ``first-order`` starts an optimisation route with SCS, ``interior-point``
#: skips that step; ``auto`` alone follows :data:`lmic.backends.auto.FIRST_ORDER_OPTIMISATION`
AUTO_VARIANTS: dict[str, bool | None] = {"": None, "first-order": True, "interior-point": False}


def is_auto(backend: Any) -> bool:
    """``None`` or ``"auto"``: the escalating route.

    >>> is_auto(None), is_auto("auto"), is_auto("cvxopt")
    (True, True, False)
    """
    return backend is None or (isinstance(backend, str) and backend.split(":")[0].lower() == "auto")


def _label(backend: Any) -> str:
    return str(getattr(backend, "label", backend))


def _instance(backend: Any) -> Any:
    from lmic.backends.base import Backend

    if isinstance(backend, Backend):
        return backend
    from lmic.backends.registry import get_backend

    return get_backend(str(backend))


def _usable(name: str, problem: Problem) -> bool:
    try:
        be = _instance(name)
    except LmicError:
        return False
    if not be.is_available():
        return False
    ok = be.supports(problem, explain=True)
    return bool(ok[0] if isinstance(ok, tuple) else ok)


def route(problem: Problem, backend: Any = None) -> list[Any]:
    """The backends :func:`decide` tries, in order.

    >>> from lmic.testing.conformance import lyapunov_problem
    >>> route(lyapunov_problem(-np.eye(2)))[:2], route(lyapunov_problem(-np.eye(2)), "scs")
    (['clarabel', 'cvxopt'], ['scs'])
    """
    if not is_auto(backend):
        return [backend]
    from lmic.backends import auto

    variant = backend.split(":", 1)[1].lower() if isinstance(backend, str) and ":" in backend else ""
    if variant not in AUTO_VARIANTS:
        raise BackendError(f"backend '{backend}': unknown auto variant; choose " + ", ".join(sorted(AUTO_VARIANTS)))
    if problem.objective.sense != "feasibility":
        chain = optimisation_chain(problem, AUTO_VARIANTS[variant])
    else:
        chain = auto.route(problem) if AUTO_VARIANTS[variant] is None else auto.route(problem, AUTO_VARIANTS[variant])
    first = [name for name in chain if _usable(name, problem)]
    usable = first + [name for name in ORDER if name not in first and _usable(name, problem)]
    if not usable:
        raise BackendError("no installed backend can take this problem (tried " + ", ".join(ORDER) + ")")
    return usable


def step_options(backend: Any, options: Any) -> Any:
    """Options for one backend: a first-order backend runs at :data:`FIRST_ORDER_TOL` or looser.

    >>> from lmic.backends.base import SolveOptions
    >>> step_options("scs", SolveOptions(tol=1e-8)).tol, step_options("cvxopt", SolveOptions(tol=1e-8)).tol
    (0.001, 1e-08)
    """
    from lmic.backends.base import SolveOptions

    options = options or SolveOptions()
    be = _instance(backend)
    if not be.interior_point:
        return replace(options, tol=max(options.tol, FIRST_ORDER_TOL))
    return options


def _solve_one(be: Any, target: Problem, options: Any, scales: list[np.ndarray] | None, judge: Problem) -> Solution:
    from lmic.reductions.pipeline import solve
    from lmic.reductions.precondition import unscale_duals

    sol = solve(be, target, options)
    if scales is not None:
        unscale_duals(sol, scales)
    if sol.x is not None and judge.objective.sense != "feasibility" and len(sol.x) == judge.n:
        sol.objective = judge.objective.value(sol.x)
    elif judge.objective.sense == "feasibility":
        sol.objective = None
    return sol


def _certify(problem: Problem, sol: Solution, exact: bool) -> tuple[Solution, Any]:
    """``(solution, certificate)`` at the point the certificate proves (a moved point is the one
    returned: :func:`lmic.certify.certified_solution`)."""
    from lmic.certify import certified_solution, certify

    return certified_solution(problem, sol, certify(problem, sol, exact=exact))


def _prove_ray(problem: Problem, sol: Solution, cert: Any) -> bool:
    """Try an exact proof of a bounded ray (one face threshold); upgrade ``cert`` in place if it holds."""
    from lmic.certify.farkas import prove_infeasible, scope

    try:
        ex = prove_infeasible(
            problem, sol.farkas or {}, cert.farkas or {}, rel_face=(1e-9,), budget_s=RAY_PROOF_ATTEMPT_S
        )
    except (LmicError, ValueError, ArithmeticError):
        return False
    if not ex.get("proven"):
        return False
    cert.exact = ex
    cert.farkas["scope"] = scope(problem, cert.farkas, ex)
    cert.verdict = "infeasible-certified"
    cert.reason = cert.farkas["scope"]["statement"] + "; " + str(ex.get("reason", ""))
    return True


class _Run:
    """The state of one :func:`decide` call: attempts so far and the best outcome."""

    def __init__(self, problem: Problem, exact: bool, rescue: bool, ray_budget_s: float | None = None) -> None:
        self.problem, self.exact, self.rescue = problem, exact, rescue
        self.ray_budget_s = ray_budget_s  # what an outer route left of its ray-proof budget
        self.attempts: list[Attempt] = []
        self.best: Outcome | None = None
        self.rejected: list[tuple[Solution, Any, str]] = []
        self.holding: list[Outcome] = []  # optimisation points that hold, from 'inaccurate' solves
        self.rays_tried = 0
        self.rays_by: dict[str, int] = {}  # proof attempts per backend
        self.ray_s = 0.0

    def record(self, backend: str, label: str, sol: Solution, t0: float, infeasibility_only: bool = False) -> Outcome:
        t1 = time.perf_counter()
        sol, cert = _certify(self.problem, sol, self.exact)
        verdict = verdict_of(self.problem, sol, cert)
        note = ""
        if infeasibility_only and verdict in ("certified", "rejected"):
            # a point of the feasibility problem is no optimum: it decides nothing here
            verdict, note = "undecided", "the feasibility problem has a point; the optimum was not reached"
        mine = self.rays_by.get(backend, 0)
        if self.ray_budget_s is None:
            more = mine < MAX_RAY_PROOFS and (not self.rays_tried or self.ray_s < RAY_PROOF_BUDGET_S)
        else:
            more = mine < MAX_RAY_PROOFS and self.ray_s < self.ray_budget_s
        # a separation below the float tolerance (x >= 1 and x <= 1 - 1e-6: g0 = -5e-7 against
        # 1e-6 x scale 2) is undecided in floats; the same exact proof decides it
        faint = verdict == "undecided" and sol.status == "infeasible" and bool(sol.farkas)
        if (verdict == "infeasible-bounded" or faint) and self.rescue and not self.exact and more:
            # an exact proof costs seconds: a few rays per backend, one face each, within one
            # CPU budget per decision (another backend's ray often proves where the first's fail)
            self.rays_tried += 1
            self.rays_by[backend] = mine + 1
            t_ray = time.process_time()  # CPU time: the same on a busy machine
            proved = _prove_ray(self.problem, sol, cert)
            self.ray_s += time.process_time() - t_ray
            if proved:
                verdict, note = "infeasible-certified", "exact proof of the ray"
            else:
                note = "exact proof of the ray failed"
        if verdict == "rejected":
            self.rejected.append((sol, cert, backend))
        reduction = f"{label}/{sol.strategy}" if sol.strategy not in (None, "", "none") else label
        if not note and verdict in ("undecided", "rejected"):
            note = " ".join(str(getattr(cert, "reason", "") or sol.message or "").split())[:160]
        now = time.perf_counter()
        self.attempts.append(
            Attempt(
                backend,
                reduction,
                sol.status,
                str(sol.native_status or ""),
                verdict,
                now - t0,
                note,
                solve_s=float(sol.solve_s or 0.0),
                certify_s=now - t1,
            )
        )
        out = Outcome(
            verdict,
            evidence_of(verdict, cert),
            str(getattr(cert, "reason", "") or sol.message or sol.status),
            solution=sol,
            certificate=cert,
            backend=backend,
        )
        if (
            verdict == "undecided"
            and not infeasibility_only
            and self.problem.objective.sense != "feasibility"
            and getattr(cert, "verdict", None) == "certified"
            and sol.x is not None
        ):
            self.holding.append(out)  # the point holds; only the solver's status is in doubt
        if self.best is None or rank(out.verdict) > rank(self.best.verdict):
            self.best = out
        return out


def decide(
    problem: Problem,
    backend: Any = None,
    options: Any = None,
    *,
    exact: bool = False,
    solve_as: Problem | None = None,
    reference: np.ndarray | None = None,
    rescue: bool = True,
    budget_s: float | None = None,
    ray_budget_s: float | None = None,
    max_bounded: int = MAX_BOUNDED,
) -> Outcome:
    """Decide ``problem`` by the policy of the module docstring.

    Parameters
    ----------
    problem : Problem
        The problem whose answer is certified (the judge).
    backend : str, Backend or None
        ``None``/``"auto"``: the escalating route; anything else: that backend alone.
    options : SolveOptions, optional
    exact : bool
        Ask the certifier for exact proofs of every answer (``--exact``).
    solve_as : Problem, optional
        What the solvers are given (same variables as ``problem``, e.g. the objective dropped
        for a bisection); default ``problem``.
    reference : numpy.ndarray, optional
        A point to precondition at first (``scaled``).
    rescue : bool
        Exact rescue of bounded rays and of points rejected only for tiny margins.
    budget_s : float, optional
        Seconds each backend may take (its strategies stop there, its solves get the rest as
        their time limit unless ``options.time_limit`` is set). An escalating route budgets
        every backend but its last by :func:`backend_budget`; a backend cut by its budget is
        retried without one when no backend decided.
    ray_budget_s : float, optional
        CPU seconds left for exact proofs of bounded rays (an outer route that calls this once
        per backend shares :data:`RAY_PROOF_BUDGET_S` across them, :mod:`lmic.routes`); default:
        the first proof always runs, the next ones while the proofs took less than
        :data:`RAY_PROOF_BUDGET_S`.
    max_bounded : int
        Stop escalating after this many backends gave bounded rays (default
        :data:`MAX_BOUNDED`); ``1`` when any infeasibility answer settles the question, e.g. the
        search for an improving ray (:mod:`lmic.route_unbounded`), where a ray problem that is
        infeasible means only "no ray found".

    Returns
    -------
    Outcome
        With ``solution``/``certificate`` of the chosen attempt and every attempt.

    Raises
    ------
    BackendError
        A single backend that cannot take the problem (bad input), or no usable backend.
    """
    from lmic.backends.base import SolveOptions
    from lmic.reductions.precondition import precondition
    from lmic.reductions.strict import has_strict

    options = options or SolveOptions()
    solve_as = solve_as if solve_as is not None else problem
    names = route(solve_as, backend)
    single = len(names) == 1 and not is_auto(backend)
    if single:
        be = _instance(names[0])
        ok, why = be.supports(solve_as, explain=True)
        if not ok:
            raise BackendError(f"backend '{be.label}' cannot take this problem: {why}")
    run = _Run(problem, exact, rescue, ray_budget_s)
    bounded = 0
    feasibility_strict = problem.objective.sense == "feasibility" and has_strict(problem)
    cut: list[Any] = []  # backends stopped by their budget (retried without one at the end)
    auto_budget = budget_s is None and not single and options.time_limit is None
    queue: list[tuple[Any, float | None]] = [
        (name, (backend_budget(solve_as) if auto_budget and k < len(names) - 1 else budget_s))
        for k, name in enumerate(names)
    ]
    qi = 0
    while qi < len(queue):
        name, budget = queue[qi]
        qi += 1
        be = _instance(name)
        label = be.label
        opts = step_options(be, options) if not single else options
        b_t0 = time.perf_counter()
        last_x: np.ndarray | None = None
        tried_strict: set[str] = set()
        plan: list[tuple[str, Problem, Any]] = []
        if reference is not None and solve_as.lmis:
            plan.append(("scaled", solve_as, reference))
        plan.append(("default", solve_as, None))
        decided = False
        k = 0
        while k < len(plan):
            tag, target, at = plan[k]
            k += 1
            t0 = time.perf_counter()
            scales = None
            step_opts = opts
            if budget is not None:
                left = budget - (t0 - b_t0)
                if left <= 0 and k > 1:  # the backend's first strategy always runs
                    cut.append(name)
                    break
                left = max(left, 1e-3)
                if opts.time_limit is None or opts.time_limit > left:
                    step_opts = replace(opts, time_limit=left)
            if tag in ("scaled", "rescaled"):
                target, scales = precondition(target, at)
            if tag.startswith("strict="):
                step_opts = replace(step_opts, strict=tag.split("=", 1)[1])
            sol = _solve_one(be, target, step_opts, scales, problem)
            if budget is not None and _timed_out(sol) and name not in cut:
                cut.append(name)
            for a in sol.info.get("strict_attempts", []) or []:
                tried_strict.add(str(a.get("strategy")))
            out = run.record(label, tag, sol, t0, infeasibility_only=tag == "feasibility")
            rays = sol.info.pop("unchosen_rays", [])  # never kept on the answer
            for ray in rays if not out.decided else []:
                # the reduction returned another attempt's answer (max-margin's, undecided): its
                # fixed-margin ray may still be proved (obs_control.thm3_2's borderline example
                # on SCS: rejected points, and a ray the exact proof makes global)
                out = run.record(label, tag, ray, time.perf_counter())
                if out.decided:
                    break
            if sol.x is not None and len(sol.x) == problem.n:
                last_x = sol.x
            if out.decided:
                decided = True
                break
            if tag in ("default", "scaled"):  # escalate within this backend
                if feasibility_strict and options.strict == "auto":  # an explicit --strict is honoured
                    for s in ("max-margin", "fixed-margin"):
                        if s not in tried_strict and s != sol.strategy:
                            plan.append((f"strict={s}", problem, None))
                if last_x is not None and solve_as.lmis and np.all(np.isfinite(last_x)) and np.any(last_x):
                    plan.append(("rescaled", solve_as, last_x))
                if problem.objective.sense != "feasibility" and sol.status in ("error", "inaccurate", "infeasible"):
                    # an optimisation solve that failed: the feasibility problem can still prove
                    # infeasibility (a Farkas ray does not depend on the objective)
                    plan.append(("feasibility", feasibility_problem(solve_as), None))
            elif tag == "feasibility" and last_x is not None and np.all(np.isfinite(last_x)) and np.any(last_x):
                # the optimisation solve failed without a point, its feasibility problem has one:
                # the optimisation problem preconditioned there (CVXOPT's ZeroDivisionError on
                # random sampled_euler.thm2, 9 states, decided by the rescaled solve)
                if solve_as.lmis and not any(t == "rescaled" for t, _, _ in plan):
                    plan.append(("rescaled", solve_as, last_x))
        if decided:
            break
        if run.best is not None and run.best.verdict == "infeasible-bounded":
            bounded += 1
            if bounded >= max_bounded:
                break
        if qi == len(queue) and cut and budget_s is None and auto_budget:
            # nothing decided within the budgets: the first backend cut by its budget, unbounded
            queue.append((cut[0], None))
            auto_budget = False
    assert run.best is not None
    best = run.best
    if not best.decided and best.verdict in ("rejected", "undecided") and run.holding:
        # a point that holds (the solver stopped short, e.g. 'inaccurate') says more than a
        # rejected one: its objective is a proven end, and the enclosure (lmic.routes) may prove
        # the optimum to the requested gap whatever the solver's status
        sign = -1.0 if problem.objective.sense == "max" else 1.0
        best = min(run.holding, key=lambda o: sign * float(o.solution.objective or 0.0))
        best.reason = f"the solver stopped '{best.solution.status}'; its point holds: {best.reason}"
    if not best.decided and rescue and not exact:
        best = rescue_rejected(problem, best, run.rejected, run.attempts, key=_rel_margin)
    best.attempts = run.attempts
    if best.solution is not None:
        best.solution.info["attempts"] = [a.to_dict() for a in run.attempts]
    if best.verdict == "infeasible-bounded":
        if exact:  # the exact proof ran and failed (the reason says why): not a way further
            best.reason = best.reason.replace(" (an exact proof, --exact, decides)", "")
        best.reason += "; to go further: a larger bound (a more accurate ray), another backend (--backend)" + (
            "" if exact else ", or an exact proof (--exact)"
        )
    if best.evidence is None:
        best.evidence = Evidence()
    return best


def _timed_out(sol: Solution) -> bool:
    from lmic.backends.outcomes import is_time_limit

    return is_time_limit(sol)


def feasibility_problem(problem: Problem) -> Problem:
    """The same constraints without the objective.

    >>> from lmic.testing.conformance import CASES
    >>> feasibility_problem(CASES["max_sense"].build()).objective.sense
    'feasibility'
    """
    from lmic.ir.problem import Objective

    return replace(problem, objective=Objective("feasibility", np.zeros(problem.n + 1)))


def min_rel_margin(cert: Any) -> float | None:
    """The smallest finite relative LMI margin of a certificate (``None`` without one).

    >>> min_rel_margin(None) is None
    True
    """
    vals = [r.get("rel_margin") for r in getattr(cert, "lmis", None) or []]
    vals = [float(v) for v in vals if isinstance(v, int | float) and np.isfinite(float(v))]
    return min(vals) if vals else None


def _rel_margin(cert: Any) -> float:
    margin = min_rel_margin(cert)
    return -np.inf if margin is None else margin
