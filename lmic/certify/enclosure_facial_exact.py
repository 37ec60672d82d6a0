"""The exact algebra of facial reduction (:mod:`lmic.certify.enclosure_facial`): exposing
certificates verified in rational arithmetic, the reduced problem and its lineality.

Everything here is exact (python-flint integers, python fractions; the IR's float coefficients
are dyadic rationals): :func:`exact_step` turns the solver's exposing direction into an exact
certificate, :func:`verify_step` checks one, :func:`reduce_problem` builds the reduced problem
(``V_i^T F_i(x) V_i >= 0``, the rows with ``a_r . d > 0`` removed) and fixes the variables
along its exact lineality space (:func:`lineality`, :func:`fix_lineality`: after a reduction
the exposing direction itself changes nothing in the reduced problem, so its dual equality
rows are dependent; fixing ``x_P = 0`` on a complement of that space keeps the optimal value
and makes them independent).

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
>>> # inf x1 s.t. [[x1, 1], [1, x2]] >= 0 is 0 (not attained); every dual Z is [[1, 0], [0, 0]]
>>> C = sp.csc_matrix(np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]))
>>> p = Problem([Variable("x", "full", (2, 1))], [LMI("M", 2, C, strict=False)],
...             LinearConstraints.empty(2), Objective("min", [0.0, 1.0, 0.0]))
>>> st = exact_step(p, np.array([1e-12, 1.0]))  # the solver's d ~ (0, 1): W = [[0, 0], [0, 1]]
>>> st["ok"], st["d"], st["V"][0]
(True, ['0', '1'], [['1'], ['0']])
>>> red = reduce_v(p, st)  # x1 >= 0
>>> [lmi.dim for lmi in red.lmis], red.lmis[0].coeffs.toarray().tolist()
([1], [[0.0, 1.0, 0.0]])
"""

from __future__ import annotations

import dataclasses
import math
from fractions import Fraction
from typing import Any

import numpy as np
import scipy.sparse as sp

from lmic.certify.enclosure_facial_int import (
    EXACT_INT,
    _block_exact,
    _dyadic,
    _exact_int_rows,
    _exact_product,
    _exact_rows_block,
    _fr,
    _int_rows,
    _int_scaled,
    _is_zero_product,
    _nullspace_int,
    _pivots,
    _primitive,
    _short,
)
from lmic.certify.enclosure_repair import _target
from lmic.errors import CertificateError
from lmic.ir.problem import LMI, LinearConstraints, Problem
from lmic.ir.svec import tril_rows_cols, tril_unvec

__all__ = [
    "NULL_TOL",
    "DENOMINATORS",
    "exact_step",
    "verify_step",
    "reduce_problem",
    "reduce_v",
    "lineality",
    "fix_lineality",
    "scale_exponents",
    "scale_variables",
]

#: an eigenvalue of ``W_i`` below this times its largest is read as zero (the null space)
NULL_TOL = 1e-6
#: the float pre-test of :func:`exact_step`: a smallest singular value of the (row-normalised)
#: system ``W(d) B = 0`` above this times the largest means no exact solution but ``d = 0``
PRETEST = 1e-13
#: denominators tried when rationalising the null space basis (smallest first)
DENOMINATORS = (64, 10_000, 1_000_000)


