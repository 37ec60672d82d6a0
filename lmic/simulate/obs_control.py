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
from lmic.simulate.custom import Custom, Signal, _ct_run, _lti_run, _state_is_linear
from lmic.simulate.lti import expression_signal
from lmic.simulate.parser import parse_vector

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
        mu = expression_signal(spec.extra.get("mu", []), self.Eu.shape[1])

        def f(x: np.ndarray, u: np.ndarray, t: float) -> np.ndarray:
            return np.zeros(n) if linear else fn.f(x, u, t)

        x0 = spec.x0
        xh0 = np.zeros(n) if spec.xhat0 is None else spec.xhat0

        s0 = np.concatenate([x0, xh0])
        if _state_is_linear(fn, linear):
            # no nonlinearity: [x; x^]' = Acl [x; x^] + [E; 0] mu integrated exactly (lmic.simulate.lti)
            BK, LC = self.B @ self.K, self.L @ self.C
            A = np.block([[self.A, -BK], [LC, self.A - BK - LC]])
            Bmu = np.vstack([self.Eu, np.zeros_like(self.Eu)])
            t, S = _lti_run(A, Bmu, s0, mu, spec)
        else:

            def rhs(t: float, s: np.ndarray) -> np.ndarray:
                x, xh = s[:n], s[n:]
                u = -self.K @ xh
                y = self.C @ x
                dx = self.A @ x + self.B @ u + f(x, u, t) + self.Eu @ mu(t)
                dxh = self.A @ xh + self.B @ u + f(xh, u, t) + self.L @ (y - self.C @ xh)
                return np.concatenate([dx, dxh])

            sol = _ct_run(rhs, s0, spec, spec.dt)
            t, S = sol.t, sol.y.T
        X, XH = S[:, :n], S[:, n:]
        U = -(XH @ self.K.T)
        MU = mu.on(t)
        return {"t": t, "x": X, "xhat": XH, "signals": {"u": U, "mu": MU}, "info": {}}
