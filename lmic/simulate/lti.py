"""Exact integration of a linear time-invariant system driven by known signals, on a fixed grid.

For ``s' = A s + B v(t)`` with ``v`` a known signal (the disturbance, the unknown input, the
input ``u(t)``: anything that does not depend on the state), an adaptive Runge-Kutta method
has to follow every oscillation of ``v`` with its step size control, evaluating the parsed
signal expressions at each of its stages. Here instead:

1. the signal is evaluated once, vectorised, on a uniform fine grid ``h = dt / m``
   (:class:`TimeSignal`); ``m`` (a power of two, at most :data:`MAX_REFINE`) is the smallest
   for which the local cubic interpolation of the samples reproduces the signal at the
   midpoints to :data:`SIGNAL_TOL` (relative to its largest value): a step size chosen from
   the fastest frequency in the signal (a sinusoid of ``omega`` needs ``omega h`` of about
   ``1e-2``);
2. on each fine interval ``v`` is the cubic through the four nearest samples, and the state is
   propagated *exactly* for that cubic: ``s(t + h) = Phi s(t) + sum_i W_i v_i`` with ``Phi =
   expm(A h)`` and ``W_i`` from one matrix exponential of the block matrix ``[[A h, B h, 0,
   ...], [0, 0, I, ...], ...]`` (the input chain ``v, v', v''/2, v'''/6``, as in
   :func:`scipy.signal.cont2discrete` for a first-order hold, one order higher);
3. the ``m`` fine steps between two output points are summed at once (powers of ``Phi``), so
   the only loop runs over the output grid.

The error is that of the cubic interpolation of ``v`` (``~ (omega h)^4 / 40`` of its
amplitude), not of a step-size controller; ``tests/simulate/test_lti.py`` compares it with
``solve_ivp`` at tight tolerances.

Examples
--------
>>> import numpy as np
>>> t = np.linspace(0.0, 1.0, 11)
>>> S = propagate(np.array([[-1.0]]), np.array([[1.0]]), np.array([0.0]), t, constant_signal(np.ones(1)))
>>> bool(abs(S[-1, 0] - (1 - np.exp(-1.0))) < 1e-12)
True
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from math import factorial
from typing import Any

import numpy as np

__all__ = [
    "TimeSignal",
    "as_signal",
    "constant_signal",
    "expression_signal",
    "propagate",
    "stack",
    "MAX_REFINE",
    "SIGNAL_TOL",
]

#: largest number of fine steps per output step
MAX_REFINE = 64
#: relative accuracy asked of the cubic interpolation of the signals
SIGNAL_TOL = 1e-9


class TimeSignal:
    """A known signal ``v(t)`` of ``size`` components, evaluated at a time or on a whole grid.

    Parameters
    ----------
    size : int
    on_grid : callable
        ``ts -> array of shape (len(ts), size)`` (vectorised).
    at : callable, optional
        ``t -> array of shape (size,)`` at one time (faster than ``on_grid`` on a single point,
        for step-by-step integrators); by default ``on_grid`` on a grid of one point.

    Examples
    --------
    >>> s = TimeSignal(2, lambda ts: np.c_[ts, 2 * ts])
    >>> s(1.5).tolist(), s.on(np.array([0.0, 1.0])).tolist()
    ([1.5, 3.0], [[0.0, 0.0], [1.0, 2.0]])
    """

    def __init__(
        self,
        size: int,
        on_grid: Callable[[np.ndarray], np.ndarray],
        at: Callable[[float], np.ndarray] | None = None,
    ) -> None:
        self.size = int(size)
        self._on = on_grid
        self._at = at

    def on(self, ts: np.ndarray) -> np.ndarray:
        """The signal on the grid ``ts``: shape ``(len(ts), size)``."""
        ts = np.asarray(ts, dtype=float)
        with np.errstate(all="ignore"):
            out = np.asarray(self._on(ts), dtype=float)
        return np.broadcast_to(out.reshape(ts.size, -1) if out.size else out, (ts.size, self.size)).copy()

    def __call__(self, t: float) -> np.ndarray:
        if self._at is not None:
            return self._at(float(t))
        return self.on(np.array([float(t)]))[0]


def constant_signal(value: np.ndarray) -> TimeSignal:
    """A constant signal (zero when ``value`` is).

    >>> constant_signal(np.zeros(3))(2.0).tolist()
    [0.0, 0.0, 0.0]
    """
    v = np.asarray(value, dtype=float).ravel()
    return TimeSignal(v.size, lambda ts: np.broadcast_to(v, (ts.size, v.size)), lambda t: v)


def expression_signal(exprs: Sequence[Any], size: int) -> TimeSignal:
    """``t -> [e(t) for e in exprs]`` from parsed expressions of ``t`` (zero of ``size`` when none).

    >>> from lmic.simulate.parser import parse_vector
    >>> s = expression_signal(parse_vector(["2*t", "1"], {"t"}, "w"), 2)
    >>> s.on(np.array([0.0, 0.5])).tolist()
    [[0.0, 1.0], [1.0, 1.0]]
    """
    if not exprs:
        return constant_signal(np.zeros(size))
    exprs = list(exprs)

    def on(ts: np.ndarray) -> np.ndarray:
        env = {"t": ts}
        return np.column_stack([np.broadcast_to(np.asarray(e.evaluate(env), dtype=float), ts.shape) for e in exprs])

    def at(t: float) -> np.ndarray:
        env = {"t": t}
        return np.array([float(e.evaluate(env)) for e in exprs])

    return TimeSignal(len(exprs), on, at)


def as_signal(f: Callable[[float], Any] | TimeSignal, size: int) -> TimeSignal:
    """A :class:`TimeSignal` from one, or from any ``t -> vector`` (evaluated point by point)."""
    if isinstance(f, TimeSignal):
        return f
    g = f

    def on(ts: np.ndarray) -> np.ndarray:
        return np.array([np.asarray(g(float(t)), dtype=float) for t in ts]).reshape(ts.size, -1)

    return TimeSignal(size, on, lambda t: np.asarray(g(t), dtype=float))


def stack(signals: Sequence[TimeSignal]) -> TimeSignal:
    """The signals one above the other: ``t -> [v1(t); v2(t); ...]``.

    >>> stack([constant_signal(np.ones(1)), constant_signal(np.zeros(2))])(0.0).tolist()
    [1.0, 0.0, 0.0]
    """
    sizes = [s.size for s in signals]
    return TimeSignal(
        sum(sizes), lambda ts: np.hstack([s.on(ts) for s in signals]) if signals else np.zeros((ts.size, 0))
    )


# -- the cubic-hold discretisation ---------------------------------------------------------------

# stencils (offsets of the four samples from the left end of the interval) and the matrix that
# maps the samples to the coefficients of the cubic in sigma = (t - t_k) / h
_STENCILS = {"first": (0, 1, 2, 3), "inner": (-1, 0, 1, 2), "last": (-2, -1, 0, 1)}


def _lagrange(offsets: Sequence[int]) -> np.ndarray:
    V = np.vander(np.asarray(offsets, dtype=float), 4, increasing=True)  # rows: samples, cols: sigma^p
    return np.linalg.inv(V)  # coefficient p = sum_i inv[p, i] * sample_i


def _cubic_hold(A: np.ndarray, B: np.ndarray, h: float) -> tuple[np.ndarray, list[np.ndarray]]:
    """``Phi = expm(A h)`` and ``Psi_p`` with ``s(h) = Phi s0 + sum_p Psi_p c_p`` for ``v = sum c_p sigma^p``."""
    from scipy.linalg import expm

    n, q = A.shape[0], B.shape[1]
    size = n + 4 * q
    M = np.zeros((size, size))
    M[:n, :n] = A * h
    M[:n, n : n + q] = B * h
    for p in range(3):  # the chain x_p' = x_{p+1} (in sigma): x_p = d^p v / d sigma^p
        M[n + p * q : n + (p + 1) * q, n + (p + 1) * q : n + (p + 2) * q] = np.eye(q)
    E = expm(M)
    Phi = E[:n, :n]
    # v(sigma) = sum_p x_p(0) sigma^p / p!, so c_p = x_p(0) / p!
    Psi = [E[:n, n + p * q : n + (p + 1) * q] * factorial(p) for p in range(4)]
    return Phi, Psi


def _refinement(signal: TimeSignal, t0: float, dt: float, count: int) -> tuple[int, np.ndarray]:
    """The number ``m`` of fine steps per output step and the samples on that fine grid."""
    m = 1
    values = signal.on(t0 + dt * np.arange(count * m + 1) / m)
    inner = _lagrange(_STENCILS["inner"])
    half = np.array([1.0, 0.5, 0.25, 0.125]) @ inner  # the cubic through 4 samples at sigma = 1/2
    while m < MAX_REFINE:
        finer = signal.on(t0 + dt * np.arange(2 * count * m + 1) / (2 * m))
        scale = float(np.max(np.abs(finer), initial=0.0))
        if values.shape[0] < 4 or scale == 0.0 or not np.all(np.isfinite(finer)):
            return m, values
        K = values.shape[0] - 1
        mid = sum(half[i] * values[i : K - 2 + i] for i in range(4))  # midpoints of intervals 1 .. K-2
        err = float(np.max(np.abs(mid - finer[3 : 2 * K - 2 : 2]), initial=0.0))
        if err <= SIGNAL_TOL * scale:
            return m, values
        m, values = 2 * m, finer
    return m, values


def propagate(A: np.ndarray, B: np.ndarray, s0: np.ndarray, grid: np.ndarray, signal: TimeSignal) -> np.ndarray:
    """``s(t)`` on ``grid`` (uniform) for ``s' = A s + B v(t)``, ``s(grid[0]) = s0`` (see the module docstring).

    Returns
    -------
    ndarray
        Shape ``(len(grid), n)``; rows may be non-finite when the system blows up (the caller
        decides what that means).

    Examples
    --------
    >>> t = np.linspace(0.0, 2.0, 21)
    >>> S = propagate(np.array([[0.0]]), np.array([[1.0]]), np.zeros(1), t,
    ...               TimeSignal(1, lambda ts: np.cos(ts)[:, None]))
    >>> bool(np.max(np.abs(S[:, 0] - np.sin(t))) < 1e-9)
    True
    """
    A = np.atleast_2d(np.asarray(A, dtype=float))
    n = A.shape[0]
    grid = np.asarray(grid, dtype=float)
    count = grid.size - 1
    out = np.empty((grid.size, n))
    out[0] = s0
    if count == 0:
        return out
    dt = float(grid[1] - grid[0])
    B = np.asarray(B, dtype=float).reshape(n, -1)
    if B.shape[1] == 0 or signal.size == 0:
        B, signal = np.zeros((n, 1)), constant_signal(np.zeros(1))
    m, V = _refinement(signal, float(grid[0]), dt, count)
    K = count * m  # fine intervals
    h = dt / m
    Phi, Psi = _cubic_hold(A, B, h)
    G = np.empty((K, n))
    with np.errstate(all="ignore"):
        if K < 3:  # too few samples for a cubic: hold linearly between the two ends of each interval
            for k in range(K):
                G[k] = Psi[0] @ V[k] + Psi[1] @ (V[k + 1] - V[k])
        else:
            W = {}
            for key, offsets in _STENCILS.items():
                lag = _lagrange(offsets)
                W[key] = [sum(Psi[p] * lag[p, i] for p in range(4)) for i in range(4)]
            G[0] = sum(W["first"][i] @ V[i] for i in range(4))
            G[K - 1] = sum(W["last"][i] @ V[K - 3 + i] for i in range(4))
            if K > 2:
                window = np.hstack([V[i : K - 2 + i] for i in range(4)])  # (K - 2, 4 q), contiguous
                G[1 : K - 1] = window @ np.ascontiguousarray(np.vstack([W["inner"][i].T for i in range(4)]))
        # the m fine steps of each output step at once: s_{j+m} = Phi^m s_j + sum_r Phi^(m-1-r) g_{j+r}
        powers = [np.eye(n)]
        for _ in range(m):
            powers.append(Phi @ powers[-1])
        weights = np.ascontiguousarray(np.vstack([powers[m - 1 - r].T for r in range(m)]))  # (m n, n)
        stepped = G.reshape(count, m * n) @ weights
        Phim = powers[m]
        s = np.asarray(s0, dtype=float)
        for k in range(count):
            s = Phim @ s + stepped[k]
            out[k + 1] = s
    return out
