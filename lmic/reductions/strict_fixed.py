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
    """``lmi`` with ``F0 - margin I`` and not strict.

    Only the constant column changes: it is rebuilt (sorted, duplicates summed) and the other
    columns' arrays are copied as they are, so the result keeps the coefficients' layout (no
    COO round trip and no re-sort of the whole matrix).
    """
    C = lmi.coeffs if lmi.coeffs.format == "csc" else lmi.coeffs.tocsc()
    if not C.has_sorted_indices:
        C = C.sorted_indices()
    ip = C.indptr
    s0, s1 = int(ip[0]), int(ip[1])
    col0 = np.zeros(C.shape[0])
    np.add.at(col0, C.indices[s0:s1], C.data[s0:s1])
    col0[_diagonal_positions(lmi.dim)] -= margin
    rows0 = np.flatnonzero(col0)
    data = np.concatenate([col0[rows0], C.data[s1:]])
    indices = np.concatenate([rows0.astype(C.indices.dtype), C.indices[s1:]])
    indptr = np.concatenate([[0], ip[1:] - s1 + len(rows0)]).astype(ip.dtype)
    coeffs = sp.csc_matrix((data, indices, indptr), shape=C.shape)
    coeffs.has_sorted_indices = True
    return replace(lmi, coeffs=coeffs, strict=False)


def _fixed_margin(problem: Problem, margin: float, normalise: bool = False) -> Problem:
    """Every strict LMI shifted by ``margin`` (:func:`_shift`), every strict row ``a0 - margin +
    a . x >= 0``; with ``normalise``, one row ``d - sum_k x_k tr F_k >= 0`` per strict LMI and
    one ``1 - a . x >= 0`` per strict row, after the original rows. The rows are assembled in
    one sparse construction (triplets), whatever their number."""
    lmis = []
    n = problem.n
    rows: list[np.ndarray] = []
    cols: list[np.ndarray] = []
    vals: list[np.ndarray] = []
    lin = problem.linear
    n_rows = len(lin)
    if n_rows:
        A = lin.A.tocoo()
        rows, cols, vals = [A.row], [A.col], [A.data]
    extra = 0  # normalisation rows so far
    for lmi in problem.lmis:
        if lmi.strict:
            if normalise:  # trace F(x) <= d  <=>  d - sum_k x_k tr F_k >= 0
                tr = _trace_row(lmi)
                ks = np.flatnonzero(tr[1:]) + 1
                rows.append(np.full(len(ks) + 1, n_rows + extra))
                cols.append(np.concatenate([[0], ks]))
                vals.append(np.concatenate([[float(lmi.dim)], -tr[ks]]))
                extra += 1
            lmi = _shift(lmi, margin)
        lmis.append(lmi)
    strict_rows = np.flatnonzero(np.asarray(lin.strict, dtype=bool)) if n_rows else np.zeros(0, dtype=int)
    if len(strict_rows):
        rows.append(strict_rows)  # a0 - margin (summed with a0 by the construction)
        cols.append(np.zeros(len(strict_rows), dtype=int))
        vals.append(np.full(len(strict_rows), -margin))
        if normalise:  # a . x <= 1 for every strict row
            S = lin.A.tocsr()[strict_rows].tocoo()
            keep = S.col > 0
            rows.append(n_rows + extra + np.concatenate([np.arange(len(strict_rows)), S.row[keep]]))
            cols.append(np.concatenate([np.zeros(len(strict_rows), dtype=int), S.col[keep]]))
            vals.append(np.concatenate([np.ones(len(strict_rows)), -S.data[keep]]))
            extra += len(strict_rows)
    shape = (n_rows + extra, 1 + n)
    if rows:
        A_new = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=shape)
    else:
        A_new = sp.csr_matrix(shape)
    kinds = list(lin.kinds) + ["ge"] * extra
    names = list(lin.names) + [f"scale normalisation {k}" for k in range(extra)]
    linear = LinearConstraints(A_new, kinds, [False] * len(kinds), names)
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
