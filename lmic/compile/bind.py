"""Bind a system's numbers to a :class:`~lmic.compile.plan.Plan`: pure numerics -> IR.

Each term ``coef * L V R`` contributes ``coef * (R^T kron L) B_V`` to the column-major
vectorisation of its block, with ``B_V`` the variable's sparse basis (``vec(V) = B_V x_V``).
Nothing is expanded entry by entry into scalar sympy expressions; identical products (the same
``L V R`` in several blocks) are computed once per bind.

Examples
--------
>>> from lmic.template import theorem, block
>>> from lmic.compile.plan import analyse
>>> @theorem(id="demo.lyap", title="t", citation="c")
... def demo(t):
...     n, = t.dims("n")
...     A = t.data("A", n, n)
...     P = t.symmetric("P", n)
...     t.lmi("stability", block(A.T * P + P * A) < 0)
>>> prob = bind(analyse(demo), {"data": {"A": [[-1.0, 0.0], [0.0, -2.0]]}})
>>> prob.n, prob.lmis[0].dim
(3, 2)
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
import scipy.sparse as sp

from lmic._version import __version__
from lmic.compile.bind_index import basis_entries as _basis_entries
from lmic.compile.bind_index import column_major_order as _column_major_order  # noqa: F401 (kept name)
from lmic.compile.bind_index import index_dtype as _index_dtype
from lmic.compile.bind_index import storage_map as _storage_map
from lmic.compile.frozen import Coef, Factor, Tree
from lmic.compile.inputs import Inputs, dim_value, resolve_inputs
from lmic.compile.warm import FrozenPlan
from lmic.errors import DataError, TemplateError
from lmic.ir.expr import evaluate
from lmic.ir.problem import (
    LMI,
    Check,
    LinearConstraints,
    NamedExpr,
    Objective,
    Problem,
    Variable,
)
from lmic.ir.svec import tril_size
from lmic.system import System, load_system

if TYPE_CHECKING:  # sympy is imported only for analysed (not frozen) plans
    import sympy

    from lmic.compile import warm
    from lmic.compile.plan import LinearForm, LmiPlan, Plan, Term

    AnyTerm = Term | warm.Term

__all__ = ["bind", "resolve_inputs", "Inputs", "BOUND_PLAN"]

_SYM_TOL = 1e-9


# -- the leaves of a plan: sympy objects (an analysed plan) or lmic.compile.frozen's (a frozen one)
def _lambdify(plan: Any, expr: Any) -> Any:
    """``f(*coefficient values)`` evaluating a coefficient."""
    if isinstance(expr, Coef):
        return expr.function([s.name for s in plan.coef_symbols])
    import sympy

    return sympy.lambdify(plan.coef_symbols, expr, modules="math", dummify=True)


def _is_identity_factor(f: Any) -> bool:
    if isinstance(f, Factor):
        return f.frozen_kind == "eye"
    from sympy.matrices.expressions import Identity

    return isinstance(f, Identity)


def _factor_value(f: Any, env: Mapping[str, Any], dims: Mapping[Any, int]) -> Any:
    if isinstance(f, Factor):
        return f.value(env, dims)
    from sympy.matrices.expressions import MatrixSymbol, Transpose

    from lmic.template.totree import to_tree

    if isinstance(f, MatrixSymbol):
        return env[f.name]
    if isinstance(f, Transpose) and isinstance(f.arg, MatrixSymbol):
        return env[f.arg.name].T
    return evaluate(to_tree(f, dims), env)


def _tree(expr: Any, dims: Mapping[Any, int]) -> dict[str, Any]:
    """The IR tree of a derived quantity or check at these dimensions."""
    if isinstance(expr, Tree):
        return expr.bound(dims)
    from lmic.template.totree import to_tree

    return to_tree(expr, dims)


class _Binder:
    def __init__(self, plan: Plan | FrozenPlan, inputs: Inputs) -> None:
        self.plan = plan
        self.inp = inputs
        self.tid = plan.id
        self.env = inputs.values
        self.dims = inputs.dims
        # variables and their layout
        self.vars: dict[str, Variable] = {}
        offset = 0
        for v in plan.template.variables:
            r, c = (self._size(s, f"variable '{v.name}'") for s in v.shape)
            blocks = tuple(self._size(b, f"variable '{v.name}'") for b in v.blocks)
            var = Variable(v.name, v.kind, (r, c), offset, blocks, v.sign)
            self.vars[v.name] = var
            offset += var.size
        self.n = offset
        self._products: dict[tuple, np.ndarray] = {}
        self._dims_key = tuple(sorted((str(k), v) for k, v in inputs.dims.items()))
        # a fixed random point at which symmetry of blocks is probed (exact up to rounding)
        self._z = np.random.default_rng(20261121).standard_normal(1 + self.n)
        self._factor_cache: dict[Any, np.ndarray] = {}
        self._param_args = [self._coef_arg(s) for s in plan.coef_symbols]

    def _coef_arg(self, s: sympy.Symbol) -> float:
        return float(self.env[s.name])

    def _size(self, expr: Any, what: str) -> int:
        v = dim_value(expr, self.dims)
        if v is None or v < 0:
            raise DataError(f"theorem {self.tid}: cannot size {what} ({expr}) from the data")
        return v

    # -- numeric pieces -------------------------------------------------------------------
    def coef(self, expr: sympy.Expr) -> float:
        if expr.is_number:
            return float(expr)
        fn = self.plan.cache.get(("coef", expr))
        if fn is None:
            fn = _lambdify(self.plan, expr)
            self.plan.cache[("coef", expr)] = fn
        try:
            value = float(fn(*self._param_args))
        except (ValueError, ZeroDivisionError, OverflowError) as err:
            raise DataError(f"theorem {self.tid}: coefficient '{expr}' cannot be evaluated: {err}") from None
        if not np.isfinite(value):
            raise DataError(f"theorem {self.tid}: coefficient '{expr}' is {value} for these parameters")
        return value

    def factor(self, f: Any) -> np.ndarray | None:
        """Numeric value of a constant factor (``None`` for an identity)."""
        if _is_identity_factor(f):
            return None
        cached = self._factor_cache.get(f)
        if cached is not None:
            return cached
        val = _factor_value(f, self.env, self.dims)
        val = np.atleast_2d(np.asarray(val, dtype=float))
        self._factor_cache[f] = val
        return val

    def product(self, factors: tuple[Any, ...]) -> np.ndarray | None:
        out = None
        for f in factors:
            v = self.factor(f)
            if v is None:
                continue
            if out is None:
                out = v
            else:
                if out.shape[1] != v.shape[0]:
                    raise TemplateError(f"theorem {self.tid}: factor '{f}' has a shape that does not fit")
                out = out @ v
        return out

    def basis(self, name: str, transposed: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
        """Basis of ``V`` (or ``V^T``) as triplets ``(i, j, k)`` with unit values, and row count.

        ``x_k`` puts a 1 at entry ``(i, j)`` (several entries per ``k`` for symmetric variables).
        """
        key = ("basis", name, transposed, self._dims_key)
        cached = self.plan.cache.get(key)
        if cached is None:
            var = self.vars[name]
            row, col = _basis_entries(var)
            r, c = var.shape
            i, j, k = row % r, row // r, col
            if transposed:
                i, j, r = j, i, c
            idx = _index_dtype(max(r, c, var.size))
            cached = (i.astype(idx), j.astype(idx), k.astype(idx), r)
            self.plan.cache[key] = cached
        return cached

    def _term_index(self, term: AnyTerm, rows: int, cols: int) -> tuple[np.ndarray, np.ndarray]:
        """(row in vec(block), IR column) of every coefficient a term can touch (dims only)."""
        key = ("term", term.left, term.var, term.transposed, term.right, rows, cols, self._dims_key)
        cached = self.plan.cache.get(key)
        if cached is not None:
            return cached
        idx = _index_dtype(max(rows * cols, 1 + self.n))
        if term.var is None or self.vars[term.var].kind == "scalar":
            col = 0 if term.var is None else 1 + self.vars[term.var].offset
            cached = (np.arange(rows * cols, dtype=idx), np.full(rows * cols, col, dtype=idx))
        else:
            var = self.vars[term.var]
            bi, bj, bk, _ = self.basis(term.var, term.transposed)
            bi, bj, bk = (a.astype(idx, copy=False) for a in (bi, bj, bk))
            L_rows = None if self._is_identity(term.left) else rows
            R_cols = None if self._is_identity(term.right) else cols
            if L_rows is None and R_cols is None:
                r_idx, k = bi + bj * rows, bk
            elif R_cols is None:
                r_idx = (np.arange(rows, dtype=idx)[None, :] + (bj * rows)[:, None]).ravel()
                k = np.repeat(bk, rows)
            elif L_rows is None:
                r_idx = (bi[:, None] + np.arange(cols, dtype=idx)[None, :] * rows).ravel()
                k = np.repeat(bk, cols)
            else:
                a, b = np.arange(rows, dtype=idx), np.arange(cols, dtype=idx)
                r_idx = np.broadcast_to(a[None, :, None] + b[None, None, :] * rows, (len(bi), rows, cols)).ravel()
                k = np.repeat(bk, rows * cols)
            cached = (r_idx, k + (1 + var.offset))
        self.plan.cache[key] = cached
        return cached

    def _is_identity(self, factors: tuple[Any, ...]) -> bool:
        return all(_is_identity_factor(f) for f in factors)

    def term_values(self, term: AnyTerm, rows: int, cols: int) -> np.ndarray:
        """Values matching :meth:`_term_index`, unscaled by the coefficient."""
        if term.var is None or self.vars[term.var].kind == "scalar":
            M = self.product(term.left)
            if M is None:
                if rows != cols:
                    raise TemplateError(f"theorem {self.tid}: identity term '{term.text}' in a non-square block")
                M = np.eye(rows)
            if M.shape != (rows, cols):
                raise TemplateError(
                    f"theorem {self.tid}: term '{term.text}' has shape {M.shape}, its block is {rows}x{cols}"
                )
            return M.reshape(-1, order="F")
        key = (term.left, term.var, term.transposed, term.right)
        cached = self._products.get(key)
        if cached is not None:
            return cached
        var = self.vars[term.var]
        bi, bj, _, vr = self.basis(term.var, term.transposed)
        vc = var.shape[0] if term.transposed else var.shape[1]
        L = self.product(term.left)
        R = self.product(term.right)
        if (L is not None and L.shape[1] != vr) or (R is not None and R.shape[0] != vc):
            shapes = " * ".join(
                f"{a}x{b}"
                for a, b in [*([L.shape] if L is not None else []), (vr, vc), *([R.shape] if R is not None else [])]
            )
            raise TemplateError(f"theorem {self.tid}: term '{term.text}' has inconsistent shapes ({shapes})")
        out_r = vr if L is None else L.shape[0]
        out_c = vc if R is None else R.shape[1]
        if (out_r, out_c) != (rows, cols):
            raise TemplateError(
                f"theorem {self.tid}: term '{term.text}' is {out_r}x{out_c}, its block is {rows}x{cols}"
            )
        # the basis entry E_ij contributes the outer product L[:, i] R[j, :]
        if L is None:
            vals = np.ones(len(bi)) if R is None else R[bj, :].ravel()
        elif R is None:
            vals = L[:, bi].T.ravel()
        else:
            vals = (L[:, bi].T[:, :, None] * R[bj, :][:, None, :]).ravel()
        self._products[key] = vals
        return vals

    def entry_pieces(
        self, terms: Sequence[AnyTerm], rows: int, cols: int
    ) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
        """(row in vec(entry), IR column, value) for every term (values scaled by the coefficient)."""
        out = []
        for term in terms:
            c = self.coef(term.coef)
            r, k = self._term_index(term, rows, cols)
            out.append((r, k, c * self.term_values(term, rows, cols)))
        return out

    def _probe(self, pieces, size: int) -> tuple[np.ndarray, np.ndarray]:
        """vec of an entry at the random point ``z`` and the sum of absolute contributions."""
        val, mag = np.zeros(size), np.zeros(size)
        for r, k, v in pieces or ():
            w = v * self._z[k]
            val += np.bincount(r, weights=w, minlength=size)
            mag += np.bincount(r, weights=np.abs(w), minlength=size)
        return val, mag

    # -- LMIs ----------------------------------------------------------------------------
    def lmi(self, lp: LmiPlan | warm.LmiPlan) -> LMI:
        sizes = [self._size(s, f"block row of LMI '{lp.name}'") for s in lp.sizes]
        d = int(sum(sizes))

        def where(i: int, j: int) -> str:
            return f"theorem {self.tid}: LMI '{lp.name}' block ({i + 1},{j + 1})"

        entries: dict[tuple[int, int], Any] = {}

        def entry(i: int, j: int):
            if (i, j) not in lp.entries:
                return None  # zero
            if (i, j) not in entries:
                try:
                    entries[(i, j)] = self.entry_pieces(lp.entries[(i, j)].terms, sizes[i], sizes[j])
                except TemplateError as err:
                    msg = str(err).removeprefix(f"theorem {self.tid}: ")
                    raise TemplateError(f"{where(i, j)}: {msg}") from None
            return entries[(i, j)]

        # which entry fills each lower block, in a fixed order; symmetry checks every bind
        order: list[tuple[int, int, int, int]] = []  # (i, j, source i, source j)
        for j in range(lp.k):
            for i in range(j, lp.k):
                if (i, j) in lp.stars:
                    if entry(j, i) is not None:
                        order.append((i, j, j, i))
                    continue
                Lw = entry(i, j)
                if i != j and (j, i) not in lp.stars:
                    self._check_mirror(Lw, entry(j, i), sizes[i], sizes[j], where(j, i), i, j)
                if Lw is None:
                    continue
                if i == j:
                    self._check_symmetric(Lw, sizes[i], where(i, i))
                order.append((i, j, i, j))
        vals = [v for (_, _, si, sj) in order for (_, _, v) in entries[(si, sj)]]
        v = np.concatenate(vals) if vals else np.zeros(0)
        shape = (tril_size(d), 1 + self.n)
        key = ("lmi", lp.name, self._dims_key, tuple(order))
        structure = self.plan.cache.get(key)
        if structure is None:  # once per plan and dimensions (re-binds only gather the values)
            structure = self._lmi_structure(order, entries, sizes)
            self.plan.cache[key] = structure
        indptr, indices, pos, nslots = structure
        data = np.bincount(pos, weights=v, minlength=nslots + 1)[:nslots]
        if lp.negated:
            np.negative(data, out=data)  # in place: no second array of every coefficient
        coeffs = sp.csc_matrix((data, indices.copy(), indptr.copy()), shape=shape)
        coeffs.has_sorted_indices = True
        coeffs.eliminate_zeros()
        return LMI(lp.name, d, coeffs, lp.strict, lp.relation, tuple(sizes))

    def _lmi_indices(self, order, entries, sizes) -> tuple[np.ndarray, np.ndarray]:
        """Storage row (-1: upper triangle, not stored) and IR column of every value.

        One gather per piece through the block's storage map (:func:`_storage_map`), no index
        arithmetic over the values.
        """
        starts = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
        d = int(starts[-1])
        rows_all, cols_all = [], []
        for i, j, si, sj in order:
            smap = _storage_map(int(starts[i]), int(starts[j]), sizes[i], sizes[j], d, (si, sj) != (i, j))
            for r, k, _ in entries[(si, sj)]:
                rows_all.append(smap[r])
                cols_all.append(k)
        if not rows_all:
            return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
        return np.concatenate(rows_all), np.concatenate(cols_all)

    def _lmi_structure(self, order, entries, sizes) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
        """CSC structure of an LMI and the slot of every value (dims only; cached).

        Returns ``(indptr, indices, pos, nslots)``: rows sorted within each column, duplicates
        merged into one slot, ``pos`` the slot of every value (``nslots`` for dropped ones).

        One stable sort of the keys ``column * rows + storage row`` (the upper triangle of a
        diagonal block above every kept key): the values come in runs already in that order (a
        term's entries by basis column, rows increasing), which the sort merges.
        """
        starts = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
        d = int(starts[-1])
        nrows, ncols = tril_size(d), 1 + self.n
        dropped = nrows * ncols
        idx = _index_dtype(max(nrows, sum(len(r) for i, j, si, sj in order for r, _, _ in entries[(si, sj)])))
        kdt = _index_dtype(dropped + nrows)
        keys = []
        for i, j, si, sj in order:
            smap = _storage_map(int(starts[i]), int(starts[j]), sizes[i], sizes[j], d, (si, sj) != (i, j))
            smap = np.where(smap < 0, dropped, smap).astype(kdt)
            for r, k, _ in entries[(si, sj)]:
                key = smap[r]
                key += k.astype(kdt, copy=False) * nrows
                keys.append(key)
        if not keys:
            return np.zeros(ncols + 1, dtype=idx), np.zeros(0, dtype=idx), np.zeros(0, dtype=np.intp), 0
        key = np.concatenate(keys) if len(keys) > 1 else keys[0]
        perm = np.argsort(key, kind="stable")
        ks = key[perm]
        new = np.empty(len(ks), dtype=bool)
        new[0] = True
        np.not_equal(ks[1:], ks[:-1], out=new[1:])
        slot = np.cumsum(new, dtype=np.intp)
        slot -= 1
        unique = ks[new]
        nslots = int(np.searchsorted(unique, dropped))
        np.minimum(slot, nslots, out=slot)  # dropped entries go to a spare slot
        pos = np.empty(len(key), dtype=np.intp)
        pos[perm] = slot
        unique = unique[:nslots]
        indptr = np.searchsorted(unique, np.arange(ncols + 1, dtype=np.int64) * nrows).astype(idx)
        return indptr, (unique % nrows).astype(idx, copy=False), pos, nslots

    def _check_symmetric(self, pieces, r: int, where: str) -> None:
        val, mag = self._probe(pieces, r * r)
        M, S = val.reshape((r, r), order="F"), mag.reshape((r, r), order="F")
        if np.any(np.abs(M - M.T) > _SYM_TOL * (S + S.T + 1e-300)):
            raise TemplateError(f"{where} is not symmetric (a diagonal block must equal its transpose)")

    def _check_mirror(self, Lw, U, ri: int, cj: int, where_upper: str, i: int, j: int) -> None:
        """An explicit upper block must be the transpose of the explicit lower one."""
        if Lw is None and U is None:
            return
        lv, lm = self._probe(Lw, ri * cj)
        uv, um = self._probe(U, ri * cj)
        Lz, Ls = lv.reshape((ri, cj), order="F"), lm.reshape((ri, cj), order="F")
        Uz, Us = uv.reshape((cj, ri), order="F").T, um.reshape((cj, ri), order="F").T
        if np.any(np.abs(Lz - Uz) > _SYM_TOL * (Ls + Us + 1e-300)):
            raise TemplateError(
                f"{where_upper} is not the transpose of block ({i + 1},{j + 1}): write '*' (STAR) "
                "for one of them, or make them agree"
            )

    # -- linear forms ----------------------------------------------------------------------
    def _trace_row(self, terms: Sequence[AnyTerm]) -> np.ndarray:
        """Row of ``trace(sum of terms)``: ``trace(L V R)`` is linear in ``V`` with weights ``(R L)^T``."""
        row = np.zeros(1 + self.n)
        for term in terms:
            c = self.coef(term.coef)
            if term.var is None or self.vars[term.var].kind == "scalar":
                M = self.product(term.left)
                value = float(np.trace(M)) if M is not None else None
                if value is None:
                    raise TemplateError(f"theorem {self.tid}: trace of an identity of unknown size in '{term.text}'")
                row[0 if term.var is None else 1 + self.vars[term.var].offset] += c * value
                continue
            var = self.vars[term.var]
            bi, bj, bk, vr = self.basis(term.var, term.transposed)
            vc = var.shape[0] if term.transposed else var.shape[1]
            L, R = self.product(term.left), self.product(term.right)
            Lm = np.eye(vr) if L is None else L
            Rm = np.eye(vc) if R is None else R
            RL = Rm @ Lm  # (vc x vr); trace(L E_ij R) = (R L)[j, i]
            np.add.at(row, 1 + var.offset + bk, c * RL[bj, bi])
        return row

    def linear_row(self, form: LinearForm | warm.LinearForm) -> np.ndarray:
        row = np.zeros(1 + self.n)
        row[0] = self.coef(form.const) if form.const != 0 else 0.0
        for coef, terms in form.traces:
            row += self.coef(coef) * self._trace_row(terms)
        for coef, (name, kind, i, j) in form.terms:
            c = self.coef(coef)
            var = self.vars[name]
            if kind == "scalar":
                row[1 + var.offset] += c
                continue
            bi, bj, bk, _ = self.basis(name, False)  # unit-valued basis triplets (cached per dims)
            if kind == "entry":
                if not (0 <= i < var.shape[0] and 0 <= j < var.shape[1]):
                    raise TemplateError(f"theorem {self.tid}: entry ({i},{j}) outside variable '{name}'")
                hit = (bi == i) & (bj == j)
            else:  # trace
                hit = bi == bj
            np.add.at(row, 1 + var.offset + bk[hit], c)
        return row

    def problem(self, system: System) -> Problem:
        plan = self.plan
        lmis = [self.lmi(lp) for lp in plan.lmis]
        rows, kinds, strict, names = [], [], [], []
        for name, kind, is_strict, form in plan.constraints:
            rows.append(self.linear_row(form))
            kinds.append(kind)
            strict.append(is_strict)
            names.append(name)
        for decl in plan.template.variables:  # element-wise signs of matrix variables
            if decl.kind == "scalar" or decl.sign == "free":
                continue
            var = self.vars[decl.name]
            flip = -1.0 if decl.sign in ("negative", "nonpositive") else 1.0
            rel = {"positive": "> 0", "nonnegative": ">= 0", "negative": "< 0", "nonpositive": "<= 0"}[decl.sign]
            for k in range(var.size):
                row = np.zeros(1 + self.n)
                row[1 + var.offset + k] = flip
                rows.append(row)
                kinds.append("ge")
                strict.append(decl.sign in ("positive", "negative"))
                names.append(f"{decl.name}[{k}] {rel}")
        A = sp.csr_matrix(np.array(rows)) if rows else sp.csr_matrix((0, 1 + self.n))
        linear = LinearConstraints(A, kinds, strict, names)
        sense, form = plan.objective
        objective = Objective(sense, self.linear_row(form) if sense != "feasibility" else np.zeros(1 + self.n))
        t = plan.template
        derived = [NamedExpr(d.name, _tree(d.expr, self.dims), d.doc) for d in t.derived]
        checks = [Check(c.name, c.spec.kind, _tree(c.spec.expr, self.dims), c.spec.bound, c.doc) for c in t.checks]
        data = {k: (v.copy() if isinstance(v, np.ndarray) else float(v)) for k, v in self.env.items()}
        meta = {
            "theorem": plan.id,
            "title": plan.theorem.title,
            "citation": plan.theorem.citation,
            "params": dict(self.inp.params),
            "options": dict(plan.options),
            "dims": {str(k): v for k, v in self.dims.items()},
            "system": system.name,
            "system_path": system.path,
            "data_hash": system.data_hash(),
            "lmic_version": __version__,
            # which theorem this is: its provider and a hash of the analysed template (certificates)
            **template_identity(plan),
        }
        if t.observer_decl is not None:
            ob = t.observer_decl
            meta["observer"] = {"model": ob.model, "time": ob.time, "roles": dict(ob.roles)}
        problem = Problem(list(self.vars.values()), lmis, linear, objective, data, derived, checks, meta)
        # the plan it was bound from, for its exact recompilation (lmic.compile.exact.exact_of):
        # a theorem passed as an object is not in the registry, so its id alone cannot find it
        setattr(problem, BOUND_PLAN, plan)
        return problem


#: the attribute of a bound Problem that holds the plan it was bound from (not part of the IR:
#: ``dataclasses.replace`` and every transformation drop it, and the recompilation then goes by
#: the theorem's id)
BOUND_PLAN = "_lmic_bound_plan"


def template_identity(plan: Plan | FrozenPlan) -> dict[str, Any]:
    """``provider`` (distribution, version) and ``template`` (hash and per-declaration parts) of a plan.

    >>> from lmic.compile import plan_for
    >>> ident = template_identity(plan_for("thesis.lyapunov"))
    >>> ident["provider"]["distribution"], len(ident["template"]["sha256"])
    ('lmic', 64)
    """
    if isinstance(plan, FrozenPlan):  # recorded when it was frozen
        return plan.identity()
    from lmic.template.builder import template_hash
    from lmic.template.theorem import Provider

    parts = plan.cache.get("template_parts")
    if parts is None:
        parts = plan.cache["template_parts"] = plan.template.fingerprint()
    provider = plan.theorem.provider or Provider.api(plan.theorem)
    return {"provider": provider.to_dict(), "template": {"sha256": template_hash(parts), "parts": dict(parts)}}


def bind(plan: Plan | FrozenPlan, system: Any, params: Mapping[str, Any] | None = None) -> Problem:
    """Compile ``plan`` with the numbers of ``system`` (path, dict or System) into an IR Problem.

    Parameters
    ----------
    plan : Plan or lmic.compile.warm.FrozenPlan
    system : str, path, dict or System
    params : mapping, optional
        Parameter overrides (``-p k=v``).
    """
    from lmic.compile.probe import probe_shapes

    sysobj = load_system(system)
    inputs = resolve_inputs(plan, sysobj, params)
    problem = _Binder(plan, inputs).problem(sysobj)
    key = (id(plan), tuple(sorted(problem.meta["dims"].items())))
    if key not in _PROBED:  # once per plan and dimensions (a sweep re-binds the same shapes)
        probe_shapes(problem)
        _PROBED.add(key)
    return problem


#: (plan, dimensions) whose derived quantities and checks :func:`lmic.compile.probe.probe_shapes`
#: has evaluated
_PROBED: set[tuple[int, tuple]] = set()
