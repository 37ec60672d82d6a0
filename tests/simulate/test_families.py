"""The observer families of :mod:`lmic.simulate.families`: each trajectory against an independent
reference (closed form, scipy's dlsim / lsim / expm / solve_ivp on the error system written out
here), the certificate checks (empirical L2 gain <= certified gamma, decay rate, and a check that
fires on a false certificate), and bad ``simulation:`` sections (one line, exit code 2)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.signal as ss
from scipy.integrate import solve_ivp

from lmic.cli import main
from lmic.errors import DataError
from lmic.simulate.certificate import checks, decay_rate, l2_ratio
from lmic.simulate.models import make_observer
from lmic.simulate.run import _Functions, read_spec, run

ROOT = Path(__file__).resolve().parents[2]
EX = ROOT / "examples"


def _simulate(obs, section):
    spec = read_spec(section, obs)
    return spec, run(obs, spec)


# -- reduced order (qib.thm2 / cor2) -----------------------------------------------------------

A4 = np.array([[1.0, 0.1, 0.0, 0.0], [-4.86, 0.874, 4.86, 0.0], [0.0, 0.0, 1.0, 1.0], [0.195, 0.0, -0.195, 1.0]])
C4 = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0]])
H4 = np.array([[0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]])


def _reduced(K):
    T = np.linalg.inv(np.vstack([H4, C4]))
    N, M = T[:, :2], T[:, 2:]
    return make_observer("reduced", "discrete", {"A": A4, "C": C4, "H": H4, "N": N, "M": M, "K": K}), N, M


def test_reduced_order_error_is_the_closed_form_power():
    K = np.array([[0.0, 0.3], [0.1, 0.2]])
    obs, N, M = _reduced(K)
    x0 = np.array([1.0, 0.5, 1.0, -0.5])
    xh0 = np.array([0.2, 0.0, -0.3, 0.4])
    _spec, traj = _simulate(obs, {"x0": x0.tolist(), "xhat0": xh0.tolist(), "horizon": 12, "dt": 1})
    AZ, CZ = H4 @ A4 @ N, C4 @ A4 @ N
    eps0 = H4 @ (x0 - xh0)
    for k in range(13):
        expect = N @ np.linalg.matrix_power(AZ - K @ CZ, k) @ eps0  # x - xhat = N (z - zhat)
        np.testing.assert_allclose(traj.x[k] - traj.xhat[k], expect, atol=1e-10)
    # the true state follows x+ = A x (no nonlinearity)
    np.testing.assert_allclose(traj.x[5], np.linalg.matrix_power(A4, 5) @ x0, rtol=1e-12)


def test_reduced_order_dead_beat_gain_and_nonlinearity():
    K = np.array([[0.0, 0.4115], [0.0, 0.1656]])  # A_Z - K C_Z nilpotent up to rounding of K
    obs, _N, _M = _reduced(K)
    sec = {"x0": [1, 0.5, 1, -0.5], "horizon": 2, "dt": 0.1, "input": "sin(t)",
           "nonlinearity": ["0", "2.16*u", "0", "-0.0333*sin(x3)"]}  # fmt: skip
    _spec, traj = _simulate(obs, sec)
    # the error obeys (20) with Delta g: check by re-running the observer equations by hand
    x = np.array(sec["x0"], dtype=float)
    zh = np.zeros(2)
    N, M = _N, _M
    for k in range(20):
        y = C4 @ x
        xh = N @ zh + M @ y
        np.testing.assert_allclose(traj.xhat[k], xh, atol=1e-12)
        u = np.sin(0.1 * k)
        fx = lambda v, u=u: np.array([0.0, 2.16 * u, 0.0, -0.0333 * np.sin(v[2])])  # noqa: E731
        x_next = A4 @ x + fx(x)
        zeta = A4 @ xh + fx(xh)
        zh = H4 @ A4 @ N @ zh + H4 @ A4 @ M @ y + H4 @ fx(xh) + K @ (C4 @ x_next - C4 @ zeta)
        x = x_next
    assert traj.final_error < 1e-3 * traj.peak_error


def test_reduced_order_rejects_inconsistent_coordinates():
    with pytest.raises(DataError, match=r"\[N M\] .* is not \[H; C\]\^-1"):
        make_observer("reduced", "discrete", {"A": A4, "C": C4, "H": H4, "N": np.ones((4, 2)), "M": np.ones((4, 2)),
                                              "K": np.zeros((2, 2))})  # fmt: skip


# -- uncertain delay systems (delay_a / delay_b / uncertain_dt) -------------------------------

AA = np.array([[-0.1, 0.2], [-0.3, -0.1]])
AD2 = np.array([[-0.1, 0.1], [-0.2, -0.1]])
BW = np.array([[1.0], [1.0]])
CA = np.array([[0.1, 0.1]])
DW = np.array([[0.7]])
LA = np.array([[1.0], [-1.0]])


def _robust(**extra):
    mats = {"A": AA, "C": CA, "L": LA, "Ad": AD2, "D1": BW, "D2": DW, "tau1": 0.0, "tau2": 2.0,
            "MA": np.array([[0.1], [-0.1]]), "MAd": np.array([[0.1], [0.2]]), "MC": np.array([[0.1]]),
            "NF": np.array([[0.1, 0.1]]), "Hz": 0.15 * np.eye(2)}  # fmt: skip
    mats.update(extra)
    return make_observer("robust", "discrete", mats)


def test_robust_constant_delay_matches_dlsim_of_the_augmented_system():
    # F = 0, constant delay tau = 2, f = 0: the augmented state [x(k), x(k-1), x(k-2), xhat(k)] is LTI
    obs = _robust()
    n = 2
    Z = np.zeros((n, n))
    I2 = np.eye(n)
    Aaug = np.block([[AA, Z, AD2, Z], [I2, Z, Z, Z], [Z, I2, Z, Z], [LA @ CA, Z, Z, AA - LA @ CA]])
    Baug = np.vstack([BW, np.zeros((2 * n, 1)), LA @ DW])
    Caug = np.hstack([I2, Z, Z, -I2])  # e = x - xhat
    x0 = np.array([2.0, 2.0])
    steps = 30
    k = np.arange(steps + 1)
    w = 1.0 / (k + 1.0)
    s0 = np.concatenate([x0, x0, x0, np.zeros(n)])  # history x(-1) = x(-2) = x(0)
    _t, yout, _x = ss.dlsim((Aaug, Baug, Caug, np.zeros((n, 1)), 1.0), w[:, None], t=k.astype(float), x0=s0)
    sec = {"x0": [2, 2], "xhat0": [0, 0], "horizon": steps, "dt": 1, "disturbance": "1/(k + 1)", "delay": "2"}
    _spec, traj = _simulate(obs, sec)
    np.testing.assert_allclose(traj.x - traj.xhat, yout, atol=1e-12)
    np.testing.assert_allclose(traj.signals["z"], 0.15 * yout, atol=1e-12)


def test_robust_time_varying_delay_and_uncertainty_by_hand():
    obs = _robust()
    sec = {"x0": [2, 2], "xhat0": [0, 0], "horizon": 15, "dt": 1, "disturbance": "1/(k + 1)",
           "uncertainty": "sin(k)", "delay": [0, 1, 2, 1], "nonlinearity": ["0.3*sin(x2)", "0.2*cos(x1)"]}  # fmt: skip
    _spec, traj = _simulate(obs, sec)
    M1, M2, M3, N = np.array([[0.1], [-0.1]]), np.array([[0.1], [0.2]]), np.array([[0.1]]), np.array([[0.1, 0.1]])
    f = lambda v: np.array([0.3 * np.sin(v[1]), 0.2 * np.cos(v[0])])  # noqa: E731
    X = [np.array([2.0, 2.0])]
    xh = np.zeros(2)
    for k in range(15):
        tau = [0, 1, 2, 1][k % 4]
        xd = X[k - tau] if k - tau >= 0 else X[0]
        F = np.sin(k)
        x = X[k]
        y = (CA + M3 * F @ N) @ x + DW[0] / (k + 1)
        np.testing.assert_allclose(traj.xhat[k], xh, atol=1e-12)
        X.append((AA + M1 * F @ N) @ x + (AD2 + M2 * F @ N) @ xd + f(x) + BW[:, 0] / (k + 1))
        xh = AA @ xh + f(xh) + LA @ (y - CA @ xh)
    np.testing.assert_allclose(traj.x, np.array(X), atol=1e-12)


def test_empirical_gain_never_exceeds_the_exact_hinf_norm():
    # F = 0, delay 0 (tau2 = 0): the map w -> z is LTI; its H-inf norm (computed here on a fine
    # grid from the closed form) bounds every finite-horizon ratio, and the worst-case sinusoid
    # comes close to it on a long horizon
    obs = _robust(tau2=0.0, gamma=10.0)
    # delay 0: x+ = (A + Ad) x + B w, e+ = (A - L C) e + Ad x + (B - L D) w (the observer has no
    # delayed term, so Ad x drives the error)
    Ae = np.block([[AA + AD2, np.zeros((2, 2))], [AD2, AA - LA @ CA]])
    Be = np.vstack([BW, BW - LA @ DW])
    Ce = np.hstack([np.zeros((2, 2)), 0.15 * np.eye(2)])
    grid = np.linspace(0, np.pi, 20001)
    hinf = max(np.linalg.norm(Ce @ np.linalg.solve(np.exp(1j * o) * np.eye(4) - Ae, Be), 2) for o in grid)
    spec = read_spec({"x0": [0, 0], "horizon": 400, "dt": 1}, obs)
    (res,) = checks(obs, spec, _Functions(spec, 2, 1))
    assert res["ok"] is True
    assert res["measured"] <= hinf * (1 + 1e-9)
    assert res["measured"] >= 0.95 * hinf
    assert "worst-case sinusoid" in res["detail"]


def test_a_false_certificate_is_flagged():
    obs = _robust(gamma=0.01)  # far below the true gain
    spec = read_spec({"x0": [0, 0], "horizon": 60, "dt": 1, "uncertainty": "sin(k)"}, obs)
    (res,) = checks(obs, spec, _Functions(spec, 2, 1))
    assert res["ok"] is False and res["measured"] > 0.01


def test_decay_rate_is_the_spectral_radius_rate():
    A3 = np.array([[0.1, 0.4, 0.1], [0.2, 0.1, 0.2], [-0.1, 0.3, 0.2]])
    C3 = np.array([[0.5, 0.2, 0.0], [0.0, 0.2, 0.1]])
    L3 = np.array([[0.3220, 1.0764], [0.3426, 1.1104], [-0.1205, 1.5892]])
    obs = make_observer("robust", "discrete", {"A": A3, "C": C3, "L": L3, "decay": 0.05})
    spec = read_spec({"x0": [0.3, -0.2, 0.5], "horizon": 30, "dt": 1}, obs)
    (res,) = checks(obs, spec, _Functions(spec, 3, 2))
    rho = max(abs(np.linalg.eigvals(A3 - L3 @ C3)))
    assert res["measured"] == pytest.approx(-np.log(rho), rel=0.05)
    assert -np.log(rho) > 0.05 and res["ok"] is True
    bad = make_observer("robust", "discrete", {"A": A3, "C": C3, "L": L3, "decay": 5.0})
    (res2,) = checks(bad, spec, _Functions(spec, 3, 2))
    assert res2["ok"] is False


def test_helpers_against_hand_values():
    t = np.arange(4.0)
    assert l2_ratio(np.c_[[1.0, 1.0, 1.0, 1.0]], np.c_[[2.0, 0.0, 0.0, 0.0]], t, "discrete") == pytest.approx(1.0)
    assert decay_rate(np.arange(40.0), 5 * 0.5 ** np.arange(40.0)) == pytest.approx(np.log(2))


# -- Euler-model observer against the exact sampled plant (sampled_euler.thm3) -----------------


def test_euler_observer_against_the_exact_discretisation():
    A = np.array([[0.0, 1.0], [-1.0, -1.0]])
    C = np.array([[1.0, 0.0]])
    L = np.array([[1.04], [0.25]])
    T = 0.1
    obs = make_observer("euler", "discrete", {"A": A, "C": C, "L": L, "T": T})
    _spec, traj = _simulate(obs, {"x0": [0.3, -0.2], "horizon": 3, "dt": T})
    Phi = sla.expm(A * T)
    Ad = np.eye(2) + T * A
    x = np.array([0.3, -0.2])
    xh = np.zeros(2)
    for k in range(31):
        np.testing.assert_allclose(traj.x[k], x, atol=1e-8)
        np.testing.assert_allclose(traj.xhat[k], xh, atol=1e-8)
        xh = Ad @ xh + L @ (C @ x - C @ xh)
        x = Phi @ x


def test_euler_needs_dt_equal_to_the_period():
    obs = make_observer("euler", "discrete", {"A": -np.eye(1), "C": np.eye(1), "L": np.eye(1) * 0.5, "T": 0.1})
    with pytest.raises(DataError, match="dt = 0.2 must equal the observer's sampling period T = 0.1"):
        _simulate(obs, {"x0": [1], "horizon": 1, "dt": 0.2})


# -- descriptor plants: reduced-order filter (descriptor.thm3_3, uir) --------------------------


def _descriptor_filter():
    """The Paper D example's filter (48), recomputed from R exactly (catalogue 5.3)."""
    A = np.array([[-2.0, 1, 0], [0, -3, -1], [0, 1, -2]])
    B = np.array([[1.0], [0], [0]])
    C = np.array([[1.0, 0, 0], [0, 1, 0]])
    F = np.array([[1.0, 1], [0, 1], [1, 0]])
    G = np.eye(2)
    D1 = np.ones((3, 1))
    D2 = np.ones((2, 1))
    M = np.array([[1.0, 4, 2], [-2, 4, 0], [-3, -2, 3]])
    eta = np.hstack([np.eye(3), np.zeros((3, 2))])
    T = np.vstack([M @ eta, np.hstack([C, G])])
    Ti = np.linalg.inv(T)
    a1, a2 = Ti[:, :3], Ti[:, 3:]
    Abar = np.hstack([A, F])
    N, L, J, E = M @ Abar @ a1, M @ Abar @ a2, a1, a2
    mats = {"A": A, "B": B, "C": C, "F": F, "G": G, "N": N, "L": L, "M": M, "J": J, "E": E, "D1": D1, "D2": D2,
            "gamma": 2.5}  # fmt: skip
    return make_observer("ui_filter", "continuous", mats), mats


