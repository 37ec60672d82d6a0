"""Suprema and infima of a parameter that enters affinely: one convex solve and its enclosure.

When a theorem's parameter ``p`` enters its constraints affinely and multiplies no decision
variable (``gamma`` in ``[A'P + PA, PB; *, -gamma I]``), the set of ``(x, p)`` that satisfy them
is convex, and ``sup {p : the theorem holds}`` is the optimal value of one convex problem: ``p``
becomes a decision variable and the objective ``max p`` (``min p`` for an infimum). That
problem is solved once by the solve policy: its certified point gives the certified end. The
other end, instead of a bisection, in this order: for a scale-free theorem (a positive scalar
fixed to 1, :mod:`lmic.studies.sweep.homogeneous`) one max-margin solve just beyond the
certified value, within the tolerance, whose Farkas ray is a global proof there; else the
proven dual bound of the convex problem (:func:`lmic.certify.enclosure.enclosure`, weak
duality: no feasible value lies beyond it), within a budget of a multiple of the solve; else
one budgeted max-margin solve beyond the certified value, whose bounded ray is labelled
``infeasible-bounded`` (never a bound).

Whether ``p`` enters affinely is decided from the template and the IR, never from a theorem's
name (:func:`affine_parameter`):

1. in the plan (:mod:`lmic.compile.plan`) ``p`` appears only in the coefficients of terms
   without a decision variable, at most affinely (``d coef / dp`` free of ``p``), and in no
   matrix factor;
2. the problems bound at three values of ``p`` have the same structure and differ only in the
   constant column, affinely (this also catches constants computed from ``p`` by a theorem's
   ``const`` function, which the template cannot show);
3. or, where ``p`` multiplies a decision variable: the bound problems are scale-free and ``p``
   changes (affinely) only the coefficients of one scalar ``w`` with a strict row ``w > 0``.

The point at the certified end is certified again on the theorem's own problem bound at that
value (:func:`lmic.studies.sweep.ends.certified_end`, gains and certificate as after a
bisection). Whenever this route cannot give a certified end (unbounded, no certified point),
:func:`enclose` returns ``None`` with the reason and the caller bisects.

Examples
--------
>>> import sympy
>>> from lmic.compile.plan import Term
>>> g, w = sympy.Symbol("gamma"), sympy.Symbol("w")
>>> _coef_affine(-g, g), _coef_affine(g**2, g), _coef_affine(2 * g * w, g)
(True, False, True)
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterator, Mapping
from dataclasses import replace
from typing import Any

import numpy as np
import scipy.sparse as sp
import sympy

from lmic.compile.exact import EXACT_MAKER
from lmic.errors import LmicError
from lmic.ir.problem import LinearConstraints, Objective, Problem, Variable
from lmic.solution import Solution
from lmic.studies.sweep.ends import certified_end
from lmic.studies.sweep.exact_lift import exact_lift
from lmic.studies.sweep.homogeneous import AFFINE_RTOL, _columns, _same_structure, fix_scalar, homogeneous_scalar, unfix
from lmic.studies.sweep.points import Evaluator, domain, in_domain, setup
from lmic.studies.sweep.results import PointResult, SupResult, kind_of

__all__ = ["affine_parameter", "monotone_affine", "lift", "enclose", "fix_scalar", "unfix"]

#: the other end is first proven infeasible this fraction of the tolerance beyond the certified
#: value (one max-margin solve, :func:`lmic.studies.sweep.points._prove`)
PROOF_FRACTION = 0.9
#: where that proof does not decide, the dual bound's search may take this multiple of the
#: convex solve's time (at least :data:`DUAL_BUDGET_MIN_S` seconds)
DUAL_BUDGET_FACTOR = 1.0
DUAL_BUDGET_MIN_S = 0.5
#: ... and the last attempt, one max-margin solve beyond the certified value, this multiple
PROOF_BUDGET_FACTOR = 4.0


def _coef_affine(coef: Any, p: sympy.Symbol) -> bool:
    """``coef`` is affine in ``p`` (its derivative in ``p`` is free of ``p``)."""
    if p not in getattr(coef, "free_symbols", set()):
        return True
    try:
        d = sympy.diff(coef, p)
    except (TypeError, ValueError):
        return False
    return p not in d.free_symbols


def _terms(plan: Any) -> Iterator[tuple[Any, Any, tuple[Any, ...]]]:
    """Every ``(coef, var, factors)`` of the plan's LMIs and linear constraints."""
    for lp in plan.lmis:
        for entry in lp.entries.values():
            for t in entry.terms:
                yield t.coef, t.var, tuple(t.left) + tuple(t.right)
    for _name, _kind, _strict, form in plan.constraints:
        yield form.const, None, ()
        for coef, atom in form.terms:
            yield coef, atom[0], ()
        for coef, terms in form.traces:
            for t in terms:
                yield coef * t.coef, t.var, tuple(t.left) + tuple(t.right)


