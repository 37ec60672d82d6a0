"""Exact proofs: every LMI positive (semi)definite at a rational point, without float doubt.

What is proved
--------------
The IR stores its coefficients as float64 numbers; every float is a dyadic rational, so the
LMI ``F(x) = F0 + sum_k x_k F_k`` the IR denotes has exact rational coefficients. The solver's
float point is dyadic too: ``x = N / 2^K_x`` exactly, ``K_x`` the bits below the binary point
of its finest entry. The proof is made at a rational point ``x_q = N / D`` (one common
denominator ``D``), which is *recorded* (``point``: ``den`` and ``num`` as decimal strings):

1. first ``x_q = x`` itself (``D = 2^K_x``; ``at_x`` is true): no rounding, so the certified
   point *is* the solver's point, and the gains derived from ``x`` are those of the certified
   point. This costs no more than a coarse rounding (size 180: ~0.7 s either way);
2. if that fails (or ``K_x`` exceeds :data:`FULL_BITS_MAX`, e.g. subnormal entries), ``x`` is
   rounded to the coarser grid ``2^-K`` with ``K`` chosen from the float margins so that the
   rounding cannot destroy them (``at_x`` false; ``distance = max |x_q - x|`` is reported).

``F(x_q)`` is built exactly: scaled by ``2^(K - e)`` it is an integer matrix ``M`` (python ints,
a :class:`flint.fmpz_mat`).

When the IR has equality rows the point is projected exactly onto them
(``x_q - A^T (A A^T)^-1 (A x_q + a0)`` in rational arithmetic, python-flint ``fmpq_mat``, over
a maximal independent subset of the rows when they are rank deficient); the common
denominator ``D`` is then no longer a power of two, and ``x_q != x``. An equality row that is
still not exactly zero at ``x_q`` (rows inconsistent in exact arithmetic) is *not* proven: its
residual is reported, and ``within_tolerance`` (listed in ``rows_within_tolerance``) says
whether it is below the float rule's tolerance ``|r| <= rel * s`` (``s = |a0| + sum_k |a_k
x_k|``, exactly at ``x_q``), which is information, never a proof. When the projected point
fails (nearly dependent rows can move it far), the same grid is tried without the projection.

A successful proof (``proven``) is the statement: *every LMI holds exactly at the rational
point ``x_q`` (strict ones positive definite, the others positive semidefinite) and every
linear row holds exactly (equalities with residual zero)*. ``statement`` says it in one line.
The objective at ``x_q`` is computed exactly and reported (``objective``, rounded to float64
for display).

How positive (semi)definiteness of ``M`` is proved or disproved exactly (congruence and
diagonal dominance, exact LDL^T, characteristic polynomial) is :mod:`lmic.certify.psd`.

A disproof at the *float* point itself (``x_q == x``) is a disproof of the solver's point; a
disproof at a rounded or projected point only says "not proven".

Linear inequality rows are checked exactly at ``x_q`` (``> 0`` strict, ``>= 0``).

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
>>> p = Problem([Variable("p", "scalar", (1, 1))], [LMI("p > 0", 1, sp.csc_matrix([[0., 1.]]))],
...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
>>> r = prove(p, np.array([0.3]))
>>> r["proven"], r["at_x"], r["denominator"]
(True, True, '2^54')
>>> r["statement"]
'every LMI and linear row holds exactly at the rational point x_q (exact.point), the returned float point x itself'
>>> prove(p, np.array([0.3]), bits=6)["point"]
{'den': '64', 'num': ['19']}
"""

from __future__ import annotations

import math
import time
from fractions import Fraction
from typing import Any

import numpy as np

from lmic.certify.psd import CHARPOLY_MAX_DIM, LDL_MAX_DIM, bit_size, load_flint, prove_pd, prove_psd
from lmic.errors import LmicError
from lmic.ir.problem import LMI, Problem
from lmic.ir.svec import tril_rows_cols, tril_unvec

__all__ = [
    "ExactPoint",
    "exact_float",
    "round_point",
    "exact_matrix",
    "prove_pd",
    "prove_psd",
    "prove",
    "LDL_MAX_DIM",
    "CHARPOLY_MAX_DIM",
    "FULL_BITS_MAX",
]

