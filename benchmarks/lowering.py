"""Benchmark: the lowering (IR -> solver data, and the duals back), old against new, interleaved.

Problems: ``qib.thm1`` on random discrete-time systems (``p = n/2``, as ``benchmarks/backends.py``),
reduced the way the SCS route gives them to the solver (the ``fixed-margin`` strict reduction with
its trace normalisation, :func:`lmic.reductions.strict.reduce`): n = 40 has 1621 variables and
LMIs of 40 and 120 rows (195 k non-zero coefficients), n = 60 has 3631 variables, 60 and 180 rows
(654 k).

Methods, each timed on the same problem, *interleaved* (one round runs every method once, in a
rotated order), medians over ``--repeat`` rounds, ratio old / new:

* ``sform:scs`` / ``sform:clarabel``: :func:`lmic.backends.lowering.conic_data` with SCS's and
  Clarabel's PSD vectorisation, against the COO-based implementation it replaced (kept below,
  ``_old_conic_data``, for this comparison only);
* ``lmiform``: :meth:`lmic.backends.lowering.LMIForm.apply` (per LMI ``F0`` and ``G``, rows
  split), against the old per-backend code (CVXOPT's loop over :func:`full_vec_coo`, SDPA's
  ``full_vec_map(d) @ coeffs`` product);
* ``invert:scs``: :meth:`lmic.backends.lowering.SForm.invert` (a stacked dual vector to the IR's
  multipliers) against the old ``Backend.split_duals``.

For scale, the SCS solve of the same problem (tolerance 1e-3, as in the ``auto`` route) is timed
once per size. Usage::

    python benchmarks/lowering.py                      # n = 40, 60; 7 rounds
    python benchmarks/lowering.py --sizes 20,40 --repeat 5

Examples
--------
>>> problem = qib_problem(4)
>>> problem.n > 0 and len(problem.lmis) == 2
True
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import scipy.sparse as sp

from lmic.backends.clarabel import clarabel_vec
from lmic.backends.lowering import LMIForm, SForm, conic_data, full_vec_coo, full_vec_map
from lmic.backends.scs import scs_vec
from lmic.ir.problem import Problem
from lmic.ir.svec import tril_size, tril_unvec
from lmic.options import SolveOptions

sys.path.insert(0, str(Path(__file__).resolve().parent))
from backends import random_qib_system  # noqa: E402 - the same random systems as the backend benchmark

__all__ = ["qib_problem", "METHODS", "main"]


def qib_problem(n: int) -> Problem:
    """``qib.thm1`` on the random system of size ``n``, after the fixed-margin strict reduction."""
    from lmic.api import load_target
    from lmic.reductions.strict import reduce

    problem, _, _ = load_target("qib.thm1", random_qib_system(n))
    reduced, _ = reduce(problem, SolveOptions(), "fixed-margin")
    return reduced


# -- the implementations the new lowering replaced (for this comparison only) ---------------------
def _old_conic_data(problem: Problem, psd_vec: Callable[[int], tuple[np.ndarray, np.ndarray]]) -> Any:
    lin = problem.linear
    kinds = np.asarray(lin.kinds, dtype=object)
    eq_rows = np.flatnonzero(kinds == "eq") if len(lin) else np.zeros(0, dtype=int)
    ge_rows = np.flatnonzero(kinds == "ge") if len(lin) else np.zeros(0, dtype=int)
    rows, cols, vals = [], [], []
    offset = 0
    for block in (lin.A[eq_rows], lin.A[ge_rows]):
        C = block.tocoo()
        rows.append(C.row + offset)
        cols.append(C.col)
        vals.append(C.data)
        offset += block.shape[0]
    for lmi in problem.lmis:
        perm, scale = psd_vec(lmi.dim)
        inverse = np.empty_like(perm)
        inverse[perm] = np.arange(len(perm))
        C = lmi.coeffs.tocoo()
        native = inverse[C.row]
        rows.append(native + offset)
        cols.append(C.col)
        vals.append(C.data * scale[native])
        offset += len(perm)
    row, col, val = np.concatenate(rows), np.concatenate(cols), np.concatenate(vals)
    const = col == 0
    b = np.zeros(offset)
    np.add.at(b, row[const], val[const])
    A = sp.csc_matrix((-val[~const], (row[~const], col[~const] - 1)), shape=(offset, problem.n))
    return A, b


def _old_lmi_form(problem: Problem) -> Any:
    out = []
    for lmi in problem.lmis:  # CVXOPT's loop
        row, col, val = full_vec_coo(lmi)
        const = col == 0
        h = np.zeros(lmi.dim * lmi.dim)
        h[row[const]] = val[const]
        var = ~const
        out.append((h, (row[var], col[var] - 1, -val[var])))
    M = sp.vstack([full_vec_map(lmi.dim) @ lmi.coeffs for lmi in problem.lmis], format="csc")  # SDPA's
    return out, M


def _old_split_duals(psd: list[int], offsets: list[int], z: np.ndarray) -> list[np.ndarray]:
    mats = []
    scale_of = {d: scs_vec(d)[1] for d in psd}
    for off, d in zip(offsets, psd, strict=True):
        mats.append(tril_unvec(z[off : off + tril_size(d)] / scale_of[d], d))
    return mats


def _new_lmi_form(problem: Problem) -> Any:
    data = LMIForm.apply(problem)
    return data, sp.vstack(data.G, format="csc")


METHODS: dict[str, tuple[Callable[[Problem], Any], Callable[[Problem], Any]]] = {
    "sform:scs": (lambda p: _old_conic_data(p, scs_vec), lambda p: conic_data(p, scs_vec)),
    "sform:clarabel": (lambda p: _old_conic_data(p, clarabel_vec), lambda p: conic_data(p, clarabel_vec)),
    "lmiform": (_old_lmi_form, _new_lmi_form),
}


def _check_same(problem: Problem) -> None:
    """The new lowering builds exactly the old data (else the timing compares different work)."""
    for vec in (scs_vec, clarabel_vec):
        A, b = _old_conic_data(problem, vec)
        new = conic_data(problem, vec)
        assert abs(A - new.A).max() == 0 and np.array_equal(b, new.b)
    _, M = _old_lmi_form(problem)
    assert abs(M[:, 1:] - sp.vstack(LMIForm.apply(problem).G)).max() == 0


def _time(fn: Callable[[], Any]) -> float:
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def run(n: int, repeat: int) -> dict[str, Any]:
    """Interleaved medians (seconds) of every method, old and new, on the problem of size ``n``."""
    problem = qib_problem(n)
    _check_same(problem)
    data = conic_data(problem, scs_vec)
    z = np.random.default_rng(0).standard_normal(data.A.shape[0])
    form = SForm(scs_vec)
    cases: dict[str, tuple[Callable[[], Any], Callable[[], Any]]] = {
        name: (lambda f=old: f(problem), lambda f=new: f(problem)) for name, (old, new) in METHODS.items()
    }
    cases["invert:scs"] = (
        lambda: _old_split_duals(data.psd, data.psd_offsets, z),
        lambda: form.invert(data, z, len(problem.linear)),
    )
    jobs = [(name, k) for name in cases for k in (0, 1)]
    times: dict[tuple[str, int], list[float]] = {job: [] for job in jobs}
    for job in jobs:  # warm-up (caches, first-call allocations)
        cases[job[0]][job[1]]()
    for r in range(repeat):
        shift = r % len(jobs)
        for job in jobs[shift:] + jobs[:shift]:
            times[job].append(_time(cases[job[0]][job[1]]))
    out: dict[str, Any] = {"n": n, "vars": problem.n, "nnz": sum(lmi.coeffs.nnz for lmi in problem.lmis)}
    for name in cases:
        old, new = statistics.median(times[(name, 0)]), statistics.median(times[(name, 1)])
        out[name] = (old, new, old / new)
    out["scs_solve_s"] = _scs_seconds(data)
    return out


def _scs_seconds(data: Any) -> float | None:
    try:
        import scs
    except ImportError:
        return None
    cone = {"z": data.n_eq, "l": data.n_ge, "s": list(data.psd)}
    t0 = time.perf_counter()
    scs.SCS({"A": data.A, "b": data.b, "c": data.c}, cone, verbose=False, eps_abs=1e-3, eps_rel=1e-3).solve()
    return time.perf_counter() - t0


def main(argv: list[str] | None = None) -> None:
    """Print one table per size: old and new medians (ms) and the ratio old / new."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", default="40,60")
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args(argv)
    for n in (int(s) for s in args.sizes.split(",")):
        res = run(n, args.repeat)
        scs_s = res["scs_solve_s"]
        print(f"qib.thm1 n={n}: {res['vars']} variables, {res['nnz']} LMI coefficients; SCS solve {scs_s:.3f} s")
        print(f"  {'method':16s} {'old ms':>9s} {'new ms':>9s} {'old/new':>8s}")
        for name in [*METHODS, "invert:scs"]:
            old, new, ratio = res[name]
            print(f"  {name:16s} {1e3 * old:9.2f} {1e3 * new:9.2f} {ratio:8.2f}")


if __name__ == "__main__":
    main()
