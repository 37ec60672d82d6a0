"""``lmic check THEOREM|MODULE.py``: find template mistakes before any data file exists.

The template is analysed at small random dimensions consistent with its shape declarations
(distinct values where possible, so that ``n`` and ``p`` cannot be confused), with random
data of the declared shapes and tags. Reported, one line each:

* every product of decision variables (bilinear term) and every non-linear use of one;
* every diagonal block that is not symmetric, and explicit mirror blocks that are not transposes;
* shape mismatches in LMIs, derived quantities and checks (``L = R P^-1`` of the wrong shape);
* declarations that nothing uses (data, parameters, constants, decision variables in no LMI):
  reported as warnings, which fail the check only with ``--strict``.

Every structural option value is analysed too (``fixed_L: 1`` audit variants included).
Exit 0 when nothing is found, 2 otherwise (one line per finding on stderr). ``lmic show`` runs the same checks.

Examples
--------
>>> from lmic.registry import get_theorem
>>> check_theorem(get_theorem("thesis.lyapunov")).findings
[]
"""

from __future__ import annotations

import argparse
import contextlib
import importlib.util
import itertools
import sys
import types
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from lmic.commands._check_values import _dim, _environment, choose_dims
from lmic.errors import DataError, LmicError

if TYPE_CHECKING:  # numpy, sympy and the template layer are imported by the functions that use them
    import numpy as np

    from lmic.template.builder import Template
    from lmic.template.theorem import Theorem

__all__ = ["register", "run", "check_theorem", "load_module_theorems", "CheckReport", "choose_dims"]


@dataclass
class CheckReport:
    """What :func:`check_theorem` found for one theorem."""

    theorem: str
    dims: dict[str, int] = field(default_factory=dict)
    findings: list[str] = field(default_factory=list)
    #: the errors behind findings (``--debug`` prints their tracebacks)
    errors: list[BaseException] = field(default_factory=list, repr=False)
    #: unused declarations (reported; they fail the check only with ``--strict``)
    warnings: list[str] = field(default_factory=list)
    summary: str = ""


# ---- the checks ----------------------------------------------------------------------------------


def _bilinear(t: Template) -> list[str]:
    """Every product of decision variables, and every non-linear use of one."""
    import sympy

    from lmic.compile.plan import _Analyser, _atom_var
    from lmic.template.blocks import STAR
    from lmic.template.convert import as_expr

    an = _Analyser(t)
    out: list[str] = []
    for lmi in t.lmis:
        b = lmi.spec.block
        for i, j in itertools.product(range(b.shape[0]), repeat=2):
            ent = b.entry(i, j)
            if ent is STAR or not isinstance(ent, sympy.Basic):
                continue
            an.where = f"LMI '{lmi.name}' block ({i + 1},{j + 1})"
            try:
                expanded = an.expand(ent) if isinstance(ent, sympy.MatrixExpr) else [(as_expr(ent), [])]
            except LmicError as err:
                out.append(str(err).split(": ", 1)[-1])
                continue
            for coef, factors in expanded:
                text = str(sympy.MatMul(coef, *factors)) if factors else str(coef)
                mats = [str(_atom_var(f)) for f in factors if _atom_var(f) in an.matrix_vars]
                for mono in sympy.Add.make_args(sympy.expand(coef)):
                    svars = sorted(an.scalar_vars[s] for s in mono.free_symbols if s in an.scalar_vars)
                    powers = [
                        an.scalar_vars[s]
                        for s in mono.free_symbols
                        if s in an.scalar_vars and sympy.degree(mono, s) > 1
                    ]
                    names = mats + svars
                    if len(names) > 1 or powers:
                        shown = " and ".join(names) if len(names) > 1 else f"{powers[0]}^2"
                        out.append(f"{an.where}: product of decision variables {shown} in term '{text}'")
                        break
    for c in t.constraints:
        try:
            an.relation(c.name, c.relation)
        except LmicError as err:
            out.append(str(err).split(": ", 1)[-1])
    if t.objective[0] != "feasibility":
        try:
            an.linear(t.objective[1], "objective")
        except LmicError as err:
            out.append(str(err).split(": ", 1)[-1])
    return out


