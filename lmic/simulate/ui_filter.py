"""The ``ui_filter`` observer family (:class:`UIFilter`; the catalogue is :mod:`lmic.simulate.families`).

``ui_filter`` (continuous) — reduced-order filter of a descriptor plant with unknown inputs
    (Papers D and E of the Delshad thesis, ``descriptor``, ``uir``): plant
    ``x' = A x + B u + f(x) + D1 w + F nu``, ``y = C x + D2 w + G nu`` (the slow, consistent
    subsystem of ``E zeta' = Abar zeta + ...``, ``zeta = [x; nu]``), filter
    ``z' = N z + L y + Gf u + M f(x^)``, ``zeta^ = J z + E y = [x^; nu^]``. Roles ``A, C, F,
    G, N, L, M, J, E``; optional ``B, Gf, D1, D2``, certified gain ``gamma``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from lmic.simulate.custom import Custom, Signal, _ct_run, _lti_run, _read_time_vector, _state_is_linear, _time_signal
from lmic.simulate.lti import as_signal, expression_signal, stack

__all__ = ["UIFilter"]


class UIFilter(Custom):
    """Reduced-order filter ``z' = N z + L y + Gf u + M f(x^)``, ``[x^; nu^] = J z + E y``."""

    name = "ui_filter"
    times = ("continuous",)
    required = ("A", "C", "F", "G", "N", "L", "M", "J", "E")
    optional = ("B", "Gf", "D1", "D2", "gamma")
    extra = ("disturbance",)

    def _check(self) -> None:
        n, p = self.n, self.p
        self.F = self.mats["F"]
        h = self.F.shape[1]
        self.h = h
        self._shape("F", (n, h))
        self._shape("G", (p, h))
        q1 = self.mats["N"].shape[0]
        for role, shape in (("N", (q1, q1)), ("L", (q1, p)), ("M", (q1, n)), ("J", (n + h, q1)), ("E", (n + h, p))):
            self._shape(role, shape)
        self.G, self.N, self.L, self.M, self.J, self.E = (self.mats[r] for r in ("G", "N", "L", "M", "J", "E"))
        self.q1 = q1
        nw = self.w_dim
        self.D1w = self.mats.get("D1", np.zeros((n, nw)))
        self.D2w = self.mats.get("D2", np.zeros((p, nw)))
        self.D1 = None
        Gf = self.mats.get("Gf")
        self.Gf = Gf if Gf is not None else (self.M @ self.B if self.B is not None else None)

    def read_extra(self, sec: Mapping[str, Any], where: str) -> dict[str, Any]:
        out = super().read_extra(sec, where)
        if "unknown_input" in sec:
            what = f"the plant has {self.h} unknown input(s)"
            out["nu"] = _read_time_vector(sec, "unknown_input", self.h, what, where)
        return out

    def custom_run(self, spec: Any, fn: Any, *, w: Signal | None = None, linear: bool = False,
                   zero: bool = False, nominal: bool = False) -> dict[str, Any]:  # fmt: skip
        n, q1 = self.n, self.q1
        wf = w if w is not None else self.disturbance(spec)
        nu = _time_signal(spec.extra.get("nu", []), self.h)

        f = (lambda x, u, tt: np.zeros(n)) if linear else fn.f
        x0 = np.zeros(n) if zero else spec.x0
        # z(0): given, else M x0 + (the initial estimate's offset) -- zero: eps(0) = z - M x = 0
        if zero:
            z0 = self.M @ x0
        elif spec.z0 is not None:
            z0 = spec.z0
        else:
            z0 = np.zeros(q1)

        s0 = np.concatenate([x0, z0])
        if _state_is_linear(fn, linear):
            # no nonlinearity: s' = Acl s + Bcl [w; nu; u] integrated exactly (lmic.simulate.lti)
            ws, nus = as_signal(wf, self.w_dim), as_signal(nu, self.h)
            A = np.block([[self.A, np.zeros((n, q1))], [self.L @ self.C, self.N]])
            cols = [np.vstack([self.D1w, self.L @ self.D2w]), np.vstack([self.F, self.L @ self.G])]
            sigs = [ws, nus]
            if self.B is not None:
                assert self.Gf is not None  # set from B when not given
                cols.append(np.vstack([self.B, self.Gf]))
                sigs.append(expression_signal(fn.spec.u, len(fn.spec.u)))
            t, S = _lti_run(A, np.hstack(cols), s0, stack(sigs), spec)
            X, Zs = S[:, :n], S[:, n:]
            W, NU = ws.on(t), nus.on(t)
        else:

            def rhs(t: float, s: np.ndarray) -> np.ndarray:
                x, z = s[:n], s[n:]
                u, w_t, nu_t = fn.u(t), wf(t), nu(t)  # each signal evaluated once per step
                y = self.C @ x + self.D2w @ w_t + self.G @ nu_t
                zeta = self.J @ z + self.E @ y
                dx = self.A @ x + f(x, u, t) + self.D1w @ w_t + self.F @ nu_t
                dz = self.N @ z + self.L @ y + self.M @ f(zeta[:n], u, t)
                if self.B is not None:
                    dx = dx + self.B @ u
                    dz = dz + self.Gf @ u
                return np.concatenate([dx, dz])

            sol = _ct_run(rhs, s0, spec, spec.dt)
            t, X, Zs = sol.t, sol.y[:n].T, sol.y[n:].T
            W = np.array([wf(tk) for tk in t]).reshape(t.size, -1)
            NU = np.array([nu(tk) for tk in t]).reshape(t.size, -1)
        Y = X @ self.C.T + W @ self.D2w.T + NU @ self.G.T
        ZETA = Zs @ self.J.T + Y @ self.E.T
        E = np.hstack([X, NU]) - ZETA
        return {
            "t": t,
            "x": X,
            "xhat": ZETA[:, :n],
            "signals": {"w": W, "z": E, "nu": NU, "nu_hat": ZETA[:, n:]},
            "info": {},
        }

    def gain_system(self) -> tuple[Callable[[float], np.ndarray], str] | None:
        if "gamma" not in self.mats or self.w_dim == 0:
            return None
        Bw = self.L @ self.D2w - self.M @ self.D1w
        Dw = self.E @ self.D2w

        def G(om: float) -> np.ndarray:
            return self.J @ np.linalg.solve(1j * om * np.eye(self.q1) - self.N, Bw) + Dw

        return G, "continuous"
