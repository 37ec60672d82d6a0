"""Helpers of the delay_a / delay_b tests (loaded by path, not a test module).

* :func:`restrict` fixes some decision variables of a compiled IR at given values (a published
  point, through :func:`lmic.published.fix_variables`) and returns the IR in the remaining
  ones, so a published ``P1, P2, Upsilon`` can be audited with the theorem's own LMIs
  (``min alpha + eps1``, ``min rho``);
* :func:`reference` is an independent CVXPY implementation of Paper A/B Theorems 3.1, 3.2 / 4.1,
  written block by block from ``thesis_catalogue.md`` sections 2-3 (not from the plugin).
"""

from __future__ import annotations

import cvxpy as cp
import numpy as np

from lmic.ir.problem import LinearConstraints, Objective, Problem
from lmic.published import fix_variables

MARGIN = 1e-7  # the catalogue's strict margin


def restrict(problem: Problem, values: dict, objective: dict | None = None, lmis=None) -> Problem:
    """``problem`` with the variables in ``values`` fixed; ``objective`` maps names to weights.

    The substitution is lmic's own :func:`lmic.published.fix_variables`; on top of it, LMIs left
    without a free variable must hold at the fixed point (checked) and are dropped, and so are
    linear rows without a free variable; ``lmis`` (names) keeps only those LMIs.
    """
    fixed, _, _ = fix_variables(problem, values)
    kept = []
    for lmi in fixed.lmis:
        if lmis is not None and lmi.name not in lmis:
            continue
        if lmi.coeffs[:, 1:].nnz == 0:
            eig = np.linalg.eigvalsh(lmi.matrix(np.zeros(fixed.n)))
            assert eig[0] > 0, f"fixed point violates '{lmi.name}' (lambda_min {eig[0]:g})"
            continue
        kept.append(lmi)
    rows = fixed.linear.A.tocsr()
    live = [i for i in range(rows.shape[0]) if rows[i, 1:].nnz]
    linear = LinearConstraints(
        rows[live],
        [fixed.linear.kinds[i] for i in live],
        [fixed.linear.strict[i] for i in live],
        [fixed.linear.names[i] for i in live],
    )
    c = np.zeros(1 + fixed.n)
    for name, weight in (objective or {}).items():
        c[1 + fixed.variable(name).offset] = weight
    return Problem(
        fixed.variables,
        kept,
        linear,
        Objective("min" if objective else "feasibility", c),
        fixed.data,
        fixed.derived,
        fixed.checks,
        fixed.meta,
    )


def tau0_of(params: dict) -> int:
    """``tau0`` as the plugin documents it: given, or ``tau2 - tau1 + 1``."""
    if params.get("tau0"):
        return int(params["tau0"])
    return int(params.get("tau2", 0)) - int(params.get("tau1", 0)) + 1


