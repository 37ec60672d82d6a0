"""PICOS as a backend in its own right (it picks its own SDP solver, CVXOPT here by default).

The IR becomes one PICOS real variable ``x`` and, per LMI, one affine matrix expression built
directly from its coefficient matrix (``picos.AffineExpression(name, (d, d), {x: M, (): m0})``
with ``M`` the full column-major vectorisation :func:`lmic.backends.base.full_vec_map`), so
PICOS sees the LMI as written with no per-entry expression building. Linear rows are one
affine vector each for ``>= 0`` and ``== 0``.

Examples
--------
>>> PICOSBackend.name
'picos'
"""

from __future__ import annotations

import time
from typing import ClassVar

import numpy as np

from lmic.backends.base import Backend, SolveOptions, full_vec_map
from lmic.backends.cvxopt import to_cvxopt_sparse
from lmic.ir.problem import Problem
from lmic.solution import Solution

__all__ = ["PICOSBackend"]


class PICOSBackend(Backend):
    """PICOS modelling layer; the SDP solver is PICOS's choice unless ``extra={"solver": ...}``."""

    name: ClassVar[str] = "picos"
    requires: ClassVar[dict[str, str]] = {"picos": "picos", "cvxopt": "cvxopt"}
    full_rank: ClassVar[bool] = True
    description: ClassVar[str] = "PICOS modelling layer (solver chosen by PICOS, CVXOPT here)"
    #: PICOS reports a problem status and a primal/dual solution status; keys are
    #: "<problem status>/<primal status>"
    STATUS_MAP: ClassVar[dict[str, str]] = {
        "feasible/optimal": "optimal",
        "feasible/feasible": "inaccurate",
        "unknown/optimal": "optimal",
        "unknown/feasible": "inaccurate",
        "feasible/unknown": "inaccurate",
        "infeasible/infeasible": "infeasible",
        "infeasible/unknown": "infeasible",
        "infeasible/empty": "infeasible",
        "unbounded/unknown": "unbounded",
        "unbounded/empty": "unbounded",
        "unbounded/infeasible": "unbounded",
        "unbounded/feasible": "unbounded",
    }

    def _solve(self, problem: Problem, options: SolveOptions) -> Solution:
        import cvxopt
        import picos
        from picos.expressions import AffineExpression

        n = problem.n
        P = picos.Problem()
        x = picos.RealVariable("x", n)
        lmi_cons = []
        for k, lmi in enumerate(problem.lmis):
            M = (full_vec_map(lmi.dim) @ lmi.coeffs).tocsc()
            expr = AffineExpression(
                f"F{k}",
                (lmi.dim, lmi.dim),
                {x: to_cvxopt_sparse(M[:, 1:]), (): cvxopt.matrix(M[:, 0].toarray().ravel())},
            )
            lmi_cons.append(P.add_constraint(expr >> 0))
        lin = problem.linear
        kinds = np.asarray(lin.kinds, dtype=object)
        eq = np.flatnonzero(kinds == "eq") if len(lin) else np.zeros(0, dtype=int)
        ge = np.flatnonzero(kinds == "ge") if len(lin) else np.zeros(0, dtype=int)
        row_cons = {}
        for key, rows in (("eq", eq), ("ge", ge)):
            if len(rows):
                Ar = lin.A[rows].tocsc()
                expr = AffineExpression(
                    key,
                    (len(rows), 1),
                    {x: to_cvxopt_sparse(Ar[:, 1:]), (): cvxopt.matrix(Ar[:, 0].toarray().ravel())},
                )
                row_cons[key] = P.add_constraint(expr == 0 if key == "eq" else expr >= 0)
        sign = -1.0 if problem.objective.sense == "max" else 1.0
        if problem.objective.sense != "feasibility":
            c = picos.Constant("c", cvxopt.matrix(sign * problem.objective.c[1:]), (1, n))
            P.set_objective("min", c * x)
        opts = {
            "verbosity": 1 if options.verbose else 0,
            "primals": None,
            "duals": None,
            "abs_prim_fsb_tol": options.tol,
            "abs_dual_fsb_tol": options.tol,
            "abs_ipm_opt_tol": options.tol,
            "rel_ipm_opt_tol": options.tol,
        }
        # PICOS's default is no limit, which it passes to CVXOPT as maxiters = 1e6: on a problem
        # whose iterates diverge CVXOPT then runs ~100 s into a ZeroDivisionError. CVXOPT's
        # own default (100) is used unless the caller sets one.
        opts["max_iterations"] = int(options.max_iter) if options.max_iter is not None else 100
        if options.time_limit is not None:
            opts["timelimit"] = int(max(1, round(options.time_limit)))
        opts.update(options.extra)
        t0 = time.perf_counter()
        solution = P.solve(**opts)
        wall = time.perf_counter() - t0
        native = f"{solution.problemStatus}/{solution.primalStatus}"
        status = self.map_status(native)
        sol = Solution(
            status=status,
            backend=self.label,
            native_status=native,
            solve_s=wall,
            info={"picos_solver": solution.solver, "solver_time_s": solution.searchTime},
        )

        def multipliers() -> dict | None:
            duals = solution.duals
            if any(duals.get(con) is None for con in lmi_cons + list(row_cons.values())):
                return None
            y = np.zeros(len(lin))
            if "eq" in row_cons:
                y[eq] = np.array(duals[row_cons["eq"]]).ravel()
            if "ge" in row_cons:
                y[ge] = np.array(duals[row_cons["ge"]]).ravel()
            mats = [np.array(duals[con], dtype=float) for con in lmi_cons]
            return {"lmis": [0.5 * (Z + Z.T) for Z in mats], "linear": y}

        value = solution.primals.get(x) if solution.primals else None
        if status in ("optimal", "inaccurate") and value is not None:
            sol.x = np.array(value, dtype=float).ravel()
            if problem.objective.sense != "feasibility":
                sol.objective = float(problem.objective.value(sol.x))
            sol.duals = multipliers() or {}
        elif status == "infeasible":
            sol.farkas = multipliers()
        elif status in ("optimal", "inaccurate"):
            sol.status = "error"
            sol.message = f"PICOS reported '{native}' without a primal point"
        if status == "error":
            sol.message = f"PICOS returned '{native}' ({solution.claimedStatus})"
        return sol