def _evaluate(e: Any, dims: dict, env: dict) -> np.ndarray | float:
    from lmic.ir.expr import evaluate
    from lmic.template.totree import to_tree

    return evaluate(to_tree(e, dims), env)


def _dims_text(dims: dict) -> str:
    return ", ".join(f"{s} = {v}" for s, v in sorted(dims.items(), key=lambda kv: str(kv[0])))


def _shape_of(v: Any) -> tuple[int, int]:
    import numpy as np

    return v.shape if isinstance(v, np.ndarray) else (1, 1)


def _lmi_numeric(t: Template, dims: dict, env: dict) -> list[str]:
    import numpy as np
    import sympy

    from lmic.template.blocks import STAR

    out: list[str] = []
    at = f"(at {_dims_text(dims)})"
    for lmi in t.lmis:
        b = lmi.spec.block
        k = b.shape[0]
        vals: dict[tuple[int, int], Any] = {}
        bad = False
        for i, j in itertools.product(range(k), repeat=2):
            ent = b.entry(i, j)
            if ent is STAR or (isinstance(ent, int | float) and ent == 0) or not isinstance(ent, sympy.Basic):
                continue
            try:
                vals[(i, j)] = _evaluate(ent, dims, env)
            except LmicError as err:
                out.append(f"LMI '{lmi.name}' block ({i + 1},{j + 1}): {err} {at}")
                bad = True
        if bad:
            continue
        rows: dict[int, int] = {}
        cols: dict[int, int] = {}
        for (i, j), v in vals.items():
            if not isinstance(v, np.ndarray):
                continue
            for store, idx, size, what in ((rows, i, v.shape[0], "rows"), (cols, j, v.shape[1], "columns")):
                if idx in store and store[idx] != size:
                    out.append(
                        f"LMI '{lmi.name}' block ({i + 1},{j + 1}) has {size} {what}, other blocks of its "
                        f"block {'row' if what == 'rows' else 'column'} {store[idx]} {at}"
                    )
                    bad = True
                store.setdefault(idx, size)
        for i in range(k):
            if i in rows and i in cols and rows[i] != cols[i]:
                out.append(
                    f"LMI '{lmi.name}': block row {i + 1} is {rows[i]} tall but block column {i + 1} "
                    f"is {cols[i]} wide {at}"
                )
                bad = True
        if bad:
            continue
        for (i, j), v in vals.items():
            if not isinstance(v, np.ndarray):
                continue
            scale = max(1.0, float(np.max(np.abs(v))))
            if i == j and float(np.max(np.abs(v - v.T))) > 1e-9 * scale:
                out.append(f"LMI '{lmi.name}' block ({i + 1},{i + 1}) is not symmetric: {b.entry(i, i)}")
            if i < j and (j, i) in vals and isinstance(vals[(j, i)], np.ndarray):
                w = vals[(j, i)]
                if w.shape != v.T.shape or float(np.max(np.abs(w - v.T))) > 1e-9 * scale:
                    out.append(
                        f"LMI '{lmi.name}': blocks ({i + 1},{j + 1}) and ({j + 1},{i + 1}) are both written "
                        "and are not transposes of each other (write STAR for one)"
                    )
    return out


def _derived_numeric(t: Template, dims: dict, env: dict) -> list[str]:
    import numpy as np
    import sympy

    out: list[str] = []
    at = f"(at {_dims_text(dims)})"
    for d in t.derived:
        try:
            env[d.name] = _evaluate(d.expr, dims, env)
        except LmicError as err:
            out.append(f"derive '{d.name}' = {d.expr}: {err} {at}")
            continue
        if isinstance(d.expr, sympy.MatrixExpr):
            want = (_dim(d.symbol.shape[0], dims), _dim(d.symbol.shape[1], dims))
            if _shape_of(env[d.name]) != want:
                out.append(f"derive '{d.name}' evaluates to {_shape_of(env[d.name])}, declared {want} {at}")
    for c in t.checks:
        e = c.spec.expr
        try:
            v = _evaluate(e, dims, env)
        except LmicError as err:
            out.append(f"check '{c.name}': {err} {at}")
            continue
        square = c.spec.kind in (
            "schur_stable",
            "hurwitz",
            "negative_definite",
            "positive_definite",
            "negative_semidefinite",
            "positive_semidefinite",
        )
        if square and isinstance(v, np.ndarray) and v.shape[0] != v.shape[1]:
            out.append(f"check '{c.name}': {e} is {v.shape[0]}x{v.shape[1]}, not square {at}")
    ob = t.observer_decl
    if ob is not None and ob.model == "luenberger" and {"A", "C", "L"} <= set(ob.roles):
        try:
            A, C, L = (np.atleast_2d(env[ob.roles[r]]) for r in ("A", "C", "L"))
            if L.shape != (A.shape[0], C.shape[0]):
                out.append(
                    f"observer: gain {ob.roles['L']} is {L.shape[0]}x{L.shape[1]}, the Luenberger observer needs "
                    f"{A.shape[0]}x{C.shape[0]} (rows of A x rows of C) {at}"
                )
        except KeyError:
            pass
    return out


