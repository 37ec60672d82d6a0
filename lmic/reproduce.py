"""Run every shipped example and compare with what the papers print and the catalogues computed.

The expectations live in ``examples/reproduction.yaml``: for each example file, one row per
quantity with the published value, the catalogue's reference value and tolerance, the expected
verdict and, where they differ, the catalogue's explanation (with its line reference). Every row
says how lmic computes the quantity (``compute:``), one of::

    claim: KEY            the audit of the file's published: section (lmic.published), the claim
                          covering KEY (of kind: K if given); with lmi: NAME (the paper's extreme
                          eigenvalue of that LMI), derived: NAME, check: NAME, or the computed
                          value of a value claim
    solve: {}             the theorem on the file (objective kept); with derived: NAME,
                          variable: NAME or objective: true (else the outcome only)
    at_published: NAME    a derived quantity computed from the printed numbers (not certified),
                          compared with the printed NAME (or published_key: KEY)
    maximize: PARAM       supremum by bisection (lmic.sweep.maximize); rtol, lo, hi
    sweep: P=a:b:n        grid (lmic.sweep.sweep): certified if some point is, else infeasible
    gain: KEY             the printed gain KEY through another theorem's fixed_KEY variant
                          (with theorem: and system:), e.g. a Theorem-4 gain as a Theorem-1 gain

Common keys: ``theorem:`` (default: the file's), ``params:`` (overrides), ``gain:`` with
``maximize`` (bisection on the fixed-gain variant).

A row agrees when lmic's finding equals the expected verdict and, when a numeric reference is
given, ``|computed - reference| <= tol`` (max over entries for matrices).

Examples
--------
>>> spec = {"quantity": "q", "compute": {"solve": {}}, "verdict": "certified"}
>>> Row.from_dict("thesis.lyapunov.ex2_3_2.yaml", spec).theorem
'thesis.lyapunov'
"""

from __future__ import annotations

import fnmatch
import os
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from lmic.errors import DataError, LmicError

__all__ = [
    "Row",
    "RowResult",
    "ReproductionReport",
    "theorem_of",
    "load_expectations",
    "reproduce",
    "render_markdown",
    "default_examples_dir",
]

_COMPUTE_KINDS = ("claim", "solve", "at_published", "maximize", "sweep", "gain")
_VERDICTS = (
    "certified",
    "infeasible",
    "infeasible-bounded",
    "rejected",
    "not reproducible",
    "matches",
    "differs",
    "skipped",
)


def theorem_of(filename: str) -> str:
    """The theorem id of an example file ``<family>.<item>.<name>.yaml``.

    >>> theorem_of("qib.thm1.flexible-joint.yaml"), theorem_of("thesis.thm3_2_1.ex3_2_1.yaml")
    ('qib.thm1', 'thesis.thm3_2_1')
    """
    parts = os.path.basename(filename).split(".")
    if len(parts) < 4 or parts[-1] not in ("yaml", "yml", "json"):
        raise DataError(f"{filename}: example files are named <family>.<item>.<name>.yaml")
    return f"{parts[0]}.{parts[1]}"


def default_examples_dir() -> Path:
    """``./examples`` if it exists, else the ``examples`` folder next to the installed package."""
    here = Path.cwd() / "examples"
    if here.is_dir():
        return here
    return Path(__file__).resolve().parent.parent / "examples"


