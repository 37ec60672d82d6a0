"""The routes of an audit of published results: one public function per kind of claim.

Each takes the :class:`~lmic.studies.published.context.AuditContext` and appends its claims to
``ctx.claims`` (see :mod:`lmic.studies.published` for what each route decides):

- :func:`point_claims`: routes (a) a full published point, certified as it stands, and (c) a partial
  one, the rest solved for;
- :func:`gain_claims`: route (b), printed gains through the theorem's ``fixed_<gain>`` variant;
- :func:`status_claim`, :func:`param_claim`: the status word, a published parameter value;
- :func:`value_claims`: derived quantities and constants compared with what lmic computes
  (:func:`compare_value`), at the published numbers (:func:`derived_at_published`) or a point.

Examples
--------
>>> claim = compare_value("gamma", 0.25, 0.2501, "the published numbers", True, rtol=0.05)
>>> claim.finding, claim.agrees
('matches', True)
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from typing import Any

import numpy as np

from lmic.errors import DataError, IRError
from lmic.formatting import value_text
from lmic.reductions.fix import fix_variables, fixed_gain_flag, with_fixed_gains
from lmic.studies.published.claims import STATUS_WORDS, Claim, finding_of, short
from lmic.studies.published.context import AuditContext
from lmic.studies.published.transforms import checks_of, lmi_extremes, min_margin, print_resolution, recover_variables

__all__ = [
    "point_claims",
    "gain_claims",
    "status_claim",
    "param_claim",
    "value_claims",
    "compare_value",
    "published_environment",
    "derived_at_published",
]


def point_claims(ctx: AuditContext, pub: Mapping[str, Any]) -> set[str]:
    """Routes (a) and (c): published decision variables (and those recovered from gains); returns the keys used."""
    given: dict[str, Any] = {}
    used: set[str] = set()
    for key, value in pub.items():
        if isinstance(value, str):
            continue
        name = key
        if key not in ctx.var_names and key.endswith("_star") and key[:-5] in ctx.var_names:
            name = key[:-5]
            if ctx.problem.variable(name).kind != "scalar":
                continue
        if name in ctx.var_names:
            try:
                ctx.problem.variable(name).pack(value)
            except IRError as err:
                raise DataError(f"{ctx.sysobj.label}: published '{key}': {err}") from None
            given[name] = value
            used.add(key)
    if not given:
        return used
    recovered = recover_variables(ctx.problem, given, pub)
    hows = [how for _, how, _ in recovered.values()]
    for name, (value, _how, source) in recovered.items():
        given[name] = value
        used.add(source)
    ctx.given = dict(given)
    keys = sorted(used, key=list(pub).index)
    missing = [v for v in ctx.var_names if v not in given]
    rec = f" ({'; '.join(hows)})" if hows else ""
    if not missing:
        x = ctx.problem.pack(given)
        _certify_point(ctx, keys, x, rec)
    else:
        _partial_point(ctx, keys, given, missing, rec)
    return used


def _certify_point(ctx: AuditContext, keys: list[str], x: np.ndarray, rec: str) -> None:
    from lmic.certify import certify
    from lmic.policy import exact_rescue_point as _exact_rescue
    from lmic.solution import Solution
    from lmic.studies.sweep.points import scalar_derived as _scalar_derived

    prob = ctx.problem
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
        margin=min_margin(cert),
        objective=prob.objective.value(x),
        derived=_scalar_derived(cert),
        checks=checks_of(cert),
        reason=cert.reason,
        published="all decision variables",
        solve_s=time.perf_counter() - t0,
    )
    ctx.claims.append(claim)
    ctx.value_point = ("the published point", prob, x)


def _partial_point(ctx: AuditContext, keys: list[str], given: dict[str, Any], missing: list[str], rec: str) -> None:
    restricted, x_fixed, free = fix_variables(ctx.problem, given)
    pt = ctx.decide(restricted)
    claim = Claim(
        keys=keys,
        kind="partial point",
        route=f"{', '.join(sorted(given))} fixed at the published values{rec}; solved in {', '.join(missing)}",
        finding=finding_of(pt.outcome),
        agrees=pt.outcome == "feasible",
        published=f"{', '.join(sorted(given))} (not {', '.join(missing)})",
    )
    ctx.fill_from_point(claim, restricted, pt)
    ctx.claims.append(claim)
    if pt.outcome == "feasible" and pt.x is not None:
        x = x_fixed.copy()
        x[free] = pt.x
        if ctx.value_point is None:
            ctx.value_point = ("the published variables completed by the solver", ctx.problem, x)


def gain_claims(ctx: AuditContext, pub: Mapping[str, Any]) -> set[str]:
    """Route (b): printed gains through the theorem's ``fixed_<gain>`` variants."""
    from lmic.compile import bind, plan_for

    gains = [k for k, v in pub.items() if not isinstance(v, str) and fixed_gain_flag(k) in ctx.option_names]
    if not gains:
        return set()
    sys2 = with_fixed_gains(ctx.sysobj, {k: pub[k] for k in gains}, ctx.params)
    plan = plan_for(ctx.theorem, sys2.params)
    declared = {d.name for d in plan.template.data_decls}
    lost = [k for k in gains if k not in declared]
    if lost:
        raise DataError(
            f"theorem {ctx.theorem}: option fixed_{lost[0]} does not declare the data '{lost[0]}' "
            "(the convention: fixed_K = 1 makes K a data matrix)"
        )
    problem = bind(plan, sys2, {})
    pt = ctx.decide(problem)
    remaining = ", ".join(v.name for v in problem.variables)
    claim = Claim(
        keys=gains,
        kind="gain",
        route=f"{', '.join('fixed_' + k + ' = 1' for k in gains)}: the theorem's LMIs in {remaining} "
        f"with {', '.join(gains)} given",
        finding=finding_of(pt.outcome),
        agrees=pt.outcome == "feasible",
        published={k: short(pub[k]) for k in gains},
    )
    ctx.fill_from_point(claim, problem, pt)
    claim.computed = pt.objective
    ctx.claims.append(claim)
    return set(gains)


