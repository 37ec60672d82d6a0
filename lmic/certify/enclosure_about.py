"""Which problem an enclosure is about: the IR, or the theorem compiled exactly.

The face route (:mod:`lmic.certify.enclosure_face`) proves its lower end on the theorem
compiled exactly from the system's numbers (:mod:`lmic.compile.exact`) when the IR's rounded
coefficients lack the exact structure. An enclosure pairs two ends: both must be about one
problem. ``enclosure.problem`` is ``"exact"`` when the dual end is proved on the exact
compilation and the primal end for it too (:func:`lmic.certify.enclosure_float.primal_end`
covers ``|G_exact(x) - G(x)|`` once the counterpart exists), ``"ir"`` otherwise.

Examples
--------
>>> about_of({"proven": True, "problem": "ir"}, None)
'ir'
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from lmic.compile.exact import ExactProblem, ExactUnavailable, exact_of
from lmic.ir.problem import Problem

__all__ = ["about_of", "one_problem", "exact_counterpart", "relative_gap", "structure_on_exact"]


def about_of(dual: dict[str, Any], pe: dict[str, Any] | None) -> str | None:
    """The ``problem`` of an enclosure from its dual end and the primal end's
    :func:`~lmic.certify.enclosure_float.primal_end` record: ``"exact"`` when the dual end is
    proved on the exact compilation (the face route) and the primal end for it too, ``"ir"``
    when the dual end is about the IR; ``None`` when the two ends are about different problems.

    >>> about_of({"proven": True, "problem": "exact"}, {"proven": True, "problem": "ir"}) is None
    True
    """
    if not (dual.get("proven") and dual.get("problem") == "exact"):
        return "ir"
    return "exact" if pe is None or not pe.get("proven") or pe.get("problem") == "exact" else None


def one_problem(first: dict[str, Any], second: dict[str, Any], tp: bool, td: bool, pkey: str, dkey: str) -> bool:
    """Whether the primal end of ``second`` (``tp``, else ``first``'s) and the dual end of
    ``second`` (``td``) are about one problem: a dual end about the exact problem needs a
    primal end proved for it (the record's ``problem``).

    >>> a = {"upper": 2.0, "lower": 1.0, "problem": "ir", "dual": {"problem": "ir"}}
    >>> b = {"upper": 2.0, "lower": 1.5, "problem": "exact", "dual": {"problem": "exact"}}
    >>> one_problem(a, b, False, True, "upper", "lower"), one_problem(a, b, True, True, "upper", "lower")
    (False, True)
    """
    p_src, d_src = (second if tp else first), (second if td else first)
    exact_dual = (d_src.get("dual") or {}).get("problem") == "exact" and d_src.get(dkey) is not None
    return not exact_dual or p_src.get(pkey) is None or p_src.get("problem") == "exact"


def exact_counterpart(problem: Problem, record: dict[str, Any]) -> str | None:
    """For a recorded enclosure about the exact problem (``problem`` ``"exact"``), build the
    problem's exact counterpart (so that :func:`~lmic.certify.enclosure_float.primal_end`
    re-proves the primal end for it too); the reason when it cannot be built, else ``None``."""
    about = record.get("problem", "ir")
    if about not in ("ir", "exact"):
        return f"unknown problem {about!r}"
    point = (record.get("dual") or {}).get("dual")
    if about == "ir" and isinstance(point, dict) and point.get("problem") == "exact":
        return "the dual end is proved for the exact compilation, the record says the IR"
    if about == "ir":
        return None
    try:
        ex = exact_of(problem)
    except ExactUnavailable as exc:
        return str(exc)
    return None if ex.about == "theorem" else "the enclosure is about an exact compilation, the IR has no theorem"


def relative_gap(lo: float, hi: float) -> float:
    """VSDP's relative gap of an enclosure ``[lo, hi]``: ``(hi - lo) / max(1, (|hi| + |lo|) / 2)``
    (absolute for ends below 1 in size; negative when the ends cross).

    >>> relative_gap(1.0, 3.0), relative_gap(0.0, 0.25)
    (1.0, 0.25)
    """
    return (hi - lo) / max(1.0, 0.5 * (abs(hi) + abs(lo)))


def structure_on_exact(
    problem: Problem, check: Callable[[ExactProblem], dict[str, Any] | None], form: str
) -> tuple[dict[str, Any] | None, str]:
    """A face route's structure ``check``-ed on the problem's exact compilation
    (:func:`~lmic.compile.exact.exact_of`): ``(structure or None, reason)``, the structure's
    ``problem`` ``"exact"`` (the theorem compiled exactly) or ``"ir"`` (the IR's own floats).

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("p", "scalar", (1, 1))], [LMI("p > 0", 1, sp.csc_matrix([[0.0, 1.0]]))],
    ...             LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
    >>> structure_on_exact(p, lambda ex: {"form": "demo"}, "demo")
    ({'form': 'demo', 'problem': 'ir'}, '')
    """
    try:
        ex = exact_of(problem)
    except ExactUnavailable as exc:
        return None, f"the face route needs the exact coefficients: {exc}"
    st = check(ex)
    if st is None:
        return None, f"the exact coefficients have no {form} structure"
    return dict(st, problem="exact" if ex.about == "theorem" else "ir"), ""
