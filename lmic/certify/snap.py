"""An exactly feasible point next to a rejected one, for feasible sets without interior.

When the feasible set of a problem is a single point or lies in a lower-dimensional face (``x
[[0, 1], [1, 0]] >= 0`` allows only ``x = 0``; ``[[x1 - x2, 0], [0, x2 - x1]] >= 0`` forces ``x1 =
x2``), a solver's point is never exactly on it: ``x = 4.8e-25`` makes ``lambda_min = -x``, and
the certifier (:mod:`lmic.certify.check`) rightly rejects it, relative to the point's own scale.
The point *on* the face is usually simple (zero entries, short dyadic rationals). :func:`snap_point`
tries such candidates near ``x`` and returns one only when :func:`lmic.certify.exact.prove` proves
every LMI and row there exactly (a non-strict LMI ``>= 0``, a strict one ``> 0``: a strict LMI
holding with margin 0 is never accepted).

The candidates, in order: ``x`` with its entries below :data:`ZERO_REL` times ``max(1, ||x||_inf)``
set to 0; ``x`` rounded to the grids ``2^-K`` of :data:`GRID_BITS`; only those within
:data:`SNAP_DIST` (relative) of ``x``: the point the solver approximates, not another feasible
point (rounding an optimal point to integers may be feasible, at a much worse objective). A candidate counts only when
it is exactly a float vector (so that ``x_q`` is the point recorded and re-certified).

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
>>> p = Problem([Variable("x", "scalar", (1, 1))],
...             [LMI("x [[0, 1], [1, 0]] >= 0", 2, sp.csc_matrix([[0.0, 0.0], [0.0, 1.0], [0.0, 0.0]]), strict=False)],
...             LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
>>> s = snap_point(p, np.array([4.8e-25]))
>>> s["x"].tolist(), s["proof"]["proven"], s["how"]
([0.0], True, 'entries below 1e-09 set to 0')
"""

from __future__ import annotations

from fractions import Fraction
from typing import Any

import numpy as np

from lmic.certify.exact import prove
from lmic.ir.problem import Problem

__all__ = [
    "ZERO_REL",
    "SNAP_DIST",
    "GRID_BITS",
    "MAX_VARIABLES",
    "SNAP_ABS",
    "snappable",
    "snap_point",
    "exact_primal_end",
]

#: entries below this times ``max(1, ||x||_inf)`` are candidates for 0
ZERO_REL = 1e-9
#: grids ``2^-K`` tried (coarsest first; a grid that moves ``x`` by more than :data:`SNAP_DIST`
#: is skipped)
GRID_BITS = (0, 10, 20, 30, 40)
#: a candidate moves no entry by more than this times ``max(1, ||x||_inf)`` (a point on the
#: face next to the solver's, not another feasible point)
SNAP_DIST = 1e-6
#: no snapping above this many variables (each candidate costs an exact proof)
MAX_VARIABLES = 2000
#: a failing constraint is worth a snap when its violation is below this times its largest
#: coefficient (an absolute scale, not the point's: at x ~ 0 every relative violation is ~1)
SNAP_ABS = 1e-7


def snappable(problem: Problem, cert: Any) -> bool:
    """Whether a rejected certificate fails only by tiny violations of non-strict LMIs and rows
    (every derived quantity, check and the objective fine), so that :func:`snap_point` may help.

    >>> from types import SimpleNamespace
    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
    >>> p = Problem([Variable("x", "scalar", (1, 1))], [LMI("x >= 0", 1, sp.csc_matrix([[0.0, 1.0]]), strict=False)],
    ...             LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
    >>> c = SimpleNamespace(lmis=[{"ok": False, "strict": False, "min_eig": -1e-20}], linear=[], derived=[],
    ...                     checks=[], objective={"ok": True})
    >>> snappable(p, c), snappable(p, SimpleNamespace(**dict(vars(c), lmis=[dict(c.lmis[0], strict=True)])))
    (True, False)
    """
    if problem.n > MAX_VARIABLES or not all(r["ok"] for r in list(cert.derived) + list(cert.checks)):
        return False
    if cert.objective is not None and not cert.objective["ok"]:
        return False
    for lmi, r in zip(problem.lmis, cert.lmis, strict=True):
        if not r["ok"]:
            top = max(1.0, float(np.max(np.abs(lmi.coeffs.data), initial=0.0)))
            if r["strict"] or not r["min_eig"] >= -SNAP_ABS * top:
                return False
    for r in cert.linear:
        if not r["ok"] and (r.get("strict") or not abs(r["residual"]) <= SNAP_ABS * max(1.0, r["scale"])):
            return False
    return True


