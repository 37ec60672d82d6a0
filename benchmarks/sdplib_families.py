"""SDPLIB-family problems with independently known optima, through ``lmic solve FILE.dat-s``.

lmic is judged on more SDPLIB problems than the shipped ones (``/work/shared/sdplib``). This
script writes instances of the same families in SDPA sparse format (its own writer,
:func:`sdpa_text`, independent of :mod:`lmic.ir.sdpa`), runs ``lmic solve FILE --json`` on each
(a subprocess: the command users run) and reports the certified enclosure against the optimum
known independently:

* ``theta_Cn``: Lovasz theta of the cycle ``C_n`` (SDPLIB ``theta``: ``min x_1`` s.t. ``x_1 I
  + sum_e x_e E_e - J >= 0``): ``n cos(pi/n) / (1 + cos(pi/n))`` for odd ``n``, ``n / 2`` for
  even ``n`` (Lovasz 1979);
* ``theta_petersen``: 4 (the Petersen graph);
* ``mcp_Kn`` / ``mcp_Cn``: the max-cut relaxation (SDPLIB ``mcp``: ``min sum x_i`` s.t.
  ``Diag(x) - L / 4 >= 0``, ``L`` the Laplacian): ``n^2 / 4`` for the complete graph ``K_n``
  (``Y = n/(n-1) (I - J/n)`` attains it, and ``<L, Y> <= n tr Y``), and ``n / 4 lambda_max(L) =
  n (1 + cos(pi/n)) / 2`` for an odd cycle (the eigenvalue bound, tight on vertex- and
  edge-transitive graphs), ``n`` for an even one;
* ``lyap_n``: control-like, ``min tr P`` s.t. ``-(A^T P + P A) - Q >= 0`` with ``A`` random
  Hurwitz: the optimum is ``tr P*`` of the Lyapunov solution (scipy, no SDP solver);
* ``qap_n``: SDPLIB's qap layout (``qap5.dat-s``: order ``n^2 + 1``, the arrow, row/column
  and gangster constraints) with random integer flows and distances; the dual has no strictly
  feasible point (facial reduction); reference CVXPY + Clarabel;
* ``truss_like_s`` / ``face_s``: random multi-block problems (two matrix blocks and a diagonal
  one, like SDPLIB ``truss``), and the same with extra variables whose coefficient is ``v v^T``
  (integer ``v``, objective 0): the dual then has *no* strictly feasible point (``v^T Y v = 0``
  on every dual-feasible ``Y``), the case of :mod:`lmic.certify.enclosure_facial`; the reference
  is CVXPY + Clarabel at tolerance 1e-10 (a second, independent solve).

Columns: problem, verdict, lower, upper, relative gap, whether the reference is inside the
enclosure (a tolerance of ``1e-6`` relative for the CVXPY references, whose duals have no interior on
the face and qap families, none for closed forms),
the dual route that proved, wall time. Usage::

    OPENBLAS_NUM_THREADS=1 python benchmarks/sdplib_families.py            # all families
    python benchmarks/sdplib_families.py --only theta_C5,face_0 --json out.json

Examples
--------
>>> round(theta_cycle(5), 6), theta_cycle(6)
(2.236068, 3.0)
>>> c, F, blocks = mcp_problem(complete_graph(3))
>>> sdpa_text(c, F, blocks).splitlines()[:3]
['3', '1', '3']
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

Problem = tuple[np.ndarray, list[list[np.ndarray]], list[int]]


def sdpa_text(c: np.ndarray, F: list[list[np.ndarray]], blocks: list[int]) -> str:
    """SDPA sparse text of ``min c'x`` s.t. ``sum_i x_i F_i - F_0 >= 0``; ``F[i][b]`` is block
    ``b`` of ``F_i`` (a vector of the diagonal for a diagonal block, size ``< 0``)."""
    lines = [str(len(c)), str(len(blocks)), " ".join(str(b) for b in blocks), " ".join(repr(float(v)) for v in c)]
    for i, Fi in enumerate(F):
        for b, M in enumerate(Fi):
            if blocks[b] < 0:
                lines += [f"{i} {b + 1} {k + 1} {k + 1} {float(v)!r}" for k, v in enumerate(M) if v != 0]
                continue
            r, s = np.nonzero(np.triu(M))
            lines += [f"{i} {b + 1} {a + 1} {e + 1} {float(M[a, e])!r}" for a, e in zip(r, s, strict=True)]
    return "\n".join(lines) + "\n"


def cycle_graph(n: int) -> list[tuple[int, int]]:
    return [(i, (i + 1) % n) for i in range(n)]


def complete_graph(n: int) -> list[tuple[int, int]]:
    return [(i, j) for i in range(n) for j in range(i + 1, n)]


def petersen_graph() -> list[tuple[int, int]]:
    outer = [(i, (i + 1) % 5) for i in range(5)]
    inner = [(5 + i, 5 + (i + 2) % 5) for i in range(5)]
    return outer + inner + [(i, i + 5) for i in range(5)]


def theta_cycle(n: int) -> float:
    """Lovasz theta of ``C_n``."""
    if n % 2 == 0:
        return n / 2.0
    return n * math.cos(math.pi / n) / (1.0 + math.cos(math.pi / n))


def _nodes(edges: list[tuple[int, int]]) -> int:
    return 1 + max(max(e) for e in edges)


def theta_problem(edges: list[tuple[int, int]]) -> Problem:
    """SDPLIB's theta form: ``min x_1`` s.t. ``x_1 I + sum_e x_e E_e - J >= 0``."""
    n = _nodes(edges)
    F = [[np.ones((n, n))], [np.eye(n)]]
    for a, b in edges:
        E = np.zeros((n, n))
        E[a, b] = E[b, a] = 1.0
        F.append([E])
    c = np.zeros(1 + len(edges))
    c[0] = 1.0
    return c, F, [n]


