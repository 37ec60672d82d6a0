"""Suprema and grids over one scalar parameter: ``lmic solve ... --maximize P`` and ``--sweep P=a:b:n``.

Both re-bind the theorem's cached plan (:func:`lmic.compile.plan_for`, :func:`lmic.compile.bind`)
for every value of the parameter: the template is analysed once, each point costs one bind
(pure numerics), one solve and one certification.

How a point is decided (:func:`decide`)
---------------------------------------
A value counts as **feasible** only when the certifier certifies a point there: every LMI, linear
row and theorem check holds at the returned ``x`` (:func:`lmic.certify.certify`). When the float
certificate fails only because the margins are below the floating-point error bound (points near a
supremum that is not attained, where ``P`` grows like ``1e8``), an exact rational proof
(:mod:`lmic.certify.exact`) may still prove every LMI at the rounded point: that also counts
("certified (exact)"). A value counts as **infeasible** only when the solver reports infeasibility
(with or without a verified Farkas certificate; which one is recorded) or when the maximal margin
``t*`` of the strict problem is ``<= 0``. Everything else is **undecided** and reported as such.

For the supremum the parameter only has to be feasible, so the theorem's objective is dropped and
the strict constraints get a fixed margin (``SolveOptions.margin``); the solver is given each LMI
after a diagonal congruence ``D F(x) D`` with ``D = diag(F(x_ref))^-1/2`` taken at the last
certified point ``x_ref``. A congruence does not change which ``x`` are feasible, and the
certificate is always computed on the original LMIs; the scaling only equilibrates LMIs whose
blocks differ by ``1e12`` near the supremum (``-rho I`` against ``P``), which is what lets the
solver get within ``1e-4`` of ``gamma_max = 51.5`` on ``uio_dt.thm4_1``. If a point is undecided
the same problem is tried unscaled, then as the max-margin problem.

The certified end's point (:func:`certified_end`) is certified again on the theorem's own
problem (objective kept): where the theorem has an objective and derives gains, a backed-off
point (:mod:`lmic.backoff`, objective within ``1e-3`` of the bisection point's, ``||x||_inf``
minimised) if it certifies, else the bisection point itself (exactly where its float margins
are too small). Its gains and derived values are reported, and ``-o`` writes its certificate
(:func:`write_end_certificate`). :func:`minimize` is the mirror image (an infimum).

Bisection (:func:`maximize`) assumes that the feasible values form an interval that contains the
lower end of the bracket (true for Lipschitz constants, delay bounds and similar parameters). Its
report is honest about both ends: ``lower`` is certified; ``upper`` is the smallest value tried
that was not certified, with whether it was proven infeasible or merely not certified.

Examples
--------
>>> parse_grid("alpha=log:1e-3:1:4")
('alpha', [0.001, 0.01, 0.1, 1.0])
>>> r = maximize("thesis.thm3_2_2", "examples/thesis.thm3_2_2.ex3_2_2.yaml", "gamma",
...              rtol=1e-4)                                           # doctest: +SKIP
>>> round(r.lower, 4), r.converged                                    # doctest: +SKIP
(0.9997, True)
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from lmic.errors import DataError, LmicError
from lmic.ir.problem import Objective, Problem
from lmic.reductions.precondition import precondition
from lmic.solution import Solution

__all__ = [
    "PointResult",
    "SupResult",
    "EndPoint",
    "certified_end",
    "write_end_certificate",
    "SweepResult",
    "decide",
    "precondition",
    "maximize",
    "minimize",
    "sweep",
    "parse_grid",
]

#: outcomes of one point (``infeasible``: a global proof; ``infeasible-bounded``: only "no solution
#: with ||x||_inf <= R")
OUTCOMES = ("feasible", "infeasible", "infeasible-bounded", "undecided")

Progress = Callable[[dict[str, Any]], None]


@dataclass
class PointResult:
    """One value of the parameter and what was decided there.

    Attributes
    ----------
    value : float
        The parameter value.
    outcome : {"feasible", "infeasible", "undecided"}
    proof : str
        How: ``certified``, ``certified (exact)``, ``infeasible-certified`` (Farkas certificate
        verified), ``infeasible (solver)`` (no verified certificate), ``t* <= 0``, or the reason
        nothing was decided.
    status, verdict : str
        The status and verdict of the attempt that decided (or of the last attempt).
    objective : float or None
        The theorem's objective at the point (grids keep the objective; bisection drops it).
    rel_margin : float or None
        Smallest relative LMI margin the certifier found (``lambda_min / term scale``).
    attempts : list of str
        One line per solve tried (``scaled fixed-margin: optimal, certified`` ...).
    bind_s, solve_s, certify_s : float
    derived : dict
        The derived quantities at a feasible point (scalars only, for the report).
    """

    value: float
    outcome: str
    proof: str
    status: str = ""
    verdict: str = ""
    objective: float | None = None
    rel_margin: float | None = None
    attempts: list[str] = field(default_factory=list)
    bind_s: float = 0.0
    solve_s: float = 0.0
    certify_s: float = 0.0
    derived: dict[str, float] = field(default_factory=dict)
    x: np.ndarray | None = field(default=None, repr=False)
    farkas_radius: float | None = None
    certificate: Any = field(default=None, repr=False)
    #: the bound problem (kept at feasible points: the certified end's gains and certificate)
    problem: Problem | None = field(default=None, repr=False)

    def to_dict(self) -> dict[str, Any]:
        """JSON-able form (without the point ``x``)."""
        return {
            "value": self.value,
            "outcome": self.outcome,
            "proof": self.proof,
            "status": self.status,
            "verdict": self.verdict,
            "objective": self.objective,
            "rel_margin": self.rel_margin,
            "derived": self.derived,
            "farkas_radius": self.farkas_radius,
            "attempts": self.attempts,
            "bind_s": self.bind_s,
            "solve_s": self.solve_s,
            "certify_s": self.certify_s,
        }


@dataclass
class EndPoint:
    """The certified point at the lower end of a supremum's bracket, and what it yields.

    Attributes
    ----------
    value : float
        The parameter value (``SupResult.lower``).
    source : str
        ``backed-off point`` (the objective within ``backoff`` of the bisection point's,
        ``||x||_inf`` minimised: well-scaled gains, :mod:`lmic.backoff`) or ``bisection point``.
    verdict, proof : str
        The certifier's verdict on the theorem's own problem at this value, and how
        (``certified`` / ``certified (exact)``).
    derived : dict
        Every derived quantity (gains as nested lists, scalars as floats).
    norm_inf : float
        ``||x||_inf`` of the point.
    problem, solution, certificate
        What :func:`lmic.certify.write_certificate` needs (not in the JSON).
    """

    value: float
    source: str
    verdict: str
    proof: str
    derived: dict[str, Any]
    norm_inf: float
    backoff: float | None = None
    notes: list[str] = field(default_factory=list)
    problem: Problem | None = field(default=None, repr=False)
    solution: Solution | None = field(default=None, repr=False)
    certificate: Any = field(default=None, repr=False)

    def gain_norms(self) -> dict[str, float]:
        """Spectral norm of every matrix-valued derived quantity.

        >>> EndPoint(1.0, "bisection point", "certified", "certified", {"L": [[3.0, 0.0], [0.0, 4.0]],
        ...          "g": 2.0}, 4.0).gain_norms()
        {'L': 4.0}
        """
        out: dict[str, float] = {}
        for name, v in self.derived.items():
            if isinstance(v, list):
                arr = np.asarray(v, dtype=float)
                if arr.size and np.all(np.isfinite(arr)):
                    out[name] = float(np.linalg.norm(np.atleast_2d(arr), 2))
        return out

    def to_dict(self) -> dict[str, Any]:
        """JSON-able form (without the problem, solution and certificate objects)."""
        return {
            "value": self.value,
            "evidence": "certified point",
            "source": self.source,
            "verdict": self.verdict,
            "proof": self.proof,
            "backoff": self.backoff,
            "norm_inf": self.norm_inf,
            "derived": self.derived,
            "derived_norms": self.gain_norms(),
            "notes": self.notes,
        }


def _derived_values(cert: Any) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for item in getattr(cert, "derived", None) or []:
        v = item.get("value")
        if isinstance(v, np.ndarray):
            v = v.tolist()
        out[item["name"]] = float(v) if isinstance(v, int | float) and not isinstance(v, bool) else v
    return out


def certified_end(
    point: PointResult, backend: Any = None, options: Any = None, backoff: float | None = None
) -> EndPoint | None:
    """The certified point at a feasible bisection value, on the theorem's own problem.

    With ``backoff`` (default :data:`lmic.backoff.DEFAULT_BACKOFF` when the theorem derives
    quantities, ``0`` off) and an objective, the problem at this value is re-solved with the
    objective within ``backoff`` (relative) of the bisection point's and ``||x||_inf``
    minimised; a certified backed-off point is used (well-scaled gains). Otherwise the bisection
    point itself is certified against the theorem's problem (objective kept), with an exact
    proof where its float margins are too small. ``None`` when neither is certified (never a
    false certificate).

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Variable
    >>> p = Problem([Variable("p", "scalar", (1, 1))], [LMI("p > 0", 1, sp.csc_matrix([[0., 1.]]))],
    ...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
    >>> pt = decide(p, value=1.0); pt.problem = p
    >>> certified_end(pt).verdict
    'certified'
    """
    from lmic.certify import certify
    from lmic.policy import exact_rescue_point

    problem = point.problem
    if point.outcome != "feasible" or problem is None or point.x is None:
        return None
    notes: list[str] = []
    x = np.asarray(point.x, dtype=float)
    rel = backoff
    if rel is None:
        from lmic.backoff import DEFAULT_BACKOFF

        rel = DEFAULT_BACKOFF if problem.derived else 0.0
    if rel and problem.objective.sense != "feasibility":
        from lmic.backoff import backoff as run_backoff

        be = "clarabel" if backend in (None, "auto") else backend
        ref = problem.objective.value(x)
        rec = run_backoff(problem, float(ref if ref is not None else 0.0), be, options, rel=float(rel))
        if rec.get("verdict") == "certified" and rec.get("x") is not None:
            xb = np.asarray(rec["x"], dtype=float)
            sol = Solution(status=rec["status"], x=xb, objective=problem.objective.value(xb), backend=str(be))
            cert = certify(problem, sol)
            if cert.verdict == "certified":
                return EndPoint(
                    value=point.value,
                    source="backed-off point",
                    verdict="certified",
                    proof="certified",
                    derived=_derived_values(cert),
                    norm_inf=float(np.max(np.abs(xb), initial=0.0)),
                    backoff=float(rel),
                    notes=notes,
                    problem=problem,
                    solution=sol,
                    certificate=cert,
                )
        notes.append(f"backed-off point ({rel:g}) not certified, the bisection point is used: {rec.get('reason')}")
    label = str(getattr(backend, "label", backend) or "auto")
    # the bisection solve had no objective: the recorded objective is lmic's value at x
    sol = Solution(status=point.status or "optimal", x=x, objective=problem.objective.value(x), backend=label)
    end_cert: Any = certify(problem, sol)
    proof = "certified"
    if end_cert.verdict != "certified":
        end_cert = exact_rescue_point(problem, sol, end_cert)
        proof = "certified (exact)"
    if end_cert is None or end_cert.verdict != "certified":
        return None
    return EndPoint(
        value=point.value,
        source="bisection point",
        verdict="certified",
        proof=proof,
        derived=_derived_values(end_cert),
        norm_inf=float(np.max(np.abs(x), initial=0.0)),
        notes=notes,
        problem=problem,
        solution=sol,
        certificate=end_cert,
    )


def write_end_certificate(result: SupResult, path: str) -> dict[str, Any]:
    """Write the certificate of the certified end of ``result`` (``lmic audit`` verifies it).

    The file is the ordinary certificate of :func:`lmic.certify.write_certificate` for the
    theorem at ``param = result.certified`` (recorded in ``params``), at the point of
    ``result.end``. Raises :class:`LmicError` when there is no certified end.

    Examples
    --------
    >>> r = maximize("uio_dt.thm4_1", "examples/uio_dt.thm4_1.flexible_joint.yaml", "gamma",
    ...              lo=50.0, hi=51.5, rtol=1e-2)                     # doctest: +SKIP
    >>> write_end_certificate(r, "end.json")["params"]["gamma"] == r.lower  # doctest: +SKIP
    True
    """
    from lmic.certify import write_certificate

    end = result.end
    if end is None or end.problem is None or end.solution is None or end.certificate is None:
        raise LmicError(f"no certified point of '{result.param}': no certificate written")
    return write_certificate(path, end.problem, end.solution, end.certificate, system=result.system)


@dataclass
class SupResult:
    """The supremum of a parameter, as far as certificates go.

    Attributes
    ----------
    lower : float or None
        Largest value with a certified point (``None``: none found).
    upper : float or None
        Smallest value tried above ``lower`` that was not certified (``None``: none found, the
        parameter was feasible up to the end of its domain or of the search).
    upper_kind : str
        ``infeasible-certified`` (a GLOBAL proof at ``upper``: the supremum is proven below it),
        ``infeasible-bounded`` (only "no solution with ``||x||_inf <= R``" at ``upper``: the
        supremum may lie above), ``undecided`` or ``none``.
    upper_proven : float or None
        Smallest value with a GLOBAL infeasibility proof (may be above ``upper``); bounded rays
        never count. ``None``: no proven upper end (the supremum may be infinite).
    converged : bool
        ``upper - lower <= max(xtol, rtol * |upper|)``.
    end : EndPoint or None
        The certified point at the certified end, its gains and derived values, and what the
        certificate file needs (:func:`write_end_certificate`).
    sense : {"max", "min"}
        A supremum (:func:`maximize`) or an infimum (:func:`minimize`; then ``upper`` is the
        certified end and ``upper_kind`` / ``upper_proven`` describe the ``lower`` end).
    """

    theorem: str
    param: str
    lower: float | None
    upper: float | None
    upper_kind: str
    upper_proven: float | None
    converged: bool
    xtol: float
    rtol: float
    iterations: int
    points: list[PointResult]
    backend: str
    plan_s: float
    total_s: float
    message: str = ""
    domain: tuple[float, float] = (-math.inf, math.inf)
    #: the certified point at the lower end (:class:`EndPoint`; ``None``: no certified value)
    end: EndPoint | None = None
    #: the loaded system (for the certificate file)
    system: Any = field(default=None, repr=False)
    #: ``max`` (a supremum, :func:`maximize`) or ``min`` (an infimum, :func:`minimize`: ``upper`` is
    #: the certified end, and ``upper_kind`` / ``upper_proven`` describe the ``lower`` end)
    sense: str = "max"

    @property
    def certified(self) -> float | None:
        """The certified end of the bracket (``lower`` of a supremum, ``upper`` of an infimum)."""
        return self.lower if self.sense == "max" else self.upper

    @property
    def other(self) -> float | None:
        """The bisection's other end (not certified)."""
        return self.upper if self.sense == "max" else self.lower

    @property
    def width(self) -> float | None:
        """``upper - lower`` (``None`` if either is missing)."""
        if self.lower is None or self.upper is None:
            return None
        return self.upper - self.lower

    @property
    def estimate(self) -> float | None:
        """Midpoint of ``[lower, upper]`` (or the certified end alone)."""
        c, o = self.certified, self.other
        if c is None:
            return None
        return c if o is None else 0.5 * (c + o)

    def exit_code(self) -> int:
        """0 a certified lower bound; else 3 / 4 / 1 as :func:`lmic.outcome.exit_code` of the points
        (every value globally infeasible / every value at least bounded-infeasible / otherwise)."""
        if self.certified is not None:
            return 0
        return _points_exit(self.points)

    def ends(self) -> dict[str, Any]:
        """Each end of the bracket with its evidence.

        ``lower`` and ``upper`` (in the parameter's order): the certified end is the certified
        point with its gains (:meth:`EndPoint.to_dict`, ``evidence: certified point``); the other
        end says whether it is a GLOBAL infeasibility proof (``is_bound: true``), a bounded one
        (``infeasible-bounded``: not a bound) or undecided. ``proven_bound``: the nearest value
        with a global infeasibility proof (may lie beyond the bisection's end).
        """
        other_pt = next((p for p in self.points if p.value == self.other and _kind(p) != "feasible"), None)
        cert_end: dict[str, Any] | None = None
        if self.end is not None:
            cert_end = self.end.to_dict()
        elif self.certified is not None:  # certified in the bisection, not re-certified on the theorem's problem
            cert_end = {"value": self.certified, "evidence": "certified point", "derived": None}
        other = None
        if self.other is not None:
            other = {
                "value": self.other,
                "evidence": self.upper_kind,
                "is_bound": self.upper_kind == "infeasible-certified",
                "proof": None if other_pt is None else other_pt.proof,
                "farkas_radius": None if other_pt is None else other_pt.farkas_radius,
            }
        proven = None
        if self.upper_proven is not None:
            pp = next((p for p in self.points if p.value == self.upper_proven), None)
            proven = {"value": self.upper_proven, "proof": None if pp is None else pp.proof}
        lower, upper = (cert_end, other) if self.sense == "max" else (other, cert_end)
        return {"lower": lower, "upper": upper, "proven_bound": proven}

    def to_dict(self) -> dict[str, Any]:
        """The ``--json`` object."""
        from lmic._version import __version__

        binds = [p.bind_s for p in self.points]
        return {
            "lmic": __version__,
            "mode": "maximize" if self.sense == "max" else "minimize",
            "sense": self.sense,
            "certified": self.certified,
            "theorem": self.theorem,
            "param": self.param,
            "backend": self.backend,
            "lower": self.lower,
            "upper": self.upper,
            "upper_kind": self.upper_kind,
            "upper_proven": self.upper_proven,
            "bracket_proven": self.upper_kind == "infeasible-certified",
            "estimate": self.estimate,
            "width": self.width,
            "converged": self.converged,
            "tolerance": {"xtol": self.xtol, "rtol": self.rtol},
            "domain": list(self.domain),
            "iterations": self.iterations,
            "evaluations": len(self.points),
            "message": self.message,
            "ends": self.ends(),
            "points": [p.to_dict() for p in self.points],
            "timings": _timings(self.plan_s, binds, self.points, self.total_s),
            "exit_code": self.exit_code(),
        }


@dataclass
class SweepResult:
    """Every grid point, and the best certified one.

    ``best`` is the certified point with the best objective (``min``/``max`` theorems). For a
    feasibility theorem it is the certified point at the edge of feasibility when the certified
    points are one run at the start (or the end) of the grid (e.g. the largest certified
    Lipschitz constant), otherwise the largest relative margin; ``best_rule`` says which.
    """

    theorem: str
    param: str
    sense: str
    points: list[PointResult]
    best: PointResult | None
    backend: str
    plan_s: float
    total_s: float
    #: how ``best`` was chosen: ``objective``, ``edge of the certified range``, ``largest margin``
    best_rule: str = ""

    def exit_code(self) -> int:
        """0 some point certified; else 3 / 4 / 1 as for :meth:`SupResult.exit_code`."""
        if self.best is not None:
            return 0
        return _points_exit(self.points)

    def to_dict(self) -> dict[str, Any]:
        """The ``--json`` object."""
        from lmic._version import __version__

        return {
            "lmic": __version__,
            "mode": "sweep",
            "theorem": self.theorem,
            "param": self.param,
            "backend": self.backend,
            "sense": self.sense,
            "best": None if self.best is None else self.best.to_dict(),
            "best_rule": self.best_rule,
            "points": [p.to_dict() for p in self.points],
            "timings": _timings(self.plan_s, [p.bind_s for p in self.points], self.points, self.total_s),
            "exit_code": self.exit_code(),
        }


def _kind(pt: PointResult) -> str:
    """What a point is: ``feasible``, ``infeasible-certified`` (global proof),
    ``infeasible-bounded`` (no solution with ``||x||_inf <= R`` only) or ``undecided``."""
    if pt.outcome == "feasible":
        return "feasible"
    if pt.outcome == "infeasible":
        return "infeasible-certified"
    if pt.outcome == "infeasible-bounded" or pt.verdict == "infeasible-bounded":
        return "infeasible-bounded"
    return "undecided"


def _points_exit(points: list[PointResult]) -> int:
    """3 every point proven infeasible (global), 4 every point at least bounded-infeasible, 1 otherwise."""
    kinds = {_kind(p) for p in points}
    if points and kinds == {"infeasible-certified"}:
        return 3
    if points and kinds <= {"infeasible-certified", "infeasible-bounded"}:
        return 4
    return 1


def _timings(plan_s: float, binds: list[float], points: list[PointResult], total_s: float) -> dict[str, float]:
    n = max(len(binds), 1)
    return {
        "plan_s": plan_s,
        "bind_s_mean": sum(binds) / n,
        "bind_s_max": max(binds, default=0.0),
        "solve_s": sum(p.solve_s for p in points),
        "certify_s": sum(p.certify_s for p in points),
        "total_s": total_s,
        # what analysing the template again at every point would have cost in addition
        "saved_by_rebinding_s": plan_s * max(len(points) - 1, 0),
    }


# --------------------------------------------------------------------------------------------
# one point


def _feasibility(problem: Problem) -> Problem:
    return replace(problem, objective=Objective("feasibility", np.zeros(problem.n + 1)))


def _zero_objective(problem: Problem) -> Problem:
    """Same constraints, objective ``min 0``: strict constraints get the fixed margin."""
    return replace(problem, objective=Objective("min", np.zeros(problem.n + 1)))


def _scalar_derived(cert: Any) -> dict[str, float]:
    out: dict[str, float] = {}
    for item in getattr(cert, "derived", None) or []:
        v = item.get("value")
        if isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(float(v)):
            out[item["name"]] = float(v)
    return out


def _rel_margin(cert: Any) -> float | None:
    vals = [r.get("rel_margin") for r in getattr(cert, "lmis", None) or []]
    vals = [float(v) for v in vals if isinstance(v, int | float) and math.isfinite(float(v))]
    return min(vals) if vals else None


def _exact_rescue(problem: Problem, sol: Solution, cert: Any) -> Any | None:
    """An exact proof at a point the float certificate rejected only for its tiny margins
    (:func:`lmic.policy.exact_rescue_point`)."""
    from lmic.policy import exact_rescue_point

    return exact_rescue_point(problem, sol, cert)


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

    Returns
    -------
    PointResult

    Examples
    --------
    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Variable
    >>> p = Problem([Variable("p", "scalar", (1, 1))], [LMI("p > 0", 1, sp.csc_matrix([[0., 1.]]))],
    ...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
    >>> r = decide(p)
    >>> r.outcome, r.proof
    ('feasible', 'certified')
    """
    from lmic.policy import decide as policy_decide

    judge = problem if keep_objective else _feasibility(problem)
    base = problem if keep_objective else _zero_objective(problem)
    t0 = time.perf_counter()
    out = policy_decide(
        judge,
        None if backend in (None, "auto") else backend,
        options,
        solve_as=base,
        reference=reference,
        rescue=exact,
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
    result.rel_margin = _rel_margin(cert)
    if out.verdict == "certified":
        exact_used = bool(getattr(cert, "exact", None) and cert.exact.get("proven"))
        result.outcome, result.proof = "feasible", "certified (exact)" if exact_used else "certified"
        result.x = out.solution.x
        result.objective = out.solution.objective if keep_objective else None
        result.derived = _scalar_derived(cert)
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


# --------------------------------------------------------------------------------------------
# plans and parameters


def _setup(theorem: str, system: Any, param: str, params: Mapping[str, Any] | None) -> tuple[Any, Any, dict, Any]:
    """Load the system, analyse the plan once, find the parameter's declaration."""
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
        raise DataError(f"theorem {plan.id}: '{param}' is {what} (numeric parameters: {numeric})")
    return sysobj, plan, overrides, decls[param]


def _domain(decl: Any) -> tuple[float, float, bool, bool]:
    """(inf, sup, inf included, sup included) of a parameter's sympy domain."""
    dom = decl.domain
    try:
        lo, hi = float(dom.inf), float(dom.sup)
        lo_in = not bool(getattr(dom, "left_open", False)) and math.isfinite(lo)
        hi_in = not bool(getattr(dom, "right_open", False)) and math.isfinite(hi)
    except (TypeError, AttributeError):
        return -math.inf, math.inf, False, False
    return lo, hi, lo_in, hi_in


def _in_domain(v: float, dom: tuple[float, float, bool, bool]) -> bool:
    lo, hi, lo_in, hi_in = dom
    return (v > lo or (lo_in and v == lo)) and (v < hi or (hi_in and v == hi))


class _Evaluator:
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
    ) -> None:
        self.plan, self.sysobj, self.overrides, self.param = plan, sysobj, overrides, param
        self.sign = sign  # called with u, binds the parameter at sign * u (infima: -1)
        self.backend, self.options = backend, options
        self.keep_objective, self.exact = keep_objective, exact
        self.progress = progress
        self.points: list[PointResult] = []
        self.reference: np.ndarray | None = None
        self.scale: float | None = None
        self.sense = "feasibility"

    def __call__(self, value: float, phase: str, **info: Any) -> PointResult:
        from lmic.compile import bind

        value = self.sign * value
        t0 = time.perf_counter()
        problem = bind(self.plan, self.sysobj, {**self.overrides, self.param: float(value)})
        bind_s = time.perf_counter() - t0
        self.sense = problem.objective.sense
        res = decide(
            problem,
            self.backend,
            self.options,
            reference=self.reference,
            keep_objective=self.keep_objective,
            exact=self.exact,
            value=float(value),
            scale=self.scale,
        )
        res.bind_s = bind_s
        if res.outcome == "feasible" and res.x is not None:
            res.problem = problem
            self.reference = res.x
            norm = float(np.max(np.abs(res.x))) if res.x.size else 0.0
            self.scale = norm if self.scale is None else max(self.scale, norm)
        self.points.append(res)
        if self.progress is not None:
            self.progress({"phase": phase, "value": float(value), "point": res, **info})
        return res


# --------------------------------------------------------------------------------------------
# supremum by bisection


def maximize(
    theorem: str,
    system: Any,
    param: str,
    *,
    lo: float | None = None,
    hi: float | None = None,
    xtol: float = 1e-6,
    rtol: float = 1e-5,
    params: Mapping[str, Any] | None = None,
    backend: Any = None,
    options: Any = None,
    exact: bool = True,
    max_evals: int = 100,
    progress: Progress | None = None,
    backoff: float | None = None,
) -> SupResult:
    """Supremum of a scalar parameter by bisection on certified feasibility.

    Parameters
    ----------
    theorem : str
        Theorem id.
    system : path, dict or System
    param : str
        A numeric parameter of the theorem (e.g. ``gamma``).
    lo, hi : float, optional
        Bracket. Without them the search starts at the system's (or the default) value, or 1,
        and expands (doubling) or shrinks (halving) until a certified and a non-certified value
        enclose the supremum; the parameter's domain bounds the search.
    xtol, rtol : float
        Stop when ``upper - lower <= max(xtol, rtol * |upper|)``.
    params : mapping, optional
        Other parameter overrides (``-p k=v``).
    backend : str or Backend
    options : SolveOptions, optional
    exact : bool
        Accept exact rational proofs at points whose float margins are too small.
    max_evals : int
        Bound on the number of points.
    progress : callable, optional
        Called with ``{"phase", "value", "point", "lower", "upper", "iteration", "total"}``.
    backoff : float, optional
        Relative backoff of the certified end's point (:func:`certified_end`; ``0`` off).

    Returns
    -------
    SupResult
        With ``end``: the certified point at ``lower``, its gains and derived values.

    Examples
    --------
    >>> r = maximize("uio_dt.thm4_1", "examples/uio_dt.thm4_1.flexible_joint.yaml", "gamma",
    ...              rtol=1e-3)                                        # doctest: +SKIP
    >>> round(r.lower, 1), next(p.proof for p in r.points if p.value == r.lower)  # doctest: +SKIP
    (51.5, 'certified (exact)')
    """
    return _bisect(
        theorem, system, param, 1.0, lo, hi, xtol, rtol, params, backend, options, exact, max_evals, progress, backoff
    )


def minimize(
    theorem: str,
    system: Any,
    param: str,
    *,
    lo: float | None = None,
    hi: float | None = None,
    xtol: float = 1e-6,
    rtol: float = 1e-5,
    params: Mapping[str, Any] | None = None,
    backend: Any = None,
    options: Any = None,
    exact: bool = True,
    max_evals: int = 100,
    progress: Progress | None = None,
    backoff: float | None = None,
) -> SupResult:
    """Infimum of a scalar parameter by bisection on certified feasibility (:func:`maximize` mirrored).

    Assumes that the feasible values form an interval that contains the upper end of the
    bracket (e.g. a decay rate or a gain bound ``gamma``). The result has ``sense == "min"``:
    ``upper`` is the certified end (``end`` its point), ``lower`` the largest value tried below
    it that was not certified, ``upper_kind`` / ``upper_proven`` that end's evidence and the
    largest value with a GLOBAL infeasibility proof.

    Parameters
    ----------
    As :func:`maximize`; ``hi`` is the certified end of the bracket, ``lo`` the other.

    Returns
    -------
    SupResult

    Examples
    --------
    >>> r = minimize("uio_dt.thm4_1", "examples/uio_dt.thm4_1.flexible_joint.yaml", "gamma",
    ...              lo=1.0, hi=2.0)                                   # doctest: +SKIP
    >>> r.sense, r.upper                                               # doctest: +SKIP
    ('min', 1.0)
    """
    return _bisect(
        theorem, system, param, -1.0, lo, hi, xtol, rtol, params, backend, options, exact, max_evals, progress, backoff
    )


def _bisect(
    theorem: str,
    system: Any,
    param: str,
    sign: float,
    lo_v: float | None,
    hi_v: float | None,
    xtol: float,
    rtol: float,
    params: Mapping[str, Any] | None,
    backend: Any,
    options: Any,
    exact: bool,
    max_evals: int,
    progress: Progress | None,
    backoff: float | None,
) -> SupResult:
    """The bisection in ``u = sign * value`` (a supremum of ``u``), reported in the parameter's terms."""
    t_start = time.perf_counter()
    if not (xtol > 0 or rtol > 0) or xtol < 0 or rtol < 0:
        raise LmicError("--xtol and --rtol must be non-negative and not both 0")
    t0 = time.perf_counter()
    sysobj, plan, overrides, decl = _setup(theorem, system, param, params)
    plan_s = time.perf_counter() - t0
    dom_v = _domain(decl)
    for name, v in (("--lo", lo_v), ("--hi", hi_v)):
        if v is not None and (not math.isfinite(v) or not _in_domain(v, dom_v)):
            raise DataError(f"theorem {plan.id}: {name} {v:g} is outside the domain {decl.domain} of '{param}'")
    if lo_v is not None and hi_v is not None and not lo_v < hi_v:
        raise DataError(f"--lo {lo_v:g} must be below --hi {hi_v:g}")
    is_max = sign > 0
    # u = sign * value: a supremum of u (the certified end first, as --lo of a supremum)
    dom = dom_v if is_max else (-dom_v[1], -dom_v[0], dom_v[3], dom_v[2])
    lo = lo_v if is_max else (None if hi_v is None else -hi_v)
    hi = hi_v if is_max else (None if lo_v is None else -lo_v)
    lo_flag, hi_flag = ("--lo", "--hi") if is_max else ("--hi", "--lo")
    what = "supremum" if is_max else "infimum"

    def vv(u: float | None) -> float | None:
        return None if u is None else sign * u

    def bracket_v(a: float | None, b: float | None) -> tuple[float | None, float | None]:
        return (a, b) if is_max else (vv(b), vv(a))

    state: dict[str, Any] = {"lower": None, "upper": None, "iteration": 0, "total": None}

    def report(event: dict[str, Any]) -> None:
        if progress is not None:
            progress({**event, **state})

    ev = _Evaluator(plan, sysobj, overrides, param, backend, options, False, exact, report, sign)
    lower: float | None = None
    upper: float | None = None
    upper_pt: PointResult | None = None
    message = ""

    def feasible(v: float, phase: str) -> bool:
        nonlocal lower, upper, upper_pt
        pt = ev(v, phase)
        if pt.outcome == "feasible":
            if lower is None or v > lower:
                lower = v
        elif upper is None or v < upper:
            upper, upper_pt = v, pt
        state["lower"], state["upper"] = bracket_v(lower, upper)
        return pt.outcome == "feasible"

    dlo, dhi, dlo_in, dhi_in = dom

    def up(v: float, k: int) -> float:
        step = abs(v) if v != 0 else 1.0
        cand = v + step * (2.0**k - 1.0) if v > 0 else v + step * 2.0 ** (k - 1)
        if cand >= dhi:
            cand = dhi if dhi_in else 0.5 * (v + dhi) if math.isfinite(dhi) else cand
        return cand

    def down(v: float, k: int) -> float:
        cand = v / 2.0**k if v > 0 else v - (abs(v) or 1.0) * (2.0**k - 1.0)
        if v > 0 and k > 40:
            cand = 0.0
        if cand <= dlo:
            cand = dlo if dlo_in else 0.5 * (v + dlo) if math.isfinite(dlo) else cand
        return cand

    # -- bracket ---------------------------------------------------------------------------
    if lo is not None:
        if not feasible(lo, "bracket"):
            message = f"no certified point at {lo_flag} {vv(lo):g}"
    if hi is not None and (lo is None or lower is not None):
        if feasible(hi, "bracket"):
            side = "at or above" if is_max else "at or below"
            message = f"{hi_flag} {vv(hi):g} is certified: the {what} is {side} the bracket"
    if lo is None and hi is None:
        start = sysobj.params.get(param, decl.default)
        x0 = sign * float(start) if isinstance(start, int | float) and float(start) != 0 else sign
        if not _in_domain(x0, dom):
            x0 = 0.5 * (dlo + dhi) if math.isfinite(dlo) and math.isfinite(dhi) else (dlo + 1.0)
        feasible(x0, "bracket")
    if not message:
        if lower is not None and upper is None:  # expand upwards
            k, base = 1, lower
            while upper is None and len(ev.points) < max_evals:
                cand = up(base, k)
                if cand <= lower or (ev.points and cand == sign * ev.points[-1].value):
                    way = "up" if is_max else "down"
                    message = f"'{param}' is certified {way} to the end of its domain ({vv(lower):g})"
                    break
                feasible(cand, "bracket")
                k += 1
        elif lower is None and upper is not None:  # shrink downwards
            k, base = 1, upper
            while lower is None and len(ev.points) < max_evals:
                cand = down(base, k)
                if cand >= upper or (ev.points and cand == sign * ev.points[-1].value):
                    message = f"no certified value of '{param}' found down to the end of its domain"
                    break
                feasible(cand, "bracket")
                k += 1
        if lower is None and not message:
            message = f"no certified value of '{param}' found"
        elif upper is None and not message:
            message = f"no {'upper' if is_max else 'lower'} bound found for '{param}' within {max_evals} points"

    # -- bisection ---------------------------------------------------------------------------
    def target(a: float, b: float) -> float:
        return max(xtol, rtol * max(abs(a), abs(b)))

    iterations = 0
    if lower is not None and upper is not None and upper > lower:
        width, tgt = upper - lower, target(lower, upper)
        state["total"] = max(0, math.ceil(math.log2(width / tgt))) if width > tgt else 0
        while upper - lower > target(lower, upper) and len(ev.points) < max_evals:
            iterations += 1
            state["iteration"] = iterations
            # remaining halvings (the relative target moves with the bracket)
            state["total"] = iterations - 1 + max(1, math.ceil(math.log2((upper - lower) / target(lower, upper))))
            feasible(0.5 * (lower + upper), "bisect")
    converged = lower is not None and upper is not None and upper - lower <= target(lower, upper)
    if lower is not None and upper is not None and not converged and not message:
        message = f"stopped after {len(ev.points)} points (--max-evals) before the tolerance"
    proven = [
        sign * p.value
        for p in ev.points
        if _kind(p) == "infeasible-certified" and (lower is None or sign * p.value > lower)
    ]
    upper_kind = "none" if upper_pt is None else _kind(upper_pt)
    end = None
    if lower is not None:
        lower_pt = next(p for p in ev.points if sign * p.value == lower and p.outcome == "feasible")
        end = certified_end(lower_pt, backend, options, backoff)
        for p in ev.points:  # only the end's problem is needed
            if p is not lower_pt:
                p.problem = None
    if upper is not None and upper_kind != "infeasible-certified" and not message:
        end_name, rel_op, more = ("upper", ">=", "larger (even infinite)") if is_max else ("lower", "<=", "smaller")
        message = (
            f"the bisection's {end_name} end {vv(upper):g} is {upper_kind}, not a proof: the {what} is {rel_op} "
            f"{vv(lower) if lower is not None else '-'} and may be {more}"
        )
    lower_v, upper_v = bracket_v(lower, upper)
    return SupResult(
        theorem=plan.id,
        param=param,
        lower=lower_v,
        upper=upper_v,
        upper_kind=upper_kind,
        upper_proven=vv(min(proven)) if proven else None,
        converged=converged,
        xtol=xtol,
        rtol=rtol,
        iterations=iterations,
        points=ev.points,
        backend=str(getattr(backend, "label", backend) or "auto"),
        plan_s=plan_s,
        total_s=time.perf_counter() - t_start,
        message=message,
        domain=(dom_v[0], dom_v[1]),
        end=end,
        sense="max" if is_max else "min",
        system=sysobj,
    )


# --------------------------------------------------------------------------------------------
# grids


def parse_grid(spec: str) -> tuple[str, list[float]]:
    """``PARAM=a:b:n`` (linear) or ``PARAM=log:a:b:n`` (geometric) -> (name, values).

    Numbers are read with ``float`` (nothing is evaluated); ``n >= 1``; a geometric grid needs
    ``a`` and ``b`` of the same sign and non-zero.

    >>> parse_grid("eps=0.5:1.5:3")
    ('eps', [0.5, 1.0, 1.5])
    >>> parse_grid("eps=0.5")
    Traceback (most recent call last):
    ...
    lmic.errors.DataError: --sweep 'eps=0.5': write PARAM=a:b:n or PARAM=log:a:b:n
    """
    bad = DataError(f"--sweep {spec!r}: write PARAM=a:b:n or PARAM=log:a:b:n")
    if "=" not in spec:
        raise bad
    name, rest = (s.strip() for s in spec.split("=", 1))
    if not name.isidentifier():
        raise DataError(f"--sweep {spec!r}: '{name}' is not a parameter name")
    parts = [s.strip() for s in rest.split(":")]
    scale = "linear"
    if parts and parts[0].lower() == "log":
        scale, parts = "log", parts[1:]
    if len(parts) != 3:
        raise bad
    try:
        a, b = float(parts[0]), float(parts[1])
        n = int(parts[2])
    except ValueError:
        raise bad from None
    if not (math.isfinite(a) and math.isfinite(b)):
        raise DataError(f"--sweep {spec!r}: the ends must be finite numbers")
    if n < 1 or n > 10000:
        raise DataError(f"--sweep {spec!r}: the number of points must be between 1 and 10000")
    if n == 1:
        return name, [a]
    if scale == "log":
        if a == 0 or b == 0 or (a > 0) != (b > 0):
            raise DataError(f"--sweep {spec!r}: a geometric grid needs non-zero ends of the same sign")
        values = np.geomspace(a, b, n)
    else:
        values = np.linspace(a, b, n)
    return name, [float(np.format_float_positional(v, precision=12, unique=True, trim="-")) for v in values]


def sweep(
    theorem: str,
    system: Any,
    param: str,
    values: Sequence[float],
    *,
    params: Mapping[str, Any] | None = None,
    backend: Any = None,
    options: Any = None,
    exact: bool = True,
    progress: Progress | None = None,
) -> SweepResult:
    """Solve and certify the theorem at every value of ``param`` (a re-bound cached plan).

    Each point is the theorem's own problem (objective kept) decided by :func:`decide`; the best
    certified point is reported (objective for ``min``/``max``, relative margin for feasibility).

    Examples
    --------
    >>> r = sweep("qib.thm2", "examples/qib.thm2.flexible-joint.yaml", "alpha",
    ...           [1e-3, 1.0])                                         # doctest: +SKIP
    >>> [p.outcome for p in r.points]                                  # doctest: +SKIP
    ['infeasible', 'infeasible']
    """
    t_start = time.perf_counter()
    t0 = time.perf_counter()
    sysobj, plan, overrides, decl = _setup(theorem, system, param, params)
    plan_s = time.perf_counter() - t0
    dom = _domain(decl)
    for v in values:
        if not _in_domain(float(v), dom):
            raise DataError(f"theorem {plan.id}: {param} = {v:g} is outside its domain {decl.domain}")
    total = len(values)

    def report(event: dict[str, Any]) -> None:
        if progress is not None:
            progress({**event, "total": total})

    ev = _Evaluator(plan, sysobj, overrides, param, backend, options, True, exact, report)
    for k, v in enumerate(values):
        ev(float(v), "sweep", iteration=k + 1)
    certified = [p for p in ev.points if p.outcome == "feasible"]
    best: PointResult | None = None
    best_rule = ""
    sense = ev.sense
    if certified:
        ok = [p.outcome == "feasible" for p in ev.points]
        k = len(certified)
        if sense in ("min", "max") and all(p.objective is not None for p in certified):
            pick = min if sense == "min" else max
            best = pick(certified, key=lambda p: float(p.objective))  # type: ignore[arg-type]
            best_rule = "objective"
        elif k < len(ok) and (all(ok[:k]) or all(ok[-k:])):
            # one certified run at an end of the grid: the interesting point is where it stops
            best = certified[-1] if all(ok[:k]) else certified[0]
            best_rule = "edge of the certified range"
        else:
            best = max(certified, key=lambda p: -math.inf if p.rel_margin is None else p.rel_margin)
            best_rule = "largest margin"
    return SweepResult(
        theorem=plan.id,
        param=param,
        sense=sense,
        points=ev.points,
        best=best,
        best_rule=best_rule,
        backend=str(getattr(backend, "label", backend) or "auto"),
        plan_s=plan_s,
        total_s=time.perf_counter() - t_start,
    )


# --------------------------------------------------------------------------------------------
# command line (options added to ``lmic solve`` by a small hook in lmic/commands/solve.py)
