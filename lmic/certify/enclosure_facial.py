"""Facial reduction for the dual (lower) end of the enclosure: duals without a strictly feasible point.

Why
---
When the dual has no strictly feasible point (SDPLIB qap5, hinf1, hinf3-6), every dual-feasible
multiplier ``Z_i`` is singular, and no dual point can be *shifted* inside the cone and repaired
(:mod:`lmic.certify.enclosure_repair`): the bound of :mod:`lmic.certify.enclosure_dual` fails
whatever the solver's accuracy. By the theorem of the alternative (Borwein and Wolkowicz,
"Facial reduction for a cone-convex programming problem", J. Austral. Math. Soc. 30 (1981);
Drusvyatskiy and Wolkowicz, "The many faces of degeneracy in conic optimization", 2017) there is
then an *exposing direction* ``d`` of the primal:

    ``W_i = sum_k d_k F_i^(k) >= 0`` (every LMI), ``a_r . d >= 0`` (``ge`` rows), ``a_r . d = 0``
    (``eq`` rows), ``q . d = 0`` (``q``: the minimisation form's objective), not all zero.

For every dual-feasible ``u = (Z_i, y)``, ``sum_k d_k g_k(u) = q . d = 0`` reads ``sum_i <W_i,
Z_i> + sum_r (a_r . d) y_r = 0``, a sum of non-negative terms: ``Z_i W_i = 0`` and ``y_r = 0``
where ``a_r . d > 0``. So every dual-feasible ``Z_i`` is ``V_i U_i V_i^T`` with ``V_i`` a basis
of the null space of ``W_i``: the dual lives on that face, and nothing is lost by restricting it.

What is proved
--------------
1. ``d`` is found by a solve on the caller's backend (:func:`exposing_problem`: the conditions
   above with ``sum_i tr W_i + sum_ge a_r . d = 1``; an interior-point solver returns a point of
   largest rank, hence the smallest face in one step); the null space of each ``W_i`` is read
   off numerically and rationalised (a basis that is the identity on pivot rows, entries
   rounded to small-denominator fractions); the exact solution space of ``W_i(d) B_i = 0`` and
   the linear conditions (python-flint, integers) gives a rational ``d*`` nearest the solver's.
2. The exposing certificate is **verified exactly** (:func:`verify_step`): ``q . d* = 0``, the
   row conditions, ``W_i(d*) V_i = 0`` for the recorded integer basis ``V_i`` of rank ``dim -
   rank W_i`` and ``W_i(d*)[P', P']`` positive definite (``P'``: the coordinates outside a set
   ``P`` of pivot rows of ``V_i``, where ``V_i[P]`` is invertible; with ``W_i V_i = 0``, the
   congruence by ``[V_i, E_P']`` shows ``W_i >= 0`` with null space exactly ``span V_i``).
3. The **reduced problem** has the same variables and objective, LMIs ``V_i^T F_i(x) V_i >= 0``
   (a block with ``V_i`` empty dropped) and the rows with ``a_r . d* = 0``. Its coefficients are
   computed exactly and must be exactly representable in floating point (else the route says so:
   the reduced problem would not be the one proved). Every feasible ``x`` of the original is
   feasible for it (``V^T F V >= 0`` whenever ``F >= 0``): it is a *relaxation*, so a lower bound
   of its optimum is a lower bound of the original's **whatever the exposing certificate**; the
   certificate only shows that the restriction loses nothing (the reduced dual is the original
   dual, and has a strictly feasible point once the face is the smallest).
4. The reduced dual bound is proved by :func:`lmic.certify.enclosure_dual.dual_bound` (float or
   exact) from the solver's multipliers mapped to the face, ``U_i = V_i^+ Z_i V_i^{+T}``. When it
   still fails, a further step is taken on the reduced problem (at most :data:`MAX_STEPS`).

The record (``dual`` of the result, ``form`` ``"facial"``) holds each step's ``d*`` and ``V_i``
(integers, as decimal strings) and the rows dropped, plus the reduced dual point;
:func:`verify_facial` replays every step exactly, rebuilds the reduced problem and re-proves its
bound (``lmic audit``).

Where it cannot help: a face that is not rational (a null space with irrational entries, e.g. an
eigenvector of generic floating-point data) has no rational exposing certificate; the step then
fails with the reason (no exact ``d*`` found, or the reduced coefficients not representable).

Examples
--------
One exact step and its reduced problem on ``inf x1 s.t. [[x1, 1], [1, x2]] >= 0``: the module
example of :mod:`lmic.certify.enclosure_facial_exact`; the search for ``d`` on the same problem:
:func:`exposing_problem`.
"""

