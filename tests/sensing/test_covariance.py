"""SPD helpers, process noise discretisation, EKF covariance recursion (vs filterpy), augmented linearisation."""

import numpy as np
import pytest
from filterpy.kalman import KalmanFilter
from hypothesis import given
from hypothesis import strategies as st

from cislunar.cr3bp.dynamics import EARTH_MOON
from cislunar.cr3bp.propagation import propagate, propagate_stm
from cislunar.sensing import covariance as C
from cislunar.sensing import measurements as M

# Wolf & Jones Table 4 target rows (near-periodic DROs, period about 16 days)
TARGETS = np.array([[7.78717734e-1, 0, 0, 0, 5.55157488e-1, 0],
                    [7.79426943e-1, 0, 0, 0, 5.54128887e-1, 0],
                    [7.81554639e-1, 0, 0, 0, 5.51070308e-1, 0]])
OBSERVER = np.array([7.80136159e-1, 0, 0, 0, 5.53104815e-1, 0])
DAY = float(EARTH_MOON.days_to_tu(1.0))


def _random_spd(rng, n, scale=1.0):
    A = rng.normal(size=(n, n))
    return scale * (A @ A.T + 0.5 * np.eye(n))


# ---------------------------------------------------------------------------------------------- SPD helpers
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 8), logscale=st.floats(-12, 12))
def test_logdet_matches_slogdet(seed, n, logscale):
    P = _random_spd(np.random.default_rng(seed), n, 10.0**logscale)
    sign, ref = np.linalg.slogdet(P)
    assert sign > 0
    assert C.logdet_spd(P) == pytest.approx(ref, rel=1e-10, abs=1e-9)


def test_spd_helpers_reject_bad_matrices():
    with pytest.raises(ValueError, match="Pbad.*positive definite"):
        C.check_spd(np.diag([1.0, -1.0]), "Pbad")
    with pytest.raises(ValueError, match="Pasym.*symmetric"):
        C.check_spd([[1.0, 0.5], [0.0, 1.0]], "Pasym")
    with pytest.raises(ValueError, match="Psq.*square"):
        C.check_spd(np.ones((2, 3)), "Psq")
    with pytest.raises(ValueError, match="Pnan"):
        C.check_spd([[np.nan, 0], [0, 1]], "Pnan")
    with pytest.raises(ValueError, match="Pzero"):
        C.logdet_spd(np.zeros((2, 2)), "Pzero")
    P = np.array([[2.0, 1.0 + 1e-12], [1.0, 2.0]])
    np.testing.assert_array_equal(C.symmetrize(P), C.symmetrize(P).T)
    L = C.cholesky_spd(P)
    np.testing.assert_allclose(L @ L.T, C.symmetrize(P), rtol=1e-14)


def test_block_diag_and_augmentation():
    blocks = np.arange(2 * 3 * 3, dtype=float).reshape(2, 3, 3)
    B = C.block_diag(blocks)
    np.testing.assert_array_equal(B[:3, :3], blocks[0])
    np.testing.assert_array_equal(B[3:, 3:], blocks[1])
    assert np.all(B[:3, 3:] == 0)
    P = C.state_covariance(100.0, 1e-2, EARTH_MOON)
    assert np.sqrt(P[0, 0]) * EARTH_MOON.length_unit_km == pytest.approx(100.0)
    assert np.sqrt(P[5, 5]) * EARTH_MOON.velocity_unit_km_s == pytest.approx(1e-2)
    PA = C.augmented_covariance(P, np.stack([P, 2 * P]))
    assert PA.shape == (18, 18)
    np.testing.assert_array_equal(PA[12:, 12:], 2 * P)
    xa = C.augment_states(OBSERVER, TARGETS)
    np.testing.assert_array_equal(xa[6:12], TARGETS[0])
    with pytest.raises(ValueError, match="P_targets"):
        C.augmented_covariance(P, -P)
    with pytest.raises(ValueError, match="targets"):
        C.augment_states(OBSERVER, TARGETS[0])


