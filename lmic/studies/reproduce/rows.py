"""The expectations of ``lmic reproduce``: rows, their results, the report, and the handler registry.

A row's ``compute:`` names how lmic computes its quantity; each way is a handler registered with
:func:`register` (:mod:`lmic.studies.reproduce.handlers` registers the shipped six), so a new
kind of row is one decorated function, not one more branch.

Examples
--------
>>> theorem_of("qib.thm1.flexible-joint.yaml")
'qib.thm1'
"""

from __future__ import annotations

import fnmatch
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from lmic.errors import DataError

__all__ = [
    "Row",
    "RowResult",
    "ReproductionReport",
    "theorem_of",
    "load_expectations",
    "default_examples_dir",
    "Selection",
    "select_examples",
    "register",
    "HANDLERS",
    "VERDICTS",
]

#: ``compute:`` kind -> handler ``(runner, row) -> (finding, value, text, detail)``, in precedence
#: order (a row naming two kinds, e.g. ``maximize`` with ``gain``, goes to the first registered)
HANDLERS: dict[str, Callable[[Any, Row], tuple[str, Any, str, str]]] = {}


def register(kind: str) -> Callable[[Callable[[Any, Row], tuple[str, Any, str, str]]], Callable[..., Any]]:
    """Decorator: the handler of rows whose ``compute:`` has the key ``kind``.

    >>> @register("demo_kind")
    ... def _demo(runner, row):
    ...     return "certified", 1.0, "1", ""
    >>> "demo_kind" in HANDLERS
    True
    >>> del HANDLERS["demo_kind"]
    """

    def wrap(fn: Callable[[Any, Row], tuple[str, Any, str, str]]) -> Callable[[Any, Row], tuple[str, Any, str, str]]:
        if kind in HANDLERS:
            raise ValueError(f"a reproduction handler for {kind!r} is already registered")
        HANDLERS[kind] = fn
        return fn

    return wrap


VERDICTS = (
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
    return Path(__file__).resolve().parents[3] / "examples"


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
        kinds = tuple(HANDLERS)
        if not isinstance(compute, dict) or sum(k in compute for k in kinds) < 1:
            raise DataError(f"{where}, {spec['quantity']!r}: compute needs one of {', '.join(kinds)}")
        verdict = str(spec.get("verdict", "certified"))
        if verdict not in VERDICTS:
            raise DataError(f"{where}, {spec['quantity']!r}: verdict {verdict!r} is not one of {', '.join(VERDICTS)}")
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


@dataclass
class Selection:
    """The example files a reproduction runs (:func:`select_examples`)."""

    folder: Path
    expectations: Path
    spec: dict[str, list[Row]]
    #: example files matching ``only`` (sorted)
    files: list[str]
    #: files the expectations list (matching ``only``) but the folder lacks
    missing: list[str]
    #: example files the expectations do not list
    unlisted: list[str]


def select_examples(
    examples: str | os.PathLike[str] | None = None,
    expectations: str | os.PathLike[str] | None = None,
    only: Sequence[str] = (),
) -> Selection:
    """The examples folder, its expectations and the example files matching the globs ``only``.

    Raises :class:`DataError` for a missing folder, bad expectations, or patterns that match
    no example file and no expectation (a typo in ``--only`` is not an empty success).

    Examples
    --------
    >>> from lmic.studies.reproduce import select_examples  # the shipped compute kinds registered
    >>> sel = select_examples(only=["thesis.lyapunov.*"])
    >>> sel.files, sel.missing
    (['thesis.lyapunov.ex2_3_2.yaml'], [])
    >>> select_examples(only=["nope.*"])
    Traceback (most recent call last):
    ...
    lmic.errors.DataError: --only 'nope.*': no example file matches (in examples)
    """
    folder = Path(examples) if examples is not None else default_examples_dir()
    if not folder.is_dir():
        raise DataError(f"{folder}: no examples folder")
    exp_path = Path(expectations) if expectations is not None else folder / "reproduction.yaml"
    spec = load_expectations(exp_path)
    names = sorted(p.name for p in folder.iterdir() if p.suffix in (".yaml", ".yml") and p.name.count(".") >= 3)

    def wanted(name: str) -> bool:
        return not only or any(fnmatch.fnmatch(name, pat) for pat in only)

    files = [f for f in names if wanted(f)]
    missing = sorted(f for f in spec if wanted(f) and f not in files)
    if only and not files and not missing:
        pats = " ".join(f"--only {p!r}" for p in only)
        raise DataError(f"{pats}: no example file matches (in {folder.name})")
    unlisted = [f for f in files if f not in spec]
    return Selection(folder, exp_path, spec, files, missing, unlisted)
