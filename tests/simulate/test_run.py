"""Simulation: observer models against independent closed forms, the section's validation, and
blow-ups reported with their time."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp

from lmic.errors import DataError
from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
from lmic.schemas import load_schema
from lmic.simulate.models import MODELS, make_observer
from lmic.simulate.plot import plot_png
from lmic.simulate.run import (
    KEYS,
    SimulationDiverged,
    Trajectory,
    check_section,
    observer_for,
    read_spec,
    run,
    simulate,
)

A2 = np.array([[0.0, 1.0], [-2.0, -0.3]])
C2 = np.array([[1.0, 0.0]])
L_CT = np.array([[3.0], [4.0]])  # A - L C Hurwitz
AD = np.array([[1.0, 0.1], [-0.2, 0.97]])
L_DT = np.array([[0.9], [1.5]])  # A - L C Schur


def luenberger(time="discrete", **extra):
    A, L = (AD, L_DT) if time == "discrete" else (A2, L_CT)
    return make_observer("luenberger", time, {"A": A, "C": C2, "L": L, **extra})


# -- models -------------------------------------------------------------------------------------


def test_discrete_luenberger_matches_a_hand_written_loop():
    obs = luenberger(B=np.array([[0.0], [0.1]]))
    sec = {"nonlinearity": ["0", "-0.05*sin(x1)"], "input": "cos(t)", "x0": [1, -1], "xhat0": [0.2, 0], "horizon": 3,
           "dt": 0.1}  # fmt: skip
    traj = run(obs, read_spec(sec, obs))
    x, xh = np.array([1.0, -1.0]), np.array([0.2, 0.0])
    B = np.array([0.0, 0.1])
    for k in range(31):
        t = 0.1 * k
        np.testing.assert_allclose(traj.x[k], x, atol=1e-14)
        np.testing.assert_allclose(traj.xhat[k], xh, atol=1e-14)
        f = lambda v: np.array([0.0, -0.05 * np.sin(v[0])])  # noqa: E731
        y = C2 @ x
        x, xh = AD @ x + B * np.cos(t) + f(x), AD @ xh + B * np.cos(t) + f(xh) + L_DT @ (y - C2 @ xh)
    assert traj.t[-1] == pytest.approx(3.0) and traj.decayed


def test_continuous_linear_error_follows_the_matrix_exponential():
    obs = luenberger("continuous")
    sec = {"x0": [1, 0], "xhat0": [0, 0.5], "horizon": 2.0, "dt": 0.01, "input": "sin(t)"}
    traj = run(obs, read_spec(sec, obs))
    e0 = np.array([1.0, -0.5])
    for k in (50, 100, 200):
        want = sla.expm((A2 - L_CT @ C2) * traj.t[k]) @ e0
        np.testing.assert_allclose(traj.x[k] - traj.xhat[k], want, atol=2e-6)
    np.testing.assert_allclose(traj.x[-1], sla.expm(A2 * 2.0) @ np.array([1.0, 0.0]), atol=1e-6)


def _sampled_error_map(A, C, L, h):
    """e(t_k+1) = (e^{A h} + int_0^h e^{A s} ds L C) e(t_k) for e' = A e + L C e(t_k)."""
    n = A.shape[0]
    big = np.zeros((2 * n, 2 * n))
    big[:n, :n], big[:n, n:] = A, np.eye(n)
    E = sla.expm(big * h)
    return E[:n, :n] + E[:n, n:] @ L @ C


def test_sampled_error_follows_the_exact_sample_map():
    L = np.array([[-2.0], [-1.0]])  # the sampled model's sign: A + L C Hurwitz
    obs = make_observer("sampled", "sampled", {"A": A2, "C": C2, "L": L})
    h = 0.1
    sec = {"x0": [1, 0], "xhat0": [0, 0], "horizon": 1.0, "dt": 0.05, "sampling": {"min": h, "max": h}}
    traj = run(obs, read_spec(sec, obs))
    np.testing.assert_allclose(traj.samples, np.arange(10) * h, atol=1e-12)
    Phi = _sampled_error_map(A2, C2, L, h)
    e = np.array([1.0, 0.0])
    for k in range(1, 11):
        e = Phi @ e
        idx = int(round(k * h / 0.05))
        np.testing.assert_allclose(traj.x[idx] - traj.xhat[idx], e, atol=1e-6)


