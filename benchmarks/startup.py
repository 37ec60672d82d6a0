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
  cache off, with an empty cache (analysis + storing) and warm (cache read), for three theorems;
* the **one-shot split** (``--split 10,30,50``): a warm ``lmic solve qib.thm1 SYSTEM --json`` on
  random ``n``-state systems, each process split into *python* (interpreter start and exit:
  the wall time minus what the driver measures inside), *imports* (every module the solve
  imports, imported up front in the order a first run imported them, under the same
  ``lmic.cli._LeanNumpyNames`` as ``lmic.cli.main`` applies to a command), *load/bind*
  (``compile_s``: system file, warm plan, bind), *lower* (``lower_s``), *solver* (``solve_s``,
  the solver's own time), *certify* (``certify_s`` + ``enclosure_s``) and *output* (the rest of
  ``main``: arguments, the JSON written); the driver ends the process as ``lmic`` does
  (``lmic.cli.exit_now``). ``share`` is lmic's share, everything but the solver
  (``1 - solver / wall``); ``share ex.`` leaves out the interpreter and the imports of numpy and
  scipy too (what a process must pay before any lmic code runs); ``sympy`` says whether the
  process imported sympy (it must not when warm).

Every process runs the code of this checkout (``PYTHONPATH`` = the checkout and its
``plugins/``). Usage::

    python benchmarks/startup.py                # 7 rounds
    python benchmarks/startup.py --rounds 11 --n 30
    python benchmarks/startup.py --rounds 5 --split 10,20,30,40,50 --only split --compare /work/main

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

#: the checkout whose ``lmic`` the processes run (``LMIC_BENCH_ROOT``: another one, e.g. a before/after
#: comparison run by the same benchmark code)
ROOT = Path(os.environ.get("LMIC_BENCH_ROOT") or Path(__file__).resolve().parents[1]).resolve()
EXAMPLE = ROOT / "examples" / "qib.thm1.flexible-joint.yaml"
LMIC = [sys.executable, "-c", "from lmic.cli import _entry; _entry()"]


def median_ratio(times: list[float], base: list[float]) -> tuple[float, float]:
    """Median of ``times`` and its ratio to the median of ``base``."""
    m = statistics.median(times)
    return m, m / statistics.median(base)


#: where the measured processes keep their compiled bytecode (``None``: as the caller's
#: environment says; ``--no-bytecode-cache``)
BYTECODE: dict[str, str | None] = {"dir": None}


def _bytecode_dir() -> str:
    if BYTECODE["dir"] is None:
        BYTECODE["dir"] = tempfile.mkdtemp(prefix="lmic-bench-pyc-")
    return str(BYTECODE["dir"])


def _env(**extra: str) -> dict[str, str]:
    """The environment of a measured process: this checkout first on the path, and (unless
    ``--no-bytecode-cache``) compiled bytecode kept in a folder of the run
    (``PYTHONPYCACHEPREFIX``), as an installed package has it: with ``PYTHONDONTWRITEBYTECODE``
    set (this machine's default) every process compiled all of lmic's sources again (~0.15 s of
    CPU per ``lmic solve``), a cost no installed lmic pays."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(
        [str(ROOT), str(ROOT / "plugins")] + ([env["PYTHONPATH"]] if env.get("PYTHONPATH") else [])
    )
    env.pop("LMIC_NO_CACHE", None)
    if BYTECODE.get("off") is None:
        env.pop("PYTHONDONTWRITEBYTECODE", None)
        env["PYTHONPYCACHEPREFIX"] = _bytecode_dir()
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
    ap.add_argument("--split", default="", help="sizes n of the one-shot split (e.g. 10,30,50)")
    ap.add_argument("--only", default="startup,plans,split", help="tables to run")
    ap.add_argument("--compare", default="", help="--split: also another checkout (before/after), interleaved")
    ap.add_argument("--no-bytecode-cache", action="store_true", help="keep the caller's bytecode settings (see _env)")
    args = ap.parse_args(argv)
    if args.no_bytecode_cache:
        BYTECODE["off"] = "1"
    work = Path(tempfile.mkdtemp(prefix="lmic-startup-"))
    only = set(args.only.split(","))
    if args.split and "split" in only:
        split_table([int(v) for v in args.split.split(",") if v], args.rounds, work, args.compare)
    if "startup" not in only:
        shutil.rmtree(work, ignore_errors=True)
        return
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
    if "plans" in only:
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


SPLIT_DRIVER = """
import importlib, io, json, sys, time
from contextlib import redirect_stdout
t_enter = time.perf_counter()
modules, argv = json.loads(sys.argv[1]), sys.argv[2:]
third = 0.0
import contextlib
try:  # what lmic.cli.main does around a command (the imports below stand for the command's)
    from lmic.cli import _LeanNumpyNames as lean
except ImportError:  # a checkout without it (--compare)
    lean = contextlib.nullcontext
with lean():
    for name in modules:
        t = time.perf_counter()
        try:
            importlib.import_module(name)
        except Exception:
            pass
        if name.split(".")[0] in ("numpy", "scipy"):
            third += time.perf_counter() - t
t_imported = time.perf_counter()
from lmic.cli import main
buf = io.StringIO()
with redirect_stdout(buf):
    rc = main(argv)
t_done = time.perf_counter()
sys.stderr.write("\\nSPLIT " + json.dumps({
    "rc": rc, "imports_s": t_imported - t_enter, "numpy_scipy_s": third, "main_s": t_done - t_imported,
    "stdout": buf.getvalue(), "modules": list(sys.modules), "sympy": "sympy" in sys.modules}) + "\\n")