def verify_step(problem: Problem, step: dict[str, Any]) -> dict[str, Any]:
    """Verify one exposing certificate exactly (module docstring, step 2).

    ``step``: ``d`` (integers, decimal strings), ``V`` (per LMI an integer ``dim x r`` basis, as
    lists of decimal strings), ``drop`` (indices of the ``ge`` rows with ``a_r . d > 0``).
    Returns ``ok`` and ``reason``.

    >>> import numpy as np, scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> C = sp.csc_matrix(np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]))
    >>> p = Problem([Variable("x", "full", (2, 1))], [LMI("M", 2, C, strict=False)],
    ...             LinearConstraints.empty(2), Objective("min", [0.0, 1.0, 0.0]))
    >>> good = {"d": ["0", "1"], "V": [[["1"], ["0"]]], "drop": []}
    >>> verify_step(p, good)["ok"], verify_step(p, dict(good, d=["1", "1"]))["ok"]
    (True, False)
    """
    from lmic.certify.psd import prove_pd

    try:
        d = [int(v) for v in step["d"]]
        Vs = [[[int(v) for v in row] for row in V] for V in step["V"]]
        drop = sorted({int(r) for r in step.get("drop", [])})
    except (KeyError, TypeError, ValueError) as exc:
        return {"ok": False, "reason": f"unusable exposing certificate: {exc}"}
    n = problem.n
    if len(d) != n or len(Vs) != len(problem.lmis):
        return {"ok": False, "reason": "the exposing certificate does not match the problem's size"}
    _, q = _target(problem)
    if sum((_fr(q[k + 1]) * d[k] for k in range(n)), Fraction(0)) != 0:
        return {"ok": False, "reason": "q . d is not exactly 0"}
    A = sp.csr_matrix(problem.linear.A) if len(problem.linear) else None
    nonzero = False
    for r, kind in enumerate(problem.linear.kinds):
        assert A is not None
        lo, hi = A.indptr[r], A.indptr[r + 1]
        s = sum((_fr(v) * d[c - 1] for c, v in zip(A.indices[lo:hi], A.data[lo:hi], strict=True) if c), Fraction(0))
        if (kind == "eq" and s != 0) or (kind == "ge" and s < 0) or ((r in drop) != (s > 0)):
            return {"ok": False, "reason": f"row '{problem.linear.names[r]}': a . d = {s} breaks the certificate"}
        nonzero = nonzero or s > 0
    for lmi, V in zip(problem.lmis, Vs, strict=True):
        W = _block_exact(lmi, d)
        dim = lmi.dim
        if len(V) != dim or any(len(row) != (len(V[0]) if V else 0) for row in V):
            return {"ok": False, "reason": f"V of '{lmi.name}' has the wrong shape"}
        r = len(V[0]) if V else 0
        piv = _pivots(V) if r else []
        if piv is None:
            return {"ok": False, "reason": f"V of '{lmi.name}' is rank deficient"}
        for a in range(dim):
            for c in range(r):
                if sum((W[a][b] * V[b][c] for b in range(dim) if V[b][c]), Fraction(0)) != 0:
                    return {"ok": False, "reason": f"W V != 0 on '{lmi.name}'"}
        rest = [a for a in range(dim) if a not in set(piv)]
        if rest:
            # one common scale for the whole block (row scaling alone would break symmetry)
            den = 1
            for a in rest:
                for b in rest:
                    den = den * W[a][b].denominator // math.gcd(den, W[a][b].denominator)
            sub = [[int(W[a][b] * den) for b in rest] for a in rest]
            pr = prove_pd(sub)
            if not pr["proven"]:
                return {"ok": False, "reason": f"W of '{lmi.name}' is not proved PSD with null space span V"}
            nonzero = True
    if not nonzero:
        return {"ok": False, "reason": "the exposing certificate is zero"}
    return {"ok": True, "reason": "exposing certificate verified exactly"}


def _rational_basis(N: np.ndarray, den: int) -> tuple[list[list[Fraction]], list[int]] | None:
    """``N`` (``dim x r``, a numerical null space basis) as ``N N[P]^-1`` (the identity on the
    pivot rows ``P``), entries rounded to fractions of denominator at most ``den``."""
    import scipy.linalg as sla

    dim, r = N.shape
    _, _, piv = sla.qr(N.T, pivoting=True)
    P = sorted(int(p) for p in piv[:r])
    B = N @ np.linalg.inv(N[P])
    out = [[Fraction(0)] * r for _ in range(dim)]
    for a in range(dim):
        for c in range(r):
            f = Fraction(float(B[a, c])).limit_denominator(den)
            if abs(float(f) - B[a, c]) > 1e-5 * max(1.0, abs(B[a, c])):
                return None
            out[a][c] = f
    for c, p in enumerate(P):
        for a in P:
            out[a][c] = Fraction(int(a == p))
    return out, P


