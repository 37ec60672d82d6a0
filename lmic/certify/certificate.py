"""Certificate files: write them atomically, read them strictly, audit them from scratch.

A certificate file (``schemas/certificate.schema.json``, version :data:`SCHEMA_VERSION`) is one
JSON object::

    {"lmic_certificate": 1, "lmic": "0.1.0", "created": "2026-01-01T00:00:00Z",
     "theorem": {"id", "title", "citation"} | null,       # null for a raw IR / SDPA problem
     "params": {...},                                      # the parameters compiled with
     "system": {"path", "name", "sha256"} | null,          # path relative to the certificate
     "ir": {"sha256", "embedded": IR dict | null},         # embedded when not recompilable
     "backend": {"name", "status", "native_status", "strategy", "margin", "iterations",
                 "solve_s", "versions": {package: version}},
     "solution": {"x": [...], "objective", "variables": {name: value}, "farkas": {...} | null},
     "tolerances": {...},
     "certificate": {verdict, reason, lmis, linear, objective, derived, checks, exact, farkas,
                     margin, ...}}                          # Certificate.to_dict() without x

The IR hash is :func:`ir_hash`: :func:`lmic.ir.jsonio.problem_hash` of the IR with the
volatile ``meta`` entries (timings ``*_s`` and the local ``system_path``) left out, so that two
compilations of the same theorem with the same numbers hash alike.

:func:`audit_certificate` trusts nothing in the file: it recompiles the IR from the recorded
theorem and system file (or loads the embedded IR), checks the data and IR hashes, re-derives
the variable values from ``x``, re-runs :func:`lmic.certify.certify` with the recorded
tolerances (and the exact proof whenever the file records one: the recorded verdict may rest
on it, e.g. a strict LMI below the float threshold proved exactly at ``exact.point``), and
compares every recorded number with the recomputed one. The first field that
differs is named (``system.sha256``, ``ir.sha256``, ``solution.variables.P``,
``certificate.lmis[0].min_eig``, ...).

Examples
--------
>>> import tempfile, os, numpy as np, scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
>>> from lmic.solution import Solution
>>> from lmic.certify import certify
>>> p = Problem([Variable("p", "scalar", (1, 1))], [LMI("p > 0", 1, sp.csc_matrix([[0., 1.]]))],
...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
>>> s = Solution("optimal", x=np.array([2.0]), backend="clarabel")
>>> path = os.path.join(tempfile.mkdtemp(), "cert.json")
>>> _ = write_certificate(path, p, s, certify(p, s))
>>> audit_certificate(path).ok
True
"""

from __future__ import annotations

import dataclasses
import datetime as _dt
import fnmatch
import hashlib
import json
import math
import os
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from lmic._version import __version__
from lmic.certify.check import Certificate, Tolerances, certify
from lmic.errors import CertificateError, LmicError
from lmic.ir.problem import Problem
from lmic.jsonable import to_jsonable
from lmic.solution import STATUSES, Solution

__all__ = [
    "SCHEMA_VERSION",
    "ir_hash",
    "certificate_document",
    "write_certificate",
    "read_certificate",
    "audit_certificate",
    "AuditResult",
    "INFORMATIONAL",
    "CLAIMED",
    "integrity_of",
    "looser_tolerances",
    "strictest",
]

#: version of the certificate file format (the ``lmic_certificate`` key)
SCHEMA_VERSION = 1

#: ``provider`` is checked on its own (:func:`theorem_changes`): a new plugin version whose
#: template is unchanged compiles to the same IR
_VOLATILE_META = ("system_path", "provider")

#: python packages behind each backend name (for the ``versions`` record)
_PACKAGES = {
    "clarabel": "clarabel",
    "scs": "scs",
    "cvxopt": "cvxopt",
    "sdpa": "sdpa-python",
    "cvxpy": "cvxpy",
    "picos": "picos",
}


def _json(value: Any) -> Any:
    """JSON form of a certificate field (non-finite floats as ``"nan"``, ``"inf"``, ``"-inf"``)."""
    return to_jsonable(value, nonfinite="string")


def ir_hash(problem: Problem) -> str:
    """SHA-256 of the IR without volatile ``meta`` (timings, local paths).

    Examples
    --------
    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LinearConstraints, Objective, Problem, Variable
    >>> p = Problem([Variable("t", "scalar", (1, 1))], [], LinearConstraints.empty(1),
    ...             Objective("min", [0.0, 1.0]), meta={"plan_s": 0.1})
    >>> q = Problem(p.variables, [], p.linear, p.objective, meta={"plan_s": 0.7})
    >>> ir_hash(p) == ir_hash(q)
    True
    """
    from lmic.ir.jsonio import problem_hash

    meta = {k: v for k, v in problem.meta.items() if not (k.endswith("_s") or k in _VOLATILE_META)}
    return problem_hash(replace(problem, meta=meta))


def _versions(backend: str, info: dict[str, Any]) -> dict[str, str]:
    from importlib import metadata

    out: dict[str, str] = {"lmic": __version__}
    names = {"numpy", "scipy", "python-flint"}
    head = backend.split(":")[0].lower()
    if head in _PACKAGES:
        names.add(_PACKAGES[head])
    tail = backend.split(":")[1].lower() if ":" in backend else ""
    if tail in _PACKAGES:
        names.add(_PACKAGES[tail])
    for name in sorted(names):
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            continue
    for key in ("version", "solver_version"):
        if isinstance(info.get(key), str):
            out["solver"] = info[key]
    return out