import functools
import time
from collections.abc import Callable
from typing import Any

import numpy as np
import scipy.sparse as sp

from lmic.certify.enclosure_dual import dual_bound, verify_dual_bound
from lmic.certify.enclosure_facial_exact import (
    exact_step,
    lineality,
    reduce_problem,
    reduce_v,
    scale_exponents,
    scale_variables,
    verify_step,
)
from lmic.certify.enclosure_repair import _target
from lmic.errors import CertificateError
from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
from lmic.ir.svec import tril_rows_cols, tril_unvec

__all__ = [
    "MAX_STEPS",
    "INNER_MIN_S",
    "exposing_problem",
    "exact_step",
    "verify_step",
    "reduce_problem",
    "facial_bound",
    "verify_facial",
    "facial_or",
    "verify_any",
]

#: largest number of facial reduction steps
MAX_STEPS = 3
#: CPU seconds the reduced dual's proof may take even when the enclosure's budget is spent (the
#: exposing step found a face: the proof on it is the only lower end there is; the dual search
#: before it spent the budget on a dual that has no interior)
INNER_MIN_S = 3.0


def exposing_problem(problem: Problem) -> Problem:
    """The search for an exposing direction ``d`` (module docstring, step 1) as an IR problem.

    >>> import numpy as np, scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> C = sp.csc_matrix(np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]))
    >>> p = Problem([Variable("x", "full", (2, 1))], [LMI("M", 2, C, strict=False)],
    ...             LinearConstraints.empty(2), Objective("min", [0.0, 1.0, 0.0]))
    >>> e = exposing_problem(p)
    >>> e.n, e.linear.kinds, e.objective.sense
    (2, ['eq', 'eq'], 'feasibility')
    """
    n = problem.n
    _, q = _target(problem)
    lmis, trace = [], np.zeros(1 + n)
    for lmi in problem.lmis:
        C = sp.csc_matrix(lmi.coeffs, copy=True)
        C = sp.hstack([sp.csc_matrix((C.shape[0], 1)), C[:, 1:]]).tocsc()
        lmis.append(LMI(f"W[{lmi.name}]", lmi.dim, C, strict=False, relation=">="))
        i, j = tril_rows_cols(lmi.dim)
        trace += np.asarray(C[np.flatnonzero(i == j)].sum(axis=0)).ravel()
    rows, kinds, names = [], [], []
    A = sp.csr_matrix(problem.linear.A) if len(problem.linear) else None
    for r, kind in enumerate(problem.linear.kinds):
        assert A is not None
        a = A[r].toarray().ravel()
        a[0] = 0.0
        rows.append(a)
        kinds.append(kind)
        names.append(f"a[{problem.linear.names[r]}] . d")
        if kind == "ge":
            trace += a
    qd = np.array(q, dtype=float)
    qd[0] = 0.0
    trace[0] = -1.0
    rows += [qd, trace]
    kinds += ["eq", "eq"]
    names += ["q . d = 0", "normalisation"]
    lin = LinearConstraints(sp.csr_matrix(np.array(rows)), kinds, [False] * len(kinds), names)
    return Problem(
        [Variable("d", "full", (n, 1))],
        lmis,
        lin,
        Objective("feasibility", np.zeros(1 + n)),
        meta={"exposing_of": problem.meta.get("theorem")},
    )