def exact_step(problem: Problem, d_float: np.ndarray) -> dict[str, Any]:
    """An exact exposing certificate near the solver's direction ``d_float`` (step 1 of the
    module docstring), verified by :func:`verify_step`. Returns ``ok``, ``reason`` and, when
    ``ok``, ``d``, ``V`` and ``drop`` (the record of :func:`verify_step`)."""
    from lmic.certify.psd import load_flint

    flint = load_flint()
    n = problem.n
    dfl = np.asarray(d_float, dtype=float).ravel()
    if dfl.size != n:
        return {"ok": False, "reason": f"the exposing direction has {dfl.size} entries, not {n}"}
    _, q = _target(problem)
    scale = float(np.max(np.abs(dfl), initial=0.0))
    if not scale > 0 or not np.all(np.isfinite(dfl)):
        return {"ok": False, "reason": "the exposing direction is zero or not finite"}
    dfl = dfl / scale
    last = "no exact exposing direction found"
    spectra = []
    for lmi in problem.lmis:
        W = tril_unvec(np.asarray(sp.csc_matrix(lmi.coeffs)[:, 1:] @ dfl).ravel(), lmi.dim)
        spectra.append(np.linalg.eigh(0.5 * (W + W.T)))
    # one scale for every block: a block whose W is round-off only is all null space
    top = max([float(np.max(np.abs(w), initial=0.0)) for w, _ in spectra] + [0.0])
    for den in DENOMINATORS:
        eqs: list[list[int]] = []
        bases: list[tuple[list[list[Fraction]], list[int]]] = []
        ok = True
        for lmi, (w, U) in zip(problem.lmis, spectra, strict=True):
            C = sp.csc_matrix(lmi.coeffs)
            null = w <= NULL_TOL * top if top > 0 else np.ones(lmi.dim, bool)
            if not null.any():
                bases.append(([], []))
                continue
            rb = _rational_basis(U[:, null], den)
            if rb is None:
                ok = False
                last = f"the null space of W[{lmi.name}] has no basis of denominators <= {den}"
                break
            bases.append(rb)
        if not ok:
            continue
        # float pre-test: the system W(d) B_i = 0 (with q . d = 0) must have a non-trivial null
        # space, else the exact one is trivial too (an irrational face): skip the exact work
        fl_rows = [np.asarray(q[1:], dtype=float)[None, :]]
        for lmi, (B, _P) in zip(problem.lmis, bases, strict=True):
            if B:
                Bf = np.array([[float(f) for f in row] for row in B])
                Ck = sp.csc_matrix(lmi.coeffs)[:, 1:].toarray()
                Fk = np.stack([tril_unvec(Ck[:, k], lmi.dim) for k in range(n)])
                fl_rows.append(np.einsum("kab,bc->ack", Fk, Bf).reshape(-1, n))
        Ef = np.vstack(fl_rows)
        Ef = Ef[np.linalg.norm(Ef, axis=1) > 0]
        if Ef.size and min(Ef.shape) == n:
            Ef = Ef / np.linalg.norm(Ef, axis=1)[:, None]
            sv = np.linalg.svd(Ef, compute_uv=False)
            if sv[-1] > PRETEST * sv[0]:
                last = (
                    f"the solver's face has no rational description with denominators <= {den}: with its null "
                    f"spaces rounded so, W(d) V = 0 and q . d = 0 leave only d = 0 (smallest singular value "
                    f"{sv[-1] / sv[0]:.2g}; an irrational face, e.g. spanned by eigenvectors of floating-point "
                    "data, has no exposing certificate in rational arithmetic: a lower end then needs algebraic "
                    "arithmetic, or a bound on ||x|| (the conditional bound))"
                )
                continue
        for lmi, (B, _P) in zip(problem.lmis, bases, strict=True):
            if not B:
                continue
            C = sp.csc_matrix(lmi.coeffs)
            r = len(B[0])
            Bi = _int_rows([list(col) for col in zip(*B, strict=True)])  # columns scaled to integers
            Bm = flint.fmpz_mat(lmi.dim, r, [Bi[c][a] for a in range(lmi.dim) for c in range(r)])
            # (W(d) B)[a, c] = sum_k d_k (F^(k) B)[a, c] = 0: in floats where provably exact
            fast = (
                _exact_rows_block(C, np.array(Bi, dtype=float).T, lmi.dim, n)
                if max(abs(v) for col in Bi for v in col) < EXACT_INT
                else None
            )
            if fast is not None:
                eqs += [row for row in fast if any(row)]
                continue
            # every column k scaled by 2^(E - e_k), in flint
            prods = {}
            for k in range(n):
                if C[:, 1 + k].nnz:
                    Fi, e = _dyadic(C[:, 1 + k].toarray().ravel(), lmi.dim)
                    prods[k] = (Fi * Bm, e)
            E = max((e for _, e in prods.values()), default=0)
            for a in range(lmi.dim):
                for c in range(r):
                    row = [0] * n
                    for k, (Mk, e) in prods.items():
                        row[k] = int(Mk[a, c]) << (E - e)
                    if any(row):
                        eqs.append(row)
        eqs += _int_rows([[_fr(v) for v in q[1:]]])
        A = sp.csr_matrix(problem.linear.A) if len(problem.linear) else None
        for r, kind in enumerate(problem.linear.kinds):
            assert A is not None
            a = A[r].toarray().ravel()[1:]
            if kind == "eq" or abs(float(a @ dfl)) <= NULL_TOL * max(1.0, float(np.abs(a).sum())):
                eqs += _int_rows([[_fr(v) for v in a]])
        basis = _nullspace_int(eqs, n)
        if not basis:
            last = (
                f"the solver's face has no rational description with denominators <= {den}: with its null "
                "spaces rounded so, W(d) V = 0 and q . d = 0 leave only d = 0 (an irrational face, e.g. spanned "
                "by eigenvectors of floating-point data, has no exposing certificate in rational arithmetic: a "
                "lower end then needs algebraic arithmetic, or a bound on ||x|| (the conditional bound))"
            )
            continue
        # columns scaled by 2^-s_j (their integers may exceed the float range)
        shifts = [max(0, max(abs(v).bit_length() for v in col) - 60) for col in basis]
        X = np.array([[float(Fraction(v, 1 << s_)) for v in col] for col, s_ in zip(basis, shifts, strict=True)]).T
        norms = np.linalg.norm(X, axis=0)
        alpha = np.linalg.lstsq(X / norms, dfl, rcond=None)[0] / norms
        al = [Fraction(float(v)) / (1 << s_) for v, s_ in zip(alpha, shifts, strict=True)]
        dq = [sum((al[j] * basis[j][k] for j in range(len(basis))), Fraction(0)) for k in range(n)]
        L = math.lcm(*(f.denominator for f in dq))
        dint = _primitive([int(f * L) for f in dq])
        Vs: list[list[list[str]]] = []
        for (B, _P), lmi in zip(bases, problem.lmis, strict=True):
            if not B:
                Vs.append([[] for _ in range(lmi.dim)] if lmi.dim else [])
                continue
            Bi = _short(_int_rows([list(col) for col in zip(*B, strict=True)]))  # integer columns, LLL
            Vs.append([[str(Bi[c][a]) for c in range(len(Bi))] for a in range(lmi.dim)])
        step = _verified_step(problem, dint, Vs)
        if step["ok"]:
            return step
        last = f"denominators <= {den}: {step['reason']}"
    direct = _direction_step(problem, dfl)  # the direction rounded, its null spaces exact
    if direct.get("ok"):
        return direct
    return {"ok": False, "reason": f"{last}; {direct['reason']}"}


