"""How ``lmic reproduce`` computes a row: one registered handler per ``compute:`` kind.

Each handler is ``(runner, row) -> (finding, value, text, detail)``; :class:`Runner` caches per
example file the loaded system, the audit and the theorem's own solution:

- ``claim``: the audit of the file's ``published:`` section (:mod:`lmic.studies.published`);
- ``solve``: the theorem on the file (objective kept);
- ``at_published``: a derived quantity computed from the printed numbers (not certified);
- ``maximize``: supremum by bisection (:func:`lmic.studies.sweep.maximize`), optionally on a fixed gain;
- ``sweep``: a grid (:func:`lmic.studies.sweep.sweep`);
- ``gain``: a printed gain through another theorem's ``fixed_<gain>`` variant
  (:func:`lmic.reductions.fix.with_fixed_gains`).

Examples
--------
>>> list(HANDLERS)
['claim', 'solve', 'at_published', 'maximize', 'sweep', 'gain']
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from lmic.errors import DataError
from lmic.formatting import value_text
from lmic.reductions.fix import with_fixed_gains
from lmic.studies.reproduce.rows import HANDLERS, Row, register

__all__ = ["Runner", "compute_row", "HANDLERS", "scalar"]


def scalar(v: Any) -> Any:
    """A 1x1 array or list as a float, a larger array as nested lists, anything else as it is.

    >>> scalar(np.array([[2.0]])), scalar(np.eye(2)), scalar("x")
    (2.0, [[1.0, 0.0], [0.0, 1.0]], 'x')
    """
    if isinstance(v, np.ndarray):
        return float(v.reshape(-1)[0]) if v.size == 1 else v.tolist()
    if isinstance(v, list):
        arr = np.asarray(v, dtype=float)
        return float(arr.reshape(-1)[0]) if arr.size == 1 else v
    return v


def _text(v: Any) -> str:
    """A computed value in a row: scalars to 6 digits, matrices on one line to 4."""
    return value_text(v, 4, scalar_digits=6)


class Runner:
    """Caches per file: the loaded system, the audit and the theorem's own solution."""

    def __init__(self, examples: Path, backend: str, options: Any) -> None:
        self.examples, self.backend, self.options = examples, backend, options
        self._audits: dict[tuple, Any] = {}
        self._solves: dict[tuple, Any] = {}

    def path(self, file: str) -> Path:
        """The example file ``file`` (a :class:`DataError` if there is none)."""
        p = self.examples / file
        if not p.is_file():
            raise DataError(f"{p}: no such example file")
        return p

    def audit(self, row: Row) -> Any:
        """The audit of the row's file (cached per file, theorem and parameters)."""
        from lmic.studies.published import audit_published

        params = dict(row.compute.get("params") or {})
        key = (row.file, row.theorem, tuple(sorted(params.items())))
        if key not in self._audits:
            self._audits[key] = audit_published(
                row.theorem, self.path(row.file), params or None, backend=self.backend, options=self.options
            )
        return self._audits[key]

    def solve(self, row: Row) -> tuple[Any, Any]:
        """``(problem, decided point)`` of the row's theorem on its file (cached)."""
        from lmic.compile import compile_theorem
        from lmic.studies.sweep import decide

        params = dict(row.compute.get("params") or {})
        key = (row.file, row.theorem, tuple(sorted(params.items())))
        if key not in self._solves:
            problem = compile_theorem(row.theorem, str(self.path(row.file)), params or None)
            self._solves[key] = (problem, decide(problem, self.backend, self.options, keep_objective=True))
        return self._solves[key]

    def gain_system(self, row: Row, key: str, system: Path) -> Any:
        """``system`` with the printed gain ``key`` of the row's file as data and ``fixed_key: 1``."""
        from lmic.system import load_system

        source = load_system(self.path(row.file))
        if key not in source.published:
            raise DataError(f"{row.file}: publishes no '{key}'")
        target = load_system(system)
        return with_fixed_gains(
            target, {key: source.published[key]}, row.compute.get("params") or {}, keep_published=False
        )


def compute_row(runner: Runner, row: Row) -> tuple[str, Any, str, str]:
    """``(finding, value, text, detail)`` of one row, by the handler of its ``compute:`` kind."""
    for kind, handler in HANDLERS.items():
        if kind in row.compute:
            return handler(runner, row)
    raise DataError(f"{row.file}: {row.quantity!r}: nothing to compute")


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
        return scalar(env[c["derived"]]), ""
    if "variable" in c:
        return scalar(env[c["variable"]]), ""
    if c.get("objective"):
        return pt.objective, ""
    return None, ""