def reference(
    data: dict, params: dict, *, pareto: bool, solver: str = "CLARABEL", margin: float = MARGIN, settings=None
):
    """Paper A/B Theorem 3.1 (``pareto=False``, eta given) or 3.2 / 4.1 (``pareto=True``).

    Block sizes of the big LMI: Psi1 rows ``e, x, alpha-e`` (``corrected``: ``+ alpha-x``), then
    Psi2 columns ``n, n, n, n, r, n, n, r`` (catalogue 2.1). Returns a dict with ``status``,
    ``value`` and, when solved, ``gamma_star``, ``eta_star``, ``L``. ``margin``: the strict
    margin (0: the closed problem); ``settings``: the solver's options.
    """
    g = {k: np.atleast_2d(np.asarray(v, dtype=float)) for k, v in data.items()}
    A, Ad, B, C, D = g["A"], g["Ad"], g["B"], g["C"], g["D"]
    M1, M2, M3, N, H = g["M1"], g["M2"], g["M3"], g["N"], g["H"]
    n, p, nw, r = A.shape[0], C.shape[0], B.shape[1], M1.shape[1]
    Cd = g.get("Cd", np.zeros((p, n)))
    M4 = g.get("M4", np.zeros((p, r)))
    t0 = tau0_of(params)
    corrected = params.get("psi1", "printed") == "corrected"
    P1 = cp.Variable((n, n), symmetric=True)
    P2 = cp.Variable((n, n), symmetric=True)
    Ups = cp.Variable((n, p))
    e1, a = cp.Variable(), cp.Variable()
    e2, e3 = float(params["eps2"]), float(params["eps3"])
    In = np.eye(n)

    sizes = [n, n, n] + ([n] if corrected else []) + [n, n, n, n, r, n, n, r]
    k1 = 4 if corrected else 3
    upper = {
        (0, 0): -P1 + H.T @ H,
        (0, 2): In,
        (1, 1): (e2 + t0 * e3) * N.T @ N - P2,
        (2, 2): -a * In,
        # Omega
        (0, k1 + 0): A.T @ P1 - C.T @ Ups.T,
        (1, k1 + 1): A.T @ P2,
        (1, k1 + 5): Ad.T @ P1 - Cd.T @ Ups.T,
        (1, k1 + 6): Ad.T @ P2,
        # Psi2
        (k1 + 0, k1 + 0): -P1 / 3,
        (k1 + 0, k1 + 2): P1 / 3,
        (k1 + 0, k1 + 4): P1 @ M1 - Ups @ M3,
        (k1 + 1, k1 + 1): -P2 / 3,
        (k1 + 1, k1 + 3): P2 / 3,
        (k1 + 1, k1 + 4): P2 @ M1,
        (k1 + 2, k1 + 2): 5 / 3 * P1 - e1 * In,
        (k1 + 3, k1 + 3): 5 / 3 * P2 - e1 * In,
        (k1 + 4, k1 + 4): -e2 * np.eye(r),
        (k1 + 5, k1 + 5): -P1 / (3 * t0),
        (k1 + 5, k1 + 7): P1 @ M2 - Ups @ M4,
        (k1 + 6, k1 + 6): -P2 / (3 * t0),
        (k1 + 6, k1 + 7): P2 @ M2,
        (k1 + 7, k1 + 7): -e3 * t0 * np.eye(r),
    }
    if corrected:
        upper[(1, 3)] = In
        upper[(3, 3)] = -a * In
    big = _assemble(upper, sizes)
    rho = cp.Variable() if pareto else float(params["eta"]) ** 2
    BP1 = B.T @ P1 - D.T @ Ups.T
    psi3 = _assemble(
        {
            (0, 0): -rho * np.eye(nw),
            (0, 1): BP1,
            (0, 2): B.T @ P2,
            (0, 3): BP1,
            (0, 4): B.T @ P2,
            (1, 1): -P1 / 3,
            (2, 2): -P2 / 3,
            (3, 3): -In,
            (4, 4): -In,
        },
        [nw, n, n, n, n],
    )
    cons = [
        P1 >> margin * In,
        P2 >> margin * In,
        big << -margin * np.eye(sum(sizes)),
        psi3 << -margin * np.eye(nw + 4 * n),
        e1 >= margin,
        a >= margin,
    ]
    if pareto:
        lam = float(params["lambda"])
        cons.append(rho >= margin)
        objective = lam * (a + e1) + (1 - lam) * rho
    else:
        objective = a + e1
    prob = cp.Problem(cp.Minimize(objective), cons)
    prob.solve(solver=solver, **(settings or {}))
    out = {"status": prob.status, "value": prob.value, "problem": prob}
    if prob.status == "optimal":
        out["gamma_star"] = 1 / np.sqrt(a.value * (1 + e1.value))
        out["eta_star"] = np.sqrt(rho.value) if pareto else np.sqrt(rho)
        out["L"] = np.linalg.solve(P1.value, Ups.value)
    return out


def closed_reference(data: dict, params: dict, *, pareto: bool, settings: dict):
    """The closed problem's optimum (margin 0): ``(status, value, tol)``, ``tol`` its accuracy
    (1e-7 relative, :data:`optimisation_instances.REF_TOL`)."""
    try:
        out = reference(data, params, pareto=pareto, margin=0.0, settings=settings)
    except cp.error.SolverError:
        return "error", None, float("inf")
    if out["status"] not in ("optimal", "optimal_inaccurate") or out["value"] is None:
        return out["status"], None, float("inf")
    value = float(out["value"])
    return out["status"], value, 1e-7 * max(1.0, abs(value))


def _assemble(upper: dict, sizes: list[int]):
    """Symmetric block matrix from its upper blocks (missing blocks are zero)."""
    k = len(sizes)
    rows = []
    for i in range(k):
        row = []
        for j in range(k):
            if (i, j) in upper:
                row.append(upper[(i, j)])
            elif (j, i) in upper:
                row.append(upper[(j, i)].T)
            else:
                row.append(np.zeros((sizes[i], sizes[j])))
        rows.append(row)
    M = cp.bmat(rows)
    return 0.5 * (M + M.T)