def _direction_step(problem: Problem, dfl: np.ndarray) -> dict[str, Any]:
    """An exposing certificate from the solver's direction ``dfl`` (largest entry 1) rounded
    to fractions of denominator at most each of :data:`DENOMINATORS` (entries below
    :data:`NULL_TOL` to zero), with the null spaces of the exact ``W_i(d)`` computed exactly:
    a face whose null spaces need larger denominators than the rounding of
    :func:`exact_step` allows (a congruence by an integer matrix with entries ``~1e6``) is
    exposed by a short direction all the same. Verified by :func:`verify_step`.

    >>> import numpy as np, scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> # inf x1 s.t. R^T [[x1, 1], [1, x2]] R >= 0 with R = [[1234567, -7654321], [7654321, 1234567]]
    >>> R = np.array([[1234567.0, -7654321.0], [7654321.0, 1234567.0]])
    >>> mats = [np.array([[0.0, 1.0], [1.0, 0.0]]), np.diag([1.0, 0.0]), np.diag([0.0, 1.0])]
    >>> C = sp.csc_matrix(np.column_stack([(R.T @ M @ R)[[0, 1, 1], [0, 0, 1]] for M in mats]))
    >>> p = Problem([Variable("x", "full", (2, 1))], [LMI("M", 2, C, strict=False)],
    ...             LinearConstraints.empty(2), Objective("min", [0.0, 1.0, 0.0]))
    >>> st = _direction_step(p, np.array([3e-13, 1.0]))
    >>> st["ok"], st["d"], st["V"][0]
    (True, ['0', '1'], [['1234567'], ['-7654321']])
    """
    last = "the rounded direction exposes no face"
    tried: set[tuple[Fraction, ...]] = set()
    for den in DENOMINATORS:
        dq = tuple(Fraction(float(v)).limit_denominator(den) if abs(v) > NULL_TOL else Fraction(0) for v in dfl)
        if dq in tried or not any(dq):
            continue
        tried.add(dq)
        dint = _primitive(_int_rows([list(dq)])[0])
        Vs: list[list[list[str]]] = []
        for lmi in problem.lmis:
            W = _block_exact(lmi, dint)
            basis = _nullspace_int(_int_rows(W), lmi.dim) if lmi.dim else []
            basis = _short(basis) if basis else []
            Vs.append([[str(col[a]) for col in basis] for a in range(lmi.dim)])
        step = _verified_step(problem, dint, Vs)
        if step["ok"]:
            return step
        last = f"the direction rounded to denominators <= {den} (its null spaces exact): {step['reason']}"
    return {"ok": False, "reason": last}


