"""Every SDPLIB file of a directory through ``lmic solve FILE --json``, against the published optima.

lmic is judged on more SDPLIB problems than the ones it ships. This script runs the command
users run (``lmic solve FILE --json``, a subprocess, one per problem, with a wall-clock
``--timeout``) on every ``*.dat-s`` of ``--dir`` (the full SDPLIB 1.2 or ``/work/shared/sdplib``;
the data are GPL test files: the directory is an argument, nothing is copied), reads the
published optima from the table of ``DIR/README.md`` (the SDPA conventions: ``min c'x`` s.t.
``sum_i x_i F_i - F_0 >= 0``, which is what lmic solves), applies the corrections that the
README's notes state in the form "The optimal objective value for `NAME` was found to be `V`"
(SDPLIB 1.2's note 14: ``qap10`` is ``-1.093e+03``, the table's ``-1.093e+01`` is a typo), and
prints per problem:

* the verdict and exit code of ``lmic solve``, the certified ``lower`` and ``upper`` ends and
  the relative gap of its enclosure;
* ``pub in``: whether the published optimum's rounding interval (the README prints few digits:
  half a unit of the last printed digit either side) meets the enclosure (``yes`` / ``NO`` /
  ``-`` when an end is missing); for an entry "primal infeasible" (resp. "dual infeasible")
  whether the verdict is ``infeasible-certified`` (resp. ``unbounded-certified``);
* the peak resident memory of the subprocess (``os.wait4``), its wall time, and the route line;
* where the published interval lies above the certified upper end (a minimisation), the point
  lmic returned is checked again here, independently of lmic: the objective ``c'x`` and the
  positive definiteness of every block of ``sum_i x_i F_i - F_0`` in exact rational arithmetic
  (python-flint, a symmetric elimination whose pivots must all be positive). When it holds, the
  published value is *refuted* (SDPLIB 1.2 prints ``hinf13`` as ``4.6e+01``; lmic's point has
  objective 44.4248, and ``gpp100``'s ``-4.49435e+01`` is truncated: a point at -44.9435504 is
  feasible), printed as ``refuted`` and not counted as a miss;
* where the published interval lies below the certified lower end of a max-cut relaxation
  (SDPLIB mcp, maxG), an exactly feasible dual point found here by the mixing method
  (:func:`maxcut_dual_bound`, rational arithmetic, no SDP solver) bounds every point from below:
  when that bound is above the interval, the published value is *refuted* the same way
  (``maxG51``: printed ``4.003809e+03``, every point has ``c'x >= 4006.2526``; lmic's
  enclosure is ``[4006.254, 4006.2556]``).

Problems run smallest file first. Usage::

    OPENBLAS_NUM_THREADS=1 python benchmarks/sdplib_full.py --dir /work/sdplib-full \
        --only control4,truss5 --timeout 600 --json out.json
    python benchmarks/sdplib_full.py --dir /work/shared/sdplib

Examples
--------
>>> text = '''| Problem | m | n | Optimal Objective Value | Notes |
... | ------- | -: | -: | ----: | :-: |
... | truss1  | 6 | 13 | -8.999996e+00 | 13 |
... | infp1   | 10 | 30 | primal infeasible | 6 |
... | qap10   | 1021 | 101 | -1.093e+01 | 9, 14 |
...
... 14. The optimal objective value for `qap10` was found to be `-1.093e+03`
...     by at least three independent experiments.
... '''
>>> pub = published_optima(text)
>>> pub["truss1"], pub["infp1"], pub["qap10"]
('-8.999996e+00', 'primal infeasible', '-1.093e+03')
>>> rounding_interval(pub["truss1"])
(-8.9999965, -8.9999955)
>>> meets((-9.0, -8.99999), pub["truss1"]), meets((-9.1, -9.0), pub["truss1"])
(True, False)
"""

from __future__ import annotations

import argparse
import json
import os
import re
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["published_optima", "rounding_interval", "meets", "run_one", "below", "exact_point_check", "main"]

_CORRECTION = re.compile(
    r"optimal\s+objective\s+value\s+for\s+`([^`]+)`\s+was\s+found\s+to\s+be\s+`([^`]+)`", re.IGNORECASE
)
_NUMBER = re.compile(r"^[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$")


