"""Observer models with their own simulation loop: one per observer family of the source papers.

The models of :mod:`lmic.simulate.models` share one plant and one loop; the families here each
need their own (a delay line, an uncertainty realisation, reduced coordinates, a continuous
plant sampled at the period of a discrete observer, a descriptor plant with unknown inputs, a
closed loop). Each model implements :meth:`Custom.custom_run` (the trajectory for a
``simulation:`` section) and, where the theorem certifies a number, :meth:`Custom.checks`
(see :mod:`lmic.simulate.certificate`).

``reduced`` (discrete) — Wang, Song & Zhang (2015) (18), ``qib.thm2`` / ``qib.cor2``
    ``z^+ = A_Z z^ + B_Z y + H f(x^) + K (y(k+1) - C zeta)``,
    ``zeta = A N z^ + A M y + f(x^)``, ``x^ = N z^ + M y`` with ``A_Z = H A N``,
    ``B_Z = H A M``; the plant is ``x+ = A x + f(x, u)`` (a known input enters through f).
    Roles ``A, C, H, N, M, K``.
``robust`` (discrete) — Luenberger observer ``x^+ = A x^ + f(x^) + L (y - C x^)`` against an
    uncertain plant with a time-varying state (and output) delay,
    ``x+ = (A + MA F NF) x + (Ad + MAd F NF) x(k - tau) + f(x) + D1 w``,
    ``y = (C + MC F NF) x + (Cd + MCd F NF) x(k - tau) + D2 w``, performance ``z = Hz e``
    (``delay_a``, ``delay_b``, ``uncertain_dt``). Roles ``A, C, L``; optional ``Ad, Cd, D1,
    D2, MA, MAd, MC, MCd, NF, Hz``, the certified L2 gain ``gamma`` and decay rate ``decay``,
    and the delay bounds ``tau1, tau2``.
``euler`` (discrete) — Abbaszadeh & Marquez (sampled_euler): the observer of the Euler model
    ``x^+ = (I + T A) x^ + T f(x^) + L (y_k - C x^)`` run at period ``T`` against the
    continuous plant ``x' = A x + f(x) + D1 w`` integrated exactly between samples. Roles
    ``A, C, L, T``.
``ui_filter`` (continuous) — reduced-order filter of a descriptor plant with unknown inputs
    (Papers D and E of the Delshad thesis, ``descriptor``, ``uir``): plant
    ``x' = A x + B u + f(x) + D1 w + F nu``, ``y = C x + D2 w + G nu`` (the slow, consistent
    subsystem of ``E zeta' = Abar zeta + ...``, ``zeta = [x; nu]``), filter
    ``z' = N z + L y + Gf u + M f(x^)``, ``zeta^ = J z + E y = [x^; nu^]``. Roles ``A, C, F,
    G, N, L, M, J, E``; optional ``B, Gf, D1, D2``, certified gain ``gamma``.
``filter_error`` (continuous, discrete) — the error system of a filter alone, for the analysis
    theorems that give the filter but not the plant: ``eps' | eps+ = N eps + (L D2 - M D1) w``,
    ``e = J eps + E D2 w`` (the Lipschitz term vanishes on the linear part). Role ``N``;
    optional ``J`` (default I), ``L, M, E, D1, D2, gamma``. The section's ``x0`` is ``eps(0)``.
``obs_control`` (continuous) — observer-based control (Paper F): ``x' = A x + B u + f(x) + E mu``,
    ``x^' = A x^ + B u + f(x^) + L (y - C x^)``, ``u = -K x^``. Roles ``A, B, C, K, L``;
    optional ``E`` and the practical-stability radius ``alpha``.

Examples
--------
>>> import numpy as np
>>> from lmic.simulate.models import make_observer
>>> obs = make_observer("filter_error", "continuous", {"N": -np.eye(2), "J": np.eye(2)})
>>> obs.name, obs.n
('filter_error', 2)
"""

from __future__ import annotations

from abc import abstractmethod
from collections.abc import Callable, Mapping
from typing import Any, ClassVar

import numpy as np

from lmic.errors import DataError
from lmic.simulate.models import MODELS, Observer, SimulationDiverged, Vector
from lmic.simulate.parser import Expression, parse, parse_vector

__all__ = ["Custom", "Reduced", "Robust", "Euler", "UIFilter", "FilterError", "ObsControl", "EXTRA_KEYS"]

#: the ``simulation:`` keys only some of these models read
EXTRA_KEYS = ("disturbance", "uncertainty", "delay", "history")

Signal = Callable[[float], Vector]


def _zeros(size: int) -> Signal:
    z = np.zeros(size)
    return lambda t: z


def _time_signal(exprs: list[Expression], size: int) -> Signal:
    """``t -> [e(t) for e in exprs]`` (zero of ``size`` when there are none)."""
    if not exprs:
        return _zeros(size)
    return lambda t: np.array([float(e.evaluate({"t": t})) for e in exprs])


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


# -- reduced order (qib.thm2, qib.cor2) --------------------------------------------------------


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


# -- uncertain delay systems (delay_a, delay_b, uncertain_dt) -----------------------------------


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
            r = next((mk.shape[1] for k in ("MA", "MAd", "MC", "MCd") if (mk := g(k)) is not None), 0)
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


# -- sampled-data: Euler-model observer against the continuous plant ---------------------------


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


