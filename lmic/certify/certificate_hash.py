"""Hashes of certificate files: the IR hash and the integrity hashes of every field.

:func:`ir_hash` is the one IR hash of lmic: :func:`lmic.ir.jsonio.problem_hash` of the IR with
the volatile ``meta`` entries left out. :func:`integrity_of` hashes every field of a certificate
(depth <= 2) except the informational ones (:data:`INFORMATIONAL`). Split out of
:mod:`lmic.certify.certificate`, which re-exports every public name.

Examples
--------
>>> integrity_of({"lmic_certificate": 1})["algorithm"]
'sha256'
"""

from __future__ import annotations

import fnmatch
import functools
import hashlib
import json
from dataclasses import replace
from typing import Any

from lmic.ir.problem import Problem

__all__ = ["ir_hash", "integrity_of", "INFORMATIONAL", "CLAIMED"]

#: ``provider`` is checked on its own (:func:`theorem_changes`): a new plugin version whose
#: template is unchanged compiles to the same IR
_VOLATILE_META = ("system_path", "provider")


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


@functools.lru_cache(maxsize=8192)  # the same paths come back for every list item and certificate
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
