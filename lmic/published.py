"""Audit what a paper prints: is the published result certified, rejected, or not reproducible?

A system file may list, under ``published:``, what the paper prints for it. :func:`audit_published`
turns every entry into a *claim* and decides it with the theorem's own LMIs and the certifier:

``point``  (route a)
    Every decision variable is given (directly, or recovered from a printed gain, below): the point
    is packed into ``x`` (:meth:`~lmic.ir.problem.Problem.pack`) and certified as it stands, no
    solver involved. Published numbers are rounded, so a point on the boundary may be rejected.
``partial point``  (route c)
    Some decision variables are given: they are fixed (:func:`fix_variables`, an IR-level
    substitution) and the theorem's problem is solved in the others, then certified. ``X_star``
    names the variable ``X`` (``eps1_star`` -> ``eps1``) when ``X`` is a scalar variable.
``gain``  (route b)
    A printed gain ``K`` that is not a decision variable, for a theorem that declares the
    audit variant: an option ``fixed_K`` (a flag) under which ``K`` is a data matrix and the LMIs
    are in the remaining variables (``R = L^T P`` substituted, ``G = P L``...). This is the
    convention the plugins follow (``sampled_euler``, ``uncertain_dt``, ``qib``, ``nonuniform``).
    The variant is solved (objective kept, e.g. the best ``gamma*`` the printed gain certifies).
``status``
    ``status: feasible | infeasible``: the theorem is solved for the file's parameters.
``param``
    A published number named like a parameter: feasibility at that value.
``value``
    A derived quantity (``L``, ``gamma_star``) or data-derived constant (``U``, ``V``) of the
    theorem: compared with the value computed at the best point available (the published point,
    else its completion, else the theorem's own solution). Informational when the theorem's
    answer is not unique (feasibility problems).

Recovering variables from gains: a derived quantity printed together with the matrix it is
divided by (``L = P^-1 Lbar`` with ``P`` and ``L`` printed) gives the variable back
(``Lbar = P L``). :func:`recover_variables` reads the IR's expression trees for the forms
``inv(A) B``, ``inv(A) B^T`` and ``B inv(A)``.

Exit code (:meth:`AuditReport.exit_code`): over the decisive claims (point, partial point, gain,
status, param), 1 if one is rejected, else 3 if one is proven infeasible, else 1 if one is not
reproducible, else 0; with value claims only, 0 if every one matches, else 1.

Examples
--------
>>> rep = audit_published("qib.thm1", "examples/qib.thm1.flexible-joint.yaml")   # doctest: +SKIP
>>> [(c.kind, c.finding) for c in rep.claims][:2]                                   # doctest: +SKIP
[('point', 'certified'), ('gain', 'certified')]
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from lmic.errors import DataError, IRError, LmicError
from lmic.ir.problem import Problem
from lmic.reductions.fix import fix_variables

__all__ = [
    "Claim",
    "AuditReport",
    "audit_published",
    "fix_variables",
    "recover_variables",
    "lmi_extremes",
    "DECISIVE",
]

#: claim kinds that decide the exit code
DECISIVE = ("point", "partial point", "gain", "status", "param")

_STATUS_WORDS = {"feasible": "feasible", "infeasible": "infeasible", "optimal": "feasible"}


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


# --------------------------------------------------------------------------------------------
# IR helpers


def _match_inverse(tree: Any) -> tuple[str, str, str] | None:
    """``(form, A, B)`` when ``tree`` is ``inv(A) B``, ``inv(A) B^T`` or ``B inv(A)`` (names)."""
    if not isinstance(tree, dict) or tree.get("op") != "mul" or len(tree.get("args", [])) != 2:
        return None
    a, b = tree["args"]

    def name(node: Any) -> str | None:
        return node.get("name") if isinstance(node, dict) and "name" in node else None

    def inv_of(node: Any) -> str | None:
        if isinstance(node, dict) and node.get("op") == "inv" and len(node.get("args", [])) == 1:
            return name(node["args"][0])
        return None

    if inv_of(a) and name(b):
        return "left", inv_of(a), name(b)  # type: ignore[return-value]
    if inv_of(a) and isinstance(b, dict) and b.get("op") == "transpose" and name(b["args"][0]):
        return "left-transposed", inv_of(a), name(b["args"][0])  # type: ignore[return-value]
    if name(a) and inv_of(b):
        return "right", inv_of(b), name(a)  # type: ignore[return-value]
    return None


def recover_variables(problem: Problem, known: Mapping[str, Any], published: Mapping[str, Any]) -> dict[str, tuple]:
    """Decision variables recovered from printed gains: ``{name: (value, how, printed key)}``.

    For a derived quantity ``D = inv(A) B`` (or ``inv(A) B^T``, ``B inv(A)``) with ``D`` printed,
    ``A`` a known variable and ``B`` an unknown one: ``B = A D`` (``(A D)^T``, ``D A``). Repeats
    until nothing new is found. A value that does not fit ``B``'s structure is not recovered.

    Examples
    --------
    >>> from lmic.ir.problem import LinearConstraints, NamedExpr, Objective, Variable
    >>> import scipy.sparse as sp
    >>> p = Problem([Variable("P", "symmetric", (1, 1)), Variable("G", "full", (1, 1), offset=1)], [],
    ...             LinearConstraints.empty(2), Objective("feasibility", [0, 0, 0]),
    ...             derived=[NamedExpr("L", {"op": "mul", "args": [{"op": "inv", "args": [{"name": "P"}]},
    ...                                                          {"name": "G"}]})])
    >>> v, how, key = recover_variables(p, {"P": [[2.0]]}, {"L": [[3.0]]})["G"]
    >>> float(v[0, 0]), how, key
    (6.0, 'G = P L', 'L')
    """
    names = {v.name for v in problem.variables}
    values = {k: np.atleast_2d(np.asarray(v, dtype=float)) for k, v in known.items()}
    found: dict[str, tuple] = {}
    changed = True
    while changed:
        changed = False
        for d in problem.derived:
            if d.name not in published or isinstance(published[d.name], str):
                continue
            m = _match_inverse(d.expr)
            if m is None:
                continue
            form, a, b = m
            if a not in values or b in values or b not in names:
                continue
            D = np.atleast_2d(np.asarray(published[d.name], dtype=float))
            A = values[a]
            try:
                if form == "left":
                    B, how = A @ D, f"{b} = {a} {d.name}"
                elif form == "left-transposed":
                    B, how = (A @ D).T, f"{b} = ({a} {d.name})^T"
                else:
                    B, how = D @ A, f"{b} = {d.name} {a}"
                problem.variable(b).pack(B)
            except (ValueError, IRError):
                continue
            values[b] = B
            found[b] = (B, how, d.name)
            changed = True
    return found


def lmi_extremes(problem: Problem, cert: Any) -> list[dict[str, Any]]:
    """Per LMI: the paper's extreme eigenvalue (``lambda_max`` of a ``<`` LMI), margin, ok.

    The certifier works with the normalised ``F(x) >= 0``; for an LMI written ``M < 0`` the
    paper's ``lambda_max(M)`` is ``-lambda_min(F)``.
    """
    out = []
    for lmi, rep in zip(problem.lmis, getattr(cert, "lmis", None) or [], strict=False):
        lam = rep.get("min_eig")
        negated = lmi.relation in ("<", "<=")
        out.append(
            {
                "name": lmi.name,
                "relation": lmi.relation,
                "which": "lambda_max" if negated else "lambda_min",
                "extreme": None if lam is None else (-lam if negated else lam),
                "min_margin": lam,
                "rel_margin": rep.get("rel_margin"),
                "ok": rep.get("ok"),
            }
        )
    return out


def _min_margin(cert: Any) -> float | None:
    vals = [r.get("min_eig") for r in getattr(cert, "lmis", None) or [] if r.get("min_eig") is not None]
    return float(min(vals)) if vals else None


def _checks(cert: Any) -> list[dict[str, Any]]:
    return [
        {"name": c.get("name"), "value": c.get("value"), "ok": c.get("ok")} for c in getattr(cert, "checks", None) or []
    ]


def _short(value: Any) -> Any:
    """A published value for the report (matrices as nested lists)."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    return value


