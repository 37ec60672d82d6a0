"""The interior-point order of the default route for optimisation problems, by shape and size.

A per-iteration cost model (:func:`ipm_costs`) of the two interior-point families decides
which goes first (:func:`optimisation_chain`); :func:`lmic.policy.route` uses it for every
optimisation problem on the default route, :mod:`lmic.routes` adds the ``--gap`` test and the
escalation. Measured numbers: ``benchmarks/optimisation.py``, docs/backends.md.

Examples
--------
>>> import numpy as np
>>> from lmic.testing.conformance import lyapunov_problem
>>> optimisation_chain(lyapunov_problem(-np.eye(2)))
['clarabel', 'cvxopt', 'sdpa']
"""

from __future__ import annotations

from typing import Any

from lmic.ir.problem import Problem

__all__ = [
    "TINY_IPM_COST",
    "SCHUR_PENALTY",
    "STRUCTURED_PENALTY",
    "STRUCTURED_MIN_COST",
    "ipm_costs",
    "structured_ipm_cost",
    "optimisation_chain",
    "MAX_GAP_ESCALATIONS",
    "GAP_ESCALATION_FACTOR",
    "GAP_ESCALATION_FLOOR_S",
    "CHEAP_ESCALATION_S",
    "gap_escalates",
    "ray_proof_s",
    "estimated_seconds",
    "affordable",
    "AFFORDABLE_FACTOR",
]

#: per-iteration cost (flop estimate of :func:`ipm_costs`) below which an optimisation problem
#: is tiny: Clarabel, the embedded default solver (the most accurate), whatever the shape; a
#: 10-state bounded-real lemma (2.5e6) takes 10-70 ms on every interior-point backend
TINY_IPM_COST = 1e7
#: a Schur-complement method (SDPA, CVXOPT) goes first when its cost estimate times this is
#: below Clarabel's: their measured rate is lower (bounded-real lemma n = 40, 821 variables:
#: estimates 3.4e9 Clarabel, 3.1e9 Schur; Clarabel 0.15 s, CVXOPT 0.38 s, SDPA 0.12 s per
#: iteration; ``uncertain_dt.thm1`` n = 8, 91 variables: 5.5e9 against 6e7; Clarabel 0.19 s,
#: CVXOPT 0.05 s, SDPA 0.02 s per iteration; docs/backends.md)
SCHUR_PENALTY = 2.5
#: where Clarabel would go first, CVXOPT with its structured KKT solver
#: (:mod:`lmic.backends.cvxopt_kkt`, where it applies) goes first instead when its estimate
#: (:func:`structured_ipm_cost`) times this is below Clarabel's (bounded-real lemma n = 40:
#: estimate 3.3e8, 39 ms per iteration, against Clarabel's 3.4e9 and 150 ms: a rate 2.7 times
#: lower). Problems where SDPA goes first keep it: on ``uncertain_dt.thm1`` n = 8 SDPA solves
#: in 0.17 s, CVXOPT structured in 1.2 s.
STRUCTURED_PENALTY = 3.0
#: ... and only from this Clarabel estimate on (Clarabel about 1 s a solve): CVXOPT is the less
#: robust solver, and where Clarabel is fast the gain does not pay for its failures. Measured:
#: bounded-real lemma n = 30 (6.8e8) CVXOPT 0.44 s against Clarabel 0.58 s, but ``uir.thm4_1``
#: n = 12 (6.7e8; rank-deficient ``Y1 W``), one seed of two: CVXOPT's enclosure stopped at gap
#: 3.5e-4 after its 10 s budget and the route escalated to Clarabel, 19.8 s against 9.8 s
STRUCTURED_MIN_COST = 1e9


def ipm_costs(problem: Problem) -> tuple[float, float]:
    """Per-iteration flop estimates ``(clarabel, schur)`` of the two interior-point families.

    Clarabel factors a sparse KKT system holding one dense block of order ``s_i = d_i (d_i +
    1) / 2`` per LMI (:mod:`lmic.backends.clarabel`): about ``sum s_i^3 + n sum s_i^2 + n^3``.
    A Schur-complement method (SDPA, CVXOPT) forms and factors an ``n x n`` matrix with one
    product per pair of variables and block: about ``n^2 sum d_i^2 + n sum d_i^3 + n^3``.

    >>> import numpy as np
    >>> from lmic.testing.conformance import lyapunov_problem
    >>> c, s = ipm_costs(lyapunov_problem(-np.eye(2)))
    >>> c > 0 and s > 0
    True
    """
    n = float(problem.n)
    dims = [float(lmi.dim) for lmi in problem.lmis]
    cones = [d * (d + 1) / 2 for d in dims] + [1.0] * len(problem.linear)
    clarabel = sum(s**3 for s in cones) + n * sum(s**2 for s in cones) + n**3
    schur = n**2 * (sum(d**2 for d in dims) + len(problem.linear)) + n * sum(d**3 for d in dims) + n**3
    return clarabel, schur


