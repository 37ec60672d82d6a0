"""A dual end from an objective cut: a global infeasibility proof of "the constraints and an
objective no better than ``r``" bounds the optimal value by ``r``.

Where the dual has no rational point near its optimum (the optimum is an infimum that is not
attained, its dual optimal face is irrational: ``uio_dt.thm4_1``), no repaired dual point can
be proved, yet the problem with the extra row ``objective <= r`` (minimisation form) may have a
Farkas certificate that :func:`lmic.certify.farkas.prove_farkas` makes exact: then no point of
the problem, as stated (its strict constraints strict), has an objective ``<= r``, and ``r`` is
a lower end of its infimum (an upper end of a supremum). The route that searches ``r`` is
:mod:`lmic.route_cut`.

The record (``enclosure.dual`` with ``route`` ``"objective cut"``) keeps ``r`` (``cut.r``, in
the minimisation form; ``lower`` is :func:`cut_bound`, ``r`` itself unless the objective has a
constant), the float certificate the exact proof started from and its face threshold;
:func:`verify_cut` (``lmic audit``) rebuilds the cut problem from the record and proves it
again.

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
>>> p = Problem([Variable("t", "scalar", (1, 1))],
...             [LMI("t - 2 >= 0", 1, sp.csc_matrix([[-2.0, 1.0]]), strict=False)],
...             LinearConstraints.empty(1), Objective("min", [0.0, 1.0]))
>>> cut = cut_problem(p, 1.5)
>>> cut.objective.sense, cut.linear.names[-1], cut.linear.residuals(np.array([1.0]))
('feasibility', 'objective cut', array([0.5]))
>>> rec = prove_cut(p, 1.5, {"lmis": [np.eye(1)], "linear": [2.0]}, {})
>>> rec["proven"], rec["lower"], verify_cut(p, rec)["ok"], verify_cut(p, dict(rec, lower=2.5))["ok"]
(True, 1.5, True, False)
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
import scipy.sparse as sp

from lmic.errors import LmicError
from lmic.ir.problem import LinearConstraints, Objective, Problem

__all__ = ["cut_problem", "cut_bound", "prove_cut", "verify_cut", "CUT_NAME", "near_dependent_rows", "NEAR_SINGULAR"]

#: the name of the cut's row in the cut problem
CUT_NAME = "objective cut"
#: the face thresholds :func:`prove_cut` tries (:func:`lmic.certify.farkas.prove_farkas`'s
#: ``rel_face``): every cut of uio_dt.thm4_1 that proved did so at 1e-9 (in 5 ms), and a
#: failing proof costs 0.1-0.7 s a threshold on 4 states
CUT_FACES = (1e-9,)


def cut_problem(problem: Problem, r: float) -> Problem:
    """The feasibility problem of ``problem``'s constraints and ``f(x) <= r``, where ``f`` is
    the objective in the minimisation form (``-(c0 + c.x)`` for ``max``): one more linear row
    ``r - f(x) >= 0``, not strict.

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
    >>> p = Problem([Variable("t", "scalar", (1, 1))], [LMI("t >= 0", 1, sp.csc_matrix([[0., 1.]]))],
    ...             LinearConstraints.empty(1), Objective("max", [1.0, 2.0]))
    >>> cut_problem(p, -3.0).linear.A.toarray()        # -3 + (1 + 2 t) >= 0: t >= 1
    array([[-2.,  2.]])
    """
    sense = problem.objective.sense
    if sense not in ("min", "max"):
        raise ValueError("an objective cut needs an optimisation problem")
    sign = 1.0 if sense == "min" else -1.0
    c = np.asarray(problem.objective.c, dtype=float).ravel()
    row = np.concatenate([[float(r) - sign * c[0]], -sign * c[1:]])
    lin = problem.linear
    cut = sp.csr_matrix(row[None, :])
    A = sp.vstack([sp.csr_matrix(lin.A), cut]).tocsr() if len(lin) else cut
    linear = LinearConstraints(A, [*lin.kinds, "ge"], [*lin.strict, False], [*lin.names, CUT_NAME])
    return dataclasses.replace(problem, linear=linear, objective=Objective("feasibility", np.zeros(problem.n + 1)))


def cut_bound(problem: Problem, r: float) -> float:
    """The lower end (minimisation form) that an infeasibility proof of :func:`cut_problem` at
    ``r`` proves: the cut row's constant is ``fl(r - s c0)`` (``s`` the sense's sign), so the
    proof excludes ``f(x) <= s c0 + fl(r - s c0)``, summed exactly and rounded down. It is ``r``
    itself when ``c0 = 0``.

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
    >>> p = Problem([Variable("t", "scalar", (1, 1))], [LMI("t >= 0", 1, sp.csc_matrix([[0., 1.]]))],
    ...             LinearConstraints.empty(1), Objective("min", [0.1, 1.0]))
    >>> cut_bound(p, 0.3) <= 0.3, cut_bound(Problem(p.variables, p.lmis, p.linear, Objective("min", [0, 1.0])), 0.3)
    (True, 0.3)
    """
    from fractions import Fraction

    sign = 1.0 if problem.objective.sense == "min" else -1.0
    c0 = float(np.asarray(problem.objective.c, dtype=float).ravel()[0])
    exact = Fraction(sign * c0) + Fraction(float(r) - sign * c0)
    value = float(exact)
    return value if Fraction(value) <= exact else math.nextafter(value, -math.inf)


def prove_cut(problem: Problem, r: float, farkas: dict[str, Any], verification: dict[str, Any]) -> dict[str, Any]:
    """Prove ``r`` a lower end (minimisation form) from a Farkas certificate of
    :func:`cut_problem` (the solver's ``farkas`` and its float ``verification``, as
    :func:`lmic.certify.farkas.prove_infeasible` takes them).

    Returns the ``enclosure.dual`` record: ``proven``, ``route`` (``"objective cut"``),
    ``lower`` (``r``), ``method`` (``"exact"``), ``kind`` (``"closed"``/``"strict"``), ``cut``
    (``{"farkas": {lmis, linear}, "threshold"}``: what :func:`verify_cut` re-proves), ``reason``.
    """
    from lmic.certify.farkas import prove_farkas
    from lmic.certify.farkas_exact import farkas_candidates

    cut = cut_problem(problem, r)
    out: dict[str, Any] = {"proven": False, "route": "objective cut", "lower": None}
    try:
        cands = [c for _, c in farkas_candidates(cut, farkas, verification)]
    except (LmicError, ValueError, ArithmeticError) as exc:
        return dict(out, reason=f"the cut at {r:.10g} has no usable certificate: {exc}")
    proof: dict[str, Any] = {}
    cand: dict[str, Any] = {}
    for cand in cands:
        try:
            proof = prove_farkas(cut, cand, rel_face=CUT_FACES)
        except (ValueError, ArithmeticError) as exc:
            proof = {"proven": False, "reason": str(exc)}
        if proof.get("proven"):
            break
    if not proof.get("proven"):
        return dict(out, reason=f"the cut at {r:.10g} is not proved infeasible: {proof.get('reason')}")
    thr = float(proof["face"]["threshold"])
    again = prove_farkas(cut, cand, rel_face=(thr,))  # what the audit will run: the same proof
    if not again.get("proven"):
        return dict(out, reason=f"the cut at {r:.10g}: the exact proof did not repeat ({again.get('reason')})")
    bound = cut_bound(problem, r)
    return {
        "proven": True,
        "route": "objective cut",
        "lower": bound,
        "method": "exact",
        "kind": again["kind"],
        "cut": {
            "r": float(r),
            "farkas": {
                "lmis": [np.asarray(Z, dtype=float).tolist() for Z in cand["lmis"]],
                "linear": np.asarray(cand.get("linear", []), dtype=float).tolist(),
            },
            "threshold": thr,
        },
        "reason": (
            f"no point with objective {'<=' if problem.objective.sense == 'min' else '>='} "
            f"{bound if problem.objective.sense == 'min' else -bound:.10g}: exact Farkas proof of the cut "
            f"({again['kind']})"
        ),
    }


def verify_cut(problem: Problem, record: dict[str, Any]) -> dict[str, Any]:
    """Re-prove a recorded objective cut (``lmic audit``): the cut problem rebuilt at the
    record's ``cut.r``, its recorded certificate proved exactly again, and the record's
    ``lower`` not above what that proof bounds (:func:`cut_bound`).

    >>> verify_cut(None, {"route": "objective cut", "lower": None})["ok"]
    False
    """
    from lmic.certify.farkas import prove_farkas

    cut = record.get("cut")
    raw = (record.get("lower"), cut.get("r") if isinstance(cut, dict) else None)
    if not isinstance(cut, dict) or not all(isinstance(v, int | float) and math.isfinite(v) for v in raw):
        return {"ok": False, "reason": "the objective cut's value or certificate is missing"}
    lower, r = float(raw[0]), float(raw[1])  # type: ignore[arg-type]  # checked numbers just above
    if lower > cut_bound(problem, r):
        return {"ok": False, "reason": f"the lower end {lower:.10g} is above the cut's bound"}
    thr = cut.get("threshold")
    if not isinstance(thr, int | float) or not 0.0 < float(thr) < 1.0:
        return {"ok": False, "reason": "the objective cut's face threshold is not in (0, 1)"}
    try:
        proof = prove_farkas(cut_problem(problem, r), cut.get("farkas") or {}, rel_face=(float(thr),))
    except (LmicError, ValueError, ArithmeticError, TypeError) as exc:  # a wrong shape: LmicError
        return {"ok": False, "reason": f"the objective cut's certificate is malformed: {exc}"}
    if not proof.get("proven"):
        return {"ok": False, "reason": f"the objective cut at {r:.10g} is not proved: {proof.get('reason')}"}
    return {"ok": True, "reason": f"objective cut re-proved ({proof['kind']})"}


#: the smallest singular value, relative to the largest, of the normalised rows of the dual
#: equality system below which :func:`near_dependent_rows` calls them dependent in floating point
NEAR_SINGULAR = 1e-12


def near_dependent_rows(problem: Problem) -> str | None:
    """Why no cut of ``problem`` can be proved infeasible, or ``None``: the rows of the dual
    equality system (one per variable the constraints involve, each normalised) are dependent
    to within :data:`NEAR_SINGULAR` in floating point, yet independent exactly.

    A Farkas certificate of a cut problem must meet these rows (with one more column, the cut's
    multiplier, which does not separate rows the objective does not involve), exactly for
    :func:`prove_cut`: the exact correction of a float certificate is its residual over the
    smallest singular value, far beyond any margin. Exactly dependent rows (a projector with
    exact entries, the flexible-joint example of ``uio_dt.thm4_1``) are consistent and the proof
    goes through; rows dependent only up to rounding (the same projector of random data:
    ``Ybar V`` with ``V`` of rank 1 in floating point) are not.

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
    >>> v = [Variable("a", "scalar", (1, 1)), Variable("b", "scalar", (1, 1), offset=1)]
    >>> F = lambda b: sp.csc_matrix(np.array([[1.0, 1.0, 1.0], [0.0, 0.0, 0.0], [1.0, 0.0, b]]))
    >>> lmi = lambda b: LMI("I + a A + b B > 0", 2, F(b))
    >>> p = Problem(v, [lmi(2.0**-52)], LinearConstraints.empty(2), Objective("min", [0.0, 1.0, 0.0]))
    >>> near_dependent_rows(p)[:31]  # a's and b's coefficients equal up to rounding
    'the dual equality system is sin'
    >>> near_dependent_rows(dataclasses.replace(p, lmis=[lmi(0.0)])) is None  # equal exactly: provable
    True
    """
    from lmic.certify.enclosure_repair import _jacobian
    from lmic.rational_rank import full_row_rank_exactly

    J = _jacobian(problem)[0].toarray()[1:]
    J = J[np.any(J != 0, axis=1)]
    if J.shape[0] < 2:
        return None
    norms = np.linalg.norm(J, axis=1, keepdims=True)
    s = np.linalg.svd(J / norms, compute_uv=False)
    if not s[-1] < NEAR_SINGULAR * s[0]:
        return None
    if not full_row_rank_exactly(J, integer_fallback=True):
        return None  # exactly dependent: the proof handles consistent rows
    return (
        f"the dual equality system is singular to {s[-1] / s[0]:.1e} (relative) in floating point and regular "
        "exactly: no cut's Farkas certificate can be made exact (variables that act only through "
        "rounding, e.g. through a projector computed in floating point: docs/writing-a-theorem.md)"
    )