def test_ui_filter_error_matches_an_independent_integration_of_the_error_system():
    obs, m = _descriptor_filter()
    sec = {"x0": [3, 2, -2], "z0": [0, 0, 0], "input": "0.1", "horizon": 4, "dt": 0.01,
           "disturbance": "0.1 + 0.5*sin(5*t)", "unknown_input": ["sin(t)", "0.5*cos(2*t)"]}  # fmt: skip
    _spec, traj = _simulate(obs, sec)
    N, L, M, J, E, D1, D2 = (m[k] for k in ("N", "L", "M", "J", "E", "D1", "D2"))
    w = lambda t: np.array([0.1 + 0.5 * np.sin(5 * t)])  # noqa: E731
    eps0 = np.zeros(3) - M @ np.array([3.0, 2, -2])  # eps = z - M x

    sol = solve_ivp(lambda t, e: N @ e + (L @ D2 - M @ D1) @ w(t), (0, 4), eps0, t_eval=traj.t, rtol=1e-10, atol=1e-12)
    e_ref = np.array([J @ sol.y[:, k] + E @ D2 @ w(tk) for k, tk in enumerate(sol.t)])  # zeta^ - zeta
    zeta = np.hstack([traj.x, traj.signals["nu"]])
    zeta_hat = np.hstack([traj.xhat, traj.signals["nu_hat"]])
    np.testing.assert_allclose(zeta_hat - zeta, e_ref, atol=2e-6)
    # the unknown input is reconstructed: the error does not depend on nu
    assert np.abs(traj.signals["nu"] - traj.signals["nu_hat"])[-50:].max() < 0.6


