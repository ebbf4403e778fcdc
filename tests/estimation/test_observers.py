"""Tests of cislunar.estimation.observers: argument checks, the singular-geometry path and the RK4 step choice."""

import numpy as np
import pytest

from cislunar.estimation import lpv
from cislunar.estimation.observers import (
    Measurements,
    make_measurements,
    simulate_ekf,
    simulate_lpv_observer,
)
from cislunar.papers.nychka_bhattacharya.scenarios import paper_scenario

MODEL = lpv.CR3BPLPV()


@pytest.fixture(scope="module")
def short_run():
    sc = paper_scenario(n_samples=400)
    t = np.arange(0.0, 0.5, 0.01)
    from cislunar.cr3bp.propagation import propagate

    truth = MODEL.planar(propagate(MODEL.system, sc.orbit.x0, t).x)
    return sc, t, truth


def test_bad_arguments_are_named(short_run):
    sc, t, truth = short_run
    rng = np.random.default_rng(0)
    with pytest.raises(TypeError, match="^rng must be"):
        make_measurements(MODEL, t, truth, 0.1, 0)
    with pytest.raises(TypeError, match="^model must be"):
        make_measurements("em", t, truth, 0.1, rng)
    with pytest.raises(ValueError, match="^truth must have shape"):
        make_measurements(MODEL, t, truth[:-1], 0.1, rng)
    meas = make_measurements(MODEL, t, truth, 0.1, rng)
    with pytest.raises(TypeError, match="^meas must be"):
        simulate_lpv_observer(MODEL, np.zeros((4, 6)), (t, t), truth[0], truth)
    with pytest.raises(ValueError, match="^L must have shape"):
        simulate_lpv_observer(MODEL, np.zeros((4, 5)), meas, truth[0], truth)
    with pytest.raises(ValueError, match="^P0"):
        simulate_ekf(MODEL, meas, truth[0], -np.eye(4), truth)
    with pytest.raises(TypeError, match="^substeps must be an integer"):
        simulate_lpv_observer(MODEL, np.zeros((4, 6)), meas, truth[0], truth, substeps=2.5)


def test_observer_on_the_earth_moon_line_uses_the_estimate():
    """Truth on the x axis (theta1 + theta2 = 0 exactly, triangulation singular): the observer must take rho from
    its estimate there instead of failing, and flag every sample."""
    t = np.arange(0.0, 0.05, 0.01)
    truth = np.tile([0.5, 0.0, 0.0, 0.0], (t.size, 1))
    meas = Measurements(t, np.zeros(t.size), np.zeros(t.size), 0.0)
    run = simulate_lpv_observer(MODEL, np.zeros((4, 6)), meas, truth[0], truth, substeps=1)
    assert run.rho_from_estimate.all()
    # zero gain: the observer is the LPV model itself, i.e. the CR3BP from x_hat0 (RK4 with h = 0.01)
    s, h = truth[0].copy(), 0.01
    for _ in range(t.size - 1):
        k1 = MODEL.f(s)
        k2 = MODEL.f(s + 0.5 * h * k1)
        k3 = MODEL.f(s + 0.5 * h * k2)
        k4 = MODEL.f(s + h * k3)
        s = s + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    assert np.allclose(run.x_hat[-1], s, rtol=1e-12, atol=1e-14)


