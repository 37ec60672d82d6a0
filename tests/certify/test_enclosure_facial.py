"""Facial reduction for the dual end (lmic.certify.enclosure_facial), the exactly feasible point
of a feasible set without interior (lmic.certify.snap), and SDPLIB-family instances with known
optima (benchmarks/sdplib_families.py) through the solve, the certifier and the audit."""

from __future__ import annotations

import importlib.util
import json
import math
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

import lmic.api
from lmic.certify import audit_certificate, certify, write_certificate
from lmic.certify.enclosure_facial import exposing_problem, verify_facial
from lmic.certify.enclosure_facial_exact import exact_step, fix_lineality, lineality, reduce_problem, verify_step
from lmic.errors import CertificateError
from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
from lmic.ir.svec import tril_vec
from lmic.solution import Solution

ROOT = Path(__file__).resolve().parents[2]


def _families():
    spec = importlib.util.spec_from_file_location("lmic_bench_families", ROOT / "benchmarks" / "sdplib_families.py")
    mod = importlib.util.module_from_spec(spec)
    assert spec.loader is not None
    spec.loader.exec_module(mod)
    return mod


def _lmi(name: str, mats: list[np.ndarray], strict: bool = False) -> LMI:
    """An LMI ``F_0 + sum_k x_k F_k`` from dense symmetric ``[F_0, F_1, ...]``."""
    d = mats[0].shape[0]
    return LMI(name, d, sp.csc_matrix(np.column_stack([tril_vec(M) for M in mats])), strict=strict)


def _rotated(T: np.ndarray) -> Problem:
    """``min x1`` s.t. ``T^T diag(x1 - 1, x2, x1 + x3) T >= 0``, ``x3 >= 0`` free of cost: the
    optimum is 1 (``x1 >= 1`` by the first diagonal entry, attained at ``(1, 0, 0)``), and the
    dual has no strictly feasible point (``x2`` has cost 0 and a PSD coefficient: every dual
    ``Z`` has ``<T^T E_22 T, Z> = 0``). ``T`` integer and unimodular: a non-coordinate face."""

    def congr(D: np.ndarray) -> np.ndarray:
        return T.T @ D @ T

    F0 = congr(np.diag([-1.0, 0.0, 0.0]))
    F1 = congr(np.diag([1.0, 0.0, 1.0]))
    F2 = congr(np.diag([0.0, 1.0, 0.0]))
    F3 = congr(np.diag([0.0, 0.0, 1.0]))
    return Problem(
        [Variable("x", "full", (3, 1))],
        [_lmi("T^T D(x) T >= 0", [F0, F1, F2, F3])],
        LinearConstraints.empty(3),
        Objective("min", [0.0, 1.0, 0.0, 0.0]),
    )


T1 = np.array([[1.0, 1.0, 0.0], [0.0, 1.0, 2.0], [0.0, 0.0, 1.0]])


def test_exposing_certificate_is_verified_exactly_and_tampering_is_rejected():
    p = _rotated(T1)
    e = exposing_problem(p)
    assert e.n == p.n and e.linear.kinds == ["eq", "eq"]
    # the exposing direction d = e2 (q . d = 0, W = T^T E_22 T >= 0), given with float noise
    st = exact_step(p, np.array([1e-11, 1.0, -2e-12]))
    assert st["ok"], st["reason"]
    assert [int(v) for v in st["d"]] == [0, 1, 0]
    V = np.array([[int(v) for v in row] for row in st["V"][0]], dtype=float)
    W = T1.T @ np.diag([0.0, 1.0, 0.0]) @ T1
    assert V.shape == (3, 2) and np.allclose(W @ V, 0.0) and np.linalg.matrix_rank(V) == 2
    assert verify_step(p, st)["ok"]
    # tampered: a direction with cost, a V that is not in the null space, a rank-deficient V
    assert not verify_step(p, dict(st, d=["1", "1", "0"]))["ok"]
    bad_v = [[row[0], row[0]] for row in st["V"][0]]
    assert "rank deficient" in verify_step(p, dict(st, V=[bad_v]))["reason"]
    shifted = [[str(int(row[0]) + (i == 1)), row[1]] for i, row in enumerate(st["V"][0])]
    assert "W V != 0" in verify_step(p, dict(st, V=[shifted]))["reason"]
    # an indefinite "exposing" matrix: d = (0, -1, 0) has W = -T^T E_22 T
    assert not verify_step(p, dict(st, d=["0", "-1", "0"]))["ok"]