# -- descriptor plants with unknown inputs: reduced-order filters (descriptor, uir) -------------


def _ct_run(rhs: Callable[[float, np.ndarray], np.ndarray], s0: np.ndarray, spec: Any, max_step: float) -> Any:
    from scipy.integrate import solve_ivp

    count = max(1, int(round(spec.horizon / spec.dt)))
    grid = np.linspace(0.0, spec.horizon, count + 1)

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

        sol = _ct_run(rhs, np.concatenate([x0, z0]), spec, spec.dt)
        X = sol.y[:n].T
        Zs = sol.y[n:].T
        W = np.array([wf(tk) for tk in sol.t]).reshape(sol.t.size, -1)
        NU = np.array([nu(tk) for tk in sol.t]).reshape(sol.t.size, -1)
        Y = X @ self.C.T + W @ self.D2w.T + NU @ self.G.T
        ZETA = Zs @ self.J.T + Y @ self.E.T
        E = np.hstack([X, NU]) - ZETA
        return {
            "t": sol.t,
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


class FilterError(Custom):
    """The filter's error system ``eps' = N eps + (L D2 - M D1) w``, ``e = J eps + E D2 w``."""

    name = "filter_error"
    times = ("continuous", "discrete")
    required = ("N",)
    optional = ("A", "C", "J", "L", "M", "E", "gamma")
    extra = ("disturbance",)

    def __init__(self, time: str, mats: Mapping[str, Any], names: Mapping[str, str] | None = None) -> None:
        mats = dict(mats)
        names = dict(names or {})
        for role in self.required:
            if role not in mats:
                raise DataError(f"observer model '{self.name}' needs the role(s) {role}")
        # the plant's disturbance matrices have the plant's rows, not the error's: kept aside
        self._w = {r: np.atleast_2d(np.asarray(mats.pop(r), dtype=float)) for r in ("D1", "D2") if r in mats}
        # the base class's plant roles: the error eps is the "state", e = J eps the "output"
        N = np.atleast_2d(np.asarray(mats["N"], dtype=float))
        J = mats.get("J", np.eye(N.shape[0]))  # without J the error itself is the output
        super().__init__(time, {**mats, "A": N, "C": J}, {**names, "A": names.get("N", "N"), "C": names.get("J", "I")})

    def _check(self) -> None:
        q1 = self.n
        nw = self.w_dim
        Bw = np.zeros((q1, nw))
        try:
            if nw and "M" in self.mats and "D1" in self._w:
                Bw = Bw - self.mats["M"] @ self._w["D1"]
            if nw and "L" in self.mats and "D2" in self._w:
                Bw = Bw + self.mats["L"] @ self._w["D2"]
            Dw = np.zeros((self.p, nw))
            if nw and "E" in self.mats and "D2" in self._w:
                Dw = self.mats["E"] @ self._w["D2"]
        except ValueError as err:
            raise DataError(f"observer model 'filter_error': roles of inconsistent shapes ({err})") from None
        self.Bw, self.Dw = Bw, Dw

    @property
    def w_dim(self) -> int:
        D1, D2 = self._w.get("D1"), self._w.get("D2")
        if D1 is not None:
            return int(D1.shape[1])
        return 0 if D2 is None else int(D2.shape[1])

    def custom_run(self, spec: Any, fn: Any, *, w: Signal | None = None, linear: bool = False,
                   zero: bool = False, nominal: bool = False) -> dict[str, Any]:  # fmt: skip
        wf = w if w is not None else self.disturbance(spec)
        e0 = np.zeros(self.n) if zero else spec.x0
        if self.time == "discrete":
            steps = max(1, int(round(spec.horizon / spec.dt)))
            times = np.arange(steps + 1) * spec.dt
            EPS = np.empty((steps + 1, self.n))
            EPS[0] = e0
            for k in range(steps):
                EPS[k + 1] = self.A @ EPS[k] + self.Bw @ wf(float(times[k]))
            if not np.all(np.isfinite(EPS)):
                raise SimulationDiverged(f"{spec.where}: the error state blew up", float(times[-1]))
        else:

            def rhs(t: float, s: np.ndarray) -> np.ndarray:
                return self.A @ s + self.Bw @ wf(t)

            sol = _ct_run(rhs, e0, spec, spec.dt)
            times, EPS = sol.t, sol.y.T
        W = np.array([wf(tk) for tk in times]).reshape(times.size, -1)
        E = EPS @ self.C.T + W @ self.Dw.T
        # the "state" is the filter error eps; the estimate is 0 so that x - xhat = eps
        return {"t": times, "x": EPS, "xhat": np.zeros_like(EPS), "signals": {"w": W, "z": E}, "info": {}}

    def gain_system(self) -> tuple[Callable[[float], np.ndarray], str] | None:
        if "gamma" not in self.mats or self.w_dim == 0:
            return None

        discrete = self.time == "discrete"

        def G(om: float) -> np.ndarray:
            s = np.exp(1j * om) if discrete else 1j * om
            return self.C @ np.linalg.solve(s * np.eye(self.n) - self.A, self.Bw) + self.Dw

        return G, self.time


# -- observer-based control (obs_control) -------------------------------------------------------


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


for _cls in (Reduced, Robust, Euler, UIFilter, FilterError, ObsControl):
    MODELS[_cls.name] = _cls
