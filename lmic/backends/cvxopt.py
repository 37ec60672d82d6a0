"""CVXOPT ``solvers.sdp``: the LMI form solved natively.

``cvxopt.solvers.sdp`` minimises ``c'x`` subject to ``Gl x + sl = hl`` (``sl >= 0``),
``Gs[k] x + ss[k] = hs[k]`` (``ss[k]`` PSD) and ``A x = b``: exactly the IR's LMI form, with
``hs[k] = F0`` and the columns of ``Gs[k]`` equal to ``-vec(F_j)`` as dense column-major
``d*d`` vectors (:class:`lmic.backends.lowering.LMIForm`, the one conversion place). Inequality
rows go to ``Gl``/``hl``, equalities to ``A x = b`` (``A = a``, ``b = -a0``; their multipliers
change sign to reach the IR's convention). CVXOPT has no time limit of its own: with
``SolveOptions.time_limit`` the solve runs in a child process.

KKT solvers, in turn: the structured one (:mod:`lmic.backends.cvxopt_kkt`) where it is cheaper,
else ``chol``; a run that stops ``unknown`` (or raises) is run again with CVXOPT's ``qr`` from
the start, except after a structured run whose last :data:`QR_TAIL_TRIED` iterations already
were ``qr`` (it hands over to ``qr`` near the optimum): on the near-unstable bounded-real lemma
(spectral abscissa -0.01, 20 to 50 states) both runs stall alike after 50 to 90 ``qr``
iterations, and the second one costs as much as the first (50 states: 83 s for the two); at 20
and 24 states (seeds 0-2) the second run rescued none of the 5 structured runs that stalled.

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

from lmic.backends.backend import KKT_ORDER, Backend, in_turn
from lmic.backends.lowering import LMIForm
from lmic.backends.results import NativeResult
from lmic.backends.threads import blas_threads
from lmic.ir.problem import Problem
from lmic.options import SolveOptions
from lmic.solution import Solution

__all__ = ["CVXOPTBackend", "to_cvxopt_sparse", "QR_TAIL_TRIED"]

#: a structured run that stopped 'unknown' after this many iterations of CVXOPT's 'qr' (its
#: hand-over near the optimum) is not run again with 'qr' from the start (module docstring)
QR_TAIL_TRIED = 10


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


def _warm_start(prev: Solution | None, n: int, n_ge: int, n_eq: int, dims: list[int]) -> dict[str, Any]:
    """``primalstart`` / ``dualstart`` of ``solvers.sdp`` from ``prev`` (``SolveOptions.warm_start``:
    a previous CVXOPT solution of a problem with the same shape), moved strictly inside the
    cones; ``{}`` (cold start) when there is none or the shapes differ.

    >>> _warm_start(None, 1, 0, 0, [2])
    {}
    """
    import cvxopt

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


def _structured_kkt(data: Any, problem: Problem) -> Any:
    """The structured KKT solver (:mod:`lmic.backends.cvxopt_kkt`) of ``data`` where it is
    cheaper than CVXOPT's 'chol' (:func:`~lmic.backends.cvxopt_kkt.worth_it`), else ``None``."""
    from lmic.backends.cvxopt_kkt import StructuredKKT, analyse, worth_it

    if not data.G or not worth_it(problem, data):
        return None
    blocks = analyse(problem, data)[2]
    return StructuredKKT([-g for g in data.G], -data.A_ge[:, 1:], data.A_eq[:, 1:], data.dims, blocks)


