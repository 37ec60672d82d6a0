"""What both strict reductions share: the inverse record, the tests of a problem and of a point.

Split out of :mod:`lmic.reductions.strict` (which re-exports every public name).

Examples
--------
>>> from lmic.testing.conformance import lyapunov_problem
>>> has_strict(lyapunov_problem(-np.eye(1))), is_scale_free(lyapunov_problem(-np.eye(1)))
(True, True)
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from lmic.backends.lowering import has_strict  # one definition; re-exported here for the passes
from lmic.certify.check import Tolerances, lmi_report
from lmic.certify.spectra import block_matrix
from lmic.ir.problem import Problem
from lmic.ir.svec import tril_size

__all__ = ["StrictInverse", "has_strict", "is_scale_free", "verify_point", "point_test"]


@dataclass
class StrictInverse:
    """What :func:`invert` needs to map a reduced problem's solution back."""

    strategy: str
    n: int
    n_rows: int
    margin: float | None = None
    scale_free: bool = False
    sense: str = "feasibility"


def is_scale_free(problem: Problem) -> bool:
    """True when every LMI has ``F0 = 0`` and every linear row ``a0 = 0`` (a conic feasible set).

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("p", "scalar", (1, 1))], [LMI("p>1", 1, sp.csc_matrix([[-1., 1.]]))],
    ...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
    >>> is_scale_free(p)
    False
    """
    for lmi in problem.lmis:  # F0 = 0: the constant column holds no nonzero
        C = lmi.coeffs if lmi.coeffs.format == "csc" else lmi.coeffs.tocsc()
        if np.any(C.data[C.indptr[0] : C.indptr[1]]):
            return False
    A = problem.linear.A.tocsr()
    return not np.any(A.data[A.indices == 0])


def _diagonal_positions(d: int) -> np.ndarray:
    """Storage positions of the diagonal entries (column-major lower triangle).

    >>> _diagonal_positions(3).tolist()
    [0, 3, 5]
    """
    j = np.arange(d)
    return j * d - j * (j - 1) // 2


def _identity_tril(d: int) -> np.ndarray:
    out = np.zeros(tril_size(d))
    out[_diagonal_positions(d)] = 1.0
    return out


def _trace_row(lmi: Any) -> np.ndarray:
    """``[tr F0, tr F_1, ..., tr F_n]`` of one LMI: the sum of its diagonal storage rows, by one
    pass over the CSC arrays (no sparse objects built).

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI
    >>> _trace_row(LMI("F", 2, sp.csc_matrix([[1.0, 2.0], [5.0, 7.0], [3.0, 0.0]]))).tolist()
    [4.0, 2.0]
    """
    C = lmi.coeffs if lmi.coeffs.format == "csc" else lmi.coeffs.tocsc()
    on_diagonal = np.zeros(C.shape[0], dtype=bool)
    on_diagonal[_diagonal_positions(lmi.dim)] = True
    ncols = C.shape[1]
    start = int(C.indptr[0])
    hits = np.flatnonzero(on_diagonal[C.indices[start : C.indptr[-1]]]) + start  # the few diagonal entries
    col = np.searchsorted(C.indptr, hits, side="right") - 1  # their columns
    return np.bincount(col, weights=C.data[hits], minlength=ncols).astype(float)


def _restrict(duals: dict | None, n_lmis: int, n_rows: int) -> dict | None:
    if not duals:
        return duals
    out = dict(duals)
    if "lmis" in out and out["lmis"] is not None:
        out["lmis"] = list(out["lmis"])[:n_lmis]
    if "linear" in out and out["linear"] is not None:
        out["linear"] = np.asarray(out["linear"], dtype=float)[:n_rows]
    return out


def verify_point(problem: Problem, x: np.ndarray | None) -> tuple[bool, str]:
    """Whether every LMI and row of ``problem`` holds at ``x`` by the certifier's rules.

    The LMIs are judged by :func:`lmic.certify.check.lmi_report` (strict LMIs: ``lambda_min``
    positive beyond float64 doubt, relative to the term scale; closed ones to ``1e-8``
    relative); rows likewise. Returns ``(ok, reason)``.

    >>> from lmic.testing.conformance import lyapunov_problem
    >>> verify_point(lyapunov_problem(-np.eye(1)), np.array([1.0]))
    (True, '')
    >>> verify_point(lyapunov_problem(-np.eye(1)), np.array([0.0]))[0]
    False
    """
    if x is None or not np.all(np.isfinite(x)):
        return False, "no finite point"
    tol = Tolerances()
    for lmi in problem.lmis:
        rep = lmi_report(lmi, x, tol)
        if not rep["ok"]:
            return False, f"LMI '{lmi.name}': lambda_min {rep['min_eig']:.3g}"
    lin = problem.linear
    if len(lin):
        xx = np.concatenate([[1.0], x])
        res = np.asarray(lin.A @ xx).ravel()
        scale = np.asarray(abs(lin.A) @ np.abs(xx)).ravel()
        for r, kind in enumerate(lin.kinds):
            allowed = tol.rel * scale[r] + 1e-15
            if kind == "eq":
                ok = abs(res[r]) <= allowed
            elif lin.strict[r]:
                ok = res[r] > tol.strict_rel * scale[r] and scale[r] > 0
            else:
                ok = res[r] >= -allowed
            if not ok:
                return False, f"row '{lin.names[r]}': {res[r]:.3g}"
    return True, ""


def point_test(problem: Problem) -> Callable[[np.ndarray], bool]:
    """:func:`verify_point` on ``problem`` as a test of a solver's iterates (``SolveOptions.accept``).

    A cheap rejection first: every strict LMI's ``F(x)`` must have a Cholesky factor (positive
    definite in float64; a failed factorisation means ``lambda_min <= 0`` up to rounding, which
    :func:`verify_point` would reject too); only then the full test, whose answer is returned.
    The certifier judges the final answer again.

    >>> from lmic.testing.conformance import lyapunov_problem
    >>> test = point_test(lyapunov_problem(-np.eye(2)))
    >>> test(np.array([1.0, 0.0, 1.0])), test(np.array([1.0, 0.0, -1.0])), test(np.zeros(2))
    (True, False, False)
    """
    strict = [lmi for lmi in problem.lmis if lmi.strict and lmi.dim]
    n = problem.n

    def accept(x: np.ndarray) -> bool:
        x = np.asarray(x, dtype=float)
        if x.shape != (n,) or not np.all(np.isfinite(x)):
            return False
        for lmi in strict:
            try:  # F(x) is kept for verify_point's spectrum at the same point (lmic.certify.spectra)
                np.linalg.cholesky(block_matrix(lmi, x))
            except np.linalg.LinAlgError:
                return False
        return verify_point(problem, x)[0]

    return accept
