"""Random instances of every optimisation theorem, and their optimum computed independently.

Shared by ``tests/plugins/test_optimisation_enclosures.py`` and
``benchmarks/theorem_enclosures.py`` (which puts this folder on ``sys.path``).

* :func:`instance` ``(tid, seed, n)``: a random plant of state dimension ``n`` with the shapes
  and structural assumptions the theorem needs (stable ``A`` scaled into the region where the
  LMIs are feasible, the examples' parameters), as a system dict for :func:`lmic.api.solve`;
* :func:`reference` ``(tid, system)``: the optimal value of the theorem's LMI problem written
  directly in CVXPY from the catalogues (``thesis_catalogue.md``, ``seeds_catalogue.md``), not
  through lmic: the **closed** problem (every strict inequality made non-strict: the infimum of
  the strict problem when it is strictly feasible), solved by Clarabel at tolerances 1e-10.
  Returns ``(status, value, tol)``: ``tol`` is the reference's own accuracy (:data:`REF_TOL`
  relative), to be allowed when checking that an enclosure contains the value.

The block matrices come from the existing independent formulations of the per-family tests
(``_delay_reference``, ``test_uncertain_dt``, ``test_uio_dt``, ``test_uir``'s catalogue
formulas), with the strict margin set to 0.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from typing import Any

import cvxpy as cp
import numpy as np

_HERE = Path(__file__).resolve().parent
if str(_HERE) not in sys.path:  # the benchmark imports this module by path
    sys.path.insert(0, str(_HERE))


def _load(name: str) -> Any:
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, _HERE / f"{name}.py")
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    sys.modules[name] = mod
    spec.loader.exec_module(mod)
    return mod


#: every optimisation theorem of the plugins (tutorial.bounded_real has its own tests)
THEOREMS = (
    "delay_a.thm3_1",
    "delay_a.thm3_2",
    "delay_b.thm3_1",
    "delay_b.thm4_1",
    "sampled_euler.thm2",
    "sampled_euler.thm3",
    "sampled_euler.thm4",
    "uio_dt.thm4_1",
    "uir.thm4_1",
    "uir.thm5_1",
    "uncertain_dt.cor1",
    "uncertain_dt.lemma3",
    "uncertain_dt.thm1",
)

#: state dimensions of the survey (small: unit tests; large: benchmark)
SIZES = {"small": 2, "large": 4}

#: Clarabel's settings for the reference solves
#: the accuracy (relative to max(1, |value|)) allowed to a reference value: Clarabel at the
#: tolerances below meets its optimality conditions to ~1e-10, the degenerate problems here to
#: ~1e-8 in value
REF_TOL = 1e-7
REF_SETTINGS = {"tol_gap_abs": 1e-10, "tol_gap_rel": 1e-10, "tol_feas": 1e-10, "tol_ktratio": 1e-8, "max_iter": 400}


def _stable(rng: np.random.Generator, n: int, radius: float) -> np.ndarray:
    A = rng.standard_normal((n, n))
    return A * (radius / max(abs(np.linalg.eigvals(A))))


def _lists(data: dict[str, Any]) -> dict[str, Any]:
    return {k: np.asarray(v, dtype=float).tolist() for k, v in data.items()}


#: theorems whose LMIs are infeasible for every instance (catalogue 1.4): no optimum to enclose
ALWAYS_INFEASIBLE = ("sampled_euler.thm4",)


def instance(tid: str, seed: int, n: int, tries: int = 30) -> dict[str, Any]:
    """A random system file (as a dict) for theorem ``tid``, state dimension ``n``: the first
    draw of the seed's stream whose closed problem :func:`reference` solves to optimality (a
    draw whose LMIs happen to be infeasible is skipped; not for :data:`ALWAYS_INFEASIBLE`).

    >>> sorted(instance("uncertain_dt.lemma3", 0, 2)["data"])
    ['A', 'B', 'H', 'M1', 'N']
    """
    for k in range(tries):
        system = draw(tid, seed, n, k)
        if tid in ALWAYS_INFEASIBLE or reference(tid, system)[0] == "optimal":
            return system
    raise RuntimeError(f"{tid}: no feasible draw in {tries} tries (seed {seed}, n {n})")


def draw(tid: str, seed: int, n: int, k: int = 0) -> dict[str, Any]:
    """Draw ``k`` of the random plants of :func:`instance`."""
    rng = np.random.default_rng([seed, n, THEOREMS.index(tid), k])
    family, item = tid.split(".")
    if family in ("delay_a", "delay_b"):
        data = {
            "A": _stable(rng, n, 0.3),
            "Ad": 0.1 * rng.standard_normal((n, n)),
            "B": rng.standard_normal((n, 1)),
            "C": 0.4 * rng.standard_normal((1, n)),
            "D": 0.5 * rng.standard_normal((1, 1)),
            "M1": 0.1 * rng.standard_normal((n, 1)),
            "M2": 0.1 * rng.standard_normal((n, 1)),
            "M3": 0.1 * rng.standard_normal((1, 1)),
            "N": 0.1 * rng.standard_normal((1, n)),
            "H": 0.2 * np.eye(n),
        }
        if family == "delay_b":
            data["Cd"] = 0.2 * rng.standard_normal((1, n))
            data["M4"] = 0.1 * rng.standard_normal((1, 1))
        psi1 = ("printed", "corrected")[seed % 2]  # both variants of Psi1 (catalogue 2.1)
        if item in ("thm3_2", "thm4_1"):
            lam = round(float(0.2 + 0.7 * rng.random()), 3)
            params = {"tau1": 1, "tau2": 2, "eps2": 0.5, "eps3": 0.5, "lambda": lam, "psi1": psi1}
        else:
            params = {"tau1": 0, "tau2": 1, "eps2": 0.3, "eps3": 0.3, "eta": 3.0, "psi1": psi1}
        return {"lmic": 1, "data": _lists(data), "params": params}
    if family == "sampled_euler":
        p = 1 if n <= 2 else 2
        A = _stable(rng, n, 1.5)
        C = rng.standard_normal((p, n))
        R = rng.standard_normal((n, n))
        Q = 0.1 * (R @ R.T + np.eye(n))
        T = 0.1
        if item == "thm3":
            Q = Q * (T / np.linalg.eigvalsh(Q)[0])
            return {"lmic": 1, "data": _lists({"A": A, "C": C, "Q": Q}), "params": {"T": T}}
        Ad = np.eye(n) + T * A
        data = {"Ad": Ad, "Cd": C, "Q": Q}
        if item == "thm4":
            data.update(Bd=rng.standard_normal((n, 1)), H=0.25 * np.eye(n))
            return {"lmic": 1, "data": _lists(data), "params": {"gamma_d": 0.05}}
        return {"lmic": 1, "data": _lists(data), "params": {}}
    if family == "uncertain_dt":
        p = 1 if n <= 2 else 2
        data = {
            "A": _stable(rng, n, 0.4),
            "B": rng.standard_normal((n, 1)),
            "C": rng.standard_normal((p, n)),
            "D": 0.2 * rng.standard_normal((p, 1)),
            "H": 0.25 * np.eye(n),
            "M1": 0.1 * rng.standard_normal((n, 1)),
            "M2": 0.1 * rng.standard_normal((p, 1)),
            "N": 0.2 * rng.standard_normal((1, n)),
            "Cw": 1 + rng.random((n, n)),
        }
        if item == "lemma3":
            keep = ("A", "B", "H", "M1", "N")
            return {"lmic": 1, "data": _lists({k: data[k] for k in keep}), "params": {"mu": 3.0}}
        if item == "thm1":
            data.pop("Cw")
            psi1 = ("printed", "corrected")[seed % 2]
            return {"lmic": 1, "data": _lists(data), "params": {"mu": 3.0, "beta": 0.05, "psi1": psi1}}
        return {"lmic": 1, "data": _lists(data), "params": {"mu": 3.0, "beta": 0.05}}
    if family == "uio_dt":
        # p = 2 outputs, h = 1 unknown input, q = 2 nonlinearity channels (q > p - h: M D = 0
        # cannot be reached, so the optimum rho is positive)
        data = {
            "A": _stable(rng, n + 1, 0.5),
            "B": rng.standard_normal((n + 1, 1)),
            "C": rng.standard_normal((2, n + 1)),
            "D": rng.standard_normal((n + 1, 2)),
            "D1": rng.standard_normal((n + 1, 1)),
        }
        return {"lmic": 1, "data": _lists(data), "params": {}}
    if family == "uir":
        p, q1 = 2, max(2, n - 1)  # rank [R; Cbar] = n + h needs q1 + p >= n + 1
        Ah = rng.standard_normal((n, n))
        Ah = Ah - (max(np.linalg.eigvals(Ah).real) + 1.0) * np.eye(n)
        data = {
            "A": Ah,
            "B": rng.standard_normal((n, 1)),
            "C": rng.standard_normal((p, n)),
            "F": rng.standard_normal((n, 1)),
            "G": rng.standard_normal((p, 1)),
            "D1": rng.standard_normal((n, 1)),
            "D2": rng.standard_normal((p, 1)),
            "R": rng.standard_normal((q1, n + 1)),
        }
        params = {"gamma0": 0.1, "mu": 5.0} if item == "thm4_1" else {"gamma0": 0.1, "lambda": 0.5}
        return {"lmic": 1, "data": _lists(data), "params": params}
    raise KeyError(tid)


# -- independent references ------------------------------------------------------------------------


def _solve(objective: Any, cons: list) -> tuple[str, float | None, float]:
    prob = cp.Problem(cp.Minimize(objective), cons)
    try:
        prob.solve(solver="CLARABEL", **REF_SETTINGS)
    except cp.error.SolverError:
        return "error", None, float("inf")
    if prob.status not in ("optimal", "optimal_inaccurate") or prob.value is None:
        return prob.status, None, float("inf")
    value = float(prob.value)
    return prob.status, value, REF_TOL * max(1.0, abs(value))


def _sym(M: Any) -> Any:
    return (M + M.T) / 2


def reference(tid: str, system: dict[str, Any]) -> tuple[str, float | None, float]:
    """The closed problem's optimal value in CVXPY: ``(status, value, tol)`` (module docstring)."""
    data = {k: np.atleast_2d(np.asarray(v, dtype=float)) for k, v in system["data"].items()}
    params = dict(system.get("params") or {})
    family, item = tid.split(".")
    if family in ("delay_a", "delay_b"):
        ref = _load("_delay_reference")
        return ref.closed_reference(data, params, pareto=item in ("thm3_2", "thm4_1"), settings=REF_SETTINGS)
    if family == "sampled_euler":
        return _sampled(item, data, params)
    if family == "uncertain_dt":
        return _uncertain(item, data, params)
    if family == "uio_dt":
        return _uio(data)
    if family == "uir":
        return _uir(item, data, params)
    raise KeyError(tid)


