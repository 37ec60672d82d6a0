"""The vendored KaTeX bundle, inlined into one self-contained report page.

``lmic/report/assets/`` holds KaTeX |version| exactly as published on npm (``katex.min.js``,
``katex.min.css``, ``contrib/auto-render.min.js`` as ``auto-render.min.js``, the ``woff2``
fonts) and its licence (``LICENSE-KaTeX.txt``, MIT). No machine that opens a report needs the
internet: :func:`katex_css` rewrites every ``@font-face`` of the stylesheet to a base64
``data:`` URI of its woff2 font (dropping the woff/ttf fallbacks, which every current browser
does without), and :func:`katex_js` returns the two scripts to inline.

Examples
--------
>>> css = katex_css()
>>> "url(fonts/" in css, css.count("data:font/woff2;base64,") == len(FONT_FILES)
(False, True)
>>> "renderMathInElement" in katex_js()
True
"""

from __future__ import annotations

import base64
import re
from functools import cache
from importlib import resources

from lmic.errors import LmicError

__all__ = ["KATEX_VERSION", "FONT_FILES", "katex_css", "katex_js", "asset_text", "asset_bytes"]

#: the vendored KaTeX release (``npm pack katex@0.19.1``)
KATEX_VERSION = "0.19.1"

#: the woff2 fonts the stylesheet references
FONT_FILES = (
    "KaTeX_AMS-Regular",
    "KaTeX_Caligraphic-Bold",
    "KaTeX_Caligraphic-Regular",
    "KaTeX_Fraktur-Bold",
    "KaTeX_Fraktur-Regular",
    "KaTeX_Main-Bold",
    "KaTeX_Main-BoldItalic",
    "KaTeX_Main-Italic",
    "KaTeX_Main-Regular",
    "KaTeX_Math-BoldItalic",
    "KaTeX_Math-Italic",
    "KaTeX_SansSerif-Bold",
    "KaTeX_SansSerif-Italic",
    "KaTeX_SansSerif-Regular",
    "KaTeX_Script-Regular",
    "KaTeX_Size1-Regular",
    "KaTeX_Size2-Regular",
    "KaTeX_Size3-Regular",
    "KaTeX_Size4-Regular",
    "KaTeX_Typewriter-Regular",
)

_FONT_SRC = re.compile(
    r'src:url\(fonts/(?P<name>[A-Za-z0-9_-]+)\.woff2\) format\("woff2"\)(?:,url\([^)]*\) format\("[a-z]+"\))*'
)


def _resource(name: str) -> resources.abc.Traversable:
    return resources.files("lmic.report").joinpath("assets", *name.split("/"))


def asset_bytes(name: str) -> bytes:
    """The bytes of ``lmic/report/assets/<name>``; :class:`LmicError` if it is missing."""
    try:
        return _resource(name).read_bytes()
    except (FileNotFoundError, OSError) as err:
        raise LmicError(f"report asset '{name}' is missing from the lmic package ({err})") from None


def asset_text(name: str) -> str:
    """The text of ``lmic/report/assets/<name>`` (UTF-8)."""
    return asset_bytes(name).decode("utf-8")


@cache
def katex_css() -> str:
    """KaTeX's stylesheet with every font inlined as a woff2 ``data:`` URI."""
    css = asset_text("katex.min.css")

    def inline(m: re.Match[str]) -> str:
        data = base64.b64encode(asset_bytes(f"fonts/{m.group('name')}.woff2")).decode("ascii")
        return f'src:url(data:font/woff2;base64,{data}) format("woff2")'

    out = _FONT_SRC.sub(inline, css)
    if "url(fonts/" in out:
        raise LmicError("report asset katex.min.css references a font the inliner did not replace")
    return out


@cache
def katex_js() -> str:
    """``katex.min.js`` followed by the auto-render extension, safe to put in ``<script>``."""
    js = asset_text("katex.min.js") + "\n" + asset_text("auto-render.min.js")
    if "</script" in js.lower():
        raise LmicError("report assets: a script contains '</script' and cannot be inlined")
    return js
