"""CVXPY as a backend in its own right, with the conic solver selectable (``cvxpy:SCS``).

The IR is rebuilt as one vector variable ``x`` and, per LMI, one affine matrix expression
``reshape(M_k x + m_0, (d, d))`` constrained ``>> 0`` (CVXPY's PSD constraint, which its
conic interfaces vectorise straight into the solver's PSD cone: no variable copies). ``M`` is
the full column-major vectorisation :func:`lmic.backends.base.full_vec_map` of the IR's
coefficients. Linear rows are ``A x + a0 >= 0`` and ``== 0``. Default sub-solver: CLARABEL;
``cvxpy:SCS``, ``cvxpy:CVXOPT``, ``cvxpy:SDPA`` select another.

Examples
--------
>>> CVXPYBackend("SCS").label
'cvxpy:SCS'
"""

from __future__ import annotations

import time
import warnings
from typing import Any, ClassVar

import numpy as np

from lmic.backends.base import Backend, SolveOptions, full_vec_map, quiet_native
from lmic.backends.outcomes import settle_inexact_infeasible
from lmic.errors import BackendUnavailable
from lmic.ir.problem import Problem
from lmic.solution import Solution

__all__ = ["CVXPYBackend", "SUBSOLVER_OPTIONS"]


def _clarabel(o: SolveOptions) -> dict[str, Any]:
    # chordal decomposition off: see lmic.backends.clarabel (wrong "Solved" on control1)
    out: dict[str, Any] = {
        "tol_gap_abs": o.tol,
        "tol_gap_rel": o.tol,
        "tol_feas": o.tol,
        "chordal_decomposition_enable": False,
    }
    if o.max_iter is not None:
        out["max_iter"] = o.max_iter
    if o.time_limit is not None:
        out["time_limit"] = o.time_limit
    return out


def _scs(o: SolveOptions) -> dict[str, Any]:
    out: dict[str, Any] = {"eps_abs": o.tol, "eps_rel": o.tol}
    if o.max_iter is not None:
        out["max_iters"] = o.max_iter
    if o.time_limit is not None:
        out["time_limit_secs"] = o.time_limit
    return out


def _cvxopt(o: SolveOptions) -> dict[str, Any]:
    out: dict[str, Any] = {"abstol": o.tol, "reltol": o.tol, "feastol": o.tol}
    if o.max_iter is not None:
        out["max_iters"] = o.max_iter
    return out


def _sdpa(o: SolveOptions) -> dict[str, Any]:
    out: dict[str, Any] = {"epsilonStar": max(o.tol, 1e-6), "epsilonDash": max(o.tol, 1e-7)}
    if o.max_iter is not None:
        out["maxIteration"] = o.max_iter
    return out


def _cvxopt_qr(c: Any, G: Any, h: Any, dims: Any, A: Any, b: Any) -> Any:
    """CVXOPT's 'qr' KKT solver in the form CVXPY accepts for ``kktsolver`` (a factory)."""
    from cvxopt import misc

    return misc.kkt_qr(G, dims, A)


#: how the uniform options map onto each CVXPY sub-solver's keyword arguments
SUBSOLVER_OPTIONS = {"CLARABEL": _clarabel, "SCS": _scs, "CVXOPT": _cvxopt, "SDPA": _sdpa}
_NATIVE_LIMIT = {"CLARABEL", "SCS"}


