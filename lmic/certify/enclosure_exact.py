"""Exact mode of the enclosure: the repaired dual point corrected and proved in rationals.

The correction ``u* = u + J_S^T M^{-1} rho`` is computed exactly (python-flint), every ``Z_i*``
is proved PSD by an integer ``LDL^T`` (:func:`lmic.certify.exact.prove_psd`), ``y_r* >= 0``
checked exactly, and ``L = q_0 - g_0(u*)`` is exact (reported rounded down). It costs a rational
solve of order ``n`` (:data:`EXACT_MAX_N`).

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
>>> from lmic.certify.enclosure_repair import jacobian
>>> p = Problem([Variable("t", "scalar", (1, 1))], [LMI("t >= 2", 1, sp.csc_matrix([[-2.0, 1.0]]))],
...             LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
>>> J, ranges = jacobian(p)
>>> prove_exact(p, J, ranges, np.array([0.0, 1.0]), [np.eye(1)], np.zeros(0))["lower_exact"]
'2'
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from lmic.certify.enclosure_float import down as _down
from lmic.certify.enclosure_repair import _default_active, _pack
from lmic.ir.problem import Problem
from lmic.ir.svec import tril_rows_cols

__all__ = ["EXACT_MAX_N", "prove_exact"]

#: largest number of variables the exact (rational) correction is attempted for
EXACT_MAX_N = 400


def _prove_exact(problem: Problem, J, ranges, q, mats, y) -> dict[str, Any]:
    from fractions import Fraction

    from lmic.certify.exact import _flint, prove_psd

    flint = _flint()
    n = problem.n
    if n > EXACT_MAX_N:
        return {"proven": False, "reason": f"{n} variables: above the exact limit {EXACT_MAX_N}"}
    ge = np.array([k == "ge" for k in problem.linear.kinds], dtype=bool)
    u = _pack(problem, mats, y)

    def fq(v: float) -> Any:
        f = Fraction(float(v))
        return flint.fmpq(f.numerator, f.denominator)

    Jc = J.tocsr()
    active = _default_active(problem, ranges, u)
    uq = [fq(v) for v in u]

    def row(k: int) -> dict[int, Any]:
        a, b = Jc.indptr[k], Jc.indptr[k + 1]
        return {int(j): fq(v) for j, v in zip(Jc.indices[a:b], Jc.data[a:b], strict=True)}

    # exact residual over every entry; the correction moves only the active ones
    rows, rho = [], []
    for k in range(1, 1 + n):
        full = row(k)
        res = fq(q[k]) - sum((v * uq[j] for j, v in full.items()), flint.fmpq(0))
        act = {j: v for j, v in full.items() if active[j]}
        if not act:
            if res != 0:
                return {"proven": False, "reason": f"x[{k - 1}] has a residual no active multiplier can absorb"}
            continue
        rows.append(act)
        rho.append(res)
    p = len(rows)
    if p:
        Mq = flint.fmpq_mat(p, p)
        for a in range(p):
            ra = rows[a]
            for b in range(a, p):
                rb = rows[b]
                s = flint.fmpq(0)
                small, big = (ra, rb) if len(ra) <= len(rb) else (rb, ra)
                for j, v in small.items():
                    w = big.get(j)
                    if w is not None:
                        s += v * w
                Mq[a, b] = s
                Mq[b, a] = s
        try:
            w = Mq.solve(flint.fmpq_mat([[r] for r in rho]))
        except ZeroDivisionError:
            return {"proven": False, "reason": "the dual equality system is singular in exact arithmetic"}
        ustar = list(uq)
        for a in range(p):
            wa = w[a, 0]
            if wa != 0:
                for j, v in rows[a].items():
                    ustar[j] += v * wa
    else:
        ustar = list(uq)
    # exact checks: Z_i* PSD, y* >= 0 on ge rows
    for lmi, (a, b) in zip(problem.lmis, ranges, strict=True):
        if not lmi.dim:
            continue
        vals = [Fraction(int(v.p), int(v.q)) for v in ustar[a:b]]
        den = 1
        for f in vals:
            den = den * f.denominator // math.gcd(den, f.denominator)
        ri, ci = tril_rows_cols(lmi.dim)
        Mi = [[0] * lmi.dim for _ in range(lmi.dim)]
        for f, r_, c_ in zip(vals, ri, ci, strict=True):
            Mi[r_][c_] = Mi[c_][r_] = int(f * den)
        pr = prove_psd(Mi)
        if not pr["proven"]:
            return {"proven": False, "reason": f"exact multiplier of LMI '{lmi.name}' not proved PSD ({pr['detail']})"}
    off = ranges[-1][1] if ranges else 0
    for r in range(len(y)):
        if ge[r] and ustar[off + r] < 0:
            return {"proven": False, "reason": f"exact multiplier of row '{problem.linear.names[r]}' is negative"}
    r0 = row(0)
    g0 = sum((v * ustar[j] for j, v in r0.items()), flint.fmpq(0))
    L = fq(q[0]) - g0
    Lf = Fraction(int(L.p), int(L.q))
    lower = float(Lf)
    if Fraction(lower) > Lf:
        lower = _down(lower)
    return {
        "proven": True,
        "lower": lower,
        "lower_exact": f"{Lf.numerator}/{Lf.denominator}" if Lf.denominator != 1 else str(Lf.numerator),
        "reason": "dual point corrected and proved feasible in exact rational arithmetic",
    }


#: public name
prove_exact = _prove_exact
