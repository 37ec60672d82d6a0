"""Build the HTML report of one theorem on one system: one self-contained page.

The page holds, in order: the theorem as printed (its LMIs typeset by the vendored KaTeX), the
system (data, parameters, published values), the solution and the derived gains (compared with
the published ones where the system file has them), the certificate with its margins and
checks, the cross-check table over several backends, and the simulation figure (a base64 PNG).
Scripts, styles and fonts are inlined (:mod:`lmic.report.assets`), so the file opens offline.

Two small scripts leave traces in the DOM for automated checks: ``body[data-katex]`` counts
the typeset formulas once KaTeX ran, and the figure's ``img[data-loaded]`` is its
``naturalWidth`` once the image decoded.

Examples
--------
>>> print(matrix_latex([[1.0, 0.5], [-2.0, 1.5e-7]]))
\\begin{bmatrix}1 & 0.5 \\\\ -2 & 1.5 \\cdot 10^{-7}\\end{bmatrix}
>>> number_latex(-3e12)
'-3 \\\\cdot 10^{12}'
"""

from __future__ import annotations

import base64
import datetime as _dt
import os
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from lmic._version import __version__
from lmic.present.html import esc as _esc
from lmic.present.latex import matrix_latex, number_latex
from lmic.present.text import number_text

__all__ = ["Report", "build_report", "render_html", "matrix_latex", "number_latex", "MAX_LATEX_SIZE"]

#: matrices with more rows or columns than this are shown as plain tables, not typeset
MAX_LATEX_SIZE = 12


@dataclass
class Report:
    """A built report and what went into it.

    Attributes
    ----------
    html : str
        The page.
    result : lmic.api.Result
    crosscheck : lmic.crosscheck.CrosscheckReport or None
    trajectory : lmic.simulate.run.Trajectory or None
    simulation_note : str
        Why there is no figure (no observer, no ``simulation:`` section, gains not certified,
        the state blew up), or ``""``.
    """

    html: str
    result: Any
    crosscheck: Any = None
    trajectory: Any = None
    simulation_note: str = ""
    extras: dict[str, Any] = field(default_factory=dict)

    def write(self, path: str | os.PathLike[str]) -> None:
        """Write the page atomically (nothing half-written)."""
        from lmic.output import write_output

        write_output(path, self.html)

    def exit_code(self) -> int:
        """The solve's exit code (0 certified, 3 infeasible, 1 otherwise)."""
        return int(self.result.exit_code())


# -- formatting -------------------------------------------------------------------------------


def _is_numeric(value: Any) -> bool:
    if isinstance(value, bool) or value is None:
        return False
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        return False
    return arr.ndim <= 2 and arr.size > 0


def _value_html(name: str, value: Any) -> str:
    """``name = value`` typeset (or a plain table for a large matrix, or text)."""
    if not _is_numeric(value):
        return f'<div class="value no-math"><code>{_esc(name)}</code> = {_esc(value)}</div>'
    arr = np.atleast_2d(np.asarray(value, dtype=float))
    if max(arr.shape) > MAX_LATEX_SIZE:
        cells = "".join("<tr>" + "".join(f"<td>{number_text(float(v))}</td>" for v in row) + "</tr>" for row in arr)
        return (
            f'<div class="value no-math"><code>{_esc(name)}</code> ({arr.shape[0]} x {arr.shape[1]})'
            f'<table class="matrix">{cells}</table></div>'
        )
    return f'<div class="value">\\[{_esc(_latex_name(name))} = {_esc(matrix_latex(arr))}\\]</div>'


def _latex_name(name: str) -> str:
    """A variable name for LaTeX: ``Ybar`` -> ``\\bar{Y}``, ``gamma_max`` -> ``\\gamma_{max}``."""
    greek = {
        "alpha", "beta", "gamma", "delta", "epsilon", "eta", "lambda", "mu", "rho", "omega", "sigma", "tau",
        "xi", "zeta", "psi", "phi", "theta", "nu", "kappa",
    }  # fmt: skip
    base, _, sub = name.partition("_")
    if base.endswith("bar") and len(base) > 3:
        core = base[:-3]
        base_tex = rf"\bar{{{(chr(92) + core) if core in greek else core}}}"
    elif base.endswith("tilde") and len(base) > 5:
        base_tex = rf"\tilde{{{base[:-5]}}}"
    elif base.lower() in greek:
        base_tex = "\\" + base
    elif len(base) > 1 and base[1:].isdigit():
        base_tex = rf"{base[0]}_{{{base[1:]}}}"
    elif len(base) > 1:
        base_tex = rf"\mathrm{{{base}}}"
    else:
        base_tex = base
    if sub:
        return rf"{base_tex}_{{\mathrm{{{sub.replace('_', ',')}}}}}"
    return base_tex


