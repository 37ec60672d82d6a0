"""SDPLIB conformance: every problem on every backend able to take it in reasonable time.

Optimal values are read from ``shared/sdplib/README.md``. Interior-point backends must match to
1e-5 relative (the ``hinf`` problems, published with few digits, to one unit of the last
published digit), SCS to 1e-3. ``infp1`` must come back infeasible with a valid Farkas ray and
``infd1`` unbounded. Combinations left out carry the reason (times measured on 2 cores).
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from lmic.backends.base import SolveOptions
from lmic.backends.registry import get_backend
from lmic.ir.io import load_problem
from lmic.reductions.pipeline import solve as solve_with_reductions
from lmic.testing.conformance import farkas_residuals

SDPLIB = Path(__file__).resolve().parents[3] / "shared" / "sdplib"
if not SDPLIB.is_dir():
    pytest.skip(f"SDPLIB test data not found at {SDPLIB}", allow_module_level=True)


def _published() -> dict[str, str]:
    out = {}
    for line in (SDPLIB / "README.md").read_text().splitlines():
        m = re.match(
            r"\|\s*(\w+)\s*\|\s*\d+\s*\|\s*\d+\s*\|\s*([-+.\deE]+|primal infeasible|dual infeasible)\s*\|", line
        )
        if m:
            out[m.group(1)] = m.group(2)
    return out


PUBLISHED = _published()
BIG = {"theta2", "arch0", "control3", "qap5", "truss2"}

#: (backend, problem) -> why it is not run
SKIP = {
    ("clarabel", "theta2"): "slow: Clarabel takes 29 s (theta2, 498 variables); sdpa covers it in 5 s",
    ("clarabel", "arch0"): "slow: Clarabel takes 20 s (arch0); sdpa covers it in 9 s",
    ("cvxopt", "theta2"): "slow: CVXOPT takes 26 s on theta2; sdpa covers it",
    ("cvxopt", "arch0"): "slow: CVXOPT takes 46 s on arch0; sdpa covers it",
    ("scs", "arch0"): "SCS needs > 60 s on arch0 at eps 1e-6",
    ("scs", "control1"): "SCS does not converge on control1: 0.398 after 100000 iterations (17.78)",
    ("scs", "control2"): "SCS does not converge on control2: 7.24 after 100000 iterations (8.30)",
    ("scs", "control3"): "SCS does not converge on control3: 12.3 after 100000 iterations (13.63)",
    ("scs", "hinf5"): "SCS stalls on hinf5: 317 after 100000 iterations (363)",
    ("scs", "hinf6"): "SCS stalls on hinf6: 348 after 100000 iterations (449)",
}
#: (backend, problem) -> why ``inaccurate`` is accepted when the objective still matches
INACCURATE_OK = {
    ("sdpa", "qap5"): "SDPA stops at phase pFEAS on qap5 at -435.9998 (published -436.0)",
}
#: (backend, problem) -> why the solver's own outcome depends on the BLAS kernels (measured with
#: OpenBLAS's Haswell kernels, ``OPENBLAS_CORETYPE=Haswell``, and its AVX-512 ones, both numpy's
#: and the solvers' wheels): these cases are held to the contract that holds on every machine.
#: The solver returns a status (never raises); an ``optimal`` status has the published objective;
#: any point it returns that lmic's certifier certifies is feasible, so its objective is not below
#: the published optimum (beyond the tolerance). CVXOPT's ``ZeroDivisionError`` turned into an
#: ``error`` status is tested deterministically in tests/backends/test_examples.py.
MACHINE_DEPENDENT = {
    ("sdpa", "control3"): "SDPA ends 'optimal' with Haswell kernels, at phase pFEAS ('inaccurate') with AVX-512 "
    "ones, at 13.633268 both times (published 13.63327)",
    ("cvxopt", "hinf2"): "CVXOPT raises ZeroDivisionError in coneprog with Haswell kernels ('error'); with "
    "AVX-512 ones it stops 'unknown' ('inaccurate') at 10.96706 (published 10.967)",
    ("cvxopt", "hinf5"): "CVXOPT stops 'unknown' ('inaccurate') at 362.19 with Haswell kernels and at 343.02 "
    "with AVX-512 ones (published 363, an infeasible point: the certifier rejects it)",
}
#: the native solver behind each modelling-layer backend (same exclusions)
SOLVER_OF = {"cvxpy": "clarabel", "cvxpy:SCS": "scs", "picos": "cvxopt"}
#: modelling layers run on a sample only: they reuse the native solvers tested above
LAYER_SAMPLE = ["control1", "truss1", "hinf4", "theta1", "infp1", "infd1"]

CASES = []
for problem in PUBLISHED:
    for backend in ("clarabel", "cvxopt", "sdpa", "scs"):
        CASES.append((backend, problem))
    if problem in LAYER_SAMPLE:
        CASES += [("cvxpy", problem), ("cvxpy:SCS", problem), ("picos", problem)]


#: (backend, problem) -> (absolute tolerance, why the usual one is not met)
TOL_OVERRIDE = {
    ("clarabel", "hinf1"): (
        2e-4,
        "Clarabel stops ('Solved') at 2.03272 where SDPA and CVXOPT give 2.03262 and 2.03260: "
        "hinf1 is not strictly feasible and Clarabel's accuracy there is ~6e-5 relative",
    ),
}


def _tolerance(backend: str, problem: str, published: str) -> float:
    if (SOLVER_OF.get(backend, backend), problem) in TOL_OVERRIDE:
        return TOL_OVERRIDE[(SOLVER_OF.get(backend, backend), problem)][0]
    value = float(published)
    rel = 1e-3 if backend.endswith("scs") or backend.endswith("SCS") else 1e-5
    tol = rel * abs(value)
    if problem.startswith("hinf"):
        mantissa = published.lower().split("e")[0].lstrip("-+")
        digits = len(mantissa.replace(".", "")) - 1
        exponent = int(published.lower().split("e")[1]) if "e" in published.lower() else 0
        tol = max(tol, 10.0 ** (exponent - digits))
    return tol


@pytest.mark.parametrize("backend,problem", CASES, ids=[f"{b}-{p}" for b, p in CASES])
def test_sdplib(backend, problem):
    solver = SOLVER_OF.get(backend, backend)
    if (solver, problem) in SKIP:
        pytest.skip(SKIP[(solver, problem)])
    prob = load_problem(SDPLIB / f"{problem}.dat-s")
    be = get_backend(backend)
    tol = 1e-6 if not be.interior_point else 1e-7
    sol = solve_with_reductions(be, prob, SolveOptions(tol=tol, time_limit=120))
    published = PUBLISHED[problem]
    if (solver, problem) in MACHINE_DEPENDENT:
        _never_a_false_claim(prob, sol, backend, problem, published)
        return
    if published == "primal infeasible":
        assert sol.status == "infeasible", sol.message
        if sol.farkas is not None:
            grad, value, sign = farkas_residuals(prob, sol.farkas)
            assert value < 0 and grad < 1e-5 * abs(value) * 1e3 and sign > -1e-6 * abs(value)
        return
    if published == "dual infeasible":
        assert sol.status == "unbounded", sol.message
        return
    allowed = {"optimal"}
    if problem.startswith("hinf") or (backend, problem) in INACCURATE_OK:
        allowed.add("inaccurate")  # published with few digits; IPMs stop near the optimum
    assert sol.status in allowed, f"{sol.status} ({sol.native_status}): {sol.message}"
    gap = abs(sol.objective - float(published))
    assert gap <= _tolerance(backend, problem, published), (
        f"{backend} {problem}: {sol.objective!r} vs published {published} (gap {gap:.3g})"
    )


def _never_a_false_claim(prob, sol, backend: str, problem: str, published: str) -> None:
    """The contract of a :data:`MACHINE_DEPENDENT` case (its docstring there)."""
    from lmic.certify import certify

    assert sol.status in ("optimal", "inaccurate", "error"), f"{sol.status}: {sol.message}"
    value, tol = float(published), _tolerance(backend, problem, published)
    if sol.status == "optimal":
        assert abs(sol.objective - value) <= tol, (sol.objective, published)
    if sol.x is not None and certify(prob, sol).verdict == "certified":
        assert prob.objective.sense == "min" and sol.objective >= value - tol, (sol.objective, published)