def _verified_step(problem: Problem, dint: list[int], Vs: list[list[list[str]]]) -> dict[str, Any]:
    """The step of the integer direction ``dint`` and the null-space bases ``Vs``, with the
    ``ge`` rows it makes slack (``a . d > 0``: dropped), checked by :func:`verify_step`: the
    step with ``ok`` and the check's ``reason``."""
    drop = []
    if len(problem.linear):
        Af = sp.csr_matrix(problem.linear.A)
        for r, kind in enumerate(problem.linear.kinds):
            lo, hi = Af.indptr[r], Af.indptr[r + 1]
            pairs = zip(Af.indices[lo:hi], Af.data[lo:hi], strict=True)
            if kind == "ge" and sum((_fr(v) * dint[c - 1] for c, v in pairs if c), Fraction(0)) > 0:
                drop.append(r)
    step: dict[str, Any] = {"d": [str(v) for v in dint], "V": Vs, "drop": drop}
    chk = verify_step(problem, step)
    return dict(step, ok=bool(chk["ok"]), reason=chk["reason"])


def reduce_problem(problem: Problem, step: dict[str, Any]) -> Problem:
    """The reduced problem of a verified step (module docstring, step 3): LMIs ``V_i^T F_i(x)
    V_i >= 0``, the rows of ``step["drop"]`` removed, and the variables ``x_p = 0`` (``p`` in
    ``step["fix"]``) fixed along its lineality directions ``step["lineality"]`` (checked exactly:
    :func:`fix_lineality`). Raises :class:`CertificateError` when a reduced coefficient is not
    exactly a float or a lineality direction does not hold.

    >>> import numpy as np, scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> C = sp.csc_matrix(np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]))
    >>> p = Problem([Variable("x", "full", (2, 1))], [LMI("M", 2, C, strict=False)],
    ...             LinearConstraints.empty(2), Objective("min", [0.0, 1.0, 0.0]))
    >>> r = reduce_problem(p, {"d": ["0", "1"], "V": [[["1"], ["0"]]], "drop": [], "lineality": [["0", "1"]],
    ...                        "fix": [1]})
    >>> r.linear.A.toarray().tolist(), r.linear.kinds
    ([[0.0, 0.0, 1.0]], ['eq'])
    """
    red = reduce_v(problem, step)
    return fix_lineality(red, step.get("lineality", []), step.get("fix", []))


