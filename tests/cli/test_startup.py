"""Start-up: what ``lmic --version`` and ``lmic theorems`` import, lazy ``lmic.<name>``, the theorem index.

Every check of imports runs in a fresh subprocess (``sys.modules`` of this test process is
shared by all tests). The theorem index (:mod:`lmic.plugin_index`) is compared with the full
registry's answer computed in this process, and its invalidation is checked with a plugin
installed in a temporary site folder (a ``.dist-info`` with ``entry_points.txt``).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
HEAVY = ("numpy", "scipy", "sympy", "cvxpy", "picos", "clarabel", "scs", "cvxopt", "sdpap")

PROBE = """
import json, sys
from lmic.cli import main
try:
    code = main(sys.argv[1:])
except SystemExit as e:
    code = e.code
sys.stdout.flush()
sys.stderr.write("\\nMODULES " + json.dumps(sorted(sys.modules)) + "\\n")
raise SystemExit(code)
"""


def _env(cache: Path | None, site: Path | None = None, **extra: str) -> dict[str, str]:
    env = dict(os.environ)
    paths = ([str(site)] if site else []) + [str(ROOT), str(ROOT / "plugins"), env.get("PYTHONPATH", "")]
    env["PYTHONPATH"] = os.pathsep.join(paths)
    env.pop("LMIC_DISABLE_PLUGIN_AUTOLOAD", None)
    env.pop("LMIC_NO_CACHE", None)
    if cache is not None:
        env["LMIC_CACHE_DIR"] = str(cache)
    env.update(extra)
    return env


def _probe(env: dict[str, str], *args: str) -> tuple[int, str, str, set[str]]:
    """Run ``lmic ARGS`` in a subprocess; return exit code, stdout, stderr and its sys.modules."""
    out = subprocess.run(
        [sys.executable, "-c", PROBE, *args], capture_output=True, text=True, env=env, cwd=ROOT, timeout=300
    )
    err, _, mods = out.stderr.rpartition("\nMODULES ")
    return out.returncode, out.stdout, err, set(json.loads(mods))


def _heavy(modules: set[str]) -> list[str]:
    return sorted(m for m in modules if m.split(".")[0] in HEAVY)


def test_version_and_parser_import_no_numpy(tmp_path):
    code, out, _, mods = _probe(_env(tmp_path), "--version")
    assert code == 0 and out.strip().startswith("lmic ")
    assert _heavy(mods) == []
    code, out, _, mods = _probe(_env(tmp_path), "--help")  # every sub-command's parser is built
    assert code == 0 and "theorems" in out and "solve" in out
    assert _heavy(mods) == []


def test_a_command_builds_only_its_own_parser_and_a_json_solve_skips_yaml_and_farkas(tmp_path):
    """``lmic backends`` imports no other command's module; a warm ``lmic solve`` of a JSON
    system (a verified feasible point) imports neither PyYAML nor the Farkas ray modules."""
    code, out, _, mods = _probe(_env(tmp_path), "backends", "--json")
    assert code == 0 and json.loads(out)
    commands = sorted(m for m in mods if m.startswith("lmic.commands.") and not m.startswith("lmic.commands._"))
    assert commands == ["lmic.commands.backends"]
    system = tmp_path / "sys.json"
    system.write_text(
        json.dumps({"lmic": 1, "data": {"A": [[0.5, 0.1], [0.0, 0.4]], "C": [[1.0, 0.0]]}, "params": {"beta": 1e-3}})
    )
    for _ in range(2):  # the first run fills the plan cache
        code, out, err, mods = _probe(_env(tmp_path / "cache"), "solve", "qib.thm1", str(system), "--json")
    assert code == 0, err
    assert json.loads(out)["verdict"] == "certified"
    assert "yaml" not in mods
    assert not [m for m in mods if m.startswith("lmic.certify.farkas")]
    code, out, _, _ = _probe(_env(tmp_path), "bogus-command")
    assert code == 2  # an unknown word still gets the full parser's one-line error


def test_lazy_names_of_lmic():
    script = (
        "import sys, lmic\n"
        "heavy = [m for m in sys.modules if m.split('.')[0] in ('numpy', 'sympy', 'scipy')]\n"
        "assert not heavy, heavy\n"
        "missing = [n for n in lmic.__all__ if n not in dir(lmic)]\n"
        "assert not missing, missing\n"
        "for name in lmic.__all__:\n"
        "    value = getattr(lmic, name)\n"
        "    assert value is not None, name\n"
        "from lmic.template.theorem import Theorem\n"
        "from lmic.api import Result\n"
        "from lmic.registry import register\n"
        "assert lmic.Theorem is Theorem and lmic.Result is Result and lmic.register is register\n"
        "assert lmic.compile.__name__ == 'lmic.compile'\n"
        "try:\n"
        "    lmic.no_such_name\n"
        "except AttributeError as err:\n"
        "    assert 'no_such_name' in str(err)\n"
        "else:\n"
        "    raise AssertionError('lmic.no_such_name did not raise')\n"
        "print('ok')\n"
    )
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=_env(None), timeout=300)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "ok"


def _expected_index() -> list[dict]:
    """The theorems as the full registry lists them (every plugin imported), in this process."""
    from lmic.registry import list_theorems

    return [
        {
            "id": t.id,
            "title": t.title,
            "citation": t.citation,
            "kind": t.kind,
            "objective": t.objective,
            "provider": t.provider.to_dict() if t.provider else None,
        }
        for t in list_theorems()
        if t.provider is not None and not t.provider.is_api  # not the notebook theorems of other tests
    ]


def test_theorems_from_the_index_equal_the_registry(tmp_path):
    cache = tmp_path / "cache"
    code1, out1, _, mods1 = _probe(_env(cache), "theorems", "--json")  # miss: full registry, stored
    code2, out2, _, mods2 = _probe(_env(cache), "theorems", "--json")  # hit
    assert code1 == code2 == 0
    assert "lmic.registry" in mods1
    assert "lmic.registry" not in mods2 and "sympy" not in mods2
    assert json.loads(out2) == json.loads(out1)
    assert out2 == out1  # byte for byte, key order included
    listed = json.loads(out2)
    assert listed["theorems"] == _expected_index()
    assert listed["broken_plugins"] == [] and listed["conflicts"] == []
    code3, table, _, mods3 = _probe(_env(cache), "theorems")  # the table, from the index too
    code4, table_full, _, _ = _probe(_env(cache, LMIC_NO_CACHE="1"), "theorems")
    assert code3 == code4 == 0 and table == table_full
    assert "sympy" not in mods3


PLUGIN = """
from lmic.template import theorem