def _table(headers: list[str], rows: list[list[str]], cls: str = "") -> str:
    """An HTML table; cells are already-escaped HTML."""
    head = "".join(f"<th>{_esc(h)}</th>" for h in headers)
    body = "".join("<tr>" + "".join(f"<td>{c}</td>" for c in row) + "</tr>" for row in rows)
    klass = f' class="{cls}"' if cls else ""
    return f"<table{klass}><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def _kv(rows: list[list[str]], cls: str = "kv no-math") -> str:
    """A two-column key/value table without a header; values are already-escaped HTML."""
    body = "".join(f"<tr><th>{_esc(k)}</th><td>{v}</td></tr>" for k, v in rows)
    return f'<table class="{cls}"><tbody>{body}</tbody></table>'


def _badge(text: str) -> str:
    good = text in (
        "certified",
        "infeasible-certified",
        "unbounded-certified",
        "feasible",
        "optimal",
        "ok",
        "yes",
        "agree",
        "decayed",
    )
    bad = text in ("rejected", "error", "infeasible", "VIOLATED", "FAILED", "no", "disagree", "did not decay")
    cls = "good" if good else ("bad" if bad else "warn")
    return f'<span class="badge {cls}">{_esc(text)}</span>'


# -- sections ---------------------------------------------------------------------------------


def _domain(domain: Any) -> str:
    """A parameter's domain typeset (``\\left[0, \\infty\\right)``)."""
    import sympy

    return "\\(" + _esc(sympy.latex(domain)) + "\\)"


def _theorem_section(thm: Any, tmpl: Any) -> str:
    from lmic.template.render import describe, theorem_latex

    d = describe(thm, tmpl)
    parts = [
        '<section id="theorem"><h2>Theorem</h2>',
        f'<p class="no-math"><b>{_esc(thm.id)}</b> — {_esc(thm.title)}<br>'
        f'<span class="cite">{_esc(thm.citation)}</span></p>',
        '<table class="kv no-math"><tbody>'
        f"<tr><th>kind</th><td>{'synthesis' if thm.kind == 'S' else 'analysis'} ({_esc(thm.kind)})</td></tr>"
        f"<tr><th>objective</th><td>{_esc(thm.objective)}</td></tr>"
        f"<tr><th>system class</th><td>{_esc(thm.system_class)}</td></tr>"
        "</tbody></table>",
    ]
    if thm.notes:
        parts.append(f'<p class="notes no-math">{_esc(thm.notes)}</p>')
    parts.append('<h3>The LMIs as printed</h3><div class="lmis">\\[' + _esc(theorem_latex(thm, tmpl)) + "\\]</div>")
    rows = [[f"<code>{_esc(x['name'])}</code>", _esc(x["shape"]), _esc(x["doc"])] for x in d["data"]]
    parts.append("<h3>Data</h3>" + _table(["name", "shape", "description"], rows, "no-math"))
    if d["params"] or d["options"]:
        rows = [
            [f"<code>{_esc(p.name)}</code>", _domain(p.domain), number_text(p.default), _esc(p.doc)]
            for p in tmpl.params
        ]
        rows += [
            [f"<code>{_esc(o['name'])}</code>", _esc(" | ".join(o["choices"])), _esc(o["default"]), _esc(o["doc"])]
            for o in d["options"]
        ]
        parts.append("<h3>Parameters</h3>" + _table(["name", "domain", "default", "description"], rows))
    rows = [
        [f"<code>{_esc(v['name'])}</code>", _esc(v["kind"]), _esc(v["shape"]), _esc(v["sign"])] for v in d["variables"]
    ]
    parts.append("<h3>Decision variables</h3>" + _table(["name", "kind", "shape", "sign"], rows, "no-math"))
    if d["checks"]:
        rows = [[_esc(c["name"]), _esc(c["kind"])] for c in d["checks"]]
        parts.append("<h3>Checks</h3>" + _table(["check", "kind"], rows, "no-math"))
    if thm.doc:
        parts.append(f'<details class="no-math"><summary>docstring</summary><pre>{_esc(thm.doc)}</pre></details>')
    parts.append("</section>")
    return "\n".join(parts)