def test_lineality_is_checked_exactly():
    p = _rotated(T1)
    st = exact_step(p, np.array([0.0, 1.0, 0.0]))
    from lmic.certify.enclosure_facial_exact import reduce_v

    red = reduce_v(p, st)
    basis, fix = lineality(red)
    # after the reduction x2 changes nothing: the lineality space is spanned by e2
    assert len(basis) == 1 and [abs(int(v)) for v in basis[0]] == [0, 1, 0] and fix == [1]
    with pytest.raises(CertificateError):
        fix_lineality(red, [["1", "1", "0"]], [1])
    with pytest.raises(CertificateError):
        fix_lineality(red, basis, [0])  # x1 does not complement the lineality space
    full = reduce_problem(p, dict(st, lineality=basis, fix=fix))
    assert full.linear.kinds == ["eq"] and full.lmis[0].dim == 2


@pytest.mark.parametrize("T", [T1, np.array([[1.0, 0.0, 0.0], [-1.0, 1.0, 0.0], [3.0, 1.0, 1.0]])])
def test_problem_without_dual_interior_gets_a_lower_end_and_the_audit_replays_it(tmp_path, T):
    p = _rotated(T)
    r = lmic.api.solve(p, backend="clarabel")
    assert r.verdict == "certified"
    e = r.enclosure
    assert e["dual"]["route"] == "facial", e["dual"].get("reason")
    assert e["lower"] <= 1.0 <= e["upper"] and e["rel_gap"] < 1e-6
    # soundness does not rest on the solver: the exact replay of the record gives the bound
    v = verify_facial(p, e["dual"])
    assert v["ok"] and v["lower"] >= e["lower"]
    path = tmp_path / "face.json"
    write_certificate(path, r.problem, r.solution, r.certificate, enclosure=r.enclosure)
    assert audit_certificate(path).ok
    doc = json.loads(path.read_text())
    # a tampered exposing direction: rejected by the exact replay
    doc["enclosure"]["dual"]["dual"]["steps"][0]["d"] = ["1", "1", "0"]
    path.write_text(json.dumps(doc))
    bad = audit_certificate(path)
    assert not bad.ok and bad.field == "enclosure.dual", bad.message
    # a raised lower end: rejected
    path2 = tmp_path / "face2.json"
    write_certificate(path2, r.problem, r.solution, r.certificate, enclosure=r.enclosure)
    doc = json.loads(path2.read_text())
    doc["enclosure"]["lower"] = doc["enclosure"]["dual"]["lower"] = 1.0 + 1e-6
    path2.write_text(json.dumps(doc))
    assert not audit_certificate(path2).ok


def _zero_problem(strict: bool) -> Problem:
    F1 = np.array([[0.0, 1.0], [1.0, 0.0]])
    return Problem(
        [Variable("x", "scalar", (1, 1))],
        [_lmi("x [[0, 1], [1, 0]]", [np.zeros((2, 2)), F1], strict=strict)],
        LinearConstraints.empty(1),
        Objective("min", [0.0, 1.0]),
    )


def test_single_point_feasible_set_is_certified_at_the_exact_point():
    p = _zero_problem(strict=False)
    c = certify(p, Solution("optimal", x=np.array([4.8e-25]), objective=4.8e-25))
    assert c.verdict == "certified" and c.x == [0.0]
    assert c.exact is not None and c.exact["proven"] and "moved to x_q" in c.reason
    # far from the point: nothing to snap, the violation stands
    assert certify(p, Solution("optimal", x=np.array([0.3]), objective=0.3)).verdict == "rejected"


def test_strict_lmi_with_margin_zero_is_never_certified():
    p = _zero_problem(strict=True)
    for x in (4.8e-25, 0.0):
        assert certify(p, Solution("optimal", x=np.array([x]), objective=x)).verdict == "rejected"
        assert certify(p, Solution("optimal", x=np.array([x]), objective=x), exact=True).verdict == "rejected"


