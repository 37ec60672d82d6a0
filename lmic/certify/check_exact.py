"""Definiteness checks decided exactly where the floating-point evaluation cannot decide them.

A theorem's check (``t.check``, e.g. ``negative_definite(block(...))`` of the original
inequality before a change of variables) is evaluated in floating point at the certified point
(:func:`lmic.certify.derived.evaluate_checks`). Near the optimum the point can be nearly
singular: a newcomer's H-infinity state feedback, ``K = Y X^-1`` with ``lambda_min(X) = 1e-7``
and ``|K|`` about ``1e7``, gave ``lambda_max = +7.3e-4`` for the closed-loop check ``P = X^-1``
in floating point, while the check holds at the point (``-1.66e-8`` in 60-digit arithmetic): the
answer was ``rejected`` for a rounding error.

:func:`recheck` re-evaluates such a failed check in rational arithmetic (python-flint
``fmpq_mat``) at the point itself: every float of the point and of the data is a rational
number, the derived quantities (inverses, products, blocks) are recomputed exactly, and the
definiteness is proved or disproved exactly (:func:`lmic.certify.psd.prove_pd`). A check that
holds exactly is ``ok`` with ``exact: "holds"``; one that fails exactly keeps its verdict with
``exact: "fails"``. Expressions with operations that have no exact value (``sqrt``, ``exp``,
eigenvalues) or matrices above :data:`MAX_DIM` keep the float verdict.

Examples
--------
>>> import numpy as np
>>> from lmic.ir.problem import Check
>>> c = Check("X^-1 < 0", "negative_definite", {"op": "inv", "args": [{"name": "X"}]})
>>> decide(c, {"X": exact_matrix(-np.eye(2))})
True
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from lmic.certify.psd import load_flint, prove_pd
from lmic.ir.problem import Check, Problem

__all__ = ["KINDS", "MAX_DIM", "decide", "exact_environment", "exact_matrix", "exact_value", "recheck"]

#: the check kinds decided exactly (a strict definiteness: its proof is a positive LDL')
KINDS = ("negative_definite", "positive_definite")
#: the largest checked matrix decided exactly
MAX_DIM = 60


class Unsupported(Exception):
    """An expression with no exact rational value (or too large for one)."""


def _q(v: float) -> Any:
    p, q = float(v).as_integer_ratio()  # every finite float is exactly p / q
    return load_flint().fmpq(p, q)


def exact_matrix(a: Any) -> Any:
    """The float array ``a`` as an exact rational matrix (``fmpq_mat``).

    >>> exact_matrix(np.array([[0.5, 0.1]]))[0, 1] == load_flint().fmpq(3602879701896397, 36028797018963968)
    True
    """
    arr = np.atleast_2d(np.asarray(a, dtype=float))
    if not np.all(np.isfinite(arr)):
        raise Unsupported("a value is not finite")
    r, c = arr.shape
    return load_flint().fmpq_mat(r, c, [_q(v) for v in arr.ravel()])


def _is_mat(v: Any) -> bool:
    return hasattr(v, "nrows")


def _mat(v: Any) -> Any:
    flint = load_flint()
    return v if _is_mat(v) else flint.fmpq_mat(1, 1, [v])


def _entrywise(a: Any, b: Any, fn: Any) -> Any:
    a, b = _mat(a), _mat(b)
    if (a.nrows(), a.ncols()) != (b.nrows(), b.ncols()):
        raise Unsupported("shapes differ")
    return load_flint().fmpq_mat(
        a.nrows(), a.ncols(), [fn(a[i, j], b[i, j]) for i in range(a.nrows()) for j in range(a.ncols())]
    )


def _add(*args: Any) -> Any:
    """As :mod:`lmic.ir.expr`'s sum: matrices of one shape, a zero scalar dropped beside a matrix."""
    out: Any = load_flint().fmpq(0)
    for a in args:
        if _is_mat(out) and _is_mat(a):
            if (out.nrows(), out.ncols()) != (a.nrows(), a.ncols()):
                raise Unsupported("a sum of matrices of different shapes")
            out = out + a
        elif _is_mat(out) or _is_mat(a):
            scalar = a if _is_mat(out) else out
            if scalar != 0:
                raise Unsupported("a non-zero scalar added to a matrix")
            out = out if _is_mat(out) else a
        else:
            out = out + a
    return out


def _mul(*args: Any) -> Any:
    out = args[0]
    for b in args[1:]:
        out = out * b
    return out


def _transpose(a: Any) -> Any:
    return a.transpose() if _is_mat(a) else a


def _inv(a: Any) -> Any:
    if _is_mat(a):
        if a.nrows() != a.ncols():
            raise Unsupported("the inverse of a matrix that is not square")
        return a.inv()  # raises ZeroDivisionError on a singular matrix
    return 1 / a


def _pow(a: Any, k: Any) -> Any:
    e = int(k) if not _is_mat(k) and load_flint().fmpq(int(k)) == k else None
    if e is None:
        raise Unsupported("a power that is not an integer")
    base = _inv(a) if e < 0 else a
    out = base
    for _ in range(abs(e) - 1):
        out = out * base
    if e == 0:
        raise Unsupported("a zeroth power")
    return out


