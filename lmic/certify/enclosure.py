"""Certified enclosures of the optimal value: a proven dual (lower) bound next to the primal one.

For an optimisation problem the certifier proves an *upper* bound on a minimum: the objective
at a certified feasible point. This module proves the *lower* bound, from the solver's dual
point, with every floating-point error accounted for (the approach of VSDP: Jansen, Chaykin
and Keil, "Rigorous error bounds for the optimal value in semidefinite programming", SIAM J.
Numer. Anal. 46 (2007); adapted to lmic's LMI form, where the free variables are ``x``).

Setting (minimisation form)
---------------------------
With ``s = +1`` for ``minimize`` and ``s = -1`` for ``maximize``, write ``q = s c`` (``q_0``
the constant). The problem is ``p* = inf q_0 + q . x`` over ``F_i(x) >= 0`` (``> 0`` when
strict) and rows ``l_r(x) = a_r0 + a_r . x`` ``== 0`` (``eq``) or ``>= 0`` (``ge``). A dual
point is ``u = (Z_i, y)`` (the layout of :attr:`lmic.solution.Solution.duals`, paired with the
normalised ``F_i``). With ``g_k(u) = sum_i <F_i^(k), Z_i> + sum_r a_rk y_r`` (``k = 0 .. n``)
the identity

    ``q_0 + q . x = sum_i <F_i(x), Z_i> + sum_r y_r l_r(x) + (q_0 - g_0(u)) + (q - g(u))_{1:} . x``

holds for every ``x``. **Theorem (weak duality).** If ``Z_i >= 0``, ``y_r >= 0`` on ``ge``
rows and ``g_k(u) = q_k`` exactly for ``k >= 1``, then every feasible ``x`` (strict or not)
has objective ``>= L = q_0 - g_0(u)``. So ``L <= p*``; for a strict problem ``p*`` is an
infimum, possibly not attained, and ``L`` bounds it all the same.

Making the conditions hold exactly
----------------------------------
The solver's dual meets ``g_k = q_k`` only to its tolerance, and at an optimum ``Z_i`` is
singular (complementarity), so neither condition can be checked by floating point as it
stands. The steps, each checked rather than trusted:

1. *signs*: ``Z_i`` is projected onto the PSD cone, ``y`` clipped to ``>= 0`` on ``ge`` rows;
2. *shift*: ``Z_i += eps I`` and ``y_r += eps`` on ``ge`` rows, ``eps = eps_rel * max_i
   lambda_max(Z_i)`` (``eps_rel`` tried in :data:`SHIFTS`, smallest first): the dual moves
   into the interior of the cone, at a cost of about ``eps (sum_i tr F_i(x*) + sum_r
   l_r(x*))`` in the bound;
3. *repair*: damped least-squares steps ``Z_i -> eps/2 I + U_i (I + E_i) U_i^T`` (``Z_i -
   eps/2 I = U_i U_i^T``, ``||E_i||_2 <= 1/2``) and ``y_r -> eps/2 + (y_r - eps/2) (1 + e_r)``
   (``ge`` rows; ``eq`` rows are free), so that every eigenvalue stays above ``eps / 2``, drive
   the residual ``rho = q_{1:} - g_{1:}(u)`` down while keeping the cone; two plain
   least-norm steps over every entry then take it to round-off (they may leave the cone by
   their own size, which the shift must cover: the proof decides);
4. *rigorous bound*, in floating point with a priori error bounds (``u = 2^-53``,
   ``gamma_m = m u / (1 - m u)``, Higham, *Accuracy and Stability*, 2nd ed., ch. 3 and 10):

   * ``rho`` is enclosed: ``|rho_k| <= |fl(rho_k)| + gamma_{m+2} (|q_k| + sum_j |J_kj| |u_j|)``
     (``J`` is the matrix of the linear map ``u -> g(u)``; its entries are IR coefficients
     times 1 or 2, exact in floating point);
   * the exact point ``u* = u + J_S^T M^{-1} rho`` (``S``: the entries of every ``Z_i`` and
     the ``y_r``; ``M = J_S J_S^T``) satisfies ``g_k(u*) = q_k`` exactly, and
     ``||u* - u||_2 <= ||rho||_2 / sqrt(lambda_min(M))``; a rigorous lower bound of
     ``lambda_min(M)`` comes from ``fl(M)`` (error ``<= gamma_m || |J_S| |J_S|^T ||_F``) and
     :func:`lambda_min_lower`;
   * every ``Z_i* = Z_i + Delta_i`` with ``||Delta_i||_2 <= ||Delta_i||_F <= sqrt(2)
     ||u* - u||_2`` (an off-diagonal unknown appears twice), so ``lambda_min(Z_i*) >=
     lambda_min_lower(Z_i) - sqrt(2) ||u* - u||`` (Weyl) must be ``>= 0``, and
     ``y_r* >= y_r - ||u* - u|| >= 0`` on ``ge`` rows;
   * ``L = q_0 - g_0(u*) >= q_0 - fl(g_0(u)) - gamma_{m+2} sum_j |J_0j| |u_j| -
     ||J_{0,S}||_2 ||u* - u||_2``, the last subtraction rounded down.

   Every bound computed in floating point is inflated by ``(1 + 1e-9)`` (their own rounding
   is below ``(m + 4) u < 1e-9`` for ``m < 10^6`` unknowns).

:func:`lambda_min_lower` proves ``lambda_min(A) >= s - gamma_{2(d+1)} ||R||_F^2 - u max_i
|b_ii|`` for a float symmetric ``A`` from a successful Cholesky factorisation ``R`` of ``B =
fl(A - s I)``: ``R^T R = B + dB`` with ``|dB| <= gamma_{d+1} |R^T| |R|`` (Higham, Thm 10.3;
the constant is doubled to cover blocked LAPACK factorisations) and ``|| |R^T| |R| ||_2 <=
||R||_F^2``.

Exact mode (``exact=True``)
---------------------------
The same dual point ``u`` (after steps 1-3) is corrected in rational arithmetic
(python-flint): ``u* = u + J_S^T M^{-1} rho`` with ``rho``, ``M`` and the solve exact, every
``Z_i*`` proved PSD by an integer ``LDL^T`` / congruence (:func:`lmic.certify.exact.prove_psd`),
``y_r* >= 0`` checked exactly and ``L = q_0 - g_0(u*)`` computed exactly (reported rounded
down). Nothing is left to an error bound; it costs a rational solve of order ``n``
(:data:`EXACT_MAX_N`).

The primal end
--------------
The other end is the objective at a point proved feasible with rigorous rounding
(:func:`primal_end`: ``F_i(x)`` with an a-priori evaluation error bound, ``lambda_min`` bounded
by :func:`lambda_min_lower`, the objective rounded outwards). The certifier's ``certified``
tolerates a non-strict LMI violated by round-off; such a point gives no primal end here (the
caller may supply one from a point strictly inside, :func:`with_primal`).

What is recorded
----------------
:func:`dual_bound` returns the bound and the dual point ``u`` it was proved from (before the
exact correction, which is implicit): :func:`verify_dual_bound` re-proves the bound from the
recorded point alone, so ``lmic audit`` rejects a tampered bound (a recorded bound above the
re-proved one) or a tampered dual point (the bound no longer follows from it).

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
>>> # min t  s.t.  [[t, 1], [1, t]] >= 0  has optimum 1 (dual Z = [[.5, -.5], [-.5, .5]])
>>> C = sp.csc_matrix(np.array([[0.0, 1.0], [1.0, 0.0], [0.0, 1.0]]))
>>> p = Problem([Variable("t", "scalar", (1, 1))], [LMI("M >= 0", 2, C, strict=False)],
...             LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
>>> r = dual_bound(p, {"lmis": [np.array([[0.5, -0.5], [-0.5, 0.5]])], "linear": []})
>>> r["proven"], 0.999999 < r["lower"] <= 1.0
(True, True)
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from lmic.certify.enclosure_about import about_of, one_problem, relative_gap
from lmic.certify.enclosure_centre import centred_bound, centring_problem
from lmic.certify.enclosure_conditional import RADIUS_FACTOR, best_box_bound, box_bound, verify_box_bound
from lmic.certify.enclosure_dual import dual_bound, verify_dual_bound
from lmic.certify.enclosure_exact import EXACT_MAX_N
from lmic.certify.enclosure_face import face_bound
from lmic.certify.enclosure_facial import FacialFirst, facial_or, obvious_face
from lmic.certify.enclosure_float import lambda_min_lower, polish_primal, primal_end
from lmic.certify.enclosure_repair import PERTURBATIONS, SHIFTS, perturbed_problem
from lmic.certify.snap import exact_primal_end
from lmic.errors import CertificateError
from lmic.formatting import bound_text, interval_text
from lmic.ir.problem import Problem

__all__ = [
    "SHIFTS",
    "EXACT_MAX_N",
    "lambda_min_lower",
    "dual_bound",
    "verify_dual_bound",
    "enclosure",
    "perturbed_problem",
    "PERTURBATIONS",
    "summary",
    "describe",
    "with_primal",
    "primal_end",
    "polish_primal",
    "best_of",
    "GAP_TARGET",
    "TIGHT_TOL",
    "box_bound",
    "best_box_bound",
    "verify_box_bound",
    "RADIUS_FACTOR",
    "centring_problem",
    "centred_bound",
    "search_budget",
    "BUDGET_FACTOR",
    "BUDGET_MIN_S",
    "relative_gap",
]


def enclosure(
    problem: Problem,
    duals: dict[str, Any] | None,
    x: np.ndarray | None,
    *,
    exact: bool = False,
    resolve: Callable[[Problem], dict[str, Any] | None] | None = None,
    solve_point: Callable[[Problem], np.ndarray | None] | None = None,
    solve_s: float = 0.0,
    budget_s: float | None = None,
) -> dict[str, Any]:
    """The certified enclosure of the optimal value, in the problem's own sense.

    Parameters
    ----------
    problem : Problem
    duals : dict or None
        The solver's dual point (``Solution.duals``).
    x : numpy.ndarray or None
        A (certified) point: when :func:`primal_end` proves it feasible, its objective
        (rounded outwards) is the primal end (an upper bound of a minimum, a lower bound of a
        maximum).
    exact : bool
    resolve : callable, optional
        A solve of a perturbed problem on the caller's backend (:func:`dual_bound`).
    solve_point : callable, optional
        A solve on the caller's backend returning its primal point (the centred route of
        :func:`dual_bound`).
    solve_s : float
        The time of the solve that gave ``duals``: the dual search (:func:`dual_bound`) may
        take :func:`search_budget` of it, and expects a re-solve to cost as much.
    budget_s : float, optional
        Seconds for the whole enclosure (:func:`dual_bound`'s ``budget_s``, the repair of the
        conditional bound, the strict polish): once spent, no new step starts, and what is not
        proven by then is reported as not proven (``budget``: ``seconds``, ``spent``). The
        dual search takes the smaller of this and :func:`search_budget`.

    Returns
    -------
    dict
        ``sense``, ``kind`` (``"infimum"`` / ``"supremum"`` for problems with a strict
        constraint, whose optimum need not be attained, else ``"minimum"`` / ``"maximum"``),
        ``lower``, ``upper`` (``None`` at an end without proof), ``gap``, ``rel_gap`` (VSDP's
        ``(upper - lower) / max(1, (|upper| + |lower|) / 2)``),
        ``primal`` (``"certified point"`` or why not), ``dual`` (the :func:`dual_bound` record
        or why not), ``reason`` (one line).

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
    >>> p = Problem([Variable("t", "scalar", (1, 1))],
    ...             [LMI("t - 2 >= 0", 1, sp.csc_matrix([[-2.0, 1.0]]), strict=False)],
    ...             LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
    >>> e = enclosure(p, {"lmis": [np.eye(1)], "linear": []}, np.array([2.0 + 1e-9]))
    >>> e["kind"], 2.0 < e["upper"] < 2.0 + 2e-9, e["rel_gap"] < 1e-8
    ('minimum', True, True)
    """
    import time

    t0 = time.perf_counter()
    deadline = None if budget_s is None else t0 + float(budget_s)
    sense = problem.objective.sense
    strict = any(lmi.strict for lmi in problem.lmis) or any(problem.linear.strict)
    kind = ("infimum" if sense == "min" else "supremum") if strict else ("minimum" if sense == "min" else "maximum")
    out: dict[str, Any] = {"sense": sense, "kind": kind, "lower": None, "upper": None, "gap": None, "rel_gap": None}
    dual: dict[str, Any]
    if not duals or duals.get("lmis") is None:  # the face route needs none (enclosure_face_kyp)
        dual = face_bound(problem, None) if sense != "feasibility" else {}
        if not dual.get("proven"):
            dual = {"proven": False, "reason": "the solver returned no dual point"}
    else:
        # a variable that exposes a face on its own (SDPLIB gpp: <J, Y> = 0): no shifted repair
        # can prove, so the facial route (lmic.certify.enclosure_facial) goes first
        face = obvious_face(problem) if solve_point is not None else None
        dual = {"proven": False, "reason": f"the dual has no strictly feasible point ({face})"}
        if face:
            dual = facial_or(problem, duals, dual, solve_point, exact=exact, resolve=resolve, deadline=deadline)
        if not dual.get("proven"):
            tried = dual.get("reason") if face else None
            face_first = face is None and solve_point is not None  # its face before dual_bound's re-solves
            first = FacialFirst(problem, duals, solve_point, exact, resolve, deadline) if face_first else None
            try:
                search = search_budget(solve_s) if budget_s is None else min(search_budget(solve_s), float(budget_s))
                dual = dual_bound(
                    problem,
                    duals,
                    exact=exact,
                    resolve=resolve,
                    solve_point=solve_point,
                    budget_s=search,
                    solve_s=solve_s,
                    before_solves=first,
                )
            except CertificateError as exc:
                dual = {"proven": False, "reason": str(exc)}
            if first is not None and dual.get("resolves") != "skipped":  # the face it lives on, if not tried yet
                dual = first.after(dual)
            elif face is not None and not dual.get("proven"):
                dual["reason"] = f"{dual.get('reason')}; {tried}"
    out["dual"] = dual
    upper_value = None
    if x is None:
        out["primal"] = "no certified point"
    else:
        pe = exact_primal_end(problem, x, primal_end(problem, x))  # a point on a face: exactly
        upper_value = pe["value"] if pe["proven"] else None
        out["primal"] = "certified point" if pe["proven"] else "no rigorous primal end: " + pe["reason"]
        in_time = deadline is None or time.perf_counter() <= deadline
        if pe["proven"] and strict and solve_point is not None and in_time and _gap_above(problem, dual, upper_value):
            # the strict problem's point keeps the solver's margin: move it towards a point of
            # the closed problem as far as the proof allows (a solve: only worth it when there
            # is a proven lower end and the gap to it is above GAP_TARGET)
            pol = _polish_strict(
                problem, np.asarray(x, dtype=float), solve_point, lambda v: not _gap_above(problem, dual, v)
            )
            better = pol.get("proven") and (
                pol["value"] < upper_value if sense == "min" else pol["value"] > upper_value
            )
            if better:
                upper_value = pol["value"]
                out["primal"] = "restored point"
                out["restored_x"] = pol["x"]
                out["polish"] = {"theta": pol["theta"], "from": pol.get("origin", "closed problem")}
    if not dual.get("proven") and x is not None and duals and duals.get("lmis") is not None:
        out["conditional"] = _conditional(problem, duals, x, deadline)
    if deadline is not None:
        out["budget"] = {"seconds": float(budget_s or 0.0), "spent": time.perf_counter() > deadline}
    bound = None
    if dual.get("proven"):
        bound = dual["lower"] if sense == "min" else -dual["lower"]
    out["problem"] = about_of(dual, pe if x is not None else None)
    if out["problem"] is None:  # never an enclosure of two different problems
        dual = out["dual"] = {
            "proven": False,
            "reason": "the face bound holds for the exact compilation; the point is not proved for it",
        }
        bound, out["problem"] = None, "ir"
    if sense == "min":
        out["lower"], out["upper"] = bound, upper_value
    else:
        out["lower"], out["upper"] = upper_value, bound
    lo, hi = out["lower"], out["upper"]
    if lo is not None and hi is not None:
        out["gap"] = hi - lo
        out["rel_gap"] = relative_gap(lo, hi) if hi >= lo else 0.0
        if hi < lo:
            # both ends proven: cannot happen unless a proof is wrong; never hide it
            out["reason"] = f"inconsistent ends: lower {lo:.10g} > upper {hi:.10g}"
            out["consistent"] = False
            return out
        out["reason"] = f"{kind} in {interval_text(lo, hi)} (relative gap {out['rel_gap']:.2g})"
    elif lo is None and hi is None:
        out["reason"] = f"no certified bound: no certified point, and {dual.get('reason')}"
    else:
        missing = "dual bound" if dual.get("proven") is not True else "primal point"
        why = dual.get("reason") if missing == "dual bound" else "no certified point"
        side, end = ("lower", bound_text(hi, "upper")) if lo is None else ("upper", bound_text(lo, "lower"))
        out["reason"] = (
            f"{kind}: only the {'upper' if side == 'lower' else 'lower'} end is certified ({end}); "
            f"no certified {side} end ({why})"
        )
    out["consistent"] = True
    return out


def _gap_above(problem: Problem, dual: dict[str, Any], primal: float | None) -> bool:
    """A proven dual end whose relative gap to the primal end ``primal`` is above
    :data:`GAP_TARGET`."""
    if not dual.get("proven") or primal is None:
        return False
    lo = dual["lower"] if problem.objective.sense == "min" else -dual["lower"]
    lo, hi = (lo, primal) if problem.objective.sense == "min" else (primal, lo)
    return bool(relative_gap(lo, hi) > GAP_TARGET)


def _polish_strict(
    problem: Problem,
    x: np.ndarray,
    solve_point: Callable[[Problem], Any],
    good_enough: Callable[[float], bool] | None = None,
) -> dict[str, Any]:
    """:func:`~lmic.certify.enclosure_float.polish_primal` from ``x`` towards the solver's
    point of the closed problem (every strict constraint made non-strict), then of the strict
    problem; the second solve is skipped when the first's proven value already satisfies
    ``good_enough`` (its gap to the proven dual end meets :data:`GAP_TARGET`: random
    ``delay_b.thm4_1`` n = 4, the closed problem's end was the better one and met it, and the
    second SDPA solve was a third of the route's time)."""
    import dataclasses

    from lmic.ir.problem import LinearConstraints

    lin = problem.linear
    closed = dataclasses.replace(
        problem,
        lmis=[dataclasses.replace(lmi, strict=False) for lmi in problem.lmis],
        linear=LinearConstraints(lin.A, list(lin.kinds), [False] * len(lin), list(lin.names)),
    )
    best: dict[str, Any] = {"proven": False}
    # the closed problem's optimum (the segment from x proves near it when the boundary is not active
    # everywhere), then the strict problem re-solved by the backend's default reduction (its small fixed
    # margin: a point the certifier's threshold may reject; sampled_euler.thm2 n = 8: 3e-4 above)
    for origin, target in (("closed problem", closed), ("strict problem", problem)):
        try:
            xb = solve_point(target)
        except (ValueError, ArithmeticError):
            xb = None
        if xb is None:
            continue
        pol = polish_primal(problem, x, np.asarray(xb, dtype=float))
        if pol.get("proven") and (not best.get("proven") or _better(problem, pol["value"], best["value"])):
            best = dict(pol, origin=origin)
        if best.get("proven") and good_enough is not None and good_enough(float(best["value"])):
            break
    return best


def _better(problem: Problem, value: float, than: float) -> bool:
    """Whether ``value`` is a better (tighter) primal end than ``than``."""
    return value < than if problem.objective.sense != "max" else value > than


#: the dual search (shifts, perturbed and centring solves) may take this many times the solve:
#: the centred route alone costs about 3 solves, after two repairs and a perturbed solve
#: (``uir.thm4_1`` n = 16, solve 1.1 s, two seeds: with 12 here and 20 in
#: ``routes.ENCLOSURE_BUDGET_FACTOR`` the centred route proves relative gaps 1.0e-7 and 1.7e-8
#: in 19 s in all; with 1 and 3 the search stopped at the perturbed route, gaps 7.2e-5 and
#: 8.5e-5 in 10.5 s; with 8 and 10, one of the two)
BUDGET_FACTOR = 12.0
#: ... and at least this many seconds of processor time (a small problem's whole search,
#: perturbed and centring solves included, takes about 1.5 s; with a thin dual interior and an
#: inexact dual, about 6 s: uir.thm4_1 n = 12 seed 4 on CVXOPT needs centring solves at two
#: losses for a relative gap of 5.6e-7, against 1.2e-4 with 3 s here; 8 s left too little of
#: ``routes.ENCLOSURE_BUDGET_FLOOR_S`` for the escalation on SDPLIB truss7: 2.2e-6, not 9.2e-9)
BUDGET_MIN_S = 5.0


def search_budget(solve_s: float) -> float:
    """The time budget of the dual search after a solve of ``solve_s`` seconds: a failing
    lower end costs at most a small multiple of the solve (each attempt of the search
    costs a repair of the dual or a solve of a problem of the dual's size).

    >>> search_budget(0.01), search_budget(5.0)
    (5.0, 60.0)
    """
    return max(BUDGET_MIN_S, BUDGET_FACTOR * float(solve_s))


#: relative gap above which a caller may re-solve at :data:`TIGHT_TOL` (:func:`best_of`)
GAP_TARGET = 1e-6
#: the solver tolerance of that re-solve (interior-point backends)
TIGHT_TOL = 1e-10


def best_of(first: dict[str, Any], second: dict[str, Any], second_x: Any) -> dict[str, Any]:
    """Both enclosures are proven: keep the better end of each, with its evidence.

    ``second`` is the enclosure of another solve (e.g. at a tighter tolerance) whose point
    ``second_x`` gave its primal end; a primal end taken from it is recorded as a
    ``"restored point"`` (its ``restored_x``), which :func:`lmic.certify.enclosure_audit.audit_enclosure` re-proves.

    >>> a = {"sense": "min", "kind": "minimum", "lower": 1.0, "upper": 3.0, "dual": {"proven": True},
    ...      "primal": "certified point"}
    >>> b = {"sense": "min", "kind": "minimum", "lower": 0.5, "upper": 2.0, "dual": {"proven": True},
    ...      "primal": "certified point"}
    >>> r = best_of(a, b, [2.0])
    >>> r["lower"], r["upper"], r["primal"], r["restored_x"], r["gap"]
    (1.0, 2.0, 'restored point', [2.0], 1.0)
    >>> c = {"sense": "min", "kind": "minimum", "lower": None, "upper": None, "primal": "no certified point",
    ...      "dual": {"proven": False, "reason": "no dual"}, "reason": "no certified bound"}
    >>> best_of(c, dict(c, upper=2.0, primal="certified point"), [2.0])["reason"]
    'minimum: only the upper end is certified (2); no certified lower end (no dual)'
    """
    out = dict(first)
    sense = first.get("sense")
    pkey, dkey = ("upper", "lower") if sense == "min" else ("lower", "upper")
    better = (lambda a, b: a < b) if sense == "min" else (lambda a, b: a > b)
    pv, pv2 = first.get(pkey), second.get(pkey)
    dv, dv2 = first.get(dkey), second.get(dkey)
    take_p = pv2 is not None and (pv is None or better(pv2, pv))
    take_d = dv2 is not None and (dv is None or better(dv, dv2))
    take_p, take_d = next(  # never the ends of two different problems (enclosure_about)
        (c for c in ((take_p, take_d), (False, take_d), (take_p, False)) if one_problem(first, second, *c, pkey, dkey)),
        (False, False),
    )
    out["problem"] = (second if take_d else first).get("problem", "ir")
    if take_p:
        out[pkey] = pv2
        if second.get("primal") == "restored point":
            out["primal"], out["restored_x"] = "restored point", second.get("restored_x")
        else:
            out["primal"], out["restored_x"] = "restored point", list(np.asarray(second_x, dtype=float).tolist())
        out.pop("polish", None)
        if "polish" in second:
            out["polish"] = second["polish"]
    if take_d:
        out[dkey] = dv2
        out["dual"] = second["dual"]
        out.pop("conditional", None)
    elif dv is None and second.get("conditional") and not first.get("conditional"):
        out["conditional"] = second["conditional"]
    lo, hi = out.get("lower"), out.get("upper")
    if lo is not None and hi is not None:
        out["gap"] = hi - lo
        out["rel_gap"] = relative_gap(lo, hi) if hi >= lo else 0.0
        out["consistent"] = bool(hi >= lo)
        out["reason"] = (
            f"{out['kind']} in {interval_text(lo, hi)} (relative gap {out['rel_gap']:.2g})"
            if hi >= lo
            else f"inconsistent ends: lower {lo:.10g} > upper {hi:.10g}"
        )
    elif take_p or take_d:  # one end, now from the other solve: the first's reason is stale
        have, missing = (pkey, dkey) if out.get(pkey) is not None else (dkey, pkey)
        why = (out.get("dual") or {}).get("reason") if missing == dkey else "no certified point"
        end = bound_text(out[have], "upper" if have == "upper" else "lower")
        out["reason"] = f"{out['kind']}: only the {have} end is certified ({end}); no certified {missing} end ({why})"
    return out


def _conditional(
    problem: Problem, duals: dict[str, Any], x: np.ndarray, deadline: float | None = None
) -> dict[str, Any]:
    """The box bound (:mod:`lmic.certify.enclosure_conditional`) in the problem's own sense,
    radius :data:`~lmic.certify.enclosure_conditional.RADIUS_FACTOR` times the point's size."""
    radius = RADIUS_FACTOR * max(1.0, float(np.max(np.abs(np.asarray(x, dtype=float)), initial=0.0)))
    box = best_box_bound(problem, duals, radius, deadline)
    if not box.get("proven"):
        return {"end": None, "value": None, "reason": box["reason"]}
    end = "lower" if problem.objective.sense == "min" else "upper"
    value = box["lower"] if end == "lower" else -box["lower"]
    return {"end": end, "value": value, "radius": radius, "norm": "inf", "reason": box["reason"], "bound": box}


def summary(record: dict[str, Any] | None) -> dict[str, Any] | None:
    """The enclosure without the dual point's matrices (for ``--json`` output).

    >>> summary({"lower": 1.0, "upper": 2.0, "dual": {"proven": True, "dual": {"lmis": []}}})
    {'lower': 1.0, 'upper': 2.0, 'dual': {'proven': True}}
    """
    if record is None:
        return None
    out = {k: v for k, v in record.items() if k != "restored_x"}
    if isinstance(out.get("dual"), dict):
        out["dual"] = {k: v for k, v in out["dual"].items() if k != "dual"}
    if isinstance(out.get("conditional"), dict):
        out["conditional"] = {k: v for k, v in out["conditional"].items() if k != "bound"}
    return out


def describe(record: dict[str, Any] | None) -> list[str]:
    """Human lines for an enclosure record (``lmic solve`` output).

    >>> describe({"kind": "minimum", "lower": 1.0, "upper": 1.5, "gap": 0.5, "rel_gap": 0.4,
    ...           "dual": {"proven": True, "method": "rigorous-float", "shift": 1e-12}})[0]
    'optimal value (minimum) in [1, 1.5]  gap 0.5 (relative 0.4)'
    """
    if not record:
        return []
    lo, hi = record.get("lower"), record.get("upper")
    dual = record.get("dual") or {}
    kind = record.get("kind", "optimum")
    if lo is not None and hi is not None:
        lines = [
            f"optimal value ({kind}) in {interval_text(lo, hi)}  "
            f"gap {record['gap']:.3g} (relative {record['rel_gap']:.3g})"
        ]
    else:
        lines = [f"optimal value ({kind}): " + record.get("reason", "no certified bound")]
    dual_end = "lower" if record.get("sense") != "max" else "upper"
    primal_end = "upper" if dual_end == "lower" else "lower"
    if dual.get("proven") and dual.get("route") == "objective cut":
        lines.append(f"  {dual_end} end: {dual.get('reason')} (exact rational arithmetic)")
    elif dual.get("proven"):
        how = "exact rational arithmetic" if dual.get("method") == "exact" else "rigorous floating-point error bounds"
        if dual.get("route") == "face":
            where = f"the optimal face W = 0 of a Lyapunov-type LMI, rank {dual.get('rank')}" + (
                "; for the theorem compiled exactly from the system's numbers" if dual.get("problem") == "exact" else ""
            )
        elif dual.get("route") == "facial":
            where = f"on the face of {dual.get('steps')} exactly verified exposing step(s), facial reduction"
        elif dual.get("route") == "centred":
            where = f"centred dual point, weight {dual.get('theta'):g} at loss {dual.get('centring_loss'):g}"
        else:
            where = f"interior shift {dual.get('shift'):g}"
        lines.append(f"  {dual_end} end: dual point proved feasible ({how}; {where})")
    else:
        lines.append(f"  {dual_end} end: no certified dual bound ({dual.get('reason', 'not attempted')})")
    lines.append(f"  {primal_end} end: {record.get('primal', 'no certified point')}")
    cut = record.get("cut") or {}
    if cut.get("steps"):
        proved = sum(1 for step in cut.get("log", []) if step.get("settled"))
        lines.append(
            f"  objective cuts: {cut['steps']} feasibility problems with the objective bounded, {proved} decided "
            f"({cut.get('time_s', 0.0):.2f} s)"
        )
    elif cut.get("skipped"):
        lines.append(f"  objective cuts: not tried ({cut['skipped']})")
    cond = record.get("conditional") or {}
    if cond.get("value") is not None:
        lines.append(
            f"  conditional {cond['end']} bound {cond['value']:.10g}: not a bound of the {kind}; it holds only "
            f"for solutions with ||x||_inf <= {cond['radius']:.3g} (VSDP's bound for the unproved dual point)"
        )
    if kind in ("infimum", "supremum"):
        lines.append(f"  strict constraints: the optimum is an {kind}, which no feasible point need attain")
    return lines


def with_primal(record: dict[str, Any], value: float, label: str) -> dict[str, Any]:
    """The enclosure with a primal end from another certified point (e.g. the backed-off one).

    Used only when the record has no primal end: ``value`` must be the objective at a point
    the certifier certified against the same problem.

    >>> e = {"sense": "min", "kind": "minimum", "lower": 1.0, "upper": None, "dual": {"proven": True}}
    >>> with_primal(e, 1.5, "certified backed-off point")["gap"]
    0.5
    """
    out = dict(record)
    key = "upper" if out.get("sense") == "min" else "lower"
    if out.get(key) is not None:
        return out
    out[key] = float(value)
    out["primal"] = label
    lo, hi = out.get("lower"), out.get("upper")
    if lo is not None and hi is not None and hi >= lo:
        out["gap"] = hi - lo
        out["rel_gap"] = relative_gap(lo, hi)
        out["reason"] = f"{out['kind']} in {interval_text(lo, hi)} (relative gap {out['rel_gap']:.2g}; {label})"
    elif lo is not None and hi is not None:
        out["reason"] = f"inconsistent ends: lower {lo:.10g} > upper {hi:.10g}"
        out["consistent"] = False
    else:
        out["reason"] = f"{out['kind']}: only the {key} end is certified ({label})"
    return out


def __getattr__(name: str) -> Any:
    """``audit_enclosure`` moved to :mod:`lmic.certify.enclosure_audit`; the old name still works."""
    if name == "audit_enclosure":
        from lmic.certify.enclosure_audit import audit_enclosure

        return audit_enclosure
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
