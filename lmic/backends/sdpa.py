"""SDPA through sdpa-python (``import sdpap``): the LMI form solved natively.

``sdpap.solve(A, b, c, K, J, option)`` takes a conic problem in SeDuMi form, primal
``min c'xi`` s.t. ``A xi - b in J``, ``xi in K`` and dual ``max b'y`` s.t. ``c - A'y in K*``.
With ``J = SymCone(f=n)`` (equalities) the *dual* is the IR's LMI form, so the decision vector
``x`` is SDPA's ``y`` and nothing is copied or slacked:

* ``b = -c_obj`` (``max -c'x``),
* ``c = [a0_eq; a0_ge; vec F0_1; ...]`` and ``A' = -[a_eq; a_ge; vec F_k ...]`` with
  ``K = SymCone(f=#eq, l=#ge, s=(d_1, ...))``, PSD blocks as full column-major ``d*d`` vectors
  (:class:`lmic.backends.lowering.LMIForm`, the one conversion place);
* SDPA's primal ``xi`` are the IR's multipliers ``(y_eq, y_ge, vec Z_i)``.

The phase value sdpa-python reports refers to the SeDuMi *primal* (the IR's dual):
``pUNBD``/``pFEAS_dINF`` mean the LMIs are infeasible, ``dUNBD``/``pINF_dFEAS`` that the IR
problem is unbounded. SDPA works in double precision and stalls ("primal < dual") at relative
gaps of a few 1e-7, so its gap tolerance is floored at :data:`TOL_FLOOR` (``pdFEAS``, a point
short of the gap tolerance, is ``inaccurate``), except for a tolerance at or below
:data:`TIGHT_TOL`: the tight re-solves of an enclosure (:func:`lmic.route_tighten.tighten`), whose
point and dual are used even when SDPA calls them inexact. Where SDPA's dual itself stops
about 1e-6 (relative) short of the optimum, the enclosure's gap stays there: on the random
instances of ``benchmarks/theorem_enclosures.py`` at 9 and 12 states, up to 4e-5 on
``uir.thm4_1`` and 7e-6 on ``sampled_euler.thm2/thm3`` (the re-solves at 1e-9 and 1e-10 end
at ``pFEAS`` with no better dual: ``uir.thm4_1`` n = 6 seed 1, 1.1e-6, 1.1e-5 and 1.4e-6);
Clarabel and CVXOPT meet 1e-6 there. SDPA has no time limit of its own: with
``SolveOptions.time_limit`` the solve runs in a child process.

Examples
--------
>>> SDPABackend.name
'sdpa'
"""

from __future__ import annotations

import dataclasses
import time
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any, ClassVar

import numpy as np
import scipy.sparse as sp

from lmic.backends.backend import Backend
from lmic.backends.lowering import LMIData, LMIForm
from lmic.backends.quiet import quiet_native
from lmic.backends.results import NativeResult
from lmic.ir.problem import Problem
from lmic.options import SolveOptions
from lmic.solution import Solution

__all__ = ["SDPABackend", "sdpa_data", "TOL_FLOOR", "TIGHT_TOL"]

#: SDPA's tolerances are not set below this (its double-precision limit) ...
TOL_FLOOR = 1e-6
#: ... unless the tolerance asked is at most this: a tight re-solve of an enclosure
#: (:data:`lmic.route_tighten.TIGHT_TOLS`), passed through. Random ``delay_b.thm4_1`` n = 10 (seed 1):
#: epsilonStar 1e-6 (the floor) gives an enclosure of relative gap 1.2e-6 at any tolerance
#: asked, 1e-9 passed through 7.2e-7 (SDPA stops at ``pdFEAS``, its point and dual still prove
#: both ends)
TIGHT_TOL = 1e-9
#: the time limit of an SDPA solve given none: every SDPA solve runs in a forked child
#: (:meth:`SDPABackend._run`)
CHILD_LIMIT_S = 7 * 24 * 3600.0


def _tolerances(tol: float) -> tuple[float, float]:
    """SDPA's ``(epsilonStar, epsilonDash)`` for the uniform tolerance ``tol``.

    >>> _tolerances(1e-8), _tolerances(1e-10)
    ((1e-06, 1e-07), (1e-10, 1e-10))
    """
    if tol <= TIGHT_TOL:
        return tol, tol
    return max(tol, TOL_FLOOR), max(tol, 1e-7)


def sdpa_data(problem: Problem) -> tuple[sp.csc_matrix, np.ndarray, np.ndarray, LMIData]:
    """SeDuMi-form data ``(A, b, c, lmi_data)`` whose dual is ``problem``'s LMI form.

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("t", "scalar", (1, 1))], [LMI("t>=1", 1, sp.csc_matrix([[-1., 1.]]),
    ...             strict=False)], LinearConstraints.empty(1), Objective("min", [0, 1]))
    >>> A, b, c, _ = sdpa_data(p)
    >>> A.toarray(), b, c
    (array([[-1.]]), array([-1.]), array([-1.]))
    """
    data = LMIForm.apply(problem)
    M = sp.vstack([data.A_eq[:, 1:], data.A_ge[:, 1:], *data.G], format="csr")
    parts = [data.A_eq[:, 0].toarray().ravel(), data.A_ge[:, 0].toarray().ravel()]
    c = np.concatenate(parts + [F0.ravel(order="F") for F0 in data.F0])
    return (-M).T.tocsc(), -data.c, c, data


