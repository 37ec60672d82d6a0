"""Benchmark: compile qib.thm1 on random systems, against CVXPY's build + canonicalisation.

Prints, for n = 10, 20, 40, 60, 100 (p = n/2): the one-off plan time; the first bind at these
dimensions (direct sparse assembly); the bind time (median of several binds of the cached plan,
as in a parameter sweep: only the numbers are recomputed); the number of non-zero IR
coefficients; and the time CVXPY takes to build the same LMI and canonicalise it for Clarabel
(``get_problem_data``), with both speed-ups.

Run: ``python benchmarks/compile.py [--sizes 10,20,40] [--repeat 5]``
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from lmic.compile import analyse, bind
from lmic.registry import get_theorem
from lmic.system import load_system


def random_system(n: int, seed: int = 0) -> dict:
    rng = np.random.default_rng(seed)
    p = max(1, n // 2)
    A = rng.standard_normal((n, n))
    A *= 0.9 / max(abs(np.linalg.eigvals(A)))
    C = rng.standard_normal((p, n))
    return {"lmic": 1, "data": {"A": A.tolist(), "C": C.tolist()}, "params": {"beta": 0.001, "gamma": 0.0}}


def cvxpy_build_seconds(system: dict) -> float:
    import cvxpy as cp

    A, C = system.data["A"], system.data["C"]
    n, p = A.shape[0], C.shape[0]
    beta, gamma = system.params["beta"], system.params["gamma"]
    t0 = time.perf_counter()
    P = cp.Variable((n, n), symmetric=True)
    R = cp.Variable((p, n))
    w = cp.Variable()
    X = A.T @ P - C.T @ R
    In = np.eye(n)
    Z = np.zeros((n, n))
    M = cp.bmat(
        [[-P + 2 * w * beta * In, X + w * gamma * In, X], [(X + w * gamma * In).T, P - 2 * w * In, Z], [X.T, Z, -P]]
    )
    cons = [P >> 1e-7 * In, -M >> 1e-7 * np.eye(3 * n), w >= 1e-7]
    prob = cp.Problem(cp.Minimize(0), cons)
    prob.get_problem_data(cp.CLARABEL)
    return time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--sizes", default="10,20,40,60,100")
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--no-cvxpy", action="store_true")
    args = ap.parse_args()
    thm = get_theorem("qib.thm1")
    t0 = time.perf_counter()
    plan = analyse(thm)
    plan_s = time.perf_counter() - t0
    print(f"plan (one-off analysis of qib.thm1): {plan_s * 1e3:.1f} ms")
    print(
        f"{'n':>4} {'p':>3} {'LMI dim':>8} {'nnz':>9} {'first bind ms':>14} {'bind ms':>8} {'ns/nnz':>7}"
        f" {'cvxpy ms':>9} {'x first':>8} {'x bind':>7}"
    )
    for n in (int(s) for s in args.sizes.split(",")):
        system = load_system(random_system(n))  # parsing the file is not part of bind
        t0 = time.perf_counter()
        bind(plan, system)  # first bind at these dimensions builds the cached assembly structure
        first_s = time.perf_counter() - t0
        times = []
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            prob = bind(plan, system)
            times.append(time.perf_counter() - t0)
        bind_s = statistics.median(times)
        nnz = sum(lmi.coeffs.nnz for lmi in prob.lmis)
        cv = float("nan") if args.no_cvxpy else cvxpy_build_seconds(system)
        print(
            f"{n:>4} {n // 2:>3} {prob.lmis[1].dim:>8} {nnz:>9} {first_s * 1e3:>14.1f} {bind_s * 1e3:>8.1f}"
            f" {bind_s / nnz * 1e9:>7.0f}"
            f" {cv * 1e3:>9.1f} {cv / first_s:>7.1f}x {cv / bind_s:>6.1f}x"
        )


if __name__ == "__main__":
    main()
