"""IR helpers of the audit: variables recovered from printed gains, the paper's extreme eigenvalues,
and the print precision of a published number.

Examples
--------
>>> print_resolution(np.array([[0.5, -2.3]]))
0.05
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from lmic.errors import IRError
from lmic.ir.problem import Problem
from lmic.reductions.fix import fix_variables

__all__ = [
    "recover_variables",
    "lmi_extremes",
    "min_margin",
    "checks_of",
    "print_resolution",
    "match_inverse",
    "fix_variables",
]


def match_inverse(tree: Any) -> tuple[str, str, str] | None:
    """``(form, A, B)`` when ``tree`` is ``inv(A) B``, ``inv(A) B^T`` or ``B inv(A)`` (names)."""
    if not isinstance(tree, dict) or tree.get("op") != "mul" or len(tree.get("args", [])) != 2:
        return None
    a, b = tree["args"]

    def name(node: Any) -> str | None:
        return node.get("name") if isinstance(node, dict) and "name" in node else None

    def inv_of(node: Any) -> str | None:
        if isinstance(node, dict) and node.get("op") == "inv" and len(node.get("args", [])) == 1:
            return name(node["args"][0])
        return None

    if inv_of(a) and name(b):
        return "left", inv_of(a), name(b)  # type: ignore[return-value]
    if inv_of(a) and isinstance(b, dict) and b.get("op") == "transpose" and name(b["args"][0]):
        return "left-transposed", inv_of(a), name(b["args"][0])  # type: ignore[return-value]
    if name(a) and inv_of(b):
        return "right", inv_of(b), name(a)  # type: ignore[return-value]
    return None


def recover_variables(problem: Problem, known: Mapping[str, Any], published: Mapping[str, Any]) -> dict[str, tuple]:
    """Decision variables recovered from printed gains: ``{name: (value, how, printed key)}``.

    For a derived quantity ``D = inv(A) B`` (or ``inv(A) B^T``, ``B inv(A)``) with ``D`` printed,
    ``A`` a known variable and ``B`` an unknown one: ``B = A D`` (``(A D)^T``, ``D A``). Repeats
    until nothing new is found. A value that does not fit ``B``'s structure is not recovered.

    Examples
    --------
    >>> from lmic.ir.problem import LinearConstraints, NamedExpr, Objective, Variable
    >>> import scipy.sparse as sp
    >>> p = Problem([Variable("P", "symmetric", (1, 1)), Variable("G", "full", (1, 1), offset=1)], [],
    ...             LinearConstraints.empty(2), Objective("feasibility", [0, 0, 0]),
    ...             derived=[NamedExpr("L", {"op": "mul", "args": [{"op": "inv", "args": [{"name": "P"}]},
    ...                                                          {"name": "G"}]})])
    >>> v, how, key = recover_variables(p, {"P": [[2.0]]}, {"L": [[3.0]]})["G"]
    >>> float(v[0, 0]), how, key
    (6.0, 'G = P L', 'L')
    """
    names = {v.name for v in problem.variables}
    values = {k: np.atleast_2d(np.asarray(v, dtype=float)) for k, v in known.items()}
    found: dict[str, tuple] = {}
    changed = True
    while changed:
        changed = False
        for d in problem.derived:
            if d.name not in published or isinstance(published[d.name], str):
                continue
            m = match_inverse(d.expr)
            if m is None:
                continue
            form, a, b = m
            if a not in values or b in values or b not in names:
                continue
            D = np.atleast_2d(np.asarray(published[d.name], dtype=float))
            A = values[a]
            try:
                if form == "left":
                    B, how = A @ D, f"{b} = {a} {d.name}"
                elif form == "left-transposed":
                    B, how = (A @ D).T, f"{b} = ({a} {d.name})^T"
                else:
                    B, how = D @ A, f"{b} = {d.name} {a}"
                problem.variable(b).pack(B)
            except (ValueError, IRError):
                continue
            values[b] = B
            found[b] = (B, how, d.name)
            changed = True
    return found


def lmi_extremes(problem: Problem, cert: Any) -> list[dict[str, Any]]:
    """Per LMI: the paper's extreme eigenvalue (``lambda_max`` of a ``<`` LMI), margin, ok.

    The certifier works with the normalised ``F(x) >= 0``; for an LMI written ``M < 0`` the
    paper's ``lambda_max(M)`` is ``-lambda_min(F)``.
    """
    out = []
    for lmi, rep in zip(problem.lmis, getattr(cert, "lmis", None) or [], strict=False):
        lam = rep.get("min_eig")
        negated = lmi.relation in ("<", "<=")
        out.append(
            {
                "name": lmi.name,
                "relation": lmi.relation,
                "which": "lambda_max" if negated else "lambda_min",
                "extreme": None if lam is None else (-lam if negated else lam),
                "min_margin": lam,
                "rel_margin": rep.get("rel_margin"),
                "ok": rep.get("ok"),
            }
        )
    return out


def min_margin(cert: Any) -> float | None:
    """The smallest ``lambda_min`` over a certificate's normalised LMIs (``None`` without LMIs)."""
    vals = [r.get("min_eig") for r in getattr(cert, "lmis", None) or [] if r.get("min_eig") is not None]
    return float(min(vals)) if vals else None


def checks_of(cert: Any) -> list[dict[str, Any]]:
    """A certificate's checks as ``name``, ``value``, ``ok``."""
    return [
        {"name": c.get("name"), "value": c.get("value"), "ok": c.get("ok")} for c in getattr(cert, "checks", None) or []
    ]


def print_resolution(values: np.ndarray) -> float:
    """Half a unit of the last printed digit of the most precise entry (``-2.3`` -> 0.05).

    Whole numbers carry no resolution (a printed ``1`` may well be exact), nor do numbers in
    exponent notation.

    >>> print_resolution(np.array([[0.5, -2.3]])), print_resolution(np.array([[1.0, -1.0]]))
    (0.05, 0.0)
    """
    digits = 0
    for v in np.asarray(values, dtype=float).ravel():
        text = repr(float(v))
        if "e" in text or "E" in text:
            return 0.0
        digits = max(digits, len(text.split(".")[1].rstrip("0")) if "." in text else 0)
    return 0.5 * 10.0**-digits if digits else 0.0