# ---------------------------------------------------------------------------------------------- process noise
def test_psd_conversion():
    q = C.psd_to_nondimensional(1e-11, EARTH_MOON)
    L, T = EARTH_MOON.length_unit_km, EARTH_MOON.time_unit_s
    assert q == pytest.approx(1e-11 * T**3 / L**2)
    assert q == pytest.approx(3.5743e-6, rel=1e-4)
    # physical check: velocity variance after dt is q dt in both unit systems
    dt_s = 86400.0
    assert q * (dt_s / T) * (L / T) ** 2 == pytest.approx(1e-11 * dt_s)
    with pytest.raises(ValueError, match="q_km2_s3"):
        C.psd_to_nondimensional(-1.0, EARTH_MOON)


def test_van_loan_double_integrator():
    A = np.zeros((6, 6))
    A[:3, 3:] = np.eye(3)
    q, dt = 0.3, 2.0
    Phi, Q = C.van_loan(A, q, dt)
    ref = np.block([[dt**3 / 3 * np.eye(3), dt**2 / 2 * np.eye(3)], [dt**2 / 2 * np.eye(3), dt * np.eye(3)]]) * q
    np.testing.assert_allclose(Q, ref, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(Phi[:3, 3:], dt * np.eye(3), rtol=1e-14)


def test_process_noise_quadrature_matches_lyapunov_ode():
    q = C.psd_to_nondimensional(C.WOLF_JONES_PSD_KM2_S3, EARTH_MOON)
    t = np.array([0.0, DAY, 3.0 * DAY])  # non-uniform intervals
    tr = propagate(EARTH_MOON, TARGETS[0], t)
    Qd = C.process_noise(EARTH_MOON, tr.x, t, q)
    assert Qd.shape == (2, 6, 6)
    for k in range(2):
        ref = C.process_noise_lyapunov(EARTH_MOON, tr.x[k], t[k + 1] - t[k], q)
        np.testing.assert_allclose(Qd[k], ref, rtol=1e-9, atol=1e-9 * np.max(np.abs(ref)))
        C.check_spd(Qd[k], "Qd")
    # a frozen-A Van Loan agrees over a short arc but not over a long one: A(t) matters, and the exact
    # discretisation along the reference is what captures it
    A = EARTH_MOON.jacobian(tr.x[0])
    _, Qvl = C.van_loan(A, q, 1e-3)
    ref = C.process_noise_lyapunov(EARTH_MOON, tr.x[0], 1e-3, q)
    np.testing.assert_allclose(Qvl, ref, rtol=1e-2, atol=1e-6 * np.max(np.abs(ref)))
    _, Qvl_long = C.van_loan(A, q, 0.5)
    ref_long = C.process_noise_lyapunov(EARTH_MOON, tr.x[0], 0.5, q)
    assert np.max(np.abs(Qvl_long - ref_long)) > 1e-2 * np.max(np.abs(ref_long))
    # linear in q; batch of objects
    Qb = C.process_noise(EARTH_MOON, np.stack([tr.x, tr.x]), t, 2 * q)
    np.testing.assert_allclose(Qb[1], 2 * Qd, rtol=1e-12)


def test_process_noise_bad_input():
    t = np.array([0.0, DAY])
    x = np.tile(TARGETS[0], (2, 1))
    with pytest.raises(ValueError, match="q"):
        C.process_noise(EARTH_MOON, x, t, -1.0)
    with pytest.raises(ValueError, match="x must hold"):
        C.process_noise(EARTH_MOON, x[:1], t, 1.0)
    with pytest.raises(ValueError, match="t"):
        C.process_noise(EARTH_MOON, x, t[::-1], 1.0)


# ---------------------------------------------------------------------------------------------- EKF vs filterpy
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(2, 7), m=st.integers(1, 4))
def test_predict_update_equal_filterpy(seed, n, m):
    rng = np.random.default_rng(seed)
    P = _random_spd(rng, n)
    F = np.eye(n) + 0.3 * rng.normal(size=(n, n))
    Q = _random_spd(rng, n, 0.01)
    H = rng.normal(size=(m, n))
    R = _random_spd(rng, m, 0.1)
    kf = KalmanFilter(dim_x=n, dim_z=m)
    kf.P, kf.F, kf.Q, kf.H, kf.R = P.copy(), F, Q, H, R
    kf.predict()
    Pp = C.ekf_predict(P, F, Q)
    np.testing.assert_allclose(Pp, kf.P, rtol=1e-12, atol=1e-13 * np.max(np.abs(Pp)))
    kf.update(np.zeros(m))
    Pu, K, S = C.ekf_update(Pp, H, R)
    np.testing.assert_allclose(K, kf.K, rtol=1e-9, atol=1e-10 * np.max(np.abs(K)))
    np.testing.assert_allclose(S, kf.S, rtol=1e-12, atol=1e-13 * np.max(np.abs(S)))
    np.testing.assert_allclose(Pu, kf.P, rtol=1e-9, atol=1e-10 * np.max(np.abs(Pp)))
    C.check_spd(Pu, "Pu")


