"""The claims of an audit of published results and the report that gathers them.

Examples
--------
>>> c = Claim(["P"], "point", "packed and certified", "certified", agrees=True)
>>> c.decisive, AuditReport("t", "s", [c]).exit_code()
(True, 0)
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["Claim", "AuditReport", "DECISIVE", "STATUS_WORDS", "finding_of", "short"]

#: claim kinds that decide the exit code
DECISIVE = ("point", "partial point", "gain", "status", "param")

STATUS_WORDS = {"feasible": "feasible", "infeasible": "infeasible", "optimal": "feasible"}


@dataclass
class Claim:
    """One published claim and what lmic found.

    Attributes
    ----------
    keys : list of str
        The published keys it covers.
    kind : str
        ``point``, ``partial point``, ``gain``, ``status``, ``param``, ``value`` or ``skipped``.
    route : str
        How it was decided, in words.
    finding : str
        ``certified``, ``rejected``, ``infeasible`` (proven, or reported by the solver: see
        ``proof``), ``not reproducible``, ``matches``, ``differs`` or ``skipped``.
    agrees : bool or None
        Whether the computation supports what the paper claims.
    verdict : str
        The certifier's verdict for the computation (``-`` for values).
    proof : str
        How the finding was reached (``certified (exact)``, ``infeasible-certified`` ...).
    lmis : list of dict
        Per LMI at the point: ``name``, ``relation``, ``extreme`` (the paper's ``lambda_max``
        for ``<`` LMIs, ``lambda_min`` for ``>``), ``rel_margin``, ``ok``.
    margin : float or None
        The smallest ``lambda_min`` of the normalised LMIs (``> 0`` is strictly satisfied).
    published, computed : object
        The printed and the computed value (values, gains' objective, status).
    difference : float or None
        ``max |computed - published|`` (values).
    objective : float or None
    derived : dict
        Scalar derived quantities at the point (e.g. ``gamma_star`` at a fixed gain).
    checks : list of dict
        The theorem's checks at the point (``name``, ``value``, ``ok``).
    reason : str
    """

    keys: list[str]
    kind: str
    route: str
    finding: str
    agrees: bool | None = None
    verdict: str = "-"
    proof: str = ""
    lmis: list[dict[str, Any]] = field(default_factory=list)
    margin: float | None = None
    published: Any = None
    computed: Any = None
    difference: float | None = None
    rel_difference: float | None = None
    objective: float | None = None
    derived: dict[str, float] = field(default_factory=dict)
    checks: list[dict[str, Any]] = field(default_factory=list)
    reason: str = ""
    solve_s: float = 0.0

    @property
    def decisive(self) -> bool:
        """True for the kinds that decide the exit code (:data:`DECISIVE`)."""
        return self.kind in DECISIVE

    def to_dict(self) -> dict[str, Any]:
        """JSON-able form."""
        from lmic.jsonable import to_jsonable

        return to_jsonable(
            {
                "keys": self.keys,
                "kind": self.kind,
                "route": self.route,
                "finding": self.finding,
                "agrees": self.agrees,
                "verdict": self.verdict,
                "proof": self.proof,
                "margin": self.margin,
                "lmis": self.lmis,
                "checks": self.checks,
                "published": self.published,
                "computed": self.computed,
                "difference": self.difference,
                "rel_difference": self.rel_difference,
                "objective": self.objective,
                "derived": self.derived,
                "reason": self.reason,
                "solve_s": self.solve_s,
            }
        )


@dataclass
class AuditReport:
    """Every claim of one system file's ``published:`` section."""

    theorem: str
    system: str
    claims: list[Claim]
    params: dict[str, Any] = field(default_factory=dict)
    time_s: float = 0.0

    def claim(self, key: str, kind: str | None = None) -> Claim:
        """The claim covering ``key`` (of ``kind`` if given).

        Raises :class:`KeyError` if none.
        """
        for c in self.claims:
            if key in c.keys and (kind is None or c.kind == kind):
                return c
        raise KeyError(f"no {kind or ''} claim for published '{key}'".replace("  ", " "))

    def exit_code(self) -> int:
        """0 certified, 1 rejected or not reproducible, 3 proven infeasible, 4 bounded infeasibility only."""
        decisive = [c for c in self.claims if c.decisive]
        if decisive:
            findings = [c.finding for c in decisive]
            if "rejected" in findings:
                return 1
            if "infeasible" in findings:
                return 3
            if "infeasible-bounded" in findings and all(f in ("certified", "infeasible-bounded") for f in findings):
                return 4  # lmic.outcome: "no solution with ||x||_inf <= R" only
            if any(f != "certified" for f in findings):
                return 1
            return 0
        values = [c for c in self.claims if c.kind == "value"]
        if values and all(c.finding == "matches" for c in values):
            return 0
        return 1

    def to_dict(self) -> dict[str, Any]:
        """The ``--json`` object."""
        from lmic._version import __version__

        return {
            "lmic": __version__,
            "theorem": self.theorem,
            "system": self.system,
            "params": self.params,
            "claims": [c.to_dict() for c in self.claims],
            "exit_code": self.exit_code(),
            "time_s": self.time_s,
        }


def finding_of(outcome: str) -> str:
    """The finding of a claim decided by solving: ``feasible`` -> ``certified``, else as the outcome says.

    >>> finding_of("feasible"), finding_of("undecided")
    ('certified', 'not reproducible')
    """
    return {"feasible": "certified", "infeasible": "infeasible", "infeasible-bounded": "infeasible-bounded"}.get(
        outcome, "not reproducible"
    )


def short(value: Any) -> Any:
    """A published value for the report (matrices as nested lists).

    >>> short(np.eye(1)), short(0.5)
    ([[1.0]], 0.5)
    """
    if isinstance(value, np.ndarray):
        return value.tolist()
    return value