@contextmanager
def _no_error_recomputation(active: bool = True) -> Iterator[None]:
    """Skip sdpa-python's recomputation of the answer's feasibility errors during a solve.

    After every solve ``sdpap.solve`` recomputes the primal and dual feasibility errors of the
    converted answer with ARPACK (``scipy.sparse.linalg.eigs``, smallest magnitude): 0.43 of
    0.93 s on a random ``uncertain_dt.thm1`` with 8 states (profiled), SDPA itself 0.42 s. lmic
    never reads them (``pinfo``'s ``primalError`` / ``dualError``; the certifier checks the
    answer), so they are reported as ``None``, as sdpa-python does when ARPACK fails (its
    ``RuntimeWarning`` about it is silenced by the caller). Not ``active`` (a ``resultFile``
    asked through ``extra``, whose writer formats them as numbers): computed as usual.
    """
    if not active:
        yield
        return
    try:
        from sdpap import sdpaputils
    except ImportError:  # pragma: no cover - the backend is unavailable then
        yield
        return
    saved = sdpaputils.get_primalerror, sdpaputils.get_dualerror
    sdpaputils.get_primalerror = sdpaputils.get_dualerror = _not_recomputed
    try:
        yield
    finally:
        sdpaputils.get_primalerror, sdpaputils.get_dualerror = saved


def _not_recomputed(*args: Any, **kwargs: Any) -> None:
    """sdpa-python's feasibility error, not recomputed (:func:`_no_error_recomputation`)."""
    return None


class SDPABackend(Backend):
    """SDPA (primal-dual interior point) through sdpa-python, LMI form."""

    name: ClassVar[str] = "sdpa"
    title: ClassVar[str] = "SDPA"
    requires: ClassVar[dict[str, str]] = {"sdpap": "sdpa-python"}
    full_rank: ClassVar[bool] = True
    description: ClassVar[str] = "SDPA interior point via sdpa-python (LMI form)"
    STATUS_MAP: ClassVar[dict[str, str]] = {
        "pdOPT": "optimal",
        "pdFEAS": "inaccurate",
        "pFEAS": "inaccurate",
        "dFEAS": "inaccurate",
        "pFEAS_dINF": "infeasible",
        "pUNBD": "infeasible",
        "pINF_dFEAS": "unbounded",
        "dUNBD": "unbounded",
        "pdINF": "infeasible",
        "noINFO": "error",
    }

    def _run(self, problem: Problem, options: SolveOptions, deadline: float | None = None) -> Solution:
        """:meth:`Backend._run` always in a forked child (:mod:`lmic.backends.sandbox`), with
        :data:`CHILD_LIMIT_S` when no time limit is given: sdpa-python ends the whole process
        on some inputs (exit code 0, no output; SDPLIB hinf1 with ``|x_k| <= 1e4`` added), which
        then ends only the child, reported as an ``error`` solution."""
        if options.time_limit is None:
            options = dataclasses.replace(options, time_limit=CHILD_LIMIT_S)
        return super()._run(problem, options, deadline)

    def settings(self, options: SolveOptions) -> dict[str, Any]:
        """sdpa-python's option dictionary from the uniform options (``extra`` verbatim, last)."""
        opts: dict[str, Any] = {
            "print": "display" if options.verbose else "no",
        }
        opts["epsilonStar"], opts["epsilonDash"] = _tolerances(float(options.tol))
        if options.max_iter is not None:
            opts["maxIteration"] = int(options.max_iter)
        opts.update(options.extra)
        return opts

    def call(self, problem: Problem, settings: dict[str, Any]) -> NativeResult:
        """Lower to SeDuMi form (:func:`sdpa_data`), run ``sdpap.solve``, invert its primal ``xi``."""
        import sdpap

        A, b, c, data = sdpa_data(problem)
        K = sdpap.SymCone(f=len(data.eq), l=len(data.ge), s=tuple(data.dims))
        J = sdpap.SymCone(f=problem.n)
        t0 = time.perf_counter()
        with (
            quiet_native(settings.get("print") == "no"),
            warnings.catch_warnings(),
            _no_error_recomputation(not settings.get("resultFile")),
        ):
            # sdpa-python recomputes feasibility errors with scipy eigs and warns on tiny blocks
            warnings.simplefilter("ignore", RuntimeWarning)
            xi, y, _pinfo, _tinfo, info = sdpap.solve(A, b, c, K, J, dict(settings))
        solve_s = time.perf_counter() - t0
        native = str(info.get("phasevalue", "noINFO"))
        xi = np.asarray(xi.toarray() if sp.issparse(xi) else xi, dtype=float).ravel()
        x = np.asarray(y.toarray() if sp.issparse(y) else y, dtype=float).ravel()
        mult = LMIForm.invert_stacked(data, xi)
        gap = float(c @ xi)
        if self.map_status(native) == "infeasible" and gap < 0:
            # SDPA detects infeasibility by a diverging dual: scale it into a Farkas ray
            mult = {"lmis": [Z / -gap for Z in mult["lmis"]], "linear": mult["linear"] / -gap}
        failed = self.map_status(native) in ("inaccurate", "error")
        message = f"SDPA stopped with phase {native}" if failed else ""
        return NativeResult(
            native, x=x, duals=mult, solve_s=solve_s, iterations=int(info.get("iteration", 0)), message=message
        )
