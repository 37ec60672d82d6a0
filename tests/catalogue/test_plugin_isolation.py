"""Plugins installed through real entry points (a temp site dir): hijack and shadowing attacks.

Each test writes a ``.dist-info`` with ``entry_points.txt`` into a temporary directory put on
``PYTHONPATH`` of a subprocess ``lmic`` run, exactly as ``pip install`` of a hostile package would.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
LYAP = ROOT / "examples" / "thesis.lyapunov.ex2_3_2.yaml"
QIB = ROOT / "examples" / "qib.thm1.flexible-joint.yaml"


def _site(tmp_path: Path, dist: str, version: str, groups: dict[str, dict[str, str]], modules: dict[str, str]) -> Path:
    site = tmp_path / "site"
    info = site / f"{dist.replace('-', '_')}-{version}.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {dist}\nVersion: {version}\n")
    lines = []
    for group, eps in groups.items():
        lines.append(f"[{group}]")
        lines += [f"{k} = {v}" for k, v in eps.items()]
    (info / "entry_points.txt").write_text("\n".join(lines) + "\n")
    for name, text in modules.items():
        (site / f"{name}.py").write_text(text)
    return site


def _lmic(site: Path, *args: str) -> subprocess.CompletedProcess:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(site), str(ROOT), str(ROOT / "plugins"), env.get("PYTHONPATH", "")])
    env.pop("LMIC_DISABLE_PLUGIN_AUTOLOAD", None)
    return subprocess.run(
        [sys.executable, "-m", "lmic.cli", *args], capture_output=True, text=True, env=env, cwd=ROOT, timeout=300
    )


def _verdict(stdout: str) -> str:
    doc = json.loads(stdout)
    return doc["verdict"] if "verdict" in doc else doc["certificate"]["verdict"]


def test_theorem_plugin_raising_systemexit_on_import_decides_nothing(tmp_path):
    site = _site(
        tmp_path, "evil-thm", "6.6", {"lmic.theorems": {"aaa": "evil_thm"}}, {"evil_thm": "raise SystemExit(3)\n"}
    )
    r = _lmic(site, "solve", "thesis.lyapunov", str(LYAP), "--json")
    assert r.returncode == 0, r.stderr
    assert _verdict(r.stdout) == "certified"
    # the broken plugin is reported by name, on stderr, and 'lmic theorems' fails
    r = _lmic(site, "theorems")
    assert r.returncode == 2
    assert "plugin aaa (evil_thm) failed to load: SystemExit(3)" in r.stderr
    assert "thesis.lyapunov" in r.stdout and "failed" not in r.stdout


def test_backend_plugin_raising_systemexit_decides_nothing(tmp_path):
    site = _site(
        tmp_path,
        "evil-backend",
        "6.6",
        {"lmic.backends": {"aaa": "evil_backend:Backend"}},
        {"evil_backend": "raise SystemExit(3)\n"},
    )
    r = _lmic(site, "solve", "thesis.lyapunov", str(LYAP), "--backend", "clarabel", "--json")
    assert r.returncode == 0, r.stderr
    assert _verdict(r.stdout) == "certified"
    r = _lmic(site, "backends", "--json")
    # 'lmic backends' lists every discovered backend, a broken one as a row with its error: the
    # listing itself succeeds (exit 0, as commands/backends.py documents)
    assert r.returncode == 0, r.stderr
    assert "aaa" in r.stdout and "SystemExit(3)" in r.stdout


SHADOW = """
from lmic.template import theorem, block


@theorem(id="qib.thm1", title="shadow", citation="nobody")
def shadow(t):
    n, p = t.dims("n p")
    t.data("A", n, n)
    t.data("C", p, n)
    t.param("beta")
    t.param("gamma", default=0.0)
    P = t.symmetric("P", n)
    t.lmi("P > 0", block(P) > 0)
"""


def test_shadowing_an_installed_id_never_changes_what_solve_certifies(tmp_path):
    clean = tmp_path / "clean"
    clean.mkdir()
    cert = tmp_path / "cert.json"
    r = _lmic(clean, "solve", "qib.thm1", str(QIB), "-o", str(cert))  # written before the attack
    assert r.returncode == 0 and cert.is_file(), r.stderr
    site = _site(tmp_path, "aaa-shadow", "9.9", {"lmic.theorems": {"aaa": "shadow_thm"}}, {"shadow_thm": SHADOW})
    r = _lmic(site, "audit", str(cert))  # the audit does not recompile with the shadow either
    assert r.returncode == 2 and "ambiguous" in r.stderr and "aaa-shadow 9.9" in r.stderr
    r = _lmic(site, "solve", "qib.thm1", str(QIB))
    assert r.returncode == 2 and "certified" not in r.stdout
    line = r.stderr.strip()
    assert "ambiguous" in line and "lmic 0.1.0" in line and "aaa-shadow 9.9" in line and "\n" not in line
    for cmd in (
        ["show", "qib.thm1"],
        ["compile", "qib.thm1", str(QIB), "-o", str(tmp_path / "ir.json")],
        ["check", "qib.thm1"],
    ):
        r = _lmic(site, *cmd)
        assert r.returncode == 2 and "ambiguous" in r.stderr, cmd
    assert not (tmp_path / "ir.json").exists()
    # other ids keep working
    r = _lmic(site, "solve", "thesis.lyapunov", str(LYAP), "--json")
    assert r.returncode == 0 and _verdict(r.stdout) == "certified"
    r = _lmic(site, "theorems")
    assert r.returncode == 2 and "ambiguous" in r.stderr and "qib.thm1" not in r.stdout
