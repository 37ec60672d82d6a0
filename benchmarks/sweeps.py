"""Sweep and supremum benchmark: lmic against a hand-written CVXPY DPP loop, interleaved.

Three studies, each at a few sizes, on random systems:

- ``sweep``: a 20-point grid of ``beta`` on ``qib.thm1`` (``lmic.studies.sweep.sweep``: one
  analysis, a re-bind, a warm-started solve and a certification a point) against a CVXPY loop
  over a ``cp.Parameter`` (DPP: the problem is built and canonicalised once, each point
  re-solved), every CVXPY point certified by lmic's certifier;
- ``maximize``: the supremum of ``beta`` on ``qib.thm1`` against a CVXPY DPP bisection with the
  same bracket and tolerance, a value counting as feasible only when lmic's certifier certifies
  CVXPY's point. ``beta`` multiplies only ``omega > 0`` in a scale-free problem: lmic fixes
  ``omega = 1``, solves ``max beta`` once and proves the upper end by one infeasibility proof
  within the tolerance (:mod:`lmic.studies.sweep.enclosed`);
- ``maxbisect``: the same supremum by lmic's bisection (``method="bisection"``: screens, stretch
  of certified points, the final end proven);
- ``minimize``: the infimum of ``gamma`` in the bounded-real lemma with ``gamma`` a parameter
  (affine: lmic solves once, then the proven dual bound, else a labelled bounded ray) against
  the same CVXPY DPP bisection.

Evidence is not the same: lmic's certified end is certified and its other end carries a global
proof (``infeasible-certified`` or ``dual-bound``) or is labelled (``infeasible-bounded``);
CVXPY's loop certifies its feasible end only, its other end is "the solver did not return a
point the certifier accepts" and proves nothing.

lmic's sweep certifies the last certified point again at the next value before solving (a
feasibility theorem: a certified point is the whole answer), and its bisection decides interior
values by one certified solve (``screen``), the full policy only at the final non-certified end
(:mod:`lmic.studies.sweep.points`). The ``evals`` column counts lmic's solved points (sweep) or
points (maximize, with how many were reused or screened).

Methods run in-process (imports and the template analysis paid once before timing), interleaved
(each round runs every method once, in a rotated order); the report gives the median time of
each method and its ratio to lmic's (``cvxpy / lmic``: above 1 means lmic is faster).
Usage::

    python benchmarks/sweeps.py                        # sizes 10,20, 3 rounds
    python benchmarks/sweeps.py --sizes 10,20,30 --repeat 5 --solver SCS
    python benchmarks/sweeps.py --studies maximize,maxbisect,minimize --lmic-backend auto

Examples
--------
>>> np.asarray(random_brl_system(3, seed=0)["data"]["A"]).shape
(3, 3)
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
import warnings
from typing import Any

import numpy as np

sys.path.insert(0, __file__.rsplit("/", 1)[0])
from backends import random_qib_system  # noqa: E402

__all__ = ["random_brl_system", "BRL", "main"]


def _brl_theorem() -> Any:
    from lmic.template import STAR, I, block, theorem

    @theorem(
        id="bench.brl_param",
        title="Bounded-real lemma with gamma a parameter",
        citation="Boyd et al. (1994), sec. 6.3.2",
        kind="analysis",
        objective="feasibility",
        system_class="continuous time, linear, stable",
    )
    def brl(t: Any) -> None:
        n, m, q = t.dims("n m q")
        A, B, C = t.data("A", n, n), t.data("B", n, m), t.data("C", q, n)
        P = t.symmetric("P", n, pd=True)
        g = t.param("gamma", default=1.0, domain="positive", doc="H-infinity bound")
        t.lmi("brl", block([[A.T * P + P * A, P * B, C.T], [STAR, -g * I(m), 0], [STAR, STAR, -g * I(q)]]) < 0)

    return brl


BRL = _brl_theorem()


def random_brl_system(n: int, seed: int = 0) -> dict[str, Any]:
    """A random stable system (``m = q = 2``) for the bounded-real lemma."""
    rng = np.random.default_rng(seed + 1000 * n)
    A = rng.standard_normal((n, n))
    A -= (max(np.linalg.eigvals(A).real) + 0.5) * np.eye(n)
    B, C = rng.standard_normal((n, 2)), rng.standard_normal((2, n))
    return {"lmic": 1, "data": {"A": A.tolist(), "B": B.tolist(), "C": C.tolist()}}


# -- CVXPY DPP formulations (strict LMIs with margin eps, the usual idiom) --------------------


def _qib_cvxpy(system: dict[str, Any], eps: float = 1e-6) -> tuple[Any, Any, Any]:
    import cvxpy as cp

    A, C = (np.asarray(system["data"][k]) for k in ("A", "C"))
    n, p = A.shape[0], C.shape[0]
    beta = cp.Parameter()
    P, R, w = cp.Variable((n, n), symmetric=True), cp.Variable((p, n)), cp.Variable()
    In, Z = np.eye(n), np.zeros((n, n))
    X = A.T @ P - C.T @ R
    M = cp.bmat([[-P + 2 * beta * w * In, X, X], [X.T, P - 2 * w * In, Z], [X.T, Z, -P]])
    prob = cp.Problem(cp.Minimize(0), [0.5 * (M + M.T) << -eps * np.eye(3 * n), P >> eps * In, w >= eps])
    return prob, beta, lambda: {"P": P.value, "R": R.value, "omega": float(w.value)}


def _brl_cvxpy(system: dict[str, Any], eps: float = 1e-6) -> tuple[Any, Any, Any]:
    import cvxpy as cp

    A, B, C = (np.asarray(system["data"][k]) for k in ("A", "B", "C"))
    n, m, q = A.shape[0], B.shape[1], C.shape[0]
    g = cp.Parameter(nonneg=True)
    P = cp.Variable((n, n), symmetric=True)
    M = cp.bmat(
        [
            [A.T @ P + P @ A, P @ B, C.T],
            [B.T @ P, -g * np.eye(m), np.zeros((m, q))],
            [C, np.zeros((q, m)), -g * np.eye(q)],
        ]
    )
    prob = cp.Problem(cp.Minimize(0), [0.5 * (M + M.T) << -eps * np.eye(n + m + q), P >> eps * np.eye(n)])
    return prob, g, lambda: {"P": P.value}


class _CvxpyPoint:
    """Solve the DPP problem at one value and certify the point with lmic's certifier."""

    def __init__(self, theorem: Any, system: dict[str, Any], param: str, build: Any, solver: str) -> None:
        from lmic.compile import plan_for

        self.theorem, self.system, self.param, self.solver = theorem, system, param, solver
        self.prob, self.par, self.values = build(system)
        self.plan = plan_for(theorem, system.get("params", {}))
        self.n_solves = 0

    def __call__(self, v: float) -> bool:
        from lmic.certify import certify
        from lmic.compile import bind
        from lmic.solution import Solution

        self.par.value = v
        self.n_solves += 1
        try:
            self.prob.solve(solver=self.solver, warm_start=True)
        except Exception:  # noqa: BLE001 - a failed solve is "not certified"
            return False
        if self.prob.status not in ("optimal", "optimal_inaccurate"):
            return False
        problem = bind(self.plan, self.system, {**self.system.get("params", {}), self.param: v})
        x = problem.pack(self.values())
        return certify(problem, Solution("feasible", x=x)).verdict == "certified"