def test_ui_filter_gain_against_the_exact_hinf_norm():
    obs, m = _descriptor_filter()
    N, L, M, J, E, D1, D2 = (m[k] for k in ("N", "L", "M", "J", "E", "D1", "D2"))
    grid = np.concatenate([[0.0], np.geomspace(1e-3, 1e4, 4000)])
    hinf = max(np.linalg.norm(J @ np.linalg.solve(1j * o * np.eye(3) - N, L @ D2 - M @ D1) + E @ D2, 2) for o in grid)
    spec = read_spec({"x0": [0, 0, 0], "horizon": 10, "dt": 0.002, "disturbance": "0.1 + 0.5*sin(62.83*t)"}, obs)
    (res,) = checks(obs, spec, _Functions(spec, 3, 2))
    assert res["ok"] is True
    assert res["measured"] <= hinf * 1.02
    assert res["measured"] >= 0.9 * hinf


def test_filter_error_matches_lsim():
    N = np.array([[-1.0, 0.5], [0.0, -2.0]])
    J = np.array([[1.0, 1.0]])
    obs = make_observer("filter_error", "continuous", {"N": N, "J": J})
    _spec, traj = _simulate(obs, {"x0": [1, -1], "horizon": 3, "dt": 0.01})
    _t, y, xs = ss.lsim((N, np.zeros((2, 1)), J, np.zeros((1, 1))), np.zeros(traj.t.size), traj.t, X0=[1, -1])
    np.testing.assert_allclose(traj.x, xs, atol=1e-6)
    dobs = make_observer("filter_error", "discrete", {"N": 0.5 * np.eye(2)})
    _spec, dtraj = _simulate(dobs, {"x0": [1, 2], "horizon": 5, "dt": 1})
    np.testing.assert_allclose(dtraj.x[5], 0.5**5 * np.array([1.0, 2.0]))


