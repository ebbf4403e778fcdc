"""OCBE transition matrix: block structure, symplectic-like identities, and Q equal to the exact process noise."""

import numpy as np
import pytest

from cislunar.cr3bp import orbits
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.cr3bp.propagation import propagate_stm
from cislunar.estimation import ocbe
from cislunar.sensing import covariance

Q_WEIGHT = 3.5e-6  # LU^2/TU^3 (1e-11 km^2/s^3)


@pytest.fixture(scope="module")
def two_hours_near_perilune():
    nrho = orbits.nrho_9_2(em)
    dt = float(em.days_to_tu(2.0 / 24.0))
    t0 = nrho.period / 2 - dt  # the two hours before perilune: the hardest stretch
    x_start = propagate_stm(em, nrho.x0, [0.0, t0]).x[-1]
    grid = np.linspace(0.0, dt, 5)
    return x_start, grid, ocbe.ocbe_transition(em, x_start, grid, Q_WEIGHT)


def test_state_block_is_the_ordinary_stm_and_costate_blocks_have_the_adjoint_structure(two_hours_near_perilune):
    x0, grid, tr = two_hours_near_perilune
    ref = propagate_stm(em, x0, grid)
    assert np.max(np.abs(tr.x - ref.x)) < 1e-13
    assert np.max(np.abs(tr.phi_xx - ref.stm)) < 1e-10 * np.max(np.abs(ref.stm))
    assert np.max(np.abs(tr.phi_px)) == 0.0
    for k in range(1, grid.size):
        inv_t = np.linalg.inv(tr.phi_xx[k]).T
        assert np.max(np.abs(tr.phi_pp[k] - inv_t)) < 1e-9 * np.max(np.abs(inv_t))
        M = tr.phi_xp[k] @ tr.phi_xx[k].T
        assert np.max(np.abs(M - M.T)) < 1e-9 * np.max(np.abs(M))


def test_ocbe_process_noise_equals_exact_white_noise_discretisation(two_hours_near_perilune):
    x0, grid, tr = two_hours_near_perilune
    Q_ocbe = ocbe.ocbe_process_noise(tr.phi[-1])
    Q_exact = covariance.process_noise_lyapunov(em, x0, grid[-1], Q_WEIGHT)
    assert np.max(np.abs(Q_ocbe - Q_exact)) < 1e-8 * np.max(np.abs(Q_exact))
    assert np.linalg.eigvalsh(Q_ocbe).min() > 0  # controllable through accelerations: full rank
    with pytest.raises(ValueError, match="phi"):
        ocbe.ocbe_process_noise(np.random.default_rng(0).standard_normal((12, 12)))


def test_estimated_control_and_bad_input(two_hours_near_perilune):
    _, _, tr = two_hours_near_perilune
    p = np.r_[np.zeros(3), 1.0, -2.0, 0.5]
    u = ocbe.estimated_control(Q_WEIGHT, tr.phi_pp, p)
    assert u.shape == (tr.t.size, 3)
    assert np.allclose(u[0], -Q_WEIGHT * p[3:])
    with pytest.raises(ValueError, match="control_weight"):
        ocbe.ocbe_transition(em, tr.x[0], 0.1, -1.0)
    with pytest.raises(ValueError, match="p"):
        ocbe.estimated_control(Q_WEIGHT, tr.phi_pp, np.zeros(5))


# ---------------------------------------------------------------------------------------------------------------
# The SRI OCBE filter / smoother
# ---------------------------------------------------------------------------------------------------------------
from filterpy.kalman import KalmanFilter  # noqa: E402

from cislunar.cr3bp.propagation import propagate  # noqa: E402
from cislunar.sensing import measurements, sites  # noqa: E402