def _template_affine(plan: Any, p: sympy.Symbol) -> str:
    """``""`` when ``p`` enters the plan affinely and multiplies no decision variable, else why not.

    Every term is checked: a coefficient of a decision variable that is not affine in ``p`` (or
    ``p`` in a matrix factor) is refused even after a term where ``p`` multiplies a variable (the
    scale-free route, :func:`affine_parameter`, lifts only an affine coefficient; its check of
    the bound data at three values cannot show affinity: a cubic through them passes it)."""
    multiplies = ""
    for coef, var, factors in _terms(plan):
        if any(p in getattr(f, "free_symbols", set()) for f in factors):
            return f"'{p}' appears in a matrix factor"
        if p not in getattr(coef, "free_symbols", set()):
            continue
        if not _coef_affine(coef, p):
            return f"'{p}' enters non-affinely ({coef})"
        if var is not None and not multiplies:
            multiplies = f"'{p}' multiplies the decision variable {var}"
    return multiplies


class _Reads(Mapping[str, Any]):
    """The values a constant's function sees, recording which it reads (``"*"``: all of them,
    for a function that iterates over the mapping)."""

    def __init__(self, values: Mapping[str, Any]) -> None:
        self._values: dict[str, Any] = dict(values)
        self.read: set[str] = set()

    def __getitem__(self, key: str) -> Any:
        self.read.add(key)
        return self._values[key]

    def __iter__(self) -> Iterator[str]:
        self.read.add("*")
        return iter(self._values)

    def __len__(self) -> int:
        self.read.add("*")
        return len(self._values)

    def __contains__(self, key: object) -> bool:
        self.read.add(str(key))
        return key in self._values


def _constants_free_of(plan: Any, sysobj: Any, overrides: Mapping[str, Any], name: str, value: float) -> str:
    """``""`` when no data-derived constant (``t.const``) reads the parameter ``name``, directly
    or through another constant, else why not.

    A constant is a function the template cannot see into: the bound data at three values of
    the parameter can agree with an affine function there and not elsewhere (a constant ``p -
    p (p - 1) (p - 1/2) / 10`` at the sample values 0, 1, 1/2), and the lifted problem would then
    not be the theorem's at any other value (tests/studies/sweep/test_lift_soundness.py). So a
    parameter that reaches a constant is never lifted: the bisection decides each value on the
    theorem's own problem."""
    from lmic.compile.inputs import resolve_inputs

    consts = list(getattr(plan.template, "consts", []) or [])
    if not consts:
        return ""
    try:
        values = dict(resolve_inputs(plan, sysobj, {**overrides, name: value}).values)
    except LmicError as err:
        return f"the constants cannot be computed at {name} = {value:g}: {err}"
    computed = {c.name for c in consts}
    for c in consts:  # the first constant that reads the parameter (or everything) decides
        before = _Reads({k: v for k, v in values.items() if k not in computed or k in _done(consts, c)})
        try:
            c.fn(before)
        except Exception:  # noqa: BLE001 - a function that needs a real dict: assume it reads everything
            before.read.add("*")
        if "*" in before.read or name in before.read:
            return (
                f"'{name}' reaches the data-derived constant '{c.name}' (t.const): "
                "not affine as far as the template shows"
            )
    return ""


