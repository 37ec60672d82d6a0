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
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from lmic.errors import DataError
from lmic.simulate.families import EXTRA_KEYS, Custom
from lmic.simulate.models import Observer, Sampled, SimulationDiverged, make_observer
from lmic.simulate.parser import Expression, parse, parse_vector

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

#: the keys a ``simulation:`` section may have
KEYS = (
    "nonlinearity",
    "output_nonlinearity",
    "x0",
    "xhat0",
    "z0",
    "input",
    "unknown_input",
    "horizon",
    "dt",
    "sampling",
    "noise",
    "method",
    *EXTRA_KEYS,
)
#: a state entry larger than this in magnitude counts as a blow-up
BLOWUP = 1e12
#: the error *decayed* when its mean over the last 10 % of the horizon is at most this
#: fraction of its peak
DECAY_RATIO = 0.1
#: most time steps, grid points or samples one simulation may take
MAX_POINTS = 200_000

_NUMERIC = re.compile(r"[-+]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][-+]?[0-9]+)?", re.ASCII)


@dataclass
class SimulationSpec:
    """A validated ``simulation:`` section (expressions parsed, vectors checked).

    Attributes
    ----------
    f, h : list of Expression
        Plant nonlinearity (``n`` entries) and output nonlinearity (``p`` entries, or empty).
    x0 : ndarray
    xhat0, z0 : ndarray or None
    u, w : list of Expression
        Known input (expressions in ``t``) and unknown input (expressions in ``t``).
    horizon : float
    dt : float
        Step (discrete time) or reporting grid (continuous and sampled).
    sampling : tuple of (float, float, int) or None
        ``(min, max, seed)`` of the measurement intervals (sampled model).
    noise_std : ndarray or None
    noise_seed : int
    method : str
    where : str
    """

    f: list[Expression]
    h: list[Expression]
    x0: np.ndarray
    xhat0: np.ndarray | None
    z0: np.ndarray | None
    u: list[Expression]
    w: list[Expression]
    horizon: float
    dt: float
    sampling: tuple[float, float, int] | None
    noise_std: np.ndarray | None
    noise_seed: int = 0
    method: str = "RK45"
    where: str = "simulation"
    #: what a model of :mod:`lmic.simulate.families` read from its extra keys
    extra: dict[str, Any] = field(default_factory=dict)


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


# -- reading the section ---------------------------------------------------------------------


def _numbers(value: Any) -> Any:
    """YAML 1.1 reads ``1e-3`` as a string: numeric literals in numeric fields become floats."""
    if isinstance(value, str) and len(value) < 400 and _NUMERIC.fullmatch(value.strip()):
        return float(value)
    if isinstance(value, list):
        return [_numbers(v) for v in value]
    return value


def check_section(section: Any, where: str = "simulation") -> dict[str, Any]:
    """Check keys and types of a ``simulation:`` section against the schema.

    Returns the section with numeric strings in numeric fields converted to numbers.

    Raises
    ------
    DataError
        Naming the first unknown key, or the first value of the wrong type (with its path).

    Examples
    --------
    >>> check_section({"x0": [1], "horizon": 1, "step": 0.1})
    Traceback (most recent call last):
    ...
    lmic.errors.DataError: simulation: unknown key 'step' (allowed: nonlinearity, output_nonlinearity, \
x0, xhat0, z0, input, unknown_input, horizon, dt, sampling, noise, method, disturbance, uncertainty, delay, history)
    """
    if not isinstance(section, dict):
        raise DataError(f"{where}: must be a mapping of keys ({', '.join(KEYS)})")
    for key in section:
        if key not in KEYS:
            raise DataError(f"{where}: unknown key '{key}' (allowed: {', '.join(KEYS)})")
    sec = dict(section)
    _check_values(sec, where)
    for key in ("x0", "xhat0", "z0", "horizon", "dt"):
        if key in sec:
            sec[key] = _numbers(sec[key])
    for key in ("sampling", "noise"):
        if isinstance(sec.get(key), dict):
            sec[key] = {k: _numbers(v) for k, v in sec[key].items()}
    for key in ("sampling", "noise"):
        if isinstance(sec.get(key), dict):
            allowed = ("min", "max", "seed") if key == "sampling" else ("std", "seed")
            for sub in sec[key]:
                if sub not in allowed:
                    raise DataError(f"{where}.{key}: unknown key '{sub}' (allowed: {', '.join(allowed)})")
    _validate_schema(sec, where)
    return sec


