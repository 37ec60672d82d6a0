"""Grids over one scalar parameter: ``lmic solve ... --sweep P=a:b:n``.

Every value re-binds the theorem's cached plan and is decided on the theorem's own problem
(objective kept, :mod:`lmic.studies.sweep.points`), warm-started from the previous value.

Examples
--------
>>> parse_grid("alpha=log:1e-3:1:4")
('alpha', [0.001, 0.01, 0.1, 1.0])
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from lmic.errors import DataError
from lmic.formatting import domain_text
from lmic.studies.sweep.points import Evaluator, domain, in_domain, setup
from lmic.studies.sweep.results import PointResult, Progress, SweepResult

__all__ = ["parse_grid", "sweep"]


def parse_grid(spec: str) -> tuple[str, list[float]]:
    """``PARAM=a:b:n`` (linear) or ``PARAM=log:a:b:n`` (geometric) -> (name, values).

    Numbers are read with ``float`` (nothing is evaluated); ``n >= 1``; a geometric grid needs
    ``a`` and ``b`` of the same sign and non-zero.

    >>> parse_grid("eps=0.5:1.5:3")
    ('eps', [0.5, 1.0, 1.5])
    >>> parse_grid("eps=0.5")
    Traceback (most recent call last):
    ...
    lmic.errors.DataError: --sweep 'eps=0.5': write PARAM=a:b:n or PARAM=log:a:b:n
    """
    bad = DataError(f"--sweep {spec!r}: write PARAM=a:b:n or PARAM=log:a:b:n")
    if "=" not in spec:
        raise bad
    name, rest = (s.strip() for s in spec.split("=", 1))
    if not name.isidentifier():
        raise DataError(f"--sweep {spec!r}: '{name}' is not a parameter name")
    parts = [s.strip() for s in rest.split(":")]
    scale = "linear"
    if parts and parts[0].lower() == "log":
        scale, parts = "log", parts[1:]
    if len(parts) != 3:
        raise bad
    try:
        a, b = float(parts[0]), float(parts[1])
        n = int(parts[2])
    except ValueError:
        raise bad from None
    if not (math.isfinite(a) and math.isfinite(b)):
        raise DataError(f"--sweep {spec!r}: the ends must be finite numbers")
    if n < 1 or n > 10000:
        raise DataError(f"--sweep {spec!r}: the number of points must be between 1 and 10000")
    if n == 1:
        return name, [a]
    if scale == "log":
        if a == 0 or b == 0 or (a > 0) != (b > 0):
            raise DataError(f"--sweep {spec!r}: a geometric grid needs non-zero ends of the same sign")
        values = np.geomspace(a, b, n)
    else:
        values = np.linspace(a, b, n)
    return name, [float(np.format_float_positional(v, precision=12, unique=True, trim="-")) for v in values]


def sweep(
    theorem: str,
    system: Any,
    param: str,
    values: Sequence[float],
    *,
    params: Mapping[str, Any] | None = None,
    backend: Any = None,
    options: Any = None,
    exact: bool = True,
    progress: Progress | None = None,
    reuse: bool = True,
) -> SweepResult:
    """Solve and certify the theorem at every value of ``param`` (a re-bound cached plan).

    Each point is the theorem's own problem (objective kept) decided by :func:`decide`; the best
    certified point is reported (objective for ``min``/``max``, relative margin for feasibility).
    For a feasibility theorem (no objective) with ``reuse``, the last certified point is first
    certified again at the next value (:func:`lmic.studies.sweep.points.reuse`): where it holds,
    that value is certified without a solve (its attempt says so); else the value is solved,
    warm-started from the last solve. ``reuse=False`` solves every value.

    Examples
    --------
    >>> r = sweep("qib.thm2", "examples/qib.thm2.flexible-joint.yaml", "alpha",
    ...           [1e-3, 1.0])                                         # doctest: +SKIP
    >>> [p.outcome for p in r.points]                                  # doctest: +SKIP
    ['infeasible', 'infeasible']
    """
    t_start = time.perf_counter()
    t0 = time.perf_counter()
    sysobj, plan, overrides, decl = setup(theorem, system, param, params)
    plan_s = time.perf_counter() - t0
    dom = domain(decl)
    for v in values:
        if not in_domain(float(v), dom):
            raise DataError(f"theorem {plan.id}: {param} = {v:g} is outside its domain {domain_text(decl.domain)}")
    total = len(values)

    def report(event: dict[str, Any]) -> None:
        if progress is not None:
            progress({**event, "total": total})

    ev = Evaluator(plan, sysobj, overrides, param, backend, options, True, exact, report, reuse=reuse)
    for k, v in enumerate(values):
        ev(float(v), "sweep", iteration=k + 1)
    certified = [p for p in ev.points if p.outcome == "feasible"]
    best: PointResult | None = None
    best_rule = ""
    sense = ev.sense
    if certified:
        ok = [p.outcome == "feasible" for p in ev.points]
        k = len(certified)
        if sense in ("min", "max") and all(p.objective is not None for p in certified):
            pick = min if sense == "min" else max
            best = pick(certified, key=lambda p: _primal_end(p, sense))
            best_rule = "proven optimum" if all(p.enclosure for p in certified) else "objective"
        elif k < len(ok) and (all(ok[:k]) or all(ok[-k:])):
            # one certified run at an end of the grid: the interesting point is where it stops
            best = certified[-1] if all(ok[:k]) else certified[0]
            best_rule = "edge of the certified range"
        else:
            best = max(certified, key=lambda p: -math.inf if p.rel_margin is None else p.rel_margin)
            best_rule = "largest margin"
    return SweepResult(
        theorem=plan.id,
        param=param,
        sense=sense,
        points=ev.points,
        best=best,
        best_rule=best_rule,
        backend=str(getattr(backend, "label", backend) or "auto"),
        plan_s=plan_s,
        total_s=time.perf_counter() - t_start,
    )


def _primal_end(p: PointResult, sense: str) -> float:
    """A point's best proven value: its enclosure's primal end (the certified point's objective
    where there is none), the one a user of the grid compares."""
    key = "upper" if sense == "min" else "lower"
    end = (p.enclosure or {}).get(key)
    value = float(p.objective) if end is None else float(end)  # type: ignore[arg-type]
    return min(value, float(p.objective)) if sense == "min" else max(value, float(p.objective))  # type: ignore[arg-type]
