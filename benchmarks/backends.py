"""Backend benchmark: lmic (compile, lowering, solver time) against hand-written CVXPY.

Problems: ``qib.thm1`` on random discrete-time systems (n = 10, 20, 30, 40 by default; ``p = n/2``
outputs, ``beta = 1e-3``) and SDPLIB control1-3. For every backend lmic's compile time, its own
overhead (strict reduction + lowering + result mapping, ``lower_s``), the solver time and the
certificate verdict are measured; the same LMI written by hand in CVXPY (``P`` symmetric, ``R``,
``omega``; ``M << -eps I``, ``P >> eps I``, ``omega >= eps`` with ``eps = 1e-6``, the usual
idiom) is timed with the same solver, and its answer is certified by lmic's certifier too.

Each run happens in a child process with a time limit, so one slow solver does not stop the
table. Usage::

    python benchmarks/backends.py                      # everything, 300 s limit per run
    python benchmarks/backends.py --sizes 10,20 --limit 60 --json out.json

Examples
--------
>>> system = random_qib_system(4, seed=0)
>>> np.asarray(system["data"]["A"]).shape
(4, 4)
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import sys
import time
import warnings
from typing import Any

import numpy as np

__all__ = ["random_qib_system", "run_lmic", "run_cvxpy", "main"]

LMIC_BACKENDS = ["clarabel", "scs", "cvxopt", "sdpa", "auto"]
CVXPY_SOLVERS = ["CLARABEL", "SCS", "CVXOPT", "SDPA"]
SDPLIB = "/work/shared/sdplib"


def random_qib_system(n: int, seed: int = 0, beta: float = 1e-3) -> dict[str, Any]:
    """A random discrete-time system for ``qib.thm1`` (spectral radius 0.9, ``p = n/2``).

    >>> random_qib_system(2)["params"]["beta"]
    0.001
    """
    rng = np.random.default_rng(seed + 1000 * n)
    A = rng.standard_normal((n, n))
    A *= 0.9 / max(abs(np.linalg.eigvals(A)))
    C = rng.standard_normal((max(1, n // 2), n))
    return {
        "lmic": 1,
        "name": f"random n={n} seed={seed}",
        "data": {"A": A.tolist(), "C": C.tolist()},
        "params": {"beta": beta, "gamma": 0.0},
    }


def _certify(problem: Any, solution: Any) -> tuple[str, float | None]:
    from lmic.certify import certify

    cert = certify(problem, solution)
    margins = [m.get("min_margin") for m in cert.lmis if m.get("min_margin") is not None]
    return cert.verdict, (min(margins) if margins else None)


def run_lmic(target: str, backend: str, n: int, tol: float) -> dict[str, Any]:
    """lmic's pipeline on one problem: compile/load, lower + solve, certify (timed)."""
    from lmic.api import solve
    from lmic.backends.base import SolveOptions

    if target == "qib":
        res = solve("qib.thm1", random_qib_system(n), backend=backend, options=SolveOptions(tol=tol))
    else:
        res = solve(f"{SDPLIB}/{target}.dat-s", backend=backend, options=SolveOptions(tol=tol))
    t = res.timings
    return {
        "status": res.status,
        "verdict": res.verdict,
        "min_margin": res.min_margin,
        "compile_s": t["compile_s"],
        "lower_s": t["lower_s"],
        "solve_s": t["solve_s"],
        "total_s": t["compile_s"] + t["lower_s"] + t["solve_s"],
        "objective": res.objective,
        "route": [a["backend"] for a in res.attempts] or [res.backend],
        "n_vars": res.problem.n,
    }


def run_cvxpy(solver: str, n: int, eps: float = 1e-6) -> dict[str, Any]:
    """``qib.thm1`` written by hand in CVXPY, solved with ``solver``; certified by lmic."""
    import cvxpy as cp

    from lmic.compile import compile_theorem
    from lmic.solution import Solution

    system = random_qib_system(n)
    A, C = (np.asarray(system["data"][k]) for k in ("A", "C"))
    beta, gamma = system["params"]["beta"], system["params"]["gamma"]
    p = C.shape[0]
    t0 = time.perf_counter()
    P = cp.Variable((n, n), symmetric=True)
    R = cp.Variable((p, n))
    w = cp.Variable()
    In = np.eye(n)
    X = A.T @ P - C.T @ R
    Z = np.zeros((n, n))
    M = cp.bmat(
        [
            [-P + 2 * w * beta * In, X + w * gamma * In, X],
            [X.T + w * gamma * In, P - 2 * w * In, Z],
            [X.T, Z, -P],
        ]
    )
    cons = [0.5 * (M + M.T) << -eps * np.eye(3 * n), P >> eps * In, w >= eps]
    prob = cp.Problem(cp.Minimize(0), cons)
    prob.solve(solver=solver)
    total = time.perf_counter() - t0
    stats = prob.solver_stats
    out: dict[str, Any] = {
        "status": prob.status,
        "total_s": total,
        "solve_s": getattr(stats, "solve_time", None),
        "compile_s": getattr(prob, "compilation_time", None),
    }
    if P.value is not None:
        ir = compile_theorem("qib.thm1", system)
        x = ir.pack({"P": P.value, "R": R.value, "omega": float(w.value)})
        out["verdict"], out["min_margin"] = _certify(ir, Solution("feasible", x=x))
    else:
        out["verdict"], out["min_margin"] = "unverified", None
    return out