def _sampled(item: str, d: dict[str, np.ndarray], params: dict[str, Any]) -> tuple[str, float | None, float]:
    """Catalogue 1.2-1.4: min xi (Theorems 2, 3), min zeta (Theorem 4, LMIs (71)-(73))."""
    if item == "thm3":
        T = float(params["T"])
        Ad, Cd, Q = np.eye(d["A"].shape[0]) + T * d["A"], d["C"], d["Q"]
    else:
        Ad, Cd, Q = d["Ad"], d["Cd"], d["Q"]
    n, p = Ad.shape[0], Cd.shape[0]
    P, G, eps = cp.Variable((n, n), symmetric=True), cp.Variable((n, p)), cp.Variable()
    lmin, lmax = np.linalg.eigvalsh(Q)[0], np.linalg.eigvalsh(Q)[-1]
    I = np.eye(n)
    lmi6 = cp.bmat([[P - Q - eps * I, Ad.T @ P - Cd.T @ G.T], [P @ Ad - G @ Cd, P]])
    cons = [P >> 0, _sym(lmi6) >> 0, eps >= 0]
    if item in ("thm2", "thm3"):
        xi = cp.Variable()
        psi2 = (lmin * xi - lmax) / 3
        cons += [_sym(cp.bmat([[psi2 * I, P], [P, psi2 * I]])) >> 0, xi >= 1]
        status, value, tol = _solve(xi, cons)
        if item == "thm3" and value is not None:  # the plugin's objective is xi as well
            return status, value, tol
        return status, value, tol
    # Theorem 4: (71) = (6), (72) [Psi1 I, P; P, Psi1 I] > 0, (73) with coupling c/2 Bd
    gd = float(params["gamma_d"])
    Bd, H = d["Bd"], d["H"]
    s = (-lmax + np.sqrt(lmax**2 + lmin**2 / gd**2)) / (gd + 2)
    zeta = cp.Variable()
    lam2 = H.T @ H - Q + gd * (3 * s + lmax) * I
    c = 2 * (gd + 1) * s + lmax
    m73 = cp.bmat([[lam2, c / 2 * Bd], [c / 2 * Bd.T, Bd.T @ P @ Bd - zeta * np.eye(Bd.shape[1])]])
    cons += [_sym(cp.bmat([[s * I, P], [P, s * I]])) >> 0, _sym(m73) << 0, zeta >= 0]
    return _solve(zeta, cons)


