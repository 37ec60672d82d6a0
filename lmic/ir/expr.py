"""Small expression trees for derived quantities and checks, evaluated numerically.

Derived quantities (``L = P^-1 G``, ``gamma* = 1/sqrt(alpha (1 + eps1))``) and theorem
checks travel with the IR as JSON-able trees, so the certifier and ``lmic audit`` need only
the IR and its data, never the plugin's Python code or sympy.

Grammar (every node is a dict):

``{"name": "P"}``
    a named value: a decision variable, a data matrix, a parameter, a data-derived constant or
    an earlier derived quantity, looked up in the environment.
``{"num": 2.5}``
    a number.
``{"eye": n}`` / ``{"zeros": [r, c]}``
    identity / zero matrix.
``{"block": [[node, ...], ...]}``
    a block matrix (every entry a node; sizes must agree).
``{"op": OP, "args": [node, ...]}``
    with ``OP`` one of :data:`OPS`: ``add``, ``neg``, ``mul`` (product: scalar times anything,
    or the matrix product of two matrices), ``hadamard``, ``pow`` (scalar power, or integer
    power of a square matrix), ``transpose``, ``inv``, ``pinv``, ``sqrt``, ``exp``, ``log``,
    ``abs``, ``trace``, ``lambda_max`` / ``lambda_min`` (of the symmetric part),
    ``spectral_radius``, ``spectral_abscissa``, ``norm2``, ``max``, ``min``, ``sym``
    (``(M + M^T)/2``), ``kron``.

Scalars are Python floats; matrices are 2-D ``numpy`` arrays (a ``1 x 1`` matrix stays a
matrix).

Examples
--------
>>> import numpy as np
>>> tree = {"op": "mul", "args": [{"op": "inv", "args": [{"name": "P"}]}, {"name": "G"}]}
>>> evaluate(tree, {"P": 2 * np.eye(2), "G": np.ones((2, 1))})
array([[0.5],
       [0.5]])
>>> names(tree) == {"P", "G"}
True
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from lmic.errors import IRError

__all__ = ["OPS", "evaluate", "names", "validate", "Value"]

Value = float | np.ndarray


def _as_matrix(v: Value) -> np.ndarray:
    return v if isinstance(v, np.ndarray) else np.array([[float(v)]])


def _is_scalar(v: Value) -> bool:
    return not isinstance(v, np.ndarray)


def _add(*args: Value) -> Value:
    out: Value = 0.0
    for a in args:
        if isinstance(out, np.ndarray) and isinstance(a, np.ndarray):
            if out.shape != a.shape:
                raise IRError(f"expression adds matrices of shapes {out.shape} and {a.shape}")
            out = out + a
        elif isinstance(out, np.ndarray):
            if a != 0:
                raise IRError("expression adds a non-zero scalar to a matrix")
        elif isinstance(a, np.ndarray):
            if out != 0:
                raise IRError("expression adds a non-zero scalar to a matrix")
            out = a
        else:
            out = out + a
    return out


def _mul(*args: Value) -> Value:
    out: Value = 1.0
    for a in args:
        if isinstance(out, np.ndarray) and isinstance(a, np.ndarray):
            if out.shape[1] != a.shape[0]:
                raise IRError(f"expression multiplies shapes {out.shape} and {a.shape}")
            out = out @ a
        else:
            out = out * a
    return out


def _pow(base: Value, expo: Value) -> Value:
    if _is_scalar(base):
        return float(base) ** float(expo)
    k = float(expo)
    if k != int(k):
        raise IRError("non-integer power of a matrix")
    if int(k) < 0:
        return np.linalg.matrix_power(np.linalg.inv(base), -int(k))
    return np.linalg.matrix_power(base, int(k))


def _sym(M: np.ndarray) -> np.ndarray:
    M = _as_matrix(M)
    return 0.5 * (M + M.T)


def _eigvals(M: Value) -> np.ndarray:
    return np.linalg.eigvals(_as_matrix(M))


def _unary(fn):
    return lambda a: fn(a)


OPS: dict[str, Any] = {
    "add": _add,
    "neg": lambda a: -a,
    "mul": _mul,
    "hadamard": lambda a, b: _as_matrix(a) * _as_matrix(b),
    "pow": _pow,
    "transpose": lambda a: a.T if isinstance(a, np.ndarray) else a,
    "inv": lambda a: np.linalg.inv(a) if isinstance(a, np.ndarray) else 1.0 / a,
    "pinv": lambda a: np.linalg.pinv(_as_matrix(a)),
    "sqrt": lambda a: float(np.sqrt(a)) if _is_scalar(a) else np.sqrt(a),
    "exp": lambda a: float(np.exp(a)) if _is_scalar(a) else np.exp(a),
    "log": lambda a: float(np.log(a)) if _is_scalar(a) else np.log(a),
    "abs": lambda a: float(abs(a)) if _is_scalar(a) else np.abs(a),
    "trace": lambda a: float(np.trace(_as_matrix(a))),
    "lambda_max": lambda a: float(np.linalg.eigvalsh(_sym(a))[-1]),
    "lambda_min": lambda a: float(np.linalg.eigvalsh(_sym(a))[0]),
    "spectral_radius": lambda a: float(np.max(np.abs(_eigvals(a)))),
    "spectral_abscissa": lambda a: float(np.max(np.real(_eigvals(a)))),
    "norm2": lambda a: float(np.linalg.norm(_as_matrix(a), 2)),
    "max": lambda *a: float(max(a)),
    "min": lambda *a: float(min(a)),
    "sym": _sym,
    "kron": lambda a, b: np.kron(_as_matrix(a), _as_matrix(b)),
}


def evaluate(node: Mapping[str, Any], env: Mapping[str, Value]) -> Value:
    """Evaluate an expression tree numerically.

    Parameters
    ----------
    node : dict
        The tree (see the module docstring for the grammar).
    env : mapping
        Values of the names the tree uses.

    Returns
    -------
    float or numpy.ndarray

    Raises
    ------
    IRError
        On an unknown name or operator, or inconsistent shapes.

    Examples
    --------
    >>> evaluate({"op": "sqrt", "args": [{"num": 4.0}]}, {})
    2.0
    """
    if "name" in node:
        key = node["name"]
        if key not in env:
            raise IRError(f"expression uses '{key}', which has no value")
        v = env[key]
        return v if isinstance(v, np.ndarray) else float(v)
    if "num" in node:
        return float(node["num"])
    if "eye" in node:
        return np.eye(int(node["eye"]))
    if "zeros" in node:
        r, c = node["zeros"]
        return np.zeros((int(r), int(c)))
    if "block" in node:
        rows = [[_as_matrix(evaluate(e, env)) for e in row] for row in node["block"]]
        try:
            return np.block(rows)
        except ValueError as err:
            raise IRError(f"block expression has inconsistent sizes: {err}") from None
    if "op" in node:
        op = node["op"]
        if op not in OPS:
            raise IRError(f"unknown expression operator '{op}'")
        args = [evaluate(a, env) for a in node.get("args", [])]
        try:
            with np.errstate(all="ignore"):
                return OPS[op](*args)
        except np.linalg.LinAlgError as err:
            raise IRError(f"'{op}' failed: {err}") from None
    raise IRError(f"malformed expression node {dict(node)!r}")


def names(node: Mapping[str, Any]) -> set[str]:
    """The set of names an expression tree refers to.

    >>> sorted(names({"op": "add", "args": [{"name": "A"}, {"name": "B"}]}))
    ['A', 'B']
    """
    if "name" in node:
        return {node["name"]}
    out: set[str] = set()
    if "block" in node:
        for row in node["block"]:
            for e in row:
                out |= names(e)
    for a in node.get("args", []):
        out |= names(a)
    return out


def validate(node: Any, where: str = "expression") -> None:
    """Check that ``node`` follows the grammar; raise :class:`IRError` naming ``where``.

    >>> validate({"op": "nope", "args": []}, "derived L")
    Traceback (most recent call last):
    ...
    lmic.errors.IRError: derived L: unknown operator 'nope'
    """
    if not isinstance(node, Mapping):
        raise IRError(f"{where}: expression node is not an object")
    keys = set(node)
    if keys == {"name"} and isinstance(node["name"], str):
        return
    if keys == {"num"} and isinstance(node["num"], int | float):
        return
    if keys == {"eye"} and isinstance(node["eye"], int):
        return
    if keys == {"zeros"} and isinstance(node["zeros"], list | tuple) and len(node["zeros"]) == 2:
        return
    if keys == {"block"} and isinstance(node["block"], list | tuple):
        for row in node["block"]:
            for e in row:
                validate(e, where)
        return
    if "op" in keys and keys <= {"op", "args"}:
        if node["op"] not in OPS:
            raise IRError(f"{where}: unknown operator '{node['op']}'")
        for a in node.get("args", []):
            validate(a, where)
        return
    raise IRError(f"{where}: malformed expression node {dict(node)!r}")
