"""The ``euler`` observer family (:class:`Euler`; the catalogue is :mod:`lmic.simulate.families`).

``euler`` (discrete) — Abbaszadeh & Marquez (sampled_euler): the observer of the Euler model
    ``x^+ = (I + T A) x^ + T f(x^) + L (y_k - C x^)`` run at period ``T`` against the
    continuous plant ``x' = A x + f(x) + D1 w`` integrated exactly between samples. Roles
    ``A, C, L, T``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from lmic.errors import DataError
from lmic.simulate.custom import Custom, Signal
from lmic.simulate.models import SimulationDiverged

__all__ = ["Euler"]


class Euler(Custom):
    """Discrete observer of the Euler model run at period T against the exact continuous plant."""

    name = "euler"
    times = ("discrete",)
    required = ("A", "C", "L", "T")
    optional = ("D1",)
    extra = ("disturbance",)

    def _check(self) -> None:
        self._shape("L", (self.n, self.p))
        self.L = self.mats["L"]
        self.T = float(self.mats["T"].ravel()[0])
        if not self.T > 0:
            raise DataError(f"observer model 'euler': the period T ('{self.names['T']}') must be positive")
        self.D1w = self.mats.get("D1", np.zeros((self.n, 0)))
        self.D1 = None
        self.Ad = np.eye(self.n) + self.T * self.A

    def custom_run(self, spec: Any, fn: Any, *, w: Signal | None = None, linear: bool = False,
                   zero: bool = False, nominal: bool = False) -> dict[str, Any]:  # fmt: skip
        from scipy.integrate import solve_ivp

        if abs(spec.dt - self.T) > 1e-9 * self.T:
            raise DataError(f"{spec.where}: dt = {spec.dt:g} must equal the observer's sampling period T = {self.T:g}")
        steps = max(1, int(round(spec.horizon / spec.dt)))
        t = np.arange(steps + 1) * self.T
        wf = w if w is not None else self.disturbance(spec)
        f = (lambda x, u, tt: np.zeros(self.n)) if linear else fn.f
        x = np.zeros(self.n) if zero else spec.x0.copy()
        xh = np.zeros(self.n) if (zero or spec.xhat0 is None) else spec.xhat0.copy()
        noise = np.zeros((steps + 1, self.p))
        if spec.noise_std is not None and not zero:
            noise = np.random.default_rng(spec.noise_seed).standard_normal((steps + 1, self.p)) * spec.noise_std
        X = np.empty((steps + 1, self.n))
        XH = np.empty_like(X)
        for k in range(steps + 1):
            tk = float(t[k])
            X[k], XH[k] = x, xh
            if k == steps:
                break
            u = fn.u(tk)
            y = self.C @ x + noise[k]

            def rhs(tt: float, s: np.ndarray) -> np.ndarray:
                return self.A @ s + f(s, fn.u(tt), tt) + self.D1w @ wf(tt)

            with np.errstate(all="ignore"):
                sol = solve_ivp(rhs, (tk, tk + self.T), x, rtol=1e-9, atol=1e-12)
            if sol.status != 0 or not np.all(np.isfinite(sol.y[:, -1])) or np.abs(sol.y[:, -1]).max() > 1e12:
                raise SimulationDiverged(f"{spec.where}: the plant state blew up at t = {tk:.6g}", tk)
            xh = self.Ad @ xh + self.T * f(xh, u, tk) + self.L @ (y - self.C @ xh)
            x = sol.y[:, -1]
        return {"t": t, "x": X, "xhat": XH, "signals": {}, "info": {"period": self.T}}
