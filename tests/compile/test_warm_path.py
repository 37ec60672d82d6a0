"""The warm one-shot path (:mod:`lmic.compile.freeze`, :mod:`lmic.compile.frozen`, :mod:`lmic.compile.warm`).

The truth a frozen plan is compared with is the analysed plan it was frozen from, bound by the
same binder (:func:`lmic.compile.bind.bind`); domains are compared with sympy's own
``Set.contains``. Whole ``lmic solve`` processes check what a user sees: the warm process does
not import sympy and gives the cold process's verdict, point and certificate (both checked by
the certifier: the verdict), an edited plugin file or a corrupt entry takes the full path.
"""

from __future__ import annotations

import glob
import json
import os
import subprocess
import sys
import textwrap
import warnings
from pathlib import Path

import numpy as np
import pytest
import sympy

from lmic.compile import bind, plan_for
from lmic.compile.freeze import Unsupported, freeze
from lmic.compile.frozen import Domain, normalise_option
from lmic.compile.warm import KIND, from_payload
from lmic.ir.jsonio import problem_to_dict
from lmic.system import load_system
from lmic.template.decls import DOMAINS
from lmic.template.decls import normalise_option as template_normalise_option

ROOT = Path(__file__).resolve().parents[2]
QIB = ROOT / "examples" / "qib.thm1.flexible-joint.yaml"


def _examples() -> list[tuple[str, str]]:
    out = []
    for f in sorted(glob.glob(str(ROOT / "examples" / "*.yaml"))):
        name = os.path.basename(f)
        if name.count(".") >= 3:
            out.append((".".join(name.split(".")[:2]), f))
    return out


def test_a_frozen_plan_binds_the_problem_of_the_analysed_one():
    """Every shipped example whose theorem freezes: the same IR, coefficients to rounding."""
    frozen_ids = set()
    for tid, path in _examples():
        sysobj = load_system(path)
        try:
            plan = plan_for(tid, sysobj.params)
        except Exception:  # noqa: BLE001 - an example of a theorem not installed here
            continue
        try:
            payload = freeze(plan)
        except Unsupported:
            assert plan.template.consts or plan.template.requirements, tid  # only plugin code stops it
            continue
        again = from_payload(json.loads(json.dumps(payload)), plan.theorem.provider.to_dict())
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            a, b = bind(plan, sysobj), bind(again, sysobj)
        da, db = problem_to_dict(a), problem_to_dict(b)
        for key in da:
            if key != "lmis":
                assert da[key] == db[key], (path, key)
        assert [(x.name, x.dim, x.strict, x.block_sizes) for x in a.lmis] == [
            (x.name, x.dim, x.strict, x.block_sizes) for x in b.lmis
        ]
        for x, y in zip(a.lmis, b.lmis, strict=True):
            diff = abs(x.coeffs - y.coeffs).max() if x.coeffs.nnz else 0.0
            assert diff <= 1e-12 * max(1.0, abs(x.coeffs).max()), (path, x.name, diff)
        frozen_ids.add(tid)
    assert {"qib.thm1", "thesis.lyapunov", "obs_control.thm3_2"} <= frozen_ids


def test_plugin_code_at_bind_time_is_never_frozen():
    """qib.thm2 computes constants from the data in Python: no frozen form."""
    with pytest.raises(Unsupported, match="constants"):
        freeze(plan_for("qib.thm2"))


@pytest.mark.parametrize("name", sorted(DOMAINS))
def test_domains_decide_like_sympy(name):
    from lmic.compile.freeze import _domain  # the encoding under test

    domain = DOMAINS[name]
    frozen = Domain.of(json.loads(json.dumps(_domain(domain))), str(domain))
    for v in (-2.0, -1.0, -0.5, 0.0, 1e-300, 0.5, 1.0, 2.0, 3.5, 1e300):
        truth = domain.contains(sympy.Float(v))
        if truth not in (sympy.true, sympy.false) and v.is_integer():
            truth = domain.contains(sympy.Integer(int(v)))
        assert frozen.contains_number(v) == (truth == sympy.true), (name, v)
    assert str(frozen) == str(domain)


def test_option_values_normalise_like_the_template():
    for v in (1, 1.0, 0.5, True, False, "printed", 2.5e-7, 0):
        assert normalise_option(v) == template_normalise_option(v)


# -- whole processes -------------------------------------------------------------------------------
DRIVER = textwrap.dedent(
    """
    import json, sys
    from lmic.cli import main
    rc = main(sys.argv[1:])
    sys.stdout.flush()
    sys.stderr.write("\\nDRIVER " + json.dumps({"rc": rc, "sympy": "sympy" in sys.modules}) + "\\n")
    """
)


def _run(args: list[str], cache: Path, extra_path: str = "") -> tuple[dict, str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in [extra_path, str(ROOT), str(ROOT / "plugins")] if p)
    env["LMIC_CACHE_DIR"] = str(cache)
    env.pop("LMIC_NO_CACHE", None)
    out = subprocess.run([sys.executable, "-c", DRIVER, *args], env=env, capture_output=True, text=True, cwd=ROOT)
    line = [x for x in out.stderr.splitlines() if x.startswith("DRIVER ")]
    assert line, out.stderr[-2000:]
    return json.loads(line[-1][7:]), out.stdout, out.stderr


