"""The engine's solve (lmic/reductions/pipeline.py): an inexact infeasibility claim is settled by
the certifier on the problem the solver was given, never by the backend; the backend-level solve
leaves it inaccurate."""

from __future__ import annotations

import numpy as np

from lmic.api import certify_solution
from lmic.backends.backend import Backend
from lmic.backends.registry import get_backend
from lmic.backends.results import NativeResult
from lmic.certify.farkas import verify_farkas
from lmic.reductions.pipeline import settle, solve
from lmic.solution import Solution
from lmic.testing.conformance import CASES


def _claiming(ray):
    class _Almost(Backend):
        name, title = "almost", "Almost"
        STATUS_MAP = {"AlmostInfeasible": "inaccurate"}
        INEXACT_INFEASIBLE = frozenset({"AlmostInfeasible"})

        def call(self, problem, settings):
            r = ray(problem) if callable(ray) else ray
            return NativeResult("AlmostInfeasible", x=np.zeros(problem.n), duals=r)

    return _Almost()


def _true_ray(problem):
    sol = solve(get_backend("clarabel"), problem)
    assert sol.status == "infeasible" and verify_farkas(problem, sol.farkas)["verified"]
    return sol.farkas


def test_a_verified_ray_makes_the_claim_infeasible_in_the_engine_only():
    problem = CASES["infeasible"].build()
    be = _claiming(_true_ray)
    alone = be.solve(problem)
    assert alone.status == "inaccurate" and alone.x is None and alone.info["claim"] == "infeasible"
    engine = solve(be, problem)
    assert engine.status == "infeasible" and engine.farkas is not None
    assert "verifies" in engine.message
    assert certify_solution(problem, engine).verdict in ("infeasible-bounded", "infeasible-certified")


def test_a_ray_that_does_not_verify_stays_inaccurate_without_a_point():
    problem = CASES["max_sense"].build()  # feasible: no ray verifies
    rng = np.random.default_rng(0)
    bad = {
        "lmis": [(lambda M: M @ M.T)(rng.standard_normal((lmi.dim, lmi.dim))) for lmi in problem.lmis],
        "linear": np.zeros(len(problem.linear)),
    }
    sol = solve(_claiming(bad), problem)
    assert sol.status == "inaccurate" and sol.x is None and sol.farkas is None
    assert "not a verified Farkas certificate" in sol.message and sol.info["inexact_farkas"] is bad
    assert certify_solution(problem, sol).verdict not in ("certified", "infeasible-certified")


def test_settle_leaves_other_answers_alone():
    sol = Solution("inaccurate", x=np.ones(2))
    assert settle(CASES["max_sense"].build(), sol) is sol and sol.x is not None


def test_auto_is_its_routes_first_backend():
    problem = CASES["max_sense"].build()
    sol = solve(get_backend("auto"), problem)
    assert sol.info["auto_route"][0] == sol.backend
    from lmic.testing.conformance import _C

    # the optimum lambda_min(C), computed by numpy (the point itself is on the boundary of the
    # non-strict LMI: what certifies it is lmic.api.solve's enclosure, not this raw solve)
    assert sol.objective is not None and abs(sol.objective - float(np.linalg.eigvalsh(_C)[0])) < 1e-6


def test_a_bug_in_lmic_is_named_as_such_not_as_the_solvers_failure(monkeypatch):
    import lmic.reductions.pipeline as pipeline

    problem = CASES["max_sense"].build()
    monkeypatch.setattr(pipeline, "eliminate_unused", {}.get)  # a programming error: wrong call signature
    sol = solve(get_backend("clarabel"), problem)
    assert sol.status == "error"
    assert sol.message.startswith("internal error in lmic at lmic/reductions/pipeline.py:"), sol.message
    assert "not the solver's" in sol.message and "TypeError" in sol.message


def test_a_solver_librarys_crash_is_the_solvers(monkeypatch):
    class _Crashing(Backend):
        name, title = "crashing", "Crashing"

        def call(self, problem, settings):
            raise RuntimeError("solver blew up")

    sol = solve(_Crashing(), CASES["max_sense"].build())
    assert sol.status == "error" and "solver blew up" in sol.message and "internal error" not in sol.message


def test_a_solve_that_would_exhaust_memory_is_refused_before_it_starts(monkeypatch):
    """SDPLIB gpp250-1 (one 250 x 250 LMI): lmic.upper_end handed it to Clarabel, whose dense
    31375^2 block (7.9 GB, three copies) ended the process out of memory. The engine now asks
    the backend first, whoever the caller."""
    import lmic.backends.clarabel as clarabel_backend

    be = get_backend("clarabel")
    problem = CASES["max_sense"].build()
    need = clarabel_backend.kkt_bytes(problem)
    monkeypatch.setattr(clarabel_backend, "_physical_memory", lambda: int(need / clarabel_backend.MEMORY_FRACTION) - 1)
    calls: list[int] = []
    monkeypatch.setattr(be, "_run", lambda *a, **k: calls.append(1))
    sol = solve(be, problem)
    assert sol.status == "error" and calls == []
    assert "needs about" in sol.message and "use --backend sdpa, cvxopt or auto" in sol.message
    assert get_backend("cvxpy:CLARABEL").too_large(problem) == sol.message  # through CVXPY as well
    assert get_backend("sdpa").too_large(problem) is None
    monkeypatch.setattr(clarabel_backend, "_physical_memory", lambda: int(need / clarabel_backend.MEMORY_FRACTION) + 10)
    monkeypatch.undo()
    assert solve(get_backend("clarabel"), problem).status == "optimal"