def _scenario(rng, dv_lu_tu=0.0, n_meas=13, q=Q_WEIGHT):
    """9:2 NRHO target near apolune tracked from L2 with angles and rates every 2 hours."""
    nrho = orbits.nrho_9_2(em)
    dt = float(em.days_to_tu(2.0 / 24.0))
    t = np.arange(n_meas) * dt
    x_true0 = nrho.x0.copy()
    x_true = propagate(em, x_true0, t).x
    if dv_lu_tu:
        k = n_meas // 2  # impulsive maneuver right after measurement k
        after = x_true[k].copy()
        after[3:] += dv_lu_tu * np.array([0.0, 1.0, 0.0])
        x_true[k + 1:] = propagate(em, after, t[k:]).x[1:]
    obs = np.tile(sites.l2_observer_state(em), (n_meas, 1))
    sig_ang = 1e-5  # rad
    sig_rate = np.sqrt(2.0) * sig_ang / float(em.days_to_tu(1.0 / 86400.0))  # Eq. 13 with 1 s differencing, rad/TU
    Rm = np.diag([sig_ang**2, sig_ang**2, sig_rate**2, sig_rate**2])
    model = measurements.ANGLES_AND_RATES
    y = model(obs, x_true) + rng.standard_normal((n_meas, 4)) * np.sqrt(np.diag(Rm))
    P0 = np.diag(np.r_[np.full(3, em.km_to_lu(10.0 / 3) ** 2), np.full(3, (1e-4 / 3 / em.velocity_unit_km_s) ** 2)])
    x0 = x_true0 + rng.multivariate_normal(np.zeros(6), P0)
    return t, y, obs, model, Rm, x0, P0, q


@pytest.fixture(scope="module")
def ocbe_run():
    rng = np.random.default_rng(7)
    args = _scenario(rng)
    return args, ocbe.ocbe_filter_smoother(em, *args)


def test_sri_ocbe_equals_covariance_form_ekf_with_independent_process_noise(ocbe_run):
    (t, y, obs, model, Rm, x0, P0, q), res = ocbe_run
    for n in range(t.size - 1):
        dt = t[n + 1] - t[n]
        F = propagate_stm(em, res.x_filt[n], [0.0, dt]).stm[-1]
        Q = covariance.process_noise_lyapunov(em, res.x_filt[n], dt, q)
        kf = KalmanFilter(dim_x=6, dim_z=4)
        kf.x, kf.P, kf.F, kf.Q = np.zeros(6), res.P_filt[n].copy(), F, Q
        kf.predict()
        assert np.max(np.abs(kf.P - res.P_pred[n + 1])) < 1e-7 * np.max(np.abs(kf.P))
        x_prior = propagate(em, res.x_filt[n], [0.0, dt]).x[-1]
        assert np.max(np.abs(x_prior - res.x_pred[n + 1])) < 1e-12
        val, _, H = model.evaluate(obs[n + 1], x_prior)
        kf.H, kf.R = H, Rm
        kf.update(model.residual(y[n + 1], val))
        assert np.max(np.abs(kf.P - res.P_filt[n + 1])) < 1e-7 * np.max(np.abs(kf.P))
        assert np.max(np.abs(x_prior + kf.x - res.x_filt[n + 1])) < 1e-7 * np.max(np.abs(kf.x)) + 1e-15


def test_costate_explains_the_update_through_the_dynamics(ocbe_run):
    (t, *_rest), res = ocbe_run
    q = _rest[-1]
    for n in (0, 5, t.size - 2):
        Phi = ocbe.ocbe_transition(em, res.x_filt[n], [t[n], t[n + 1]], q).phi[-1]
        dx_n = -res.P_filt[n] @ res.costate_step[n]  # Eq. 31 solved for x_{n|n+1} - x_{n|n}
        lhs = res.x_filt[n + 1] - res.x_pred[n + 1]
        rhs = Phi[:6, :6] @ dx_n + Phi[:6, 6:] @ res.costate_step[n]
        assert np.max(np.abs(lhs - rhs)) < 1e-8 * np.max(np.abs(lhs))


def test_full_smoother_equals_rts_and_never_loses_information(ocbe_run):
    (t, *_rest), res = ocbe_run
    N = t.size
    assert np.allclose(res.x_smooth[-1], res.x_filt[-1]) and np.allclose(res.P_smooth[-1], res.P_filt[-1])
    xs, Ps = res.x_filt[-1].copy(), res.P_filt[-1].copy()
    for n in range(N - 2, -1, -1):
        dt = t[n + 1] - t[n]
        F = propagate_stm(em, res.x_filt[n], [0.0, dt]).stm[-1]
        C = res.P_filt[n] @ F.T @ np.linalg.inv(res.P_pred[n + 1])
        xs = res.x_filt[n] + C @ (xs - res.x_pred[n + 1])
        Ps = res.P_filt[n] + C @ (Ps - res.P_pred[n + 1]) @ C.T
        assert np.max(np.abs(xs - res.x_smooth[n])) < 1e-8 * np.max(np.abs(xs - res.x_filt[n])) + 1e-14
        assert np.max(np.abs(Ps - res.P_smooth[n])) < 1e-6 * np.max(np.abs(Ps))
        assert np.linalg.eigvalsh(res.P_filt[n] - res.P_smooth[n]).min() > -1e-10 * np.max(np.abs(res.P_filt[n]))