def _farkas_json(farkas: dict[str, Any] | None) -> dict[str, Any] | None:
    if farkas is None:
        return None
    out: dict[str, Any] = {
        "lmis": [None if Z is None else np.asarray(Z, dtype=float).tolist() for Z in farkas.get("lmis") or []],
        "linear": np.asarray(farkas.get("linear") if farkas.get("linear") is not None else [], dtype=float).tolist(),
    }
    return out


def certificate_document(
    problem: Problem,
    solution: Solution,
    certificate: Certificate,
    *,
    system: Any = None,
    path: str | os.PathLike[str] | None = None,
    embed_ir: bool | None = None,
    enclosure: dict[str, Any] | None = None,
    backoff: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """The certificate file's content as a dict (see the module docstring).

    Parameters
    ----------
    problem, solution, certificate
        The IR, the backend's answer and what :func:`lmic.certify.certify` made of it.
    system : lmic.system.System, optional
        The system the problem was compiled from (its path and data hash are recorded).
    path : path, optional
        Where the file will live (the system path is recorded relative to it).
    embed_ir : bool, optional
        Embed the IR (default: unless ``system`` is given, has a path, and the problem records
        its theorem; then the audit recompiles it).
    enclosure : dict, optional
        The optimal-value enclosure (:func:`lmic.certify.enclosure.enclosure`), recorded as
        the ``enclosure`` section with its dual point; the audit re-verifies both ends.
    backoff : dict, optional
        The backed-off point (:func:`lmic.backoff.backoff`); the audit re-certifies it.

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
    >>> p = Problem([Variable("p", "scalar", (1, 1))], [LMI("p>0", 1, sp.csc_matrix([[0., 1.]]))],
    ...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
    >>> s = Solution("optimal", x=np.array([2.0]))
    >>> doc = certificate_document(p, s, certify(p, s))
    >>> doc["theorem"], doc["ir"]["embedded"] is not None, doc["certificate"]["verdict"]
    (None, True, 'certified')
    """
    meta = problem.meta or {}
    theorem_id = meta.get("theorem")
    theorem = (
        {"id": str(theorem_id), "title": meta.get("title"), "citation": meta.get("citation")} if theorem_id else None
    )
    if theorem is not None:  # who provided the theorem, and a hash of its analysed template
        theorem.update(_theorem_identity(meta))
    sys_entry = None
    sys_path = getattr(system, "path", None) if system is not None else meta.get("system_path")
    if system is not None or sys_path:
        rel = None
        if sys_path:
            base = Path(path).resolve().parent if path is not None else Path.cwd()
            try:
                rel = os.path.relpath(Path(sys_path).resolve(), base)
            except ValueError:  # another drive (Windows)
                rel = str(Path(sys_path).resolve())
        digest = system.data_hash() if system is not None else meta.get("data_hash")
        sys_entry = {"path": rel, "name": getattr(system, "name", "") or meta.get("system", ""), "sha256": digest}
    # recompile only from a System the caller compiled with; an IR file (even one that
    # records its theorem) is embedded, since that IR is what was solved
    recompilable = (
        theorem is not None and system is not None and sys_entry is not None and sys_entry["path"] is not None
    )
    if embed_ir is None:
        embed_ir = not recompilable
    embedded = None
    if embed_ir:
        from lmic.ir.jsonio import problem_to_dict

        embedded = problem_to_dict(problem)
    cert = certificate.to_dict()
    cert.pop("x", None)
    x = None if solution.x is None else np.asarray(solution.x, dtype=float)
    doc = {
        "lmic_certificate": SCHEMA_VERSION,
        "lmic": __version__,
        "created": _dt.datetime.now(_dt.UTC).replace(microsecond=0).isoformat().replace("+00:00", "Z"),
        "theorem": theorem,
        "params": _json(meta.get("params") or {}),
        "system": sys_entry,
        "ir": {"sha256": ir_hash(problem), "embedded": embedded},
        "backend": {
            "name": solution.backend,
            "status": solution.status,
            "native_status": solution.native_status,
            "strategy": solution.strategy,
            "margin": solution.margin,
            "iterations": solution.iterations,
            "solve_s": solution.solve_s,
            "versions": _versions(solution.backend or "", solution.info or {}),
            # every solve the policy ran (lmic.policy): backend, reduction, statuses, verdict, time
            "attempts": list((solution.info or {}).get("attempts", [])),
        },
        "solution": {
            "x": None if x is None else x.tolist(),
            "objective": None if solution.objective is None else float(solution.objective),
            "variables": None if x is None else _json(problem.unpack(x)),
            "farkas": _farkas_json(solution.farkas) if solution.status == "infeasible" else None,
        },
        "tolerances": dict(certificate.tolerances),
        "certificate": cert,
    }
    if enclosure is not None:  # -- optimal-value enclosure (lmic.certify.enclosure) --
        doc["enclosure"] = enclosure
    if backoff is not None:  # -- backed-off point (lmic.backoff) --
        doc["backoff"] = backoff
    doc = _json(doc)
    doc["integrity"] = integrity_of(doc)
    return doc


def _theorem_identity(meta: dict[str, Any]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    if meta.get("provider") is not None:
        out["provider"] = meta["provider"]
    template = meta.get("template") or {}
    if template.get("sha256"):
        out["template_hash"] = template["sha256"]
        out["template_parts"] = dict(template.get("parts") or {})
    return out


def theorem_changes(recorded: dict[str, Any] | None, problem: Problem) -> tuple[str | None, str]:
    """Compare a certificate's ``theorem`` section with a recompiled problem.

    Returns ``(message, note)``: ``message`` is one line naming what changed in the template
    (``None`` when nothing did, or when the certificate predates template hashes); ``note``
    mentions a provider change that left the template as it was.

    >>> meta = {"template": {"sha256": "b", "parts": {"LMI (7)": "2", "check c": "3"}}}
    >>> rec = {"id": "a.b", "template_hash": "a", "template_parts": {"LMI (7)": "1", "derive L": "4"}}
    >>> from lmic.ir.problem import LinearConstraints, Objective, Problem
    >>> p = Problem([], [], LinearConstraints.empty(0), Objective("feasibility", [0.0]), meta=meta)
    >>> theorem_changes(rec, p)[0].split(": ", 1)[1]
    'LMI (7) differs; derive L removed; check c added'
    """
    if not recorded or not recorded.get("template_hash"):
        return None, ""
    meta = problem.meta or {}
    now = (meta.get("template") or {}).get("sha256")
    old_p, new_p = recorded.get("provider") or {}, meta.get("provider") or {}
    moved = ""
    key = ("distribution", "version")
    if old_p and new_p and [old_p.get(k) for k in key] != [new_p.get(k) for k in key]:
        moved = (
            f"provider {old_p.get('distribution') or 'inline'} {old_p.get('version') or ''} -> "
            f"{new_p.get('distribution') or 'inline'} {new_p.get('version') or ''}"
        ).replace("  ", " ")
    if now == recorded["template_hash"]:
        return None, (f"{moved} (template unchanged)" if moved else "")
    old, new = recorded.get("template_parts") or {}, (meta.get("template") or {}).get("parts") or {}
    what = [f"{k} differs" for k in old if k in new and old[k] != new[k]]
    what += [f"{k} removed" for k in old if k not in new]
    what += [f"{k} added" for k in new if k not in old]
    if moved:
        what.append(moved)
    detail = "; ".join(what) or "template hash differs"
    return (
        f"theorem {recorded.get('id')} changed since the certificate was written (plugin or recorded "
        f"parameters): {detail}",
        "",
    )


def write_certificate(
    path: str | os.PathLike[str],
    problem: Problem,
    solution: Solution,
    certificate: Certificate,
    *,
    system: Any = None,
    embed_ir: bool | None = None,
    enclosure: dict[str, Any] | None = None,
    backoff: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """Write a certificate file atomically (temporary file + rename); return its content.

    Examples
    --------
    >>> import tempfile, os, numpy as np, scipy.sparse as sp, json
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
    >>> p = Problem([Variable("p", "scalar", (1, 1))], [LMI("p>0", 1, sp.csc_matrix([[0., 1.]]))],
    ...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
    >>> s = Solution("optimal", x=np.array([2.0]))
    >>> f = os.path.join(tempfile.mkdtemp(), "c.json")
    >>> doc = write_certificate(f, p, s, certify(p, s))
    >>> json.load(open(f))["certificate"]["verdict"]
    'certified'
    """
    from lmic.output import write_output

    doc = certificate_document(
        problem,
        solution,
        certificate,
        system=system,
        path=path,
        embed_ir=embed_ir,
        enclosure=enclosure,
        backoff=backoff,
    )
    text = json.dumps(doc, indent=1, allow_nan=False) + "\n"
    write_output(path, text)  # atomic; the output-path rules of lmic.output
    return doc


def _schema() -> dict[str, Any]:
    try:
        from lmic.schemas import load_schema

        return load_schema("certificate")
    except (ImportError, LmicError):
        here = Path(__file__).resolve().parents[2] / "schemas" / "certificate.schema.json"
        return json.loads(here.read_text(encoding="utf-8"))


def _reject_constant(name: str) -> float:
    raise ValueError(f"{name} is not allowed")


def read_certificate(path: str | os.PathLike[str]) -> dict[str, Any]:
    """Read and validate a certificate file.

    Raises
    ------
    CertificateError
        One line: unreadable, not JSON (e.g. truncated), unknown schema version, or not
        following ``schemas/certificate.schema.json`` (naming the field).

    Examples
    --------
    >>> import tempfile, os
    >>> f = os.path.join(tempfile.mkdtemp(), "c.json")
    >>> _ = open(f, "w").write('{"lmic_certificate": 99}')
    >>> read_certificate(f)
    Traceback (most recent call last):
    ...
    lmic.errors.CertificateError: c.json: unknown certificate schema version 99 (this lmic reads 1)
    """
    p = Path(path)
    name = p.name
    from lmic.limits import MAX_INPUT_BYTES, MAX_INT_DIGITS, check_depth

    def parse_int(t: str) -> int:
        if len(t.lstrip("-")) > MAX_INT_DIGITS:
            raise ValueError(f"an integer of {len(t.lstrip('-'))} digits (at most {MAX_INT_DIGITS})")
        return int(t)

    def parse_float(t: str) -> float:
        value = float(t)
        if not math.isfinite(value):
            raise ValueError(f"the number {t[:24]} overflows float64")
        return value

    try:
        if p.stat().st_size > MAX_INPUT_BYTES:
            raise CertificateError(f"{p}: larger than the input limit of {MAX_INPUT_BYTES} bytes")
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise CertificateError(f"{p}: no such certificate file") from None
    except (OSError, UnicodeDecodeError) as err:
        raise CertificateError(f"{p}: cannot read: {err}") from None
    if not text.strip():
        raise CertificateError(f"{name}: empty certificate file")
    try:
        doc = json.loads(text, parse_constant=_reject_constant, parse_int=parse_int, parse_float=parse_float)
    except json.JSONDecodeError as err:
        raise CertificateError(
            f"{name}: not valid JSON (truncated or corrupted?) at line {err.lineno} column {err.colno}: {err.msg}"
        ) from None
    except ValueError as err:
        raise CertificateError(f"{name}: {err}") from None
    except RecursionError:
        raise CertificateError(f"{name}: nested too deeply") from None
    check_depth(doc, name, CertificateError)
    if not isinstance(doc, dict) or "lmic_certificate" not in doc:
        raise CertificateError(f"{name}: not an lmic certificate (no 'lmic_certificate' key)")
    version = doc["lmic_certificate"]
    if version != SCHEMA_VERSION or isinstance(version, bool):
        raise CertificateError(
            f"{name}: unknown certificate schema version {version!r} (this lmic reads {SCHEMA_VERSION})"
        )
    import jsonschema

    validator = jsonschema.Draft202012Validator(_schema())
    errors = sorted(validator.iter_errors(doc), key=lambda e: list(e.absolute_path))
    if errors:
        first = errors[0]
        where = "".join(f"[{p}]" if isinstance(p, int) else f".{p}" for p in first.absolute_path).lstrip(".")
        msg = " ".join(first.message.split())
        if len(msg) > 160:
            msg = msg[:157] + "..."
        raise CertificateError(f"{name}: {where or 'top level'}: {msg}")
    return doc


#: fields that carry no claim: never compared, not covered by the integrity hash, free to differ
#: (``lmic audit --json`` lists them). Patterns match dotted paths (``fnmatch``; ``*`` one key).
INFORMATIONAL = (
    "created",
    "certificate.time_s",
    "certificate.*.time_s",
    "certificate.*.*.time_s",
)

#: claims the audit cannot recompute: the solver's own answer (``solution.x`` and the Farkas
#: ray are the *inputs* of the recomputation), the backend's report, the writer's version, the
#: embedded IR (its content is checked through ``ir.sha256``) and where the system file was.
#: They are covered by the integrity hashes; every other field is recomputed and compared.
CLAIMED = (
    "lmic",
    "theorem.provider",  # a new plugin version with the same template is a note (theorem_changes)
    "system.path",
    "ir.embedded",
    "backend",
    "solution.x",
    "solution.objective",
    "solution.farkas",
)

#: free text and bit sizes inside recomputed sections: covered by the hash, not compared
#: (a reason quotes numbers whose last digits may vary between BLAS builds; the exact Farkas
#: multipliers come out of a float least-squares repair)
_TEXT_KEYS = ("reason", "note", "detail", "statement", "denominator_bits")

#: tolerances that are looser when larger / when smaller (strict_rel is a required margin,
#: zero_rel the fraction below which a point counts as ~0 and is rejected)
_LOOSER_IF_LARGER = ("rel", "objective_rel", "farkas_rel")
_LOOSER_IF_SMALLER = ("strict_rel", "zero_rel")


def _matches(path: str, patterns: tuple[str, ...]) -> bool:
    parts = path.split(".")
    for pat in patterns:
        pp = pat.split(".")
        if len(pp) <= len(parts) and all(fnmatch.fnmatchcase(a, b) for a, b in zip(parts, pp, strict=False)):
            if len(pp) == len(parts) or pat in CLAIMED:
                return True
    return False


def _strip(value: Any, where: str) -> Any:
    """A copy of ``value`` without its informational fields."""
    if isinstance(value, dict):
        out = {}
        for k, v in value.items():
            sub = f"{where}.{k}" if where else str(k)
            if _matches(sub, INFORMATIONAL):
                continue
            out[k] = _strip(v, sub)
        return out
    if isinstance(value, list):
        return [_strip(v, where) for v in value]
    return value


def _digest(value: Any) -> str:
    text = json.dumps(value, sort_keys=True, separators=(",", ":"), allow_nan=False, ensure_ascii=True)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def _field_paths(doc: dict[str, Any]) -> list[tuple[str, Any]]:
    """The hashed fields: every key down to depth 2, in document order (informational left out)."""
    out: list[tuple[str, Any]] = []
    for k, v in doc.items():
        if k == "integrity" or _matches(k, INFORMATIONAL):
            continue
        if isinstance(v, dict) and v:
            for kk, vv in v.items():
                path = f"{k}.{kk}"
                if not _matches(path, INFORMATIONAL):
                    out.append((path, _strip(vv, path)))
        else:
            out.append((k, _strip(v, k)))
    return out


def integrity_of(doc: dict[str, Any]) -> dict[str, Any]:
    """The ``integrity`` section of a certificate: SHA-256 of every field (depth <= 2) and of all.

    Anyone can recompute these hashes: they do not make a forgery harder, the recomputation
    does. They cover the fields :func:`audit_certificate` cannot recompute (:data:`CLAIMED`,
    free text), so that a change to any non-informational field is detected and named.

    Examples
    --------
    >>> sec = integrity_of({"lmic_certificate": 1, "created": "now", "backend": {"name": "scs"}})
    >>> sorted(sec["fields"]), len(sec["sha256"])
    (['backend.name', 'lmic_certificate'], 64)
    """
    fields = {path: _digest(v) for path, v in _field_paths(doc)}
    body = {k: v for k, v in doc.items() if k != "integrity"}
    return {"algorithm": "sha256", "fields": fields, "sha256": _digest(_strip(body, ""))}


def _integrity_finding(doc: dict[str, Any]) -> tuple[str, str] | None:
    """The first field whose hash differs from the recorded one (field, message), or None."""
    rec = doc.get("integrity")
    if not isinstance(rec, dict) or not isinstance(rec.get("fields"), dict):
        return ("integrity", "integrity: the certificate records no integrity hashes")
    want = integrity_of(doc)
    recorded = rec["fields"]
    for path, digest in want["fields"].items():
        if recorded.get(path) != digest:
            why = "not hashed in the file" if path not in recorded else "its hash differs from integrity.fields"
            return (path, f"{path} was modified ({why})")
    for path in recorded:
        if path not in want["fields"]:
            return (f"integrity.fields.{path}", f"integrity.fields names {path}, which the certificate lacks")
    if rec.get("sha256") != want["sha256"] or rec.get("algorithm") != "sha256":
        return ("integrity.sha256", "integrity.sha256 differs from the content")
    return None


def looser_tolerances(recorded: dict[str, Any], than: Tolerances) -> list[tuple[str, Any, float]]:
    """Tolerances of ``recorded`` that are looser than ``than`` (or unknown): ``(name, value, bound)``.

    Examples
    --------
    >>> looser_tolerances({"rel": 1e300, "strict_rel": 1e-12}, Tolerances())
    [('rel', 1e+300, 1e-08)]
    >>> looser_tolerances({"strict_rel": 0.0}, Tolerances())
    [('strict_rel', 0.0, 1e-12)]
    """
    ref = than.to_dict()
    out: list[tuple[str, Any, float]] = []
    for key, value in recorded.items():
        num = _num(value)
        if key not in ref or num is None or not math.isfinite(num):
            out.append((key, value, float("nan") if key not in ref else ref[key]))
        elif key in _LOOSER_IF_LARGER and num > ref[key]:
            out.append((key, value, ref[key]))
        elif key in _LOOSER_IF_SMALLER and num < ref[key]:
            out.append((key, value, ref[key]))
        elif key not in _LOOSER_IF_LARGER and key not in _LOOSER_IF_SMALLER and num != ref[key]:
            out.append((key, value, ref[key]))
    return out


def strictest(a: Tolerances, b: Tolerances) -> Tolerances:
    """Key by key, the stricter of two tolerance sets.

    >>> strictest(Tolerances(rel=1e-6), Tolerances(rel=1e-9, strict_rel=0.0)).to_dict()["rel"]
    1e-09
    """
    da, db = a.to_dict(), b.to_dict()
    out = {}
    for k in da:
        out[k] = max(da[k], db[k]) if k in _LOOSER_IF_SMALLER else min(da[k], db[k])
    return Tolerances(**out)


@dataclass
class AuditResult:
    """The outcome of :func:`audit_certificate`.

    Attributes
    ----------
    ok : bool
        Every hash and number matches the recomputation.
    verdict : str
        The recomputed verdict when ``ok``; ``"rejected"`` otherwise.
    recorded_verdict : str
    field : str or None
        The first field that differs.
    message : str
        One line.
    certificate : Certificate or None
        The recomputed certificate (``None`` when the audit stopped before certifying).
    exact : bool
        Whether an exact proof was run (always when the certificate records one).
    theorem : str or None
    checked : list of str
        What was checked, in order.
    label : str
        The verdict as displayed: ``certified (exact)`` when an exact proof backs it.
    tolerances : dict
        The tolerances the audit decided with (lmic's defaults or stricter).
    informational : list of str
        The fields left unchecked (:data:`INFORMATIONAL`).
    """

    ok: bool
    verdict: str
    recorded_verdict: str
    field: str | None = None
    message: str = ""
    certificate: Certificate | None = None
    exact: bool = False
    theorem: str | None = None
    checked: list[str] = dataclasses.field(default_factory=list)
    label: str = ""
    tolerances: dict[str, float] = dataclasses.field(default_factory=lambda: Tolerances().to_dict())
    informational: list[str] = dataclasses.field(default_factory=lambda: list(INFORMATIONAL))

    def __post_init__(self) -> None:
        if not self.label:
            self.label = self.verdict

    def to_dict(self) -> dict[str, Any]:
        """JSON-able form."""
        return _json(
            {
                "ok": self.ok,
                "verdict": self.verdict,
                "recorded_verdict": self.recorded_verdict,
                "field": self.field,
                "message": self.message,
                "theorem": self.theorem,
                "exact": self.exact,
                "label": self.label,
                "checked": self.checked,
                "tolerances": self.tolerances,
                "informational": self.informational,
                "certificate": None if self.certificate is None else self.certificate.to_dict(),
            }
        )


def _fail(doc: dict, fld: str, message: str, cert: Certificate | None = None, **kw: Any) -> AuditResult:
    rec = doc.get("certificate")
    return AuditResult(
        ok=False,
        verdict="rejected",
        recorded_verdict=str(rec.get("verdict")) if isinstance(rec, dict) else "?",
        field=fld,
        message=message,
        certificate=cert,
        **kw,
    )


def _rebuild(doc: dict[str, Any], base: Path) -> tuple[Problem, str, Any]:
    """The problem to audit against, a label, and the loaded system (None for an embedded IR)."""
    embedded = doc["ir"]["embedded"]
    theorem = doc["theorem"]
    if embedded is not None:
        from lmic.ir.jsonio import problem_from_dict

        try:
            problem = problem_from_dict(embedded, source="certificate ir.embedded")
        except LmicError as err:
            raise CertificateError(f"embedded IR is malformed: {err}") from None
        return problem, "embedded IR", None
    if theorem is None or doc["system"] is None or not doc["system"].get("path"):
        raise CertificateError("the certificate neither embeds its IR nor records a theorem and a system file")
    from lmic.compile import compile_theorem
    from lmic.registry import get_theorem
    from lmic.system import load_system

    try:
        thm = get_theorem(theorem["id"])
    except LmicError as err:
        if "ambiguous" in str(err):  # two plugins offer the id: refuse rather than guess
            raise CertificateError(str(err)) from None
        raise CertificateError(f"theorem '{theorem['id']}' is not installed here") from None
    sys_path = Path(doc["system"]["path"])
    if not sys_path.is_absolute():
        sys_path = base / sys_path
    if not sys_path.is_file():
        raise CertificateError(f"system file {sys_path} (recorded in the certificate) not found")
    system = load_system(sys_path)
    if system.data_hash() != doc["system"]["sha256"]:
        why = f"system.sha256 differs: the data of {sys_path.name} changed since the certificate was written"
        return None, why, system  # type: ignore[return-value]
    params = doc["params"] or {}
    problem = compile_theorem(thm, system, params=params)
    return problem, f"theorem {theorem['id']} on {sys_path.name}", system


def _num(v: Any) -> float | None:
    if isinstance(v, bool):
        return None
    if isinstance(v, int | float):
        return float(v)
    if v in ("nan", "inf", "-inf"):
        return float(v)
    return None


def _close(a: float, b: float, atol: float) -> bool:
    if math.isnan(a) or math.isnan(b):
        return math.isnan(a) and math.isnan(b)
    if math.isinf(a) or math.isinf(b):
        return a == b
    return abs(a - b) <= 1e-9 * max(abs(a), abs(b)) + atol


def _first_diff(rec: Any, new: Any, where: str, atol: float = 1e-300) -> tuple[str, Any, Any] | None:
    """The first leaf where the recorded and the recomputed value differ (numbers to 1e-9 rel)."""
    ra, na = _num(rec), _num(new)
    if ra is not None and na is not None and type(rec) is not str and type(new) is not str:
        if isinstance(rec, int) != isinstance(new, int) and (isinstance(rec, int) or isinstance(new, int)):
            if float(rec) != float(new):
                return (where, rec, new)
        return None if _close(ra, na, atol) else (where, rec, new)
    if isinstance(rec, dict) and isinstance(new, dict):
        scale = _num(new.get("scale")) if "min_eig" in new else None
        sub_atol = 1e-12 * scale if scale and math.isfinite(scale) else atol
        keys = [k for k in rec if k not in ("verdict", "label")] + [k for k in new if k not in rec]
        keys += [k for k in ("verdict", "label") if k in rec or k in new]
        for key in keys:
            sub = f"{where}.{key}"
            if key in _TEXT_KEYS or _matches(sub, INFORMATIONAL):
                continue
            if key not in rec or key not in new:
                return (sub, rec.get(key, "<missing>"), new.get(key, "<missing>"))
            d = _first_diff(rec[key], new[key], sub, sub_atol)
            if d:
                return d
        return None
    if isinstance(rec, list) and isinstance(new, list):
        if len(rec) != len(new):
            return (f"{where} (length)", len(rec), len(new))
        for i, (a, b) in enumerate(zip(rec, new, strict=True)):
            d = _first_diff(a, b, f"{where}[{i}]", atol)
            if d:
                return d
        return None
    if type(rec) is not type(new):
        return (where, rec, new)
    return None if rec == new else (where, rec, new)


def _short(v: Any) -> str:
    s = json.dumps(v) if not isinstance(v, str) else v
    return s if len(s) <= 60 else s[:57] + "..."


def _recomputed_diff(doc: dict[str, Any], new: dict[str, Any], infeasible: bool) -> tuple[str, Any, Any] | None:
    """First difference between the file and the regenerated document, on recomputed fields."""
    keys = [k for k in doc if k != "integrity"] + [k for k in new if k not in doc and k != "integrity"]
    for key in keys:
        if _matches(key, INFORMATIONAL) or _matches(key, CLAIMED):
            continue
        if key not in new or (new[key] is None and doc.get(key) is not None):
            continue  # a claim this lmic cannot recompute (e.g. the system of an embedded IR): hashed
        if key not in doc:
            return (key, "<missing>", new[key])
        rec, fresh = doc[key], new[key]
        if isinstance(rec, dict) and isinstance(fresh, dict):
            sub_keys = [k for k in rec if k not in ("verdict", "label")] + [k for k in fresh if k not in rec]
            sub_keys += [k for k in ("verdict", "label") if k in rec or k in fresh]
            for sk in sub_keys:
                path = f"{key}.{sk}"
                if _matches(path, INFORMATIONAL) or _matches(path, CLAIMED) or sk in _TEXT_KEYS:
                    continue
                if sk not in fresh or (fresh[sk] is None and rec.get(sk) is not None):
                    continue  # not recomputable here: hash-covered
                if sk not in rec:
                    return (path, "<missing>", fresh[sk])
                # a Farkas verification is normalised to sum tr Z_i + sum |y_r| = 1 and a repaired
                # certificate comes out of least squares: its round-off-level entries may differ
                # in the last bits between BLAS builds, so they compare with an absolute 1e-12
                atol = 1e-12 if path == "certificate.farkas" or (path == "certificate.exact" and infeasible) else 1e-300
                d = _first_diff(rec[sk], fresh[sk], path, atol)
                if d:
                    return d
            continue
        d = _first_diff(rec, fresh, key)
        if d:
            return d
    return None


def audit_certificate(
    path: str | os.PathLike[str],
    exact: bool = False,
    tol: Tolerances | float | dict | None = None,
) -> AuditResult:
    """Recompute a certificate from scratch and compare it with the file.

    The audit trusts nothing in the file but the data it recomputes from: it decides with its
    own tolerances (``tol``: lmic's defaults, or stricter), and a file that records looser ones
    is rejected, naming the tolerance. It rebuilds the IR (recompiling the theorem on the system
    file, or loading the embedded IR, both checked against ``ir.sha256``), re-runs the certifier
    on the recorded point (or Farkas ray), regenerates the whole document with
    :func:`certificate_document` and compares it field by field; the fields it cannot recompute
    (:data:`CLAIMED`, free text) are checked against the ``integrity`` hashes. Only the
    :data:`INFORMATIONAL` fields may differ.

    Parameters
    ----------
    path : path
        The certificate file.
    exact : bool
        Also run the exact rational proof when the file does not record one (it is reported,
        not compared). A recorded exact proof is always re-run and compared: the recorded
        verdict may rest on it.
    tol : Tolerances, float or dict, optional
        The auditor's tolerances; looser than lmic's defaults is refused (``LmicError``).

    Returns
    -------
    AuditResult
        ``ok`` is False (verdict ``rejected``) when any hash or number differs; ``field`` names
        the first one.

    Raises
    ------
    CertificateError
        Malformed, truncated or unknown-version file; theorem not installed; system file
        missing (one line each).

    Examples
    --------
    >>> import tempfile, os, json, numpy as np, scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
    >>> p = Problem([Variable("p", "scalar", (1, 1))], [LMI("p>0", 1, sp.csc_matrix([[0., 1.]]))],
    ...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
    >>> s = Solution("optimal", x=np.array([2.0]))
    >>> f = os.path.join(tempfile.mkdtemp(), "c.json")
    >>> doc = write_certificate(f, p, s, certify(p, s))
    >>> doc["solution"]["x"] = [-1.0]; _ = open(f, "w").write(json.dumps(doc))
    >>> r = audit_certificate(f)
    >>> r.ok, r.field
    (False, 'solution.variables.p')
    """
    auditor = Tolerances.coerce(tol)
    too_loose = looser_tolerances(auditor.to_dict(), Tolerances())
    if too_loose:
        k, v, b = too_loose[0]
        raise LmicError(f"audit tolerance {k}={v} is looser than lmic's default {b}: an audit may only be stricter")
    p = Path(path)
    doc = read_certificate(p)
    theorem_id = (doc["theorem"] or {}).get("id")
    common: dict[str, Any] = {"theorem": theorem_id, "tolerances": auditor.to_dict()}
    recorded = doc["certificate"]
    # 1. the file may not ask for tolerances looser than the audit's
    # (looser than lmic's defaults; between those and stricter ones the auditor asked for, the
    # file's numbers are checked with its own tolerances and the verdict with the auditor's)
    for key, value, bound in looser_tolerances(doc["tolerances"], Tolerances()):
        what = "an unknown tolerance" if math.isnan(bound) else f"looser than lmic's default {bound:g}"
        return _fail(doc, f"tolerances.{key}", f"tolerances.{key} = {_short(value)} is {what}", **common)
    file_tol = strictest(Tolerances.coerce(dict(doc["tolerances"])), Tolerances())
    hashed = _integrity_finding(doc)
    # 2. the IR: recompiled from the theorem and the system file, or the embedded one
    try:
        problem, label, system = _rebuild(doc, p.resolve().parent)
    except LmicError as err:
        if hashed is not None:  # e.g. a modified system.path or params: name the modified field
            return _fail(doc, hashed[0], hashed[1], **common)
        if isinstance(err, CertificateError):
            raise
        raise CertificateError(f"cannot rebuild the IR the certificate records: {err}") from None
    if problem is None:
        return _fail(doc, "system.sha256", label, **common)
    checked = ["schema", "tolerances", "system.sha256" if doc["ir"]["embedded"] is None else "embedded IR"]
    if doc["ir"]["embedded"] is None:  # recompiled from the installed theorem: is it the same theorem?
        changed, note = theorem_changes(doc["theorem"], problem)
        if changed:
            return _fail(doc, "theorem.template_hash", changed, checked=checked, **common)
        if doc["theorem"] and doc["theorem"].get("template_hash"):
            checked.append("theorem.template_hash" + (f" ({note})" if note else ""))
    if ir_hash(problem) != doc["ir"]["sha256"]:
        why = (
            "the embedded IR was modified"
            if doc["ir"]["embedded"] is not None
            else "recompiling gives a different IR (the theorem plugin, the compiler or the parameters changed)"
        )
        return _fail(doc, "ir.sha256", f"ir.sha256 differs: {why}", checked=checked, **common)
    checked.append("ir.sha256")
    # 3. the solver's claims, as recorded, re-certified
    sol = doc["solution"]
    x = None if sol["x"] is None else np.asarray(sol["x"], dtype=float)
    if x is not None and x.shape != (problem.n,):
        why = f"solution.x has {x.size} entries, the IR {problem.n} variables"
        return _fail(doc, "solution.x", why, checked=checked, **common)
    backend = doc["backend"]
    status = backend["status"] if backend["status"] in STATUSES else "error"
    solution = Solution(
        status=status,
        x=x,
        objective=sol["objective"],
        backend=backend["name"] or "",
        native_status=backend.get("native_status") or "",
        farkas=sol.get("farkas"),
        margin=backend.get("margin"),
        strategy=backend.get("strategy") or "none",
        iterations=backend.get("iterations"),
        solve_s=float(backend.get("solve_s") or 0.0),
    )
    # recompute in the recorded mode: a certificate that records an exact proof may rest on it
    # (a strict LMI below the float threshold, proved exactly), so the proof is re-run
    recorded_exact = recorded.get("exact") is not None
    cert = certify(problem, solution, exact=recorded_exact, tol=file_tol)
    fresh = certificate_document(
        problem, solution, cert, system=system, path=p, embed_ir=doc["ir"]["embedded"] is not None
    )
    # 4. every recomputed field, in document order; then the hashes of the rest
    d = _recomputed_diff(doc, fresh, backend["status"] == "infeasible")
    kw = {"theorem": theorem_id, "exact": recorded_exact, "checked": checked, "tolerances": auditor.to_dict()}
    if d:
        fld, a, b = d
        if fld.startswith("solution.variables."):
            fld = ".".join(fld.split(".")[:3]).split("[")[0]  # name the variable
            msg = f"{fld} differs from the value solution.x gives"
        else:
            msg = f"{fld} differs: recorded {_short(a)}, recomputed {_short(b)}"
        return _fail(doc, fld, msg, cert, **kw)
    checked.append("recomputed fields")
    # the sections that other modules re-verify (before the hashes: they name what is wrong)
    # -- optimal-value enclosure (lmic.certify.enclosure): both ends re-verified --
    if doc.get("enclosure") is not None:
        from lmic.certify.enclosure import audit_enclosure

        try:
            enc = audit_enclosure(problem, doc["enclosure"], cert, doc.get("backoff"))
        except (ValueError, TypeError, KeyError, IndexError, AttributeError) as err:
            # a malformed section (the enclosure audit expects what lmic writes)
            fld, why = hashed if hashed is not None else ("enclosure", f"enclosure is malformed: {err}")
            return _fail(doc, fld, " ".join(why.split())[:200], cert, **kw)
        if not enc["ok"]:
            return _fail(doc, enc["field"], enc["message"], cert, **kw)
        checked.append("enclosure")
    if doc.get("backoff") is not None and doc["backoff"].get("x") is not None:  # -- lmic.backoff --
        rec_b = doc["backoff"]
        try:
            xb = np.asarray(rec_b["x"], dtype=float)
        except (ValueError, TypeError):
            xb = np.zeros(0)
        if xb.shape != (problem.n,):
            return _fail(doc, "backoff.x", "backoff.x has the wrong length", cert, **kw)
        cb = certify(problem, Solution(status=rec_b.get("status") or "optimal", x=xb), tol=file_tol)
        if cb.verdict != rec_b.get("verdict") or problem.objective.value(xb) != rec_b.get("objective"):
            return _fail(
                doc, "backoff", f"backoff differs: recorded {rec_b.get('verdict')}, recomputed {cb.verdict}", cert, **kw
            )
        checked.append("backoff")
    if hashed is not None:
        return _fail(doc, hashed[0], hashed[1], cert, **kw)
    checked.append("integrity")
    # 5. the verdict under the auditor's tolerances, when stricter than the file's
    final = strictest(file_tol, auditor)
    if final != file_tol:
        cert = certify(problem, solution, exact=recorded_exact, tol=final)
        checked.append("auditor tolerances")
        if cert.verdict != recorded["verdict"]:
            return _fail(
                doc,
                "certificate.verdict",
                f"under the audit's tolerances the verdict is {cert.verdict}, not {recorded['verdict']}: {cert.reason}",
                cert,
                **kw,
            )
    shown = cert
    msg = f"every hash and number matches ({label}); verdict {cert.label}"
    if exact and not recorded_exact:
        # asked for a proof the file does not record: run it, report it, compare nothing new
        shown = certify(problem, solution, exact=True, tol=final)
        assert shown.exact is not None
        if shown.exact["proven"]:
            msg += "; exact proof (not recorded) holds: " + shown.exact.get("statement", shown.exact["reason"])
            if shown.verdict != cert.verdict:
                msg += f" (with it the verdict would be {shown.label}; re-certify with --exact)"
        else:
            msg += "; exact proof (not recorded) not obtained: " + shown.exact["reason"]
    elif recorded_exact and cert.exact is not None:
        msg += "; exact proof re-run: " + ("holds" if cert.exact["proven"] else "not obtained: " + cert.exact["reason"])
    label_out = cert.label
    if shown is not cert and shown.verdict == cert.verdict:
        label_out = shown.label  # e.g. 'certified (exact)' from the proof run on request
    return AuditResult(
        ok=True,
        verdict=cert.verdict,
        recorded_verdict=recorded["verdict"],
        message=msg,
        certificate=shown,
        exact=exact or recorded_exact,
        theorem=theorem_id,
        checked=checked,
        label=label_out,
        tolerances=auditor.to_dict(),
    )