@dataclass
class Row:
    """One expectation: a quantity of one example file."""

    file: str
    quantity: str
    compute: dict[str, Any]
    theorem: str
    published: Any = None
    reference: Any = None
    tol: float | None = None
    verdict: str = "certified"
    catalogue: str = ""
    explanation: str = ""

    @classmethod
    def from_dict(cls, file: str, spec: dict[str, Any]) -> Row:
        """Validate one row of the expectations file (raises :class:`DataError`)."""
        where = f"reproduction.yaml: {file}"
        if not isinstance(spec, dict):
            raise DataError(f"{where}: each row is a mapping")
        unknown = set(spec) - {
            "quantity",
            "compute",
            "published",
            "reference",
            "tol",
            "verdict",
            "catalogue",
            "explanation",
        }
        if unknown:
            raise DataError(f"{where}: unknown key(s) {sorted(unknown)}")
        if "quantity" not in spec or "compute" not in spec:
            raise DataError(f"{where}: a row needs 'quantity' and 'compute'")
        compute = spec["compute"]
        if not isinstance(compute, dict) or sum(k in compute for k in _COMPUTE_KINDS) < 1:
            raise DataError(f"{where}, {spec['quantity']!r}: compute needs one of {', '.join(_COMPUTE_KINDS)}")
        verdict = str(spec.get("verdict", "certified"))
        if verdict not in _VERDICTS:
            raise DataError(f"{where}, {spec['quantity']!r}: verdict {verdict!r} is not one of {', '.join(_VERDICTS)}")
        tol = spec.get("tol")
        if tol is not None:
            tol = float(tol)
        return cls(
            file=file,
            quantity=str(spec["quantity"]),
            compute=dict(compute),
            theorem=str(compute.get("theorem") or theorem_of(file)),
            published=spec.get("published"),
            reference=spec.get("reference"),
            tol=tol,
            verdict=verdict,
            catalogue=str(spec.get("catalogue", "")),
            explanation=" ".join(str(spec.get("explanation", "")).split()),
        )


@dataclass
class RowResult:
    """What lmic computed for a row, and whether it agrees with the expectation."""

    row: Row
    finding: str
    value: Any = None
    text: str = ""
    verdict_ok: bool = False
    value_ok: bool | None = None
    detail: str = ""
    time_s: float = 0.0

    @property
    def ok(self) -> bool:
        """The expected verdict, and the reference value within tolerance (when numeric)."""
        return self.verdict_ok and self.value_ok is not False

    def to_dict(self) -> dict[str, Any]:
        """JSON-able form."""
        from lmic.jsonable import to_jsonable

        r = self.row
        return to_jsonable(
            {
                "file": r.file,
                "theorem": r.theorem,
                "quantity": r.quantity,
                "published": r.published,
                "computed": self.value,
                "computed_text": self.text,
                "finding": self.finding,
                "expected_verdict": r.verdict,
                "reference": r.reference,
                "tol": r.tol,
                "verdict_ok": self.verdict_ok,
                "value_ok": self.value_ok,
                "ok": self.ok,
                "detail": self.detail,
                "catalogue": r.catalogue,
                "explanation": r.explanation,
                "time_s": self.time_s,
            }
        )


@dataclass
class ReproductionReport:
    """Every row of every example, plus the examples that have no expectation."""

    results: list[RowResult]
    unlisted: list[str] = field(default_factory=list)
    missing: list[str] = field(default_factory=list)
    backend: str = "auto"
    total_s: float = 0.0
    file_times: dict[str, float] = field(default_factory=dict)

    def exit_code(self) -> int:
        """0 when every row agrees with its expectation, 1 otherwise."""
        return 0 if all(r.ok for r in self.results) and not self.missing else 1

    def to_dict(self) -> dict[str, Any]:
        """The ``--json`` object."""
        from lmic._version import __version__

        return {
            "lmic": __version__,
            "backend": self.backend,
            "rows": [r.to_dict() for r in self.results],
            "agree": sum(r.ok for r in self.results),
            "disagree": sum(not r.ok for r in self.results),
            "unlisted_examples": self.unlisted,
            "missing_examples": self.missing,
            "file_times": self.file_times,
            "total_s": self.total_s,
            "exit_code": self.exit_code(),
        }


