"""Cross-check one problem on several backends: do they agree, and is each answer certified?

The problem is compiled (or loaded) once; each backend solves it and the certifier checks every
answer independently. Backends *agree* when their statuses fall in the same class
(``optimal``/``feasible`` together, ``infeasible``, ``unbounded``) and, for optimisation
problems, the largest relative objective gap is within ``rtol``. A backend that errors or is
inaccurate breaks the agreement.

Examples
--------
>>> from lmic.testing.conformance import CASES
>>> report = crosscheck(CASES["max_sense"].build(), backends=["clarabel", "cvxopt"])
>>> report.agree, [r["status"] for r in report.results]
(True, ['optimal', 'optimal'])
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from lmic.api import Result, load_target, solve
from lmic.backends.base import SolveOptions
from lmic.errors import LmicError
from lmic.ir.problem import Problem

__all__ = ["CrosscheckReport", "crosscheck", "status_class", "DEFAULT_RTOL", "Progress"]

#: ``progress(done, total, backend, row)``: called before each backend (``row`` is ``None``) and
#: after it (``row`` is its result row)
Progress = Callable[[int, int, str, "dict[str, Any] | None"], None]

#: default tolerance on the relative objective gap (first-order solvers meet ~1e-3 here)
DEFAULT_RTOL = 1e-3


def status_class(status: str) -> str:
    """``optimal`` and ``feasible`` are one class; every other status is its own.

    >>> status_class("feasible"), status_class("infeasible")
    ('solved', 'infeasible')
    """
    return "solved" if status in ("optimal", "feasible") else status


@dataclass
class CrosscheckReport:
    """Per-backend results, whether they agree, and the largest relative objective gap."""

    target: str
    results: list[dict[str, Any]]
    agree: bool
    max_rel_objective_gap: float | None
    rtol: float = DEFAULT_RTOL
    runs: list[Result] = field(default_factory=list, repr=False)

    def to_dict(self) -> dict[str, Any]:
        """The ``lmic crosscheck --json`` object (DESIGN section 7)."""
        return {
            "target": self.target,
            "results": self.results,
            "agree": self.agree,
            "max_rel_objective_gap": self.max_rel_objective_gap,
            "rtol": self.rtol,
        }

    def exit_code(self) -> int:
        """0: agree and every answer certified; 3: agree that it is infeasible; 1 otherwise."""
        if not self.agree or not self.results:
            return 1
        verdicts = {r["verdict"] for r in self.results}
        classes = {status_class(r["status"]) for r in self.results}
        if classes == {"solved"} and verdicts == {"certified"}:
            return 0
        if classes == {"infeasible"} and "rejected" not in verdicts:
            return 3
        return 1


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

    Each backend's failure (unavailable, cannot take the problem) is a row with status
    ``error`` and the reason, not an exception, so one missing solver does not hide the others.
    Every row has ``backend, status, objective, verdict, min_margin`` (the certifier's smallest
    LMI margin), ``strategy`` and ``margin`` (how strict LMIs were reduced and the margin the
    backend reported), ``solve_s`` and ``message``. ``progress`` (see :data:`Progress`) is
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
    >>> [(row["strategy"], row["verdict"]) for row in r.results]
    [('max-margin', 'certified'), ('fixed-margin', 'certified')]
    """
    from lmic.backends.registry import available_backend_names

    problem, _theorem, _ = load_target(target, system, params)
    names = backends or available_backend_names()
    if not names:
        raise LmicError("no backend to cross-check with")
    rows: list[dict[str, Any]] = []
    runs: list[Result] = []
    for k, name in enumerate(names):
        if progress is not None:
            progress(k, len(names), name, None)
        try:
            res = solve(problem, backend=name, options=options)
        except LmicError as err:
            row: dict[str, Any] = {
                "backend": name,
                "status": "error",
                "objective": None,
                "verdict": "unverified",
                "min_margin": None,
                "strategy": None,
                "margin": None,
                "solve_s": 0.0,
                "message": " ".join(str(err).split()),
            }
        else:
            runs.append(res)
            row = {
                "backend": res.backend,
                "status": res.status,
                "objective": res.objective,
                "verdict": res.verdict,
                "min_margin": res.min_margin,
                "strategy": res.solution.strategy,
                "margin": res.solution.margin,
                "solve_s": res.timings["solve_s"],
                "message": res.solution.message,
            }
        rows.append(row)
        if progress is not None:
            progress(k + 1, len(names), name, row)
    classes = {status_class(r["status"]) for r in rows}
    objectives = [r["objective"] for r in rows if r["objective"] is not None]
    gap = None
    if len(objectives) >= 2:
        lo, hi = min(objectives), max(objectives)
        gap = (hi - lo) / max(1.0, max(abs(lo), abs(hi)))
    agree = (
        len(classes) == 1
        and not classes & {"error", "inaccurate"}
        and (gap is None or gap <= rtol)
        and not (classes == {"solved"} and problem.objective.sense != "feasibility" and len(objectives) != len(rows))
    )
    label = target if isinstance(target, str) else ("<problem>" if isinstance(target, Problem) else os.fspath(target))
    if system is not None:
        if isinstance(system, str | os.PathLike):
            label = f"{label} {os.fspath(system)}"
        else:  # a dict, a System or a plant object
            label = f"{label} {getattr(system, 'path', None) or '<system>'}"
    return CrosscheckReport(str(label), rows, agree, gap, rtol, runs)
