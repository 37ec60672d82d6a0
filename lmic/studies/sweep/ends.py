"""The certified end of a supremum's bracket: its point, gains and certificate file.

:func:`certified_end` certifies the point at a feasible bisection value again on the theorem's
own problem (objective kept): where the theorem has an objective and derives gains, a
backed-off point (:mod:`lmic.backoff`, objective within ``1e-3`` of the bisection point's,
``||x||_inf`` minimised) if it certifies, else the bisection point itself (exactly where its
float margins are too small). :func:`write_end_certificate` writes its certificate (``-o``).

Examples
--------
>>> import scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
>>> p = Problem([Variable("p", "scalar", (1, 1))], [LMI("p > 0", 1, sp.csc_matrix([[0., 1.]]))],
...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
>>> from lmic.studies.sweep.points import decide
>>> pt = decide(p, value=1.0); pt.problem = p
>>> certified_end(pt).source
'bisection point'
"""

from __future__ import annotations

from typing import Any

import numpy as np

from lmic.errors import LmicError
from lmic.solution import Solution
from lmic.studies.sweep.results import EndPoint, PointResult, SupResult

__all__ = ["certified_end", "write_end_certificate", "derived_values"]


def derived_values(cert: Any) -> dict[str, Any]:
    """Every derived quantity of a certificate (matrices as nested lists).

    >>> derived_values(None)
    {}
    """
    out: dict[str, Any] = {}
    for item in getattr(cert, "derived", None) or []:
        v = item.get("value")
        if isinstance(v, np.ndarray):
            v = v.tolist()
        out[item["name"]] = float(v) if isinstance(v, int | float) and not isinstance(v, bool) else v
    return out


def certified_end(
    point: PointResult, backend: Any = None, options: Any = None, backoff: float | None = None
) -> EndPoint | None:
    """The certified point at a feasible bisection value, on the theorem's own problem.

    With ``backoff`` (default :data:`lmic.backoff.DEFAULT_BACKOFF` when the theorem derives
    quantities, ``0`` off) and an objective, the problem at this value is re-solved with the
    objective within ``backoff`` (relative) of the bisection point's and ``||x||_inf``
    minimised; a certified backed-off point is used (well-scaled gains). Otherwise the bisection
    point itself is certified against the theorem's problem (objective kept), with an exact
    proof where its float margins are too small. ``None`` when neither is certified (never a
    false certificate).

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
    >>> p = Problem([Variable("p", "scalar", (1, 1))], [LMI("p > 0", 1, sp.csc_matrix([[0., 1.]]))],
    ...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
    >>> from lmic.studies.sweep.points import decide
    >>> pt = decide(p, value=1.0); pt.problem = p
    >>> certified_end(pt).verdict
    'certified'
    """
    from lmic.certify import certified_solution, certify
    from lmic.rescue import exact_rescue_point

    problem = point.problem
    if point.outcome != "feasible" or problem is None or point.x is None:
        return None
    notes: list[str] = []
    x = np.asarray(point.x, dtype=float)
    rel = backoff
    if rel is None:
        from lmic.backoff import DEFAULT_BACKOFF

        rel = DEFAULT_BACKOFF if problem.derived else 0.0
    if rel and problem.objective.sense != "feasibility":
        from lmic.backoff import backoff as run_backoff

        be = "clarabel" if backend in (None, "auto") else backend
        ref = problem.objective.value(x)
        rec = run_backoff(problem, float(ref if ref is not None else 0.0), be, options, rel=float(rel))
        if rec.get("verdict") == "certified" and rec.get("x") is not None:
            xb = np.asarray(rec["x"], dtype=float)
            sol = Solution(status=rec["status"], x=xb, objective=problem.objective.value(xb), backend=str(be))
            sol, cert = certified_solution(problem, sol, certify(problem, sol))  # the point proved
            xb = np.asarray(sol.x, dtype=float)
            if cert.verdict == "certified":
                return EndPoint(
                    value=point.value,
                    source="backed-off point",
                    verdict="certified",
                    proof="certified",
                    derived=derived_values(cert),
                    norm_inf=float(np.max(np.abs(xb), initial=0.0)),
                    backoff=float(rel),
                    notes=notes,
                    problem=problem,
                    solution=sol,
                    certificate=cert,
                )
        notes.append(f"backed-off point ({rel:g}) not certified, the bisection point is used: {rec.get('reason')}")
    label = str(getattr(backend, "label", backend) or "auto")
    # the bisection solve had no objective: the recorded objective is lmic's value at x
    sol = Solution(status=point.status or "optimal", x=x, objective=problem.objective.value(x), backend=label)
    end_cert: Any = certify(problem, sol)
    proof = "certified"
    if end_cert.verdict != "certified":
        end_cert = exact_rescue_point(problem, sol, end_cert)
        proof = "certified (exact)"
    if end_cert is None or end_cert.verdict != "certified":
        return None
    # the point reported and written (lmic audit re-proves it) is the point proved
    sol, end_cert = certified_solution(problem, sol, end_cert)
    x = np.asarray(sol.x, dtype=float)
    return EndPoint(
        value=point.value,
        source="bisection point",
        verdict="certified",
        proof=proof,
        derived=derived_values(end_cert),
        norm_inf=float(np.max(np.abs(x), initial=0.0)),
        notes=notes,
        problem=problem,
        solution=sol,
        certificate=end_cert,
    )


def write_end_certificate(result: SupResult, path: str) -> dict[str, Any]:
    """Write the certificate of the certified end of ``result`` (``lmic audit`` verifies it).

    The file is the ordinary certificate of :func:`lmic.certify.write_certificate` for the
    theorem at ``param = result.certified`` (recorded in ``params``), at the point of
    ``result.end``. Raises :class:`LmicError` when there is no certified end.

    Examples
    --------
    >>> from lmic.studies.sweep import maximize
    >>> r = maximize("uio_dt.thm4_1", "examples/uio_dt.thm4_1.flexible_joint.yaml", "gamma",
    ...              lo=50.0, hi=51.5, rtol=1e-2)                     # doctest: +SKIP
    >>> write_end_certificate(r, "end.json")["params"]["gamma"] == r.lower  # doctest: +SKIP
    True
    """
    from lmic.certify import write_certificate

    end = result.end
    if end is None or end.problem is None or end.solution is None or end.certificate is None:
        raise LmicError(f"no certified point of '{result.param}': no certificate written")
    return write_certificate(path, end.problem, end.solution, end.certificate, system=result.system)