def lineality(problem: Problem) -> tuple[list[list[str]], list[int]]:
    """An exact integer basis ``l_j`` of the lineality space ``{d : F_i^(k)-combination 0 on
    every LMI, a_r . d = 0 on every row, q . d = 0}`` (moving ``x`` along it changes nothing) and
    variables ``P`` with ``[l_j]_P`` invertible: fixing ``x_P = 0`` loses no value.

    >>> import numpy as np, scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("x", "full", (2, 1))], [LMI("M", 1, sp.csc_matrix([[0.0, 1.0, 0.0]]), strict=False)],
    ...             LinearConstraints.empty(2), Objective("min", [0.0, 1.0, 0.0]))
    >>> basis, fix = lineality(p)
    >>> [abs(int(v)) for v in basis[0]], fix
    ([0, 1], [1])
    """
    from lmic.certify.psd import load_flint

    flint = load_flint()
    n = problem.n
    A = sp.csr_matrix(problem.linear.A) if len(problem.linear) else sp.csr_matrix((0, 1 + n))
    _, q = _target(problem)
    mats = [sp.csr_matrix(lmi.coeffs)[:, 1:] for lmi in problem.lmis] + [A[:, 1:], sp.csr_matrix(q[None, 1:])]
    M = sp.vstack(mats).toarray() if mats else np.zeros((0, n))
    rows = _exact_int_rows(M[np.any(M != 0, axis=1)])
    if rows:
        X, nullity = flint.fmpz_mat(len(rows), n, [v for r in rows for v in r]).nullspace()
        basis = [_primitive([int(X[i, j]) for i in range(n)]) for j in range(int(nullity))]
    else:
        basis = [[int(i == j) for i in range(n)] for j in range(n)]
    if not basis:
        return [], []
    piv = _pivots([list(r) for r in zip(*basis, strict=True)])
    assert piv is not None  # a nullspace basis has full rank
    return [[str(v) for v in b] for b in basis], piv


