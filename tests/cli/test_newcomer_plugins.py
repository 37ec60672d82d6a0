"""Plugins written by newcomers, installed like any third-party distribution (a temporary site folder).

Each typical mistake (a bilinear term, a non-symmetric block, wrong dimensions, a build function
that raises or takes no argument, an undeclared name, a matrix objective, a parameter default
outside its domain, metadata of the wrong type, an id clash with a shipped theorem) is one line
naming the theorem and the problem, exit code 2; ``lmic theorems`` still lists every other
theorem, and a broken plugin is never stored in the theorem index (lmic.plugin_index).

The commands run in one subprocess (the registry reads entry points once per process).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

NEWBIE = """
import sympy
from lmic.template import theorem, block, STAR, I, hurwitz

print("newbie plugin loaded")  # a newcomer's debugging print, at import


def _lyap(t):
    (n,) = t.dims("n")
    A = t.data("A", n, n)
    P = t.symmetric("P", n, pd=True)
    return n, A, P


@theorem(id="newbie.good", title="fine", citation="c", kind="analysis")
def good(t):
    n, A, P = _lyap(t)
    print("building", A)  # and while building
    k = t.const("k", lambda v: print("computing k") or 1.0)  # and in a constant (at every bind)
    t.lmi("L", A.T * P + P * A - k * P < 0)


@theorem(id="newbie.bilinear", title="t", citation="c")
def bilinear(t):
    n, A, P = _lyap(t)
    Q = t.symmetric("Q", n)
    t.lmi("L", A.T * P * Q + Q * P * A < 0)


@theorem(id="newbie.nonsym", title="t", citation="c", kind="analysis")
def nonsym(t):
    n, A, P = _lyap(t)
    t.lmi("L", block([[A.T * P + P * A, P], [A, -P]]) < 0)


@theorem(id="newbie.dims", title="t", citation="c", kind="analysis")
def dims(t):
    n, p = t.dims("n p")
    A, C = t.data("A", n, n), t.data("C", p, n)
    P = t.symmetric("P", n, pd=True)
    t.lmi("L", A.T * P + P * C < 0)  # P C: n x n times p x n


@theorem(id="newbie.raises", title="t", citation="c", kind="analysis")
def raises(t):
    raise ValueError("oops in build")


@theorem(id="newbie.noargs", title="t", citation="c", kind="analysis")
def noargs():
    pass


@theorem(id="newbie.undeclared", title="t", citation="c", kind="analysis")
def undeclared(t):
    n, A, P = _lyap(t)
    t.lmi("L", A.T * P + P * A + sympy.Symbol("mu") * P < 0)


@theorem(id="newbie.matobj", title="t", citation="c", kind="analysis")
def matobj(t):
    n, A, P = _lyap(t)
    t.lmi("L", A.T * P + P * A < 0)
    t.minimize(P)


@theorem(id="newbie.baddefault", title="t", citation="c", kind="analysis")
def baddefault(t):
    n, A, P = _lyap(t)
    a = t.param("a", default=-1, domain="positive")
    t.lmi("L", A.T * P + P * A + a * P < 0)


@theorem(id="newbie.gainshape", title="t", citation="c", kind="synthesis")
def gainshape(t):
    n, p = t.dims("n p")
    A, C = t.data("A", n, n), t.data("C", p, n)
    P = t.symmetric("P", n, pd=True)
    t.lmi("L", A.T * P + P * A < 0)
    t.derive("L_gain", P.inv() * C)  # C^T meant: n x n times p x n


@theorem(id="newbie.checkshape", title="t", citation="c", kind="analysis")
def checkshape(t):
    n, p = t.dims("n p")
    A, C = t.data("A", n, n), t.data("C", p, n)
    P = t.symmetric("P", n, pd=True)
    t.lmi("L", A.T * P + P * A > 0)  # infeasible for a Hurwitz A: the bug must still be named
    t.check("C Hurwitz", hurwitz(C))  # not square


@theorem(id="qib.thm1", title="a clash", citation="c", kind="analysis")
def clash(t):
    n, A, P = _lyap(t)
    t.lmi("L", A.T * P + P * A < 0)
"""

META = """
from lmic.template import theorem


@theorem(id="meta.t", title=3, citation="c", kind="analysis")
def t(t):
    pass
"""

RUN = """
import contextlib, io, json, sys
from lmic.cli import main
out = []
for argv in json.loads(sys.argv[1]):
    err, so = io.StringIO(), io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(so):
        try:
            code = main(argv)
        except SystemExit as e:
            code = e.code
    out.append([code, so.getvalue(), err.getvalue()])