def load_expectations(path: str | os.PathLike[str]) -> dict[str, list[Row]]:
    """Read ``reproduction.yaml``: ``{file name: [Row, ...]}`` (raises :class:`DataError`)."""
    p = Path(path)
    from lmic.limits import load_yaml_text, read_text

    if not p.exists():
        raise DataError(f"{p}: no such file")
    raw = load_yaml_text(read_text(p, p.name), p.name)  # the input limits of lmic.limits
    if not isinstance(raw, dict) or not isinstance(raw.get("examples"), dict):
        raise DataError(f"{p.name}: expected a mapping with an 'examples' section")
    out: dict[str, list[Row]] = {}
    for file, rows in raw["examples"].items():
        if not isinstance(rows, list) or not rows:
            raise DataError(f"{p.name}: {file}: a list of rows is expected")
        out[str(file)] = [Row.from_dict(str(file), r) for r in rows]
    return out


# --------------------------------------------------------------------------------------------
# computing one row


def _scalar(v: Any) -> Any:
    if isinstance(v, np.ndarray):
        return float(v.reshape(-1)[0]) if v.size == 1 else v.tolist()
    if isinstance(v, list):
        arr = np.asarray(v, dtype=float)
        return float(arr.reshape(-1)[0]) if arr.size == 1 else v
    return v


def _fmt(v: Any, digits: int = 4) -> str:
    if v is None:
        return "-"
    if isinstance(v, bool):
        return str(v)
    if isinstance(v, int | float):
        return f"{float(v):.{max(digits, 6)}g}"
    if isinstance(v, list | np.ndarray):
        arr = np.atleast_2d(np.asarray(v, dtype=float))
        return "[" + "; ".join(" ".join(f"{e:.{digits}g}" for e in row) for row in arr) + "]"
    return str(v)


class _Runner:
    """Caches per file: the loaded system, the audit and the theorem's own solution."""

    def __init__(self, examples: Path, backend: str, options: Any) -> None:
        self.examples, self.backend, self.options = examples, backend, options
        self._audits: dict[tuple, Any] = {}
        self._solves: dict[tuple, Any] = {}

    def path(self, file: str) -> Path:
        p = self.examples / file
        if not p.is_file():
            raise DataError(f"{p}: no such example file")
        return p

    def audit(self, row: Row) -> Any:
        from lmic.published import audit_published

        params = dict(row.compute.get("params") or {})
        key = (row.file, row.theorem, tuple(sorted(params.items())))
        if key not in self._audits:
            self._audits[key] = audit_published(
                row.theorem, self.path(row.file), params or None, backend=self.backend, options=self.options
            )
        return self._audits[key]

    def solve(self, row: Row) -> tuple[Any, Any]:
        from lmic.compile import compile_theorem
        from lmic.sweep import decide

        params = dict(row.compute.get("params") or {})
        key = (row.file, row.theorem, tuple(sorted(params.items())))
        if key not in self._solves:
            problem = compile_theorem(row.theorem, self.path(row.file), params or None)
            self._solves[key] = (problem, decide(problem, self.backend, self.options, keep_objective=True))
        return self._solves[key]

    def gain_system(self, row: Row, key: str, system: Path) -> tuple[Any, dict[str, Any]]:
        """``system`` with the printed gain ``key`` of the row's file added as data, and ``fixed_key: 1``."""
        from lmic.system import System, load_system

        source = load_system(self.path(row.file))
        if key not in source.published:
            raise DataError(f"{row.file}: publishes no '{key}'")
        target = load_system(system)
        data = dict(target.data)
        data[key] = np.atleast_2d(np.asarray(source.published[key], dtype=float))
        params = dict(target.params)
        params[f"fixed_{key}"] = "1"
        params.update(row.compute.get("params") or {})
        sysobj = System(data, params, {}, target.name, target.source, target.path, target.raw)
        return sysobj, params


def _outcome_finding(outcome: str) -> str:
    return {"feasible": "certified", "infeasible": "infeasible", "infeasible-bounded": "infeasible-bounded"}.get(
        outcome, "not reproducible"
    )