def _map_duals(problem: Problem, step: dict[str, Any], duals: dict[str, Any]) -> dict[str, Any]:
    """The solver's multipliers on the face: ``U_i = V_i^+ Z_i V_i^{+T}``, the kept rows' ``y``."""
    from lmic.certify.multipliers import parse_multipliers

    mats, y = parse_multipliers(problem, duals, "dual point", missing_is_zero=True)
    out = []
    for Z, Vraw in zip(mats, step["V"], strict=True):
        V = np.array([[float(int(v)) for v in row] for row in Vraw], dtype=float)
        if V.ndim != 2 or V.shape[1] == 0:
            continue
        Vp = np.linalg.pinv(V)
        U = Vp @ Z @ Vp.T
        out.append(0.5 * (U + U.T))
    drop = set(int(r) for r in step.get("drop", []))
    yk = [float(v) for r, v in enumerate(np.asarray(y, dtype=float)) if r not in drop]
    yk += [0.0] * len(step.get("fix", []))
    return {"lmis": out, "linear": yk}


def facial_bound(
    problem: Problem,
    duals: dict[str, Any],
    solve_point: Callable[[Problem], np.ndarray | None],
    *,
    exact: bool = False,
    resolve: Callable[[Problem], dict[str, Any] | None] | None = None,
    deadline: float | None = None,
) -> dict[str, Any]:
    """The dual end by facial reduction (module docstring).

    ``deadline``: a :func:`time.perf_counter` value after which no step starts. Returns the
    record of :func:`lmic.certify.enclosure_dual.dual_bound` for the reduced problem, with
    ``route`` ``"facial"``, ``steps`` and ``dual`` ``{"form": "facial", "steps", "reduced",
    "inner_route", "inner_method"}``; or ``proven`` false with the reason.
    """
    t0 = time.perf_counter()
    steps: list[dict[str, Any]] = []
    cur, cur_duals = problem, duals
    why = "no step taken"
    for s in range(MAX_STEPS):
        if deadline is not None and time.perf_counter() > deadline:
            why = f"{why}; time budget spent after {s} facial steps"
            break
        try:
            d = solve_point(exposing_problem(cur))
        except (ValueError, ArithmeticError, CertificateError):
            d = None
        if d is None:
            why = f"step {s + 1}: no exposing direction (the {'reduced ' if s else ''}dual may have an interior)"
            break
        st = exact_step(cur, np.asarray(d, dtype=float))
        if not st["ok"]:
            why = f"step {s + 1}: {st['reason']}"
            break
        try:
            st["lineality"], st["fix"] = lineality(reduce_v(cur, st))
            red = reduce_problem(cur, st)
        except CertificateError as exc:
            why = f"step {s + 1}: {exc}"
            break
        rec = {k: st[k] for k in ("d", "V", "drop", "lineality", "fix")}
        steps.append(rec)
        cur_duals = _map_duals(cur, st, cur_duals)
        cur = red
        left = INNER_MIN_S if deadline is None else max(INNER_MIN_S, deadline - time.perf_counter())
        try:
            # the variables scaled by powers of two (exact): a well-conditioned equality map
            exps = scale_exponents(cur)
            scaled = scale_variables(cur, exps)
            inner = dual_bound(scaled, cur_duals, exact=exact, resolve=resolve, budget_s=left)
            if not inner.get("proven") and resolve is not None and time.perf_counter() < (deadline or np.inf):
                d2 = resolve(scaled)
                if d2 and d2.get("lmis") is not None:
                    left = INNER_MIN_S if deadline is None else max(INNER_MIN_S, deadline - time.perf_counter())
                    inner2 = dual_bound(scaled, d2, exact=exact, budget_s=left)
                    inner = inner2 if inner2.get("proven") else inner
        except CertificateError as exc:
            inner = {"proven": False, "reason": str(exc)}
        if inner.get("proven"):
            out = dict(inner)
            out["dual"] = {
                "form": "facial",
                "steps": steps,
                "reduced": inner.get("dual"),
                "inner_route": inner.get("route"),
                "inner_method": inner.get("method"),
                "scale": exps,
            }
            out.update(
                route="facial",
                steps=len(steps),
                reason=f"dual point on the face of {len(steps)} exactly verified exposing step(s): {inner['reason']}",
                time_s=time.perf_counter() - t0,
            )
            return out
        why = f"after {s + 1} facial step(s) the reduced dual is not proved: {inner.get('reason')}"
    return {"proven": False, "route": "facial", "reason": why, "time_s": time.perf_counter() - t0}


