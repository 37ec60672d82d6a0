"""SCS 3.x (native Python API): a first-order (ADMM) conic solver.

SCS solves ``min c'x`` s.t. ``A x + s = b``, ``s`` in ``{0}^z x R+^l x S_1 x ...``. Its PSD cone
``s`` takes the *lower* triangle column by column with off-diagonal entries times ``sqrt(2)``,
which is the IR's storage order scaled by :func:`lmic.ir.svec.svec_scale`. The dual ``y`` gives
``Z_i`` and the row multipliers; on infeasibility SCS returns the Farkas ray normalised to
``b'y = -1``.

SCS is fast on large LMIs but only accurate to its tolerance: a point on the boundary of a
strict LMI is not certifiable, which is why strict feasibility goes through the normalised
``max-margin`` reduction (:mod:`lmic.reductions.strict`).

Examples
--------
>>> SCSBackend.name, SCSBackend.interior_point
('scs', False)
"""

from __future__ import annotations

import functools
import time
from typing import Any, ClassVar

import numpy as np

from lmic.backends.backend import Backend
from lmic.backends.lowering import SForm, psd_unvec
from lmic.backends.quiet import quiet_native
from lmic.backends.results import NativeResult
from lmic.ir.problem import Problem
from lmic.ir.svec import svec_scale, tril_size
from lmic.options import SolveOptions
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


@functools.lru_cache(maxsize=64)
def scs_vec(d: int) -> tuple[np.ndarray, np.ndarray]:
    """SCS's PSD vectorisation as ``(perm, scale)`` (storage order, ``sqrt(2)`` off-diagonal).

    >>> scs_vec(2)[1]
    array([1.        , 1.41421356, 1.        ])
    """
    perm, scale = np.arange(tril_size(d)), svec_scale(d)
    perm.setflags(write=False)
    scale.setflags(write=False)
    return perm, scale


def scs_unvec(v: np.ndarray, d: int) -> np.ndarray:
    """Dense symmetric matrix from one SCS PSD block.

    >>> scs_unvec(np.array([1.0, np.sqrt(2), 1.0]), 2)
    array([[1., 1.],
           [1., 1.]])
    """
    return psd_unvec(scs_vec, v, d)


#: SCS's s-form lowering (apply: ConicData; invert: IR multipliers)
FORM = SForm(scs_vec)

#: with ``SolveOptions.accept``: iterations between two tests of the iterate (SCS tests its own
#: convergence only every 25; a restart from the iterate every iteration stalls, every 2-3 does
#: not: ``qib.thm1`` n = 10..50 verifies at iteration 3-6, benchmarks/routes.py)
CHECK_EVERY = 3
#: ... up to this many iterations; then SCS's own solve runs, from the start
CHECK_UNTIL = 30

#: SCS's set-up factorises its KKT matrix: up to this many variables SCS's bundled QDLDL is
#: faster than the MKL PARDISO its ``auto`` choice prefers (``qib.thm1``: 0.6 against 2.1 ms at
#: 106 variables, 64 against 119 ms at 1621, about even at 2526; PARDISO ahead from ~3600:
#: 0.65 against 1.3 s), unless ``SolveOptions.extra`` names a ``linear_solver``
QDLDL_MAX_VARIABLES = 3000
#: SCS's ``status_val`` after a pause at ``max_iters``: unfinished (0) or an inaccurate answer
#: (2 solved, -6 unbounded, -7 infeasible), which at max_iters is no answer yet
_PAUSED = frozenset({0, 2, -6, -7})