#: largest denominator exponent of the float point tried first, before a coarser rounding
FULL_BITS_MAX = 256

#: the name :mod:`lmic.certify.farkas` imports (until it imports :func:`lmic.certify.psd.load_flint`)
_flint = load_flint


def exact_float(v: float) -> tuple[int, int]:
    """``(m, e)`` with ``v == m * 2**e`` exactly and ``m`` odd (or ``(0, 0)``).

    >>> exact_float(0.75), exact_float(-3.0), exact_float(0.0)
    ((3, -2), (-3, 0), (0, 0))
    """
    if v == 0:
        return 0, 0
    if not math.isfinite(v):
        raise LmicError(f"cannot make {v} exact")
    f, e = math.frexp(v)
    m = int(f * (1 << 53))
    e -= 53
    tz = (m & -m).bit_length() - 1
    return m >> tz, e + tz


def _float_bits(x: np.ndarray) -> int:
    """Smallest ``K >= 0`` with every ``x_k * 2^K`` an integer."""
    K = 0
    for v in np.asarray(x, dtype=float):
        if v != 0:
            K = max(K, -exact_float(float(v))[1])
    return K


class ExactPoint:
    """A rational point ``x = num / den`` (python ints, one common positive denominator).

    Examples
    --------
    >>> p = round_point(np.array([0.3, -1.25]), 3)
    >>> p.num, p.den, p.describe()
    ([2, -10], 8, '2^3')
    >>> [str(v) for v in p.fractions()]
    ['1/4', '-5/4']
    """

    def __init__(self, num: list[int], den: int, K: int | None = None) -> None:
        if den <= 0:
            raise LmicError("an exact point needs a positive denominator")
        self.num = [int(v) for v in num]
        self.den = int(den)
        self.K = K

    def fractions(self) -> list[Fraction]:
        """The coordinates as :class:`fractions.Fraction`."""
        return [Fraction(v, self.den) for v in self.num]

    def describe(self) -> str:
        """The denominator, as ``2^K`` when it is a power of two."""
        if self.den & (self.den - 1) == 0:
            return f"2^{self.den.bit_length() - 1}"
        return str(self.den)

    def floats(self) -> np.ndarray:
        """The point in float64 (for reporting)."""
        return np.array([float(Fraction(v, self.den)) for v in self.num])


def round_point(x: np.ndarray, K: int) -> ExactPoint:
    """Round ``x`` to the dyadic grid ``2^-K`` (``K >= 0``): ``x_q = round(x 2^K) / 2^K``.

    >>> round_point(np.array([0.5, 0.26]), 2).num
    [2, 1]
    """
    K = int(max(K, 0))
    x = np.asarray(x, dtype=float).ravel()
    scaled = np.ldexp(x, K)
    if x.size == 0 or (np.all(np.isfinite(scaled)) and float(np.max(np.abs(scaled))) < 2.0**52):
        # fast path: x 2^K is exact in float64, its rounding to an integer too (half away
        # from zero, like the exact path below)
        q = np.where(scaled >= 0, np.floor(scaled + 0.5), -np.floor(-scaled + 0.5))
        return ExactPoint(q.astype(np.int64).tolist(), 1 << K, K)
    num = []
    for v in x:
        m, e = exact_float(float(v))
        s = e + K
        if s >= 0:
            num.append(m << s)
        else:  # round half away from zero, in exact integer arithmetic
            q, r = divmod(abs(m), 1 << -s)
            if 2 * r >= (1 << -s):
                q += 1
            num.append(q if m >= 0 else -q)
    return ExactPoint(num, 1 << K, K)


_LIMB = 24
_MASK = np.uint64((1 << _LIMB) - 1)


