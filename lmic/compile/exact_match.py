"""Whether an exact compilation rounds to the IR it stands for (the same problem, or not).

:func:`lmic.compile.exact.exact_of` recompiles a theorem exactly from the numbers a problem was
bound from; a problem derived from it (a cut, a lifted or backed-off problem) may keep its
metadata and change its rows or objective. A bound proved on the exact compilation is then about
another problem, so every LMI coefficient, every linear row and the objective must round to the
IR's (to ``1e-9`` relative: the exact and the float values differ by the rounding of ``bind``).

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> from fractions import Fraction
>>> from types import SimpleNamespace
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
>>> p = Problem([Variable("t", "scalar", (1, 1))], [], LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
>>> mismatch(SimpleNamespace(lmis=[], linear=[], objective=[Fraction(0), Fraction(1)]), p) is None
True
>>> mismatch(SimpleNamespace(lmis=[], linear=[], objective=[Fraction(0), Fraction(2)]), p)
"the exact compilation's objective differs from the IR's"
"""

from __future__ import annotations

from typing import Any

import numpy as np

from lmic.ir.problem import Problem

__all__ = ["mismatch", "MATCH_RTOL"]

#: relative difference allowed between an exact coefficient and the IR's float
MATCH_RTOL = 1e-9


def _differs(got: np.ndarray, want: np.ndarray) -> bool:
    scale = max(1.0, float(np.max(np.abs(want), initial=0.0)))
    return got.shape != want.shape or float(np.max(np.abs(got - want), initial=0.0)) > MATCH_RTOL * scale


def mismatch(ex: Any, problem: Problem) -> str | None:
    """``None`` when ``ex`` (an :class:`lmic.compile.exact.ExactProblem`) rounds to ``problem``,
    else what differs."""
    if len(ex.lmis) != len(problem.lmis) or len(ex.linear) != len(problem.linear):
        return "the theorem's exact compilation does not match the IR"
    for e, lmi in zip(ex.lmis, problem.lmis, strict=True):
        if e.dim != lmi.dim or e.indptr.size != lmi.coeffs.shape[1] + 1:
            return f"LMI '{lmi.name}' of the exact compilation does not match the IR"
        D = abs(e.rounded() - lmi.coeffs.tocsc())
        scale = max(1.0, float(abs(lmi.coeffs).max()) if lmi.coeffs.nnz else 1.0)
        if D.nnz and float(D.max()) > MATCH_RTOL * scale:
            return f"LMI '{lmi.name}' of the exact compilation differs from the IR's"
    if len(problem.linear):
        A = problem.linear.A.tocsr()
        for r, row in enumerate(ex.linear):
            want = A[r].toarray().ravel()
            got = np.zeros_like(want)
            for k, v in row.items():
                got[int(k)] += float(v)
            if _differs(got, want):
                return f"row '{problem.linear.names[r]}' of the exact compilation differs from the IR's"
    want = np.asarray(problem.objective.c, dtype=float).ravel()
    if _differs(np.array([float(v) for v in ex.objective]), want):
        return "the exact compilation's objective differs from the IR's"
    return None
