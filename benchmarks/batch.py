"""Batch benchmark: a shell loop of ``lmic solve`` against ``lmic batch`` (1 and 2 workers, Dask).

The study is ``examples/studies/qib_monte_carlo.yaml`` (200 random plants for ``qib.thm1``).
Methods, each timed as the wall clock of the whole command (start-up included, as a user sees
it):

- ``shell``: ``for f in plants/*.yaml; do lmic solve qib.thm1 $f -p beta=.. -p gamma=..; done``,
  over the first ``--loop-jobs`` plants (default 20; the throughput of a loop does not depend on
  its length, and 200 runs take several minutes);
- ``batch-1``, ``batch-2``: ``lmic batch STUDY -o FRESH_DIR --workers 1|2`` (local executor);
- ``dask-2``: ``lmic batch STUDY -o FRESH_DIR --executor dask --workers 2`` (a LocalCluster of two
  worker processes, started and stopped inside the command).

The methods run interleaved (each round runs every method once, in a rotated order) for
``--repeat`` rounds; the report gives the median jobs per second of each method, the speed-up of
``batch-1`` over the shell loop, and the scaling from 1 to 2 workers (``batch-2 / batch-1`` and
the efficiency ``(batch-2 / batch-1) / 2``). The load average is recorded around every run: the
machine may be shared; so is the CPU time of each run (user + system of every process it
started: the driver, its runners or Dask workers), which a busy machine does not inflate.

Every run uses one cache folder (``LMIC_CACHE_DIR`` in the work folder), warmed before the
timed rounds by a small study and one ``lmic solve``: the timed runs read the theorem's analysed
(frozen) plan as any run after the first does (:mod:`lmic.compile.warm`). Usage::

    python benchmarks/batch.py                      # 3 rounds
    python benchmarks/batch.py --repeat 5 --loop-jobs 30 --json out.json

Examples
--------
>>> rotate(["a", "b", "c"], 1)
['b', 'c', 'a']
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

__all__ = ["rotate", "main"]

REPO = Path(__file__).resolve().parents[1]
STUDY = REPO / "examples" / "studies" / "qib_monte_carlo.yaml"
METHODS = ["shell", "batch-1", "batch-2", "dask-2"]


def rotate(items: list[str], k: int) -> list[str]:
    """``items`` rotated left by ``k``."""
    k %= len(items)
    return items[k:] + items[:k]


#: the cache folder of every run (set by main), and the checkout compared with (--compare)
CACHE: dict[str, str] = {}
COMPARE: dict[str, Path] = {}


def _env(root: Path = REPO) -> dict[str, str]:
    paths = [str(root), str(root / "plugins")]
    old = os.environ.get("PYTHONPATH")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(paths + ([old] if old and root == REPO else []))}
    env.pop("LMIC_NO_CACHE", None)
    cache = {k: v + ("-compare" if root != REPO else "") for k, v in CACHE.items()}
    return {**env, **cache}


def _write_plants(folder: Path) -> tuple[list[Path], dict[str, Any]]:
    """The study's plants as system files (what a shell loop needs) and its fixed parameters."""
    import yaml

    sys.path[:0] = [str(REPO), str(REPO / "plugins")]
    from lmic.studies.spec import load_study

    study = load_study(str(STUDY))
    files = []
    for k, job in enumerate(study.jobs):
        p = folder / f"plant_{k:03d}.yaml"
        p.write_text(yaml.safe_dump(job.system), encoding="utf-8")
        files.append(p)
    return files, dict(study.jobs[0].params)


def _cpu() -> float:
    import resource

    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def _run(cmd: list[str], timeout: float, root: Path = REPO) -> tuple[float, float]:
    """Wall and CPU seconds of ``cmd`` (CPU: every process it started and waited for)."""
    c0, t0 = _cpu(), time.perf_counter()
    proc = subprocess.run(cmd, env=_env(root), stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, timeout=timeout)
    elapsed, cpu = time.perf_counter() - t0, _cpu() - c0
    if proc.returncode not in (0, 1, 3):
        raise RuntimeError(f"{' '.join(cmd[:4])}...: exit {proc.returncode}: {proc.stderr.decode()[-300:]}")
    return elapsed, cpu


def measure(method: str, plants: list[Path], params: dict[str, Any], loop_jobs: int, work: Path) -> dict[str, Any]:
    """One timed run of ``method``: ``{"jobs", "seconds", "cpu_s", "jobs_per_s", "load"}``.

    ``METHOD@compare`` runs ``METHOD`` with the code of the ``--compare`` checkout.
    """
    lmic = [sys.executable, "-m", "lmic.cli"]
    root = REPO
    if method.endswith("@compare"):
        method, root = method[: -len("@compare")], COMPARE["root"]
    load_before = os.getloadavg()[0]
    if method == "shell":
        sel = plants[:loop_jobs]
        pflags = " ".join(f"-p {k}={v}" for k, v in params.items())
        script = "; ".join(f"{' '.join(lmic)} solve qib.thm1 {p} {pflags} --json >/dev/null" for p in sel)
        seconds, cpu = _run(["bash", "-c", script], timeout=3600, root=root)
        jobs = len(sel)
    else:
        out = Path(tempfile.mkdtemp(dir=work, prefix=f"{method}-"))
        workers = method.split("-")[1]
        extra = ["--executor", "dask"] if method.startswith("dask") else []
        seconds, cpu = _run(
            [*lmic, "batch", str(STUDY), "-o", str(out), "--workers", workers, "--no-progress", *extra],
            timeout=3600,
            root=root,
        )
        lines = (out / "results.jsonl").read_text(encoding="utf-8").splitlines()
        jobs = len(lines)
        if jobs != len(plants):
            raise RuntimeError(f"{method}: {jobs} results for {len(plants)} jobs")
        shutil.rmtree(out)
    return {
        "jobs": jobs,
        "seconds": seconds,
        "cpu_s": cpu,
        "jobs_per_s": jobs / seconds,
        "load": [round(load_before, 2), round(os.getloadavg()[0], 2)],
    }