def _limb_sums(mant: np.ndarray, shifts: np.ndarray, xv: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """Per-row ``sum mant * 2^shift * x`` exactly, in int64 limbs of 24 bits.

    ``mant`` (|mant| < 2^53), ``shifts`` (>= 0) and ``xv`` (|x| < 2^62) are int64 arrays over
    the non-zeros, rows start at ``starts``. Every limb product is < 2^48 and a row has fewer
    than 2^14 terms, so the int64 row sums are exact; the limbs are recombined in python ints
    (one object operation per row and limb pair instead of three per non-zero).
    """
    sign = np.sign(mant) * np.sign(xv)
    am = np.abs(mant).astype(np.uint64)
    ax = np.abs(xv).astype(np.uint64)
    n_c = (53 + int(shifts.max()) + _LIMB - 1) // _LIMB
    n_x = max(1, (int(ax.max()).bit_length() + _LIMB - 1) // _LIMB)
    x_limbs = [((ax >> np.uint64(_LIMB * k)) & _MASK).astype(np.int64) for k in range(n_x)]
    total = np.zeros(len(starts), dtype=object)
    for j in range(n_c):
        t = shifts - _LIMB * j  # bit j*24 of (mant << shift) is bit -t of mant
        limb = np.zeros(len(am), dtype=np.uint64)
        up = (t >= 0) & (t < _LIMB)
        limb[up] = (am[up] << t[up].astype(np.uint64)) & _MASK
        down = (t < 0) & (t > -64)
        limb[down] = (am[down] >> (-t[down]).astype(np.uint64)) & _MASK
        c = limb.astype(np.int64) * sign
        if not c.any():
            continue
        for k in range(n_x):
            part = np.add.reduceat(c * x_limbs[k], starts)
            if part.any():
                total = total + (part.astype(object) << (_LIMB * (j + k)))
    return total


def exact_matrix(lmi: LMI, point: ExactPoint) -> list[list[int]]:
    """``F(x_q)`` scaled by a positive power of two and ``den``: an exact integer matrix.

    Returns the matrix as nested python-int lists (``c * F(x_q)`` for some ``c > 0``).

    >>> import scipy.sparse as sp
    >>> L = LMI("m", 2, sp.csc_matrix([[1.0, 0.0], [0.0, 0.5], [2.0, 0.0]]))
    >>> exact_matrix(L, ExactPoint([3], 2))
    [[4, 3], [3, 8]]
    """
    C = lmi.coeffs.tocsr()
    C.sum_duplicates()
    d = lmi.dim
    rows, cols = tril_rows_cols(d)
    vals = [0] * C.shape[0]
    if C.nnz:
        f, e = np.frexp(C.data)
        mant = (f * 2.0**53).astype(np.int64)
        e = e.astype(np.int64) - 53
        tz = np.zeros_like(mant)
        low = mant & -mant  # lowest set bit, exact in int64
        nz = low != 0
        tz[nz] = np.round(np.log2(np.abs(low[nz]).astype(float))).astype(np.int64)
        mant = np.where(nz, mant >> tz, 0)
        e = e + tz
        emin = int(e[nz].min()) if nz.any() else 0
        shifts = e - emin
        counts = np.diff(C.indptr)
        nonempty = np.flatnonzero(counts)
        starts = C.indptr[:-1][nonempty]
        xs = [point.den] + point.num
        sums = None
        if len(nonempty) and max(map(abs, xs)) < 2**62 and int(counts.max()) < 2**14:
            sums = _limb_sums(mant, shifts, np.array(xs, dtype=np.int64)[C.indices], starts)
        elif len(nonempty):
            xnum = np.array(xs, dtype=object)
            terms = np.left_shift(mant.astype(object) * xnum[C.indices], shifts.astype(object))
            sums = np.add.reduceat(terms, starts)
        if sums is not None:
            for r, v in zip(nonempty.tolist(), sums.tolist(), strict=True):
                vals[r] = int(v)
    M = [[0] * d for _ in range(d)]
    for k, (i, j) in enumerate(zip(rows.tolist(), cols.tolist(), strict=True)):
        M[i][j] = vals[k]
        M[j][i] = vals[k]
    return M


def _needed_bits(problem: Problem, x: np.ndarray, min_eigs: list[float] | None = None) -> int | None:
    """Bits ``K`` so that rounding to ``2^-K`` keeps every positive float margin (None: use x)."""
    xx = np.concatenate([[1.0], x])
    need = 0
    for i, lmi in enumerate(problem.lmis):
        C = lmi.coeffs.tocsr()
        if min_eigs is not None:
            lmin = float(min_eigs[i])
        else:
            F = tril_unvec(C @ xx, lmi.dim)
            lmin = float(np.linalg.eigvalsh(F)[0]) if lmi.dim else 1.0
        G = tril_unvec(abs(C[:, 1:]) @ np.ones(problem.n), lmi.dim)
        g = float(np.max(np.sum(np.abs(G), axis=1))) if lmi.dim else 0.0
        if g == 0:
            continue
        if not lmin > 0 or not math.isfinite(lmin):
            return None
        need = max(need, math.ceil(math.log2(16.0 * g / lmin)))
    lin = problem.linear
    if len(lin):
        A = lin.A.tocsr()
        r = np.asarray(A @ xx).ravel()
        row_scale = np.asarray(abs(A[:, 1:]) @ np.ones(problem.n)).ravel()
        for i in range(len(lin)):
            if lin.kinds[i] == "eq" or row_scale[i] == 0:
                continue
            if r[i] <= 0:
                return None
            need = max(need, math.ceil(math.log2(16.0 * row_scale[i] / r[i])))
    return max(need, 0)


def _project_eq(problem: Problem, point: ExactPoint) -> tuple[ExactPoint, str]:
    """Project ``point`` exactly onto the equality rows (``x - A^T (A A^T)^-1 (A x + a0)``).

    Rank-deficient rows are reduced to a maximal independent subset first (the pivot columns
    of the exact reduced row echelon form of ``A^T``); the dependent rows then vanish at the
    projection when the system is consistent in exact arithmetic.
    """
    lin = problem.linear
    eq = [i for i, k in enumerate(lin.kinds) if k == "eq"]
    if not eq:
        return point, ""
    flint = load_flint()
    A = lin.A.tocsr()[eq].toarray()

    def q(v: float):
        f = Fraction(float(v))
        return flint.fmpq(f.numerator, f.denominator)

    xq = flint.fmpq_mat([[flint.fmpq(v, point.den)] for v in point.num])
    Aq = flint.fmpq_mat([[q(v) for v in row[1:]] for row in A])
    a0 = flint.fmpq_mat([[q(row[0])] for row in A])
    res = Aq * xq + a0
    if all(v == 0 for v in res.entries()):
        return point, ""
    R, rank = Aq.transpose().rref()
    if rank == 0:
        return point, "the equality rows have no variable terms; no exact projection"
    note = "projected exactly onto the equality rows"
    if rank < len(eq):
        width = R.ncols()
        flat = R.entries()
        pivots = []
        for r in range(rank):
            row = flat[r * width : (r + 1) * width]
            pivots.append(next(c for c in range(width) if row[c] != 0))
        Aq = flint.fmpq_mat([[q(v) for v in A[c][1:]] for c in pivots])
        res = flint.fmpq_mat([[res[c, 0]] for c in pivots])
        note += f" ({rank} independent of {len(eq)})"
    y = (Aq * Aq.transpose()).solve(res)
    xp = xq - Aq.transpose() * y
    fr = [Fraction(int(v.p), int(v.q)) for v in xp.entries()]
    den = 1
    for f in fr:
        den = den * f.denominator // math.gcd(den, f.denominator)
    return ExactPoint([int(f * den) for f in fr], den), note


def _linear_exact(problem: Problem, point: ExactPoint, rel: float) -> list[dict[str, Any]]:
    """Every linear row exactly at ``point``; an equality row may hold within ``rel``."""
    lin = problem.linear
    out: list[dict[str, Any]] = []
    if not len(lin):
        return out
    A = lin.A.tocsr()
    xs = [Fraction(1)] + point.fractions()
    rel_q = Fraction(rel) if math.isfinite(rel) and rel >= 0 else Fraction(0)
    for i in range(len(lin)):
        lo, hi = A.indptr[i], A.indptr[i + 1]
        terms = [Fraction(float(v)) * xs[j] for v, j in zip(A.data[lo:hi], A.indices[lo:hi], strict=True)]
        r = sum(terms, Fraction(0))
        kind, strict = lin.kinds[i], bool(lin.strict[i])
        ok = r == 0 if kind == "eq" else (r > 0 if strict else r >= 0)
        within = bool(kind == "eq" and not ok and abs(r) <= rel_q * sum((abs(t) for t in terms), Fraction(0)))
        out.append(
            {
                "name": lin.names[i],
                "kind": kind,
                "strict": strict,
                "proven": bool(ok),
                "within_tolerance": within,
                "value": float(r),
            }
        )
    return out


def _objective_exact(problem: Problem, point: ExactPoint) -> float | None:
    """``c0 + c . x_q`` computed exactly, rounded to float64 (``None`` for feasibility)."""
    obj = problem.objective
    if obj.sense == "feasibility":
        return None
    c = np.asarray(obj.c, dtype=float)
    num = sum(
        (Fraction(float(c[1 + k])) * v for k, v in enumerate(point.num) if c[1 + k] != 0 and v != 0),
        Fraction(0),
    )
    return float(Fraction(float(c[0])) + num / point.den)


def prove(
    problem: Problem,
    x: np.ndarray,
    *,
    inaccurate: bool = False,
    tol: Any = None,
    bits: int | None = None,
    min_eigs: list[float] | None = None,
) -> dict[str, Any]:
    """Prove every LMI and linear row of ``problem`` at a rational point ``x_q`` near ``x``.

    Parameters
    ----------
    problem : Problem
    x : numpy.ndarray
        The float point (length ``problem.n``).
    inaccurate : bool
        Unused by the proof itself (kept for a uniform call from :func:`certify`).
    tol : Tolerances or float, optional
        Only its ``rel`` is used: the tolerance of an equality row that cannot be met exactly
        (default ``1e-8``). LMIs and inequality rows are proved without tolerance.
    bits : int, optional
        Force the denominator ``2^bits`` (default: ``x`` itself first, then a coarser grid
        chosen from the float margins; see the module docstring).
    min_eigs : list of float, optional
        The float ``lambda_min`` of every LMI at ``x``, when already known (saves work).

    Returns
    -------
    dict
        ``proven`` (all LMIs and rows), ``disproved`` (an LMI exactly fails at the float point
        itself), ``reason``, ``statement`` (what a proof means, one line), ``point``
        (``{"den", "num"}``: ``x_q`` as decimal strings), ``at_x`` (``x_q == x``), ``distance``
        (``max |x_q - x|``), ``objective`` (exact at ``x_q``), ``denominator`` (e.g.
        ``"2^23"``), ``bits``, ``numerator_bits``, ``rounded`` (``x_q != x``), ``projection``,
        ``rows_within_tolerance``, ``attempts`` (per denominator tried: ``denominator,
        proven, disproved``), ``time_s``, ``lmis`` (``name, strict, proven, disproved,
        method, detail, entry_bits``), ``linear`` (``name, kind, strict, proven,
        within_tolerance, value``).

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
    >>> p = Problem([Variable("p", "scalar", (1, 1))],
    ...             [LMI("p >= 0", 1, sp.csc_matrix([[0., 1.]]), strict=False)],
    ...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
    >>> r = prove(p, np.array([0.0]))
    >>> r["proven"], r["at_x"], r["point"]
    (True, True, {'den': '1', 'num': ['0']})
    """
    del inaccurate
    rel = _rel_of(tol)
    t0 = time.perf_counter()
    x = np.asarray(x, dtype=float).ravel()
    K_full = _float_bits(x)
    tried: list[dict[str, Any]] = []
    result: dict[str, Any] | None = None
    at_full: dict[str, Any] | None = None
    if bits is not None:
        plan: list[int | None] = [int(bits)]
    elif K_full <= FULL_BITS_MAX:
        plan = [K_full, None]  # None: the coarse grid, computed only if needed
    else:
        plan = [None, K_full]
    for K in plan:
        if K is None:
            K = _needed_bits(problem, x, min_eigs)
            if K is None or K >= K_full:
                continue
        attempt = _attempt(problem, x, K, K_full, rel)
        if not attempt["proven"] and attempt["projection"]:
            # the exact projection can move the point far (nearly dependent rows) or away from
            # the LMIs' margins: without it, the equality rows may still hold within tolerance
            plain = _attempt(problem, x, K, K_full, rel, project=False)
            if plain["proven"]:
                attempt = plain
        tried.append({k: attempt[k] for k in ("denominator", "proven", "disproved")})
        if K == K_full:
            at_full = attempt
        result = attempt
        if attempt["proven"]:
            break
    assert result is not None  # the plan always holds K_full or a forced K
    if not result["proven"] and at_full is not None:
        result = at_full  # a failure is reported at the solver's point itself (a disproof there is final)
    result["attempts"] = tried
    result["time_s"] = time.perf_counter() - t0
    return result


def _rel_of(tol: Any) -> float:
    if tol is None:
        return 1e-8
    if isinstance(tol, int | float) and not isinstance(tol, bool):
        return float(tol)
    return float(getattr(tol, "rel", 1e-8))


def _attempt(problem: Problem, x: np.ndarray, K: int, K_full: int, rel: float, project: bool = True) -> dict[str, Any]:
    point = round_point(x, K)
    proj = ""
    if project:
        point, proj = _project_eq(problem, point)
    rounded = K < K_full or point.den != (1 << K) or proj.startswith("projected")
    lmis = []
    for lmi in problem.lmis:
        M = exact_matrix(lmi, point)
        bitsz = bit_size(M)
        r = prove_pd(M) if lmi.strict else prove_psd(M)
        lmis.append(
            {
                "name": lmi.name,
                "strict": bool(lmi.strict),
                "proven": r["proven"],
                "disproved": bool(r["disproved"] and not rounded),
                "method": r["method"],
                "detail": r["detail"],
                "entry_bits": bitsz,
            }
        )
    linear = _linear_exact(problem, point, rel)
    within = [e["name"] for e in linear if e["within_tolerance"]]
    proven = all(e["proven"] for e in lmis) and all(e["proven"] for e in linear)  # equalities exactly
    disproved = any(e["disproved"] for e in lmis)
    distance = 0.0
    if rounded and point.num:
        distance = max(
            float(abs(Fraction(v, point.den) - Fraction(float(xk)))) for v, xk in zip(point.num, x, strict=True)
        )
    where = "the returned float point x itself" if not rounded else f"max |x_q - x| = {distance:.3g}"
    statement = (
        f"every LMI and linear row holds exactly at the rational point x_q (exact.point), {where}" if proven else ""
    )
    if proven:
        reason = f"every LMI and row proved at the rational point (denominator {point.describe()})"
    else:
        bad = next((e for e in lmis if not e["proven"]), None)
        if bad is not None:
            what = "is not positive definite" if bad["strict"] else "is not positive semidefinite"
            if bad["disproved"]:
                reason = f"LMI '{bad['name']}' {what} at the solver's point ({bad['detail']})"
            else:
                reason = f"LMI '{bad['name']}' not proven ({bad['detail']})"
        else:
            row = next(e for e in linear if not e["proven"])
            held = ", within tolerance only" if row["within_tolerance"] else ""
            reason = f"row '{row['name']}' not proven at the rational point (value {row['value']:.3g}{held})"
        if proj and not proj.startswith("projected"):
            reason += "; " + proj
    return {
        "proven": bool(proven),
        "disproved": bool(disproved),
        "reason": reason,
        "statement": statement,
        "point": {"den": str(point.den), "num": [str(v) for v in point.num]},
        "at_x": not rounded,
        "distance": distance,
        "objective": _objective_exact(problem, point),
        "denominator": point.describe(),
        "bits": int(K),
        "numerator_bits": max((abs(v).bit_length() for v in point.num), default=0),
        "rounded": bool(rounded),
        "projection": proj,
        "rows_within_tolerance": within,
        "lmis": lmis,
        "linear": linear,
    }