def snap_point(problem: Problem, x: np.ndarray, *, tol: Any = None) -> dict[str, Any] | None:
    """An exactly feasible float point near ``x`` (module docstring), or ``None``.

    Returns
    -------
    dict or None
        ``x`` (the point, floats that are exactly the proved rationals), ``proof`` (the
        :func:`lmic.certify.exact.prove` record *at* that point, ``at_x`` true), ``distance``
        (``max |x_q - x|``), ``how`` (which candidate).
    """
    x = np.asarray(x, dtype=float).ravel()
    if x.size > MAX_VARIABLES or not np.all(np.isfinite(x)):
        return None
    scale = max(1.0, float(np.max(np.abs(x), initial=0.0)))
    cands: list[tuple[str, np.ndarray, int | None]] = []
    xz = np.where(np.abs(x) <= ZERO_REL * scale, 0.0, x)
    if np.any(xz != x):
        cands.append((f"entries below {ZERO_REL:g} set to 0", xz, None))
    cands += [(f"rounded to the grid 2^-{K}", x, K) for K in GRID_BITS]
    seen: set[tuple[float, ...]] = set()
    cap = SNAP_DIST * scale
    for how, xc, K in cands:
        moved = xc if K is None else np.ldexp(np.round(np.ldexp(x, K)), -K)
        if float(np.max(np.abs(moved - x), initial=0.0)) > cap:
            continue  # too far from the solver's point: not the point it approximates
        r = prove(problem, xc, tol=tol, bits=K)
        if not r["proven"]:
            continue
        den = int(r["point"]["den"])
        xq = [Fraction(int(v), den) for v in r["point"]["num"]]
        xf = np.array([float(f) for f in xq])
        if any(Fraction(float(f)) != f for f in xq) or tuple(xf) in seen:
            continue
        seen.add(tuple(xf))
        again = prove(problem, xf, tol=tol)
        if again["proven"] and again["at_x"] and float(np.max(np.abs(xf - x), initial=0.0)) <= cap:
            return {"x": xf, "proof": again, "distance": float(np.max(np.abs(xf - x), initial=0.0)), "how": how}
    return None


def exact_primal_end(problem: Problem, x: np.ndarray, float_end: dict[str, Any]) -> dict[str, Any]:
    """``float_end`` (:func:`lmic.certify.enclosure_float.primal_end` at ``x``) when proven;
    else, for a point on a face that :func:`snap_point` produced (singular ``F(x)``, which no
    floating-point bound proves; entries on the grid ``2^-40`` or coarser), the exact proof at
    ``x`` itself: the objective then is exact, rounded outwards (up for ``min``, down for ``max``).

    >>> import numpy as np, scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
    >>> p = Problem([Variable("x", "scalar", (1, 1))],
    ...             [LMI("M", 2, sp.csc_matrix([[0.0, 0.0], [0.0, 1.0], [0.0, 0.0]]), strict=False)],
    ...             LinearConstraints.empty(1), Objective("min", [0.5, 1.0]))
    >>> exact_primal_end(p, np.array([0.0]), {"proven": False, "value": None, "reason": "lambda_min >= -inf"})
    {'proven': True, 'value': 0.5, 'reason': 'every LMI and row proved exactly at the point'}
    """
    import math

    if float_end.get("proven") or problem.objective.sense == "feasibility":
        return float_end
    from lmic.certify.exact import _float_bits

    x = np.asarray(x, dtype=float).ravel()
    if x.size != problem.n or x.size > MAX_VARIABLES or not np.all(np.isfinite(x)):
        return float_end
    equalities = any(kind == "eq" for kind in problem.linear.kinds)
    if _float_bits(x) > max(GRID_BITS) and not equalities:
        # only the points :func:`snap_point` produces (short dyadic entries): a full-precision
        # point gets its end from the restoration of :mod:`lmic.backoff`, near the optimum. With
        # equality rows no float point holds them, and no restoration does: the exact proof at
        # the point's exact projection onto them is the end (a Lyapunov equation written as rows)
        return float_end
    r = prove(problem, x)
    if not (r["proven"] and not r["rows_within_tolerance"]) or not (r["at_x"] or equalities):
        return float_end
    point = x.tolist()
    if not r["at_x"]:  # the recorded rational point (the projection onto the equality rows)
        den = int(r["point"]["den"])
        point = [Fraction(int(num), den) for num in r["point"]["num"]]
    c = problem.objective.c
    exact = Fraction(float(c[0])) + sum(
        (Fraction(float(ck)) * Fraction(xk) for ck, xk in zip(c[1:], point, strict=True)), Fraction(0)
    )
    v = float(exact)
    if problem.objective.sense == "min" and Fraction(v) < exact:
        v = math.nextafter(v, math.inf)
    elif problem.objective.sense == "max" and Fraction(v) > exact:
        v = math.nextafter(v, -math.inf)
    where = "the point" if r["at_x"] else "the point's exact projection onto the equality rows"
    return {"proven": True, "value": v, "reason": f"every LMI and row proved exactly at {where}"}