def test_ekf_update_bad_input():
    P = np.eye(3)
    with pytest.raises(ValueError, match="R"):
        C.ekf_update(P, np.ones((2, 3)), -np.eye(2))
    with pytest.raises(ValueError, match="H"):
        C.ekf_update(P, np.ones((2, 4)), np.eye(2))
    with pytest.raises(ValueError, match="R"):
        C.ekf_update(P, np.ones((2, 3)), np.eye(3))
    with pytest.raises(ValueError, match="P"):
        C.ekf_predict(np.ones((3, 2)), np.eye(3), np.eye(3))
    with pytest.raises(ValueError, match="F"):
        C.ekf_predict(P, np.eye(4), np.eye(3))


@pytest.fixture(scope="module")
def dro_window():
    """Observer + 2 targets on Table 4 DROs, range/range-rate, 6 daily measurements (t = 0..5 days)."""
    t = np.arange(6) * DAY
    P0 = C.block_diag([C.state_covariance(100.0, 1e-2, EARTH_MOON)] * 3)
    R = M.range_range_rate_noise(0.1, 0.01, EARTH_MOON)
    q = C.psd_to_nondimensional(1e-11, EARTH_MOON)
    return C.linearize_augmented(EARTH_MOON, OBSERVER, TARGETS[:2], t, M.RANGE_RANGE_RATE, R, P0, q=q,
                                 derivatives=True)


def test_crlb_equals_filterpy_along_dro(dro_window):
    lin = dro_window
    hist = C.covariance_analysis(*lin.arrays)
    n, m = lin.P0.shape[0], lin.H.shape[1]
    kf = KalmanFilter(dim_x=n, dim_z=m)
    kf.P = lin.P0.copy()
    for k in range(lin.t.size):
        if k > 0:
            kf.F, kf.Q = lin.F[k - 1], lin.Q[k - 1]
            kf.predict()
        np.testing.assert_allclose(hist.prior[k], kf.P, rtol=1e-7, atol=1e-9 * np.max(np.abs(kf.P)))
        kf.H, kf.R = lin.H[k], lin.R[k]
        kf.update(np.zeros(m))
        np.testing.assert_allclose(hist.posterior[k], kf.P, rtol=1e-7, atol=1e-8 * np.max(np.abs(kf.P)))
    # every covariance stays SPD and measurements never increase the uncertainty
    C.check_spd(hist.prior, "prior")
    C.check_spd(hist.posterior, "posterior")
    assert np.all(np.trace(hist.posterior, axis1=1, axis2=2) <= np.trace(hist.prior, axis1=1, axis2=2))
    sig = C.position_sigma_km(hist.posterior, 0, EARTH_MOON)
    assert sig.shape == (6,) and sig[0] < np.sqrt(3) * 100.0
    # with measurements the final uncertainty is below the open-loop propagation of P0 (which grows to ~5000 km
    # in 5 days from the 1 cm/s velocity uncertainty: the transient the paper describes for its Figure 4)
    P_open = lin.P0
    for k in range(lin.t.size - 1):
        P_open = C.ekf_predict(P_open, lin.F[k], lin.Q[k])
    for i in range(3):
        assert C.position_sigma_km(hist.posterior[-1], i, EARTH_MOON) < C.position_sigma_km(P_open, i, EARTH_MOON)


