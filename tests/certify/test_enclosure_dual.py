"""The dual search's re-solves (lmic/certify/enclosure_dual.py): skipped where the dual equality
system is singular only through rounding (no float dual point can be corrected exactly), run
where it is regular or exactly singular; the primal end and the verdict do not change."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from lmic.certify import enclosure_dual
from lmic.certify.enclosure_dual import dual_bound, rounding_only
from lmic.certify.enclosure_repair import _jacobian
from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "plugins"))

import optimisation_instances as oi  # noqa: E402


def _two_directions(b: float) -> Problem:
    """min b s.t. [[1 + a + b, 0], [0, 1 + beta b]] >= 0 with beta = ``b``'s weight on the second
    entry: ``a`` and ``b`` act alike up to ``beta``."""
    v = [Variable("a", "scalar", (1, 1)), Variable("b", "scalar", (1, 1), offset=1)]
    F = sp.csc_matrix(np.array([[1.0, 1.0, 1.0], [0.0, 0.0, 0.0], [1.0, 0.0, b]]))
    return Problem(
        v, [LMI("F(a, b) >= 0", 2, F, strict=False)], LinearConstraints.empty(2), Objective("min", [0.0, 0.0, 1.0])
    )


def _counting():
    calls: list[str] = []

    def resolve(problem):
        calls.append("resolve")
        return None

    def solve_point(problem):
        calls.append("solve_point")
        return None

    def before():
        calls.append("facial")
        return {"proven": False, "reason": "facial route: nothing"}

    return calls, resolve, solve_point, before


def test_rows_equal_up_to_rounding_skip_every_re_solve():
    problem = _two_directions(2.0**-52)
    assert rounding_only(problem, _jacobian(problem)[0]) is not None
    calls, resolve, solve_point, before = _counting()
    bad = {"lmis": [np.diag([1.0, -1.0])], "linear": np.zeros(0)}  # no repair proves from here
    out = dual_bound(problem, bad, resolve=resolve, solve_point=solve_point, before_solves=before)
    assert not out["proven"] and out["resolves"] == "skipped"
    assert "no re-solve tried: the dual equality system is singular to" in out["reason"]
    assert calls == []


def test_independent_rows_keep_their_re_solves():
    problem = _two_directions(0.5)  # the same shape, rows far from dependent
    assert rounding_only(problem, _jacobian(problem)[0]) is None
    calls, resolve, solve_point, before = _counting()
    bad = {"lmis": [np.diag([1.0, -1.0])], "linear": np.zeros(0)}
    out = dual_bound(problem, bad, resolve=resolve, solve_point=solve_point, before_solves=before)
    # the repair of this dual does not prove (b's entry has no interior): the facial route, the
    # perturbed re-solves and the centring solves are all tried (they return nothing here)
    assert not out["proven"] and "resolves" not in out
    assert calls[0] == "facial" and "resolve" in calls and "solve_point" in calls


def test_the_test_is_not_run_on_large_systems(monkeypatch):
    problem = _two_directions(2.0**-52)
    J = _jacobian(problem)[0]
    monkeypatch.setattr(enclosure_dual, "ROUNDING_TEST_MAX", 0.5 * J.shape[0] ** 2 * J.shape[1])
    assert rounding_only(problem, J) is None


def test_random_uio_instance_same_ends_fewer_solves(monkeypatch):
    """uio_dt.thm4_1 (3 states, seed 1): its projector is computed in floating point, so no
    lower end is provable; without the re-solves the route proves the same primal end and
    verdict with fewer solves (7 states: 8-10 s -> 2-3 s)."""
    import lmic.reductions.pipeline as pipeline
    from lmic.api import solve

    system = oi.instance("uio_dt.thm4_1", 1, 3)
    native = pipeline.solve
    calls: list[int] = []

    def counted(*args, **kwargs):
        calls.append(1)
        return native(*args, **kwargs)

    monkeypatch.setattr(pipeline, "solve", counted)
    now = solve("uio_dt.thm4_1", system)
    n_now = len(calls)
    calls.clear()
    monkeypatch.setattr(enclosure_dual, "rounding_only", lambda problem, J: None)  # the search as before
    before = solve("uio_dt.thm4_1", system)
    assert now.enclosure["dual"]["resolves"] == "skipped" and "no re-solve tried" in now.enclosure["dual"]["reason"]
    assert now.verdict == before.verdict == "certified"
    assert (
        now.enclosure["upper"] == before.enclosure["upper"]
        and now.enclosure["lower"] is before.enclosure["lower"] is None
    )
    assert n_now < len(calls)
    # the upper end is the objective at a point the certifier accepts, and lies above the
    # optimum computed independently (CVXPY + Clarabel on the theorem's LMIs)
    status, value, tol = oi.reference("uio_dt.thm4_1", system)
    assert status == "optimal" and now.enclosure["upper"] >= value - tol * max(1.0, abs(value))
