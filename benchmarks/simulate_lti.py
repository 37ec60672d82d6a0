"""Simulator benchmark: the exact cubic-hold LTI integrator against RK45, interleaved.

The workload is the L2-gain check of the Paper D descriptor filter (``ui_filter``, the model of
the shipped ``descriptor.thm3_3`` and ``uir.thm4_1`` examples): the linear filter-error loop
driven by the worst-case sinusoid (``omega = 0.2 pi / dt``, 314 rad/s at ``dt = 0.002``) over
a 10 s horizon. ``rk45`` is what the simulator did before :mod:`lmic.simulate.lti`: scipy's
``solve_ivp`` (``rtol = 1e-8``, ``atol = 1e-10``, ``max_step = dt``) with the signal evaluated at
every stage; ``lti`` is :func:`lmic.simulate.lti.propagate`. The two methods run alternately
``--repeat`` times; the report gives the median time of each, their ratio, and the largest
difference between the two trajectories (relative to the largest state), which must stay far
below the 2 % quadrature tolerance of the gain check. Usage::

    python benchmarks/simulate_lti.py --repeat 5

Examples
--------
>>> A, B = descriptor_loop()
>>> A.shape, B.shape
((6, 6), (6, 3))
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
from scipy.integrate import solve_ivp

from lmic.simulate.lti import TimeSignal, propagate


def descriptor_loop() -> tuple[np.ndarray, np.ndarray]:
    """``(A, B)`` of ``[x; z]' = A [x; z] + B [w; nu]`` for the Paper D filter (tests/simulate)."""
    A = np.array([[-2.0, 1, 0], [0, -3, -1], [0, 1, -2]])
    C = np.array([[1.0, 0, 0], [0, 1, 0]])
    F = np.array([[1.0, 1], [0, 1], [1, 0]])
    G = np.eye(2)
    D1, D2 = np.ones((3, 1)), np.ones((2, 1))
    M = np.array([[1.0, 4, 2], [-2, 4, 0], [-3, -2, 3]])
    eta = np.hstack([np.eye(3), np.zeros((3, 2))])
    Ti = np.linalg.inv(np.vstack([M @ eta, np.hstack([C, G])]))
    Abar = np.hstack([A, F])
    N, L = M @ Abar @ Ti[:, :3], M @ Abar @ Ti[:, 3:]
    Acl = np.block([[A, np.zeros((3, 3))], [L @ C, N]])
    Bcl = np.hstack([np.vstack([D1, L @ D2]), np.vstack([F, L @ G])])
    return Acl, Bcl


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--horizon", type=float, default=10.0)
    ap.add_argument("--dt", type=float, default=0.002)
    args = ap.parse_args(argv)
    A, B = descriptor_loop()
    om = 0.2 * np.pi / args.dt
    amp = np.array([1.0, 0.0, 0.0])
    grid = np.linspace(0.0, args.horizon, int(round(args.horizon / args.dt)) + 1)
    s0 = np.zeros(A.shape[0])
    signal = TimeSignal(3, lambda ts: np.outer(np.cos(om * ts), amp))

    def rk45() -> np.ndarray:
        sol = solve_ivp(lambda t, s: A @ s + B @ signal(t), (0.0, args.horizon), s0, t_eval=grid,
                        rtol=1e-8, atol=1e-10, max_step=args.dt)  # fmt: skip
        return sol.y.T

    def lti() -> np.ndarray:
        return propagate(A, B, s0, grid, signal)

    methods = {"rk45": rk45, "lti": lti}
    times: dict[str, list[float]] = {k: [] for k in methods}
    out: dict[str, np.ndarray] = {}
    for r in range(args.repeat):
        for name in list(methods)[r % 2 :] + list(methods)[: r % 2]:  # rotated order
            t0 = time.perf_counter()
            out[name] = methods[name]()
            times[name].append(time.perf_counter() - t0)
    med = {k: statistics.median(v) for k, v in times.items()}
    diff = float(np.max(np.abs(out["rk45"] - out["lti"])) / np.max(np.abs(out["lti"])))
    print(f"omega = {om:.4g} rad/s, horizon {args.horizon:g} s, dt {args.dt:g}, {args.repeat} rounds")
    for k in methods:
        print(f"  {k:5s} median {med[k]:.3f} s")
    print(f"  ratio rk45 / lti = {med['rk45'] / med['lti']:.1f}; largest relative difference {diff:.2e}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
