"""Jupyter displays of theorems and results: they work after ``import lmic`` alone (no import of
:mod:`lmic.present`, which sits above the studies layer) and agree with :mod:`lmic.present`."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap

import numpy as np

import lmic
from lmic.certify import certify
from lmic.present.html import result_html, theorem_html
from lmic.present.latex import matrix_latex, result_latex, theorem_latex_block


def test_rich_display_in_jupyter():
    r = lmic.solve("thesis.lyapunov", {"data": {"A": [[-1.0]]}})
    assert certify(r.problem, r.solution).verdict == "certified"
    html = r._repr_html_()
    assert "certified" in html and "<table" in html and "P &gt; 0" in html
    assert r._repr_latex_().startswith("$")
    thm = lmic.theorem("qib.thm1")
    assert r"\begin{bmatrix}" in thm.latex()
    assert "Wang, Song" in thm._repr_html_() and thm._repr_latex_().startswith("$$")
    assert "verdict='certified'" in repr(r)


def test_reprs_work_after_import_lmic_alone_and_match_present():
    script = textwrap.dedent(
        """
        import json, sys
        import lmic
        thm = lmic.theorem("qib.thm1")
        r = lmic.solve("thesis.lyapunov", {"data": {"A": [[-2.0, 1.0], [0.0, -1.0]]}})
        out = {"thm_html": thm._repr_html_(), "thm_latex": thm._repr_latex_(),
               "res_html": r._repr_html_(), "res_latex": r._repr_latex_(),
               "present_loaded": any(m == "lmic.present" or m.startswith("lmic.present.") for m in sys.modules)}
        print(json.dumps(out))
        """
    )
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=True)
    out = json.loads(done.stdout)
    assert out["present_loaded"] is False
    thm = lmic.theorem("qib.thm1")
    assert out["thm_html"] == theorem_html(thm)
    assert out["thm_latex"] == theorem_latex_block(thm)
    assert out["thm_latex"] == "$$" + thm.latex() + "$$"
    r = lmic.solve("thesis.lyapunov", {"data": {"A": [[-2.0, 1.0], [0.0, -1.0]]}})
    assert certify(r.problem, r.solution).verdict == "certified"
    assert out["res_html"] == result_html(r) and out["res_latex"] == result_latex(r)
    # every LMI of the template appears in the theorem's HTML, named
    for decl in thm.template().lmis:
        assert f"<b>{decl.name.replace('>', '&gt;')}</b>" in out["thm_html"]


def _read_latex_number(text: str) -> float:
    mant, _, exp = text.partition(r" \cdot 10^")
    return float(mant) * 10.0 ** int(exp.strip("{}") or 0)


def test_matrix_latex_rows_and_entries_read_back():
    rng = np.random.default_rng(3)
    m = rng.normal(size=(3, 2)) * 10.0 ** rng.integers(-6, 6, size=(3, 2))
    text = matrix_latex(m, digits=6)
    body = text.removeprefix(r"\begin{bmatrix}").removesuffix(r"\end{bmatrix}")
    rows = [row.split(" & ") for row in body.split(r" \\ ")]
    back = np.array([[_read_latex_number(e) for e in row] for row in rows])
    assert back.shape == m.shape
    np.testing.assert_allclose(back, m, rtol=1e-5)
