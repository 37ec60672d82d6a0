"""Optimisation benchmark (issue 14): lmic's default route against CVXPY + Clarabel, certified.

One interleaved run (``--repeat`` rounds, the order of the methods rotated each round, every run
in a fresh forked child with a time limit; the solvers, CVXPY and lmic's plans are imported and
analysed once in the parent), medians, ratios:

* **bounded-real lemma** (``tutorial.bounded_real``, ``min gamma``) on random stable systems
  of ``--brl-sizes`` states, two kinds per size (:func:`enclosure.brl_problems`): ``random``
  (random diagonal of ``A``) and ``eighths`` (the diagonal rounded to eighths: the IR's
  Lyapunov coefficients are exact, so the exact face route proves the lower end); the
  H-infinity norm comes from a Hamiltonian bisection (:func:`enclosure.hinf_bracket`, no LMI
  solver) and ``in`` says whether lmic's enclosure contains it (``*``: only the upper end is
  proven, and checked); CVXPY + Clarabel is the LMI written by hand (``eps = 1e-7`` margins,
  :func:`routes._cvxpy_brl`), ``err`` its ``gamma`` against the norm;
* **uncertain_dt.thm1, delay_b.thm4_1** on random plants (:func:`routes._plant`, seed 1, sizes
  ``--theorem-sizes``): CVXPY + Clarabel is the same LMIs written in CVXPY from the IR's
  coefficient matrices (one ``reshape(F x + F0) >> eps I`` per LMI, the rows as they are; the
  matrices are prepared outside the timer, CVXPY's build and canonicalisation are timed), and
  ``in`` says whether lmic's proven lower end is below CVXPY's optimum (an independent solve
  whose point meets the LMIs with ``eps`` margins to its tolerance: not a proof; the enclosure
  is).

Columns: ``lmic s`` the whole ``lmic.api.solve`` call (bind, route, certification, enclosure),
``solve s`` the solver's share, ``encl s`` the enclosure's, ``verdict`` and ``gap`` (relative)
of the last run, ``route`` the route lmic printed; ``cvxpy s`` and ``x`` the ratio of CVXPY's
median to lmic's (> 1: lmic faster). ``--methods`` adds lmic with one backend alone (e.g.
``clarabel,cvxopt,sdpa``) as extra columns, for the route rule's measurements. Usage::

    OPENBLAS_NUM_THREADS=1 python benchmarks/optimisation.py                  # all, 3 rounds
    OPENBLAS_NUM_THREADS=1 python benchmarks/optimisation.py --quick          # a few minutes
    OPENBLAS_NUM_THREADS=1 python benchmarks/optimisation.py --only theorems --methods clarabel,cvxopt,sdpa

Examples
--------
>>> fmt(None), fmt(1.23456), fmt(2e-7, ".1e")
('-', '1.235', '2.0e-07')
"""

from __future__ import annotations

import argparse
import os
import sys
import time
import warnings
from typing import Any

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from enclosure import BRL_KINDS, brl_problems, brl_system  # noqa: E402
from routes import _cvxpy_brl, _med, _plant, _rounds, ratio  # noqa: E402

__all__ = ["fmt", "cvxpy_ir", "lmic_run", "main"]


def fmt(v: Any, spec: str = ".3f") -> str:
    """A table cell: ``-`` for ``None``."""
    return "-" if v is None else format(v, spec) if isinstance(v, float) else str(v)


def lmic_run(target: str, system: dict[str, Any], backend: str | None) -> dict[str, Any]:
    """``lmic.api.solve`` (bind included, no backoff): times, verdict, enclosure, route."""
    from lmic.api import solve

    t0 = time.perf_counter()
    r = solve(target, system, backend=backend, backoff=0)
    total = time.perf_counter() - t0
    enc = r.enclosure or {}
    return {
        "verdict": r.verdict,
        "total_s": total,
        "solve_s": r.timings["solve_s"],
        "enclosure_s": r.timings.get("enclosure_s", 0.0),
        "lower": enc.get("lower"),
        "upper": enc.get("upper"),
        "rel_gap": enc.get("rel_gap"),
        "route": (r.route or {}).get("text", ""),
    }