def _uncertain(item: str, d: dict[str, np.ndarray], params: dict[str, Any]) -> tuple[str, float | None, float]:
    """Catalogue 2.1-2.3 (Lemma 3, Theorem 1, Corollary 1), block matrices of test_uncertain_dt."""
    tu = _load("test_uncertain_dt")
    n = d["A"].shape[0]
    mu = float(params["mu"])
    alpha, e1, e2 = cp.Variable(), cp.Variable(), cp.Variable()
    if item == "lemma3":
        P = cp.Variable((n, n), symmetric=True)
        l15, l16 = tu.lemma3_lmis(d, P, alpha, e1, e2, mu, cp.bmat)
        cons = [P >> 0, _sym(l15) << 0, _sym(l16) << 0, alpha >= 0, e1 >= 0, e2 >= 0]
        return _solve(alpha + e1, cons)
    p = d["C"].shape[0]
    P1, P2 = cp.Variable((n, n), symmetric=True), cp.Variable((n, n), symmetric=True)
    G = cp.Variable((n, p))
    beta = float(params["beta"])
    if item == "cor1":
        Acal = cp.Variable((n, n))
        big, xi1 = tu.thm1_lmis(d, P1, P2, G, alpha, e1, e2, mu, beta, cp.bmat, Acal=Acal)
        cons = [P1 >> 0, P2 >> 0, _sym(big) << 0, _sym(xi1) << 0, e1 >= 0, e2 >= 0, Acal >= 0]
        return _solve(e1 - cp.sum(cp.multiply(d["Cw"], Acal)), cons)
    big, xi1 = tu.thm1_lmis(d, P1, P2, G, alpha, e1, e2, mu, beta, cp.bmat, params.get("psi1", "printed"))
    cons = [P1 >> 0, P2 >> 0, _sym(big) << 0, _sym(xi1) << 0, alpha >= 0, e1 >= 0, e2 >= 0]
    return _solve(alpha + e1, cons)