def published_optima(readme: str) -> dict[str, str]:
    """The published optimum of every problem of an SDPLIB README table, as printed.

    The value column is the header cell containing "optimal" (the last column but one in
    SDPLIB 1.2, the last in ``/work/shared/sdplib``); a note "The optimal objective value for
    `NAME` was found to be `V`" overrides the table (SDPLIB 1.2's note 14 on ``qap10``). Entries
    that are words ("primal infeasible") are kept as they are.

    Examples
    --------
    >>> published_optima("| problem | m | optimal value |\\n|---|---|---|\\n| theta1 | 104 | 2.3e+01 |")
    {'theta1': '2.3e+01'}
    """
    out: dict[str, str] = {}
    col: int | None = None
    for line in readme.splitlines():
        s = line.strip()
        if not s.startswith("|"):
            continue
        cells = [c.strip() for c in s.strip("|").split("|")]
        lowered = [c.lower() for c in cells]
        if any("optimal" in c for c in lowered):
            col = next(i for i, c in enumerate(lowered) if "optimal" in c)
            continue
        if col is None or len(cells) <= col or set(cells[0]) <= set("-: "):
            continue
        value = cells[col]
        if _NUMBER.match(value) or "infeasible" in value.lower():
            out[cells[0]] = value
    for name, value in _CORRECTION.findall(readme):
        if _NUMBER.match(value.strip()):
            out[name.strip()] = value.strip()
    return out


def rounding_interval(text: str) -> tuple[float, float]:
    """Values that print as ``text`` (half a unit of its last digit either side).

    Examples
    --------
    >>> rounding_interval("2e-1")
    (0.15, 0.25)
    """
    mant, _, e = text.lower().partition("e")
    exp = int(e) if e else 0
    digits = len(mant.split(".")[1]) if "." in mant else 0
    half = 0.5 * 10.0 ** (exp - digits)
    v = float(text)
    return round(v - half, 12), round(v + half, 12)


def meets(enclosure: tuple[float | None, float | None], published: str) -> bool | None:
    """Whether the rounding interval of ``published`` meets ``[lower, upper]`` (``None``: an
    end is missing or the entry is not a number).

    Examples
    --------
    >>> meets((None, 3.0), "2.5"), meets((2.6, 3.0), "2.5")
    (None, False)
    """
    lo, hi = enclosure
    if lo is None or hi is None or not _NUMBER.match(published):
        return None
    a, b = rounding_interval(published)
    return bool(lo <= b and a <= hi)


def _expected_verdict(published: str) -> str | None:
    low = published.lower()
    if "primal infeasible" in low:
        return "infeasible-certified"
    if "dual infeasible" in low:
        return "unbounded-certified"
    return None


def run_one(path: Path, timeout: float) -> dict[str, Any]:
    """``lmic solve path --json`` in a subprocess (its own process group, killed with its
    children at ``timeout`` seconds): the parsed JSON (or an ``error``/``timeout`` entry), the
    exit code, the wall time and the peak resident memory in MB."""
    certdir = tempfile.TemporaryDirectory()
    cert = Path(certdir.name) / "certificate.json"
    cmd = [sys.executable, "-c", "from lmic.cli import _entry; _entry()", "solve", str(path), "--json", "-o", str(cert)]
    with certdir, tempfile.TemporaryFile("w+") as out, tempfile.TemporaryFile("w+") as err:
        t0 = time.perf_counter()
        proc = subprocess.Popen(cmd, stdout=out, stderr=err, text=True, start_new_session=True)
        timed_out, status, usage = False, 0, None
        while True:  # reap it with wait4 (not Popen.wait) to read its peak memory
            pid, status, usage = os.wait4(proc.pid, os.WNOHANG)
            if pid == proc.pid:
                break
            if time.perf_counter() - t0 > timeout:
                timed_out = True
                os.killpg(proc.pid, signal.SIGKILL)
                _, status, usage = os.wait4(proc.pid, 0)
                break
            time.sleep(0.05)
        dt = time.perf_counter() - t0
        code = os.waitstatus_to_exitcode(status)
        proc.returncode = code
        rss = usage.ru_maxrss / 1024.0
        out.seek(0)
        err.seek(0)
        text, etext = out.read(), err.read()
        try:  # the enclosure's restored point (the --json output leaves it out)
            restored = (json.loads(cert.read_text()).get("enclosure") or {}).get("restored_x")
        except (OSError, ValueError):
            restored = None
    if timed_out:
        return {"verdict": "timeout", "exit_code": None, "time_s": dt, "rss_mb": rss}
    try:
        data = json.loads(text)
    except json.JSONDecodeError:
        tail = (etext or text).strip().splitlines()[-1:] or ["no output"]
        data = {"verdict": "error", "message": tail[0]}
    data["restored_x"] = restored
    data["exit_code"] = code
    data["time_s"] = dt
    data["rss_mb"] = rss
    return data


