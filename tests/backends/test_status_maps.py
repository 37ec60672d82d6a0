"""Every backend's native-status table: complete against the statuses the solver library itself
defines, inexact claims ``inaccurate``, only the solver's own "solved" word a success, anything
unlisted ``error``.

The native statuses are read from the installed libraries (not from lmic): Clarabel's
``SolverStatus`` enum, CVXPY's ``settings`` constants, the status strings in CVXOPT's
``coneprog.conelp`` source, sdpa-python's phase table, SCS's status codes as CVXPY's SCS
interface lists them, and PICOS's ``PS_*`` / ``SS_*`` constants.
"""

from __future__ import annotations

import inspect
import re

import pytest

from lmic.backends.registry import get_backend
from lmic.solution import STATUSES

BACKENDS = ["clarabel", "scs", "cvxopt", "sdpa", "cvxpy", "picos"]

#: the one native word per solver that means "solved to tolerance" (from each solver's docs)
SOLVED = {
    "clarabel": {"Solved"},
    "scs": {"solved"},
    "cvxopt": {"optimal"},
    "sdpa": {"pdOPT"},
    "cvxpy": {"optimal"},
    "picos": {"feasible/optimal", "unknown/optimal"},
}
#: lmic's own words of success, not the solver's: SCS paused at an iterate that passed the
#: original problem's point check (``SolveOptions.accept``, lmic.backends.scs._solve_checked)
LMIC_SOLVED = {"scs": {"point_verified"}}


def _clarabel() -> set[str]:
    import clarabel

    return {name for name in dir(clarabel.SolverStatus) if not name.startswith("_")}


def _cvxpy() -> set[str]:
    import cvxpy.settings as s

    return set(s.SOLUTION_PRESENT) | set(s.INF_OR_UNB) | set(s.ERROR)


def _cvxopt() -> set[str]:
    import cvxopt.coneprog

    return set(re.findall(r"'status': '([a-z ]+)'", inspect.getsource(cvxopt.coneprog.conelp)))


def _sdpa() -> set[str]:
    import sdpap.sdpap

    source = inspect.getsource(sdpap.sdpap)
    table = source[source.index("GET_PRIMAL_STATUS_FROM_DUAL = {") :]
    table = table[: table.index("}")]
    return set(re.findall(r'"(\w+)":', table))


def _scs() -> set[str]:
    from cvxpy.reductions.solvers.conic_solvers.scs_conif import SCS

    from lmic.backends.scs import _STATUS_NAMES

    codes = set(SCS.STATUS_MAP)
    assert codes <= set(_STATUS_NAMES), f"SCS codes lmic does not name: {codes - set(_STATUS_NAMES)}"
    return {_STATUS_NAMES[c] for c in codes}


def _picos() -> set[str]:
    # the (problem, primal) pairs PICOS's CVXOPT interface produces (solver_cvxopt.py), plus the
    # solver-independent ones every interface may report for a finished solve
    import picos.solvers.solver_cvxopt as sc

    source = inspect.getsource(sc)
    pairs = re.findall(r"primalStatus\s*=\s*(SS_\w+).*?problemStatus\s*=\s*(PS_\w+)", source, re.S)
    import picos.modeling.solution as sol

    return {f"{getattr(sol, ps)}/{getattr(sol, ss)}" for ss, ps in pairs}


NATIVE = {"clarabel": _clarabel, "scs": _scs, "cvxopt": _cvxopt, "sdpa": _sdpa, "cvxpy": _cvxpy, "picos": _picos}


@pytest.mark.parametrize("name", BACKENDS)
def test_every_native_status_of_the_library_is_in_the_table(name):
    be = get_backend(name)
    native = NATIVE[name]()
    assert native, f"no native statuses read for {name}"
    missing = native - set(be.STATUS_MAP)
    assert not missing, f"{name}: native statuses with no entry (they would be 'error'): {missing}"


@pytest.mark.parametrize("name", BACKENDS)
def test_table_follows_the_rules(name):
    be = get_backend(name)
    for native, status in be.STATUS_MAP.items():
        assert be.map_status(native) == status
        assert status in STATUSES and status != "feasible", (native, status)
        inexact = "almost" in native.lower() or "inaccurate" in native.lower()
        if inexact:
            assert status == "inaccurate", f"{name}: inexact '{native}' maps to {status}"
        if status == "optimal":
            assert native in SOLVED[name] | LMIC_SOLVED.get(name, set()), f"{name}: '{native}' claims success"
    for solved in SOLVED[name]:
        assert be.map_status(solved) == "optimal"


@pytest.mark.parametrize("name", BACKENDS)
@pytest.mark.parametrize("native", ["SOMETHING_NEW", "", "Solved ", "OPTIMAL", "solved/optimal"])
def test_an_unlisted_status_is_an_error(name, native):
    assert get_backend(name).map_status(native) == "error"


def test_clarabel_almost_primal_infeasible_is_not_an_infeasibility():
    be = get_backend("clarabel")
    assert be.map_status("AlmostPrimalInfeasible") == "inaccurate"
    assert be.map_status("AlmostDualInfeasible") == "inaccurate"
    assert be.map_status("PrimalInfeasible") == "infeasible"
