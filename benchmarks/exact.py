"""Benchmark: exact proof of the qib.thm1 LMI (size 3n) at a float point, n = 20, 40, 60.

The LMI of Wang, Song & Zhang (2015), Theorem 1, in ``(P, R, omega)``::

    [ -P + 2 w beta I , A^T P - C^T R + w gamma I , A^T P - C^T R ]
    [  *              , P - 2 w I                 , 0             ]  < 0,   P > 0
    [  *              , *                         , -P            ]

is built directly as an IR (no compiler needed) on a random system with ``||A|| = 0.5``, at a
strictly feasible float point with full 53-bit mantissas (``P = I + small``, ``R = small``,
``omega = 1 + small``), then certified with ``exact=True``. The target is under 1 s at size 180.
The proof is made at the float point itself (its own dyadic denominator, ~2^79 here), which
costs about as much as a coarse margin-preserving rounding (~2^18) did.

Run ``python benchmarks/exact.py [n ...]``; it prints one line per size.
"""

from __future__ import annotations

import sys
import time

import numpy as np
import scipy.sparse as sp

from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
from lmic.ir.svec import tril_index, tril_rows_cols
from lmic.solution import Solution

__all__ = ["qib_thm1_problem", "feasible_point", "run"]


def _commutation(r: int, c: int) -> sp.csr_matrix:
    """``K`` with ``vec(X^T) = K vec(X)`` for ``X`` of shape ``r x c``."""
    idx = np.arange(r * c)
    i, j = idx % r, idx // r  # X[i, j] at vec position j r + i
    return sp.csr_matrix((np.ones(r * c), (i * c + j, idx)), shape=(r * c, r * c))


def qib_thm1_problem(n: int, p: int, seed: int = 0, beta: float = 0.00110889, gamma: float = 0.0) -> Problem:
    """The qib.thm1 IR for a random ``(A, C)`` with ``||A||_2 = 0.5``.

    Examples
    --------
    >>> prob = qib_thm1_problem(3, 1)
    >>> [lmi.dim for lmi in prob.lmis], prob.n
    ([9, 3], 10)
    """
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    A *= 0.5 / np.linalg.norm(A, 2)
    C = rng.standard_normal((p, n))
    P = Variable("P", "symmetric", (n, n), offset=0)
    R = Variable("R", "full", (p, n), offset=P.size)
    w = Variable("omega", "scalar", (1, 1), offset=P.size + R.size)
    N = P.size + R.size + 1
    BP = sp.hstack([P.basis(), sp.csc_matrix((n * n, N - P.size))]).tocsr()
    BRt = sp.hstack(
        [sp.csc_matrix((n * p, P.size)), _commutation(p, n) @ R.basis(), sp.csc_matrix((n * p, 1))]
    ).tocsr()  # vec(R^T)
    Bw = sp.csr_matrix(([1.0], ([0], [N - 1])), shape=(1, N))
    I = np.eye(n)
    vecI = sp.csr_matrix(I.reshape(-1, 1, order="F"))

    def lin(L, B, Rm):  # vec(L V Rm) as a map of x
        return sp.kron(sp.csr_matrix(Rm).T, sp.csr_matrix(L)) @ B

    # lower blocks of M (the "< 0" matrix); F = -M is stored
    blocks = {
        (0, 0): -BP + 2 * beta * vecI @ Bw,
        (1, 0): lin(I, BP, A) - lin(I, BRt, C) + gamma * vecI @ Bw,  # P A - R^T C + w g I
        (2, 0): lin(I, BP, A) - lin(I, BRt, C),
        (1, 1): BP - 2 * vecI @ Bw,
        (2, 2): -BP,
    }
    d = 3 * n
    rows, cols = tril_rows_cols(d)
    parts = []
    for (bi, bj), M in blocks.items():
        M = sp.csr_matrix(M)
        r, c = np.arange(n * n) % n, np.arange(n * n) // n
        gi, gj = bi * n + r, bj * n + c
        keep = gi >= gj
        target = tril_index(gi[keep], gj[keep], d)
        sel = sp.csr_matrix((np.ones(keep.sum()), (target, np.flatnonzero(keep))), shape=(len(rows), n * n))
        parts.append(sel @ M)
    Fx = -sum(parts)
    coeffs = sp.hstack([sp.csc_matrix((len(rows), 1)), Fx]).tocsc()
    lmi = LMI("qib.thm1 (7)", d, coeffs, strict=True, relation="<", block_sizes=(n, n, n))
    pr, pc = tril_rows_cols(n)
    pos = sp.hstack([sp.csc_matrix((len(pr), 1)), BP[pc * n + pr]]).tocsc()
    lmi_p = LMI("P > 0", n, pos, strict=True, relation=">")
    return Problem(
        [P, R, w],
        [lmi, lmi_p],
        LinearConstraints.empty(N),
        Objective("feasibility", np.zeros(1 + N)),
        data={"A": A.tolist(), "C": C.tolist(), "beta": beta, "gamma": gamma},
        meta={"theorem": "qib.thm1", "benchmark": True},
    )


def feasible_point(prob: Problem, seed: int = 1, size: float = 1e-2) -> np.ndarray:
    """A strictly feasible float point near ``P = I, R = 0, omega = 1``."""
    rng = np.random.default_rng(seed)
    n = prob.variable("P").shape[0]
    p = prob.variable("R").shape[0]
    S = rng.standard_normal((n, n))
    return prob.pack(
        {
            "P": np.eye(n) + size * (S + S.T) / np.sqrt(n),
            "R": size * rng.standard_normal((p, n)) / (np.sqrt(n) + np.sqrt(p)) ** 2,
            "omega": 1.0 + size * rng.standard_normal(),
        }
    )


def run(n: int, p: int | None = None) -> dict:
    """Certify the size-``3n`` problem exactly; return timings and denominators."""
    from lmic.certify import certify

    prob = qib_thm1_problem(n, p or max(1, n // 2))
    x = feasible_point(prob)
    t0 = time.perf_counter()
    cert = certify(prob, Solution("feasible", x=x, backend="benchmark"), exact=True)
    total = time.perf_counter() - t0
    e = cert.exact
    return {
        "size": 3 * n,
        "verdict": cert.label,
        "exact_s": e["time_s"],
        "certify_s": total,
        "denominator": e["denominator"],
        "at_x": e["at_x"],
        "method": e["lmis"][0]["method"],
        "entry_bits": e["lmis"][0]["entry_bits"],
        "min_eig": cert.lmis[0]["min_eig"],
    }


if __name__ == "__main__":
    sizes = [int(a) for a in sys.argv[1:]] or [20, 40, 60]
    for n in sizes:
        r = run(n)
        print(
            f"size {r['size']:4d}: {r['verdict']:<18} exact {r['exact_s']:.3f} s "
            f"(certify total {r['certify_s']:.3f} s), denominator {r['denominator']}"
            f"{' (x itself)' if r['at_x'] else ' (rounded)'}, "
            f"method {r['method']}, entry bits {r['entry_bits']}, lambda_min {r['min_eig']:.3g}"
        )
