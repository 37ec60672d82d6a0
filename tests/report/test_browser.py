"""Open the report in a real browser (Debian's ``chromium``, headless) and check what a reader
sees: the LaTeX is typeset by KaTeX (no raw TeX left in the visible text, no KaTeX error), the
figure decoded (``naturalWidth > 0``), and the tables are there. Skipped only when chromium is
not installed (CI installs it: ``apt-get install -y chromium``)."""

from __future__ import annotations

import shutil
import subprocess
from html.parser import HTMLParser

import pytest

CHROMIUM = shutil.which("chromium")

pytestmark = pytest.mark.skipif(CHROMIUM is None, reason="chromium is not installed (apt-get install -y chromium)")

FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--virtual-time-budget=5000",
]


class Visible(HTMLParser):
    """The visible text (no script, style, or KaTeX's hidden MathML annotation with the TeX
    source), the attributes of every element, and the classes seen."""

    HIDDEN = ("script", "style", "annotation", "title")

    def __init__(self) -> None:
        super().__init__()
        self.depth = 0
        self.text: list[str] = []
        self.elements: list[tuple[str, dict[str, str]]] = []

    def handle_starttag(self, tag, attrs):
        self.elements.append((tag, {k: v or "" for k, v in attrs}))
        if tag in self.HIDDEN:
            self.depth += 1

    def handle_endtag(self, tag):
        if tag in self.HIDDEN and self.depth:
            self.depth -= 1

    def handle_data(self, data):
        if not self.depth:
            self.text.append(data)

    def with_class(self, cls: str) -> list[dict[str, str]]:
        return [a for _, a in self.elements if cls in a.get("class", "").split()]


def chromium(*args: str, tmp_path) -> subprocess.CompletedProcess:
    profile = tmp_path / "profile"
    profile.mkdir(exist_ok=True)
    return subprocess.run(
        [CHROMIUM, *FLAGS, f"--user-data-dir={profile}", *args],
        capture_output=True,
        text=True,
        timeout=90,
        check=False,
    )


def test_report_renders_in_chromium(small_report_file, tmp_path):
    run = chromium("--dump-dom", small_report_file.as_uri(), tmp_path=tmp_path)
    assert run.returncode == 0, run.stderr[-2000:]
    dom = Visible()
    dom.feed(run.stdout)
    body = next(a for t, a in dom.elements if t == "body")
    # KaTeX ran and typeset every formula without an error
    assert int(body["data-katex"]) >= 5, body
    assert body["data-katex-errors"] == "0"
    assert len(dom.with_class("katex")) == int(body["data-katex"])
    assert dom.with_class("katex-display")  # the display-mode LMIs and matrices
    text = "".join(dom.text)
    for raw in (r"\begin{bmatrix}", r"\prec", r"\star", "\\[", "\\("):
        assert raw not in text, f"raw TeX {raw!r} left in the visible text"
    # the figure decoded
    img = next(a for t, a in dom.elements if a.get("id") == "simulation-plot")
    assert int(img["data-loaded"]) > 0
    # the tables
    tables = " ".join(a.get("class", "") for t, a in dom.elements if t == "table")
    for cls in ("margins", "checks", "crosscheck"):
        assert cls in tables
    assert "certified" in text and "decayed" in text


def test_report_screenshot_is_not_blank(small_report_file, tmp_path):
    shot = tmp_path / "report.png"
    run = chromium("--window-size=1200,2400", f"--screenshot={shot}", small_report_file.as_uri(), tmp_path=tmp_path)
    assert run.returncode == 0, run.stderr[-2000:]
    from matplotlib.image import imread

    pixels = imread(shot)
    assert pixels.shape[0] == 2400 and pixels.shape[1] == 1200
    assert pixels[..., :3].std() > 0.05  # text, formulas and the figure, not an empty page