def _point_value(row: Row, problem: Any, pt: Any) -> tuple[Any, str]:
    c = row.compute
    if pt.x is None:
        return None, pt.proof
    env = problem.environment(pt.x)
    if "derived" in c:
        return _scalar(env[c["derived"]]), ""
    if "variable" in c:
        return _scalar(env[c["variable"]]), ""
    if c.get("objective"):
        return pt.objective, ""
    return None, ""


def _compute(runner: _Runner, row: Row) -> tuple[str, Any, str, str]:
    """(finding, value, text, detail) for one row."""
    c = row.compute
    if "claim" in c:
        rep = runner.audit(row)
        try:
            claim = rep.claim(str(c["claim"]), c.get("kind"))
        except KeyError as err:
            raise DataError(f"{row.file}: {err.args[0]}") from None
        value: Any = None
        if "lmi" in c:
            match = [e for e in claim.lmis if e["name"] == c["lmi"]]
            if not match:
                raise DataError(f"{row.file}: the claim on '{c['claim']}' has no LMI named {c['lmi']!r}")
            value = match[0]["extreme"]
            text = f"{match[0]['which']} {_fmt(value)}"
        elif "derived" in c:
            value = claim.derived.get(c["derived"])
            text = f"{c['derived']} = {_fmt(value)}"
        elif "check" in c:
            match = [e for e in claim.checks if e["name"] == c["check"]]
            value = match[0]["value"] if match else None
            text = f"{c['check']}: {_fmt(value)}"
        elif claim.kind == "value":
            value = _scalar(claim.computed)
            text = _fmt(value)
        else:
            text = claim.proof or claim.finding
        return claim.finding, value, text, claim.reason
    if "solve" in c:
        problem, pt = runner.solve(row)
        value, why = _point_value(row, problem, pt)
        finding = _outcome_finding(pt.outcome)
        text = _fmt(value) if value is not None else (pt.proof or finding)
        return finding, value, text, pt.proof or why
    if "at_published" in c:
        from lmic.published import _Auditor

        auditor = _Auditor(row.theorem, runner.path(row.file), c.get("params"), runner.backend, runner.options, 0.05)
        auditor.point_claims(auditor.sysobj.published)
        value = auditor.derived_at_published(str(c["at_published"]))
        if value is None:
            return "not reproducible", None, "-", "not computable from the printed numbers"
        value = _scalar(value)
        key = str(c.get("published_key", c["at_published"]))
        pub = auditor.sysobj.published.get(key)
        if pub is None:
            return "not reproducible", value, _fmt(value), f"{row.file} publishes no '{key}'"
        claim = auditor._compare(key, pub, value, "the published numbers", True)
        return claim.finding, value, _fmt(value), claim.reason
    if "maximize" in c:
        from lmic.sweep import maximize

        system: Any = runner.path(row.file)
        params = dict(c.get("params") or {})
        if "gain" in c:
            system, _ = runner.gain_system(row, str(c["gain"]), runner.path(row.file))
        res = maximize(
            row.theorem,
            system,
            str(c["maximize"]),
            lo=c.get("lo"),
            hi=c.get("hi"),
            rtol=float(c.get("rtol", 1e-4)),
            xtol=float(c.get("xtol", 1e-6)),
            params=params or None,
            backend=runner.backend,
            options=runner.options,
        )
        if res.lower is None:
            finding = "infeasible" if res.exit_code() == 3 else "not reproducible"
            return finding, None, "no certified value", res.message
        text = f"[{res.lower:.6g}, {_fmt(res.upper)}]"
        detail = f"lower certified, upper {res.upper_kind}; {res.iterations} bisection steps, {len(res.points)} points"
        return "certified", res.lower, text, detail
    if "sweep" in c:
        from lmic.sweep import parse_grid, sweep

        name, values = parse_grid(str(c["sweep"]))
        swept = sweep(
            row.theorem,
            runner.path(row.file),
            name,
            values,
            params=c.get("params"),
            backend=runner.backend,
            options=runner.options,
        )
        ok = [p.value for p in swept.points if p.outcome == "feasible"]
        if ok:
            text = f"certified at {name} = {', '.join(f'{v:g}' for v in ok)}"
            return "certified", (swept.best.value if swept.best else None), text, f"{len(values)} points"
        finding = "infeasible" if swept.exit_code() == 3 else "not reproducible"
        return finding, None, f"no certified point in {len(values)}", ""
    if "gain" in c:
        from lmic.compile import compile_theorem
        from lmic.sweep import decide

        system_file = runner.path(str(c.get("system", row.file)))
        sysobj, _ = runner.gain_system(row, str(c["gain"]), system_file)
        problem = compile_theorem(row.theorem, sysobj)
        pt = decide(problem, runner.backend, runner.options, keep_objective=True)
        value, why = _point_value(row, problem, pt)
        finding = _outcome_finding(pt.outcome)
        return finding, value, _fmt(value) if value is not None else (pt.proof or finding), pt.proof or why
    raise DataError(f"{row.file}: {row.quantity!r}: nothing to compute")


