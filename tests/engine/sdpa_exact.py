"""Independent exact checks for the upper-end tests (no lmic code): an SDPA file read on its own,
``F(x) = sum_i x_i F_i - F0`` formed in rational arithmetic and proved positive definite by
exact Gaussian elimination (every leading pivot ``> 0``), the objective ``c . x`` exactly.

The approach of /work/indep/exact_psd.py, copied so that a test depends on nothing but the
shipped SDPLIB files.
"""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path


def read_sdpa(path: str | Path) -> tuple[int, list[int], list[Fraction], dict[tuple[int, int], dict]]:
    """``(m, block sizes, c, F)`` with ``F[(mat, block)][(i, j)]`` exact (1-based indices)."""
    toks: list[str] = []
    for line in Path(path).read_text().splitlines():
        if line.lstrip().startswith(('"', "*")):
            continue
        for ch in ",{}()":
            line = line.replace(ch, " ")
        toks += line.split()
    m, nb = int(toks[0]), int(toks[1])
    sizes = [int(t) for t in toks[2 : 2 + nb]]
    c = [Fraction(t) for t in toks[2 + nb : 2 + nb + m]]
    rest = toks[2 + nb + m :]
    F: dict[tuple[int, int], dict] = {}
    for k in range(0, len(rest), 5):
        mat, blk, i, j, v = int(rest[k]), int(rest[k + 1]), int(rest[k + 2]), int(rest[k + 3]), Fraction(rest[k + 4])
        F.setdefault((mat, blk), {})[(i, j)] = v
    return m, sizes, c, F


def positive_definite(M: list[list[Fraction]]) -> bool:
    """Exact: every pivot of Gaussian elimination without pivoting is positive."""
    rows = [list(r) for r in M]
    n = len(rows)
    for k in range(n):
        p = rows[k][k]
        if p <= 0:
            return False
        for i in range(k + 1, n):
            f = rows[i][k] / p
            if f:
                for j in range(k, n):
                    rows[i][j] -= f * rows[k][j]
    return True


def check_point(path: str | Path, x: list[float]) -> tuple[bool, Fraction]:
    """``(every block of F(x) positive definite, c . x)``, exactly, for the float point ``x``."""
    m, sizes, c, F = read_sdpa(path)
    xq = [Fraction(float(v)) for v in x]
    assert len(xq) == m
    ok = True
    for b, s in enumerate(sizes, 1):
        n = abs(s)
        M = [[Fraction(0)] * n for _ in range(n)]
        for mat in range(m + 1):
            coef = Fraction(-1) if mat == 0 else xq[mat - 1]
            for (i, j), v in F.get((mat, b), {}).items():
                M[i - 1][j - 1] += coef * v
                if i != j:
                    M[j - 1][i - 1] += coef * v
        if s < 0:  # a diagonal block: its entries
            ok = ok and all(M[i][i] > 0 for i in range(n))
        else:
            ok = ok and positive_definite(M)
    return ok, sum((ci * xi for ci, xi in zip(c, xq, strict=True)), Fraction(0))
