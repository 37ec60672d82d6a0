"""One parameter value: bind the cached plan, decide, record (:mod:`lmic.studies.sweep`).

How a point is decided (:func:`decide`)
---------------------------------------
A value counts as **feasible** only when the certifier certifies a point there: every LMI, linear
row and theorem check holds at the returned ``x`` (:func:`lmic.certify.certify`). When the float
certificate fails only because the margins are below the floating-point error bound (points near a
supremum that is not attained, where ``P`` grows like ``1e8``), an exact rational proof
(:mod:`lmic.certify.exact`) may still prove every LMI at the rounded point: that also counts
("certified (exact)"). A value counts as **infeasible** only with a GLOBAL proof (a verified
Farkas certificate, :mod:`lmic.outcome`); a bounded ray ("no solution with ``||x||_inf <= R``")
is recorded as ``infeasible-bounded``. Everything else is **undecided** and reported as such.

The decision itself is the one solve policy (:func:`lmic.policy.decide`): this module only
chooses what the solver is given (the objective dropped for a bisection, kept for a grid), the
reference point to precondition at (the last certified point, once a point needed a
preconditioned problem), and the warm start (the
neighbouring point's solution, :attr:`lmic.options.SolveOptions.warm_start`), and turns the
policy's :class:`~lmic.outcome.Outcome` into a :class:`PointResult`.

Examples
--------
>>> import scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
>>> p = Problem([Variable("p", "scalar", (1, 1))], [LMI("p > 0", 1, sp.csc_matrix([[0., 1.]]))],
...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
>>> decide(p).outcome
'feasible'
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from dataclasses import replace
from typing import Any

import numpy as np

from lmic.errors import DataError, LmicError
from lmic.ir.problem import Problem
from lmic.policy import feasibility_problem, min_rel_margin
from lmic.solution import Solution
from lmic.studies.sweep.results import PointResult, Progress
from lmic.studies.sweep.screens import STRETCH_FRACTION, reach, scalar_derived, screen

__all__ = [
    "decide",
    "screen",
    "reuse",
    "reach",
    "setup",
    "domain",
    "in_domain",
    "Evaluator",
    "scalar_derived",
    "warm_options",
]


def decide(
    problem: Problem,
    backend: Any = None,
    options: Any = None,
    *,
    reference: np.ndarray | None = None,
    keep_objective: bool = False,
    exact: bool = True,
    value: float = math.nan,
    scale: float | None = None,
    budget_s: float | None = None,
) -> PointResult:
    """Decide one compiled problem: feasible (certified), infeasible, or undecided.

    Runs the one solve policy (:func:`lmic.policy.decide`) on ``problem`` (the objective dropped
    unless ``keep_objective``): the problem preconditioned at ``reference`` first (if given),
    then as compiled, the other strict reduction, the problem preconditioned at the returned
    point, the next backend of the route, exact rescue. ``infeasible`` means a GLOBAL proof
    (verdict ``infeasible-certified``); a bounded ray ("no solution with ``||x||_inf <= R``",
    verdict ``infeasible-bounded``) leaves the point ``undecided`` with the radius recorded.

    Parameters
    ----------
    problem : Problem
        The IR at this parameter value.
    backend : str, Backend or None
        ``None``/``"auto"``: the escalating route; a backend: that backend alone.
    options : SolveOptions, optional
    reference : numpy.ndarray, optional
        A certified point at a nearby value: the LMIs are preconditioned at it
        (:func:`precondition`).
    keep_objective : bool
        Solve the theorem's own problem (grids). ``False`` drops the objective (bisection).
    exact : bool
        Allow the exact rescue of points with margins below the float error bound.
    value : float
        The parameter value (for the report).
    scale : float, optional
        ``||x||_inf`` of the certified points seen so far (reported next to a bounded ray's
        radius).
    budget_s : float, optional
        Seconds each backend may take (:func:`lmic.policy.decide`).

    Returns
    -------
    PointResult

    Examples
    --------
    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("p", "scalar", (1, 1))], [LMI("p > 0", 1, sp.csc_matrix([[0., 1.]]))],
    ...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
    >>> r = decide(p)
    >>> r.outcome, r.proof
    ('feasible', 'certified')
    """
    from lmic.policy import decide as policy_decide

    # a bisection point is a feasibility problem: the policy then routes it as one (SCS for
    # large strict problems) and its strict reduction decides both ways in one attempt
    judge = problem if keep_objective else feasibility_problem(problem)
    t0 = time.perf_counter()
    enc = None
    if judge.objective.sense in ("min", "max"):
        # a grid point of an optimisation theorem: its optimum, as a single solve proves it (the
        # route and its enclosure). The policy alone certified any point (margin strategies): a
        # newcomer's sweep reported objectives 11-14 % above the optimum and the wrong best value
        out, enc = _routed(judge, backend, options)
    else:
        out = policy_decide(
            judge,
            None if backend in (None, "auto") else backend,
            options,
            solve_as=judge,
            reference=reference,
            rescue=exact,
            budget_s=budget_s,
        )
    total = time.perf_counter() - t0
    cert = out.certificate
    result = PointResult(value=value, outcome="undecided", proof=out.reason or out.verdict)
    result.attempts = [a.line() for a in out.attempts]
    result.solve_s = sum(a.time_s for a in out.attempts)
    result.certify_s = max(0.0, total - result.solve_s)
    result.status = out.solution.status if out.solution is not None else ""
    result.verdict = out.verdict
    result.certificate = cert
    result.solution = out.solution
    result.rel_margin = min_rel_margin(cert)
    if enc is not None and (enc.get("lower") is not None or enc.get("upper") is not None):
        result.enclosure = {"lower": enc.get("lower"), "upper": enc.get("upper"), "rel_gap": enc.get("rel_gap")}
    if out.verdict == "certified":
        exact_used = bool(getattr(cert, "exact", None) and cert.exact.get("proven"))
        result.outcome, result.proof = "feasible", "certified (exact)" if exact_used else "certified"
        result.x = out.solution.x
        result.objective = out.solution.objective if keep_objective else None
        result.derived = scalar_derived(cert)
    elif out.verdict == "infeasible-certified":
        result.outcome = "infeasible"
        result.proof = "infeasible-certified: " + out.evidence.statement
    elif out.verdict == "infeasible-bounded":
        # never called infeasible: only "no solution with ||x||_inf <= R"
        result.outcome = "infeasible-bounded"
        result.farkas_radius = out.evidence.radius
        result.proof = "infeasible-bounded: " + out.evidence.statement
        if scale is not None and out.evidence.radius is not None:
            result.proof += f"; certified points reach ||x||_inf = {scale:.3g}"
    return result


def _routed(problem: Problem, backend: Any, options: Any) -> tuple[Any, dict[str, Any] | None]:
    """An optimisation problem decided as :func:`lmic.api.solve` decides it: the route, then the
    enclosure of its optimal value (``(outcome, enclosure or None)``)."""
    from lmic.routes import decide_route, enclosure_of

    routed = decide_route(problem, None if backend in (None, "auto") else backend, options)
    out, enc = routed.outcome, routed.enclosure
    if enc is None and out.solution is not None and out.certificate is not None:
        used = out.backend or str(getattr(backend, "label", backend) or "clarabel")
        enc, _ = enclosure_of(problem, out.solution, out.certificate, False, used, options)
    return out, enc


def reuse(problem: Problem, x: np.ndarray, *, value: float = math.nan, source: float = math.nan) -> PointResult | None:
    """A certified point at a neighbouring value, certified again at this one (no solve).

    The certifier alone decides (:func:`lmic.certify.certify` on ``problem`` at ``x``): the
    result is ``feasible`` with an ordinary certificate when every LMI, row, check and derived
    quantity holds, else ``None`` (nothing is concluded from a failure). Only for feasibility
    questions: a grid of an optimisation problem needs each value's optimum.

    Parameters
    ----------
    problem : Problem
        The problem at this value (its objective is ignored).
    x : numpy.ndarray
        A point certified at another value of the parameter (the same plan: same variables).
    value, source : float
        This value and the value ``x`` was certified at (for the report).

    Returns
    -------
    PointResult or None

    Examples
    --------
    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("p", "scalar", (1, 1))], [LMI("p > 0", 1, sp.csc_matrix([[0., 1.]]))],
    ...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
    >>> reuse(p, np.array([2.0]), value=1.0, source=0.5).proof
    'certified'
    >>> reuse(p, np.array([-2.0])) is None
    True
    """
    from lmic.certify import certify

    if x is None or len(x) != problem.n:
        return None
    judge = feasibility_problem(problem)
    t0 = time.perf_counter()
    sol = Solution(status="feasible", x=np.asarray(x, dtype=float), backend="reuse")
    cert = certify(judge, sol)
    if cert.verdict != "certified":
        return None
    res = PointResult(value=value, outcome="feasible", proof="certified", status="feasible", verdict="certified")
    res.attempts = [f"reuse: the certified point of {source:.6g}, certified again -> certified"]
    res.certify_s = time.perf_counter() - t0
    res.certificate, res.solution, res.x = cert, sol, sol.x
    res.rel_margin = min_rel_margin(cert)
    res.derived = scalar_derived(cert)
    res.reused = True
    return res


def _prove(
    problem: Problem,
    backend: Any,
    options: Any,
    value: float,
    exact: bool,
    budget_s: float | None = None,
    escalate: bool = True,
) -> PointResult | None:
    """A value expected infeasible: the max-margin reduction alone on one interior-point backend.

    Near a supremum the fixed-margin reduction ends in a numerical error there (Clarabel's
    ``NumericalError`` on ``qib.thm1``) and the policy then runs max-margin anyway: this starts
    with it, on the first interior-point backend of the route (the given backend when it is one).
    Returns the point when it decided (certified, or a GLOBAL infeasibility proof), else ``None``
    (the caller runs the full policy). ``exact``: exact rescue of points and bounded rays (a
    failing exact ray proof costs seconds); ``budget_s``: the backend's time budget.
    """
    from lmic.options import SolveOptions
    from lmic.policy import _instance, is_auto, route
    from lmic.reductions.strict import has_strict

    options = options or SolveOptions()
    judge = feasibility_problem(problem)
    if options.strict != "auto" or not has_strict(judge):
        return None
    try:
        names = route(judge, backend)
        ip = next((n for n in names if _instance(n).interior_point), None)
    except LmicError:
        return None
    if ip is None or (not is_auto(backend) and ip is not names[0]):
        return None
    try:
        res = decide(problem, ip, replace(options, strict="max-margin"), exact=exact, value=value, budget_s=budget_s)
    except LmicError:
        return None
    return res if res.outcome in ("feasible", "infeasible") or not escalate else None


def setup(theorem: str, system: Any, param: str, params: Mapping[str, Any] | None) -> tuple[Any, Any, dict, Any]:
    """Load the system, analyse the plan once, find the parameter's declaration.

    Returns ``(system, plan, overrides, declaration)``.

    >>> setup("qib.thm1", {"A": [[-1.0]], "C": [[1.0]]}, "nope", None)  # doctest: +SKIP
    Traceback (most recent call last):
    lmic.errors.DataError: ...
    """
    from lmic.compile import plan_for
    from lmic.system import load_system

    sysobj = load_system(system)
    overrides = dict(params or {})
    if param in overrides:
        raise DataError(f"-p {param}=...: the swept parameter '{param}' cannot also be fixed")
    merged = dict(sysobj.params)
    merged.update(overrides)
    plan = plan_for(theorem, merged)
    decls = {p.name: p for p in plan.template.params}
    if param not in decls:
        options = {o.name for o in plan.template.options}
        numeric = ", ".join(sorted(decls)) or "none"
        what = "a structural option, not a number" if param in options else "not a parameter"
        if param in {v.name for v in plan.template.variables}:
            what = (
                "a decision variable, not a parameter: the solve optimises it when the theorem says "
                f"t.maximize({param}) or t.minimize({param}); --maximize and --minimize sweep a parameter"
            )
        raise DataError(f"theorem {plan.id}: '{param}' is {what} (numeric parameters: {numeric})")
    return sysobj, plan, overrides, decls[param]


def domain(decl: Any) -> tuple[float, float, bool, bool]:
    """(inf, sup, inf included, sup included) of a parameter's sympy domain.

    >>> import sympy
    >>> class D: domain = sympy.Interval.open(0, 1)
    >>> domain(D())
    (0.0, 1.0, False, False)
    """
    dom = decl.domain
    try:
        lo, hi = float(dom.inf), float(dom.sup)
        lo_in = not bool(getattr(dom, "left_open", False)) and math.isfinite(lo)
        hi_in = not bool(getattr(dom, "right_open", False)) and math.isfinite(hi)
    except (TypeError, AttributeError):
        return -math.inf, math.inf, False, False
    return lo, hi, lo_in, hi_in


def in_domain(v: float, dom: tuple[float, float, bool, bool]) -> bool:
    """``v`` inside a :func:`domain` tuple.

    >>> in_domain(0.0, (0.0, 1.0, False, True)), in_domain(1.0, (0.0, 1.0, False, True))
    (False, True)
    """
    lo, hi, lo_in, hi_in = dom
    return (v > lo or (lo_in and v == lo)) and (v < hi or (hi_in and v == hi))


def _preconditioned(res: PointResult) -> bool:
    """The point was decided on a preconditioned problem (``scaled`` / ``rescaled`` attempt)."""
    last = res.attempts[-1] if res.attempts else ""
    return " / scaled" in last or " / rescaled" in last


def warm_options(options: Any, warm: Solution | None) -> Any:
    """``options`` with :attr:`~lmic.options.SolveOptions.warm_start` set to ``warm``.

    An explicit ``warm_start`` of the caller's options is kept for the first point only
    (``warm`` is ``None`` there).

    >>> warm_options(None, None).warm_start is None
    True
    """
    from lmic.options import SolveOptions

    options = options or SolveOptions()
    if warm is None:
        return options
    return replace(options, warm_start=warm)


class Evaluator:
    """Bind, decide and record one value at a time (re-binding the cached plan)."""

    def __init__(
        self,
        plan: Any,
        sysobj: Any,
        overrides: dict,
        param: str,
        backend: Any,
        options: Any,
        keep_objective: bool,
        exact: bool,
        progress: Progress | None,
        sign: float = 1.0,
        *,
        reuse: bool = True,
        screen: bool = False,
    ) -> None:
        self.plan, self.sysobj, self.overrides, self.param = plan, sysobj, overrides, param
        self.sign = sign  # called with u, binds the parameter at sign * u (infima: -1)
        self.backend, self.options = backend, options
        self.keep_objective, self.exact = keep_objective, exact
        self.progress = progress
        self.points: list[PointResult] = []
        self.reference: np.ndarray | None = None
        #: precondition at ``reference`` (only once a point needed it: the congruence costs the
        #: warm start, and most sweeps do not need it)
        self.precondition = False
        self.scale: float | None = None
        self.sense = "feasibility"
        #: the last solution with a point: the next solve's warm start (same shape: a re-bound plan)
        self.warm: Solution | None = None
        #: try the last certified point first (:func:`reuse`; feasibility questions only)
        self.reuse = reuse
        #: decide by one certified solve first (:func:`screen`; bisections), the policy only
        #: when that does not decide
        self.screen = screen
        #: screens may start with the route's first-order backend (off once it failed to
        #: decide: the bracket only narrows towards the supremum, where it is slow)
        self.first_order = True
        self.last_value = math.nan
        #: the problems bound at the last few values (``stretch`` needs two of them)
        self._bound: dict[float, Problem] = {}

    def bound(self, value: float) -> Problem:
        """The plan bound at ``value`` (the parameter's own value, not ``sign * value``)."""
        from lmic.compile import bind

        got = self._bound.get(value)
        if got is None:
            got = bind(self.plan, self.sysobj, {**self.overrides, self.param: float(value)})
            if len(self._bound) >= 8:
                self._bound.pop(next(iter(self._bound)))
            self._bound[value] = got
        return got

    def stretch(self, lower: float, upper: float, phase: str = "stretch") -> PointResult | None:
        """The last certified point, certified again as far towards ``upper`` as it reaches.

        ``lower`` (where :attr:`reference` was certified) and ``upper`` are in the
        evaluator's terms (``sign * value``). The LMIs at the point are modelled as affine in
        the parameter from the problems bound at both ends; the largest step ``s`` keeping
        every strict LMI positive definite and every row positive (:func:`reach`) gives the
        candidate ``lower + STRETCH_FRACTION * s * (upper - lower)`` (below ``upper``), where the
        point is certified again (:func:`reuse`: the certifier alone decides, the model only
        picks the value). Returns the recorded point, or ``None`` (nothing concluded).
        """
        if self.reference is None or self.keep_objective or not upper > lower:
            return None
        va, vb = self.sign * lower, self.sign * upper
        pa, pb = self.bound(va), self.bound(vb)
        s = reach(pa, pb, self.reference)
        if s is None or s <= 0.0:
            return None
        cand = lower + min(STRETCH_FRACTION * s, STRETCH_FRACTION) * (upper - lower)
        if not lower < cand < upper:
            return None
        value = self.sign * cand
        t0 = time.perf_counter()
        problem = self.bound(value)
        bind_s = time.perf_counter() - t0
        res = reuse(problem, self.reference, value=value, source=self.last_value)
        if res is None:
            return None
        res.attempts = [f"stretch: the certified point of {self.last_value:.6g}, certified again -> certified"]
        res.bind_s, res.stretched, res.problem = bind_s, True, problem
        self.last_value = value
        self.points.append(res)
        if self.progress is not None:
            self.progress({"phase": phase, "value": value, "point": res})
        return res

    def __call__(
        self,
        value: float,
        phase: str,
        *,
        full: bool = False,
        prove: bool = False,
        escalate: bool = True,
        exact: bool | None = None,
        budget_s: float | None = None,
        **info: Any,
    ) -> PointResult:
        """Decide ``sign * value``: reuse, screen (as configured), else the full policy.

        ``full``: the full policy only (a bracket's final end, whose evidence is reported).
        ``prove`` (with ``full``): a value expected infeasible, decided by the max-margin
        reduction on the route's first interior-point backend first (:func:`_prove`), the full
        policy where that does not decide (``escalate=False``: not then, the point is what the
        one solve gave). ``exact`` (default: the evaluator's) and ``budget_s`` apply to that solve.
        """
        value = self.sign * value
        t0 = time.perf_counter()
        problem = self.bound(float(value))
        bind_s = time.perf_counter() - t0
        self.sense = problem.objective.sense
        res: PointResult | None = None
        feasibility_question = not self.keep_objective or problem.objective.sense == "feasibility"
        if not full and self.reuse and feasibility_question and self.reference is not None:
            res = reuse(problem, self.reference, value=float(value), source=self.last_value)
        if res is None and not full and self.screen and not self.precondition:
            res = screen(
                problem,
                self.backend,
                warm_options(self.options, self.warm),
                value=float(value),
                first_order=self.first_order,
            )
            if res is not None and res.fallback:
                self.first_order = False
        if res is None and full and prove:
            res = _prove(
                problem,
                self.backend,
                self.options,
                float(value),
                self.exact if exact is None else exact,
                budget_s=budget_s,
                escalate=escalate,
            )
            if res is None and not escalate:
                res = PointResult(value=float(value), outcome="undecided", proof="not decided by one max-margin solve")
                res.attempts = ["max-margin on an interior-point backend: no decision"]
        if res is None:
            res = decide(
                problem,
                self.backend,
                warm_options(self.options, self.warm),
                reference=self.reference if self.precondition else None,
                keep_objective=self.keep_objective,
                exact=self.exact,
                value=float(value),
                scale=self.scale,
            )
        res.bind_s = bind_s
        if not res.reused and res.solution is not None and res.solution.x is not None:
            self.warm = res.solution
        if res.outcome == "feasible" and res.x is not None:
            res.problem = problem
            self.last_value = float(value)
            self.reference = res.x
            self.precondition = self.precondition or _preconditioned(res)
            norm = float(np.max(np.abs(res.x))) if res.x.size else 0.0
            self.scale = norm if self.scale is None else max(self.scale, norm)
        self.points.append(res)
        if self.progress is not None:
            self.progress({"phase": phase, "value": float(value), "point": res, **info})
        return res