def structured_ipm_cost(problem: Problem) -> float | None:
    """Per-iteration flop estimate of CVXOPT with the structured KKT solver (the Schur
    complement from cross-shaped coefficients, :func:`lmic.backends.cvxopt_kkt.structured_cost`,
    plus its Cholesky factorisation ``n^3 / 3``); ``None`` where CVXOPT would not use it (or is
    not installed).

    >>> import numpy as np
    >>> from lmic.testing.conformance import lyapunov_problem
    >>> structured_ipm_cost(lyapunov_problem(-np.eye(2))) is None
    True
    """
    import importlib.util

    if importlib.util.find_spec("cvxopt") is None or not problem.lmis:
        return None
    from lmic.backends.cvxopt_kkt import analyse, worth_it

    if not worth_it(problem):
        return None
    return analyse(problem)[0] + float(problem.n) ** 3 / 3


def optimisation_chain(problem: Problem, first_order: bool | None = None) -> list[str]:
    """The interior-point order of the default route for an optimisation problem.

    Tiny problems (:data:`TINY_IPM_COST`) and problems whose Schur complement is not clearly
    cheaper (:data:`SCHUR_PENALTY`, :func:`ipm_costs`): Clarabel, CVXOPT, SDPA, except that
    CVXOPT goes first on large problems (:data:`STRUCTURED_MIN_COST`) where its structured KKT
    solver is clearly cheaper than Clarabel (:data:`STRUCTURED_PENALTY`,
    :func:`structured_ipm_cost`: Lyapunov-type coefficients, e.g. the bounded-real lemma from
    about 33 states); otherwise (few variables against large PSD blocks) SDPA, CVXOPT, Clarabel.
    ``first_order`` puts SCS first (``auto:first-order``; ``None``:
    :data:`lmic.backends.auto.FIRST_ORDER_OPTIMISATION`).

    >>> import numpy as np
    >>> from lmic.testing.conformance import lyapunov_problem
    >>> optimisation_chain(lyapunov_problem(-np.eye(2)))
    ['clarabel', 'cvxopt', 'sdpa']
    """
    from lmic.backends import auto

    clarabel, schur = ipm_costs(problem)
    if clarabel <= TINY_IPM_COST or SCHUR_PENALTY * schur >= clarabel:
        ipm = ["clarabel", "cvxopt", "sdpa"]
    else:
        ipm = ["sdpa", "cvxopt", "clarabel"]
    if ipm[0] == "clarabel" and clarabel >= STRUCTURED_MIN_COST:
        structured = structured_ipm_cost(problem)
        if structured is not None and STRUCTURED_PENALTY * structured < clarabel:
            ipm = ["cvxopt", "clarabel", "sdpa"]
    fo = auto.FIRST_ORDER_OPTIMISATION if first_order is None else first_order
    return (["scs"] if fo else []) + ipm


#: interior-point backends a route tries after the first certified one, when its enclosure
#: does not meet ``--gap`` (:func:`gap_escalates`)
MAX_GAP_ESCALATIONS = 2
#: ... and only while the route has run less than ``max(FLOOR, FACTOR x)`` the time to its
#: first certified interior-point answer and its enclosure (each escalation pays a solve and an
#: enclosure; on a random 8-state bounded-real lemma without the exact face the three
#: enclosures took 10 s and closed the gap from 6e-2 to 1.2e-4)
GAP_ESCALATION_FACTOR = 2.0
GAP_ESCALATION_FLOOR_S = 20.0
#: an enclosure that meets ``--gap`` but not ``GAP_TARGET`` (1e-6) still escalates once to the
#: next interior point while the route has run less than this: a second solve of a moderate
#: problem (SDPA's relative gap stops near 1e-6 on the shipped uncertain_dt examples, Clarabel's
#: 3e-8; random ``delay_b.thm4_1`` n = 8: SDPA 2.5e-6 after 2.9 s, then CVXOPT 7.0e-9, 9.0 s in
#: all; with 2 s here the route stopped at 2.5e-6); as ``routes.ENCLOSURE_BUDGET_FLOOR_S``
#: (SDPLIB truss7: Clarabel's step takes 8-11 s to 2.2e-6, CVXOPT's next 1.5 s to 9.2e-9; with
#: 10 here the route stopped at 2.2e-6 in some runs)
CHEAP_ESCALATION_S = 20.0