def read_dats(text: str) -> tuple[Any, list[int], dict[tuple[int, int], dict[tuple[int, int], float]]]:
    """A minimal SDPA sparse reader of its own (independent of :mod:`lmic.ir.sdpa`, for the
    comparison): ``c``, the block sizes and ``{(matno, block): {(i, j): value}}`` (0-based
    ``i <= j``).

    Examples
    --------
    >>> c, sizes, F = read_dats('"x"\\n1\\n1\\n1\\n1.0\\n0 1 1 1 2.0\\n1 1 1 1 1.0\\n')
    >>> c.tolist(), sizes, F[(0, 0)]
    ([1.0], [1], {(0, 0): 2.0})
    """
    import numpy as np

    lines = [ln for ln in text.splitlines() if ln.strip() and ln.lstrip()[0] not in '"*']
    split = [re.sub(r"[,(){}]", " ", ln).split() for ln in lines]
    m, nb = int(split[0][0]), int(split[1][0])
    words = iter(w for row in split[2:] for w in row)
    sizes = [int(float(next(words))) for _ in range(nb)]
    c = np.array([float(next(words)) for _ in range(m)])
    rest = list(words)
    F: dict[tuple[int, int], dict[tuple[int, int], float]] = {}
    for k in range(0, len(rest) - 4, 5):
        mat, blk, i, j, v = (
            int(rest[k]),
            int(rest[k + 1]) - 1,
            int(rest[k + 2]) - 1,
            int(rest[k + 3]) - 1,
            float(rest[k + 4]),
        )
        F.setdefault((mat, blk), {})[(min(i, j), max(i, j))] = v
    return c, sizes, F


def _positive_definite(M: list[list[Any]]) -> bool:
    """Whether the exact symmetric matrix ``M`` (rationals) is positive definite: every pivot of
    its symmetric elimination, in order, positive (Sylvester's criterion)."""
    n = len(M)
    M = [row[:] for row in M]
    for k in range(n):
        pivot = M[k][k]
        if pivot <= 0:
            return False
        for i in range(k + 1, n):
            f = M[i][k] / pivot
            if f != 0:
                row_i, row_k = M[i], M[k]
                for j in range(k + 1, n):
                    row_i[j] -= f * row_k[j]
    return True


def fmpq_of(a: float) -> Any:
    """The float ``a`` as an exact python-flint rational.

    >>> fmpq_of(0.75)
    3/4
    """
    from fractions import Fraction

    from flint import fmpq

    f = Fraction(a)
    return fmpq(f.numerator, f.denominator)


def below(objective: Any, a: float) -> bool:
    """Whether the exact rational ``objective`` (python-flint ``fmpq``) is below the float ``a``,
    compared exactly.

    >>> from flint import fmpq
    >>> below(fmpq(1, 3), 0.3333333333333333), below(fmpq(1, 3), 0.33333333333333337)
    (False, True)
    """
    return bool(objective < fmpq_of(a))


def exact_point_check(path: Path, x: list[float]) -> tuple[Any, bool]:
    """``(c'x, feasible)`` of the point ``x`` of an SDPA file, in exact rational arithmetic and
    independently of lmic (this module's own reader): ``feasible`` when every block of ``sum_i
    x_i F_i - F_0`` is positive definite (a diagonal block: every entry positive).

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.NamedTemporaryFile("w", suffix=".dat-s", delete=False) as f:
    ...     _ = f.write('1\\n1\\n2\\n1.0\\n0 1 1 1 1.0\\n1 1 1 1 1.0\\n1 1 2 2 1.0\\n')
    >>> exact_point_check(Path(f.name), [2.0]), exact_point_check(Path(f.name), [1.0])[1]
    ((2, True), False)
    """
    from flint import fmpq

    q = fmpq_of
    c, sizes, F = read_dats(path.read_text())
    xq = [q(float(v)) for v in x]
    objective = sum((q(float(ci)) * xi for ci, xi in zip(c, xq, strict=True)), fmpq(0))
    for b, d in enumerate(sizes):
        size = abs(d)
        M = [[fmpq(0)] * size for _ in range(size)]
        for (mat, blk), entries in F.items():
            if blk != b:
                continue
            coef = fmpq(-1) if mat == 0 else xq[mat - 1]
            for (i, j), v in entries.items():
                M[i][j] += coef * q(v)
                if i != j:
                    M[j][i] += coef * q(v)
        if d < 0:
            if any(M[k][k] <= 0 for k in range(size)):
                return objective, False
        elif not _positive_definite(M):
            return objective, False
    return objective, True