def status_claim(ctx: AuditContext, word: str) -> None:
    """The ``status:`` word (feasible / infeasible / optimal) against the theorem solved for the file."""
    claimed = STATUS_WORDS.get(word.strip().lower())
    if claimed is None:
        ctx.claims.append(Claim(["status"], "skipped", "-", "skipped", reason=f"unknown status {word!r}"))
        return
    pt = ctx.synthesis()
    claim = Claim(
        keys=["status"],
        kind="status",
        route="the theorem solved for the file's parameters",
        finding=finding_of(pt.outcome),
        agrees=None if pt.outcome in ("undecided", "infeasible-bounded") else (pt.outcome == claimed),
        published=word,
        computed=pt.outcome,
    )
    ctx.fill_from_point(claim, ctx.problem, pt)
    ctx.claims.append(claim)
    if pt.outcome == "feasible" and pt.x is not None and ctx.value_point is None:
        ctx.value_point = ("the theorem's solution", ctx.problem, pt.x)


def param_claim(ctx: AuditContext, key: str, value: float) -> None:
    """A published parameter value: feasibility of the theorem at ``key = value``."""
    from lmic.compile import bind

    problem = bind(ctx.plan, ctx.sysobj, {**ctx.params, key: float(value)})
    pt = ctx.decide(problem, keep_objective=False)
    claim = Claim(
        keys=[key],
        kind="param",
        route=f"feasibility at {key} = {value:g}",
        finding=finding_of(pt.outcome),
        agrees=pt.outcome == "feasible",
        published=value,
    )
    ctx.fill_from_point(claim, problem, pt)
    ctx.claims.append(claim)


def published_environment(ctx: AuditContext) -> tuple[dict[str, Any], set[str]]:
    """What the printed numbers determine: ``(env, computed)``.

    ``env`` holds the data, the constants, the published (and recovered) variables, the
    published derived quantities that cannot be computed from those (e.g. ``Y`` without
    ``P``), and every derived quantity computable from all of these (e.g. ``E = U + Y V``
    from the printed ``Y``); ``computed`` names the ones lmic computed.
    """
    from lmic.ir.expr import evaluate, names

    pub = ctx.sysobj.published
    env: dict[str, Any] = {}
    for k, v in ctx.problem.data.items():
        env[k] = np.asarray(v, dtype=float) if isinstance(v, list | np.ndarray) else float(v)
    for k, v in ctx.given.items():
        var = ctx.problem.variable(k)
        x = np.zeros(ctx.problem.n)
        x[var.slice] = var.pack(v)
        env[k] = var.value(x)
    computed: set[str] = set()
    for d in ctx.problem.derived:
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