def _warm_up(plant: Path, params: dict[str, Any], work: Path, root: Path = REPO) -> None:
    """Fill the cache folder: a 2-job version of the study and one ``lmic solve``."""
    small = work / "warm-up.yaml"
    small.write_text(STUDY.read_text(encoding="utf-8").replace("count: 200", "count: 2"), encoding="utf-8")
    lmic = [sys.executable, "-m", "lmic.cli"]
    _run([*lmic, "batch", str(small), "-o", str(work / "warm-up"), "--workers", "1", "--no-progress"], 600, root)
    pflags = [f"-p{k}={v}" for k, v in params.items()]
    _run([*lmic, "solve", "qib.thm1", str(plant), *pflags, "--json"], 600, root)
    shutil.rmtree(work / "warm-up", ignore_errors=True)


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark and print the table."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--loop-jobs", type=int, default=20)
    ap.add_argument("--methods", default=",".join(METHODS))
    ap.add_argument("--json", default=None)
    ap.add_argument("--compare", default=None, help="another checkout: its batch-1 and batch-2 too (before/after)")
    args = ap.parse_args(argv)
    methods = args.methods.split(",")
    if args.compare:
        COMPARE["root"] = Path(args.compare).resolve()
        methods += [f"{m}@compare" for m in ("batch-1", "batch-2")]
    work = Path(tempfile.mkdtemp(prefix="lmic-batch-bench-"))
    CACHE["LMIC_CACHE_DIR"] = str(work / "cache")
    try:
        plants, params = _write_plants(work)
        _warm_up(plants[0], params, work)
        if args.compare:
            _warm_up(plants[0], params, work, COMPARE["root"])
        runs: dict[str, list[dict[str, Any]]] = {m: [] for m in methods}
        for r in range(args.repeat):
            for m in rotate(methods, r):
                res = measure(m, plants, params, args.loop_jobs, work)
                runs[m].append(res)
                print(
                    f"round {r + 1} {m:8s} {res['jobs']:4d} jobs {res['seconds']:8.2f} s cpu {res['cpu_s']:7.2f} s "
                    f"{res['jobs_per_s']:7.2f} jobs/s  load {res['load'][0]:.1f}->{res['load'][1]:.1f}",
                    file=sys.stderr,
                )
    finally:
        shutil.rmtree(work, ignore_errors=True)
    med = {m: statistics.median(x["jobs_per_s"] for x in runs[m]) for m in methods}
    loads = [v for m in methods for x in runs[m] for v in x["load"]]
    print(
        f"\n200-job study {STUDY.name} ({os.cpu_count()} cores; load average during the runs "
        f"{min(loads):.1f}-{max(loads):.1f}); median of {args.repeat} interleaved rounds\n"
    )
    print("| method | jobs | median s | median jobs/s | median CPU s |")
    print("|---|---:|---:|---:|---:|")
    for m in methods:
        wall = statistics.median(x["seconds"] for x in runs[m])
        cpu = statistics.median(x["cpu_s"] for x in runs[m])
        print(f"| {m} | {runs[m][0]['jobs']} | {wall:.2f} | {med[m]:.2f} | {cpu:.2f} |")
    summary: dict[str, Any] = {"median_jobs_per_s": med, "runs": runs}
    if "shell" in med and "batch-1" in med:
        summary["batch1_over_shell"] = med["batch-1"] / med["shell"]
        print(f"\nbatch-1 / shell loop: {summary['batch1_over_shell']:.1f}x (target >= 5x)")
    if "batch-1" in med and "batch-2" in med:
        summary["scaling_1_to_2"] = med["batch-2"] / med["batch-1"]
        print(
            f"batch-2 / batch-1: {summary['scaling_1_to_2']:.2f}x, efficiency "
            f"{summary['scaling_1_to_2'] / 2:.0%} (target > 1.7x)"
        )
    if "batch-1@compare" in med:
        comp = med["batch-2@compare"] / med["batch-1@compare"]
        per = [
            b["jobs_per_s"] / a["jobs_per_s"]
            for a, b in zip(runs["batch-1@compare"], runs["batch-2@compare"], strict=True)
        ]
        print(
            f"--compare {COMPARE['root']}: batch-2 / batch-1 {comp:.2f}x; per round "
            + ", ".join(f"{x:.2f}x" for x in per)
        )
    if "dask-2" in med and "batch-2" in med:
        print(f"dask-2 / batch-2: {med['dask-2'] / med['batch-2']:.2f}x")
    if "batch-1" in runs and "batch-2" in runs:  # the same ratio, round by round (same load)
        per_round = [b["jobs_per_s"] / a["jobs_per_s"] for a, b in zip(runs["batch-1"], runs["batch-2"], strict=True)]
        summary["scaling_per_round"] = per_round
        print("batch-2 / batch-1 per round: " + ", ".join(f"{x:.2f}x" for x in per_round))
    if args.json:
        Path(args.json).write_text(json.dumps(summary, indent=1), encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
