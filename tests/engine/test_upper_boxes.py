"""The primal end without a dual end (lmic.upper_end.upper_from_boxes, the route's last resort in
lmic.routes / lmic.route_upper) and the exposing direction rounded first
(lmic.certify.enclosure_facial_exact._direction_step).

SDPLIB hinf10 and hinf13 (not shipped) ended with no end at all: the solvers stop at ``|x| ~ 1e20``
far below the optimum, no point of theirs holds and the dual has no interior. Every point here is
checked exactly by an independent rational computation (``sdpa_exact``: the shipped SDPA file
read on its own) and by the certifier.
"""

from __future__ import annotations

import sys
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

sys.path.insert(0, str(Path(__file__).parent))
from sdpa_exact import check_point, positive_definite  # noqa: E402

import lmic.api  # noqa: E402
import lmic.route_upper  # noqa: E402
import lmic.routes  # noqa: E402
from lmic.certify import certify  # noqa: E402
from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable  # noqa: E402
from lmic.solution import Solution  # noqa: E402
from lmic.upper_end import upper_from_boxes  # noqa: E402

SDPLIB = Path("/work/shared/sdplib")
if not SDPLIB.is_dir():
    SDPLIB = Path(__file__).parents[3] / "shared" / "sdplib"


def _infimum_at_infinity(R: np.ndarray) -> Problem:
    """``inf t`` s.t. ``R^T [[t, 1], [1, s]] R >= 0``: infimum 0 (``t s >= 1``), not attained."""
    mats = [np.array([[0.0, 1.0], [1.0, 0.0]]), np.diag([1.0, 0.0]), np.diag([0.0, 1.0])]
    C = sp.csc_matrix(np.column_stack([(R.T @ M @ R)[[0, 1, 1], [0, 0, 1]] for M in mats]))
    return Problem(
        [Variable("t", "scalar", (1, 1)), Variable("s", "scalar", (1, 1), offset=1)],
        [LMI("M >= 0", 2, C, strict=False)],
        LinearConstraints.empty(2),
        Objective("min", [0.0, 1.0, 0.0]),
    )


def test_upper_from_boxes_approaches_an_infimum_at_infinity() -> None:
    p = _infimum_at_infinity(np.eye(2))
    r = upper_from_boxes(p, "clarabel", alternatives=("cvxopt",))
    assert r["proven"], r["reason"]
    t, s = (Fraction(float(v)) for v in r["x"])
    # exactly inside: [[t, 1], [1, s]] positive definite, and the end is at least the objective
    assert positive_definite([[t, Fraction(1)], [Fraction(1), s]])
    assert Fraction(r["value"]) >= t > 0
    assert r["value"] <= 1e-3  # the infimum is 0: the boxes grew to |s| >= 1e4
    assert len(r["boxes"]) >= 3 and r["boxes"][-1]["radius"] >= 1e4
    x = np.asarray(r["x"], dtype=float)
    cert = certify(p, Solution(status="optimal", x=x, objective=p.objective.value(x)))
    assert cert.verdict == "certified", cert.reason


def test_upper_from_boxes_shaped_like_a_far_solver_point() -> None:
    p = _infimum_at_infinity(np.eye(2))
    # the solver's point went far out along s (t s ~ 1): the boxes shaped like it come first
    r = upper_from_boxes(p, "clarabel", x_hint=np.array([1e-7, 1e7]), alternatives=("cvxopt",))
    assert r["proven"], r["reason"]
    shaped = [b for b in r["boxes"] if b["shaped"]]
    assert shaped and r["boxes"][0]["shaped"] and any(b["proven"] for b in shaped)
    t, s = (Fraction(float(v)) for v in r["x"])
    assert positive_definite([[t, Fraction(1)], [Fraction(1), s]])
    assert Fraction(r["value"]) >= t > 0 and r["value"] <= 1e-3


def _without_primal_end(enclosure_of):  # the route's enclosures lose their primal end
    def patched(*args, **kwargs):
        enc, t = enclosure_of(*args, **kwargs)
        if enc is not None:
            enc = dict(enc, upper=None, gap=None, rel_gap=None, primal="dropped by the test")
        return enc, t

    return patched