def test_linearization_structure(dro_window):
    lin = dro_window
    N, n = lin.t.size, 18
    assert lin.F.shape == (N - 1, n, n) and lin.H.shape == (N, 4, n) and lin.R.shape == (N, 4, 4)
    # Eq. 22: block diagonal transitions; Eq. 21: observer columns are minus the target columns
    assert np.all(lin.F[:, :6, 6:] == 0) and np.all(lin.Q[:, :6, 6:] == 0)
    np.testing.assert_allclose(lin.H[:, 0:2, 0:6], -lin.H[:, 0:2, 6:12], rtol=0)
    np.testing.assert_allclose(lin.H[:, 2:4, 0:6], -lin.H[:, 2:4, 12:18], rtol=0)
    assert np.all(lin.H[:, 0:2, 12:18] == 0)
    # running product of interval STMs equals the STM propagated in one go (no long-arc inversion needed)
    ref = propagate_stm(EARTH_MOON, OBSERVER, lin.t)
    np.testing.assert_allclose(lin.observer_stm, ref.stm, rtol=1e-9, atol=1e-10)
    np.testing.assert_allclose(lin.targets[1], propagate(EARTH_MOON, TARGETS[1], lin.t).x, atol=1e-12)
    # measurement values along the trajectories
    np.testing.assert_allclose(lin.H[3, 2:4, 12:18], M.RANGE_RANGE_RATE.jacobians(lin.observer[3],
                                                                                lin.targets[1, 3])[1])


def test_linearization_derivatives_match_finite_differences(dro_window):
    lin = dro_window
    h = 1e-6
    dF = np.zeros_like(lin.dF)
    dH = np.zeros_like(lin.dH)
    R = lin.R[0, :2, :2]
    for j in range(6):
        e = np.zeros(6)
        e[j] = h
        lp = C.linearize_augmented(EARTH_MOON, OBSERVER + e, TARGETS[:2], lin.t, M.RANGE_RANGE_RATE, R, lin.P0,
                                   Q=lin.Q)
        lm = C.linearize_augmented(EARTH_MOON, OBSERVER - e, TARGETS[:2], lin.t, M.RANGE_RANGE_RATE, R, lin.P0,
                                   Q=lin.Q)
        dF[..., j] = (lp.F - lm.F) / (2 * h)
        dH[..., j] = (lp.H - lm.H) / (2 * h)
    np.testing.assert_allclose(lin.dF, dF, atol=1e-6 * np.max(np.abs(dF)))
    np.testing.assert_allclose(lin.dH, dH, atol=1e-5 * np.max(np.abs(dH)))


def test_linearize_bad_input():
    t = np.arange(3) * DAY
    P0 = np.eye(12) * 1e-6
    R = np.eye(2) * 1e-12
    with pytest.raises(ValueError, match="exactly one of q"):
        C.linearize_augmented(EARTH_MOON, OBSERVER, TARGETS[:1], t, M.RANGE_RANGE_RATE, R, P0)
    with pytest.raises(ValueError, match="P0"):
        C.linearize_augmented(EARTH_MOON, OBSERVER, TARGETS[:1], t, M.RANGE_RANGE_RATE, R, np.eye(18), q=0.0)
    with pytest.raises(ValueError, match="P0"):
        C.linearize_augmented(EARTH_MOON, OBSERVER, TARGETS[:1], t, M.RANGE_RANGE_RATE, R, -P0, q=0.0)
    with pytest.raises(ValueError, match="noise"):
        C.linearize_augmented(EARTH_MOON, OBSERVER, TARGETS[:1], t, M.RANGE_RANGE_RATE, np.eye(3), P0, q=0.0)
    with pytest.raises(ValueError, match="model"):
        C.linearize_augmented(EARTH_MOON, OBSERVER, TARGETS[:1], t, "range", R, P0, q=0.0)


def test_covariance_analysis_bad_input():
    rng = np.random.default_rng(0)
    P0 = np.eye(3)
    F = np.tile(np.eye(3), (2, 1, 1))
    H = rng.normal(size=(3, 2, 3))
    with pytest.raises(ValueError, match="Q must be positive semi-definite"):
        C.covariance_analysis(P0, F, -np.eye(3), H, np.eye(2))
    with pytest.raises(ValueError, match="R"):
        C.covariance_analysis(P0, F, np.eye(3), H, np.diag([1.0, -1.0]))
    with pytest.raises(ValueError, match="F"):
        C.covariance_analysis(P0, F[:1], np.eye(3), H, np.eye(2))
    with pytest.raises(ValueError, match="H"):
        C.covariance_analysis(P0, F, np.eye(3), H[..., :2], np.eye(2))
    with pytest.raises(ValueError, match="P0"):
        C.covariance_analysis(np.diag([1.0, 0.0, 1.0]), F, np.eye(3), H, np.eye(2))