def _system_section(system: Any, params: dict[str, Any]) -> str:
    parts = ['<section id="system"><h2>System</h2>']
    head = _esc(system.name or system.label)
    src = f'<br><span class="cite">{_esc(system.source)}</span>' if system.source else ""
    parts.append(f'<p class="no-math"><b>{head}</b> (<code>{_esc(system.label)}</code>){src}</p>')
    parts.append('<div class="values">' + "".join(_value_html(k, v) for k, v in system.data.items()) + "</div>")
    merged = {**system.params, **params}
    if merged:
        rows = [
            [f"<code>{_esc(k)}</code>", number_text(v, 8) + (" (from -p)" if k in params else "")]
            for k, v in merged.items()
        ]
        parts.append("<h3>Parameters</h3>" + _table(["name", "value"], rows, "no-math"))
    if system.published:
        parts.append("<h3>Published values</h3>")
        parts.append(
            '<div class="values">' + "".join(_value_html(k, v) for k, v in system.published.items()) + "</div>"
        )
    parts.append("</section>")
    return "\n".join(parts)


def _solution_section(result: Any, system: Any) -> str:
    sol = result.solution
    rows = [
        ["backend", _esc(result.backend)],
        ["status", _badge(result.status) + (f" ({_esc(sol.native_status)})" if sol.native_status else "")],
        ["objective", number_text(result.objective, 10)],
        ["strict inequalities", f"{_esc(sol.strategy)}, margin {number_text(sol.margin)}"],
    ]
    if sol.message:
        rows.append(["message", _esc(sol.message)])
    rows += [[k.replace("_s", "") + " time", f"{v:.3f} s"] for k, v in result.timings.items()]
    parts = ['<section id="solution"><h2>Solution</h2>', _kv(rows)]
    if result.derived:
        parts.append("<h3>Gains and derived quantities</h3>")
        parts.append('<div class="values">' + "".join(_value_html(k, v) for k, v in result.derived.items()) + "</div>")
        comparison = []
        for name, value in result.derived.items():
            pub = system.published.get(name)
            if pub is None or not _is_numeric(value) or not _is_numeric(pub):
                continue
            a, b = np.atleast_2d(np.asarray(value, float)), np.atleast_2d(np.asarray(pub, float))
            if a.shape != b.shape:
                comparison.append([f"<code>{_esc(name)}</code>", f"shapes differ: {a.shape} vs {b.shape}"])
                continue
            comparison.append([f"<code>{_esc(name)}</code>", number_text(float(np.max(np.abs(a - b))))])
        if comparison:
            parts.append(
                "<h3>Against the published values</h3>"
                + _table(["quantity", "max |computed - published|"], comparison, "no-math")
                + '<p class="cite no-math">A feasibility LMI has many solutions: a certified gain may differ '
                "from the published one; the certificate, not the distance, decides.</p>"
            )
    if result.variables:
        parts.append("<h3>Decision variables</h3>")
        parts.append(
            '<div class="values">' + "".join(_value_html(k, v) for k, v in result.variables.items()) + "</div>"
        )
    parts.append("</section>")
    return "\n".join(parts)


