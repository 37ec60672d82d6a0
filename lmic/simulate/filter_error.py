"""The ``filter_error`` observer family (:class:`FilterError`; the catalogue is :mod:`lmic.simulate.families`).

``filter_error`` (continuous, discrete) — the error system of a filter alone, for the analysis
    theorems that give the filter but not the plant: ``eps' | eps+ = N eps + (L D2 - M D1) w``,
    ``e = J eps + E D2 w`` (the Lipschitz term vanishes on the linear part). Role ``N``;
    optional ``J`` (default I), ``L, M, E, D1, D2, gamma``. The section's ``x0`` is ``eps(0)``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from lmic.errors import DataError
from lmic.simulate.custom import Custom, Signal, _lti_run
from lmic.simulate.lti import as_signal
from lmic.simulate.models import SimulationDiverged

__all__ = ["FilterError"]


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
            W = np.array([wf(tk) for tk in times]).reshape(times.size, -1)
        else:  # linear: integrated exactly (lmic.simulate.lti)
            ws = as_signal(wf, self.w_dim)
            times, EPS = _lti_run(self.A, self.Bw, e0, ws, spec)
            W = ws.on(times)
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
