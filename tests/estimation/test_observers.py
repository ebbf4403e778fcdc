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