def _child(conn: Any, fn: Any, args: tuple) -> None:
    warnings.simplefilter("ignore")
    try:
        conn.send(fn(*args))
    except Exception as err:  # noqa: BLE001 - reported in the table
        conn.send({"status": "error", "message": f"{type(err).__name__}: {err}"})
    conn.close()


def _timed(fn: Any, args: tuple, limit: float) -> dict[str, Any]:
    ctx = multiprocessing.get_context("fork")
    recv, send = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_child, args=(send, fn, args), daemon=True)
    t0 = time.perf_counter()
    proc.start()
    send.close()
    try:
        if recv.poll(limit):
            out = recv.recv()
        else:
            out = {"status": f"timeout > {limit:g} s"}
    except EOFError:
        out = {"status": "crashed"}
    finally:
        if proc.is_alive():
            proc.terminate()
        proc.join(2)
    out["wall_s"] = time.perf_counter() - t0
    return out


def _fmt(v: Any, spec: str = ".3f") -> str:
    if v is None:
        return "-"
    if isinstance(v, float):
        return format(v, spec)
    return str(v)


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark and print the table."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", default="10,20,30,40")
    ap.add_argument("--backends", default=",".join(LMIC_BACKENDS))
    ap.add_argument("--cvxpy", default=",".join(CVXPY_SOLVERS), help="hand-written CVXPY solvers")
    ap.add_argument("--sdplib", default="control1,control2,control3")
    ap.add_argument("--limit", type=float, default=300.0, help="seconds per run")
    ap.add_argument("--tol", type=float, default=1e-8)
    ap.add_argument("--json", default=None, help="also write the rows to this file")
    args = ap.parse_args(argv)
    sizes = [int(s) for s in args.sizes.split(",") if s]
    backends = [b for b in args.backends.split(",") if b]
    solvers = [s for s in args.cvxpy.split(",") if s]
    problems = [("qib", n) for n in sizes] + [(p, 0) for p in args.sdplib.split(",") if p]
    rows = []
    header = (
        f"{'problem':10s} {'method':16s} {'status':10s} {'verdict':22s} {'margin':>9s} "
        f"{'compile':>8s} {'lower':>8s} {'solver':>8s} {'total':>8s} {'ovh%':>6s}"
    )
    print(header)
    print("-" * len(header))
    for target, n in problems:
        label = f"qib n={n}" if target == "qib" else target
        for be in backends:
            r = _timed(run_lmic, (target, be, n, args.tol), args.limit)
            r.update(problem=label, method=f"lmic {be}")
            rows.append(r)
            ovh = None
            if r.get("solve_s"):
                ovh = 100.0 * (r["compile_s"] + r["lower_s"]) / r["solve_s"]
            method = f"lmic {be}" + (f"->{r['route'][-1]}" if be == "auto" and "route" in r else "")
            print(
                f"{label:10s} {method:16s} {r['status'][:10]:10s} {r.get('verdict', '-'):22s} "
                f"{_fmt(r.get('min_margin'), '.2e'):>9s} {_fmt(r.get('compile_s')):>8s} "
                f"{_fmt(r.get('lower_s')):>8s} {_fmt(r.get('solve_s')):>8s} "
                f"{_fmt(r.get('total_s', r['wall_s'])):>8s} {_fmt(ovh, '.1f'):>6s}",
                flush=True,
            )
        if target != "qib":
            continue
        for solver in solvers:
            r = _timed(run_cvxpy, (solver, n), args.limit)
            r.update(problem=label, method=f"cvxpy {solver}")
            rows.append(r)
            print(
                f"{label:10s} {'cvxpy ' + solver:16s} {str(r['status'])[:10]:10s} "
                f"{r.get('verdict', '-'):22s} {_fmt(r.get('min_margin'), '.2e'):>9s} "
                f"{_fmt(r.get('compile_s')):>8s} {'':>8s} {_fmt(r.get('solve_s')):>8s} "
                f"{_fmt(r.get('total_s', r['wall_s'])):>8s}",
                flush=True,
            )
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(rows, fh, indent=1, default=str)
    return 0


if __name__ == "__main__":
    sys.exit(main())
