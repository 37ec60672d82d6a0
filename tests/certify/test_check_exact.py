"""Definiteness checks decided exactly when the floating-point evaluation cannot decide them
(lmic/certify/check_exact.py): a check that holds at the point is never a 'rejected' for a
rounding error; one that fails exactly stays failed."""

from __future__ import annotations

from fractions import Fraction

import numpy as np

import lmic
from lmic.certify.check_exact import decide, exact_matrix
from lmic.ir.problem import Check
from lmic.template import I, negative_definite, theorem

N = 9
H = np.array([[1.0 / (i + j + 1) for j in range(N)] for i in range(N)])  # Hilbert: condition 1e12


def _exact_inverse(M: np.ndarray) -> list[list[Fraction]]:
    """Gauss-Jordan in Python fractions (independent of python-flint)."""
    n = len(M)
    a = [[Fraction(float(M[i][j])) for j in range(n)] + [Fraction(int(i == j)) for j in range(n)] for i in range(n)]
    for c in range(n):
        p = next(r for r in range(c, n) if a[r][c] != 0)
        a[c], a[p] = a[p], a[c]
        piv = a[c][c]
        a[c] = [v / piv for v in a[c]]
        for r in range(n):
            if r != c and a[r][c] != 0:
                f = a[r][c]
                a[r] = [u - f * v for u, v in zip(a[r], a[c], strict=True)]
    return [row[n:] for row in a]


def _negative_definite_exactly(E: list[list[Fraction]]) -> bool:
    """All leading minors of -E positive (Sylvester), by fraction elimination."""
    m = [[-v for v in row] for row in E]
    n = len(m)
    for c in range(n):
        if m[c][c] <= 0:
            return False
        for r in range(c + 1, n):
            f = m[r][c] / m[c][c]
            m[r] = [u - f * v for u, v in zip(m[r], m[c], strict=True)]
    return True


HINV = _exact_inverse(H)
G = np.array([[float(v) for v in row] for row in HINV])  # the exact inverse, rounded


@theorem(id="nb.ill_check", title="t", citation="c", kind="analysis")
def ill_check(t):
    (n,) = t.dims("n")
    Hd, Gd = t.data("H", n, n), t.data("G", n, n)
    P = t.symmetric("P", n, pd=True)
    t.lmi("P < I", P - I(n) < 0)
    # inv(H) - G is exactly the rounding error of G (entries <= 2e-3): below 1 I, negative definite
    t.check("inverse recomputed", negative_definite(Hd.inv() - Gd - I(n)))


def test_the_ill_conditioned_check_fails_in_floats_and_holds_exactly():
    E = [[HINV[i][j] - Fraction(float(G[i, j])) - int(i == j) for j in range(N)] for i in range(N)]
    assert _negative_definite_exactly(E)  # the truth, in Python fractions
    float_E = np.linalg.inv(H) - G - np.eye(N)
    assert np.linalg.eigvalsh(0.5 * (float_E + float_E.T))[-1] > 0  # floating point says it fails
    r = lmic.solve(ill_check, {"data": {"H": H.tolist(), "G": G.tolist()}})
    (check,) = r.certificate.checks
    assert r.verdict == "certified" and check["ok"] and check["exact"] == "holds"
    assert "holds exactly at the point" in check["note"]


def test_a_check_that_fails_exactly_stays_failed():
    expr = {"op": "add", "args": [{"op": "inv", "args": [{"name": "H"}]}, {"op": "neg", "args": [{"name": "G"}]}]}
    env = {"H": exact_matrix(H), "G": exact_matrix(G)}
    # inv(H) - G (without the -I) is the rounding error itself: indefinite, exactly
    truth = [[HINV[i][j] - Fraction(float(G[i, j])) for j in range(N)] for i in range(N)]
    assert not _negative_definite_exactly(truth)
    assert decide(Check("c", "negative_definite", expr), env) is False
    assert decide(Check("c", "hurwitz", expr), env) is None  # not a kind decided exactly
    sqrt = {"op": "sqrt", "args": [{"name": "H"}]}
    assert decide(Check("c", "negative_definite", sqrt), env) is None  # no exact value