# -- observer-based control (obs_control) -------------------------------------------------------


def test_closed_loop_matches_the_separation_form_exponential():
    A = np.array([[0.0, -1, -1], [1, 0.2, 0], [0, 0, -5.7]])
    B = np.array([[1.0], [0], [0]])
    C = np.array([[1.0, 0, 0], [0, 1, 0]])
    K = np.array([[2.0, 1.0, -0.5]])
    L = np.array([[3.0, 0.0], [0.0, 3.0], [0.0, 0.0]])
    obs = make_observer("obs_control", "continuous", {"A": A, "B": B, "C": C, "K": K, "L": L})
    _spec, traj = _simulate(obs, {"x0": [1, -1, 0.5], "xhat0": [0, 0, 0], "horizon": 2, "dt": 0.01})
    # [x; e]' = [A - B K, B K; 0, A - L C] [x; e]
    Acl = np.block([[A - B @ K, B @ K], [np.zeros((3, 3)), A - L @ C]])
    s0 = np.concatenate([[1, -1, 0.5], [1, -1, 0.5]])
    for k in (0, 50, 200):
        s = sla.expm(Acl * traj.t[k]) @ s0
        np.testing.assert_allclose(traj.x[k], s[:3], atol=1e-6)
        np.testing.assert_allclose(traj.x[k] - traj.xhat[k], s[3:], atol=1e-6)
    np.testing.assert_allclose(traj.signals["u"][:, 0], -(traj.xhat @ K.T)[:, 0])


