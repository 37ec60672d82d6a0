"""The pipeline in one call: compile -> lower + solve -> certify -> :class:`Result`.

``target`` is a theorem id (with a system file), an IR (``.json``) or SDPA (``.dat-s``) file, or
an IR :class:`~lmic.ir.problem.Problem`. The result carries the status, the objective, the
variables, the derived quantities, the certificate and the timings, and maps to the exit codes
of DESIGN section 7 (:meth:`Result.exit_code`).

Every solve goes through the one solve policy (:func:`lmic.policy.decide`): no backend (or
``"auto"``) is the escalating route (strategies, then the next backend, then exact rescue), a
named backend is that backend alone. The verdict and exit code follow :mod:`lmic.outcome`.

Examples
--------
>>> import scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
>>> p = Problem([Variable("p", "scalar", (1, 1))], [LMI("p > 0", 1, sp.csc_matrix([[0., 1.]]))],
...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
>>> result = solve(p)
>>> result.status, result.verdict, result.exit_code()
('feasible', 'certified', 0)
"""

from __future__ import annotations

import math
import os
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeGuard, cast

import numpy as np

from lmic._version import __version__
from lmic.backends.base import Backend, SolveOptions
from lmic.errors import BackendError, LmicError
from lmic.ir.problem import Problem
from lmic.jsonable import to_jsonable
from lmic.reductions.pipeline import solve as solve_with_reductions
from lmic.solution import Solution

if TYPE_CHECKING:
    from lmic.template.theorem import Theorem

__all__ = ["Result", "solve", "load_target", "solve_problem", "certify_solution", "EXIT_CODES"]

#: exit codes (kept for callers of the old names; the table is :data:`lmic.outcome.EXIT_CODES`)
EXIT_CODES = {"certified": 0, "failed": 1, "usage": 2, "infeasible": 3, "infeasible-bounded": 4, "unbounded": 5}

_FILE_SUFFIXES = (".json", ".dat-s")


