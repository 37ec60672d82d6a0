"""The ``fixed-margin`` pass: strict constraints shifted by a margin ``delta`` (apply and invert).

The rules (absolute or relative margin, trace normalisation of scale-free problems) are in the
docstring of :mod:`lmic.reductions.strict`, which runs this pass and re-exports its names.

Examples
--------
>>> from lmic.testing.conformance import lyapunov_problem
>>> _fixed_margin(lyapunov_problem(-np.eye(1)), 1e-4, normalise=True).lmis[0].strict
False
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

import numpy as np
import scipy.sparse as sp

from lmic.certify.spectra import block_spectrum
from lmic.ir.problem import LinearConstraints, Objective, Problem
from lmic.reductions.strict_common import StrictInverse, _diagonal_positions, _restrict, _trace_row
from lmic.solution import Solution

__all__ = ["achieved_margin", "invert_fixed"]


def _shift(lmi: Any, margin: float) -> Any:
    """``lmi`` with ``F0 - margin I`` and not strict."""
    C = lmi.coeffs.tocoo()
    d = _diagonal_positions(lmi.dim)
    coeffs = sp.csc_matrix(
        (
            np.concatenate([C.data, np.full(len(d), -margin)]),
            (np.concatenate([C.row, d]), np.concatenate([C.col, np.zeros(len(d), dtype=C.col.dtype)])),
        ),
        shape=C.shape,
    )
    return replace(lmi, coeffs=coeffs, strict=False)


def _fixed_margin(problem: Problem, margin: float, normalise: bool = False) -> Problem:
    lmis = []
    norm_rows = []
    n = problem.n
    for lmi in problem.lmis:
        if lmi.strict:
            if normalise:  # trace F(x) <= d  <=>  d - sum_k x_k tr F_k >= 0
                norm_rows.append(np.concatenate([[float(lmi.dim)], -_trace_row(lmi)[1:]]))
            lmi = _shift(lmi, margin)
        lmis.append(lmi)
    lin = problem.linear
    A = lin.A.tolil(copy=True)
    strict_rows: list[int] = np.flatnonzero(np.asarray(lin.strict, dtype=bool)).tolist() if len(lin) else []
    for r in strict_rows:
        if normalise:  # a . x <= 1
            norm_rows.append(np.concatenate([[1.0], -lin.A[r].toarray().ravel()[1:]]))
        A[r, 0] = A[r, 0] - margin
    kinds, names = list(lin.kinds), list(lin.names)
    A = A.tocsr()
    if norm_rows:
        A = (
            sp.vstack([A, sp.csr_matrix(np.vstack(norm_rows))], format="csr")
            if len(lin)
            else (sp.csr_matrix(np.vstack(norm_rows)))
        )
        kinds += ["ge"] * len(norm_rows)
        names += [f"scale normalisation {k}" for k in range(len(norm_rows))]
    linear = LinearConstraints(A, kinds, [False] * len(kinds), names)
    objective = problem.objective
    if objective.sense == "feasibility":
        objective = Objective("feasibility", np.zeros(n + 1))
    return replace(problem, lmis=lmis, linear=linear, objective=objective)


def achieved_margin(problem: Problem, x: np.ndarray, scale_free: bool) -> float:
    """The margin ``x`` achieves on the strict constraints of ``problem``.

    ``min_i lambda_min(F_i(x)) / (trace F_i(x) / d_i)`` over the strict LMIs and
    ``(a0 + a . x) / |a . x|`` over the strict rows when ``scale_free``; the absolute
    ``lambda_min`` and row values otherwise. ``inf`` when nothing is strict.

    >>> from lmic.testing.conformance import lyapunov_problem
    >>> float(achieved_margin(lyapunov_problem(-np.eye(1)), np.array([2.0]), True))
    1.0
    """
    x = np.asarray(x, dtype=float)
    values = [math.inf]
    for lmi in problem.lmis:
        if not lmi.strict or lmi.dim == 0:
            continue
        F, eig = block_spectrum(lmi, x)  # shared with verify_point and the certifier
        lmin = float(eig[0])
        if scale_free:
            mean = float(np.trace(F)) / lmi.dim
            lmin = lmin / mean if mean > 0 else -math.inf
        values.append(lmin)
    lin = problem.linear
    if len(lin) and any(lin.strict):
        res = lin.residuals(x)
        for r in np.flatnonzero(np.asarray(lin.strict, dtype=bool)):
            v = float(res[r])
            if scale_free:
                v = 1.0 if v > 0 else -math.inf
            values.append(v)
    return float(min(values))


def invert_fixed(solution: Solution, inverse: StrictInverse, problem: Problem | None = None) -> Solution:
    """The fixed-margin answer mapped back to the original problem (see :func:`lmic.reductions.strict.invert`)."""
    solution.margin = inverse.margin
    if solution.farkas is not None:
        solution.farkas = dict(solution.farkas, margin=inverse.margin)
    if inverse.sense == "feasibility":
        n_lmis = len(problem.lmis) if problem is not None else None
        if n_lmis is not None:
            solution.duals = _restrict(solution.duals, n_lmis, inverse.n_rows) or {}
            if solution.farkas is not None:
                solution.farkas = _restrict(solution.farkas, n_lmis, inverse.n_rows)
        solution.info["imposed_margin"] = inverse.margin
        solution.info["scale_free"] = inverse.scale_free
        solution.objective = None
        if problem is not None and solution.x is not None:
            solution.margin = achieved_margin(problem, solution.x, inverse.scale_free)
        if solution.status == "optimal":
            if solution.margin is not None and solution.margin <= 0:
                solution.status = "inaccurate"
                solution.message = (
                    f"the solver's point misses the strict constraints (margin {solution.margin:.3g}); "
                    "it met the closed ones only to its tolerance"
                )
            else:
                solution.status = "feasible"
        elif solution.status == "infeasible":
            solution.message = (
                f"no point with margin {inverse.margin:g}"
                + (" (relative, under the trace normalisation)" if inverse.scale_free else "")
                + "; a smaller margin may exist (strict='max-margin' decides)"
            )
    return solution
