"""The time limit of a solve: a forked child stopped at the limit, or the solver's own limit.

:func:`run_limited` runs one closed-problem solve (a callable ``solve(problem, options)``, in
practice :meth:`lmic.backends.backend.Backend._solve`) within ``SolveOptions.time_limit`` and the
time left before a deadline; a solver without a native limit runs in a forked child
(:func:`run_in_child`) stopped with SIGTERM, then SIGKILL, when the time is up. A stopped solve is
the ``error`` solution of :func:`lmic.backends.outcomes.time_limit_solution`.

Examples
--------
>>> describe(ValueError("bad  input\\n here"))
'ValueError: bad input here'
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import replace
from typing import Any

from lmic.backends.outcomes import mark_time_limit, time_limit_solution
from lmic.ir.problem import Problem
from lmic.options import SolveOptions
from lmic.solution import Solution

__all__ = ["describe", "call_safely", "run_in_child", "run_limited"]

SolveFn = Callable[[Problem, SolveOptions], Solution]


def describe(err: BaseException) -> str:
    """One line: the exception's type and its message, whitespace collapsed."""
    msg = " ".join(str(err).split()) or "no message"
    return f"{type(err).__name__}: {msg}"


def call_safely(solve: SolveFn, label: str, problem: Problem, options: SolveOptions) -> Solution:
    """``solve(problem, options)`` here, a crash turned into an ``error`` solution (timed as solver time).

    >>> call_safely(lambda p, o: 1 / 0, "x", None, SolveOptions()).message
    'ZeroDivisionError: division by zero'
    """
    t0 = time.perf_counter()
    try:
        return solve(problem, options)
    except Exception as err:  # noqa: BLE001 - the solver's crash is a status
        return Solution(status="error", backend=label, message=describe(err), solve_s=time.perf_counter() - t0)


def _child(conn: Any, solve: SolveFn, label: str, problem: Problem, options: SolveOptions) -> None:
    try:
        conn.send(solve(problem, options))
    except BaseException as err:  # noqa: BLE001 - reported to the parent as a status
        conn.send(Solution(status="error", backend=label, message=describe(err)))
    finally:
        conn.close()


def run_in_child(
    solve: SolveFn, label: str, problem: Problem, options: SolveOptions, seconds: float
) -> Solution | None:
    """Run ``solve`` in a forked child for at most ``seconds``; ``None`` on time-out.

    The child is stopped (SIGTERM, then SIGKILL after 1 s) when the time is up or when the
    parent is interrupted. Where ``fork`` is unavailable the solve runs here, relying on the
    solver's native limit.
    """
    import multiprocessing  # only for a time-limited solve in a child: ~5 ms of every process otherwise

    try:
        ctx = multiprocessing.get_context("fork")
    except ValueError:  # no fork (Windows): native limits only
        return call_safely(solve, label, problem, options)
    recv, send = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_child, args=(send, solve, label, problem, options), daemon=True)
    proc.start()
    send.close()
    try:
        if recv.poll(seconds):
            sol: Solution = recv.recv()
            return sol
        return None
    except EOFError:
        proc.join(1.0)  # reap it, so that its exit code is known
        return Solution(status="error", backend=label, message=f"solver process died (exit code {proc.exitcode})")
    finally:
        if proc.is_alive():
            proc.terminate()
            proc.join(1.0)
            if proc.is_alive():
                proc.kill()
        proc.join(1.0)
        recv.close()


def run_limited(
    solve: SolveFn,
    label: str,
    problem: Problem,
    options: SolveOptions,
    deadline: float | None = None,
    native_limit: bool = False,
) -> Solution:
    """One solve within ``options.time_limit`` and before ``deadline`` (``time.monotonic()`` s).

    The attempt gets the time left (at most ``options.time_limit``); one that starts after the
    deadline returns the time-limit solution at once. With ``native_limit`` the solver stops
    itself, here (a forked child of a process that has already run Clarabel hangs in Clarabel's
    thread pool: SDPLIB infp1, measured); otherwise the solve runs in a forked child. A solve
    that stops at the limit by itself is marked the same way (:func:`mark_time_limit`).

    >>> run_limited(lambda p, o: Solution("optimal"), "x", None, SolveOptions()).status
    'optimal'
    """
    limit = options.time_limit
    if limit is None:
        return call_safely(solve, label, problem, options)
    left = limit if deadline is None else min(limit, deadline - time.monotonic())
    if left <= 0.0:
        return time_limit_solution(label, limit, 0.0)
    child_options = replace(options, time_limit=left)
    t0 = time.perf_counter()
    if native_limit:
        sol: Solution | None = call_safely(solve, label, problem, child_options)
    else:
        sol = run_in_child(solve, label, problem, child_options, left)
    elapsed = time.perf_counter() - t0
    if sol is None:
        return time_limit_solution(label, limit, elapsed)
    stopped = sol.status in ("error", "inaccurate") and elapsed >= 0.95 * left
    if sol.info.get("time_limit") or stopped:
        sol.solve_s = sol.solve_s or elapsed
        mark_time_limit(sol, limit, elapsed)
    return sol
