"""A solver said ``unbounded``: prove what can be proved, and decide when both halves hold.

An optimisation problem (``min q.x``) is *unbounded* when it has a feasible point and an
improving ray ``d`` (``q.d < 0``, every LMI's homogeneous part PSD along ``d``, every row kept):
then ``x + t d`` is feasible for every ``t >= 0`` and the objective goes to ``-inf``
(``+inf`` for ``max``). :func:`unbounded_outcome` looks for both:

* the ray, from the policy on :func:`lmic.certify.farkas_unbounded.ray_problem`, proved in exact
  rational arithmetic (:func:`~lmic.certify.farkas_unbounded.prove_improving_ray`);
* the point, from the policy on the feasibility problem, certified on the *original* problem.

With both the verdict is ``unbounded-certified`` (exit 5): a decision, with its evidence in the
outcome's ``unbounded`` record (the exact ray as fraction strings, its slope ``q.d``) and the
certified point. ``lmic solve -o`` writes both into the certificate file, and ``lmic audit``
re-proves the ray exactly and re-certifies the point
(:func:`lmic.certify.farkas_unbounded.audit_unbounded`). With the ray alone the problem is
"unbounded or infeasible" (``undecided``, the reason says so); a feasibility decision of
infeasible is the outcome itself.

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
>>> # min -t over [[t, 1], [1, t]] >= 0: feasible for t >= 1, unbounded along d = 1
>>> C = sp.csc_matrix(np.array([[0.0, 1.0], [1.0, 0.0], [0.0, 1.0]]))
>>> p = Problem([Variable("t", "scalar", (1, 1))], [LMI("M", 2, C, strict=False)],
...             LinearConstraints.empty(1), Objective("min", [0.0, -1.0]))
>>> out = unbounded_outcome(p, Outcome("undecided", None, "unbounded"))
>>> out.verdict, out.exit_code(), out.unbounded["ray"]
('unbounded-certified', 5, ['1'])
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from lmic.ir.problem import Problem
from lmic.outcome import Evidence, Outcome

__all__ = ["unbounded_outcome", "unbounded_checked"]


def unbounded_outcome(problem: Problem, best: Outcome, options: Any = None) -> Outcome:
    """Decide an optimisation problem a solver called unbounded (module docstring).

    Parameters
    ----------
    problem : Problem
        The optimisation problem (a feasibility problem is returned unchanged: nothing to decide).
    best : Outcome
        The route's outcome so far (its attempts are kept; it is returned, with a reason saying
        what was not proved, when no exact ray is found).
    options : SolveOptions, optional

    Returns
    -------
    Outcome
        ``unbounded-certified`` with ``unbounded`` = ``{"ray", "slope", "sense", "statement"}``;
        the feasibility problem's ``infeasible-certified``; or ``undecided`` saying what holds.

    Examples
    --------
    >>> from lmic.testing.conformance import lyapunov_problem
    >>> o = Outcome("undecided", None, "unbounded")
    >>> unbounded_outcome(lyapunov_problem(-np.eye(1)), o).verdict  # a feasibility problem
    'undecided'
    """
    from lmic.policy import decide, feasibility_problem

    if problem.objective.sense == "feasibility":
        return best
    t0 = time.perf_counter()
    ray, ray_attempts, ray_verdict = _improving_ray(problem, options)
    feas = decide(feasibility_problem(problem), None, options)
    attempts = best.attempts + ray_attempts + feas.attempts
    if feas.verdict == "infeasible-certified":
        feas.attempts = attempts
        return feas
    word = "below" if problem.objective.sense == "min" else "above"
    if ray is None or not ray["proven"]:
        why = ray["reason"] if ray is not None else f"no improving ray found ({ray_verdict})"
        best.reason = f"{best.reason}; the solver reports unbounded, not proved: {why}".lstrip("; ")
        best.ray_search_s += time.perf_counter() - t0
        return best
    point = _certified_point(problem, feas) if feas.verdict == "certified" else None
    if point is not None:
        sol, cert = point
        inf = "-inf" if word == "below" else "+inf"
        statement = (
            f"unbounded {word}: a certified feasible point and an exact improving ray "
            f"(q.d = {ray['slope']:.3g}); the optimal value is {inf}, no optimum exists (the dual is infeasible)"
        )
        out = Outcome("unbounded-certified", Evidence("exact-proof", None, statement), statement, solution=sol)
        out.certificate, out.backend = cert, best.backend or feas.backend  # the backend that said unbounded
        out.unbounded = {
            "ray": ray["ray"],
            "slope": ray["slope"],
            "sense": problem.objective.sense,
            "statement": statement,
        }
        out.attempts = attempts
        return out
    statement = (
        f"the dual is infeasible (an exact improving ray, q.d = {ray['slope']:.3g}): the problem is unbounded "
        f"{word} if it has a feasible point, else infeasible; feasibility not decided ({feas.verdict})"
    )
    out = Outcome("undecided", Evidence("exact-proof", None, statement), statement, solution=best.solution)
    out.certificate, out.backend = best.certificate, best.backend
    out.attempts = attempts
    return out


#: entries of a solver's ray below these fractions of its largest entry are also tried as 0
#: (a ray on the boundary of the recession cone, e.g. ``[[d1, d2], [d2, 0]] >= 0`` forces
#: ``d2 = 0``, comes back with ``d2 ~ 1e-9``; only the exact proof decides)
RAY_ZERO_TOLS = (1e-12, 1e-9, 1e-6)


def _improving_ray(problem: Problem, options: Any) -> tuple[dict[str, Any] | None, list[Any], str]:
    """An exactly proved improving ray: the strict ray problem first (a ray with a margin),
    then the non-strict one (rays on the cone's boundary), each solver point tried as it is and
    with its tiny entries set to zero. Returns ``(proof or None, attempts, last verdict)``."""
    from lmic.certify.farkas_unbounded import prove_improving_ray, ray_problem
    from lmic.policy import decide

    attempts: list[Any] = []
    ray: dict[str, Any] | None = None
    verdict = "undecided"
    for strict in (True, False):
        # any infeasibility answer ends the search on this ray problem: it only means "no ray
        # found" here, and a second backend's proof of it costs time and proves nothing wanted
        # (Clarabel: 13 s to its AlmostPrimalInfeasible on a 100-vertex graph partitioning
        # problem that CVXOPT had settled in 0.25 s)
        out = decide(ray_problem(problem, strict=strict), None, options, rescue=False, max_bounded=1)
        attempts += out.attempts
        verdict = out.verdict
        x = None if out.solution is None else out.solution.x
        if x is None or not np.all(np.isfinite(x)) or not np.any(x):
            continue
        x = np.asarray(x, dtype=float)
        top = float(np.max(np.abs(x)))
        tries = [x] + [np.where(np.abs(x) <= tol * top, 0.0, x) for tol in RAY_ZERO_TOLS]
        for d in tries:
            ray = prove_improving_ray(problem, d)
            if ray["proven"]:
                return ray, attempts, verdict
    return ray, attempts, verdict


def _certified_point(problem: Problem, feas: Outcome) -> tuple[Any, Any] | None:
    """The feasibility outcome's point certified on ``problem`` itself (same constraints, its
    own objective): the solution and certificate an ``unbounded-certified`` outcome records."""
    from lmic.certify import certify
    from lmic.solution import Solution

    src = feas.solution
    if src is None or src.x is None:
        return None
    x = np.asarray(src.x, dtype=float)
    sol = Solution(
        status="feasible",
        x=x,
        objective=problem.objective.value(x),
        backend=src.backend,
        native_status=src.native_status,
        margin=src.margin,
        strategy=src.strategy,
        iterations=src.iterations,
        solve_s=src.solve_s,
    )
    cert = certify(problem, sol)
    if cert.verdict != "certified":
        return None
    # an exact improving ray proves "unbounded" only with a point that IS feasible: the solver's
    # point itself, proved with rigorous rounding (rows exactly) or exactly (the certifier may
    # have certified a projected or snapped x_q instead; and it once granted a 1e-8 tolerance)
    from lmic.certify.enclosure_float import primal_end
    from lmic.certify.snap import exact_primal_end

    return (sol, cert) if exact_primal_end(problem, x, primal_end(problem, x))["proven"] else None


def unbounded_checked(problem: Problem, out: Outcome, options: Any) -> Outcome:
    """:func:`unbounded_outcome` when a solve of an optimisation problem said ``unbounded``
    and nothing was decided; ``out`` unchanged otherwise.

    >>> from lmic.testing.conformance import lyapunov_problem
    >>> unbounded_checked(lyapunov_problem(-np.eye(1)), Outcome("certified"), None).verdict
    'certified'
    """
    said = any(a.status == "unbounded" for a in out.attempts)
    if out.decided or problem.objective.sense == "feasibility" or not said:
        return out
    return unbounded_outcome(problem, out, options)
