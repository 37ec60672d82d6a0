"""The one native-result mapping (lmic/backends/results.py) and every backend's tables."""

from __future__ import annotations

import numpy as np
import pytest

from lmic.backends.backend import Backend
from lmic.backends.outcomes import is_time_limit
from lmic.backends.registry import get_backend
from lmic.backends.results import NativeResult, to_solution
from lmic.testing.conformance import CASES

BACKENDS = ["clarabel", "scs", "cvxopt", "sdpa", "cvxpy", "picos"]


class _Tables(Backend):
    name, title = "tables", "Tables"
    STATUS_MAP = {"ok": "optimal", "meh": "inaccurate", "inf": "infeasible", "unb": "unbounded", "inf?": "inaccurate"}
    INEXACT_INFEASIBLE = frozenset({"inf?"})
    INEXACT_UNBOUNDED = frozenset({"unb?"})
    TIME_LIMIT = frozenset({"clock"})


P = CASES["max_sense"].build()
X = np.arange(P.n, dtype=float)
RAY = {"lmis": [np.eye(lmi.dim) for lmi in P.lmis], "linear": np.zeros(len(P.linear))}


def _map(native, **kw):
    return to_solution(_Tables(), P, NativeResult(native, **kw), 2.0)


def test_a_point_gets_its_objective_recomputed_from_the_problem():
    sol = _map("ok", x=X, duals=RAY)
    assert sol.status == "optimal" and np.array_equal(sol.x, X) and sol.duals is RAY
    assert sol.objective == pytest.approx(P.objective.c[0] + P.objective.c[1:] @ X)


def test_a_claim_without_a_point_is_an_error_and_an_inaccurate_point_is_kept():
    assert _map("ok").status == "error" and "no point" in _map("ok").message
    meh = _map("meh", x=X)
    assert meh.status == "inaccurate" and meh.x is not None and "Tables stopped with status 'meh'" == meh.message


def test_rays_go_to_farkas_or_info():
    assert _map("inf", x=X, duals=RAY).farkas is RAY and _map("inf", x=X, duals=RAY).x is None
    unb = _map("unb", x=X)
    assert unb.status == "unbounded" and unb.x is None and np.array_equal(unb.info["ray"], X)


def test_an_inexact_infeasibility_claim_keeps_its_ray_for_the_engine_and_no_point():
    sol = _map("inf?", x=X, duals=RAY)
    assert sol.status == "inaccurate" and sol.x is None and sol.farkas is None
    assert sol.info["claim"] == "infeasible" and sol.info["inexact_farkas"] is RAY
    assert "without a ray" in _map("inf?", x=X).message


def test_an_inexact_unboundedness_claim_and_a_time_limit():
    unb = _map("unb?", x=X)
    assert unb.status == "error" and unb.x is None and np.array_equal(unb.info["inexact_ray"], X)
    clock = _map("clock", x=X, solve_s=2.1)
    assert clock.status == "error" and is_time_limit(clock) and clock.x is None
    assert clock.message.startswith("time limit of 2 s exceeded")


@pytest.mark.parametrize("name", BACKENDS)
def test_every_backend_declares_consistent_tables(name):
    be = get_backend(name)
    assert be.title and callable(be.settings)
    for native in be.INEXACT_INFEASIBLE | be.INEXACT_UNBOUNDED:
        assert be.STATUS_MAP[native] == "inaccurate", native
    for native in be.TIME_LIMIT:
        assert be.map_status(native) == "error", native
