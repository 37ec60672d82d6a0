"""Suprema and infima of a scalar parameter by bisection on certified feasibility.

:func:`maximize` and :func:`minimize` re-bind the theorem's cached plan
(:func:`lmic.compile.plan_for`, :func:`lmic.compile.bind`) at every value: the template is
analysed once, each point costs one bind, one solve (warm-started from the neighbouring point)
and one certification (:mod:`lmic.studies.sweep.points`).

Where the parameter enters the theorem's constraints affinely and multiplies no decision
variable (``gamma`` in ``[..., -gamma I]``), or multiplies only a positive scalar of a
scale-free theorem (``beta omega`` in ``qib.thm1``, :mod:`lmic.studies.sweep.homogeneous`), the
supremum is itself the optimal value of a convex problem: it is solved once and its other end
proven (:mod:`lmic.studies.sweep.enclosed`) instead of bisected, unless ``method="bisection"``.

Interior values are cheap where they can be: a certified point is certified again further up
where its LMIs, modelled as affine in the parameter, stay definite (``stretch``, no solve), and
screens impose a small margin (near a supremum the best margin is about the tolerance).

For the supremum the parameter only has to be feasible, so the theorem's objective is dropped:
each point is a feasibility problem, routed and reduced as one by the solve policy. Once a point
needed it, the solver is given each LMI after a diagonal congruence ``D F(x) D`` with ``D =
diag(F(x_ref))^-1/2`` taken at the last certified point ``x_ref``
(:mod:`lmic.reductions.precondition`). A congruence does not change which ``x`` are feasible,
and the certificate is always computed on the original LMIs.

Evidence where the answer needs it: until a value is certified, and at the bracket's final
non-certified end, the full solve policy decides (escalation, proofs). Interior values of a
problem that is not small first try the last certified point (certified again, no solve), then
one certified solve (:func:`lmic.studies.sweep.points.screen`): a certified point moves the
lower end; anything else moves the upper end *without* evidence (``screened``), and the final
upper end is then decided by the full policy. If that end turns out certified, the screen was
wrong: screening stops, the bracket moves up to the nearest value not certified (or expands
again) and the bisection goes on. A screened value is never reported as a proof.

Bisection assumes that the feasible values form an interval that contains the lower end of the
bracket (true for Lipschitz constants, delay bounds and similar parameters). Its report is
honest about both ends: ``lower`` is certified; ``upper`` is the smallest value tried that was
not certified, with whether it was proven infeasible or merely not certified.

Examples
--------
>>> r = maximize("thesis.thm3_2_2", "examples/thesis.thm3_2_2.ex3_2_2.yaml", "gamma",
...              rtol=1e-4)                                           # doctest: +SKIP
>>> round(r.lower, 4), r.converged                                    # doctest: +SKIP
(0.9997, True)
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from typing import Any

from lmic.errors import DataError, LmicError
from lmic.studies.sweep.ends import certified_end
from lmic.studies.sweep.points import Evaluator, domain, in_domain, setup
from lmic.studies.sweep.results import PointResult, Progress, SupResult, kind_of

__all__ = ["maximize", "minimize", "METHODS"]

#: how a supremum is found: ``auto`` (the enclosure where the parameter enters affinely, else
#: bisection), ``enclosure`` (fails over to bisection when it cannot decide), ``bisection``
METHODS = ("auto", "enclosure", "bisection")


def maximize(
    theorem: str,
    system: Any,
    param: str,
    *,
    lo: float | None = None,
    hi: float | None = None,
    xtol: float = 1e-6,
    rtol: float = 1e-5,
    params: Mapping[str, Any] | None = None,
    backend: Any = None,
    options: Any = None,
    exact: bool = True,
    max_evals: int = 100,
    progress: Progress | None = None,
    backoff: float | None = None,
    method: str = "auto",
) -> SupResult:
    """Supremum of a scalar parameter by bisection on certified feasibility.

    Parameters
    ----------
    theorem : str
        Theorem id.
    system : path, dict or System
    param : str
        A numeric parameter of the theorem (e.g. ``gamma``).
    lo, hi : float, optional
        Bracket. Without them the search starts at the system's (or the default) value, or 1,
        and expands (doubling) or shrinks (halving) until a certified and a non-certified value
        enclose the supremum; the parameter's domain bounds the search.
    xtol, rtol : float
        Stop when ``upper - lower <= max(xtol, rtol * |upper|)``.
    params : mapping, optional
        Other parameter overrides (``-p k=v``).
    backend : str or Backend
    options : SolveOptions, optional
    exact : bool
        Accept exact rational proofs at points whose float margins are too small.
    max_evals : int
        Bound on the number of points.
    progress : callable, optional
        Called with ``{"phase", "value", "point", "lower", "upper", "iteration", "total"}``.
    backoff : float, optional
        Relative backoff of the certified end's point (:func:`certified_end`; ``0`` off).
    method : {"auto", "enclosure", "bisection"}
        ``auto``: where the parameter enters affinely, one convex solve and its enclosure
        (:mod:`lmic.studies.sweep.enclosed`; ``lo``/``hi`` are then not needed), else bisection;
        ``bisection``: always bisect. ``SupResult.method`` says which ran, ``method_note`` why.

    Returns
    -------
    SupResult
        With ``end``: the certified point at ``lower``, its gains and derived values.

    Examples
    --------
    >>> r = maximize("uio_dt.thm4_1", "examples/uio_dt.thm4_1.flexible_joint.yaml", "gamma",
    ...              rtol=1e-3)                                        # doctest: +SKIP
    >>> round(r.lower, 1), next(p.proof for p in r.points if p.value == r.lower)  # doctest: +SKIP
    (51.5, 'certified (exact)')
    """
    return _sup(
        theorem,
        system,
        param,
        1.0,
        lo,
        hi,
        xtol,
        rtol,
        params,
        backend,
        options,
        exact,
        max_evals,
        progress,
        backoff,
        method,
    )


def minimize(
    theorem: str,
    system: Any,
    param: str,
    *,
    lo: float | None = None,
    hi: float | None = None,
    xtol: float = 1e-6,
    rtol: float = 1e-5,
    params: Mapping[str, Any] | None = None,
    backend: Any = None,
    options: Any = None,
    exact: bool = True,
    max_evals: int = 100,
    progress: Progress | None = None,
    backoff: float | None = None,
    method: str = "auto",
) -> SupResult:
    """Infimum of a scalar parameter by bisection on certified feasibility (:func:`maximize` mirrored).

    Assumes that the feasible values form an interval that contains the upper end of the
    bracket (e.g. a decay rate or a gain bound ``gamma``). The result has ``sense == "min"``:
    ``upper`` is the certified end (``end`` its point), ``lower`` the largest value tried below
    it that was not certified, ``upper_kind`` / ``upper_proven`` that end's evidence and the
    largest value with a GLOBAL infeasibility proof.

    Parameters
    ----------
    As :func:`maximize`; ``hi`` is the certified end of the bracket, ``lo`` the other.

    Returns
    -------
    SupResult

    Examples
    --------
    >>> r = minimize("uio_dt.thm4_1", "examples/uio_dt.thm4_1.flexible_joint.yaml", "gamma",
    ...              lo=1.0, hi=2.0)                                   # doctest: +SKIP
    >>> r.sense, r.upper                                               # doctest: +SKIP
    ('min', 1.0)
    """
    return _sup(
        theorem,
        system,
        param,
        -1.0,
        lo,
        hi,
        xtol,
        rtol,
        params,
        backend,
        options,
        exact,
        max_evals,
        progress,
        backoff,
        method,
    )


def _sup(
    theorem: str,
    system: Any,
    param: str,
    sign: float,
    lo_v: float | None,
    hi_v: float | None,
    xtol: float,
    rtol: float,
    params: Mapping[str, Any] | None,
    backend: Any,
    options: Any,
    exact: bool,
    max_evals: int,
    progress: Progress | None,
    backoff: float | None,
    method: str,
) -> SupResult:
    """The enclosure where it applies (``method``), else the bisection."""
    if method not in METHODS:
        raise LmicError(f"method '{method}' unknown; choose {', '.join(METHODS)}")
    if not (xtol > 0 or rtol > 0) or xtol < 0 or rtol < 0:
        raise LmicError("--xtol and --rtol must be non-negative and not both 0")
    note = "bisection asked for"
    if method != "bisection":
        from lmic.studies.sweep.enclosed import enclose

        res, why = enclose(
            theorem,
            system,
            param,
            sign,
            params=params,
            backend=backend,
            options=options,
            exact=exact,
            xtol=xtol,
            rtol=rtol,
            backoff=backoff,
        )
        if res is not None:
            fixed = f" with {res.method_note}" if res.method_note else ""
            res.method_note = f"'{param}' enters affinely{fixed}: one convex solve, enclosed"
            return res
        note = f"no enclosure: {why}"
    res = _bisect(
        theorem,
        system,
        param,
        sign,
        lo_v,
        hi_v,
        xtol,
        rtol,
        params,
        backend,
        options,
        exact,
        max_evals,
        progress,
        backoff,
    )
    res.method_note = note
    return res


def _bisect(
    theorem: str,
    system: Any,
    param: str,
    sign: float,
    lo_v: float | None,
    hi_v: float | None,
    xtol: float,
    rtol: float,
    params: Mapping[str, Any] | None,
    backend: Any,
    options: Any,
    exact: bool,
    max_evals: int,
    progress: Progress | None,
    backoff: float | None,
) -> SupResult:
    """The bisection in ``u = sign * value`` (a supremum of ``u``), reported in the parameter's terms."""
    t_start = time.perf_counter()
    if not (xtol > 0 or rtol > 0) or xtol < 0 or rtol < 0:
        raise LmicError("--xtol and --rtol must be non-negative and not both 0")
    t0 = time.perf_counter()
    sysobj, plan, overrides, decl = setup(theorem, system, param, params)
    interval = _interval_proven(plan, sysobj, overrides, decl)
    plan_s = time.perf_counter() - t0
    dom_v = domain(decl)
    for name, v in (("--lo", lo_v), ("--hi", hi_v)):
        if v is not None and (not math.isfinite(v) or not in_domain(v, dom_v)):
            raise DataError(f"theorem {plan.id}: {name} {v:g} is outside the domain {decl.domain} of '{param}'")
    if lo_v is not None and hi_v is not None and not lo_v < hi_v:
        raise DataError(f"--lo {lo_v:g} must be below --hi {hi_v:g}")
    is_max = sign > 0
    # u = sign * value: a supremum of u (the certified end first, as --lo of a supremum)
    dom = dom_v if is_max else (-dom_v[1], -dom_v[0], dom_v[3], dom_v[2])
    lo = lo_v if is_max else (None if hi_v is None else -hi_v)
    hi = hi_v if is_max else (None if lo_v is None else -lo_v)
    lo_flag, hi_flag = ("--lo", "--hi") if is_max else ("--hi", "--lo")
    what = "supremum" if is_max else "infimum"

    def vv(u: float | None) -> float | None:
        return None if u is None else sign * u

    def bracket_v(a: float | None, b: float | None) -> tuple[float | None, float | None]:
        return (a, b) if is_max else (vv(b), vv(a))

    state: dict[str, Any] = {"lower": None, "upper": None, "iteration": 0, "total": None}

    def report(event: dict[str, Any]) -> None:
        if progress is not None:
            progress({**event, **state})

    # interior values: the last certified point first, then one certified solve (screen); the
    # full policy only where that does not decide, and at the final non-certified end
    ev = Evaluator(plan, sysobj, overrides, param, backend, options, False, exact, report, sign, screen=True)
    lower: float | None = None
    upper: float | None = None
    upper_pt: PointResult | None = None
    message = ""

    def feasible(v: float, phase: str) -> bool:
        nonlocal lower, upper, upper_pt
        # until a value is certified, the full policy decides (a screen's "not certified"
        # would end the search without evidence); then interior values are screened
        pt = ev(v, phase, full=lower is None)
        if pt.outcome == "feasible":
            if lower is None or v > lower:
                lower = v
            if upper is not None and not pt.reused and lower == v:
                # the point may hold further up: certified again there, no solve
                st = ev.stretch(v, upper)
                if st is not None:
                    lower = sign * st.value
        elif upper is None or v < upper:
            upper, upper_pt = v, pt
        state["lower"], state["upper"] = bracket_v(lower, upper)
        return pt.outcome == "feasible"

    dlo, dhi, dlo_in, dhi_in = dom

    def up(v: float, k: int) -> float:
        step = abs(v) if v != 0 else 1.0
        cand = v + step * (2.0**k - 1.0) if v > 0 else v + step * 2.0 ** (k - 1)
        if cand >= dhi:  # halfway from the latest certified value to an open end (not from v: a
            # fixed base gave the same midpoint twice and stopped at half the start, "certified to the end")
            ref = v if lower is None else max(v, lower)
            cand = dhi if dhi_in else 0.5 * (ref + dhi) if math.isfinite(dhi) else cand
        return cand

    def down(v: float, k: int) -> float:
        cand = v / 2.0**k if v > 0 else v - (abs(v) or 1.0) * (2.0**k - 1.0)
        if v > 0 and k > 40:
            cand = 0.0
        if cand <= dlo:
            ref = v if upper is None else min(v, upper)
            cand = dlo if dlo_in else 0.5 * (ref + dlo) if math.isfinite(dlo) else cand
        return cand

    # -- bracket ---------------------------------------------------------------------------
    if lo is not None:
        if not feasible(lo, "bracket"):
            message = f"no certified point at {lo_flag} {vv(lo):g}"
    if hi is not None and (lo is None or lower is not None):
        if feasible(hi, "bracket"):
            side = "at or above" if is_max else "at or below"
            message = f"{hi_flag} {vv(hi):g} is certified: the {what} is {side} the bracket"
    if lo is None and hi is None:
        start = sysobj.params.get(param, decl.default)
        x0 = sign * float(start) if isinstance(start, int | float) and float(start) != 0 else sign
        if not in_domain(x0, dom):
            x0 = 0.5 * (dlo + dhi) if math.isfinite(dlo) and math.isfinite(dhi) else (dlo + 1.0)
        feasible(x0, "bracket")

    def expand() -> str:
        """Expand upwards from the certified ``lower`` until a value is not certified."""
        assert lower is not None
        k, base = 1, lower
        while upper is None and len(ev.points) < max_evals:
            cand = up(base, k)
            if cand <= lower or (ev.points and cand == sign * ev.points[-1].value):
                way = "up" if is_max else "down"
                return f"'{param}' is certified {way} to the end of its domain ({vv(lower):g})"
            feasible(cand, "bracket")
            k += 1
        return ""

    if not message:
        if lower is not None and upper is None:  # expand upwards
            message = expand()
        elif lower is None and upper is not None:  # shrink downwards
            k, base = 1, upper
            while lower is None and len(ev.points) < max_evals:
                cand = down(base, k)
                if cand >= upper or (ev.points and cand == sign * ev.points[-1].value):
                    message = f"no certified value of '{param}' found down to the end of its domain"
                    break
                feasible(cand, "bracket")
                k += 1
        if lower is None and not message:
            message = f"no certified value of '{param}' found"
        elif upper is None and not message:
            message = f"no {'upper' if is_max else 'lower'} bound found for '{param}' within {max_evals} points"

    # -- bisection ---------------------------------------------------------------------------
    def target(a: float, b: float) -> float:
        return max(xtol, rtol * max(abs(a), abs(b)))

    iterations = 0
    at_resolution = [False]

    def bisect_loop() -> None:
        nonlocal iterations
        assert lower is not None and upper is not None
        width, tgt = upper - lower, target(lower, upper)
        state["total"] = max(0, math.ceil(math.log2(width / tgt))) if width > tgt else 0
        while upper - lower > target(lower, upper) and len(ev.points) < max_evals:
            iterations += 1
            state["iteration"] = iterations
            # remaining halvings (the relative target moves with the bracket)
            state["total"] = iterations - 1 + max(1, math.ceil(math.log2((upper - lower) / target(lower, upper))))
            mid = 0.5 * (lower + upper)
            if not lower < mid < upper:  # the bracket is two adjacent floats: it cannot shrink
                at_resolution[0] = True
                break
            feasible(mid, "bisect")

    while lower is not None and upper is not None and upper > lower:
        bisect_loop()
        if upper_pt is None or not upper_pt.screened:
            break
        # the final non-certified end was only screened (the solver said infeasible): its
        # evidence comes from the full policy (a proof, or an honest label)
        pt = ev(upper, "prove", full=True, prove=True)
        if pt.outcome != "feasible":
            upper_pt = pt
            break
        # the screen was wrong: the bracket moves up to the next value not certified; a wrong
        # first-order screen ends first-order screens, a wrong interior-point screen ends
        # screening (the rest of the bisection uses the full policy: screens disagree with it
        # near this end)
        if upper_pt.first_order:
            ev.first_order = False
        else:
            ev.screen = False
        lower = upper
        # the next upper end: the nearest value not certified (if it was only screened, the
        # full policy decides it when it is the final end again)
        above = [sign * p.value for p in ev.points if p.outcome != "feasible" and sign * p.value > lower]
        upper, upper_pt = None, None
        if above:
            upper = min(above)
            upper_pt = next(p for p in reversed(ev.points) if sign * p.value == upper and p.outcome != "feasible")
        state["lower"], state["upper"] = bracket_v(lower, upper)
        if upper is None:  # no value above was tried: expand again
            message = expand() or message
            if upper is None and not message:
                message = f"no {'upper' if is_max else 'lower'} bound found for '{param}' within {max_evals} points"
    converged = lower is not None and upper is not None and upper - lower <= target(lower, upper)
    if lower is not None and upper is not None and not converged and not message:
        if at_resolution[0]:
            message = "stopped at floating-point resolution: the bracket's ends are adjacent numbers"
        else:
            message = f"stopped after {len(ev.points)} points (--max-evals) before the tolerance"
    proven = [
        sign * p.value
        for p in ev.points
        if kind_of(p) == "infeasible-certified" and (lower is None or sign * p.value > lower)
    ]
    upper_kind = "none" if upper_pt is None else kind_of(upper_pt)
    end = None
    if lower is not None:
        lower_pt = next(p for p in ev.points if sign * p.value == lower and p.outcome == "feasible")
        end = certified_end(lower_pt, backend, options, backoff)
        for p in ev.points:  # only the end's problem is needed
            if p is not lower_pt:
                p.problem = None
    if upper is not None and upper_kind != "infeasible-certified" and not message:
        end_name, rel_op, more = ("upper", ">=", "larger (even infinite)") if is_max else ("lower", "<=", "smaller")
        message = f"the bisection's {end_name} end {vv(upper):g} is {upper_kind}, not a proof: the {what} is "
        if proven and lower is not None:  # a farther point is proved infeasible: the proven bracket
            lo_v, hi_v = sorted((sign * lower, sign * min(proven)))
            message += f"in [{lo_v:g}, {hi_v:g}] ({sign * min(proven):g}: infeasible-certified)"
        else:
            message += f"{rel_op} {vv(lower) if lower is not None else '-'} and may be {more}"
    if lower is not None and (upper_kind == "infeasible-certified" or proven) and not interval:
        message = (message + "; " if message else "") + (
            f"the bracket assumes that the feasible values of '{param}' form an interval, which lmic "
            f"does not prove ('{param}' is not shown to enter affinely): proven are a certified point at "
            f"{vv(lower):g} and infeasibility at {vv(min(proven)) if proven else vv(upper):g}"
        )
    lower_v, upper_v = bracket_v(lower, upper)
    return SupResult(
        theorem=plan.id,
        param=param,
        lower=lower_v,
        upper=upper_v,
        upper_kind=upper_kind,
        upper_proven=vv(min(proven)) if proven else None,
        converged=converged,
        xtol=xtol,
        rtol=rtol,
        iterations=iterations,
        points=ev.points,
        backend=str(getattr(backend, "label", backend) or "auto"),
        plan_s=plan_s,
        total_s=time.perf_counter() - t_start,
        message=message,
        domain=(dom_v[0], dom_v[1]),
        end=end,
        sense="max" if is_max else "min",
        system=sysobj,
        interval_proven=interval,
    )


def _interval_proven(plan: Any, sysobj: Any, overrides: Any, decl: Any) -> bool:
    """The feasible values of the parameter form an interval: it enters affinely (then the feasible
    set in ``(x, p)`` is convex and its projection on ``p`` an interval), or affinely through a
    power ``p^k`` that multiplies no decision variable, ``p >= 0`` (``gamma^2``)."""
    from lmic.studies.sweep.enclosed import affine_parameter, monotone_affine

    try:
        return bool(
            affine_parameter(plan, sysobj, overrides, decl)[0] or monotone_affine(plan, sysobj, overrides, decl)
        )
    except (LmicError, ValueError, ArithmeticError):
        return False