def _code_strings(fn: Any, depth: int = 0) -> set[str]:
    """String constants in a callable's code (names a ``values`` lookup uses), recursively."""
    out: set[str] = set()
    code = getattr(fn, "__code__", None)
    if code is None or depth > 4:
        return out
    stack = [code]
    while stack:
        c = stack.pop()
        for k in c.co_consts:
            if isinstance(k, str):
                out.add(k)
            elif isinstance(k, types.CodeType):
                stack.append(k)
        out.update(c.co_names)
        for name in c.co_names:  # helper functions of the plugin module (one level of globals)
            g = getattr(fn, "__globals__", {}).get(name)
            if isinstance(g, types.FunctionType) and depth < 2:
                out |= _code_strings(g, depth + 1)
    for cell in getattr(fn, "__closure__", None) or ():
        try:
            val = cell.cell_contents
        except ValueError:
            continue
        if callable(val):
            out |= _code_strings(val, depth + 1)
        elif isinstance(val, str):
            out.add(val)
    return out


def _unused(t: Template) -> list[str]:
    from lmic.template.blocks import STAR, Block

    def names(e: Any) -> set[str]:
        if isinstance(e, Block):
            return set().union(*(names(x) for row in e.rows for x in row if x is not STAR))
        return {getattr(s, "name", str(s)) for s in getattr(e, "free_symbols", set())}

    in_lmis: set[str] = set()
    for lmi in t.lmis:
        in_lmis |= names(lmi.spec.block)
    for c in t.constraints:
        in_lmis |= names(c.relation)
    in_lmis |= names(t.objective[1])
    used = set(in_lmis)
    for d in t.derived:
        used |= names(d.expr)
    for chk in t.checks:
        used |= names(chk.spec.expr)
    if t.observer_decl is not None:
        used |= set(t.observer_decl.roles.values())
    opaque: list[Any] = [k.fn for k in t.consts] + [r.predicate for r in t.requirements]
    for fn in opaque + [dd.default for dd in t.data_decls]:
        if callable(fn):
            used |= _code_strings(fn)
    out = []
    for dd in t.data_decls:
        if dd.name not in used:
            out.append(f"data '{dd.name}' is declared but not used")
    for p in t.params:
        if p.name not in used:
            out.append(f"parameter '{p.name}' is declared but not used")
    for k in t.consts:
        if k.name not in used:
            out.append(f"constant '{k.name}' is declared but not used")
    for v in t.variables:
        if v.name not in in_lmis:
            out.append(f"decision variable '{v.name}' appears in no LMI, constraint or objective")
    return out


def _one(
    thm: Theorem, options: dict[str, Any], seed: int, errors: list | None = None
) -> tuple[list[str], dict, Template | None]:
    import numpy as np

    try:
        t = thm.template(options)
    except LmicError as err:
        if errors is not None:
            errors.append(err)
        return [str(err)], {}, None
    findings = _bilinear(t)
    dims = choose_dims(t, seed)
    if dims is None:
        findings.append("no small dimensions make every declared shape positive (check the shape declarations)")
        return findings, {}, t
    env = _environment(t, dims, np.random.default_rng(seed))
    try:
        findings += _lmi_numeric(t, dims, env)
        findings += _derived_numeric(t, dims, env)
    except (ValueError, TypeError, ArithmeticError, np.linalg.LinAlgError) as err:
        findings.append(f"cannot evaluate the template at {_dims_text(dims)}: {type(err).__name__}: {err}")
    return findings, dims, t


