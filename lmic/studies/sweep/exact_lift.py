"""The exact counterpart of a lifted problem (:func:`lmic.studies.sweep.enclosed.lift`).

:func:`~lmic.studies.sweep.enclosed.lift` makes an affine parameter ``p`` a decision variable:
every constant column becomes ``c0 + p g`` with ``g = (C(v1) - C(v0)) / (v1 - v0)`` and ``c0 =
C(v0) - v0 g``, computed in floating point from the problems bound at two values ``v0, v1``.
The proofs that need the exact structure of a template (the face route of
:mod:`lmic.certify.enclosure_face`) need the same combination in rational arithmetic:
:func:`exact_lift` takes the exact counterparts of the two bound problems
(:func:`lmic.compile.exact.exact_of`) and combines them exactly, after checking exactly that
``p`` enters no coefficient of a decision variable. Anything else declines
(:class:`~lmic.compile.exact.ExactUnavailable`, with the reason).

Examples
--------
>>> import scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
>>> from lmic.studies.sweep.enclosed import lift
>>> P = lambda v: Problem([Variable("q", "scalar", (1, 1))],
...     [LMI("v - q > 0", 1, sp.csc_matrix([[v, -1.0]]))], LinearConstraints.empty(1),
...     Objective("feasibility", [0.0, 0.0]))
>>> L = lift([P(0.1), P(0.3)], [0.1, 0.3], "v", "min", (0.0, 1.0, True, True))
>>> ex = exact_lift(P(0.1), P(0.3), 0.1, 0.3, L, "v")
>>> [ex.lmis[0].value(0, k) for k in range(3)]     # c0, the coefficient of q, g: exactly 0, -1, 1
[Fraction(0, 1), Fraction(-1, 1), Fraction(1, 1)]
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np

from lmic.compile.exact import ExactLMI, ExactProblem, ExactUnavailable, exact_of
from lmic.ir.problem import Problem
from lmic.ir.svec import tril_size

__all__ = ["exact_lift"]

Column = dict[int, Fraction]


def _columns(lmi: ExactLMI) -> list[Column]:
    """Every column of an exact LMI as ``{row: value}``."""
    out = []
    for k in range(len(lmi.indptr) - 1):
        rows, num = lmi.column(k)
        out.append({int(r): Fraction(int(v), lmi.den) for r, v in zip(rows.tolist(), num, strict=True) if v})
    return out


def _widen(col0: list[Column], col1: list[Column], v0: Fraction, v1: Fraction, what: str) -> list[Column]:
    """``[c0, columns 1.. of col0, g]`` (module docstring), exactly; the variables' columns of
    the two bound problems must be equal."""
    if any(a != b for a, b in zip(col0[1:], col1[1:], strict=True)):
        raise ExactUnavailable(f"the lifted parameter enters a coefficient of a decision variable in {what}")
    g = {
        r: (col1[0].get(r, Fraction(0)) - col0[0].get(r, Fraction(0))) / (v1 - v0)
        for r in col0[0].keys() | col1[0].keys()
    }
    c0 = {r: col0[0].get(r, Fraction(0)) - v0 * g.get(r, Fraction(0)) for r in col0[0].keys() | g.keys()}
    return [{r: v for r, v in c0.items() if v}, *col0[1:], {r: v for r, v in g.items() if v}]


def _exact_lmi(name: str, dim: int, columns: list[Column]) -> ExactLMI:
    """An :class:`ExactLMI` from its columns (one common denominator)."""
    den = 1
    for col in columns:
        for v in col.values():
            den = den * v.denominator // math.gcd(den, v.denominator)
    indptr, indices, num = [0], [], []
    for col in columns:
        for r in sorted(col):
            indices.append(r)
            num.append(int(col[r] * den))
        indptr.append(len(indices))
    nums = np.empty(len(num), dtype=object)
    nums[:] = num
    return ExactLMI(name, dim, np.array(indptr, dtype=np.int64), np.array(indices, dtype=np.int64), nums, den)


def exact_lift(p0: Problem, p1: Problem, v0: float, v1: float, lifted: Problem, name: str) -> ExactProblem:
    """The exact counterpart of ``lifted`` (module docstring), from the bound problems ``p0``
    and ``p1`` at the parameter values ``v0`` and ``v1``.

    Raises
    ------
    ExactUnavailable
        When either bound problem has no exact counterpart, the parameter enters a decision
        variable's coefficient exactly (not only in floating point), or the shapes differ.
    """
    e0, e1 = exact_of(p0), exact_of(p1)
    q0, q1 = Fraction(float(v0)), Fraction(float(v1))
    if q0 == q1 or len(e0.lmis) != len(lifted.lmis) or len(e1.lmis) != len(lifted.lmis):
        raise ExactUnavailable(f"the problems lifted in '{name}' do not match")
    lmis = []
    for a, b in zip(e0.lmis, e1.lmis, strict=True):
        cols = _widen(_columns(a), _columns(b), q0, q1, f"LMI '{a.name}'")
        if max((max(c, default=-1) for c in cols), default=-1) >= tril_size(a.dim):
            raise ExactUnavailable(f"LMI '{a.name}' does not match its lifted problem")
        lmis.append(_exact_lmi(a.name, a.dim, cols))
    n = p0.n
    linear: list[Column] = []
    for r0, r1 in zip(e0.linear, e1.linear, strict=True):
        c0 = [{0: r0[k]} if r0.get(k) else {} for k in range(1 + n)]
        c1 = [{0: r1[k]} if r1.get(k) else {} for k in range(1 + n)]
        wide = _widen(c0, c1, q0, q1, "a linear row")
        linear.append({k: c[0] for k, c in enumerate(wide) if c})
    A = lifted.linear.A.tocsr()
    for r in range(len(e0.linear), len(lifted.linear)):  # the parameter's domain: lift's own rows
        cols, vals = A.indices[A.indptr[r] : A.indptr[r + 1]], A.data[A.indptr[r] : A.indptr[r + 1]]
        linear.append({int(k): Fraction(float(v)) for k, v in zip(cols, vals, strict=True) if v})
    objective = [Fraction(float(v)) for v in lifted.objective.c]
    return ExactProblem(lmis, linear, objective, e0.about, f"{e0.source}, lifted in '{name}' exactly")