try:  # the process ends as the lmic command's does (lmic.cli._entry)
    from lmic.cli import exit_now
except ImportError:  # a checkout without it (--compare)
    exit_now = sys.exit
exit_now(rc)
"""


def one_shot(
    argv: list[str], env: dict[str, str], modules: list[str] | None = None, cwd: Path = ROOT
) -> dict[str, Any]:
    """One ``lmic`` process run through :data:`SPLIT_DRIVER`: its wall time and its split.

    ``modules``: imported up front (a first run's ``modules``); ``None`` imports nothing first.
    ``cwd``: the working folder (``python -c`` puts it first on ``sys.path``: the checkout run).
    Returns the driver's record plus ``wall_s``, the JSON result's ``timings`` and ``verdict``.
    """
    t0 = time.perf_counter()
    out = subprocess.run(
        [sys.executable, "-c", SPLIT_DRIVER, json.dumps(modules or []), *argv],
        env=env,
        cwd=cwd,
        capture_output=True,
        text=True,
    )
    wall = time.perf_counter() - t0
    lines = [x for x in out.stderr.splitlines() if x.startswith("SPLIT ")]
    if not lines:
        raise SystemExit(f"lmic {' '.join(argv)}: {out.stderr.strip()[-300:]}")
    rec = json.loads(lines[-1][6:])
    rec["wall_s"] = wall
    result = json.loads(rec["stdout"]) if rec["stdout"].lstrip().startswith("{") else {}
    rec["timings"] = result.get("timings", {})
    rec["verdict"] = result.get("verdict")
    return rec


def split_parts(rec: dict[str, Any]) -> dict[str, float]:
    """The phases of one :func:`one_shot` record (seconds) and the two shares."""
    t = rec["timings"]
    inside = sum(t.get(k, 0.0) for k in ("compile_s", "lower_s", "solve_s", "certify_s", "enclosure_s"))
    parts = {
        "python": rec["wall_s"] - rec["imports_s"] - rec["main_s"],
        "imports": rec["imports_s"],
        "load/bind": t.get("compile_s", 0.0),
        "lower": t.get("lower_s", 0.0),
        "solver": t.get("solve_s", 0.0),
        "certify": t.get("certify_s", 0.0) + t.get("enclosure_s", 0.0),
        "output": rec["main_s"] - inside,
        "wall": rec["wall_s"],
    }
    parts["share"] = 1 - parts["solver"] / parts["wall"]
    rest = parts["wall"] - parts["python"] - rec["numpy_scipy_s"]
    parts["share ex."] = 1 - parts["solver"] / rest
    return parts


def split_table(sizes: list[int], rounds: int, work: Path, compare: str = "") -> None:
    """Print the one-shot split of warm ``lmic solve qib.thm1`` runs (interleaved over sizes).

    ``compare``: another checkout (e.g. ``/work/main``) run the same way in the same rounds, for
    a before/after table (its own cache folder, warmed the same way).
    """
    roots = {"this": ROOT} | ({"compare": Path(compare).resolve()} if compare else {})
    envs = {}
    for label, root in roots.items():
        env = _env(LMIC_CACHE_DIR=str(work / f"split-cache-{label}"))
        env["PYTHONPATH"] = os.pathsep.join([str(root), str(root / "plugins")])
        envs[label] = env
    systems = {}
    modules: dict[tuple[str, int], list[str]] = {}
    for n in sizes:
        systems[n] = work / f"split-qib{n}.json"
        _random_qib_system(n, systems[n])
        argv = ["solve", "qib.thm1", str(systems[n]), "--json"]
        for label, env in envs.items():
            one_shot(argv, env, cwd=roots[label])  # cold: analyses and stores the plan
            modules[(label, n)] = one_shot(argv, env, cwd=roots[label])["modules"]  # warm: what it imports
    keys = [(label, n) for n in sizes for label in envs]
    recs: dict[tuple[str, int], list[dict[str, Any]]] = {k: [] for k in keys}
    for r in range(rounds):
        for label, n in keys[r % len(keys) :] + keys[: r % len(keys)]:
            argv = ["solve", "qib.thm1", str(systems[n]), "--json"]
            recs[(label, n)].append(one_shot(argv, envs[label], modules[(label, n)], roots[label]))
    cols = ["python", "imports", "load/bind", "lower", "solver", "certify", "output", "wall"]
    print(f"one-shot 'lmic solve qib.thm1 SYSTEM --json', warm plan cache, {rounds} interleaved rounds, medians (s)")
    if compare:
        print(f"  this = {ROOT}, compare = {roots['compare']}")
    head = f"{'n':>3} {'code':>7} " + " ".join(f"{c:>9}" for c in cols)
    print(head + f" {'share':>6} {'share ex.':>9} {'sympy':>6} verdict")
    for label, n in keys:
        parts = [split_parts(x) for x in recs[(label, n)]]
        med = {k: statistics.median(p[k] for p in parts) for k in parts[0]}
        sympy = any(x["sympy"] for x in recs[(label, n)])
        cells = " ".join(f"{med[c]:9.3f}" for c in cols)
        verdict = recs[(label, n)][-1]["verdict"]
        print(f"{n:3d} {label:>7} {cells} {med['share']:6.0%} {med['share ex.']:9.0%} {str(sympy):>6} {verdict}")
    load = os.getloadavg() if hasattr(os, "getloadavg") else None
    print(f"load average {load}; share = 1 - solver/wall; share ex. leaves out python start and numpy/scipy imports")


if __name__ == "__main__":
    main()
