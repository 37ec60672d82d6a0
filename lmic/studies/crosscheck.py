"""Cross-check one problem on several backends: each backend's decision, and do they conflict?

The problem is compiled (or loaded) once; each backend, alone, runs the one solve policy
(:func:`lmic.policy.decide` with that backend: its strategies and exact rescue, no other
backend) and gets an outcome verdict (:mod:`lmic.outcome`). One row per backend.

* A *decision* is ``certified``, ``infeasible-certified`` or ``infeasible-bounded``.
* ``rejected`` and ``undecided`` rows (and backends that cannot run) are *failures*: listed and
  counted, never a disagreement.
* Two decisions *conflict* when one certifies a point and another proves the problem infeasible
  (globally, or within a radius the certified point lies in), when two certified optima
  differ by more than ``rtol`` (relative), or when the proven enclosures of the optimal value
  (each backend's ``[lower, upper]``, :mod:`lmic.certify.enclosure`) do not intersect: two
  proofs that contradict each other, whatever ``rtol``.
* Each row has the backend's whole time (``time_s``: solve, certification, enclosure) besides
  its solve's (``solve_s``). No backed-off second solve runs (the rows report the optimum).
* ``agree``: at least one decision and no conflict. Exit code 0 then, 1 on a conflict or when
  no backend decided.

Examples
--------
>>> from lmic.testing.conformance import CASES
>>> report = crosscheck(CASES["max_sense"].build(), backends=["clarabel", "cvxopt"])
>>> report.agree, [r["decision"] for r in report.results], report.failures
(True, ['certified', 'certified'], 0)
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from lmic.api import Result, load_target, solve
from lmic.backends.base import SolveOptions
from lmic.errors import LmicError
from lmic.ir.problem import Problem

__all__ = [
    "CrosscheckReport",
    "crosscheck",
    "check_rtol",
    "backend_row",
    "error_row",
    "assemble",
    "target_label",
    "status_class",
    "conflicts",
    "DEFAULT_RTOL",
    "ENCLOSURE_SLACK",
    "DECISIONS",
    "Progress",
]

#: verdicts that are decisions (the others are failures)
DECISIONS = ("certified", "infeasible-certified", "infeasible-bounded", "unbounded-certified")

#: ``progress(done, total, backend, row)``: called before each backend (``row`` is ``None``) and
#: after it (``row`` is its result row)
Progress = Callable[[int, int, str, "dict[str, Any] | None"], None]

#: default tolerance on the relative objective gap (first-order solvers meet ~1e-3 here)
DEFAULT_RTOL = 1e-3
#: two backends' proven enclosures of the optimal value must intersect up to this (relative):
#: an end proven on the theorem compiled exactly and one on the float IR differ by rounding
ENCLOSURE_SLACK = 1e-12


def status_class(status: str) -> str:
    """``optimal`` and ``feasible`` are one class; every other status is its own.

    >>> status_class("feasible"), status_class("infeasible")
    ('solved', 'infeasible')
    """
    return "solved" if status in ("optimal", "feasible") else status


@dataclass
class CrosscheckReport:
    """Per-backend rows, whether the decisions agree, conflicts, failures, largest objective gap."""

    target: str
    results: list[dict[str, Any]]
    agree: bool
    max_rel_objective_gap: float | None
    rtol: float = DEFAULT_RTOL
    runs: list[Result] = field(default_factory=list, repr=False)
    conflicts: list[str] = field(default_factory=list)

    @property
    def enclosure(self) -> tuple[float | None, float | None]:
        """The intersection of every certified row's proven enclosure of the optimal value:
        ``(largest lower end, smallest upper end)``, ``None`` for an end no backend proved."""
        rows = [r for r in self.results if r["decision"] == "certified"]
        lows = [r["lower"] for r in rows if r.get("lower") is not None]
        highs = [r["upper"] for r in rows if r.get("upper") is not None]
        return (max(lows) if lows else None, min(highs) if highs else None)

    @property
    def decisions(self) -> int:
        """Rows with a decision (:data:`DECISIONS`)."""
        return sum(1 for r in self.results if r["decision"] in DECISIONS)

    @property
    def failures(self) -> int:
        """Rows without a decision (rejected, undecided, could not run)."""
        return len(self.results) - self.decisions

    def to_dict(self) -> dict[str, Any]:
        """The ``lmic crosscheck --json`` object."""
        return {
            "target": self.target,
            "results": self.results,
            "agree": self.agree,
            "decisions": self.decisions,
            "failures": self.failures,
            "conflicts": self.conflicts,
            "max_rel_objective_gap": self.max_rel_objective_gap,
            "enclosure": list(self.enclosure),
            "rtol": self.rtol,
            "exit_code": self.exit_code(),
        }

    def exit_code(self) -> int:
        """0: at least one decision and no conflict; 1: a conflict, or no backend decided."""
        return 0 if self.agree else 1


def conflicts(rows: list[dict[str, Any]], sense: str, rtol: float) -> tuple[list[str], float | None]:
    """The conflicts between the rows' decisions, and the largest relative gap of certified optima.

    >>> rows = [{"backend": "a", "decision": "certified", "objective": 1.0, "x_norm": 1.0},
    ...         {"backend": "b", "decision": "infeasible-bounded", "radius": 10.0, "objective": None}]
    >>> print(conflicts(rows, "feasibility", 1e-3)[0][0])
    a certifies a point with ||x||_inf = 1 but b proves no solution with ||x||_inf <= 10
    """
    found: list[str] = []
    points = [r for r in rows if r["decision"] == "certified"]
    for r in rows:  # an unbounded problem has a feasible point and no optimum
        if r["decision"] != "unbounded-certified":
            continue
        for q in rows:
            if q["decision"] == "infeasible-certified":
                found.append(f"{r['backend']} proves the problem unbounded but {q['backend']} proves it infeasible")
            elif q["decision"] == "certified" and sense != "feasibility":
                found.append(f"{q['backend']} certifies an optimum but {r['backend']} proves the problem unbounded")
    for r in points:
        for q in rows:
            if q["decision"] == "infeasible-certified":
                found.append(f"{r['backend']} certifies a point but {q['backend']} proves the problem infeasible")
            elif q["decision"] == "infeasible-bounded" and r.get("x_norm") is not None:
                if q.get("rho") is not None:  # scale-free: the bound is on the relative margin
                    m = r.get("min_margin")
                    if m is not None and r["x_norm"] > 0 and m / r["x_norm"] > q["rho"]:
                        found.append(
                            f"{r['backend']} certifies a point of relative margin {m / r['x_norm']:.3g} but "
                            f"{q['backend']} proves none above {q['rho']:.3g}"
                        )
                elif q.get("radius") is not None and r["x_norm"] <= q["radius"]:
                    found.append(
                        f"{r['backend']} certifies a point with ||x||_inf = {r['x_norm']:.3g} but "
                        f"{q['backend']} proves no solution with ||x||_inf <= {q['radius']:.3g}"
                    )
    # every proven end bounds the one optimal value: a lower end above another backend's upper
    # end means a wrong proof (ENCLOSURE_SLACK: the exact and the float compilation of one
    # theorem differ by rounding)
    lows = [(r["lower"], r["backend"]) for r in points if r.get("lower") is not None]
    highs = [(r["upper"], r["backend"]) for r in points if r.get("upper") is not None]
    if lows and highs and sense != "feasibility":
        (lo, a), (hi, b) = max(lows), min(highs)
        if lo > hi + ENCLOSURE_SLACK * max(1.0, abs(hi)):
            found.append(f"{a} proves the optimum >= {lo:.10g} but {b} proves it <= {hi:.10g}")
    gap = None
    optima = [r["objective"] for r in points if r.get("objective") is not None]
    if sense != "feasibility" and len(optima) >= 2:
        lo, hi = min(optima), max(optima)
        gap = (hi - lo) / max(1.0, max(abs(lo), abs(hi)))
        if gap > rtol:
            found.append(f"certified optima differ by {gap:.3g} (relative) > rtol {rtol:g}")
    return found, gap


def check_rtol(rtol: float) -> None:
    """Refuse an agreement tolerance that is negative or not a number (:class:`LmicError`).

    >>> check_rtol(1e-4)
    >>> check_rtol(-1)
    Traceback (most recent call last):
    ...
    lmic.errors.LmicError: rtol must be a non-negative number, got -1
    """
    if not (isinstance(rtol, int | float) and math.isfinite(rtol) and rtol >= 0):
        raise LmicError(f"rtol must be a non-negative number, got {rtol}")


def crosscheck(
    target: str | os.PathLike[str] | Problem,
    system: Any = None,
    params: dict[str, Any] | None = None,
    backends: list[str] | None = None,
    options: SolveOptions | None = None,
    rtol: float = DEFAULT_RTOL,
    progress: Progress | None = None,
) -> CrosscheckReport:
    """Solve ``target`` on every backend in ``backends`` (default: every available one).

    Each backend's failure (unavailable, cannot take the problem) is a row with decision
    ``undecided`` and the reason, not an exception, so one missing solver does not hide the
    others. Every row has ``backend, decision`` (its outcome verdict), ``status``,
    ``objective`` (certified rows), ``radius`` (bounded rows), ``x_norm``, ``min_margin`` (the
    certifier's smallest LMI margin), ``strategy`` and ``margin`` (how strict LMIs were
    reduced), ``solve_s``, ``attempts`` and ``message``. ``progress`` (see :data:`Progress`) is
    told about each backend before and after it runs (``lmic crosscheck`` draws a progress bar
    with it).

    Examples
    --------
    >>> from lmic.testing.conformance import CASES
    >>> seen = []
    >>> r = crosscheck(CASES["lyapunov_stable"].build(), backends=["clarabel", "scs"],
    ...                progress=lambda done, total, name, row: seen.append((done, name, row is None)))
    >>> seen
    [(0, 'clarabel', True), (1, 'clarabel', False), (1, 'scs', True), (2, 'scs', False)]
    >>> [(row["strategy"], row["decision"]) for row in r.results]
    [('max-margin', 'certified'), ('fixed-margin', 'certified')]
    """
    from lmic.backends.registry import available_backend_names

    check_rtol(rtol)
    problem, _theorem, _ = load_target(target, system, params)
    names = backends or available_backend_names()
    if not names:
        raise LmicError("no backend to cross-check with")
    rows: list[dict[str, Any]] = []
    runs: list[Result] = []
    for k, name in enumerate(names):
        if progress is not None:
            progress(k, len(names), name, None)
        row, res = backend_row(problem, name, options)
        if res is not None:
            runs.append(res)
        rows.append(row)
        if progress is not None:
            progress(k + 1, len(names), name, row)
    return assemble(target_label(target, system), rows, problem.objective.sense, rtol, runs)


def error_row(name: str, message: str, status: str = "error") -> dict[str, Any]:
    """The row of a backend that could not run (decision ``undecided``, the reason as message).

    >>> r = error_row("mosek", "not installed")
    >>> r["decision"], r["status"], r["message"]
    ('undecided', 'error', 'not installed')
    """
    return {
        "backend": name,
        "decision": "undecided",
        "status": status,
        "objective": None,
        "verdict": "undecided",
        "radius": None,
        "rho": None,
        "x_norm": None,
        "min_margin": None,
        "strategy": None,
        "margin": None,
        "solve_s": 0.0,
        "time_s": 0.0,
        "lower": None,
        "upper": None,
        "rel_gap": None,
        "attempts": [],
        "message": " ".join(str(message).split()),
    }


def backend_row(
    problem: Problem, name: str, options: SolveOptions | None = None
) -> tuple[dict[str, Any], Result | None]:
    """Decide ``problem`` with backend ``name`` alone: its crosscheck row, and the result if it ran.

    This is one job of a cross-check (:func:`crosscheck` runs it for each backend in turn;
    ``lmic crosscheck --executor`` runs it in a worker, :func:`lmic.studies.parallel.crosscheck_parallel`).

    Examples
    --------
    >>> from lmic.testing.conformance import CASES
    >>> row, res = backend_row(CASES["lyapunov_stable"].build(), "clarabel")
    >>> row["backend"], row["decision"], res.verdict
    ('clarabel', 'certified', 'certified')
    """
    t0 = time.perf_counter()
    try:
        # no backed-off second solve: a row reports the optimum, its point and its enclosure
        res = solve(problem, backend=name, options=options, backoff=0.0)
    except LmicError as err:
        return error_row(name, str(err)), None
    time_s = time.perf_counter() - t0
    x = res.solution.x
    decision = res.verdict
    # both ends, even inconsistent ones: conflicts() reports a backend that contradicts itself
    enc = res.enclosure if decision == "certified" and res.enclosure else {}
    row = {
        "backend": res.backend,
        "decision": decision,
        "status": res.status,
        "objective": res.objective if decision == "certified" else None,
        "verdict": decision,
        "radius": res.outcome.evidence.radius if decision == "infeasible-bounded" else None,
        # a scale-free problem's bound: no point of relative margin above rho (farkas_scope)
        "rho": _rho(res) if decision == "infeasible-bounded" else None,
        "x_norm": float(np.max(np.abs(x))) if decision == "certified" and x is not None and len(x) else None,
        "min_margin": res.min_margin,
        "strategy": res.solution.strategy,
        "margin": res.solution.margin,
        "solve_s": res.timings["solve_s"],
        "time_s": time_s,
        "lower": enc.get("lower"),
        "upper": enc.get("upper"),
        "rel_gap": enc.get("rel_gap"),
        "attempts": res.attempts,
        "message": res.solution.message if decision not in DECISIONS else "",
    }
    if decision not in DECISIONS:
        row["message"] = res.outcome.reason or res.solution.message
    return row, res


def _rho(res: Result) -> float | None:
    """The relative-margin bound of a scale-free problem's bounded answer, else ``None``."""
    farkas = getattr(getattr(res.outcome, "certificate", None), "farkas", None) or {}
    sc = farkas.get("scope") or {}
    return sc.get("rho") if sc.get("basis") == "homogeneous" else None


def target_label(target: Any, system: Any = None) -> str:
    """How a report names what was cross-checked (target, then the system file if any).

    >>> target_label("qib.thm1", "plant.yaml")
    'qib.thm1 plant.yaml'
    """
    label = target if isinstance(target, str) else ("<problem>" if isinstance(target, Problem) else os.fspath(target))
    if system is not None:
        if isinstance(system, str | os.PathLike):
            label = f"{label} {os.fspath(system)}"
        else:  # a dict, a System or a plant object
            label = f"{label} {getattr(system, 'path', None) or '<system>'}"
    return str(label)


def assemble(
    label: str, rows: list[dict[str, Any]], sense: str, rtol: float = DEFAULT_RTOL, runs: list[Result] | None = None
) -> CrosscheckReport:
    """The report of a cross-check from its rows (in backend order): conflicts, agreement, gap.

    >>> rows = [{"backend": "a", "decision": "certified", "objective": 1.0, "x_norm": 1.0}]
    >>> assemble("p", rows, "feasibility").agree
    True
    """
    found, gap = conflicts(rows, sense, rtol)
    agree = not found and any(r["decision"] in DECISIONS for r in rows)
    return CrosscheckReport(label, rows, agree, gap, rtol, list(runs or []), found)
