"""CVXOPT ``solvers.sdp``: the LMI form solved natively.

``cvxopt.solvers.sdp`` minimises ``c'x`` subject to ``Gl x + sl = hl`` (``sl >= 0``),
``Gs[k] x + ss[k] = hs[k]`` (``ss[k]`` PSD) and ``A x = b``: exactly the IR's LMI form, with
``hs[k] = F0`` and the columns of ``Gs[k]`` equal to ``-vec(F_j)`` as dense column-major
``d*d`` vectors (:func:`lmic.backends.base.full_vec_coo`, the one conversion place). Inequality
rows go to ``Gl``/``hl``, equalities to ``A x = b`` (``A = a``, ``b = -a0``; their multipliers
change sign to reach the IR's convention). CVXOPT has no time limit of its own: with
``SolveOptions.time_limit`` the solve runs in a child process.

Examples
--------
>>> CVXOPTBackend.name
'cvxopt'
"""

from __future__ import annotations

import time
from typing import Any, ClassVar

import numpy as np
import scipy.sparse as sp

from lmic.backends.base import Backend, SolveOptions, full_vec_coo
from lmic.ir.problem import Problem
from lmic.solution import Solution

__all__ = ["CVXOPTBackend", "to_cvxopt_sparse"]


def to_cvxopt_sparse(M: sp.spmatrix):
    """A ``cvxopt.spmatrix`` from a scipy sparse matrix (vectorised, no Python loop).

    >>> import scipy.sparse as sp
    >>> to_cvxopt_sparse(sp.eye(2)).size
    (2, 2)
    """
    import cvxopt

    C = sp.coo_matrix(M)
    return cvxopt.spmatrix(
        cvxopt.matrix(C.data.astype(float)),
        cvxopt.matrix(C.row.astype(np.int64)) if C.nnz else [],
        cvxopt.matrix(C.col.astype(np.int64)) if C.nnz else [],
        C.shape,
    )


def _lower_sym(M) -> np.ndarray:
    """Symmetric matrix from CVXOPT's 'L'-stored PSD block (only the lower triangle is valid)."""
    M = np.array(M, dtype=float)
    L = np.tril(M)
    return L + np.tril(M, -1).T


# -- warm start (SolveOptions.warm_start) ------------------------------------------------------
#: how far the previous iterates are pushed into the interior of their cones, relative to
#: their size (CVXOPT requires strictly interior starting points)
_WARM_SHIFT = 1e-3


def _iterates(result: dict) -> dict[str, Any]:
    """The primal and dual iterates of a ``solvers.sdp`` result as numpy arrays (or ``{}``)."""
    keys = ("x", "sl", "y", "zl")
    try:
        out: dict[str, Any] = {k: np.array(result[k], dtype=float).ravel() for k in keys if result.get(k) is not None}
        out["ss"] = [np.array(S, dtype=float) for S in result.get("ss") or []]
        out["zs"] = [np.array(Z, dtype=float) for Z in result.get("zs") or []]
    except (TypeError, ValueError):
        return {}
    return out


def _interior(M: np.ndarray) -> np.ndarray:
    """A symmetric block moved strictly inside the PSD cone (relative shift :data:`_WARM_SHIFT`)."""
    S = _lower_sym(M)
    w = np.linalg.eigvalsh(S)
    scale = max(float(np.max(np.abs(w), initial=0.0)), 1.0)
    return S + (max(0.0, -float(w[0])) + _WARM_SHIFT * scale) * np.eye(len(S))


