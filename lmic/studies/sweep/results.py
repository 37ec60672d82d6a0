"""Result types of a sweep, a supremum or an infimum (:mod:`lmic.studies.sweep`).

:class:`PointResult` (one parameter value and what was decided there), :class:`EndPoint` (the
certified point at a bracket's certified end), :class:`SupResult` (a supremum or infimum with
the evidence of both ends) and :class:`SweepResult` (a grid).

Examples
--------
>>> SweepResult("t", "a", "feasibility", [], None, "auto", 0.0, 0.0).exit_code()
1
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from lmic.ir.problem import Problem
from lmic.solution import Solution

__all__ = ["OUTCOMES", "Progress", "PointResult", "EndPoint", "SupResult", "SweepResult", "PROVEN_KINDS"]

#: outcomes of one point (``infeasible``: a global proof; ``infeasible-bounded``: only "no solution
#: with ||x||_inf <= R")
OUTCOMES = ("feasible", "infeasible", "infeasible-bounded", "undecided")

Progress = Callable[[dict[str, Any]], None]

#: evidence at the non-certified end that is a GLOBAL proof: a verified infeasibility
#: certificate at that value, or a proven dual bound of the optimal value (the enclosure)
PROVEN_KINDS = ("infeasible-certified", "dual-bound")


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
    #: the solver's answer that decided (the next point's warm start; not in the JSON)
    solution: Solution | None = field(default=None, repr=False)
    #: certified without a solve: a neighbouring value's certified point holds here too
    reused: bool = False
    #: decided for a bisection only: the solver said infeasible, nothing is proven (a bracket's
    #: final end is proven separately, never reported on this evidence)
    screened: bool = False
    #: a screen whose first-order backend did not decide: the interior-point backend did
    fallback: bool = False
    #: decided by a first-order screen (its "not certified" is the least reliable)
    first_order: bool = False
    #: certified at a value the bisection did not ask for: the point certified at a lower value
    #: still holds here (:meth:`lmic.studies.sweep.points.Evaluator.stretch`)
    stretched: bool = False
    #: an optimisation theorem's grid point: the proven enclosure of its optimal value
    #: (``lower``, ``upper``, ``rel_gap``; :func:`lmic.routes.enclosure_of`)
    enclosure: dict[str, Any] | None = None

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
            "reused": self.reused,
            "enclosure": self.enclosure,
            "screened": self.screened,
            "stretched": self.stretched,
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
        ``dual-bound`` (a proven dual bound of the supremum, :mod:`lmic.certify.enclosure`:
        no value above ``upper`` is feasible), ``infeasible-bounded`` (only "no solution with
        ``||x||_inf <= R``" at ``upper``: the supremum may lie above), ``undecided`` or ``none``.
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
    #: ``bisection`` or ``enclosure`` (the parameter solved for as a decision variable)
    method: str = "bisection"
    #: the enclosure of the supremum (``method == "enclosure"``, :func:`lmic.certify.enclosure.summary`)
    enclosure: dict[str, Any] | None = None
    #: why the method was chosen (e.g. why the enclosure could not replace the bisection)
    method_note: str = ""
    #: the feasible values of the parameter are proven to form an interval (it enters affinely,
    #: :func:`lmic.studies.sweep.enclosed.affine_parameter`): only then do a certified value and a
    #: proven infeasible one bracket the supremum; otherwise the bisection assumes it
    interval_proven: bool = False

    @property
    def bracket_proven(self) -> bool:
        """Both ends proven *and* the feasible values an interval: ``sup in [lower, upper]`` is a theorem."""
        return self.ends_proven and self.interval_proven

    @property
    def ends_proven(self) -> bool:
        """A certified value and a proven bound (global infeasibility or dual bound) at the other end."""
        return self.certified is not None and self.upper_kind in PROVEN_KINDS

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
        other_pt = next((p for p in self.points if p.value == self.other and kind_of(p) != "feasible"), None)
        cert_end: dict[str, Any] | None = None
        if self.end is not None:
            cert_end = self.end.to_dict()
        elif self.certified is not None:  # certified in the bisection, not re-certified on the theorem's problem
            cert_end = {"value": self.certified, "evidence": "certified point", "derived": None}
        other = None
        if self.other is not None:
            proof = None if other_pt is None else other_pt.proof
            if self.upper_kind == "dual-bound":
                dual = (self.enclosure or {}).get("dual") or {}
                how = "exact rational arithmetic" if dual.get("method") == "exact" else "rigorous float error bounds"
                proof = f"dual point proved feasible ({how}): weak duality bounds every feasible value"
            other = {
                "value": self.other,
                "evidence": self.upper_kind,
                "is_bound": self.upper_kind in PROVEN_KINDS,
                "proof": proof,
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
            # the evidence of each end by its side (the attribute upper_kind is the end opposite
            # the certified one: for an infimum that is the lower end)
            "lower_kind": "certified point" if self.sense == "max" else self.upper_kind,
            "upper_kind": self.upper_kind if self.sense == "max" else "certified point",
            "upper_proven": self.upper_proven,
            "bracket_proven": self.bracket_proven,
            "ends_proven": self.ends_proven,
            "interval_proven": self.interval_proven,
            "method": self.method,
            "method_note": self.method_note,
            "enclosure": self.enclosure,
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


def kind_of(pt: PointResult) -> str:
    """What a point is: ``feasible``, ``infeasible-certified`` (global proof),
    ``infeasible-bounded`` (no solution with ``||x||_inf <= R`` only) or ``undecided``.

    >>> kind_of(PointResult(1.0, "infeasible", "infeasible-certified: ..."))
    'infeasible-certified'
    """
    if pt.outcome == "feasible":
        return "feasible"
    if pt.outcome == "infeasible":
        return "infeasible-certified"
    if pt.outcome == "infeasible-bounded" or pt.verdict == "infeasible-bounded":
        return "infeasible-bounded"
    return "undecided"


def _points_exit(points: list[PointResult]) -> int:
    """3 every point proven infeasible (global), 4 every point at least bounded-infeasible, 1 otherwise."""
    kinds = {kind_of(p) for p in points}
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
