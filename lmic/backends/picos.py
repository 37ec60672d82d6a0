"""PICOS as a backend in its own right (it picks its own SDP solver, CVXOPT here by default).

The IR becomes one PICOS real variable ``x`` and, per LMI, one affine matrix expression built
directly from its coefficient matrix (``picos.AffineExpression(name, (d, d), {x: M, (): m0})``
with ``M`` the full column-major vectorisation :func:`lmic.backends.base.full_vec_map`), so
PICOS sees the LMI as written with no per-entry expression building. Linear rows are one
affine vector each for ``>= 0`` and ``== 0``.

PICOS reports a *problem* status and a claimed *primal* status (``picos.modeling.solution``:
``PS_*`` and ``SS_*``); the native status is ``"<problem>/<primal>"`` and
:attr:`PICOSBackend.STATUS_MAP` lists every pair lmic understands (any other pair is
``error``). With CVXOPT underneath, PICOS turns CVXOPT's ``unknown`` (iteration limit or
numerical trouble; CVXOPT still returns its last iterate) into ``unknown/unknown``: that point
is kept as ``inaccurate`` and the certifier decides, exactly as the ``cvxopt`` backend does.

PICOS's own CVXOPT call tries the ``chol`` KKT solver and then ``ldl``; ``ldl`` divides by zero
inside CVXOPT on SDPLIB control1 (``ZeroDivisionError`` in ``misc.update_scaling``). This
backend follows the ``cvxopt`` backend instead: ``chol`` first, ``qr`` when ``chol`` fails or
stops ``unknown`` (``extra={"cvxopt_kktsolver": ...}`` chooses one). PICOS has no time limit
for CVXOPT, so ``SolveOptions.time_limit`` is enforced by the child-process sandbox.

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
    #: ``"<problem status>/<claimed primal status>"`` -> lmic status; unlisted pairs are ``error``
    STATUS_MAP: ClassVar[dict[str, str]] = {
        "feasible/optimal": "optimal",
        "unknown/optimal": "optimal",
        "feasible/feasible": "inaccurate",
        "unknown/feasible": "inaccurate",
        "feasible/unknown": "inaccurate",
        "feasible/premature": "inaccurate",
        "unknown/premature": "inaccurate",
        # CVXOPT's 'unknown' with its last iterate: kept when there is a point (else error)
        "unknown/unknown": "inaccurate",
        "infeasible/infeasible": "infeasible",
        "infeasible/unknown": "infeasible",
        "infeasible/empty": "infeasible",
        "unbounded/unknown": "unbounded",
        "unbounded/empty": "unbounded",
        "unbounded/infeasible": "unbounded",
        "unbounded/feasible": "unbounded",
        "infeasible or unbounded/unknown": "error",
        "infeasible or unbounded/empty": "error",
        "unknown/empty": "error",
        "unknown/failure": "error",
        "unstable/unknown": "error",
        "illposed/unknown": "error",
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
            # CVXOPT's feastol is min(rel_prim_fsb_tol, rel_dual_fsb_tol); abstol, reltol the
            # ipm tolerances: the same settings as the cvxopt backend
            "abs_prim_fsb_tol": options.tol,
            "abs_dual_fsb_tol": options.tol,
            "rel_prim_fsb_tol": options.tol,
            "rel_dual_fsb_tol": options.tol,
            "abs_ipm_opt_tol": options.tol,
            "rel_ipm_opt_tol": options.tol,
        }
        # PICOS's default is no limit, which it passes to CVXOPT as maxiters = 1e6: on a problem
        # whose iterates diverge CVXOPT then runs ~100 s into a ZeroDivisionError. CVXOPT's
        # own default (100) is used unless the caller sets one.
        opts["max_iterations"] = int(options.max_iter) if options.max_iter is not None else 100
        opts.update(options.extra)
        chosen = opts.pop("cvxopt_kktsolver", None)
        kkt_order = [chosen] if chosen else ["chol", "qr"]
        t0 = time.perf_counter()
        for k, kktsolver in enumerate(kkt_order):
            last = k == len(kkt_order) - 1
            try:
                solution = P.solve(cvxopt_kktsolver=kktsolver, **opts)
            except (ValueError, ArithmeticError):
                if last:
                    raise
                continue
            if solution.problemStatus != "unknown" or last:
                break
        wall = time.perf_counter() - t0
        native = f"{solution.problemStatus}/{solution.primalStatus}"
        status = self.map_status(native)
        sol = Solution(
            status=status,
            backend=self.label,
            native_status=native,
            solve_s=wall,
            info={
                "picos_solver": solution.solver,
                "solver_time_s": solution.searchTime,
                "kktsolver": kktsolver,
                "claimed": solution.claimedStatus,
            },
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
                sol.objective = problem.objective.value(sol.x)
            sol.duals = multipliers() or {}
        elif status == "infeasible":
            sol.farkas = multipliers()
        elif status in ("optimal", "inaccurate"):
            sol.status = "error"
            sol.message = f"PICOS reported '{native}' without a primal point"
        if sol.status == "inaccurate" and not sol.message:
            sol.message = f"PICOS returned '{native}' (claimed {solution.claimedStatus}); the point is checked"
        if status == "error":
            sol.message = f"PICOS returned '{native}' (claimed {solution.claimedStatus})"
        return sol