def _warm_start(options: SolveOptions, n: int, n_ge: int, n_eq: int, dims: list[int]) -> dict[str, Any]:
    """``primalstart`` / ``dualstart`` of ``solvers.sdp`` from ``options.warm_start`` (a previous
    CVXOPT solution of a problem with the same shape), moved strictly inside the cones; ``{}``
    (cold start) when there is none or the shapes differ.

    >>> _warm_start(SolveOptions(), 1, 0, 0, [2])
    {}
    """
    import cvxopt

    prev = getattr(options, "warm_start", None)
    it = None if prev is None else prev.info.get("cvxopt_iterates")
    if not isinstance(it, dict) or not it:
        return {}
    shapes_ok = (
        np.shape(it.get("x", ())) == (n,)
        and [np.shape(S) for S in it.get("ss", [])] == [(d, d) for d in dims]
        and [np.shape(Z) for Z in it.get("zs", [])] == [(d, d) for d in dims]
        and (n_ge == 0 or (np.shape(it.get("sl", ())) == (n_ge,) and np.shape(it.get("zl", ())) == (n_ge,)))
        and (n_eq == 0 or np.shape(it.get("y", ())) == (n_eq,))
    )
    if not shapes_ok:
        return {}
    with np.errstate(all="ignore"):
        ss, zs = [_interior(S) for S in it["ss"]], [_interior(Z) for Z in it["zs"]]
    if not all(np.all(np.isfinite(M)) for M in ss + zs) or not np.all(np.isfinite(it["x"])):
        return {}
    primal: dict[str, Any] = {"x": cvxopt.matrix(it["x"]), "ss": [cvxopt.matrix(S) for S in ss]}
    dual: dict[str, Any] = {"zs": [cvxopt.matrix(Z) for Z in zs]}
    if n_ge:
        lift = lambda v: np.maximum(v, 0.0) + _WARM_SHIFT * max(1.0, float(np.max(np.abs(v))))  # noqa: E731
        primal["sl"], dual["zl"] = cvxopt.matrix(lift(it["sl"])), cvxopt.matrix(lift(it["zl"]))
    if n_eq:
        dual["y"] = cvxopt.matrix(it["y"])
    return {"primalstart": primal, "dualstart": dual}


