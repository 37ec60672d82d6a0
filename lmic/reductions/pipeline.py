"""The engine's solve of one problem with one backend: reductions composed around a backend.

A backend only lowers, calls the solver and maps its answer (:meth:`lmic.backends.backend.Backend.solve`
solves the closed problem as given). :func:`solve` is what the solve policy (:mod:`lmic.policy`)
and every direct caller use instead:

1. :mod:`lmic.reductions.eliminate`: entries of ``x`` no constraint sees are dropped (and, for
   backends with ``full_rank``, linearly dependent ones); they come back as ``0``;
2. :mod:`lmic.reductions.strict`: strict constraints -> closed problems (``fixed-margin`` /
   ``max-margin``), each attempt run by the backend within one deadline
   (``SolveOptions.time_limit``);
3. after every attempt, an inexact infeasibility claim is settled by the certifier
   (:func:`settle_inexact_infeasible`): ``infeasible`` only when its ray verifies for the
   closed problem the solver was given.

The result is the old ``Backend.solve`` (lmic <= 0.x): same statuses, ``strategy``, ``margin``,
``solve_s`` (summed over the attempts) and ``lower_s`` (everything else lmic did).

Examples
--------
>>> from lmic.backends.registry import get_backend
>>> from lmic.testing.conformance import lyapunov_problem
>>> import numpy as np
>>> sol = solve(get_backend("clarabel"), lyapunov_problem(-np.eye(2)))
>>> sol.status, sol.strategy
('feasible', 'max-margin')
"""

from __future__ import annotations

import os
import time
import traceback
from typing import Any

from lmic.backends.backend import Backend
from lmic.backends.sandbox import describe
from lmic.ir.problem import Problem
from lmic.options import SolveOptions
from lmic.reductions import memo, strict
from lmic.reductions.eliminate import eliminate_unused, restore_eliminated
from lmic.solution import Solution

__all__ = ["solve", "settle", "settle_inexact_infeasible"]


def settle_inexact_infeasible(problem: Problem, sol: Solution, farkas: dict[str, Any] | None) -> Solution:
    """Keep an inexact infeasibility claim ``inaccurate`` unless its ray verifies.

    ``sol`` is the ``inaccurate`` solution of an inexact infeasibility status and ``farkas``
    the solver's ray (``{"lmis": [...], "linear": y}``, normalised or not). When the certifier
    (:func:`lmic.certify.farkas.ray_report`) verifies it for ``problem`` (the closed problem the
    solver was given), the status becomes ``infeasible`` with the ray as ``sol.farkas`` (the
    certifier checks it again); otherwise ``sol`` stays ``inaccurate`` with no point, the ray
    in ``sol.info["inexact_farkas"]``.

    >>> from lmic.testing.conformance import CASES
    >>> import numpy as np
    >>> p = CASES["infeasible"].build()
    >>> s = settle_inexact_infeasible(p, Solution("inaccurate"), {"lmis": [np.zeros((1, 1))], "linear": np.zeros(0)})
    >>> s.status
    'inaccurate'
    """
    sol.x = None
    sol.info["claim"] = "infeasible"
    if farkas is None or farkas.get("lmis") is None:
        sol.message = f"{sol.native_status}: inexact infeasibility claim without a ray"
        return sol
    from lmic.certify.farkas import ray_report  # only for an infeasibility claim (import time)

    report = ray_report(problem, farkas)
    if report.get("verified"):
        sol.status = "infeasible"
        sol.farkas = farkas
        sol.info.pop("inexact_farkas", None)
        sol.message = f"{sol.native_status}: inexact infeasibility claim whose Farkas ray verifies"
    else:
        sol.info["inexact_farkas"] = farkas
        sol.message = (
            f"{sol.native_status}: inexact infeasibility claim; its ray is not a verified Farkas "
            f"certificate ({report.get('reason', 'not verified')})"
        )
    return sol


def settle(problem: Problem, sol: Solution) -> Solution:
    """Settle a backend's inexact infeasibility claim (``info["claim"]``) on the problem it solved.

    >>> settle(None, Solution("optimal")).status
    'optimal'
    """
    if sol.status == "inaccurate" and sol.info.get("claim") == "infeasible":
        return settle_inexact_infeasible(problem, sol, sol.info.get("inexact_farkas"))
    return sol