@dataclass
class Result:
    """Everything one pipeline run produced.

    Attributes
    ----------
    target : str
        What was solved (theorem id, file path or ``"<problem>"``).
    theorem : str or None
    backend : str
        The backend that produced the answer (for ``auto``: the one finally used).
    status : str
        The backend's status (:data:`lmic.solution.STATUSES`).
    objective : float or None
    variables, derived : dict
        Values at the returned point (derived quantities from the IR's expression trees).
    certificate : object or None
        :class:`lmic.certify.Certificate` (``None`` if the certifier is not installed).
    timings : dict
        ``compile_s`` (compile or file load), ``lower_s`` (lmic's reduction, lowering and result
        mapping), ``solve_s`` (inside the solver), ``certify_s``; ``enclosure_s`` (optimisation
        problems), ``backoff_s`` (the backed-off solve) and ``ray_search_s`` (the search for an
        improving ray after a solver said ``unbounded``, when it proved nothing) when they ran.
    attempts : list of dict
        For ``auto``: every backend tried, its status and verdict.
    enclosure : dict or None
        Optimisation problems: the certified enclosure of the optimal value
        (:func:`lmic.certify.enclosure.enclosure`).
    backoff : dict or None
        The backed-off, well-scaled point near the optimum (:func:`lmic.backoff.backoff`).
    route : dict or None
        The route taken (:mod:`lmic.routes`): ``steps`` (backend, verdict, relative gap) and
        ``text``, the line the CLI prints.
    """

    target: str
    theorem: str | None
    backend: str
    status: str
    objective: float | None
    variables: dict[str, Any]
    derived: dict[str, Any]
    certificate: Any
    timings: dict[str, float]
    problem: Problem
    solution: Solution
    params: dict[str, Any] = field(default_factory=dict)
    attempts: list[dict[str, Any]] = field(default_factory=list)
    outcome: Any = None
    enclosure: dict[str, Any] | None = None
    backoff: dict[str, Any] | None = None
    route: dict[str, Any] | None = None

    @property
    def verdict(self) -> str:
        """The outcome's verdict (:data:`lmic.outcome.VERDICTS`: ``certified``, ``rejected``,
        ``undecided``, ``infeasible-certified``, ``infeasible-bounded``, ``unbounded-certified``)."""
        if self.outcome is not None:
            return str(self.outcome.verdict)
        from lmic.outcome import verdict_of

        return verdict_of(self.problem, self.solution, self.certificate)

    @property
    def min_margin(self) -> float | None:
        """Smallest ``min_margin`` over the LMIs in the certificate (``None`` if unknown)."""
        lmis = getattr(self.certificate, "lmis", None) or []
        margins = [m.get("min_margin") for m in lmis if m.get("min_margin") is not None]
        return float(min(margins)) if margins else None

    @property
    def gains(self) -> dict[str, Any]:
        """Derived quantities (back-substituted gains, scalars) as numpy arrays / floats."""
        return {k: _as_numeric(v) for k, v in (self.derived or {}).items() if not isinstance(v, str)}

    @property
    def values(self) -> dict[str, Any]:
        """Decision variables at the returned point, as numpy arrays / floats."""
        return {k: _as_numeric(v) for k, v in (self.variables or {}).items()}

    def __repr__(self) -> str:
        objective = "" if self.objective is None else f", objective={self.objective:.6g}"
        return (
            f"Result({self.target!r}, backend={self.backend!r}, status={self.status!r}{objective}, "
            f"verdict={self.verdict!r}, gains={sorted(self.gains)})"
        )

    def _repr_html_(self) -> str:
        from lmic.formatting import result_html

        return result_html(self)

    def _repr_latex_(self) -> str:
        from lmic.formatting import result_latex

        return result_latex(self)

    def exit_code(self) -> int:
        """:func:`lmic.outcome.exit_code` of the verdict (0 certified, 1 rejected / undecided,
        3 infeasible-certified, 4 infeasible-bounded, 5 unbounded-certified)."""
        from lmic.outcome import exit_code

        return exit_code(self.verdict)

    def certificate_dict(self) -> dict[str, Any]:
        """The certificate as JSON-ready dict (``verdict``, ``lmis``, ``checks``, ``exact`` ...)."""
        if self.certificate is None:
            return {"verdict": "unverified", "lmis": [], "checks": [], "exact": None}
        d = dict(self.certificate.to_dict())
        d.setdefault("verdict", self.verdict)
        d.setdefault("lmis", [])
        d.setdefault("checks", [])
        d.setdefault("exact", None)
        return d

    def to_dict(self) -> dict[str, Any]:
        """The ``lmic solve --json`` object (DESIGN section 7)."""
        sol = self.solution
        return {
            "lmic": __version__,
            "target": self.target,
            "theorem": self.theorem,
            # every parameter and option the compilation used (defaults and file values included)
            "params": {**(self.problem.meta or {}).get("params", {}), **self.params},
            "backend": self.backend,
            "status": self.status,
            "native_status": sol.native_status,
            "message": sol.message,
            "objective": self.objective,
            "variables": self.variables,
            "derived": self.derived,
            "strict": {"strategy": sol.strategy, "margin": sol.margin},
            "certificate": self.certificate_dict(),
            "timings": self.timings,
            "verdict": self.verdict,
            "evidence": self.outcome.evidence.to_dict() if self.outcome is not None else None,
            "attempts": self.attempts,
            "route": self.route,  # lmic.routes: the backends tried, their method and verdict
            # -- optimal-value enclosure (lmic.certify.enclosure) --
            "enclosure": _enclosure_summary(self.enclosure),
            # -- unboundedness (lmic.route_unbounded): the exact improving ray --
            "unbounded": getattr(self.outcome, "unbounded", None),
            "backoff": to_jsonable(self.backoff),
            "exit_code": self.exit_code(),
        }


def load_target(
    target: str | os.PathLike[str] | Problem | Theorem,
    system: Any = None,
    params: dict[str, Any] | None = None,
) -> tuple[Problem, str | None, float]:
    """The IR for ``target`` (compiled or loaded), the theorem id, and the time it took.

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("p", "scalar", (1, 1))], [LMI("p > 0", 1, sp.csc_matrix([[0., 1.]]))],
    ...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
    >>> load_target(p)[1] is None
    True
    """
    t0 = time.perf_counter()
    if isinstance(target, Problem):
        if system is not None or params:
            raise LmicError("a system and parameters apply to a theorem, not to an IR problem")
        return target, target.meta.get("theorem"), time.perf_counter() - t0
    if _is_theorem(target):  # an inline theorem (notebook): no registration needed
        if system is None:
            raise LmicError(f"theorem {target.id}: give a system (file, dict or StateSpace) to solve it")
        from lmic.compile import compile_theorem

        return compile_theorem(target, system, params), target.id, time.perf_counter() - t0
    text = os.fspath(cast("str | os.PathLike[str]", target))  # not a Problem, not a Theorem
    if text.endswith(_FILE_SUFFIXES) or (Path(text).is_file() and system is None):
        if system is not None:
            shown = getattr(system, "label", None) or (system if isinstance(system, str | os.PathLike) else "a system")
            raise LmicError(f"{text}: an IR or SDPA file takes no system file (got '{shown}')")
        if params:
            raise LmicError(f"{text}: -p parameters apply to a theorem, not to an IR or SDPA file")
        if not Path(text).is_file():
            raise LmicError(f"{text}: no such file")
        from lmic.ir.io import load_problem

        problem = load_problem(text)
        return problem, problem.meta.get("theorem"), time.perf_counter() - t0
    if system is None:
        raise LmicError(
            f"'{text}' is neither an IR/SDPA file (.json, .dat-s) nor usable as a theorem "
            "without a system file: give THEOREM SYSTEM"
        )
    swapped = isinstance(system, str) and not Path(system).exists() and Path(text).is_file()
    if swapped and text.lower().endswith((".yaml", ".yml")):
        raise LmicError(f"{system}: no such file; the arguments are THEOREM SYSTEM (lmic solve {system} {text}?)")
    from lmic.compile import compile_theorem

    problem = compile_theorem(text, system, params)
    return problem, text, time.perf_counter() - t0


