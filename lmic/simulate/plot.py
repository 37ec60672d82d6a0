"""Figures of a simulated run, drawn with matplotlib's Agg canvas (no display, no pyplot state).

Like the papers' figures: one panel per state with the true state (solid) and its estimate
(dashed), one panel per reconstructed unknown input (``nu`` against ``nu^``, the reduced-order
filters of Papers D and E) and for the control input (observer-based control, Paper F), and a
last panel with the estimation error norm ``|x - xhat|`` on a log scale. Certificate checks
(certified against measured, :mod:`lmic.simulate.certificate`) are printed under the title, a
violation in red.

Examples
--------
>>> import numpy as np
>>> from lmic.simulate.trajectory import Trajectory
>>> t = np.linspace(0, 1, 11)
>>> traj = Trajectory(t, np.c_[np.cos(t), np.sin(t)], np.c_[np.cos(t), np.sin(t) * (1 - np.exp(-t))],
...                   "luenberger", "continuous")
>>> png = plot_png(traj, title="demo")
>>> png[:8] == b"\\x89PNG\\r\\n\\x1a\\n"
True
"""

from __future__ import annotations

import io
import math
from typing import Any

import numpy as np

from lmic.simulate.trajectory import Trajectory

__all__ = ["figure", "plot_png"]

_TRUE = "#1f4e9c"
_EST = "#d9480f"
_ERR = "#2b8a3e"


def figure(traj: Trajectory, title: str = "") -> object:
    """A matplotlib :class:`~matplotlib.figure.Figure` of ``traj`` (Agg canvas attached).

    States fill a grid of two columns; the error norm spans the bottom row.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D

    n = traj.x.shape[1]
    extra = _extra_panels(traj)
    panels = n + len(extra)
    cols = 1 if panels == 1 else 2
    rows = math.ceil(panels / cols)
    foot = 0.22 * len(traj.checks)
    height = 1.9 * rows + 2.4 + foot
    fig = Figure(figsize=(5.2 * cols, height), dpi=100)
    FigureCanvasAgg(fig)
    gs = fig.add_gridspec(rows + 1, cols, height_ratios=[1.0] * rows + [1.25])
    fig.subplots_adjust(
        left=0.08, right=0.985, top=1 - 0.75 / height, bottom=(0.5 + foot) / height, hspace=0.32, wspace=0.2
    )
    discrete = traj.time == "discrete"
    style: dict[str, Any] = {"marker": ".", "markersize": 3} if discrete and traj.t.size <= 200 else {}
    dt = float(traj.t[1] - traj.t[0]) if traj.t.size > 1 else 1.0
    xlabel = ("sample k" if abs(dt - 1.0) < 1e-12 else f"t = k T (s), T = {dt:g} s") if discrete else "t (s)"
    first = None
    for i in range(n):
        ax = fig.add_subplot(gs[i // cols, i % cols], sharex=first)
        first = first or ax
        ax.plot(traj.t, traj.x[:, i], color=_TRUE, lw=1.4, **style)
        ax.plot(traj.t, traj.xhat[:, i], color=_EST, lw=1.2, ls="--", **style)
        ax.set_ylabel(f"$x_{{{i + 1}}}$")
        ax.grid(alpha=0.3)
        ax.tick_params(labelbottom=i >= panels - cols)
    for j, (label, true, est) in enumerate(extra):
        i = n + j
        ax = fig.add_subplot(gs[i // cols, i % cols], sharex=first)
        ax.plot(traj.t, true, color=_TRUE, lw=1.4, **style)
        if est is not None:
            ax.plot(traj.t, est, color=_EST, lw=1.2, ls="--", **style)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
        ax.tick_params(labelbottom=i >= panels - cols)
    ax = fig.add_subplot(gs[rows, :], sharex=first)
    err = traj.error_norm
    floor = max(float(err.max()) * 1e-16, 1e-300)
    ax.semilogy(traj.t, np.maximum(err, floor), color=_ERR, lw=1.4, **style)
    if traj.samples is not None and traj.samples.size <= 2000:
        lo = float(np.maximum(err, floor).min())
        ax.plot(traj.samples, np.full(traj.samples.size, lo), "|", color="0.45", ms=7)
    ax.set_ylabel(r"$\|x - \hat{x}\|$")
    ax.set_xlabel(xlabel)
    ax.grid(alpha=0.3, which="major")
    handles = [
        Line2D([], [], color=_TRUE, lw=1.4, label="true state $x_i$"),
        Line2D([], [], color=_EST, lw=1.2, ls="--", label=r"estimate $\hat{x}_i$"),
        Line2D([], [], color=_ERR, lw=1.4, label=r"error norm $\|x - \hat{x}\|$"),
    ]
    if traj.samples is not None:
        handles.append(Line2D([], [], color="0.45", ls="none", marker="|", ms=7, label="samples $t_k$"))
    fig.legend(
        handles=handles,
        loc="upper center",
        ncols=len(handles),
        fontsize=8.5,
        frameon=False,
        bbox_to_anchor=(0.5, 1 - 0.32 / height),
    )
    verdict = "decayed" if traj.decayed else "did not decay"
    head = f"{title}: " if title else ""
    fig.suptitle(
        f"{head}{traj.model} observer, {traj.time} time; final error {traj.final_error:.3g} ({verdict})",
        fontsize=10.5,
        y=1 - 0.06 / height,
        va="top",
    )
    for k, c in enumerate(traj.checks):
        ok = c.get("ok")
        word = {True: "holds", False: "VIOLATED", None: "informative"}[ok]
        fig.text(
            0.5,
            (0.08 + 0.22 * (len(traj.checks) - 1 - k)) / height,
            f"{c['property']}: certified {c['certified']:.4g}, measured {c['measured']:.4g} ({word})",
            ha="center",
            fontsize=8,
            color="#c92a2a" if ok is False else "0.25",
        )
    return fig


def _extra_panels(traj: Trajectory) -> list[tuple[str, np.ndarray, np.ndarray | None]]:
    """Reconstructed unknown inputs (``nu`` against ``nu_hat``) and the control input ``u``."""
    out: list[tuple[str, np.ndarray, np.ndarray | None]] = []
    nu, nu_hat = traj.signals.get("nu"), traj.signals.get("nu_hat")
    if nu is not None and nu_hat is not None:
        for i in range(nu.shape[1]):
            out.append((rf"$\nu_{{{i + 1}}}$, $\hat\nu_{{{i + 1}}}$", nu[:, i], nu_hat[:, i]))
    u = traj.signals.get("u")
    if u is not None:
        for i in range(u.shape[1]):
            out.append((f"control $u_{{{i + 1}}} = -K \\hat x$", u[:, i], None))
    return out


def plot_png(traj: Trajectory, title: str = "", dpi: int = 100) -> bytes:
    """The figure of ``traj`` as PNG bytes.

    Parameters
    ----------
    traj : Trajectory
    title : str
        Prefix of the figure title (e.g. the theorem id).
    dpi : int
    """
    fig = figure(traj, title)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)  # type: ignore[attr-defined]
    return buf.getvalue()
