"""The conformance suite every backend runs: small IR problems with known answers.

Each :class:`Case` builds an IR :class:`~lmic.ir.problem.Problem`, states the status a correct
backend returns and checks the answer *independently of the solver* (eigenvalues of the LMIs at
the returned point, the objective against a value computed another way, Farkas certificates and
KKT stationarity of the duals when the backend returns them). Tolerances depend on the method:
interior-point backends to ``1e-5`` relative, first-order ones (SCS) to ``1e-3``.

A backend that cannot pass a case is excluded only with a written reason in :data:`EXCLUSIONS`
(``(backend label, case name) -> reason``), MathOptInterface style; a case the backend does not
``support`` is skipped, not failed.

Cases: ``lyapunov_stable`` (strict, scale-free feasibility), ``lyapunov_unstable`` (strict,
infeasible), ``bounded_real`` (minimise gamma in the bounded-real lemma, against the H-infinity
norm computed by bisection on the Hamiltonian's imaginary-axis eigenvalues), ``strict_affine``
(strict feasibility with constants and a strict linear row), ``infeasible`` (closed LMIs with
no solution; the Farkas ray is verified), ``unbounded``, ``linear_equalities`` (``min <C, X>``
s.t. ``tr X = 1``, ``X >= 0``: ``lambda_min(C)``, duals verified), ``max_sense`` (``max t`` s.t.
``C - t I >= 0``).

Examples
--------
>>> from lmic.backends.registry import get_backend
>>> result = run_case(get_backend("clarabel"), CASES["linear_equalities"])
>>> result.passed, result.status
(True, 'optimal')
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp

from lmic.backends.base import Backend, SolveOptions
from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
from lmic.ir.svec import tril_vec
from lmic.reductions.pipeline import solve as solve_with_reductions
from lmic.solution import Solution

__all__ = [
    "Case",
    "CaseResult",
    "CASES",
    "EXCLUSIONS",
    "run_case",
    "run_suite",
    "hinf_norm",
    "dense_lmi",
    "lyapunov_problem",
    "bounded_real_problem",
    "farkas_residuals",
    "stationarity_residual",
]


# -- building blocks -------------------------------------------------------------------------


def dense_lmi(name: str, F0: np.ndarray, Fs: list[np.ndarray], strict: bool, relation: str = ">") -> LMI:
    """An IR LMI ``F0 + sum_k x_k Fs[k] (>= or >) 0`` from dense symmetric matrices.

    >>> L = dense_lmi("x > 0", np.zeros((1, 1)), [np.eye(1)], strict=True)
    >>> L.matrix([2.0])
    array([[2.]])
    """
    cols = [tril_vec(np.asarray(F0, dtype=float))] + [tril_vec(np.asarray(F, dtype=float)) for F in Fs]
    return LMI(name, F0.shape[0], sp.csc_matrix(np.column_stack(cols)), strict=strict, relation=relation)


def _basis_mats(var: Variable) -> list[np.ndarray]:
    B = var.basis().toarray()
    r, c = var.shape
    return [B[:, k].reshape(r, c, order="F") for k in range(var.size)]


def lyapunov_problem(A: np.ndarray) -> Problem:
    """Feasibility of ``A^T P + P A < 0, P > 0`` (both strict, scale-free).

    >>> lyapunov_problem(-np.eye(2)).n
    3
    """
    A = np.asarray(A, dtype=float)
    n = A.shape[0]
    P = Variable("P", "symmetric", (n, n))
    Ps = _basis_mats(P)
    lyap = dense_lmi("A'P + PA < 0", np.zeros((n, n)), [-(A.T @ Pk + Pk @ A) for Pk in Ps], True, "<")
    pos = dense_lmi("P > 0", np.zeros((n, n)), Ps, True, ">")
    return Problem(
        [P],
        [lyap, pos],
        LinearConstraints.empty(P.size),
        Objective("feasibility", np.zeros(1 + P.size)),
    )


def bounded_real_problem(A: np.ndarray, B: np.ndarray, C: np.ndarray) -> Problem:
    """``min gamma`` s.t. ``[[A'P+PA, PB, C'], [B'P, -gI, 0], [C, 0, -gI]] < 0`` and ``P > 0``.

    The optimum is the H-infinity norm of ``C (sI - A)^-1 B`` (bounded-real lemma).

    >>> bounded_real_problem(-np.eye(1), np.eye(1), np.eye(1)).n
    2
    """
    A, B, C = (np.atleast_2d(np.asarray(M, dtype=float)) for M in (A, B, C))
    n, m, p = A.shape[0], B.shape[1], C.shape[0]
    P = Variable("P", "symmetric", (n, n))
    g = Variable("gamma", "scalar", (1, 1), offset=P.size)
    N = n + m + p
    Fs = []
    for Pk in _basis_mats(P):
        M = np.zeros((N, N))
        M[:n, :n] = A.T @ Pk + Pk @ A
        M[:n, n : n + m] = Pk @ B
        M[n : n + m, :n] = B.T @ Pk
        Fs.append(-M)
    G = np.zeros((N, N))
    G[n:, n:] = -np.eye(m + p)
    Fs.append(-G)
    F0 = np.zeros((N, N))
    F0[:n, n + m :] = C.T
    F0[n + m :, :n] = C
    brl = dense_lmi("bounded real lemma < 0", -F0, Fs, True, "<")
    pos = dense_lmi("P > 0", np.zeros((n, n)), _basis_mats(P) + [np.zeros((n, n))], True, ">")
    c = np.zeros(1 + P.size + 1)
    c[-1] = 1.0
    return Problem([P, g], [brl, pos], LinearConstraints.empty(P.size + 1), Objective("min", c))


def hinf_norm(A: np.ndarray, B: np.ndarray, C: np.ndarray, rtol: float = 1e-10) -> float:
    """H-infinity norm of the stable, strictly proper ``C (sI - A)^-1 B``, by bisection.

    ``||G||_inf < gamma`` iff ``H(gamma) = [[A, B B'/gamma^2], [-C'C, -A']]`` has no eigenvalue
    on the imaginary axis (Boyd, Balakrishnan & Kabamba 1989).

    >>> round(hinf_norm(-np.eye(1), np.eye(1), np.eye(1)), 8)
    1.0
    """
    A, B, C = (np.atleast_2d(np.asarray(M, dtype=float)) for M in (A, B, C))
    n = A.shape[0]

    def gain(w: float) -> float:
        return float(la.svdvals(C @ la.solve(1j * w * np.eye(n) - A, B))[0])

    freqs = np.concatenate([[0.0], np.logspace(-3, 3, 200)])
    lo = max(gain(w) for w in freqs)
    hi = 2.0 * lo + 1.0

    def has_imag(gamma: float) -> bool:
        H = np.block([[A, B @ B.T / gamma**2], [-C.T @ C, -A.T]])
        ev = la.eigvals(H)
        return bool(np.any(np.abs(ev.real) < 1e-9 * max(1.0, float(np.max(np.abs(ev))))))

    while has_imag(hi):
        hi *= 2.0
    while hi - lo > rtol * hi:
        mid = 0.5 * (lo + hi)
        if has_imag(mid):
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def farkas_residuals(problem: Problem, farkas: dict) -> tuple[float, float, float]:
    """``(max_k |sum_i <F_i^(k), Z_i> + a_k . y|, sum_i <F0_i, Z_i> + a0 . y, min eig / sign)``.

    The third value is the most negative of ``lambda_min(Z_i)`` and of ``y`` on ``>=`` rows
    (should be ``>= 0``).

    >>> p = lyapunov_problem(-np.eye(1))
    >>> farkas_residuals(p, {"lmis": [np.eye(1), np.eye(1)], "linear": np.zeros(0)})[1]
    0.0
    """
    total = np.zeros(1 + problem.n)
    worst_sign = np.inf
    for lmi, Z in zip(problem.lmis, farkas["lmis"], strict=True):
        Z = np.asarray(Z, dtype=float)
        w = tril_vec(2 * Z - np.diag(np.diag(Z)))  # <F, Z> = w . tril(F)
        total += lmi.coeffs.T @ w
        worst_sign = min(worst_sign, float(np.linalg.eigvalsh(0.5 * (Z + Z.T))[0]))
    y = np.asarray(farkas.get("linear", np.zeros(0)), dtype=float)
    if len(y):
        total += problem.linear.A.T @ y
        ge = np.asarray(problem.linear.kinds) == "ge"
        if ge.any():
            worst_sign = min(worst_sign, float(np.min(y[ge])))
    return float(np.max(np.abs(total[1:]))) if problem.n else 0.0, float(total[0]), worst_sign


def stationarity_residual(problem: Problem, duals: dict) -> float:
    """``max_k |c_k - sum_i <F_i^(k), Z_i> - a_k . y|`` (``c`` of the minimisation form).

    >>> p = lyapunov_problem(-np.eye(1))
    >>> stationarity_residual(p, {"lmis": [np.zeros((1, 1)), np.zeros((1, 1))], "linear": []})
    0.0
    """
    grad, _, _ = 0.0, 0.0, 0.0
    sign = -1.0 if problem.objective.sense == "max" else 1.0
    c = np.zeros(problem.n) if problem.objective.sense == "feasibility" else sign * problem.objective.c[1:]
    total = np.zeros(1 + problem.n)
    for lmi, Z in zip(problem.lmis, duals["lmis"], strict=True):
        Z = np.asarray(Z, dtype=float)
        total += lmi.coeffs.T @ tril_vec(2 * Z - np.diag(np.diag(Z)))
    y = np.asarray(duals.get("linear", []), dtype=float)
    if len(y):
        total += problem.linear.A.T @ y
    grad = float(np.max(np.abs(c - total[1:]))) if problem.n else 0.0
    return grad


def _strict_margins(problem: Problem, x: np.ndarray) -> list[float]:
    out = [float(np.linalg.eigvalsh(lmi.matrix(x))[0]) for lmi in problem.lmis]
    res = problem.linear.residuals(x)
    for k, kind in enumerate(problem.linear.kinds):
        out.append(float(res[k]) if kind == "ge" else -abs(float(res[k])))
    return out


# -- cases -----------------------------------------------------------------------------------


@dataclass
class Case:
    """A conformance case: a problem, the expected status and an independent check."""

    name: str
    build: Callable[[], Problem]
    expect: str
    check: Callable[[Problem, Solution, float], str]
    doc: str = ""


@dataclass
class CaseResult:
    """The outcome of one case on one backend (``message`` says what failed)."""

    case: str
    backend: str
    passed: bool
    status: str
    message: str
    seconds: float
    excluded: str = ""
    skipped: str = ""


def _check_feasible_point(problem: Problem, sol: Solution, tol: float) -> str:
    if sol.x is None:
        return "no point returned"
    margins = _strict_margins(problem, sol.x)
    scale = max(1.0, float(np.max(np.abs(sol.x))))
    bad = [(lmi.name, m) for lmi, m in zip(problem.lmis, margins, strict=False) if m <= 0 and lmi.strict]
    bad += [(lmi.name, m) for lmi, m in zip(problem.lmis, margins, strict=False) if m < -tol * scale]
    if bad:
        return f"constraint '{bad[0][0]}' violated: min eigenvalue {bad[0][1]:.3g}"
    if sol.margin is None or sol.margin <= 0:
        return f"margin {sol.margin} recorded, expected > 0"
    return ""


def _check_infeasible(problem: Problem, sol: Solution, tol: float) -> str:
    if sol.farkas is None:
        return ""  # a certificate is welcome, not required
    grad, value, sign = farkas_residuals(problem, sol.farkas)
    scale = max(1.0, max(float(np.abs(np.asarray(Z)).max()) for Z in sol.farkas["lmis"]))
    if sol.farkas.get("strict"):
        if value > tol * scale or grad > tol * scale * 10 or sign < -tol * scale:
            return f"strict Farkas ray fails: grad {grad:.2g}, value {value:.2g}, sign {sign:.2g}"
        return ""
    if not (value < 0 and grad <= tol * 10 * abs(value) * scale and sign >= -tol * 10 * abs(value) * scale):
        return f"Farkas certificate fails: grad {grad:.2g}, value {value:.2g}, sign {sign:.2g}"
    return ""


def _lyap_stable() -> Problem:
    A = np.array([[-1.0, 2.0, 0.0], [-3.0, -4.0, 1.0], [0.5, 0.0, -2.0]])
    return lyapunov_problem(A)


def _lyap_unstable() -> Problem:
    A = np.array([[0.5, 1.0, 0.0], [0.0, -1.0, 1.0], [0.0, 0.0, -2.0]])
    return lyapunov_problem(A)


_BRL = (
    np.array([[-1.0, 1.0, 0.0], [-1.0, -0.5, 0.2], [0.0, 0.3, -2.0]]),
    np.array([[1.0], [0.5], [0.0]]),
    np.array([[1.0, 0.0, 1.0]]),
)


def _check_brl(problem: Problem, sol: Solution, tol: float) -> str:
    ref = hinf_norm(*_BRL)
    if sol.x is None or sol.objective is None:
        return "no point returned"
    gamma = float(sol.x[-1])
    if abs(gamma - ref) > max(tol, 1e-6) * 10 * ref:
        return f"gamma = {gamma:.8g}, H-infinity norm = {ref:.8g}"
    if abs(sol.objective - gamma) > 1e-6 * max(1.0, ref):
        return f"objective {sol.objective} differs from gamma {gamma}"
    margins = _strict_margins(problem, sol.x)
    if min(margins) < -tol * 10:
        return f"LMI violated at the optimum: min eigenvalue {min(margins):.3g}"
    return ""


def _strict_affine() -> Problem:
    x = Variable("x", "scalar", (1, 1), offset=0)
    y = Variable("y", "scalar", (1, 1), offset=1)
    F0 = np.array([[0.0, 1.0], [1.0, 0.0]])
    lmi = dense_lmi("[[x, 1], [1, y]] > 0", F0, [np.diag([1.0, 0.0]), np.diag([0.0, 1.0])], True)
    rows = LinearConstraints(sp.csr_matrix([[3.0, -1.0, -1.0]]), ["ge"], [True], ["x + y < 3"])
    return Problem([x, y], [lmi], rows, Objective("feasibility", np.zeros(3)))


def _infeasible() -> Problem:
    x = Variable("x", "scalar", (1, 1))
    lmi = dense_lmi("diag(x - 1, -1 - x) >= 0", np.diag([-1.0, -1.0]), [np.diag([1.0, -1.0])], False)
    return Problem([x], [lmi], LinearConstraints.empty(1), Objective("min", np.array([0.0, 1.0])))


def _unbounded() -> Problem:
    x = Variable("x", "full", (2, 1))
    lmi = dense_lmi(
        "[[1 + x1, x2], [x2, 1]] >= 0",
        np.eye(2),
        [np.diag([1.0, 0.0]), np.array([[0.0, 1.0], [1.0, 0.0]])],
        False,
    )
    return Problem([x], [lmi], LinearConstraints.empty(2), Objective("max", np.array([0.0, 1.0, 0.0])))


_C = np.array([[2.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 2.0]])


def _linear_equalities() -> Problem:
    X = Variable("X", "symmetric", (3, 3))
    Xs = _basis_mats(X)
    lmi = dense_lmi("X >= 0", np.zeros((3, 3)), Xs, False)
    tr = np.array([np.trace(M) for M in Xs])
    rows = LinearConstraints(sp.csr_matrix(np.concatenate([[-1.0], tr]).reshape(1, -1)), ["eq"], [False], ["tr X = 1"])
    c = np.concatenate([[0.0], [np.sum(_C * M) for M in Xs]])
    return Problem([X], [lmi], rows, Objective("min", c))


def _max_sense() -> Problem:
    t = Variable("t", "scalar", (1, 1))
    lmi = dense_lmi("C - t I >= 0", _C, [-np.eye(3)], False)
    return Problem([t], [lmi], LinearConstraints.empty(1), Objective("max", np.array([0.0, 1.0])))


def _check_value(expected: float, with_duals: bool = True) -> Callable[[Problem, Solution, float], str]:
    def check(problem: Problem, sol: Solution, tol: float) -> str:
        if sol.x is None or sol.objective is None:
            return "no point returned"
        if abs(sol.objective - expected) > tol * max(1.0, abs(expected)):
            return f"objective {sol.objective:.10g}, expected {expected:.10g}"
        obj = problem.objective.value(sol.x)
        if obj is not None and abs(obj - sol.objective) > 1e-6 * max(1.0, abs(expected)):
            return f"reported objective {sol.objective} but c . x = {obj}"
        margins = _strict_margins(problem, sol.x)
        if min(margins) < -tol * 10:
            return f"a constraint is violated: {min(margins):.3g}"
        if with_duals and sol.duals.get("lmis"):
            res = stationarity_residual(problem, sol.duals)
            if res > tol * 100:
                return f"duals fail stationarity c = A'(Z, y): residual {res:.3g}"
        return ""

    return check


def _expect_unbounded(problem: Problem, sol: Solution, tol: float) -> str:
    return ""


_LMIN = float(np.linalg.eigvalsh(_C)[0])

#: every conformance case by name
CASES: dict[str, Case] = {
    c.name: c
    for c in [
        Case(
            "lyapunov_stable",
            _lyap_stable,
            "feasible",
            _check_feasible_point,
            "A'P + PA < 0, P > 0",
        ),
        Case("lyapunov_unstable", _lyap_unstable, "infeasible", _check_infeasible, "unstable A"),
        Case(
            "bounded_real",
            lambda: bounded_real_problem(*_BRL),
            "optimal",
            _check_brl,
            "BRL vs H-inf",
        ),
        Case(
            "strict_affine",
            _strict_affine,
            "feasible",
            _check_feasible_point,
            "constants + strict row",
        ),
        Case("infeasible", _infeasible, "infeasible", _check_infeasible, "x >= 1 and x <= -1"),
        Case("unbounded", _unbounded, "unbounded", _expect_unbounded, "max x1, 1 + x1 >= x2^2"),
        Case(
            "linear_equalities",
            _linear_equalities,
            "optimal",
            _check_value(_LMIN),
            "min <C,X>, tr X = 1",
        ),
        Case("max_sense", _max_sense, "optimal", _check_value(_LMIN), "max t, C - t I >= 0"),
    ]
}

#: (backend label, case name) -> the reason the backend is excused from the case
EXCLUSIONS: dict[tuple[str, str], str] = {}


def _tolerance(backend: Backend) -> float:
    return 1e-5 if getattr(backend, "interior_point", True) else 1e-3


def run_case(backend: Backend, case: Case, options: SolveOptions | None = None) -> CaseResult:
    """Run one case on one backend and check the answer independently.

    >>> from lmic.backends.registry import get_backend
    >>> run_case(get_backend("clarabel"), CASES["max_sense"]).passed
    True
    """
    label = backend.label
    reason = EXCLUSIONS.get((label, case.name)) or EXCLUSIONS.get((backend.name, case.name))
    if reason:
        return CaseResult(case.name, label, True, "", "", 0.0, excluded=reason)
    problem = case.build()
    ok, why = backend.supports(problem, explain=True)  # type: ignore[misc]
    if not ok:
        return CaseResult(case.name, label, True, "", "", 0.0, skipped=why)
    t0 = time.perf_counter()
    sol = solve_with_reductions(backend, problem, options)
    seconds = time.perf_counter() - t0
    if sol.status != case.expect:
        msg = f"status '{sol.status}' (native '{sol.native_status}'), expected '{case.expect}'"
        if sol.message:
            msg += f": {sol.message}"
        return CaseResult(case.name, label, False, sol.status, msg, seconds)
    message = case.check(problem, sol, _tolerance(backend))
    return CaseResult(case.name, label, not message, sol.status, message, seconds)


def run_suite(backend: Backend, options: SolveOptions | None = None) -> list[CaseResult]:
    """Every case on one backend.

    >>> from lmic.backends.registry import get_backend
    >>> all(r.passed for r in run_suite(get_backend("clarabel")))
    True
    """
    return [run_case(backend, case, options) for case in CASES.values()]
