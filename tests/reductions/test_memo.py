"""Solves remembered within a route (lmic/reductions/memo.py): the same closed problem at the
same options is solved once; anything that changes the answer is a new solve; the answers
(and the route's enclosure) are the same with and without the memory."""

from __future__ import annotations

import dataclasses
import sys
from pathlib import Path

import numpy as np
import pytest

from lmic.backends.registry import get_backend
from lmic.options import SolveOptions
from lmic.reductions import memo
from lmic.reductions.memo import options_key, problem_key, remembered_solves
from lmic.reductions.pipeline import solve
from lmic.solution import Solution
from lmic.testing.conformance import CASES, lyapunov_problem


@pytest.fixture
def counted(monkeypatch):
    """Clarabel, its native closed solves counted."""
    be = get_backend("clarabel")
    calls: list[int] = []
    native = be._run

    def run(problem, options, deadline=None):
        calls.append(problem.n)
        return native(problem, options, deadline)

    monkeypatch.setattr(be, "_run", run)
    return be, calls


def test_the_same_problem_at_the_same_options_is_solved_once(counted):
    be, calls = counted
    problem = CASES["max_sense"].build()
    with remembered_solves():
        first = solve(be, problem, SolveOptions(time_limit=30.0))
        again = solve(be, CASES["max_sense"].build(), SolveOptions(time_limit=5.0))  # a new object, another limit
        assert first.status == again.status == "optimal"
        assert np.array_equal(first.x, again.x) and again.x is not first.x
        assert again.info.get("remembered") and again.solve_s == 0.0 and not first.info.get("remembered")
        again.x[:] = 7.0  # a caller's change does not reach the memory
        third = solve(be, problem)
    assert len(calls) == 1 and np.array_equal(third.x, first.x)


def test_outside_a_route_every_solve_runs(counted):
    be, calls = counted
    problem = CASES["max_sense"].build()
    solve(be, problem)
    solve(be, problem)
    assert len(calls) == 2


def test_what_changes_the_answer_is_a_new_solve(counted):
    be, calls = counted
    problem = CASES["max_sense"].build()
    with remembered_solves():
        solve(be, problem)
        solve(be, problem, SolveOptions(tol=1e-9))  # another tolerance
        solve(be, problem, SolveOptions(extra={"max_iter": 50}))  # another native setting
        solve(be, problem, SolveOptions(warm_start=Solution("optimal", x=np.zeros(problem.n))))  # never remembered
        solve(be, problem, SolveOptions(warm_start=Solution("optimal", x=np.zeros(problem.n))))
        c = problem.objective.c.copy()
        c[-1] += 1e-12  # one coefficient of the objective
        solve(be, dataclasses.replace(problem, objective=dataclasses.replace(problem.objective, c=c)))
        solve(be, problem, SolveOptions(tol=1e-9))  # seen
    assert len(calls) == 6


def test_errors_and_time_limits_are_not_remembered():
    problem = lyapunov_problem(-np.eye(1))
    options = SolveOptions()
    with remembered_solves():
        for sol in (
            Solution("error", message="crash"),
            Solution("inaccurate", message="time limit of 1 s exceeded", info={"time_limit": True}),
        ):
            key, known = memo.recall("clarabel", problem, options)
            assert key is not None and known is None
            memo.remember(key, sol)
        key, known = memo.recall("clarabel", problem, options)
        assert known is None
        memo.remember(key, Solution("optimal", x=np.ones(problem.n)))
        assert memo.recall("clarabel", problem, options)[1].status == "optimal"
        assert memo.recall("cvxopt", problem, options)[1] is None  # another backend
    assert memo.recall("clarabel", problem, options) == (None, None)  # outside a route


def test_problem_key_sees_every_number_a_backend_reads():
    base = CASES["max_sense"].build()
    assert problem_key(base) == problem_key(CASES["max_sense"].build())
    lmi = base.lmis[0]
    coeffs = lmi.coeffs.tocsr(copy=True)
    coeffs.data[0] += 1e-15
    changed = [
        dataclasses.replace(base, lmis=[dataclasses.replace(lmi, coeffs=coeffs)] + base.lmis[1:]),
        dataclasses.replace(base, lmis=[dataclasses.replace(lmi, strict=not lmi.strict)] + base.lmis[1:]),
        dataclasses.replace(base, objective=dataclasses.replace(base.objective, sense="min")),
    ]
    keys = {problem_key(p) for p in changed}
    assert problem_key(base) not in keys and len(keys) == 3
    # the same matrix in another sparse format (and with its entries split) is the same problem
    coo = lmi.coeffs.tocoo()
    rows, cols = np.r_[coo.row, coo.row], np.r_[coo.col, coo.col]
    split = type(coo)((np.r_[coo.data / 2, coo.data / 2], (rows, cols)), coo.shape)
    same = dataclasses.replace(base, lmis=[dataclasses.replace(lmi, coeffs=split.tocsc())] + base.lmis[1:])
    assert problem_key(same) == problem_key(base)  # halves of a float add up to it exactly


def test_options_key_ignores_only_the_time_limit():
    assert options_key(SolveOptions(time_limit=1.0)) == options_key(SolveOptions(time_limit=100.0))
    assert options_key(SolveOptions(margin=1e-6)) != options_key(SolveOptions())
    assert options_key(SolveOptions(extra={"solver": object()})) is None
    assert options_key(SolveOptions(accept=lambda x: True)) is None


def test_the_memory_keeps_the_newest_entries(monkeypatch, counted):
    be, calls = counted
    monkeypatch.setattr(memo, "MAX_ENTRIES", 2)
    problems = [lyapunov_problem(-k * np.eye(1)) for k in (1.0, 2.0, 3.0)]
    with remembered_solves():
        for p in problems:
            solve(be, p)
        solve(be, problems[2])  # kept
        solve(be, problems[0])  # dropped: solved again
    assert len(calls) == 4


def test_a_route_gives_the_same_enclosure_with_fewer_solves(monkeypatch):
    """uir.thm5_1 (2 states, seed 2): the strict polish re-solves problems the route solved
    before; remembered, the route makes fewer native solves and proves the same ends."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "plugins"))
    import optimisation_instances as oi

    from lmic.api import solve as api_solve

    system = oi.instance("uir.thm5_1", 2, 2)
    seen: list[tuple[str, str, tuple]] = []
    native = type(get_backend("clarabel"))._run

    def run(self, problem, options, deadline=None):
        seen.append((self.label, problem_key(problem), options_key(options)))
        return native(self, problem, options, deadline)

    for name in ("clarabel", "cvxopt", "sdpa"):
        monkeypatch.setattr(type(get_backend(name)), "_run", run)
    with_memo = api_solve("uir.thm5_1", system)
    solves_with = list(seen)
    seen.clear()
    monkeypatch.setattr(memo, "_key", lambda label, problem, options: None)  # nothing remembered
    without = api_solve("uir.thm5_1", system)
    solves_without = list(seen)
    assert len(set(solves_with)) == len(solves_with)  # no closed problem solved twice
    assert len(solves_without) > len(solves_with)
    assert with_memo.verdict == without.verdict == "certified"
    for end in ("lower", "upper"):
        assert with_memo.enclosure[end] == without.enclosure[end]
    # the ends are proven, and contain the optimum computed independently (CVXPY + Clarabel)
    status, value, tol = oi.reference("uir.thm5_1", system)
    assert status == "optimal" and oi.contains(with_memo.enclosure, value, tol)
