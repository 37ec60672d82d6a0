"""The ``robust`` observer family (:class:`Robust`; the catalogue is :mod:`lmic.simulate.families`).

``robust`` (discrete) — Luenberger observer ``x^+ = A x^ + f(x^) + L (y - C x^)`` against an
    uncertain plant with a time-varying state (and output) delay,
    ``x+ = (A + MA F NF) x + (Ad + MAd F NF) x(k - tau) + f(x) + D1 w``,
    ``y = (C + MC F NF) x + (Cd + MCd F NF) x(k - tau) + D2 w``, performance ``z = Hz e``
    (``delay_a``, ``delay_b``, ``uncertain_dt``). Roles ``A, C, L``; optional ``Ad, Cd, D1,
    D2, MA, MAd, MC, MCd, NF, Hz``, the certified L2 gain ``gamma`` and decay rate ``decay``,
    and the delay bounds ``tau1, tau2``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from lmic.errors import DataError
from lmic.simulate.custom import Custom, Signal, _scalar, _zeros
from lmic.simulate.models import SimulationDiverged
from lmic.simulate.parser import Expression, parse, parse_vector

__all__ = ["Robust"]


class Robust(Custom):
    """Luenberger observer against an uncertain DT plant with a time-varying delay."""

    name = "robust"
    times = ("discrete",)
    required = ("A", "C", "L")
    optional = ("Ad", "Cd", "D1", "D2", "MA", "MAd", "MC", "MCd", "NF", "Hz", "gamma", "decay", "tau0", "tau1", "tau2")
    extra = ("disturbance", "uncertainty", "delay", "history")

    def _check(self) -> None:
        n, p = self.n, self.p
        self._shape("L", (n, p))
        self.L = self.mats["L"]
        g = self.mats.get
        self.Ad = g("Ad", np.zeros((n, n)))
        self.Cd = g("Cd", np.zeros((p, n)))
        if "Ad" in self.mats:
            self._shape("Ad", (n, n))
        if "Cd" in self.mats:
            self._shape("Cd", (p, n))
        nw = self.w_dim
        self.D1w = g("D1", np.zeros((n, nw)))
        self.D2w = g("D2", np.zeros((p, nw)))
        self.D1 = None  # the base plant's unknown input is not used here
        self.NF = g("NF")
        r = 0 if self.NF is None else None
        if self.NF is not None:
            r = next((int(m.shape[1]) for m in (g(k) for k in ("MA", "MAd", "MC", "MCd")) if m is not None), 0)
        self.r = int(r or 0)
        self.s = 0 if self.NF is None else int(self.NF.shape[0])
        self.MA = g("MA", np.zeros((n, self.r)))
        self.MAd = g("MAd", np.zeros((n, self.r)))
        self.MC = g("MC", np.zeros((p, self.r)))
        self.MCd = g("MCd", np.zeros((p, self.r)))
        self.Hz = g("Hz", np.eye(n))
        self.tau1 = int(round(_scalar(self, "tau1") or 0.0))
        self.tau2 = int(round(_scalar(self, "tau2") or 0.0))
        tau0 = int(round(_scalar(self, "tau0") or 0.0))
        if tau0 > self.tau2 - self.tau1 + 1:  # tau0 given alone: any window of tau0 delays
            self.tau2 = self.tau1 + tau0 - 1
        self.has_delay = "Ad" in self.mats or "Cd" in self.mats

    def read_extra(self, sec: Mapping[str, Any], where: str) -> dict[str, Any]:
        """``disturbance`` (in ``t``, ``k`` and the state ``x1..xn``), ``uncertainty`` (F(k) row by
        row, or ``{seed}``), ``delay`` (an expression in ``t``, ``k``, or a cyclic list of whole
        numbers of steps), ``history`` (``x(k)`` for ``k < 0``)."""
        sec = dict(sec)
        dist = sec.pop("disturbance", None)
        out = super().read_extra(sec, where)
        if dist is not None:
            texts = dist if isinstance(dist, list) else [dist]
            if len(texts) != self.w_dim:
                raise DataError(
                    f"{where}.disturbance: has {len(texts)} entries, the model has {self.w_dim} disturbance(s)"
                )
            names = {"t", "k"} | {f"x{i + 1}" for i in range(self.n)}
            out["w"] = parse_vector(texts, names, f"{where}.disturbance")
        if "uncertainty" in sec:
            if self.NF is None:
                raise DataError(f"{where}.uncertainty: this theorem declares no uncertainty (role NF)")
            unc = sec["uncertainty"]
            if isinstance(unc, dict):
                bad = [k for k in unc if k != "seed"]
                if bad or not isinstance(unc.get("seed", 0), int):
                    raise DataError(f"{where}.uncertainty: a mapping must be {{seed: <integer>}}")
                out["F_seed"] = int(unc.get("seed", 0))
            else:
                texts = unc if isinstance(unc, list) else [unc]
                if len(texts) != self.r * self.s:
                    raise DataError(
                        f"{where}.uncertainty: has {len(texts)} entries, F is {self.r}x{self.s} "
                        f"({self.r * self.s} entries, row by row)"
                    )
                out["F"] = parse_vector(texts, {"t", "k"}, f"{where}.uncertainty")
        if "delay" in sec:
            if not self.has_delay:
                raise DataError(f"{where}.delay: this theorem's plant has no delayed term (roles Ad, Cd)")
            if isinstance(sec["delay"], list):
                vals = sec["delay"]
                if not vals or not all(isinstance(v, int) and not isinstance(v, bool) for v in vals):
                    raise DataError(f"{where}.delay: a list must hold whole numbers of steps (repeated cyclically)")
                out["tau_list"] = [int(v) for v in vals]
            else:
                out["tau"] = parse(sec["delay"], {"t", "k"}, f"{where}.delay")
        if "history" in sec:
            if not self.has_delay:
                raise DataError(f"{where}.history: this theorem's plant has no delayed term (roles Ad, Cd)")
            h = np.asarray(sec["history"], dtype=float) if isinstance(sec["history"], list) else None
            if h is None or h.shape != (self.n,) or not np.all(np.isfinite(h)):
                raise DataError(f"{where}.history: expected {self.n} numbers (x(k) for k < 0)")
            out["history"] = h
        return out

    def _F(self, spec: Any, steps: int, nominal: bool) -> np.ndarray:
        """``F(k)`` for every step, ``(steps + 1, r, s)``, checked ``||F(k)|| <= 1``."""
        r, s = self.r, self.s
        out = np.zeros((steps + 1, r, s))
        if nominal or self.NF is None:
            return out
        if "F_seed" in spec.extra:
            rng = np.random.default_rng(spec.extra["F_seed"])
            for k in range(steps + 1):
                F = rng.uniform(-1.0, 1.0, (r, s))
                out[k] = F / max(1.0, float(np.linalg.norm(F, 2)))
            return out
        exprs = spec.extra.get("F")
        if not exprs:
            return out
        for k in range(steps + 1):
            env = {"t": k * spec.dt, "k": float(k)}
            out[k] = np.array([float(e.evaluate(env)) for e in exprs]).reshape(r, s)
            norm = float(np.linalg.norm(out[k], 2))
            if not np.isfinite(norm) or norm > 1.0 + 1e-12:
                raise DataError(
                    f"{spec.where}.uncertainty: ||F(k)|| = {norm:.4g} > 1 at k = {k} (the theorem needs ||F|| <= 1)"
                )
        return out

    def _tau(self, spec: Any, steps: int) -> np.ndarray:
        if not self.has_delay:
            return np.zeros(steps + 1, dtype=int)
        expr = spec.extra.get("tau")
        cyc = spec.extra.get("tau_list")
        if expr is None and cyc is None:
            return np.full(steps + 1, self.tau2, dtype=int)
        out = np.empty(steps + 1, dtype=int)
        for k in range(steps + 1):
            v = float(cyc[k % len(cyc)]) if cyc else float(expr.evaluate({"t": k * spec.dt, "k": float(k)}))
            if not np.isfinite(v) or abs(v - round(v)) > 1e-9:
                raise DataError(f"{spec.where}.delay: tau({k}) = {v:g} is not a whole number of steps")
            tau = int(round(v))
            if not self.tau1 <= tau <= self.tau2:
                raise DataError(
                    f"{spec.where}.delay: tau({k}) = {tau} is outside the certified range [{self.tau1}, {self.tau2}]"
                )
            out[k] = tau
        return out

    def custom_run(self, spec: Any, fn: Any, *, w: Signal | None = None, linear: bool = False,
                   zero: bool = False, nominal: bool = False) -> dict[str, Any]:  # fmt: skip
        steps = max(1, int(round(spec.horizon / spec.dt)))
        t = np.arange(steps + 1) * spec.dt
        F = self._F(spec, steps, nominal)
        tau = self._tau(spec, steps)
        wx = None if w is not None else self._state_disturbance(spec)
        wf = w if w is not None else self.disturbance(spec)
        f = (lambda x, u, tt: np.zeros(self.n)) if linear else fn.f
        n = self.n
        x = np.zeros(n) if zero else spec.x0.copy()
        hist = np.zeros(n) if zero else spec.extra.get("history", x.copy())
        xh = np.zeros(n) if (zero or spec.xhat0 is None) else spec.xhat0.copy()
        noise = np.zeros((steps + 1, self.p))
        if spec.noise_std is not None and not zero:
            noise = np.random.default_rng(spec.noise_seed).standard_normal((steps + 1, self.p)) * spec.noise_std
        X = np.empty((steps + 1, n))
        XH = np.empty_like(X)
        W = np.empty((steps + 1, self.w_dim))
        for k in range(steps + 1):
            tk = float(t[k])
            X[k] = x  # before the delayed state is read: tau(k) = 0 reads x(k) itself
            xd = X[k - tau[k]] if k - tau[k] >= 0 else hist
            Fk = F[k]
            NF = self.NF if self.NF is not None else np.zeros((0, n))
            wk = wx(tk, x) if wx is not None else wf(tk)
            y = (self.C + self.MC @ Fk @ NF) @ x + (self.Cd + self.MCd @ Fk @ NF) @ xd + self.D2w @ wk + noise[k]
            X[k], XH[k], W[k] = x, xh, wk
            if (
                not (np.all(np.isfinite(x)) and np.all(np.isfinite(xh)))
                or max(np.abs(x).max(), np.abs(xh).max()) > 1e12
            ):
                raise SimulationDiverged(f"{spec.where}: the state blew up at t = {tk:.6g}", tk)
            if k == steps:
                break
            u = fn.u(tk)
            x_next = (
                (self.A + self.MA @ Fk @ NF) @ x + (self.Ad + self.MAd @ Fk @ NF) @ xd + f(x, u, tk) + self.D1w @ wk
            )
            xh = self.A @ xh + f(xh, u, tk) + self.L @ (y - self.C @ xh)
            x = x_next
        Z = (X - XH) @ self.Hz.T
        info = {
            "max_delay": int(tau.max()),
            "max_norm_F": float(max(np.linalg.norm(Fk, 2) for Fk in F)) if self.r else 0.0,
        }
        return {"t": t, "x": X, "xhat": XH, "signals": {"w": W, "z": Z}, "info": info}

    def _state_disturbance(self, spec: Any) -> Callable[[float, np.ndarray], np.ndarray] | None:
        exprs: list[Expression] = spec.extra.get("w", [])
        if not exprs:
            return None
        xn = [f"x{i + 1}" for i in range(self.n)]
        dt = spec.dt

        def w(t: float, x: np.ndarray) -> np.ndarray:
            env = {"t": t, "k": t / dt, **dict(zip(xn, x, strict=True))}
            return np.array([float(e.evaluate(env)) for e in exprs])

        return w

    def disturbance(self, spec: Any) -> Signal:
        """``w(t)`` along the zero state (a disturbance reading the state is not a fixed signal)."""
        wx = self._state_disturbance(spec)
        if wx is None:
            return _zeros(self.w_dim)
        zero = np.zeros(self.n)
        return lambda t: wx(t, zero)

    def gain_system(self) -> tuple[Callable[[float], np.ndarray], str] | None:
        if "gamma" not in self.mats or self.w_dim == 0:
            return None
        n, A, Ad, LC = self.n, self.A, self.Ad, self.L @ self.C
        tau = self.tau2

        def G(om: float) -> np.ndarray:
            zq = np.exp(1j * om)
            d = zq ** (-tau)
            X = np.linalg.solve(zq * np.eye(n) - A - Ad * d, self.D1w)
            E = np.linalg.solve(
                zq * np.eye(n) - (A - LC), (Ad - self.L @ self.Cd) * d @ X + self.D1w - self.L @ self.D2w
            )
            return self.Hz @ E

        return G, "discrete"