def _done(consts: list[Any], c: Any) -> set[str]:
    """The names of the constants computed before ``c``."""
    out: set[str] = set()
    for d in consts:
        if d is c:
            break
        out.add(d.name)
    return out


#: the powers ``h = p^k`` tried when ``p`` itself does not enter affinely (:func:`monotone_affine`)
MONOTONE_POWERS = (2, 3, 4, -1, -2)


def monotone_affine(plan: Any, sysobj: Any, overrides: Mapping[str, Any], decl: Any) -> str:
    """The power ``p^k`` (as text) in which the theorem is affine, ``""`` when there is none.

    ``p`` must be non-negative on its domain, in no matrix factor and in no coefficient of a
    decision variable, and read by no data-derived constant; every coefficient that holds it must
    be affine in ``g = p^k``. The feasible set in ``(x, g)`` is then convex, so the feasible values
    of ``g`` form an interval, and so do those of ``p`` (``p -> p^k`` is monotone for ``p > 0``):
    ``gamma^2`` in an H-infinity bound.

    >>> from lmic.studies.sweep.points import setup
    >>> s, plan, o, d = setup("thesis.thm3_2_2", "examples/thesis.thm3_2_2.ex3_2_2.yaml", "gamma", None)
    >>> monotone_affine(plan, s, o, d)
    'gamma**2'
    """
    p = decl.symbol
    lo, _hi, lo_in, _ = domain(decl)
    if not lo >= 0.0:
        return ""
    coefs = []
    for coef, var, factors in _terms(plan):
        if any(p in getattr(f, "free_symbols", set()) for f in factors):
            return ""
        if p in getattr(coef, "free_symbols", set()):
            if var is not None:
                return ""
            coefs.append(coef)
    start = sysobj.params.get(decl.name, decl.default)
    value = float(start) if isinstance(start, int | float) and not isinstance(start, bool) else 1.0
    if not coefs or _constants_free_of(plan, sysobj, overrides, decl.name, value):
        return ""
    g = sympy.Symbol("_g", positive=True)
    for k in MONOTONE_POWERS:
        if k < 0 and lo == 0.0 and lo_in:
            continue  # p^k is not defined at p = 0
        try:
            if all(_coef_affine(sympy.expand(c.subs(p, g ** sympy.Rational(1, k))), g) for c in coefs):
                return f"{p}**{k}"
        except (TypeError, ValueError):
            return ""
    return ""


def _data_affine(probs: list[Problem], values: list[float]) -> str:
    """``""`` when the bound problems differ only in the constant column, affinely in the value."""
    p0, p1, p2 = probs
    v0, v1, v2 = values
    if not (_same_structure(p0, p1) and _same_structure(p0, p2)):
        return "the bound problems differ in structure"
    for M0, M1, M2 in zip(_columns(p0), _columns(p1), _columns(p2), strict=True):
        scale = max(abs(M0).max() if M0.nnz else 0.0, abs(M1).max() if M1.nnz else 0.0, 1.0)
        D1, D2 = (M1 - M0).tocsc(), (M2 - M0).tocsc()
        if D1.shape[1] > 1 and (abs(D1[:, 1:]).max() if D1[:, 1:].nnz else 0.0) > AFFINE_RTOL * scale:
            return "the parameter changes a coefficient of a decision variable"
        if D2.shape[1] > 1 and (abs(D2[:, 1:]).max() if D2[:, 1:].nnz else 0.0) > AFFINE_RTOL * scale:
            return "the parameter changes a coefficient of a decision variable"
        g1 = D1[:, 0].toarray().ravel() / (v1 - v0)
        g2 = D2[:, 0].toarray().ravel() / (v2 - v0)
        if np.max(np.abs(g1 - g2), initial=0.0) > AFFINE_RTOL * scale * max(1.0, abs(v1), abs(v2), abs(v0)):
            return "the constant terms are not affine in the parameter"
    return ""


