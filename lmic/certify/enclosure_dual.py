"""The dual (lower) end of the enclosure: :func:`dual_bound` and :func:`verify_dual_bound`.

:func:`dual_bound` tries, in order, the exact point on the optimal face of a Lyapunov-type
LMI (:mod:`lmic.certify.enclosure_face`, when the IR's coefficients have that structure
exactly), the solver's dual shifted inside the cone (:data:`SHIFTS`: the smallest, then the
largest as a probe, then the ones between), the dual of VSDP's perturbed problem, and a
centred dual point (the dual problem solved for the largest interior margin at a small loss of
objective, combined with the solver's dual); each float candidate is repaired
(:mod:`lmic.certify.enclosure_repair`) and proved (:mod:`lmic.certify.enclosure_float`,
optionally :mod:`lmic.certify.enclosure_exact`). The search stops at its time budget (an
attempt is not started when its expected cost would overrun it).

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
>>> p = Problem([Variable("t", "scalar", (1, 1))],
...             [LMI("t - 2 >= 0", 1, sp.csc_matrix([[-2.0, 1.0]]), strict=False)],
...             LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
>>> dual_bound(p, {"lmis": [np.eye(1)], "linear": []})["proven"]
True
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np

from lmic.certify.enclosure_centre import centred_bound
from lmic.certify.enclosure_exact import _prove_exact
from lmic.certify.enclosure_face import face_bound, verify_face
from lmic.certify.enclosure_float import _prove_float
from lmic.certify.enclosure_repair import (
    PERTURBATIONS,
    SHIFTS,
    _active_of,
    _jacobian,
    _pack,
    _parse,
    _prepare,
    _scale,
    _target,
    perturbed_problem,
)
from lmic.errors import CertificateError
from lmic.ir.problem import Problem

__all__ = [
    "dual_bound",
    "verify_dual_bound",
    "needed_shift",
    "rounding_only",
    "FACE_SLACK",
    "LOOSE",
    "REFINE_GAIN",
    "ROUNDING_TEST_MAX",
]

#: a face bound within this (relative) of the solver's dual objective ends the search
FACE_SLACK = 1e-6
#: a shifted bound further than this (relative) below the solver's dual objective also tries
#: the centred route (:func:`dual_bound`)
LOOSE = 3e-7


#: :func:`rounding_only` runs its test when the dual equality system's rows squared times its
#: columns are at most this (an SVD of about 50 ms; the bounded-real lemma at 30 states, where
#: the rows are independent and the re-solves prove, is above it)
ROUNDING_TEST_MAX = 2e8


def rounding_only(problem: Problem, J: Any) -> str | None:
    """Why no re-solve (facial, perturbed, centred) can prove a dual end of ``problem``, or
    ``None``: the rows of its dual equality system ``J`` are dependent to rounding and
    independent exactly (:func:`lmic.certify.enclosure_cut.near_dependent_rows`), so the exact
    correction of any float dual point is its residual over a singular value near ``1e-17``
    of the largest (variables that act only through a projector computed in floating point:
    docs/writing-a-theorem.md). Not tested above :data:`ROUNDING_TEST_MAX`.

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
    >>> v = [Variable("a", "scalar", (1, 1)), Variable("b", "scalar", (1, 1), offset=1)]
    >>> F = sp.csc_matrix(np.array([[1.0, 1.0, 1.0], [0.0, 0.0, 0.0], [1.0, 0.0, 2.0**-52]]))
    >>> p = Problem(v, [LMI("I + a A + b B > 0", 2, F)], LinearConstraints.empty(2), Objective("min", [0.0, 1.0, 0.0]))
    >>> rounding_only(p, _jacobian(p)[0])[:31]
    'the dual equality system is sin'
    """
    from lmic.certify.enclosure_cut import near_dependent_rows

    rows, cols = J.shape
    if float(rows) ** 2 * float(cols) > ROUNDING_TEST_MAX:
        return None
    return near_dependent_rows(problem)


def dual_bound(
    problem: Problem,
    duals: dict[str, Any],
    *,
    exact: bool = False,
    resolve: Callable[[Problem], dict[str, Any] | None] | None = None,
    budget_s: float = 20.0,
    solve_s: float = 0.0,
    solve_point: Callable[[Problem], np.ndarray | None] | None = None,
    before_solves: Callable[[], dict[str, Any]] | None = None,
) -> dict[str, Any]:
    """Prove a lower bound of the minimisation form's optimal value from a dual point.

    Parameters
    ----------
    problem : Problem
        An optimisation problem (``min`` or ``max``).
    duals : dict
        ``{"lmis": [Z_i], "linear": y}`` (:attr:`lmic.solution.Solution.duals`).
    exact : bool
        Prove in rational arithmetic (module docstring, *Exact mode*) after the float proof.
    resolve : callable, optional
        ``resolve(problem) -> duals`` (a solve on the caller's backend). When the solver's own
        dual cannot be proved (a degenerate dual: no strictly feasible point near it), the
        dual of :func:`perturbed_problem` is tried (``route`` ``"perturbed"``).
    budget_s : float
        No new attempt (shift, perturbation or centring solve) starts after this many seconds
        of this process's CPU time
        (:func:`lmic.certify.enclosure.search_budget` gives the callers' default); an attempt
        is not started when the time spent plus its expected cost (the last attempt's, plus
        ``solve_s`` for one that solves) would exceed it.
    solve_s : float
        The expected time of a solve on the caller's backend (the original solve's).
    solve_point : callable, optional
        ``solve_point(problem) -> x or None`` (a solve on the caller's backend, its primal
        point). When neither the shifts nor the perturbation prove, the dual problem is solved
        for a centred point (:mod:`lmic.certify.enclosure_centre`, ``route`` ``"centred"``).
    before_solves : callable, optional
        ``before_solves() -> record``: a route tried when the solver's dual fails, before any
        re-solve (the caller's facial reduction, :mod:`lmic.certify.enclosure_facial`: one solve
        when the dual has no strictly feasible point, where no re-solve here can prove). Its
        record is returned when it proves (the caller keeps its reason otherwise).

    Returns
    -------
    dict
        ``proven`` (bool), ``route`` (``"face"``, ``"solver dual"``, ``"perturbed"`` or
        ``"centred"``), ``lower`` (a
        bound ``<= inf q_0 + q . x``, the minimisation form:
        for ``max`` problems ``-lower`` bounds the maximum from above), ``method``
        (``"rigorous-float"`` or ``"exact"``), ``shift`` (the ``eps_rel`` used), ``reason``,
        ``dual`` (the dual point the bound was proved from, JSON-ready), ``time_s``; the float
        proof's ``residual_bound``, ``correction_bound``, ``min_eig_lower``.

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
    >>> p = Problem([Variable("t", "scalar", (1, 1))],
    ...             [LMI("t - 2 >= 0", 1, sp.csc_matrix([[-2.0, 1.0]]), strict=False)],
    ...             LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
    >>> r = dual_bound(p, {"lmis": [np.eye(1)], "linear": []})
    >>> r["proven"], 1.9999999 < r["lower"] <= 2.0
    (True, True)
    """
    t0 = time.perf_counter()
    c0 = time.process_time()  # the budget counts this process's CPU time: stable on a busy machine
    if problem.objective.sense == "feasibility":
        raise CertificateError("a feasibility problem has no optimal value to bound")
    mats0, y0 = _parse(problem, duals)
    _, q = _target(problem)
    J, ranges = _jacobian(problem)
    out: dict[str, Any] = {"proven": False, "reason": "no shift gave a provable dual point"}
    top = _scale(problem, mats0, y0)
    last = [0.0]  # the duration of the last attempt: the next one is not started if it would overrun

    def spent(solves: bool = False) -> bool:
        return time.process_time() - c0 + last[0] + (solve_s if solves else 0.0) > budget_s

    last_proof: list[Any] = []  # (mats, y, record): the repair's last proof, kept with its point

    def prove_here(mats: list, y: np.ndarray, active: np.ndarray) -> dict[str, Any]:
        res = _prove_float(problem, J, ranges, q, mats, y, active)
        last_proof[:] = [mats, y, res]
        return res

    def proof_of(mats: list, y: np.ndarray, active: np.ndarray) -> dict[str, Any]:
        """The proof of the point the repair returned: its own when it stopped at a proof of
        these very arrays, else a new one."""
        if last_proof and last_proof[0] is mats and last_proof[1] is y:
            return last_proof[2]
        return _prove_float(problem, J, ranges, q, mats, y, active)

    def attempt(route: str, eps_rel: float, mz: Any, yz: Any) -> dict[str, Any]:
        ta = time.process_time()
        try:
            mats, y, active = _prepare(
                problem, J, ranges, q, mz, yz, eps_rel, top, deadline=t0 + budget_s, prove=prove_here
            )
            res = proof_of(mats, y, active)
            last_proof.clear()
            if not res["proven"] and ("singular" in res["reason"] or "absorb" in res["reason"]):
                mats, y, active = _prepare(
                    problem, J, ranges, q, mz, yz, eps_rel, top, drop=False, deadline=t0 + budget_s
                )
                res = _prove_float(problem, J, ranges, q, mats, y, active)
        except (np.linalg.LinAlgError, ValueError, FloatingPointError) as exc:
            res = {"proven": False, "reason": f"numerical failure in the repair: {exc}"}
        res.update(method="rigorous-float", shift=eps_rel, route=route)
        res["dual"] = {"lmis": [Z.tolist() for Z in mats], "linear": y.tolist()} if res["proven"] else None
        last[0] = time.process_time() - ta
        return res

    # a Lyapunov-type LMI whose IR coefficients have the exact structure: the exact point on
    # the optimal face (lmic.certify.enclosure_face), cheap and tight; its interior is too thin
    # for the repairs below from about 15 states
    try:
        face = face_bound(problem, duals)
    except (np.linalg.LinAlgError, ValueError, IndexError, ArithmeticError) as exc:  # a heuristic's failure
        face = {"proven": False, "reason": f"the exact face route failed: {type(exc).__name__}: {exc}"}
    if face["proven"]:
        # as good as the solver's dual objective: done; else the routes below may do better
        L0 = float(q[0] - (J[0] @ _pack(problem, mats0, y0))[0])
        if face["lower"] >= L0 - FACE_SLACK * max(1.0, abs(L0)):
            face["time_s"] = time.perf_counter() - t0
            return face
    # the solver's dual: the smallest shift, then the largest as a probe (PROBE): when even it
    # fails, the shifts between are not tried (each costs a repair; on a dual whose interior
    # is thinner than the shifts, as the bounded-real lemma's from about 15 states, they all
    # fail), else the smallest proving shift of the ladder, refined
    n_tried = 1
    out = attempt("solver dual", SHIFTS[0], mats0, y0)
    ladder = list(SHIFTS)
    jump = needed_shift(out, top)
    if jump is not None and not spent():
        # the first attempt failed by a PSD deficit that the ladder's k-th shift covers: that
        # shift first (on a dual at the boundary of the cone, e.g. Clarabel's, this replaces
        # the probe and the scan up from the smallest: 3 to 6 repairs instead of 8 to 10)
        n_tried += 1
        res = attempt("solver dual", SHIFTS[jump], mats0, y0)
        if res["proven"]:
            # down the ladder while the shifts prove (the repair at a larger floor often leaves
            # a smaller deficit than the first one: CVXOPT's dual on uncertain_dt.thm1 n = 8
            # is predicted 1e-8 and proves from 1e-10), then refined below the smallest
            L0 = float(q[0] - (J[0] @ _pack(problem, mats0, y0))[0])
            k, best = jump, res
            # what the shift costs the bound: eps times the dual objective's weight on the
            # identity, SHIFT_COST_SAFETY times over (the repair moves the point too: 5.6e-8
            # lost from 1e-11 to 1e-10 on uncertain_dt.thm1 n = 8, against 4e-9 for the weight)
            ge = np.array([kind == "ge" for kind in problem.linear.kinds], dtype=float)
            eyes = [np.eye(lmi.dim) for lmi in problem.lmis]
            per_shift = SHIFT_COST_SAFETY * top * abs(float((J[0] @ _pack(problem, eyes, ge))[0]))
            worth = REFINE_GAIN * max(1.0, abs(L0))
            while k > 1 and not spent() and L0 - best["lower"] > worth and SHIFTS[k] * per_shift > worth:
                n_tried += 1
                below = attempt("solver dual", SHIFTS[k - 1], mats0, y0)
                if not below["proven"]:
                    break
                k, best = k - 1, below
            if L0 - best["lower"] <= worth or SHIFTS[k] * per_shift <= worth or spent():
                out = best  # a smaller shift could gain at most this: not worth two repairs
            else:
                out = _refine(problem, J, ranges, q, mats0, y0, top, SHIFTS[k - 1], SHIFTS[k], best)
            ladder = []
        else:
            ladder = list(SHIFTS[jump:])  # its first entry failed: the low end of the scan
            out = res if len(ladder) < 2 else out
    if not out["proven"] and len(ladder) > 1 and not spent():
        n_tried += 1
        probe = attempt("solver dual", ladder[-1], mats0, y0)
        if probe["proven"]:
            low, high, best = ladder[0], ladder[-1], probe
            for eps_rel in ladder[1:-1]:
                if spent():
                    break
                n_tried += 1
                res = attempt("solver dual", eps_rel, mats0, y0)
                if res["proven"]:
                    high, best = eps_rel, res
                    break
                low = eps_rel
            out = _refine(problem, J, ranges, q, mats0, y0, top, low, high, best) if not spent() else best
        else:
            out = probe
    elif not out["proven"] and len(ladder) > 1:
        out["reason"] = f"{out.get('reason')}; time budget {budget_s:g} s spent after {n_tried} attempts"
    if not out["proven"] and (before_solves is not None or resolve is not None or solve_point is not None):
        why = rounding_only(problem, J)
        if why is not None:  # no re-solve can prove (random uio_dt.thm4_1, 7 states: 8 futile solves)
            out["reason"] = f"{out.get('reason')}; no re-solve tried: {why}"
            out["resolves"] = "skipped"
            out["time_s"] = time.perf_counter() - t0
            return out
    if not out["proven"] and before_solves is not None and not spent(solves=True):
        first = before_solves()
        if first.get("proven"):
            first["time_s"] = time.perf_counter() - t0
            return first
    if not out["proven"] and resolve is not None:
        for eps_rel in PERTURBATIONS:
            if spent(solves=True):
                out["reason"] = f"{out.get('reason')}; time budget {budget_s:g} s spent after {n_tried} attempts"
                break
            ta = time.process_time()
            try:
                d2 = resolve(perturbed_problem(problem, eps_rel * top))
                mz, yz = _parse(problem, d2) if d2 else (None, None)
            except CertificateError:
                mz = None
            if mz is None:
                continue
            # Z = Z' + eps I: the perturbed dual shifted back (the shift of _prepare)
            n_tried += 1
            res = attempt("perturbed", eps_rel, mz, yz)
            last[0] = time.process_time() - ta  # a solve and a repair
            out = res
            if res["proven"]:
                break
    # a proven bound that lost more than LOOSE of the solver's dual objective to its shift (a
    # thin dual interior: the shift that proves is far above the solver's accuracy) is also
    # tried on the centred route, and the better bound kept
    L0 = float(q[0] - (J[0] @ _pack(problem, mats0, y0))[0])
    loose = bool(out.get("proven")) and L0 - out["lower"] > LOOSE * max(1.0, abs(L0))
    if (not out.get("proven") or loose) and solve_point is not None and not spent(solves=True):
        mats_c, y_c, res = _centred(problem, J, ranges, q, mats0, y0, top, solve_point, lambda: spent(solves=True))
        res.update(method="rigorous-float", shift=0.0, route="centred")
        if res["proven"] and (not out.get("proven") or res["lower"] > out["lower"]):
            res["dual"] = {"lmis": [Z.tolist() for Z in mats_c], "linear": y_c.tolist()}
            out = res
        elif not out.get("proven"):
            out["reason"] = f"{out.get('reason')}; {res['reason']}"
    elif not out.get("proven") and solve_point is not None:
        out["reason"] = f"{out.get('reason')}; time budget {budget_s:g} s spent before the centred route"
    if face["proven"] and (not out.get("proven") or out["lower"] <= face["lower"]):
        out = face
    if exact and out.get("proven") and out.get("method") != "exact":
        mats, y = _parse(problem, out["dual"])
        ex = _prove_exact(problem, J, ranges, q, mats, y)
        out["exact"] = ex
        if ex["proven"]:
            out.update(method="exact", lower=ex["lower"], lower_exact=ex["lower_exact"])
    out["time_s"] = time.perf_counter() - t0
    return out


#: a shift that proves a bound within this (relative) of the solver's dual objective is kept
#: without refining between it and the failing shift below it (each try is a repair; the gain
#: is below the enclosure's relative gap target, 1e-6, by a factor 100)
REFINE_GAIN = 1e-8

#: the bound a smaller shift could gain is taken as this many times the shift's weight on the
#: dual objective (:func:`dual_bound`'s walk down the ladder)
SHIFT_COST_SAFETY = 30.0

#: the predicted shift is this many times the PSD deficit of the first attempt (relative to
#: the dual's scale): the repair at a larger floor lands near, not at, the floor
DEFICIT_SAFETY = 4.0


def needed_shift(res: dict[str, Any], top: float) -> int | None:
    """The index in :data:`SHIFTS` of the smallest shift that covers the PSD deficit of a failed
    attempt ``res`` (:data:`DEFICIT_SAFETY` times ``lambda_min`` below zero plus the correction,
    relative to the dual's scale ``top``), when that is above the smallest shift and within the
    ladder; ``None`` otherwise (a proven attempt, another failure, a deficit beyond the ladder).

    >>> needed_shift({"proven": False, "psd_deficit": 1.2e-11}, 6.0)  # 8e-12 relative
    5
    >>> SHIFTS[5], needed_shift({"proven": True}, 6.0), needed_shift({"proven": False, "psd_deficit": 1.0}, 6.0)
    (1e-11, None, None)
    """
    deficit = res.get("psd_deficit")
    if res.get("proven") or deficit is None or not (deficit > 0) or not (top > 0):
        return None
    want = DEFICIT_SAFETY * float(deficit) / float(top)
    k = next((i for i, s in enumerate(SHIFTS) if s >= want), None)
    return k if k is not None and k > 0 else None


def _refine(problem: Problem, J, ranges, q, mats0, y0, top, low, high, best):
    """Two shifts between a failing ``low`` and the proving ``high`` (geometric thirds,
    smallest first): a smaller shift costs less of the bound."""
    for f in (2.0 / 3.0, 1.0 / 3.0):
        eps_rel = low**f * high ** (1.0 - f)
        try:
            mats, y, active = _prepare(problem, J, ranges, q, mats0, y0, eps_rel, top)
            res = _prove_float(problem, J, ranges, q, mats, y, active)
        except (np.linalg.LinAlgError, ValueError, FloatingPointError):
            continue
        if res["proven"] and res["lower"] > best["lower"]:
            res.update(method="rigorous-float", shift=eps_rel, route="solver dual")
            res["dual"] = {"lmis": [Z.tolist() for Z in mats], "linear": y.tolist()}
            return res
    return best


def _centred(problem: Problem, J, ranges, q, mats0, y0, top, solve_point, deadline):
    """The centred route: the solver's dual projected onto the cone, the drop rule's active
    entries, then :func:`lmic.certify.enclosure_centre.centred_bound`."""
    ge = np.array([k == "ge" for k in problem.linear.kinds], dtype=bool)
    proj = []
    for Z in mats0:
        if not Z.size:
            proj.append(Z)
            continue
        w, V = np.linalg.eigh(Z)
        proj.append((V * np.maximum(w, 0.0)) @ V.T)
    y = np.where(ge, np.maximum(y0, 0.0), y0)
    active = _active_of(problem, proj, y, ranges, top)
    # the drop rule's face first (inactive blocks exactly zero need no margin); where that face
    # has no interior of its own (uir.thm4_1 at n = 4: margin 5e-13 at a loss of 1e-2, while
    # every block kept gives 1e-8), every block and ge row is kept
    tries = [active] + ([np.ones_like(active)] if not np.all(active) else [])
    res: dict[str, Any] = {"proven": False, "reason": "no centring attempted"}
    mats, yk = proj, y
    for k, act in enumerate(tries):
        if k and deadline():
            break
        try:
            res_k, mats_k, y_k = centred_bound(problem, J, ranges, q, proj, y, act, top, solve_point, deadline)
        except (np.linalg.LinAlgError, ValueError, FloatingPointError) as exc:
            res_k, mats_k, y_k = {"proven": False, "reason": f"numerical failure in the centred route: {exc}"}, proj, y
        if res_k["proven"] or not k:
            res, mats, yk = res_k, mats_k, y_k
        if res_k["proven"]:
            break
    return mats, yk, res


def verify_dual_bound(problem: Problem, record: dict[str, Any], *, exact: bool = False) -> dict[str, Any]:
    """Re-prove a recorded dual bound from its recorded dual point alone (for ``lmic audit``).

    The recorded point is used as it stands (no shift, no repair): its rigorous bound must be
    at least the recorded ``lower`` (minimisation form).

    Returns
    -------
    dict
        ``ok`` (bool), ``lower`` (re-proved), ``reason``.

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
    >>> p = Problem([Variable("t", "scalar", (1, 1))],
    ...             [LMI("t - 2 >= 0", 1, sp.csc_matrix([[-2.0, 1.0]]), strict=False)],
    ...             LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
    >>> r = dual_bound(p, {"lmis": [np.eye(1)], "linear": []})
    >>> verify_dual_bound(p, r)["ok"], verify_dual_bound(p, dict(r, lower=2.5))["ok"]
    (True, False)
    """
    if not record.get("dual") or record.get("lower") is None:
        return {"ok": False, "lower": None, "reason": "no dual point recorded"}
    if isinstance(record["dual"], dict) and record["dual"].get("form") == "face":
        return verify_face(problem, record)
    try:
        mats, y = _parse(problem, record["dual"])
    except CertificateError as exc:
        return {"ok": False, "lower": None, "reason": str(exc)}
    _, q = _target(problem)
    J, ranges = _jacobian(problem)
    if exact or record.get("method") == "exact":
        res = _prove_exact(problem, J, ranges, q, mats, y)
    else:
        res = _prove_float(problem, J, ranges, q, mats, y)
    if not res["proven"]:
        return {
            "ok": False,
            "lower": None,
            "reason": "the recorded dual point does not prove a bound: " + res["reason"],
        }
    rec = float(record["lower"])
    if rec > res["lower"]:
        return {
            "ok": False,
            "lower": res["lower"],
            "reason": f"recorded lower bound {rec:.17g} exceeds the bound the dual point proves ({res['lower']:.17g})",
        }
    return {
        "ok": True,
        "lower": res["lower"],
        "lower_exact": res.get("lower_exact"),
        "reason": "lower bound re-proved from the recorded dual point",
    }