def _full(lmi: Any) -> Any:
    """The IR's tril storage as the full ``d*d x (1 + n)`` matrix (row-major ``(i, j)``)."""
    import scipy.sparse as sp

    from lmic.ir.svec import tril_rows_cols

    d = lmi.dim
    r, c = tril_rows_cols(d)
    F = sp.csr_matrix(lmi.coeffs)
    off = r != c
    rows = np.r_[r * d + c, (c * d + r)[off]]
    cols = np.r_[np.arange(r.size), np.arange(r.size)[off]]
    S = sp.csr_matrix((np.ones(rows.size), (rows, cols)), shape=(d * d, r.size))
    return sp.csc_matrix(S @ F)


def cvxpy_ir(prepared: dict[str, Any], eps: float = 1e-7) -> dict[str, Any]:
    """The problem's LMIs written in CVXPY (+ Clarabel) from its coefficient matrices; timed from
    the build to the answer."""
    import cvxpy as cp

    t0 = time.perf_counter()
    n = prepared["n"]
    x = cp.Variable(n)
    cons = []
    for d, F, strict in prepared["lmis"]:
        M = cp.reshape(F[:, 1:] @ x + F[:, 0].toarray().ravel(), (d, d), order="C")
        cons.append(0.5 * (M + M.T) >> (eps if strict else 0.0) * np.eye(d))
    A, kinds, strict_rows = prepared["rows"]
    for k, kind in enumerate(kinds):
        row = A[k, 1:] @ x + A[k, 0]
        cons.append(row == 0 if kind == "eq" else row >= (eps if strict_rows[k] else 0.0))
    c = prepared["c"]
    expr = c[1:] @ x + c[0]
    obj = cp.Minimize(expr) if prepared["sense"] == "min" else cp.Maximize(expr)
    prob = cp.Problem(obj, cons)
    prob.solve(solver="CLARABEL")
    return {"status": prob.status, "total_s": time.perf_counter() - t0, "objective": prob.value}


def _prepare(problem: Any) -> dict[str, Any]:
    A = problem.linear.A.toarray() if len(problem.linear) else np.zeros((0, problem.n + 1))
    return {
        "n": problem.n,
        "lmis": [(lmi.dim, _full(lmi), lmi.strict) for lmi in problem.lmis],
        "rows": (A, list(problem.linear.kinds), list(problem.linear.strict)),
        "c": np.asarray(problem.objective.c, dtype=float),
        "sense": problem.objective.sense,
    }


def _inside(last: dict[str, Any], lo: float | None, hi: float | None) -> str:
    """Whether the enclosure contains ``[lo, hi]`` (the reference), ``*`` when an end is missing."""
    if lo is None:
        return "-"
    a, b = last.get("lower"), last.get("upper")
    ok = (a is None or a <= lo * (1 + 1e-12) + 1e-12) and (hi is None or b is None or b >= hi * (1 - 1e-12) - 1e-12)
    if a is None and b is None:
        return "-"
    return ("yes" if ok else "NO") + ("" if a is not None and b is not None else "*")


def _table(cases: list[tuple[str, Any, Any, tuple, Any]], methods: list[str], repeat: int, limit: float) -> list[str]:
    heads = ["problem", "lmic s", "solve s", "encl s", "verdict", "gap", "in", "cvxpy s", "ref err", "x"]
    heads += [f"{m} s" for m in methods]
    widths = [20, 7, 7, 7, 10, 8, 4, 8, 8, 6] + [max(8, len(m) + 2) for m in methods]
    lines = [" ".join(f"{h:>{w}}" for h, w in zip(heads, widths, strict=True)) + "  route"]
    for label, (target, system), cv_fn, cv_args, ref in cases:
        jobs = [("lmic", lmic_run, (target, system, None)), ("cvxpy", cv_fn, cv_args)]
        jobs += [(m, lmic_run, (target, system, m)) for m in methods]
        res = _rounds(jobs, repeat, limit, label)
        last = res["lmic"][-1]
        lm, cv = _med(res["lmic"], "total_s"), _med(res["cvxpy"], "total_s")
        obj = res["cvxpy"][-1].get("objective")
        # the theorems: CVXPY's optimum (its point meets the LMIs with eps margins, to its
        # tolerance) is checked against the proven lower end only
        lo, hi = ref if ref is not None else (obj, None)
        err = None if obj is None or lo is None else abs(obj - lo) / max(1.0, abs(lo))
        cells = [label, fmt(lm), fmt(_med(res["lmic"], "solve_s")), fmt(_med(res["lmic"], "enclosure_s"))]
        cells += [str(last.get("verdict", last.get("status")))[:10], fmt(last.get("rel_gap"), ".1e")]
        cells += [_inside(last, lo, hi), fmt(cv), fmt(err if ref is not None else None, ".1e")]
        cells += [fmt(ratio(cv, lm), ".2f")] + [fmt(_med(res[m], "total_s")) for m in methods]
        lines.append(" ".join(f"{c:>{w}}" for c, w in zip(cells, widths, strict=True)) + "  " + last.get("route", ""))
    return lines