def _is_theorem(obj: Any) -> TypeGuard[Theorem]:
    """Whether ``obj`` is a :class:`~lmic.template.theorem.Theorem`, without importing the
    template layer (sympy) when it was never loaded (then ``obj`` cannot be one)."""
    module = sys.modules.get("lmic.template.theorem")
    return module is not None and isinstance(obj, module.Theorem)


def _backend(spec: str | Backend) -> Backend:
    if isinstance(spec, Backend):
        return spec
    from lmic.backends.registry import get_backend

    return get_backend(spec)


def solve_problem(problem: Problem, backend: str | Backend, options: SolveOptions | None = None) -> Solution:
    """Solve with one backend after checking it can take the problem.

    Raises :class:`BackendError` with the ``supports(..., explain=True)`` reason otherwise.

    >>> from lmic.testing.conformance import CASES
    >>> solve_problem(CASES["max_sense"].build(), "clarabel").status
    'optimal'
    """
    be = _backend(backend)
    ok, why = be.supports(problem, explain=True)  # type: ignore[misc]
    if not ok:
        raise BackendError(f"backend '{be.label}' cannot take this problem: {why}")
    return solve_with_reductions(be, problem, options)


def certify_solution(problem: Problem, solution: Solution, exact: bool = False) -> Any:
    """The certifier's :class:`~lmic.certify.Certificate`, or ``None`` if it is not installed."""
    try:
        from lmic.certify import certify
    except ImportError:
        return None
    return certify(problem, solution, exact=exact)


def _values(problem: Problem, x: np.ndarray | None, certificate: Any) -> tuple[dict, dict]:
    if x is None:
        return {}, {}
    variables = problem.unpack(x)
    derived: dict[str, Any] = {}
    from_cert = getattr(certificate, "derived", None) or []
    if from_cert:
        for item in from_cert:
            derived[item["name"]] = item.get("value")
    elif problem.derived:
        try:
            env = problem.environment(x)
            derived = {d.name: env[d.name] for d in problem.derived}
        except Exception as err:  # noqa: BLE001 - a gain that cannot be computed is reported
            derived = {"error": f"{type(err).__name__}: {err}"}
    return variables, derived


def _as_numeric(value: Any) -> Any:
    if isinstance(value, list):
        return np.atleast_2d(np.asarray(value, dtype=float))
    if isinstance(value, int | float):
        return float(value)
    return value


