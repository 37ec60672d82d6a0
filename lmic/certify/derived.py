"""The certifier's judgement of what follows from a point: derived quantities, theorem checks, objective.

Derived quantities (gains) are evaluated in order (:meth:`lmic.ir.problem.Problem.environment`),
theorem checks by kind (:data:`lmic.ir.problem.CHECK_KINDS`), and the objective against the
solver's claim. Split out of :mod:`lmic.certify.check`, which re-exports :func:`evaluate_checks`.

Examples
--------
>>> import numpy as np
>>> from lmic.ir.problem import Check
>>> evaluate_checks([Check("stable", "hurwitz", {"name": "M"})], {"M": -np.eye(2)}, Tolerances())[0]["ok"]
True
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from lmic.certify import margins
from lmic.certify.margins import _g
from lmic.certify.result import Tolerances
from lmic.errors import IRError
from lmic.ir.expr import evaluate
from lmic.ir.problem import Check, Problem
from lmic.solution import Solution

__all__ = ["evaluate_checks", "environment_report", "objective_report", "check_reason"]


def _value_json(v: Any) -> Any:
    if isinstance(v, np.ndarray):
        return v.tolist()
    return float(v)


def _finite(v: Any) -> bool:
    return bool(np.all(np.isfinite(np.asarray(v, dtype=float))))


def _not_real(v: Any) -> str:
    """Why a derived value is not a real number ("" when it is): a complex value (the square
    root of a negative variable at a solver's point, ``1 / sqrt(rho)`` with ``rho < 0``) or a
    non-numeric one.

    >>> _not_real(2.0), _not_real(np.sqrt(complex(-1.0))), _not_real("x")
    ('', 'complex value', 'not a number')
    """
    try:
        arr = np.asarray(v)
    except (TypeError, ValueError):
        return "not a number"
    if np.iscomplexobj(arr):
        return "complex value"
    if arr.dtype.kind not in "biuf":
        return "not a number"
    return ""


def environment_report(problem: Problem, x: np.ndarray) -> tuple[dict, list[dict]]:
    """Environment for expression trees and the per-quantity derived report."""
    try:
        env = problem.environment(x)
        failed: dict[str, str] = {}
    except (IRError, ValueError, TypeError, ZeroDivisionError, FloatingPointError):
        # locate the failure: evaluate quantity by quantity (same order as environment())
        env = {}
        for k, v in problem.data.items():
            env[k] = np.asarray(v, dtype=float) if isinstance(v, list | np.ndarray) else float(v)
        env.update(problem.unpack(x))
        failed = {}
        for d in problem.derived:
            try:
                env[d.name] = evaluate(d.expr, env)
            except (IRError, ValueError, TypeError, ZeroDivisionError) as err:
                failed[d.name] = str(err) or type(err).__name__
    report = []
    for d in problem.derived:
        if d.name in failed:
            report.append({"name": d.name, "value": None, "ok": False, "error": failed[d.name]})
            continue
        v = env[d.name]
        why = _not_real(v)
        if why:
            report.append({"name": d.name, "value": None, "ok": False, "error": why})
            continue
        ok = _finite(v)
        report.append({"name": d.name, "value": _value_json(v), "ok": ok, "error": "" if ok else "not finite"})
    return env, report


def evaluate_checks(checks: list[Check], env: dict, tol: Tolerances) -> list[dict]:
    """Evaluate theorem checks (kinds :data:`lmic.ir.problem.CHECK_KINDS`) in ``env``.

    Examples
    --------
    >>> from lmic.ir.problem import Check
    >>> c = Check("A - L C Schur", "schur_stable", {"name": "M"})
    >>> evaluate_checks([c], {"M": np.diag([0.5, 1.2])}, Tolerances())[0]["ok"]
    False
    """
    out = []
    for c in checks:
        entry: dict[str, Any] = {
            "name": c.name,
            "kind": c.kind,
            "value": None,
            "bound": c.bound,
            "ok": False,
            "error": "",
        }
        try:
            with np.errstate(all="ignore"):
                v = evaluate(c.expr, env)
            entry["value"], entry["ok"] = _judge(c, v, tol)
        except (IRError, ValueError, TypeError, ZeroDivisionError, np.linalg.LinAlgError) as err:
            entry["error"] = str(err) or type(err).__name__
        out.append(entry)
    return out


def _judge(c: Check, v: Any, tol: Tolerances) -> tuple[float, bool]:
    M = np.atleast_2d(np.asarray(v, dtype=float))
    if c.kind == "finite":
        finite = bool(np.all(np.isfinite(M)))
        return (float(np.max(np.abs(M))) if finite and M.size else (0.0 if finite else float("inf"))), finite
    if not np.all(np.isfinite(M)):
        raise ValueError("the checked quantity is not finite")
    if c.kind in ("less_than", "greater_than"):
        if M.size != 1:
            raise ValueError(f"'{c.kind}' needs a scalar, got shape {M.shape}")
        val = float(M.ravel()[0])
        bound = 0.0 if c.bound is None else float(c.bound)
        return val, (val < bound) if c.kind == "less_than" else (val > bound)
    if M.shape[0] != M.shape[1]:
        raise ValueError(f"'{c.kind}' needs a square matrix, got shape {M.shape}")
    if c.kind == "schur_stable":
        rho = float(np.max(np.abs(np.linalg.eigvals(M))))
        return rho, rho < 1.0
    if c.kind == "hurwitz":
        a = float(np.max(np.real(np.linalg.eigvals(M))))
        return a, a < 0.0
    S = 0.5 * (M + M.T)
    eig = np.linalg.eigvalsh(S)
    norm = float(np.max(np.abs(eig)))
    err = max(tol.strict_rel, 10.0 * (S.shape[0] + 2) * margins._U) * norm
    if c.kind == "negative_definite":
        return float(eig[-1]), bool(eig[-1] < -err)
    if c.kind == "positive_definite":
        return float(eig[0]), bool(eig[0] > err)
    if c.kind == "negative_semidefinite":
        return float(eig[-1]), bool(eig[-1] <= tol.rel * norm)
    if c.kind == "positive_semidefinite":
        return float(eig[0]), bool(eig[0] >= -tol.rel * norm)
    raise ValueError(f"unknown check kind '{c.kind}'")  # pragma: no cover - Check validates


def check_reason(r: dict) -> str:
    if r["error"]:
        return f"check '{r['name']}' ({r['kind']}) failed: {r['error']}"
    what = {
        "schur_stable": "spectral radius {v}, needs < 1",
        "hurwitz": "spectral abscissa {v}, needs < 0",
        "negative_definite": "lambda_max {v}, needs < 0",
        "positive_definite": "lambda_min {v}, needs > 0",
        "negative_semidefinite": "lambda_max {v}, needs <= 0",
        "positive_semidefinite": "lambda_min {v}, needs >= 0",
        "less_than": "value {v}, needs < {b}",
        "greater_than": "value {v}, needs > {b}",
        "finite": "value is not finite",
    }[r["kind"]]
    b = 0.0 if r["bound"] is None else r["bound"]
    return f"check '{r['name']}' failed: " + what.format(v=_g(r["value"]), b=_g(b))


def objective_report(problem: Problem, solution: Solution, x: np.ndarray, tol: Tolerances) -> dict[str, Any] | None:
    """The objective recomputed at ``x`` against the solver's claim (``None`` for a feasibility problem)."""
    obj = problem.objective
    val = obj.value(x)
    if val is None:  # a feasibility problem
        return None
    claimed = solution.objective
    entry: dict[str, Any] = {
        "sense": obj.sense,
        "value": val,
        "claimed": claimed,
        "rel_diff": None,
        "ok": math.isfinite(val),
    }
    if claimed is not None:
        claimed = float(claimed)
        diff = abs(val - claimed) / max(1.0, abs(val), abs(claimed))
        entry.update(claimed=claimed, rel_diff=diff, ok=bool(diff <= tol.objective_rel))
    return entry