def _check_values(sec: dict[str, Any], where: str) -> None:
    """Before any conversion: bounded nesting, names as keys, finite numbers of float64 range.

    >>> _check_values({"sampling": {"max": float("nan")}}, "simulation")
    Traceback (most recent call last):
    ...
    lmic.errors.DataError: simulation.sampling.max: nan is not a finite number
    """
    from lmic.limits import check_depth

    check_depth(sec, where)
    stack: list[tuple[Any, str]] = [(sec, where)]
    while stack:
        value, path = stack.pop()
        if isinstance(value, bool):
            continue
        if isinstance(value, float) and not math.isfinite(value):
            raise DataError(f"{path}: {value} is not a finite number")
        if isinstance(value, int) and abs(value) >= 2**63:
            raise DataError(f"{path}: the integer {str(value)[:12]}... is too large")
        if isinstance(value, dict):
            for k, v in value.items():
                if not isinstance(k, str):
                    raise DataError(f"{path}: key {k!r} is not a name")
                stack.append((v, f"{path}.{k}"))
        elif isinstance(value, list):
            stack.extend((v, f"{path}[{i + 1}]") for i, v in enumerate(value))


def _validate_schema(sec: dict[str, Any], where: str) -> None:
    import jsonschema

    from lmic.schemas import load_schema

    validator = jsonschema.Draft202012Validator(load_schema("simulation"))
    error = jsonschema.exceptions.best_match(validator.iter_errors(sec))
    if error is None:
        return
    path = "".join(f"[{p + 1}]" if isinstance(p, int) else f".{p}" for p in error.absolute_path)
    value = error.instance
    shown = repr(value) if not isinstance(value, dict | list) or len(repr(value)) < 60 else type(value).__name__
    if error.validator == "required":
        message = error.message.replace(" is a required property", " is required")
    elif error.validator in ("type", "oneOf"):
        want = {
            "nonlinearity": "a list of expressions (one per state) or a mapping x<i> -> expression",
            "output_nonlinearity": "a list of expressions (one per output) or a mapping y<i> -> expression",
            "input": "an expression or a list of expressions",
            "unknown_input": "an expression or a list of expressions",
            "std": "a number or a list of numbers",
        }.get(str(error.absolute_path[-1]) if error.absolute_path else "", "")
        message = f"{shown} is not {want}" if want else error.message
    else:
        message = error.message
    raise DataError(f"{where}{path}: {message}")


def _vector(value: Any, size: int, key: str, where: str) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    if arr.shape != (size,):
        raise DataError(f"{where}.{key}: has {arr.size} entries, expected {size}")
    if not np.all(np.isfinite(arr)):
        raise DataError(f"{where}.{key}: entries must be finite numbers")
    return arr


def _expr_list(value: Any) -> list[Any]:
    return list(value) if isinstance(value, list) else [value]


def _per_component(value: Any, size: int, prefix: str, key: str, where: str) -> list[Any]:
    """A list of ``size`` expressions from a list or a mapping ``<prefix><i> -> expression``."""
    if isinstance(value, dict):
        out: list[Any] = ["0"] * size
        for k, v in value.items():
            digits = str(k)[len(prefix) :]
            if not str(k).startswith(prefix) or not (digits.isascii() and digits.isdigit() and len(digits) < 9):
                raise DataError(f"{where}.{key}: '{k}' is not {prefix}1..{prefix}{size}")
            i = int(digits)
            if not 1 <= i <= size:
                raise DataError(f"{where}.{key}: '{k}' is out of range ({prefix}1..{prefix}{size})")
            out[i - 1] = v
        return out
    items = _expr_list(value)
    if len(items) != size:
        what = "states" if prefix == "x" else "outputs"
        raise DataError(f"{where}.{key}: has {len(items)} entries, expected {size} (one per {what[:-1]})")
    return items


def _names(prefix: str, size: int) -> list[str]:
    return [f"{prefix}{i + 1}" for i in range(size)]


