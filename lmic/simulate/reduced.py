"""The ``reduced`` observer family (:class:`Reduced`; the catalogue is :mod:`lmic.simulate.families`).

``reduced`` (discrete) — Wang, Song & Zhang (2015) (18), ``qib.thm2`` / ``qib.cor2``
    ``z^+ = A_Z z^ + B_Z y + H f(x^) + K (y(k+1) - C zeta)``,
    ``zeta = A N z^ + A M y + f(x^)``, ``x^ = N z^ + M y`` with ``A_Z = H A N``,
    ``B_Z = H A M``; the plant is ``x+ = A x + f(x, u)`` (a known input enters through f).
    Roles ``A, C, H, N, M, K``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from lmic.errors import DataError
from lmic.simulate.custom import Custom, Signal
from lmic.simulate.models import SimulationDiverged

__all__ = ["Reduced"]


class Reduced(Custom):
    """Reduced-order observer (18) of Wang, Song & Zhang in the coordinates ``z = H x``."""

    name = "reduced"
    times = ("discrete",)
    required = ("A", "C", "H", "N", "M", "K")
    optional = ()

    def _check(self) -> None:
        n, p = self.n, self.p
        k = n - p
        for role, shape in (("H", (k, n)), ("N", (n, k)), ("M", (n, p)), ("K", (k, p))):
            self._shape(role, shape)
        self.H, self.N, self.M, self.K = (self.mats[r] for r in ("H", "N", "M", "K"))
        T = np.vstack([self.H, self.C])
        if np.max(np.abs(T @ np.hstack([self.N, self.M]) - np.eye(n))) > 1e-8 * max(1.0, float(np.abs(T).max())):
            raise DataError(
                f"observer model 'reduced': [N M] ('{self.names['N']}', '{self.names['M']}') is not [H; C]^-1"
            )
        self.AZ = self.H @ self.A @ self.N
        self.BZ = self.H @ self.A @ self.M

    def custom_run(self, spec: Any, fn: Any, *, w: Signal | None = None, linear: bool = False,
                   zero: bool = False, nominal: bool = False) -> dict[str, Any]:  # fmt: skip
        steps = max(1, int(round(spec.horizon / spec.dt)))
        t = np.arange(steps + 1) * spec.dt
        f = (lambda x, u, tt: np.zeros(self.n)) if linear else fn.f
        x = np.zeros(self.n) if zero else spec.x0.copy()
        xh0 = np.zeros(self.n) if (zero or spec.xhat0 is None) else spec.xhat0
        zh = self.H @ xh0
        X = np.empty((steps + 1, self.n))
        XH = np.empty_like(X)
        y = self.C @ x
        for k in range(steps + 1):
            tk = float(t[k])
            xh = self.N @ zh + self.M @ y
            X[k], XH[k] = x, xh
            if k == steps:
                break
            u = fn.u(tk)
            fx = f(x, u, tk)
            x = self.A @ x + fx
            y_next = self.C @ x
            fh = f(xh, u, tk)
            zeta = self.A @ xh + fh
            zh = self.AZ @ zh + self.BZ @ y + self.H @ fh + self.K @ (y_next - self.C @ zeta)
            y = y_next
            if not (np.all(np.isfinite(x)) and np.all(np.isfinite(zh))):
                raise SimulationDiverged(
                    f"{spec.where}: the state blew up at t = {float(t[k + 1]):.6g}", float(t[k + 1])
                )
        return {"t": t, "x": X, "xhat": XH, "signals": {}, "info": {}}
