"""The on-disk plan cache (:mod:`lmic.compile.cache`) and the cache store (:mod:`lmic.cache`).

The truth a cached plan is compared with is a fresh analysis of the same template
(:func:`lmic.compile.plan.analyse_template`, which the cache does not touch); a solve from a
cached plan is checked through the certifier (its verdict).
"""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

import lmic.compile.cache as plan_cache
from lmic import cache
from lmic.compile.bind import bind
from lmic.compile.plan import analyse_template
from lmic.ir.jsonio import problem_to_dict
from lmic.registry import get_theorem, list_theorems
from lmic.template import I, theorem

ROOT = Path(__file__).resolve().parents[2]
QIB = ROOT / "examples" / "qib.thm1.flexible-joint.yaml"


@pytest.fixture
def cache_dir(tmp_path, monkeypatch):
    monkeypatch.setenv("LMIC_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.delenv("LMIC_NO_CACHE", raising=False)
    return tmp_path / "cache"


@pytest.fixture
def count(monkeypatch):
    """Counts the analyses :func:`cached_analyse` runs."""
    calls = []

    def counting(thm, t):
        calls.append(thm.id)
        return analyse_template(thm, t)

    monkeypatch.setattr(plan_cache, "analyse_template", counting)
    return calls


def _same(a, b) -> bool:
    return (
        [(lp.name, lp.relation, lp.k, lp.entries, lp.zeros, lp.stars, lp.sizes) for lp in a.lmis]
        == [(lp.name, lp.relation, lp.k, lp.entries, lp.zeros, lp.stars, lp.sizes) for lp in b.lmis]
        and a.constraints == b.constraints
        and a.objective == b.objective
        and a.coef_symbols == b.coef_symbols
        and a.options == b.options
    )


def _entries(root: Path) -> list[Path]:
    return sorted((root / plan_cache.KIND).glob("*.json")) if (root / plan_cache.KIND).exists() else []


def test_every_shipped_plan_round_trips(cache_dir):
    """Every registered theorem, every option value: the cached plan equals a fresh analysis."""
    checked = 0
    for thm in list_theorems():
        if thm.provider is None or thm.provider.is_api:
            continue
        t = thm.template()
        for opts in [{}] + [{o.name: c} for o in t.options for c in o.choices if c != o.value]:
            first = plan_cache.cached_analyse(thm, opts)  # analysed and stored
            again = plan_cache.cached_analyse(thm, opts)  # decoded from the entry
            assert _same(again, analyse_template(thm, again.template)), (thm.id, opts)
            assert _same(first, again)
            checked += 1
    assert checked > 30 and len(_entries(cache_dir)) == checked


def test_hit_skips_the_analysis_and_binds_the_same_problem(cache_dir, count):
    thm = get_theorem("qib.thm1")
    first = plan_cache.cached_analyse(thm)
    assert count == ["qib.thm1"] and len(_entries(cache_dir)) == 1
    second = plan_cache.cached_analyse(thm)
    assert count == ["qib.thm1"]  # no second analysis
    assert first.cache["template_parts"] == second.cache["template_parts"]
    a, b = bind(first, str(QIB)), bind(second, str(QIB))
    assert json.dumps(problem_to_dict(a), sort_keys=True) == json.dumps(problem_to_dict(b), sort_keys=True)


def test_a_warm_solve_is_certified(cache_dir):
    """A solve in a new process with the plan read from the cache: the certifier's verdict."""
    env = dict(os.environ, LMIC_CACHE_DIR=str(cache_dir))
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), str(ROOT / "plugins"), env.get("PYTHONPATH", "")])
    script = (
        "import sys, lmic.compile.cache as c\n"
        "calls = []\n"
        "orig = c.analyse_template\n"
        "c.analyse_template = lambda thm, t: calls.append(1) or orig(thm, t)\n"
        "import lmic\n"
        f"r = lmic.solve('qib.thm1', {str(QIB)!r})\n"
        "print(r.verdict, len(calls))\n"
    )
    runs = [
        subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=env, timeout=600)
        for _ in range(2)
    ]
    assert [r.returncode for r in runs] == [0, 0], runs[0].stderr + runs[1].stderr
    assert runs[0].stdout.split() == ["certified", "1"]  # cold: analysed
    assert runs[1].stdout.split() == ["certified", "0"]  # warm: read from the cache


def _inline(entry: str):
    @theorem(id="cachetest.t", title="t", citation="c")
    def build(t):
        (n,) = t.dims("n")
        A = t.data("A", n, n)
        P = t.symmetric("P", n, pd=True)
        w = t.scalar("w", sign="positive")
        if entry == "lyapunov":
            t.lmi("L", A.T * P + P * A + w * I(n) < 0)
        else:
            t.lmi("L", A.T * P + P * A + 2 * w * I(n) < 0)

    return build


def test_a_changed_template_or_version_is_a_miss(cache_dir, count, monkeypatch):
    one, two = _inline("lyapunov"), _inline("scaled")  # same id, one LMI differs
    p1 = plan_cache.cached_analyse(one)
    p2 = plan_cache.cached_analyse(two)
    assert count == ["cachetest.t", "cachetest.t"] and len(_entries(cache_dir)) == 2
    assert _same(p2, analyse_template(two, p2.template)) and not _same(p1, p2)
    plan_cache.cached_analyse(one)
    assert len(count) == 2  # both stay cached
    monkeypatch.setattr(plan_cache, "__version__", "999.0")
    plan_cache.cached_analyse(one)
    assert len(count) == 3 and len(_entries(cache_dir)) == 3


