"""The backend interface every solver plugin implements.

A backend is a class with class attributes ``name``, ``requires`` (importable module name ->
pip package), ``STATUS_MAP`` (native status -> :data:`lmic.solution.STATUSES`) and
``capabilities``, and the methods :meth:`Backend.is_available`, :meth:`Backend.supports` and
:meth:`Backend.solve`. Native solver modules are imported inside methods, never at import time.

:meth:`Backend.solve` is the same for every backend: it validates the problem, applies the
strict-inequality reduction (:mod:`lmic.reductions.strict`), calls the backend's
:meth:`Backend._solve` on the resulting *closed* problem (no strict constraints), maps the answer
back, and turns any exception or time-out into a ``status="error"`` :class:`Solution` carrying
the message. Backends only implement ``_solve``.

Conic data (:func:`conic_data`) is the stacked form ``A x + s = b``, ``s`` in
``{0}^eq x R+^ge x PSD_1 x ... x PSD_L`` shared by the ``s``-form solvers (Clarabel, SCS,
CVXOPT); each backend passes its own PSD vectorisation (one conversion place per backend).

Examples
--------
>>> SolveOptions(tol=1e-9).tol
1e-09
"""

from __future__ import annotations

import contextlib
import functools
import importlib
import importlib.util
import multiprocessing
import os
import sys
import time
import traceback
from abc import ABC, abstractmethod
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
import scipy.sparse as sp

from lmic.ir.problem import Problem
from lmic.ir.svec import tril_rows_cols, tril_size
from lmic.options import SolveOptions
from lmic.reductions.eliminate import eliminate_unused, independent_columns, restore_eliminated
from lmic.solution import Solution

__all__ = [
    "SolveOptions",
    "Backend",
    "ConicData",
    "conic_data",
    "problem_kinds",
    "full_vec_map",
    "full_vec_coo",
    "quiet_native",
    "eliminate_unused",
    "independent_columns",
    "restore_eliminated",
]


def problem_kinds(problem: Problem) -> set[str]:
    """The constraint kinds a problem uses: a subset of ``{"lmi", "eq", "ge"}``.

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("t", "scalar", (1, 1))], [LMI("t>0", 1, sp.csc_matrix([[0., 1.]]))],
    ...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
    >>> sorted(problem_kinds(p))
    ['lmi']
    """
    kinds = {"lmi"} if problem.lmis else set()
    kinds.update(problem.linear.kinds)
    return kinds


@dataclass
class ConicData:
    """``min c . x`` (plus ``c0``) subject to ``A x + s = b``, ``s`` in the cone ``dims``.

    Attributes
    ----------
    A : scipy.sparse.csc_matrix
    b, c : numpy.ndarray
    c0 : float
        Constant of the objective (in the minimisation sense).
    sign : float
        ``+1`` when the IR minimises (or is a feasibility problem), ``-1`` when it maximises.
    n_eq, n_ge : int
        Numbers of equality and inequality rows (first ``n_eq`` rows, then ``n_ge``).
    psd : list of int
        LMI dimensions, in IR order.
    eq_rows, ge_rows : numpy.ndarray
        Indices of the IR's linear rows placed in each block.
    """

    A: sp.csc_matrix
    b: np.ndarray
    c: np.ndarray
    c0: float
    sign: float
    n_eq: int
    n_ge: int
    psd: list[int]
    eq_rows: np.ndarray
    ge_rows: np.ndarray

    @property
    def psd_offsets(self) -> list[int]:
        """Row where each PSD block starts."""
        off, out = self.n_eq + self.n_ge, []
        for d in self.psd:
            out.append(off)
            off += tril_size(d)
        return out