def _sample_values(dom: tuple[float, float, bool, bool], start: float | None) -> list[float] | None:
    """Three distinct values inside the domain (the first two exact steps apart when possible)."""
    lo, hi, _, _ = dom
    cands = [0.0, 1.0, 2.0, -1.0, 0.5, 0.25, 0.75]
    if start is not None and math.isfinite(start):
        cands = [float(start), float(start) + 1.0, float(start) + 0.5] + cands
    if math.isfinite(lo) and math.isfinite(hi):
        cands += [lo + (hi - lo) * t for t in (0.25, 0.5, 0.75)]
    if math.isfinite(lo):
        cands += [lo + 1.0, lo + 2.0, lo + 0.5]
    if math.isfinite(hi):
        cands += [hi - 1.0, hi - 2.0, hi - 0.5]
    out: list[float] = []
    for v in cands:
        if in_domain(v, dom) and v not in out:
            out.append(v)
        if len(out) == 3:
            return out
    return None


def affine_parameter(plan: Any, sysobj: Any, overrides: Mapping[str, Any], decl: Any) -> tuple[bool, str, Any]:
    """Whether the parameter ``decl`` enters the theorem affinely (the enclosure replaces bisection).

    Two cases: the parameter enters only the constant terms, affinely (``gamma`` in ``-gamma
    I``); or the problem is scale-free, the parameter multiplies only one scalar decision
    variable ``w`` (affinely) and a strict row ``w > 0`` holds (``beta omega`` in
    ``qib.thm1``): then ``w = 1`` loses nothing (:func:`fix_scalar`) and the parameter enters
    the constant terms of the fixed problem.

    Returns ``(affine, reason, bound)``: ``bound`` is ``(problems, values, k)`` at three values
    of the parameter (what :func:`lift` needs; ``k`` the index of the variable fixed to 1, or
    ``None``) when ``affine``; ``reason`` then names the fixed variable (``""`` if none).

    Examples
    --------
    >>> from lmic.studies.sweep.points import setup
    >>> s, plan, o, d = setup("qib.thm1", "examples/qib.thm1.flexible-joint.yaml", "beta", None)  # doctest: +SKIP
    >>> affine_parameter(plan, s, o, d)[:2]                                   # doctest: +SKIP
    (False, "'beta' multiplies the decision variable omega")
    """
    from lmic.compile import bind

    why = _template_affine(plan, decl.symbol)
    if why and "multiplies the decision variable" not in why:
        return False, why, None
    dom = domain(decl)
    start = sysobj.params.get(decl.name, decl.default)
    values = _sample_values(dom, float(start) if isinstance(start, int | float) else None)
    if values is None:
        return False, "no three values inside the parameter's domain", None
    hidden = _constants_free_of(plan, sysobj, overrides, decl.name, values[0])
    if hidden:
        return False, hidden, None
    try:
        probs = [bind(plan, sysobj, {**overrides, decl.name: v}) for v in values]
    except LmicError as err:
        return False, f"binding at a sample value failed: {err}", None
    if not why:
        why = _data_affine(probs, values)
        if not why:
            return True, "", (probs, values, None)
    k, name = homogeneous_scalar(probs, values)
    if k is None:
        return False, f"{why}; {name}", None
    return True, name, ([fix_scalar(q, k) for q in probs], values, k)


