"""Tests of the LPV model, the precision LMIs (Theorems 1-2) and the observer simulation (cislunar.estimation.lpv, .observers)."""

import os
import pickle
import types

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from cislunar.cr3bp.propagation import propagate
from cislunar.estimation import lpv
from cislunar.estimation.observers import (
    make_measurements,
    simulate_ekf,
    simulate_lpv_observer,
)
from cislunar.papers.nychka_bhattacharya.scenarios import paper_scenario

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
    return paper_scenario(n_samples=600)


# One fixture per design (each well under 5 s of CPU on the 2-core machine; they were one 14 s set-up): the
# notebooks' designs with all six sensors offered (Fig. 2) and the theta1-only problems of the comparison rows;
# H-infinity with the bandwidth bound R = 1000 /TU.  The six-sensor H-infinity problem starts, as in
# sensing_precision.paper_designs, from the scaling on which PrecisionLMI.solve's first retry lands (the default one
# ends optimal_inaccurate): the same problem object and solve as the retry's, so the same design, one solve fewer.
@pytest.fixture(scope="module")
def design_h2_6(scenario):
    return lpv.design_observer(MODEL, scenario.box.vertices(), GAMMA, "h2")


@pytest.fixture(scope="module")
def design_hinf_6(scenario):
    lmi = lpv.PrecisionLMI.for_cr3bp(MODEL, scenario.box.vertices(), "hinf", pole_radius=1000.0)
    return lmi.rescaled(lpv.RETRY_SCALINGS[0][0], lmi.balanced_state_scale).solve(GAMMA)


@pytest.fixture(scope="module")
def design_h2_1(scenario):
    return lpv.design_observer(MODEL, scenario.box.vertices(), GAMMA, "h2", sensors=[0, 1])


@pytest.fixture(scope="module")
def design_hinf_1(scenario):
    return lpv.design_observer(MODEL, scenario.box.vertices(), GAMMA, "hinf", sensors=[0, 1], pole_radius=1000.0)


@pytest.fixture(scope="module")
def designs(design_h2_6, design_hinf_6, design_h2_1, design_hinf_1):
    return {"h2": design_h2_6, "hinf": design_hinf_6, "h2_1": design_h2_1, "hinf_1": design_hinf_1}


@pytest.fixture(scope="module")
def theta1_designs(design_h2_1, design_hinf_1):
    """The theta1-only designs alone, for tests that need neither six-sensor solve."""
    return {"h2_1": design_h2_1, "hinf_1": design_hinf_1}


def test_box_from_orbit(scenario):
    box = scenario.box
    assert box.vertices().shape == (64, 6)
    assert np.all(box.contains(scenario.rho))
    o = scenario.orbit
    assert abs(o.period / (2 * np.pi) - 1.0) < 0.02  # 2:1 resonance: about one synodic period in the frame
    end = propagate(MODEL.system, o.x0, o.period).x[-1]
    assert np.linalg.norm(end - o.x0) < 1e-8


def test_notebook_solves_end_optimal_with_finite_gain(designs):
    for key, d in designs.items():
        assert d.status == "optimal", (key, d.status)
        assert d.optimal
        assert np.isfinite(d.gain_norm) and d.gain_norm < 2e3, (key, d.gain_norm)  # the unbounded Hinf gain was 3e7


def test_designs_sparse_and_verified(scenario, designs):
    """Theorems 1-2 checked without trusting the solver: A + LC Hurwitz and the frozen-parameter norm below gamma
    at all 64 vertices and at random interior points, for every design the notebooks use."""
    rng = np.random.default_rng(0)
    for key, d in designs.items():
        assert d.used[:2].all() and not d.used[2:].any(), key  # only sin/cos theta1 needed (paper Fig. 2)
        v = lpv.verify_observer(MODEL, d, scenario.box, 40, rng, L=d.L)
        assert v.hurwitz, key
        assert v.worst < GAMMA * (1 + 1e-5), (key, v.worst)
        assert v.worst > 0.5 * GAMMA, (key, v.worst)  # the bound is nearly tight somewhere: not a trivial design


