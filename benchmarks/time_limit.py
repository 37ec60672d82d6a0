"""Time-limit overshoot per backend: how long ``Backend.solve`` takes past ``--time-limit``.

Problem: the bounded-real lemma (``min gamma``, strict LMIs) on a random stable system with
``n`` states (default 40: every backend needs longer than the limits below to solve it).
For every backend and limit the solve runs ``--repeat`` times, backends *interleaved* (one round
runs each backend once, rotated), in this process (imports warmed up first). Reported: the
median wall time of ``Backend.solve``, the median overshoot ``wall - limit``, and whether every
run ended with the time-limit result (``status == "error"`` and ``info["time_limit"]``).
Usage::

    python benchmarks/time_limit.py                       # n = 40, limits 0.001, 0.5, 2
    python benchmarks/time_limit.py --n 30 --limits 0.01,1 --repeat 5

Examples
--------
>>> brl(4).n
11
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from lmic.backends.base import SolveOptions
from lmic.backends.outcomes import is_time_limit
from lmic.backends.registry import get_backend
from lmic.ir.problem import Problem
from lmic.reductions.pipeline import solve as solve_with_reductions
from lmic.testing.conformance import bounded_real_problem

BACKENDS = ["clarabel", "scs", "cvxopt", "sdpa", "cvxpy", "cvxpy:SCS", "picos"]


def brl(n: int, seed: int = 7) -> Problem:
    """The bounded-real-lemma problem of a random stable ``n``-state system (2 inputs, 2 outputs)."""
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    A -= (max(np.linalg.eigvals(A).real) + 0.5) * np.eye(n)
    return bounded_real_problem(A, rng.standard_normal((n, 2)), rng.standard_normal((2, n)))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=40)
    ap.add_argument("--limits", default="0.001,0.5,2")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--backends", default=",".join(BACKENDS))
    args = ap.parse_args()
    problem = brl(args.n)
    names = args.backends.split(",")
    limits = [float(v) for v in args.limits.split(",")]
    for name in names:  # warm the imports (not part of any limit)
        solve_with_reductions(get_backend(name), brl(3))
    walls: dict[tuple[str, float], list[float]] = {(b, lim): [] for b in names for lim in limits}
    stopped: dict[tuple[str, float], bool] = {(b, lim): True for b in names for lim in limits}
    for r in range(args.repeat):
        order = names[r % len(names) :] + names[: r % len(names)]
        for lim in limits:
            for name in order:
                t0 = time.perf_counter()
                sol = solve_with_reductions(get_backend(name), problem, SolveOptions(time_limit=lim))
                walls[(name, lim)].append(time.perf_counter() - t0)
                stopped[(name, lim)] &= sol.status == "error" and is_time_limit(sol)
    print(f"bounded-real lemma, n = {args.n} ({problem.n} variables), {args.repeat} interleaved rounds")
    print(f"{'backend':12s} {'limit (s)':>9s} {'median wall (s)':>15s} {'overshoot (s)':>13s}  stopped")
    for name in names:
        for lim in limits:
            med = statistics.median(walls[(name, lim)])
            print(f"{name:12s} {lim:9g} {med:15.3f} {med - lim:13.3f}  {'yes' if stopped[(name, lim)] else 'NO'}")


if __name__ == "__main__":
    main()
