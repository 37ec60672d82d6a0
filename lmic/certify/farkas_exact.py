"""Exact (rational) Farkas certificates: a float ray made into a global proof of infeasibility.

:func:`prove_farkas` rounds a verified float certificate onto its face and projects it exactly
onto the conditions ``g_k = 0`` (the method is in the docstring of :mod:`lmic.certify.farkas`);
:func:`prove_infeasible` is the entry the certifier calls with ``exact=True``. Split out of
:mod:`lmic.certify.farkas`, which re-exports every public name.

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
>>> p = Problem([Variable("p", "scalar", (1, 1))],
...             [LMI("p >= 0", 1, sp.csc_matrix([[0., 1.]]), strict=False),
...              LMI("-1 - p >= 0", 1, sp.csc_matrix([[-1., -1.]]), strict=False)],
...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
>>> prove_farkas(p, {"lmis": [np.eye(1), np.eye(1)], "linear": []})["proven"]
True
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from lmic.certify.farkas_face import (
    _FACE_BITS,
    _face_thresholds,
    _rational_basis,
    _snap,
    _towards_center,
)
from lmic.certify.farkas_ray import _parse, _weights
from lmic.ir.problem import Problem
from lmic.ir.svec import tril_rows_cols

__all__ = ["prove_farkas", "prove_infeasible", "farkas_candidates", "EXACT_MAX_ENTRIES"]

#: largest exact Jacobian ((1 + n) x (tril entries) x (face unknowns)) an exact proof builds
EXACT_MAX_ENTRIES = 50_000_000

#: seconds per unit of ``n^2 m`` (``n`` variables, ``m`` unknowns of the face) of the exact
#: linear algebra (``rref`` and the projection onto the trace conditions); measured: ``n = 210``,
#: ``m = 400`` took 6-9 s, about 10 s with the PSD proofs. Under a time budget an attempt whose
#: estimate exceeds twice the budget is not started: it cannot be stopped once it runs.
EXACT_WORK_S = 5e-7


def prove_farkas(
    problem: Problem,
    farkas: dict[str, Any],
    *,
    rel_face: tuple[float, ...] = (1e-9, 1e-7, 1e-5, 1e-3),
    keep_certificate: bool = False,
    budget_s: float | None = None,
) -> dict[str, Any]:
    """Make a (float) Farkas certificate exact on its face and prove it (module docstring).

    Parameters
    ----------
    problem : Problem
    farkas : dict
        ``{"lmis": [Z_i], "linear": y}`` in the conic-dual convention (``Z_i >= 0``), e.g. the
        ``certificate`` :func:`verify_farkas` recorded after a repair.
    rel_face : tuple of float
        Eigenvalues of ``Z_i`` (and multipliers ``y_r``) above ``rel_face`` times the largest
        multiplier span the face; tried in order. A direction the solver left with a tiny
        weight where the exact conditions force none (a PSD coefficient that must be
        orthogonal to ``Z_i``) makes the face too large, and the next threshold drops it.
    keep_certificate : bool
        Also return the exact multipliers (``exact_certificate``: ``lmis`` as lists of
        :class:`fractions.Fraction` matrices, ``linear`` as Fractions). Large; not JSON.
    budget_s : float, optional
        No further face or method is tried once this many seconds have passed, or when the
        longest attempt so far would take it beyond them (the first attempt always runs).

    Returns
    -------
    dict
        ``proven`` (bool), ``kind`` (``"closed"``, ``"strict"`` or ``None``), ``reason``,
        ``face`` (rank of every ``Z_i``, the rows used and the threshold that worked),
        ``equations`` (independent ones),
        ``g0`` (exact, rounded to float, for ``sum tr Z_i + sum |y_r| = 1``), ``tau`` (likewise),
        ``denominator_bits`` (of the exact multipliers), ``time_s``.

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
    >>> p = Problem([Variable("p", "scalar", (1, 1))],
    ...             [LMI("p >= 0", 1, sp.csc_matrix([[0., 1.]]), strict=False),
    ...              LMI("-1 - p >= 0", 1, sp.csc_matrix([[-1., -1.]]), strict=False)],
    ...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
    >>> r = prove_farkas(p, {"lmis": [np.eye(1), (1 + 1e-12) * np.eye(1)], "linear": []})
    >>> r["proven"], r["kind"], r["g0"]
    (True, 'closed', -0.5)
    """
    import time

    t0 = time.perf_counter()
    out: dict[str, Any] = {}
    longest = 0.0  # the longest attempt so far: the next is not started if it would overrun the budget

    def spent() -> bool:
        return budget_s is not None and time.perf_counter() - t0 + longest > budget_s

    for rel in _face_thresholds(problem, farkas, rel_face):
        for center, rational in ((False, False), (False, True), (True, False), (True, True), ("schur", False)):
            if out and spent():
                break
            t_try = time.perf_counter()
            left = None if budget_s is None else budget_s - (t_try - t0)
            attempt = _prove_farkas(problem, farkas, rel, keep_certificate, center, rational, left)
            longest = max(longest, time.perf_counter() - t_try)
            if attempt["face"] is not None:
                attempt["face"]["threshold"] = rel
                attempt["face"]["centered"] = center
                attempt["face"]["rational_basis"] = rational
            if not out or attempt["proven"]:
                out = attempt
            if attempt["proven"]:
                break
        if out.get("proven") or spent():
            break
    out["time_s"] = time.perf_counter() - t0
    return out


def _prove_farkas(
    problem: Problem,
    farkas: dict[str, Any],
    rel_face: float,
    keep: bool,
    center: bool | str = False,
    rational: bool = False,
    budget_s: float | None = None,
) -> dict[str, Any]:
    from fractions import Fraction

    from lmic.certify.exact import _flint, prove_psd

    flint = _flint()
    mats, y = _parse(problem, farkas)
    fail: dict[str, Any] = {"proven": False, "kind": None, "face": None, "equations": 0, "g0": None, "tau": None}
    fail["denominator_bits"] = 0
    lin = problem.linear
    ge = np.array([k == "ge" for k in lin.kinds], dtype=bool)
    strict_rows = np.asarray(lin.strict, dtype=bool) if len(y) else np.zeros(0, bool)
    eigs = [np.linalg.eigh(Z) if Z.size else (np.zeros(0), np.zeros((0, 0))) for Z in mats]
    top = max([float(np.max(w)) for w, _ in eigs if w.size] + [float(np.max(np.where(ge, y, np.abs(y)), initial=0))])
    if not top > 0:
        return dict(fail, reason="the certificate has no positive multiplier")
    thr = rel_face * top
    n = problem.n

    def q(v: float) -> Any:
        f = Fraction(float(v))
        return flint.fmpq(f.numerator, f.denominator)

    # unknowns: svec(S_i) with Z_i = W_i S_i W_i^T on every face (W_i = round(V_i 2^50), an
    # integer matrix), then y on the rows used; one column of the exact Jacobian per unknown
    columns: list[list[Any]] = []  # 1 + n fmpq per unknown: d g_k / d unknown
    u0: list[Any] = []
    blocks: list[tuple[int, np.ndarray, int]] = []  # (lmi index, W_i as python ints, r)
    ranks: list[int] = []
    sels = [w > thr for w, _ in eigs]
    rows = [r for r in range(len(y)) if (not ge[r]) or y[r] > thr]
    bases: list[np.ndarray | None] = [None] * len(eigs)
    if rational:
        # the face spanned by small-denominator rationals (module docstring); a block whose
        # face has no such basis is dropped (its multiplier set to 0): the exact check decides
        for i, ((_w, V), sel) in enumerate(zip(eigs, sels, strict=True)):
            if np.any(sel):
                bases[i] = _rational_basis(_snap(V[:, sel]))
                if bases[i] is None:
                    sels[i] = np.zeros_like(sel)
        if not any(np.any(sel) for sel in sels) and not rows:
            return dict(fail, reason="no face block has a small-denominator rational basis")
    # the float starting point: S_i = diag(w) on the face, y on the rows used
    parts = []
    for (w, _), sel in zip(eigs, sels, strict=True):
        ia, ib = np.triu_indices(int(np.sum(sel)))
        parts.append(np.where(ia == ib, w[sel][ia], 0.0))
    u0f = np.concatenate([*parts, y[rows]])
    if center and u0f.size:
        method = "schur" if center == "schur" else "dense"
        moved = _towards_center(problem, eigs, sels, rows, ge, u0f, top, method)
        if moved is None:
            return dict(fail, reason="no point inside the face's certificates was found (float centering)")
        u0f = moved
    k0 = 0
    for i, (lmi, (_w, V)) in enumerate(zip(problem.lmis, eigs, strict=True)):
        sel = sels[i]
        r = int(np.sum(sel))
        ranks.append(r)
        if not r:
            continue
        t = lmi.dim * (lmi.dim + 1) // 2
        if (1 + n) * t * r * (r + 1) // 2 > EXACT_MAX_ENTRIES:
            return dict(fail, reason=f"the face of LMI '{lmi.name}' is too large for an exact proof")
        basis = bases[i]
        if basis is None:
            W = np.rint(np.ldexp(_snap(V[:, sel]), _FACE_BITS)).astype(np.int64).astype(object)
        else:
            W = basis
        ri, ci = tril_rows_cols(lmi.dim)
        ia, ib = np.triu_indices(r)
        P, Q = W[ri], W[ci]
        # <F^(k), W E_ab W^T> over the tril storage: T[t, ab] = W[p,a] W[q,b] + W[p,b] W[q,a]
        # (halved when a == b), times the tril weight (2 off the diagonal)
        T = P[:, ia] * Q[:, ib] + P[:, ib] * Q[:, ia]
        T[:, ia == ib] //= 2
        T = T * _weights(lmi.dim).astype(np.int64).astype(object)[:, None]
        Cq = flint.fmpq_mat([[q(v) for v in row] for row in lmi.coeffs.tocsc().T.toarray()])
        Jl = (Cq * flint.fmpq_mat(T.tolist())).tolist()  # (1 + n) x r(r+1)/2
        for col in range(len(ia)):
            columns.append([Jl[k][col] for k in range(1 + n)])
        seg = u0f[k0 : k0 + len(ia)]
        if basis is None:
            # V diag(w) V^T = W (diag(w) 2^-100) W^T
            scale = flint.fmpq(1, 1 << (2 * _FACE_BITS))
            u0 += [q(float(v)) * scale for v in seg]
        else:
            # the same face matrix V S V^T in the rational basis: S_W = W^+ V S V^T W^+T
            Sv = np.zeros((r, r))
            Sv[ia, ib] = Sv[ib, ia] = seg
            U = _snap(V[:, sel])
            Wp = np.linalg.pinv(W.astype(float))
            Sw = Wp @ (U @ Sv @ U.T) @ Wp.T
            u0 += [q(float(v)) for v in Sw[ia, ib]]
        k0 += len(ia)
        blocks.append((i, W, r))
    if rows:
        A = lin.A.tocsc()
        Ad = A.toarray()
        for r in rows:
            columns.append([q(v) for v in Ad[r]])
            u0.append(q(float(u0f[k0])))
            k0 += 1
    if not columns:
        return dict(fail, reason="the certificate has an empty face")
    m = len(columns)
    if budget_s is not None and EXACT_WORK_S * n * n * m > 2.0 * max(budget_s, 0.0):
        return dict(
            fail,
            face={"ranks": ranks, "rows": len(rows)},
            reason=(
                f"the exact system on the face ({n} equations, {m} unknowns, about "
                f"{EXACT_WORK_S * n * n * m:.0f} s) does not fit the time budget of {budget_s:.1f} s"
            ),
        )
    Jall = flint.fmpq_mat([[columns[j][k] for j in range(m)] for k in range(1 + n)])
    Jx = flint.fmpq_mat([[columns[j][k] for j in range(m)] for k in range(1, 1 + n)])
    u = flint.fmpq_mat([[v] for v in u0])
    res = Jx * u
    R, rank = Jx.transpose().rref()
    if rank and any(v != 0 for v in res.entries()):
        width = R.ncols()
        flat = R.entries()
        piv = []
        for rr in range(rank):
            row = flat[rr * width : (rr + 1) * width]
            piv.append(next(c for c in range(width) if row[c] != 0))
        Ji = flint.fmpq_mat([[Jx[k, j] for j in range(m)] for k in piv])
        ri_ = flint.fmpq_mat([[res[k, 0]] for k in piv])
        u = u - Ji.transpose() * (Ji * Ji.transpose()).solve(ri_)
        if any(v != 0 for v in (Jx * u).entries()):
            return dict(
                fail,
                face={"ranks": ranks, "rows": len(rows)},
                equations=rank,
                reason="the trace conditions are inconsistent on the face in exact arithmetic",
            )
    uv = u.entries()
    face = {"ranks": ranks, "rows": len(rows)}
    # exact signs: every S_i PSD, y >= 0 on ge rows
    k = 0
    exact_lmis: list[Any] = [[[Fraction(0)] * lmi.dim for _ in range(lmi.dim)] for lmi in problem.lmis]
    trace_strict = Fraction(0)
    trace_all = Fraction(0)
    den_bits = 0
    for i, W, r in blocks:
        ia, ib = np.triu_indices(r)
        S = [[Fraction(0)] * r for _ in range(r)]
        for a, b in zip(ia, ib, strict=True):
            v = uv[k]
            S[a][b] = S[b][a] = Fraction(int(v.p), int(v.q))
            k += 1
        den = 1
        for row in S:
            for f in row:
                den = den * f.denominator // math.gcd(den, f.denominator)
        den_bits = max(den_bits, den.bit_length())
        Sint = [[int(f * den) for f in row] for row in S]
        pr = prove_psd(Sint)
        if not pr["proven"]:
            return dict(
                fail,
                face=face,
                equations=rank,
                reason=f"the exact multiplier of LMI '{problem.lmis[i].name}' is not proved PSD ({pr['detail']})",
            )
        if keep:
            Sm = np.array(S, dtype=object)
            exact_lmis[i] = (W @ Sm @ W.T).tolist()
        G = W.T @ W  # tr(Z_i) = tr(S W^T W)
        tr = sum((S[a][b] * int(G[b][a]) for a in range(r) for b in range(r)), Fraction(0))
        trace_all += tr
        if problem.lmis[i].strict:
            trace_strict += tr
    yv = {}
    for r in rows:
        v = uv[k]
        yv[r] = Fraction(int(v.p), int(v.q))
        den_bits = max(den_bits, int(v.q).bit_length())
        k += 1
        if ge[r] and yv[r] < 0:
            return dict(
                fail, face=face, equations=rank, reason=f"the exact multiplier of row '{lin.names[r]}' is negative"
            )
    g0v = (Jall * u)[0, 0]
    g0 = Fraction(int(g0v.p), int(g0v.q))
    tau = trace_strict + sum((yv[r] for r in rows if ge[r] and strict_rows[r]), Fraction(0))
    eta = trace_all + sum((abs(v) for v in yv.values()), Fraction(0))
    base: dict[str, Any] = {"face": face, "equations": rank, "denominator_bits": den_bits}
    if keep:
        base["exact_certificate"] = {
            "lmis": exact_lmis,
            "linear": [yv.get(r, Fraction(0)) for r in range(len(y))],
        }
    base["g0"] = float(g0 / eta) if eta else None
    base["tau"] = float(tau / eta) if eta else None
    exactly = "exact Farkas certificate: g_k = 0 exactly (k >= 1), multipliers proved PSD"
    if g0 < 0:
        reason = f"{exactly}, g_0 = {base['g0']:.3g} < 0 (even the closed problem is infeasible)"
        return dict(base, proven=True, kind="closed", reason=reason)
    if g0 <= 0 and tau > 0:
        reason = f"{exactly}, g_0 = 0 and tau = {base['tau']:.3g} > 0 (the strict problem is infeasible)"
        return dict(base, proven=True, kind="strict", reason=reason)
    return dict(base, proven=False, kind=None, reason=f"no exact separation: g_0 = {float(g0):.3g}")


def farkas_candidates(
    problem: Problem, farkas: dict[str, Any], verification: dict[str, Any]
) -> list[tuple[str, dict[str, Any]]]:
    """The certificates an exact proof of infeasibility starts from, in order, as
    ``(source, {"lmis", "linear"})``: the repaired certificate (when :func:`verify_farkas`
    repaired one), then the solver's in the orientation that verified (both when none did).

    >>> import numpy as np, scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
    >>> p = Problem([Variable("p", "scalar", (1, 1))], [LMI("p > 0", 1, sp.csc_matrix([[0., 1.]]))],
    ...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
    >>> [(s, float(c["lmis"][0][0, 0])) for s, c in farkas_candidates(p, {"lmis": [np.eye(1)]}, {})]
    [('solver', 1.0), ('solver', -1.0)]
    """
    mats, y = _parse(problem, farkas)
    out: list[tuple[str, dict[str, Any]]] = []
    if verification.get("repaired") and verification.get("certificate"):
        out.append(("repaired", verification["certificate"]))
    signs = [-1.0 if verification.get("negated") else 1.0] if verification.get("verified") else [1.0, -1.0]
    out += [("solver", {"lmis": [sg * Z for Z in mats], "linear": sg * y}) for sg in signs]
    return out


def prove_infeasible(
    problem: Problem,
    farkas: dict[str, Any],
    verification: dict[str, Any],
    rel_face: tuple[float, ...] | None = None,
    budget_s: float | None = None,
) -> dict[str, Any]:
    """The exact proof :func:`lmic.certify.certify` runs for an ``infeasible`` answer.

    Tries the repaired certificate (when :func:`verify_farkas` repaired one), then the
    solver's certificate in the orientation that verified (or both when none did). ``rel_face``
    (default: :func:`prove_farkas`'s) limits the face thresholds tried (each try costs seconds on
    problems with a few dozen variables). ``budget_s`` is shared by the candidates: none starts
    after it has run out (the first always runs), and none runs a further face or method.

    Returns
    -------
    dict
        :func:`prove_farkas`'s result (the first proof, or the first failure), with
        ``source`` (``"repaired"`` or ``"solver"``) and the ``denominator`` the certificate
        schema asks for.

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
    >>> p = Problem([Variable("p", "scalar", (1, 1))],
    ...             [LMI("p > 0", 1, sp.csc_matrix([[0., 1.]])),
    ...              LMI("-p > 0", 1, sp.csc_matrix([[0., -1.]]))],
    ...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
    >>> from lmic.certify.farkas_ray import verify_farkas
    >>> f = {"lmis": [np.eye(1), np.eye(1)]}
    >>> r = prove_infeasible(p, f, verify_farkas(p, f))
    >>> r["proven"], r["kind"], r["source"]
    (True, 'strict', 'solver')
    """
    import time

    t0 = time.perf_counter()
    out: dict[str, Any] = {}
    for source, cand in farkas_candidates(problem, farkas, verification):
        left = None if budget_s is None else budget_s - (time.perf_counter() - t0)
        if out and left is not None and left <= 0:
            break  # one budget for every candidate: the first is always tried
        kw: dict[str, Any] = {"budget_s": left} if rel_face is None else {"rel_face": rel_face, "budget_s": left}
        r = prove_farkas(problem, cand, **kw)
        r["source"] = source
        if not out or r["proven"]:
            out = r
        if r["proven"]:
            break
    out["denominator"] = "rational" if out["proven"] else "-"  # sizes in denominator_bits
    return out
