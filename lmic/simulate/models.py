"""Observer models: how a designed observer runs, by the name a theorem declares.

A theorem declares its observer with ``t.observer(model, time, **roles)`` (see
:meth:`lmic.template.builder.Template.observer`); the IR carries
``meta["observer"] = {"model", "time", "roles": {role: name}}`` and the roles are looked up by
name in :meth:`lmic.ir.problem.Problem.environment` (data, variables, derived gains).

Every model shares one plant (``f``, ``h`` from the system file's ``simulation:`` section,
``w`` the unknown input)::

    x+ (discrete) or x' (continuous) = A x + B u + f(x, u, t) + D1 w(t),   y = C x + h(x, u, t)

and differs in the observer:

``luenberger`` (discrete, continuous)
    ``xh+ | xh' = A xh + B u + f(xh, u, t) + L (y - C xh - h(xh, u, t))``; roles ``A, C, L``,
    optional ``B``, ``D1``. (qib.thm1, thesis.thm3_2_x, thesis.cor3_19.)
``uio`` (discrete, continuous)
    unknown-input observer ``z+ | z' = N z + G u + L y + M f(xh, u, t)``, ``xh = z - E y``;
    roles ``A, C, N, L, M, E``, optional ``B``, ``G`` (default ``M B``), ``D1``. The output is
    linear (no ``h``). (uio_dt.thm3_2 / thm4_1, thesis.thm4_1_2 / 4_1_3.)
``sampled`` (sampled)
    continuous plant, output sampled at ``t_k`` and held: on ``[t_k, t_k+1)``
    ``xh' = A xh + B u + f(xh, u, t) + L (C xh(t_k) + h(xh(t_k)) - y_k)`` — the sign of the
    source (nonuniform.thm1: ``A + L C`` Hurwitz). Roles ``A, C, L``, optional ``B``, ``D1``.

Examples
--------
>>> import numpy as np
>>> obs = make_observer("luenberger", "discrete", {"A": np.eye(2), "C": np.array([[1.0, 0.0]]),
...                                                "L": np.array([[0.5], [0.1]])})
>>> obs.n, obs.p, obs.m
(2, 1, 0)
>>> make_observer("kalman", "discrete", {})  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
lmic.errors.DataError: unknown observer model 'kalman' (known: euler, filter_error, luenberger, ...)
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping
from typing import Any, ClassVar

import numpy as np

from lmic.errors import DataError

__all__ = [
    "SimulationDiverged",
    "Observer",
    "Luenberger",
    "UnknownInput",
    "Sampled",
    "MODELS",
    "make_observer",
    "Vector",
]

Vector = np.ndarray
#: ``f(x, u, t)`` or ``h(x, u, t)``: a vector function of state, input and time
VectorFn = Callable[[Vector, Vector, float], Vector]


class SimulationDiverged(DataError):
    """The plant or observer state blew up; ``time`` is when it was first seen."""

    def __init__(self, message: str, time: float) -> None:
        super().__init__(message)
        self.time = time


def _matrix(value: Any, role: str, name: str) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 0:
        arr = arr.reshape(1, 1)
    if arr.ndim != 2:
        raise DataError(f"observer role {role} ('{name}') is not a matrix (shape {arr.shape})")
    if not np.all(np.isfinite(arr)):
        raise DataError(f"observer role {role} ('{name}') has non-finite entries")
    return arr


class Observer(ABC):
    """Base class: the plant shared by every model, role checks, and the observer interface.

    Parameters
    ----------
    time : str
        ``discrete``, ``continuous`` or ``sampled`` (must be one of the model's ``times``).
    mats : mapping
        Role -> matrix (the values of the declared names).
    names : mapping, optional
        Role -> IR name, for error messages.
    """

    name: ClassVar[str] = ""
    times: ClassVar[tuple[str, ...]] = ()
    required: ClassVar[tuple[str, ...]] = ("A", "C")
    optional: ClassVar[tuple[str, ...]] = ("B", "D1")
    #: whether ``h`` (an output nonlinearity) is supported
    output_nonlinearity: ClassVar[bool] = True

    def __init__(self, time: str, mats: Mapping[str, Any], names: Mapping[str, str] | None = None) -> None:
        if time not in self.times:
            raise DataError(f"observer model '{self.name}' runs in {' or '.join(self.times)} time, not '{time}'")
        names = dict(names or {})
        missing = [r for r in self.required if r not in mats]
        if missing:
            raise DataError(f"observer model '{self.name}' needs the role(s) {', '.join(missing)}")
        unknown = [r for r in mats if r not in self.required + self.optional]
        if unknown:
            allowed = ", ".join(self.required + self.optional)
            raise DataError(f"observer model '{self.name}' has no role {unknown[0]} (roles: {allowed})")
        self.time = time
        self.names = {r: names.get(r, r) for r in mats}
        self.mats = {r: _matrix(v, r, self.names[r]) for r, v in mats.items()}
        A, C = self.mats["A"], self.mats["C"]
        self.n: int = A.shape[0]
        self.p: int = C.shape[0]
        self._shape("A", (self.n, self.n))
        self._shape("C", (self.p, self.n))
        self.B = self.mats.get("B")
        if self.B is not None:
            self._shape("B", (self.n, self.B.shape[1]))
        self.m = 0 if self.B is None else self.B.shape[1]
        self.D1 = self.mats.get("D1")
        if self.D1 is not None:
            self._shape("D1", (self.n, self.D1.shape[1]))
        self.h_dim = 0 if self.D1 is None else self.D1.shape[1]
        self.A, self.C = A, C
        self._check()

    def _shape(self, role: str, shape: tuple[int, int]) -> None:
        got = self.mats[role].shape
        if got != shape:
            raise DataError(
                f"observer role {role} ('{self.names[role]}') has shape {got[0]}x{got[1]}, "
                f"expected {shape[0]}x{shape[1]}"
            )

    def _check(self) -> None:  # noqa: B027 - optional hook, most models check their roles
        """Shapes of the model's own roles (subclasses)."""

    # -- the plant -------------------------------------------------------------------------
    def plant(self, x: Vector, u: Vector, w: Vector, fx: Vector) -> Vector:
        """``A x + B u + f + D1 w`` (the next state, or the derivative)."""
        out = self.A @ x + fx
        if self.B is not None:
            out = out + self.B @ u
        if self.D1 is not None:
            out = out + self.D1 @ w
        return out

    def output(self, x: Vector, hx: Vector) -> Vector:
        """``C x + h``."""
        return self.C @ x + hx

    def _bu(self, u: Vector) -> Vector | float:
        return 0.0 if self.B is None else self.B @ u

    # -- the observer ----------------------------------------------------------------------
    def initial(self, xhat0: Vector | None, z0: Vector | None, y0: Vector) -> Vector:
        """The observer's initial internal state."""
        if z0 is not None:
            raise DataError(f"simulation: 'z0' applies to unknown-input observers, not '{self.name}' (use xhat0)")
        return np.zeros(self.n) if xhat0 is None else np.asarray(xhat0, dtype=float)

    def estimate(self, z: Vector, y: Vector) -> Vector:
        """The state estimate from the observer state ``z`` and the measurement ``y``."""
        return z

    @abstractmethod
    def update(self, z: Vector, y: Vector, u: Vector, t: float, f: VectorFn, h: VectorFn) -> Vector:
        """The observer's next state (discrete) or derivative (continuous)."""


class Luenberger(Observer):
    """``xh+ | xh' = A xh + B u + f(xh) + L (y - C xh - h(xh))``."""

    name = "luenberger"
    times = ("discrete", "continuous")
    required = ("A", "C", "L")

    def _check(self) -> None:
        self._shape("L", (self.n, self.p))
        self.L = self.mats["L"]

    def update(self, z: Vector, y: Vector, u: Vector, t: float, f: VectorFn, h: VectorFn) -> Vector:
        innovation = y - self.C @ z - h(z, u, t)
        return self.A @ z + self._bu(u) + f(z, u, t) + self.L @ innovation


class UnknownInput(Observer):
    """``z+ | z' = N z + G u + L y + M f(xh)``, ``xh = z - E y`` (``M D1 = 0`` decouples ``w``)."""

    name = "uio"
    times = ("discrete", "continuous")
    required = ("A", "C", "N", "L", "M", "E")
    optional = ("B", "G", "D1")
    output_nonlinearity = False

    def _check(self) -> None:
        n, p = self.n, self.p
        for role, shape in (("N", (n, n)), ("L", (n, p)), ("M", (n, n)), ("E", (n, p))):
            self._shape(role, shape)
        self.N, self.L, self.M, self.E = (self.mats[r] for r in ("N", "L", "M", "E"))
        G = self.mats.get("G")
        if G is not None:
            if self.B is None:
                raise DataError(f"observer role G ('{self.names['G']}') given without B")
            self._shape("G", (n, self.m))
        elif self.B is not None:
            G = self.M @ self.B
        self.G = G

    def initial(self, xhat0: Vector | None, z0: Vector | None, y0: Vector) -> Vector:
        """``z0`` as given, else ``xhat0 + E y0`` (so the first estimate is ``xhat0``)."""
        if z0 is not None:
            if xhat0 is not None:
                raise DataError("simulation: give either 'xhat0' or 'z0', not both")
            return np.asarray(z0, dtype=float)
        xh = np.zeros(self.n) if xhat0 is None else np.asarray(xhat0, dtype=float)
        return xh + self.E @ y0

    def estimate(self, z: Vector, y: Vector) -> Vector:
        """``xh = z - E y``."""
        return z - self.E @ y

    def update(self, z: Vector, y: Vector, u: Vector, t: float, f: VectorFn, h: VectorFn) -> Vector:
        xh = z - self.E @ y
        out = self.N @ z + self.L @ y + self.M @ f(xh, u, t)
        if self.G is not None:
            out = out + self.G @ u
        return out


class Sampled(Observer):
    """Continuous observer corrected by the last held sample: ``+ L (C xh(t_k) + h - y_k)``."""

    name = "sampled"
    times = ("sampled",)
    required = ("A", "C", "L")

    def _check(self) -> None:
        self._shape("L", (self.n, self.p))
        self.L = self.mats["L"]

    def correction(self, zk: Vector, yk: Vector, uk: Vector, tk: float, h: VectorFn) -> Vector:
        """``L (C xh(t_k) + h(xh(t_k)) - y_k)``, held on ``[t_k, t_k+1)``."""
        return self.L @ (self.C @ zk + h(zk, uk, tk) - yk)

    def flow(self, z: Vector, u: Vector, t: float, f: VectorFn, held: Vector) -> Vector:
        """``A xh + B u + f(xh) + held`` between samples."""
        return self.A @ z + self._bu(u) + f(z, u, t) + held

    def update(self, z: Vector, y: Vector, u: Vector, t: float, f: VectorFn, h: VectorFn) -> Vector:
        """Not used: a sampled observer runs :meth:`flow` with the :meth:`correction` held between samples."""
        raise TypeError("a sampled observer is advanced by flow() and correction(), not update()")


#: model name -> class
MODELS: dict[str, type[Observer]] = {cls.name: cls for cls in (Luenberger, UnknownInput, Sampled)}


def make_observer(model: str, time: str, mats: Mapping[str, Any], names: Mapping[str, str] | None = None) -> Observer:
    """The observer ``model`` running in ``time`` with the role matrices ``mats``.

    Raises
    ------
    DataError
        For an unknown model, a time it does not run in, a missing or unknown role, or a role
        of the wrong shape (naming the role and its IR name).

    Examples
    --------
    >>> import numpy as np
    >>> obs = make_observer("sampled", "sampled", {"A": -np.eye(1), "C": np.eye(1), "L": -np.eye(1)})
    >>> obs.correction(np.array([1.0]), np.array([0.5]), np.zeros(0), 0.0, lambda x, u, t: 0 * x)
    array([-0.5])
    """
    cls = MODELS.get(model)
    if cls is None:
        raise DataError(f"unknown observer model '{model}' (known: {', '.join(sorted(MODELS))})")
    return cls(time, mats, names)
