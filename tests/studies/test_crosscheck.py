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