def test_random_sampling_is_seeded_and_bounded():
    L = np.array([[-2.0], [-1.0]])
    obs = make_observer("sampled", "sampled", {"A": A2, "C": C2, "L": L})
    sec = {"x0": [1, 0], "horizon": 2.0, "dt": 0.01, "sampling": {"min": 0.01, "max": 0.2, "seed": 3}}
    a = run(obs, read_spec(sec, obs))
    b = run(obs, read_spec(sec, obs))
    c = run(obs, read_spec({**sec, "sampling": {"min": 0.01, "max": 0.2, "seed": 4}}, obs))
    np.testing.assert_array_equal(a.samples, b.samples)
    assert not np.array_equal(a.samples, c.samples)
    gaps = np.diff(a.samples)
    assert gaps.min() >= 0.01 - 1e-12 and gaps.max() <= 0.2 + 1e-12
    assert a.final_error < 0.2 * a.initial_error and a.summary()["samples"] == a.samples.size


def _uio_design():
    """n = 2, C = I, unknown input through D1 = e1: E = -e1 e1^T gives M D1 = 0; N = 0.5 I."""
    A = np.array([[0.9, 0.2], [-0.1, 0.8]])
    C = np.eye(2)
    D1 = np.array([[1.0], [0.0]])
    E = np.array([[-1.0, 0.0], [0.0, 0.0]])
    M = np.eye(2) + E @ C
    K = M @ A - 0.5 * np.eye(2)
    N = M @ A - K @ C
    L = K @ (np.eye(2) + C @ E) - M @ A @ E
    return {"A": A, "C": C, "D1": D1, "E": E, "M": M, "N": N, "L": L}


def test_unknown_input_observer_rejects_the_unknown_input():
    obs = make_observer("uio", "discrete", _uio_design())
    sec = {"x0": [1, 2], "xhat0": [0, 0], "unknown_input": "5*sin(t) + 3", "horizon": 40, "dt": 1}
    traj = run(obs, read_spec(sec, obs))
    err = traj.error_norm
    np.testing.assert_allclose(err[1:], 0.5 ** np.arange(40) * err[1], rtol=1e-9, atol=1e-13)
    assert np.abs(traj.x).max() > 10  # the unknown input moves the plant
    assert traj.final_error < 1e-11


def test_unknown_input_observer_initial_state_z0_or_xhat0():
    obs = make_observer("uio", "continuous", _uio_design())
    spec = read_spec({"x0": [1, 2], "xhat0": [0.5, 0.5], "horizon": 0.1}, obs)
    traj = run(obs, spec)
    np.testing.assert_allclose(traj.xhat[0], [0.5, 0.5], atol=1e-12)
    traj = run(obs, read_spec({"x0": [1, 2], "z0": [0, 0], "horizon": 0.1}, obs))
    np.testing.assert_allclose(traj.xhat[0], -obs.E @ np.array([1.0, 2.0]), atol=1e-12)


def test_input_through_B_equals_input_through_the_nonlinearity():
    B = np.array([[0.0], [0.1]])
    base = {"x0": [1, -1], "horizon": 2, "dt": 0.1, "input": "sin(t)"}
    with_b = luenberger(B=B)
    a = run(with_b, read_spec({**base, "nonlinearity": ["0", "0"]}, with_b))
    plain = luenberger()
    b = run(plain, read_spec({**base, "nonlinearity": ["0", "0.1*u"]}, plain))
    np.testing.assert_allclose(a.x, b.x, atol=1e-14)
    np.testing.assert_allclose(a.xhat, b.xhat, atol=1e-14)


def test_output_nonlinearity_enters_plant_and_observer():
    """h = 0.5 x2 makes the output (C + [0 0.5]) x: the run equals the linear one with that C."""
    C_h = C2 + np.array([[0.0, 0.5]])
    obs = luenberger()
    a = run(obs, read_spec({"x0": [1, 1], "horizon": 3, "dt": 0.1, "output_nonlinearity": ["0.5*x2"]}, obs))
    lin = make_observer("luenberger", "discrete", {"A": AD, "C": C_h, "L": L_DT})
    b = run(lin, read_spec({"x0": [1, 1], "horizon": 3, "dt": 0.1}, lin))
    np.testing.assert_allclose(a.xhat, b.xhat, atol=1e-13)
    assert run(obs, read_spec({"x0": [1, 1], "horizon": 3, "output_nonlinearity": {"y1": "0.5*x2"}}, obs)).t.size == 4


def test_mapping_and_list_nonlinearities_agree():
    obs = luenberger("continuous")
    a = run(obs, read_spec({"x0": [1, 0], "horizon": 1, "nonlinearity": {"x2": "-sin(x1)"}}, obs))
    b = run(obs, read_spec({"x0": [1, 0], "horizon": 1, "nonlinearity": [0, "-sin(x1)"]}, obs))
    np.testing.assert_array_equal(a.x, b.x)