def fix_lineality(problem: Problem, basis: list[list[str]], fix: list[int]) -> Problem:
    """``problem`` with rows ``x_p = 0`` (``p`` in ``fix``), after checking exactly that every
    ``l`` of ``basis`` is a lineality direction (changes no LMI, row or objective) and that
    ``[l_j]_fix`` is invertible, so that every ``x`` has a point with ``x_fix = 0`` of the same
    constraint values and objective: the optimal value is unchanged.

    >>> import numpy as np, scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("x", "full", (2, 1))], [LMI("M", 1, sp.csc_matrix([[0.0, 1.0, 0.0]]), strict=False)],
    ...             LinearConstraints.empty(2), Objective("min", [0.0, 1.0, 0.0]))
    >>> fix_lineality(p, [["0", "1"]], [1]).linear.kinds
    ['eq']
    >>> fix_lineality(p, [["1", "1"]], [1])
    Traceback (most recent call last):
    lmic.errors.CertificateError: a lineality direction is not exact
    """
    n = problem.n
    try:
        L = [[int(v) for v in b] for b in basis]
        P = [int(p) for p in fix]
    except (TypeError, ValueError) as exc:
        raise CertificateError(f"unusable lineality record: {exc}") from exc
    if len(L) != len(P) or any(len(b) != n for b in L) or any(not 0 <= p < n for p in P) or len(set(P)) != len(P):
        raise CertificateError("the lineality record does not match the problem")
    if not L:
        return problem
    _, q = _target(problem)
    A = sp.csr_matrix(problem.linear.A) if len(problem.linear) else sp.csr_matrix((0, 1 + n))
    mats = [sp.csr_matrix(lmi.coeffs) for lmi in problem.lmis] + [A]
    if max(abs(v) for ell in L for v in ell) >= EXACT_INT:
        raise CertificateError("the lineality record's integers are too large")
    Lf = np.array(L, dtype=float).T
    for M in mats:
        if not _is_zero_product(M[:, 1:].toarray(), Lf):
            raise CertificateError("a lineality direction is not exact")
    if not _is_zero_product(np.asarray(q[1:], dtype=float)[None, :], Lf):
        raise CertificateError("a lineality direction is not exact")
    from lmic.certify.psd import load_flint

    flint = load_flint()
    if flint.fmpz_mat(len(P), len(P), [L[j][p] for p in P for j in range(len(L))]).det() == 0:
        raise CertificateError("the fixed variables do not complement the lineality space")
    rows = sp.csr_matrix(([1.0] * len(P), (list(range(len(P))), [1 + p for p in P])), shape=(len(P), 1 + n))
    lin = problem.linear
    new = LinearConstraints(
        sp.vstack([A, rows]).tocsr(),
        list(lin.kinds) + ["eq"] * len(P),
        list(lin.strict) + [False] * len(P),
        list(lin.names) + [f"x[{p}] = 0 (lineality)" for p in P],
    )
    return dataclasses.replace(problem, linear=new)


def reduce_v(problem: Problem, step: dict[str, Any]) -> Problem:
    """:func:`reduce_problem` without the lineality rows."""
    from lmic.certify.psd import load_flint

    flint = load_flint()
    n = problem.n
    lmis = []
    for lmi, Vraw in zip(problem.lmis, step["V"], strict=True):
        V = [[int(v) for v in row] for row in Vraw]
        r = len(V[0]) if V else 0
        if r == 0:
            continue
        Vm = flint.fmpz_mat(lmi.dim, r, [v for row in V for v in row])
        Vf = np.array(V, dtype=float) if max(abs(v) for row in V for v in row) < EXACT_INT else None
        C = sp.csc_matrix(lmi.coeffs)
        ri, ci = tril_rows_cols(r)
        vals, rows_, cols_ = [], [], []
        for k in range(1 + n):
            col = C[:, k]
            if not col.nnz:
                continue
            N, e = _int_scaled(tril_unvec(col.toarray().ravel(), lmi.dim))
            R = _exact_product(Vf.T, N, Vf) if Vf is not None else None
            if R is not None:
                Rt = R[ri, ci]
                nz = np.flatnonzero(Rt)
                fl = np.ldexp(Rt[nz], -e)
                if np.any(np.ldexp(fl, e) != Rt[nz]):
                    raise CertificateError(f"the reduced coefficient of '{lmi.name}' is not exactly a float")
                vals += fl.tolist()
                rows_ += nz.tolist()
                cols_ += [k] * nz.size
                continue
            Fi = flint.fmpz_mat(lmi.dim, lmi.dim, [int(v) for v in N.ravel().tolist()])
            Rm = Vm.transpose() * Fi * Vm
            for t in range(ri.size):
                m = int(Rm[int(ri[t]), int(ci[t])])
                if m:
                    f = Fraction(m, 1 << e)
                    fv = float(f)
                    if Fraction(fv) != f:
                        raise CertificateError(f"the reduced coefficient of '{lmi.name}' is not exactly a float")
                    vals.append(fv)
                    rows_.append(t)
                    cols_.append(k)
        coeffs = sp.csc_matrix((vals, (rows_, cols_)), shape=(ri.size, 1 + n))
        lmis.append(LMI(f"V^T {lmi.name} V", r, coeffs, strict=lmi.strict, relation=lmi.relation))
    drop = set(int(r) for r in step.get("drop", []))
    keep = [r for r in range(len(problem.linear)) if r not in drop]
    lin = problem.linear
    if len(lin):
        A = sp.csr_matrix(lin.A)[keep] if keep else sp.csr_matrix((0, 1 + n))
        lin = LinearConstraints(
            A, [lin.kinds[r] for r in keep], [lin.strict[r] for r in keep], [lin.names[r] for r in keep]
        )
    return dataclasses.replace(problem, lmis=lmis, linear=lin)