def _fmt_value(v: Any) -> str:
    """A short text for a scalar or a small matrix."""
    if isinstance(v, list):
        return "[" + "; ".join(" ".join(f"{float(e):.4g}" for e in row) for row in v) + "]"
    return f"{float(v):.4g}" if isinstance(v, int | float) else str(v)


def _print_resolution(values: np.ndarray) -> float:
    """Half a unit of the last printed digit of the most precise entry (``-2.3`` -> 0.05).

    Whole numbers carry no resolution (a printed ``1`` may well be exact), nor do numbers in
    exponent notation.

    >>> _print_resolution(np.array([[0.5, -2.3]])), _print_resolution(np.array([[1.0, -1.0]]))
    (0.05, 0.0)
    """
    digits = 0
    for v in np.asarray(values, dtype=float).ravel():
        text = repr(float(v))
        if "e" in text or "E" in text:
            return 0.0
        digits = max(digits, len(text.split(".")[1].rstrip("0")) if "." in text else 0)
    return 0.5 * 10.0**-digits if digits else 0.0


def _finding_of(outcome: str) -> str:
    return {"feasible": "certified", "infeasible": "infeasible", "infeasible-bounded": "infeasible-bounded"}.get(
        outcome, "not reproducible"
    )


# --------------------------------------------------------------------------------------------
# the audit