def ray_proof_s(attempts: list[Any]) -> float:
    """Seconds the attempts spent in exact proofs of bounded rays (their certification time).

    >>> from lmic.outcome import Attempt
    >>> a = Attempt("sdpa", "default", "infeasible", "", "infeasible-bounded", 9.0, "exact proof of the ray failed")
    >>> a.certify_s = 8.5
    >>> ray_proof_s([a])
    8.5
    """
    return float(sum(a.certify_s for a in attempts if "exact proof of the ray" in (a.note or "")))


def gap_escalates(problem: Problem, enc: dict[str, Any] | None) -> bool:
    """Whether another interior-point solver may close an enclosure's gap: both ends proven but
    too far apart (the solver's accuracy), or the dual end proven and the primal end not (its
    point is not provably feasible). Not when the dual end is missing: the dual search has
    tried its perturbed and centred re-solves, and a missing dual end is the dual's structure
    (a dual interior thinner than the rounding, the bounded-real lemma's), not one solver's.

    >>> from lmic.testing.conformance import CASES
    >>> p = CASES["max_sense"].build()
    >>> gap_escalates(p, {"lower": 1.0, "upper": 2.0, "rel_gap": 0.6}), gap_escalates(p, None)
    (True, False)
    """
    if enc is None:
        return False
    if enc.get("rel_gap") is not None:
        return True
    dual_end = "lower" if problem.objective.sense == "min" else "upper"
    primal_end = "upper" if dual_end == "lower" else "lower"
    return enc.get(dual_end) is not None and enc.get(primal_end) is None


#: an interior-point re-solve that only narrows a gap (a cross re-solve, a gap escalation) runs
#: only when its estimated time (:func:`estimated_seconds`) is at most this times the solve it
#: follows, or :data:`CHEAP_ESCALATION_S`: SDPLIB arch8 (174 variables, PSD 161 and a diagonal
#: of 174) is solved by SDPA in 3 s, and Clarabel's cross re-solve (a dense KKT block of order
#: 13041, estimate 2.2e12 against SDPA's 1.5e9 a step) held 9 GB for minutes
AFFORDABLE_FACTOR = 4.0


def _family_cost(problem: Problem, name: str) -> float | None:
    """The per-iteration estimate of backend ``name`` in Clarabel's units (a Schur-complement
    method's flops count :data:`SCHUR_PENALTY` times); ``None`` for a first-order or unknown
    backend."""
    inner = str(name).lower().split(":")[-1]
    clarabel, schur = ipm_costs(problem)
    if inner == "clarabel":
        return clarabel
    if inner == "sdpa":
        return SCHUR_PENALTY * schur
    if inner == "cvxopt":
        structured = structured_ipm_cost(problem)
        return STRUCTURED_PENALTY * structured if structured is not None else SCHUR_PENALTY * schur
    return None


def estimated_seconds(problem: Problem, done: str, done_s: float, other: str) -> float | None:
    """Seconds a solve on ``other`` would take, scaled from ``done_s`` seconds on ``done`` by the
    ratio of their per-iteration estimates (:func:`ipm_costs`); ``None`` when either backend has
    no estimate (first-order, modelling layers other than their inner interior point).

    >>> import numpy as np
    >>> from lmic.testing.conformance import lyapunov_problem
    >>> p = lyapunov_problem(-np.eye(2))
    >>> estimated_seconds(p, "clarabel", 1.0, "clarabel"), estimated_seconds(p, "scs", 1.0, "sdpa")
    (1.0, None)
    """
    a, b = _family_cost(problem, done), _family_cost(problem, other)
    if a is None or b is None or a <= 0:
        return None
    return float(done_s) * b / a


def affordable(problem: Problem, done: str, done_s: float, other: str, left_s: float | None = None) -> bool:
    """Whether a re-solve on ``other`` that only narrows a gap is worth starting after a solve of
    ``done_s`` seconds on ``done``: its estimate (:func:`estimated_seconds`) is within
    :data:`AFFORDABLE_FACTOR` times that solve or :data:`CHEAP_ESCALATION_S`, and twice it fits
    in ``left_s`` seconds when given. Without an estimate only ``left_s`` decides (as before).

    >>> import numpy as np
    >>> from lmic.testing.conformance import lyapunov_problem
    >>> affordable(lyapunov_problem(-np.eye(2)), "sdpa", 0.01, "clarabel")
    True
    """
    est = estimated_seconds(problem, done, done_s, other)
    if est is None:
        return True
    if est > max(AFFORDABLE_FACTOR * float(done_s), CHEAP_ESCALATION_S):
        return False
    return left_s is None or 2.0 * est <= left_s