def _warm_up() -> None:
    """Imports and plans once in the parent (not Clarabel: a forked child of a process that has
    run Clarabel hangs in its thread pool)."""
    import clarabel  # noqa: F401
    import cvxpy  # noqa: F401
    from routes import brl_system

    from lmic.api import load_target, solve

    for backend in ("scs", "cvxopt", "sdpa"):
        solve("tutorial.bounded_real", brl_system(3, 0), backend=backend, backoff=0)
    for tid in ("uncertain_dt.thm1", "delay_b.thm4_1"):
        load_target(tid, _plant(tid, 2, 0))


def main(argv: list[str] | None = None) -> int:
    """Run the tables (interleaved rounds) and print them."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--brl-sizes", default="10,20,30,40")
    ap.add_argument("--kinds", default="random,eighths", help="bounded-real lemma systems: random, eighths, near")
    ap.add_argument("--theorem-sizes", default="4,8")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--limit", type=float, default=300.0, help="seconds per run")
    ap.add_argument("--methods", default="", help="lmic with one backend alone, e.g. clarabel,cvxopt,sdpa")
    ap.add_argument("--only", default="brl,theorems")
    ap.add_argument("--quick", action="store_true", help="n = 10, 40 eighths and n = 4, one round")
    args = ap.parse_args(argv)
    if args.quick:
        args.brl_sizes, args.kinds, args.theorem_sizes, args.repeat = "10,40", "eighths", "4", 1
    warnings.simplefilter("ignore")
    _warm_up()
    ints = lambda s: [int(v) for v in s.split(",") if v]  # noqa: E731
    methods = [m for m in args.methods.split(",") if m]
    only = set(args.only.split(","))
    out: list[str] = []
    if "brl" in only:
        cases = []
        kinds = [k for k in args.kinds.split(",") if k]
        unknown = [k for k in kinds if k not in BRL_KINDS]
        if unknown:
            ap.error(f"unknown --kinds {', '.join(unknown)}; known: {', '.join(BRL_KINDS)}")
        for label, _problem, bracket in brl_problems(ints(args.brl_sizes), tuple(kinds)):
            system = _system_of(label)  # the same system, for lmic's bind and the CVXPY version
            cases.append((label, ("tutorial.bounded_real", system), _cvxpy_brl, (system,), bracket))
        out += ["", "Bounded-real lemma (min gamma); in: the enclosure contains the H-infinity norm"]
        out += _table(cases, methods, args.repeat, args.limit)
    if "theorems" in only:
        from lmic.api import load_target

        cases = []
        for tid in ("uncertain_dt.thm1", "delay_b.thm4_1"):
            for n in ints(args.theorem_sizes):
                plant = _plant(tid, n, 1)
                problem = load_target(tid, plant)[0]
                cases.append((f"{tid} n={n}", (tid, plant), cvxpy_ir, (_prepare(problem),), None))
        out += ["", "uncertain_dt.thm1, delay_b.thm4_1 (random plants); in: the lower end is below CVXPY's optimum"]
        out += _table(cases, methods, args.repeat, args.limit)
    out.append("  x: CVXPY + Clarabel's median over lmic's (> 1: lmic faster); * = one end of the enclosure missing")
    print("\n".join(out))
    return 0


def _system_of(label: str) -> dict[str, Any]:
    """The system of a :func:`enclosure.brl_problems` case (``brl n=N KIND``), from its generator."""
    n = int(label.split("n=")[1].split()[0])
    return brl_system(n, label.split()[-1])


if __name__ == "__main__":
    sys.exit(main())
