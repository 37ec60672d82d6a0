"""Cost of the certified lower bound: the extra time of the enclosure over today's solve.

For every problem, two methods run interleaved (``--repeat`` rounds, the order rotated):

* ``plain``: compile or load, solve, certify (:func:`lmic.api.solve_problem` and
  :func:`lmic.certify.certify`): what ``lmic solve`` did before the enclosure;
* ``enclosure``: :func:`lmic.api.solve` without backoff, which adds
  :func:`lmic.certify.enclosure.enclosure` (dual repair, rigorous proof, the perturbed and
  centred solves when the dual is degenerate, the box bound when nothing proves, a re-solve at
  tol 1e-10 when the gap is above 1e-6) and, when the solver's point has no rigorous primal
  end, the restoration solve (:mod:`lmic.backoff`); its own ``enclosure_s`` is reported too.

The report gives medians, the extra time ``enclosure - plain`` and the ratio, the enclosure
(lower, upper, relative gap, the dual route that proved, the conditional box bound), the
relative gap of one run on a second backend (``--compare``, SCS by default) and, for SDPLIB,
whether the published optimum (its rounding interval: the README prints few digits) meets the
enclosure. Usage::

    python benchmarks/enclosure.py                      # examples + SDPLIB, 3 rounds
    python benchmarks/enclosure.py --repeat 5 --json out.json --backend cvxopt
    python benchmarks/enclosure.py --only control1,truss1
    python benchmarks/enclosure.py --brl-sizes 10,20,30,40   # the bounded-real lemma instead

``--brl-sizes`` runs the bounded-real lemma (``tutorial.bounded_real``) on random stable systems
(``--brl-seed``, 0) of those sizes, for each of ``--brl-kinds``: ``random`` (a random diagonal:
the IR's coefficients ``A_aa + A_bb`` are rounded sums, so the face route of
:mod:`lmic.certify.enclosure_face` proves on the theorem compiled exactly,
:mod:`lmic.compile.exact`: ``problem`` ``exact``), ``eighths`` (the diagonal in eighths: the
sums are exact, the IR itself has the structure: ``problem`` ``ir``) and ``near`` (spectral
abscissa -0.01: Clarabel alone stops at AlmostSolved or NumericalError on many seeds; the
``solver alone`` column gives its status, ``--default-route`` adds one run of the default
policy; its ``primal`` says where the upper end comes from: a ``restored point`` is the
point :mod:`lmic.upper_end` proves near the dual end when the solver's gives none).
``inside`` says whether the enclosure is consistent with the H-infinity norm's bracket
``[a, b]`` from a Hamiltonian bisection (``lower <= b``, ``a <= upper``); ``lower err`` and
``upper err`` are ``(a - lower) / a`` and ``(upper - b) / b``.

On a shared machine run it with ``OPENBLAS_NUM_THREADS=1``: the proof does many small dense
solves (``n x n``), which multi-threaded BLAS slows down ten-fold when the cores are busy
(control3: 0.6 s single-threaded, 6.8 s with contended threads).

Examples
--------
>>> rounding_interval("-8.999996e+00")
(-8.9999965, -8.9999955)
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path
from typing import Any

__all__ = ["rounding_interval", "problems", "run_once", "main"]

ROOT = Path(__file__).resolve().parents[1]
SDPLIB = ROOT.parent / "shared" / "sdplib"
if not SDPLIB.is_dir():
    SDPLIB = Path("/work/shared/sdplib")
SDPLIB_NAMES = (
    ["control1", "control2", "control3"] + [f"hinf{k}" for k in range(1, 7)] + [f"truss{k}" for k in range(1, 5)]
)
#: the rest of the SDPLIB subset (issues 13/14, SDPLIB breadth): the Lovasz theta, QAP and
#: arch problems (large blocks: the repair's cost), and the infeasible / dual-infeasible pair
#: (their "published" entry is a word, not a value: no rounding interval)
SDPLIB_BREADTH = ("theta1", "theta2", "qap5", "arch0", "infp1", "infd1")
EXAMPLES = [
    ("sampled_euler.thm2", "sampled_euler.thm2.example.yaml"),
    ("sampled_euler.thm3", "sampled_euler.thm3.example.yaml"),
    ("sampled_euler.thm4", "sampled_euler.thm4.example.yaml"),
    ("delay_b.thm4_1", "delay_b.thm4_1.ex1_lambda0_5.yaml"),
    ("uncertain_dt.thm1", "uncertain_dt.thm1.example.yaml"),
    ("uncertain_dt.lemma3", "uncertain_dt.lemma3.example-plant.yaml"),
    ("uncertain_dt.cor1", "uncertain_dt.cor1.example-plant.yaml"),
    ("uio_dt.thm4_1", "uio_dt.thm4_1.flexible_joint.yaml"),
    ("delay_a.thm3_2", "delay_a.thm3_2.example.yaml"),
]


def rounding_interval(text: str) -> tuple[float, float]:
    """Values that print as ``text`` (half a unit of its last digit either side)."""
    low = text.lower()
    mant, _, e = low.partition("e")
    exp = int(e) if e else 0
    digits = len(mant.split(".")[1]) if "." in mant else 0
    half = 0.5 * 10.0 ** (exp - digits)
    v = float(text)
    return round(v - half, 12), round(v + half, 12)


def _published() -> dict[str, str]:
    out = {}
    readme = SDPLIB / "README.md"
    if readme.is_file():
        for line in readme.read_text().splitlines():
            cells = [c.strip() for c in line.strip().strip("|").split("|")]
            if len(cells) == 4 and cells[0] and cells[3][:1] in "-0123456789":
                out[cells[0]] = cells[3]
    return out


def hinf_bracket(A: Any, B: Any, C: Any, tol: float = 1e-12) -> tuple[float, float]:
    """``(lo, hi)`` around the H-infinity norm of ``(A, B, C, 0)``: bisection on the imaginary
    eigenvalues of the Hamiltonian (no LMI solver involved)."""
    import numpy as np

    def crosses(g: float) -> bool:
        H = np.block([[A, B @ B.T / g], [-C.T @ C / g, -A.T]])
        ev = np.linalg.eigvals(H)
        return bool(np.any(np.abs(ev.real) < 1e-8 * max(1.0, float(np.abs(ev).max()))))

    lo, hi = 0.0, 1.0
    while crosses(hi):
        lo, hi = hi, 2 * hi
    while hi - lo > tol * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if crosses(mid) else (lo, mid)
    return lo, hi


#: the kinds of ``--brl-sizes`` systems: the spectral abscissa and whether the diagonal is in eighths
BRL_KINDS = {"random": (-0.5, False), "eighths": (-0.5, True), "near": (-0.01, False)}


def brl_system(n: int, kind: str, seed: int = 0) -> dict[str, Any]:
    """The system file (as a dict) of one bounded-real lemma case: ``n`` states, a kind of
    :data:`BRL_KINDS`, ``m = q = 2``."""
    import numpy as np

    abscissa, eighths = BRL_KINDS[kind]
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    A -= (max(np.linalg.eigvals(A).real) - abscissa) * np.eye(n)
    if eighths:
        A[np.diag_indices(n)] = np.round(A[np.diag_indices(n)] * 8) / 8
        while max(np.linalg.eigvals(A).real) >= -0.1:
            A -= 0.125 * np.eye(n)
    B, C = rng.standard_normal((n, 2)), rng.standard_normal((2, n))
    return {"lmic": 1, "data": {"A": A.tolist(), "B": B.tolist(), "C": C.tolist()}}


def brl_problems(
    sizes: list[int], kinds: tuple[str, ...] = ("random", "eighths"), seed: int = 0
) -> list[tuple[str, Any, tuple[float, float]]]:
    """``(label, Problem, H-infinity bracket)`` of the bounded-real lemma for each size and kind
    (:data:`BRL_KINDS`: a random diagonal, the diagonal in eighths, or a random system with
    spectral abscissa -0.01, where Clarabel alone stops at AlmostSolved / NumericalError;
    the systems of :func:`brl_system`)."""
    import numpy as np

    from lmic.api import load_target

    out = []
    for n in sizes:
        for kind in kinds:
            system = brl_system(n, kind, seed)
            A, B, C = (np.asarray(system["data"][k]) for k in ("A", "B", "C"))
            label = f"brl n={n} {kind}" + (f" seed {seed}" if seed else "")
            out.append((label, load_target("tutorial.bounded_real", system)[0], hinf_bracket(A, B, C)))
    return out


def problems(only: set[str] | None = None) -> list[tuple[str, Any]]:
    """``(label, Problem)`` for every benchmark problem (compiled once, outside the timing)."""
    from lmic.api import load_target

    out = []
    for thm, system in EXAMPLES:
        if only and thm not in only:
            continue
        path = ROOT / "examples" / system
        if path.is_file():
            out.append((thm, load_target(thm, str(path))[0]))
    for name in [*SDPLIB_NAMES, *SDPLIB_BREADTH]:
        if only and name not in only:
            continue
        path = SDPLIB / f"{name}.dat-s"
        if path.is_file():
            out.append((name, load_target(str(path))[0]))
    return out


def run_once(problem: Any, backend: str, method: str) -> dict[str, Any]:
    """One timed run of ``method``: ``plain`` (solve and certify) or ``enclosure``
    (:func:`lmic.api.solve` without backoff: solve, certify, the enclosure with every route
    it takes, the restoration of a primal end; its own ``enclosure_s`` timing is reported)."""
    import lmic.api
    from lmic.api import solve_problem
    from lmic.certify import certify

    t0 = time.perf_counter()
    if method == "plain":
        sol = solve_problem(problem, backend)
        cert = certify(problem, sol)
        return {"verdict": cert.verdict, "time_s": time.perf_counter() - t0, "status": sol.native_status}
    r = lmic.api.solve(problem, backend=backend, backoff=0)
    out: dict[str, Any] = {"verdict": r.verdict, "time_s": time.perf_counter() - t0}
    enc = r.enclosure or {}
    dual = enc.get("dual") or {}
    out.update(
        lower=enc.get("lower"),
        upper=enc.get("upper"),
        rel_gap=enc.get("rel_gap"),
        kind=enc.get("kind"),
        about=enc.get("problem"),
        backend=r.backend,
        route=dual.get("route") if dual.get("proven") else None,
        primal=enc.get("primal"),
        conditional=(enc.get("conditional") or {}).get("value"),
        dual=dual.get("reason", ""),
        enclosure_s=r.timings.get("enclosure_s"),
    )
    # the point of the primal end (the answer's, or the one the enclosure restored), for the
    # independent check of a published value it beats (:func:`refutes`)
    x_end = enc.get("restored_x")
    if x_end is None and enc.get("primal") == "certified point" and r.solution is not None:
        x_end = r.solution.x
    out["upper_x"] = None if x_end is None else [float(v) for v in x_end]
    return out


def refutes(label: str, row: dict[str, Any], a: float) -> bool | None:
    """Whether the primal end of an SDPLIB row whose value lies below the published rounding
    interval's low end ``a`` (a minimisation) is a point that is feasible exactly, checked
    independently of lmic (:func:`sdplib_full.exact_point_check`: this benchmark's own SDPA
    reader, python-flint rationals, every block positive definite): then the published value
    is refuted, not missed; ``None`` when there is nothing to check."""
    from sdplib_full import below, exact_point_check

    x, hi = row.get("upper_x"), row.get("upper")
    if x is None or hi is None or not hi < a:
        return None
    objective, feasible = exact_point_check(SDPLIB / f"{label}.dat-s", x)
    return bool(feasible and below(objective, a))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--backend", default="clarabel")
    ap.add_argument("--only", default="", help="comma-separated problem labels")
    ap.add_argument("--json", default=None)
    ap.add_argument("--compare", default="scs", help="a second backend run once for its gap ('' for none)")
    ap.add_argument("--brl-sizes", default="", help="run the bounded-real lemma at these sizes instead")
    ap.add_argument("--brl-kinds", default="random,eighths", help=f"of {', '.join(BRL_KINDS)}")
    ap.add_argument("--brl-seed", type=int, default=0)
    ap.add_argument("--default-route", action="store_true", help="also one run of the default policy (brl rows)")
    args = ap.parse_args(argv)
    only = {s for s in args.only.split(",") if s} or None
    published = _published()
    truth: dict[str, tuple[float, float]] = {}
    if args.brl_sizes:
        todo = []
        kinds = tuple(k for k in args.brl_kinds.split(",") if k)
        for label, prob, bracket in brl_problems(
            [int(k) for k in args.brl_sizes.split(",") if k], kinds, args.brl_seed
        ):
            todo.append((label, prob))
            truth[label] = bracket
    else:
        todo = problems(only)
    rows = []
    for label, prob in todo:
        times: dict[str, list[float]] = {"plain": [], "enclosure": []}
        alone = None
        last: dict[str, Any] = {}
        for r in range(args.repeat):
            order = ["plain", "enclosure"] if r % 2 == 0 else ["enclosure", "plain"]
            for m in order:
                try:
                    res = run_once(prob, args.backend, m)
                except Exception as exc:  # a benchmark row, not a crash: report it
                    res = {"time_s": float("nan"), "error": f"{type(exc).__name__}: {exc}"}
                times[m].append(res["time_s"])
                if m == "enclosure":
                    last = res
                elif "status" in res:
                    alone = res["status"]
        plain, enc = statistics.median(times["plain"]), statistics.median(times["enclosure"])
        row = {
            "problem": label,
            "backend": args.backend,
            "plain_s": plain,
            "enclosure_s": enc,
            "extra_s": enc - plain,
            "enclosure_only_s": last.get("enclosure_s"),
            "ratio": enc / plain if plain > 0 else float("nan"),
            **{
                k: last.get(k)
                for k in (
                    *("verdict", "kind", "lower", "upper", "rel_gap", "route", "conditional", "dual"),
                    *("error", "upper_x"),
                )
            },
        }
        if args.compare:
            try:
                other = run_once(prob, args.compare, "enclosure")
                row["compare_rel_gap"] = other.get("rel_gap")
                row["compare_ends"] = (other.get("lower"), other.get("upper"))
            except Exception as exc:  # a benchmark cell, not a crash
                row["compare_rel_gap"] = f"{type(exc).__name__}"
        if label in truth:
            a, b = truth[label]
            lo, hi = row["lower"], row["upper"]
            row["published"] = f"{0.5 * (a + b):.12g}"
            # the norm is in [a, b]: each end on the right side of the bracket (a face bound can
            # be within 1e-12 of the norm, below b)
            row["inside"] = bool((lo is None or lo <= b) and (hi is None or a <= hi))
            row["clarabel_alone"] = alone
            row["lower_err"] = None if lo is None else (a - lo) / a
            row["upper_err"] = None if hi is None else (hi - b) / b
            row["about"], row["backend"] = last.get("about"), last.get("backend")
            if args.default_route:
                try:
                    d = run_once(prob, None, "enclosure")
                    row["default_route"] = {
                        k: d.get(k)
                        for k in ("verdict", "backend", "lower", "upper", "rel_gap", "route", "primal", "time_s")
                    }
                except Exception as exc:  # a benchmark cell, not a crash
                    row["default_route"] = f"{type(exc).__name__}: {exc}"
        if label in published and published[label][:1] in "+-0123456789.":
            a, b = rounding_interval(published[label])
            lo, hi = row["lower"], row["upper"]
            row["published"] = published[label]
            row["inside"] = (
                "-" if lo is None and hi is None else bool((lo is None or lo <= b) and (hi is None or a <= hi))
            )
            if row["inside"] is False and refutes(label, row, a):
                # SDPLIB hinf5's 3.63e+02 against a point at 362.4874, positive definite exactly
                row["inside"] = "refuted"
        row.pop("upper_x", None)
        rows.append(row)
        _print_row(row)
        sys.stdout.flush()
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1, default=str))
    return 0


def _fmt(v: Any, spec: str = ".4g") -> str:
    return "-" if v is None else (format(v, spec) if isinstance(v, float) else str(v))


def _print_row(row: dict[str, Any]) -> None:
    print(
        f"| {row['problem']} | {_fmt(row['plain_s'], '.3f')} | {_fmt(row['enclosure_s'], '.3f')} | "
        f"{_fmt(row['extra_s'], '.3f')} | {_fmt(row.get('enclosure_only_s'), '.3f')} | {_fmt(row['ratio'], '.2f')} | "
        f"{_fmt(row['lower'], '.10g')} | "
        f"{_fmt(row['upper'], '.10g')} | {_fmt(row['rel_gap'], '.2g')} | {_fmt(row.get('route'))} | "
        f"{_fmt(row.get('conditional'), '.8g')} | {_fmt(row.get('compare_rel_gap'), '.2g')} | "
        f"{row.get('published', '-')} | {row.get('inside', '-')} |"
        + (
            f" {_fmt(row.get('clarabel_alone'))} | {_fmt(row.get('about'))} | {_fmt(row.get('lower_err'), '.2g')} | "
            f"{_fmt(row.get('upper_err'), '.2g')} |"
            if "clarabel_alone" in row
            else ""
        )
        + (f" default route: {row['default_route']}" if "default_route" in row else "")
    )


if __name__ == "__main__":
    print(
        "| problem | plain s | with enclosure s | extra s | enclosure s | ratio | lower | upper | rel gap | dual route "
        "| box bound | SCS rel gap | published | inside | (brl: solver alone | problem | lower err | upper err) |"
    )
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|---|")
    sys.exit(main())
