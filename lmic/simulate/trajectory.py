"""A simulated run (:class:`Trajectory`): times, true and estimated states, error statistics.

Split out of :mod:`lmic.simulate.run`, which re-exports it.

Examples
--------
>>> import numpy as np
>>> tr = Trajectory(np.array([0.0, 1.0]), np.ones((2, 1)), np.zeros((2, 1)), "luenberger", "discrete")
>>> tr.final_error
1.0
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["Trajectory", "DECAY_RATIO"]

#: the error *decayed* when its mean over the last 10 % of the horizon is at most this
#: fraction of its peak
DECAY_RATIO = 0.1


@dataclass
class Trajectory:
    """A simulated run: times, true and estimated states, and error statistics.

    Attributes
    ----------
    t : ndarray, shape (K,)
    x, xhat : ndarray, shape (K, n)
    model, time : str
        The observer model and its time (``discrete``, ``continuous``, ``sampled``).
    samples : ndarray or None
        Measurement instants of a sampled observer.
    """

    t: np.ndarray
    x: np.ndarray
    xhat: np.ndarray
    model: str
    time: str
    samples: np.ndarray | None = None
    info: dict[str, Any] = field(default_factory=dict)
    #: further signals by name (``w``, ``z`` performance output, ``nu`` / ``nu_hat``, ``u``...)
    signals: dict[str, np.ndarray] = field(default_factory=dict)
    #: certificate-meets-trajectory checks (:mod:`lmic.simulate.certificate`)
    checks: list[dict[str, Any]] = field(default_factory=list)

    @property
    def error_norm(self) -> np.ndarray:
        """``|x - xhat|`` at every time."""
        return np.linalg.norm(self.x - self.xhat, axis=1)

    @property
    def initial_error(self) -> float:
        """``|e(0)|``."""
        return float(self.error_norm[0])

    @property
    def final_error(self) -> float:
        """``|e(T)|``."""
        return float(self.error_norm[-1])

    @property
    def peak_error(self) -> float:
        """``max_t |e(t)|``."""
        return float(self.error_norm.max())

    @property
    def tail_error(self) -> float:
        """Mean of ``|e|`` over the last 10 % of the horizon."""
        t = self.t
        tail = self.error_norm[t >= t[0] + 0.9 * (t[-1] - t[0])]
        return float(tail.mean()) if tail.size else self.final_error

    @property
    def decayed(self) -> bool:
        """Whether the error's tail mean is at most :data:`DECAY_RATIO` of its peak."""
        peak = self.peak_error
        return peak == 0.0 or self.tail_error <= DECAY_RATIO * peak

    def summary(self) -> dict[str, Any]:
        """A JSON-ready summary (no arrays)."""
        return {
            "model": self.model,
            "time": self.time,
            "horizon": float(self.t[-1] - self.t[0]),
            "points": int(self.t.size),
            "samples": None if self.samples is None else int(self.samples.size),
            "initial_error": self.initial_error,
            "peak_error": self.peak_error,
            "final_error": self.final_error,
            "tail_error": self.tail_error,
            "decayed": self.decayed,
            **self.info,
            "checks": self.checks,
        }