def _strip(doc):
    """A certificate without what differs between two runs (timings, date, their hashes)."""
    if isinstance(doc, dict):
        return {
            k: _strip(v) for k, v in doc.items() if not (k.endswith("_s") or k in ("created", "integrity", "timings"))
        }
    if isinstance(doc, list):
        return [_strip(v) for v in doc]
    return doc


def test_a_warm_solve_does_not_import_sympy_and_matches_the_cold_one(tmp_path):
    cache = tmp_path / "cache"
    cold, out_cold, _ = _run(["solve", "qib.thm1", str(QIB), "--json", "-o", str(tmp_path / "cold.json")], cache)
    assert cold == {"rc": 0, "sympy": True}
    assert list((cache / KIND).glob("*.json")), "the cold run stores the frozen plan"
    warm, out_warm, _ = _run(["solve", "qib.thm1", str(QIB), "--json", "-o", str(tmp_path / "warm.json")], cache)
    assert warm == {"rc": 0, "sympy": False}
    a, b = json.loads(out_cold), json.loads(out_warm)
    assert a["verdict"] == b["verdict"] == "certified"
    for name, value in a["variables"].items():
        np.testing.assert_allclose(np.asarray(b["variables"][name]), np.asarray(value), rtol=1e-9, atol=1e-12)
    assert _strip(a["certificate"]) == _strip(b["certificate"])
    cert_a = json.loads((tmp_path / "cold.json").read_text())
    cert_b = json.loads((tmp_path / "warm.json").read_text())
    assert _strip(cert_a) == _strip(cert_b)  # theorem, provider, template hash, margins, point
    text, _, _ = _run(["solve", "qib.thm1", str(QIB)], cache)  # the text output too
    assert text == {"rc": 0, "sympy": False}


def test_a_corrupt_entry_takes_the_full_path(tmp_path):
    cache = tmp_path / "cache"
    first, out_first, _ = _run(["solve", "qib.thm1", str(QIB), "--json"], cache)
    entries = list((cache / KIND).glob("*.json"))
    assert first["rc"] == 0 and len(entries) == 1
    good = entries[0].read_bytes()
    for damaged in (good[: len(good) // 2], good.replace(b'"relation":"<"', b'"relation":">"'), b"\x00garbage"):
        entries[0].write_bytes(damaged)
        res, out, err = _run(["solve", "qib.thm1", str(QIB), "--json"], cache)
        assert res == {"rc": 0, "sympy": True}, err[-500:]  # a miss: analysed again, no crash
        assert json.loads(out)["verdict"] == json.loads(out_first)["verdict"] == "certified"
        assert entries[0].read_bytes() == good  # and written again
    assert _run(["solve", "qib.thm1", str(QIB), "--json"], cache)[0] == {"rc": 0, "sympy": False}


PLUGIN = """
from lmic.template import block, theorem

@theorem(id="warmtest.lyap", title="t", citation="c")
def lyap(t):
    (n,) = t.dims("n")
    A = t.data("A", n, n)
    P = t.symmetric("P", n, pd=True)
    t.lmi("stability", block(A.T * P + P * A + {shift} * P) < 0)
"""


def _install_plugin(site: Path, shift: str) -> None:
    (site / "warmtest").mkdir(parents=True, exist_ok=True)
    (site / "warmtest" / "__init__.py").write_text(PLUGIN.format(shift=shift))
    dist = site / "warmtest-0.1.dist-info"
    dist.mkdir(exist_ok=True)
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: warmtest\nVersion: 0.1\n")
    (dist / "entry_points.txt").write_text("[lmic.theorems]\nwarmtest = warmtest\n")


def test_an_edited_plugin_file_is_never_served_from_the_old_entry(tmp_path):
    """A = -I: ``A^T P + P A + s P < 0`` holds for s = 1 and fails (P > 0) for s = 3."""
    site, cache = tmp_path / "site", tmp_path / "cache"
    system = tmp_path / "sys.json"
    system.write_text(json.dumps({"lmic": 1, "data": {"A": [[-1.0, 0.0], [0.0, -1.0]]}}))
    _install_plugin(site, "1")
    args = ["solve", "warmtest.lyap", str(system), "--json", "--backend", "clarabel"]
    cold, out, _ = _run(args, cache, str(site))
    warm, out_warm, _ = _run(args, cache, str(site))
    assert (cold["rc"], warm) == (0, {"rc": 0, "sympy": False})
    assert json.loads(out)["verdict"] == json.loads(out_warm)["verdict"] == "certified"
    _install_plugin(site, "3")  # same size, a new modification time: the entry's key changes
    os.utime(site / "warmtest" / "__init__.py", ns=(1, 1))
    edited, out_edited, _ = _run(args, cache, str(site))
    assert edited["sympy"] is True  # a miss: the plugin was imported and analysed again
    assert json.loads(out_edited)["verdict"] in ("infeasible-certified", "infeasible-bounded")
    assert edited["rc"] in (3, 4)
    again, out_again, _ = _run(args, cache, str(site))
    assert again == {"rc": edited["rc"], "sympy": False}  # the new entry is warm
    assert json.loads(out_again)["verdict"] == json.loads(out_edited)["verdict"]