def test_hinf_precision_tends_to_the_measurement_inversion_limit(scenario, designs):
    """With the bandwidth bound R the H-infinity allowance stays below the unbounded-gain limit
    asin(gamma / max r13) and approaches it as R grows."""
    limit = np.degrees(np.arcsin(GAMMA * scenario.box.lower[2]))  # box.lower[2] = 1 / max r13
    lmi = lpv.PrecisionLMI.for_cr3bp(MODEL, scenario.box.vertices(), "hinf", sensors=[0, 1], pole_radius=200.0)
    n200 = lmi.solve(GAMMA).noise_deg[0]
    n1000 = designs["hinf_1"].noise_deg[0]
    assert n200 < n1000 < limit
    assert n1000 == pytest.approx(limit, rel=0.02)
    assert designs["hinf"].noise_deg[0] < limit


def test_precisions_do_not_depend_on_tolerance_margin_or_scaling(scenario, theta1_designs):
    designs = theta1_designs
    """Tolerance 1e-9 instead of Clarabel's 1e-8, a tenfold smaller strictness margin and another variable scale
    must all give the same precision within 1e-4 (relative): the answer is the problem's, not the solver's."""
    V = scenario.box.vertices()
    for key, kw in (("h2_1", {}), ("hinf_1", {"pole_radius": 1000.0})):
        ref = designs[key].kappa[:2]
        norm = key.split("_")[0]
        lmi = lpv.PrecisionLMI.for_cr3bp(MODEL, V, norm, sensors=[0, 1], **kw)
        tight = lmi.solve(GAMMA, tol=1e-9)
        small_eps = lpv.PrecisionLMI.for_cr3bp(MODEL, V, norm, sensors=[0, 1], eps=1e-9, **kw).solve(GAMMA)
        rescaled = lpv.PrecisionLMI.for_cr3bp(MODEL, V, norm, sensors=[0, 1], variable_scale=3.0,
                                              **kw).solve(GAMMA)
        for d in (tight, small_eps, rescaled):
            assert d.status == "optimal", (key, d.status)
            assert np.allclose(d.kappa[:2], ref, rtol=1e-4), (key, d.kappa[:2], ref)


def _svec_by_columns(M):
    """Upper triangle of a symmetric matrix column by column, off-diagonals times sqrt(2), written as loops."""
    k = M.shape[0]
    return [M[i, j] * (1.0 if i == j else np.sqrt(2.0)) for j in range(k) for i in range(j + 1)]


@pytest.mark.parametrize("norm, kw", [("h2", {}), ("hinf", {"pole_radius": 1000.0}), ("h2", {"objective": "l2"}),
                                      ("hinf", {"objective": "linf", "pole_radius": 1000.0})])
def test_direct_conic_data_equal_the_lmi_matrices(scenario, norm, kw):
    """The rows s = b - A z the direct backend hands Clarabel equal, at a random z and disturbance ratio 0.3, the
    linear rows, the (t, beta) cone rows and the upper triangles (by columns, off-diagonals times sqrt 2) of the
    LMI matrices evaluated there (a wrong triangle order, a missing sqrt 2 or a wrong affine read-off breaks this)."""
    lmi = lpv.PrecisionLMI.for_cr3bp(MODEL, scenario.box.vertices()[:3], norm, sensors=[0, 1, 4], **kw)
    lay, n = lmi._layout()
    z = np.random.default_rng(3).standard_normal(n)
    q, (A0, b0), (A1, b1), cones = lmi._conic
    r = 0.3
    s_rows = b0 + r * b1 - (A0 + r * A1) @ z
    psd, lin = lmi._blocks(*lmi._unpack(z), r)
    beta, t = z[lay["beta"]], z[lay["t"]]
    expected = list(np.concatenate([v.ravel() for v in lin]))
    if kw.get("objective") == "linf":
        expected += list(t - beta)
    if kw.get("objective") == "l2":
        expected += list(t) + list(beta)
    for M in psd:
        for m in M.reshape(-1, M.shape[-1], M.shape[-1]):
            expected += _svec_by_columns(m)
    np.testing.assert_allclose(s_rows, expected, rtol=1e-12, atol=1e-12)
    assert q[lay["beta"] if "objective" not in kw else lay["t"]].sum() == (3 if "objective" not in kw else 1)


