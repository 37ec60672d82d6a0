"""The audit of a system file's ``published:`` section: every entry a claim, each decided by its route.

Examples
--------
>>> audit_published("thesis.lyapunov", {"data": {"A": [[-1.0]]}})
Traceback (most recent call last):
...
lmic.errors.DataError: <system>: has no 'published:' section to audit
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from typing import Any

import numpy as np

from lmic.errors import LmicError
from lmic.studies.published.claims import AuditReport, Claim, short
from lmic.studies.published.context import AuditContext
from lmic.studies.published.routes import gain_claims, param_claim, point_claims, status_claim, value_claims

__all__ = ["audit_published"]


def audit_published(
    theorem: str,
    system: Any,
    params: Mapping[str, Any] | None = None,
    *,
    backend: Any = None,
    options: Any = None,
    rtol: float = 0.05,
) -> AuditReport:
    """Decide every claim of ``system``'s ``published:`` section with ``theorem``.

    Parameters
    ----------
    theorem : str
        Theorem id.
    system : path, dict or System
        A system file with a ``published:`` section.
    params : mapping, optional
        Parameter overrides (``-p k=v``).
    backend : str or Backend
    options : SolveOptions, optional
    rtol : float
        Relative tolerance for ``value`` claims (printed numbers are rounded).

    Returns
    -------
    AuditReport

    Raises
    ------
    DataError
        No ``published:`` section, or a published variable of the wrong shape or structure.

    Examples
    --------
    >>> rep = audit_published("thesis.lyapunov", "examples/thesis.lyapunov.ex2_3_2.yaml")  # doctest: +SKIP
    >>> rep.claims[0].finding, round(rep.claims[0].lmis[1]["extreme"], 4)                  # doctest: +SKIP
    ('certified', -0.0003)
    """
    t0 = time.perf_counter()
    if not (rtol >= 0 and math.isfinite(rtol)):
        raise LmicError(f"--rtol must be a non-negative number, got {rtol}")
    a = AuditContext(theorem, system, params, backend, options, rtol)
    pub = a.sysobj.published
    used = point_claims(a, pub)
    used |= gain_claims(a, pub)
    if "status" in pub:
        used.add("status")
        if isinstance(pub["status"], str):
            status_claim(a, pub["status"])
        else:
            a.claims.append(Claim(["status"], "skipped", "-", "skipped", reason="status is not a word"))
    value_keys = []
    for key, value in pub.items():
        if key in used:
            continue
        known = {*a.param_names, *a.derived_names, *a.const_names, *a.var_names}
        if isinstance(value, str) and key in known:
            a.claims.append(Claim([key], "skipped", "-", "skipped", reason=f"{value!r} is not a number"))
        elif key in a.param_names:
            if np.size(value) == 1:
                param_claim(a, key, float(np.asarray(value).reshape(-1)[0]))
            else:
                reason = f"parameter '{key}' is a number, not a {np.shape(value)} matrix"
                a.claims.append(Claim([key], "skipped", "-", "skipped", published=short(value), reason=reason))
        elif key in a.derived_names or key in a.const_names:
            value_keys.append(key)
        else:
            what = (
                "input data of the system file"
                if key in a.data_names
                else (f"not a variable, gain, derived quantity, constant or parameter of {a.plan.id}")
            )
            a.claims.append(
                Claim([key], "skipped", "-", "skipped", published=short(value), reason=f"'{key}' is {what}")
            )
    value_claims(a, value_keys, pub)
    return AuditReport(
        theorem=a.plan.id,
        system=a.sysobj.path or a.sysobj.label,
        claims=a.claims,
        params=dict(params or {}),
        time_s=time.perf_counter() - t0,
    )