def lift(
    problems: list[Problem], values: list[float], name: str, sense: str, dom: tuple[float, float, bool, bool]
) -> Problem:
    """The problem with the parameter as one more scalar decision variable (the last), ``sense p``.

    The constant column of every LMI and row at ``p`` is ``c0 + p g`` (``g`` from the first two
    bound problems); the parameter's domain becomes linear rows; the theorem's objective,
    derived quantities and checks are dropped (the end's point is certified on the theorem's
    own problem, :func:`lmic.studies.sweep.ends.certified_end`).

    >>> from lmic.ir.problem import LMI
    >>> P = lambda v: Problem([Variable("q", "scalar", (1, 1))],
    ...     [LMI("v - q > 0", 1, sp.csc_matrix([[v, -1.0]]))], LinearConstraints.empty(1),
    ...     Objective("feasibility", [0.0, 0.0]))
    >>> L = lift([P(0.0), P(1.0)], [0.0, 1.0], "v", "min", (0.0, math.inf, True, False))
    >>> L.n, L.lmis[0].coeffs.toarray().tolist(), L.objective.c.tolist()
    (2, [[0.0, -1.0, 1.0]], [0.0, 0.0, 1.0])
    """
    p0, p1 = problems[0], problems[1]
    v0, v1 = values[0], values[1]
    n = p0.n
    var_name = name
    while var_name in {v.name for v in p0.variables}:
        var_name += "_"

    def widen(M0: sp.spmatrix, M1: sp.spmatrix) -> sp.csc_matrix:
        M0, M1 = sp.csc_matrix(M0), sp.csc_matrix(M1)
        g = (M1[:, 0] - M0[:, 0]) / (v1 - v0)
        c0 = M0[:, 0] - v0 * g
        return sp.hstack([c0, M0[:, 1:], g], format="csc")

    lmis = [replace(a, coeffs=widen(a.coeffs, b.coeffs)) for a, b in zip(p0.lmis, p1.lmis, strict=True)]
    rows = [widen(p0.linear.A, p1.linear.A)]
    kinds, strict, names = list(p0.linear.kinds), list(p0.linear.strict), list(p0.linear.names)
    lo, hi, lo_in, hi_in = dom
    for bound, inside, sgn, op in ((lo, lo_in, 1.0, ">"), (hi, hi_in, -1.0, "<")):
        if math.isfinite(bound):  # sgn (p - bound) >= 0 (> 0 for an open end)
            r = np.zeros(n + 2)
            r[0], r[-1] = -sgn * bound, sgn
            rows.append(sp.csc_matrix(r.reshape(1, -1)))
            kinds.append("ge")
            strict.append(not inside)
            names.append(f"{name} {op}{'' if not inside else '='} {bound:g} (domain)")
    c = np.zeros(n + 2)
    c[-1] = 1.0
    out = Problem(
        variables=[*p0.variables, Variable(var_name, "scalar", (1, 1), offset=n)],
        lmis=lmis,
        linear=LinearConstraints(sp.vstack(rows, format="csr"), kinds, strict, names),
        objective=Objective(sense, c),
        data=p0.data,
        meta={**p0.meta, "lifted_parameter": name},
    )
    # its exact counterpart, built when a proof asks for it (the face route of the enclosure)
    setattr(out, EXACT_MAKER, lambda: exact_lift(p0, p1, v0, v1, out, name))
    return out


