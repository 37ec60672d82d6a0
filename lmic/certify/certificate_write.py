"""Writing certificate files: the document (:func:`certificate_document`) and the atomic write.

Split out of :mod:`lmic.certify.certificate`, which re-exports every public name.

Examples
--------
>>> _versions("clarabel", {})["lmic"] == __version__
True
"""

from __future__ import annotations

import datetime as _dt
import functools
import json
import os
from pathlib import Path
from typing import Any

import numpy as np

from lmic._version import __version__
from lmic.certify.certificate_format import SCHEMA_VERSION
from lmic.certify.certificate_hash import integrity_of, ir_hash
from lmic.certify.check import Certificate
from lmic.ir.problem import Problem
from lmic.jsonable import to_jsonable
from lmic.solution import Solution

__all__ = ["certificate_document", "write_certificate", "theorem_changes"]

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


@functools.lru_cache(maxsize=64)
def _installed_version(name: str) -> str | None:
    """The installed version of distribution ``name`` (read once per process: a study's worker
    writes hundreds of certificates)."""
    from importlib import metadata

    try:
        return metadata.version(name)
    except metadata.PackageNotFoundError:
        return None


def _versions(backend: str, info: dict[str, Any]) -> dict[str, str]:
    out: dict[str, str] = {"lmic": __version__}
    names = {"numpy", "scipy", "python-flint"}
    head = backend.split(":")[0].lower()
    if head in _PACKAGES:
        names.add(_PACKAGES[head])
    tail = backend.split(":")[1].lower() if ":" in backend else ""
    if tail in _PACKAGES:
        names.add(_PACKAGES[tail])
    for name in sorted(names):
        version = _installed_version(name)
        if version is not None:
            out[name] = version
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
    unbounded: dict[str, Any] | None = None,
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
    unbounded : dict, optional
        An ``unbounded-certified`` outcome's exact improving ray
        (:mod:`lmic.route_unbounded`): the audit re-proves it exactly, and the point is the
        certified feasible point.

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
    >>> from lmic.certify.check import certify
    >>> from lmic.certify.certificate_write import write_certificate
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
    if unbounded is not None:  # -- unboundedness: exact improving ray (lmic.route_unbounded) --
        doc["unbounded"] = unbounded
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
    unbounded: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """Write a certificate file atomically (temporary file + rename); return its content.

    Examples
    --------
    >>> import tempfile, os, numpy as np, scipy.sparse as sp, json
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
    >>> from lmic.certify.check import certify
    >>> from lmic.certify.certificate_write import write_certificate
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
        unbounded=unbounded,
    )
    text = json.dumps(doc, indent=1, allow_nan=False) + "\n"
    write_output(path, text)  # atomic; the output-path rules of lmic.output
    return doc