def derived_at_published(ctx: AuditContext, name: str) -> Any:
    """The derived quantity ``name`` computed from the printed numbers (``None`` if it cannot be)."""
    env, computed = published_environment(ctx)
    return env.get(name) if name in computed else None


def value_claims(ctx: AuditContext, keys: list[str], pub: Mapping[str, Any]) -> None:
    """Value claims: each derived quantity or constant in ``keys`` compared with lmic's."""
    if not keys:
        return
    env_pub, computed_pub = published_environment(ctx)
    at_published = {k: env_pub[k] for k in computed_pub}
    point_ok = any(c.kind in ("point", "partial point") and c.finding == "certified" for c in ctx.claims)
    refuted = any(c.kind in ("point", "partial point") and c.finding != "certified" for c in ctx.claims)
    env: dict[str, Any] = {}
    where = ""
    unique = True
    if any(k in ctx.derived_names and (refuted or k not in at_published) for k in keys):
        if ctx.value_point is None:
            pt = ctx.synthesis()
            if pt.x is not None:
                ctx.value_point = ("the theorem's solution", ctx.problem, pt.x)
        if ctx.value_point is not None:
            where, prob, x = ctx.value_point
            unique = where != "the theorem's solution" or ctx.problem.objective.sense != "feasibility"
            try:
                env = prob.environment(x)
            except Exception as err:  # noqa: BLE001 - a singular P is reported, not raised
                env = {"_error": f"{type(err).__name__}: {err}"}
    for key in keys:
        published = pub[key]
        if key in ctx.const_names:
            claim = compare_value(key, published, ctx.problem.data.get(key), "data-derived constant", True, ctx.rtol)
        elif key in at_published and (not refuted or key not in env):
            what = "the published numbers" + ("" if point_ok else " (not certified)")
            claim = compare_value(key, published, at_published[key], what, True, ctx.rtol)
        elif key in env:
            claim = compare_value(key, published, env[key], where, unique, ctx.rtol)
            if key in at_published:
                other = compare_value(key, published, at_published[key], "", True, ctx.rtol)
                claim.reason += (
                    f"; from the published numbers (not certified) it is {value_text(other.computed)} "
                    f"(diff {other.difference:.3g})"
                )
        else:
            why = env.get("_error")
            if not why and ctx._synthesis is not None and ctx._synthesis.outcome == "infeasible":
                why = f"the theorem's problem is infeasible for this system ({ctx._synthesis.proof})"
            claim = Claim(
                [key],
                "value",
                "-",
                "not reproducible",
                published=short(published),
                reason=why or "no certified point to evaluate it at",
            )
        ctx.claims.append(claim)


def compare_value(key: str, published: Any, computed: Any, at: str, unique: bool, rtol: float = 0.05) -> Claim:
    """A value claim: ``published`` against ``computed`` (at ``at``), within ``rtol`` or the print precision.

    ``unique`` is false when the theorem's answer is not unique (a feasibility problem): a
    difference is then reported but does not count against the paper.
    """
    P = np.atleast_2d(np.asarray(published, dtype=float))
    C = np.atleast_2d(np.asarray(computed, dtype=float))
    claim = Claim(
        [key],
        "value",
        f"computed at {at}",
        "differs",
        published=short(published),
        computed=short(computed) if C.size > 1 else float(C.reshape(-1)[0]),
    )
    if P.shape != C.shape:
        claim.reason = f"published shape {P.shape}, computed {C.shape}"
        return claim
    diff = float(np.max(np.abs(P - C))) if P.size else 0.0
    scale = float(np.max(np.abs(P))) if P.size else 0.0
    claim.difference = diff
    claim.rel_difference = diff / scale if scale > 0 else (0.0 if diff == 0 else math.inf)
    ok = diff <= max(rtol * max(scale, 1e-12), 1.01 * print_resolution(P))
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
            f"(relative {claim.rel_difference:.3g}, tolerance {rtol:g} or the print precision)"
        )
    return claim