class CVXPYBackend(Backend):
    """CVXPY with a selectable conic solver (``cvxpy:CLARABEL`` by default)."""

    name: ClassVar[str] = "cvxpy"
    requires: ClassVar[dict[str, str]] = {"cvxpy": "cvxpy"}
    variants: ClassVar[tuple[str, ...]] = tuple(SUBSOLVER_OPTIONS)
    description: ClassVar[str] = "CVXPY modelling layer; cvxpy:CLARABEL (default), :SCS, :CVXOPT, :SDPA"
    STATUS_MAP: ClassVar[dict[str, str]] = {
        "optimal": "optimal",
        "optimal_inaccurate": "inaccurate",
        "infeasible": "infeasible",
        # an inexact infeasibility claim: kept only if its ray verifies (settle_inexact_infeasible)
        "infeasible_inaccurate": "inaccurate",
        "unbounded": "unbounded",
        "unbounded_inaccurate": "inaccurate",
        "infeasible_or_unbounded": "error",
        # an iteration or time limit with the last iterate (SOLUTION_PRESENT): the certifier decides
        "user_limit": "inaccurate",
        "solver_error": "error",
    }

    def __init__(self, variant: str | None = None) -> None:
        solver = (variant or "CLARABEL").upper()
        if solver not in SUBSOLVER_OPTIONS:
            raise BackendUnavailable(
                f"cvxpy sub-solver '{variant}' is not supported; choose one of "
                f"{', '.join('cvxpy:' + s for s in SUBSOLVER_OPTIONS)}"
            )
        self.variant = solver
        self.solver = solver
        self.native_time_limit = solver in _NATIVE_LIMIT  # type: ignore[misc]
        self.interior_point = solver != "SCS"  # type: ignore[misc]
        self.full_rank = solver in ("CVXOPT", "SDPA")  # type: ignore[misc]
        self.tol_floor = 1e-6 if solver == "SCS" else 0.0  # type: ignore[misc]  # as the scs backend

    @property
    def label(self) -> str:
        return f"cvxpy:{self.solver}"

    def missing_packages(self) -> list[str]:
        missing = super().missing_packages()
        if missing:
            return missing
        import cvxpy as cp

        if self.solver not in cp.installed_solvers():
            pkg = {"CLARABEL": "clarabel", "SCS": "scs", "CVXOPT": "cvxopt", "SDPA": "sdpa-python"}
            return [pkg[self.solver]]
        return []

    def _solve(self, problem: Problem, options: SolveOptions) -> Solution:
        import cvxpy as cp

        t_build = time.perf_counter()
        n = problem.n
        x = cp.Variable(n, name="x")
        lmi_cons = []
        for lmi in problem.lmis:
            M = (full_vec_map(lmi.dim) @ lmi.coeffs).tocsc()
            vec = M[:, 1:] @ x + M[:, 0].toarray().ravel()
            lmi_cons.append(cp.reshape(vec, (lmi.dim, lmi.dim), order="F") >> 0)
        lin = problem.linear
        kinds = np.asarray(lin.kinds, dtype=object)
        eq = np.flatnonzero(kinds == "eq") if len(lin) else np.zeros(0, dtype=int)
        ge = np.flatnonzero(kinds == "ge") if len(lin) else np.zeros(0, dtype=int)
        row_cons = []
        if len(eq):
            Aeq = lin.A[eq].tocsc()
            row_cons.append(Aeq[:, 1:] @ x + Aeq[:, 0].toarray().ravel() == 0)
        if len(ge):
            Age = lin.A[ge].tocsc()
            row_cons.append(Age[:, 1:] @ x + Age[:, 0].toarray().ravel() >= 0)
        sign = -1.0 if problem.objective.sense == "max" else 1.0
        if problem.objective.sense == "feasibility":
            objective = cp.Minimize(0)
        else:
            objective = cp.Minimize(sign * problem.objective.c[1:] @ x)
        prob = cp.Problem(objective, lmi_cons + row_cons)
        kwargs = SUBSOLVER_OPTIONS[self.solver](options)
        kwargs.update(options.extra)
        build_s = time.perf_counter() - t_build
        # CVXPY calls CVXOPT with the 'chol' KKT solver and turns CVXOPT's failures into
        # solver_error; like the cvxopt backend, 'qr' is tried next (given to CVXPY as a KKT
        # factory), which solves SDPLIB control1 and the bounded-real lemma where 'chol' fails
        attempts: list[Any] = [None]
        if self.solver == "CVXOPT" and "kktsolver" not in kwargs:
            attempts = ["chol", _cvxopt_qr]
        t0 = time.perf_counter()
        for kkt in attempts:
            if kkt is not None:
                kwargs["kktsolver"] = kkt
            try:
                with quiet_native(not options.verbose), warnings.catch_warnings():
                    warnings.simplefilter("ignore", UserWarning)  # "may be inaccurate": a status
                    prob.solve(solver=self.solver, verbose=options.verbose, **kwargs)
                native = str(prob.status)
                message = ""
            except cp.error.SolverError as err:
                native, message = "solver_error", " ".join(str(err).split())
            if native != "solver_error":
                break
        wall = time.perf_counter() - t0
        stats = prob.solver_stats
        solver_s = getattr(stats, "solve_time", None) if stats is not None else None
        status = self.map_status(native)
        sol = Solution(
            status=status,
            backend=self.label,
            native_status=native,
            message=message,
            solve_s=wall,
            iterations=getattr(stats, "num_iters", None) if stats is not None else None,
            info={
                "cvxpy_build_s": build_s,
                "solver_time_s": solver_s,
                "cvxpy_compile_s": getattr(prob, "compilation_time", None),
            },
        )

        def multipliers() -> dict | None:
            if any(con.dual_value is None for con in lmi_cons + row_cons):
                return None
            y = np.zeros(len(lin))
            k = 0
            if len(eq):
                y[eq] = -np.asarray(row_cons[k].dual_value, dtype=float).ravel()
                k += 1
            if len(ge):
                y[ge] = np.asarray(row_cons[k].dual_value, dtype=float).ravel()
            mats = [np.asarray(con.dual_value, dtype=float) for con in lmi_cons]
            return {"lmis": [0.5 * (Z + Z.T) for Z in mats], "linear": y}

        if native == "infeasible_inaccurate":
            settle_inexact_infeasible(problem, sol, multipliers())
        elif native == "unbounded_inaccurate":
            sol.message = f"CVXPY/{self.solver} returned status '{native}' (inexact unboundedness claim)"
        elif status in ("optimal", "inaccurate") and x.value is not None:
            sol.x = np.asarray(x.value, dtype=float)
            if problem.objective.sense != "feasibility":
                sol.objective = problem.objective.value(sol.x)
            sol.duals = multipliers() or {}
        elif status == "infeasible":
            sol.farkas = multipliers()
        if status in ("error", "inaccurate") and not sol.message:
            sol.message = f"CVXPY/{self.solver} returned status '{native}'"
        return sol
