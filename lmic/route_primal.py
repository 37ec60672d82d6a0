"""The primal end of an optimal-value enclosure, improved after the solve; and the answer it decides.

:func:`lmic.api.solve` computes the enclosure of an optimisation answer
(:func:`lmic.routes.enclosure_of`) and the backed-off point (:mod:`lmic.backoff`). When the
enclosure has no rigorous primal end, or one whose relative gap misses
:data:`lmic.certify.enclosure.GAP_TARGET`, :func:`better_primal` looks for a better one (the
backed-off point, points polished toward the solver's, a restored point), each proved on its own;
:func:`decided_by_enclosure` then turns a ``rejected`` or ``undecided`` answer whose enclosure
meets ``--gap`` from a restored point the certifier certifies into a ``certified`` one with that
point. Split out of :mod:`lmic.api` (the module size limit).

Examples
--------
>>> import scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
>>> from lmic.solution import Solution
>>> p = Problem([Variable("t", "scalar", (1, 1))], [LMI("t >= 1", 1, sp.csc_matrix([[-1.0, 1.0]]), strict=False)],
...             LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
>>> enc = {"sense": "min", "kind": "minimum", "lower": 1.0, "upper": 1.5, "rel_gap": 0.4, "dual": {"proven": True}}
>>> out = better_primal(p, enc, None, Solution("optimal", x=np.array([1.0]), objective=1.0), None, "clarabel", None)
>>> out["upper"] < 1.0 + 1e-6, out["primal"]
(True, 'restored point')
"""

from __future__ import annotations

from typing import Any

import numpy as np

from lmic.ir.problem import Problem
from lmic.options import SolveOptions
from lmic.solution import Solution

__all__ = ["better_primal", "decided_by_enclosure", "nearer_point", "NEARER_STEPS", "PROVES"]


def _primal_of(problem: Problem, enc: dict[str, Any]) -> float | None:
    return enc["upper"] if problem.objective.sense == "min" else enc["lower"]


def better_primal(
    problem: Problem,
    enc: dict[str, Any],
    back: dict[str, Any] | None,
    sol: Solution,
    tight_x: Any,
    backend: str,
    options: SolveOptions | None,
    *,
    restore_tried: bool = False,
) -> dict[str, Any]:
    """The enclosure with the best primal end lmic can prove, when it has none or its relative
    gap exceeds :data:`lmic.certify.enclosure.GAP_TARGET`.

    Candidates, each proved on its own (:func:`lmic.certify.enclosure.primal_end`, nothing is
    trusted) and kept only when it improves the primal end: the backed-off point; the points
    of the segment from a proven point toward the solver's point (and the tight re-solve's)
    (:func:`lmic.certify.enclosure.polish_primal`); then, while the gap is still missed, a point
    strictly inside from a solve with every constraint tightened (:func:`lmic.backoff.restore`,
    the smallest tightening of three that gives a proven point, polished the same way). A
    primal end from the backed-off point is recorded as such; any other as a ``restored point``
    with its ``restored_x`` (both re-proved by ``lmic audit``).

    An existing primal end without a proven dual end is only compared with the backed-off
    point's (a proof, no solve: there is no gap to meet); with one, the polish and the
    restoration solve follow, the latter on interior-point backends only (a first-order one's
    points are too coarse). It is also what closes the gap of a certified point that keeps the strict
    reduction's margin (random sampled_euler.thm3 at 12 states, seed 3, on Clarabel: 1.9e-6).
    """
    from lmic.certify.enclosure import GAP_TARGET, polish_primal, primal_end, with_primal

    sgn = 1.0 if problem.objective.sense == "min" else -1.0
    key = "upper" if sgn > 0 else "lower"

    def done(e: dict[str, Any]) -> bool:
        return _primal_of(problem, e) is not None and e.get("rel_gap") is not None and e["rel_gap"] <= GAP_TARGET

    if done(enc) or problem.objective.sense == "feasibility":
        return enc
    x_solver, primal0 = sol.x, _primal_of(problem, enc)
    # no dual end: no gap to meet, so no solve; the backed-off point's proven end is still kept
    # when better (a proof, no solve)
    one_end = primal0 is not None and (enc["lower"] if sgn > 0 else enc["upper"]) is None

    def better(value: float) -> bool:
        old = _primal_of(problem, enc)
        return old is None or sgn * value < sgn * old

    def take(value: float, label: str, x: Any) -> dict[str, Any]:
        base = {k: v for k, v in enc.items() if k not in ("restored_x", "polish")}
        base[key] = None
        out = with_primal(base, value, label)
        if label == "restored point":
            out["restored_x"] = np.asarray(x, dtype=float).tolist()
        return out

    outers = [np.asarray(o, dtype=float) for o in (x_solver, tight_x) if o is not None]

    def polished(inner: Any, pe: dict[str, Any]) -> tuple[dict[str, Any], Any]:
        """``pe`` at ``inner``, or a better proven point toward the solver's points."""
        best, bx = pe, inner
        for outer in outers:
            pol = polish_primal(problem, np.asarray(inner, dtype=float), outer)
            if pol["proven"] and sgn * pol["value"] < sgn * best["value"]:
                best, bx = pol, pol["x"]
        return best, bx

    if back is not None and back.get("x") is not None:
        xb = np.asarray(back["x"], dtype=float)
        pe = primal_end(problem, xb)
        if pe["proven"]:
            if better(pe["value"]):
                enc = take(pe["value"], "certified backed-off point", xb)
            if one_end:
                return enc
            pol, xp = polished(xb, pe)
            if pol is not pe and better(pol["value"]):
                enc = take(pol["value"], "restored point", xp)
    # restore_tried: the route already restored from x_solver
    if one_end or done(enc) or x_solver is None or restore_tried:
        return enc
    if primal0 is not None:
        from lmic.routes import method_of

        if method_of(backend) != "interior point":
            return enc
    from lmic.route_upper import restored_end

    # a point strictly inside from a solve with every constraint tightened, as close to the
    # solver's points as the proof allows (the rows at a larger margin last: RESTORE_RELS)
    rest = restored_end(problem, x_solver, backend, options, outer=() if tight_x is None else (tight_x,))
    if rest["proven"] and better(rest["value"]):
        enc = take(rest["value"], "restored point", rest["x"])
    return enc


