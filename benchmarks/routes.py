"""Route benchmark: lmic's default route against hand-written CVXPY, interleaved, certified.

Tables (issue 14, "Done when"):

* **feasibility**, ``qib.thm1`` on random discrete-time systems (``benchmarks/backends.py``'s
  generator): default ``lmic`` (no backend) against the same LMI hand-written in CVXPY +
  Clarabel, and the expert route CVXPY + SCS with a trace normalisation (``trace P = n``,
  ``M << -delta I``, ``P >> delta I`` with ``delta = 1e-2``), whose point is then certified by
  lmic's certifier; ``lmic%`` is lmic's own share of its in-process time (everything but the
  solver's own time), split into ``bind%`` (compile), ``route%`` (strict reduction, lowering,
  the tests of SCS's iterates, result mapping, route decisions) and ``cert%`` (certification);
  ``it`` is SCS's iteration count (``--no-clarabel`` drops the slow CVXPY + Clarabel column;
  ``--warm-child`` runs every method once on n = 3 in its timed child first, so that no method
  pays the fork's copy-on-write faults on the parent's pages, a cost of the harness);
* **optimisation**, the bounded-real lemma (``tutorial.bounded_real``, ``min gamma``) on random
  stable systems: default ``lmic`` (solve, then the certified enclosure of the optimal value)
  against CVXPY + Clarabel (``min gamma`` with ``eps = 1e-7`` margins); the H-infinity norm is
  computed independently (``control.norm(..., method="scipy")``, a Hamiltonian bisection) and
  every enclosure is checked to contain it (``in``); ``gap`` is the enclosure's relative gap;
  ``err`` the relative error of CVXPY's ``gamma`` against the norm;
* **optimisation**, ``uncertain_dt.thm1`` and ``delay_b.thm4_1`` on random plants
  (:func:`lmic.studies.plants.random_plants`): default ``lmic`` against lmic with Clarabel alone
  (no hand-written CVXPY version: the LMIs have 4-5 blocks of 20 block entries); the reference
  optimum is Clarabel's certified objective, which must not be below the default route's
  proven lower end.

Every method runs ``--repeat`` times, methods *interleaved* (rotated order per round), each run in
a fresh forked child with a time limit (``qib.thm1``'s plan analysed once in the parent). Times
are whole in-process times of the call; medians; ``x lmic`` is the ratio of a method's median to
default lmic's. ``--cli`` adds a one-shot ``lmic solve`` process for the default route, with a warm
plan cache (a folder of its own, filled by one run before the rounds: the analysed plan is read,
not recomputed, as in any run after the first), and in the same rounds a baseline process
``python -c "import numpy, scipy.sparse, scs"`` (``base s``: what any script calling SCS on
sparse data pays before its first line). ``cli s`` is the one-shot run's wall time; its two
shares: ``cli%a``, everything but the solver's own time, interpreter included (``1 - solver /
wall``), and ``cli%b``, lmic's own time beyond the baseline (``(wall - base - solver) / wall``),
both from the medians over the rounds; ``cli%b'`` the same against ``lean s``, a baseline that
makes those imports the way ``lmic`` makes them (:data:`LEAN_BASELINE`: lmic avoids part of what
the plain baseline pays, so ``cli%b`` can be negative; ``cli%b'`` is lmic's own code); ``start
s`` the interpreter start and the imports (``benchmarks/startup.py``'s split; its ``--split``
table has every phase); ``--compare ROOT`` adds another checkout's one-shot run to the same
rounds (``cmp s``, ``cmp%a``, ``cmp%b``: before/after). Usage::

    python benchmarks/routes.py --quick          # a few minutes
    python benchmarks/routes.py --sizes 10,20,30,40,50 --brl-sizes 10,20,30,40 --repeat 3 --cli
    python benchmarks/routes.py --only feasibility --repeat 3 --warm-child

Examples
--------
>>> brl_system(3, 0)["data"]["A"].__len__()
3
>>> ratio(2.0, 1.0)
2.0
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import tempfile
import time
import warnings
from typing import Any

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from backends import _timed, random_qib_system, run_cvxpy  # noqa: E402

__all__ = ["brl_system", "hinf_norm", "ratio", "main"]


def ratio(a: float | None, b: float | None) -> float | None:
    """``a / b`` or ``None``."""
    return a / b if a is not None and b else None


def brl_system(n: int, seed: int) -> dict[str, Any]:
    """A random stable continuous-time system (2 inputs, 2 outputs), abscissa -0.5."""
    rng = np.random.default_rng(seed + 7919 * n)
    A = rng.standard_normal((n, n))
    A -= (max(np.linalg.eigvals(A).real) + 0.5) * np.eye(n)
    B, C = rng.standard_normal((n, 2)), rng.standard_normal((2, n))
    return {"lmic": 1, "name": f"random n={n}", "data": {"A": A.tolist(), "B": B.tolist(), "C": C.tolist()}}


def hinf_norm(system: dict[str, Any]) -> float:
    """The H-infinity norm, independently of any LMI solver (python-control's Hamiltonian bisection)."""
    import control

    A, B, C = (np.asarray(system["data"][k]) for k in ("A", "B", "C"))
    return float(
        control.norm(control.ss(A, B, C, np.zeros((C.shape[0], B.shape[1]))), p="inf", tol=1e-10, method="scipy")
    )


def _lmic(target: str, system: dict[str, Any], backend: str | None) -> dict[str, Any]:
    from lmic.api import solve

    t0 = time.perf_counter()
    r = solve(target, system, backend=backend, backoff=0)
    total = time.perf_counter() - t0
    enc = r.enclosure or {}
    t = r.timings
    return {
        "status": r.status,
        "verdict": r.verdict,
        "total_s": total,
        "solve_s": t["solve_s"],
        "enclosure_s": t.get("enclosure_s", 0.0),
        "lmic_s": total - t["solve_s"] - t.get("enclosure_s", 0.0),
        # lmic's own time, by stage: compile (bind), route (reduction, lowering, iterate tests,
        # result mapping, decisions), certify; the rest of the call is the Result's assembly
        "compile_s": t.get("compile_s", 0.0),
        "route_s": t.get("lower_s", 0.0),
        "certify_s": t.get("certify_s", 0.0),
        "iterations": r.solution.iterations,
        "point_s": total - t.get("enclosure_s", 0.0),
        "lower": enc.get("lower"),
        "upper": enc.get("upper"),
        "rel_gap": enc.get("rel_gap"),
        "objective": r.objective,
        "route": (r.route or {}).get("text", ""),
    }


def _expert_scs(n: int, delta: float = 1e-2) -> dict[str, Any]:
    """qib.thm1 hand-written in CVXPY + SCS with a trace normalisation; certified by lmic."""
    import cvxpy as cp

    from lmic.certify import certify
    from lmic.compile import compile_theorem
    from lmic.solution import Solution

    system = random_qib_system(n)
    A, C = (np.asarray(system["data"][k]) for k in ("A", "C"))
    beta = system["params"]["beta"]
    p = C.shape[0]
    t0 = time.perf_counter()
    P, R, w = cp.Variable((n, n), symmetric=True), cp.Variable((p, n)), cp.Variable()
    In, Z = np.eye(n), np.zeros((n, n))
    X = A.T @ P - C.T @ R
    M = cp.bmat([[-P + 2 * w * beta * In, X, X], [X.T, P - 2 * w * In, Z], [X.T, Z, -P]])
    cons = [0.5 * (M + M.T) << -delta * np.eye(3 * n), P >> delta * In, w >= delta, cp.trace(P) == n]
    prob = cp.Problem(cp.Minimize(0), cons)
    prob.solve(solver="SCS", eps=1e-3)
    out: dict[str, Any] = {"status": prob.status, "verdict": "unverified"}
    if P.value is not None:
        ir = compile_theorem("qib.thm1", system)
        x = ir.pack({"P": P.value, "R": R.value, "omega": float(w.value)})
        out["verdict"] = certify(ir, Solution("feasible", x=x)).verdict
    out["total_s"] = time.perf_counter() - t0
    return out


def _cvxpy_brl(system: dict[str, Any], eps: float = 1e-7) -> dict[str, Any]:
    """min gamma of the bounded-real lemma, hand-written in CVXPY + Clarabel."""
    import cvxpy as cp

    A, B, C = (np.asarray(system["data"][k]) for k in ("A", "B", "C"))
    n, m, q = A.shape[0], B.shape[1], C.shape[0]
    t0 = time.perf_counter()
    P, g = cp.Variable((n, n), symmetric=True), cp.Variable()
    M = cp.bmat(
        [
            [A.T @ P + P @ A, P @ B, C.T],
            [B.T @ P, -g * np.eye(m), np.zeros((m, q))],
            [C, np.zeros((q, m)), -g * np.eye(q)],
        ]
    )
    prob = cp.Problem(cp.Minimize(g), [0.5 * (M + M.T) << -eps * np.eye(n + m + q), P >> eps * np.eye(n)])
    prob.solve(solver="CLARABEL")
    return {
        "status": prob.status,
        "total_s": time.perf_counter() - t0,
        "objective": None if g.value is None else float(g.value),
    }


#: the one-shot runs' cache folders and the modules a warm run imports, per checkout (``""``: this
#: one, else a ``--compare`` checkout; set by _cli_warm_up)
_CLI: dict[str, dict[str, Any]] = {}


def _cli_env(root: str) -> tuple[dict[str, str], Any]:
    """The environment and working folder of a one-shot run of checkout ``root`` (``""``: this one)."""
    from startup import ROOT, _env

    env = _env(LMIC_CACHE_DIR=_CLI[root]["cache"])
    if not root:
        return env, ROOT
    from pathlib import Path

    env["PYTHONPATH"] = os.pathsep.join([root, os.path.join(root, "plugins")])
    return env, Path(root)


def _cli_run(target: str, system: dict[str, Any], root: str = "") -> dict[str, Any]:
    from startup import one_shot

    with tempfile.NamedTemporaryFile("w", suffix=".json", delete=False) as fh:
        json.dump(system, fh)
    try:
        argv = ["solve", target, fh.name, "--backoff", "0", "--json"]
        env, cwd = _cli_env(root)
        return one_shot(argv, env, _CLI[root].get("modules"), cwd)
    finally:
        os.unlink(fh.name)


def _cli_warm_up(target: str, system: dict[str, Any], root: str = "") -> None:
    """Fill the one-shot runs' cache folder and learn what a warm run imports."""
    _CLI.setdefault(root, {"cache": tempfile.mkdtemp(prefix="lmic-routes-cli-")})
    _cli_run(target, system, root)  # cold: analyses and stores the plan
    _CLI[root]["modules"] = _cli_run(target, system, root)["modules"]


def _cli(target: str, system: dict[str, Any], root: str = "") -> dict[str, Any]:
    """One warm one-shot ``lmic solve`` process (the default route): wall time and split."""
    from startup import split_parts

    rec = _cli_run(target, system, root)
    parts = split_parts(rec)
    return {
        "total_s": parts["wall"],
        "share": parts["share"],
        "solver_s": parts["solver"],
        "start_s": parts["python"] + parts["imports"],
        "verdict": rec["verdict"],
        "sympy": rec["sympy"],
        "status": f"exit {rec['rc']}",
    }


#: what any Python script calling SCS on sparse data must import: the baseline of a one-shot run
BASELINE_IMPORTS = "import numpy, scipy.sparse, scs"


#: the same imports as a script can make them, with the two savings of ``lmic.cli`` (SciPy's
#: array-API shim kept from importing numpy.f2py / testing / ma, no teardown at exit): what is
#: left of a one-shot run's cost beyond it is lmic's own code
LEAN_BASELINE = """import os, numpy
hide, full_all, full_dir = {"f2py", "testing", "ma"}, numpy.__all__, numpy.__dir__
numpy.__all__ = [n for n in full_all if n not in hide]
numpy.__dir__ = lambda: [n for n in full_dir() if n not in hide]
import scipy.sparse, scs
numpy.__all__, numpy.__dir__ = full_all, full_dir
os._exit(0)
"""


def _baseline(lean: bool = False) -> dict[str, Any]:
    """One ``python -c "import numpy, scipy.sparse, scs"`` process (same environment as ``_cli``):
    the interpreter's start and exit and the imports any script using the solver pays
    (``lean``: :data:`LEAN_BASELINE`, the same imports made the way ``lmic`` makes them)."""
    import subprocess

    from startup import _env

    t0 = time.perf_counter()
    code = LEAN_BASELINE if lean else BASELINE_IMPORTS
    out = subprocess.run([sys.executable, "-c", code], env=_env(), capture_output=True, text=True)
    return {"total_s": time.perf_counter() - t0, "status": f"exit {out.returncode}", "verdict": "baseline"}


def cli_shares(cli_rows: list[dict[str, Any]], base_rows: list[dict[str, Any]]) -> tuple[float | None, float | None]:
    """The two shares of a one-shot run (percent), from the medians over the rounds.

    ``(a)``: everything but the solver's own time, interpreter included (``1 - solver / wall``);
    ``(b)``: lmic's own time beyond the baseline process (``(wall - baseline - solver) / wall``).
    Medians first (a loaded machine gives single processes outliers of either kind).

    >>> cli_shares([{"total_s": 1.0, "solver_s": 0.5}], [{"total_s": 0.25}])
    (50.0, 25.0)
    """
    wall, solver, base = _med(cli_rows, "total_s"), _med(cli_rows, "solver_s"), _med(base_rows, "total_s")
    if not wall or solver is None:
        return None, None
    return 100 * (1 - solver / wall), (None if base is None else 100 * (wall - base - solver) / wall)


def _plant(tid: str, n: int, seed: int) -> dict[str, Any]:
    from lmic.registry import get_theorem
    from lmic.studies.plants import random_plants

    if tid == "uncertain_dt.thm1":
        dims, params = {"n": n, "p": 2, "nw": 1, "nz": n, "r": 2, "s": 2}, {"mu": 1.25, "beta": 0.05}
    else:
        dims = {"n": n, "p": 1, "nw": 1, "nz": n, "r": 1, "s": 1}
        params = {"tau1": 0, "tau2": 2, "eps2": 1, "eps3": 1, "lambda": 0.5}
    spec = {"count": 1, "seed": seed, "dims": dims, "spectral_radius": {"A": 0.3}, "scale": 0.1}
    plant = random_plants(get_theorem(tid).template(), spec, "benchmark")[0]
    plant["params"] = params
    return plant


def _warmed(fn: Any, warm_args: tuple, args: tuple) -> dict[str, Any]:
    """``fn(*warm_args)`` once (untimed), then ``fn(*args)``: in a forked child, the first call
    pays copy-on-write page faults on every page of the parent it touches (the parent holds the
    imports and analysed plans: ~15-20 ms at n = 10 for lmic, more for CVXPY), a cost of the
    harness, not of a session; ``--warm-child`` pays it before the timed call, for every method."""
    fn(*warm_args)
    return fn(*args)


def _rounds(jobs: list[tuple[str, Any, tuple]], repeat: int, limit: float, label: str) -> dict[str, list[dict]]:
    out: dict[str, list[dict]] = {name: [] for name, _, _ in jobs}
    for k in range(repeat):
        order = jobs[k % len(jobs) :] + jobs[: k % len(jobs)]
        for name, fn, args in order:
            r = _timed(fn, args, limit)
            out[name].append(r)
            what = r.get("verdict", r.get("status"))
            print(
                f"  [{label} {k + 1}/{repeat}] {name}: {what} {r.get('total_s', r['wall_s']):.3f} s",
                file=sys.stderr,
                flush=True,
            )
    return out


def _med(rows: list[dict], key: str) -> float | None:
    vals = [r[key] for r in rows if isinstance(r.get(key), int | float)]
    return statistics.median(vals) if vals else None


def _f(v: Any, spec: str = ".3f") -> str:
    return "-" if v is None else format(v, spec) if isinstance(v, float) else str(v)


def _row(cells: list[tuple[Any, int, str]]) -> str:
    """One table row: ``(value, width, format)`` per cell, right-aligned; a string is as is."""
    return " ".join(f"{_f(v, spec) if not isinstance(v, str) else v:>{w}}" for v, w, spec in cells)


def feasibility(
    sizes: list[int],
    repeat: int,
    limit: float,
    cli: bool,
    warm_child: bool = False,
    clarabel: bool = True,
    compare: str = "",
    session: bool = False,
) -> list[str]:
    """The qib.thm1 table (``warm_child``: see :func:`_warmed`; ``clarabel``: the CVXPY + Clarabel
    column; ``compare``: another checkout's one-shot run too, in the same rounds; ``session``: lmic's
    solve after a first one of another system of the same size, in the same child)."""
    heads = [("n", 3), ("lmic s", 8), ("lmic%", 6), ("bind%", 6), ("route%", 6), ("cert%", 6), ("it", 3)]
    heads += [("verdict", 10), ("cvxpy+clarabel s", 17), ("x lmic", 7)]
    heads += [("expert scs s", 13), ("x lmic", 7), ("verdict", 10), ("cli s", 7), ("cli%a", 6), ("cli%b", 6)]
    heads += [("base s", 7), ("cli%b'", 6), ("lean s", 7), ("start s", 8)]
    heads += [("cmp s", 7), ("cmp%a", 6), ("cmp%b", 6)] if compare else []
    heads += [("ses s", 7), ("ses%", 6)] if session else []
    lines = [" ".join(f"{h:>{w}}" for h, w in heads) + "  route"]
    for n in sizes:
        system = random_qib_system(n)
        jobs: list[tuple[str, Any, tuple]] = [
            ("lmic", _lmic, ("qib.thm1", system, None)),
            ("expert", _expert_scs, (n,)),
        ]
        if clarabel:
            jobs.insert(1, ("cvxpy:CLARABEL", run_cvxpy, ("CLARABEL", n)))
        if warm_child:
            small = {
                "lmic": ("qib.thm1", random_qib_system(3, seed=1), None),
                "cvxpy:CLARABEL": ("CLARABEL", 3),
                "expert": (3,),
            }
            jobs = [(name, _warmed, (fn, small[name], args)) for name, fn, args in jobs]
        if session:  # a later solve of a session: another system of the same size solved first
            first = ("qib.thm1", random_qib_system(n, seed=1), None)
            jobs.append(("session", _warmed, (_lmic, first, ("qib.thm1", system, None))))
        if cli:
            for root in [""] + ([compare] if compare else []):
                if "modules" not in _CLI.get(root, {}):
                    _cli_warm_up("qib.thm1", system, root)
            jobs.append(("cli", _cli, ("qib.thm1", system)))
            jobs.append(("baseline", _baseline, ()))
            jobs.append(("baseline-lean", _baseline, (True,)))
            if compare:
                jobs.append(("cli-compare", _cli, ("qib.thm1", system, compare)))
        res = _rounds(jobs, repeat, limit, f"qib n={n}")
        res.setdefault("cvxpy:CLARABEL", [])
        lm, cv, ex = (_med(res[k], "total_s") for k in ("lmic", "cvxpy:CLARABEL", "expert"))
        shares = [_share(res["lmic"], key) for key in ("lmic_s", "compile_s", "route_s", "certify_s")]
        last = res["lmic"][-1]
        cv_rows = res["cvxpy:CLARABEL"]
        cv_txt = _f(cv) if cv is not None else (str(cv_rows[-1].get("status"))[:17] if cv_rows else "-")
        cells = [(n, 3, "d"), (lm, 8, ".3f")] + [(v, 6, ".1f") for v in shares]
        cells += [(_med(res["lmic"], "iterations"), 3, ".0f")]
        cells += [(str(last.get("verdict"))[:10], 10, ""), (cv_txt, 17, ""), (ratio(cv, lm), 7, ".1f")]
        cells += [(ex, 13, ".3f"), (ratio(ex, lm), 7, ".1f"), (str(res["expert"][-1].get("verdict"))[:10], 10, "")]
        share_a, share_b = cli_shares(res.get("cli", []), res.get("baseline", []))
        cells += [(_med(res.get("cli", []), "total_s"), 7, ".3f"), (share_a, 6, ".0f"), (share_b, 6, ".0f")]
        share_lean = cli_shares(res.get("cli", []), res.get("baseline-lean", []))[1]
        cells += [(_med(res.get("baseline", []), "total_s"), 7, ".3f"), (share_lean, 6, ".0f")]
        cells += [(_med(res.get("baseline-lean", []), "total_s"), 7, ".3f")]
        cells += [(_med(res.get("cli", []), "start_s"), 8, ".3f")]
        if compare:
            cmp_a, cmp_b = cli_shares(res.get("cli-compare", []), res.get("baseline", []))
            cells += [(_med(res.get("cli-compare", []), "total_s"), 7, ".3f"), (cmp_a, 6, ".0f"), (cmp_b, 6, ".0f")]
        if session:
            cells += [(_med(res["session"], "total_s"), 7, ".3f"), (_share(res["session"], "lmic_s"), 6, ".1f")]
        lines.append(_row(cells) + "  " + str(last.get("route", "")))
    lines.append("  lmic%: lmic's own share of its in-process time (everything but the solver's own time), the")
    lines.append("  median of the per-run shares; bind% / route% / cert%: compile, the route (reduction, lowering,")
    lines.append("  iterate tests, result mapping) and the certification; it: the solver's iterations")
    if cli:
        lines.append("  cli s: a warm one-shot 'lmic solve' process (plan cache warm); two shares of it, from the")
        lines.append("  medians: cli%a = everything but the solver's own time, interpreter included")
        lines.append("  (1 - solver / wall); cli%b = lmic's own time beyond the baseline process")
        lines.append(f"  ((wall - base - solver) / wall), base s = python -c '{BASELINE_IMPORTS}' (interpreter")
        lines.append("  start and exit plus the imports any script calling SCS pays); cli%b' = the same against")
        lines.append("  lean s, those imports made as lmic makes them (numpy.f2py/testing/ma not pulled in by")
        lines.append("  SciPy's array-API shim, no teardown at exit): lmic's own code; start s: python + imports")
    if session:
        lines.append("  ses s / ses%: lmic's solve in a child that solved another system of the same size first (a")
        lines.append("  session's later solve: the LMI's structure at these dimensions cached, memory warm)")
    if cli and compare:
        lines.append(f"  cmp s / cmp%a / cmp%b: the same one-shot run of {compare}, in the same rounds")
    return lines


def _share(rows: list[dict], key: str) -> float | None:
    """Median over the runs of ``100 * row[key] / row["total_s"]``."""
    vals = [100 * r[key] / r["total_s"] for r in rows if isinstance(r.get(key), int | float) and r.get("total_s")]
    return statistics.median(vals) if vals else None


def brl(sizes: list[int], repeat: int, limit: float, variant: str | None = None) -> list[str]:
    """The bounded-real-lemma table (``variant``: e.g. ``"auto:first-order"`` as lmic's route)."""
    heads = [("n", 3), ("lmic s", 8), ("point s", 8), ("encl s", 8), ("verdict", 10), ("gap", 8), ("in", 4)]
    heads += [("cvxpy+clarabel s", 17), ("err", 8), ("x lmic", 7), ("x point", 7)]
    lines = [" ".join(f"{h:>{w}}" for h, w in heads) + "  route"]
    for n in sizes:
        system = brl_system(n, 0)
        norm = hinf_norm(system)
        jobs = [("lmic", _lmic, ("tutorial.bounded_real", system, variant)), ("cvxpy", _cvxpy_brl, (system,))]
        res = _rounds(jobs, repeat, limit, f"brl n={n}")
        lm, cv, pt = _med(res["lmic"], "total_s"), _med(res["cvxpy"], "total_s"), _med(res["lmic"], "point_s")
        last = res["lmic"][-1]
        lo, hi = last.get("lower"), last.get("upper")
        inside = (lo is None or lo <= norm * (1 + 1e-9)) and (hi is None or hi >= norm * (1 - 1e-9))
        obj = res["cvxpy"][-1].get("objective")
        err = None if obj is None else abs(obj - norm) / norm
        cells = [(n, 3, "d"), (lm, 8, ".3f"), (pt, 8, ".3f"), (_med(res["lmic"], "enclosure_s"), 8, ".3f")]
        cells += [(str(last.get("verdict"))[:10], 10, ""), (last.get("rel_gap"), 8, ".1e")]
        cells += [(("yes" if inside else "NO") + ("" if lo is not None else "*"), 4, "")]
        cells += [(cv, 17, ".3f"), (err, 8, ".1e"), (ratio(cv, lm), 7, ".2f"), (ratio(cv, pt), 7, ".2f")]
        lines.append(_row(cells) + "  " + str(last.get("route", "")))
    lines.append("  point s: to the certified point (no enclosure); in: the enclosure contains the H-infinity norm")
    lines.append("  (* = no certified lower end: only the upper end is checked); err: CVXPY's gamma against the norm")
    return lines


def theorems(sizes: list[int], repeat: int, limit: float) -> list[str]:
    """The uncertain_dt.thm1 / delay_b.thm4_1 table."""
    heads = [("theorem", 18), ("n", 3), ("lmic s", 8), ("encl s", 8), ("verdict", 10), ("gap", 8), ("ok", 4)]
    heads += [("clarabel s", 11), ("x lmic", 7)]
    lines = [" ".join(f"{h:>{w}}" for h, w in heads) + "  route"]
    for tid in ("uncertain_dt.thm1", "delay_b.thm4_1"):
        for n in sizes:
            plant = _plant(tid, n, 1)
            jobs = [("lmic", _lmic, (tid, plant, None)), ("clarabel", _lmic, (tid, plant, "clarabel"))]
            res = _rounds(jobs, repeat, limit, f"{tid} n={n}")
            lm, cl = _med(res["lmic"], "total_s"), _med(res["clarabel"], "total_s")
            last, ref = res["lmic"][-1], res["clarabel"][-1]
            lo, obj = last.get("lower"), ref.get("objective")
            ok = "-" if obj is None else ("yes" if lo is None or lo <= obj * (1 + 1e-9) + 1e-12 else "NO")
            ok += "" if lo is not None or obj is None else "*"
            cells = [(tid, 18, ""), (n, 3, "d"), (lm, 8, ".3f"), (_med(res["lmic"], "enclosure_s"), 8, ".3f")]
            cells += [(str(last.get("verdict"))[:10], 10, ""), (last.get("rel_gap"), 8, ".1e"), (ok, 4, "")]
            cells += [(cl, 11, ".3f"), (ratio(cl, lm), 7, ".2f")]
            lines.append(_row(cells) + "  " + str(last.get("route", "")))
    lines.append("  ok: the proven lower end is not above Clarabel's certified objective; * = no certified lower end")
    return lines


def _warm_up() -> None:
    """Import the solvers and CVXPY and analyse every template once in the parent (as a session
    does); the timed children are forked from it, so no method pays imports or the analysis."""
    import clarabel  # noqa: F401
    import cvxpy  # noqa: F401

    from lmic.api import solve
    from lmic.compile import compile_theorem

    # the plants first: they load the theorem registry, after which a theorem id no longer takes
    # the frozen (one-shot) plan but the analysed one (lmic.compile.warm); analysed after that,
    # the plans below are the ones the children use (before, every child analysed qib.thm1's
    # template again and recomputed the plugin fingerprint: ~0.1 s of CPU per run)
    for tid in ("uncertain_dt.thm1", "delay_b.thm4_1"):
        compile_theorem(tid, _plant(tid, 2, 0))
    # not Clarabel: a forked child of a process that has run Clarabel hangs in its thread pool
    for backend in ("scs", "cvxopt"):
        solve("qib.thm1", random_qib_system(3), backend=backend)
        solve("tutorial.bounded_real", brl_system(3, 0), backend=backend, backoff=0)


def main(argv: list[str] | None = None) -> int:
    """Run the tables (interleaved rounds) and print them."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="small sizes, one round: a few minutes")
    ap.add_argument("--sizes", default="10,20,30,40,50", help="qib.thm1 sizes")
    ap.add_argument("--brl-sizes", default="10,20,30,40")
    ap.add_argument("--theorem-sizes", default="4,8")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--limit", type=float, default=300.0, help="seconds per run")
    ap.add_argument("--cli", action="store_true", help="also a one-shot 'lmic solve' process (default route)")
    ap.add_argument(
        "--warm-child",
        action="store_true",
        help="feasibility: each timed child runs its method once on n = 3 first (pays the fork's copy-on-write faults)",
    )
    ap.add_argument("--no-clarabel", action="store_true", help="feasibility: skip the (slow) CVXPY + Clarabel column")
    ap.add_argument(
        "--session", action="store_true", help="feasibility: also lmic's solve after another of the same size"
    )
    ap.add_argument("--only", default="feasibility,brl,theorems")
    ap.add_argument("--compare", default="", help="--cli: also the one-shot run of another checkout (e.g. /work/main)")
    ap.add_argument("--brl-route", default=None, help="lmic's backend for the BRL table, e.g. auto:first-order")
    args = ap.parse_args(argv)
    if args.quick:
        args.sizes, args.brl_sizes, args.theorem_sizes, args.repeat = "10,40", "10,20", "4", 1
    warnings.simplefilter("ignore")
    _warm_up()  # imports and analysed plans, once: the forked children inherit them
    ints = lambda s: [int(v) for v in s.split(",") if v]  # noqa: E731
    only = set(args.only.split(","))
    out: list[str] = []
    if "feasibility" in only:
        title = "Feasibility, qib.thm1 (medians of interleaved runs" + (", warm children)" if args.warm_child else ")")
        out += ["", title] + feasibility(
            ints(args.sizes),
            args.repeat,
            args.limit,
            args.cli,
            args.warm_child,
            not args.no_clarabel,
            os.path.abspath(args.compare) if args.compare else "",
            args.session,
        )
    if "brl" in only:
        out += ["", "Optimisation, bounded-real lemma (min gamma)"] + brl(
            ints(args.brl_sizes), args.repeat, args.limit, args.brl_route
        )
    if "theorems" in only:
        out += ["", "Optimisation, uncertain_dt.thm1 and delay_b.thm4_1 (random plants)"] + theorems(
            ints(args.theorem_sizes), args.repeat, args.limit
        )
    print("\n".join(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
