"""Certificates: independent verification of a solver's answer, from the IR alone.

* :func:`certify` (:mod:`lmic.certify.check`): eigenvalue margins, residuals, objective,
  derived gains and theorem checks, and a verdict;
* :mod:`lmic.certify.exact`: exact rational proofs of every LMI;
* :mod:`lmic.certify.farkas`: verification of dual certificates of infeasibility;
* :mod:`lmic.certify.certificate`: certificate files (write, read, audit).

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
>>> from lmic.solution import Solution
>>> p = Problem([Variable("p", "scalar", (1, 1))], [LMI("p > 0", 1, sp.csc_matrix([[0., 1.]]))],
...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
>>> certify(p, Solution("optimal", x=np.array([1.0]))).verdict
'certified'
"""

from __future__ import annotations

from lmic.certify.check import VERDICTS, Certificate, Tolerances, certified_solution, certify

__all__ = [
    "VERDICTS",
    "Certificate",
    "Tolerances",
    "certify",
    "certified_solution",
    "write_certificate",
    "read_certificate",
    "audit_certificate",
    "AuditResult",
    "certificate_document",
]


def __getattr__(name: str):
    # certificate files need the IR JSON layer; import it only when asked for
    if name in (
        "write_certificate",
        "read_certificate",
        "audit_certificate",
        "AuditResult",
        "certificate_document",
    ):
        from lmic.certify import certificate

        return getattr(certificate, name)
    raise AttributeError(f"module 'lmic.certify' has no attribute '{name}'")
