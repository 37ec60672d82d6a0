"""What lmic concluded, the evidence it rests on, and the one exit-code rule.

Every command, the Python API and every JSON object report an :class:`Outcome`:

=========================  ==========================================================  =====
verdict                    meaning                                                     exit
=========================  ==========================================================  =====
``certified``              a point verified by the certifier (feasibility), or a        0
                           certified optimum point
``rejected``               the solver's point fails the certifier                       1
``undecided``              no decision (solver error, inaccurate, time limit: the       1
                           ``reason`` says which)
``bad input``              the input is wrong (one line names what)                     2
``infeasible-certified``   a GLOBAL proof of infeasibility: an exact Farkas proof       3
                           (:func:`lmic.certify.farkas.scope`)
``infeasible-bounded``     only "no solution with ``||x||_inf <= R``" (scale-free:      4
                           with margin >= 1); never called infeasible
``unbounded-certified``    an optimisation problem with no optimum: a certified         5
                           feasible point and an exact improving ray (the optimal
                           value is ``-inf`` for ``min``, ``+inf`` for ``max``;
                           :mod:`lmic.route_unbounded`)
``interrupted``            Ctrl-C (``lmic: interrupted``)                               130
=========================  ==========================================================  =====

The evidence (:class:`Evidence`) is one of ``point`` (the certified ``x``), ``global-ray``
(a verified Farkas ray valid for the original, unbounded problem), ``bounded-ray`` (with its
radius ``R``), ``exact-proof`` (exact rational certificate) or ``none``. ``attempts`` lists every
solve the policy (:mod:`lmic.policy`) ran: backend, reduction, native status, time.

Examples
--------
>>> exit_code("infeasible-bounded"), exit_code("certified"), exit_code("bad input")
(4, 0, 2)
>>> o = Outcome("infeasible-bounded", Evidence("bounded-ray", radius=333.0), "no solution with ||x||_inf <= 333")
>>> o.exit_code(), o.to_dict()["evidence"]["radius"]
(4, 333.0)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

__all__ = [
    "VERDICTS",
    "EXIT_CODES",
    "EVIDENCE_KINDS",
    "Evidence",
    "Attempt",
    "Outcome",
    "exit_code",
    "verdict_of",
    "evidence_of",
    "rank",
]

#: verdict -> exit code (the one table; README and docs/backends.md show it)
EXIT_CODES: dict[str, int] = {
    "certified": 0,
    "rejected": 1,
    "undecided": 1,
    "bad input": 2,
    "infeasible-certified": 3,
    "infeasible-bounded": 4,
    "unbounded-certified": 5,
    "interrupted": 130,
}
VERDICTS = tuple(EXIT_CODES)
EVIDENCE_KINDS = ("point", "global-ray", "bounded-ray", "exact-proof", "none")


def exit_code(outcome: Outcome | str) -> int:
    """The exit code of an outcome (or of a verdict string); unknown verdicts are ``undecided``.

    >>> [exit_code(v) for v in VERDICTS]
    [0, 1, 1, 2, 3, 4, 5, 130]
    """
    verdict = outcome if isinstance(outcome, str) else outcome.verdict
    return EXIT_CODES.get(verdict, 1)


def rank(verdict: str) -> int:
    """How good a verdict is, for choosing among attempts (higher is better).

    >>> rank("certified") > rank("infeasible-bounded") > rank("rejected") > rank("undecided")
    True
    """
    decided = ("certified", "infeasible-certified", "unbounded-certified")
    return 4 if verdict in decided else {"infeasible-bounded": 2, "rejected": 1}.get(verdict, 0)


@dataclass
class Evidence:
    """What a verdict rests on.

    Attributes
    ----------
    kind : {"point", "global-ray", "bounded-ray", "exact-proof", "none"}
    radius : float or None
        ``bounded-ray``: no solution with ``||x||_inf <= radius``.
    statement : str
        What exactly was proven, in one line.
    """

    kind: str = "none"
    radius: float | None = None
    statement: str = ""

    def to_dict(self) -> dict[str, Any]:
        """JSON form (an infinite radius is ``None``).

        >>> Evidence("global-ray", math.inf).to_dict()["radius"] is None
        True
        """
        r = self.radius
        return {
            "kind": self.kind,
            "radius": r if r is not None and math.isfinite(r) else None,
            "statement": self.statement,
        }


@dataclass
class Attempt:
    """One solve the policy ran: backend, reduction, native and mapped status, verdict, time."""

    backend: str
    reduction: str
    status: str
    native_status: str = ""
    verdict: str = "undecided"
    time_s: float = 0.0
    note: str = ""
    solve_s: float = 0.0
    certify_s: float = 0.0

    def to_dict(self) -> dict[str, Any]:
        """JSON form.

        >>> Attempt("clarabel", "max-margin", "feasible", "Solved", "certified", 0.01).to_dict()["reduction"]
        'max-margin'
        """
        return {
            "backend": self.backend,
            "reduction": self.reduction,
            "status": self.status,
            "native_status": self.native_status,
            "verdict": self.verdict,
            "time_s": self.time_s,
            "solve_s": self.solve_s,
            "certify_s": self.certify_s,
            "note": self.note,
        }

    def line(self) -> str:
        """One human line.

        >>> Attempt("scs", "fixed-margin", "error", "", "undecided", 1.5, "iteration limit").line()
        'scs / fixed-margin: error -> undecided (1.50 s; iteration limit)'
        """
        native = f" ({self.native_status})" if self.native_status and self.native_status != self.status else ""
        note = f"; {self.note}" if self.note else ""
        return f"{self.backend} / {self.reduction}: {self.status}{native} -> {self.verdict} ({self.time_s:.2f} s{note})"


@dataclass
class Outcome:
    """What lmic concluded about one problem: verdict, evidence, reason, the attempts behind it."""

    verdict: str
    evidence: Evidence = field(default_factory=Evidence)
    reason: str = ""
    attempts: list[Attempt] = field(default_factory=list)
    solution: Any = field(default=None, repr=False)
    certificate: Any = field(default=None, repr=False)
    backend: str | None = None
    #: ``unbounded-certified``: the exact improving ray (:mod:`lmic.route_unbounded`)
    unbounded: dict[str, Any] | None = field(default=None, repr=False)
    #: seconds of the search for an improving ray after a solver said ``unbounded`` (the ray
    #: problems and the feasibility check), when it proved nothing (its solves are not among
    #: ``attempts``: :mod:`lmic.route_unbounded`)
    ray_search_s: float = 0.0

    def exit_code(self) -> int:
        """:func:`exit_code` of this outcome."""
        return exit_code(self)

    @property
    def decided(self) -> bool:
        """A certified point, a global infeasibility proof or a proof of unboundedness."""
        return self.verdict in ("certified", "infeasible-certified", "unbounded-certified")

    def to_dict(self) -> dict[str, Any]:
        """JSON form (without the solution and certificate objects)."""
        return {
            "verdict": self.verdict,
            "evidence": self.evidence.to_dict(),
            "reason": self.reason,
            "backend": self.backend,
            "attempts": [a.to_dict() for a in self.attempts],
            "exit_code": self.exit_code(),
            "unbounded": self.unbounded,
        }


def verdict_of(problem: Any, solution: Any, certificate: Any) -> str:
    """The outcome verdict of one certified solve.

    ``certified`` needs the certifier's ``certified`` and, for an optimisation problem, a solver
    status ``optimal``/``feasible`` (an inaccurate solve's point is feasible, its optimality is
    not shown); a solver ``infeasible`` whose certificate did not verify is ``undecided``.

    >>> from types import SimpleNamespace as N
    >>> p = N(objective=N(sense="min"))
    >>> verdict_of(p, N(status="inaccurate"), N(verdict="certified"))
    'undecided'
    >>> verdict_of(p, N(status="infeasible"), N(verdict="unverified"))
    'undecided'
    """
    v = getattr(certificate, "verdict", None) if certificate is not None else None
    if v == "certified":
        if solution.status in ("optimal", "feasible") or problem.objective.sense == "feasibility":
            return "certified"
        return "undecided"
    if v in ("rejected", "infeasible-certified", "infeasible-bounded"):
        return str(v)
    return "undecided"


def evidence_of(verdict: str, certificate: Any) -> Evidence:
    """The :class:`Evidence` behind ``verdict`` from a certificate.

    >>> evidence_of("undecided", None).kind
    'none'
    """
    if certificate is None:
        return Evidence()
    if verdict == "certified":
        exact = getattr(certificate, "exact", None) or {}
        how = "exact proof at the point" if exact.get("proven") else "float certificate"
        return Evidence("point", statement=f"a point that satisfies every constraint ({how})")
    if verdict in ("infeasible-certified", "infeasible-bounded"):
        sc = (getattr(certificate, "farkas", None) or {}).get("scope") or {}
        if verdict == "infeasible-certified":
            kind = "exact-proof" if sc.get("basis") == "exact" else "global-ray"
            return Evidence(kind, math.inf, sc.get("statement", ""))
        return Evidence("bounded-ray", sc.get("radius"), sc.get("statement", ""))
    return Evidence()
