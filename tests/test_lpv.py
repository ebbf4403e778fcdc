"""Tests of the LPV model, the precision LMIs (Theorems 1-2) and the observer simulation (cislunar.lpv, .observers)."""

import warnings

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from cislunar import lpv
from cislunar.observers import make_measurements, simulate_ekf, simulate_lpv_observer
from cislunar.propagation import propagate

MODEL = lpv.CR3BPLPV()
MU = MODEL.mu
GAMMA = 0.0013


def _planar_states(draw_xy, vel):
    return np.array([draw_xy[0], draw_xy[1], vel[0], vel[1]])


coord = st.floats(-1.6, 1.6, allow_nan=False)
speed = st.floats(-3.0, 3.0, allow_nan=False)


def _far_from_primaries(s):
    return np.hypot(s[0] + MU, s[1]) > 1e-2 and np.hypot(s[0] - 1 + MU, s[1]) > 1e-2 and abs(s[1]) > 1e-9


@given(st.tuples(coord, coord), st.tuples(speed, speed))
def test_lpv_dynamics_equal_nonlinear(xy, v):
    s = _planar_states(xy, v)
    if not _far_from_primaries(s):
        return
    f = MODEL.f(s)
    g = MODEL.lpv_rhs(s)
    assert np.all(np.abs(f - g) <= 1e-12 * np.maximum(1.0, np.abs(f)))


@given(st.tuples(coord, coord), st.tuples(speed, speed))
def test_sensor_model_eq22_equals_geometry(xy, v):
    s = _planar_states(xy, v)
    if not _far_from_primaries(s):
        return
    y = MODEL.measure(s)
    assert np.all(np.abs(y - MODEL.lpv_measure(s)) <= 1e-12 * np.maximum(1.0, np.abs(y)))
    # triangulation from the two angles recovers rho
    r = MODEL.rho(s)
    rt = MODEL.rho_from_angles(*MODEL.angles(s))
    if abs(np.sin(np.sum(MODEL.angles(s)))) > 1e-3:
        assert np.allclose(rt, r, rtol=1e-8, atol=1e-10)


def test_eq23_d_as_printed_is_inconsistent_and_batch_shapes():
    rng = np.random.default_rng(3)
    s = rng.uniform(-1.2, 1.2, (500, 4))
    rho = MODEL.rho(s)
    y = MODEL.measure(s)
    printed = np.einsum("...ij,...j->...i", MODEL.C(rho), s) + MODEL.d_as_printed_eq23(rho)
    assert np.max(np.abs(printed - y)) > 1e-2
    assert np.max(np.abs(MODEL.lpv_measure(s) - y)) < 1e-12 * np.max(np.abs(y))
    assert MODEL.A(rho).shape == (500, 4, 4) and MODEL.C(rho).shape == (500, 6, 4)
    # affine coefficients: A(rho) = A0 + sum rho_i A_i, checked entrywise against Eq. 23
    a = 1 - (1 - MU) * rho[:, 0] - MU * rho[:, 1]
    A = MODEL.A(rho)
    assert np.allclose(A[:, 2, 0], a) and np.allclose(A[:, 3, 1], a)
    assert np.allclose(MODEL.b(rho)[:, 2], MU * (rho[:, 0] - rho[:, 1]) * (MU - 1.0))


@pytest.fixture(scope="module")
def scenario():
    return lpv.paper_scenario(n_samples=600)


@pytest.fixture(scope="module")
def designs(scenario):
    V = scenario.box.vertices()
    out = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for norm in ("h2", "hinf"):
            out[norm] = lpv.design_observer(MODEL, V, GAMMA, norm)
            # notebook 12's implementable gains: theta1 sensors only, poles in |lambda| < 200 /TU
            out[norm + "_R"] = lpv.design_observer(MODEL, V, GAMMA, norm, pole_radius=200.0, sensors=[0, 1])
    return out


def test_box_from_orbit(scenario):
    box = scenario.box
    assert box.vertices().shape == (64, 6)
    assert np.all(box.contains(scenario.rho))
    o = scenario.orbit
    assert abs(o.period / (2 * np.pi) - 1.0) < 0.02  # 2:1 resonance: about one synodic period in the frame
    end = propagate(MODEL.system, o.x0, o.period).x[-1]
    assert np.linalg.norm(end - o.x0) < 1e-8


def test_designs_sparse_and_verified(scenario, designs):
    rng = np.random.default_rng(0)
    for key, d in designs.items():
        assert d.used[:2].all() and not d.used[2:].any(), key  # only sin/cos theta1 needed (paper Fig. 2)
        v = lpv.verify_observer(MODEL, d, scenario.box, 40, rng)
        assert v.hurwitz, key
        assert v.worst < GAMMA * (1 + 1e-5), (key, v.worst)
    # H-infinity: noise level gamma / max r13 (the measurement-inversion limit), about 0.078 deg
    r13max = 1.0 / scenario.box.lower[2]
    assert designs["hinf"].kappa[0] * GAMMA / r13max == pytest.approx(1.0, rel=1e-3)


def test_verification_can_fail(scenario, designs):
    d = designs["h2"]
    v = lpv.verify_observer(MODEL, d, scenario.box, 5, np.random.default_rng(1), L=-d.gain())
    assert not v.hurwitz and not v.passed