def _warm_start(prev: Solution | None, shape: tuple[int, int]) -> dict[str, np.ndarray]:
    """SCS's ``x``, ``y``, ``s`` initial guesses from ``prev`` (``SolveOptions.warm_start``: a
    previous SCS solution of a problem with the same lowered shape ``(m, n)``), else ``{}``.

    >>> _warm_start(None, (2, 1))
    {}
    """
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
    title: ClassVar[str] = "SCS"
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
        # an inexact infeasibility claim: kept only if its ray verifies (INEXACT_INFEASIBLE)
        "infeasible_inaccurate": "inaccurate",
        "unbounded": "unbounded",
        "unbounded_inaccurate": "inaccurate",
        "indeterminate": "error",
        "failed": "error",
        "sigint": "error",
        "unfinished": "error",
        # stopped early by lmic: the iterate passed SolveOptions.accept (the original problem's
        # point check); certified like any other answer
        "point_verified": "optimal",
    }
    INEXACT_INFEASIBLE: ClassVar[frozenset[str]] = frozenset({"infeasible_inaccurate"})
    INEXACT_UNBOUNDED: ClassVar[frozenset[str]] = frozenset({"unbounded_inaccurate"})
    #: SCS's own time limit: a status string mentioning ``time_limit`` (set by :meth:`call`)
    TIME_LIMIT: ClassVar[frozenset[str]] = frozenset({"time_limit"})

    def settings(self, options: SolveOptions) -> dict[str, Any]:
        """Keyword arguments of ``scs.SCS`` from the options (``extra`` verbatim, last)."""
        s: dict[str, Any] = {
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
        if options.warm_start is not None:  # taken out again by call(): not an scs.SCS keyword
            s["_warm_start"] = options.warm_start
        if options.accept is not None:  # likewise
            s["_accept"] = options.accept
        return s

    def call(self, problem: Problem, settings: dict[str, Any]) -> NativeResult:
        """Lower to ``A x + s = b``, run ``scs.SCS`` (warm-started from ``SolveOptions.warm_start``
        when its iterates fit), invert ``y`` (the dual or the ray)."""
        import scs

        settings = dict(settings)

        data = FORM.apply(problem)
        cone: dict[str, Any] = {}
        if data.n_eq:
            cone["z"] = data.n_eq
        if data.n_ge:
            cone["l"] = data.n_ge
        if data.psd:
            cone["s"] = list(data.psd)
        warm_from = settings.pop("_warm_start", None)  # SolveOptions.warm_start (sweeps), see settings()
        accept = settings.pop("_accept", None)  # SolveOptions.accept, see settings()
        warm = _warm_start(warm_from, data.A.shape)
        qp = {"A": data.A, "b": data.b, "c": data.c}
        if "linear_solver" not in settings and hasattr(scs, "LinearSolver") and data.A.shape[1] <= QDLDL_MAX_VARIABLES:
            settings["linear_solver"] = "qdldl"
        extra_info: dict[str, Any] = {}
        if accept is None:
            t0 = time.perf_counter()
            solver = scs.SCS(qp, cone, **settings)
            result = solver.solve(warm_start=True, **warm) if warm else solver.solve()
            solve_s = time.perf_counter() - t0
            verified_at = None
        else:
            # SCS prints "could not determine problem status" at a pause even when not verbose
            with quiet_native(not settings.get("verbose", False)):
                result, solve_s, verified_at, extra_info = _solve_checked(scs, qp, cone, settings, warm, accept)
        info = result["info"]
        shown = str(info.get("status", ""))
        native = _STATUS_NAMES.get(int(info["status_val"]), shown)
        if "time_limit" in shown or extra_info.pop("time_limit", False):
            native = "time_limit"
        if verified_at is not None:
            native, shown = "point_verified", f"point verified at iteration {verified_at} ({shown})"
        return NativeResult(
            native,
            x=np.asarray(result["x"], dtype=float),
            duals=FORM.invert(data, np.asarray(result["y"], dtype=float), len(problem.linear)),
            solve_s=solve_s,
            iterations=int(extra_info.get("iterations", info.get("iter", 0))),
            info={
                **extra_info,
                "solver_time_s": float(info.get("solve_time", 0.0)) / 1e3,
                "warm_started": bool(warm),
                # the native iterates, for the next solve of a problem of the same shape
                "scs_iterates": {k: np.asarray(result[k], dtype=float) for k in ("x", "y", "s")},
            },
            shown=shown or native,
        )


def _solve_checked(
    scs: Any,
    qp: dict[str, Any],
    cone: dict[str, Any],
    settings: dict[str, Any],
    warm: dict[str, np.ndarray],
    accept: Any,
) -> tuple[dict[str, Any], float, int | None, dict[str, Any]]:
    """SCS paused every :data:`CHECK_EVERY` iterations (up to :data:`CHECK_UNTIL`) to test its
    iterate with ``accept``; when none passes, SCS's own solve from the start (the caller's warm
    start, if any).

    Returns ``(result, solve_s, verified_at, info)``: SCS's last result, the time inside SCS
    (set-up and iterations, not the tests), the iteration whose point passed (``None``: none
    did, the result is SCS's own) and ``{"iterations", "accept_tests", "accept_s"}`` (and
    ``"time_limit": True`` when the time limit ran out between two pauses).
    """
    budget = int(settings.get("max_iters", 100_000))
    limit = settings.get("time_limit_secs")
    step = min(CHECK_EVERY, budget)
    t0 = time.perf_counter()
    solver = scs.SCS(qp, cone, **dict(settings, max_iters=step))
    result = solver.solve(warm_start=True, **warm) if warm else solver.solve()
    solve_s = time.perf_counter() - t0
    done, tests, tests_s = int(result["info"]["iter"]), 0, 0.0
    while True:
        info = result["info"]
        # SCS stopped on its own (converged, infeasible, unbounded, failed, its time limit); an
        # inaccurate status at the pause (2 solved, -6 unbounded, -7 infeasible: "inaccurate")
        # only means max_iters was reached, and is no answer
        if int(info["iter"]) < step or int(info["status_val"]) not in _PAUSED or "time_limit" in str(info["status"]):
            break
        t1 = time.perf_counter()
        x = np.asarray(result["x"], dtype=float)
        ok = bool(np.all(np.isfinite(x)) and accept(x))
        tests, tests_s = tests + 1, tests_s + time.perf_counter() - t1
        if ok:
            return result, solve_s, done, {"iterations": done, "accept_tests": tests, "accept_s": tests_s}
        left = budget - done
        if left <= 0:
            break
        if limit is not None and time.perf_counter() - t0 >= float(limit):
            stopped = {"iterations": done, "accept_tests": tests, "accept_s": tests_s, "time_limit": True}
            return result, solve_s, None, stopped
        t1 = time.perf_counter()
        if done + step <= CHECK_UNTIL and left >= step:
            result = solver.solve(warm_start=True)  # from the iterate it stopped at
        else:
            # no iterate verified: SCS's own solve from the start (or from the caller's warm
            # start), as without the tests. Not from the last iterate: a restart resets SCS's
            # homogeneous embedding (tau, kappa) and acceleration, and on an infeasible problem
            # its ray then came out too inaccurate to prove (obs_control.thm3_2, z-coordinates)
            rest = dict(settings, max_iters=budget)
            if limit is not None:
                rest["time_limit_secs"] = max(1e-3, float(limit) - (time.perf_counter() - t0))
            fresh = scs.SCS(qp, cone, **rest)
            result = fresh.solve(warm_start=True, **warm) if warm else fresh.solve()
            solve_s += time.perf_counter() - t1
            done += int(result["info"]["iter"])
            break
        solve_s += time.perf_counter() - t1
        done += int(result["info"]["iter"])
    return result, solve_s, None, {"iterations": done, "accept_tests": tests, "accept_s": tests_s}