class _Auditor:
    def __init__(
        self, theorem: str, system: Any, params: Mapping[str, Any] | None, backend: Any, options: Any, rtol: float
    ) -> None:
        from lmic.compile import bind, plan_for
        from lmic.system import load_system

        self.sysobj = load_system(system)
        if not self.sysobj.published:
            raise DataError(f"{self.sysobj.label}: has no 'published:' section to audit")
        self.theorem = theorem
        self.params = dict(params or {})
        merged = dict(self.sysobj.params)
        merged.update(self.params)
        self.plan = plan_for(theorem, merged)
        self.problem = bind(self.plan, self.sysobj, self.params)
        self.backend, self.options, self.rtol = backend, options, rtol
        t = self.plan.template
        self.var_names = [v.name for v in self.problem.variables]
        self.derived_names = [d.name for d in self.problem.derived]
        self.const_names = [c.name for c in t.consts]
        self.data_names = [d.name for d in t.data_decls]
        self.param_names = [p.name for p in t.params]
        self.option_names = [o.name for o in t.options]
        self.claims: list[Claim] = []
        self.value_point: tuple[str, Problem, np.ndarray] | None = None  # (where, problem, x)
        self.given: dict[str, Any] = {}  # published (and recovered) variable values
        self._synthesis: Any = None

    # -- helpers -----------------------------------------------------------------------------
    def decide(self, problem: Problem, keep_objective: bool = True) -> Any:
        from lmic.sweep import decide

        return decide(problem, self.backend, self.options, keep_objective=keep_objective)

    def synthesis(self) -> Any:
        """The theorem's own problem, decided once (for status and value claims)."""
        if self._synthesis is None:
            self._synthesis = self.decide(self.problem)
        return self._synthesis

    def _fill_from_point(self, claim: Claim, problem: Problem, pt: Any) -> None:
        cert = pt.certificate
        claim.verdict = pt.verdict
        claim.proof = pt.proof
        claim.lmis = lmi_extremes(problem, cert) if cert is not None and cert.lmis else []
        claim.margin = _min_margin(cert) if cert is not None else None
        claim.checks = _checks(cert) if cert is not None else []
        claim.objective = pt.objective
        claim.derived = dict(pt.derived)
        claim.solve_s = pt.solve_s
        claim.reason = (cert.reason if cert is not None else "") or pt.proof

    # -- routes ------------------------------------------------------------------------------
    def point_claims(self, pub: Mapping[str, Any]) -> set[str]:
        """Routes (a) and (c); returns the published keys used."""
        given: dict[str, Any] = {}
        used: set[str] = set()
        for key, value in pub.items():
            if isinstance(value, str):
                continue
            name = key
            if key not in self.var_names and key.endswith("_star") and key[:-5] in self.var_names:
                name = key[:-5]
                if self.problem.variable(name).kind != "scalar":
                    continue
            if name in self.var_names:
                try:
                    self.problem.variable(name).pack(value)
                except IRError as err:
                    raise DataError(f"{self.sysobj.label}: published '{key}': {err}") from None
                given[name] = value
                used.add(key)
        if not given:
            return used
        recovered = recover_variables(self.problem, given, pub)
        hows = [how for _, how, _ in recovered.values()]
        for name, (value, _how, source) in recovered.items():
            given[name] = value
            used.add(source)
        self.given = dict(given)
        keys = sorted(used, key=list(pub).index)
        missing = [v for v in self.var_names if v not in given]
        rec = f" ({'; '.join(hows)})" if hows else ""
        if not missing:
            x = self.problem.pack(given)
            self._certify_point(keys, x, rec)
        else:
            self._partial_point(keys, given, missing, rec)
        return used

    def _certify_point(self, keys: list[str], x: np.ndarray, rec: str) -> None:
        from lmic.certify import certify
        from lmic.solution import Solution
        from lmic.sweep import _exact_rescue, _scalar_derived

        prob = self.problem
        sol = Solution("feasible", x=x, objective=prob.objective.value(x), backend="published")
        t0 = time.perf_counter()
        cert = certify(prob, sol)
        proof = cert.verdict
        if cert.verdict == "rejected":
            rescued = _exact_rescue(prob, sol, cert)
            if rescued is not None:
                cert, proof = rescued, "certified (exact)"
        finding = "certified" if cert.verdict == "certified" or proof == "certified (exact)" else "rejected"
        claim = Claim(
            keys=keys,
            kind="point",
            route="published point packed into x and certified (no solver)" + rec,
            finding=finding,
            agrees=finding == "certified",
            verdict="certified" if finding == "certified" else cert.verdict,
            proof=proof,
            lmis=lmi_extremes(prob, cert),
            margin=_min_margin(cert),
            objective=prob.objective.value(x),
            derived=_scalar_derived(cert),
            checks=_checks(cert),
            reason=cert.reason,
            published="all decision variables",
            solve_s=time.perf_counter() - t0,
        )
        self.claims.append(claim)
        self.value_point = ("the published point", prob, x)

    def _partial_point(self, keys: list[str], given: dict[str, Any], missing: list[str], rec: str) -> None:
        restricted, x_fixed, free = fix_variables(self.problem, given)
        pt = self.decide(restricted)
        claim = Claim(
            keys=keys,
            kind="partial point",
            route=f"{', '.join(sorted(given))} fixed at the published values{rec}; solved in {', '.join(missing)}",
            finding=_finding_of(pt.outcome),
            agrees=pt.outcome == "feasible",
            published=f"{', '.join(sorted(given))} (not {', '.join(missing)})",
        )
        self._fill_from_point(claim, restricted, pt)
        self.claims.append(claim)
        if pt.outcome == "feasible" and pt.x is not None:
            x = x_fixed.copy()
            x[free] = pt.x
            if self.value_point is None:
                self.value_point = ("the published variables completed by the solver", self.problem, x)

    def gain_claims(self, pub: Mapping[str, Any]) -> set[str]:
        """Route (b): printed gains through the theorem's ``fixed_<gain>`` variants."""
        from lmic.compile import bind, plan_for
        from lmic.system import System

        gains = [k for k, v in pub.items() if not isinstance(v, str) and f"fixed_{k}" in self.option_names]
        if not gains:
            return set()
        params = dict(self.sysobj.params)
        params.update(self.params)
        params.update({f"fixed_{k}": "1" for k in gains})
        data = dict(self.sysobj.data)
        for k in gains:
            data[k] = np.atleast_2d(np.asarray(pub[k], dtype=float))
        sys2 = System(
            data,
            params,
            dict(self.sysobj.published),
            self.sysobj.name,
            self.sysobj.source,
            self.sysobj.path,
            self.sysobj.raw,
        )
        plan = plan_for(self.theorem, params)
        declared = {d.name for d in plan.template.data_decls}
        lost = [k for k in gains if k not in declared]
        if lost:
            raise DataError(
                f"theorem {self.theorem}: option fixed_{lost[0]} does not declare the data '{lost[0]}' "
                "(the convention: fixed_K = 1 makes K a data matrix)"
            )
        problem = bind(plan, sys2, {})
        pt = self.decide(problem)
        remaining = ", ".join(v.name for v in problem.variables)
        claim = Claim(
            keys=gains,
            kind="gain",
            route=f"{', '.join('fixed_' + k + ' = 1' for k in gains)}: the theorem's LMIs in {remaining} "
            f"with {', '.join(gains)} given",
            finding=_finding_of(pt.outcome),
            agrees=pt.outcome == "feasible",
            published={k: _short(pub[k]) for k in gains},
        )
        self._fill_from_point(claim, problem, pt)
        claim.computed = pt.objective
        self.claims.append(claim)
        return set(gains)

    def status_claim(self, word: str) -> None:
        claimed = _STATUS_WORDS.get(word.strip().lower())
        if claimed is None:
            self.claims.append(Claim(["status"], "skipped", "-", "skipped", reason=f"unknown status {word!r}"))
            return
        pt = self.synthesis()
        claim = Claim(
            keys=["status"],
            kind="status",
            route="the theorem solved for the file's parameters",
            finding=_finding_of(pt.outcome),
            agrees=None if pt.outcome in ("undecided", "infeasible-bounded") else (pt.outcome == claimed),
            published=word,
            computed=pt.outcome,
        )
        self._fill_from_point(claim, self.problem, pt)
        self.claims.append(claim)
        if pt.outcome == "feasible" and pt.x is not None and self.value_point is None:
            self.value_point = ("the theorem's solution", self.problem, pt.x)

    def param_claim(self, key: str, value: float) -> None:
        from lmic.compile import bind

        problem = bind(self.plan, self.sysobj, {**self.params, key: float(value)})
        pt = self.decide(problem, keep_objective=False)
        claim = Claim(
            keys=[key],
            kind="param",
            route=f"feasibility at {key} = {value:g}",
            finding=_finding_of(pt.outcome),
            agrees=pt.outcome == "feasible",
            published=value,
        )
        self._fill_from_point(claim, problem, pt)
        self.claims.append(claim)

    def _published_environment(self) -> tuple[dict[str, Any], set[str]]:
        """What the printed numbers determine: ``(env, computed)``.

        ``env`` holds the data, the constants, the published (and recovered) variables, the
        published derived quantities that cannot be computed from those (e.g. ``Y`` without
        ``P``), and every derived quantity computable from all of these (e.g. ``E = U + Y V``
        from the printed ``Y``); ``computed`` names the ones lmic computed.
        """
        from lmic.ir.expr import evaluate, names

        pub = self.sysobj.published
        env: dict[str, Any] = {}
        for k, v in self.problem.data.items():
            env[k] = np.asarray(v, dtype=float) if isinstance(v, list | np.ndarray) else float(v)
        for k, v in self.given.items():
            var = self.problem.variable(k)
            x = np.zeros(self.problem.n)
            x[var.slice] = var.pack(v)
            env[k] = var.value(x)
        computed: set[str] = set()
        for d in self.problem.derived:
            if names(d.expr) <= set(env):
                try:
                    env[d.name] = evaluate(d.expr, env)
                    computed.add(d.name)
                    continue
                except Exception:  # noqa: BLE001 - e.g. a singular published P: not computable
                    pass
            value = pub.get(d.name)
            if value is not None and not isinstance(value, str):
                env[d.name] = value if isinstance(value, float) else np.atleast_2d(np.asarray(value, dtype=float))
        return env, computed

    def derived_at_published(self, name: str) -> Any:
        """The derived quantity ``name`` computed from the printed numbers (``None`` if it cannot be)."""
        env, computed = self._published_environment()
        return env.get(name) if name in computed else None

    def value_claims(self, keys: list[str], pub: Mapping[str, Any]) -> None:
        if not keys:
            return
        env_pub, computed_pub = self._published_environment()
        at_published = {k: env_pub[k] for k in computed_pub}
        point_ok = any(c.kind in ("point", "partial point") and c.finding == "certified" for c in self.claims)
        refuted = any(c.kind in ("point", "partial point") and c.finding != "certified" for c in self.claims)
        env: dict[str, Any] = {}
        where = ""
        unique = True
        if any(k in self.derived_names and (refuted or k not in at_published) for k in keys):
            if self.value_point is None:
                pt = self.synthesis()
                if pt.x is not None:
                    self.value_point = ("the theorem's solution", self.problem, pt.x)
            if self.value_point is not None:
                where, prob, x = self.value_point
                unique = where != "the theorem's solution" or self.problem.objective.sense != "feasibility"
                try:
                    env = prob.environment(x)
                except Exception as err:  # noqa: BLE001 - a singular P is reported, not raised
                    env = {"_error": f"{type(err).__name__}: {err}"}
        for key in keys:
            published = pub[key]
            if key in self.const_names:
                claim = self._compare(key, published, self.problem.data.get(key), "data-derived constant", True)
            elif key in at_published and (not refuted or key not in env):
                what = "the published numbers" + ("" if point_ok else " (not certified)")
                claim = self._compare(key, published, at_published[key], what, True)
            elif key in env:
                claim = self._compare(key, published, env[key], where, unique)
                if key in at_published:
                    other = self._compare(key, published, at_published[key], "", True)
                    claim.reason += (
                        f"; from the published numbers (not certified) it is {_fmt_value(other.computed)} "
                        f"(diff {other.difference:.3g})"
                    )
            else:
                why = env.get("_error")
                if not why and self._synthesis is not None and self._synthesis.outcome == "infeasible":
                    why = f"the theorem's problem is infeasible for this system ({self._synthesis.proof})"
                claim = Claim(
                    [key],
                    "value",
                    "-",
                    "not reproducible",
                    published=_short(published),
                    reason=why or "no certified point to evaluate it at",
                )
            self.claims.append(claim)

    def _compare(self, key: str, published: Any, computed: Any, at: str, unique: bool) -> Claim:
        P = np.atleast_2d(np.asarray(published, dtype=float))
        C = np.atleast_2d(np.asarray(computed, dtype=float))
        claim = Claim(
            [key],
            "value",
            f"computed at {at}",
            "differs",
            published=_short(published),
            computed=_short(computed) if C.size > 1 else float(C.reshape(-1)[0]),
        )
        if P.shape != C.shape:
            claim.reason = f"published shape {P.shape}, computed {C.shape}"
            return claim
        diff = float(np.max(np.abs(P - C))) if P.size else 0.0
        scale = float(np.max(np.abs(P))) if P.size else 0.0
        claim.difference = diff
        claim.rel_difference = diff / scale if scale > 0 else (0.0 if diff == 0 else math.inf)
        ok = diff <= max(self.rtol * max(scale, 1e-12), 1.01 * _print_resolution(P))
        claim.finding = "matches" if ok else "differs"
        claim.agrees = ok if unique else None
        if not unique:
            claim.reason = (
                "the theorem is a feasibility problem: any certified point is an answer, "
                "so a different value is not an error"
            )
        else:
            claim.reason = (
                f"max |computed - published| = {diff:.3g} "
                f"(relative {claim.rel_difference:.3g}, tolerance {self.rtol:g} or the print precision)"
            )
        return claim


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
    a = _Auditor(theorem, system, params, backend, options, rtol)
    pub = a.sysobj.published
    used = a.point_claims(pub)
    used |= a.gain_claims(pub)
    if "status" in pub:
        used.add("status")
        if isinstance(pub["status"], str):
            a.status_claim(pub["status"])
        else:
            a.claims.append(Claim(["status"], "skipped", "-", "skipped", reason="status is not a word"))
    value_keys = []
    for key, value in pub.items():
        if key in used:
            continue
        if key in a.param_names and not isinstance(value, str | np.ndarray):
            a.param_claim(key, float(value))
        elif key in a.derived_names or key in a.const_names:
            if isinstance(value, str):
                a.claims.append(Claim([key], "skipped", "-", "skipped", reason=f"{value!r} is not a number"))
            else:
                value_keys.append(key)
        else:
            what = (
                "input data of the system file"
                if key in a.data_names
                else (f"not a variable, gain, derived quantity, constant or parameter of {a.plan.id}")
            )
            a.claims.append(
                Claim([key], "skipped", "-", "skipped", published=_short(value), reason=f"'{key}' is {what}")
            )
    a.value_claims(value_keys, pub)
    return AuditReport(
        theorem=a.plan.id,
        system=a.sysobj.path or a.sysobj.label,
        claims=a.claims,
        params=dict(params or {}),
        time_s=time.perf_counter() - t0,
    )