def enclose(
    theorem: Any,
    system: Any,
    param: str,
    sign: float,
    *,
    params: Mapping[str, Any] | None = None,
    backend: Any = None,
    options: Any = None,
    exact: bool = True,
    xtol: float = 1e-6,
    rtol: float = 1e-5,
    backoff: float | None = None,
) -> tuple[SupResult | None, str]:
    """The supremum (``sign = 1``) or infimum (``-1``) of an affine parameter, enclosed.

    Returns ``(result, "")``, or ``(None, reason)`` when the parameter does not enter affinely or
    this route gave no certified end (then the caller bisects).

    Examples
    --------
    >>> r, why = enclose("my.brl", "plant.yaml", "gamma", -1.0)            # doctest: +SKIP
    >>> r.method, r.upper_kind, r.lower <= r.upper                         # doctest: +SKIP
    ('enclosure', 'dual-bound', True)
    """
    from lmic.certify.enclosure import summary
    from lmic.policy import decide as policy_decide

    t_start = time.perf_counter()
    t0 = time.perf_counter()
    sysobj, plan, overrides, decl = setup(theorem, system, param, params)
    plan_s = time.perf_counter() - t0
    affine, why, bound = affine_parameter(plan, sysobj, overrides, decl)
    if not affine:
        return None, why
    probs, values, k = bound
    fixed_note = f"{why} = 1 (scale-free, {why} > 0)" if k is not None else ""
    dom = domain(decl)
    is_max = sign > 0
    lifted = lift(probs, values, param, "max" if is_max else "min", dom)
    try:
        out = policy_decide(lifted, backend, options)
    except LmicError as err:
        return None, f"the convex problem in '{param}' was not solved: {err}"
    solve_s = float(sum(a.time_s for a in out.attempts))
    sol = out.solution
    if out.verdict != "certified" or sol is None or sol.x is None:
        return None, f"no certified point of the convex problem in '{param}' ({out.verdict}: {out.reason})"
    x = np.asarray(sol.x, dtype=float)
    value = float(x[-1])
    # the point at the end, certified on the theorem's own problem bound at that value
    ev = Evaluator(plan, sysobj, overrides, param, backend, options, False, exact, None)
    xt = unfix(x[:-1], k)
    ev.reference = xt
    pt = _certify_at(ev, value, xt) if in_domain(value, dom) else None
    if pt is None:
        return None, f"the convex problem's point at {param} = {value:g} is not certified on the theorem"
    pt.solve_s += solve_s  # the convex problem's solve
    what = "supremum" if is_max else "infimum"
    tol = max(xtol, rtol * abs(value))
    # the other end: for a scale-free theorem one infeasibility proof just beyond the certified
    # value, within the tolerance (global when its ray is proved exactly); the proven dual bound
    # of the convex problem (first for other theorems: the exact upgrade costs seconds); last the policy
    other, kind, enc = None, "none", None
    beyond = value + sign * PROOF_FRACTION * tol
    if beyond == value:  # a tolerance below the float spacing: the next float beyond
        beyond = math.nextafter(value, sign * math.inf)
    proof = None
    if k is not None and in_domain(beyond, dom):
        proof = ev(beyond, "prove", full=True, prove=True, escalate=False)
        if proof.outcome == "feasible":
            return None, f"'{param}' = {beyond:g} beyond the convex problem's optimum {value:g} is certified"
        if proof.outcome == "infeasible":
            other, kind = beyond, "infeasible-certified"
    if other is None:
        budget = max(DUAL_BUDGET_MIN_S, DUAL_BUDGET_FACTOR * solve_s)
        enc = _dual_end(lifted, sol, out.backend, options, solve_s, budget)
        dual = None if enc is None else (enc.get("upper") if is_max else enc.get("lower"))
        if dual is not None:
            other, kind = float(dual), "dual-bound"
            if (is_max and other < value) or (not is_max and other > value):
                return None, f"inconsistent enclosure ({other:g} against the certified {value:g})"
    if other is None and in_domain(beyond, dom):
        # one max-margin solve, budgeted, no exact upgrade of a bounded ray (it costs seconds
        # and rarely holds on these inhomogeneous problems): a bounded ray is labelled as such
        budget = max(DUAL_BUDGET_MIN_S, PROOF_BUDGET_FACTOR * solve_s)
        proof = ev(beyond, "prove", full=True, prove=True, escalate=False, exact=False, budget_s=budget)
        if proof.outcome == "feasible":
            return None, f"'{param}' = {beyond:g} beyond the convex problem's optimum {value:g} is certified"
        if proof.outcome == "infeasible":
            other, kind = beyond, "infeasible-certified"
        else:
            kind = kind_of(proof)
    end = certified_end(pt, backend, options, backoff)
    gap = abs(other - value) if other is not None else math.inf
    converged = gap <= max(tol, max(xtol, rtol * abs(other)) if other is not None else 0.0)
    message = ""
    if other is None:
        bounded = f" (at {beyond:g}: {proof.proof})" if proof is not None else ""
        rel = ">=" if is_max else "<="
        message = f"no proven {'upper' if is_max else 'lower'} end{bounded}: the {what} is {rel} {value:g}"
    elif not converged:
        message = f"the enclosure's gap {gap:.3g} is above the tolerance {tol:.3g}"
    shown = other if other is not None else (beyond if proof is not None else None)
    lower, upper = (value, shown) if is_max else (shown, value)
    return (
        SupResult(
            theorem=plan.id,
            param=param,
            lower=lower,
            upper=upper,
            upper_kind=kind,
            upper_proven=other,
            converged=bool(converged),
            xtol=xtol,
            rtol=rtol,
            iterations=0,
            points=ev.points,
            backend=str(out.backend),
            plan_s=plan_s,
            total_s=time.perf_counter() - t_start,
            message=message,
            domain=(dom[0], dom[1]),
            end=end,
            sense="max" if is_max else "min",
            system=sysobj,
            method="enclosure",
            enclosure=summary(enc) if enc is not None else None,
            method_note=fixed_note,
            interval_proven=True,  # affine in the parameter: the feasible values form an interval
        ),
        "",
    )