def test_route_last_resort_boxes_on_hinf1(monkeypatch: pytest.MonkeyPatch) -> None:
    path = SDPLIB / "hinf1.dat-s"
    if not path.is_file():
        pytest.skip("the shipped SDPLIB files are not here")
    # the solver's points give no primal end and no point is restored near them (hinf10's case)
    monkeypatch.setattr(lmic.routes, "enclosure_of", _without_primal_end(lmic.routes.enclosure_of))
    monkeypatch.setattr(
        lmic.route_upper, "restored_end", lambda *a, **k: {"proven": False, "x": None, "value": None, "reason": "off"}
    )
    r = lmic.api.solve(str(path), backoff=0)
    enc = r.enclosure
    assert enc["primal"] == "restored point" and enc["upper"] is not None, enc["reason"]
    boxed = [st["upper_boxed"] for st in r.route["steps"] if "upper_boxed" in st]
    assert len(boxed) == 1 and boxed[0]["proven"], r.route["steps"]
    # independent exact check of the recorded point against the SDPA file
    ok, value = check_point(path, enc["restored_x"])
    assert ok
    assert Fraction(enc["upper"]) >= value
    # near the optimum: within 1e-3 of an interior-point solve's objective (not trusted, a reference)
    ref = lmic.api.solve_problem(r.problem, "cvxopt")
    assert ref.objective is not None and enc["upper"] <= ref.objective + 1e-3 * abs(ref.objective)
    x = np.asarray(enc["restored_x"], dtype=float)
    cert = certify(r.problem, Solution(status="optimal", x=x, objective=r.problem.objective.value(x)))
    assert cert.verdict == "certified", cert.reason


def test_direction_step_exposes_a_face_with_large_denominators() -> None:
    from lmic.certify import enclosure_facial_exact as fe

    a, b = 1234567, 7654321
    p = _infimum_at_infinity(np.array([[a, -b], [b, a]], dtype=float))
    d_float = np.array([3e-13, 1.0])  # the solver's exposing direction (s grows, t fixed)
    st = fe.exact_step(p, d_float)
    assert st["ok"], st["reason"]
    assert fe.verify_step(p, st)["ok"]
    # independently: d moves s only, and W(d) = R^T diag(0, 1) R kills the recorded V exactly
    d = [int(v) for v in st["d"]]
    assert d[0] == 0 and d[1] != 0
    V = [[int(v) for v in row] for row in st["V"][0]]
    assert any(any(row) for row in V)
    W = [[b * b, a * b], [a * b, a * a]]  # (R^T e2)(R^T e2)^T with R^T e2 = (b, a)
    assert all(sum(W[i][k] * V[k][c] for k in range(2)) == 0 for i in range(2) for c in range(len(V[0])))
    # the null-space rounding alone (denominators <= 1e6) cannot find it
    assert b > fe.DENOMINATORS[-1]


def test_sdpa_ending_the_process_is_an_error_solution(tmp_path: Path) -> None:
    """sdpa-python ends the whole process (exit code 0, no output) on shipped hinf1 boxed at
    ``|x_k| <= 1e4``; every SDPA solve runs in a forked child, so ``lmic solve`` reports it."""
    import json
    import os
    import subprocess

    from lmic.ir.io import load_problem, save_problem
    from lmic.upper_end import boxed_problem

    path = SDPLIB / "hinf1.dat-s"
    if not path.is_file():
        pytest.skip("the shipped SDPLIB files are not here")
    boxed = tmp_path / "hinf1_boxed.dat-s"
    save_problem(boxed_problem(load_problem(path), 1e4), boxed)
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
    cmd = [sys.executable, "-m", "lmic.cli", "solve", str(boxed), "--backend", "sdpa", "--json"]
    run = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=600)
    assert run.stdout.strip(), f"no output (exit code {run.returncode}): the process was ended"
    out = json.loads(run.stdout)
    # the dead solve is an error (sdpa-python 0.2.3 ends the process on this input): undecided, exit 1
    assert "solver process died" in out["message"], out["message"]
    assert out["verdict"] == "undecided" and run.returncode == out["exit_code"] == 1
