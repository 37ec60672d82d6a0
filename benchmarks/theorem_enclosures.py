"""Survey: certified enclosures of the optimal value on random instances of every optimisation theorem.

For each theorem of ``tests/plugins/optimisation_instances.THEOREMS``, ``--seeds`` random
instances at each state dimension of ``--sizes`` are solved by lmic (default route and each
``--backends``), and the enclosure is compared with the optimum computed independently (the
theorem's LMIs written directly in CVXPY, closed problem, Clarabel at 1e-10). One row per
theorem and backend: instances, how many have a certified lower end, the largest relative gap
among them (VSDP's ``(upper - lower) / max(1, (|upper| + |lower|) / 2)``), how many enclosures
contain the reference (within its accuracy), the median time of ``lmic.api.solve``.

Usage::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=.:plugins python benchmarks/theorem_enclosures.py [--seeds 5]
        [--sizes 2 4] [--backends auto clarabel cvxopt sdpa scs] [--only delay_a.thm3_2 ...] [--verbose]
        [--first-seed 0] [--json results.json]

``--json`` writes every instance's row (theorem, backend, size, seed, verdict, ends, gap, inside,
time) and the summary rows, so that several shorter runs can be merged.

The times are wall-clock on whatever else the machine runs. The enclosure's budgets count
processor time (:class:`lmic.route_escalation.RouteClock`, the dual search's
``time.process_time``), so a loaded machine shows longer times, not larger gaps.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
import warnings
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "plugins"))

import optimisation_instances as oi  # noqa: E402

from lmic.api import solve  # noqa: E402


def run(tid: str, system: dict[str, Any], backend: str, ref: tuple[str, float | None, float]) -> dict[str, Any]:
    """One lmic solve and its comparison with the reference."""
    t0 = time.perf_counter()
    try:
        r = solve(tid, system, backend=None if backend == "auto" else backend)
    except Exception as exc:  # a survey records crashes, it does not stop on them
        return {"verdict": f"error: {type(exc).__name__}", "time": time.perf_counter() - t0, "lower": False}
    dt = time.perf_counter() - t0
    enc = r.enclosure or {}
    status, value, tol = ref
    inside = oi.contains(enc, value, tol) if value is not None else None
    return {
        "verdict": r.verdict,
        "time": dt,
        "lower": enc.get("lower") is not None and enc.get("upper") is not None,
        "rel_gap": enc.get("rel_gap"),
        "lower_end": enc.get("lower"),
        "upper_end": enc.get("upper"),
        "reference": value,
        "route": (r.route or {}).get("text"),
        "inside": inside,
        "ref_status": status,
        "backend": r.backend,
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--sizes", type=int, nargs="+", default=[2, 4])
    ap.add_argument("--backends", nargs="+", default=["auto", "clarabel", "cvxopt", "sdpa", "scs"])
    ap.add_argument("--only", nargs="*", default=None)
    ap.add_argument("--first-seed", type=int, default=0, help="seeds first-seed .. first-seed + seeds - 1")
    ap.add_argument("--json", default=None, help="write every instance's row and the summary here")
    ap.add_argument("--verbose", action="store_true", help="one line per instance as well")
    args = ap.parse_args(argv)
    warnings.filterwarnings("ignore")
    print(
        f"{'theorem':22s} {'backend':9s} {'inst':>4s} {'lower':>5s} {'max gap':>9s} {'med gap':>9s} "
        f"{'inside':>6s} {'t med s':>7s}  verdicts"
    )
    every: list[dict[str, Any]] = []
    summary: list[dict[str, Any]] = []
    for tid in oi.THEOREMS:
        if args.only and tid not in args.only:
            continue
        cases, missing = [], []
        for n in args.sizes:
            for seed in range(args.first_seed, args.first_seed + args.seeds):
                try:
                    system = oi.instance(tid, seed, n)
                except RuntimeError:  # the generator found no feasible draw at this size
                    missing.append(f"seed {seed} n {n}")
                    continue
                cases.append((system, oi.reference(tid, system), n, seed))
        if missing:
            print(f"{tid:22s} no feasible random draw for {', '.join(missing)}", flush=True)
        if not cases:
            continue
        for backend in args.backends:
            rows = []
            for system, ref, n, seed in cases:
                row = run(tid, system, backend, ref)
                row.update(theorem=tid, requested=backend, n=n, seed=seed)
                rows.append(row)
            every.extend(rows)
            if args.verbose:
                for k, r in enumerate(rows):
                    print(f"    {tid} {backend} case {k}: {r}")
            gaps = [r["rel_gap"] for r in rows if r["lower"] and r["rel_gap"] is not None]
            inside = [r["inside"] for r in rows if r.get("inside") is not None]
            verdicts: dict[str, int] = {}
            for r in rows:
                verdicts[r["verdict"]] = verdicts.get(r["verdict"], 0) + 1
            refs = {r.get("ref_status") for r in rows}
            summary.append(
                {
                    "theorem": tid,
                    "backend": backend,
                    "instances": len(rows),
                    "lower": sum(r["lower"] for r in rows),
                    "max_gap": max(gaps) if gaps else None,
                    "inside": sum(bool(v) for v in inside),
                    "compared": len(inside),
                    "median_s": statistics.median(r["time"] for r in rows),
                    "verdicts": verdicts,
                }
            )
            print(
                f"{tid:22s} {backend:9s} {len(rows):4d} {sum(r['lower'] for r in rows):5d} "
                f"{(max(gaps) if gaps else float('nan')):9.2e} "
                f"{(statistics.median(gaps) if gaps else float('nan')):9.2e} "
                f"{sum(bool(v) for v in inside):3d}/{len(inside):<2d} "
                f"{statistics.median(r['time'] for r in rows):7.2f}  "
                + ", ".join(f"{k} {v}" for k, v in sorted(verdicts.items()))
                + ("" if refs <= {"optimal"} else f"  (reference: {', '.join(sorted(str(s) for s in refs))})"),
                flush=True,
            )
        if args.json:
            Path(args.json).write_text(json.dumps({"rows": every, "summary": summary}, indent=1, default=str))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