def _certificate_section(result: Any) -> str:
    cert = result.certificate_dict()
    parts = ['<section id="certificate"><h2>Certificate</h2>']
    reason = f" — {_esc(cert.get('reason'))}" if cert.get("reason") else ""
    parts.append(f'<p class="no-math">verdict {_badge(result.verdict)}{reason}</p>')
    rows = []
    for lmi in cert.get("lmis", []):
        strict = "strict" if lmi.get("strict") else "non-strict"
        rows.append(
            [
                _esc(lmi.get("name")),
                _esc(lmi.get("dim", "-")),
                strict,
                number_text(lmi.get("min_margin")),
                number_text(lmi.get("rel_margin")),
                number_text(lmi.get("threshold")),
                _badge("ok" if lmi.get("ok") else "VIOLATED"),
            ]
        )
    if rows:
        parts.append(
            "<h3>LMI margins</h3>"
            + _table(["LMI", "size", "", "min margin", "relative", "threshold", ""], rows, "margins no-math")
        )
    rows = [
        [
            _esc(c.get("name")),
            _esc(c.get("kind", "")),
            number_text(c.get("value")),
            number_text(c.get("bound")),
            _badge("ok" if c.get("ok") else "FAILED"),
        ]
        for c in cert.get("checks", [])
    ]
    if rows:
        parts.append("<h3>Checks</h3>" + _table(["check", "kind", "value", "bound", ""], rows, "checks no-math"))
    exact = cert.get("exact")
    if exact:
        parts.append(f'<p class="no-math">exact proof: <code>{_esc(exact)}</code></p>')
    parts.append("</section>")
    return "\n".join(parts)


def _crosscheck_section(report: Any, note: str) -> str:
    parts = ['<section id="crosscheck"><h2>Cross-check</h2>']
    if report is None:
        parts.append(f'<p class="no-math">{_esc(note or "not run")}</p></section>')
        return "\n".join(parts)
    rows = [
        [
            _esc(r["backend"]),
            _badge(r["status"]),
            number_text(r["objective"], 8),
            _badge(r["verdict"]),
            number_text(r["min_margin"]),
            number_text(r["solve_s"], 3),
        ]
        for r in report.results
    ]
    parts.append(
        _table(["backend", "status", "objective", "verdict", "min margin", "solve (s)"], rows, "crosscheck no-math")
    )
    gap = report.max_rel_objective_gap
    parts.append(
        f'<p class="no-math">{_badge("agree" if report.agree else "disagree")} '
        f"largest relative objective gap {number_text(gap)} (tolerance {report.rtol:g})</p>"
    )
    parts.append("</section>")
    return "\n".join(parts)


def _simulation_section(traj: Any, png: bytes | None, note: str, observer: Any) -> str:
    parts = ['<section id="simulation"><h2>Simulation</h2>']
    if traj is None or png is None:
        parts.append(f'<p class="no-math">{_esc(note)}</p></section>')
        return "\n".join(parts)
    s = traj.summary()
    rows = [
        ["observer", f"{_esc(observer.name)} ({_esc(observer.time)} time)"],
        ["horizon", f"{number_text(s['horizon'])} ({s['points']} points"
         + (f", {s['samples']} samples)" if s["samples"] is not None else ")")],
        ["initial error", number_text(s["initial_error"])],
        ["peak error", number_text(s["peak_error"])],
        ["final error", number_text(s["final_error"])],
        ["error", _badge("decayed" if s["decayed"] else "did not decay")],
    ]  # fmt: skip
    for c in getattr(traj, "checks", []):
        word = {True: "ok", False: "VIOLATED", None: "informative"}[c.get("ok")]
        rows.append(
            [
                c["property"],
                f"certified {number_text(c['certified'])}, measured {number_text(c['measured'])} "
                f"{_badge(word)}<br><small>{_esc(c['detail'])}</small>",
            ]
        )
    if any(c.get("ok") is False for c in getattr(traj, "checks", [])):
        parts.append(
            '<p class="bad"><strong>Red flag:</strong> the trajectory violates what the theorem certified: '
            "the theorem, its transcription or the certificate is wrong.</p>"
        )
    parts.append(_kv(rows))
    data = base64.b64encode(png).decode("ascii")
    parts.append(
        '<figure><img id="simulation-plot" alt="true and estimated states and the estimation error norm" '
        f'src="data:image/png;base64,{data}" '
        "onload=\"this.setAttribute('data-loaded', String(this.naturalWidth))\">"
        "<figcaption>True states (solid), estimates (dashed), reconstructed unknown inputs and the "
        "control input where the observer has them, and the error norm (log scale).</figcaption>"
        "</figure>"
    )
    parts.append("</section>")
    return "\n".join(parts)


