"""Dual repair of the enclosure (steps 1-3 of :mod:`lmic.certify.enclosure`).

The solver's dual point ``u = (Z_i, y)`` is projected onto the cone, shifted inside, and
repaired by damped least-squares steps that keep every eigenvalue above a floor until the dual
equalities ``g_k(u) = q_k`` hold to round-off. The linear map ``u -> g(u)`` is the sparse
matrix of :func:`jacobian`. :func:`perturbed_problem` is VSDP's perturbation for a degenerate
dual. Nothing here is a proof: :mod:`lmic.certify.enclosure_float` and
:mod:`lmic.certify.enclosure_exact` decide.

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
>>> p = Problem([Variable("t", "scalar", (1, 1))], [LMI("t > 2", 1, sp.csc_matrix([[-2.0, 1.0]]))],
...             LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
>>> J, ranges = jacobian(p)
>>> J.toarray().tolist(), ranges
([[-2.0], [1.0]], [(0, 1)])
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
import scipy.sparse as sp

from lmic.certify.enclosure_gram import dense_cost, entries, free_cost, gram, step_matrix
from lmic.certify.multipliers import parse_multipliers
from lmic.ir.problem import Problem
from lmic.ir.svec import tril_rows_cols, tril_unvec

__all__ = ["SHIFTS", "PERTURBATIONS", "DROP", "CHECK_AT", "HOPELESS", "jacobian", "pivot_blocks", "perturbed_problem"]

#: relative shifts ``eps_rel`` tried, smallest first (step 2 of the module docstring)
SHIFTS = (1e-15, 1e-14, 1e-13, 3e-13, 1e-12, 1e-11, 1e-10, 1e-9, 1e-8, 1e-7, 1e-6)


#: relative perturbations ``eps_rel`` of :func:`perturbed_problem` tried when the solver's
#: own dual is degenerate
PERTURBATIONS = (1e-8, 1e-6)


#: a multiplier block below this times the largest multiplier is set to exactly zero (an
#: inactive constraint; it then needs no interior shift)
DROP = 1e-6


def _weights(d: int) -> np.ndarray:
    i, j = tril_rows_cols(d)
    return np.where(i == j, 1.0, 2.0)


def _jacobian(problem: Problem) -> tuple[sp.csr_matrix, list[tuple[int, int]]]:
    """``J`` (``(1 + n) x m``, ``g = J u``) and the column range of every LMI's ``svec(Z_i)``."""
    cols, ranges, start = [], [], 0
    for lmi in problem.lmis:
        C = lmi.coeffs.tocsc()
        cols.append(sp.csr_matrix(C.T.multiply(_weights(lmi.dim)[None, :])))
        t = C.shape[0]
        ranges.append((start, start + t))
        start += t
    if len(problem.linear):
        cols.append(sp.csr_matrix(problem.linear.A.T))
    if not cols:
        return sp.csr_matrix((1 + problem.n, 0)), ranges
    return sp.csr_matrix(sp.hstack(cols)), ranges


def _pack(problem: Problem, mats: list[np.ndarray], y: np.ndarray) -> np.ndarray:
    parts = []
    for lmi, Z in zip(problem.lmis, mats, strict=True):
        r, c = tril_rows_cols(lmi.dim)
        parts.append(Z[r, c])
    parts.append(y)
    return np.concatenate(parts) if parts else np.zeros(0)


def _unpack(problem: Problem, u: np.ndarray, ranges: list[tuple[int, int]]) -> tuple[list[np.ndarray], np.ndarray]:
    mats = [tril_unvec(u[a:b], lmi.dim) for lmi, (a, b) in zip(problem.lmis, ranges, strict=True)]
    off = ranges[-1][1] if ranges else 0
    return mats, u[off:].copy()


def _parse(problem: Problem, record: dict[str, Any]) -> tuple[list[np.ndarray], np.ndarray]:
    return parse_multipliers(problem, record, "dual point", missing_is_zero=False)


def _target(problem: Problem) -> tuple[float, np.ndarray]:
    s = -1.0 if problem.objective.sense == "max" else 1.0
    q = s * problem.objective.c
    return s, q


#: entries of one chunk of the dense factor of :func:`_block_gradient` (bounds its memory)
CHUNK_ENTRIES = 4_000_000