@pytest.mark.parametrize("norm, kw", [("h2", {}), ("hinf", {"pole_radius": 1000.0}), ("h2", {"objective": "l2"}),
                                      ("h2", {"objective": "linf"})])
def test_direct_backend_equals_cvxpy(scenario, norm, kw):
    """Clarabel on the directly built data and on cvxpy's canonicalisation of the same LMI (theta1-only, 8 distinct
    vertices, plus the six-sensor objectives on 8 vertices) reach the same optimum to solver tolerance: precisions within 1e-5,
    the same status, the objective within 1e-6."""
    sensors = [0, 1] if not kw.get("objective") else None
    # theta1-only: all 64 vertices (8 distinct); six sensors: every eighth vertex (cvxpy's canonicalisation of all
    # 64 six-sensor blocks would take most of this file's time)
    V = scenario.box.vertices() if sensors else scenario.box.vertices()[::8]
    direct = lpv.PrecisionLMI.for_cr3bp(MODEL, V, norm, sensors=sensors, backend="direct", **kw)
    a = direct.solve_once(GAMMA)
    # the built problem pickles (process pools) and solves to the same bits after the round trip
    assert np.array_equal(pickle.loads(pickle.dumps(direct)).solve_once(GAMMA).kappa, a.kappa)
    b = lpv.PrecisionLMI.for_cr3bp(MODEL, V, norm, sensors=sensors, backend="cvxpy", **kw).solve_once(GAMMA)
    assert a.status == b.status == "optimal"
    used = b.used
    np.testing.assert_allclose(a.kappa[used], b.kappa[used], rtol=1e-5)
    assert np.array_equal(a.used, b.used)
    assert a.objective == pytest.approx(b.objective, rel=1e-6)


@pytest.mark.skipif(os.environ.get("CISLUNAR_SCS_TEST") != "1",
                    reason="SCS needs 1-2 min on this problem; set CISLUNAR_SCS_TEST=1 (two-tolerance test above)")
def test_precisions_agree_between_clarabel_and_scs(scenario, theta1_designs):
    designs = theta1_designs
    """SCS (first-order) against Clarabel (interior point) on the theta1-only H2 problem, within 1e-3."""
    lmi = lpv.PrecisionLMI.for_cr3bp(MODEL, scenario.box.vertices(), "h2", sensors=[0, 1])
    d = lmi.solve(GAMMA, solver="SCS", tol=1e-8, retry=False)
    assert np.allclose(d.kappa[:2], designs["h2_1"].kappa[:2], rtol=1e-3)


def test_verification_can_fail(scenario, design_h2_6):
    d = design_h2_6
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


def test_batched_sigma_max_equals_one_frequency_at_a_time():
    """The H-infinity kernel evaluates its frequency grid in one batched call: the largest singular value of
    C (jwI - A)^-1 B at each frequency, as the one-frequency form computes it (and, at w = 0, the DC gain's)."""
    rng = np.random.default_rng(7)
    A = rng.standard_normal((4, 4)) - 3 * np.eye(4)
    B, C = rng.standard_normal((4, 5)), rng.standard_normal((2, 4))
    w = np.concatenate([[0.0], np.geomspace(1e-3, 1e3, 25)])
    one = np.array([lpv._sigma_max(A, B, C, x) for x in w])
    assert lpv._sigma_max_many(A, B, C, w) == pytest.approx(one, rel=1e-13)
    assert one[0] == pytest.approx(np.linalg.norm(C @ np.linalg.solve(-A, B), 2), rel=1e-12)