def test_norms_against_python_control():
    control = pytest.importorskip("control")
    rng = np.random.default_rng(4)
    for _ in range(5):
        A = rng.standard_normal((4, 4)) - 3 * np.eye(4)
        B = rng.standard_normal((4, 2))  # square system: python-control 0.10.2 without slycot assumes p == m
        C = rng.standard_normal((2, 4))
        sys = control.ss(A, B, C, np.zeros((2, 2)))
        assert lpv.h2_norm(A, B, C) == pytest.approx(control.norm(sys, p=2), rel=1e-8)
        assert lpv.hinf_norm(A, B, C) == pytest.approx(control.norm(sys, p="inf", tol=1e-10), rel=1e-6)


def test_scalar_h2_known_answer():
    # xdot = a x + sd w, y = x + n / kappa: Kalman variance P solves 2 a P + sd^2 - kappa^2 P^2 = 0, so the least
    # precision with H2 norm gamma is beta = kappa^2 = (sd^2 + 2 a gamma^2) / gamma^4
    a, sd, gamma = -0.5, 1.0, 0.3
    lmi = lpv.PrecisionLMI(np.array([[[a]]]), np.array([[[1.0]]]), "h2",
                           disturbance=(np.eye(1), sd * np.eye(1), np.zeros((1, 1))), eps=1e-10)
    d = lmi.solve(gamma)
    expected = (sd**2 + 2 * a * gamma**2) / gamma**4
    assert d.beta[0] == pytest.approx(expected, rel=1e-5)
    assert lmi.solve(2 * gamma).beta[0] == pytest.approx((sd**2 + 2 * a * 4 * gamma**2) / (16 * gamma**4), rel=1e-5)


def test_lti_h2_matches_riccati():
    control = pytest.importorskip("control")
    # damped oscillator, position measured: the LMI's least precision at gamma reproduces the Kalman filter's
    # error (Riccati) for that precision
    A = np.array([[0.0, 1.0], [-2.0, -0.3]])
    C = np.array([[1.0, 0.0]])
    Bd = np.array([[0.0], [1.0]])
    gamma = 0.2
    lmi = lpv.PrecisionLMI(A[None], C[None], "h2", disturbance=(Bd, np.eye(1), np.zeros((1, 1))),
                           Cz=np.array([[1.0, 0.0]]), eps=1e-10)
    d = lmi.solve(gamma)
    _, P, _ = control.lqe(A, Bd, C, np.eye(1), np.array([[1.0 / d.beta[0]]]))
    assert np.sqrt(P[0, 0]) == pytest.approx(gamma, rel=1e-4)


def test_infeasible_raises_with_gamma_and_status():
    # unstable and unobservable: no gain can stabilise it
    lmi = lpv.PrecisionLMI(np.array([[[1.0]]]), np.array([[[0.0]]]), "h2",
                           disturbance=(np.eye(1), np.eye(1), np.zeros((1, 1))))
    with pytest.raises(lpv.InfeasibleLMIError, match=r"gamma = 0\.5.*status"):
        lmi.solve(0.5)


def test_bad_input_raises_value_error(scenario):
    V = scenario.box.vertices()
    with pytest.raises(ValueError, match="norm"):
        lpv.PrecisionLMI.for_cr3bp(MODEL, V, "h3")
    with pytest.raises(ValueError, match="objective"):
        lpv.PrecisionLMI.for_cr3bp(MODEL, V, objective="l0")
    with pytest.raises(ValueError, match="vertices"):
        lpv.PrecisionLMI.for_cr3bp(MODEL, V[:, :5])
    with pytest.raises(ValueError, match="upper"):
        lpv.ParameterBox(np.ones(6), np.zeros(6))
    with pytest.raises(ValueError, match="perigee_radius"):
        lpv.resonant_orbit(perigee_radius=2.0)
    with pytest.raises(ValueError, match="state"):
        MODEL.rho(np.zeros((3, 5)))
    with pytest.raises(ValueError, match="gamma"):
        lpv.PrecisionLMI(np.array([[[-1.0]]]), np.array([[[1.0]]]),
                         disturbance=(np.eye(1), np.eye(1), np.zeros((1, 1)))).solve(-1.0)
    with pytest.raises(ValueError, match="solver"):
        lpv.PrecisionLMI(np.array([[[-1.0]]]), np.array([[[1.0]]]),
                         disturbance=(np.eye(1), np.eye(1), np.zeros((1, 1)))).solve(1.0, solver="MOSEK")
    with pytest.raises(ValueError, match="kappa"):
        lpv.precision_to_noise_deg(-1.0)


def test_eq24_conversion():
    assert lpv.precision_to_noise_deg(lpv.noise_deg_to_precision(0.1)) == pytest.approx(0.1, rel=1e-12)
    assert lpv.precision_to_noise_deg(0.5) == 90.0


def test_observer_error_bounded(scenario, designs):
    o = scenario.orbit
    t = np.arange(0.0, 0.35 * o.period, 0.01)
    truth = MODEL.planar(propagate(MODEL.system, o.x0, t).x)
    meas = make_measurements(MODEL, t, truth, 0.1, np.random.default_rng(0))
    x0 = truth[0] + np.array([0.02, -0.02, 0.01, 0.01])
    run = simulate_lpv_observer(MODEL, designs["h2_R"].gain(), meas, x0, truth)
    assert run.position_error[0] == pytest.approx(0.02 * np.sqrt(2))
    assert np.max(run.position_error[len(t) // 2:]) < 0.01  # < 3800 km after convergence
    assert np.median(run.position_error[len(t) // 2:]) < 0.005
    ekf = simulate_ekf(MODEL, meas, x0, np.eye(4) * 0.03**2, truth)
    assert np.max(ekf.position_error[len(t) // 2:]) < 0.005
    with pytest.raises(ValueError, match="sigma_deg"):
        make_measurements(MODEL, t, truth, -0.1, np.random.default_rng(0))
