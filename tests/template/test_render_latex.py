"""``lmic show --latex`` (lmic/template/render.py): the checks are part of the theorem, and a
name's < and > print in plain LaTeX (whose text font has neither: 'P > 0' came out as 'P ¿ 0')."""

from __future__ import annotations

from lmic.registry import get_theorem


def test_checks_and_relations_in_names_are_rendered():
    latex = get_theorem("qib.thm1").latex()
    assert r"\text{P \(>\) 0}" in latex and "P > 0" not in latex
    (line,) = [ln for ln in latex.splitlines() if ln.startswith(r"\text{check ")]
    assert r"\rho\left(" in line and line.rstrip(" \\").endswith("< 1")


def test_a_block_check_is_a_bmatrix():
    latex = get_theorem("obs_control.thm3_1").latex()
    checks = [ln for ln in latex.splitlines() if ln.startswith(r"\text{check ")]
    assert any(r"\begin{bmatrix}" in ln and r"\prec 0" in ln for ln in checks)
    assert any(r"\operatorname{Re} \lambda" in ln for ln in checks)