def decided_by_enclosure(
    problem: Problem,
    outcome: Any,
    enc: dict[str, Any] | None,
    options: SolveOptions | None,
    back: dict[str, Any] | None = None,
) -> Any | None:
    """The answer an optimisation outcome becomes from its enclosure's proven point.

    The enclosure's primal end may come from a point of its own: a restored point
    (``restored_x``) or the certified backed-off point (``back``). When the certifier certifies
    that point:

    * a ``rejected`` or ``undecided`` outcome whose enclosure has both ends proven within
      ``options.gap``: ``certified`` with that point (its evidence: the certifier's and the
      enclosure's, both proofs);
    * a ``rejected`` or ``undecided`` outcome without a point that holds (the solver's point
      fails, or there is none) whose gap is not met: ``undecided`` *with that point*, as for a
      point that holds from an inexact solve (:mod:`lmic.policy`): the point is proven, the
      optimum is not, and the reason says so. The answer's variables and gains are then those
      of a proven point, not of the rejected one.

    ``None`` otherwise (the outcome stands).
    """
    gap = (options or SolveOptions()).gap
    if outcome.verdict not in ("rejected", "undecided") or enc is None:
        return None
    point_holds = getattr(outcome.certificate, "verdict", None) == "certified"
    x_enc, label = enc.get("restored_x"), "the enclosure's restored point"
    if x_enc is None and enc.get("primal") == "certified backed-off point" and back and back.get("x") is not None:
        x_enc, label = back["x"], "the certified backed-off point"
    # the enclosure's primal end is the adopted point's: its gap is that point's
    proven_optimum = x_enc is not None and enc.get("rel_gap") is not None and enc["rel_gap"] <= gap
    if x_enc is None or (point_holds and not proven_optimum):
        return None  # nothing proven to adopt, or the answer's own point already holds
    from lmic.certify import certified_solution, certify
    from lmic.outcome import Outcome, evidence_of

    x = np.asarray(x_enc, dtype=float)
    old = outcome.solution
    sol2 = Solution(
        status=old.status if old is not None else "error",
        x=x,
        objective=problem.objective.value(x),
        duals=old.duals if old is not None else {},
        backend=old.backend if old is not None else outcome.backend,
        message=f"{label} (lmic.api)",
    )
    cert2 = certify(problem, sol2)
    if cert2.verdict != "certified":
        return None
    sol2, cert2 = certified_solution(problem, sol2, cert2)
    if proven_optimum:
        verdict = "certified"
        why = f"the enclosure proves the optimum: {enc['reason']}"
    else:
        verdict = "undecided"
        why = f"the optimum is not proven to --gap {gap:g}: {enc.get('reason')}"
    return Outcome(
        verdict,
        evidence_of("certified", cert2),
        f"{cert2.reason} ({label}; the solver's point: {outcome.verdict}); {why}",
        list(outcome.attempts),
        sol2,
        cert2,
        outcome.backend,
    )