def verify_facial(problem: Problem, record: dict[str, Any]) -> dict[str, Any]:
    """Replay a recorded facial bound (``lmic audit``): every step verified exactly
    (:func:`verify_step`), the reduced problem rebuilt (:func:`reduce_problem`), its bound
    re-proved (:func:`lmic.certify.enclosure_dual.verify_dual_bound`). Returns ``ok``,
    ``lower`` and ``reason``."""
    d = record.get("dual")
    if not isinstance(d, dict) or d.get("form") != "facial" or not isinstance(d.get("steps"), list):
        return {"ok": False, "lower": None, "reason": "no facial dual point recorded"}
    cur = problem
    for s, st in enumerate(d["steps"]):
        if not isinstance(st, dict):
            return {"ok": False, "lower": None, "reason": f"facial step {s + 1} is unusable"}
        chk = verify_step(cur, st)
        if not chk["ok"]:
            return {"ok": False, "lower": None, "reason": f"facial step {s + 1}: {chk['reason']}"}
        try:
            cur = reduce_problem(cur, st)
        except CertificateError as exc:
            return {"ok": False, "lower": None, "reason": f"facial step {s + 1}: {exc}"}
    if d.get("scale") is not None:
        try:
            cur = scale_variables(cur, [int(e) for e in d["scale"]])
        except (CertificateError, TypeError, ValueError) as exc:
            return {"ok": False, "lower": None, "reason": f"the recorded variable scaling: {exc}"}
    inner = {
        "dual": d.get("reduced"),
        "lower": record.get("lower"),
        "route": d.get("inner_route"),
        "method": d.get("inner_method"),
    }
    v = verify_dual_bound(cur, inner)
    return dict(v, reason=f"facial reduction ({len(d['steps'])} step(s)) verified; {v['reason']}")