def _dual_end(
    lifted: Problem, sol: Solution, backend: Any, options: Any, solve_s: float, budget: float
) -> dict[str, Any] | None:
    """The enclosure of the convex problem's optimum from its certified point and its dual.

    :func:`lmic.certify.enclosure.enclosure` within ``budget`` seconds, its re-solves (perturbed
    problem, centred dual point) on ``backend``; a float proof with rigorous error bounds (no
    rational re-proof on top) and no re-solve at tighter tolerances (the study's tolerance is
    met by the other end's proof, or reported as not met).
    """
    from lmic.backends.registry import get_backend
    from lmic.certify.enclosure import enclosure
    from lmic.options import SolveOptions
    from lmic.reductions.pipeline import solve

    if sol.duals is None:
        return None
    deadline = time.perf_counter() + budget
    try:
        be = get_backend(str(backend))
    except LmicError:
        return None
    opts = options or SolveOptions()

    def again(problem: Problem) -> Solution | None:
        if time.perf_counter() + solve_s > deadline:
            return None  # the re-solve would not fit in the budget
        try:
            other = solve(be, problem, opts) if be.supports(problem) else None
        except LmicError:
            return None
        return other if other is not None and other.status in ("optimal", "inaccurate") else None

    def resolve(problem: Problem) -> dict[str, Any] | None:
        other = again(problem)
        return None if other is None else other.duals

    def solve_point(problem: Problem) -> np.ndarray | None:
        other = again(problem)
        return None if other is None else other.x

    try:
        return enclosure(
            lifted,
            sol.duals,
            sol.x,
            exact=False,
            resolve=resolve,
            solve_point=solve_point,
            solve_s=solve_s,
            budget_s=budget,
        )
    except LmicError:
        return None


def _certify_at(ev: Evaluator, value: float, x: np.ndarray) -> PointResult | None:
    """The theorem bound at ``value`` and certified at ``x`` (else decided afresh there)."""
    from lmic.certify import certified_solution, certify
    from lmic.compile import bind
    from lmic.rescue import exact_rescue_point
    from lmic.studies.sweep.points import scalar_derived

    problem = bind(ev.plan, ev.sysobj, {**ev.overrides, ev.param: value})
    judge = replace(problem, objective=Objective("feasibility", np.zeros(problem.n + 1)))
    sol = Solution(status="optimal", x=x, backend="enclosure")
    t0 = time.perf_counter()
    cert: Any = certify(judge, sol)
    proof = "certified"
    if cert.verdict != "certified" and ev.exact:
        cert, proof = exact_rescue_point(judge, sol, cert), "certified (exact)"
    if cert is not None and cert.verdict == "certified":
        sol, cert = certified_solution(judge, sol, cert)  # the point proved, if it moved
        pt = PointResult(value=value, outcome="feasible", proof=proof, status="optimal", verdict="certified")
        pt.x, pt.problem, pt.certificate, pt.solution = np.asarray(sol.x, dtype=float), problem, cert, sol
        pt.certify_s = time.perf_counter() - t0
        pt.derived = scalar_derived(cert)
        pt.attempts = ["enclosure point: " + proof]
        ev.points.append(pt)
        return pt
    pt = ev(value, "enclosure")  # a full decision at this value, preconditioned at x
    return pt if pt.outcome == "feasible" else None
