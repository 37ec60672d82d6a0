"""Cross-checking one problem on several backends."""

from __future__ import annotations

from lmic.studies.crosscheck import crosscheck, status_class
from lmic.testing.conformance import CASES


def test_agreeing_backends():
    rep = crosscheck(CASES["max_sense"].build(), backends=["clarabel", "cvxopt", "sdpa", "scs"])
    assert rep.agree and rep.exit_code() == 0
    assert rep.max_rel_objective_gap < 1e-3
    assert [r["verdict"] for r in rep.results] == ["certified"] * 4


def test_infeasible_agreement_exits_0():
    rep = crosscheck(CASES["infeasible"].build(), backends=["clarabel", "cvxopt"])
    assert rep.agree and rep.exit_code() == 0 and rep.failures == 0
    assert {r["decision"] for r in rep.results} == {"infeasible-certified"}
    assert {r["verdict"] for r in rep.results} == {"infeasible-certified"}


def test_a_failing_backend_is_a_failure_not_a_disagreement():
    rep = crosscheck(CASES["bounded_real"].build(), backends=["clarabel", "nope"])
    # a backend that cannot run is a failure, listed and counted, not a disagreement
    assert rep.agree and rep.exit_code() == 0 and rep.failures == 1 and rep.decisions == 1
    assert rep.results[1]["status"] == "error" and "unknown backend" in rep.results[1]["message"]


def test_status_classes():
    assert status_class("optimal") == status_class("feasible") != status_class("infeasible")
    assert set(crosscheck(CASES["max_sense"].build(), backends=["clarabel"]).to_dict()) >= {
        "target",
        "results",
        "agree",
        "max_rel_objective_gap",
    }


def test_progress_callback_and_strict_columns():
    calls = []
    rep = crosscheck(
        CASES["lyapunov_stable"].build(),
        backends=["clarabel", "nope"],
        progress=lambda done, total, name, row: calls.append(
            (done, total, name, None if row is None else row["status"])
        ),
    )
    assert calls == [
        (0, 2, "clarabel", None),
        (1, 2, "clarabel", "feasible"),
        (1, 2, "nope", None),
        (2, 2, "nope", "error"),
    ]
    ok, missing = rep.results
    assert ok["strategy"] == "max-margin" and ok["margin"] > 0 and ok["min_margin"] > 0
    assert missing["strategy"] is None and missing["margin"] is None


def test_crosscheck_accepts_a_loaded_system_object():
    from pathlib import Path

    from lmic.studies.crosscheck import crosscheck
    from lmic.system import load_system

    path = Path(__file__).resolve().parents[2] / "examples" / "qib.thm1.flexible-joint.yaml"
    report = crosscheck("qib.thm1", load_system(path), backends=["clarabel", "cvxopt"])
    assert report.agree
    assert report.target.endswith("qib.thm1.flexible-joint.yaml")


def test_each_row_has_its_backends_proven_enclosure_and_they_intersect():
    """An optimisation problem: every certified row carries its backend's proven ``[lower,
    upper]`` and its whole time; the report's enclosure is their intersection and contains
    the H-infinity norm (Hamiltonian bisection, no LMI). No backed-off second solve runs."""
    import numpy as np
    from certify_helpers import hinf_norm

    rng = np.random.default_rng(3)
    A = rng.standard_normal((4, 4))
    A -= (max(np.linalg.eigvals(A).real) + 0.5) * np.eye(4)
    B, C = rng.standard_normal((4, 2)), rng.standard_normal((2, 4))
    system = {"lmic": 1, "data": {"A": A.tolist(), "B": B.tolist(), "C": C.tolist()}}
    r = crosscheck("tutorial.bounded_real", system, backends=["clarabel", "cvxopt"])
    assert r.agree and not r.conflicts
    lo, hi = hinf_norm(A, B, C)
    for row in r.results:
        assert row["decision"] == "certified" and row["lower"] <= hi and lo <= row["upper"]
        assert row["rel_gap"] <= 1e-6 and row["time_s"] >= row["solve_s"] > 0
    low, high = r.enclosure
    assert low == max(row["lower"] for row in r.results) and high == min(row["upper"] for row in r.results)
    assert low <= hi and lo <= high
    assert r.to_dict()["enclosure"] == [low, high]
    assert all(run.backoff is None for run in r.runs)


def test_disjoint_enclosures_are_a_conflict_whatever_rtol():
    """Two proven enclosures that do not intersect mean a wrong proof: a conflict even when the
    certified objectives agree within rtol; one rounding's worth apart (ENCLOSURE_SLACK) is not."""
    from lmic.studies.crosscheck import ENCLOSURE_SLACK, conflicts

    def row(name, lower, upper):
        return {
            "backend": name,
            "decision": "certified",
            "objective": upper,
            "x_norm": 1.0,
            "lower": lower,
            "upper": upper,
        }

    found, _ = conflicts([row("a", 1.0, 1.0001), row("b", 1.0002, 1.0003)], "min", 1e-2)
    assert found == ["b proves the optimum >= 1.0002 but a proves it <= 1.0001"]
    assert (
        conflicts([row("a", 1.0, 1.0001), row("b", 1.0001 * (1 + ENCLOSURE_SLACK / 2), 1.0003)], "min", 1e-2)[0] == []
    )
    # a backend whose own ends contradict each other
    assert conflicts([row("a", 2.0, 1.0)], "min", 1e-2)[0] == ["a proves the optimum >= 2 but a proves it <= 1"]