@theorem(id="startup_probe.t", title="{title}", citation="c", kind="analysis", objective="feasibility")
def t(t):
    (n,) = t.dims("n")
    A = t.data("A", n, n)
    P = t.symmetric("P", n, pd=True)
    t.lmi("L", A.T * P + P * A < 0)
"""


def _site(tmp_path: Path, title: str) -> Path:
    site = tmp_path / "site"
    info = site / "startup_probe-1.0.dist-info"
    info.mkdir(parents=True, exist_ok=True)
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: startup-probe\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text("[lmic.theorems]\nstartup_probe = startup_probe_mod\n")
    (site / "startup_probe_mod.py").write_text(PLUGIN.format(title=title))
    return site


def _titles(out: str) -> dict[str, str]:
    return {t["id"]: t["title"] for t in json.loads(out)["theorems"]}


def test_index_follows_a_changed_plugin_and_never_stores_a_failure(tmp_path):
    cache = tmp_path / "cache"
    site = _site(tmp_path, "first title")
    code, out, _, _ = _probe(_env(cache, site), "theorems", "--json")
    assert code == 0 and _titles(out)["startup_probe.t"] == "first title"
    code, out, _, mods = _probe(_env(cache, site), "theorems", "--json")
    assert code == 0 and "lmic.registry" not in mods  # served by the index
    # the plugin's file changes (an editable install: same version): the index is rebuilt
    time.sleep(0.01)
    _site(tmp_path, "second title")
    code, out, _, mods = _probe(_env(cache, site), "theorems", "--json")
    assert code == 0 and "lmic.registry" in mods
    assert _titles(out)["startup_probe.t"] == "second title"
    # a broken plugin: exit 2 with its line, on every run (a failure is never served from the index)
    (site / "startup_probe_mod.py").write_text("raise RuntimeError('probe plugin is broken')\n")
    for _ in range(2):
        code, out, err, mods = _probe(_env(cache, site), "theorems", "--json")
        assert code == 2 and "probe plugin is broken" in err
        assert "lmic.registry" in mods
        assert "startup_probe.t" not in _titles(out)