# -- bad sections: one line, exit code 2 -------------------------------------------------------


@pytest.mark.parametrize(
    ("section", "message"),
    [
        ({"uncertainty": "2*sin(k)"}, "||F(k)|| = 1.683 > 1 at k = 1"),
        ({"delay": [0, 3]}, "tau(1) = 3 is outside the certified range [0, 2]"),
        ({"delay": "0.5"}, "tau(0) = 0.5 is not a whole number of steps"),
        ({"delay": [0, 1.5]}, "delay[2]: 1.5 is not of type 'integer'"),
        ({"history": [1, 2, 3]}, "history: expected 2 numbers"),
        ({"disturbance": ["1", "2"]}, "disturbance: has 2 entries, the model has 1 disturbance(s)"),
        ({"uncertainty": ["1", "0"]}, "uncertainty: has 2 entries, F is 1x1"),
        ({"uncertainty": {"seed": 1, "x": 2}}, "uncertainty: {'seed': 1, 'x': 2} is not valid"),
        ({"disturbance": "os.system(1)"}, "unknown name 'os'"),
    ],
)
def test_bad_family_sections(section, message):
    obs = _robust()
    with pytest.raises(DataError) as info:
        spec = read_spec({"x0": [1, 1], "horizon": 3, "dt": 1, **section}, obs)
        run(obs, spec)
    assert message in str(info.value)
    assert "\n" not in str(info.value)


