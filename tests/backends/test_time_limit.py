"""``--time-limit`` on every backend: one deadline for the whole solve, the solver stopped in its
forked child, a recognisable result (``error`` + ``info["time_limit"]``); and SolveOptions
validation (bad numbers are bad input: LmicError, exit code 2 on the command line)."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest

from lmic.api import certify_solution
from lmic.backends.base import Backend, SolveOptions
from lmic.backends.outcomes import is_time_limit
from lmic.backends.registry import get_backend
from lmic.cli import main
from lmic.errors import LmicError
from lmic.reductions.pipeline import solve as solve_with_reductions
from lmic.solution import Solution
from lmic.testing.conformance import bounded_real_problem, lyapunov_problem

BACKENDS = ["clarabel", "scs", "cvxopt", "sdpa", "cvxpy", "cvxpy:SCS", "picos"]
LIMIT = 0.02
#: fork, stop and join of the child; generous for a machine shared by many processes
GRACE = 3.0


def _brl(n: int = 24):
    rng = np.random.default_rng(7)
    A = rng.standard_normal((n, n))
    A -= (max(np.linalg.eigvals(A).real) + 0.5) * np.eye(n)
    return bounded_real_problem(A, rng.standard_normal((n, 2)), rng.standard_normal((2, n)))


@pytest.mark.parametrize("name", BACKENDS)
def test_a_tiny_time_limit_stops_every_backend(name):
    problem = _brl()
    be = get_backend(name)
    free = solve_with_reductions(be, problem)
    # the problem needs longer than the limit, and is solvable: the limit is what stops it
    assert free.solve_s > LIMIT
    assert certify_solution(problem, free).verdict == "certified", free.message
    t0 = time.perf_counter()
    sol = solve_with_reductions(be, problem, SolveOptions(time_limit=LIMIT))
    wall = time.perf_counter() - t0
    assert wall < LIMIT + GRACE
    assert sol.status == "error" and is_time_limit(sol), (sol.status, sol.message)
    assert sol.message.startswith(f"time limit of {LIMIT:g} s exceeded")
    assert sol.x is None
    assert certify_solution(problem, sol).verdict not in ("certified", "infeasible-certified")


class _Sleepy(Backend):
    name = "sleepy"
    STATUS_MAP = {"done": "optimal"}

    def _solve(self, problem, options):
        time.sleep(30)
        return Solution("optimal", x=np.zeros(problem.n))


def test_one_deadline_covers_every_strict_attempt():
    """A feasibility problem whose plan has two attempts (fixed-margin, then max-margin): both
    together stay within one limit; the second starts after the deadline and returns at once."""
    problem = lyapunov_problem(-np.eye(30))
    limit = 1.5
    t0 = time.perf_counter()
    sol = solve_with_reductions(_Sleepy(), problem, SolveOptions(time_limit=limit))
    wall = time.perf_counter() - t0
    attempts = sol.info.get("strict_attempts", [])
    assert len(attempts) == 2, attempts
    assert is_time_limit(sol)
    assert wall < 2 * limit  # two attempts with a limit each would take at least 2 * limit


@pytest.mark.parametrize(
    "field,value",
    [
        ("time_limit", -1.0),
        ("time_limit", 0.0),
        ("time_limit", math.nan),
        ("time_limit", math.inf),
        ("tol", -1e-8),
        ("tol", math.nan),
        ("tol", math.inf),
        ("tol", 0.0),
        ("max_iter", 0),
        ("max_iter", -5),
        ("max_iter", 2.5),
        ("max_iter", math.nan),
        ("margin", -1e-3),
        ("margin", math.nan),
        ("margin", math.inf),
        ("margin", "1e-3"),
    ],
)
def test_bad_solve_options_are_bad_input(field, value):
    with pytest.raises(LmicError, match=field):
        SolveOptions(**{field: value})
    opts = SolveOptions()
    with pytest.raises(LmicError, match=field):
        setattr(opts, field, value)


def test_good_solve_options_are_kept():
    opts = SolveOptions(time_limit=0.001, tol=1e-6, max_iter=50, margin=1e-5)
    assert (opts.time_limit, opts.tol, opts.max_iter, opts.margin) == (0.001, 1e-6, 50, 1e-5)
    opts.time_limit = None
    assert opts.time_limit is None


@pytest.mark.parametrize(
    "flag,value",
    [("--time-limit", "-1"), ("--time-limit", "nan"), ("--tol", "inf"), ("--max-iter", "0"), ("--margin=", "-1")],
)
def test_cli_rejects_bad_numbers_with_exit_2(tmp_path, capsys, flag, value):
    target = tmp_path / "p.json"
    from lmic.ir.io import save_problem

    save_problem(lyapunov_problem(-np.eye(2)), target)
    args = ["solve", str(target), f"{flag}{value}"] if flag.endswith("=") else ["solve", str(target), flag, value]
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("lmic: error:")


def test_cli_time_limit_is_reported_as_a_time_limit(tmp_path, capsys):
    from lmic.ir.io import save_problem

    target = tmp_path / "brl.json"
    save_problem(_brl(), target)
    code = main(["solve", str(target), "--backend", "cvxopt", "--time-limit", "0.001", "--json"])
    out = capsys.readouterr().out
    assert code == 1
    assert "time limit of 0.001 s exceeded" in out
