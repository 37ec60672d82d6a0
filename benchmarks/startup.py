"""Start-up of the ``lmic`` command against an ``import numpy`` process, and the plan cache.

Whole processes (interpreter start and imports included), run in one interleaved loop: each
round runs every method once, in a rotated order; reported are medians over the rounds and the
ratio to ``python -c "import numpy"`` (issue 14: ``lmic --version`` at most 3x, ``lmic
theorems`` at most 6x). Methods:

* ``import numpy``: ``python -c "import numpy"``, the yardstick;
* ``lmic --version``;
* ``lmic theorems``: with the theorem index warm in the cache (``lmic.plugin_index``), and with
  ``LMIC_NO_CACHE=1`` (every plugin imported: the path before the index);
* ``lmic solve qib.thm1 examples/qib.thm1.flexible-joint.yaml --json``: with an empty cache
  folder each time (cold: the template is analysed) and with a warm one (the analysed plan is
  read from the cache); ``compile_s`` (template build + analysis or cache read + bind) is
  taken from the JSON's ``timings``;
* lmic's own share of the warm one-shot solve: ``1 - solve_s / wall`` (``solve_s``: the
  solver's own time, from the JSON) -- for the small example (where start-up dominates) and,
  with ``--n N``, for a random ``N``-state ``qib.thm1`` system;
* ``plan_for`` alone in a new process (imports excluded): template build plus analysis with the
  cache off, with an empty cache (analysis + storing) and warm (cache read), for three theorems.

Every process runs the code of this checkout (``PYTHONPATH`` = the checkout and its
``plugins/``). Usage::

    python benchmarks/startup.py                # 7 rounds
    python benchmarks/startup.py --rounds 11 --n 30

Examples
--------
>>> median_ratio([1.0, 3.0, 2.0], [0.5, 0.5, 0.5])
(2.0, 4.0)
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "qib.thm1.flexible-joint.yaml"
LMIC = [sys.executable, "-c", "from lmic.cli import _entry; _entry()"]


def median_ratio(times: list[float], base: list[float]) -> tuple[float, float]:
    """Median of ``times`` and its ratio to the median of ``base``."""
    m = statistics.median(times)
    return m, m / statistics.median(base)


def _env(**extra: str) -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(
        [str(ROOT), str(ROOT / "plugins")] + ([env["PYTHONPATH"]] if env.get("PYTHONPATH") else [])
    )
    env.pop("LMIC_NO_CACHE", None)
    env.update(extra)
    return env


def _run(cmd: list[str], env: dict[str, str]) -> tuple[float, str]:
    t0 = time.perf_counter()
    out = subprocess.run(cmd, env=env, cwd=ROOT, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if out.returncode not in (0, 1, 3):
        raise SystemExit(f"{' '.join(cmd[3:]) or cmd}: exit {out.returncode}: {out.stderr.strip()[:300]}")
    return wall, out.stdout


def _random_qib_system(n: int, path: Path, seed: int = 0) -> None:
    """A random discrete-time ``qib.thm1`` system (spectral radius 0.9, ``p = n/2``) as JSON."""
    import numpy as np

    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    A *= 0.9 / max(abs(np.linalg.eigvals(A)))
    C = rng.standard_normal((max(1, n // 2), n))
    doc = {"lmic": 1, "data": {"A": A.tolist(), "C": C.tolist()}, "params": {"beta": 1e-3, "gamma": 0.0}}
    path.write_text(json.dumps(doc))


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--n", type=int, default=0, help="also a warm solve of a random N-state qib.thm1 system")
    args = ap.parse_args(argv)
    work = Path(tempfile.mkdtemp(prefix="lmic-startup-"))
    warm_dir = work / "warm"
    solve = [*LMIC, "solve", "qib.thm1", str(EXAMPLE), "--json"]
    methods: dict[str, tuple[list[str], Any]] = {
        "import numpy": ([sys.executable, "-c", "import numpy"], lambda: _env()),
        "lmic --version": ([*LMIC, "--version"], lambda: _env(LMIC_CACHE_DIR=str(warm_dir))),
        "lmic theorems (index warm)": ([*LMIC, "theorems"], lambda: _env(LMIC_CACHE_DIR=str(warm_dir))),
        "lmic theorems (LMIC_NO_CACHE=1)": ([*LMIC, "theorems"], lambda: _env(LMIC_NO_CACHE="1")),
        "lmic solve (plan cache cold)": (solve, lambda: _env(LMIC_CACHE_DIR=tempfile.mkdtemp(dir=work))),
        "lmic solve (plan cache warm)": (solve, lambda: _env(LMIC_CACHE_DIR=str(warm_dir))),
    }
    if args.n:
        system = work / f"qib{args.n}.json"
        _random_qib_system(args.n, system)
        methods[f"lmic solve n={args.n} (warm)"] = (
            [*LMIC, "solve", "qib.thm1", str(system), "--json"],
            lambda: _env(LMIC_CACHE_DIR=str(warm_dir)),
        )
    # warm-up: the page cache, the theorem index and the plans in the warm folder
    for cmd, env in methods.values():
        _run(cmd, env())
    walls: dict[str, list[float]] = {m: [] for m in methods}
    timings: dict[str, list[dict[str, float]]] = {m: [] for m in methods}
    names = list(methods)
    for r in range(args.rounds):
        for name in names[r % len(names) :] + names[: r % len(names)]:
            cmd, env = methods[name]
            wall, out = _run(cmd, env())
            walls[name].append(wall)
            if "--json" in cmd:
                timings[name].append(json.loads(out)["timings"])
    base = walls["import numpy"]
    where = f"python {sys.version.split()[0]}, {os.cpu_count()} cpus"
    print(f"start-up, {args.rounds} interleaved rounds, medians ({where})")
    print(f"{'method':38} {'wall s':>8} {'x numpy':>8} {'compile_s':>10} {'solver s':>9} {'lmic share':>11}")
    for name in names:
        med, ratio = median_ratio(walls[name], base)
        extra = ""
        if timings[name]:
            comp = statistics.median(t["compile_s"] for t in timings[name])
            solver = statistics.median(t["solve_s"] for t in timings[name])
            share = statistics.median(1 - t["solve_s"] / w for t, w in zip(timings[name], walls[name], strict=True))
            extra = f" {comp:10.3f} {solver:9.3f} {share:10.0%}"
        print(f"{name:38} {med:8.3f} {ratio:7.2f}x{extra}")
    cold = statistics.median(t["compile_s"] for t in timings["lmic solve (plan cache cold)"])
    warm = statistics.median(t["compile_s"] for t in timings["lmic solve (plan cache warm)"])
    print(f"plan cache: compile_s {cold:.3f} s cold -> {warm:.3f} s warm ({cold - warm:+.3f} s of analysis skipped)")
    _plan_times(args.rounds, work)
    shutil.rmtree(work, ignore_errors=True)


PLAN_PROBE = """
import sys, time
from lmic.compile import plan_for
from lmic.registry import get_theorem
thm = get_theorem(sys.argv[1])
t0 = time.perf_counter()
plan_for(thm)
print(time.perf_counter() - t0)
"""


def _plan_times(rounds: int, work: Path) -> None:
    """``plan_for`` alone (template build + analysis, or + cache read), each in a new process."""
    ids = ["qib.thm1", "uncertain_dt.thm1", "delay_b.thm4_1"]
    warm_dir = work / "plans-warm"
    for tid in ids:  # fill the warm folder
        _run([sys.executable, "-c", PLAN_PROBE, tid], _env(LMIC_CACHE_DIR=str(warm_dir)))
    times: dict[tuple[str, str], list[float]] = {(tid, m): [] for tid in ids for m in ("off", "cold", "warm")}
    for _ in range(rounds):
        for tid in ids:
            for mode in ("off", "cold", "warm"):
                env = {
                    "off": _env(LMIC_NO_CACHE="1"),
                    "cold": _env(LMIC_CACHE_DIR=tempfile.mkdtemp(dir=work)),
                    "warm": _env(LMIC_CACHE_DIR=str(warm_dir)),
                }[mode]
                _, out = _run([sys.executable, "-c", PLAN_PROBE, tid], env)
                times[(tid, mode)].append(float(out.strip()))
    print("plan_for in a new process (template build + analysis / cache read), medians, s")
    print(f"{'theorem':22} {'no cache':>9} {'cold':>9} {'warm':>9} {'warm/no cache':>14}")
    for tid in ids:
        off, cold, warm = (statistics.median(times[(tid, m)]) for m in ("off", "cold", "warm"))
        print(f"{tid:22} {off:9.3f} {cold:9.3f} {warm:9.3f} {warm / off:13.2f}x")


if __name__ == "__main__":
    main()