def _cvxpy_bisect(point: _CvxpyPoint, good: float, bad: float, rtol: float, max_evals: int = 60) -> tuple[float, int]:
    """Bisection between a certified ``good`` and a not-certified ``bad`` end (either order)."""
    ok_good = point(good)
    if not ok_good:
        return float("nan"), point.n_solves
    point(bad)
    while abs(bad - good) > rtol * max(abs(good), abs(bad)) and point.n_solves < max_evals:
        mid = 0.5 * (good + bad)
        if point(mid):
            good = mid
        else:
            bad = mid
    return good, point.n_solves


# -- the studies ------------------------------------------------------------------------------


def run(study: str, method: str, n: int, solver: str, rtol: float, lmic_backend: str | None = None) -> dict[str, Any]:
    """One timed run of ``study`` by ``method`` (``lmic`` or ``cvxpy``) at size ``n``."""
    from lmic.studies.sweep import maximize, minimize, sweep

    backend = lmic_backend or solver.lower()
    backend = None if backend == "auto" else backend
    t0 = time.perf_counter()
    if study == "sweep":
        system = random_qib_system(n)
        values = list(np.linspace(1e-4, 2e-3, 20))
        if method == "lmic":
            r = sweep("qib.thm1", system, "beta", values, backend=backend)
            found = sum(p.outcome == "feasible" for p in r.points)
            solved = sum(not p.reused for p in r.points)
            return {"time_s": time.perf_counter() - t0, "value": found, "evals": solved, "how": "solved/20"}
        else:
            pt = _CvxpyPoint("qib.thm1", system, "beta", _qib_cvxpy, solver)
            found = sum(pt(v) for v in values)
        return {"time_s": time.perf_counter() - t0, "value": found, "evals": 20}
    if study in ("maximize", "maxbisect"):
        system = random_qib_system(n)
        lo, hi = 1e-4, 0.5
        if method == "lmic":
            how_m = "auto" if study == "maximize" else "bisection"
            kw = {"rtol": rtol, "xtol": 0.0, "backend": backend, "backoff": 0.0, "method": how_m}
            r = maximize("qib.thm1", system, "beta", lo=lo, hi=hi, **kw)
            how = f"{r.method}, upper {r.upper_kind}, {sum(p.reused for p in r.points)} reused"
            how += f" ({sum(p.stretched for p in r.points)} stretched), {sum(p.screened for p in r.points)} screened"
            return {"time_s": time.perf_counter() - t0, "value": r.lower, "evals": len(r.points), "how": how}
        pt = _CvxpyPoint("qib.thm1", system, "beta", _qib_cvxpy, solver)
        v, k = _cvxpy_bisect(pt, lo, hi, rtol)
        return {"time_s": time.perf_counter() - t0, "value": v, "evals": k, "how": "bisection"}
    system = random_brl_system(n)
    lo, hi = 1e-2, 1e3
    if method == "lmic":
        r = minimize(BRL, system, "gamma", lo=lo, hi=hi, rtol=rtol, xtol=0.0, backend=backend, backoff=0.0)
        how = f"{r.method}, lower {r.upper_kind}"
        return {"time_s": time.perf_counter() - t0, "value": r.upper, "evals": len(r.points), "how": how}
    pt = _CvxpyPoint(BRL, system, "gamma", _brl_cvxpy, solver)
    v, k = _cvxpy_bisect(pt, hi, lo, rtol)
    return {"time_s": time.perf_counter() - t0, "value": v, "evals": k, "how": "bisection"}