_CSS = """
body { font-family: system-ui, -apple-system, "Segoe UI", Roboto, sans-serif; color: #1d2433; margin: 0;
       background: #f6f7f9; }
main { max-width: 1120px; margin: 0 auto; padding: 1.5rem 2rem 4rem; background: #fff; }
header { border-bottom: 3px solid #1f4e9c; margin-bottom: 1rem; }
h1 { font-size: 1.6rem; margin: 0.4rem 0; } h2 { font-size: 1.3rem; border-bottom: 1px solid #d5dae3;
     padding-bottom: 0.2rem; margin-top: 2rem; } h3 { font-size: 1.05rem; margin: 1.2rem 0 0.4rem; }
nav a { margin-right: 1rem; color: #1f4e9c; text-decoration: none; }
.cite { color: #5b6478; font-size: 0.92rem; } .notes { background: #fff8e6; padding: 0.5rem 0.8rem;
     border-left: 3px solid #e6a700; }
table { border-collapse: collapse; margin: 0.4rem 0; font-size: 0.92rem; }
th, td { border: 1px solid #d5dae3; padding: 0.25rem 0.6rem; text-align: left; vertical-align: top; }
thead th { background: #eef1f6; } table.kv th { background: #f3f5f9; font-weight: 600; }
table.matrix td { font-family: ui-monospace, monospace; text-align: right; }
.values { display: flex; flex-wrap: wrap; gap: 0 2.5rem; align-items: center; } .value { max-width: 100%; }
.katex-display { margin: 0.6em 0; }
.lmis .katex-display > .katex { overflow-x: auto; overflow-y: hidden; padding: 0.2em 0; }
.lmis { font-size: 0.95rem; }
.badge { display: inline-block; padding: 0 0.45rem; border-radius: 0.6rem; font-size: 0.85rem; font-weight: 600; }
.badge.good { background: #d3f9d8; color: #2b8a3e; } .badge.bad { background: #ffe3e3; color: #c92a2a; }
.badge.warn { background: #fff3bf; color: #8a6100; }
figure { margin: 0.8rem 0; } figure img { max-width: 100%; height: auto; border: 1px solid #d5dae3; }
figcaption { color: #5b6478; font-size: 0.88rem; } pre { white-space: pre-wrap; font-size: 0.85rem; }
footer { margin-top: 3rem; color: #5b6478; font-size: 0.85rem; }
"""

_RENDER = """
(function () {
  var body = document.body;
  try {
    renderMathInElement(body, {
      delimiters: [{left: "\\\\[", right: "\\\\]", display: true}, {left: "\\\\(", right: "\\\\)", display: false}],
      ignoredClasses: ["no-math"], throwOnError: false
    });
    body.setAttribute("data-katex", String(document.querySelectorAll(".katex").length));
    body.setAttribute("data-katex-errors", String(document.querySelectorAll(".katex-error").length));
  } catch (err) {
    body.setAttribute("data-katex", "failed: " + err);
  }
  var img = document.getElementById("simulation-plot");
  if (img && img.complete && img.naturalWidth) img.setAttribute("data-loaded", String(img.naturalWidth));
})();
"""


def render_html(
    title: str,
    sections: list[str],
    subtitle: str = "",
) -> str:
    """Assemble a page: inlined KaTeX (styles, fonts, scripts), the sections, a footer."""
    from lmic.report.assets import KATEX_VERSION, katex_css, katex_js

    stamp = _dt.datetime.now(_dt.UTC).strftime("%Y-%m-%d %H:%M UTC")
    nav = "".join(
        f'<a href="#{s}">{s}</a>' for s in ("theorem", "system", "solution", "certificate", "crosscheck", "simulation")
    )
    return (
        '<!DOCTYPE html>\n<html lang="en">\n<head>\n<meta charset="utf-8">\n'
        '<meta name="viewport" content="width=device-width, initial-scale=1">\n'
        f"<title>{_esc(title)}</title>\n"
        f'<meta name="generator" content="lmic {__version__}">\n'
        f"<style>{katex_css()}</style>\n<style>{_CSS}</style>\n</head>\n<body>\n<main>\n"
        f'<header><h1 class="no-math">{_esc(title)}</h1><p class="no-math">{subtitle}</p>'
        f'<nav class="no-math">{nav}</nav></header>\n'
        + "\n".join(sections)
        + f'\n<footer class="no-math">Generated by lmic {__version__} on {stamp}. '
        f"Mathematics typeset with KaTeX {KATEX_VERSION} (MIT licence), embedded in this file.</footer>\n"
        f"</main>\n<script>{katex_js()}</script>\n<script>{_RENDER}</script>\n</body>\n</html>\n"
    )