def maxcut_shape(c: Any, sizes: list[int], F: dict[tuple[int, int], dict[tuple[int, int], float]]) -> bool:
    """Whether an SDPA problem is a max-cut relaxation: one block of order ``m``, ``c = 1`` and
    ``F_i = e_i e_i'`` (SDPLIB mcp, maxG): its dual is ``max <F_0, Y>`` over correlation
    matrices ``Y`` (``Y >= 0``, ``diag Y = 1``).

    >>> import numpy as np
    >>> maxcut_shape(np.ones(2), [2], {(0, 0): {(0, 1): 1.0}, (1, 0): {(0, 0): 1.0}, (2, 0): {(1, 1): 1.0}})
    True
    """
    m = len(c)
    if len(sizes) != 1 or sizes[0] != m or any(float(v) != 1.0 for v in c):
        return False
    return all(F.get((i + 1, 0)) == {(i, i): 1.0} for i in range(m)) and all(mat <= m for mat, _ in F)


def maxcut_dual_bound(path: Path, rank: int = 60, sweeps: int = 300, seed: int = 0) -> Any:
    """An exact lower bound of a max-cut relaxation's optimum (:func:`maxcut_shape`), independent
    of lmic and of any SDP solver; ``None`` for another shape.

    Rows ``v_i`` of unit norm (the mixing method: ``v_i`` <- the normalised ``sum_j F0_ij v_j``,
    ``j != i``, in sweeps) are rounded to rationals and shrunk so that ``|v_i|^2 < 1``; then
    ``Y = V V' + Diag(1 - |v_i|^2)`` is exactly positive semidefinite with ``diag Y = 1``, so
    every primal point ``x`` has ``c'x = <Diag(x) - F_0, Y> + <F_0, Y> >= <F_0, Y>``, computed
    here in rational arithmetic (python-flint).

    Examples
    --------
    >>> import tempfile
    >>> text = "2\\n1\\n2\\n1.0 1.0\\n0 1 1 2 1.0\\n1 1 1 1 1.0\\n2 1 2 2 1.0\\n"  # optimum 2
    >>> with tempfile.NamedTemporaryFile("w", suffix=".dat-s", delete=False) as f:
    ...     _ = f.write(text)
    >>> 1.999999 < float(maxcut_dual_bound(Path(f.name), rank=2, sweeps=20)) <= 2.0
    True
    """

    import numpy as np
    from flint import fmpq

    c, sizes, F = read_dats(path.read_text())
    if not maxcut_shape(c, sizes, F):
        return None
    m = len(c)
    F0 = F.get((0, 0), {})
    nbr: list[list[tuple[int, float]]] = [[] for _ in range(m)]
    for (i, j), v in F0.items():
        if i != j:
            nbr[i].append((j, v))
            nbr[j].append((i, v))
    idx = [np.array([j for j, _ in row], dtype=int) for row in nbr]
    wts = [np.array([v for _, v in row]) for row in nbr]
    V = np.random.default_rng(seed).standard_normal((m, rank))
    V /= np.linalg.norm(V, axis=1, keepdims=True)
    for _ in range(sweeps):
        for i in range(m):
            if len(idx[i]):
                g = wts[i] @ V[idx[i]]
                norm = float(np.linalg.norm(g))
                if norm > 0:
                    V[i] = g / norm
    V *= 1.0 - 2.0**-40  # every |v_i|^2 below 1 after rounding
    q = fmpq_of
    Vq = [[q(float(v)) for v in row] for row in V]
    if any(sum((a * a for a in row), fmpq(0)) >= 1 for row in Vq):
        return None
    total = fmpq(0)
    for (i, j), v in F0.items():
        if i == j:
            total += q(v)  # Y_ii = 1 exactly
        else:
            total += 2 * q(v) * sum((a * b for a, b in zip(Vq[i], Vq[j], strict=True)), fmpq(0))
    return total