def main(argv: list[str] | None = None) -> int:
    """Run the interleaved benchmark and print the table."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", default="10,20")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--solver", default="CLARABEL", help="the same solver for both (CLARABEL, SCS, CVXOPT)")
    ap.add_argument("--studies", default="sweep,maximize,minimize")
    ap.add_argument("--rtol", type=float, default=1e-4)
    ap.add_argument("--lmic-backend", default=None, help="lmic's backend (default: the same; 'auto': the policy)")
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore")
    sizes = [int(s) for s in args.sizes.split(",")]
    studies = args.studies.split(",")
    rows: dict[tuple[str, int, str], list[dict[str, Any]]] = {}
    for study in studies:  # warm-up: imports, template analysis, CVXPY's first canonicalisation
        for method in ("lmic", "cvxpy"):
            run(study, method, 4, args.solver, args.rtol, args.lmic_backend)
    for k in range(args.repeat):
        for study in studies:
            for n in sizes:
                order = ["lmic", "cvxpy"] if (k + n) % 2 == 0 else ["cvxpy", "lmic"]
                for method in order:
                    one = run(study, method, n, args.solver, args.rtol, args.lmic_backend)
                    rows.setdefault((study, n, method), []).append(one)
    print(
        f"cvxpy solver {args.solver}, lmic backend {args.lmic_backend or args.solver.lower()}, "
        f"{args.repeat} rounds (medians), rtol {args.rtol:g}"
    )
    print(
        f"{'study':<9} {'n':>3}  {'lmic s':>8} {'cvxpy s':>8} {'ratio':>6}  {'lmic value':>12} "
        f"{'cvxpy value':>12}  evals l/c  how"
    )
    for study in studies:
        for n in sizes:
            lm, cv = rows[(study, n, "lmic")], rows[(study, n, "cvxpy")]
            tl = statistics.median(r["time_s"] for r in lm)
            tc = statistics.median(r["time_s"] for r in cv)
            print(
                f"{study:<9} {n:>3}  {tl:8.2f} {tc:8.2f} {tc / tl:6.2f}  {lm[-1]['value']:>12.6g} "
                f"{cv[-1]['value']:>12.6g}  {lm[-1]['evals']:>4}/{cv[-1]['evals']:<4}  {lm[-1].get('how', '')}"
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