def check_option_names(t: Template, options: dict[str, Any]) -> None:
    """Refuse a ``-p`` name that is neither an option nor a parameter of the template (:class:`DataError`).

    >>> from lmic.registry import get_theorem
    >>> thm = get_theorem("qib.thm1")
    >>> check_option_names(thm.template(), {"fixed_L": "1"})
    >>> check_option_names(thm.template(), {"zzz": 1})
    Traceback (most recent call last):
    ...
    lmic.errors.DataError: theorem qib.thm1: unknown parameter 'zzz' (the theorem takes: beta, fixed_L, gamma)
    """
    known = {o.name for o in t.options} | {p.name for p in t.params}
    for key in options:
        if key not in known:
            accepted = ", ".join(sorted(known)) or "none"
            raise DataError(f"theorem {t.theorem_id}: unknown parameter '{key}' (the theorem takes: {accepted})")


def check_theorem(thm: Theorem, options: dict[str, Any] | None = None, seed: int = 0) -> CheckReport:
    """Analyse ``thm`` (default options, then every other option value) without data.

    Returns a :class:`CheckReport`; ``findings`` are one-line messages (empty when clean).

    >>> from lmic.template import theorem
    >>> @theorem(id="demo.bad", title="t", citation="c")
    ... def bad(t):
    ...     n, p = t.dims("n p")
    ...     A, C = t.data("A", n, n), t.data("C", p, n)
    ...     P = t.symmetric("P", n, pd=True); R = t.full("R", p, n)
    ...     t.lmi("(1)", A.T * P - C.T * R < 0)
    ...     t.luenberger(A, C, L=R * P.inv())
    >>> for line in check_theorem(bad).findings: print(line)  # doctest: +ELLIPSIS, +NORMALIZE_WHITESPACE
    LMI '(1)' block (1,1) is not symmetric: A.T*P - C.T*R
    check 'A - L C Schur stable': expression multiplies shapes (6, 5) and (6, 5) (at n = 5, p = 6)
    observer: gain L is 6x5, the Luenberger observer needs 5x6 (rows of A x rows of C) (at n = 5, p = 6)
    """
    base = dict(options or {})
    errors: list[BaseException] = []
    findings, dims, t = _one(thm, base, seed, errors)
    report = CheckReport(thm.id, {str(k): v for k, v in dims.items()}, list(dict.fromkeys(findings)), errors)
    if t is None:
        return report
    report.warnings = _unused(t)
    for opt in t.options:
        if opt.name in base:
            continue
        for choice in opt.choices:
            if choice == opt.value:
                continue
            more, _, _ = _one(thm, {**base, opt.name: choice}, seed)
            for line in more:
                tagged = f"[{opt.name}: {choice}] {line}"
                if line not in report.findings and tagged not in report.findings:
                    report.findings.append(tagged)
    report.summary = (
        f"{len(t.lmis)} LMIs, {len(t.variables)} variables, {len(t.derived)} derived, {len(t.checks)} checks"
        + (f"; options {', '.join(o.name for o in t.options)} (every value analysed)" if t.options else "")
    )
    return report


# ---- modules ---------------------------------------------------------------------------------------