#: the fixed margin and the relative resolution of the uio_dt.thm4_1 bisection (catalogue 4.3 and
#: 11.3: bisection on feasibility at margin 1e-7 gives gamma_max 51.50, published 51.5 +- 0.1)
UIO_MARGIN = 1e-7
UIO_RTOL = 2e-3


def _uio(d: dict[str, np.ndarray]) -> tuple[str, float | None, float]:
    """Paper C Theorem 4.1, LMI (25)-(26), catalogue 4.3 (d13, d23 of test_uio_dt).

    ``min rho`` has no attained minimum (P grows without bound near it) and a direct solve stops
    early, far above it (Clarabel at rho ~ 7e-3 on the example, against 1/51.5^2 = 3.77e-4). The
    reference is the catalogue's method instead: bisection on ``rho = 1 / gamma^2`` of the
    feasibility problem of Theorem 3.2, ``M(gamma) <= -margin I`` (Clarabel), a point counting
    as feasible only when numpy's eigenvalues of ``M`` at it are all negative; the tolerance is
    the bisection's resolution (relative :data:`UIO_RTOL`) plus the direct solve's own."""
    A, C, D, D1 = d["A"], d["C"], d["D"], d["D1"]
    n, p, q = A.shape[0], C.shape[0], D.shape[1]
    dh = _load("delshad_helpers")
    CD1 = C @ D1
    U, V = -D1 @ dh.pinv(CD1), dh.exact_projector(CD1)
    P = cp.Variable((n, n), symmetric=True)
    Yb, Kb, rho = cp.Variable((n, p)), cp.Variable((n, p)), cp.Variable()
    d13 = A.T @ P + (U @ C @ A).T @ P + (V @ C @ A).T @ Yb.T - C.T @ Kb.T
    d23 = D.T @ P + (U @ C @ D).T @ P + (V @ C @ D).T @ Yb.T
    M = _sym(dh.uio_thm4_1_block(P, d13, d23, rho, n, q))
    status, early, _ = _solve(rho, [M << 0, rho >= 0])
    if early is None:
        return status, None, float("inf")
    # feasibility at gamma = 1 / sqrt(rho) in Theorem 3.2's form (its LMI (20), of which (25) is
    # the Schur complement): the catalogue's bisection, which reproduces Table 2's 51.5
    g2 = cp.Parameter(nonneg=True)
    Z = np.zeros
    M32 = _sym(cp.bmat([[-P + g2 * np.eye(n), Z((n, q)), d13], [Z((q, n)), -np.eye(q), d23], [d13.T, d23.T, -P]]))
    feas = cp.Problem(cp.Minimize(0), [M32 << -UIO_MARGIN * np.eye(M32.shape[0])])

    def feasible(value: float) -> bool:  # value: rho
        g2.value = 1.0 / value
        try:
            feas.solve(solver="CLARABEL", **REF_SETTINGS)
        except cp.error.SolverError:
            return False
        if feas.status not in ("optimal", "optimal_inaccurate") or P.value is None:
            return False
        return bool(np.max(np.linalg.eigvalsh(M32.value)) < 0)

    hi = max(early, 1e-12)
    if not feasible(hi):
        hi *= 1.0 + 1e-3
        if not feasible(hi):
            return "error", None, float("inf")
    lo = 0.0
    while hi - lo > UIO_RTOL * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if feasible(mid) else (mid, hi)
    return "optimal", 0.5 * (lo + hi), 0.5 * (hi - lo) + REF_TOL * max(1.0, hi)