def test_noise_is_seeded():
    obs = luenberger()
    sec = {"x0": [1, 0], "horizon": 5, "noise": {"std": 0.1, "seed": 7}}
    a, b = run(obs, read_spec(sec, obs)), run(obs, read_spec(sec, obs))
    np.testing.assert_array_equal(a.xhat, b.xhat)
    c = run(obs, read_spec({**sec, "noise": {"std": [0.1], "seed": 8}}, obs))
    assert not np.array_equal(a.xhat, c.xhat)
    np.testing.assert_array_equal(a.x, c.x)  # measurement noise does not touch the plant
    ct = luenberger("continuous")
    sec = {"x0": [1, 0], "horizon": 1, "dt": 0.01}
    clean = run(ct, read_spec(sec, ct))
    noisy = run(ct, read_spec({**sec, "noise": {"std": 0.01, "seed": 1}}, ct))
    gap = np.abs(noisy.xhat - clean.xhat).max()
    assert 1e-4 < gap < 0.1


# -- blow-ups -----------------------------------------------------------------------------------


def test_continuous_blow_up_names_the_time():
    """x1' = x1^2 from x1 = 1 escapes at t = 1."""
    obs = make_observer("luenberger", "continuous", {"A": np.zeros((1, 1)), "C": np.eye(1), "L": np.eye(1)})
    with pytest.raises(SimulationDiverged) as info:
        run(obs, read_spec({"x0": [1], "horizon": 2, "nonlinearity": ["x1**2"]}, obs, where="p.yaml: simulation"))
    assert info.value.time == pytest.approx(1.0, abs=1e-3)
    assert str(info.value).startswith("p.yaml: simulation: the plant state blew up at t = 1 (")
    assert isinstance(info.value, DataError)


def test_discrete_blow_up_names_the_step_time():
    obs = make_observer("luenberger", "discrete", {"A": np.eye(1), "C": np.eye(1), "L": np.zeros((1, 1))})
    with pytest.raises(SimulationDiverged, match=r"the plant state blew up at t = 0\.4 ") as info:
        # 10, 110, 12210, 1.5e8, 2.2e16 > 1e12 at k = 4
        run(obs, read_spec({"x0": [10], "horizon": 5, "dt": 0.1, "nonlinearity": ["x1**2"]}, obs))
    assert info.value.time == pytest.approx(0.4)


def test_observer_blow_up_and_non_finite_values():
    obs = make_observer("luenberger", "discrete", {"A": np.eye(1) * 0.5, "C": np.eye(1), "L": np.eye(1) * -3})
    with pytest.raises(SimulationDiverged, match="the observer state blew up at t = "):
        run(obs, read_spec({"x0": [1], "horizon": 100}, obs))
    # log of a negative state: NaN at the first step
    with pytest.raises(SimulationDiverged, match=r"plant state blew up at t = 1 "):
        run(obs, read_spec({"x0": [-1], "horizon": 5, "nonlinearity": ["log(x1)"]}, obs))
    ct = make_observer("luenberger", "continuous", {"A": -np.eye(1), "C": np.eye(1), "L": np.eye(1)})
    with pytest.raises(SimulationDiverged, match="blew up at t = "):
        run(ct, read_spec({"x0": [1], "horizon": 5, "nonlinearity": ["sqrt(x1 - 0.5)"]}, ct))


def test_sampled_blow_up():
    obs = make_observer("sampled", "sampled", {"A": np.eye(1), "C": np.eye(1), "L": -np.eye(1)})
    sec = {"x0": [1], "horizon": 3, "nonlinearity": ["x1**2"], "sampling": {"max": 0.1}}
    with pytest.raises(SimulationDiverged, match="plant state blew up at t = 0.6"):
        run(obs, read_spec(sec, obs))