def test_default_substeps_keep_a_high_gain_observer_stable(short_run):
    """A gain with |lambda(A + LC)| ~ 1000 /TU at 0.01 TU sampling: 4 fixed RK4 steps (h|lambda| ~ 2.5) blow up or
    ring, the automatic step count does not."""
    sc, t, truth = short_run
    d = lpv.design_observer(MODEL, sc.box.vertices(), 0.0013, "hinf", sensors=[0, 1], pole_radius=1000.0)
    meas = make_measurements(MODEL, t, truth, 0.0, np.random.default_rng(1))
    run = simulate_lpv_observer(MODEL, d.gain(), meas, truth[0] + [1e-3, 0, 0, 0], truth)
    assert np.all(np.isfinite(run.x_hat))
    # noiseless but held between samples: a high-gain observer tracks the held measurement, so it lags the truth
    # by at most about |v| dt (zero-order-hold lag), and no more
    lag = np.max(np.hypot(truth[:, 2], truth[:, 3])) * 0.01
    assert np.max(run.position_error[t.size // 2:]) < lag
    try:
        bad = simulate_lpv_observer(MODEL, d.gain(), meas, truth[0] + [1e-3, 0, 0, 0], truth, substeps=1)
    except RuntimeError:
        return
    assert bad.position_error[-1] > 10 * run.position_error[-1] + 1e-6


def test_h2_guarantee_holds_with_exact_rho_and_held_noise():
    """Theorem 1 in simulation: with the true rho and 0.1 deg noise held over dt (intensity sigma^2 dt) the RMS
    position error of the H2 observer stays below gamma * kappa * sigma * sqrt(dt), the bound the LMI certifies.
    A wrong noise model (the whole measurement held: lag acts as extra noise) breaks it."""
    from cislunar.cr3bp.propagation import propagate

    sc = paper_scenario(n_samples=600)
    d = lpv.design_observer(MODEL, sc.box.vertices(), 0.0013, "h2", sensors=[0, 1])
    dt = 0.004
    t = np.arange(0.0, sc.orbit.period, dt)
    truth = MODEL.planar(propagate(MODEL.system, sc.orbit.x0, t).x)
    meas = make_measurements(MODEL, t, truth, 0.1, np.random.default_rng(0))
    bound = lpv.guaranteed_error_rms(d, 0.1, dt)
    run = simulate_lpv_observer(MODEL, d.gain(), meas, truth[0], truth, exact_rho=True)
    rms = np.sqrt(np.mean(run.position_error**2))
    assert rms < bound
    assert rms > 0.2 * bound  # the bound is not vacuous
    held = simulate_lpv_observer(MODEL, d.gain(), meas, truth[0], truth, exact_rho=True, hold="measurement")
    assert np.sqrt(np.mean(held.position_error**2)) > 2 * bound


@pytest.mark.parametrize("hold", ["noise", "measurement"])
def test_precomputed_rk4_maps_equal_a_plain_rk4_of_eq_3a(short_run, hold):
    """The simulator's affine RK4 maps (and its step-by-step path near the Earth-Moon line) against a plain RK4 of
    Eq. 3a written here from the model's public A, b, C, d, with the measurement held over each interval and rho
    from the triangulated angles or, below the threshold, from the estimate.  A run that crosses the line
    (threshold raised to 0.5 so that both paths are taken)."""
    sc, t, truth = short_run
    rng = np.random.default_rng(7)
    meas = make_measurements(MODEL, t, truth, 0.1, rng)
    L = rng.standard_normal((4, 6)) * 0.5
    x0 = truth[0] + np.array([0.01, -0.01, 0.005, 0.0])
    thr, substeps = 0.5, 3
    run = simulate_lpv_observer(MODEL, L, meas, x0, truth, sin3_threshold=thr, substeps=substeps, hold=hold)
    assert 0 < run.rho_from_estimate.sum() < t.size  # both paths are exercised

    def stage(k, tau):
        if hold == "measurement":
            th1, th2 = meas.theta1[k], meas.theta2[k]
        else:  # continuous sensor (cubic Hermite truth) with the noise of interval k held
            hk = t[k + 1] - t[k]
            u = (tau - t[k]) / hk
            pos = ((2 * u**3 - 3 * u**2 + 1) * truth[k, :2] + (u**3 - 2 * u**2 + u) * hk * truth[k, 2:]
                   + (-2 * u**3 + 3 * u**2) * truth[k + 1, :2] + (u**3 - u**2) * hk * truth[k + 1, 2:])
            a1, a2 = MODEL.angles(pos)
            n1, n2 = (np.angle(np.exp(1j * (m - a))) for m, a in zip((meas.theta1[k], meas.theta2[k]),
                                                                      MODEL.angles(truth[k])))
            th1, th2 = a1 + n1, a2 + n2
        if abs(np.sin(th1 + th2)) < thr:
            return np.r_[np.sin(th1), np.cos(th1), np.sin(th2), np.cos(th2), 0.0, 0.0], None
        rho = MODEL.rho_from_angles(th1, th2)
        return np.r_[np.sin(th1), np.cos(th1), np.sin(th2), np.cos(th2), 1 / rho[2] ** 2, 1 / rho[3] ** 2], rho

    def f(x, y, rho):
        rho = MODEL.rho(x) if rho is None else rho
        return (MODEL.A(rho) + L @ MODEL.C(rho)) @ x - L @ y + MODEL.b(rho) + L @ MODEL.d(rho)

    x, out = x0.copy(), [x0.copy()]
    for k in range(t.size - 1):
        h = (t[k + 1] - t[k]) / substeps
        for j in range(substeps):
            (ya, ra), (yb, rb), (yc, rc) = (stage(k, t[k] + (j + c) * h) for c in (0.0, 0.5, 1.0))
            k1 = f(x, ya, ra)
            k2 = f(x + 0.5 * h * k1, yb, rb)
            k3 = f(x + 0.5 * h * k2, yb, rb)
            k4 = f(x + h * k3, yc, rc)
            x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        out.append(x.copy())
    assert np.allclose(run.x_hat, np.array(out), rtol=1e-9, atol=1e-12)


def test_ekf_against_the_package_vector_field(short_run):
    """The EKF's planar field (written out for speed) against CR3BP.eom: with no
    measurement information (huge noise) and no process noise, one EKF step is an RK4 step of the package's field."""
    sc, t, truth = short_run
    meas = Measurements(t[:2], MODEL.angles(truth[:2])[0], MODEL.angles(truth[:2])[1], 1e6)
    x0, P0 = truth[0], np.eye(4) * 1e-8
    run = simulate_ekf(MODEL, meas, x0, P0, truth[:2], sigma_acc=0.0, substeps=1)
    h = t[1] - t[0]
    sys = MODEL.system

    def f(x):
        return sys.eom(MODEL.spatial(x))[[0, 1, 3, 4]]

    k1 = f(x0)
    k2 = f(x0 + 0.5 * h * k1)
    k3 = f(x0 + 0.5 * h * k2)
    k4 = f(x0 + h * k3)
    assert np.allclose(run.x_hat[1], x0 + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4), rtol=0, atol=1e-12)


def test_ekf_step_against_the_package_jacobian(short_run):
    """One EKF interval (RK4 of the state and of P' = F P + P F^T + Q with F from CR3BP.jacobian, then the angle
    update) written here from the package's field and Jacobian: the simulator's written-out planar Jacobian must
    give the same estimate (a wrong Jacobian entry changes the gain and hence the estimate)."""
    sc, t, truth = short_run
    rng = np.random.default_rng(3)
    meas = make_measurements(MODEL, t[:2], truth[:2], 0.05, rng)
    x0, P0, q = truth[0] + np.array([1e-3, -2e-3, 1e-3, 0.0]), np.diag([4e-6, 4e-6, 1e-6, 1e-6]), 1e-3
    run = simulate_ekf(MODEL, meas, x0, P0, truth[:2], sigma_acc=q, substeps=1)
    sys, idx, mu = MODEL.system, [0, 1, 3, 4], MODEL.mu
    R, Qc = np.eye(2) * meas.sigma**2, np.diag([0.0, 0.0, q**2, q**2])

    def update(k, x, P):
        dx1, dx2, y = x[0] + mu, 1.0 - mu - x[0], x[1]
        H = np.array([[-y / (dx1**2 + y**2), dx1 / (dx1**2 + y**2), 0, 0],
                      [y / (dx2**2 + y**2), dx2 / (dx2**2 + y**2), 0, 0]])
        nu = np.angle(np.exp(1j * (np.array([meas.theta1[k], meas.theta2[k]])
                                   - np.array([np.arctan2(y, dx1), np.arctan2(y, dx2)]))))
        K = P @ H.T @ np.linalg.inv(H @ P @ H.T + R)
        return x + K @ nu, (np.eye(4) - K @ H) @ P @ (np.eye(4) - K @ H).T + K @ R @ K.T

    def d(x, P):
        F = sys.jacobian(MODEL.spatial(x))[np.ix_(idx, idx)]
        return sys.eom(MODEL.spatial(x))[idx], F @ P + P @ F.T + Qc

    x, P = update(0, x0, P0)
    h = t[1] - t[0]
    f1, p1 = d(x, P)
    f2, p2 = d(x + 0.5 * h * f1, P + 0.5 * h * p1)
    f3, p3 = d(x + 0.5 * h * f2, P + 0.5 * h * p2)
    f4, p4 = d(x + h * f3, P + h * p3)
    x, P = update(1, x + h / 6 * (f1 + 2 * f2 + 2 * f3 + f4), P + h / 6 * (p1 + 2 * p2 + 2 * p3 + p4))
    assert np.allclose(run.x_hat[1], x, rtol=0, atol=1e-12)