def obvious_face(problem: Problem) -> str | None:
    """A variable that exposes a face of the dual on its own, or ``None``: ``q_k = 0`` (the
    minimisation form's objective), every LMI's coefficient ``F_i^(k)`` positive semidefinite
    (or every one negative semidefinite), not all zero, ``a_rk`` of the same sign on ``ge`` rows
    and ``0`` on ``eq`` rows. Then ``d = +-e_k`` is an exposing direction (module docstring):
    the dual has no strictly feasible point, and the shifted repairs of
    :func:`~lmic.certify.enclosure_dual.dual_bound` cannot prove (SDPLIB gpp: ``<J, Y> = 0``).

    A routing test in floating point (eigenvalues of the coefficient on its support, after the
    2 x 2 minor test: an off-diagonal entry needs both diagonal entries of its sign); the facial
    route verifies its own exposing certificate exactly.

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> # min x2 s.t. [[x1, x1 + 1], [x1 + 1, x1 + x2]] >= 0: x1's coefficient J >= 0, q_1 = 0
    >>> C = sp.csc_matrix([[0.0, 1.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 1.0]])
    >>> p = Problem([Variable("x", "full", (2, 1))], [LMI("M", 2, C, strict=False)],
    ...             LinearConstraints.empty(2), Objective("min", [0.0, 0.0, 1.0]))
    >>> obvious_face(p)
    'variable 1: a semidefinite coefficient of cost 0'
    """
    _, q = _target(problem)
    lin = problem.linear
    A = sp.csc_matrix(lin.A) if len(lin) else None
    ge = np.array([k == "ge" for k in lin.kinds], dtype=bool)
    cols = [sp.csc_matrix(lmi.coeffs) for lmi in problem.lmis]
    for k in _semidefinite_candidates(problem, cols, np.flatnonzero(q[1:] == 0.0)):
        signs: set[int] = set()
        if A is not None:
            a = A[:, 1 + k].toarray().ravel()
            if np.any(a[~ge] != 0.0):
                continue
            signs |= {int(v) for v in np.sign(a[ge & (a != 0.0)])}
            if len(signs) > 1:
                continue
        nonzero = False
        for lmi, C in zip(problem.lmis, cols, strict=True):
            col = C[:, 1 + k]
            if not col.nnz:
                continue
            nonzero = True
            i, j = tril_rows_cols(lmi.dim)
            rows, vals = col.indices, col.data
            diag = {int(i[r]): float(v) for r, v in zip(rows, vals, strict=True) if i[r] == j[r]}
            dsign = {int(np.sign(v)) for v in diag.values() if v != 0.0}
            signs |= dsign
            if len(signs) != 1:
                break
            sg = next(iter(signs))
            off = [(int(i[r]), int(j[r])) for r in rows if i[r] != j[r]]
            if any(sg * diag.get(a, 0.0) <= 0.0 or sg * diag.get(b, 0.0) <= 0.0 for a, b in off):
                break  # a 2 x 2 principal minor is negative
            sup = sorted(diag)
            M = tril_unvec(col.toarray().ravel(), lmi.dim)[np.ix_(sup, sup)]
            w = np.linalg.eigvalsh(sg * M)
            if w[0] < -1e-12 * max(1.0, float(w[-1])):
                break
        else:
            if nonzero and len(signs) == 1:
                return f"variable {k + 1}: a semidefinite coefficient of cost 0"
    return None


def _semidefinite_candidates(problem: Problem, cols: list[sp.csc_matrix], ks: np.ndarray) -> np.ndarray:
    """The variables of ``ks`` that pass :func:`obvious_face`'s sign tests in one vectorised
    pass: a variable whose non-zero diagonal coefficients have both signs, or with an
    off-diagonal coefficient next to a zero diagonal one (a negative 2 x 2 minor), is out.
    Only variables the per-variable test would reject are dropped (bounded-real lemma, 40
    states: 821 variables, 0.14 s of that loop before, none a candidate).

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> C = sp.csc_matrix([[0.0, 1.0, 0.0], [1.0, 1.0, 1.0], [0.0, 1.0, 0.0]])
    >>> p = Problem([Variable("x", "full", (2, 1))], [LMI("M", 2, C, strict=False)],
    ...             LinearConstraints.empty(2), Objective("min", [0.0, 0.0, 0.0]))
    >>> _semidefinite_candidates(p, [C], np.array([0, 1])).tolist()   # x2: an off-diagonal alone
    [0]
    """
    n = problem.n
    pos = np.zeros(n, dtype=bool)
    neg = np.zeros(n, dtype=bool)
    bad = np.zeros(n, dtype=bool)
    for lmi, C in zip(problem.lmis, cols, strict=True):
        body = sp.coo_matrix(C[:, 1:])
        keep = body.data != 0.0
        r, k, v = body.row[keep], body.col[keep], body.data[keep]
        i, j = tril_rows_cols(lmi.dim)
        on = i[r] == j[r]
        pos[k[on & (v > 0)]] = True
        neg[k[on & (v < 0)]] = True
        diag_keys = np.unique(k[on].astype(np.int64) * lmi.dim + i[r[on]])
        off_k = k[~on].astype(np.int64)
        for end in (i[r[~on]], j[r[~on]]):
            bad[off_k[~np.isin(off_k * lmi.dim + end, diag_keys)]] = True
    ks = np.asarray(ks, dtype=np.int64)
    return ks[~(pos & neg | bad)[ks]]