def laplacian(edges: list[tuple[int, int]]) -> np.ndarray:
    n = _nodes(edges)
    L = np.zeros((n, n))
    for a, b in edges:
        L[a, a] += 1
        L[b, b] += 1
        L[a, b] -= 1
        L[b, a] -= 1
    return L


def mcp_problem(edges: list[tuple[int, int]]) -> Problem:
    """SDPLIB's mcp form: ``min sum x_i`` s.t. ``Diag(x) - L / 4 >= 0``."""
    L = laplacian(edges)
    n = L.shape[0]
    F = [[L / 4.0]]
    for i in range(n):
        E = np.zeros((n, n))
        E[i, i] = 1.0
        F.append([E])
    return np.ones(n), F, [n]


def mcp_value(edges: list[tuple[int, int]], kind: str) -> float:
    n = _nodes(edges)
    if kind == "complete":
        return n * n / 4.0
    return float(n) if n % 2 == 0 else n * (1.0 + math.cos(math.pi / n)) / 2.0


def lyap_problem(ns: int, seed: int) -> tuple[Problem, float]:
    """``min tr P`` s.t. ``-(A^T P + P A) - I >= 0`` (``P`` symmetric, ``ns`` states), and
    ``tr P*`` of ``A^T P* + P* A + I = 0`` (scipy)."""
    import scipy.linalg as sla

    rng = np.random.default_rng(seed)
    A = np.round(rng.standard_normal((ns, ns)) * 8) / 8
    A -= (max(np.linalg.eigvals(A).real) + 0.5) * np.eye(ns)
    A = np.round(A * 64) / 64
    assert max(np.linalg.eigvals(A).real) < 0
    F: list[list[np.ndarray]] = [[np.eye(ns)]]
    c = []
    for j in range(ns):
        for i in range(j, ns):
            E = np.zeros((ns, ns))
            E[i, j] = E[j, i] = 1.0
            F.append([-(A.T @ E + E @ A)])
            c.append(1.0 if i == j else 0.0)
    P = sla.solve_continuous_lyapunov(A.T, -np.eye(ns))
    return (np.array(c), F, [ns]), float(np.trace(P))


def random_problem(seed: int, extra_faces: int = 0) -> Problem:
    """Two matrix blocks and a diagonal one, ``m`` variables; the dual has an interior (``c =
    <F_i, Y_0>`` for a ``Y_0 > 0``) unless ``extra_faces`` variables with coefficient ``v v^T``
    and cost 0 are added (every dual ``Y`` then has ``v^T Y v = 0``)."""
    rng = np.random.default_rng(seed)
    blocks = [4, 3, -3]
    m = 6

    def sym(d: int) -> np.ndarray:
        M = np.round(rng.standard_normal((d, d)) * 4) / 4
        return M + M.T

    F: list[list[np.ndarray]] = [[sym(4), sym(3), np.round(rng.standard_normal(3) * 4) / 4]]
    F.append([np.eye(4), np.eye(3), np.ones(3)])
    for _ in range(m - 1):
        F.append([sym(4), sym(3), np.round(rng.standard_normal(3) * 4) / 4])
    Y0 = [np.eye(4) + 0.1 * np.ones((4, 4)), np.eye(3), np.ones(3)]
    c = [sum(float(np.sum(Fi[b] * Y0[b])) for b in range(3)) for Fi in F[1:]]
    for k in range(extra_faces):
        v = rng.integers(-2, 3, size=4).astype(float)
        v[k % 4] = 1.0
        F.append([np.outer(v, v), np.zeros((3, 3)), np.zeros(3)])
        c.append(0.0)
    return np.array(c), F, blocks