#: a block's dense gradient (``n x r (r + 1) / 2``) from this many entries on is replaced by the
#: matrix-free form of :mod:`lmic.certify.enclosure_gram` where that is cheaper; below it the
#: dense form's one ``G G^T`` beats the per-block overhead (SDPLIB truss6: 151 blocks of order
#: 3, 172 rows: 1.0e3 entries each)
FREE_MIN_ENTRIES = 1_000_000


#: the support form's cost unit (a gathered entry) against the congruence form's (a BLAS flop),
#: measured: ``uncertain_dt.thm1`` n = 8, 58 x 58 block, rank 58, 91 rows: support 13.4 ms for
#: 4.0e6 units, congruence 2.6 ms for 3.6e7 flops; its 33 x 33 block: 0.43 ms for 2.6e5 units
#: against 0.54 ms for 6.3e6 flops (a ratio of 20 to 45)
CONGRUENCE_RATE = 20.0


def _block_gradient(Jb: sp.spmatrix, U: np.ndarray, dim: int, ia: np.ndarray, ib: np.ndarray) -> np.ndarray:
    """``Jb @ T`` with ``T[s, (a, b)] = d svec(U E U^T)_s / d E_ab`` (``E`` symmetric).

    Only the rows ``s`` of ``T`` where ``Jb`` has a nonzero column are formed, in chunks of at
    most :data:`CHUNK_ENTRIES` entries: the cost is ``O(nnz(Jb) r^2)`` time and
    ``O(CHUNK_ENTRIES)`` memory, not the ``O(dim^2 r^2)`` of the full ``T`` (6 GB on SDPLIB's
    arch0, a 161 x 161 block).

    >>> U = np.eye(2)
    >>> ia, ib = np.triu_indices(2)
    >>> _block_gradient(sp.csc_matrix([[1.0, 0.0, 1.0]]), U, 2, ia, ib).tolist()
    [[1.0, 0.0, 1.0]]
    """
    Jc = sp.csc_matrix(Jb)
    support = np.flatnonzero(np.diff(Jc.indptr))
    out = np.zeros((Jc.shape[0], ia.size))
    if not support.size or not ia.size:
        return out
    r = U.shape[1]
    rows_used = np.unique(Jc.indices)
    # the support form costs |support| x (the factor's pairs) for T and nnz(Jb) x pairs for the
    # product, in gathers; the congruence form r d^2 + r^2 d flops per row of Jb, in BLAS
    # (:data:`CONGRUENCE_RATE`)
    if rows_used.size * (r * dim * dim + r * r * dim) < CONGRUENCE_RATE * (support.size + Jc.nnz) * ia.size:
        return _congruence_gradient(Jc, U, dim, ia, ib, rows_used, out)
    ri, ci = tril_rows_cols(dim)
    diag = ia == ib
    step = max(1, CHUNK_ENTRIES // max(1, ia.size))
    for s0 in range(0, support.size, step):
        rows = support[s0 : s0 + step]
        P, Qm = U[ri[rows]], U[ci[rows]]
        T = P[:, ia] * Qm[:, ib] + P[:, ib] * Qm[:, ia]
        T[:, diag] *= 0.5
        out += np.asarray(Jc[:, rows] @ T)
    return out


def _congruence_gradient(
    Jc: sp.csc_matrix, U: np.ndarray, dim: int, ia: np.ndarray, ib: np.ndarray, rows_used: np.ndarray, out: np.ndarray
) -> np.ndarray:
    """:func:`_block_gradient` row by row: row ``i`` of ``Jb T`` is the upper triangle of ``U' S_i
    U`` (its diagonal halved), ``S_i`` the symmetric matrix of row ``i``'s tril entries (each
    placed at ``(r, c)`` and ``(c, r)``, a diagonal one twice). Dense products of order ``dim``
    for every row of ``Jb`` with a nonzero, in chunks of at most :data:`CHUNK_ENTRIES` entries:
    cheaper than the support form when ``Jb`` is dense on a large block (``uncertain_dt.thm1``
    n = 8: a 58 x 58 block, 1.7e3 support rows, 91 rows of ``Jb``).

    >>> import scipy.sparse as sp
    >>> ia, ib = np.triu_indices(2)
    >>> J = sp.csc_matrix([[1.0, 0.0, 1.0]])
    >>> _congruence_gradient(J, np.eye(2), 2, ia, ib, np.array([0]), np.zeros((1, 3))).tolist()
    [[1.0, 0.0, 1.0]]
    """
    ri, ci = tril_rows_cols(dim)
    coo = sp.coo_matrix(Jc)
    diag = ia == ib
    step = max(1, CHUNK_ENTRIES // max(1, dim * dim))
    for s0 in range(0, rows_used.size, step):
        chunk = rows_used[s0 : s0 + step]
        local = np.full(Jc.shape[0], -1)
        local[chunk] = np.arange(chunk.size)
        keep = local[coo.row] >= 0
        k, col, val = local[coo.row[keep]], coo.col[keep], coo.data[keep]
        S = np.zeros((chunk.size, dim, dim))
        np.add.at(S, (k, ri[col], ci[col]), val)
        np.add.at(S, (k, ci[col], ri[col]), val)
        C = np.matmul(np.matmul(U.T, S), U)
        block = C[:, ia, ib]
        block[:, diag] *= 0.5
        out[chunk] = block
    return out


#: the damped steps after which :func:`_repair` asks its caller's ``check`` (the proof after the
#: least-norm steps) whether the point already proves: a dual at the boundary of the cone
#: (Clarabel's, chordal) takes all 40 steps to polish a point that proves after 6 to 10
#: (``uncertain_dt.thm1`` n = 12: 1.0 s a repair, 20 ms a step for its 86 x 86 block)
CHECK_AT = (5, 10, 20)

#: from the second check on, a proof that fails by a PSD deficit above this many times the
#: shift also stops the steps: the shift is far too small for this dual (Clarabel's on
#: ``uncertain_dt.thm1`` n = 12: a deficit of 1e-11 against a shift of 6e-15, which 40 steps do
#: not close), and the caller's next shift (:func:`lmic.certify.enclosure_dual.needed_shift`)
#: is chosen from the deficit
HOPELESS = 100.0


def _repair(
    problem: Problem,
    J: sp.csr_matrix,
    ranges: list,
    q: np.ndarray,
    mats: list,
    y: np.ndarray,
    floor: float = 0.0,
    steps: int = 40,
    objective: float | None = None,
    deadline: float | None = None,
    check: Any = None,
):
    import time

    import scipy.linalg

    ge = np.array([k == "ge" for k in problem.linear.kinds], dtype=bool)
    # with ``objective``, g_0(u) is held at it too (the repair then keeps the dual objective)
    Jx = J[1:].tocsc() if objective is None else J.tocsc()
    qn = q[1:] if objective is None else np.concatenate([[objective], q[1:]])
    scale = float(np.max(np.abs(qn), initial=0.0)) + 1e-300
    history: list[float] = []
    cache: dict[tuple[int, int], Any] = {}

    def entries_of(a: int, b: int, dim: int) -> Any:
        if (a, b) not in cache:
            cache[(a, b)] = entries(Jx[:, a:b], dim)
        return cache[(a, b)]

    for _ in range(steps):
        u = _pack(problem, mats, y)
        rho = qn - Jx @ u
        now = float(np.max(np.abs(rho), initial=0.0))
        if now <= 1e-15 * scale or (len(history) >= 6 and now > 0.9 * history[-6]):
            break  # converged, or stalled (no interior point near: the proof will say so)
        if deadline is not None and history and time.perf_counter() > deadline:
            break  # the caller's time budget is spent: the proof decides on what is there
        if check is not None and len(history) in CHECK_AT and check(mats, y, len(history)):
            break  # the caller's proof already holds (more steps only polish), or cannot at this shift
        history.append(now)
        blocks: list[Any] = []  # dense gradient blocks (n x r(r+1)/2): G's columns
        factors: list[Any] = []
        for lmi, Z, (a, b) in zip(problem.lmis, mats, ranges, strict=True):
            if not lmi.dim:
                factors.append(None)
                continue
            w, V = np.linalg.eigh(Z - floor * np.eye(lmi.dim))
            sel = w > 0
            U = V[:, sel] * np.sqrt(w[sel])
            r = U.shape[1]
            if not r:
                factors.append(None)
                continue
            ia, ib = np.triu_indices(r)
            big = Jx.shape[0] * len(ia) >= FREE_MIN_ENTRIES
            ent = entries_of(a, b, lmi.dim) if big else None
            if ent is not None and free_cost(ent, r) < dense_cost(Jx.shape[0], r):
                # a large block with sparse coefficients: G G^T and G^T lambda without G (enclosure_gram)
                factors.append((U, ia, ib, ent))
                continue
            # d svec(Z) / d E_ab, mapped by J's columns of this LMI (:func:`_block_gradient`)
            blocks.append(_block_gradient(Jx[:, a:b], U, lmi.dim, ia, ib))
            factors.append((U, ia, ib, None))
        off = ranges[-1][1] if ranges else 0
        rows = [r for r in range(len(y)) if (not ge[r]) or y[r] > floor]
        top = max([float(np.max(np.abs(y), initial=0.0))] + [float(np.max(np.abs(Z), initial=0.0)) for Z in mats])
        srow = np.array([y[r] - floor if ge[r] else max(abs(y[r]), 1e-3 * top, 1e-300) for r in rows])
        if rows:
            blocks.append(Jx[:, [off + r for r in rows]].toarray() * srow[None, :])
        free = [f for f in factors if f is not None and f[3] is not None]
        if not blocks and not free:
            break
        G = np.hstack(blocks) if blocks else np.zeros((Jx.shape[0], 0))
        # least-norm step through the Gram matrix (n x n, cheap for the wide G of a face)
        Gm = G @ G.T
        for f in free:
            Gm += gram(f[3], f[0])
        Gm[np.diag_indices_from(Gm)] += 1e-14 * float(np.trace(Gm)) / max(1, Gm.shape[0]) + 1e-300
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", scipy.linalg.LinAlgWarning)
                lam = np.linalg.solve(Gm, rho)
            e = G.T @ lam
        except (np.linalg.LinAlgError, ValueError):
            if free:
                lam = scipy.linalg.lstsq(Gm, rho, lapack_driver="gelsy", check_finite=False)[0]
                e = G.T @ lam
            else:
                e = scipy.linalg.lstsq(G, rho, lapack_driver="gelsy", check_finite=False)[0]
        k, norms = 0, [0.0]
        Es: list[Any] = []
        for f in factors:
            if f is None:
                Es.append(None)
                continue
            U, ia, ib, ent = f
            if ent is not None:
                E = step_matrix(ent, U, lam)
            else:
                r = U.shape[1]
                E = np.zeros((r, r))
                E[ia, ib] = e[k : k + len(ia)]
                E[ib, ia] = e[k : k + len(ia)]
                k += len(ia)
            Es.append(E)
            norms.append(float(np.max(np.abs(np.linalg.eigvalsh(E)))))
        ey = e[k:]
        norms += [abs(float(v)) for r, v in zip(rows, ey, strict=True) if ge[r]]
        alpha = 1.0 if max(norms) <= 0.5 else 0.5 / max(norms)
        new = []
        for Z, f, E in zip(mats, factors, Es, strict=True):
            if f is None:
                new.append(Z)
            else:
                U = f[0]
                Zn = U @ (np.eye(U.shape[1]) + alpha * E) @ U.T + floor * np.eye(U.shape[0])
                new.append(0.5 * (Zn + Zn.T))
        mats = new
        y = y.copy()
        for r, v, sr in zip(rows, ey, srow, strict=True):
            y[r] += alpha * float(v) * sr
    return mats, y


def _scale(problem: Problem, mats: list, y: np.ndarray) -> float:
    ge = np.array([k == "ge" for k in problem.linear.kinds], dtype=bool)
    top = max(
        [float(np.max(np.abs(y[ge]), initial=0.0))]
        + [float(np.max(np.linalg.eigvalsh(Z), initial=0.0)) if Z.size else 0.0 for Z in mats]
    )
    return top if top > 0 else 1.0


def perturbed_problem(problem: Problem, eps: float) -> Problem:
    """The closed problem whose duals are ``eps`` inside the cone (VSDP's perturbation).

    Its objective is the minimisation form's ``q`` minus ``eps t`` with ``t_k = sum_i tr
    F_i^(k) + sum_{r ge} a_rk``: a dual point ``(Z_i', y')`` of it gives ``Z_i = Z_i' + eps I``,
    ``y_r = y_r' + eps`` (``ge`` rows), a dual point of ``problem`` whose every eigenvalue is at
    least ``eps``. Strict constraints are closed (the dual bound holds for the closure).

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("t", "scalar", (1, 1))], [LMI("t > 2", 1, sp.csc_matrix([[-2.0, 1.0]]))],
    ...             LinearConstraints.empty(1), Objective("max", [1.0, -1.0]))
    >>> q = perturbed_problem(p, 0.5)
    >>> q.objective.sense, q.objective.c.tolist(), q.lmis[0].strict
    ('min', [-1.0, 0.5], False)
    """
    import dataclasses

    from lmic.ir.problem import LinearConstraints, Objective

    _, q = _target(problem)
    t = np.zeros(1 + problem.n)
    for lmi in problem.lmis:
        i, j = tril_rows_cols(lmi.dim)
        t += np.asarray(lmi.coeffs.tocsr()[np.flatnonzero(i == j)].sum(axis=0)).ravel()
    ge = np.array([k == "ge" for k in problem.linear.kinds], dtype=bool)
    if np.any(ge):
        t += np.asarray(problem.linear.A.tocsr()[np.flatnonzero(ge)].sum(axis=0)).ravel()
    c = q - eps * t
    c[0] = q[0]
    lin = problem.linear
    return Problem(
        list(problem.variables),
        [dataclasses.replace(lmi, strict=False) for lmi in problem.lmis],
        LinearConstraints(lin.A, list(lin.kinds), [False] * len(lin), list(lin.names)),
        Objective("min", c),
        meta={"perturbed_from": problem.meta.get("theorem") if problem.meta else None},
    )


def _prepare(
    problem: Problem,
    J,
    ranges,
    q,
    mats,
    y,
    eps_rel: float,
    top: float | None = None,
    drop: bool = True,
    objective: float | None = None,
    deadline: float | None = None,
    prove: Any = None,
) -> tuple[list, np.ndarray, np.ndarray]:
    """Steps 1-3 of the module docstring; returns ``(Z_i, y, active)`` (``active``: the
    entries of ``u`` the proof may correct; the others are exactly zero). With
    ``objective``, the repair also holds ``g_0(u)`` at that value (the solver's dual
    objective), so the least-norm steps do not trade objective for feasibility. With
    ``deadline`` (a :func:`time.perf_counter` value) the damped steps stop once it is passed.
    With ``prove`` (``prove(mats, y, active) -> record``, the caller's proof), the damped steps
    stop at the first of :data:`CHECK_AT` where the point after the least-norm steps proves, or
    (from the second) fails by a PSD deficit above :data:`HOPELESS` times the shift."""
    ge = np.array([k == "ge" for k in problem.linear.kinds], dtype=bool)
    proj = []
    for Z in mats:
        if not Z.size:
            proj.append(Z)
            continue
        w, V = np.linalg.eigh(Z)
        proj.append((V * np.maximum(w, 0.0)) @ V.T)
    y = np.where(ge, np.maximum(y, 0.0), y)
    if top is None:
        top = _scale(problem, proj, y)
    eps = eps_rel * top
    active = np.ones(_pack(problem, proj, y).size, dtype=bool)
    keep = []
    for Z, (a, b) in zip(proj, ranges, strict=True):
        on = not drop or (Z.size and float(np.max(np.linalg.eigvalsh(Z))) > DROP * top)
        keep.append(on)
        active[a:b] = on
    off = ranges[-1][1] if ranges else 0
    rows_on = ~ge | (y > DROP * top) | (not drop)
    active[off:] = rows_on
    proj = [Z + eps * np.eye(Z.shape[0]) if on else np.zeros_like(Z) for Z, on in zip(proj, keep, strict=True)]
    y = np.where(ge & rows_on, y + eps, np.where(ge, 0.0, y))
    proj = [0.5 * (Z + Z.T) for Z in proj]
    check, proved = None, []
    if prove is not None:

        def check(m: list, yy: np.ndarray, done: int) -> bool:
            m2, y2 = _least_norm(problem, J, ranges, q, m, yy, active, objective=objective)
            res = prove(m2, y2, active)
            if res.get("proven"):
                proved.append((m2, y2))  # the steps stop here: this is the point returned
                return True
            deficit = res.get("psd_deficit")
            return done > CHECK_AT[0] and deficit is not None and deficit > HOPELESS * eps

    mats, y = _repair(
        problem, J, ranges, q, proj, y, floor=0.5 * eps, objective=objective, deadline=deadline, check=check
    )
    if proved:
        return proved[0][0], proved[0][1], active
    mats, y = _least_norm(problem, J, ranges, q, mats, y, active, objective=objective)
    return mats, y, active


def _least_norm(
    problem: Problem, J, ranges, q, mats, y, active: np.ndarray, steps: int = 2, objective: float | None = None
):
    """What the damped steps left: plain least-norm steps over the active entries (they may
    leave the cone by their own size, which the shift pays for; the proof decides)."""
    u = _pack(problem, mats, y)
    Jr = J[1:] if objective is None else J
    qr = q[1:] if objective is None else np.concatenate([[objective], q[1:]])
    Js = Jr[:, np.flatnonzero(active)]
    for _ in range(steps):
        rho = qr - Jr @ u
        if not np.any(rho):
            break
        M = (Js @ Js.T).toarray()
        w = np.linalg.lstsq(M, rho, rcond=None)[0]
        u[active] += Js.T @ w
    return _unpack(problem, u, ranges)


def _active_of(problem: Problem, mats: list, y: np.ndarray, ranges: list, top: float) -> np.ndarray:
    """The entries of ``u`` kept by the drop rule of :func:`_prepare` (blocks and ``ge`` rows
    whose multiplier is above :data:`DROP` times the largest; ``eq`` rows always)."""
    ge = np.array([k == "ge" for k in problem.linear.kinds], dtype=bool)
    active = np.ones(_pack(problem, mats, y).size, dtype=bool)
    for Z, (a, b) in zip(mats, ranges, strict=True):
        active[a:b] = bool(Z.size and float(np.max(np.linalg.eigvalsh(Z))) > DROP * top)
    off = ranges[-1][1] if ranges else 0
    active[off:] = ~ge | (y > DROP * top)
    return active


def _default_active(problem: Problem, ranges: list, u: np.ndarray) -> np.ndarray:
    """Entries a proof may correct: every nonzero block, ``eq`` rows, nonzero ``ge`` rows."""
    ge = np.array([k == "ge" for k in problem.linear.kinds], dtype=bool)
    active = np.ones(u.size, dtype=bool)
    for a, b in ranges:
        active[a:b] = bool(np.any(u[a:b]))
    off = ranges[-1][1] if ranges else 0
    active[off:] = ~ge | (u[off:] != 0)
    return active


#: public name of the Jacobian builder
jacobian = _jacobian


def pivot_blocks(problem: Problem, J: sp.spmatrix, ranges: list[tuple[int, int]]) -> dict[int, np.ndarray]:
    """LMI blocks whose every entry appears in exactly one dual equality row (``k >= 1``), all
    rows distinct: ``{block: row of each tril entry}`` (the multiplier of ``P > 0``, each
    entry of which absorbs one equality of ``P`` with an exact coefficient).

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("p", "scalar", (1, 1))], [LMI("p > 0", 1, sp.csc_matrix([[0.0, 1.0]]))],
    ...             LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
    >>> J, ranges = jacobian(p)
    >>> {k: v.tolist() for k, v in pivot_blocks(p, J, ranges).items()}
    {0: [1]}
    """
    J1 = sp.csc_matrix(J)[1:]
    J1.eliminate_zeros()
    J1 = sp.csc_matrix(J1)
    counts = np.diff(J1.indptr)
    out: dict[int, np.ndarray] = {}
    used: set[int] = set()
    for i, (a, b) in enumerate(ranges):
        if a == b or not np.all(counts[a:b] == 1):
            continue
        rows = (J1.indices[J1.indptr[a:b]] + 1).astype(int)
        if np.unique(rows).size == rows.size and not used.intersection(rows.tolist()):
            out[i] = rows
            used.update(rows.tolist())
    return out