def load_module_theorems(path: str | Path) -> tuple[list[Theorem], list[str]]:
    """Import a Python file and return its theorems, plus problems (undecorated build functions).

    Raises :class:`DataError` (one line, with the file and line) when the file cannot be imported.
    """
    from lmic.template.theorem import Theorem

    p = Path(path)
    if not p.is_file():
        raise DataError(f"{p}: no such file")
    name = f"_lmic_check_{abs(hash(str(p.resolve())))}"
    spec = importlib.util.spec_from_file_location(name, p)
    if spec is None or spec.loader is None:
        raise DataError(f"{p}: cannot be imported as a Python module")
    module = importlib.util.module_from_spec(spec)
    try:
        with contextlib.redirect_stdout(sys.stderr):  # the module's prints never mix into --json
            spec.loader.exec_module(module)
    except KeyboardInterrupt:
        raise
    except BaseException as err:  # noqa: BLE001 - the user's module, reported in one line
        import traceback

        frames = [f for f in traceback.extract_tb(err.__traceback__) if Path(f.filename).resolve() == p.resolve()]
        line = f":{frames[-1].lineno}" if frames else ""
        text = " ".join(str(err).split())
        if isinstance(err, SystemExit):
            text = f"SystemExit({err.code!r})"
        raise DataError(f"{p.name}{line}: import failed: {type(err).__name__}: {text}") from err
    thms = list(getattr(module, "THEOREMS", None) or [v for v in vars(module).values() if isinstance(v, Theorem)])
    problems = []
    for key, v in vars(module).items():
        if isinstance(v, types.FunctionType) and v.__module__ == name and not key.startswith("_"):
            args = v.__code__.co_varnames[: v.__code__.co_argcount]
            if args == ("t",):
                problems.append(
                    f"{p.name}:{v.__code__.co_firstlineno}: function '{key}' takes t but is not a theorem: "
                    "decorate it with @theorem(id=..., title=..., citation=...)"
                )
    if not thms and not problems:
        problems.append(f"{p.name}: defines no theorem (decorate build functions with @theorem(...))")
    return thms, problems


# ---- the command -----------------------------------------------------------------------------------


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``check`` sub-command."""
    p = sub.add_parser(
        "check",
        help="find template mistakes (bilinear terms, asymmetric blocks, shapes, unused names) without data",
        description=__doc__.split("Examples")[0] if __doc__ else None,
        epilog="examples:\n  lmic check qib.thm1\n  lmic check my_theorems.py\n  lmic check mine.py -p fixed_L=1",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("target", help="theorem id, or a Python file defining theorems")
    p.add_argument("-p", "--param", action="append", default=[], metavar="K=V", help="fix a structural option")
    p.add_argument("--seed", type=int, default=0, help="random seed for dimensions and data (default 0)")
    p.add_argument("--strict", action="store_true", help="unused declarations fail the check too")
    p.add_argument("--json", action="store_true", help="print one JSON object (findings per theorem)")
    p.set_defaults(func=run)


def report_lines(report: CheckReport, warnings: bool = True) -> list[str]:
    """The findings as printed: ``THEOREM: finding`` (the theorem id is not repeated)."""
    out = []
    for f in report.findings + (report.warnings if warnings else []):
        f = f.removeprefix("theorem ").removeprefix(f"{report.theorem}: ")
        out.append(f if f.startswith(f"{report.theorem} ") else f"{report.theorem}: {f}")
    return out


def run(args: argparse.Namespace) -> int:
    """Check every theorem named; print one line per finding; exit 0 (clean) or 2."""
    from lmic.commands._common import parse_params

    options = parse_params(args.param)
    target = args.target
    problems: list[str] = []
    if target.endswith(".py") or Path(target).is_file():
        thms, problems = load_module_theorems(target)
    else:
        from lmic.registry import get_theorem

        thms = [get_theorem(target)]
        if options:
            check_option_names(thms[0].template(options), options)
    if getattr(args, "json", False):
        from lmic.commands._common import print_json

        reports = [check_theorem(thm, options, seed=args.seed) for thm in thms]
        fail = bool(problems) or any(r.findings or (args.strict and r.warnings) for r in reports)
        print_json(
            {
                "problems": problems,
                "theorems": [
                    {"id": r.theorem, "dims": r.dims, "findings": r.findings, "warnings": r.warnings} for r in reports
                ],
                "exit_code": 2 if fail else 0,
            }
        )
        return 2 if fail else 0
    for line in problems:
        sys.stderr.write(f"lmic check: {line}\n")
    bad = bool(problems)
    for thm in thms:
        report = check_theorem(thm, options, seed=args.seed)
        if getattr(args, "debug", False):
            import traceback

            for err in report.errors:
                traceback.print_exception(err)
        for line in report_lines(report):
            sys.stderr.write(f"lmic check: {line}\n")
        if report.findings or (args.strict and report.warnings):
            bad = True
        else:
            dims = ", ".join(f"{k} = {v}" for k, v in report.dims.items())
            note = f"; {len(report.warnings)} unused declarations" if report.warnings else ""
            print(f"{thm.id}: ok ({report.summary}; analysed at {dims or 'no dimensions'}{note})")
    return 2 if bad else 0
