"""A centred dual point for a dual whose interior is too thin for the shift of the repair.

Why it is needed
----------------
For some problems the dual feasible set has an interior, but a very thin one. The
bounded-real lemma is the standard case: with ``P`` free in ``A^T P + P A ...``, the dual
equalities force the multiplier's state block ``X`` to solve a Lyapunov equation
``A X + X A^T + B V^T + V B^T = Z_P`` (``Z_P``: the multiplier of ``P > 0``, zero at the
optimum), so ``X`` is a controllability-Gramian-like matrix whose eigenvalues decay
geometrically with the number of states. A shift ``eps I`` of the solver's (singular) dual
breaks these equalities by ``O(eps)`` in every direction, and the dual point cannot be repaired
inside the cone: no dual point near it has all eigenvalues above ``eps``. VSDP's perturbed
problem then has no solution either (it asks for exactly such a point).

What is done instead
--------------------
The dual problem itself is solved, on the caller's backend, for the *largest interior margin*
``t`` at a small, fixed loss ``delta`` of dual objective (:func:`centring_problem`)::

    max t  s.t.  g_k(u) = q_k (k >= 1),  Z_i - t I >= 0 (active LMIs),  y_r - t >= 0 (active
                 ge rows),  q_0 - g_0(u) >= L_0 - delta,  sum_i tr Z_i <= T

(``L_0``: the solver's dual objective; ``T``: ten times the solver's dual trace, which keeps
``t`` bounded). Its point ``u_c`` is interior by ``t``, and the convex combination ``u =
(1 - theta) u_0 + theta u_c`` with the solver's (projected) dual ``u_0`` has every eigenvalue
above about ``theta t`` while losing only ``theta delta`` of objective. The smallest ``theta``
that the rigorous proof (:func:`lmic.certify.enclosure_float.prove_float`) accepts, after the
repair of :mod:`lmic.certify.enclosure_repair`, gives the bound. The losses are tried in the
order of :data:`LOSSES`; a proof that gave up more than :data:`CHEAP_LOSS` is compared with
the other losses' (a wider interior may prove at a smaller weight), and the best bound is
kept. Nothing about ``u_c`` is trusted: the solver's point is only a candidate, the proof
decides.

Where the interior is thinner than the floating-point resolution (the bounded-real lemma from
about 15 states), no candidate proves: :mod:`lmic.certify.enclosure_face` proves such problems
exactly on their optimal face when the IR's coefficients have the Lyapunov structure exactly;
otherwise :mod:`lmic.certify.enclosure_conditional` gives a bound that holds for solutions in a
box only, labelled as such.

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
>>> from lmic.certify.enclosure_repair import jacobian
>>> p = Problem([Variable("t", "scalar", (1, 1))], [LMI("t >= 2", 1, sp.csc_matrix([[-2.0, 1.0]]))],
...             LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
>>> J, ranges = jacobian(p)
>>> c, idx = centring_problem(p, J, ranges, np.array([0.0, 1.0]), np.ones(1, bool), 1.9, 10.0)
>>> c.n, c.objective.sense, [l.dim for l in c.lmis], c.linear.kinds
(2, 'max', [1], ['eq', 'ge', 'ge'])
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import scipy.sparse as sp

from lmic.certify.enclosure_float import _prove_float
from lmic.certify.enclosure_repair import _least_norm, _pack, _repair, _unpack
from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
from lmic.ir.svec import tril_rows_cols

#: a proof attempt's ``(proof record, Z_i, y)``
_Proof = tuple[dict[str, Any], list[np.ndarray], np.ndarray]

__all__ = ["CHEAP_LOSS", "LOSSES", "OVERRUN_LOSS", "THETAS", "centring_problem", "centred_bound"]

#: relative losses ``delta / max(1, |L_0|)`` of dual objective tried, in this order: 1e-4
#: first (its interior suffices at a weight of 1e-4, a loss of 1e-8, wherever 1e-6's does), then
#: wider interiors, then 1e-6 for a proof in hand that gave up more than :data:`CHEAP_LOSS`
LOSSES = (1e-4, 1e-3, 1e-2, 1e-6)
#: weights ``theta`` of the centred point in the combination, smallest first
THETAS = (1e-4, 1e-3, 1e-2, 0.03, 0.1, 0.3, 1.0)
#: a proof that gave up at most this relative share ``theta * delta`` of the dual objective is
#: kept; one that gave up more is compared with the other losses' (a larger loss has a wider
#: interior, so a smaller weight may prove: uir.thm4_1 n = 12 seed 4 on CVXOPT proved only at
#: theta 1 at loss 1e-4, a relative gap of 1.2e-4)
CHEAP_LOSS = 1e-7
#: ... and a proof that gave up more than this (the enclosure's target gap,
#: ``enclosure.GAP_TARGET``) gets one more loss even past the search's deadline
OVERRUN_LOSS = 1e-6


def centring_problem(
    problem: Problem,
    J: sp.csr_matrix,
    ranges: list[tuple[int, int]],
    q: np.ndarray,
    active: np.ndarray,
    level: float,
    trace_cap: float,
) -> tuple[Problem, np.ndarray]:
    """The dual problem asking for the largest interior margin ``t`` (module docstring).

    Its variables are the active entries of ``u`` (in the order of ``np.flatnonzero(active)``,
    returned as the second element) followed by ``t``; ``level`` is ``L_0 - delta``.

    >>> import numpy as np, scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> from lmic.certify.enclosure_repair import jacobian
    >>> p = Problem([Variable("t", "scalar", (1, 1))], [LMI("t >= 2", 1, sp.csc_matrix([[-2.0, 1.0]]))],
    ...             LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
    >>> J, ranges = jacobian(p)
    >>> centring_problem(p, J, ranges, np.array([0.0, 1.0]), np.ones(1, bool), 1.9, 10.0)[1].tolist()
    [0]
    """
    idx = np.flatnonzero(active)
    k = idx.size
    nvar = k + 1
    tcol = 1 + k
    pos = -np.ones(J.shape[1], dtype=int)
    pos[idx] = np.arange(k)
    lmis, trace = [], np.zeros(1 + nvar)
    for lmi, (a, b) in zip(problem.lmis, ranges, strict=True):
        if not lmi.dim or not np.all(active[a:b]):
            continue
        i, j = tril_rows_cols(lmi.dim)
        diag = np.flatnonzero(i == j)
        rows = np.concatenate([np.arange(b - a), diag])
        cols = np.concatenate([1 + pos[a:b], np.full(diag.size, tcol)])
        vals = np.concatenate([np.ones(b - a), -np.ones(diag.size)])
        lmis.append(
            LMI(
                f"Z[{lmi.name}] - t I >= 0",
                lmi.dim,
                sp.csc_matrix((vals, (rows, cols)), shape=(b - a, 1 + nvar)),
                False,
            )
        )
        trace[1 + pos[a:b][diag]] = -1.0
    Js = J[:, idx].tocsr()
    nz = np.flatnonzero(np.asarray(abs(Js[1:]).sum(axis=1)).ravel() > 0)
    eq = sp.hstack([sp.csr_matrix(-q[1:, None]), Js[1:], sp.csr_matrix((problem.n, 1))]).tocsr()[nz]
    extra, kinds = [], ["eq"] * nz.size
    ge = np.array([kk == "ge" for kk in problem.linear.kinds], dtype=bool)
    off = ranges[-1][1] if ranges else 0
    for r in np.flatnonzero(ge):
        if active[off + r]:
            v = np.zeros(1 + nvar)
            v[1 + pos[off + r]], v[tcol] = 1.0, -1.0
            extra.append(v)
            kinds.append("ge")
    v = np.zeros(1 + nvar)
    v[0] = q[0] - level
    v[1 : 1 + k] = -Js[0].toarray().ravel()
    extra.append(v)
    trace[0] = trace_cap
    extra.append(trace)
    kinds += ["ge", "ge"]
    A = sp.vstack([eq, sp.csr_matrix(np.array(extra))]).tocsr()
    lin = LinearConstraints(A, kinds, [False] * len(kinds), [f"centring row {r}" for r in range(len(kinds))])
    c = np.zeros(1 + nvar)
    c[tcol] = 1.0
    variables = [Variable("u", "full", (k, 1)), Variable("t", "scalar", (1, 1), offset=k)]
    return Problem(variables, lmis, lin, Objective("max", c), meta={"centring_of": problem.meta.get("theorem")}), idx


def centred_bound(
    problem: Problem,
    J: sp.csr_matrix,
    ranges: list[tuple[int, int]],
    q: np.ndarray,
    mats0: list[np.ndarray],
    y0: np.ndarray,
    active: np.ndarray,
    top: float,
    solve_point: Callable[[Problem], np.ndarray | None],
    deadline: Callable[[], bool],
) -> _Proof:
    """Try the centred candidates (module docstring); returns ``(proof, Z_i, y)``.

    ``mats0``, ``y0``: the solver's dual projected onto the cone (inactive entries zero);
    ``solve_point(problem) -> x or None`` solves a problem on the caller's backend;
    ``deadline()`` is true when no new attempt may start.

    >>> import numpy as np, scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> from lmic.certify.enclosure_repair import jacobian
    >>> p = Problem([Variable("t", "scalar", (1, 1))], [LMI("t >= 2", 1, sp.csc_matrix([[-2.0, 1.0]]))],
    ...             LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
    >>> J, ranges = jacobian(p)
    >>> res, _, _ = centred_bound(p, J, ranges, np.array([0.0, 1.0]), [np.eye(1)], np.zeros(0),
    ...                           np.ones(1, bool), 1.0, lambda c: np.array([1.0, 0.5]), lambda: False)
    >>> res["proven"], res["lower"] <= 2.0
    (True, True)
    """
    u0 = _pack(problem, mats0, y0)
    u0[~active] = 0.0
    L0 = float(q[0] - (J[0] @ u0)[0])
    cap = 10.0 * sum(float(np.trace(Z)) for Z, (a, b) in zip(mats0, ranges, strict=True) if np.all(active[a:b]))
    cap = max(cap, 10.0 * top)
    out: dict[str, Any] = {"proven": False, "reason": "no centred dual point was found"}
    best: tuple[list[np.ndarray], np.ndarray] = (mats0, y0)
    proved: _Proof | None = None  # the best proof so far
    overrun = False  # whether a loss was started past the deadline
    scale = max(1.0, abs(L0))
    for loss in LOSSES:
        # a proof at loss delta and weight theta gives up about theta * delta of the bound: a
        # larger loss pays only if its smallest weight could give up less
        if proved is not None and THETAS[0] * loss >= _given_up(proved[0]):
            continue
        if deadline():
            if proved is None:
                out["reason"] += "; time budget spent"
                break
            if overrun or _given_up(proved[0]) <= OVERRUN_LOSS:
                break
            # a proof in hand that gave up more than the target gap by itself: one more loss
            # (a solve and its weights) past the deadline, once (uir.thm4_1 n = 12 seed 4 on
            # CVXOPT on a machine 1.5x slower: 1.2e-4 without it)
            overrun = True
        prob, idx = centring_problem(problem, J, ranges, q, active, L0 - loss * scale, cap)
        x = solve_point(prob)
        if x is None or x.shape != (prob.n,) or not np.all(np.isfinite(x)) or not x[-1] > 0:
            if proved is None:
                out["reason"] = f"the centring problem at loss {loss:g} gave no interior point"
            continue
        t = float(x[-1])
        uc = np.zeros(u0.size)
        uc[idx] = x[:-1]

        def combine(theta: float, uc: np.ndarray = uc, t: float = t) -> _Proof:
            return _combined(problem, J, ranges, q, u0, uc, t, theta, active)

        for k, theta in enumerate(THETAS):
            if proved is not None and theta * loss >= _given_up(proved[0]):
                break  # no better than the proof in hand
            res, mats, y = combine(theta)
            if res["proven"]:
                res.update(centring_loss=loss, centring_margin=t, theta=theta)
                if k:
                    # the bound loses about theta * delta: the weights between the last that
                    # failed and this one (geometric thirds, smallest first) may lose less
                    # (uir.thm4_1 n = 12, seed 1: theta 1e-2 at loss 1e-4 costs 1e-6 of the bound,
                    # theta 4.6e-3 4.8e-7). Not subject to the deadline: it is at most two more
                    # combinations (a repair and a proof each, no solve) after one that proved,
                    # and a deadline here made the bound depend on the machine's speed (the
                    # search's 3 s minimum was spent just before it on a slower machine)
                    res, mats, y = _refined(combine, THETAS[k - 1], theta, (res, mats, y))
                    res.update(centring_loss=loss, centring_margin=t)
                if proved is None or res["lower"] > proved[0]["lower"]:
                    proved = (res, mats, y)
                break
            if proved is None:
                out = dict(res, reason=f"centred point (loss {loss:g}, margin {t:.3g}): {res['reason']}")
                best = (mats, y)
        if proved is not None and _given_up(proved[0]) <= CHEAP_LOSS:
            break
    if proved is not None:
        return proved
    return out, best[0], best[1]


def _given_up(res: dict[str, Any]) -> float:
    """The relative share of the dual objective a centred proof gave up: ``theta * delta``."""
    return float(res["theta"]) * float(res["centring_loss"])


def _combined(
    problem: Problem,
    J: sp.csr_matrix,
    ranges: list[tuple[int, int]],
    q: np.ndarray,
    u0: np.ndarray,
    uc: np.ndarray,
    t: float,
    theta: float,
    active: np.ndarray,
) -> _Proof:
    """The combination ``(1 - theta) u0 + theta uc`` repaired and proved: ``(proof, Z_i, y)``."""
    u = (1.0 - theta) * u0 + theta * uc
    mats, y = _unpack(problem, u, ranges)
    mats = [0.5 * (Z + Z.T) for Z in mats]
    mats, y = _repair(problem, J, ranges, q, mats, y, floor=0.5 * theta * t, steps=80)
    res = _prove_float(problem, J, ranges, q, mats, y, active)
    if not res["proven"]:
        # the damped steps stalled above round-off: plain least-norm steps (which may leave
        # the cone by their size; the proof decides)
        mats, y = _least_norm(problem, J, ranges, q, mats, y, active)
        res = _prove_float(problem, J, ranges, q, mats, y, active)
    return res, mats, y


def _refined(
    combine: Callable[[float], _Proof],
    low: float,
    high: float,
    found: _Proof,
) -> _Proof:
    """The smallest of two weights between a failing ``low`` and the proving ``high``
    (geometric thirds) that proves a better bound than ``found``; else ``found``.
    ``combine(theta)`` is :func:`_combined` at that weight."""
    for f in (2.0 / 3.0, 1.0 / 3.0):
        theta = low**f * high ** (1.0 - f)
        try:
            res, mats, y = combine(theta)
        except (np.linalg.LinAlgError, ValueError, FloatingPointError):
            continue
        if res["proven"] and res["lower"] > found[0]["lower"]:
            res.update(theta=theta)
            return res, mats, y
    return found
