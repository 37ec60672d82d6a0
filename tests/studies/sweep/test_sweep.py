"""lmic.studies.sweep: bisection on certified feasibility, grids, and the --maximize/--sweep options of lmic solve."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

import lmic.compile
from lmic.certify import certify
from lmic.cli import main
from lmic.compile import bind, plan_for
from lmic.errors import DataError
from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
from lmic.solution import Solution
from lmic.studies.sweep import decide, maximize, parse_grid, precondition, sweep
from lmic.system import load_system
from lmic.template import block, theorem

ROOT = Path(__file__).resolve().parents[3]
EX = ROOT / "examples"


@theorem(id="toy.decay", title="decay rate", citation="test")
def toy_decay(t):
    """``P > 0``, ``A^T P + P A + 2 a P < 0``: feasible iff ``a`` is below the decay rate of ``A``."""
    (n,) = t.dims("n")
    A = t.data("A", n, n)
    a = t.param("a", default=0.0, domain="real")
    P = t.symmetric("P", n)
    t.lmi("P > 0", block(P) > 0)
    t.lmi("decay", block(A.T * P + P * A + 2 * a * P) < 0)


TOY = {"lmic": 1, "data": {"A": [[-1.0, 2.0], [0.0, -3.0]]}}  # decay rate 1


def _certified_at(theorem_id, system, param, value, x):
    """Independent check: re-bind at ``value`` and certify ``x`` (exactly if the float margins are tiny)."""
    sysobj = load_system(system)
    prob = bind(plan_for(theorem_id, sysobj.params), sysobj, {param: value})
    cert = certify(prob, Solution("feasible", x=x))
    if cert.verdict != "certified":
        cert = certify(prob, Solution("feasible", x=x), exact=True)
        assert cert.exact["proven"], cert.reason
        assert all(c["ok"] for c in cert.checks)
        return
    assert cert.verdict == "certified"


# -- grids --------------------------------------------------------------------------------------


def test_parse_grid_linear_log_and_errors():
    assert parse_grid("eps=0.5:1.5:3") == ("eps", [0.5, 1.0, 1.5])
    name, values = parse_grid("alpha=log:1e-3:1:4")
    assert name == "alpha" and np.allclose(values, [1e-3, 1e-2, 1e-1, 1.0])
    assert parse_grid("x=2:3:1") == ("x", [2.0])
    for bad in ("eps", "eps=1:2", "eps=a:b:3", "eps=1:2:0", "1x=1:2:3", "e=log:0:1:3", "e=log:-1:1:3", "e=1:inf:3"):
        with pytest.raises(DataError):
            parse_grid(bad)


def test_precondition_is_a_congruence_that_keeps_feasibility():
    lmi = LMI("F > 0", 2, sp.csc_matrix(np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 1e6]])))
    p = Problem(
        [Variable("a", "scalar", (1, 1)), Variable("b", "scalar", (1, 1), offset=1)],
        [lmi],
        LinearConstraints.empty(2),
        Objective("feasibility", [0, 0, 0]),
    )
    q, scales = precondition(p, np.array([2.0, 3.0]))
    for x in ([2.0, 3.0], [1.0, -1e-9], [5.0, 1e-3]):
        assert np.all(
            np.sign(np.linalg.eigvalsh(p.lmis[0].matrix(x))) == np.sign(np.linalg.eigvalsh(q.lmis[0].matrix(x)))
        )
    assert np.allclose(np.diag(q.lmis[0].matrix([2.0, 3.0])), 1.0)
    assert np.allclose(scales[0], [1 / np.sqrt(2.0), 1 / np.sqrt(3e6)])


def test_decide_feasible_and_infeasible_through_the_certifier():
    ok = Problem(
        [Variable("p", "scalar", (1, 1))],
        [LMI("p > 1", 1, sp.csc_matrix([[-1.0, 1.0]]))],
        LinearConstraints.empty(1),
        Objective("feasibility", [0, 0]),
    )
    r = decide(ok)
    assert (r.outcome, r.proof) == ("feasible", "certified") and r.x[0] > 1
    bad = Problem(
        [Variable("p", "scalar", (1, 1))],
        [LMI("p > 1", 1, sp.csc_matrix([[-1.0, 1.0]])), LMI("p < 0", 1, sp.csc_matrix([[0.0, -1.0]]))],
        LinearConstraints.empty(1),
        Objective("feasibility", [0, 0]),
    )
    r = decide(bad)
    assert r.outcome == "infeasible" and r.proof.startswith("infeasible-certified")


def test_sweep_toy_reports_every_point_and_the_best_margin():
    res = sweep(toy_decay, TOY, "a", [0.0, 0.5, 1.5, 2.0])
    assert [p.outcome for p in res.points] == ["feasible", "feasible", "infeasible", "infeasible"]
    assert all(p.verdict == "infeasible-certified" for p in res.points[2:])
    # feasibility ends after 0.5: the best point is the edge of the certified range, not the
    # largest margin (a = 0); a grid with certified points on both sides of a gap keeps the margin
    assert res.best is res.points[1] and res.best_rule == "edge of the certified range"
    assert res.points[0].rel_margin > res.points[1].rel_margin
    assert res.exit_code() == 0
    d = res.to_dict()
    assert d["mode"] == "sweep" and len(d["points"]) == 4 and d["best"]["value"] == 0.5
    assert d["best_rule"] == "edge of the certified range"
    mixed = sweep(toy_decay, TOY, "a", [0.0, 1.5, 0.5])
    assert mixed.points[0].outcome == mixed.points[2].outcome == "feasible" != mixed.points[1].outcome
    assert mixed.best_rule == "largest margin" and mixed.best is mixed.points[0]
    assert d["timings"]["bind_s_mean"] > 0


# -- bisection ----------------------------------------------------------------------------------


def test_maximize_toy_finds_the_decay_rate_and_rebinds_without_reanalysis(monkeypatch):
    plan_for(toy_decay)  # analysed once, outside the measurement
    analyses, binds = [], []
    real_analyse, real_bind = lmic.compile.analyse, lmic.compile.bind
    monkeypatch.setattr(lmic.compile, "analyse", lambda *a, **k: analyses.append(1) or real_analyse(*a, **k))
    monkeypatch.setattr(lmic.compile, "bind", lambda *a, **k: binds.append(1) or real_bind(*a, **k))
    res = maximize(toy_decay, TOY, "a", rtol=1e-4)
    # one bind per point, plus the three sample values of the affinity check (the enclosure
    # route) and the bracket's upper end for a stretch when it left the evaluator's cache
    assert analyses == []
    assert len(res.points) <= len(binds) <= len(res.points) + 3 + sum(p.stretched for p in res.points)
    assert res.converged and res.lower < 1.0 <= res.upper
    assert res.upper - res.lower <= 1e-4 * res.upper + 1e-12
    assert res.lower == pytest.approx(1.0, abs=2e-4)
    assert res.exit_code() == 0
    best = next(p for p in res.points if p.value == res.lower)
    _certified_at(toy_decay, TOY, "a", res.lower, best.x)


def test_maximize_with_a_bracket_and_an_infeasible_bracket():
    res = maximize(toy_decay, TOY, "a", lo=0.0, hi=4.0, rtol=1e-3)
    assert res.lower == pytest.approx(1.0, abs=2e-3) and res.points[0].value == 0.0
    none = maximize(toy_decay, {"lmic": 1, "data": {"A": [[1.0]]}}, "a", lo=0.5, hi=1.0)
    assert none.lower is None and none.exit_code() == 3 and "no certified point" in none.message
    above = maximize(toy_decay, TOY, "a", lo=0.0, hi=0.5)
    assert above.lower == 0.5 and "at or above" in above.message


def test_maximize_thesis_thm3_2_2_sup_gamma_0_9997():
    """Catalogue T11.4: sup gamma of (3.14) = 0.9997 (margin 1e-7), 0.9996 (1e-6); exactly certified here."""
    f = EX / "thesis.thm3_2_2.ex3_2_2.yaml"
    res = maximize("thesis.thm3_2_2", f, "gamma", rtol=1e-5)
    assert res.converged and res.lower == pytest.approx(0.9997, abs=1.5e-4)
    assert res.upper_kind != "none" and res.upper < 1.0
    # the example's gamma: infeasible in closed form (gamma = 3.33 > sigma_min(A|ker C) = 1,
    # tests/engine/test_engine.py), proven exactly on a rational face of the solver's ray
    assert res.points[0].value == 3.33 and res.points[0].outcome == "infeasible"
    best = next(p for p in res.points if p.value == res.lower)
    _certified_at("thesis.thm3_2_2", f, "gamma", res.lower, best.x)
    # a global proof of an upper end: an exact Farkas certificate (on a rational face of the ray).
    # It can only be true above the supremum (catalogue T11.4: 0.9997), hence above the certified
    # lower end; past the closed-form bound (gamma < sigma_min(A|ker C) = 1 is necessary,
    # tests/engine/test_engine.py) every value is infeasible, so a proof there is one we expect
    assert res.upper_proven is not None and res.lower < res.upper_proven
    assert res.upper_proven >= 0.9997 - 1.5e-4 and res.upper_proven < 3.33
    # the bisection's own (tighter) upper end rests on a bounded ray only: not a proven bracket
    assert res.upper_kind == "infeasible-bounded" and not res.to_dict()["bracket_proven"]


def test_maximize_uio_dt_thm4_1_gamma_max_51_5():
    """Catalogue T4.3/T10: gamma_max = 51.5 by bisection (+-0.1); P is unbounded near the supremum."""
    f = EX / "uio_dt.thm4_1.flexible_joint.yaml"
    res = maximize("uio_dt.thm4_1", f, "gamma", rtol=1e-3)
    assert res.lower == pytest.approx(51.5, abs=0.1) and res.upper <= 52.0
    best = next(p for p in res.points if p.value == res.lower)
    _certified_at("uio_dt.thm4_1", f, "gamma", res.lower, best.x)
    # the bisection's own upper end is only infeasible-bounded (P grows without bound near the
    # supremum), but a farther point, gamma = 52 (the first expansion), is proved infeasible by an
    # exact ray: a proven bracket, consistent with the catalogue's 51.5 +- 0.1
    assert res.upper_kind == "infeasible-bounded" and res.upper_proven == 52.0
    pp = next(p for p in res.points if p.value == res.upper_proven)
    assert pp.outcome != "feasible" and pp.proof is not None
    assert "not a proof" in res.message and "in [51.4375, 52] (52: infeasible-certified)" in res.message


def test_maximize_bad_input():
    with pytest.raises(DataError, match="numeric parameters: a"):
        maximize(toy_decay, TOY, "b")
    with pytest.raises(DataError, match="must be below"):
        maximize(toy_decay, TOY, "a", lo=1.0, hi=0.5)
    with pytest.raises(DataError, match="outside the domain"):
        maximize("thesis.thm3_2_2", EX / "thesis.thm3_2_2.ex3_2_2.yaml", "gamma", lo=-1.0)
    with pytest.raises(DataError, match="cannot also be fixed"):
        maximize(toy_decay, TOY, "a", params={"a": 1.0})


# -- the lmic solve hook ------------------------------------------------------------------------


def test_solve_maximize_json(capsys):
    f = str(EX / "thesis.thm3_2_2.ex3_2_2.yaml")
    assert main(["solve", "thesis.thm3_2_2", f, "--maximize", "gamma", "--rtol", "1e-3", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["mode"] == "maximize" and d["param"] == "gamma" and d["converged"]
    assert d["lower"] == pytest.approx(0.9997, abs=1.5e-3) and d["lower"] < d["upper"]
    assert d["tolerance"] == {"xtol": 1e-6, "rtol": 1e-3}
    assert d["iterations"] >= 5 and len(d["points"]) == d["evaluations"]
    assert {"plan_s", "bind_s_mean", "solve_s", "certify_s", "total_s"} <= set(d["timings"])


def test_solve_maximize_text_and_sweep_table(capsys):
    f = str(EX / "thesis.thm3_2_2.ex3_2_2.yaml")
    assert (
        main(["solve", "thesis.thm3_2_2", f, "--maximize", "gamma", "--lo", "0.5", "--hi", "1.5", "--rtol", "1e-2"])
        == 0
    )
    out = capsys.readouterr().out
    # the bisection's upper end is proven exactly (a Farkas ray on a rational face): a proven bracket
    assert "sup gamma in [" in out and "lower" in out and "upper" in out and "bisection steps" in out
    q = str(EX / "qib.thm2.flexible-joint.yaml")
    assert main(["solve", "qib.thm2", q, "--sweep", "alpha=log:1e-3:1:3"]) == 3  # (26): proven at every alpha
    out = capsys.readouterr().out
    assert "no certified point" in out and out.count("infeasible") >= 3


def test_solve_sweep_json_obs_control_young_eps(capsys):
    """Catalogue T7.2: the z-coordinate example is infeasible by a hair at eps = 0.8; smaller eps certify it."""
    f = str(EX / "obs_control.thm3_2.rossler_z.yaml")
    assert main(["solve", "obs_control.thm3_2", f, "--sweep", "eps=0.6:0.8:2", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    # eps = 0.8: infeasible by a hair (catalogue T7.2, T11.7: max margin -1.63e-5), proven by an
    # exact rational Farkas certificate on the face of the solver's ray
    assert [p["outcome"] for p in d["points"]] == ["feasible", "infeasible"]
    assert d["best"]["value"] == 0.6 and d["best"]["verdict"] == "certified"


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--maximize", "nope"], "numeric parameters"),
        (["--sweep", "gamma=1:2"], "PARAM=a:b:n"),
        (["--maximize", "gamma", "--sweep", "gamma=1:2:3"], "give one of"),
        (["--sweep", "gamma=1:2:3", "-o", "x.json"], "-o is not available"),
        (["--maximize", "gamma", "--lo", "-1"], "outside the domain"),
    ],
)
def test_solve_maximize_bad_usage_exit_2(extra, message, capsys):
    f = str(EX / "thesis.thm3_2_2.ex3_2_2.yaml")
    assert main(["solve", "thesis.thm3_2_2", f, *extra]) == 2
    assert message in capsys.readouterr().err