def _uir(item: str, d: dict[str, np.ndarray], params: dict[str, Any]) -> tuple[str, float | None, float]:
    """Paper E Theorems 4.1 (mu given) and 5.1 (lambda given), catalogue 6.2-6.3."""
    dh = _load("delshad_helpers")
    A, C, F, G, R, D1, D2 = (d[k] for k in ("A", "C", "F", "G", "R", "D1", "D2"))
    n, h, p, q1, nw = A.shape[0], F.shape[1], C.shape[0], R.shape[0], D1.shape[1]
    nh = n + h
    eta = np.hstack([np.eye(n), np.zeros((n, h))])
    Abar, Cbar = np.hstack([A, F]), np.hstack([C, G])
    M = (R @ dh.pinv(np.vstack([eta, Cbar])))[:, :n]
    T = np.vstack([M @ eta, Cbar])
    Tp, Pi = dh.pinv(T), dh.exact_projector(T)
    a1, a2, b1, b2 = Tp[:, :q1], Tp[:, q1:], Pi[:, :q1], Pi[:, q1:]
    P = cp.Variable((q1, q1), symmetric=True)
    Gam = cp.Variable((n, n), symmetric=True)
    Yb1, Y2 = cp.Variable((q1, q1 + p)), cp.Variable((nh, q1 + p))
    rho = cp.Variable()
    gamma0 = float(params["gamma0"])
    PN = P @ M @ Abar @ a1 + Yb1 @ b1
    a13 = P @ M @ Abar @ a2 @ D2 + Yb1 @ b2 @ D2 - P @ M @ D1
    a14 = a1.T + b1.T @ Y2.T
    a34 = D2.T @ a2.T + D2.T @ b2.T @ Y2.T
    cons = [rho >= 0]
    if item == "thm4_1":
        mu = float(params["mu"])
        a33, objective = -(mu**2) * np.eye(nw), rho
    else:
        lam = float(params["lambda"])
        mubar = cp.Variable()
        a33, objective = -mubar * np.eye(nw), lam * rho + (1 - lam) * mubar
        cons.append(mubar >= 0)
    big = dh.uir_big_block(PN, P, M, Gam, a13, a14, a33, a34, rho, n, nw, nh)
    cons += [P >> 0, _sym(Gam - np.eye(n)) << 0, _sym(big) << 0, 1 - (1 + gamma0**2) * rho >= 0]
    return _solve(objective, cons)


def contains(enclosure: dict[str, Any] | None, value: float, tol: float) -> bool | None:
    """Whether ``[lower, upper]`` (a missing end is unbounded) contains ``value`` within ``tol``;
    ``None`` when the enclosure has neither end."""
    if not enclosure or (enclosure.get("lower") is None and enclosure.get("upper") is None):
        return None
    lo, hi = enclosure.get("lower"), enclosure.get("upper")
    return (lo is None or lo - tol <= value) and (hi is None or value <= hi + tol)