def solve(
    target: str | os.PathLike[str] | Problem | Theorem,
    system: Any = None,
    params: dict[str, Any] | None = None,
    backend: str | Backend | None = None,
    options: SolveOptions | None = None,
    exact: bool = False,
    backoff: float | None = None,
) -> Result:
    """Compile (or load), solve, certify.

    Parameters
    ----------
    target : str, path, Theorem or Problem
        A theorem id or a :class:`~lmic.template.Theorem` object (an inline theorem, registered
        or not; then ``system`` is required), an ``.json`` IR or ``.dat-s`` SDPA file, or a
        Problem.
    system : path, dict or System, optional
    params : dict, optional
        Parameter overrides (theorems only).
    backend : str, Backend or None
        A backend name (``"clarabel"``, ``"cvxpy:SCS"`` ...) or instance: that backend alone.
        ``None`` or ``"auto"`` (the default): the escalating policy of :mod:`lmic.policy`
        (Clarabel -> CVXOPT -> SDPA -> SCS, skipping what cannot take the problem).
    options : SolveOptions, optional
    exact : bool
        Ask the certifier for an exact rational proof too.
    backoff : float or None
        Optimisation problems: relative backoff of the objective for a second, well-scaled
        solve (:mod:`lmic.backoff`); ``None`` is :data:`lmic.backoff.DEFAULT_BACKOFF` when the
        problem derives quantities (gains) and off otherwise, ``0`` is off.

    Returns
    -------
    Result

    Examples
    --------
    >>> from lmic.testing.conformance import CASES
    >>> r = solve(CASES["linear_equalities"].build(), backend="cvxopt")
    >>> r.status, round(r.objective, 6)
    ('optimal', 0.585786)
    """
    if backoff is not None and not (isinstance(backoff, int | float) and 0 <= backoff < math.inf):
        raise LmicError(f"backoff must be a non-negative number, got {backoff}")
    if system is not None and not isinstance(target, Problem):
        from lmic.plant import as_system

        system = as_system(target, system)
    problem, theorem, compile_s = load_target(target, system, params)
    if isinstance(target, Problem):
        name = "<problem>"
    elif isinstance(target, str | os.PathLike):
        name = os.fspath(target)
    else:  # a Theorem object: its id
        name = theorem or target.id
    from lmic.reductions.memo import remembered_solves

    with remembered_solves():  # the route, its enclosure and the backoff never solve one problem twice
        return _decided(problem, theorem, compile_s, str(name), backend, options, exact, backoff, params)


def _decided(
    problem: Problem,
    theorem: str | None,
    compile_s: float,
    name: str,
    backend: str | Backend | None,
    options: SolveOptions | None,
    exact: bool,
    backoff: float | None,
    params: dict[str, Any] | None,
) -> Result:
    """:func:`solve` once the problem is compiled: the route, the enclosure, the backoff, the result."""
    from lmic.routes import decide_route

    t0 = time.perf_counter()
    routed = decide_route(problem, backend, options, exact=exact)  # the default route (lmic.routes)
    outcome = routed.outcome
    total = time.perf_counter() - t0 - routed.enclosure_s - outcome.ray_search_s
    sol, cert = outcome.solution, outcome.certificate
    used = outcome.backend or str(getattr(backend, "label", backend))
    attempts = [a.to_dict() for a in outcome.attempts]
    certify_s = sum(a.certify_s for a in outcome.attempts)
    solve_s = sum(a.solve_s for a in outcome.attempts)
    variables, derived = _values(problem, sol.x, cert)
    # -- optimal-value enclosure (lmic.certify.enclosure) --
    enc: dict[str, Any] | None
    if routed.enclosure is not None:  # computed by the route (its --gap test)
        enc, enclosure_s = routed.enclosure, routed.enclosure_s
    elif outcome.verdict == "unbounded-certified":  # no optimum: nothing to enclose or back off
        enc, enclosure_s = None, 0.0
    else:
        enc, enclosure_s = _enclosure(problem, sol, cert, exact, used, options)
    tight_x = enc.pop("tight_x", None) if enc is not None else None
    enc, cut_s = _cut(problem, enc, used, options, exact, solve_s, routed.route)
    enclosure_s += cut_s
    back = _backoff(problem, enc, backoff, used, options, sol.objective)
    if enc is not None:
        # no rigorous primal end at the solver's point, or one that misses GAP_TARGET: a better
        # one from the backed-off point, a point polished toward the solver's, a restored point
        t_rest = time.perf_counter()
        from lmic.route_primal import better_primal, decided_by_enclosure, nearer_point

        # the route's last resort (lmic.routes._boxed_upper) restored from the same point: not twice
        tried = any("upper_boxed" in st for st in (routed.route or {}).get("steps", []))
        enc = better_primal(problem, enc, back, sol, tight_x, used, options, restore_tried=tried)
        upgraded = decided_by_enclosure(problem, outcome, enc, options, back)
        if upgraded is not None:  # the enclosure's proven point passes the certifier
            outcome, sol, cert = upgraded, upgraded.solution, upgraded.certificate
            variables, derived = _values(problem, sol.x, cert)
        nearer = nearer_point(problem, outcome, enc, exact)  # the answer's point as near the primal end as certified
        if nearer is not None:
            outcome, sol, cert = nearer, nearer.solution, nearer.certificate
            variables, derived = _values(problem, sol.x, cert)
        enclosure_s += time.perf_counter() - t_rest
        outcome.reason = _quoting(outcome.reason, enc)
    timings = {
        "compile_s": compile_s,
        "lower_s": max(0.0, total - solve_s - certify_s),
        "solve_s": solve_s,
        "certify_s": certify_s,
        "enclosure_s": enclosure_s,
    }
    if outcome.ray_search_s:
        timings["ray_search_s"] = outcome.ray_search_s
    if back is not None:
        timings["backoff_s"] = back["time_s"]
    return Result(
        target=name,
        theorem=theorem,
        backend=used,
        status=sol.status,
        objective=sol.objective,
        variables=to_jsonable(variables),
        derived=to_jsonable(derived),
        certificate=cert,
        timings=timings,
        problem=problem,
        solution=sol,
        params=dict(params or {}),
        attempts=attempts,
        outcome=outcome,
        enclosure=enc,
        backoff=back,
        route=routed.route,
    )