@register("claim")
def claim_row(runner: Runner, row: Row) -> tuple[str, Any, str, str]:
    """The claim of the file's audit covering ``claim: KEY`` (its LMI, derived, check or value)."""
    c = row.compute
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
        text = f"{match[0]['which']} {_text(value)}"
    elif "derived" in c:
        value = claim.derived.get(c["derived"])
        text = f"{c['derived']} = {_text(value)}"
    elif "check" in c:
        found = [e for e in claim.checks if e["name"] == c["check"]]
        value = found[0]["value"] if found else None
        text = f"{c['check']}: {_text(value)}"
    elif claim.kind == "value":
        value = scalar(claim.computed)
        text = _text(value)
    else:
        text = claim.proof or claim.finding
    return claim.finding, value, text, claim.reason


@register("solve")
def solve_row(runner: Runner, row: Row) -> tuple[str, Any, str, str]:
    """The theorem on the file: the outcome, and a derived quantity, variable or the objective."""
    problem, pt = runner.solve(row)
    value, why = _point_value(row, problem, pt)
    finding = _outcome_finding(pt.outcome)
    text = _text(value) if value is not None else (pt.proof or finding)
    return finding, value, text, pt.proof or why


@register("at_published")
def at_published_row(runner: Runner, row: Row) -> tuple[str, Any, str, str]:
    """A derived quantity computed from the printed numbers, compared with the printed one."""
    from lmic.studies.published import AuditContext, compare_value, derived_at_published, point_claims

    c = row.compute
    ctx = AuditContext(row.theorem, runner.path(row.file), c.get("params"), runner.backend, runner.options)
    point_claims(ctx, ctx.sysobj.published)
    value = derived_at_published(ctx, str(c["at_published"]))
    if value is None:
        return "not reproducible", None, "-", "not computable from the printed numbers"
    value = scalar(value)
    key = str(c.get("published_key", c["at_published"]))
    pub = ctx.sysobj.published.get(key)
    if pub is None:
        return "not reproducible", value, _text(value), f"{row.file} publishes no '{key}'"
    claim = compare_value(key, pub, value, "the published numbers", True, ctx.rtol)
    return claim.finding, value, _text(value), claim.reason


@register("maximize")
def maximize_row(runner: Runner, row: Row) -> tuple[str, Any, str, str]:
    """The supremum of a parameter by bisection (on the fixed-gain variant with ``gain:``)."""
    from lmic.studies.sweep import maximize

    c = row.compute
    system: Any = runner.path(row.file)
    params = dict(c.get("params") or {})
    if "gain" in c:
        system = runner.gain_system(row, str(c["gain"]), runner.path(row.file))
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
    text = f"[{res.lower:.6g}, {_text(res.upper)}]"
    detail = f"lower certified, upper {res.upper_kind}; {res.iterations} bisection steps, {len(res.points)} points"
    return "certified", res.lower, text, detail


@register("sweep")
def sweep_row(runner: Runner, row: Row) -> tuple[str, Any, str, str]:
    """A grid over one parameter: certified if some point is."""
    from lmic.studies.sweep import parse_grid, sweep

    c = row.compute
    name, values = parse_grid(str(c["sweep"]))
    res = sweep(
        row.theorem,
        runner.path(row.file),
        name,
        values,
        params=c.get("params"),
        backend=runner.backend,
        options=runner.options,
    )
    ok = [p.value for p in res.points if p.outcome == "feasible"]
    if ok:
        text = f"certified at {name} = {', '.join(f'{v:g}' for v in ok)}"
        return "certified", (res.best.value if res.best else None), text, f"{len(values)} points"
    finding = "infeasible" if res.exit_code() == 3 else "not reproducible"
    return finding, None, f"no certified point in {len(values)}", ""


@register("gain")
def gain_row(runner: Runner, row: Row) -> tuple[str, Any, str, str]:
    """The printed gain through another theorem's ``fixed_<gain>`` variant (``theorem:``, ``system:``)."""
    from lmic.compile import compile_theorem
    from lmic.studies.sweep import decide

    c = row.compute
    system_file = runner.path(str(c.get("system", row.file)))
    sysobj = runner.gain_system(row, str(c["gain"]), system_file)
    problem = compile_theorem(row.theorem, sysobj)
    pt = decide(problem, runner.backend, runner.options, keep_objective=True)
    value, why = _point_value(row, problem, pt)
    finding = _outcome_finding(pt.outcome)
    return finding, value, _text(value) if value is not None else (pt.proof or finding), pt.proof or why