def facial_or(
    problem: Problem,
    duals: dict[str, Any] | None,
    dual: dict[str, Any],
    solve_point: Callable[[Problem], np.ndarray | None] | None,
    *,
    exact: bool = False,
    resolve: Callable[[Problem], dict[str, Any] | None] | None = None,
    deadline: float | None = None,
) -> dict[str, Any]:
    """``dual`` (a :func:`~lmic.certify.enclosure_dual.dual_bound` record) when it is proven or
    the facial route cannot run (no dual point, no solve); else :func:`facial_bound`'s record
    when it proves, or ``dual`` with the facial route's reason appended.

    >>> facial_or(None, None, {"proven": True, "lower": 1.0}, None)["lower"]
    1.0
    """
    if dual.get("proven") or solve_point is None or not duals or duals.get("lmis") is None:
        return dual
    before = f"{dual['reason']}; " if dual.get("reason") else ""
    if deadline is not None and time.perf_counter() > deadline:
        return dict(dual, reason=f"{before}facial reduction not tried (time budget spent)")
    try:
        fac = facial_bound(problem, duals, solve_point, exact=exact, resolve=resolve, deadline=deadline)
    except (OverflowError, ValueError, ZeroDivisionError, ArithmeticError, np.linalg.LinAlgError) as exc:
        fac = {"proven": False, "reason": f"numerical failure ({type(exc).__name__}: {exc})"}
    if fac["proven"]:
        return fac
    return dict(dual, reason=f"{before}facial reduction: {fac['reason']}")


class FacialFirst:
    """The facial route as :func:`~lmic.certify.enclosure_dual.dual_bound`'s ``before_solves``:
    tried when the solver's dual fails, before the perturbed and centring re-solves, which
    cannot prove where the dual has no strictly feasible point (SDPLIB qap: 6 perturbed and 3
    centring solves, 8 of the enclosure's 9 s, before the facial route proved). ``record`` is
    its result once it ran; :meth:`after` gives the dual end after ``dual_bound``.

    >>> f = FacialFirst(None, None, None, False, None, None)
    >>> f.after({"proven": False, "reason": "r"})["reason"]  # not run yet: run now (no dual point)
    'r'
    >>> f()["proven"], f.after({"proven": False, "reason": "r"})["reason"]
    (False, 'r')
    """

    def __init__(
        self,
        problem: Problem,
        duals: dict[str, Any] | None,
        solve_point: Callable[[Problem], np.ndarray | None] | None,
        exact: bool,
        resolve: Callable[[Problem], dict[str, Any] | None] | None,
        deadline: float | None,
    ) -> None:
        self._run = functools.partial(
            facial_or, problem, duals, solve_point=solve_point, exact=exact, resolve=resolve, deadline=deadline
        )
        self.record: dict[str, Any] | None = None

    def __call__(self) -> dict[str, Any]:
        self.record = self._run({"proven": False, "reason": ""})
        return self.record

    def after(self, dual: dict[str, Any]) -> dict[str, Any]:
        """``dual`` (``dual_bound``'s record) when proven; else the facial route's proof, or
        ``dual`` with the facial route's reason (running it now when it did not run before)."""
        if self.record is None:
            return self._run(dual)
        if dual.get("proven") or not self.record.get("reason"):
            return dual
        return dict(dual, reason=f"{dual.get('reason')}; {self.record['reason']}")


def verify_any(problem: Problem, record: dict[str, Any]) -> dict[str, Any]:
    """:func:`verify_facial` for a facial record, :func:`~lmic.certify.enclosure_cut.verify_cut`
    for an objective cut, else :func:`~lmic.certify.enclosure_dual.verify_dual_bound`.

    >>> verify_any(None, {"dual": None, "lower": None})["ok"]
    False
    """
    d = record.get("dual")
    if isinstance(d, dict) and d.get("form") == "facial":
        return verify_facial(problem, record)
    if record.get("route") == "objective cut":
        from lmic.certify.enclosure_cut import verify_cut

        return verify_cut(problem, record)
    return verify_dual_bound(problem, record)