@pytest.mark.parametrize("zeta", [0.15, 0.3, 0.45, 0.6])
@pytest.mark.parametrize("omega", [0.37, 3.7, 41.0])
def test_hinf_norm_second_order_closed_form(zeta, omega):
    """G(s) = w^2 / (s^2 + 2 zeta w s + w^2) peaks at w sqrt(1 - 2 zeta^2), strictly between the modal frequency
    w sqrt(1 - zeta^2) and zero, with |G| = 1 / (2 zeta sqrt(1 - zeta^2)) (zeta < 1/sqrt 2).  The peak falls between
    the points of any fixed frequency grid, so a norm that stops at its grid's lower bound (the level-set step
    replaced by the crossing frequencies themselves) is off by up to ~1e-3 here; the level-set iteration is exact."""
    A = np.array([[0.0, 1.0], [-omega**2, -2 * zeta * omega]])
    B = np.array([[0.0], [omega**2]])
    C = np.array([[1.0, 0.0]])
    peak = 1.0 / (2 * zeta * np.sqrt(1 - zeta**2))
    assert lpv.hinf_norm(A, B, C) == pytest.approx(peak, rel=1e-8)
    # two inputs, two outputs: this mode beside a better damped one at twice the frequency (zeta 0.7, peak
    # 1.0001 < every peak above) -> the norm of the block-diagonal system is the larger peak
    w2 = 2.0 * omega
    A2 = np.block([[A, np.zeros((2, 2))], [np.zeros((2, 2)), np.array([[0.0, 1.0], [-w2**2, -1.4 * w2]])]])
    B2 = np.block([[B, np.zeros((2, 1))], [np.zeros((2, 1)), np.array([[0.0], [w2**2]])]])
    assert lpv.hinf_norm(A2, B2, np.eye(4)[[0, 2]]) == pytest.approx(peak, rel=1e-8)


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