def read_spec(section: Any, observer: Observer, where: str = "simulation") -> SimulationSpec:
    """Validate a ``simulation:`` section for ``observer`` and parse its expressions.

    Parameters
    ----------
    section : mapping
        The raw section (from YAML or JSON).
    observer : Observer
        Gives the dimensions (``n`` states, ``p`` outputs, ``m`` inputs, unknown inputs) and
        what the model supports.
    where : str
        Prefix of error messages (e.g. ``"plant.yaml: simulation"``).

    Raises
    ------
    DataError
        An unknown key, a value of the wrong type or size, a forbidden token in an expression
        (naming it and its column), or a key the model does not support.
    """
    sec = check_section(section, where)
    n, p = observer.n, observer.p
    time = observer.time
    custom = isinstance(observer, Custom)
    extra = observer.read_extra(sec, where) if isinstance(observer, Custom) else {}
    if not custom:
        for key in EXTRA_KEYS:
            if key in sec:
                raise DataError(f"{where}: '{key}' does not apply to the '{observer.name}' observer")
    if time == "sampled":
        if "sampling" not in sec:
            raise DataError(f"{where}: the sampled observer needs 'sampling: {{min, max, seed}}'")
    elif "sampling" in sec:
        raise DataError(f"{where}: 'sampling' applies to sampled observers; this one runs in {time} time (use dt)")
    if "method" in sec and time == "discrete":
        raise DataError(f"{where}: 'method' applies to continuous time; this observer is discrete")
    if "output_nonlinearity" in sec and not observer.output_nonlinearity:
        raise DataError(f"{where}: the '{observer.name}' observer assumes y = C x: remove 'output_nonlinearity'")
    if "unknown_input" in sec and observer.D1 is None and not custom:
        raise DataError(
            f"{where}: 'unknown_input' needs an unknown-input matrix, and the '{observer.name}' "
            "observer of this theorem declares none (role D1)"
        )
    if "z0" in sec and observer.name not in ("uio", "ui_filter"):
        raise DataError(f"{where}: 'z0' applies to unknown-input observers, not '{observer.name}' (use xhat0)")
    if "z0" in sec and "xhat0" in sec:
        raise DataError(f"{where}: give either 'xhat0' or 'z0', not both")

    # inputs: u1..um (expressions in t)
    u_texts = _expr_list(sec["input"]) if "input" in sec else []
    if observer.B is not None and u_texts and len(u_texts) != observer.m:
        raise DataError(f"{where}.input: has {len(u_texts)} entries, B has {observer.m} columns")
    m = observer.m if observer.B is not None else len(u_texts)
    u = parse_vector(u_texts, {"t"}, f"{where}.input") if u_texts else [parse("0", (), where)] * m
    w: list[Expression] = []
    if "unknown_input" in sec and not custom:
        w_texts = _expr_list(sec["unknown_input"])
        if len(w_texts) != observer.h_dim:
            raise DataError(
                f"{where}.unknown_input: has {len(w_texts)} entries, the unknown-input matrix has "
                f"{observer.h_dim} columns"
            )
        w = parse_vector(w_texts, {"t"}, f"{where}.unknown_input")
    elif observer.D1 is not None:
        w = [parse("0", (), where)] * observer.h_dim

    names = set(_names("x", n)) | {"t"}
    if m:
        names |= set(_names("u", m)) | {"u"}
    f_texts = _per_component(sec["nonlinearity"], n, "x", "nonlinearity", where) if "nonlinearity" in sec else []
    f = parse_vector(f_texts, names, f"{where}.nonlinearity") if f_texts else []
    h: list[Expression] = []
    if "output_nonlinearity" in sec:
        h_texts = _per_component(sec["output_nonlinearity"], p, "y", "output_nonlinearity", where)
        h = parse_vector(h_texts, names, f"{where}.output_nonlinearity")

    x0 = _vector(sec["x0"], n, "x0", where)
    xhat0 = _vector(sec["xhat0"], n, "xhat0", where) if "xhat0" in sec else None
    z0 = _vector(sec["z0"], getattr(observer, "q1", n), "z0", where) if "z0" in sec else None
    horizon = float(sec["horizon"])
    dt = float(sec.get("dt", 1.0 if time == "discrete" else horizon / 1000.0))
    if horizon / dt > MAX_POINTS:
        raise DataError(f"{where}: horizon / dt = {horizon / dt:.0f} points (at most {MAX_POINTS})")
    sampling = None
    if "sampling" in sec:
        s = sec["sampling"]
        hi = float(s["max"])
        lo = float(s.get("min", hi))
        if lo > hi:
            raise DataError(f"{where}.sampling: min = {lo:g} is larger than max = {hi:g}")
        if horizon / lo > MAX_POINTS:
            raise DataError(f"{where}.sampling: up to {horizon / lo:.0f} samples (at most {MAX_POINTS})")
        sampling = (lo, hi, int(s.get("seed", 0)))
    noise_std = None
    noise_seed = 0
    if "noise" in sec:
        std = sec["noise"]["std"]
        noise_std = np.full(p, float(std)) if not isinstance(std, list) else _vector(std, p, "noise.std", where)
        noise_seed = int(sec["noise"].get("seed", 0))
    return SimulationSpec(
        f=f,
        h=h,
        x0=x0,
        xhat0=xhat0,
        z0=z0,
        u=u,
        w=w,
        horizon=horizon,
        dt=dt,
        sampling=sampling,
        noise_std=noise_std,
        noise_seed=noise_seed,
        method=str(sec.get("method", "RK45")),
        where=where,
        extra=extra,
    )


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
