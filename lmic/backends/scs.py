"""SCS 3.x (native Python API): a first-order (ADMM) conic solver.

SCS solves ``min c'x`` s.t. ``A x + s = b``, ``s`` in ``{0}^z x R+^l x S_1 x ...``. Its PSD cone
``s`` takes the *lower* triangle column by column with off-diagonal entries times ``sqrt(2)``,
which is the IR's storage order scaled by :func:`lmic.ir.svec.svec_scale`. The dual ``y`` gives
``Z_i`` and the row multipliers; on infeasibility SCS returns the Farkas ray normalised to
``b'y = -1``.

SCS is fast on large LMIs but only accurate to its tolerance: a point on the boundary of a
strict LMI is not certifiable, which is why strict feasibility goes through the normalised
``max-margin`` reduction (:mod:`lmic.backends.strict`).

Examples
--------
>>> SCSBackend.name, SCSBackend.interior_point
('scs', False)
"""

from __future__ import annotations

import time
from typing import ClassVar

import numpy as np

from lmic.backends.base import Backend, SolveOptions, conic_data
from lmic.backends.outcomes import mark_time_limit, settle_inexact_infeasible
from lmic.ir.problem import Problem
from lmic.ir.svec import svec_scale, tril_size, tril_unvec
from lmic.solution import Solution

__all__ = ["SCSBackend", "scs_vec", "scs_unvec"]

#: SCS's integer status codes and their names
_STATUS_NAMES = {
    1: "solved",
    2: "solved_inaccurate",
    -1: "unbounded",
    -6: "unbounded_inaccurate",
    -2: "infeasible",
    -7: "infeasible_inaccurate",
    -3: "indeterminate",
    -4: "failed",
    -5: "sigint",
    0: "unfinished",
}


def scs_vec(d: int) -> tuple[np.ndarray, np.ndarray]:
    """SCS's PSD vectorisation as ``(perm, scale)`` (storage order, ``sqrt(2)`` off-diagonal).

    >>> scs_vec(2)[1]
    array([1.        , 1.41421356, 1.        ])
    """
    return np.arange(tril_size(d)), svec_scale(d)


def scs_unvec(v: np.ndarray, d: int) -> np.ndarray:
    """Dense symmetric matrix from one SCS PSD block.

    >>> scs_unvec(np.array([1.0, np.sqrt(2), 1.0]), 2)
    array([[1., 1.],
           [1., 1.]])
    """
    return tril_unvec(np.asarray(v, dtype=float) / svec_scale(d), d)


def _warm_start(options: SolveOptions, shape: tuple[int, int]) -> dict[str, np.ndarray]:
    """SCS's ``x``, ``y``, ``s`` initial guesses from ``options.warm_start`` (a previous SCS
    solution of a problem with the same lowered shape ``(m, n)``), else ``{}`` (cold start).

    >>> _warm_start(SolveOptions(), (2, 1))
    {}
    """
    prev = getattr(options, "warm_start", None)
    iterates = None if prev is None else prev.info.get("scs_iterates")
    if not isinstance(iterates, dict):
        return {}
    m, n = shape
    want = {"x": n, "y": m, "s": m}
    out = {k: np.asarray(iterates.get(k), dtype=float) for k in want}
    if any(v.shape != (want[k],) or not np.all(np.isfinite(v)) for k, v in out.items()):
        return {}
    return out


class SCSBackend(Backend):
    """SCS (splitting conic solver) through its native API."""

    name: ClassVar[str] = "scs"
    requires: ClassVar[dict[str, str]] = {"scs": "scs"}
    native_time_limit: ClassVar[bool] = True
    interior_point: ClassVar[bool] = False
    #: SCS is a first-order method: at 1e-8 it runs into its iteration limit on most LMI
    #: problems (10-40 s, docs/backends.md); 1e-6 with the margin floor of the strict reduction
    #: (10 tol) is certified where it converges
    tol_floor: ClassVar[float] = 1e-6
    description: ClassVar[str] = "SCS first-order (ADMM), native API"
    STATUS_MAP: ClassVar[dict[str, str]] = {
        "solved": "optimal",
        "solved_inaccurate": "inaccurate",
        "infeasible": "infeasible",
        # an inexact infeasibility claim: kept only if its ray verifies (settle_inexact_infeasible)
        "infeasible_inaccurate": "inaccurate",
        "unbounded": "unbounded",
        "unbounded_inaccurate": "inaccurate",
        "indeterminate": "error",
        "failed": "error",
        "sigint": "error",
        "unfinished": "error",
    }

    def _settings(self, options: SolveOptions) -> dict:
        s = {
            "verbose": bool(options.verbose),
            "eps_abs": options.tol,
            "eps_rel": options.tol,
            "eps_infeas": min(1e-7, options.tol * 10),
        }
        if options.max_iter is not None:
            s["max_iters"] = int(options.max_iter)
        if options.time_limit is not None:
            s["time_limit_secs"] = float(options.time_limit)
        s.update(options.extra)
        return s

    def _solve(self, problem: Problem, options: SolveOptions) -> Solution:
        import scs

        data = conic_data(problem, scs_vec)
        cone: dict = {}
        if data.n_eq:
            cone["z"] = data.n_eq
        if data.n_ge:
            cone["l"] = data.n_ge
        if data.psd:
            cone["s"] = list(data.psd)
        settings = self._settings(options)
        t0 = time.perf_counter()
        solver = scs.SCS({"A": data.A, "b": data.b, "c": data.c}, cone, **settings)
        warm = _warm_start(options, data.A.shape)  # SolveOptions.warm_start (sweeps)
        result = solver.solve(warm_start=True, **warm) if warm else solver.solve()
        solve_s = time.perf_counter() - t0
        info = result["info"]
        native = _STATUS_NAMES.get(int(info["status_val"]), str(info.get("status", "")))
        status = self.map_status(native)
        raw_status = str(info.get("status", native))
        sol = Solution(
            status=status,
            backend=self.label,
            native_status=raw_status,
            solve_s=solve_s,
            iterations=int(info.get("iter", 0)),
            info={"solver_time_s": float(info.get("solve_time", 0.0)) / 1e3, "warm_started": bool(warm)},
        )
        # the native iterates, for the next solve of a problem of the same shape (warm start)
        sol.info["scs_iterates"] = {k: np.asarray(result[k], dtype=float) for k in ("x", "y", "s")}
        y = np.asarray(result["y"], dtype=float)
        if "time_limit" in raw_status:
            mark_time_limit(sol, options.time_limit, solve_s)
            sol.message += f" ({raw_status})"
        elif native == "infeasible_inaccurate":
            settle_inexact_infeasible(problem, sol, self.split_duals(data, y, scs_unvec, len(problem.linear)))
        elif native == "unbounded_inaccurate":
            sol.info["inexact_ray"] = np.asarray(result["x"], dtype=float)
        elif sol.status in ("optimal", "inaccurate") and native.startswith("solved"):
            sol.x = np.asarray(result["x"], dtype=float)
            sol.objective = data.sign * (float(data.c @ sol.x) + data.c0)
            sol.duals = self.split_duals(data, y, scs_unvec, len(problem.linear))
        elif sol.status == "infeasible":
            sol.farkas = self.split_duals(data, y, scs_unvec, len(problem.linear))
        elif sol.status == "unbounded":
            sol.info["ray"] = np.asarray(result["x"], dtype=float)
        if sol.status in ("error", "inaccurate") and not sol.message:
            sol.message = f"SCS stopped with status '{raw_status}'"
        return sol
