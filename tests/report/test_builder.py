"""The report page: self-contained (no external resource), every section present, formatting
helpers, and the notes that replace the figure when there is nothing to simulate."""

from __future__ import annotations

import html
import re
from html.parser import HTMLParser

import numpy as np
import pytest

from lmic.errors import DataError
from lmic.report import KATEX_VERSION, build_report
from lmic.report.assets import FONT_FILES, asset_bytes, katex_css, katex_js
from lmic.report.builder import MAX_LATEX_SIZE, _latex_name, _value_html, matrix_latex, number_latex


class Elements(HTMLParser):
    """Collects (tag, attrs) of every element."""

    def __init__(self) -> None:
        super().__init__()
        self.elements: list[tuple[str, dict[str, str]]] = []

    def handle_starttag(self, tag, attrs):
        self.elements.append((tag, {k: v or "" for k, v in attrs}))


def elements(page: str) -> list[tuple[str, dict[str, str]]]:
    p = Elements()
    p.feed(page)
    return p.elements


def test_the_page_is_self_contained(small_report):
    page = small_report.html
    els = elements(page)
    assert not [e for e in els if e[0] == "link"]
    for tag, attrs in els:
        for key in ("src", "href"):
            value = attrs.get(key, "")
            assert not value or value.startswith(("data:", "#")), (tag, key, value[:60])
    assert "url(fonts/" not in page and page.count("data:font/woff2;base64,") == len(FONT_FILES)
    assert "renderMathInElement" in page and f"KaTeX {KATEX_VERSION}" in page


def test_every_section_and_table_is_there(small_report):
    page = small_report.html
    ids = [a.get("id") for t, a in elements(page) if t == "section"]
    assert ids == ["theorem", "system", "solution", "certificate", "crosscheck", "simulation"]
    classes = " ".join(a.get("class", "") for t, a in elements(page) if t == "table")
    for cls in ("margins", "checks", "crosscheck", "kv"):
        assert cls in classes
    assert r"\begin{bmatrix}" in page and r"\star" in page  # the LMI (7), as printed, for KaTeX
    assert 'id="simulation-plot"' in page and "data:image/png;base64," in page
    assert "Two-state DT plant &amp; friends &lt;demo&gt;" in page  # text is escaped
    assert small_report.trajectory is not None and small_report.trajectory.decayed
    assert [r["backend"] for r in small_report.crosscheck.results] == ["clarabel", "cvxopt"]
    assert "Against the published values" in page


def test_assets_are_the_vendored_files():
    assert asset_bytes("fonts/KaTeX_Main-Regular.woff2")[:4] == b"wOF2"
    assert b"MIT" in asset_bytes("LICENSE-KaTeX.txt")
    assert katex_css().count("@font-face") == len(FONT_FILES)
    assert "</script" not in katex_js().lower()


def test_formatting_helpers():
    assert number_latex(1e-7) == r"1 \cdot 10^{-7}"
    assert number_latex(float("inf")) == r"\infty" and number_latex(-float("inf")) == r"-\infty"
    assert matrix_latex(2.5) == "2.5" and matrix_latex([[1.0]]) == "1"
    assert matrix_latex([[1, 2]]) == r"\begin{bmatrix}1 & 2\end{bmatrix}"
    big = _value_html("P", np.eye(MAX_LATEX_SIZE + 1))
    assert "<table" in big and r"\begin{bmatrix}" not in big and "no-math" in big
    assert "no-math" in _value_html("status", "feasible")
    assert _latex_name("Ybar") == r"\bar{Y}" and _latex_name("D1") == "D_{1}"
    assert _latex_name("gamma_max") == r"\gamma_{\mathrm{max}}"


def _system(**changes):
    system = {
        "lmic": 1,
        "data": {"A": [[0.9, 0.2], [-0.1, 0.95]], "C": [[1.0, 0.0]]},
        "params": {"beta": 0.001},
        "simulation": {"x0": [1.0, -1.0], "horizon": 5},
    }
    system.update(changes)
    return {k: v for k, v in system.items() if v is not None}


@pytest.mark.parametrize(
    ("theorem", "system", "kwargs", "note"),
    [
        ("qib.thm1", _system(simulation=None), {}, "has no 'simulation:' section"),
        ("qib.thm1", _system(), {"run_simulation": False}, "Simulation not run"),
        (
            "thesis.lyapunov",
            {"lmic": 1, "data": {"A": [[-1.0]]}, "simulation": {"x0": [1], "horizon": 1}},
            {},
            "declares no observer",
        ),
        ("qib.thm1", _system(params={"beta": 50}), {}, "No certified gains"),
        (
            "qib.thm1",
            _system(simulation={"x0": [1.0, 10.0], "horizon": 10, "nonlinearity": ["0", "x2**3"]}),
            {},
            "The simulation failed: <system>: simulation: the plant state blew up at t = ",
        ),
    ],
)
def test_notes_replace_the_figure(theorem, system, kwargs, note):
    report = build_report(theorem, system, run_crosscheck=False, **kwargs)
    assert report.trajectory is None
    assert note in html.unescape(report.html) and note in report.simulation_note
    assert 'id="simulation-plot"' not in report.html
    assert "Cross-check not run" in report.html


def test_bad_simulation_section_fails_before_solving(monkeypatch):
    import lmic.api

    def no_solve(*args, **kwargs):
        raise AssertionError("solved despite bad input")

    monkeypatch.setattr(lmic.api, "solve", no_solve)
    with pytest.raises(DataError, match=r"<system>: simulation: unknown key 'x_0'"):
        build_report("qib.thm1", _system(simulation={"x_0": [1, 2], "horizon": 1}))


def test_report_escapes_latex_for_html(small_report):
    # the LMI's relation and the \text{P > 0} label reach KaTeX through escaped HTML
    body = re.search(r'<div class="lmis">(.*?)</div>', small_report.html, re.S).group(1)
    assert "&gt;" in body and "<" not in body.replace("&lt;", "")
