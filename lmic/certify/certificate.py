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

The module is split by job and re-exports every name it had: the file format and reader
(:mod:`lmic.certify.certificate_format`), writing (:mod:`lmic.certify.certificate_write`),
hashing (:mod:`lmic.certify.certificate_hash`) and the audit (:mod:`lmic.certify.audit`).
"""

from __future__ import annotations

from lmic.certify.audit import AuditResult, audit_certificate, looser_tolerances, strictest
from lmic.certify.certificate_format import SCHEMA_VERSION, _schema, read_certificate
from lmic.certify.certificate_hash import CLAIMED, INFORMATIONAL, _matches, integrity_of, ir_hash
from lmic.certify.certificate_write import certificate_document, theorem_changes, write_certificate

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
    "theorem_changes",
    "_matches",
    "_schema",
]