def conic_data(
    problem: Problem,
    psd_vec: Callable[[int], tuple[np.ndarray, np.ndarray]],
) -> ConicData:
    """Stack a closed problem as ``A x + s = b`` with ``s`` in ``{0} x R+ x PSD...``.

    Parameters
    ----------
    problem : Problem
        A problem without strict constraints (strictness is ignored here).
    psd_vec : callable
        ``psd_vec(d) -> (perm, scale)``: the solver's vectorisation of a ``d x d`` block,
        ``native = scale * tril_storage[perm]`` (from :mod:`lmic.ir.svec`).

    Each LMI ``F0 + sum x_k F_k >= 0`` becomes ``s = F(x)``: ``b = vec(F0)``, ``A = -vec(F_k)``.
    Everything is sparse and vectorised (no loop over entries).

    Examples
    --------
    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Variable
    >>> p = Problem([Variable("t", "scalar", (1, 1))], [LMI("t>=1", 1, sp.csc_matrix([[-1., 1.]]))],
    ...             LinearConstraints.empty(1), Objective("min", [0, 1]))
    >>> data = conic_data(p, lambda d: (np.arange(d * (d + 1) // 2), np.ones(d * (d + 1) // 2)))
    >>> data.A.toarray(), data.b
    (array([[-1.]]), array([-1.]))
    """
    lin = problem.linear
    kinds = np.asarray(lin.kinds, dtype=object)
    eq_rows = np.flatnonzero(kinds == "eq") if len(lin) else np.zeros(0, dtype=int)
    ge_rows = np.flatnonzero(kinds == "ge") if len(lin) else np.zeros(0, dtype=int)
    # one COO triple for the whole stack: each block's entries are moved to their native row
    # (storage row r goes to native row k with perm[k] = r, times scale[k]); no sparse products
    rows, cols, vals = [], [], []
    offset = 0
    for block in (lin.A[eq_rows], lin.A[ge_rows]):
        C = block.tocoo()
        rows.append(C.row + offset)
        cols.append(C.col)
        vals.append(C.data)
        offset += block.shape[0]
    for lmi in problem.lmis:
        perm, scale = psd_vec(lmi.dim)
        inverse = np.empty_like(perm)
        inverse[perm] = np.arange(len(perm))
        C = lmi.coeffs.tocoo()
        native = inverse[C.row]
        rows.append(native + offset)
        cols.append(C.col)
        vals.append(C.data * scale[native])
        offset += len(perm)
    row = np.concatenate(rows) if rows else np.zeros(0, dtype=int)
    col = np.concatenate(cols) if cols else np.zeros(0, dtype=int)
    val = np.concatenate(vals) if vals else np.zeros(0)
    const = col == 0
    b = np.zeros(offset)
    np.add.at(b, row[const], val[const])
    A = sp.csc_matrix((-val[~const], (row[~const], col[~const] - 1)), shape=(offset, problem.n))
    obj = problem.objective
    sign = -1.0 if obj.sense == "max" else 1.0
    if obj.sense == "feasibility":
        c, c0 = np.zeros(problem.n), 0.0
    else:
        c, c0 = sign * obj.c[1:], sign * float(obj.c[0])
    return ConicData(
        A=A,
        b=b,
        c=np.asarray(c, dtype=float),
        c0=c0,
        sign=sign,
        n_eq=len(eq_rows),
        n_ge=len(ge_rows),
        psd=[lmi.dim for lmi in problem.lmis],
        eq_rows=eq_rows,
        ge_rows=ge_rows,
    )


def full_vec_map(d: int) -> sp.csr_matrix:
    """Sparse ``E`` (``d*d x tril_size(d)``) with ``vec(M) = E @ tril_storage(M)`` (column-major).

    >>> full_vec_map(2).toarray()
    array([[1., 0., 0.],
           [0., 1., 0.],
           [0., 1., 0.],
           [0., 0., 1.]])
    """
    i, j = tril_rows_cols(d)
    k = np.arange(len(i))
    off = i != j
    rows = np.concatenate([i + j * d, (j + i * d)[off]])
    cols = np.concatenate([k, k[off]])
    return sp.csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(d * d, len(i)))


