"""Survey: lmic's verdicts on fresh random instances of the feasibility theorems, against CVXPY.

Every generator and every reference is the test-suite's own (``tests/plugins/test_*.py``: the
random plants and the theorems' LMIs written directly in CVXPY from the catalogues, not
through lmic), drawn here on seeds (and, where the generator takes one, state dimensions) the
tests do not use. The reference decides an instance by the largest margin ``t`` of the strict
LMIs (CVXPY, Clarabel): feasible when ``t`` is clearly positive, infeasible when clearly
negative (or below the phase-1 threshold), too close to call otherwise (skipped).

A row is a **finding** when lmic certifies an instance the reference finds infeasible, does not
certify one the reference finds strictly feasible (``rejected``, ``undecided``, an
infeasibility verdict), or crashes.

Usage::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=.:plugins python benchmarks/feasibility_seeds.py
        [--seeds 3] [--first-seed 1000] [--backends auto clarabel cvxopt] [--only qib.thm1 ...]
        [--json rows.json]
"""

from __future__ import annotations

import argparse
import importlib
import json
import statistics
import sys
import time
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "plugins"))

from lmic.api import solve  # noqa: E402

Case = tuple[dict[str, Any], bool | None, str]  # system, reference verdict, label


def _mod(name: str) -> Any:
    return importlib.import_module(name)


def _margin(t: float | None) -> bool | None:
    """A max-margin reference: feasible above 1e-5, infeasible below -1e-5 (the tests' rule)."""
    if t is None:
        return None
    return True if t > 1e-5 else (False if t < -1e-5 else None)


def _lists(d: dict[str, Any]) -> dict[str, Any]:
    return {k: np.asarray(v, dtype=float).tolist() for k, v in d.items()}


def sampled_euler_thm1(seed: int, n: int) -> Iterator[Case]:
    import cvxpy as cp

    m, h = _mod("test_sampled_euler"), _mod("seeds_helpers")
    A, C, Q = m.random_system(np.random.default_rng(seed), n=n)
    for gd in (0.01, 0.3):
        P, G, eps = cp.Variable((n, n), symmetric=True), cp.Variable((n, 1)), cp.Variable()
        s = m.psi1(Q, gd)
        ref = h.cvx_feasible(
            [], [P, m.cvx_lmi6(P, G, eps, Q, A, C), cp.bmat([[s * np.eye(n), P], [P, s * np.eye(n)]])], [eps]
        )
        yield {"lmic": 1, "data": _lists({"Ad": A, "Cd": C, "Q": Q}), "params": {"gamma_d": gd}}, ref, f"gd={gd}"


def qib_thm1(seed: int, n: int) -> Iterator[Case]:
    import cvxpy as cp

    m, h = _mod("test_qib"), _mod("seeds_helpers")
    A, C, _ = m.random_plant(seed, n=n)
    for beta, gamma in ((0.01, 0.1), (0.5, 0.0)):
        P, R, w = cp.Variable((n, n), symmetric=True), cp.Variable((1, n)), cp.Variable()
        ref = h.cvx_feasible([m.lmi7(A, C, P, R, w, beta, gamma, cp.bmat)], [P], [w], box=[P, R, w])
        yield (
            {"lmic": 1, "data": _lists({"A": A, "C": C}), "params": {"beta": beta, "gamma": gamma}},
            ref,
            f"beta={beta}",
        )


def qib_thm2(seed: int, n: int) -> Iterator[Case]:
    import cvxpy as cp

    m, h = _mod("test_qib"), _mod("seeds_helpers")
    A, C, H = m.random_plant(seed, n=n, p=1, rho=0.9)
    for beta in (0.001, 0.2):
        K, w = cp.Variable((n - 1, 1)), cp.Variable()
        ref = h.cvx_feasible([m.lmi26(A, C, H, K, w, 1.0, beta, 0.0, cp.bmat)], [], [w], box=[K, w])
        yield {"lmic": 1, "data": _lists({"A": A, "C": C, "H": H}), "params": {"beta": beta}}, ref, f"beta={beta}"


def nonuniform_thm1(seed: int, n: int) -> Iterator[Case]:
    import cvxpy as cp

    m, h = _mod("test_nonuniform"), _mod("seeds_helpers")
    D = m.random_system(seed, n=n)
    for gamma, delta in ((0.2, 0.05), (3.0, 0.5)):
        P, Lt = cp.Variable((n, n), symmetric=True), cp.Variable((n, 1))
        N1, N2, N3 = cp.Variable((n, n)), cp.Variable((n, n)), cp.Variable((1, n))
        a, b = m.lmi9(D["A"], D["C"], D["G"], D["H"], gamma, delta, P, Lt, N1, N2, N3, cp.bmat)
        ref = h.cvx_feasible([a, b], [P])
        yield m.sysdict(D, gamma=gamma, delta_bar=delta), ref, f"gamma={gamma}"


