"""The certifier's data types: the verdicts, the tolerances and the :class:`Certificate` it returns.

Split out of :mod:`lmic.certify.check` (which re-exports every name); the rules that fill a
:class:`Certificate` are in :mod:`lmic.certify.margins` (LMIs and linear rows),
:mod:`lmic.certify.derived` (derived quantities, checks, objective) and :func:`lmic.certify.check.certify`.

Examples
--------
>>> Certificate("rejected", reason="LMI 'p > 0' violated").ok
False
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, fields, is_dataclass
from typing import Any

from lmic.errors import LmicError
from lmic.jsonable import to_jsonable

__all__ = ["VERDICTS", "Tolerances", "Certificate"]

#: The verdicts of the certifier (``infeasible-bounded``: only "no solution with ||x||_inf <= R").
VERDICTS = ("certified", "rejected", "infeasible-certified", "infeasible-bounded", "unverified")


@dataclass(frozen=True)
class Tolerances:
    """Thresholds of the certifier (all relative; see the module docstring).

    Parameters
    ----------
    rel : float
        Float tolerance of non-strict LMIs, equality rows and non-strict ``ge`` rows: within
        it a constraint is not violated but not proved either, and only an exact proof makes
        the point ``certified`` (:mod:`lmic.certify.check`); beyond it, a violation.
    strict_rel : float
        Minimum relative margin of a strict LMI or a strict row (never below the float64
        error bound of the evaluation).
    zero_rel : float
        A point whose term scale is below this fraction of the coefficient scale is "~0".
    objective_rel : float
        Allowed relative disagreement between the recomputed and the claimed objective.
    farkas_rel : float
        Relative residual allowed in a Farkas certificate (:mod:`lmic.certify.farkas`).

    Examples
    --------
    >>> Tolerances().rel
    1e-08
    >>> Tolerances.coerce(1e-6).rel, Tolerances.coerce({"strict_rel": 1e-9}).strict_rel
    (1e-06, 1e-09)
    """

    rel: float = 1e-8
    strict_rel: float = 1e-12
    zero_rel: float = 1e-12
    objective_rel: float = 1e-6
    farkas_rel: float = 1e-6

    @classmethod
    def coerce(cls, tol: Tolerances | float | dict | None) -> Tolerances:
        """A :class:`Tolerances` from ``None`` (defaults), a float (``rel``) or a dict."""
        if tol is None:
            return cls()
        if isinstance(tol, Tolerances):
            return tol
        if isinstance(tol, int | float) and not isinstance(tol, bool):
            if not (math.isfinite(tol) and tol >= 0):
                raise LmicError(f"tolerance must be a finite non-negative number, got {tol}")
            return cls(rel=float(tol))
        if isinstance(tol, dict):
            known = {f.name for f in fields(cls)}
            bad = set(tol) - known
            if bad:
                raise LmicError(f"unknown tolerance(s) {sorted(bad)}; known: {sorted(known)}")
            return cls(**{k: float(v) for k, v in tol.items()})
        raise LmicError(f"tolerance must be a number or a dict, got {type(tol).__name__}")

    def to_dict(self) -> dict[str, float]:
        """JSON-able form."""
        return asdict(self)


@dataclass
class Certificate:
    """What the certifier found (JSON-able through :meth:`to_dict`).

    Attributes
    ----------
    verdict : str
        One of :data:`VERDICTS`.
    reason : str
        One line: why (the violated constraint and by how much, or what could not be verified).
    status : str
        The solver's status (a claim, reported for reference).
    lmis : list of dict
        Per LMI: ``name, dim, strict, min_eig, max_eig, max_abs, scale, min_margin,
        rel_margin, threshold, ok`` (``min_margin`` is ``lambda_min``, the absolute distance
        to the boundary of the cone; ``rel_margin = lambda_min / scale``).
    linear : list of dict
        Per row: ``name, kind, strict, residual, scale, rel_residual, ok``.
    objective : dict or None
        ``sense, value`` (recomputed), ``claimed``, ``rel_diff``, ``ok``.
    derived : list of dict
        ``name, value`` (JSON-able), ``ok`` (computable and finite), ``error``.
    checks : list of dict
        ``name, kind, value, bound, ok`` (and ``error``).
    exact : dict or None
        The exact proof, when requested: of every LMI at a rational point
        (:func:`lmic.certify.exact.prove`), or for an ``infeasible`` answer of an exact Farkas
        certificate (:func:`lmic.certify.farkas.prove_infeasible`).
    farkas : dict or None
        The verification of an infeasibility certificate (:mod:`lmic.certify.farkas`).
    margin : dict or None
        The strict-inequality margin the backend claims and the smallest one found.
    tolerances : dict
    x : list of float or None
    time_s : float

    Examples
    --------
    >>> c = Certificate("certified", exact={"proven": True})
    >>> c.ok, c.label, c.min_margin
    (True, 'certified (exact)', None)
    """

    verdict: str
    reason: str = ""
    status: str = ""
    backend: str = ""
    lmis: list[dict[str, Any]] = field(default_factory=list)
    linear: list[dict[str, Any]] = field(default_factory=list)
    objective: dict[str, Any] | None = None
    derived: list[dict[str, Any]] = field(default_factory=list)
    checks: list[dict[str, Any]] = field(default_factory=list)
    exact: dict[str, Any] | None = None
    farkas: dict[str, Any] | None = None
    margin: dict[str, Any] | None = None
    tolerances: dict[str, float] = field(default_factory=dict)
    x: list[float] | None = None
    time_s: float = 0.0

    @property
    def ok(self) -> bool:
        """True for ``certified`` and ``infeasible-certified``."""
        return self.verdict in ("certified", "infeasible-certified")

    @property
    def min_margin(self) -> float | None:
        """The smallest ``lambda_min`` over the LMIs (``None`` without a point)."""
        vals = [e["min_eig"] for e in self.lmis if e.get("min_eig") is not None]
        return min(vals) if vals else None

    @property
    def label(self) -> str:
        """The verdict, with ``(exact)`` when an exact proof backs it (``certified (exact)``,
        ``infeasible-certified (exact)``)."""
        if self.verdict in ("certified", "infeasible-certified") and self.exact and self.exact.get("proven"):
            return f"{self.verdict} (exact)"
        return self.verdict

    def to_dict(self) -> dict[str, Any]:
        """JSON-able form (floats, lists, dicts; non-finite floats become strings).

        Besides the fields it holds ``label`` (the verdict as displayed, e.g.
        ``certified (exact)``).

        >>> Certificate("certified", exact={"proven": True}).to_dict()["label"]
        'certified (exact)'
        """
        # the fields as they are (to_jsonable builds new containers: no deep copy by asdict, whose
        # copy of every LMI's report was ~10 ms of a 40-state solve); a nested dataclass as asdict had it
        d = {f.name: getattr(self, f.name) for f in fields(self)}
        d = {k: asdict(v) if is_dataclass(v) and not isinstance(v, type) else v for k, v in d.items()}
        d["label"] = self.label
        return to_jsonable(d, nonfinite="string")
