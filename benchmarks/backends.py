"""Backend benchmark: lmic (compile, lowering, solver time) against hand-written CVXPY, interleaved.

Problems: ``qib.thm1`` on random discrete-time systems (n = 10, 20, 30, 40 by default; ``p = n/2``
outputs, ``beta = 1e-3``) and SDPLIB control1-3. For every lmic backend the compile time, lmic's
own overhead (elimination, strict reduction, lowering, result mapping and the check of a
fixed-margin point: ``lower_s``), the solver time and the certificate verdict are measured; the
same LMI written by hand in CVXPY (``P`` symmetric, ``R``, ``omega``; ``M << -eps I``,
``P >> eps I``, ``omega >= eps`` with ``eps = 1e-6``, the usual idiom) is timed with the same
solver, and its answer is certified by lmic's certifier too.

By default the template of ``qib.thm1`` is analysed once in the parent process (as a session or a
sweep does: :func:`lmic.compile.plan_for` caches it), so ``compile`` is the binding of the data;
``--cold`` makes every run pay the analysis too (~0.5 s here).

The machine is shared, so absolute times drift: every method runs ``--repeat`` times, the methods
*interleaved* (one round runs each method once, in a rotated order), each run in a fresh child
process with a time limit, and the report gives medians and, per size, the ratio of every
method's median total time to lmic ``auto``'s (measured in the same rounds). Usage::

    python benchmarks/backends.py                                 # 3 rounds, sizes 10..40
    python benchmarks/backends.py --sizes 20,40 --repeat 5 --json out.json
    python benchmarks/backends.py --methods lmic:auto,cvxpy:CLARABEL --sdplib ""

Examples
--------
>>> system = random_qib_system(4, seed=0)
>>> np.asarray(system["data"]["A"]).shape
(4, 4)
>>> parse_method("cvxpy:SCS"), parse_method("lmic:auto")
(('cvxpy', 'SCS'), ('lmic', 'auto'))
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import statistics
import sys
import time
import warnings
from typing import Any

import numpy as np

__all__ = ["random_qib_system", "run_lmic", "run_cvxpy", "parse_method", "summarise", "main"]

METHODS = [
    "lmic:auto",
    "lmic:clarabel",
    "lmic:scs",
    "lmic:cvxopt",
    "cvxpy:CLARABEL",
    "cvxpy:SCS",
    "cvxpy:CVXOPT",
]
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


def parse_method(spec: str) -> tuple[str, str]:
    """``"lmic:BACKEND"`` or ``"cvxpy:SOLVER"`` as ``(kind, name)``."""
    kind, _, name = spec.partition(":")
    if kind not in ("lmic", "cvxpy") or not name:
        raise ValueError(f"method '{spec}': expected lmic:BACKEND or cvxpy:SOLVER")
    return kind, name


def _certify(problem: Any, solution: Any) -> tuple[str, float | None]:
    from lmic.certify import certify

    cert = certify(problem, solution)
    margins = [m.get("rel_margin") for m in cert.lmis if m.get("rel_margin") is not None]
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
    rel = [m.get("rel_margin") for m in res.certificate_dict().get("lmis", []) if m.get("rel_margin") is not None]
    return {
        "status": res.status,
        "verdict": res.verdict,
        "rel_margin": min(rel) if rel else None,
        "compile_s": t["compile_s"],
        "lower_s": t["lower_s"],
        "solve_s": t["solve_s"],
        "total_s": t["compile_s"] + t["lower_s"] + t["solve_s"],
        "objective": res.objective,
        "route": [a["backend"] for a in res.attempts] or [res.backend],
        "strategy": res.solution.strategy,
        "iterations": res.solution.iterations,
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
        "iterations": getattr(stats, "num_iters", None),
    }
    if P.value is not None:
        ir = compile_theorem("qib.thm1", system)
        x = ir.pack({"P": P.value, "R": R.value, "omega": float(w.value)})
        out["verdict"], out["rel_margin"] = _certify(ir, Solution("feasible", x=x))
    else:
        out["verdict"], out["rel_margin"] = "unverified", None
    return out


def _child(conn: Any, fn: Any, args: tuple) -> None:
    warnings.simplefilter("ignore")
    try:
        conn.send(fn(*args))
    except Exception as err:  # noqa: BLE001 - reported in the table
        conn.send({"status": "error", "message": f"{type(err).__name__}: {err}"})
    conn.close()


def _timed(fn: Any, args: tuple, limit: float) -> dict[str, Any]:
    """``fn(*args)`` in a forked child (not a daemon: lmic's time-limited solves fork their own
    children), killed after ``limit`` seconds."""
    ctx = multiprocessing.get_context("fork")
    recv, send = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_child, args=(send, fn, args), daemon=False)
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
            proc.kill()
        proc.join(5)
    out["wall_s"] = time.perf_counter() - t0
    return out


def _median(rows: list[dict[str, Any]], key: str) -> float | None:
    vals = [r[key] for r in rows if isinstance(r.get(key), int | float)]
    return statistics.median(vals) if vals else None


def summarise(runs: list[dict[str, Any]], reference: str = "lmic:auto") -> list[dict[str, Any]]:
    """Median times per ``(problem, method)`` and the ratio of each total to ``reference``'s.

    >>> runs = [{"problem": "p", "method": "lmic:auto", "total_s": 1.0, "solve_s": 0.9, "status": "feasible"},
    ...         {"problem": "p", "method": "cvxpy:SCS", "total_s": 3.0, "solve_s": 2.0, "status": "optimal"}]
    >>> [(r["method"], r["ratio"]) for r in summarise(runs)]
    [('lmic:auto', 1.0), ('cvxpy:SCS', 3.0)]
    """
    out: list[dict[str, Any]] = []
    problems = list(dict.fromkeys(r["problem"] for r in runs))
    for prob in problems:
        mine = [r for r in runs if r["problem"] == prob]
        ref = _median([r for r in mine if r["method"] == reference], "total_s")
        for method in dict.fromkeys(r["method"] for r in mine):
            rows = [r for r in mine if r["method"] == method]
            last = rows[-1]
            total = _median(rows, "total_s")
            solve = _median(rows, "solve_s")
            compile_s, lower = _median(rows, "compile_s"), _median(rows, "lower_s")
            out.append(
                {
                    "problem": prob,
                    "method": method,
                    "runs": len(rows),
                    "status": last.get("status"),
                    "verdict": last.get("verdict"),
                    "strategy": last.get("strategy"),
                    "route": last.get("route"),
                    "iterations": last.get("iterations"),
                    "rel_margin": last.get("rel_margin"),
                    "compile_s": compile_s,
                    "lower_s": lower,
                    "solve_s": solve,
                    "total_s": total,
                    "lower_pct": 100.0 * lower / solve if lower is not None and solve else None,
                    "overhead_pct": (
                        100.0 * (lower + compile_s) / solve if None not in (lower, compile_s) and solve else None
                    ),
                    "ratio": (total / ref if total is not None and ref else None),
                }
            )
    return out


def _fmt(v: Any, spec: str = ".3f") -> str:
    if v is None:
        return "-"
    if isinstance(v, float):
        return format(v, spec)
    return str(v)


def _print_table(summary: list[dict[str, Any]]) -> None:
    header = (
        f"{'problem':10s} {'method':15s} {'status':11s} {'verdict':21s} {'rel.marg':>9s} {'it':>6s} "
        f"{'compile':>8s} {'lower':>7s} {'solver':>8s} {'total':>8s} {'low%':>6s} {'ovh%':>6s} {'x auto':>7s}"
    )
    print(header)
    print("-" * len(header))
    for r in summary:
        method = r["method"]
        if method.startswith("lmic:auto") and r.get("route"):
            method += "->" + str(r["route"][-1])
        print(
            f"{r['problem']:10s} {method[:15]:15s} {str(r['status'])[:11]:11s} {str(r.get('verdict') or '-')[:21]:21s} "
            f"{_fmt(r.get('rel_margin'), '.1e'):>9s} {_fmt(r.get('iterations')):>6s} {_fmt(r['compile_s']):>8s} "
            f"{_fmt(r['lower_s']):>7s} {_fmt(r['solve_s']):>8s} {_fmt(r['total_s']):>8s} "
            f"{_fmt(r['lower_pct'], '.1f'):>6s} {_fmt(r['overhead_pct'], '.1f'):>6s} {_fmt(r['ratio'], '.2f'):>7s}"
        )


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark (interleaved rounds), print the medians and ratios."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", default="10,20,30,40")
    ap.add_argument("--methods", default=",".join(METHODS), help="lmic:BACKEND and cvxpy:SOLVER, comma-separated")
    ap.add_argument("--sdplib", default="control1,control2,control3", help="SDPLIB problems (lmic methods only)")
    ap.add_argument("--repeat", type=int, default=3, help="interleaved rounds")
    ap.add_argument("--limit", type=float, default=300.0, help="seconds per run")
    ap.add_argument("--tol", type=float, default=1e-8)
    ap.add_argument("--json", default=None, help="also write every run and the summary to this file")
    ap.add_argument(
        "--cold",
        action="store_true",
        help="do not analyse qib.thm1 in the parent first (each run then pays the cold template analysis)",
    )
    args = ap.parse_args(argv)
    if not args.cold:
        # a session or a sweep analyses the template once and re-binds (lmic.compile's plan cache);
        # the children are forked after this and inherit the cached plan
        from lmic.compile import compile_theorem

        t0 = time.perf_counter()
        compile_theorem("qib.thm1", random_qib_system(2))
        print(f"qib.thm1 template analysis (once per process, not in the table): {time.perf_counter() - t0:.3f} s")
    sizes = [int(s) for s in args.sizes.split(",") if s]
    methods = [m for m in args.methods.split(",") if m]
    for m in methods:
        parse_method(m)
    problems = [("qib", n) for n in sizes] + [(p, 0) for p in args.sdplib.split(",") if p]
    runs: list[dict[str, Any]] = []
    for target, n in problems:
        label = f"qib n={n}" if target == "qib" else target
        todo = [m for m in methods if target == "qib" or m.startswith("lmic:")]
        for k in range(args.repeat):
            order = todo[k % len(todo) :] + todo[: k % len(todo)]  # rotate: no method always first
            for method in order:
                kind, name = parse_method(method)
                if kind == "lmic":
                    r = _timed(run_lmic, (target, name, n, args.tol), args.limit)
                else:
                    r = _timed(run_cvxpy, (name, n), args.limit)
                r.update(problem=label, method=method, round=k)
                runs.append(r)
                print(
                    f"  [{label} round {k + 1}/{args.repeat}] {method}: {r.get('status')} "
                    f"{r.get('verdict', '')} total {_fmt(r.get('total_s', r['wall_s']))} s",
                    file=sys.stderr,
                    flush=True,
                )
    summary = summarise(runs)
    _print_table(summary)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"runs": runs, "summary": summary}, fh, indent=1, default=str)
    return 0


if __name__ == "__main__":
    sys.exit(main())