def qap_problem(n: int, seed: int) -> Problem:
    """SDPLIB's qap form (the layout of ``qap5.dat-s``): ``Y`` of order ``n^2 + 1`` (index 0 and
    the assignments ``(i, j) -> 1 + i n + j``), ``<J, Y_N> = n^2``, ``tr Y_N + tr`` of a row or a
    column group ``= n + 1`` (``2n - 1`` groups), the arrow ``Y_0p = Y_pp``, ``Y_00 + <J, Y_N> =
    n^2 + 1`` and the gangster zeros ``Y_pq = 0`` (same row or column, different assignment); the
    cost ``-(A kron B)`` with random symmetric integer ``A``, ``B`` (zero diagonal). The dual has
    no strictly feasible point (the case of :mod:`lmic.certify.enclosure_facial`)."""
    rng = np.random.default_rng(seed)
    N, d = n * n, n * n + 1

    def sym_int(hi: int) -> np.ndarray:
        M = np.triu(rng.integers(1, hi, size=(n, n)), 1).astype(float)
        return M + M.T

    A, B = sym_int(10), sym_int(6)
    F0 = np.zeros((d, d))
    F0[1:, 1:] = -np.kron(A, B)
    F: list[list[np.ndarray]] = [[F0]]
    c: list[float] = []
    J = np.zeros((d, d))
    J[1:, 1:] = 1.0
    F.append([J])
    c.append(float(N))
    idx = np.arange(N).reshape(n, n)
    groups = [idx[i, :] for i in range(n)] + [idx[:, j] for j in range(1, n)]
    for g in groups:
        D = np.zeros((d, d))
        D[1:, 1:] = np.eye(N)
        D[1 + g, 1 + g] += 1.0
        F.append([D])
        c.append(float(n + 1))
    for p_ in range(N):
        E = np.zeros((d, d))
        E[0, 1 + p_] = E[1 + p_, 0] = 1.0
        E[1 + p_, 1 + p_] = -2.0
        F.append([E])
        c.append(0.0)
    K = J.copy()
    K[0, 0] = 1.0
    F.append([K])
    c.append(float(N + 1))
    for p_ in range(N):
        for q_ in range(p_ + 1, N):
            (i, j), (k, l) = divmod(p_, n), divmod(q_, n)
            if (i == k) != (j == l):
                G = np.zeros((d, d))
                G[1 + p_, 1 + q_] = G[1 + q_, 1 + p_] = 1.0
                F.append([G])
                c.append(0.0)
    return np.array(c), F, [d]


def cvxpy_value(prob: Problem) -> float:
    """The optimum by CVXPY + Clarabel at tolerance 1e-10 (the dual ``max <F_0, Y>``)."""
    import cvxpy as cp

    c, F, blocks = prob
    Ys = [cp.Variable((b, b), symmetric=True) if b > 0 else cp.Variable(-b) for b in blocks]
    cons = [Y >> 0 if b > 0 else Y >= 0 for Y, b in zip(Ys, blocks, strict=True)]

    def inner(Fi: list[np.ndarray]) -> Any:
        return sum(cp.sum(cp.multiply(M, Y)) for M, Y in zip(Fi, Ys, strict=True))

    cons += [inner(F[i + 1]) == c[i] for i in range(len(c))]
    pr = cp.Problem(cp.Maximize(inner(F[0])), cons)
    tol = {"tol_gap_abs": 1e-10, "tol_gap_rel": 1e-10, "tol_feas": 1e-10}
    attempts: list[tuple[str, dict[str, Any]]] = [("CLARABEL", tol), ("CLARABEL", {}), ("CVXOPT", {})]
    for solver, opts in attempts:  # no dual interior (qap): Clarabel may fail; then CVXOPT
        try:
            pr.solve(solver=solver, **opts)
        except cp.error.SolverError:
            continue
        if pr.status in ("optimal", "optimal_inaccurate") and pr.value is not None:
            return float(pr.value)
    # the primal form min c'x s.t. sum_i x_i F_i - F_0 >= 0 (it has an interior where the dual
    # has none)
    x = cp.Variable(len(c))
    lmis = []
    for b, size in enumerate(blocks):
        expr = sum(x[i] * F[i + 1][b] for i in range(len(c)) if np.any(F[i + 1][b])) - F[0][b]
        lmis.append(expr >= 0 if size < 0 else 0.5 * (expr + expr.T) >> 0)
    pp = cp.Problem(cp.Minimize(c @ x), lmis)
    pp.solve(solver="CLARABEL")
    if pp.status not in ("optimal", "optimal_inaccurate") or pp.value is None:
        raise RuntimeError("no reference solve succeeded")
    return float(pp.value)