# -- validation ---------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("section", "message"),
    [
        ([1, 2], "simulation: must be a mapping"),
        ({"x0": [1, 0], "horizon": 1, "steps": 3}, "unknown key 'steps' (allowed: nonlinearity,"),
        ({"x0": [1, 0], "horizon": 1, "noise": {"sigma": 1}}, "simulation.noise: unknown key 'sigma'"),
        ({"x0": [1, 0], "horizon": 1, "sampling": {"max": 1, "every": 2}}, "simulation.sampling: unknown key 'every'"),
        ({"x0": [1, 0]}, "simulation: 'horizon' is required"),
        ({"x0": [1, 0], "horizon": -1}, "simulation.horizon: -1 is less than or equal to the minimum of 0"),
        ({"x0": [1, 0], "horizon": "ten"}, "simulation.horizon: 'ten' is not of type 'number'"),
        ({"x0": "zero", "horizon": 1}, "simulation.x0: 'zero' is not of type 'array'"),
        ({"x0": [1, "a"], "horizon": 1}, "simulation.x0[2]: 'a' is not of type 'number'"),
        ({"x0": [1, 0], "horizon": 1, "nonlinearity": 3}, "simulation.nonlinearity: 3 is not a list of expressions"),
        ({"x0": [1, 0], "horizon": 1, "nonlinearity": {"z1": "1"}}, "simulation.nonlinearity"),
        ({"x0": [1, 0], "horizon": 1, "noise": {"std": -1}}, "simulation.noise.std"),
        ({"x0": [1, 0], "horizon": 1, "method": "Euler"}, "simulation.method: 'Euler' is not one of"),
    ],
)
def test_section_errors(section, message):
    with pytest.raises(DataError) as info:
        check_section(section)
    assert message in str(info.value)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize(
    ("model", "section", "message"),
    [
        ("dt", {"x0": [1], "horizon": 1}, "x0: has 1 entries, expected 2"),
        ("dt", {"x0": [1, 0], "xhat0": [0, 0, 0], "horizon": 1}, "xhat0: has 3 entries, expected 2"),
        ("dt", {"x0": [1, 0], "horizon": 1, "nonlinearity": ["x1"]}, "nonlinearity: has 1 entries, expected 2"),
        ("dt", {"x0": [1, 0], "horizon": 1, "nonlinearity": {"x3": "1"}}, "'x3' is out of range (x1..x2)"),
        ("dt", {"x0": [1, 0], "horizon": 1, "nonlinearity": ["0", "import os"]},
         "simulation.nonlinearity[2]: unknown name 'import' at column 1"),
        ("dt", {"x0": [1, 0], "horizon": 1, "nonlinearity": ["0", "u"]},
         "simulation.nonlinearity[2]: unknown name 'u' at column 1 (allowed: t, x1, x2)"),
        ("dt", {"x0": [1, 0], "horizon": 1, "input": "x1"},
         "simulation.input[1]: unknown name 'x1' at column 1 (allowed: t)"),
        ("dt", {"x0": [1, 0], "horizon": 1, "z0": [0, 0]}, "'z0' applies to unknown-input observers"),
        ("dt", {"x0": [1, 0], "horizon": 1, "unknown_input": "1"}, "'unknown_input' needs an unknown-input matrix"),
        ("dt", {"x0": [1, 0], "horizon": 1, "sampling": {"max": 0.1}}, "'sampling' applies to sampled observers"),
        ("dt", {"x0": [1, 0], "horizon": 1, "method": "BDF"}, "'method' applies to continuous time"),
        ("dt", {"x0": [1, 0], "horizon": 1e9}, "points (at most 200000)"),
        ("dt", {"x0": [1, 0], "horizon": 1, "noise": {"std": [1, 2]}}, "noise.std: has 2 entries, expected 1"),
        ("sampled", {"x0": [1, 0], "horizon": 1}, "the sampled observer needs 'sampling"),
        ("sampled", {"x0": [1, 0], "horizon": 1, "sampling": {"min": 0.2, "max": 0.1}}, "min = 0.2 is larger than max"),
        ("sampled", {"x0": [1, 0], "horizon": 1e3, "sampling": {"min": 1e-4, "max": 0.1}}, "samples (at most"),
        ("uio", {"x0": [1, 0], "horizon": 1, "output_nonlinearity": ["x1", "0"]}, "assumes y = C x"),
        ("uio", {"x0": [1, 0], "horizon": 1, "z0": [0, 0], "xhat0": [0, 0]}, "either 'xhat0' or 'z0'"),
        ("uio", {"x0": [1, 0], "horizon": 1, "unknown_input": ["1", "2"]}, "unknown_input: has 2 entries"),
    ],
)  # fmt: skip
def test_spec_errors(model, section, message):
    obs = {
        "dt": lambda: luenberger(),
        "sampled": lambda: make_observer("sampled", "sampled", {"A": A2, "C": C2, "L": -L_CT}),
        "uio": lambda: make_observer("uio", "discrete", _uio_design()),
    }[model]()
    with pytest.raises(DataError) as info:
        read_spec(section, obs)
    assert message in str(info.value)


