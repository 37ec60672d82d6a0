"""The IR's coefficients in exact rational arithmetic, from the same plan and numbers as
:mod:`lmic.compile.bind`.

Why
---
:func:`lmic.compile.bind.bind` computes every coefficient in floating point: the coefficient
of ``P_ab`` at entry ``(a, b)`` of ``A^T P + P A`` is ``fl(A_aa + A_bb)``, a rounded sum.
Proofs that need the exact algebraic structure of a template (the face route of
:mod:`lmic.certify.enclosure_face`) run on :class:`ExactProblem` instead: each system number
read as its binary float (an exact dyadic rational), products of data factors (data matrices,
their transposes, identities) exact, scalar coefficients exact when they are rational
functions of the parameters, and duplicate ``(row, column)`` entries summed exactly.

What declines
-------------
Anything not exactly representable raises :class:`ExactUnavailable` with a reason, never an
approximation: coefficients with ``sqrt``, ``exp``, ...; factors that are computed (inverses,
products inside a tree, data-derived constants); a frozen plan's non-integer numbers (the
freeze wrote a template's ``1/3`` as a float: the analysed plan is used instead).

Which problem
-------------
:func:`exact_of` gives a compiled problem's exact counterpart lazily (cached on the problem):
the one its transformation attached (:data:`EXACT_MAKER`: a study's lifted problem); for a
problem compiled from a theorem (``meta["theorem"]``, the template hash recorded), the theorem
compiled again exactly from ``problem.data`` by the plan it was bound from
(:data:`lmic.compile.bind.BOUND_PLAN`: an inline theorem is in no registry), else by its id;
for an IR with no theorem (``.json``, SDPA), the IR's own floats (:func:`from_ir`).
:meth:`ExactProblem.perturbation` bounds ``|G_exact(x) - G_float(x)|`` rigorously (a certified
point is then proved for both problems: :func:`lmic.certify.enclosure_float.primal_end`).

Examples
--------
>>> from lmic.template import theorem, block
>>> from lmic.compile.plan import analyse
>>> @theorem(id="demo.exact", title="t", citation="c")
... def demo(t):
...     n, = t.dims("n")
...     A = t.data("A", n, n)
...     P = t.symmetric("P", n)
...     t.lmi("stability", block(A.T * P + P * A) < 0)
>>> ex = exact_bind(analyse(demo), {"data": {"A": [[-0.1, 0.0], [0.0, -0.2]]}})
>>> ex.lmis[0].value(0, 1) == -2 * (Fraction(-0.1) + Fraction(-0.1)) / 2  # -(A^T P + P A), P_00
True
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any

import numpy as np
import scipy.sparse as sp

from lmic.compile.bind import _Binder, _is_identity_factor
from lmic.compile.frozen import Coef, Factor
from lmic.compile.inputs import resolve_inputs
from lmic.errors import LmicError
from lmic.ir.problem import Problem
from lmic.ir.svec import tril_rows_cols, tril_size
from lmic.system import load_system

__all__ = ["ExactUnavailable", "ExactLMI", "ExactProblem", "exact_bind", "exact_of", "from_ir", "cached_exact"]

_U = 2.0**-53
_ATTR = "_lmic_exact"
#: a problem's attribute: a callable that builds its :class:`ExactProblem` (a transformation's)
EXACT_MAKER = "_lmic_exact_maker"


class ExactUnavailable(LmicError):
    """A coefficient (or the problem's origin) has no exact rational value: the reason."""


@dataclass
class ExactLMI:
    """One LMI's coefficients ``num / den`` (CSC over ``(tril_size(dim), 1 + n)``, the layout
    of :attr:`lmic.ir.problem.LMI.coeffs`; ``num`` python ints, ``den > 0``)."""

    name: str
    dim: int
    indptr: np.ndarray
    indices: np.ndarray
    num: np.ndarray
    den: int

    def column(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        """Rows and numerators of IR column ``k``."""
        a, b = int(self.indptr[k]), int(self.indptr[k + 1])
        return self.indices[a:b], self.num[a:b]

    def value(self, row: int, k: int) -> Fraction:
        """The exact coefficient at ``(row, k)``."""
        rows, num = self.column(k)
        hit = np.flatnonzero(rows == row)
        return Fraction(int(num[hit[0]]), self.den) if hit.size else Fraction(0)

    def rounded(self) -> sp.csc_matrix:
        """The coefficients rounded to nearest (python's ``int / int`` is correctly rounded)."""
        data = np.array([int(v) / self.den for v in self.num], dtype=float)
        return sp.csc_matrix((data, self.indices, self.indptr), shape=(tril_size(self.dim), len(self.indptr) - 1))


@dataclass
class ExactProblem:
    """The exact counterpart of a :class:`~lmic.ir.problem.Problem`: ``lmis``, ``linear``
    (one ``{column: Fraction}`` per row of ``problem.linear``), ``objective`` (``c``, length
    ``1 + n``), ``about`` (``"theorem"``: compiled exactly from the theorem and the system's
    numbers; ``"ir"``: the IR's own floats) and ``source`` (one line)."""

    lmis: list[ExactLMI]
    linear: list[dict[int, Fraction]]
    objective: list[Fraction]
    about: str
    source: str
    _diff: tuple[Any, ...] = field(default=(), repr=False)

    def perturbation(self, problem: Problem, x: np.ndarray) -> tuple[list[float], list[float], float]:
        """Rigorous upper bounds of ``||F_i^exact(x) - F_i(x)||_F`` per LMI, of ``|l_r^exact(x)
        - l_r(x)|`` per linear row and of ``|c_exact . x - c . x|`` (``x`` without the leading 1).

        Each coefficient difference is bounded by ``|fl(r - f)| (1 + u) + u |r| + 2^-1074``
        (``r``: the exact value rounded to nearest, ``f``: the IR's); the sums are evaluated in
        floating point and inflated by ``(1 + 4 (m + 2) u)`` (``m`` terms, all non-negative).
        """
        xx = np.abs(np.concatenate([[1.0], np.asarray(x, dtype=float).ravel()]))
        if not self._diff:
            self._diff = self._differences(problem)
        lmi_d, lin_d, obj_d = self._diff
        out = []
        for D, lmi in zip(lmi_d, problem.lmis, strict=True):
            e = np.asarray(D @ xx).ravel() * _grow(D.shape[1])
            i, j = tril_rows_cols(lmi.dim)
            w = np.where(i == j, 1.0, 2.0)
            ss = float(np.sum(w * e * e))
            out.append(_up(math.sqrt(_up(ss * _grow(e.size)))) if ss > 0 or np.any(e) else 0.0)
        lin = [float(v) for v in (np.asarray(lin_d @ xx).ravel() * _grow(xx.size))] if lin_d is not None else []
        obj = float(obj_d @ xx) * _grow(xx.size)
        return out, lin, obj

    def _differences(self, problem: Problem) -> tuple[list[sp.csr_matrix], sp.csr_matrix | None, np.ndarray]:
        if len(self.lmis) != len(problem.lmis) or len(self.linear) != len(problem.linear):
            raise ExactUnavailable("the exact problem does not match the IR's constraints")
        mats = [sp.csr_matrix(_bound(ex, lmi.coeffs.tocsc())) for ex, lmi in zip(self.lmis, problem.lmis, strict=True)]
        lin_d = None
        if len(problem.linear):
            A = problem.linear.A.tocsr()
            rows, cols, vals = [], [], []
            for r, row in enumerate(self.linear):
                have = dict(
                    zip(
                        A.indices[A.indptr[r] : A.indptr[r + 1]].tolist(),
                        A.data[A.indptr[r] : A.indptr[r + 1]].tolist(),
                        strict=True,
                    )
                )
                for k in set(row) | set(have):
                    dv = abs(row.get(k, Fraction(0)) - Fraction(have.get(k, 0.0)))
                    if dv:
                        rows.append(r)
                        cols.append(k)
                        vals.append(_up(float(dv)))
            lin_d = sp.csr_matrix((vals, (rows, cols)), shape=A.shape)
        c = np.asarray(problem.objective.c, dtype=float)
        dq = [abs(b - Fraction(float(a))) for a, b in zip(c, self.objective, strict=True)]
        obj_d = np.array([_up(float(v)) if v else 0.0 for v in dq])
        return mats, lin_d, obj_d


def _grow(m: int) -> float:
    return 1.0 + 4.0 * (m + 2) * _U


def _up(v: float) -> float:
    return float(np.nextafter(v, np.inf))


def _bound(ex: ExactLMI, F: sp.csc_matrix) -> sp.csc_matrix:
    """Entrywise bounds of ``|exact - F|``: ``|fl(r - f)| (1 + u) + 2^-1074`` where ``r`` (the
    exact value rounded to nearest, python's correctly rounded ``int / int``) differs from
    ``f``, plus ``u |r| + 2^-1074`` where ``r`` is not the exact value itself."""
    r = np.array([int(v) / ex.den for v in ex.num], dtype=float)
    inexact = np.array(
        [
            p * ex.den != int(v) * q
            for v, (p, q) in zip(ex.num, (x.as_integer_ratio() for x in r.tolist()), strict=True)
        ],
        dtype=bool,
    )
    shape = F.shape
    R = sp.csc_matrix((r, ex.indices, ex.indptr), shape=shape)
    Dm = abs(R - F).tocsc()
    Dm.eliminate_zeros()
    Dm.data = Dm.data * (1 + _U) + 2.0**-1074
    Ra = sp.csc_matrix((np.where(inexact, np.abs(r) * _U + 2.0**-1074, 0.0), ex.indices, ex.indptr), shape=shape)
    return (Dm + Ra).tocsc()


# -- exact numbers ------------------------------------------------------------------------------


def _dyadic(arr: Any) -> tuple[np.ndarray, int]:
    """``(N, e)`` with ``arr = N / 2^e`` exactly (``N`` python ints, ``e >= 0``)."""
    a = np.atleast_2d(np.asarray(arr, dtype=float))
    if not np.all(np.isfinite(a)):
        raise ExactUnavailable("a data value is not finite")
    m, ex = np.frexp(a)
    mi = (m * 2.0**53).astype(np.int64)
    nz = mi != 0
    e = max(0, -int((ex - 53)[nz].min())) if nz.any() else 0
    shift = np.where(nz, ex - 53 + e, 0)
    N = np.empty(a.shape, dtype=object)
    flat = N.reshape(-1)
    for t, (v, s) in enumerate(zip(mi.ravel().tolist(), shift.ravel().tolist(), strict=True)):
        flat[t] = v << s
    return N, e


class _RoundedNumber(ExactUnavailable):
    """A frozen plan's non-integer number (the freeze may have rounded a rational)."""


def _fraction_of_number(v: float, strict_dyadic: bool) -> Fraction:
    f = Fraction(float(v))
    if strict_dyadic and f.denominator != 1:
        raise _RoundedNumber(f"the frozen plan's number {v!r} may be a rounded rational")
    return f


def _tree_value(tree: Any, env: Mapping[str, Fraction]) -> Fraction:
    """A frozen coefficient tree evaluated exactly (rational operations only)."""
    if "name" in tree:
        if tree["name"] not in env:
            raise ExactUnavailable(f"'{tree['name']}' is a constant computed from the data in floating point")
        return env[tree["name"]]
    if "num" in tree:
        return _fraction_of_number(tree["num"], True)
    op, args = tree.get("op"), [_tree_value(a, env) for a in tree.get("args", [])]
    if op == "add":
        return sum(args, Fraction(0))
    if op == "mul":
        return math.prod(args, start=Fraction(1))
    if op == "neg":
        return -args[0]
    if op == "inv" and args[0] != 0:
        return 1 / args[0]
    if op == "pow" and args[1].denominator == 1 and (args[1] >= 0 or args[0] != 0):
        return args[0] ** int(args[1])
    raise ExactUnavailable(f"operation '{op}' has no exact rational value")


def _sympy_value(expr: Any, env: Mapping[str, Fraction]) -> Fraction:
    """An analysed plan's sympy coefficient evaluated exactly."""
    import sympy

    if isinstance(expr, sympy.Rational):
        return Fraction(int(expr.p), int(expr.q))
    if isinstance(expr, sympy.Float):
        if expr._prec > 53:
            raise ExactUnavailable(f"the number {expr} has more than double precision")
        return Fraction(float(expr))
    if isinstance(expr, sympy.Symbol):
        if expr.name not in env:
            raise ExactUnavailable(f"'{expr.name}' is a constant computed from the data in floating point")
        return env[expr.name]
    if isinstance(expr, sympy.Add):
        return sum((_sympy_value(a, env) for a in expr.args), Fraction(0))
    if isinstance(expr, sympy.Mul):
        return math.prod((_sympy_value(a, env) for a in expr.args), start=Fraction(1))
    if isinstance(expr, sympy.Pow) and expr.exp.is_Integer:
        base = _sympy_value(expr.base, env)
        if base == 0 and int(expr.exp) < 0:
            raise ExactUnavailable(f"coefficient '{expr}' divides by zero")
        return base ** int(expr.exp)
    raise ExactUnavailable(f"coefficient '{expr}' has no exact rational value")


# -- the exact binder -------------------------------------------------------------------------


Q = tuple[np.ndarray, int]  # (N, e): N / 2^e


class _ExactBinder(_Binder):
    """:class:`lmic.compile.bind._Binder`'s layout (variables, bases, term indices, CSC
    structure: shared with the float bind) with exact values."""

    def __init__(self, plan: Any, inputs: Any) -> None:
        super().__init__(plan, inputs)
        self._params = {p.name: Fraction(float(inputs.values[p.name])) for p in plan.template.params}
        self._computed = {c.name for c in plan.template.consts}
        self._qf: dict[Any, Q] = {}
        self._qc: dict[Any, Fraction] = {}

    def qcoef(self, expr: Any) -> Fraction:
        hit = self._qc.get(expr)
        if hit is not None:
            return hit
        if isinstance(expr, Coef):
            v = _tree_value(expr.tree, self._params)
        elif isinstance(expr, int | float):
            v = Fraction(float(expr))
        else:
            v = _sympy_value(expr, self._params)
        self._qc[expr] = v
        return v

    def qfactor(self, f: Any) -> Q | None:
        if _is_identity_factor(f):
            return None
        hit = self._qf.get(f)
        if hit is not None:
            return hit
        name, transposed = None, False
        if isinstance(f, Factor):
            if f.frozen_kind in ("name", "nameT"):
                name, transposed = f.name, f.frozen_kind == "nameT"
        else:
            from sympy.matrices.expressions import MatrixSymbol, Transpose

            if isinstance(f, MatrixSymbol):
                name = f.name
            elif isinstance(f, Transpose) and isinstance(f.arg, MatrixSymbol):
                name, transposed = f.arg.name, True
        if name is None:
            raise ExactUnavailable(f"factor '{f}' is computed (its exact value is not known)")
        if name in self._computed:
            raise ExactUnavailable(f"'{name}' is a constant computed from the data in floating point")
        N, e = _dyadic(self.env[name])
        out = (N.T if transposed else N, e)
        self._qf[f] = out
        return out

    def qproduct(self, factors: tuple[Any, ...]) -> Q | None:
        out: Q | None = None
        for f in factors:
            v = self.qfactor(f)
            if v is None:
                continue
            out = v if out is None else (np.dot(out[0], v[0]), out[1] + v[1])
        return out

    def qterm(self, term: Any, rows: int, cols: int) -> Q:
        """The values of :meth:`_Binder.term_values`, exactly (unscaled by the coefficient)."""
        if term.var is None or self.vars[term.var].kind == "scalar":
            M = self.qproduct(term.left)
            if M is None:
                return np.eye(rows, dtype=np.int64).astype(object).reshape(-1, order="F"), 0
            return M[0].reshape(-1, order="F"), M[1]
        bi, bj, _, _ = self.basis(term.var, term.transposed)
        L, R = self.qproduct(term.left), self.qproduct(term.right)
        if L is None and R is None:
            return np.ones(len(bi), dtype=np.int64).astype(object), 0
        if L is None:
            assert R is not None
            return R[0][bj, :].ravel(), R[1]
        if R is None:
            return L[0][:, bi].T.ravel(), L[1]
        return (L[0][:, bi].T[:, :, None] * R[0][bj, :][:, None, :]).ravel(), L[1] + R[1]

    def qlmi(self, lp: Any) -> ExactLMI:
        sizes = [self._size(s, f"block row of LMI '{lp.name}'") for s in lp.sizes]
        d = int(sum(sizes))
        entries: dict[tuple[int, int], list[tuple[np.ndarray, np.ndarray, tuple[np.ndarray, int]]]] = {}

        def entry(i: int, j: int) -> Any:
            if (i, j) not in lp.entries:
                return None
            if (i, j) not in entries:
                pieces = []
                for term in lp.entries[(i, j)].terms:
                    c = self.qcoef(term.coef)
                    r, k = self._term_index(term, sizes[i], sizes[j])
                    N, e = self.qterm(term, sizes[i], sizes[j])
                    pieces.append((r, k, (N * c.numerator, c.denominator << e)))
                entries[(i, j)] = pieces
            return entries[(i, j)]

        order: list[tuple[int, int, int, int]] = []  # as _Binder.lmi (its checks already passed)
        for j in range(lp.k):
            for i in range(j, lp.k):
                if (i, j) in lp.stars:
                    if entry(j, i) is not None:
                        order.append((i, j, j, i))
                    continue
                if entry(i, j) is None:
                    continue
                order.append((i, j, i, j))
        key = ("lmi", lp.name, self._dims_key, tuple(order))
        structure = self.plan.cache.get(key)
        if structure is None:
            structure = self._lmi_structure(order, entries, sizes)
            self.plan.cache[key] = structure
        indptr, indices, pos, nslots = structure
        pieces = [v for (_, _, si, sj) in order for (_, _, v) in entries[(si, sj)]]
        den = 1
        for _, q in pieces:
            den = den * q // math.gcd(den, q)
        vals = [N * (den // q) for N, q in pieces]
        v = np.concatenate(vals) if vals else np.zeros(0, dtype=object)
        data = np.zeros(nslots + 1, dtype=object)
        np.add.at(data, pos, v)
        data = data[:nslots]
        if lp.negated:
            data = -data
        keep = np.array([x != 0 for x in data], dtype=bool)
        col_of = np.repeat(np.arange(len(indptr) - 1), np.diff(indptr))
        counts = np.bincount(col_of[keep], minlength=len(indptr) - 1)
        new_ptr = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        return ExactLMI(lp.name, d, new_ptr, indices[keep].astype(np.int64), data[keep], den)

    def qtrace_row(self, terms: Any) -> dict[int, Fraction]:
        row: dict[int, Fraction] = {}
        for term in terms:
            c = self.qcoef(term.coef)
            if term.var is None or self.vars[term.var].kind == "scalar":
                M = self.qproduct(term.left)
                if M is None:
                    raise ExactUnavailable(f"trace of an identity of unknown size in '{term.text}'")
                col = 0 if term.var is None else 1 + self.vars[term.var].offset
                row[col] = row.get(col, Fraction(0)) + c * Fraction(int(np.trace(M[0])), 1 << M[1])
                continue
            var = self.vars[term.var]
            bi, bj, bk, vr = self.basis(term.var, term.transposed)
            vc = var.shape[0] if term.transposed else var.shape[1]
            L, R = self.qproduct(term.left), self.qproduct(term.right)
            Lm = (np.eye(vr, dtype=np.int64).astype(object), 0) if L is None else L
            Rm = (np.eye(vc, dtype=np.int64).astype(object), 0) if R is None else R
            RL = np.dot(Rm[0], Lm[0])
            den = 1 << (Lm[1] + Rm[1])
            for i, j, k in zip(bi.tolist(), bj.tolist(), bk.tolist(), strict=True):
                col = 1 + var.offset + k
                row[col] = row.get(col, Fraction(0)) + c * Fraction(int(RL[j, i]), den)
        return row

    def qlinear_row(self, form: Any) -> dict[int, Fraction]:
        row: dict[int, Fraction] = {}

        def add(col: int, v: Fraction) -> None:
            row[col] = row.get(col, Fraction(0)) + v

        if form.const != 0:
            add(0, self.qcoef(form.const))
        for coef, terms in form.traces:
            c = self.qcoef(coef)
            for col, v in self.qtrace_row(terms).items():
                add(col, c * v)
        for coef, (name, kind, i, j) in form.terms:
            c = self.qcoef(coef)
            var = self.vars[name]
            if kind == "scalar":
                add(1 + var.offset, c)
                continue
            bi, bj, bk, _ = self.basis(name, False)
            hit = (bi == i) & (bj == j) if kind == "entry" else bi == bj
            for k in bk[hit].tolist():
                add(1 + var.offset + k, c)
        return {k: v for k, v in row.items() if v != 0}

    def qproblem(self, problem: Problem, source: str) -> ExactProblem:
        plan = self.plan
        if [lp.name for lp in plan.lmis] != [lmi.name for lmi in problem.lmis]:
            raise ExactUnavailable("the IR's LMIs are not the theorem's")
        lmis = [self.qlmi(lp) for lp in plan.lmis]
        linear = [self.qlinear_row(form) for _, _, _, form in plan.constraints]
        for decl in plan.template.variables:
            if decl.kind == "scalar" or decl.sign == "free":
                continue
            var = self.vars[decl.name]
            flip = Fraction(-1 if decl.sign in ("negative", "nonpositive") else 1)
            linear.extend({1 + var.offset + k: flip} for k in range(var.size))
        sense, form = plan.objective
        obj = self.qlinear_row(form) if sense != "feasibility" else {}
        objective = [obj.get(k, Fraction(0)) for k in range(1 + self.n)]
        return ExactProblem(lmis, linear, objective, "theorem", source)


def _check_match(ex: ExactProblem, problem: Problem) -> None:
    """The exact problem rounds to the IR: LMIs, rows and objective (:mod:`lmic.compile.exact_match`)."""
    from lmic.compile.exact_match import mismatch

    why = mismatch(ex, problem)
    if why is not None:
        raise ExactUnavailable(why)


def exact_bind(plan: Any, system: Any, params: Mapping[str, Any] | None = None) -> ExactProblem:
    """The exact counterpart of ``bind(plan, system, params)`` (module docstring).

    Raises
    ------
    ExactUnavailable
        Naming the coefficient or factor without an exact rational value.
    """
    from lmic.compile.bind import bind

    sysobj = load_system(system)
    return _exact(plan, sysobj, params, bind(plan, sysobj, params))


def _exact(plan: Any, sysobj: Any, params: Mapping[str, Any] | None, problem: Problem) -> ExactProblem:
    inputs = resolve_inputs(plan, sysobj, params)
    ex = _ExactBinder(plan, inputs).qproblem(problem, f"theorem {plan.id} compiled exactly from the system's numbers")
    _check_match(ex, problem)
    return ex


def from_ir(problem: Problem) -> ExactProblem:
    """The IR's own coefficients as exact rationals (its floats are the data).

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("t", "scalar", (1, 1))], [LMI("t > 0", 1, sp.csc_matrix([[0.1, 1.0]]))],
    ...             LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
    >>> from_ir(p).lmis[0].value(0, 0) == Fraction(0.1)
    True
    """
    lmis = []
    for lmi in problem.lmis:
        C = lmi.coeffs.tocsc()
        C.sort_indices()
        N, e = _dyadic(C.data[None, :]) if C.nnz else (np.zeros((1, 0), dtype=object), 0)
        lmis.append(ExactLMI(lmi.name, lmi.dim, C.indptr.astype(np.int64), C.indices.astype(np.int64), N[0], 1 << e))
    A = problem.linear.A.tocsr()
    rows = [A.getrow(r).tocoo() for r in range(A.shape[0])]
    linear = [{int(k): Fraction(float(v)) for k, v in zip(R.col, R.data, strict=True)} for R in rows]
    objective = [Fraction(float(v)) for v in problem.objective.c]
    return ExactProblem(lmis, linear, objective, "ir", "the IR's own coefficients")


def cached_exact(problem: Problem) -> ExactProblem | None:
    """The exact counterpart :func:`exact_of` already built for ``problem`` (``None`` if none)."""
    ex = getattr(problem, _ATTR, None)
    return ex if isinstance(ex, ExactProblem) else None


def exact_of(problem: Problem) -> ExactProblem:
    """The exact counterpart of a compiled problem (module docstring), built once and cached
    on the problem.

    Raises
    ------
    ExactUnavailable
        When the theorem cannot be compiled exactly (the reason), or the recompilation does not
        match the IR.
    """
    hit = getattr(problem, _ATTR, None)
    if isinstance(hit, ExactProblem):
        return hit
    if isinstance(hit, ExactUnavailable):
        raise hit
    try:
        ex = _recompile(problem)
    except ExactUnavailable as exc:
        setattr(problem, _ATTR, exc)
        raise
    setattr(problem, _ATTR, ex)
    return ex


def _recompile(problem: Problem) -> ExactProblem:
    maker = getattr(problem, EXACT_MAKER, None)
    if maker is not None:
        return maker()
    meta = problem.meta or {}
    tid = meta.get("theorem")
    if not isinstance(tid, str):
        return from_ir(problem)
    from lmic.compile import plan_for
    from lmic.compile.bind import BOUND_PLAN, template_identity
    from lmic.compile.warm import FrozenPlan, warm_plan

    params = dict(meta.get("params") or {})
    bound = getattr(problem, BOUND_PLAN, None)  # an inline theorem is found by nothing else
    try:
        plan: Any = bound if getattr(bound, "id", None) == tid else warm_plan(tid, params) or plan_for(tid, params)
        for attempt in range(2):
            want = (meta.get("template") or {}).get("sha256")
            if want is not None and template_identity(plan)["template"]["sha256"] != want:
                raise ExactUnavailable(f"theorem {tid}'s template changed since the problem was compiled")
            names = {d.name for d in plan.template.data_decls}
            data = {k: np.asarray(v).tolist() for k, v in problem.data.items() if k in names}
            try:
                return _exact(plan, load_system({"data": data}), params, problem)
            except _RoundedNumber:
                if attempt or not isinstance(plan, FrozenPlan):
                    raise
                plan = plan_for(tid, params)  # the analysed plan (sympy) has the exact numbers
        raise AssertionError("unreachable")  # pragma: no cover
    except ExactUnavailable:
        raise
    except Exception as exc:  # noqa: BLE001 - a proof's helper declines, it never crashes the solve
        raise ExactUnavailable(f"theorem {tid} cannot be compiled exactly: {type(exc).__name__}: {exc}") from None
