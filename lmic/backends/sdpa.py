"""SDPA through sdpa-python (``import sdpap``): the LMI form solved natively.

``sdpap.solve(A, b, c, K, J, option)`` takes a conic problem in SeDuMi form, primal
``min c'xi`` s.t. ``A xi - b in J``, ``xi in K`` and dual ``max b'y`` s.t. ``c - A'y in K*``.
With ``J = SymCone(f=n)`` (equalities) the *dual* is the IR's LMI form, so the decision vector
``x`` is SDPA's ``y`` and nothing is copied or slacked:

* ``b = -c_obj`` (``max -c'x``),
* ``c = [a0_eq; a0_ge; vec F0_1; ...]`` and ``A' = -[a_eq; a_ge; vec F_k ...]`` with
  ``K = SymCone(f=#eq, l=#ge, s=(d_1, ...))``, PSD blocks as full column-major ``d*d`` vectors
  (:func:`lmic.backends.base.full_vec_map`, the one conversion place);
* SDPA's primal ``xi`` are the IR's multipliers ``(y_eq, y_ge, vec Z_i)``.

The phase value sdpa-python reports refers to the SeDuMi *primal* (the IR's dual):
``pUNBD``/``pFEAS_dINF`` mean the LMIs are infeasible, ``dUNBD``/``pINF_dFEAS`` that the IR
problem is unbounded. SDPA works in double precision and stalls ("primal < dual") at relative
gaps of a few 1e-7, so its gap tolerance is floored at :data:`TOL_FLOOR` (``pdFEAS``, a point
short of the gap tolerance, is ``inaccurate``). SDPA has no time limit of its own: with
``SolveOptions.time_limit`` the solve runs in a child process.

Examples
--------
>>> SDPABackend.name
'sdpa'
"""

from __future__ import annotations

import time
import warnings
from typing import ClassVar

import numpy as np
import scipy.sparse as sp

from lmic.backends.base import Backend, SolveOptions, full_vec_map, quiet_native
from lmic.ir.problem import Problem
from lmic.solution import Solution

__all__ = ["SDPABackend", "sdpa_data", "TOL_FLOOR"]

#: SDPA's tolerances are never set below this (its double-precision limit)
TOL_FLOOR = 1e-6


def sdpa_data(problem: Problem) -> tuple[sp.csc_matrix, np.ndarray, np.ndarray, dict]:
    """SeDuMi-form data ``(A, b, c, layout)`` whose dual is ``problem``'s LMI form.

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("t", "scalar", (1, 1))], [LMI("t>=1", 1, sp.csc_matrix([[-1., 1.]]),
    ...             strict=False)], LinearConstraints.empty(1), Objective("min", [0, 1]))
    >>> A, b, c, layout = sdpa_data(p)
    >>> A.toarray(), b, c
    (array([[-1.]]), array([-1.]), array([-1.]))
    """
    lin = problem.linear
    kinds = np.asarray(lin.kinds, dtype=object)
    eq = np.flatnonzero(kinds == "eq") if len(lin) else np.zeros(0, dtype=int)
    ge = np.flatnonzero(kinds == "ge") if len(lin) else np.zeros(0, dtype=int)
    blocks = [lin.A[eq], lin.A[ge]]
    blocks += [full_vec_map(lmi.dim) @ lmi.coeffs for lmi in problem.lmis]
    M = sp.vstack(blocks, format="csc")
    c = M[:, 0].toarray().ravel()
    A = (-M[:, 1:]).T.tocsc()
    sign = -1.0 if problem.objective.sense == "max" else 1.0
    if problem.objective.sense == "feasibility":
        b = np.zeros(problem.n)
    else:
        b = -sign * problem.objective.c[1:]
    layout = {"eq": eq, "ge": ge, "dims": [lmi.dim for lmi in problem.lmis]}
    return A, np.asarray(b, dtype=float), c, layout