def _kron(a: Any, b: Any) -> Any:
    a, b = _mat(a), _mat(b)
    ra, ca, rb, cb = a.nrows(), a.ncols(), b.nrows(), b.ncols()
    return load_flint().fmpq_mat(
        ra * rb,
        ca * cb,
        [a[i // rb, j // cb] * b[i % rb, j % cb] for i in range(ra * rb) for j in range(ca * cb)],
    )


def _sym(a: Any) -> Any:
    return (a + a.transpose()) * load_flint().fmpq(1, 2) if _is_mat(a) else a


OPS: dict[str, Any] = {
    "add": _add,
    "neg": lambda a: -a,
    "mul": _mul,
    "hadamard": lambda a, b: _entrywise(a, b, lambda u, v: u * v),
    "pow": _pow,
    "transpose": _transpose,
    "inv": _inv,
    "sym": _sym,
    "kron": _kron,
}


def exact_value(node: Mapping[str, Any], env: Mapping[str, Any]) -> Any:
    """An expression tree (:mod:`lmic.ir.expr`) evaluated in rational arithmetic: ``fmpq`` or
    ``fmpq_mat`` values; :class:`Unsupported` for an operation with no exact value.

    >>> exact_value({"op": "mul", "args": [{"num": 0.5}, {"name": "a"}]}, {"a": load_flint().fmpq(3)})
    3/2
    """
    flint = load_flint()
    if "name" in node:
        if node["name"] not in env:
            raise Unsupported(f"'{node['name']}' has no exact value")
        return env[node["name"]]
    if "num" in node:
        return _q(node["num"])
    if "eye" in node:
        n = int(node["eye"])
        return flint.fmpq_mat(n, n, [int(i == j) for i in range(n) for j in range(n)])
    if "zeros" in node:
        r, c = (int(v) for v in node["zeros"])
        return flint.fmpq_mat(r, c)
    if "block" in node:
        rows = [[_mat(exact_value(e, env)) for e in row] for row in node["block"]]
        heights = [row[0].nrows() for row in rows]
        widths = [m.ncols() for m in rows[0]]
        entries: list[Any] = []
        for row, h in zip(rows, heights, strict=True):
            if [m.nrows() for m in row] != [h] * len(row) or [m.ncols() for m in row] != widths:
                raise Unsupported("a block of inconsistent sizes")
            for i in range(h):
                for m in row:
                    entries.extend(m[i, j] for j in range(m.ncols()))
        return flint.fmpq_mat(sum(heights), sum(widths), entries)
    op = node.get("op")
    if op not in OPS:
        raise Unsupported(f"'{op}' has no exact value here")
    args = [exact_value(a, env) for a in node.get("args", [])]
    try:
        return OPS[op](*args)
    except (ZeroDivisionError, ValueError, TypeError) as err:
        raise Unsupported(f"'{op}' failed exactly: {err}") from None


def exact_environment(problem: Problem, x: np.ndarray) -> dict[str, Any]:
    """Data, the variables at ``x`` and the derived quantities, each exactly (a derived quantity
    with no exact value is left out: a check that uses it keeps its float verdict)."""
    env: dict[str, Any] = {}
    for name, value in problem.inputs(x).items():
        try:
            arr = np.asarray(value, dtype=float)
            env[name] = exact_matrix(arr) if arr.ndim else _q(float(arr))
        except (Unsupported, TypeError, ValueError):
            continue
    for d in problem.derived:
        try:
            env[d.name] = exact_value(d.expr, env)
        except Unsupported:
            continue
    return env


def decide(check: Check, env: Mapping[str, Any]) -> bool | None:
    """Whether ``check`` holds exactly in ``env`` (``None``: not decided exactly).

    >>> c = Check("X > 0", "positive_definite", {"name": "X"})
    >>> decide(c, {"X": exact_matrix(np.diag([1.0, -1e-30]))})
    False
    """
    if check.kind not in KINDS:
        return None
    try:
        M = _mat(exact_value(check.expr, env))
    except Unsupported:
        return None
    n = M.nrows()
    if n != M.ncols() or n > MAX_DIM:
        return None
    S = _sym(M) if check.kind == "positive_definite" else -_sym(M)
    den = 1
    for i in range(n):
        for j in range(n):
            q = int(S[i, j].q)
            den = den * q // math.gcd(den, q)
    ints = [[int((S[i, j] * den).p) for j in range(n)] for i in range(n)]
    proof = prove_pd(ints)
    if proof["proven"]:
        return True
    return False if proof["disproved"] else None


def recheck(problem: Problem, x: np.ndarray, reports: list[dict[str, Any]]) -> None:
    """Decide exactly, in place, each failed definiteness check of ``reports`` (the reports of
    :func:`lmic.certify.derived.evaluate_checks` for ``problem.checks`` at ``x``)."""
    todo = [
        (c, r)
        for c, r in zip(problem.checks, reports, strict=True)
        if not r["ok"] and not r["error"] and c.kind in KINDS
    ]
    if not todo:
        return
    env = exact_environment(problem, np.asarray(x, dtype=float))
    for c, r in todo:
        verdict = decide(c, env)
        if verdict is True:
            r["ok"] = True
            r["exact"] = "holds"
            r["note"] = (
                f"holds exactly at the point (rational arithmetic); the floating-point evaluation "
                f"gave {r['value']:.3g}, off by rounding"
            )
        elif verdict is False:
            r["exact"] = "fails"
