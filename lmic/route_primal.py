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

__all__ = ["better_primal", "decided_by_enclosure"]


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

    An existing primal end is worked on only when the dual end is proven (a gap to meet); the
    restoration solve then runs on interior-point backends only (a first-order one's points are
    too coarse). It is also what closes the gap of a certified point that keeps the strict
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
    if primal0 is not None and (enc["lower"] if sgn > 0 else enc["upper"]) is None:
        return enc  # no dual end: no gap to meet

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
            pol, xp = polished(xb, pe)
            if pol is not pe and better(pol["value"]):
                enc = take(pol["value"], "restored point", xp)
    if done(enc) or x_solver is None or restore_tried:  # restore_tried: the route already restored from x_solver
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
    problem: Problem, outcome: Any, enc: dict[str, Any] | None, options: SolveOptions | None
) -> Any | None:
    """A ``rejected`` or ``undecided`` optimisation outcome whose enclosure has both ends proven
    within ``options.gap`` from a restored point (``restored_x``): ``certified`` with that point
    when the certifier certifies it (its evidence: the certifier's and the enclosure's, both
    proofs); ``None`` otherwise (the outcome stands)."""
    gap = (options or SolveOptions()).gap
    if outcome.verdict not in ("rejected", "undecided") or enc is None or outcome.solution is None:
        return None
    if enc.get("restored_x") is None or enc.get("rel_gap") is None or enc["rel_gap"] > gap:
        return None
    from lmic.certify import certify
    from lmic.outcome import Outcome, evidence_of

    x = np.asarray(enc["restored_x"], dtype=float)
    old = outcome.solution
    sol2 = Solution(
        status=old.status,
        x=x,
        objective=problem.objective.value(x),
        duals=old.duals,
        backend=old.backend,
        message="the restored point of the enclosure (lmic.api)",
    )
    cert2 = certify(problem, sol2)
    if cert2.verdict != "certified":
        return None
    return Outcome(
        "certified",
        evidence_of("certified", cert2),
        f"{cert2.reason} (the enclosure's restored point; the solver's point: {outcome.verdict}); "
        f"the enclosure proves the optimum: {enc['reason']}",
        list(outcome.attempts),
        sol2,
        cert2,
        outcome.backend,
    )
