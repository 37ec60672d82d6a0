"""The ``obs_control`` observer family (:class:`ObsControl`; the catalogue is :mod:`lmic.simulate.families`).

``obs_control`` (continuous) — observer-based control (Paper F): ``x' = A x + B u + f(x) + E mu``,
    ``x^' = A x^ + B u + f(x^) + L (y - C x^)``, ``u = -K x^``. Roles ``A, B, C, K, L``;
    optional ``E`` and the practical-stability radius ``alpha``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from lmic.errors import DataError
from lmic.simulate.custom import Custom, Signal, _ct_run
from lmic.simulate.parser import Expression, parse_vector

__all__ = ["ObsControl"]


class ObsControl(Custom):
    """Plant, observer and ``u = -K x^`` in closed loop; unknown input ``mu`` through ``E``."""

    name = "obs_control"
    times = ("continuous",)
    required = ("A", "B", "C", "K", "L")
    optional = ("E", "alpha")

    def _check(self) -> None:
        n, p, m = self.n, self.p, self.m
        self._shape("K", (m, n))
        self._shape("L", (n, p))
        self.K, self.L = self.mats["K"], self.mats["L"]
        self.Eu = self.mats.get("E", np.zeros((n, 0)))
        if "E" in self.mats:
            self._shape("E", (n, self.Eu.shape[1]))

    def read_extra(self, sec: Mapping[str, Any], where: str) -> dict[str, Any]:
        out = super().read_extra(sec, where)
        if "input" in sec:
            raise DataError(f"{where}.input: the input is the feedback u = -K xhat (remove 'input')")
        if "unknown_input" in sec:
            texts = sec["unknown_input"] if isinstance(sec["unknown_input"], list) else [sec["unknown_input"]]
            if len(texts) != self.Eu.shape[1]:
                raise DataError(f"{where}.unknown_input: has {len(texts)} entries, E has {self.Eu.shape[1]} column(s)")
            out["mu"] = parse_vector(texts, {"t"}, f"{where}.unknown_input")
        return out

    def custom_run(self, spec: Any, fn: Any, *, w: Signal | None = None, linear: bool = False,
                   zero: bool = False, nominal: bool = False) -> dict[str, Any]:  # fmt: skip
        n = self.n
        mu_ex: list[Expression] = spec.extra.get("mu", [])

        def mu(t: float) -> np.ndarray:
            return np.array([float(e.evaluate({"t": t})) for e in mu_ex]) if mu_ex else np.zeros(self.Eu.shape[1])

        def f(x: np.ndarray, u: np.ndarray, t: float) -> np.ndarray:
            return np.zeros(n) if linear else fn.f(x, u, t)

        x0 = spec.x0
        xh0 = np.zeros(n) if spec.xhat0 is None else spec.xhat0

        def rhs(t: float, s: np.ndarray) -> np.ndarray:
            x, xh = s[:n], s[n:]
            u = -self.K @ xh
            y = self.C @ x
            dx = self.A @ x + self.B @ u + f(x, u, t) + self.Eu @ mu(t)
            dxh = self.A @ xh + self.B @ u + f(xh, u, t) + self.L @ (y - self.C @ xh)
            return np.concatenate([dx, dxh])

        sol = _ct_run(rhs, np.concatenate([x0, xh0]), spec, spec.dt)
        X, XH = sol.y[:n].T, sol.y[n:].T
        U = -(XH @ self.K.T)
        MU = np.array([mu(tk) for tk in sol.t]).reshape(sol.t.size, -1)
        return {"t": sol.t, "x": X, "xhat": XH, "signals": {"u": U, "mu": MU}, "info": {}}
