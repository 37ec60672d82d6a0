"""Decision rate and time to a decision: the default solve policy against each single backend.

Random instances of several theorem families (the shipped example of each, with every data
non-symmetric matrix replaced by a random one of the same shape, scaled by 0.3, 1 or 3 times the
example's largest entry: a mix of feasible and infeasible instances). Every instance is decided by every
method in one interleaved run (the order of the methods rotates from instance to instance):

* ``policy``: no ``--backend`` (the escalating policy of :mod:`lmic.policy`);
* ``clarabel``, ``cvxopt``, ``sdpa``, ``scs``: ``--backend X`` (that backend alone).

A *decision* is ``certified`` or ``infeasible-certified`` (a global proof); ``infeasible-bounded``
("no solution with ||x||_inf <= R") is counted apart. Each method's verdicts are checked against
the others': a certified point and a global infeasibility proof on the same instance would be a
false certificate (reported as ``conflicts``).

Usage::

    PYTHONPATH=.:plugins python benchmarks/decisions.py [--per-family 20] [--time-limit 30] [--json out.json]
"""

from __future__ import annotations

import argparse
import copy
import json
import statistics
import sys
import time
from pathlib import Path

import numpy as np
import yaml

ROOT = Path(__file__).resolve().parents[1]
FAMILIES = {
    "delay_a.thm3_2": "delay_a.thm3_2.example",
    "delay_b.thm4_1": "delay_b.thm4_1.ex1_lambda0_5",
    "uir.thm5_1": "uir.thm5_1.rossler",
    "sampled_euler.thm3": "sampled_euler.thm3.example",
    "uncertain_dt.thm1": "uncertain_dt.thm1.example",
    "thesis.thm3_2_2": "thesis.thm3_2_2.ex3_2_2",
}
METHODS = ("policy", "clarabel", "cvxopt", "sdpa", "scs")
DECISIONS = ("certified", "infeasible-certified")


def random_system(example: str, seed: int) -> dict:
    """The example's system with every non-symmetric data matrix random (same shape)."""
    rng = np.random.default_rng(seed)
    d = yaml.safe_load((ROOT / "examples" / f"{example}.yaml").read_text())
    d = copy.deepcopy(d)
    d.pop("published", None)
    scale = float(rng.choice([0.3, 1.0, 3.0]))
    for key, value in d["data"].items():
        a = np.asarray(value, dtype=float)
        if a.ndim != 2 or a.size <= 1:
            continue
        top = float(np.abs(a).max()) or 1.0
        if a.shape[0] == a.shape[1] and np.allclose(a, a.T):
            continue  # symmetric data (weights, Q = T I of sampled_euler.thm3) keep the example's value
        d["data"][key] = (scale * top * rng.standard_normal(a.shape)).tolist()
    return d


def run_one(theorem: str, system: dict, method: str, time_limit: float) -> tuple[str, float]:
    """(verdict, seconds) of one method on one instance; exceptions are ``error``."""
    from lmic.api import solve
    from lmic.backends.base import SolveOptions
    from lmic.errors import LmicError

    t0 = time.perf_counter()
    try:
        r = solve(
            theorem,
            system,
            backend=None if method == "policy" else method,
            options=SolveOptions(time_limit=time_limit),
        )
        verdict = r.verdict
    except LmicError as err:
        verdict = "bad input" if "cannot take" not in str(err) else "cannot take"
    except Exception as err:  # noqa: BLE001 - a benchmark records crashes
        verdict = f"error: {type(err).__name__}"
    return verdict, time.perf_counter() - t0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--per-family", type=int, default=17)
    ap.add_argument("--time-limit", type=float, default=30.0)
    ap.add_argument("--json", default=None)
    args = ap.parse_args()
    rows: list[dict] = []
    k = 0
    for seed in range(args.per_family):
        for theorem, example in FAMILIES.items():
            system = random_system(example, 1000 + seed)
            order = METHODS[k % len(METHODS) :] + METHODS[: k % len(METHODS)]
            k += 1
            rec: dict = {"theorem": theorem, "seed": seed}
            for method in order:
                verdict, secs = run_one(theorem, system, method, args.time_limit)
                rec[method] = {"verdict": verdict, "time_s": secs}
            verdicts = {rec[m]["verdict"] for m in METHODS}
            rec["conflict"] = "certified" in verdicts and "infeasible-certified" in verdicts
            rows.append(rec)
            print(
                f"[{len(rows)}] {theorem} seed {seed}: "
                + ", ".join(f"{m} {rec[m]['verdict']} {rec[m]['time_s']:.2f}s" for m in METHODS),
                file=sys.stderr,
                flush=True,
            )
    n = len(rows)
    print(f"\n{n} instances, {len(FAMILIES)} families, one interleaved run\n")
    print("| method | decided (global) | infeasible-bounded | no decision | median s to decision | median s (all) |")
    print("|---|---|---|---|---|---|")
    for m in METHODS:
        verdicts = [r[m]["verdict"] for r in rows]
        dec = [r[m]["time_s"] for r in rows if r[m]["verdict"] in DECISIONS]
        bounded = sum(v == "infeasible-bounded" for v in verdicts)
        none = n - len(dec) - bounded
        med = f"{statistics.median(dec):.2f}" if dec else "-"
        allm = statistics.median(r[m]["time_s"] for r in rows)
        print(f"| {m} | {len(dec)}/{n} ({100 * len(dec) / n:.0f} %) | {bounded} | {none} | {med} | {allm:.2f} |")
    some = sum(any(r[m]["verdict"] in DECISIONS for m in METHODS[1:]) for r in rows)
    pol = sum(r["policy"]["verdict"] in DECISIONS for r in rows)
    missed = [
        (r["theorem"], r["seed"])
        for r in rows
        if r["policy"]["verdict"] not in DECISIONS and any(r[m]["verdict"] in DECISIONS for m in METHODS[1:])
    ]
    print(f"\nsome single backend decides: {some}/{n}; the policy decides {pol}/{n}; policy misses: {missed}")
    print(f"conflicts (certified vs infeasible-certified on one instance): {sum(r['conflict'] for r in rows)}")
    for fam in FAMILIES:
        fr = [r for r in rows if r["theorem"] == fam]
        cells = ", ".join(f"{m} {sum(r[m]['verdict'] in DECISIONS for r in fr)}" for m in METHODS)
        print(f"  {fam} ({len(fr)}): {cells}")
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
