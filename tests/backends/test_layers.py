"""The modelling-layer backends (PICOS, CVXPY) give the answers their underlying solvers give,
checked through the certifier: SDPLIB control1 (PICOS raised ZeroDivisionError there), random
bounded-real-lemma instances against the H-infinity norm computed by Hamiltonian bisection,
a problem where CVXOPT stops 'unknown', and inexact infeasibility claims."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from lmic.api import certify_solution, load_target
from lmic.backends.base import SolveOptions
from lmic.backends.registry import get_backend
from lmic.ir.io import load_problem
from lmic.reductions.pipeline import settle_inexact_infeasible
from lmic.reductions.pipeline import solve as solve_with_reductions
from lmic.solution import Solution
from lmic.testing.conformance import CASES, bounded_real_problem, hinf_norm

ROOT = Path(__file__).resolve().parents[2]
SDPLIB = ROOT.parent / "shared" / "sdplib"


def _published(name: str) -> float:
    for line in (SDPLIB / "README.md").read_text().splitlines():
        m = re.match(rf"\|\s*{name}\s*\|\s*\d+\s*\|\s*\d+\s*\|\s*([-+.\deE]+)\s*\|", line)
        if m:
            return float(m.group(1))
    raise LookupError(name)


@pytest.mark.skipif(not (SDPLIB / "control1.dat-s").is_file(), reason="SDPLIB not found")
@pytest.mark.parametrize("backend", ["picos", "cvxpy", "cvxpy:CVXOPT"])
def test_control1_is_certified_at_the_published_optimum(backend):
    problem = load_problem(SDPLIB / "control1.dat-s")
    sol = solve_with_reductions(get_backend(backend), problem)
    cert = certify_solution(problem, sol)
    assert sol.status == "optimal", sol.message
    assert cert.verdict == "certified", cert.reason
    assert sol.objective == pytest.approx(_published("control1"), rel=1e-5)


def _brl(seed: int, n: int):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    A -= (max(np.linalg.eigvals(A).real) + 0.5) * np.eye(n)
    B, C = rng.standard_normal((n, 2)), rng.standard_normal((2, n))
    return bounded_real_problem(A, B, C), hinf_norm(A, B, C)


@pytest.mark.parametrize("backend", ["picos", "cvxpy", "cvxpy:CVXOPT", "cvxpy:SCS"])
@pytest.mark.parametrize("seed", [0, 1])
def test_minimal_gamma_is_certified_and_is_the_hinf_norm(backend, seed):
    problem, reference = _brl(seed, 8)
    be = get_backend(backend)
    sol = solve_with_reductions(be, problem)
    cert = certify_solution(problem, sol)
    assert sol.status == "optimal", f"{sol.native_status}: {sol.message}"
    assert cert.verdict == "certified", cert.reason
    # every certified gamma is an upper bound of the norm (strict LMI): approached from above
    rel = 1e-3 if not be.interior_point else 1e-5
    assert sol.objective >= reference * (1 - 1e-7)
    assert sol.objective == pytest.approx(reference, rel=rel)


def test_picos_keeps_cvxopts_last_iterate_where_cvxopt_stops_unknown():
    """uio_dt.thm4_1 (shipped example): CVXOPT stops 'unknown' after 100 iterations; PICOS
    reports unknown/unknown. Both backends must hand the same iterate to the certifier."""
    problem, _, _ = load_target("uio_dt.thm4_1", ROOT / "examples" / "uio_dt.thm4_1.flexible_joint.yaml")
    native = solve_with_reductions(get_backend("cvxopt"), problem)
    layer = solve_with_reductions(get_backend("picos"), problem)
    assert native.native_status == "unknown" and layer.native_status == "unknown/unknown"
    assert layer.status == native.status == "inaccurate"
    assert layer.x is not None and native.x is not None
    assert np.allclose(layer.x, native.x, rtol=1e-6, atol=1e-9 * np.abs(native.x).max())
    assert certify_solution(problem, layer).verdict == certify_solution(problem, native).verdict


def test_picos_time_limit_is_enforced_by_the_sandbox():
    problem, _ = _brl(3, 30)  # ~0.5 s on CVXOPT
    sol = solve_with_reductions(get_backend("picos"), problem, SolveOptions(time_limit=0.01))
    assert sol.status == "error" and sol.info["time_limit"] and sol.x is None


@pytest.mark.skipif(not (SDPLIB / "infp1.dat-s").is_file(), reason="SDPLIB not found")
def test_cvxpy_inexact_infeasibility_is_kept_when_its_ray_verifies():
    """CVXPY/Clarabel reports infp1 'infeasible_inaccurate': the ray verifies, so it stays a
    infeasibility; the certifier checks it independently (exactly, for a global proof)."""
    problem = load_problem(SDPLIB / "infp1.dat-s")
    sol = solve_with_reductions(get_backend("cvxpy"), problem, SolveOptions(tol=1e-7))
    assert sol.native_status == "infeasible_inaccurate"
    assert sol.status == "infeasible"
    # the float ray verifies (bounded infeasibility); the exact proof makes it global
    assert certify_solution(problem, sol).verdict == "infeasible-bounded"
    assert certify_solution(problem, sol, exact=True).verdict == "infeasible-certified"


def test_an_inexact_infeasibility_claim_with_a_bad_ray_is_inaccurate_without_a_point():
    problem = CASES["max_sense"].build()  # feasible: no ray can verify
    rng = np.random.default_rng(0)
    bad = {
        "lmis": [(lambda M: M @ M.T)(rng.standard_normal((lmi.dim, lmi.dim))) for lmi in problem.lmis],
        "linear": np.zeros(len(problem.linear)),
    }
    sol = settle_inexact_infeasible(
        problem, Solution("inaccurate", x=np.zeros(problem.n), native_status="AlmostPrimalInfeasible"), bad
    )
    assert sol.status == "inaccurate" and sol.x is None and sol.farkas is None
    assert "not a verified Farkas certificate" in sol.message
    assert certify_solution(problem, sol).verdict not in ("certified", "infeasible-certified")
