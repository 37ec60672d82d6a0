"""Clarabel's memory: the guard's estimate (:func:`lmic.backends.clarabel.kkt_bytes`) against the
measured peak resident memory of a solve.

Each measurement runs in a fresh child process (``python benchmarks/clarabel_memory.py --child
KIND D``): it builds the problem, reads its resident memory and resets the peak (``VmRSS``,
``VmHWM`` of ``/proc/self/status``; ``resource.getrusage`` elsewhere), runs
``ClarabelBackend().solve`` with ``max_iter = 2`` (the peak is reached at the setup and the
first factorisation of the KKT system; more iterations reuse that memory) and reads the peak
again. The solve's memory is the difference. Problems:

* ``maxcut``: ``min sum x`` s.t. ``diag(x) - W/4 >= 0`` (SDPLIB's maxcut form, one ``d x d``
  LMI, 10 % dense graph): an optimisation problem, Clarabel without chordal decomposition;
* ``lyapunov``: ``P > 0``, ``A'P + PA < 0`` for a random stable ``A`` (two dense ``d x d`` LMIs):
  a strict feasibility problem (lmic's strict reduction, chordal decomposition on).

The table prints, per problem and size, the PSD entries ``sum t_i^2`` (``t = d(d+1)/2``), the
estimate, the measured peak and their ratio, and the least-squares bytes per ``t^2`` entry (with a
constant) over the runs: the figure :data:`lmic.backends.clarabel.BYTES_PER_KKT_ENTRY` uses.
Usage::

    python benchmarks/clarabel_memory.py                         # both problems, d = 40..120
    python benchmarks/clarabel_memory.py --sizes 60,100,140 --kinds maxcut

Examples
--------
>>> maxcut(8).lmis[0].dim, lyapunov(5).n
(8, 15)
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys

import numpy as np
import scipy.sparse as sp

from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
from lmic.ir.svec import tril_index, tril_size
from lmic.reductions.pipeline import solve as solve_with_reductions


def maxcut(d: int) -> Problem:
    """``min sum x_i`` s.t. ``diag(x) - L/4 >= 0`` (max-cut SDP relaxation, dual form)."""
    rng = np.random.default_rng(d)
    W = np.triu((rng.random((d, d)) < 0.1).astype(float), 1)
    W = W + W.T
    lap = np.diag(W.sum(1)) - W
    i, j = np.nonzero(np.tril(lap))
    rows = list(tril_index(i, j, d)) + list(tril_index(np.arange(d), np.arange(d), d))
    cols = [0] * len(i) + list(range(1, d + 1))
    vals = list(-lap[i, j] / 4) + [1.0] * d
    coeffs = sp.csc_matrix((vals, (rows, cols)), shape=(tril_size(d), 1 + d))
    return Problem(
        [Variable("x", "full", (d, 1))],
        [LMI("block 1", d, coeffs, strict=False, relation=">=")],
        LinearConstraints.empty(d),
        Objective("min", np.r_[0.0, np.ones(d)]),
    )


def lyapunov(d: int) -> Problem:
    """``P > 0``, ``A'P + PA < 0`` for a random stable ``d x d`` matrix ``A``."""
    from lmic.testing.conformance import lyapunov_problem

    rng = np.random.default_rng(d)
    A = rng.standard_normal((d, d)) / np.sqrt(d)
    A -= (max(np.linalg.eigvals(A).real) + 0.5) * np.eye(d)
    return lyapunov_problem(A)


KINDS = {"maxcut": maxcut, "lyapunov": lyapunov}


def _status_kib(key: str) -> int | None:
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith(key + ":"):
                    return int(line.split()[1])
    except OSError:
        pass
    return None


def _reset_peak() -> int:
    """Current resident memory (bytes); resets the kernel's high-water mark where it can.

    ``getrusage``'s ``ru_maxrss`` survives ``exec``: a child of a large process (pytest) starts
    with its parent's size as its peak. ``VmHWM`` in ``/proc/self/status`` belongs to this
    process image, and writing ``5`` to ``/proc/self/clear_refs`` resets it (Linux >= 4.0).
    """
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
    except OSError:
        pass
    rss = _status_kib("VmRSS")
    return (rss if rss is not None else resource.getrusage(resource.RUSAGE_SELF).ru_maxrss) * 1024


def _peak() -> int:
    """Peak resident memory of this process image (bytes): ``VmHWM``, else ``ru_maxrss``."""
    hwm = _status_kib("VmHWM")
    return (hwm if hwm is not None else resource.getrusage(resource.RUSAGE_SELF).ru_maxrss) * 1024


def child(kind: str, d: int) -> None:
    """Measure one solve; print one JSON line."""
    from lmic.backends.base import SolveOptions
    from lmic.backends.clarabel import ClarabelBackend, kkt_bytes

    problem = KINDS[kind](d)
    be = ClarabelBackend()
    solve_with_reductions(be, KINDS[kind](4), SolveOptions(max_iter=2))  # imports and first-call allocations
    before = _reset_peak()
    sol = solve_with_reductions(be, problem, SolveOptions(max_iter=2))
    after = _peak()
    entries = sum((lmi.dim * (lmi.dim + 1) // 2) ** 2 for lmi in problem.lmis)
    print(
        json.dumps(
            {
                "kind": kind,
                "d": d,
                "entries": entries,
                "estimate": kkt_bytes(problem),
                "measured": max(0, after - before),
                "status": sol.native_status,
            }
        )
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", default="40,60,80,100,120")
    ap.add_argument("--kinds", default="maxcut,lyapunov")
    ap.add_argument("--child", nargs=2, metavar=("KIND", "D"))
    args = ap.parse_args()
    if args.child:
        child(args.child[0], int(args.child[1]))
        return
    rows = []
    for d in [int(v) for v in args.sizes.split(",")]:
        for kind in args.kinds.split(","):
            out = subprocess.run(
                [sys.executable, __file__, "--child", kind, str(d)], capture_output=True, text=True, check=False
            )
            if out.returncode != 0:
                print(f"{kind} d={d}: child failed: {out.stderr.strip().splitlines()[-1:]}")
                continue
            rows.append(json.loads(out.stdout.strip().splitlines()[-1]))
            r = rows[-1]
            print(
                f"{r['kind']:9s} d={r['d']:4d}  sum t^2 = {r['entries']:.3e}  estimate {r['estimate'] / 2**20:9.1f} MiB"
                f"  measured {r['measured'] / 2**20:9.1f} MiB  measured/estimate {r['measured'] / r['estimate']:.2f}"
                f"  bytes/entry {r['measured'] / r['entries']:.1f}",
                flush=True,
            )
    if len(rows) >= 2:
        X = np.array([[r["entries"], 1.0] for r in rows])
        y = np.array([r["measured"] for r in rows], dtype=float)
        (a, b), *_ = np.linalg.lstsq(X, y, rcond=None)
        worst = (
            max(r["measured"] / r["entries"] for r in rows if r["entries"] > 1e6)
            if any(r["entries"] > 1e6 for r in rows)
            else float("nan")
        )
        print(
            f"least squares: measured = {a:.1f} bytes x sum t^2 + {b / 2**20:.1f} MiB; "
            f"worst bytes/entry (t^2 > 1e6) {worst:.1f}"
        )


if __name__ == "__main__":
    main()