def instances(only: set[str] | None = None) -> list[tuple[str, Problem, float, str]]:
    """``(name, problem, reference, source)`` for every family member."""
    out: list[tuple[str, Problem, float, str]] = []

    def add(name: str, make: Any) -> None:
        if only is None or name in only:
            prob, ref, src = make()
            out.append((name, prob, ref, src))

    for n in (5, 6, 7, 9, 12):
        add(f"theta_C{n}", lambda n=n: (theta_problem(cycle_graph(n)), theta_cycle(n), "closed form"))
    add("theta_petersen", lambda: (theta_problem(petersen_graph()), 4.0, "closed form"))
    for n in (4, 7, 10):
        g = complete_graph(n)
        add(f"mcp_K{n}", lambda g=g: (mcp_problem(g), mcp_value(g, "complete"), "closed form"))
    for n in (5, 8, 11):
        g = cycle_graph(n)
        add(f"mcp_C{n}", lambda g=g: (mcp_problem(g), mcp_value(g, "cycle"), "closed form"))
    for ns, seed in ((3, 0), (5, 1), (8, 2)):
        add(f"lyap_{ns}", lambda ns=ns, seed=seed: (*lyap_problem(ns, seed), "scipy Lyapunov"))
    for n in (4, 5, 6):
        add(f"qap_{n}", lambda n=n: (qap_problem(n, n), cvxpy_value(qap_problem(n, n)), "cvxpy+clarabel"))
    for s in range(3):
        add(f"truss_like_{s}", lambda s=s: (random_problem(s), cvxpy_value(random_problem(s)), "cvxpy+clarabel"))
    for s in range(3):
        add(
            f"face_{s}",
            lambda s=s: (random_problem(s, 1 + s % 2), cvxpy_value(random_problem(s, 1 + s % 2)), "cvxpy+clarabel"),
        )
    return out


def run_one(path: Path, timeout: float = 300.0) -> tuple[dict[str, Any], float]:
    """``lmic solve path --json`` (a subprocess) and its wall time."""
    t0 = time.perf_counter()
    p = subprocess.run(
        [sys.executable, "-c", "from lmic.cli import _entry; _entry()", "solve", str(path), "--json"],
        capture_output=True,
        text=True,
        timeout=timeout,
    )
    dt = time.perf_counter() - t0
    try:
        return json.loads(p.stdout), dt
    except json.JSONDecodeError:
        return {"verdict": "error", "message": (p.stderr or p.stdout).strip().splitlines()[-1:]}, dt


def inside(enc: dict[str, Any] | None, ref: float, source: str) -> bool | None:
    """The reference within the enclosure (closed forms: exactly; solver references: to 1e-6)."""
    if not enc or enc.get("lower") is None or enc.get("upper") is None:
        return None
    slack = 0.0 if source in ("closed form", "scipy Lyapunov") else 1e-6 * max(1.0, abs(ref))
    if source == "scipy Lyapunov":
        slack = 1e-12 * max(1.0, abs(ref))  # scipy's own rounding
    return bool(enc["lower"] - slack <= ref <= enc["upper"] + slack)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--only", help="comma-separated instance names")
    ap.add_argument("--json", help="write the rows here")
    ap.add_argument("--keep", help="write the .dat-s files to this directory")
    args = ap.parse_args(argv)
    only = set(args.only.split(",")) if args.only else None
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        where = Path(args.keep or tmp)
        where.mkdir(parents=True, exist_ok=True)
        for name, prob, ref, src in instances(only):
            path = where / f"{name}.dat-s"
            path.write_text(sdpa_text(*prob))
            out, dt = run_one(path)
            enc = out.get("enclosure") or {}
            dual = enc.get("dual") or {}
            row = {
                "problem": name,
                "verdict": out.get("verdict"),
                "lower": enc.get("lower"),
                "upper": enc.get("upper"),
                "rel_gap": enc.get("rel_gap"),
                "reference": ref,
                "source": src,
                "inside": inside(enc, ref, src),
                "route": dual.get("route") if dual.get("proven") else None,
                "time_s": dt,
                "reason": None if enc.get("rel_gap") is not None else enc.get("reason", out.get("message")),
            }
            rows.append(row)

            def f(v: Any) -> str:
                return "-" if v is None else f"{v:.9g}" if isinstance(v, float) else str(v)

            print(
                f"{name:16s} {f(row['verdict']):10s} {f(row['lower']):>16s} {f(row['upper']):>16s} "
                f"{f(row['rel_gap']):>10s} {f(ref):>14s} {f(row['inside']):>6s} {f(row['route']):>12s} {dt:6.2f}s",
                flush=True,
            )
            if row["reason"]:
                print(f"    {row['reason']}"[:400], flush=True)
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))
    bad = [r for r in rows if r["inside"] is False]
    return 1 if bad else 0


if __name__ == "__main__":
    raise SystemExit(main())