class CVXOPTBackend(Backend):
    """CVXOPT's primal-dual interior-point SDP solver (``solvers.sdp``), LMI form."""

    name: ClassVar[str] = "cvxopt"
    requires: ClassVar[dict[str, str]] = {"cvxopt": "cvxopt"}
    full_rank: ClassVar[bool] = True
    description: ClassVar[str] = "CVXOPT interior point, native solvers.sdp (LMI form)"
    STATUS_MAP: ClassVar[dict[str, str]] = {
        "optimal": "optimal",
        "primal infeasible": "infeasible",
        "dual infeasible": "unbounded",
        "unknown": "inaccurate",
    }

    def _options(self, options: SolveOptions) -> dict:
        opts = {
            "show_progress": bool(options.verbose),
            "abstol": options.tol,
            "reltol": options.tol,
            "feastol": options.tol,
        }
        if options.max_iter is not None:
            opts["maxiters"] = int(options.max_iter)
        opts.update(options.extra)
        return opts

    def _solve(self, problem: Problem, options: SolveOptions) -> Solution:
        import cvxopt
        from cvxopt import solvers

        n = problem.n
        lin = problem.linear
        kinds = np.asarray(lin.kinds, dtype=object)
        eq = np.flatnonzero(kinds == "eq") if len(lin) else np.zeros(0, dtype=int)
        ge = np.flatnonzero(kinds == "ge") if len(lin) else np.zeros(0, dtype=int)
        sign = -1.0 if problem.objective.sense == "max" else 1.0
        c = np.zeros(n) if problem.objective.sense == "feasibility" else sign * problem.objective.c[1:]
        Gs, hs = [], []
        for lmi in problem.lmis:
            row, col, val = full_vec_coo(lmi)
            const = col == 0
            h = np.zeros(lmi.dim * lmi.dim)
            h[row[const]] = val[const]
            hs.append(cvxopt.matrix(h.reshape(lmi.dim, lmi.dim, order="F")))
            var = ~const
            Gs.append(
                cvxopt.spmatrix(
                    cvxopt.matrix(-val[var]),
                    cvxopt.matrix(row[var].astype(np.int64)),
                    cvxopt.matrix(col[var].astype(np.int64) - 1),
                    (lmi.dim * lmi.dim, n),
                )
                if var.any()
                else cvxopt.spmatrix([], [], [], (lmi.dim * lmi.dim, n))
            )
        kwargs: dict = {}
        if len(ge):
            Age = lin.A[ge]
            kwargs["Gl"] = to_cvxopt_sparse(-Age[:, 1:])
            kwargs["hl"] = cvxopt.matrix(Age[:, 0].toarray().ravel())
        if len(eq):
            Aeq = lin.A[eq]
            kwargs["A"] = to_cvxopt_sparse(Aeq[:, 1:])
            kwargs["b"] = cvxopt.matrix(-Aeq[:, 0].toarray().ravel())
        if Gs:
            kwargs["Gs"], kwargs["hs"] = Gs, hs
        t0 = time.perf_counter()
        opts = self._options(options)
        # conelp's default KKT solver for SDP cones is 'qr'; 'chol' (CVXPY's choice) is 2.5x faster
        # on qib.thm1 (n = 20: 0.53 s against 1.33 s) and needs rank [G; A] = n, which the
        # elimination of dependent entries of x (Backend.full_rank) provides, but it is less
        # robust: it stops 'unknown' on SDPLIB control1-3 and qap5, where 'qr' solves. So 'chol'
        # first, 'qr' when 'chol' fails (unless extra={"kktsolver": ...} chooses one).
        chosen = opts.pop("kktsolver", None)
        kkt_order = [chosen] if chosen else ["chol", "qr"]
        c_mat = cvxopt.matrix(np.asarray(c, dtype=float))
        warm = _warm_start(options, n, len(ge), len(eq), [lmi.dim for lmi in problem.lmis])  # SolveOptions.warm_start
        for k, kktsolver in enumerate(kkt_order):
            last = k == len(kkt_order) - 1
            try:
                result = solvers.sdp(c_mat, kktsolver=kktsolver, options=dict(opts), **kwargs, **warm)
            except (ValueError, ArithmeticError):
                if warm:  # a starting point CVXOPT refuses: solve cold
                    warm = {}
                    result = solvers.sdp(c_mat, kktsolver=kktsolver, options=dict(opts), **kwargs)
                elif last:
                    raise
                else:
                    continue
            if str(result["status"]) != "unknown" or last:
                break
        solve_s = time.perf_counter() - t0
        native = str(result["status"])
        status = self.map_status(native)
        sol = Solution(
            status=status,
            backend=self.label,
            native_status=native,
            solve_s=solve_s,
            iterations=result.get("iterations"),
            info={"warm_started": bool(warm)},
        )
        # the native iterates, for the next solve of a problem of the same shape (warm start)
        sol.info["cvxopt_iterates"] = _iterates(result)

        def duals() -> dict:
            y = np.zeros(len(lin))
            if len(ge) and result.get("zl") is not None:
                y[ge] = np.array(result["zl"]).ravel()
            if len(eq) and result.get("y") is not None:
                y[eq] = -np.array(result["y"]).ravel()
            return {"lmis": [_lower_sym(Z) for Z in (result.get("zs") or [])], "linear": y}

        if status in ("optimal", "inaccurate") and result.get("x") is not None:
            sol.x = np.array(result["x"]).ravel()
            sol.objective = problem.objective.value(sol.x) if problem.objective.sense != "feasibility" else None
            if result.get("zs") is not None or result.get("zl") is not None:
                sol.duals = duals()
            if status == "inaccurate":
                sol.message = "CVXOPT stopped with status 'unknown' (iteration limit or numerical trouble)"
        elif status == "infeasible":
            sol.farkas = duals()
        elif status == "unbounded" and result.get("x") is not None:
            sol.info["ray"] = np.array(result["x"]).ravel()
        elif status == "inaccurate":
            sol.status = "error"
            sol.message = "CVXOPT stopped with status 'unknown' and no point"
        return sol
