"""The README parser of benchmarks/sdplib_full.py (published optima, note corrections, rounding
intervals) on small strings in SDPLIB's two table layouts."""

from __future__ import annotations

import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
_spec = importlib.util.spec_from_file_location("lmic_bench_sdplib_full", ROOT / "benchmarks" / "sdplib_full.py")
assert _spec is not None and _spec.loader is not None
bench = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(bench)

FULL = """| Problem   |    m |    n | Optimal Objective Value | Notes |
| --------- | ---: | ---: | ----------------------: | :---: |
| arch0     |  174 |  335 |  5.66517e-01            |     1 |
| infd1     |   10 |   30 |  dual infeasible        |     6 |
| qap10     | 1021 |  101 | -1.093e+01              | 9, 14 |

14. The optimal objective value for `qap10` was found to be `-1.093e+03`
    by at least three indepentend experiments
"""

SHARED = """| problem | m | n | optimal value |
|---|---:|---:|---:|
| truss1 | 6 | 13 | -8.999996e+00 |
| infp1 | 10 | 30 | primal infeasible |
"""


def test_full_layout_with_the_note_correction():
    pub = bench.published_optima(FULL)
    assert pub == {"arch0": "5.66517e-01", "infd1": "dual infeasible", "qap10": "-1.093e+03"}


def test_shared_layout():
    assert bench.published_optima(SHARED) == {"truss1": "-8.999996e+00", "infp1": "primal infeasible"}


def test_rounding_interval_and_meets():
    lo, hi = bench.rounding_interval("5.66517e-01")
    assert abs(lo - 0.5665165) < 1e-15 and abs(hi - 0.5665175) < 1e-15
    assert bench.meets((0.56651, 0.566517), "5.66517e-01")
    assert not bench.meets((0.5665176, 0.57), "5.66517e-01")
    assert bench.meets((None, 1.0), "5.66517e-01") is None
    assert bench.meets((0.0, 1.0), "primal infeasible") is None


def test_a_directory_without_problems_is_one_line_and_exit_2(tmp_path, capsys):
    assert bench.main(["--dir", str(tmp_path)]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [f"sdplib_full: no .dat-s file in {tmp_path}"]
    (tmp_path / "a.dat-s").write_text("1\n1\n1\n1.0\n0 1 1 1 1.0\n")
    assert bench.main(["--dir", str(tmp_path), "--only", "b"]) == 2
    assert capsys.readouterr().err.strip() == f"sdplib_full: no file b.dat-s in {tmp_path}"


def test_exact_point_check_reads_every_block_exactly(tmp_path):
    # min x1 + x2 s.t. [[x1, 1, 0], [1, x2, 1], [0, 1, x1]] - 0 >= 0 (F0 = 0) and diag(x1 - 1) >= 0
    text = (
        "2\n2\n3 -1\n1.0 1.0\n1 1 1 1 1.0\n1 1 3 3 1.0\n2 1 2 2 1.0\n"
        "0 1 1 2 -1.0\n0 1 2 3 -1.0\n0 2 1 1 1.0\n1 2 1 1 1.0\n"
    )
    path = tmp_path / "toy.dat-s"
    path.write_text(text)
    # at x = (2, 1.01): pivots 2, 1.01 - 1/2, 2 - 1/0.51 > 0 and x1 - 1 = 1 > 0
    objective, feasible = bench.exact_point_check(path, [2.0, 1.01])
    assert feasible
    assert abs(float(objective) - 3.01) < 1e-15
    # x = (2, 0.9): the 3 x 3 block's determinant 2 * (1.8 - 1) - 2 = -0.4 < 0 although its
    # first two pivots are positive
    assert bench.exact_point_check(path, [2.0, 0.9])[1] is False
    # x = (1, 5): the diagonal block x1 - 1 = 0 is not positive
    assert bench.exact_point_check(path, [1.0, 5.0])[1] is False


def test_below_compares_an_exact_objective_with_a_float_exactly():
    """``fmpq < float`` is not defined in python-flint (the refutation check raised TypeError)."""
    from flint import fmpq

    third = 0.3333333333333333  # the float just below 1/3
    assert bench.below(fmpq(1, 3), third) is False and bench.below(fmpq(1, 3), 0.33333333333333337) is True
    assert bench.below(fmpq(362487, 1000), 362.5) is True


def _maxcut_text(W):
    """An SDPLIB max-cut relaxation of the weights ``W`` (``F_0 = -L / 4``, ``F_i = e_i e_i'``)."""
    import numpy as np

    n = len(W)
    L = np.diag(W.sum(axis=1)) - W
    lines = [str(n), "1", str(n), " ".join(["1.0"] * n)]
    lines += [f"0 1 {i + 1} {j + 1} {float(-L[i, j] / 4)!r}" for i in range(n) for j in range(i, n) if L[i, j] != 0]
    lines += [f"{i + 1} 1 {i + 1} {i + 1} 1.0" for i in range(n)]
    return "\n".join(lines) + "\n"


def test_maxcut_dual_bound_is_below_and_near_the_optimum_of_an_independent_solve(tmp_path):
    """The benchmark's exact dual bound for a max-cut relaxation never exceeds the optimum (CVXPY
    + Clarabel on the dual, written here) and is within 1e-5 relative of it; a problem of another
    shape gets no bound."""
    import cvxpy as cp
    import numpy as np

    for seed in range(3):
        rng = np.random.default_rng(seed)
        n = 7
        W = np.triu((rng.random((n, n)) < 0.5) * rng.integers(1, 4, (n, n)), 1).astype(float)
        W = W + W.T
        path = tmp_path / f"mc{seed}.dat-s"
        path.write_text(_maxcut_text(W))
        L = np.diag(W.sum(axis=1)) - W
        Y = cp.Variable((n, n), symmetric=True)
        opt = cp.Problem(cp.Maximize(cp.trace(-L / 4 @ Y)), [Y >> 0, cp.diag(Y) == 1]).solve(solver=cp.CLARABEL)
        low = float(bench.maxcut_dual_bound(path))
        assert low <= opt + 1e-7 * max(1.0, abs(opt))
        assert low >= opt - 1e-5 * max(1.0, abs(opt))
    other = tmp_path / "other.dat-s"
    other.write_text("1\n1\n2\n1.0\n0 1 1 1 1.0\n1 1 1 1 1.0\n1 1 2 2 1.0\n")
    assert bench.maxcut_dual_bound(other) is None
