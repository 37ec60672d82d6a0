"""Clarabel (native Python API): the embedded default backend.

Clarabel solves ``min 1/2 x'Px + q'x`` s.t. ``A x + s = b``, ``s`` in a product of cones. Each
LMI ``F(x) >= 0`` is one ``PSDTriangleConeT(d)`` block with ``s = svec(F(x))`` in Clarabel's
vectorisation: the *upper* triangle, column by column, off-diagonal entries times ``sqrt(2)``
(:func:`lmic.ir.svec.tril_to_triu_colmajor_perm`). Equalities go to ``ZeroConeT``, inequalities
to ``NonnegativeConeT``. The dual ``z`` gives ``Z_i`` and ``y`` in the IR's convention
(``c_k = sum_i <F_i^(k), Z_i> + a_k . y``); on ``PrimalInfeasible`` it is the Farkas ray
(``A'z = 0``, ``b'z < 0``).

Examples
--------
>>> ClarabelBackend.name
'clarabel'
"""

from __future__ import annotations

import functools
import os
import time
from typing import Any, ClassVar

import numpy as np
import scipy.sparse as sp

from lmic.backends.backend import Backend
from lmic.backends.lowering import SForm, psd_unvec
from lmic.backends.results import NativeResult
from lmic.ir.problem import Problem
from lmic.ir.svec import svec_scale, tril_to_triu_colmajor_perm
from lmic.options import SolveOptions

__all__ = [
    "ClarabelBackend",
    "clarabel_vec",
    "clarabel_unvec",
    "kkt_bytes",
    "memory_refusal",
    "MEMORY_FRACTION",
    "BYTES_PER_KKT_ENTRY",
    "BYTES_PER_FILL_ENTRY",
    "KKT_CONSTANT_BYTES",
]

#: Clarabel is refused when its estimated memory exceeds this share of the machine's memory
MEMORY_FRACTION = 0.4
#: bytes per entry of the dense ``t x t`` block a PSD cone of ``t = d(d+1)/2`` rows adds to
#: Clarabel's KKT system (matrix, LDL factor and workspace), calibrated against the peak
#: resident memory of solves measured by ``benchmarks/clarabel_memory.py``: 52.2-54.7 bytes on
#: max-cut SDPs (d = 40-130), 51.5 in the issue's d = 150 max-cut (6.6 GB); 56 covers them
BYTES_PER_KKT_ENTRY = 56
#: bytes per entry of the ``n x n`` block the factorisation fills in among the ``n`` decision
#: variables once the dense PSD blocks are eliminated (``A' H^-1 A``): negligible on max-cut
#: (``n = d``), but a Lyapunov LMI pair at d = 90 (n = 4095) peaked at 1849 MiB and at d = 130
#: (n = 8515) passed 9.4 GiB, above the PSD term alone (1791 MiB and 7.6 GiB)
BYTES_PER_FILL_ENTRY = 32
#: fixed part of the estimate (solver workspace besides the KKT system)
KKT_CONSTANT_BYTES = 64 << 20


