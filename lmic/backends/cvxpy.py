"""CVXPY as a backend in its own right, with the conic solver selectable (``cvxpy:SCS``).

The IR is rebuilt as one vector variable ``x`` and, per LMI, one affine matrix expression
``reshape(M_k x + m_0, (d, d))`` constrained ``>> 0`` (CVXPY's PSD constraint, which its
conic interfaces vectorise straight into the solver's PSD cone: no variable copies). ``M`` is
the full column-major vectorisation of the IR's coefficients
(:class:`lmic.backends.lowering.LMIForm`). Linear rows are ``A x + a0 >= 0`` and ``== 0``. Default sub-solver: CLARABEL;
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

from lmic.backends.backend import KKT_ORDER, Backend, in_turn
from lmic.backends.lowering import LMIForm
from lmic.backends.quiet import quiet_native
from lmic.backends.results import NativeResult
from lmic.errors import BackendUnavailable
from lmic.ir.problem import Problem
from lmic.options import SolveOptions

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
        # an inexact infeasibility claim: kept only if its ray verifies (INEXACT_INFEASIBLE)
        "infeasible_inaccurate": "inaccurate",
        "unbounded": "unbounded",
        "unbounded_inaccurate": "inaccurate",
        "infeasible_or_unbounded": "error",
        # an iteration or time limit with the last iterate (SOLUTION_PRESENT): the certifier decides
        "user_limit": "inaccurate",
        "solver_error": "error",
    }
    INEXACT_INFEASIBLE: ClassVar[frozenset[str]] = frozenset({"infeasible_inaccurate"})
    INEXACT_UNBOUNDED: ClassVar[frozenset[str]] = frozenset({"unbounded_inaccurate"})

    def __init__(self, variant: str | None = None) -> None:
        solver = (variant or "CLARABEL").upper()
        if solver not in SUBSOLVER_OPTIONS:
            raise BackendUnavailable(
                f"cvxpy sub-solver '{variant}' is not supported; choose one of "
                f"{', '.join('cvxpy:' + s for s in SUBSOLVER_OPTIONS)}"
            )
        self.variant = solver
        self.solver = solver
        self.title = f"CVXPY/{solver}"  # type: ignore[misc]
        self.native_time_limit = solver in _NATIVE_LIMIT  # type: ignore[misc]
        self.interior_point = solver != "SCS"  # type: ignore[misc]
        self.full_rank = solver in ("CVXOPT", "SDPA")  # type: ignore[misc]
        self.tol_floor = 1e-6 if solver == "SCS" else 0.0  # type: ignore[misc]  # as the scs backend

    def too_large(self, problem: Problem) -> str | None:
        """Through CVXPY, Clarabel's dense PSD blocks as natively (:func:`lmic.backends.clarabel.memory_refusal`)."""
        if self.solver != "CLARABEL":
            return None
        from lmic.backends.clarabel import memory_refusal

        return memory_refusal(problem)

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

    def settings(self, options: SolveOptions) -> dict[str, Any]:
        """Keyword arguments of ``Problem.solve`` for the sub-solver (``extra`` verbatim, last)."""
        kwargs = SUBSOLVER_OPTIONS[self.solver](options)
        kwargs["verbose"] = bool(options.verbose)
        kwargs.update(options.extra)
        return kwargs

    def call(self, problem: Problem, settings: dict[str, Any]) -> NativeResult:
        """Build the CVXPY problem from the LMI form, solve it, read its multipliers."""
        import cvxpy as cp

        t_build = time.perf_counter()
        data = LMIForm.apply(problem)
        x = cp.Variable(problem.n, name="x")
        lmi_cons = [
            cp.reshape(G @ x + F0.ravel(order="F"), (F0.shape[0], F0.shape[0]), order="F") >> 0
            for F0, G in zip(data.F0, data.G, strict=True)
        ]
        row_cons = []
        if len(data.eq):
            row_cons.append(data.A_eq[:, 1:] @ x + data.A_eq[:, 0].toarray().ravel() == 0)
        if len(data.ge):
            row_cons.append(data.A_ge[:, 1:] @ x + data.A_ge[:, 0].toarray().ravel() >= 0)
        objective = cp.Minimize(data.c @ x) if problem.objective.sense != "feasibility" else cp.Minimize(0)
        prob = cp.Problem(objective, lmi_cons + row_cons)
        kwargs = dict(settings)
        verbose = bool(kwargs.pop("verbose", False))
        build_s = time.perf_counter() - t_build
        # CVXPY calls CVXOPT with the 'chol' KKT solver and turns CVXOPT's failures into
        # solver_error; like the cvxopt backend, 'qr' is tried next (given to CVXPY as a KKT
        # factory), which solves SDPLIB control1 and the bounded-real lemma where 'chol' fails
        attempts: list[Any] = [None]
        if self.solver == "CVXOPT" and "kktsolver" not in kwargs:
            attempts = [KKT_ORDER[0], _cvxopt_qr]

        def run(kkt: Any) -> tuple[str, str]:
            extra = {} if kkt is None else {"kktsolver": kkt}
            try:
                with quiet_native(not verbose), warnings.catch_warnings():
                    warnings.simplefilter("ignore", UserWarning)  # "may be inaccurate": a status
                    prob.solve(solver=self.solver, verbose=verbose, **kwargs, **extra)
                return str(prob.status), ""
            except cp.error.SolverError as err:
                return "solver_error", " ".join(str(err).split())

        t0 = time.perf_counter()
        (native, message), _ = in_turn(attempts, run, lambda r: r[0] == "solver_error", errors=())
        wall = time.perf_counter() - t0
        stats = prob.solver_stats
        duals = None
        if all(con.dual_value is not None for con in lmi_cons + row_cons):
            values = iter(con.dual_value for con in row_cons)
            y_eq = -np.asarray(next(values), dtype=float) if len(data.eq) else None
            y_ge = next(values) if len(data.ge) else None
            duals = LMIForm.invert(data, [con.dual_value for con in lmi_cons], y_eq, y_ge)
        return NativeResult(
            native,
            x=None if x.value is None else np.asarray(x.value, dtype=float),
            duals=duals,
            solve_s=wall,
            iterations=getattr(stats, "num_iters", None) if stats is not None else None,
            info={
                "cvxpy_build_s": build_s,
                "solver_time_s": getattr(stats, "solve_time", None) if stats is not None else None,
                "cvxpy_compile_s": getattr(prob, "compilation_time", None),
            },
            message=message,
        )
