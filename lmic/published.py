"""Deprecated alias of :mod:`lmic.studies.published` (the audit of published results moved there).

Examples
--------
>>> from lmic.published import audit_published as a
>>> from lmic.studies.published import audit_published as b
>>> a is b
True
"""

from __future__ import annotations

from lmic.studies.published import (
    DECISIVE,
    AuditReport,
    Claim,
    audit_published,
    fix_variables,
    lmi_extremes,
    recover_variables,
)

__all__ = [
    "Claim",
    "AuditReport",
    "audit_published",
    "fix_variables",
    "recover_variables",
    "lmi_extremes",
    "DECISIVE",
]
