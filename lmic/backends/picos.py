"""PICOS as a backend in its own right (it picks its own SDP solver, CVXOPT here by default).

The IR becomes one PICOS real variable ``x`` and, per LMI, one affine matrix expression built
directly from its coefficient matrix (``picos.AffineExpression(name, (d, d), {x: M, (): m0})``
with ``M`` the full column-major vectorisation of :class:`lmic.backends.lowering.LMIForm`), so
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
from typing import Any, ClassVar

import numpy as np

from lmic.backends.backend import KKT_ORDER, Backend, in_turn
from lmic.backends.cvxopt import to_cvxopt_sparse
from lmic.backends.lowering import LMIForm
from lmic.backends.results import NativeResult
from lmic.ir.problem import Problem
from lmic.options import SolveOptions

__all__ = ["PICOSBackend"]


class PICOSBackend(Backend):
    """PICOS modelling layer; the SDP solver is PICOS's choice unless ``extra={"solver": ...}``."""

    name: ClassVar[str] = "picos"
    title: ClassVar[str] = "PICOS"
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

    def settings(self, options: SolveOptions) -> dict[str, Any]:
        """PICOS solve options from the uniform ones (``extra`` verbatim, last)."""
        opts: dict[str, Any] = {
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
            # PICOS's default is no limit, which it passes to CVXOPT as maxiters = 1e6: on a problem
            # whose iterates diverge CVXOPT then runs ~100 s into a ZeroDivisionError. CVXOPT's
            # own default (100) is used unless the caller sets one.
            "max_iterations": int(options.max_iter) if options.max_iter is not None else 100,
        }
        opts.update(options.extra)
        return opts

    def call(self, problem: Problem, settings: dict[str, Any]) -> NativeResult:
        """Build the PICOS problem from the LMI form, solve it (``chol``, then ``qr``), read its multipliers."""
        import cvxopt
        import picos
        from picos.expressions import AffineExpression

        data = LMIForm.apply(problem)
        P = picos.Problem()
        x = picos.RealVariable("x", problem.n)
        lmi_cons = []
        for k, (F0, G) in enumerate(zip(data.F0, data.G, strict=True)):
            d = F0.shape[0]
            expr = AffineExpression(f"F{k}", (d, d), {x: to_cvxopt_sparse(G), (): cvxopt.matrix(F0.ravel(order="F"))})
            lmi_cons.append(P.add_constraint(expr >> 0))
        row_cons = {}
        for key, A in (("eq", data.A_eq), ("ge", data.A_ge)):
            if A.shape[0]:
                expr = AffineExpression(
                    key, (A.shape[0], 1), {x: to_cvxopt_sparse(A[:, 1:]), (): cvxopt.matrix(A[:, 0].toarray().ravel())}
                )
                row_cons[key] = P.add_constraint(expr == 0 if key == "eq" else expr >= 0)
        if problem.objective.sense != "feasibility":
            P.set_objective("min", picos.Constant("c", cvxopt.matrix(data.c), (1, problem.n)) * x)
        opts = dict(settings)
        chosen = opts.pop("cvxopt_kktsolver", None)
        t0 = time.perf_counter()
        solution, kktsolver = in_turn(
            [chosen] if chosen else KKT_ORDER,
            lambda kkt: P.solve(cvxopt_kktsolver=kkt, **opts),
            lambda s: s.problemStatus == "unknown",
        )
        wall = time.perf_counter() - t0
        native = f"{solution.problemStatus}/{solution.primalStatus}"
        found = solution.duals or {}
        duals = None
        if all(found.get(con) is not None for con in lmi_cons + list(row_cons.values())):
            y = {key: np.array(found[con]).ravel() for key, con in row_cons.items()}
            duals = LMIForm.invert(data, [found[con] for con in lmi_cons], y.get("eq"), y.get("ge"))
        value = solution.primals.get(x) if solution.primals else None
        claimed = f"{native}' (claimed {solution.claimedStatus})"
        status = self.map_status(native)
        message = ""
        if status == "error":
            message = f"PICOS returned '{claimed}"
        elif status == "inaccurate" and value is not None:
            message = f"PICOS returned '{claimed}; the point is checked"
        elif status in ("optimal", "inaccurate"):
            message = f"PICOS reported '{native}' without a primal point"
        return NativeResult(
            native,
            x=None if value is None else np.array(value, dtype=float),
            duals=duals,
            solve_s=wall,
            info={
                "picos_solver": solution.solver,
                "solver_time_s": solution.searchTime,
                "kktsolver": kktsolver,
                "claimed": solution.claimedStatus,
            },
            message=message,
        )