print(json.dumps(out))
"""


def _dist(site: Path, name: str, code: str) -> None:
    info = site / f"{name}-1.0.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {name}\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text(f"[lmic.theorems]\n{name} = {name}_mod\n")
    (site / f"{name}_mod.py").write_text(code)


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("newcomer")
    site = tmp / "site"
    _dist(site, "newbie", NEWBIE)
    _dist(site, "meta", META)
    system = tmp / "sys.yaml"
    system.write_text("data:\n  A: [[-1, 0.5], [0, -2]]\n  C: [[1, 0]]\n")
    ids = ["bilinear", "nonsym", "dims", "raises", "noargs", "undeclared", "matobj", "baddefault", "gainshape"]
    ids += ["checkshape", "good"]
    argvs = [["theorems", "--json"], ["theorems", "--json"], ["solve", "qib.thm1", str(system)]]
    argvs += [["solve", f"newbie.{i}", str(system), "-o", str(tmp / f"{i}.json")] for i in ids]
    argvs += [["solve", "newbie.good", str(system), "--json"]]
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(site), str(ROOT), str(ROOT / "plugins"), env.get("PYTHONPATH", "")])
    env["LMIC_CACHE_DIR"] = str(tmp / "cache")
    for key in ("LMIC_DISABLE_PLUGIN_AUTOLOAD", "LMIC_NO_CACHE"):
        env.pop(key, None)
    proc = subprocess.run(
        [sys.executable, "-c", RUN, json.dumps(argvs)], capture_output=True, text=True, env=env, timeout=600
    )
    assert proc.returncode == 0, proc.stderr
    results = json.loads(proc.stdout)
    return {
        "theorems": results[:2],
        "clash": results[2],
        "solve": dict(zip(ids, results[3:-1], strict=True)),
        "json": results[-1],
        "cache": tmp / "cache",
        "written": {i for i in ids if (tmp / f"{i}.json").exists()},
    }


def test_theorems_lists_the_others_and_names_each_broken_plugin(runs):
    for code, out, err in runs["theorems"]:  # twice: the second run is not served from a stored index
        assert code == 2
        ids = {t["id"] for t in json.loads(out)["theorems"]}
        assert {"qib.thm2", "newbie.good", "newbie.bilinear"} <= ids
        assert "qib.thm1" not in ids and "meta.t" not in ids  # ambiguous; broken
        assert "meta (meta_mod) failed to load: TemplateError: theorem meta.t: title must be a string, not int" in err
        assert "theorem id 'qib.thm1' is ambiguous: provided by" in err
    assert not (runs["cache"] / "theorems").exists() or not any((runs["cache"] / "theorems").iterdir())


def test_a_clash_with_a_shipped_theorem_refuses_the_id(runs):
    code, _, err = runs["clash"]
    assert code == 2 and err.count("\n") == 1
    assert "'qib.thm1' is ambiguous" in err and "newbie 1.0" in err and "lmic " in err


@pytest.mark.parametrize(
    ("name", "fragments"),
    [
        ("bilinear", ["newbie.bilinear", "LMI 'L' block (1,1): product of decision variables"]),
        ("nonsym", ["theorem newbie.nonsym", "block (1,2) is not the transpose of block (2,1)"]),
        ("dims", ["theorem newbie.dims: LMI 'L' block (1,1): term", "inconsistent shapes (2x2 * 1x2)"]),
        ("raises", ["theorem newbie.raises: template failed to build at newbie_mod.py:", "ValueError: oops in build"]),
        ("noargs", ["theorem newbie.noargs: template failed to build at newbie_mod.py:", "TypeError"]),
        ("undeclared", ["theorem newbie.undeclared: LMI 'L' uses Symbol 'mu', which is not declared"]),
        ("matobj", ["newbie.matobj", "the objective 'P' is a matrix"]),
        ("baddefault", ["newbie.baddefault", "the default -1 of parameter 'a' is not a number in its domain"]),
        # found before any solve (they were a 'rejected' certificate, exit 1, or nothing at exit 3)
        ("gainshape", ["theorem newbie.gainshape: derived 'L_gain': expression multiplies shapes (2, 2) and (1, 2)"]),
        ("checkshape", ["theorem newbie.checkshape: check 'C Hurwitz' (hurwitz) needs a square matrix, got 1x2"]),
    ],
)
def test_each_newcomer_mistake_is_one_line_exit_2(runs, name, fragments):
    code, _, err = runs["solve"][name]
    assert name not in runs["written"]  # nothing half-written
    err = "".join(line for line in err.splitlines(keepends=True) if not line.startswith("lmic: note: "))
    assert code == 2 and err.count("\n") == 1 and err.startswith("lmic: error: "), err
    assert "internal error" not in err
    for fragment in fragments:
        assert fragment in err, err


def test_the_good_theorem_of_a_plugin_with_mistakes_still_solves(runs):
    code, out, _ = runs["solve"]["good"]
    assert code == 0 and "certified" in out and "good" in runs["written"]


def test_what_a_plugin_prints_goes_to_stderr_never_into_json(runs):
    code, out, err = runs["solve"]["good"]  # the first build of newbie.good
    assert code == 0 and "building A" in err and "building" not in out
    code, out, err = runs["json"]
    assert code == 0 and json.loads(out)["verdict"] == "certified" and "computing k" in err
    _, out, err = runs["theorems"][0]  # the registry imports the plugins once per process
    assert "newbie plugin loaded" in err
    json.loads(out)  # the import-time print is not in it