# ---------------------------------------------------------------------------------------------- reliability (issue 11)
def test_ekf_predict_rejects_non_spd_arguments_by_name():
    P, F, Q = np.eye(3), np.eye(3), 0.1 * np.eye(3)
    np.testing.assert_allclose(C.ekf_predict(P, F, Q), 1.1 * np.eye(3))
    np.testing.assert_allclose(C.ekf_predict(P, F, np.zeros((3, 3))), P)  # zero process noise is allowed
    with pytest.raises(ValueError, match=r"\bP\b.*positive definite"):
        C.ekf_predict(-P, F, Q)
    with pytest.raises(ValueError, match=r"\bP\b.*positive definite"):
        C.ekf_predict(np.diag([1.0, 1.0, 0.0]), F, Q)  # singular: semi-definite is not enough for P
    with pytest.raises(ValueError, match=r"\bQ\b.*semi-definite"):
        C.ekf_predict(P, F, np.diag([0.1, -0.1, 0.1]))
    with pytest.raises(ValueError, match=r"\bQ\b.*symmetric"):
        C.ekf_predict(P, F, [[0.1, 0.05, 0], [0, 0.1, 0], [0, 0, 0.1]])
    with pytest.raises(ValueError, match=r"\bP\b.*symmetric"):
        C.ekf_predict([[1.0, 0.5, 0], [0, 1.0, 0], [0, 0, 1.0]], F, Q)
    with pytest.raises(ValueError, match="F and Q"):
        C.ekf_predict(P, np.eye(2), Q)
    with pytest.raises(ValueError, match=r"\bQ\b.*NaN"):
        C.ekf_predict(P, F, np.full((3, 3), np.nan))


def test_ekf_update_rejects_non_spd_prior():
    H, R = np.ones((1, 2)), np.eye(1)
    with pytest.raises(ValueError, match=r"\bP\b.*positive definite"):
        C.ekf_update(np.diag([1.0, -2.0]), H, R)
    with pytest.raises(ValueError, match=r"\bR\b.*positive definite"):
        C.ekf_update(np.eye(2), H, -R)


def test_check_psd_tolerance_and_batch():
    # a rank-deficient PSD matrix with round-off passes; a clearly negative eigenvalue fails
    v = np.array([1.0, 2.0, 3.0])
    Q = np.outer(v, v)
    Q[0, 0] -= 1e-14
    np.testing.assert_allclose(C.check_psd(Q), Q)
    batch = np.stack([np.eye(2), np.diag([1.0, -1e-3])])
    with pytest.raises(ValueError, match="Qb.*semi-definite"):
        C.check_psd(batch, "Qb")


def test_symmetrize_rejects_non_square_and_is_projection():
    with pytest.raises(ValueError, match=r"\bP\b.*square"):
        C.symmetrize(np.ones((2, 3)))
    with pytest.raises(ValueError, match="Mx.*square"):
        C.symmetrize(np.ones(4), "Mx")
    A = np.random.default_rng(1).normal(size=(2, 4, 4))
    S = C.symmetrize(A)
    np.testing.assert_allclose(S, np.swapaxes(S, -1, -2))
    np.testing.assert_allclose(C.symmetrize(S), S)  # idempotent
    np.testing.assert_allclose(S + 0.5 * (A - np.swapaxes(A, -1, -2)), A)  # symmetric + skew parts recover A