def thesis_thm3_2_1(seed: int, n: int) -> Iterator[Case]:
    m = _mod("test_thesis")
    for hidden in (False, True):
        A, C = m._observable_pair(np.random.default_rng(seed), n, 1, unstable_hidden=hidden)
        status, _ = m._ref_luenberger(A, C)
        ref = True if status == "optimal" else (False if status == "infeasible" else None)
        yield m._sys(A=A, B=np.ones((n, 1)), C=C), ref, f"hidden={hidden}"


def thesis_thm4_1_2_linear(seed: int, n: int) -> Iterator[Case]:
    m = _mod("test_thesis")
    rng = np.random.default_rng(seed)
    A, C, D = rng.normal(size=(n, n)), rng.normal(size=(1, n)), rng.normal(size=(n, 1))
    status, _ = m._ref_ct_uio(A, C, D, nonlinear=False)
    ref = True if status == "optimal" else (False if status == "infeasible" else None)
    yield m._sys(A=A, B=np.ones((n, 1)), C=C, D=D), ref, ""


def uio_dt_thm3_2(seed: int, n: int) -> Iterator[Case]:
    m = _mod("test_uio_dt")
    d = m._random_plant(seed)
    for gamma in (0.05, 0.3, 4.0):
        yield m._system(d, gamma=gamma), _margin(m._cvx_thm3_2(d, gamma)), f"gamma={gamma}"


def uio_dt_thm3_1(seed: int, n: int) -> Iterator[Case]:
    m = _mod("test_uio_dt")
    rng = np.random.default_rng(seed)
    N = rng.normal(size=(3, 3))
    N *= 0.8 / max(abs(np.linalg.eigvals(N)))
    M, D = rng.normal(size=(3, 3)), rng.normal(size=(3, 1))
    for gamma in (0.1, 2.0):
        ref = _margin(m._cvx_thm3_1(N, M, D, gamma))
        yield m._system({"N": N, "M": M, "D": D}, gamma=gamma), ref, f"gamma={gamma}"


def descriptor_thm3_1(seed: int, n: int) -> Iterator[Case]:
    m = _mod("test_descriptor")
    g = m._random_filter_gains(seed)
    for gamma in (0.05, 5.0):
        data = {k: g[k] for k in ("N", "J", "M", "D")}
        yield m._system(data, gamma=gamma), _margin(m._cvx_thm3_1(g, gamma)), f"gamma={gamma}"


def descriptor_thm3_2(seed: int, n: int) -> Iterator[Case]:
    m = _mod("test_descriptor")
    g = m._random_filter_gains(seed)
    for gamma, mu in ((0.01, 50.0), (0.05, 0.5)):
        yield m._system(g, gamma=gamma, mu=mu), _margin(m._cvx_thm3_2(g, gamma, mu)), f"gamma={gamma},mu={mu}"


def descriptor_thm3_3(seed: int, n: int) -> Iterator[Case]:
    m = _mod("test_descriptor")
    for q1, gamma, mu in ((2, 0.1, 20.0), (1, 0.1, 20.0), (2, 0.1, 0.2)):
        d = m._random_plant(seed, q1)
        yield m._system(d, gamma=gamma, mu=mu), _margin(m._cvx_thm3_3(d, gamma, mu)), f"q1={q1},mu={mu}"


def uir_thm3_1(seed: int, n: int) -> Iterator[Case]:
    m = _mod("test_uir")
    g = m._random_gains(seed)
    for gamma in (0.1, 20.0):
        data = {k: g[k] for k in ("N", "J", "M")}
        yield m._system(data, gamma=gamma), _margin(m._cvx_thm3_1(g, gamma)), f"gamma={gamma}"


def uir_thm3_2(seed: int, n: int) -> Iterator[Case]:
    m = _mod("test_uir")
    g = m._random_gains(seed)
    for gamma, mu in ((0.1, 20.0), (0.1, 0.05)):
        yield m._system(g, gamma=gamma, mu=mu), _margin(m._cvx_thm3_2(g, gamma, mu)), f"mu={mu}"


def obs_control_thm3_1(seed: int, n: int) -> Iterator[Case]:
    m = _mod("test_obs_control")
    d = m._random_plant(seed)
    for gamma, alpha in ((0.1, 10.0), (0.1, 1.0), (3.0, 1.0)):
        sysd = m._system(d, gamma=gamma, alpha=alpha, **m.SCALARS)
        yield sysd, _margin(m._cvx_thm3_1(d, gamma, alpha)), f"gamma={gamma},alpha={alpha}"


def obs_control_thm3_2(seed: int, n: int) -> Iterator[Case]:
    m = _mod("test_obs_control")
    d = {k: v for k, v in m._random_plant(seed).items() if k not in ("K", "L")}
    for gamma, alpha, eps in ((0.1, 10.0, 1.0), (0.1, 2.0, 0.5), (0.1, 1.0, 1.0)):
        sysd = m._system(d, gamma=gamma, alpha=alpha, eps=eps, **m.SCALARS)
        yield sysd, _margin(m._cvx_thm3_2(d, gamma, alpha, eps)), f"alpha={alpha},eps={eps}"