def _judge(row: Row, finding: str, value: Any) -> tuple[bool, bool | None]:
    verdict_ok = finding == row.verdict
    ref = row.reference
    if ref is None or isinstance(ref, str) or isinstance(ref, bool):
        return verdict_ok, None
    if value is None:
        return verdict_ok, False
    try:
        a = np.atleast_2d(np.asarray(value, dtype=float))
        b = np.atleast_2d(np.asarray(ref, dtype=float))
    except (TypeError, ValueError):
        return verdict_ok, False
    if a.shape != b.shape:
        return verdict_ok, False
    tol = row.tol if row.tol is not None else 1e-3
    return verdict_ok, bool(np.max(np.abs(a - b)) <= tol * (1 + 1e-9))


def reproduce(
    examples: str | os.PathLike[str] | None = None,
    expectations: str | os.PathLike[str] | None = None,
    *,
    only: Sequence[str] = (),
    backend: str = "auto",
    options: Any = None,
    progress: Callable[[dict[str, Any]], None] | None = None,
) -> ReproductionReport:
    """Run every example (or those matching ``only``) against its expectations.

    Parameters
    ----------
    examples : path, optional
        The examples folder (default :func:`default_examples_dir`).
    expectations : path, optional
        Default ``<examples>/reproduction.yaml``.
    only : sequence of str
        Glob patterns on file names (``qib.*``); empty = every example.
    backend : str
    options : SolveOptions, optional
    progress : callable, optional
        Called after each row with ``{"done", "total", "file", "row"}``.

    Returns
    -------
    ReproductionReport

    Examples
    --------
    >>> rep = reproduce(only=["thesis.lyapunov.*"])                       # doctest: +SKIP
    >>> [r.finding for r in rep.results]                                  # doctest: +SKIP
    ['certified', 'certified', 'certified']
    """
    t0 = time.perf_counter()
    folder = Path(examples) if examples is not None else default_examples_dir()
    if not folder.is_dir():
        raise DataError(f"{folder}: no examples folder")
    spec = load_expectations(expectations if expectations is not None else folder / "reproduction.yaml")
    files = sorted(p.name for p in folder.iterdir() if p.suffix in (".yaml", ".yml") and p.name.count(".") >= 3)

    def wanted(name: str) -> bool:
        return not only or any(fnmatch.fnmatch(name, pat) for pat in only)

    files = [f for f in files if wanted(f)]
    missing = sorted(f for f in spec if wanted(f) and f not in files)
    unlisted = [f for f in files if f not in spec]
    rows = [row for f in files for row in spec.get(f, [])]
    runner = _Runner(folder, backend, options)
    results: list[RowResult] = []
    file_times: dict[str, float] = {}
    for k, row in enumerate(rows):
        t1 = time.perf_counter()
        try:
            finding, value, text, detail = _compute(runner, row)
        except LmicError as err:
            finding, value, text, detail = "error", None, "error", " ".join(str(err).split())
        verdict_ok, value_ok = _judge(row, finding, value)
        res = RowResult(row, finding, _scalar(value), text, verdict_ok, value_ok, detail, time.perf_counter() - t1)
        results.append(res)
        file_times[row.file] = file_times.get(row.file, 0.0) + res.time_s
        if progress is not None:
            progress({"done": k + 1, "total": len(rows), "file": row.file, "row": res})
    return ReproductionReport(
        results=results,
        unlisted=unlisted,
        missing=missing,
        backend=backend,
        total_s=time.perf_counter() - t0,
        file_times=file_times,
    )