def cvxpy_clarabel(path: Path) -> dict[str, Any]:
    """``min c'x`` s.t. ``sum x_i F_i - F_0 >= 0`` through CVXPY + Clarabel (default
    tolerances): status, objective and wall time (model building included, the file read not)."""
    import cvxpy as cp
    import numpy as np
    import scipy.sparse as sp

    c, sizes, F = read_dats(path.read_text())
    t0 = time.perf_counter()
    x = cp.Variable(len(c))
    cons = []
    for b, d in enumerate(sizes):
        size = abs(d)
        rows, cols, vals, const = [], [], [], np.zeros(size * size)
        for (mat, blk), entries in F.items():
            if blk != b:
                continue
            for (i, j), v in entries.items():
                pairs = {(i, j), (j, i)} if d > 0 else {(i, i)}
                for a, e in pairs:
                    if mat == 0:
                        const[a + e * size] -= v
                    else:
                        rows.append(a + e * size)
                        cols.append(mat - 1)
                        vals.append(v)
        A = sp.csc_matrix((vals, (rows, cols)), shape=(size * size, len(c)))
        if d < 0:
            diag = [k * size + k for k in range(size)]
            cons.append(A[diag] @ x + const[diag] >= 0)
        else:
            cons.append(cp.reshape(A @ x + const, (size, size), order="F") >> 0)
    prob = cp.Problem(cp.Minimize(c @ x), cons)
    try:
        prob.solve(solver="CLARABEL")
        status, value = prob.status, prob.value
    except cp.error.SolverError as exc:
        status, value = f"error: {exc}"[:80], None
    return {"status": status, "objective": value, "time_s": time.perf_counter() - t0}


def _compare_in_child(path: Path, timeout: float) -> dict[str, Any]:
    """:func:`cvxpy_clarabel` in a subprocess (the memory of this process, which forks the
    ``lmic solve`` children, stays small; a time limit like theirs)."""
    code = (
        "import json, sys; from pathlib import Path; sys.path.insert(0, sys.argv[2]); import sdplib_full as s; "
        "r = s.cvxpy_clarabel(Path(sys.argv[1])); "
        "print(json.dumps({k: (float(v) if k != 'status' and v is not None else v) for k, v in r.items()}))"
    )
    t0 = time.perf_counter()
    try:
        p = subprocess.run(
            [sys.executable, "-c", code, str(path), str(Path(__file__).resolve().parent)],
            capture_output=True,
            text=True,
            timeout=timeout,
        )
        return json.loads(p.stdout.strip().splitlines()[-1])
    except subprocess.TimeoutExpired:
        return {"status": "timeout", "objective": None, "time_s": time.perf_counter() - t0}
    except (json.JSONDecodeError, IndexError):
        return {"status": "error", "objective": None, "time_s": time.perf_counter() - t0}


def _row(name: str, published: str | None, out: dict[str, Any]) -> dict[str, Any]:
    enc = out.get("enclosure") or {}
    route = out.get("route") or {}
    lo, hi = enc.get("lower"), enc.get("upper")
    if out.get("verdict") in ("infeasible-certified", "unbounded-certified"):
        lo = hi = None
    expected = _expected_verdict(published) if published else None
    inside = (out.get("verdict") == expected) if expected else meets((lo, hi), published) if published else None
    reason = None
    if enc.get("rel_gap") is None:
        reason = enc.get("reason") or out.get("message") or (out.get("certificate") or {}).get("reason")
    return {
        "problem": name,
        "verdict": out.get("verdict"),
        "exit_code": out.get("exit_code"),
        "lower": lo,
        "upper": hi,
        "rel_gap": enc.get("rel_gap"),
        "published": published,
        "inside": inside,
        "route": route.get("text") if isinstance(route, dict) else None,
        "dual_route": (enc.get("dual") or {}).get("route"),
        "time_s": out.get("time_s"),
        "rss_mb": out.get("rss_mb"),
        "timings": out.get("timings"),
        "reason": reason,
    }


def _short(route: str) -> str:
    """The route line with runs of equal block sizes written ``size x count`` (truss8: 34 blocks).

    Examples
    --------
    >>> _short("PSD 2+2+2+1)")
    'PSD 2x3+1)'
    """

    def run(m: re.Match[str]) -> str:
        parts = m.group(0).split("+")
        return f"{parts[0]}x{len(parts)}"

    return re.sub(r"\b(\d+)(?:\+\1\b)+", run, route)