def test_extra_keys_rejected_where_they_do_not_apply():
    luen = make_observer("luenberger", "discrete", {"A": AA, "C": CA, "L": LA})
    with pytest.raises(DataError, match="'delay' does not apply to the 'luenberger' observer"):
        read_spec({"x0": [1, 1], "horizon": 3, "delay": 1}, luen)
    nodelay = make_observer("robust", "discrete", {"A": AA, "C": CA, "L": LA})
    with pytest.raises(DataError, match="no delayed term"):
        read_spec({"x0": [1, 1], "horizon": 3, "delay": 1}, nodelay)
    with pytest.raises(DataError, match="declares no uncertainty"):
        read_spec({"x0": [1, 1], "horizon": 3, "uncertainty": "0"}, nodelay)


def test_cli_bad_family_section_is_one_line_exit_2(tmp_path, capsys):
    text = (EX / "delay_a.thm3_2.example.yaml").read_text().replace("delay: [0, 1, 2, 1, 2, 0]", "delay: [0, 5]")
    bad = tmp_path / "bad.yaml"
    bad.write_text(text)
    assert main(["simulate", "delay_a.thm3_2", str(bad)]) == 2
    err = capsys.readouterr().err
    assert err.strip().count("\n") == 0
    assert "outside the certified range [0, 2]" in err


# -- shipped examples: solve, simulate, and the certificate holds on the trajectory ------------


@pytest.mark.parametrize(
    ("theorem", "file"),
    [
        ("delay_a.thm3_2", "delay_a.thm3_2.example.yaml"),
        ("delay_b.thm4_1", "delay_b.thm4_1.ex2_lambda0_9.yaml"),
        ("uncertain_dt.thm1", "uncertain_dt.thm1.example.yaml"),
        ("descriptor.thm3_3", "descriptor.thm3_3.example.yaml"),
        ("qib.thm2", "simulation/qib.thm2.flexible-joint-deadbeat-K.yaml"),
        ("uir.thm4_1", "simulation/uir.thm4_1.paperD-plant.yaml"),
        ("sampled_euler.thm3", "sampled_euler.thm3.example.yaml"),
        ("obs_control.thm3_1", "obs_control.thm3_1.rossler_z_published_gains.yaml"),
    ],
)
def test_shipped_example_simulates_and_the_certificate_holds(theorem, file, capsys):
    import json

    from lmic.api import solve

    assert main(["simulate", theorem, str(EX / file), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    sim = out["simulation"]
    assert sim["decayed"] is True
    for c in sim["checks"]:
        if c["property"].startswith("practical stability"):
            assert c["ok"] is None  # informative: the time to enter the ball is not certified
        elif c["property"].startswith("decay rate"):
            assert c["ok"] is True and c["measured"] >= c["certified"]
        else:
            assert c["ok"] is True and c["measured"] <= c["certified"] * 1.02
    if theorem in ("delay_a.thm3_2", "delay_b.thm4_1"):
        result = solve(theorem, system=str(EX / file))
        env = result.problem.environment(result.solution.x)
        (gain,) = [c for c in sim["checks"] if c["property"].startswith("L2 gain")]
        assert gain["certified"] == pytest.approx(float(env["eta_star"]), rel=1e-6)


# -- figure and report ------------------------------------------------------------------------


def test_figure_and_report_show_reconstruction_and_a_red_flag():
    from lmic.report.builder import _simulation_section
    from lmic.simulate.plot import figure, plot_png

    obs, _m = _descriptor_filter()
    sec = {"x0": [3, 2, -2], "z0": [0, 0, 0], "horizon": 1, "dt": 0.01, "unknown_input": ["sin(t)", "0"]}
    _spec, traj = _simulate(obs, sec)
    fig = figure(traj)
    labels = [ax.get_ylabel() for ax in fig.axes]  # type: ignore[attr-defined]
    assert sum("nu" in s for s in labels) == 2  # both reconstructed inputs have a panel
    traj.checks = [{"property": "L2 gain w -> z", "certified": 0.1, "measured": 0.5, "ok": False, "detail": "d"}]
    png = plot_png(traj)
    html = _simulation_section(traj, png, "", obs)
    assert "Red flag" in html and "VIOLATED" in html and "certified 0.1" in html