def test_single_point_sdpa_file_is_certified_and_audited(tmp_path):
    f = tmp_path / "zero.dat-s"
    f.write_text("1\n1\n2\n1.0\n1 1 1 2 1.0\n")
    r = lmic.api.solve(str(f), backend="clarabel")
    assert r.verdict == "certified" and r.certificate.x == [0.0]
    path = tmp_path / "zero.json"
    write_certificate(path, r.problem, r.solution, r.certificate, enclosure=r.enclosure)
    assert audit_certificate(path).ok


@pytest.mark.parametrize(
    "name",
    ["theta_C5", "theta_C6", "theta_petersen", "mcp_K4", "mcp_C5", "lyap_3"],
)
def test_family_instances_enclose_the_known_optimum(tmp_path, name):
    fam = _families()
    ((_, prob, ref, src),) = fam.instances({name})
    # the closed forms against a second computation where one is cheap: the eigenvalue bound
    if name.startswith("mcp_C"):
        L = fam.laplacian(fam.cycle_graph(5))
        assert math.isclose(ref, 5 / 4 * np.linalg.eigvalsh(L)[-1], rel_tol=1e-12)
    f = tmp_path / f"{name}.dat-s"
    f.write_text(fam.sdpa_text(*prob))
    r = lmic.api.solve(str(f), backend="clarabel")
    assert r.verdict == "certified"
    e = r.enclosure
    assert fam.inside(e, ref, src), (e["lower"], ref, e["upper"], e.get("reason"))
    assert e["rel_gap"] < 1e-6


def test_family_face_instance_against_an_independent_solve(tmp_path):
    cp = pytest.importorskip("cvxpy")
    del cp
    fam = _families()
    ((_, prob, ref, src),) = fam.instances({"face_0"})
    f = tmp_path / "face_0.dat-s"
    f.write_text(fam.sdpa_text(*prob))
    r = lmic.api.solve(str(f), backend="clarabel")
    assert r.verdict == "certified"
    e = r.enclosure
    assert e["dual"]["route"] == "facial"
    assert fam.inside(e, ref, src), (e["lower"], ref, e["upper"])


def test_a_dual_without_interior_goes_facial_before_any_re_solve(tmp_path, monkeypatch):
    """SDPLIB's qap layout (4 facilities): the dual has no strictly feasible point (the
    gangster constraints), the face is not exposed by one variable (no ``obvious_face``), and
    the shifted repairs of the solver's dual fail. The facial route is then the next step,
    before the perturbed and centring re-solves of ``dual_bound`` (which cannot prove there:
    6 perturbed and 3 centring solves, 8 of the 9 s of the enclosure on the 6-facility layout).
    Every solve of the enclosure is recorded: the exposing problem's comes first, and the
    bound encloses CVXPY + Clarabel's optimum (an independent solve of the dual form)."""
    import lmic.routes as routes
    from lmic.certify.enclosure_facial import obvious_face

    fam = _families()
    prob = fam.qap_problem(4, 4)
    ref = fam.cvxpy_value(prob)
    f = tmp_path / "qap_4.dat-s"
    f.write_text(fam.sdpa_text(*prob))
    seen: list[str] = []
    real = routes._solve_on

    def recording(backend, problem, options):
        meta = problem.meta or {}
        kind = "exposing" if "exposing_of" in meta else ("perturbed-or-centring" if problem.lmis else "other")
        seen.append(kind)
        return real(backend, problem, options)

    monkeypatch.setattr(routes, "_solve_on", recording)
    r = lmic.api.solve(str(f))
    assert obvious_face(r.problem) is None
    assert r.verdict == "certified"
    e = r.enclosure
    assert e["dual"]["route"] == "facial", e["dual"].get("reason")
    assert seen and seen[0] == "exposing", seen
    assert e["lower"] - 1e-6 * abs(ref) <= ref <= e["upper"] + 1e-6 * abs(ref), (e["lower"], ref, e["upper"])
    assert e["rel_gap"] < 1e-6