def full_vec_coo(lmi: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(row, col, value)`` of ``full_vec_map(d) @ lmi.coeffs`` without a sparse product.

    Storage entry ``(i, j)`` of column ``k`` goes to rows ``i + j d`` and, off the diagonal,
    ``j + i d`` of the column-major ``d*d`` vectorisation (CVXOPT's and SDPA's form). At
    ``d = 120`` with 1621 columns this is 5x faster than the product.

    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI
    >>> row, col, val = full_vec_coo(LMI("F", 2, sp.csc_matrix([[1.0], [2.0], [3.0]])))
    >>> row.tolist(), col.tolist(), val.tolist()
    ([0, 1, 3, 2], [0, 0, 0, 0], [1.0, 2.0, 3.0, 2.0])
    """
    d = lmi.dim
    i, j = tril_rows_cols(d)
    C = lmi.coeffs.tocoo()
    ii, jj = i[C.row], j[C.row]
    off = ii != jj
    row = np.concatenate([ii + jj * d, (jj + ii * d)[off]])
    col = np.concatenate([C.col, C.col[off]])
    val = np.concatenate([C.data, C.data[off]])
    return row, col, val


@contextlib.contextmanager
def quiet_native(active: bool = True) -> Iterator[None]:
    """Silence a native library's own prints (file descriptors 1 and 2) while ``active``.

    >>> with quiet_native():
    ...     pass
    """
    if not active:
        yield
        return
    try:
        saved = [os.dup(1), os.dup(2)]
    except OSError:  # no real file descriptors (embedded interpreters)
        yield
        return
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        sys.stdout.flush()
        sys.stderr.flush()
        os.dup2(devnull, 1)
        os.dup2(devnull, 2)
        yield
    finally:
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        for fd in (*saved, devnull):
            os.close(fd)


def _child(conn: Any, backend: Backend, problem: Problem, options: SolveOptions) -> None:
    try:
        conn.send(backend._solve(problem, options))
    except BaseException as err:  # noqa: BLE001 - reported to the parent as a status
        conn.send(Solution(status="error", backend=backend.label, message=_describe(err)))
    finally:
        conn.close()


def _sandboxed(backend: Backend, problem: Problem, options: SolveOptions, seconds: float) -> Solution | None:
    """Run ``backend._solve`` in a forked child for at most ``seconds``; ``None`` on time-out.

    The child is stopped (SIGTERM, then SIGKILL after 1 s) when the time is up or when the
    parent is interrupted. Where ``fork`` is unavailable the solve runs here, relying on the
    solver's native limit.
    """
    try:
        ctx = multiprocessing.get_context("fork")
    except ValueError:  # no fork (Windows): native limits only
        t0 = time.perf_counter()
        try:
            return backend._solve(problem, options)
        except Exception as err:  # noqa: BLE001 - the solver's crash is a status
            return Solution(
                status="error", backend=backend.label, message=_describe(err), solve_s=time.perf_counter() - t0
            )
    recv, send = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_child, args=(send, backend, problem, options), daemon=True)
    proc.start()
    send.close()
    try:
        if recv.poll(seconds):
            return recv.recv()
        return None
    except EOFError:
        return Solution(
            status="error",
            backend=backend.label,
            message=f"solver process died (exit code {proc.exitcode})",
        )
    finally:
        if proc.is_alive():
            proc.terminate()
            proc.join(1.0)
            if proc.is_alive():
                proc.kill()
        proc.join(1.0)
        recv.close()


def _describe(err: BaseException) -> str:
    msg = " ".join(str(err).split()) or "no message"
    return f"{type(err).__name__}: {msg}"


class Backend(ABC):
    """Base class of every backend plugin.

    Subclasses set the class attributes and implement :meth:`_solve` for a *closed* problem
    (every LMI ``F(x) >= 0``, every row ``== 0`` or ``>= 0``), returning a :class:`Solution` in
    the same problem's variable space with ``solve_s`` set to the time spent inside the solver.
    """

    name: ClassVar[str] = ""
    #: importable module names the backend needs, and the pip package that provides each
    requires: ClassVar[dict[str, str]] = {}
    STATUS_MAP: ClassVar[dict[str, str]] = {}
    #: constraint kinds the backend takes: subset of {"lmi", "eq", "ge"}
    capabilities: ClassVar[frozenset[str]] = frozenset({"lmi", "eq", "ge"})
    #: whether the solver enforces ``SolveOptions.time_limit`` itself
    native_time_limit: ClassVar[bool] = False
    #: interior-point (True) or first-order (False) method, for documentation and ``auto``
    interior_point: ClassVar[bool] = True
    #: whether the solver needs a constraint matrix of full column rank (CVXOPT, SDPA): linearly
    #: dependent entries of ``x`` are then eliminated first (:func:`eliminate_unused`)
    full_rank: ClassVar[bool] = False
    #: the smallest tolerance the solver is asked for (``SolveOptions.tol`` is raised to it)
    tol_floor: ClassVar[float] = 0.0
    #: one line shown by ``lmic backends``
    description: ClassVar[str] = ""
    #: accepted ``name:VARIANT`` suffixes (e.g. the sub-solvers of ``cvxpy``); empty: none
    variants: ClassVar[tuple[str, ...]] = ()

    def __init__(self, variant: str | None = None) -> None:
        if variant is not None and variant.upper() not in self.variants:
            from lmic.errors import BackendUnavailable

            raise BackendUnavailable(f"backend '{self.name}' has no variant '{variant}'")
        self.variant = variant

    @property
    def label(self) -> str:
        """The name shown in results (e.g. ``"cvxpy:SCS"`` for a configured backend)."""
        return self.name

    def missing_packages(self) -> list[str]:
        """The pip packages whose modules cannot be imported here."""
        missing = []
        for mod, pkg in self.requires.items():
            try:
                found = importlib.util.find_spec(mod) is not None
            except (ImportError, ValueError):
                found = False
            if not found:
                missing.append(pkg)
        return missing

    def is_available(self) -> bool:
        """True when every required module is importable."""
        return not self.missing_packages()

    def supports(self, problem: Problem, explain: bool = False) -> bool | tuple[bool, str]:
        """Whether this backend can take ``problem``; with ``explain``, also why not.

        The default compares the problem's constraint kinds with :attr:`capabilities` and
        requires at least one decision variable.
        """
        reason = ""
        extra = problem_kinds(problem) - set(self.capabilities)
        if extra:
            reason = (
                f"backend '{self.label}' cannot take {', '.join(sorted(extra))} constraints "
                f"(it takes {', '.join(sorted(self.capabilities))})"
            )
        elif problem.n == 0:
            reason = "the problem has no decision variables"
        ok = not reason
        return (ok, reason) if explain else ok

    def solve(self, problem: Problem, options: SolveOptions | None = None) -> Solution:
        """Solve ``problem``; map every outcome (crashes included) into a :class:`Solution`.

        Decision-variable entries that appear in no constraint and not in the objective (and,
        for backends with :attr:`full_rank`, linearly dependent ones) are removed first
        (:func:`eliminate_unused`; they come back as ``0``). Strict constraints
        are handled by :func:`lmic.reductions.strict.solve` (recorded in ``Solution.strategy``
        and ``Solution.margin``). ``solve_s`` is the time inside the solver (summed over the
        attempts of the strict strategy), ``lower_s`` everything else lmic did: elimination,
        reduction, lowering, result mapping and the check of a fixed-margin point.
        """
        from lmic.reductions import strict

        options = options or SolveOptions()
        if options.tol < self.tol_floor:
            from dataclasses import replace as _replace

            options = _replace(options, tol=self.tol_floor)
        try:
            for module in self.requires:  # import time is not lmic's overhead
                importlib.import_module(module)
            # used by the strict reductions and the elimination of dependent entries
            for module in ("lmic.reductions.strict", "scipy.linalg", "scipy.sparse.csgraph"):
                importlib.import_module(module)
        except ImportError as err:
            return Solution(
                status="error",
                backend=self.label,
                message=f"{_describe(err)}; pip install {' '.join(self.missing_packages())}",
            )
        t0 = time.perf_counter()
        try:
            kept, keep = eliminate_unused(problem, dependent=self.full_rank)
            # one deadline for every attempt of the strict reduction (SolveOptions.time_limit)
            deadline = None if options.time_limit is None else time.monotonic() + options.time_limit
            run = functools.partial(self._run, deadline=deadline)
            sol = strict.solve(kept, options, run, first_order=not self.interior_point)
            if keep is not None:
                restore_eliminated(sol, keep, problem)
        except Exception as err:  # noqa: BLE001 - a crash is a status, never a traceback
            detail = traceback.extract_tb(err.__traceback__)
            where = f" (at {detail[-1].name})" if detail else ""
            return Solution(
                status="error",
                backend=self.label,
                message=_describe(err) + where,
                solve_s=time.perf_counter() - t0,
            )
        sol.backend = sol.backend or self.label
        sol.lower_s = max(0.0, time.perf_counter() - t0 - sol.solve_s)
        return sol

    def _run(self, problem: Problem, options: SolveOptions, deadline: float | None = None) -> Solution:
        """Call :meth:`_solve`; with a time limit, in a forked child stopped at the limit.

        ``deadline`` (``time.monotonic()`` seconds) is the end of the whole :meth:`solve` call;
        each attempt gets the time left (at most ``options.time_limit``), and an attempt that
        starts after the deadline returns the time-limit solution at once. A solver that stops
        by itself at the limit (a native limit) is marked the same way
        (:func:`lmic.backends.outcomes.mark_time_limit`).
        """
        from lmic.backends.progress import solve_progress

        # a solve longer than 2 s shows "lmic: <label> | <step> | <seconds>" on a terminal
        with solve_progress(self.label):
            return self._run_limited(problem, options, deadline)

    def _call(self, problem: Problem, options: SolveOptions) -> Solution:
        """:meth:`_solve` here, a crash turned into an ``error`` solution."""
        t0 = time.perf_counter()
        try:
            return self._solve(problem, options)
        except Exception as err:  # noqa: BLE001 - the solver's crash, timed as solver time
            return Solution(
                status="error",
                backend=self.label,
                message=_describe(err),
                solve_s=time.perf_counter() - t0,
            )

    def _run_limited(self, problem: Problem, options: SolveOptions, deadline: float | None) -> Solution:
        from lmic.backends.outcomes import mark_time_limit, time_limit_solution

        limit = options.time_limit
        if limit is None:
            return self._call(problem, options)
        left = limit if deadline is None else min(limit, deadline - time.monotonic())
        if left <= 0.0:
            return time_limit_solution(self.label, limit, 0.0)
        from dataclasses import replace as _replace

        child_options = _replace(options, time_limit=left)
        t0 = time.perf_counter()
        if self.native_time_limit:
            # the solver stops itself, here: a forked child of a process that has already run
            # Clarabel hangs in Clarabel's thread pool (SDPLIB infp1, measured), so no fork
            sol: Solution | None = self._call(problem, child_options)
        else:
            sol = _sandboxed(self, problem, child_options, left)
        elapsed = time.perf_counter() - t0
        if sol is None:
            return time_limit_solution(self.label, limit, elapsed)
        stopped = sol.status in ("error", "inaccurate") and elapsed >= 0.95 * left
        if sol.info.get("time_limit") or stopped:
            sol.solve_s = sol.solve_s or elapsed
            mark_time_limit(sol, limit, elapsed)
        return sol

    @abstractmethod
    def _solve(self, problem: Problem, options: SolveOptions) -> Solution:
        """Solve a closed ``problem`` (no strict constraints) with the native solver."""

    def map_status(self, native: str) -> str:
        """Map a native status into the shared vocabulary (unknown -> ``error``)."""
        return self.STATUS_MAP.get(str(native), "error")

    # -- helpers shared by the s-form backends ---------------------------------------------

    @staticmethod
    def split_duals(
        data: ConicData,
        z: np.ndarray,
        unvec: Callable[[np.ndarray, int], np.ndarray],
        n_rows: int,
    ) -> dict[str, Any]:
        """IR-shaped ``{"lmis": [Z_i], "linear": y}`` from a stacked dual vector ``z``.

        ``unvec(v, d)`` turns one native PSD block back into a dense symmetric matrix.
        """
        z = np.asarray(z, dtype=float).ravel()
        y = np.zeros(n_rows)
        y[data.eq_rows] = z[: data.n_eq]
        y[data.ge_rows] = z[data.n_eq : data.n_eq + data.n_ge]
        mats = []
        for off, d in zip(data.psd_offsets, data.psd, strict=True):
            mats.append(unvec(z[off : off + tril_size(d)], d))
        return {"lmis": mats, "linear": y}
