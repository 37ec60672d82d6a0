"""The ``max-margin`` pass: maximise a margin ``t`` on the strict constraints (apply and invert).

The decisions on ``t*`` (feasible, infeasible with a verified dual, inaccurate) are in the
docstring of :mod:`lmic.reductions.strict`, which runs this pass and re-exports its names.

Examples
--------
>>> from lmic.testing.conformance import lyapunov_problem
>>> reduced, inverse = _max_margin(lyapunov_problem(-np.eye(1)))
>>> reduced.variables[-1].name, inverse.strategy
('_lmic_margin_t', 'max-margin')
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np
import scipy.sparse as sp

from lmic.ir.problem import LinearConstraints, Objective, Problem, Variable
from lmic.ir.svec import tril_size
from lmic.options import SolveOptions
from lmic.reductions.strict_common import (
    StrictInverse,
    _identity_tril,
    _restrict,
    _trace_row,
    is_scale_free,
    verify_point,
)
from lmic.solution import Solution

__all__ = ["MARGIN_VARIABLE", "invert_max"]


#: name of the margin variable added by the ``max-margin`` strategy
MARGIN_VARIABLE = "_lmic_margin_t"


def _max_margin(problem: Problem) -> tuple[Problem, StrictInverse]:
    n = problem.n
    scale_free = is_scale_free(problem)
    t_var = Variable(MARGIN_VARIABLE, "scalar", (1, 1), offset=n)
    lmis = []
    norm_rows = []
    for lmi in problem.lmis:
        m = tril_size(lmi.dim)
        col = -_identity_tril(lmi.dim) if lmi.strict else np.zeros(m)
        coeffs = sp.hstack([lmi.coeffs, sp.csc_matrix(col.reshape(-1, 1))], format="csc")
        lmis.append(replace(lmi, coeffs=coeffs, strict=False))
        if lmi.strict and scale_free:
            # trace F(x) <= d  <=>  d - sum_k x_k tr F_k >= 0
            norm_rows.append(np.concatenate([[float(lmi.dim)], -_trace_row(lmi)[1:], [0.0]]))
    lin = problem.linear
    strict_mask = np.asarray(lin.strict, dtype=bool) if len(lin) else np.zeros(0, dtype=bool)
    t_col = -strict_mask.astype(float).reshape(-1, 1)
    A = sp.hstack([lin.A, sp.csr_matrix(t_col)], format="csr") if len(lin) else sp.csr_matrix((0, n + 2))
    if scale_free:
        for r in np.flatnonzero(strict_mask):
            a = lin.A[r].toarray().ravel()
            norm_rows.append(np.concatenate([[1.0], -a[1:], [0.0]]))
    cap = np.zeros(n + 2)
    cap[0], cap[-1] = 1.0, -1.0  # 1 - t >= 0
    extra = sp.csr_matrix(np.vstack([cap, *norm_rows]))
    linear = LinearConstraints(
        sp.vstack([A, extra], format="csr"),
        list(lin.kinds) + ["ge"] * extra.shape[0],
        [False] * (len(lin) + extra.shape[0]),
        list(lin.names) + ["margin t <= 1"] + [f"scale normalisation {k}" for k in range(len(norm_rows))],
    )
    c = np.zeros(n + 2)
    c[-1] = 1.0
    reduced = Problem(
        variables=[*problem.variables, t_var],
        lmis=lmis,
        linear=linear,
        objective=Objective("max", c),
        data=problem.data,
        derived=[],
        checks=[],
        meta=dict(problem.meta),
    )
    return reduced, StrictInverse("max-margin", n, len(lin), scale_free=scale_free)


def invert_max(
    solution: Solution, inverse: StrictInverse, options: SolveOptions, problem: Problem | None = None
) -> Solution:
    """The max-margin answer mapped back to the original problem (see :func:`lmic.reductions.strict.invert`)."""
    n_lmis = len(problem.lmis) if problem is not None else len(solution.duals.get("lmis", []) or [])
    x = solution.x
    t = None
    if x is not None and len(x) == inverse.n + 1:
        t = float(x[-1])
        solution.x = x[: inverse.n]
    solution.margin = t
    solution.objective = None
    duals = _restrict(solution.duals, n_lmis, inverse.n_rows) or {}
    solution.duals = duals
    if solution.farkas is not None:
        solution.farkas = _restrict(solution.farkas, n_lmis, inverse.n_rows)
    solution.info["scale_free"] = inverse.scale_free
    threshold = 10.0 * max(options.tol, 1e-12)
    if solution.status in ("optimal", "feasible") and t is not None:
        if t > threshold or (t > 0 and problem is not None and verify_point(problem, solution.x)[0]):
            solution.status = "feasible"
        elif t <= 0 or problem is None or _dual_verifies(duals, problem):
            solution.status = "infeasible"
            solution.message = f"maximal margin t* = {t:.3g} <= 0: the strict constraints cannot be met"
            if t > 0:
                solution.message = (
                    f"maximal margin t* = {t:.3g} is within the tolerance of 0 and the dual of the margin "
                    "problem proves the strict constraints infeasible"
                )
            if duals.get("lmis") is not None:
                solution.farkas = dict(duals, strict=True)
        else:
            solution.status = "inaccurate"
            solution.message = (
                f"maximal margin t* = {t:.3g} is positive but within {threshold:.1g} (10 tol) of 0: the point "
                "does not verify and the dual is no Farkas certificate; a tighter tolerance decides"
            )
    elif solution.status == "inaccurate" and t is not None and problem is not None:
        _inaccurate_max_margin(solution, t, duals, problem, options)
    return solution


def _dual_verifies(duals: dict, problem: Problem) -> bool:
    """Whether the max-margin dual (restricted to the original constraints) is a Farkas ray."""
    if duals.get("lmis") is None or len(duals["lmis"]) != len(problem.lmis):
        return False
    from lmic.certify.farkas import verify_farkas  # only when a dual is to be judged (import time)

    try:
        return bool(verify_farkas(problem, duals).get("verified"))
    except Exception:  # noqa: BLE001 - a malformed dual is just not a certificate
        return False


def _inaccurate_max_margin(solution: Solution, t: float, duals: dict, problem: Problem, options: SolveOptions) -> None:
    """Issue an ``infeasible`` for an inaccurate max-margin solve only on a verified dual."""
    threshold = 10.0 * max(options.tol, 1e-12)
    if t >= -threshold:
        return
    report: dict[str, Any] = {"verified": False, "reason": "the solver returned no dual"}
    if duals.get("lmis") is not None and len(duals["lmis"]) == len(problem.lmis):
        from lmic.certify.farkas import ray_report  # only when a dual is to be judged (import time)

        report = ray_report(problem, duals)
    if report.get("verified"):
        solution.status = "infeasible"
        solution.farkas = dict(duals, strict=True)
        solution.message = (
            f"max-margin solve inaccurate ({solution.native_status}) at t* = {t:.3g} < "
            f"-{threshold:.1g}, and its dual verifies as a {report.get('kind', '')} Farkas "
            "certificate: infeasible"
        )
    else:
        why = report.get("reason") or "residuals above tolerance"
        solution.message = (
            f"max-margin solve inaccurate ({solution.native_status}) at t* = {t:.3g}: suggests "
            f"infeasibility, but its dual is not a verified Farkas certificate ({why})"
        )
