"""The default route: the fastest route that can *prove* the answer, chosen by shape and size.

With no backend (or ``"auto"``) :func:`decide_route` runs:

* **feasibility problems**: the escalating policy of :mod:`lmic.policy` on the route of
  :func:`lmic.backends.auto.route`: above a tiny size, strict feasibility problems take the
  certified first-order route (SCS under the trace normalisation, a fixed-margin point, checked
  by the certifier), escalating to CVXOPT and the rest of :data:`lmic.policy.ORDER` when it
  fails; tiny ones take Clarabel, the embedded default solver;
* **optimisation problems**: each backend of the route alone (:func:`lmic.policy.decide`) until
  one gives a certified point, then the certified enclosure of the optimal value
  (:func:`lmic.certify.enclosure.enclosure`, from the primal point and the repaired dual). A
  first-order step (``auto:first-order``) whose enclosure does not meet
  :attr:`lmic.options.SolveOptions.gap` is polished by the interior-point method that suits the
  shape (:func:`lmic.backends.auto.schur_complement_shape`: CVXOPT when the variables are few
  against the PSD dimension, Clarabel otherwise); the route stops at the first certified
  interior-point answer (a gap it cannot close is reported, never hidden).

An explicit backend is that backend alone, as before. :func:`describe` gives the one line the
CLI prints (``route: scs (first-order, n=40) -> certified``), also in the JSON (``route``).

Examples
--------
>>> from lmic.testing.conformance import lyapunov_problem
>>> import numpy as np
>>> r = decide_route(lyapunov_problem(-np.eye(2)))
>>> r.outcome.verdict, r.route["text"]
('certified', 'route: clarabel (interior point; 3 variables, PSD 2+2) -> certified')
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from lmic.ir.problem import Problem
from lmic.outcome import Outcome, rank

__all__ = [
    "RouteResult",
    "decide_route",
    "describe",
    "enclosure_of",
    "method_of",
    "OPTIMISATION_FIRST_ORDER_TOL",
    "OPTIMISATION_FIRST_ORDER_ITERS",
]

#: tolerance of the first-order step of an optimisation route ("moderate accuracy": the
#: enclosure, not the solver, says how close the point is)
OPTIMISATION_FIRST_ORDER_TOL = 1e-6
#: iteration cap of that step (each strategy of it): a first-order solve that has not met the
#: tolerance by then is polished by the interior-point step instead (SCS without a cap took
#: 200 s on a 30-state bounded-real lemma where CVXOPT takes 2 s)
OPTIMISATION_FIRST_ORDER_ITERS = 2000


@dataclass
class RouteResult:
    """What :func:`decide_route` concluded: the outcome, the enclosure (optimisation problems
    on the default route; ``None`` otherwise: the caller computes it), and the route taken."""

    outcome: Outcome
    enclosure: dict[str, Any] | None = None
    enclosure_s: float = 0.0
    route: dict[str, Any] = field(default_factory=dict)


def method_of(backend: str) -> str:
    """``"first-order"`` or ``"interior point"``.

    >>> method_of("scs"), method_of("cvxopt")
    ('first-order', 'interior point')
    """
    from lmic.policy import _instance

    try:
        return "interior point" if _instance(backend).interior_point else "first-order"
    except Exception:  # noqa: BLE001 - a label only (an unknown backend was refused earlier)
        return "interior point"


def describe(route: list[dict[str, Any]], problem: Problem) -> str:
    """The one-line route: each backend tried with its method and verdict.

    >>> from lmic.testing.conformance import lyapunov_problem
    >>> import numpy as np
    >>> describe([{"backend": "scs", "verdict": "certified"}], lyapunov_problem(-np.eye(2)))
    'route: scs (first-order; 3 variables, PSD 2+2) -> certified'
    """
    parts = []
    blocks = "+".join(str(lmi.dim) for lmi in problem.lmis) or "0"
    for step in route:
        shape = f"{problem.n} variables, PSD {blocks}"
        text = f"{step['backend']} ({method_of(step['backend'])}; {shape}) -> {step['verdict']}"
        if step.get("rel_gap") is not None:
            text += f", relative gap {step['rel_gap']:.1e}"
        elif step.get("gap_note"):
            text += f", {step['gap_note']}"
        parts.append(text)
    return "route: " + " => ".join(parts)


def _steps(outcome: Outcome) -> list[dict[str, Any]]:
    """One step per backend of the attempts, with the verdict of its last attempt."""
    steps: list[dict[str, Any]] = []
    for a in outcome.attempts:
        if steps and steps[-1]["backend"] == a.backend:
            steps[-1]["verdict"] = a.verdict if rank(a.verdict) >= rank(steps[-1]["verdict"]) else steps[-1]["verdict"]
        else:
            steps.append({"backend": a.backend, "verdict": a.verdict})
    return steps


def _solve_on(backend: Any, problem: Problem, options: Any) -> Any:
    """``problem`` solved on ``backend`` with the reductions (``None`` if it cannot take it or fails)."""
    from lmic.errors import LmicError
    from lmic.policy import _instance
    from lmic.reductions.pipeline import solve

    try:
        be = _instance(backend)
        if not be.supports(problem):
            return None  # as lmic.api.solve_problem: a backend that cannot take it is no answer
        return solve(be, problem, options)
    except LmicError:
        return None


def enclosure_of(
    problem: Problem, sol: Any, cert: Any, exact: bool, backend: Any, options: Any
) -> tuple[dict[str, Any] | None, float]:
    """The certified enclosure of ``problem``'s optimal value from a solution's point and dual.

    ``None`` for a feasibility problem, or without a certificate or a solution to work from. A
    degenerate dual is retried on a perturbed problem, then on a centred dual point (the dual
    problem solved for the largest interior margin), both on ``backend``; a gap above
    :data:`lmic.certify.enclosure.GAP_TARGET` on an interior-point backend gets one re-solve at
    :data:`~lmic.certify.enclosure.TIGHT_TOL` (:func:`tighten`).

    >>> from lmic.testing.conformance import lyapunov_problem
    >>> import numpy as np
    >>> enclosure_of(lyapunov_problem(-np.eye(1)), None, None, False, "clarabel", None)
    (None, 0.0)
    """
    if problem.objective.sense == "feasibility" or cert is None or sol is None:
        return None, 0.0
    if sol.status in ("infeasible", "unbounded"):
        return None, 0.0
    from lmic.certify.enclosure import enclosure

    t0 = time.perf_counter()
    x = sol.x if getattr(cert, "verdict", None) == "certified" else None

    def resolve(perturbed: Problem) -> dict[str, Any] | None:
        other = _solve_on(backend, perturbed, options)
        return other.duals if other is not None and other.status in ("optimal", "inaccurate") else None

    def solve_point(other_problem: Problem) -> np.ndarray | None:
        other = _solve_on(backend, other_problem, options)
        return other.x if other is not None and other.status in ("optimal", "inaccurate") else None

    # solve_s: a failing lower end costs a few solves at most (search_budget)
    solve_s = float(getattr(sol, "solve_s", 0.0))
    enc = enclosure(problem, sol.duals, x, exact=exact, resolve=resolve, solve_point=solve_point, solve_s=solve_s)
    enc = tighten(problem, enc, x, exact, backend, options, resolve, solve_point)
    return enc, time.perf_counter() - t0


def tighten(
    problem: Problem,
    enc: dict[str, Any],
    x: Any,
    exact: bool,
    backend: Any,
    options: Any,
    resolve: Any,
    solve_point: Any,
) -> dict[str, Any]:
    """A gap above :data:`lmic.certify.enclosure.GAP_TARGET` on an interior-point backend: a
    re-solve at :data:`~lmic.certify.enclosure.TIGHT_TOL` and the better proven end of each.

    When the tight point's primal end is met only to round-off, the end comes from a point
    polished toward it (``restored point``); without any proven end there, ``tight_x`` records
    the tight point for the restoration of :func:`lmic.api.solve`.
    """
    from dataclasses import replace

    from lmic.certify.enclosure import (
        GAP_TARGET,
        TIGHT_TOL,
        best_of,
        enclosure,
        polish_primal,
        with_primal,
    )
    from lmic.options import SolveOptions

    gap = enc.get("rel_gap")
    label = str(getattr(backend, "name", backend) or "")
    if (gap is not None and gap <= GAP_TARGET) or "scs" in label.lower():
        return enc
    key = "upper" if problem.objective.sense == "min" else "lower"
    if gap is None and enc.get(key) is not None:
        # the primal end is proven and the dual end is not: the dual search already tried its
        # perturbed and centred routes; a tighter solve puts the dual nearer the boundary of its
        # cone, not inside it (on the bounded-real lemma at n = 20 it doubled the time, 6.5 s of
        # 12, and proved nothing), so there is nothing for a re-solve to tighten
        return enc
    if options is not None and options.tol <= TIGHT_TOL:
        return enc
    tight = replace(options, tol=TIGHT_TOL) if options is not None else SolveOptions(tol=TIGHT_TOL)
    sol2 = _solve_on(backend, problem, tight)
    if sol2 is None or sol2.status not in ("optimal", "inaccurate") or sol2.x is None:
        return enc
    enc2 = enclosure(
        problem,
        sol2.duals,
        sol2.x,
        exact=exact,
        resolve=resolve,
        solve_point=solve_point,
        solve_s=sol2.solve_s,
    )
    inner = enc.get("restored_x") if enc.get("primal") == "restored point" else x
    if enc2.get(key) is None and enc.get(key) is not None and inner is not None:
        # the tight point is met only to round-off: as close to it as the proof allows
        pol = polish_primal(problem, np.asarray(inner, dtype=float), np.asarray(sol2.x, dtype=float))
        if pol["proven"]:
            enc2 = dict(with_primal(enc2, pol["value"], "restored point"), restored_x=pol["x"])
            return best_of(enc, enc2, pol["x"])
    out = best_of(enc, enc2, sol2.x)
    if out.get(key) is None:
        out["tight_x"] = np.asarray(sol2.x, dtype=float).tolist()  # the restoration's target (solve())
    return out


def decide_route(problem: Problem, backend: Any = None, options: Any = None, *, exact: bool = False) -> RouteResult:
    """Decide ``problem`` on the route of the module docstring.

    Parameters
    ----------
    problem : Problem
    backend : str, Backend or None
        ``None`` / ``"auto"`` / ``"auto:first-order"`` / ``"auto:interior-point"``: the default
        route; anything else: that backend alone (:func:`lmic.policy.decide`).
    options : SolveOptions, optional
        ``options.gap`` is the relative gap an optimisation route stops at.
    exact : bool

    Returns
    -------
    RouteResult
    """
    from lmic.options import SolveOptions
    from lmic.policy import decide, is_auto, route

    options = options or SolveOptions()
    if not is_auto(backend) or problem.objective.sense == "feasibility":
        out = decide(problem, backend, options, exact=exact)
        done = _steps(out)
        return RouteResult(out, None, 0.0, {"steps": done, "text": describe(done, problem)})
    names = route(problem, backend)
    best: Outcome | None = None
    best_enc: dict[str, Any] | None = None
    enc_s = 0.0
    attempts: list[Any] = []
    steps: list[dict[str, Any]] = []
    bounded = 0
    for name in names:
        first_order = method_of(name) == "first-order"
        opts = options
        if first_order:
            from dataclasses import replace

            opts = replace(
                options,
                tol=max(options.tol, OPTIMISATION_FIRST_ORDER_TOL),
                max_iter=options.max_iter or OPTIMISATION_FIRST_ORDER_ITERS,
            )
        out = decide(problem, name, opts, exact=exact)
        attempts.extend(out.attempts)
        step: dict[str, Any] = {"backend": name, "verdict": out.verdict}
        steps.append(step)
        enc = None
        if out.verdict == "certified":
            enc, t_enc = enclosure_of(problem, out.solution, out.certificate, exact, name, opts)
            enc_s += t_enc
            rel = None if enc is None else enc.get("rel_gap")
            step["rel_gap"] = rel
            if rel is None:
                step["gap_note"] = "no certified lower end" if enc and enc.get("upper") is not None else "no enclosure"
        if best is None or rank(out.verdict) > rank(best.verdict) or _tighter(enc, best_enc, out, best):
            best, best_enc = out, enc
        if out.verdict == "certified":
            rel = step.get("rel_gap")
            if rel is not None and rel <= options.gap:
                break  # the enclosure proves the optimum to the requested gap
            if not first_order:
                break  # a certified interior-point answer: its enclosure is what can be proved
            continue  # a first-order point whose gap is too wide: polish
        if out.verdict == "infeasible-certified":
            break
        if out.verdict == "infeasible-bounded":
            bounded += 1
            if bounded >= 2:
                break
    assert best is not None
    best.attempts = attempts
    if best.solution is not None:
        best.solution.info["attempts"] = [a.to_dict() for a in attempts]
    return RouteResult(best, best_enc, enc_s, {"steps": steps, "text": describe(steps, problem), "gap": options.gap})


def _tighter(enc: dict[str, Any] | None, best_enc: dict[str, Any] | None, out: Outcome, best: Outcome) -> bool:
    """A later certified answer (a polish) replaces an earlier one unless the earlier one's
    enclosure has a smaller relative gap."""
    if out.verdict != "certified" or best.verdict != "certified":
        return False
    new, old = (enc or {}).get("rel_gap"), (best_enc or {}).get("rel_gap")
    return old is None or (new is not None and new <= old)