def scale_exponents(problem: Problem) -> list[int]:
    """Power-of-two exponents ``e_k`` that equilibrate the rows of the dual equality map (row
    ``k``: every coefficient of ``x_k``): :func:`scale_variables` with them makes the proof's
    ``J_S J_S^T`` well conditioned (the exact correction it defines does not change).

    >>> import numpy as np, scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
    >>> p = Problem([Variable("x", "full", (2, 1))],
    ...             [LMI("M", 1, sp.csc_matrix([[0.0, 1024.0, 0.25]]), strict=False)],
    ...             LinearConstraints.empty(2), Objective("min", [0.0, 1.0, 1.0]))
    >>> scale_exponents(p)
    [-10, 2]
    """
    from lmic.certify.enclosure_repair import jacobian

    J, _ = jacobian(problem)
    norms = sp.linalg.norm(J[1:], axis=1) if J.shape[1] else np.zeros(problem.n)
    return [0 if not v > 0 else -round(math.log2(float(v))) for v in np.asarray(norms).ravel()]


def scale_variables(problem: Problem, exps: list[int]) -> Problem:
    """The same problem in ``x_k = 2^e_k x'_k``: column ``1 + k`` of every coefficient and of
    the objective times ``2^e_k`` (exact; a :class:`CertificateError` when a scaled coefficient
    under- or overflows). Its optimal value is the original's (a bijection of the points)."""
    import dataclasses

    n = problem.n
    if len(exps) != n or any(not isinstance(e, int) or abs(e) > 200 for e in exps):
        raise CertificateError("the variable scaling does not match the problem")
    f = np.ldexp(1.0, np.array([0] + list(exps)))
    D = sp.diags(f)

    def scaled(M: sp.spmatrix) -> sp.csc_matrix:
        out = sp.csc_matrix(M @ D)
        back = sp.csc_matrix(out @ sp.diags(1.0 / f))
        if abs(back - sp.csc_matrix(M)).max() != 0 or not np.all(np.isfinite(out.data)):
            raise CertificateError("a scaled coefficient is not exact")
        return out

    lmis = [dataclasses.replace(lmi, coeffs=scaled(lmi.coeffs)) for lmi in problem.lmis]
    lin = problem.linear
    if len(lin):
        lin = LinearConstraints(sp.csr_matrix(scaled(lin.A)), list(lin.kinds), list(lin.strict), list(lin.names))
    c = np.asarray(problem.objective.c, dtype=float) * f
    if np.any(c / f != problem.objective.c):
        raise CertificateError("a scaled objective coefficient is not exact")
    return dataclasses.replace(problem, lmis=lmis, linear=lin, objective=dataclasses.replace(problem.objective, c=c))