def kkt_bytes(problem: Problem) -> int:
    """Estimated peak memory of a Clarabel solve of ``problem`` (bytes).

    Clarabel factors a dense ``t x t`` scaling block per PSD cone with ``t = d (d + 1) / 2`` rows:
    memory grows as ``d^4`` (:data:`BYTES_PER_KKT_ENTRY` per entry), plus the fill among the
    ``n`` decision variables (:data:`BYTES_PER_FILL_ENTRY` per ``n^2``) and
    :data:`KKT_CONSTANT_BYTES`. Measured: a 130 x 130 max-cut LMI peaks at 3.5 GiB against an
    estimate of 3.8 GiB; a 250 x 250 LMI would need about 55 GB (SDPA solves it in 0.3 s).

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("t", "scalar", (1, 1))], [LMI("t>0", 1, sp.csc_matrix([[0., 1.]]))],
    ...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
    >>> kkt_bytes(p) - KKT_CONSTANT_BYTES
    88
    """
    blocks = sum((lmi.dim * (lmi.dim + 1) // 2) ** 2 for lmi in problem.lmis)
    return BYTES_PER_KKT_ENTRY * blocks + BYTES_PER_FILL_ENTRY * problem.n**2 + KKT_CONSTANT_BYTES


def memory_refusal(problem: Problem) -> str | None:
    """Why a Clarabel solve of ``problem`` would not fit in this machine's memory, or ``None``
    (:func:`kkt_bytes` against :data:`MEMORY_FRACTION` of the memory; also for Clarabel through
    CVXPY)."""
    need, have = kkt_bytes(problem), _physical_memory()
    if need <= MEMORY_FRACTION * have or not problem.lmis:
        return None
    big = max(problem.lmis, key=lambda lmi: lmi.dim)
    return (
        f"Clarabel factors a dense block of (d(d+1)/2)^2 entries per LMI; LMI '{big.name}' "
        f"({big.dim}x{big.dim}) needs about {_size(need)} of the {_size(have)} here: "
        "use --backend sdpa, cvxopt or auto"
    )


def _size(n: float) -> str:
    return f"{n / 2**30:.1f} GB" if n >= 2**30 else f"{n / 2**20:.1f} MB"


def _physical_memory() -> int:
    try:
        return int(os.sysconf("SC_PHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return 8 << 30


@functools.lru_cache(maxsize=64)
def clarabel_vec(d: int) -> tuple[np.ndarray, np.ndarray]:
    """Clarabel's PSD vectorisation as ``(perm, scale)``: ``native = scale * storage[perm]``.

    >>> clarabel_vec(2)[0]
    array([0, 1, 2])
    """
    perm = tril_to_triu_colmajor_perm(d)
    return _frozen(perm), _frozen(svec_scale(d)[perm])


def _frozen(a: np.ndarray) -> np.ndarray:
    """``a`` made read-only (it is cached and shared)."""
    a.setflags(write=False)
    return a


def clarabel_unvec(v: np.ndarray, d: int) -> np.ndarray:
    """Dense symmetric matrix from one Clarabel PSD block (inverse of :func:`clarabel_vec`).

    >>> clarabel_unvec(np.array([1.0, np.sqrt(2) * 2, 3.0]), 2)
    array([[1., 2.],
           [2., 3.]])
    """
    return psd_unvec(clarabel_vec, v, d)


#: Clarabel's s-form lowering (apply: ConicData; invert: IR multipliers)
FORM = SForm(clarabel_vec)


class ClarabelBackend(Backend):
    """Clarabel interior-point solver through its native API."""

    name: ClassVar[str] = "clarabel"
    title: ClassVar[str] = "Clarabel"
    requires: ClassVar[dict[str, str]] = {"clarabel": "clarabel"}
    native_time_limit: ClassVar[bool] = True
    description: ClassVar[str] = "Clarabel interior point, native API (default)"
    STATUS_MAP: ClassVar[dict[str, str]] = {
        "Solved": "optimal",
        "AlmostSolved": "inaccurate",
        "PrimalInfeasible": "infeasible",
        # an inexact infeasibility claim: kept only if its ray verifies (INEXACT_INFEASIBLE)
        "AlmostPrimalInfeasible": "inaccurate",
        "DualInfeasible": "unbounded",
        "AlmostDualInfeasible": "inaccurate",
        "MaxIterations": "inaccurate",
        "MaxTime": "error",
        "NumericalError": "error",
        "InsufficientProgress": "inaccurate",
        "CallbackTerminated": "error",
        "Unsolved": "error",
    }
    INEXACT_INFEASIBLE: ClassVar[frozenset[str]] = frozenset({"AlmostPrimalInfeasible"})
    INEXACT_UNBOUNDED: ClassVar[frozenset[str]] = frozenset({"AlmostDualInfeasible"})
    TIME_LIMIT: ClassVar[frozenset[str]] = frozenset({"MaxTime"})

    def supports(self, problem: Problem, explain: bool = False) -> bool | tuple[bool, str]:
        """Refuses problems whose dense PSD scaling blocks would not fit in memory."""
        why = self.too_large(problem)
        if why is not None:
            return (False, why) if explain else False
        return super().supports(problem, explain)

    def too_large(self, problem: Problem) -> str | None:
        """:func:`memory_refusal` (Clarabel's dense scaling blocks against this machine's memory)."""
        return memory_refusal(problem)

    def settings(self, options: SolveOptions) -> dict[str, Any]:
        """Clarabel's ``DefaultSettings`` fields from the options (``extra`` verbatim, last)."""
        import clarabel

        tol = options.tol
        s: dict[str, Any] = {
            "verbose": bool(options.verbose),
            # Clarabel 0.11's chordal decomposition reports "Solved" at a suboptimal point on
            # SDPLIB control1 (18.0568 instead of 17.7846; its dual has eigenvalue -3e-3): off by
            # default, re-enable with extra={"chordal_decomposition_enable": True}. Without an
            # objective there is no optimum to get wrong, and the point is verified and certified:
            # on for feasibility problems (call), 1.45x faster on qib.thm1 (n = 30, 6.0-6.9 s
            # against 8.8-10.3 s; its zero blocks make cliques)
            "chordal_decomposition_enable": None,
            "tol_gap_abs": tol,
            "tol_gap_rel": tol,
            "tol_feas": tol,
            "tol_infeas_abs": tol,
            "tol_infeas_rel": tol,
            "tol_ktratio": min(clarabel.DefaultSettings().tol_ktratio, max(tol, 1e-12) * 1e2),
        }
        if options.max_iter is not None:
            s["max_iter"] = int(options.max_iter)
        if options.time_limit is not None:
            s["time_limit"] = float(options.time_limit)
        s.update(options.extra)
        return s

    def call(self, problem: Problem, settings: dict[str, Any]) -> NativeResult:
        """Lower to ``A x + s = b``, run ``DefaultSolver``, invert ``z`` (the dual or the ray)."""
        import clarabel

        data = FORM.apply(problem)
        cones: list[Any] = []
        if data.n_eq:
            cones.append(clarabel.ZeroConeT(data.n_eq))
        if data.n_ge:
            cones.append(clarabel.NonnegativeConeT(data.n_ge))
        cones += [clarabel.PSDTriangleConeT(d) for d in data.psd]
        s = clarabel.DefaultSettings()
        settings = dict(settings)
        if settings.get("chordal_decomposition_enable") is None:
            settings["chordal_decomposition_enable"] = problem.objective.sense == "feasibility"
        for key, value in settings.items():
            setattr(s, key, value)
        t0 = time.perf_counter()
        P = sp.csc_matrix((problem.n, problem.n))
        result = clarabel.DefaultSolver(P, data.c, data.A, data.b, cones, s).solve()
        solve_s = time.perf_counter() - t0
        native = str(result.status).split(".")[-1]
        z = np.asarray(result.z, dtype=float)
        duals = FORM.invert(data, z, len(problem.linear))
        scale = -float(data.b @ z)
        if native in ("PrimalInfeasible", "AlmostPrimalInfeasible") and scale > 0:
            duals = {"lmis": [Z / scale for Z in duals["lmis"]], "linear": duals["linear"] / scale}
        return NativeResult(
            native,
            x=np.asarray(result.x, dtype=float),
            duals=duals,
            solve_s=solve_s,
            iterations=int(result.iterations),
            info={"solver_time_s": float(result.solve_time)},
        )
