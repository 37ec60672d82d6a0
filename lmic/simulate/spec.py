"""The ``simulation:`` section of a system file: checked, parsed and validated into a :class:`SimulationSpec`.

Split out of :mod:`lmic.simulate.run` (which re-exports every name); the keys and their meaning
are in its module docstring and in ``schemas/simulation.schema.json``.

Examples
--------
>>> check_section({"x0": [1, 0], "horizon": 2, "dt": "1e-1"})["dt"]
0.1
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from lmic.errors import DataError
from lmic.simulate.families import EXTRA_KEYS, Custom
from lmic.simulate.models import Observer
from lmic.simulate.parser import Expression, parse, parse_vector

__all__ = ["SimulationSpec", "KEYS", "MAX_POINTS", "check_section", "read_spec"]

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
    q1 = getattr(observer, "q1", None)  # the reduced-order filter's own dimension
    z0 = _vector(sec["z0"], n if q1 is None else int(q1), "z0", where) if "z0" in sec else None
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
