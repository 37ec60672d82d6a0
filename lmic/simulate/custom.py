"""The base of the observer families that run their own simulation loop (:class:`Custom`).

Each family of :mod:`lmic.simulate.families` (one module each) subclasses :class:`Custom`; the
helpers here read their time signals and integrate their continuous-time loops.

Examples
--------
>>> issubclass(Custom, Observer)
True
"""

from __future__ import annotations

from abc import abstractmethod
from collections.abc import Callable, Mapping
from typing import Any, ClassVar

import numpy as np

from lmic.errors import DataError
from lmic.simulate.lti import TimeSignal, constant_signal, expression_signal, propagate
from lmic.simulate.models import Observer, SimulationDiverged, Vector
from lmic.simulate.parser import Expression, parse_vector

__all__ = ["Custom", "EXTRA_KEYS", "Signal"]

#: the ``simulation:`` keys only some of these models read
EXTRA_KEYS = ("disturbance", "uncertainty", "delay", "history")

Signal = Callable[[float], Vector]


def _zeros(size: int) -> TimeSignal:
    return constant_signal(np.zeros(size))


def _time_signal(exprs: list[Expression], size: int) -> TimeSignal:
    """``t -> [e(t) for e in exprs]`` (zero of ``size`` when there are none), vectorised on a grid."""
    return expression_signal(exprs, size)


def _read_time_vector(sec: Mapping[str, Any], key: str, size: int, what: str, where: str) -> list[Expression]:
    """The ``key:`` entry of a ``simulation:`` section: ``size`` expressions of ``t``."""
    texts = sec[key] if isinstance(sec[key], list) else [sec[key]]
    if len(texts) != size:
        raise DataError(f"{where}.{key}: has {len(texts)} entries, {what}")
    return parse_vector(texts, {"t"}, f"{where}.{key}")


def _scalar(obs: Observer, role: str) -> float | None:
    m = obs.mats.get(role)
    return None if m is None else float(np.asarray(m).ravel()[0])


class Custom(Observer):
    """An observer model that runs its own loop (see the module docstring).

    Subclasses set :attr:`extra` (the extra ``simulation:`` keys they read), implement
    :meth:`custom_run` and, where a number is certified, :meth:`gain_system`.
    """

    #: extra keys of the ``simulation:`` section this model reads
    extra: ClassVar[tuple[str, ...]] = ()
    #: the role holding the certified L2 gain (``gamma``) — a scalar
    gain_role: ClassVar[str] = "gamma"
    output_nonlinearity = False

    def update(self, z: Vector, y: Vector, u: Vector, t: float, f: Any, h: Any) -> Vector:
        """Not used: these models run :meth:`custom_run`."""
        raise TypeError(f"the '{self.name}' observer runs its own loop (custom_run)")

    @property
    def w_dim(self) -> int:
        """Number of disturbance channels (``w``)."""
        D1 = self.mats.get("D1")
        D2 = self.mats.get("D2")
        if D1 is not None:
            return int(D1.shape[1])
        return 0 if D2 is None else int(D2.shape[1])

    def read_extra(self, sec: Mapping[str, Any], where: str) -> dict[str, Any]:
        """Parse the extra keys this model reads (``disturbance`` by default)."""
        out: dict[str, Any] = {}
        for key in EXTRA_KEYS:
            if key in sec and key not in self.extra:
                allowed = ", ".join(self.extra) or "none"
                raise DataError(
                    f"{where}: '{key}' does not apply to the '{self.name}' observer (its extra keys: {allowed})"
                )
        if "disturbance" in sec:
            what = f"the model has {self.w_dim} disturbance(s)"
            out["w"] = _read_time_vector(sec, "disturbance", self.w_dim, what, where)
        return out

    def disturbance(self, spec: Any) -> Signal:
        """``w(t)`` from the ``disturbance:`` key (zero when absent)."""
        return _time_signal(spec.extra.get("w", []), self.w_dim)

    @abstractmethod
    def custom_run(self, spec: Any, fn: Any, *, w: Signal | None = None, linear: bool = False,
                   zero: bool = False, nominal: bool = False) -> dict[str, Any]:  # fmt: skip
        """The trajectory: ``{"t", "x", "xhat", "signals", "info"}``.

        ``w`` replaces the disturbance, ``linear`` drops the nonlinearity, ``zero`` starts every
        state (and the delay history) at 0, ``nominal`` drops the uncertainty.
        """

    def gain_system(self) -> tuple[Callable[[float], np.ndarray], str] | None:
        """``(G(omega), time)``: the linear nominal map ``w -> z`` at a frequency, or None."""
        return None


def _ct_run(rhs: Callable[[float, np.ndarray], np.ndarray], s0: np.ndarray, spec: Any, max_step: float) -> Any:
    from scipy.integrate import solve_ivp

    grid = _output_grid(spec)

    def blowup(t: float, s: np.ndarray) -> float:
        return 1e12 - float(np.max(np.abs(s)))

    blowup.terminal = True  # type: ignore[attr-defined]
    with np.errstate(all="ignore"):
        sol = solve_ivp(rhs, (0.0, spec.horizon), s0, t_eval=grid, events=blowup, rtol=1e-8, atol=1e-10,
                        max_step=max_step)  # fmt: skip
    if sol.status != 0 or not np.all(np.isfinite(sol.y)):
        tf = float(sol.t[-1]) if sol.t.size else 0.0
        raise SimulationDiverged(f"{spec.where}: the state blew up at t = {tf:.6g} (not finite or |x| > 1e12)", tf)
    return sol


def _output_grid(spec: Any) -> np.ndarray:
    count = max(1, int(round(spec.horizon / spec.dt)))
    return np.linspace(0.0, spec.horizon, count + 1)


def _state_is_linear(fn: Any, linear: bool) -> bool:
    """True when the plant's nonlinearity is absent (dropped by ``linear``, or none in the section)."""
    return linear or not getattr(getattr(fn, "spec", None), "f", True)


def _lti_run(
    A: np.ndarray, B: np.ndarray, s0: np.ndarray, signal: TimeSignal, spec: Any
) -> tuple[np.ndarray, np.ndarray]:
    """``(t, s)`` on the output grid for ``s' = A s + B v(t)`` (:func:`lmic.simulate.lti.propagate`).

    The same grid, and the same blow-up rule and message, as :func:`_ct_run`.
    """
    grid = _output_grid(spec)
    S = propagate(A, B, np.asarray(s0, dtype=float), grid, signal)
    with np.errstate(all="ignore"):
        bad = ~np.all(np.isfinite(S), axis=1) | (np.max(np.abs(S), axis=1, initial=0.0) > 1e12)
    if bad.any():
        tf = float(grid[int(np.argmax(bad))])
        raise SimulationDiverged(f"{spec.where}: the state blew up at t = {tf:.6g} (not finite or |x| > 1e12)", tf)
    return grid, S
