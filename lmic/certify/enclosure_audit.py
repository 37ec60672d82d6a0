"""``lmic audit``'s re-verification of a recorded enclosure (:func:`audit_enclosure`): both
ends re-proved from the record alone, for the problem the record says it is about.

Split out of :mod:`lmic.certify.enclosure` (which builds the record).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from lmic.certify.enclosure_about import exact_counterpart, relative_gap
from lmic.certify.enclosure_conditional import verify_box_bound
from lmic.certify.enclosure_facial import verify_any
from lmic.certify.enclosure_float import primal_end
from lmic.certify.snap import exact_primal_end
from lmic.ir.problem import Problem

__all__ = ["audit_enclosure"]


def audit_enclosure(
    problem: Problem, record: dict[str, Any], certificate: Any, backoff: dict[str, Any] | None = None
) -> dict[str, Any]:
    """Re-verify both ends of a recorded enclosure (``lmic audit``).

    The primal end must be the objective the certifier recomputes at the recorded point, and
    only when that point is certified; the dual end must be re-proved from the recorded dual
    point (:func:`verify_dual_bound`). A primal end taken from the backed-off point
    (:func:`with_primal`) must be the objective at ``backoff["x"]``, re-certified here.
    Returns ``ok``, ``field`` (the first failing one) and ``message``.

    >>> import numpy as np, scipy.sparse as sp
    >>> from lmic.certify.enclosure import enclosure
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
    >>> p = Problem([Variable("t", "scalar", (1, 1))],
    ...             [LMI("t - 2 >= 0", 1, sp.csc_matrix([[-2.0, 1.0]]), strict=False)],
    ...             LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
    >>> e = enclosure(p, {"lmis": [np.eye(1)], "linear": []}, None)
    >>> audit_enclosure(p, e, None)["ok"], audit_enclosure(p, dict(e, lower=2.1), None)["ok"]
    (True, False)
    """
    sense = problem.objective.sense
    if record.get("sense") != sense:
        return {"ok": False, "field": "enclosure.sense", "message": "enclosure.sense differs from the IR's objective"}
    strict = any(lmi.strict for lmi in problem.lmis) or any(problem.linear.strict)
    kind = ("infimum" if sense == "min" else "supremum") if strict else ("minimum" if sense == "min" else "maximum")
    if record.get("kind", kind) != kind:
        # "minimum" says the optimum is attained; a strict problem's need not be
        return {"ok": False, "field": "enclosure.kind", "message": f"enclosure.kind is not the IR's ({kind})"}
    why = exact_counterpart(problem, record)  # record["problem"] "exact": both ends re-proved for it too
    if why is not None:
        return {"ok": False, "field": "enclosure.problem", "message": f"enclosure.problem: {why}"}
    primal_key, dual_key = ("upper", "lower") if sense == "min" else ("lower", "upper")
    pv = record.get(primal_key)
    if pv is not None:
        if record.get("primal") == "certified backed-off point":
            xs = None if not backoff else backoff.get("x")
        elif record.get("primal") == "restored point":
            xs = record.get("restored_x")
        else:
            xs = getattr(certificate, "x", None)
        xa = np.asarray(xs, dtype=float) if xs is not None else None
        pe = exact_primal_end(problem, xa, primal_end(problem, xa)) if xa is not None else {"proven": False}
        if not pe["proven"] or float(pv) != pe["value"]:
            return {
                "ok": False,
                "field": f"enclosure.{primal_key}",
                "message": f"enclosure.{primal_key} {pv!r} is not the rigorous objective at the recorded point "
                f"({pe.get('value')!r}; {pe.get('reason', 'no point recorded')})",
            }
    dv = record.get(dual_key)
    dual = record.get("dual") or {}
    if dv is not None:
        if not dual.get("proven"):
            return {
                "ok": False,
                "field": f"enclosure.{dual_key}",
                "message": f"enclosure.{dual_key} has no proof recorded",
            }
        lower = -float(dv) if sense == "max" else float(dv)
        if float(dual.get("lower", math.nan)) != lower:
            return {
                "ok": False,
                "field": f"enclosure.{dual_key}",
                "message": f"enclosure.{dual_key} differs from the recorded dual bound",
            }
        v = verify_any(problem, dual)
        if not v["ok"]:
            return {"ok": False, "field": "enclosure.dual", "message": "enclosure.dual: " + v["reason"]}
        if dual.get("lower_exact") is not None and not _exact_not_above(dual["lower_exact"], v.get("lower_exact")):
            # the exact bound recorded next to the rounded one is a claim of its own
            return {
                "ok": False,
                "field": "enclosure.dual",
                "message": "enclosure.dual: the recorded lower_exact is not the exact bound the dual point proves "
                f"({v.get('lower_exact')})",
            }
    cond = record.get("conditional") or {}
    if cond.get("value") is not None:
        box = cond.get("bound") or {}
        expect = -float(box.get("lower", math.nan)) if sense == "max" else float(box.get("lower", math.nan))
        v = verify_box_bound(problem, box) if box else {"ok": False, "reason": "no dual point recorded"}
        if float(cond["value"]) != expect or float(cond.get("radius", math.nan)) != float(box.get("radius", math.nan)):
            v = {"ok": False, "reason": "the value or radius differs from the recorded box bound"}
        if not v["ok"]:
            return {"ok": False, "field": "enclosure.conditional", "message": "enclosure.conditional: " + v["reason"]}
    lo, hi = record.get("lower"), record.get("upper")
    if lo is not None and hi is not None:
        if float(lo) > float(hi):
            return {"ok": False, "field": "enclosure", "message": "enclosure: lower end above upper end"}
        if record.get("gap") is not None and float(record["gap"]) != float(hi) - float(lo):
            return {"ok": False, "field": "enclosure.gap", "message": "enclosure.gap differs from upper - lower"}
        if record.get("rel_gap") is not None and float(record["rel_gap"]) < relative_gap(float(lo), float(hi)):
            return {"ok": False, "field": "enclosure.rel_gap", "message": "enclosure.rel_gap is below the ends' gap"}
    return {"ok": True, "field": None, "message": "enclosure re-verified (both recorded ends)"}


def _exact_not_above(recorded: Any, proved: Any) -> bool:
    """Whether the recorded exact bound (``"p/q"``) is a rational not above the re-proved one
    (``None``: no exact bound was re-proved, so a recorded one is unsupported).

    >>> _exact_not_above("3/2", "3/2"), _exact_not_above("2", "3/2"), _exact_not_above("1", None)
    (True, False, False)
    """
    from fractions import Fraction

    try:
        return proved is not None and Fraction(str(recorded)) <= Fraction(str(proved))
    except (ValueError, ZeroDivisionError, TypeError):
        return False