def test_observer_error_bounded(scenario, theta1_designs):
    designs = theta1_designs
    o = scenario.orbit
    t = np.arange(0.0, 0.35 * o.period, 0.01)
    truth = MODEL.planar(propagate(MODEL.system, o.x0, t).x)
    meas = make_measurements(MODEL, t, truth, 0.1, np.random.default_rng(0))
    x0 = truth[0] + np.array([0.02, -0.02, 0.01, 0.01])
    run = simulate_lpv_observer(MODEL, designs["h2_1"].gain(), meas, x0, truth)
    assert run.position_error[0] == pytest.approx(0.02 * np.sqrt(2))
    assert np.max(run.position_error[len(t) // 2:]) < 0.01  # < 3800 km after convergence
    assert np.median(run.position_error[len(t) // 2:]) < 0.005
    ekf = simulate_ekf(MODEL, meas, x0, np.eye(4) * 0.03**2, truth)
    assert np.max(ekf.position_error[len(t) // 2:]) < 0.005
    with pytest.raises(ValueError, match="sigma_deg"):
        make_measurements(MODEL, t, truth, -0.1, np.random.default_rng(0))


def test_infeasible_error_survives_pickling():
    import pickle

    exc = lpv.InfeasibleLMIError("h2 precision LMI infeasible at gamma = 0.5", 0.5, "infeasible")
    back = pickle.loads(pickle.dumps(exc))
    assert type(back) is lpv.InfeasibleLMIError and str(back) == str(exc)
    assert back.gamma == 0.5 and back.status == "infeasible"


def test_public_functions_name_bad_arguments():
    with pytest.raises(ValueError, match="^B must have 2 rows"):
        lpv.hinf_norm(-np.eye(2), np.ones((3, 1)), np.ones((1, 2)))
    with pytest.raises(ValueError, match="^C must have 2 columns"):
        lpv.h2_norm(-np.eye(2), np.ones((2, 1)), np.ones((1, 3)))
    with pytest.raises(ValueError, match="^A must be a square"):
        lpv.hinf_norm(np.ones((2, 3)), np.ones((2, 1)), np.ones((1, 2)))
    with pytest.raises(ValueError, match="theta1 \\+ theta2 is a multiple of pi"):
        MODEL.rho_from_angles(1.0, np.pi - 1.0)  # float pi: sin(theta3) ~ 1e-16, not 0
    with pytest.raises(TypeError, match="^p must be an integer"):
        lpv.resonant_orbit(p="2")
    with pytest.raises(TypeError, match="^design must be"):
        lpv.guaranteed_error_rms("design", 0.1, 0.01)
    with pytest.raises(ValueError, match="^structure must be one of"):
        lpv.disturbance_model("solar")
    with pytest.raises(TypeError, match="^rng must be"):
        lpv.ParameterBox(np.zeros(2), np.ones(2), names=("a", "b")).sample(3, 0)


def test_guaranteed_error_rms_formula(theta1_designs):
    designs = theta1_designs
    d2, dinf = designs["h2_1"], designs["hinf_1"]
    k2, kinf = d2.kappa[:2].max(), dinf.kappa[:2].max()
    sig = np.radians(0.1)
    assert lpv.guaranteed_error_rms(d2, 0.1, 0.01) == pytest.approx(GAMMA * k2 * sig * 0.1, rel=1e-12)
    assert lpv.guaranteed_error_rms(dinf, 0.1) == pytest.approx(GAMMA * kinf * sig, rel=1e-12)
    # at the allowed noise the guarantee is gamma itself (Eq. 24 inverted, small-angle)
    allowed = float(dinf.noise_deg[:2].min())
    assert lpv.guaranteed_error_rms(dinf, allowed) == pytest.approx(GAMMA, rel=1e-5)
    with pytest.raises(ValueError, match="dt"):
        lpv.guaranteed_error_rms(d2, 0.1)


def test_h2_per_sample_conversion(theta1_designs):
    designs = theta1_designs
    d = designs["h2_1"]
    dt = 0.01
    # per-sample sigma = intensity / sqrt(dt): sin(per-sample) * sqrt(dt) = 1 / kappa
    per = d.noise_per_sample_deg(dt)[0]
    assert np.sin(np.radians(per)) * np.sqrt(dt) == pytest.approx(1.0 / d.kappa[0], rel=1e-12)
    with pytest.raises(ValueError, match="H2"):
        designs["hinf_1"].noise_per_sample_deg(dt)


def test_solve_returns_the_best_optimal_retry_not_the_first(monkeypatch, scenario):
    """When the problem's own scaling does not end optimal, solve() tries every retry scaling and returns the
    optimal design with the smallest objective (a scaling that makes the strictness margin bind ends 'optimal' at a
    worse objective); the own scaling's optimal design is returned at once."""
    lmi = lpv.PrecisionLMI.for_cr3bp(MODEL, scenario.box.vertices(), "h2")
    calls = []

    def fake(self, gamma, solver, dscale, sparsity_tol, options):
        k = len(calls)
        calls.append(self)
        if k == 0:
            raise lpv.InfeasibleLMIError("numerical failure", gamma, "numerical error")
        objective = {1: 2.0, 2: 1.0, 3: 1.5}.get(k, 3.0)
        return types.SimpleNamespace(optimal=True, objective=objective, index=k, gamma=gamma, status="optimal")

    monkeypatch.setattr(lpv.PrecisionLMI, "_solve_once", fake)
    d = lmi.solve(GAMMA)
    assert d.index == 2 and d.objective == 1.0
    assert len(calls) == len({id(c) for c in calls}) > 3  # every distinct scaling was tried

    calls.clear()

    def own_optimal(self, gamma, solver, dscale, sparsity_tol, options):
        calls.append(self)
        return types.SimpleNamespace(optimal=True, objective=5.0 - len(calls), index=len(calls), gamma=gamma,
                                     status="optimal")

    monkeypatch.setattr(lpv.PrecisionLMI, "_solve_once", own_optimal)
    assert lmi.solve(GAMMA).index == 1 and len(calls) == 1  # no retry when the own scaling is optimal
