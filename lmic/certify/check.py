"""The certifier: decide from the IR alone whether a solver's answer is what it claims.

A solver's ``optimal`` is a claim. :func:`certify` re-evaluates everything from the IR
(:class:`~lmic.ir.problem.Problem`), never from a backend's model:

* every LMI ``F(x)`` (sparse, from the IR coefficients) and its extreme eigenvalues;
* every linear row, the objective, the derived quantities (gains) and the theorem's checks;
* for an ``infeasible`` status, the dual (Farkas) certificate (:mod:`lmic.certify.farkas`);
* optionally (``exact=True``) an exact rational proof of every LMI (:mod:`lmic.certify.exact`).

Margins are relative to the *term scale*
----------------------------------------
For an LMI ``F(x) = F0 + sum_k x_k F_k`` the certifier computes the term scale

    ``T = || |F0| + sum_k |x_k| |F_k| ||_2``      (entrywise absolute values, spectral norm)

which bounds ``||F(x)||`` and is what the floating-point error of evaluating ``F(x)`` is
proportional to: the computed ``lambda_min`` is within ``(k + d + 2) u T`` of the exact one
(``k`` terms per entry, dimension ``d``, unit round-off ``u``). The relative margin is
``lambda_min / T``. It is scale-free, so a homogeneous LMI (``F0 = 0``) evaluated at a
near-zero point is judged at its own scale: the near-zero points SCS returns on homogeneous
LMIs (``omega ~ 1.7e-7``), whose tiny absolute violations would pass an absolute tolerance,
have a relative margin of order ``-1e-2`` and are rejected.

Acceptance rules (defaults in :class:`Tolerances`)
--------------------------------------------------
strict LMI (``F(x) > 0``)
    ``lambda_min > max(strict_rel, 10 (k + d + 2) u) * T``: positive beyond any doubt from
    floating-point evaluation (``strict_rel = 1e-12``; the second term is ~1e-13 for d = 180).
    A point at which every term of the LMI vanishes (``T == 0``, or ``T`` below ``zero_rel``
    times the coefficient scale ``|| |F0| + sum_k |F_k| ||``) is "~0" and rejected: a
    homogeneous LMI says nothing at ``x = 0``.
non-strict LMI (``F(x) >= 0``)
    proved in float when ``lambda_min >= 10 (k + d + 2) u T`` (above its error bound). Between
    ``-rel * T`` (``rel = 1e-8``, a typical solver tolerance) and that bound it *holds within
    tolerance*, which proves nothing: the exact proof is then run (below, also without
    ``exact``, up to :data:`AUTO_PROOF_MAX`), and the point is rejected unless it proves it
    (at ``x`` itself, at an exact projection onto the equality rows, or at the exactly feasible
    point next to it, :mod:`lmic.certify.snap`). When the solver itself reported
    ``inaccurate``, ``lambda_min`` below ``-10 (k + d + 2) u T`` is a violation outright. A
    marginally infeasible problem comes back as ``inaccurate`` with a small violation
    (Clarabel, +1.6e-7 at ``||P|| ~ 7.5``); it must not pass as a certificate.
linear rows
    ``eq``: a float residual never proves an equality: ``|r| <= rel * s`` holds within
    tolerance and goes to the exact proof like a non-strict LMI; ``ge``: proved when ``r`` is
    above its rounding error ``10 (k + 2) u s``, within tolerance down to ``-rel * s``; strict
    ``ge``: ``r > max(strict_rel, 10 (k + 2) u) * s``, with ``s = |a0| + sum_k |a_k x_k|``.
objective
    The IR's ``c0 + c . x`` must agree with the solver's claim to ``objective_rel`` (relative to
    ``max(1, |value|)``); a disagreement rejects the answer.
derived quantities and checks
    Derived quantities are evaluated in order (``Problem.environment``); a failure (singular
    ``P``) or a non-finite value fails every check that uses it. Checks follow
    :data:`lmic.ir.problem.CHECK_KINDS` (``schur_stable``: spectral radius ``< 1``;
    ``hurwitz``: spectral abscissa ``< 0``; definiteness of the symmetric part with a
    ``strict_rel`` margin relative to its norm; ...). A failed check rejects the answer even
    when every LMI holds (e.g. an SCS "success" whose gain leaves ``A - L C`` unstable).

Exact mode (``exact=True``)
---------------------------
The float rules above are a test; an exact proof (:func:`lmic.certify.exact.prove`) is a
theorem, so in exact mode it decides the LMIs and the linear rows:

* when the whole proof holds (every LMI and row exactly, equalities with residual zero),
  every LMI and row is accepted, whatever its float margin: a strict LMI whose relative margin
  is below ``strict_rel`` (e.g. ``uio_dt.thm3_2`` near its supremum, ~2e-13) is certified. The
  proof holds at the *recorded* rational point ``x_q`` (``exact.point``), which is the solver's
  float point itself whenever that can be proved (``exact.at_x``), and otherwise a rounding or
  an exact projection onto the equality rows, at distance ``exact.distance`` from ``x``;
* otherwise, if ``x_q`` is the float point, each LMI or row proved on its own is accepted and
  an LMI disproved exactly (strict or not) is rejected; elsewhere the float rules stay;
* whatever holds only within the float tolerance and is not proved exactly is rejected:
  ``certified`` never rests on a tolerance.

Every LMI and row entry reports both: ``float_ok`` (the float rule), ``exact`` (``proved``,
``disproved``, ``not proven``; ``within tolerance`` for equality rows; ``None`` outside exact
mode), ``ok`` (the decision) and ``decided_by`` (``float`` or ``exact``). Derived quantities,
checks and the objective are evaluated in float64 at ``x`` in either mode, and must hold; the
exact objective at ``x_q`` is reported in ``exact.objective``. The label is
``certified (exact)`` when the verdict is ``certified`` and the whole proof holds.

Verdicts
--------
``certified``            every criterion above holds at ``x`` (the solver status does not matter).
``rejected``             some criterion fails; ``reason`` names the first violated constraint
                         (LMIs, then linear rows, then derived quantities and checks, then the
                         objective) and by how much.
``infeasible-certified`` the status is ``infeasible`` and the Farkas certificate is a GLOBAL proof
                         (exact, or homogeneous problem: :func:`lmic.certify.farkas.scope`).
``infeasible-bounded``   the Farkas certificate verifies in float but only excludes solutions with
                         ``||x||_inf <= R`` (never called infeasible).
``unverified``           nothing to check: ``infeasible`` without a verifiable certificate,
                         ``unbounded``, or an ``error`` without a point.

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
>>> from lmic.solution import Solution
>>> p = Problem([Variable("p", "scalar", (1, 1))], [LMI("p > 0", 1, sp.csc_matrix([[0., 1.]]))],
...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
>>> certify(p, Solution("optimal", x=np.array([2.0]))).verdict
'certified'
>>> c = certify(p, Solution("optimal", x=np.array([-1e-9])))
>>> c.verdict, c.reason
('rejected', "LMI 'p > 0' violated: lambda_min = -1e-09 (relative -1), needs > 0 (strict)")

A strict LMI below the float threshold, decided by the exact proof:

>>> q = Problem([Variable("p", "scalar", (1, 1))],
...             [LMI("M > 0", 2, sp.csc_matrix([[1e6, 0.], [0., 0.], [1e-7, 0.]]))],
...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
>>> certify(q, Solution("optimal", x=np.array([0.0]))).verdict
'rejected'
>>> c = certify(q, Solution("optimal", x=np.array([0.0])), exact=True)
>>> c.label, c.lmis[0]["float_ok"], c.lmis[0]["exact"], c.lmis[0]["decided_by"]
('certified (exact)', False, 'proved', 'exact')

The certifier is split by job: the data types (:mod:`lmic.certify.result`), the float rules for
LMIs and rows (:mod:`lmic.certify.margins`), derived quantities, checks and the objective
(:mod:`lmic.certify.derived`); this module composes them in :func:`certify` and re-exports
every public name it had (``VERDICTS``, ``Tolerances``, ``Certificate``, ``lmi_report``,
``evaluate_checks``).
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from lmic.certify.derived import check_reason, environment_report, evaluate_checks, objective_report
from lmic.certify.margins import _g, linear_reason, linear_reports, lmi_reason, lmi_report
from lmic.certify.result import VERDICTS, Certificate, Tolerances
from lmic.errors import LmicError
from lmic.ir.problem import Problem
from lmic.solution import Solution

__all__ = ["VERDICTS", "Tolerances", "Certificate", "certify", "certified_solution", "lmi_report", "evaluate_checks"]


def _reasons(cert: Certificate) -> list[str]:
    """Every failed criterion, in the documented order (LMIs, rows, derived, checks, objective)."""
    reasons: list[str] = []
    failing = [r for r in cert.lmis if not r["ok"]]
    if failing:
        worst = min(failing, key=lambda r: r["rel_margin"] if math.isfinite(r["rel_margin"]) else -math.inf)
        if worst["decided_by"] == "exact":
            reasons.append(f"exact: LMI '{worst['name']}' {worst['note']}")
        else:
            reasons.append(lmi_reason(worst, cert.objective is not None))
        if len(failing) > 1:
            reasons[-1] += f" (and {len(failing) - 1} more LMI(s))"
    reasons += [linear_reason(r) for r in cert.linear if not r["ok"]]
    reasons += [f"derived '{r['name']}' failed: {r['error']}" for r in cert.derived if not r["ok"]]
    reasons += [check_reason(r) for r in cert.checks if not r["ok"]]
    if cert.objective is not None and not cert.objective["ok"]:
        o = cert.objective
        reasons.append(f"objective: the solver reports {o['claimed']!r}, the point gives {o['value']!r}")
    return reasons


def _apply_exact(cert: Certificate, ex: dict[str, Any]) -> None:
    """Let the exact proof decide the LMIs and linear rows (rules of the module docstring).

    * the whole proof holds (at ``x_q``, recorded): every LMI and row is accepted, whatever its
      float margin;
    * otherwise, when ``x_q`` is the float point itself, each LMI or row proved exactly is
      accepted (the others are proved in float at the same point, or fail), and an LMI disproved
      exactly is rejected, strict or not;
    * what holds only within the float tolerance and is not proved exactly is rejected later
      (:func:`_unproved`).
    """
    whole, at_x = bool(ex["proven"]), bool(ex["at_x"])
    for r, e in zip(cert.lmis, ex.get("lmis", []), strict=True):
        r["exact"] = "proved" if e["proven"] else ("disproved" if e["disproved"] else "not proven")
        if (whole or (at_x and e["proven"])) and (not r["ok"] or r.get("within_tolerance")):
            r["ok"], r["decided_by"] = True, "exact"
            what = "positive definite" if r["strict"] else "positive semidefinite"
            r["note"] = (
                f"below the float threshold (relative margin {_g(r['rel_margin'])}); {what} by the exact proof at x_q"
            )
        elif e["disproved"] and r["ok"]:
            r["ok"], r["decided_by"] = False, "exact"
            what = "positive definite" if r["strict"] else "positive semidefinite"
            r["note"] = f"is not {what} at the solver's point ({e['detail']})"
    for r, e in zip(cert.linear, ex.get("linear", []), strict=True):
        r["exact"] = "proved" if e["proven"] else ("within tolerance" if e["within_tolerance"] else "not proven")
        if (whole or (at_x and e["proven"])) and (not r["ok"] or r.get("within_tolerance")):
            r["ok"], r["decided_by"] = True, "exact"


def _tolerance_only(cert: Certificate) -> list[dict[str, Any]]:
    """The LMIs and rows accepted by the float tolerance alone (not proved in float or exactly)."""
    return [r for r in cert.lmis + cert.linear if r["ok"] and r.get("within_tolerance") and r["decided_by"] == "float"]


def _unproved(cert: Certificate) -> None:
    """Reject what holds only within the tolerance: ``certified`` means proved."""
    for r in _tolerance_only(cert):
        r["ok"], r["decided_by"] = False, "float"
        r["note"] = "holds within tolerance, not proved" + (
            " (the exact proof failed too)" if cert.exact is not None else ""
        )


#: the largest ``sum_i d_i^2`` (LMI orders) at which a point that holds only within the float
#: tolerance is given an exact proof automatically (:func:`certify` without ``exact``)
AUTO_PROOF_MAX = 250_000


# --------------------------------------------------------------------------------------------
# the certifier


def _snapped(problem: Problem, solution: Solution, cert: Certificate, exact: bool, tol: Any, why: str):
    """The certificate at an exactly feasible point next to a rejected ``x``
    (:mod:`lmic.certify.snap`), or ``None``."""
    import dataclasses

    from lmic.certify.snap import snap_point, snappable

    if not snappable(problem, cert):
        return None
    snap = snap_point(problem, np.asarray(cert.x, dtype=float), tol=Tolerances.coerce(tol))
    if snap is None:
        return None
    moved = dataclasses.replace(solution, x=snap["x"], objective=problem.objective.value(snap["x"]), strategy="snapped")
    # re-certified with the exact proof (the snap rests on it; an audit re-runs it)
    again = certify(problem, moved, exact=True, tol=tol)
    if again.verdict != "certified":
        return None
    again.reason += (
        f"; the solver's point was rejected ({why}) and moved to x_q, proved exactly feasible "
        f"({snap['how']}, max |x_q - x| = {snap['distance']:.3g}): the feasible set has no interior there"
    )
    return again


def certify(
    problem: Problem,
    solution: Solution,
    *,
    exact: bool = False,
    tol: Tolerances | float | dict | None = None,
) -> Certificate:
    """Certify (or reject) a solver's answer from the IR alone.

    Parameters
    ----------
    problem : Problem
        The IR the answer is for.
    solution : Solution
        The backend's answer (its status and objective are claims to check).
    exact : bool
        Also prove every LMI in exact rational arithmetic (:func:`lmic.certify.exact.prove`).
    tol : Tolerances, float or dict, optional
        Tolerances (a float sets :attr:`Tolerances.rel`).

    Returns
    -------
    Certificate

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
    >>> from lmic.solution import Solution
    >>> p = Problem([Variable("p", "scalar", (1, 1))],
    ...             [LMI("1 - p >= 0", 1, sp.csc_matrix([[1., -1.]]), strict=False)],
    ...             LinearConstraints.empty(1), Objective("max", [0, 1]))
    >>> c = certify(p, Solution("optimal", x=np.array([1.0]), objective=1.0), exact=True)
    >>> c.verdict, c.objective["ok"], c.exact["proven"]
    ('certified', True, True)
    """
    t0 = time.perf_counter()
    tolr = Tolerances.coerce(tol)
    cert = Certificate(
        verdict="unverified",
        status=solution.status,
        backend=solution.backend,
        tolerances=tolr.to_dict(),
    )
    if solution.status == "infeasible":
        from lmic.certify.farkas import verify_farkas

        if solution.farkas is None:
            cert.reason = "the solver reports infeasible but gave no dual (Farkas) certificate"
        else:
            cert.farkas = verify_farkas(problem, solution.farkas, tol=tolr.farkas_rel)
            if exact:
                from lmic.certify.farkas import prove_infeasible

                cert.exact = prove_infeasible(problem, solution.farkas, cert.farkas)
            # global (exact, or homogeneous) or bounded ("no solution with ||x|| <= R"): farkas.scope
            from lmic.certify.farkas import scope

            cert.farkas["scope"] = scope(problem, cert.farkas, cert.exact)
            kind = cert.farkas["scope"]["scope"]
            if kind == "global" and cert.farkas["verified"]:
                cert.verdict = "infeasible-certified"
                cert.reason = cert.farkas["reason"]
                if cert.exact is not None:
                    cert.reason += "; exact proof: " + cert.exact["reason"]
            elif kind == "global" and cert.exact is not None:
                # the float tolerances failed but an exact certificate exists: a theorem
                cert.verdict = "infeasible-certified"
                cert.reason = cert.exact["reason"] + " (the float verification failed: " + cert.farkas["reason"] + ")"
            elif kind == "bounded":
                cert.verdict = "infeasible-bounded"
                cert.reason = cert.farkas["scope"]["statement"]
                if cert.exact is not None:
                    cert.reason += "; exact proof failed: " + cert.exact["reason"]
            else:
                cert.reason = "infeasibility not verified: " + (
                    cert.farkas["reason"] if not cert.farkas["verified"] else cert.farkas["scope"]["statement"]
                )
        cert.time_s = time.perf_counter() - t0
        return cert
    if solution.x is None:
        cert.reason = f"the solver reports '{solution.status}' and returned no point to check"
        if solution.message:
            cert.reason += f" ({' '.join(solution.message.split())})"
        cert.time_s = time.perf_counter() - t0
        return cert

    x = np.asarray(solution.x, dtype=float).ravel()
    if x.shape != (problem.n,):
        raise LmicError(f"the solution has {x.size} entries, the problem {problem.n} variables")
    cert.x = x.tolist()
    if not np.all(np.isfinite(x)):
        cert.verdict = "rejected"
        cert.reason = "the point has non-finite entries"
        cert.time_s = time.perf_counter() - t0
        return cert

    inaccurate = solution.status == "inaccurate"
    cert.lmis = [lmi_report(lmi, x, tolr, inaccurate=inaccurate) for lmi in problem.lmis]
    cert.linear = linear_reports(problem, x, tolr, inaccurate)
    cert.objective = objective_report(problem, solution, x, tolr)
    env, cert.derived = environment_report(problem, x)
    cert.checks = evaluate_checks(problem.checks, env, tolr)
    if any(not r["ok"] for r in cert.checks):  # a definiteness off by rounding: decided exactly
        from lmic.certify.check_exact import recheck

        recheck(problem, x, cert.checks)
    strict_eigs = [r["min_eig"] for r in cert.lmis if r["strict"]]
    if solution.margin is not None or strict_eigs:
        cert.margin = {
            "strategy": solution.strategy,
            "claimed": solution.margin,
            "achieved": min(strict_eigs) if strict_eigs else None,
        }

    # only an exact proof turns "within tolerance" into "holds": it runs without ``exact`` too
    # when that is all that is missing (and the LMIs are not too large)
    auto = (
        not exact
        and bool(_tolerance_only(cert))
        and not _reasons(cert)
        and sum(lmi.dim**2 for lmi in problem.lmis) <= AUTO_PROOF_MAX
    )
    if exact or auto:
        from lmic.certify.exact import prove

        cert.exact = prove(problem, x, inaccurate=inaccurate, tol=tolr, min_eigs=[r["min_eig"] for r in cert.lmis])
        _apply_exact(cert, cert.exact)
    if not _reasons(cert):
        _unproved(cert)  # after every genuine failure: those are named first
    reasons = _reasons(cert)
    if reasons and solution.strategy != "snapped":
        snapped = _snapped(problem, solution, cert, exact, tol, reasons[0])  # no interior: x_q on the face
        if snapped is not None:
            snapped.time_s = time.perf_counter() - t0
            return snapped

    if reasons:
        cert.verdict, cert.reason = "rejected", reasons[0]
    else:
        cert.verdict = "certified"
        worst = min(cert.lmis, key=lambda r: r["rel_margin"], default=None)
        cert.reason = "every constraint and check holds"
        if worst is not None:
            cert.reason += (
                f"; smallest margin {_g(worst['min_eig'])} (relative {_g(worst['rel_margin'])}) on '{worst['name']}'"
            )
        if inaccurate:
            cert.reason += " (despite the solver's 'inaccurate' status)"
        if cert.exact is not None:
            rescued = [r["name"] for r in cert.lmis + cert.linear if r["decided_by"] == "exact"]
            if cert.exact["proven"]:
                cert.reason += "; exact proof: " + cert.exact["statement"]
            else:
                cert.reason += "; exact proof: " + cert.exact["reason"]
            if rescued:
                cert.reason += f"; below the float threshold but proved exactly: {', '.join(repr(n) for n in rescued)}"
    cert.time_s = time.perf_counter() - t0
    return cert


def _exact_floats(point: dict[str, Any] | None) -> tuple[np.ndarray | None, bool]:
    """The rational point ``{"den", "num"}`` of an exact proof as its nearest floats, and
    whether they are that point exactly (a dyadic rounding of ``x`` is; a projection onto the
    equality rows usually is not); ``(None, False)`` without a point."""
    from fractions import Fraction

    if not point or "den" not in point:
        return None, False
    den = int(point["den"])
    values = [Fraction(int(n), den) for n in point["num"]]
    floats = [float(v) for v in values]  # correctly rounded
    exact = all(Fraction(f) == v for f, v in zip(floats, values, strict=True))
    return np.array(floats), exact


def certified_solution(problem: Problem, solution: Solution, cert: Certificate) -> tuple[Solution, Certificate]:
    """``(solution, certificate)`` at the point the certificate proves, for every caller that
    reports a point: the variables, the objective, the derived gains and a certificate file
    must be those of the proven point, never of a solver's point that was moved.

    * a point moved by the certifier (``cert.x`` differs from ``solution.x``: the snap of
      :func:`_snapped` onto an exactly feasible point) replaces the solver's;
    * a proof that holds only at a rational point ``x_q`` near ``x`` (``exact.at_x`` false: a
      rounding of ``x``, or its projection onto the equality rows) moves the point to the
      nearest floats of ``x_q`` and certifies it again there (the proof then holds at ``x_q``
      itself when it is a float, else at a rational point within rounding of it), so that the
      variables and the objective reported are those of a proven point to the last bit, not
      the solver's (a projection can move it by 1e-8: ``x1 = 3 x2`` missed by 9e-9, an
      objective below the minimum); when that proof fails, ``solution`` is returned
      unchanged with the certificate of ``x_q`` and its distance recorded;
    * anything not ``certified`` is returned unchanged.

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
    >>> p = Problem([Variable("p", "scalar", (1, 1))],
    ...             [LMI("1 - p >= 0", 1, sp.csc_matrix([[1., -1.]]), strict=False)],
    ...             LinearConstraints.empty(1), Objective("max", [0, 1]))
    >>> sol = Solution("optimal", x=np.array([0.5]), objective=0.5)
    >>> s2, c2 = certified_solution(p, sol, certify(p, sol))
    >>> s2 is sol, c2.verdict
    (True, 'certified')
    """
    import dataclasses

    if cert.verdict != "certified" or solution.x is None or cert.x is None:
        return solution, cert
    x = np.asarray(cert.x, dtype=float)
    old = np.asarray(solution.x, dtype=float)
    if x.shape != old.shape or not np.array_equal(x, old):
        moved = dataclasses.replace(solution, x=x, objective=problem.objective.value(x))
        return moved, cert
    ex = cert.exact or {}
    if not ex.get("proven") or ex.get("at_x", True):
        return solution, cert
    xq, representable = _exact_floats(ex.get("point"))
    if xq is None or xq.shape != old.shape:
        return solution, cert
    moved = dataclasses.replace(solution, x=xq, objective=problem.objective.value(xq))
    again = certify(problem, moved, exact=True, tol=cert.tolerances)
    if again.verdict != "certified":
        # said as it is: the proof is of x_q, the numbers reported are the solver's point's
        dist = float(np.max(np.abs(xq - old), initial=0.0))
        cert.reason += (
            f"; the variables and objective reported are the solver's point, within {dist:.3g} of "
            "the proven rational point x_q (exact.point)"
        )
        return solution, cert
    if representable:
        again.reason += "; the point returned is x_q, the rounding of the solver's point the proof holds at"
    else:
        # x_q (a projection onto the equality rows) has no float coordinates: the nearest
        # floats are returned, proved again (their own exact point is within rounding of them)
        again.reason += "; the point returned is the nearest floats to the proven rational point"
    return moved, again