#: how a verdict's reason quotes the enclosure that proved the optimum (its last clause)
PROVES = "; the enclosure proves the optimum: "

#: :func:`nearer_point` tries ``theta = 2^-k`` for ``k`` up to this (bisected over ``k``)
NEARER_STEPS = 30


def nearer_point(problem: Problem, outcome: Any, enc: dict[str, Any] | None, exact: bool = False) -> Any | None:
    """A certified answer whose point is nearer the enclosure's restored point, or ``None``.

    When the optimum is certified with a point the certifier accepts (often the most interior
    point near the proven dual end, :mod:`lmic.upper_end`) while the enclosure's primal end
    comes from a restored point proved feasible below the certifier's threshold, the answer's
    objective can lie well above the enclosure (a newcomer's H2 norm by ``min trace(Z)``: the
    answer at 29.65593, the enclosure ``[29.653266, 29.653274]``). The points
    ``x_r + theta (x_c - x_r)`` between them (``x_c`` the answer's point, ``x_r`` the restored
    one) keep the margins of both on the segment (each LMI is concave there): the smallest
    ``theta = 2^-k`` whose point the certifier certifies (bisected over ``k``) becomes the answer's
    point, with its own certificate; the enclosure is unchanged. ``None`` when nothing
    improves the objective by more than ``1e-9`` relative; with ``exact`` (the answer's exact
    proof is kept, not redone for each candidate); and for a problem with derived values
    (gains): a point nearer the boundary has worse-conditioned gains (issue 13: gains of 1e6 to
    1e9 at the optimum), so there the answer keeps its interior point and the backed-off point
    (:mod:`lmic.backoff`) gives the gains.
    """
    from lmic.certify import certified_solution, certify
    from lmic.outcome import Outcome, evidence_of

    sol = outcome.solution
    if exact or problem.derived or enc is None or enc.get("restored_x") is None or sol is None or sol.x is None:
        return None
    if outcome.verdict != "certified" or getattr(outcome.certificate, "verdict", None) != "certified":
        return None
    sign = -1.0 if problem.objective.sense == "max" else 1.0
    xc, xr = np.asarray(sol.x, dtype=float), np.asarray(enc["restored_x"], dtype=float)
    if xc.shape != xr.shape or not np.all(np.isfinite(xr)):
        return None
    fc, fr = problem.objective.value(xc), problem.objective.value(xr)
    if fc is None or fr is None or sign * (fc - fr) <= 1e-9 * max(1.0, abs(fc)):
        return None

    def attempt(k: int) -> tuple[Solution, Any] | None:
        x = xr + 2.0**-k * (xc - xr)
        cand = Solution(
            status=sol.status, x=x, objective=problem.objective.value(x), duals=sol.duals, backend=sol.backend
        )
        cert = certify(problem, cand)
        return (cand, cert) if cert.verdict == "certified" else None

    lo, hi, best = 0, NEARER_STEPS + 1, None  # k = 0 is the answer's own point: certified
    while hi - lo > 1:
        mid = (lo + hi) // 2
        found = attempt(mid)
        if found is None:
            hi = mid
        else:
            lo, best = mid, found
    if best is None:
        return None
    cand, cert = best
    cand.message = f"the certified point nearest the enclosure's restored point (lmic.api; theta 2^-{lo})"
    cand, cert = certified_solution(problem, cand, cert)
    proven = outcome.reason.split(PROVES, 1)
    tail = PROVES + proven[1] if len(proven) == 2 else ""
    return Outcome(
        "certified",
        evidence_of("certified", cert),
        f"{cert.reason} (the certified point nearest the enclosure's restored point, objective "
        f"{cand.objective:.10g}; the answer's point before: {fc:.10g}){tail}",
        list(outcome.attempts),
        cand,
        cert,
        outcome.backend,
    )