class CVXOPTBackend(Backend):
    """CVXOPT's primal-dual interior-point SDP solver (``solvers.sdp``), LMI form."""

    name: ClassVar[str] = "cvxopt"
    title: ClassVar[str] = "CVXOPT"
    requires: ClassVar[dict[str, str]] = {"cvxopt": "cvxopt"}
    full_rank: ClassVar[bool] = True
    description: ClassVar[str] = "CVXOPT interior point, native solvers.sdp (LMI form)"
    STATUS_MAP: ClassVar[dict[str, str]] = {
        "optimal": "optimal",
        "primal infeasible": "infeasible",
        "dual infeasible": "unbounded",
        # the iteration limit or numerical trouble, with the last iterate: the certifier decides
        "unknown": "inaccurate",
    }

    def settings(self, options: SolveOptions) -> dict[str, Any]:
        """``solvers.sdp`` options from the uniform ones (``extra`` verbatim, last)."""
        opts: dict[str, Any] = {
            "show_progress": bool(options.verbose),
            "abstol": options.tol,
            "reltol": options.tol,
            "feastol": options.tol,
        }
        if options.max_iter is not None:
            opts["maxiters"] = int(options.max_iter)
        opts.update(options.extra)
        if options.warm_start is not None:  # taken out again by call(): not a solvers.sdp option
            opts["_warm_start"] = options.warm_start
        return opts

    def call(self, problem: Problem, settings: dict[str, Any]) -> NativeResult:
        """Lower to the LMI form, run ``solvers.sdp`` (``chol``, then ``qr``), invert its multipliers."""
        import cvxopt
        from cvxopt import solvers

        data = LMIForm.apply(problem)
        kwargs: dict[str, Any] = {}
        if len(data.ge):
            kwargs["Gl"] = to_cvxopt_sparse(-data.A_ge[:, 1:])
            kwargs["hl"] = cvxopt.matrix(data.A_ge[:, 0].toarray().ravel())
        if len(data.eq):
            kwargs["A"] = to_cvxopt_sparse(data.A_eq[:, 1:])
            kwargs["b"] = cvxopt.matrix(-data.A_eq[:, 0].toarray().ravel())
        if data.G:
            kwargs["Gs"] = [to_cvxopt_sparse(-G) for G in data.G]
            kwargs["hs"] = [cvxopt.matrix(F0) for F0 in data.F0]
        # conelp's default KKT solver for SDP cones is 'qr'; 'chol' is 2.5x faster but stops
        # 'unknown' where 'qr' solves (KKT_ORDER): 'chol' first, 'qr' when 'chol' fails (unless
        # extra={"kktsolver": ...} chooses one)
        opts = dict(settings)
        warm_from = opts.pop("_warm_start", None)  # SolveOptions.warm_start, see settings()
        chosen = opts.pop("kktsolver", None)
        c = cvxopt.matrix(data.c)
        warm = _warm_start(warm_from, len(data.c), len(data.ge), len(data.eq), [lmi.dim for lmi in problem.lmis])

        structured = None if chosen else _structured_kkt(data, problem)

        def run(kkt: Any) -> Any:
            nonlocal warm
            if warm:
                try:
                    return solvers.sdp(c, kktsolver=kkt, options=dict(opts), **kwargs, **warm)
                except (ValueError, ArithmeticError):  # a starting point CVXOPT refuses: solve cold
                    warm = {}
            return solvers.sdp(c, kktsolver=kkt, options=dict(opts), **kwargs)

        t0 = time.perf_counter()

        def qr_tried() -> bool:
            # the structured run's last QR_TAIL_TRIED iterations already were 'qr': a run with
            # 'qr' from the start would stall alike (module docstring)
            return structured is not None and structured.qr_tail >= QR_TAIL_TRIED

        def again(r: Any) -> bool:
            return str(r["status"]) == "unknown" and not qr_tried()

        if structured is not None and not chosen:
            try:
                with blas_threads(1):  # its many mid-sized products lose to BLAS threads (threads.py)
                    result, kkt = run(structured), structured
            except (ValueError, ArithmeticError):
                if qr_tried():
                    raise
                result, kkt = run("qr"), "qr"
            else:
                if again(result):
                    result, kkt = run("qr"), "qr"
        else:
            result, kkt = in_turn([chosen] if chosen else KKT_ORDER, run, again)
        solve_s = time.perf_counter() - t0
        native = str(result["status"])
        duals = None
        if result.get("zs") is not None or result.get("zl") is not None:
            y_eq = None if result.get("y") is None else -np.array(result["y"]).ravel()
            blocks = [_lower_sym(Z) for Z in (result.get("zs") or [])]
            duals = LMIForm.invert(data, blocks, y_eq, result.get("zl"))
        x = result.get("x")
        message = ""
        if native == "unknown" and x is not None:
            message = "CVXOPT stopped with status 'unknown' (iteration limit or numerical trouble)"
        return NativeResult(
            native,
            x=None if x is None else np.array(x).ravel(),
            duals=duals,
            solve_s=solve_s,
            iterations=result.get("iterations"),
            message=message,
            # the native iterates, for the next solve of a problem of the same shape (warm start)
            info={
                "warm_started": bool(warm),
                "cvxopt_iterates": _iterates(result),
                "kktsolver": "structured" if kkt is structured and structured is not None else str(kkt),
            },
        )