#: theorem id -> (instances of one seed and size, the sizes it takes: None = fixed by the generator)
GENERATORS: dict[str, tuple[Callable[[int, int], Iterator[Case]], tuple[int, ...] | None]] = {
    "sampled_euler.thm1": (sampled_euler_thm1, (2, 4, 6)),
    "qib.thm1": (qib_thm1, (3, 5, 7)),
    "qib.thm2": (qib_thm2, (3, 5, 7)),
    "nonuniform.thm1": (nonuniform_thm1, (3, 5)),
    "thesis.thm3_2_1": (thesis_thm3_2_1, (3, 6)),
    "thesis.thm4_1_2_linear": (thesis_thm4_1_2_linear, (3, 5)),
    "uio_dt.thm3_1": (uio_dt_thm3_1, None),
    "uio_dt.thm3_2": (uio_dt_thm3_2, None),
    "descriptor.thm3_1": (descriptor_thm3_1, None),
    "descriptor.thm3_2": (descriptor_thm3_2, None),
    "descriptor.thm3_3": (descriptor_thm3_3, None),
    "uir.thm3_1": (uir_thm3_1, None),
    "uir.thm3_2": (uir_thm3_2, None),
    "obs_control.thm3_1": (obs_control_thm3_1, None),
    "obs_control.thm3_2": (obs_control_thm3_2, None),
}


def finding(ref: bool | None, verdict: str) -> str | None:
    """Why a verdict disagrees with the reference (``None`` when it agrees or the reference is undecided).

    >>> finding(True, "certified"), finding(False, "certified"), finding(True, "undecided")
    (None, 'certified an infeasible instance', 'no certificate for a strictly feasible instance')
    """
    if verdict.startswith("error"):
        return "crash"
    if ref is None:
        return None
    if ref is False and verdict == "certified":
        return "certified an infeasible instance"
    if ref is True and verdict != "certified":
        return "no certificate for a strictly feasible instance"
    return None


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--first-seed", type=int, default=1000)
    ap.add_argument("--backends", nargs="+", default=["auto", "clarabel", "cvxopt"])
    ap.add_argument("--only", nargs="*", default=None)
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    warnings.filterwarnings("ignore")
    rows: list[dict[str, Any]] = []
    head = f"{'theorem':24s} {'backend':9s} {'inst':>4s} {'feas':>4s} {'infs':>4s} {'skip':>4s} {'t med s':>7s}"
    print(head + "  verdicts / findings")
    for tid, (gen, sizes) in GENERATORS.items():
        if args.only and tid not in args.only:
            continue
        cases = []
        for n in sizes or (0,):
            for seed in range(args.first_seed, args.first_seed + args.seeds):
                try:
                    for system, ref, label in gen(seed, n):
                        cases.append((system, ref, f"seed {seed} n {n} {label}"))
                except Exception as exc:  # noqa: BLE001 - a reference that fails is reported, not fatal
                    print(f"{tid}: reference failed for seed {seed} n {n}: {type(exc).__name__}: {exc}")
        for backend in args.backends:
            mine = []
            for system, ref, label in cases:
                t0 = time.perf_counter()
                try:
                    verdict = solve(tid, system, backend=None if backend == "auto" else backend).verdict
                except Exception as exc:  # noqa: BLE001 - a survey records crashes
                    verdict = f"error: {type(exc).__name__}: {exc}"
                row = {
                    "theorem": tid,
                    "backend": backend,
                    "case": label,
                    "reference": ref,
                    "verdict": verdict,
                    "time": time.perf_counter() - t0,
                    "finding": finding(ref, verdict),
                }
                mine.append(row)
            rows.extend(mine)
            verdicts: dict[str, int] = {}
            for r in mine:
                key = r["verdict"] if not r["verdict"].startswith("error") else "error"
                verdicts[key] = verdicts.get(key, 0) + 1
            bad = [f"{r['case']}: {r['finding']} ({r['verdict']})" for r in mine if r["finding"]]
            print(
                f"{tid:24s} {backend:9s} {len(mine):4d} {sum(r['reference'] is True for r in mine):4d} "
                f"{sum(r['reference'] is False for r in mine):4d} {sum(r['reference'] is None for r in mine):4d} "
                f"{statistics.median(r['time'] for r in mine) if mine else float('nan'):7.2f}  "
                + ", ".join(f"{k} {v}" for k, v in sorted(verdicts.items()))
                + "".join(f"\n    FINDING {b}" for b in bad),
                flush=True,
            )
        if args.json:
            Path(args.json).write_text(json.dumps(rows, indent=1, default=str))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