# -- optimal-value enclosure (lmic.certify.enclosure) -----------------------------------------


def _quoting(reason: str, enc: dict[str, Any]) -> str:
    """``reason`` with its quoted enclosure replaced by ``enc``'s: the route quotes the enclosure
    of the step that proved the optimum, and a later step may narrow it (a restored point's
    re-search), so the answer shows one enclosure, the final one.

    >>> final = {"reason": "minimum in [1, 2]", "rel_gap": 0.5}
    >>> _quoting("holds; the enclosure proves the optimum: minimum in [1, 3]", final)
    'holds; the enclosure proves the optimum: minimum in [1, 2]'
    >>> _quoting("holds", final)
    'holds'
    """
    from lmic.route_primal import PROVES

    if PROVES not in reason or enc.get("rel_gap") is None or not enc.get("reason"):
        return reason
    return reason.rsplit(PROVES, 1)[0] + PROVES + str(enc["reason"])


def _enclosure(
    problem: Problem, sol: Solution, cert: Any, exact: bool, backend: str, options: SolveOptions | None
) -> tuple[dict[str, Any] | None, float]:
    """The enclosure of an optimisation problem's optimal value (``None`` for feasibility):
    :func:`lmic.routes.enclosure_of`."""
    from lmic.routes import enclosure_of

    return enclosure_of(problem, sol, cert, exact, backend, options)


def _cut(
    problem: Problem,
    enc: dict[str, Any] | None,
    backend: Any,
    options: SolveOptions | None,
    exact: bool,
    solve_s: float,
    route: dict[str, Any] | None = None,
) -> tuple[dict[str, Any] | None, float]:
    """An enclosure with a primal end and no dual end: the objective-cut search
    (:mod:`lmic.route_cut`) on the answer's backend; the route's text says what it proved."""
    from lmic.route_cut import cut_budget, cut_route, wants_cut

    if not wants_cut(problem, enc):
        return enc, 0.0
    assert enc is not None
    t0 = time.perf_counter()
    enc = cut_route(problem, enc, backend, options or SolveOptions(), exact, cut_budget(solve_s))
    if route is not None and route.get("text"):
        if enc["cut"].get("skipped"):
            tail = "objective cuts not tried (dual equality system singular in floats)"
        else:
            ends = f"relative gap {enc['rel_gap']:.2g}" if enc.get("rel_gap") is not None else "no dual end proved"
            tail = f"objective cuts ({enc['cut']['steps']} feasibility problems) -> {ends}"
        route["text"] = f"{route['text']} => {tail}"
    return enc, time.perf_counter() - t0


def _backoff(
    problem: Problem,
    enc: dict[str, Any] | None,
    rel: float | None,
    backend: str,
    options: SolveOptions | None,
    claimed: float | None = None,
) -> dict[str, Any] | None:
    """The backed-off point (``None`` when off or without a reference objective).

    The reference is the certified primal end, else the solver's claimed objective (the
    backed-off point is certified on its own either way).
    """
    from lmic.backoff import DEFAULT_BACKOFF, backoff

    if rel is None:
        rel = DEFAULT_BACKOFF if problem.derived else 0.0
    if not rel or enc is None:
        return None
    value = enc["upper"] if problem.objective.sense == "min" else enc["lower"]
    if value is None:
        value = claimed
    if value is None or not np.isfinite(value):
        return None
    given = enc.get("restored_x") if enc.get("cut") else None  # the objective-cut search's point
    return backoff(problem, float(value), backend, options, rel=float(rel), fallback=given)


def _enclosure_summary(enc: dict[str, Any] | None) -> dict[str, Any] | None:
    if enc is None:  # a feasibility problem: the enclosure module is not even imported
        return None
    from lmic.certify.enclosure import summary

    return to_jsonable(summary(enc))