def _auto(backend: Backend, problem: Problem, options: SolveOptions | None) -> Solution:
    """``auto`` as one backend: the first of its route, at that step's options."""
    from lmic.backends import auto
    from lmic.backends.registry import get_backend

    chain = auto.route(problem)
    sol = solve(get_backend(chain[0]), problem, auto.step_options(chain[0], options))
    sol.info["auto_route"] = chain
    return sol


#: exceptions that, raised in lmic's own code, are a bug of lmic's rather than the solver's failure
_BUG_TYPES = (NameError, AttributeError, TypeError, KeyError, IndexError, AssertionError)
_LMIC_DIR = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def crash_message(err: BaseException) -> str:
    """One line for a crash inside a solve: the exception, where it was raised, and whether it
    is a bug in lmic (a programming error raised in lmic's own code, not in a solver library),
    so that it is never mistaken for a solver's failure.

    >>> try:
    ...     {}["x"]
    ... except KeyError as e:
    ...     crash_message(e).startswith("KeyError: 'x' (at <module>)")
    True
    """
    detail = traceback.extract_tb(err.__traceback__)
    last = detail[-1] if detail else None
    message = describe(err) + (f" (at {last.name})" if last is not None else "")
    ours = last is not None and os.path.abspath(last.filename).startswith(_LMIC_DIR + os.sep)
    if last is not None and ours and isinstance(err, _BUG_TYPES):
        where = f"{os.path.relpath(last.filename, os.path.dirname(_LMIC_DIR))}:{last.lineno}"
        return f"internal error in lmic at {where}, not the solver's (please report it): {message}"
    return message


def solve(backend: Backend, problem: Problem, options: SolveOptions | None = None) -> Solution:
    """Solve ``problem`` with ``backend`` and the reductions; every outcome (crashes too) is a :class:`Solution`.

    Decision-variable entries that appear in no constraint and not in the objective (and, for
    backends with ``full_rank``, linearly dependent ones) are removed first; strict constraints
    are handled by :func:`lmic.reductions.strict.solve` (recorded in ``Solution.strategy`` and
    ``Solution.margin``). ``solve_s`` is the time inside the solver (summed over the attempts),
    ``lower_s`` everything else: elimination, reduction, lowering, result mapping, the check of
    a fixed-margin point and of an inexact infeasibility ray.
    """
    if backend.name == "auto":
        return _auto(backend, problem, options)
    options = backend.floor_options(options)
    # the elimination of dependent entries (full-rank backends only) uses these
    failed = backend.import_native(*(("scipy.linalg", "scipy.sparse.csgraph") if backend.full_rank else ()))
    if failed is not None:
        return failed
    t0 = time.perf_counter()
    too_large = backend.too_large(problem)
    if too_large is not None:  # a solve that would end the process out of memory (SDPLIB gpp250 on Clarabel)
        return Solution(status="error", backend=backend.label, message=too_large)
    try:
        kept, keep = eliminate_unused(problem, dependent=backend.full_rank)
        # one deadline for every attempt of the strict reduction (SolveOptions.time_limit)
        deadline = None if options.time_limit is None else time.monotonic() + options.time_limit

        def run(closed: Problem, opts: SolveOptions) -> Solution:
            key, known = memo.recall(backend.label, closed, opts)  # solved before in this route
            if known is not None:
                return known
            sol = settle(closed, backend._run(closed, opts, deadline))
            memo.remember(key, sol)
            return sol

        sol = strict.solve(kept, options, run, first_order=not backend.interior_point)
        if keep is not None:
            restore_eliminated(sol, keep, problem)
    except Exception as err:  # noqa: BLE001 - a crash is a status, never a traceback
        return Solution(
            status="error",
            backend=backend.label,
            message=crash_message(err),
            solve_s=time.perf_counter() - t0,
        )
    sol.backend = sol.backend or backend.label
    sol.lower_s = max(0.0, time.perf_counter() - t0 - sol.solve_s)
    return sol
