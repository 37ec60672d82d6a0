"""Certificate meets trajectory: measure on simulated runs what the theorem certified.

A theorem that certifies an L2 gain ``gamma`` (from the disturbance ``w`` to the performance
output ``z``, zero initial state) or a decay rate ``beta`` declares it as the observer role
``gamma`` / ``decay`` (see :mod:`lmic.simulate.families`). :func:`checks` then runs the model
again, on the same horizon, and reports both numbers:

``L2 gain``
    ``||z||_2 / ||w||_2`` with every state (and the delay history) at zero, the nonlinearity
    dropped (``f = 0`` is Lipschitz with any constant, so it is always admissible) and the
    section's uncertainty realisation kept, for a set of disturbances: the section's own, a
    unit pulse, a step, seeded white noise and the worst-case sinusoid — the frequency where
    the largest singular value of the nominal linear map ``w -> z`` peaks, along its top input
    direction. On a finite horizon a causal system's gain can only be smaller than its
    infinite-horizon bound, so a measured ratio above ``gamma`` (beyond :data:`TOLERANCE`
    for quadrature) means the theorem, its transcription or the certificate is wrong.
``decay rate``
    the slope of ``log ||e(k)||`` over the second half of the nominal linear run (``w = 0``,
    ``F = 0``, ``f = 0``), which must be at least the certified ``beta`` (per step).

Each check is a dict ``{"property", "certified", "measured", "ok", "detail"}``; ``ok`` is False
for a violation (``lmic simulate`` then exits 1 and prints a red flag).

Examples
--------
>>> import numpy as np
>>> l2_ratio(np.array([[1.0], [0.5]]), np.array([[2.0], [0.0]]), np.array([0.0, 1.0]), "discrete")
0.5590169943749475
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from lmic.simulate.families import Custom
from lmic.simulate.lti import TimeSignal, as_signal, constant_signal
from lmic.simulate.models import Observer

__all__ = ["checks", "l2_ratio", "peak_frequency", "decay_rate", "TOLERANCE"]

#: relative slack on a measured gain: 1e-9 in discrete time (exact sums), 2 % in continuous
#: time (trapezoidal quadrature of an integrated trajectory)
TOLERANCE = {"discrete": 1e-9, "continuous": 0.02}


def l2_ratio(z: np.ndarray, w: np.ndarray, t: np.ndarray, time: str) -> float:
    """``||z||_2 / ||w||_2`` over the samples (sums in discrete time, trapezoids in continuous).

    Examples
    --------
    >>> t = np.linspace(0, 1, 101)
    >>> round(l2_ratio(np.c_[2 * np.ones(101)], np.c_[np.ones(101)], t, "continuous"), 12)
    2.0
    """
    zz = np.sum(np.abs(z) ** 2, axis=1)
    ww = np.sum(np.abs(w) ** 2, axis=1)
    if time == "discrete":
        num, den = float(zz.sum()), float(ww.sum())
    else:
        num, den = float(np.trapezoid(zz, t)), float(np.trapezoid(ww, t))
    return float(np.sqrt(num / den)) if den > 0 else 0.0


def peak_frequency(
    G: Callable[[float], np.ndarray], time: str, dt: float, horizon: float
) -> tuple[float, np.ndarray, float]:
    """``(omega*, v, sigma_max)``: the frequency where ``sigma_max(G)`` peaks on a grid, and the
    top right singular vector there.

    Discrete time: ``omega`` in ``[0, pi]`` per step; continuous: from ``2 pi / horizon`` up to
    a fifth of the grid's Nyquist frequency ``pi / dt`` (log spaced).

    Examples
    --------
    >>> G = lambda om: np.array([[1.0 / (np.exp(1j * om) - 0.5)]])
    >>> om, v, s = peak_frequency(G, "discrete", 1.0, 100.0)
    >>> om, round(s, 9)
    (0.0, 2.0)
    """
    if time == "discrete":
        grid = np.linspace(0.0, np.pi, 1025)
    else:
        lo = 2 * np.pi / horizon
        hi = max(lo * 2, 0.2 * np.pi / dt)
        grid = np.concatenate([[0.0], np.geomspace(lo, hi, 800)])
    best = (-1.0, 0.0, np.zeros(0, dtype=complex))
    for om in grid:
        try:
            M = G(float(om))
        except np.linalg.LinAlgError:
            continue
        _u, s, vh = np.linalg.svd(M)
        if s.size and s[0] > best[0]:
            best = (float(s[0]), float(om), vh[0].conj())
    # refine around the best grid point
    sig, om0, v = best
    step = (grid[1] - grid[0]) if time == "discrete" else om0 * 0.02
    for om in np.linspace(max(0.0, om0 - step), om0 + step, 41):
        try:
            _u, s, vh = np.linalg.svd(G(float(om)))
        except np.linalg.LinAlgError:
            continue
        if s[0] > sig:
            sig, om0, v = float(s[0]), float(om), vh[0].conj()
    return om0, v, sig


def decay_rate(t: np.ndarray, err: np.ndarray) -> float:
    """Least-squares slope of ``-log ||e||`` over the second half of the run (per unit of ``t``).

    Samples below ``1e-250`` (underflow) are left out.

    Examples
    --------
    >>> k = np.arange(50.0)
    >>> round(decay_rate(k, 3 * np.exp(-0.2 * k)), 9)
    0.2
    """
    half = t >= t[0] + 0.5 * (t[-1] - t[0])
    keep = half & (err > 1e-250)
    if keep.sum() < 2:
        return float("inf")
    slope = np.polyfit(t[keep], np.log(err[keep]), 1)[0]
    return float(-slope)


def _signals(
    obs: Custom, spec: Any, G: Callable[[float], np.ndarray] | None, time: str
) -> list[tuple[str, TimeSignal]]:
    """The test disturbances, each a vectorised :class:`~lmic.simulate.lti.TimeSignal`."""
    nw = obs.w_dim
    dt, T = spec.dt, spec.horizon
    ones = np.ones(nw) / np.sqrt(nw)
    out: list[tuple[str, TimeSignal]] = []
    own = obs.disturbance(spec)
    if spec.extra.get("w"):
        out.append(("the section's disturbance", as_signal(own, nw)))
    if time == "discrete":
        out.append(("unit pulse at k = 0", TimeSignal(nw, lambda ts: (np.abs(ts) < 0.5 * dt)[:, None] * ones)))
    else:
        out.append(("pulse on [0, 10 dt)", TimeSignal(nw, lambda ts: (ts < 10 * dt)[:, None] * ones)))
    out.append(("step", constant_signal(ones)))
    steps = max(1, int(round(T / dt)))
    noise = np.random.default_rng(0).standard_normal((steps + 2, nw))

    def white(ts: np.ndarray) -> np.ndarray:
        return noise[np.minimum(np.rint(ts / dt).astype(int), steps + 1)]

    out.append(("white noise (seed 0)", TimeSignal(nw, white)))
    if G is not None:
        om, v, sig = peak_frequency(G, time, dt, T)
        amp, ph = np.abs(v), np.angle(v)
        scale = 1.0 / dt if time == "discrete" else 1.0  # discrete time: omega is per step
        unit = "rad/step" if time == "discrete" else "rad/s"
        label = f"worst-case sinusoid (omega = {om:.4g} {unit}, sigma_max = {sig:.4g})"
        out.append((label, TimeSignal(nw, lambda ts: amp * np.cos(om * scale * ts[:, None] + ph))))
    return out


def checks(obs: Observer, spec: Any, fn: Any) -> list[dict[str, Any]]:
    """The certificate checks for ``obs`` (empty for a model that certifies no number).

    Parameters
    ----------
    obs : Observer
        With the roles ``gamma`` (certified L2 gain) and/or ``decay`` (certified decay rate).
    spec : SimulationSpec
    fn : the section's functions (``f``, ``u``) as :func:`lmic.simulate.run.run` builds them
    """
    if not isinstance(obs, Custom):
        return []
    out: list[dict[str, Any]] = []
    time = obs.time
    gamma = obs.mats.get(obs.gain_role)
    if gamma is not None and obs.w_dim > 0:
        g = float(np.asarray(gamma).ravel()[0])
        sysG = obs.gain_system()
        G = sysG[0] if sysG else None
        worst = (-1.0, "")
        rows = []
        for label, w in _signals(obs, spec, G, time):
            res = obs.custom_run(spec, fn, w=w, linear=True, zero=True)
            ratio = l2_ratio(res["signals"]["z"], res["signals"]["w"], res["t"], time)
            rows.append({"signal": label, "ratio": ratio})
            if ratio > worst[0]:
                worst = (ratio, label)
        tol = TOLERANCE[time]
        out.append(
            {
                "property": "L2 gain w -> z",
                "certified": g,
                "measured": worst[0],
                "ok": bool(worst[0] <= g * (1 + tol)),
                "detail": f"largest ||z||2/||w||2 by {worst[1]}; zero initial state, f = 0"
                + (", the section's F(k)" if getattr(obs, "r", 0) else ""),
                "signals": rows,
            }
        )
    beta = obs.mats.get("decay")
    if beta is not None:
        b = float(np.asarray(beta).ravel()[0])
        res = obs.custom_run(spec, fn, w=constant_signal(np.zeros(obs.w_dim)), linear=True, nominal=True)
        err = np.linalg.norm(res["x"] - res["xhat"], axis=1)
        steps = res["t"] / spec.dt
        rate = decay_rate(steps, err)
        out.append(
            {
                "property": "decay rate (per step)",
                "certified": b,
                "measured": rate,
                "ok": bool(rate >= b * (1 - 1e-3)),
                "detail": "slope of -log||e(k)|| over the second half; nominal (F = 0), w = 0, f = 0",
            }
        )
    alpha = obs.mats.get("alpha")
    if alpha is not None and obs.name == "obs_control":
        a = float(np.asarray(alpha).ravel()[0])
        res = obs.custom_run(spec, fn, linear=True)
        t = res["t"]
        tail = np.linalg.norm(res["x"][t >= t[0] + 0.8 * (t[-1] - t[0])], axis=1)
        sup = float(tail.max())
        out.append(
            {
                "property": "practical stability sup ||x|| (last 20 %)",
                "certified": a,
                "measured": sup,
                "ok": None,
                "detail": "linear part (f = 0) with the section's unknown input; informative only: the "
                "theorem bounds x once it has entered the ball, and the time to enter is not certified",
            }
        )
    return out
