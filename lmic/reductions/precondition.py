"""Diagonal congruence ``D F(x) D`` of every LMI at a reference point (a reduction pass).

A congruence with a positive diagonal ``D`` keeps exactly the same feasible ``x`` (strict and
non-strict); it only equilibrates the blocks for the solver (LMIs whose blocks differ by
``1e12`` near a supremum: ``-rho I`` against ``P``). ``D = diag(F(x_ref))^-1/2``; a dual ``Z``
of the scaled LMI is ``D Z D`` for the original one (:func:`unscale_duals`, the inverse).

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
>>> p = Problem([Variable("p", "scalar", (1, 1))], [LMI("p > 0", 1, sp.csc_matrix([[0., 1.]]))],
...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
>>> q, inverse = apply(p, np.array([4.0]))
>>> float(q.lmis[0].matrix([4.0])[0, 0])
1.0
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import numpy as np
import scipy.sparse as sp

from lmic.ir.problem import Problem
from lmic.ir.svec import tril_rows_cols
from lmic.solution import Solution

__all__ = ["apply", "precondition", "unscale_duals"]


def precondition(problem: Problem, x_ref: np.ndarray, floor: float = 1e-12) -> tuple[Problem, list[np.ndarray]]:
    """Each LMI ``F`` replaced by ``D F D``, ``D = diag(F(x_ref))^-1/2``; returns the ``D`` too.

    Diagonal entries below ``floor * max`` are clipped.

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("p", "scalar", (1, 1))], [LMI("p > 0", 1, sp.csc_matrix([[0., 1.]]))],
    ...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
    >>> q, ds = precondition(p, np.array([4.0]))
    >>> float(ds[0][0])
    0.5
    """
    lmis, scales = [], []
    for lmi in problem.lmis:
        diag = np.abs(np.diag(lmi.matrix(x_ref)))
        top = float(diag.max()) if diag.size else 0.0
        if not np.isfinite(top) or top <= 0:
            d = np.ones(lmi.dim)
        else:
            d = 1.0 / np.sqrt(np.maximum(diag, floor * top))
        i, j = tril_rows_cols(lmi.dim)
        lmis.append(replace(lmi, coeffs=sp.diags(d[i] * d[j]) @ lmi.coeffs))
        scales.append(d)
    return replace(problem, lmis=lmis), scales


def unscale_duals(sol: Solution, scales: list[np.ndarray]) -> None:
    """Map the LMI duals / Farkas blocks of a preconditioned solve back: ``Z -> D Z D``.

    >>> s = Solution("infeasible", farkas={"lmis": [np.eye(1)], "linear": []})
    >>> unscale_duals(s, [np.array([0.5])]); float(s.farkas["lmis"][0][0, 0])
    0.25
    """
    for holder in (sol.duals, sol.farkas):
        if not holder or holder.get("lmis") is None:
            continue
        mats = list(holder["lmis"])
        for k, d in enumerate(scales[: len(mats)]):
            if mats[k] is not None:
                Z = np.asarray(mats[k], dtype=float)
                mats[k] = d[:, None] * Z * d[None, :]
        holder["lmis"] = mats


def apply(problem: Problem, x_ref: np.ndarray) -> tuple[Problem, Callable[[Solution], Solution]]:
    """The pass: the preconditioned problem and the inverse (duals mapped back; ``x`` unchanged).

    >>> from lmic.testing.conformance import lyapunov_problem
    >>> q, inverse = apply(lyapunov_problem(-np.eye(1)), np.array([2.0]))
    >>> inverse(Solution("optimal", x=np.array([1.0]))).x.tolist()
    [1.0]
    """
    reduced, scales = precondition(problem, x_ref)

    def inverse(sol: Solution) -> Solution:
        unscale_duals(sol, scales)
        return sol

    return reduced, inverse