def test_assembled_from_cached_targets_equals_one_shot_linearisation(dro_window):
    """Propagating the targets once and assembling must give the same linearisation as linearize_augmented."""
    lin = dro_window
    R = M.range_range_rate_noise(0.1, 0.01, EARTH_MOON)
    q = C.psd_to_nondimensional(1e-11, EARTH_MOON)
    obs = C.propagate_arcs(EARTH_MOON, OBSERVER, lin.t, q=q, order=2)
    tgt = C.propagate_arcs(EARTH_MOON, TARGETS[:2], lin.t, q=q)
    lin2 = C.assemble_augmented(M.RANGE_RANGE_RATE, R, lin.P0, obs, tgt)
    for a, b in zip(lin.arrays + (lin.dF, lin.dH), lin2.arrays + (lin2.dF, lin2.dH)):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-300)
    stm = obs.stm_from_start[0]
    np.testing.assert_allclose(stm[-1], propagate_stm(EARTH_MOON, OBSERVER, [lin.t[0], lin.t[-1]]).stm[-1],
                               rtol=1e-9, atol=1e-9)


def test_position_sigma_axes_split_the_trace():
    """In-plane and out-of-plane parts add up in squares to the full RMS; one axis is its own diagonal entry."""
    rng = np.random.default_rng(3)
    A = rng.standard_normal((5, 12, 12))
    P = A @ np.swapaxes(A, -1, -2) * 1e-8
    for i in (0, 1):
        full = C.position_sigma_km(P, i, EARTH_MOON)
        xy = C.position_sigma_km(P, i, EARTH_MOON, axes=(0, 1))
        z = C.position_sigma_km(P, i, EARTH_MOON, axes=(2,))
        assert np.max(np.abs(xy**2 + z**2 - full**2) / full**2) < 1e-14
        assert np.allclose(z, np.sqrt(P[:, 6 * i + 2, 6 * i + 2]) * EARTH_MOON.length_unit_km, rtol=1e-15)
    assert np.array_equal(C.position_sigma_km(P, 0, EARTH_MOON, axes=[2, 0]),
                          C.position_sigma_km(P, 0, EARTH_MOON, axes=(0, 2)))
    for bad in ((0, 0), (3,), ()):
        with pytest.raises(ValueError, match="axes"):
            C.position_sigma_km(P, 0, EARTH_MOON, axes=bad)
    with pytest.raises(TypeError, match="axes"):
        C.position_sigma_km(P, 0, EARTH_MOON, axes="xy")


def test_window_assembler_equals_assemble_augmented(dro_window):
    """WindowAssembler (model, noise, P0, targets and a fixed Q checked once) returns, for every observer candidate
    of a batch, exactly what assemble_augmented returns; it refuses arcs on another grid and bad fixed ingredients."""
    lin = dro_window
    R = M.range_range_rate_noise(0.1, 0.01, EARTH_MOON)
    q = C.psd_to_nondimensional(1e-11, EARTH_MOON)
    tgt = C.propagate_arcs(EARTH_MOON, TARGETS[:2], lin.t, q=q)
    obs = C.propagate_arcs(EARTH_MOON, OBSERVER + np.array([[0.0] * 6, [1e-4, 0, 0, 0, 0, 1e-4]]), lin.t, q=q,
                           order=2)
    for Q in (None, lin.Q):
        asm = C.WindowAssembler(M.RANGE_RANGE_RATE, R, lin.P0, tgt, Q=Q)
        for i in range(2):
            a = asm(obs, i)
            b = C.assemble_augmented(M.RANGE_RANGE_RATE, R, lin.P0, obs, tgt, Q=Q, index=i)
            for name in ("t", "observer", "targets", "P0", "F", "Q", "H", "R", "dF", "dH", "observer_stm"):
                assert np.array_equal(getattr(a, name), getattr(b, name)), (name, i)
    assert not np.array_equal(asm(obs, 0).H, asm(obs, 1).H)  # the index selects the candidate
    short = C.propagate_arcs(EARTH_MOON, OBSERVER, lin.t[:-1], q=q)
    with pytest.raises(ValueError, match="time grid"):
        asm(short)
    with pytest.raises(ValueError, match="index"):
        asm(obs, 2)
    with pytest.raises(ValueError, match="P0"):
        C.WindowAssembler(M.RANGE_RANGE_RATE, R, -lin.P0, tgt)
    with pytest.raises(ValueError, match="noise"):
        C.WindowAssembler(M.RANGE_RANGE_RATE, -R, lin.P0, tgt)
    with pytest.raises(ValueError, match="Q"):
        C.WindowAssembler(M.RANGE_RANGE_RATE, R, lin.P0, tgt, Q=-lin.Q)