# -- building ---------------------------------------------------------------------------------


def build_report(
    theorem: str,
    system: Any,
    params: dict[str, Any] | None = None,
    backend: str | None = None,
    crosscheck_backends: list[str] | None = None,
    run_crosscheck: bool = True,
    run_simulation: bool = True,
    options: Any = None,
) -> Report:
    """Solve, certify, cross-check and simulate ``theorem`` on ``system``; build the page.

    Parameters
    ----------
    theorem : str
        A theorem id.
    system : path, dict or lmic.system.System
    params : dict, optional
        Parameter overrides (``-p``).
    backend : str
        The backend of the main solve.
    crosscheck_backends : list of str, optional
        Backends of the cross-check (default: every available one).
    run_crosscheck, run_simulation : bool
        Skip those sections (they then say why).
    options : lmic.backends.base.SolveOptions, optional

    Returns
    -------
    Report

    Raises
    ------
    LmicError
        Bad input: an unknown theorem, a malformed system file or ``simulation:`` section (a
        state that blows up is *reported* in the page, not raised).
    """
    from lmic.api import solve
    from lmic.registry import get_theorem
    from lmic.system import load_system

    params = dict(params or {})
    sysobj = load_system(system)
    thm = get_theorem(theorem)
    section = sysobj.raw.get("simulation")
    if run_simulation and section is not None:
        from lmic.simulate.run import check_section

        check_section(section, f"{sysobj.label}: simulation")  # bad input fails before any solve
    tmpl = thm.template({**sysobj.params, **params})
    result = solve(theorem, system=sysobj, params=params or None, backend=backend, options=options)

    xreport, xnote = None, ""
    if run_crosscheck:
        from lmic.studies.crosscheck import crosscheck

        # the system as given (a path or a mapping): crosscheck labels its report with it
        source = sysobj.path if sysobj.path else sysobj.raw
        xreport = crosscheck(
            theorem, system=source, params=params or None, backends=crosscheck_backends, options=options
        )
    else:
        xnote = "Cross-check not run (--no-crosscheck)."

    traj, png, observer, note = None, None, None, ""
    if not run_simulation:
        note = "Simulation not run (--no-simulation)."
    elif section is None:
        note = f"{sysobj.label} has no 'simulation:' section: nothing to simulate."
    elif not result.problem.meta.get("observer"):
        note = f"Theorem {theorem} declares no observer (t.observer(...)): nothing to simulate."
    elif result.exit_code() != 0:
        note = f"No certified gains (status {result.status}, verdict {result.verdict}): nothing simulated."
    else:
        from lmic.simulate.plot import plot_png
        from lmic.simulate.run import SimulationDiverged, simulate

        try:
            observer, traj = simulate(result.problem, result.solution.x, sysobj)
        except SimulationDiverged as err:
            note = f"The simulation failed: {err}"
        else:
            png = plot_png(traj, title=theorem)

    verdict = _badge(result.verdict)
    subtitle = f"{_esc(thm.title)} &nbsp;·&nbsp; system <code>{_esc(sysobj.label)}</code> &nbsp;·&nbsp; {verdict}"
    sections = [
        _theorem_section(thm, tmpl),
        _system_section(sysobj, params),
        _solution_section(result, sysobj),
        _certificate_section(result),
        _crosscheck_section(xreport, xnote),
        _simulation_section(traj, png, note, observer),
    ]
    page = render_html(f"lmic report: {theorem}", sections, subtitle)
    return Report(page, result, xreport, traj, note, {"plot_bytes": len(png) if png else 0})