def _corruptions(entry: Path) -> list[bytes]:
    good = entry.read_bytes()
    doc = json.loads(good)
    bad_class = json.loads(good)
    bad_class["payload"]["nodes"].append(["eval", 0])
    bad_index = json.loads(good)
    bad_index["payload"]["nodes"].append(["Add", 10**6])
    huge = json.loads(good)
    huge["payload"]["nodes"].append(["Integer", 10**40])
    wrong_lmi = json.loads(good)
    wrong_lmi["payload"]["lmis"][0]["name"] = "another"
    wrong_var = json.loads(good)
    entry_terms = wrong_var["payload"]["lmis"][-1]["entries"][0][2]
    entry_terms[0][1] = "not_a_variable"

    def resealed(d: dict) -> bytes:  # a valid checksum over a damaged payload
        body = json.dumps(d["payload"], sort_keys=True, separators=(",", ":")).encode()
        d["sha256"] = hashlib.sha256(body).hexdigest()
        return json.dumps(d).encode()

    doc["payload"]["lmis"][0]["k"] = 7  # checksum no longer matches
    return [
        b"",
        good[: len(good) // 2],
        b"\x00\xff garbage",
        b"[1, 2, 3]",
        json.dumps(doc).encode(),
        resealed(bad_class),
        resealed(bad_index),
        resealed(huge),
        resealed(wrong_lmi),
        resealed(wrong_var),
    ]


def test_a_corrupt_entry_is_ignored_and_replaced(cache_dir, count):
    thm = get_theorem("thesis.lyapunov")
    truth = plan_cache.cached_analyse(thm)
    (entry,) = _entries(cache_dir)
    good = entry.read_bytes()
    for k, damaged in enumerate(_corruptions(entry)):
        entry.write_bytes(damaged)
        plan = plan_cache.cached_analyse(thm)
        assert len(count) == k + 2, k  # analysed again
        assert _same(plan, truth)
        assert json.loads(entry.read_bytes())["payload"] == json.loads(good)["payload"]  # replaced
    entry.chmod(0o000)  # unreadable: a miss, never an error
    try:
        assert _same(plan_cache.cached_analyse(thm), truth)
    finally:
        entry.chmod(0o644)


def test_disabled_by_the_environment(cache_dir, count, monkeypatch):
    monkeypatch.setenv("LMIC_NO_CACHE", "1")
    thm = get_theorem("thesis.lyapunov")
    plan_cache.cached_analyse(thm)
    plan_cache.cached_analyse(thm)
    assert len(count) == 2 and not cache_dir.exists()
    assert cache.load("plans", {"a": 1}) is None and cache.store("plans", {"a": 1}, [1]) is False


def test_an_unwritable_cache_folder_is_no_error(tmp_path, monkeypatch, count):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    monkeypatch.setenv("LMIC_CACHE_DIR", str(blocker / "cache"))
    thm = get_theorem("thesis.lyapunov")
    plan = plan_cache.cached_analyse(thm)
    assert _same(plan, analyse_template(thm, plan.template)) and len(count) == 1


WRITER = """
import sys
from lmic import cache
payload = {"who": sys.argv[1], "data": [int(sys.argv[1])] * 200000}
for _ in range(15):
    assert cache.store("race", {"k": 1}, payload)
"""


def test_concurrent_writers_leave_one_complete_entry(cache_dir):
    env = dict(os.environ, LMIC_CACHE_DIR=str(cache_dir))
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")])
    procs = [subprocess.Popen([sys.executable, "-c", WRITER, str(k)], env=env) for k in range(1, 4)]
    seen = set()
    while any(p.poll() is None for p in procs):
        got = cache.load("race", {"k": 1})
        if got is not None:  # never a mix of two writers, never a partial entry
            assert got["data"] == [int(got["who"])] * 200000
            seen.add(got["who"])
    assert [p.wait() for p in procs] == [0, 0, 0]
    final = cache.load("race", {"k": 1})
    assert final is not None and final["data"] == [int(final["who"])] * 200000
    assert [p.name for p in (cache_dir / "race").iterdir()] == [cache.entry_path("race", {"k": 1}).name]
    assert seen | {final["who"]} <= {"1", "2", "3"}


@pytest.mark.skipif(not hasattr(os, "geteuid") or os.geteuid() != 0, reason="chown to another user needs root")
def test_an_entry_owned_by_another_user_is_not_trusted(cache_dir, count):
    thm = get_theorem("thesis.lyapunov")
    plan_cache.cached_analyse(thm)
    (entry,) = _entries(cache_dir)
    os.chown(entry, 12345, 12345)  # as if planted in a shared LMIC_CACHE_DIR
    plan = plan_cache.cached_analyse(thm)
    assert len(count) == 2 and _same(plan, analyse_template(thm, plan.template))
    assert entry.stat().st_uid == os.geteuid()  # replaced by the user's own entry