def test_yaml_style_numeric_strings_are_numbers():
    obs = luenberger()
    spec = read_spec({"x0": ["1e-3", 0], "horizon": "2e0", "dt": "5e-1"}, obs)
    assert spec.x0[0] == 1e-3 and spec.horizon == 2.0 and spec.dt == 0.5
    assert set(KEYS) == set(load_schema("simulation")["properties"])


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (("kalman", "discrete", {}), "unknown observer model 'kalman' (known: euler, filter_error, luenberger, "),
        (("luenberger", "sampled", {}), "runs in discrete or continuous time, not 'sampled'"),
        (("sampled", "continuous", {}), "runs in sampled time"),
        (("luenberger", "discrete", {"A": AD, "C": C2}), "needs the role(s) L"),
        (("luenberger", "discrete", {"A": AD, "C": C2, "L": L_DT, "K": L_DT}), "has no role K"),
        (("luenberger", "discrete", {"A": AD, "C": C2, "L": L_DT.T}), "role L ('L') has shape 1x2, expected 2x1"),
        (("luenberger", "discrete", {"A": AD, "C": C2, "L": L_DT * np.nan}), "role L ('L') has non-finite"),
        (("uio", "discrete", {**_uio_design(), "G": np.ones((2, 1))}), "role G ('G') given without B"),
    ],
)
def test_model_errors(args, message):
    with pytest.raises(DataError) as info:
        make_observer(*args)
    assert message in str(info.value)
    assert sorted(MODELS) == [
        "euler", "filter_error", "luenberger", "obs_control", "reduced", "robust", "sampled", "ui_filter", "uio"
    ]  # fmt: skip


# -- from a solved problem ------------------------------------------------------------------------


def _problem(observer=None):
    """A tiny IR whose variable is the gain L (2 x 1) and whose data are A and C."""
    var = Variable("L", "full", (2, 1))
    lmi = LMI("dummy", 1, sp.csc_matrix(np.array([[1.0, 0.0, 0.0]])))
    meta = {"theorem": "demo.thm"}
    if observer:
        meta["observer"] = observer
    return Problem(
        [var],
        [lmi],
        LinearConstraints.empty(2),
        Objective("feasibility", [0, 0, 0]),
        data={"A": AD.tolist(), "C": C2.tolist()},
        meta=meta,
    )


def test_observer_for_a_problem_and_simulate_from_a_system_dict():
    decl = {"model": "luenberger", "time": "discrete", "roles": {"A": "A", "C": "C", "L": "L"}}
    prob = _problem(decl)
    obs = observer_for(prob, L_DT.ravel())
    np.testing.assert_allclose(obs.L, L_DT)
    system = {"lmic": 1, "data": {"A": AD.tolist()}, "simulation": {"x0": [1, 0], "horizon": 4}}
    obs, traj = simulate(prob, L_DT.ravel(), system)
    assert isinstance(traj, Trajectory) and traj.t.size == 5
    with pytest.raises(DataError, match="has no 'simulation:' section"):
        simulate(prob, L_DT.ravel(), {"lmic": 1, "data": {"A": [[1]]}})
    with pytest.raises(DataError, match="<system>: simulation: unknown key 'xo'"):
        simulate(prob, L_DT.ravel(), {"lmic": 1, "data": {"A": [[1]]}, "simulation": {"xo": [1], "horizon": 1}})


def test_observer_for_errors():
    with pytest.raises(DataError, match="theorem demo.thm declares no observer"):
        observer_for(_problem(), L_DT.ravel())
    decl = {"model": "luenberger", "time": "discrete", "roles": {"A": "A", "C": "C", "L": "Lbar"}}
    with pytest.raises(DataError, match="observer role L names 'Lbar', which the problem does not define"):
        observer_for(_problem(decl), L_DT.ravel())
    with pytest.raises(DataError, match="no solution"):
        observer_for(_problem(decl), None)


def test_plot_png_of_every_time_kind():
    obs = make_observer("sampled", "sampled", {"A": A2, "C": C2, "L": -L_CT})
    traj = run(obs, read_spec({"x0": [1, 0], "horizon": 1, "sampling": {"max": 0.1}}, obs))
    png = plot_png(traj, "demo")
    assert png.startswith(b"\x89PNG") and len(png) > 10_000
    one = Trajectory(np.arange(3.0), np.zeros((3, 1)), np.zeros((3, 1)), "luenberger", "discrete")
    assert plot_png(one).startswith(b"\x89PNG")  # zero error: the log axis still works
