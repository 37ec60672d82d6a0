"""The dual repair's shift ladder jumps to the shift a failed attempt's PSD deficit calls for.

``min lambda`` s.t. ``lambda I - A >= 0``: the optimum is ``lambda_max(A)`` (numpy's eigenvalues,
not lmic) and the optimal dual ``Z = v v'`` has rank 1, on the boundary of the cone, as an
interior-point solver that stops at the boundary (Clarabel) returns it. The smallest shift
fails by a deficit of the repaired ``Z``; the ladder used to probe the largest shift and scan
up from the smallest (6 repairs here, 8 to 10 on ``uncertain_dt.thm1``); it now tries the
shift that covers the deficit (2 repairs), and the bound it proves is as tight.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

import lmic.certify.enclosure_dual as ed
from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
from lmic.ir.svec import tril_rows_cols


def _largest_eigenvalue_problem(A: np.ndarray) -> Problem:
    d = A.shape[0]
    ri, ci = tril_rows_cols(d)
    coeffs = sp.csc_matrix(np.column_stack([-A[ri, ci], (ri == ci).astype(float)]))
    return Problem(
        [Variable("lam", "scalar", (1, 1))],
        [LMI("lam I - A >= 0", d, coeffs, strict=False)],
        LinearConstraints.empty(1),
        Objective("min", [0.0, 1.0]),
    )


def _bound(problem: Problem, Z: np.ndarray, monkeypatch, jump: bool) -> tuple[dict, list[float]]:
    shifts: list[float] = []
    prepare = ed._prepare

    def counted(*args, **kwargs):
        shifts.append(args[6])
        return prepare(*args, **kwargs)

    with monkeypatch.context() as m:
        m.setattr(ed, "_prepare", counted)
        if not jump:
            m.setattr(ed, "needed_shift", lambda res, top: None)
        out = ed.dual_bound(problem, {"lmis": [Z], "linear": []})
    return out, shifts


@pytest.mark.parametrize("noise", [0.0, 1e-10])
def test_a_boundary_dual_is_proved_in_two_repairs_and_as_tightly(monkeypatch, noise):
    rng = np.random.default_rng(0)
    A = rng.normal(size=(30, 30))
    A = A + A.T
    w, V = np.linalg.eigh(A)
    truth = float(w[-1])
    v = V[:, -1]
    Z = np.outer(v, v) + noise * (V[:, :-1] @ np.diag(rng.uniform(-1, 1, 29)) @ V[:, :-1].T)
    p = _largest_eigenvalue_problem(A)

    jumped, shifts = _bound(p, Z, monkeypatch, jump=True)
    scanned, shifts_scan = _bound(p, Z, monkeypatch, jump=False)
    assert shifts[0] == ed.SHIFTS[0] and len(shifts) == 2 and shifts[1] > ed.SHIFTS[0]
    assert len(shifts_scan) >= 4  # the probe, the scan up to the proving shift, the refinement
    for out in (jumped, scanned):
        assert out["proven"] and out["route"] == "solver dual"
        # a lower end: below the true optimum (numpy's eigenvalue, accurate to ~1e-14 here)
        assert out["lower"] <= truth + 1e-13
        assert out["lower"] >= truth - 1e-6 * abs(truth)
    # the jump loses at most REFINE_GAIN (relative) against the full scan's refined bound
    assert jumped["lower"] >= scanned["lower"] - ed.REFINE_GAIN * max(1.0, abs(truth))


def test_needed_shift_reads_the_deficit_of_a_failed_attempt():
    top = 6.0
    assert ed.needed_shift({"proven": False, "psd_deficit": 1.2e-11}, top) == ed.SHIFTS.index(1e-11)
    assert ed.needed_shift({"proven": False, "psd_deficit": 1e-18}, top) is None  # the smallest covers it
    assert ed.needed_shift({"proven": False, "psd_deficit": 1e-3}, top) is None  # beyond the ladder
    assert ed.needed_shift({"proven": False, "reason": "singular"}, top) is None  # not a PSD failure


def _far_dual() -> tuple[Problem, float, tuple]:
    """A random symmetric ``A`` (30 x 30, seed 0) and ``Z = 1000 v v' + 1e-3 (5 more
    directions)``: far from ``tr Z = 1``, so the damped repair takes more than
    :data:`CHECK_AT`'s first steps. Returns the problem, ``lambda_max(A)`` and the repair's
    inputs ``(J, ranges, q, mats0, y0, top)``."""
    rng = np.random.default_rng(0)
    A = rng.normal(size=(30, 30))
    A = A + A.T
    w, V = np.linalg.eigh(A)
    Z = 1000.0 * np.outer(V[:, -1], V[:, -1]) + 1e-3 * V[:, :5] @ V[:, :5].T
    p = _largest_eigenvalue_problem(A)
    mats0, y0 = ed._parse(p, {"lmis": [Z], "linear": []})
    _, q = ed._target(p)
    J, ranges = ed._jacobian(p)
    return p, float(w[-1]), (J, ranges, q, mats0, y0, ed._scale(p, mats0, y0))


def test_the_repair_stops_at_the_first_check_where_the_proof_holds():
    from lmic.certify.enclosure_float import _prove_float
    from lmic.certify.enclosure_repair import CHECK_AT, _prepare

    p, truth, (J, ranges, q, mats0, y0, top) = _far_dual()
    calls: list[bool] = []

    def prove(m, y, active):
        res = _prove_float(p, J, ranges, q, m, y, active)
        calls.append(bool(res["proven"]))
        return res

    early = _prove_float(p, J, ranges, q, *_prepare(p, J, ranges, q, mats0, y0, 1e-12, top, prove=prove))
    full = _prove_float(p, J, ranges, q, *_prepare(p, J, ranges, q, mats0, y0, 1e-12, top))
    # asked at CHECK_AT's steps until the proof held, then stopped
    assert calls and calls[-1] is True and not any(calls[:-1]) and len(calls) < len(CHECK_AT)
    assert early["proven"] and full["proven"]
    assert early["lower"] <= truth and full["lower"] <= truth  # lower ends (numpy's lambda_max)
    assert abs(early["lower"] - full["lower"]) <= 1e-9 * abs(truth)


def test_a_hopeless_shift_stops_the_repair_at_the_second_check():
    """A proof that fails by a PSD deficit above HOPELESS times the shift ends the steps."""
    from lmic.certify.enclosure_repair import HOPELESS, _prepare

    p, _, (J, ranges, q, mats0, y0, top) = _far_dual()
    calls: list[int] = []

    def failing(m, y, active):
        calls.append(1)
        return {"proven": False, "psd_deficit": 2 * HOPELESS * 1e-12 * top}

    stopped, _, _ = _prepare(p, J, ranges, q, mats0, y0, 1e-12, top, prove=failing)
    assert len(calls) == 2  # the first check goes on, the second stops

    def small(m, y, active):
        return {"proven": False, "psd_deficit": 0.5 * HOPELESS * 1e-12 * top}

    # a deficit the shift may still cover: the steps go on to the end, as without checks
    went_on, _, _ = _prepare(p, J, ranges, q, mats0, y0, 1e-12, top, prove=small)
    plain, _, _ = _prepare(p, J, ranges, q, mats0, y0, 1e-12, top)
    assert np.array_equal(went_on[0], plain[0]) and not np.array_equal(stopped[0], plain[0])