def _fmt(v: Any) -> str:
    if v is None:
        return "-"
    if isinstance(v, bool):
        return "yes" if v else "NO"
    if isinstance(v, float):
        return f"{v:.9g}"
    return str(v)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    ap.add_argument("--dir", required=True, help="directory of SDPLIB *.dat-s files and their README.md")
    ap.add_argument("--only", help="comma-separated problem names (default: every file)")
    ap.add_argument("--timeout", type=float, default=600.0, help="seconds per problem (default 600)")
    ap.add_argument("--json", help="write the rows here (rewritten after every problem)")
    ap.add_argument("--compare", action="store_true", help="also time CVXPY + Clarabel (a subprocess) after each")
    args = ap.parse_args(argv)
    where = Path(args.dir)
    readme = where / "README.md"
    pub = published_optima(readme.read_text()) if readme.is_file() else {}
    files = sorted(where.glob("*.dat-s"), key=lambda p: (p.stat().st_size, p.name))
    if not files:
        print(f"sdplib_full: no .dat-s file in {where}", file=sys.stderr)
        return 2
    if args.only:
        wanted = [s.strip() for s in args.only.split(",") if s.strip()]
        missing = [w for w in wanted if not (where / f"{w}.dat-s").is_file()]
        if missing:
            print(f"sdplib_full: no file {missing[0]}.dat-s in {where}", file=sys.stderr)
            return 2
        files = [f for f in files if f.name[: -len(".dat-s")] in set(wanted)]
    rows = []
    print(
        f"{'problem':10s} {'verdict':20s} {'rc':>3s} {'lower':>16s} {'upper':>16s} {'rel gap':>9s} "
        f"{'published':>13s} {'pub in':>6s} {'MB':>6s} {'time':>8s}",
        flush=True,
    )
    for path in files:
        name = path.name[: -len(".dat-s")]
        out = run_one(path, args.timeout)
        row = _row(name, pub.get(name), out)
        row["_out"] = out
        rows.append(row)
        gap = "-" if row["rel_gap"] is None else f"{row['rel_gap']:.2g}"
        mb = "-" if row["rss_mb"] is None else f"{row['rss_mb']:.0f}"
        print(
            f"{name:10s} {_fmt(row['verdict']):20s} {_fmt(row['exit_code']):>3s} {_fmt(row['lower']):>16s} "
            f"{_fmt(row['upper']):>16s} {gap:>9s} {_fmt(row['published']):>13s} {_fmt(row['inside']):>6s} "
            f"{mb:>6s} {row['time_s']:7.1f}s",
            flush=True,
        )
        if row["route"]:
            print(f"    {_short(row['route'])}"[:300], flush=True)
        if row["reason"]:
            print(f"    {row['reason']}"[:300], flush=True)
        if row["inside"] is False and row["lower"] is not None and row["published"]:
            a, b = rounding_interval(row["published"])
            miss = max(a - row["upper"], row["lower"] - b)
            row["miss_rel"] = miss / max(1.0, abs(a))
            print(f"    published interval [{a:.10g}, {b:.10g}] misses the enclosure by {miss:.3g}", flush=True)
            out_ = row.pop("_out")
            points = [((out_.get("variables") or {}).get("x")), out_.get("restored_x")] if a > row["upper"] else []
            points = [p for p in points if p is not None]
            low = maxcut_dual_bound(path) if b < row["lower"] else None
            if low is not None:
                # the published value below lmic's proven lower end: an independent dual point
                row["refuted"] = bool(fmpq_of(b) < low)
                verdict = "refuted" if row["refuted"] else "not refuted"
                print(
                    f"    published value {verdict}: an exactly feasible dual point (max-cut relaxation, "
                    f"mixing method, checked here in rational arithmetic) gives every point c'x >= {float(low):.10g}",
                    flush=True,
                )
            for which, x in zip(("point", "restored point"), points, strict=False):
                objective, feasible = exact_point_check(path, [float(v) for v in np.ravel(x)])
                row["refuted"] = bool(feasible and below(objective, a))
                verdict = "refuted" if row["refuted"] else "not refuted"
                print(
                    f"    published value {verdict}: lmic's {which}, checked here in exact arithmetic, is "
                    f"{'feasible' if feasible else 'not proved feasible'} with c'x = {float(objective):.10g}",
                    flush=True,
                )
                if row["refuted"]:
                    break
        row.pop("_out", None)
        if args.compare:
            cmp = _compare_in_child(path, args.timeout)
            row["cvxpy_clarabel"] = cmp
            obj = "-" if cmp["objective"] is None else f"{cmp['objective']:.9g}"
            print(f"    cvxpy+clarabel: {cmp['status']} {obj} {cmp['time_s']:.1f}s", flush=True)
        if args.json:
            Path(args.json).write_text(json.dumps(rows, indent=1))
    return 1 if any(r["inside"] is False and not r.get("refuted") for r in rows) else 0


if __name__ == "__main__":
    raise SystemExit(main())
