"""Simulate a plant and its designed observer from a system file's ``simulation:`` section.

The observer comes from the theorem's declaration (``problem.meta["observer"]``, see
:mod:`lmic.simulate.models`) with its gains taken from the certified solution; the plant's
nonlinearity, inputs, initial states, horizon, sampling and noise come from the system file::

    simulation:
      nonlinearity: ["0", "0", "0", "-0.0333*sin(x3)"]   # or {x4: "-0.0333*sin(x3)"}
      input: "sin(t)"                                    # u(t); a list for several inputs
      x0: [3, 2, 3, -2]
      xhat0: [0, 0, 0, 0]
      horizon: 10
      dt: 0.1                                            # sampling period (discrete time)
      noise: {std: 0.01, seed: 1}

Discrete time iterates the difference equations; continuous time integrates with scipy's
``solve_ivp``; the ``sampled`` model integrates between measurement instants ``t_k`` whose
intervals are drawn uniformly in ``[sampling.min, sampling.max]`` (seeded), holding the
correction computed from the last sample. A state that stops being finite (or exceeds
:data:`BLOWUP` in magnitude) raises :class:`SimulationDiverged` naming the time.

Examples
--------
>>> import numpy as np
>>> from lmic.simulate.models import make_observer
>>> obs = make_observer("luenberger", "discrete",
...                     {"A": np.array([[1.0, 0.1], [0.0, 1.0]]), "C": np.array([[1.0, 0.0]]),
...                      "L": np.array([[1.0], [2.0]])})
>>> spec = read_spec({"x0": [1, 1], "horizon": 5, "dt": 0.1,
...                   "nonlinearity": ["0", "-0.1*sin(x1)"]}, obs)
>>> traj = run(obs, spec)
>>> traj.t.shape, traj.decayed, traj.final_error < 1e-6
((51,), True, True)

The module is split by job: the section (:mod:`lmic.simulate.spec`), the result
(:mod:`lmic.simulate.trajectory`), the loops here; every name it had is re-exported.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from lmic.errors import DataError
from lmic.simulate.families import Custom
from lmic.simulate.models import Observer, Sampled, SimulationDiverged, make_observer
from lmic.simulate.parser import Expression
from lmic.simulate.spec import KEYS, MAX_POINTS, SimulationSpec, _names, check_section, read_spec
from lmic.simulate.trajectory import DECAY_RATIO, Trajectory

__all__ = [
    "SimulationSpec",
    "Trajectory",
    "SimulationDiverged",
    "KEYS",
    "BLOWUP",
    "DECAY_RATIO",
    "MAX_POINTS",
    "check_section",
    "read_spec",
    "observer_for",
    "run",
    "simulate",
]

#: a state entry larger than this in magnitude counts as a blow-up
BLOWUP = 1e12


# -- the observer from a solved problem ------------------------------------------------------


def observer_for(problem: Any, x: np.ndarray | None) -> Observer:
    """The observer a solved problem designs: its declared model with the roles' values.

    Parameters
    ----------
    problem : lmic.ir.problem.Problem
        With ``meta["observer"]`` (from the theorem's ``t.observer(...)``).
    x : ndarray
        The solution (the derived gains are evaluated at it).

    Raises
    ------
    DataError
        No observer declared, no solution, a role naming nothing, or gains that cannot be
        computed (e.g. a singular ``P``).
    """
    theorem = problem.meta.get("theorem") or "this problem"
    decl = problem.meta.get("observer")
    if not decl:
        raise DataError(f"theorem {theorem} declares no observer (t.observer(...)): nothing to simulate")
    if x is None:
        raise DataError(f"theorem {theorem}: no solution to take the observer gains from")
    try:
        env = problem.environment(np.asarray(x, dtype=float))
    except Exception as err:  # noqa: BLE001 - e.g. a singular P: say which, in one line
        why = f"{type(err).__name__}: {err}"
        raise DataError(f"theorem {theorem}: the observer gains cannot be computed ({why})") from None
    roles = dict(decl.get("roles") or {})
    mats: dict[str, Any] = {}
    for role, name in roles.items():
        if name not in env:
            raise DataError(
                f"theorem {theorem}: observer role {role} names '{name}', which the problem does not define"
            )
        mats[role] = env[name]
    return make_observer(str(decl.get("model")), str(decl.get("time")), mats, roles)


# -- running ---------------------------------------------------------------------------------


class _Functions:
    """``f(x, u, t)``, ``h(x, u, t)``, ``u(t)``, ``w(t)`` from the parsed expressions."""

    def __init__(self, spec: SimulationSpec, n: int, p: int) -> None:
        self.n, self.p = n, p
        self.xn = _names("x", n)
        self.un = _names("u", len(spec.u))
        self.spec = spec

    def env(self, x: np.ndarray, u: np.ndarray, t: float) -> dict[str, Any]:
        env: dict[str, Any] = dict(zip(self.xn, x, strict=True))
        env.update(zip(self.un, u, strict=True))
        if len(u):
            env["u"] = u[0]
        env["t"] = t
        return env

    @staticmethod
    def _eval(exprs: Sequence[Expression], env: Mapping[str, Any], size: int) -> np.ndarray:
        if not exprs:
            return np.zeros(size)
        return np.array([float(e.evaluate(env)) for e in exprs])

    def f(self, x: np.ndarray, u: np.ndarray, t: float) -> np.ndarray:
        return self._eval(self.spec.f, self.env(x, u, t), self.n) if self.spec.f else np.zeros(self.n)

    def h(self, x: np.ndarray, u: np.ndarray, t: float) -> np.ndarray:
        return self._eval(self.spec.h, self.env(x, u, t), self.p) if self.spec.h else np.zeros(self.p)

    def u(self, t: float) -> np.ndarray:
        return self._eval(self.spec.u, {"t": t}, 0)

    def w(self, t: float) -> np.ndarray:
        return self._eval(self.spec.w, {"t": t}, 0)


def _blown(v: np.ndarray) -> bool:
    return not bool(np.all(np.isfinite(v))) or bool(np.max(np.abs(v), initial=0.0) > BLOWUP)


def _diverged(where: str, which: str, t: float, detail: str = "") -> SimulationDiverged:
    extra = f" ({detail})" if detail else ""
    return SimulationDiverged(
        f"{where}: the {which} state blew up at t = {t:.6g} (not finite or |x| > {BLOWUP:g}){extra}", t
    )


class _NonFinite(Exception):
    """Raised inside the integrator's right-hand side when a value stops being finite."""

    def __init__(self, time: float, which: str) -> None:
        super().__init__(time, which)
        self.time, self.which = time, which


def _noise(spec: SimulationSpec, count: int, p: int) -> np.ndarray:
    if spec.noise_std is None:
        return np.zeros((count, p))
    rng = np.random.default_rng(spec.noise_seed)
    return rng.standard_normal((count, p)) * spec.noise_std


def _discrete(obs: Observer, spec: SimulationSpec, fn: _Functions) -> Trajectory:
    steps = max(1, int(round(spec.horizon / spec.dt)))
    t = np.arange(steps + 1) * spec.dt
    noise = _noise(spec, steps + 1, obs.p)
    X = np.empty((steps + 1, obs.n))
    XH = np.empty_like(X)
    x = spec.x0.copy()
    z: np.ndarray | None = None
    with np.errstate(all="ignore"):
        for k in range(steps + 1):
            tk = float(t[k])
            u = fn.u(tk)
            y = obs.output(x, fn.h(x, u, tk)) + noise[k]
            if z is None:
                z = obs.initial(spec.xhat0, spec.z0, y)
            xh = obs.estimate(z, y)
            if _blown(x):
                raise _diverged(spec.where, "plant", tk)
            if _blown(xh):
                raise _diverged(spec.where, "observer", tk)
            X[k], XH[k] = x, xh
            if k == steps:
                break
            x_next = obs.plant(x, u, fn.w(tk), fn.f(x, u, tk))
            z = obs.update(z, y, u, tk, fn.f, fn.h)
            x = x_next
    return Trajectory(t, X, XH, obs.name, obs.time)


def _grid(spec: SimulationSpec) -> np.ndarray:
    count = max(1, int(round(spec.horizon / spec.dt)))
    return np.linspace(0.0, spec.horizon, count + 1)


def _ivp(
    rhs: Callable[[float, np.ndarray], np.ndarray],
    span: tuple[float, float],
    s0: np.ndarray,
    t_eval: np.ndarray,
    spec: SimulationSpec,
    n: int,
    max_step: float,
) -> Any:
    from scipy.integrate import solve_ivp

    def blowup(t: float, s: np.ndarray) -> float:
        return BLOWUP - float(np.max(np.abs(s)))

    blowup.terminal = True  # type: ignore[attr-defined]

    def guarded(t: float, s: np.ndarray) -> np.ndarray:
        # a NaN derivative must never reach the integrator: its step-size control can loop
        # forever on NaN error estimates
        d = rhs(t, s)
        if not np.all(np.isfinite(d)) or not np.all(np.isfinite(s)):
            bad_plant = not (np.all(np.isfinite(d[:n])) and np.all(np.isfinite(s[:n])))
            raise _NonFinite(float(t), "plant" if bad_plant else "observer")
        return d

    try:
        with np.errstate(all="ignore"):
            sol = solve_ivp(
                guarded, span, s0, method=spec.method, t_eval=t_eval, events=blowup, rtol=1e-7, atol=1e-9,
                max_step=max_step,
            )  # fmt: skip
    except _NonFinite as err:
        raise _diverged(spec.where, err.which, err.time) from None
    if sol.status == 1:  # the blow-up event fired
        tb = float(sol.t_events[0][0])
        sb = sol.y_events[0][0]
        which = "plant" if np.max(np.abs(sb[:n])) >= np.max(np.abs(sb[n:])) else "observer"
        raise _diverged(spec.where, which, tb)
    if sol.status != 0 or not np.all(np.isfinite(sol.y)):
        tf = float(sol.t[-1]) if sol.t.size else span[0]
        last = sol.y[:, -1] if sol.t.size else s0
        which = "plant" if _blown(last[:n]) or not _blown(last[n:]) else "observer"
        raise _diverged(spec.where, which, tf, f"the integrator stopped: {sol.message}")
    return sol


def _continuous(obs: Observer, spec: SimulationSpec, fn: _Functions) -> Trajectory:
    n = obs.n
    grid = _grid(spec)
    noise = _noise(spec, grid.size, obs.p)
    last = grid.size - 1

    def v(t: float) -> np.ndarray:
        k = int(t / spec.dt) if np.isfinite(t) else last
        return noise[min(max(k, 0), last)]

    def y_of(x: np.ndarray, u: np.ndarray, t: float) -> np.ndarray:
        return obs.output(x, fn.h(x, u, t)) + v(t)

    u0 = fn.u(0.0)
    z0 = obs.initial(spec.xhat0, spec.z0, y_of(spec.x0, u0, 0.0))

    def rhs(t: float, s: np.ndarray) -> np.ndarray:
        x, z = s[:n], s[n:]
        u = fn.u(t)
        y = y_of(x, u, t)
        return np.concatenate([obs.plant(x, u, fn.w(t), fn.f(x, u, t)), obs.update(z, y, u, t, fn.f, fn.h)])

    max_step = spec.dt if spec.noise_std is not None else np.inf
    sol = _ivp(rhs, (0.0, spec.horizon), np.concatenate([spec.x0, z0]), grid, spec, n, max_step)
    X = sol.y[:n].T
    Z = sol.y[n:].T
    with np.errstate(all="ignore"):
        XH = np.array([obs.estimate(Z[k], y_of(X[k], fn.u(tk), tk)) for k, tk in enumerate(sol.t)])
    bad = [k for k in range(len(sol.t)) if _blown(XH[k])]
    if bad:
        raise _diverged(spec.where, "observer", float(sol.t[bad[0]]))
    return Trajectory(sol.t, X, XH, obs.name, obs.time, info={"method": spec.method})


def _sampled(obs: Sampled, spec: SimulationSpec, fn: _Functions) -> Trajectory:
    assert spec.sampling is not None
    lo, hi, seed = spec.sampling
    n = obs.n
    grid = _grid(spec)
    rng = np.random.default_rng(seed)
    noise_rng = np.random.default_rng(spec.noise_seed)
    T = spec.horizon
    s = np.concatenate([spec.x0, np.zeros(n)])
    out = np.empty((grid.size, 2 * n))
    samples: list[float] = []
    intervals: list[float] = []
    tk = 0.0
    gi = 0  # next grid point to fill
    while True:
        x, z = s[:n], s[n:]
        uk = fn.u(tk)
        yk = obs.output(x, fn.h(x, uk, tk))
        if spec.noise_std is not None:
            yk = yk + noise_rng.standard_normal(obs.p) * spec.noise_std
        if not samples:
            z = obs.initial(spec.xhat0, spec.z0, yk)
            s = np.concatenate([x, z])
        samples.append(tk)
        if _blown(x) or _blown(z):
            raise _diverged(spec.where, "plant" if _blown(x) else "observer", tk)
        held = obs.correction(z, yk, uk, tk, fn.h)
        delta = float(rng.uniform(lo, hi)) if hi > lo else hi
        t_next = tk + delta
        if t_next >= T - 1e-9 * max(1.0, T):  # accumulated rounding must not leave a sliver
            t_next = T
        intervals.append(t_next - tk)
        end = grid.size if t_next >= T else int(np.searchsorted(grid, t_next, side="left"))
        pts = grid[gi:end]

        def rhs(t: float, st: np.ndarray, held: np.ndarray = held) -> np.ndarray:
            xx, zz = st[:n], st[n:]
            u = fn.u(t)
            return np.concatenate([obs.plant(xx, u, fn.w(t), fn.f(xx, u, t)), obs.flow(zz, u, t, fn.f, held)])

        t_eval = np.unique(np.concatenate([pts, [t_next]]))
        if t_next > tk:
            sol = _ivp(rhs, (tk, t_next), s, t_eval, spec, n, np.inf)
            vals = sol.y.T
        else:
            vals = s[None, :].repeat(t_eval.size, axis=0)
        # rows of ``vals`` follow t_eval: the grid points in [tk, t_next) then t_next
        out[gi:end] = vals[: end - gi]
        gi = end
        s = vals[-1]
        if t_next >= T or len(samples) > MAX_POINTS:
            break
        tk = t_next
    X, XH = out[:, :n], out[:, n:]
    info = {"sampling_min": lo, "sampling_max": hi, "mean_interval": float(np.mean(intervals))}
    return Trajectory(grid, X, XH, obs.name, obs.time, samples=np.array(samples), info=info)


def run(observer: Observer, spec: SimulationSpec) -> Trajectory:
    """Simulate ``observer`` and its plant as ``spec`` says (see the module docstring).

    Raises
    ------
    SimulationDiverged
        When the plant or observer state stops being finite, naming the time.
    """
    fn = _Functions(spec, observer.n, observer.p)
    if isinstance(observer, Custom):
        out = observer.custom_run(spec, fn)
        info = dict(out.get("info") or {})
        return Trajectory(out["t"], out["x"], out["xhat"], observer.name, observer.time, info=info,
                          signals=dict(out.get("signals") or {}))  # fmt: skip
    if observer.time == "discrete":
        return _discrete(observer, spec, fn)
    if observer.time == "continuous":
        return _continuous(observer, spec, fn)
    if isinstance(observer, Sampled):
        return _sampled(observer, spec, fn)
    raise DataError(f"observer model '{observer.name}' cannot run in {observer.time} time")  # pragma: no cover


def simulate(problem: Any, x: np.ndarray | None, system: Any) -> tuple[Observer, Trajectory]:
    """Simulate the observer a solved problem designs, with the system file's ``simulation:``.

    Parameters
    ----------
    problem : lmic.ir.problem.Problem
    x : ndarray
        The (certified) solution.
    system : path, dict or lmic.system.System
        The system file; its ``simulation:`` section drives the run.

    Returns
    -------
    (Observer, Trajectory)
    """
    from lmic.system import load_system

    sysobj = load_system(system)
    section = sysobj.raw.get("simulation")
    where = f"{sysobj.label}: simulation"
    if section is None:
        raise DataError(f"{sysobj.label}: has no 'simulation:' section (see schemas/simulation.schema.json)")
    check_section(section, where)
    obs = observer_for(problem, x)
    spec = read_spec(section, obs, where)
    traj = run(obs, spec)
    from lmic.simulate.certificate import checks

    traj.checks = checks(obs, spec, _Functions(spec, obs.n, obs.p))
    return obs, traj