class SDPABackend(Backend):
    """SDPA (primal-dual interior point) through sdpa-python, LMI form."""

    name: ClassVar[str] = "sdpa"
    requires: ClassVar[dict[str, str]] = {"sdpap": "sdpa-python"}
    full_rank: ClassVar[bool] = True
    description: ClassVar[str] = "SDPA interior point via sdpa-python (LMI form)"
    STATUS_MAP: ClassVar[dict[str, str]] = {
        "pdOPT": "optimal",
        "pdFEAS": "inaccurate",
        "pFEAS": "inaccurate",
        "dFEAS": "inaccurate",
        "pFEAS_dINF": "infeasible",
        "pUNBD": "infeasible",
        "pINF_dFEAS": "unbounded",
        "dUNBD": "unbounded",
        "pdINF": "infeasible",
        "noINFO": "error",
    }

    def _options(self, options: SolveOptions) -> dict:
        opts: dict = {
            "print": "display" if options.verbose else "no",
            "epsilonStar": max(float(options.tol), TOL_FLOOR),
            "epsilonDash": max(float(options.tol), 1e-7),
        }
        if options.max_iter is not None:
            opts["maxIteration"] = int(options.max_iter)
        opts.update(options.extra)
        return opts

    def _solve(self, problem: Problem, options: SolveOptions) -> Solution:
        import sdpap

        A, b, c, layout = sdpa_data(problem)
        eq, ge, dims = layout["eq"], layout["ge"], layout["dims"]
        K = sdpap.SymCone(f=len(eq), l=len(ge), s=tuple(dims))
        J = sdpap.SymCone(f=problem.n)
        t0 = time.perf_counter()
        with quiet_native(not options.verbose), warnings.catch_warnings():
            # sdpa-python recomputes feasibility errors with scipy eigs and warns on tiny blocks
            warnings.simplefilter("ignore", RuntimeWarning)
            xi, y, _pinfo, _tinfo, info = sdpap.solve(A, b, c, K, J, self._options(options))
        solve_s = time.perf_counter() - t0
        native = str(info.get("phasevalue", "noINFO"))
        status = self.map_status(native)
        sol = Solution(
            status=status,
            backend=self.label,
            native_status=native,
            solve_s=solve_s,
            iterations=int(info.get("iteration", 0)),
        )
        xi = np.asarray(xi.toarray() if sp.issparse(xi) else xi, dtype=float).ravel()
        x = np.asarray(y.toarray() if sp.issparse(y) else y, dtype=float).ravel()
        mult = self._multipliers(xi, layout, len(problem.linear))
        if status in ("optimal", "inaccurate"):
            sol.x = x
            if problem.objective.sense != "feasibility":
                sol.objective = problem.objective.value(x)
            sol.duals = mult
            if status == "inaccurate":
                sol.message = f"SDPA stopped with phase {native}"
        elif status == "infeasible":
            # SDPA detects infeasibility by a diverging dual: scale it into a Farkas ray
            gap = float(c @ xi)
            if gap < 0:
                mult = {
                    "lmis": [Z / -gap for Z in mult["lmis"]],
                    "linear": mult["linear"] / -gap,
                }
            sol.farkas = mult
        elif status == "unbounded":
            sol.info["ray"] = x
        else:
            sol.message = f"SDPA stopped with phase {native}"
        return sol

    @staticmethod
    def _multipliers(xi: np.ndarray, layout: dict, n_rows: int) -> dict:
        eq, ge = layout["eq"], layout["ge"]
        y = np.zeros(n_rows)
        y[eq] = xi[: len(eq)]
        y[ge] = xi[len(eq) : len(eq) + len(ge)]
        off = len(eq) + len(ge)
        mats = []
        for d in layout["dims"]:
            Z = xi[off : off + d * d].reshape(d, d, order="F")
            mats.append(0.5 * (Z + Z.T))
            off += d * d
        return {"lmis": mats, "linear": y}
