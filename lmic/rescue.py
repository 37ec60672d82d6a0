"""The exact rescue of the solve policy (:mod:`lmic.policy`): a point the float certificate
rejected only for its tiny margins, proved in rational arithmetic.

:func:`exact_rescue_point` proves one point; :func:`rescue_rejected` is the policy's last step,
after the route: the best rejected points in turn, until one is proved. A proved point holds;
for an optimisation problem it is the optimum only as far as the solver's status says
(:func:`lmic.outcome.verdict_of`): an ``inaccurate`` solve's point is a proven end,
``undecided``, which the enclosure (:mod:`lmic.routes`) may then decide.

Examples
--------
>>> import numpy as np
>>> from lmic.solution import Solution
>>> from lmic.testing.conformance import lyapunov_problem
>>> exact_rescue_point(lyapunov_problem(-np.eye(1)), Solution("optimal", x=np.array([1.0])), None) is None
True
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

from lmic.errors import LmicError
from lmic.ir.problem import Problem
from lmic.outcome import Attempt, Outcome, evidence_of, verdict_of
from lmic.solution import Solution

__all__ = ["exact_rescue_point", "rescue_rejected"]


def exact_rescue_point(problem: Problem, sol: Solution, cert: Any) -> Any | None:
    """An exact proof at a point the float certificate rejected only for its tiny margins.

    Returns the exact certificate when every LMI and row is proven exactly and every derived
    quantity and check holds; ``None`` otherwise.

    >>> import numpy as np
    >>> from lmic.testing.conformance import lyapunov_problem
    >>> p = lyapunov_problem(-np.eye(1))
    >>> exact_rescue_point(p, Solution("optimal", x=np.array([1.0])), None) is None
    True
    """
    from lmic.certify import certify

    if sol.x is None or getattr(cert, "verdict", None) != "rejected":
        return None
    if any(r.get("min_eig") is None or r["min_eig"] <= 0 for r in cert.lmis):
        return None  # a negative eigenvalue in float: an exact proof will not help
    if not all(c.get("ok") for c in cert.checks) or not all(d.get("ok") for d in cert.derived):
        return None
    if cert.objective is not None and not cert.objective.get("ok", True):
        return None
    try:
        exact = certify(problem, sol, exact=True)
    except LmicError:
        return None
    return exact if exact.exact and exact.exact.get("proven") and exact.verdict == "certified" else None


def rescue_rejected(
    problem: Problem,
    best: Outcome,
    rejected: list[tuple[Solution, Any, str]],
    attempts: list[Attempt],
    key: Callable[[Any], float],
) -> Outcome:
    """The policy's answer after the exact rescue of its ``rejected`` points ``(solution,
    certificate, backend)``, tried in decreasing ``key(certificate)`` (the relative margin):
    the first one proved, with :func:`lmic.outcome.verdict_of`'s verdict (a point that holds
    after an inexact solve stays ``undecided``, and does not replace a point that already holds
    and is at least as good); ``best`` when none is proved. Each rescue is appended to
    ``attempts``.

    >>> from lmic.outcome import Outcome
    >>> rescue_rejected(None, Outcome("rejected"), [], [], key=lambda c: 0.0).verdict
    'rejected'
    """
    from lmic.certify import certified_solution

    for sol, cert, label in sorted(rejected, key=lambda r: -key(r[1])):
        t0 = time.perf_counter()
        rescued = exact_rescue_point(problem, sol, cert)
        if rescued is None:
            continue
        # the point reported is the point proved (the proof may hold at a rounding of it)
        sol, rescued = certified_solution(problem, sol, rescued)
        # (a point 2.4e-3 above the infimum of uio_dt.thm4_1 was called 'certified' here)
        verdict = verdict_of(problem, sol, rescued)
        status = str(sol.native_status or "")
        attempts.append(Attempt(label, "exact rescue", sol.status, status, verdict, time.perf_counter() - t0))
        reason = rescued.reason
        if verdict != "certified":
            reason = f"the solver stopped '{sol.status}'; its point holds (exact proof): {reason}"
            if best.verdict == "undecided" and getattr(best.certificate, "verdict", None) == "certified":
                sign = -1.0 if problem.objective.sense == "max" else 1.0
                if sign * float(best.solution.objective or 0.0) <= sign * float(sol.objective or 0.0):
                    continue  # a point that already holds is at least as good
        return Outcome(
            verdict, evidence_of("certified", rescued), reason, solution=sol, certificate=rescued, backend=label
        )
    return best