# --------------------------------------------------------------------------------------------
# docs/reproduction.md


def _cell(text: Any) -> str:
    s = _fmt(text) if not isinstance(text, str) else text
    return " ".join(s.split()).replace("|", "\\|")


def render_markdown(report: ReproductionReport, *, command: str = "lmic reproduce -o docs/reproduction.md") -> str:
    """The reproduction table as Markdown (what ``lmic reproduce -o`` writes)."""
    from lmic._version import __version__

    lines = [
        "# Reproduction of the published examples",
        "",
        f"Generated by `{command}` (lmic {__version__}, backend {report.backend}); do not edit by hand.",
        "Expectations, reference values, tolerances and the catalogues' explanations: `examples/reproduction.yaml`",
        "(from `theorems/seeds_catalogue.md` section 6 and `theorems/thesis_catalogue.md` sections 10-11).",
        "",
        "Columns: *published* is what the paper prints; *computed* is lmic's value (certified unless the verdict says",
        "otherwise); *verdict* is lmic's finding (`certified`: a certificate at the point; `infeasible`: the solver's",
        "infeasibility with a verified Farkas certificate where the backend gives one; `rejected`: the printed point",
        "violates the LMI; `matches`/`differs`: a printed value against the computed one); *reference* is the",
        "catalogue's value with the tolerance used; *ok* says whether verdict and value agree with the expectation.",
        "",
        f"**{sum(r.ok for r in report.results)} of {len(report.results)} rows agree** with the expectations; "
        f"run time {report.total_s:.1f} s.",
        "",
    ]
    if report.missing:
        lines += [f"Missing example files: {', '.join(report.missing)}.", ""]
    if report.unlisted:
        lines += [f"Examples without expectations (not run): {', '.join(report.unlisted)}.", ""]
    current = None
    header = "| quantity | published | computed | verdict | reference (tol) | ok | catalogue / explanation |"
    for r in report.results:
        row = r.row
        if row.file != current:
            current = row.file
            t = report.file_times.get(row.file, 0.0)
            lines += ["", f"### `{row.file}` ({row.theorem}, {t:.1f} s)", "", header, "|---|---|---|---|---|---|---|"]
        ref = (
            "-"
            if row.reference is None
            else (row.reference if isinstance(row.reference, str) else _fmt(row.reference, digits=8))
        )
        if row.reference is not None and row.tol is not None and not isinstance(row.reference, str):
            ref += f" (±{row.tol:g})"
        verdict = r.finding if r.finding == row.verdict else f"{r.finding} (expected {row.verdict})"
        note = row.catalogue
        if row.explanation:
            note = f"{note}: {row.explanation}" if note else row.explanation
        if not r.ok and r.detail:
            note += f" [lmic: {r.detail}]"
        lines.append(
            f"| {_cell(row.quantity)} | {_cell(row.published if row.published is not None else '-')} | "
            f"{_cell(r.text)} | {verdict} | {ref} | {'yes' if r.ok else '**no**'} | {_cell(note)} |"
        )
    return "\n".join(lines) + "\n"