def test_a_maneuver_shows_as_a_smoothed_control_spike_in_its_interval():
    dv = 1e-3 / em.velocity_unit_km_s  # 1 m/s, the paper's active station-keeping mean
    q = Q_WEIGHT * 1e-2
    z_quiet, z_burn = [], []
    for seed in range(3):
        quiet = ocbe.ocbe_filter_smoother(em, *_scenario(np.random.default_rng(seed), q=q, n_meas=25))
        burn = ocbe.ocbe_filter_smoother(em, *_scenario(np.random.default_rng(seed), dv_lu_tu=dv, q=q, n_meas=25))
        z_quiet.append(quiet.z_smooth)
        z_burn.append(burn.z_smooth)
        per_interval = np.trapezoid(np.linalg.norm(burn.control_smooth, axis=-1), burn.t_sub, axis=-1)
        # the burn happens right after measurement 12; the smoothed control peaks next to it
        assert abs(int(np.argmax(per_interval)) - 25 // 2) <= 1
    assert min(z_burn) > 3 * max(z_quiet)


def test_several_observers_equal_sequential_updates_and_gaps_are_time_updates(ocbe_run):
    (t, y, obs, model, Rm, x0, P0, q), res = ocbe_run
    # the same observer twice with the same measurement is one measurement with half the noise covariance
    twice = ocbe.ocbe_filter_smoother(em, t, np.stack([y, y], axis=1), np.stack([obs, obs], axis=1), model, Rm, x0,
                                      P0, q, smooth=False)
    half = ocbe.ocbe_filter_smoother(em, t, y, obs, model, Rm / 2, x0, P0, q, smooth=False)
    assert np.max(np.abs(twice.P_filt - half.P_filt)) < 1e-9 * np.max(np.abs(half.P_filt))
    assert np.max(np.abs(twice.x_filt - half.x_filt)) < 1e-9
    # an epoch without measurements: the filtered estimate is the prediction
    avail = np.ones((t.size, 1), dtype=bool)
    avail[4] = False
    gap = ocbe.ocbe_filter_smoother(em, t, y, obs, model, Rm, x0, P0, q, available=avail, smooth=False)
    assert np.array_equal(gap.x_filt[4], gap.x_pred[4]) and np.allclose(gap.P_filt[4], gap.P_pred[4], rtol=1e-12)


def test_block_integrator_equals_the_full_variational_system(two_hours_near_perilune):
    """The 114-state block integrator (Phi_px = 0 and the p-terms dropped) equals the 156-state one to round-off.

    Two references (the fixture's and a perturbed one, with different control weights) run in one batch; each is
    compared with :func:`cislunar.estimation.ocbe.ocbe_transition` on the same grid, block by block.  A sign error in the
    -q B B^T coupling or in -A^T would show in phi_xp / phi_pp at order one.
    """
    x0, grid, _ = two_hours_near_perilune
    lay = ocbe.BLOCK_LAYOUT
    starts = np.array([x0, x0 + np.r_[1e-5, -2e-5, 1e-5, 3e-5, 0.0, -1e-5]])
    qs = np.array([Q_WEIGHT, 40 * Q_WEIGHT])
    out = _propagate_blocks(ocbe.block_integrator(2), starts, qs, grid, costate_block=True)  # (grid, 114, 2)
    for b in range(2):
        full = ocbe.ocbe_transition(em, starts[b], grid, qs[b])
        assert np.max(np.abs(out[:, lay["x"], b] - full.x)) < 1e-14
        for name, ref in (("phi_xx", full.phi_xx), ("phi_xp", full.phi_xp), ("phi_pp", full.phi_pp)):
            blk = out[:, lay[name], b].reshape(-1, 6, 6)
            assert np.max(np.abs(blk - ref)) < 1e-12 * np.max(np.abs(ref)), name
        assert np.max(np.abs(full.phi_px)) == 0.0  # the block that is dropped
    with pytest.raises(ValueError, match="batch_size"):
        ocbe.block_integrator(0)
    with pytest.raises(ValueError, match="tol"):
        ocbe.block_integrator(2, tol=1.0)


def _propagate_blocks(tb, starts, qs, grid, *, costate_block: bool):
    """Run a 2-lane block integrator from identity blocks at ``starts`` (2, 6) with weights ``qs`` over ``grid``;
    returns its states on the grid, shape (grid, n_states, 2)."""
    lay = ocbe.BLOCK_LAYOUT
    init = np.zeros((lay["phi_pp" if costate_block else "phi_xp"].stop, 2))
    init[lay["x"]] = starts.T
    init[lay["phi_xx"]] = np.eye(6).ravel()[:, None]
    if costate_block:
        init[lay["phi_pp"]] = np.eye(6).ravel()[:, None]
    tb.set_time(np.full(2, grid[0]))
    tb.state[:] = init
    tb.pars[0] = em.mu
    tb.pars[1] = qs
    return tb.propagate_grid(np.repeat(grid[:, None], 2, axis=1))[-1]


def test_spike_contrast_of_a_known_spike():
    """Norm 5 within +-0.1 of 0.5 on a 2-D sub-grid, 1 elsewhere: contrast 5 per leading row; flat: 1."""
    t = np.linspace(0.0, 1.0, 20).reshape(4, 5)
    spike = np.where(np.abs(t - 0.5) <= 0.1, 5.0, 1.0)
    u = np.stack([spike, np.ones_like(t), 2.0 * spike])
    got = ocbe.spike_contrast(t, u, 0.5, 0.1)
    assert np.allclose(got, [5.0, 1.0, 5.0], rtol=0, atol=1e-14)
    # a mean, not a maximum: one large sample among several near samples counts by its share
    u1 = np.ones_like(t)
    near = np.flatnonzero(np.abs(t.ravel() - 0.5) <= 0.1)
    u1.ravel()[near[0]] = 1.0 + near.size
    assert abs(ocbe.spike_contrast(t, u1, 0.5, 0.1) - 2.0) < 1e-14
    with pytest.raises(ValueError, match="control_norm"):
        ocbe.spike_contrast(t, np.ones((2, 3)), 0.5, 0.1)
    with pytest.raises(ValueError, match="t_centre"):
        ocbe.spike_contrast(t, u, 5.0, 0.1)


def test_block_integrator_without_the_costate_block_equals_the_full_variational_system(two_hours_near_perilune):
    """The 78-state block integrator (Phi_pp = K Phi_xx K^-1 from the CR3BP's invariant form, not integrated) equals
    the 156-state one to round-off, and K Phi_xx K^-1 is the integrated Phi_pp (= Phi_xx^-T) near perilune.

    A wrong entry of the linear Phi_pp rows (a sign, or the factor 2 of the Coriolis term) shows in phi_xp at order
    one; a wrong K in ``_costate_block`` shows against the integrated phi_pp."""
    x0, grid, _ = two_hours_near_perilune
    lay = ocbe.BLOCK_LAYOUT
    starts = np.array([x0, x0 + np.r_[1e-5, -2e-5, 1e-5, 3e-5, 0.0, -1e-5]])
    qs = np.array([Q_WEIGHT, 40 * Q_WEIGHT])
    tb = ocbe.block_integrator(2, costate_block=False)
    assert tb.state.shape == (lay["phi_xp"].stop, 2)
    out = _propagate_blocks(tb, starts, qs, grid, costate_block=False)  # (grid, 78, 2)
    for b in range(2):
        full = ocbe.ocbe_transition(em, starts[b], grid, qs[b])
        # other states, other step sizes: the two integrations agree to the tolerance's level, not to the last bit
        assert np.max(np.abs(out[:, lay["x"], b] - full.x)) < 1e-13
        for name, ref in (("phi_xx", full.phi_xx), ("phi_xp", full.phi_xp)):
            blk = out[:, lay[name], b].reshape(-1, 6, 6)
            assert np.max(np.abs(blk - ref)) < 1e-12 * np.max(np.abs(ref)), name
        pp = ocbe._costate_block(out[:, lay["phi_xx"], b].reshape(-1, 6, 6))
        assert np.max(np.abs(pp - full.phi_pp)) < 1e-12 * np.max(np.abs(full.phi_pp))
        assert np.max(np.abs(pp - np.swapaxes(np.linalg.inv(full.phi_xx), -1, -2))) < 1e-10 * np.max(np.abs(pp))
    with pytest.raises(TypeError, match="costate_block"):
        ocbe.block_integrator(2, costate_block="no")
