"""The batched OCBE: equal to the single-trial filter (one or several observers, availability masks, filter only, failing
trials flagged as the single-trial filter flags them), to the full-12x12 oracle, and independent of the lockstep split."""

import numpy as np
import pytest
from reference_batched_ocbe import ocbe_batch_reference

from cislunar.cr3bp import orbits
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.cr3bp.propagation import ImpactError, propagate
from cislunar.estimation import batched_ocbe, ocbe
from cislunar.sensing import measurements, sites
from cislunar.utils import validation

Q_WEIGHT = 3.5e-6  # LU^2/TU^3 (1e-11 km^2/s^3)


def _trials(B, n_meas=9, seed=3):
    """B trials of a 9:2 NRHO target near apolune tracked from L2 with angles and rates every 2 hours.

    Trials differ in their measurement noise and prior error; trial 1 also has a 1 m/s burn mid-arc.
    """
    rng = np.random.default_rng(seed)
    nrho = orbits.nrho_9_2(em)
    t = np.arange(n_meas) * float(em.days_to_tu(2.0 / 24.0))
    obs = np.tile(sites.l2_observer_state(em), (n_meas, 1))
    sig_ang = 1e-5  # rad
    sig_rate = np.sqrt(2.0) * sig_ang / float(em.days_to_tu(1.0 / 86400.0))
    Rm = np.diag([sig_ang**2, sig_ang**2, sig_rate**2, sig_rate**2])
    P0 = np.diag(np.r_[np.full(3, em.km_to_lu(10.0 / 3) ** 2), np.full(3, (1e-4 / 3 / em.velocity_unit_km_s) ** 2)])
    model = measurements.ANGLES_AND_RATES
    truth = np.repeat(propagate(em, nrho.x0, t).x[None], B, axis=0)
    k = n_meas // 2
    after = truth[1, k].copy()
    after[4] += 1e-3 / em.velocity_unit_km_s
    truth[1, k + 1:] = propagate(em, after, t[k:]).x[1:]
    y = np.array([model(obs, x) for x in truth]) + rng.standard_normal((B, n_meas, 4)) * np.sqrt(np.diag(Rm))
    x0 = nrho.x0 + rng.multivariate_normal(np.zeros(6), P0, size=B)
    q = np.full(n_meas - 1, Q_WEIGHT)
    q[k - 1:k + 2] *= 30.0  # a raised-weight window, as the detection paper's
    return t, y, obs, model, Rm, x0, P0, q


@pytest.fixture(scope="module")
def batch_run():
    args = _trials(4)
    return args, batched_ocbe.ocbe_batch(em, *args, n_sub=5)


def _rel(a, b):
    return np.max(np.abs(a - b)) / np.max(np.abs(b))


def test_batched_ocbe_equals_the_single_trial_filter(batch_run):
    (t, y, obs, model, Rm, x0, P0, q), batch = batch_run
    for b in range(y.shape[0]):
        one = ocbe.ocbe_filter_smoother(em, t, y[b], obs, model, Rm, x0[b], P0, q, n_sub=5)
        for name in ("x_pred", "x_filt", "P_filt", "x_smooth", "P_smooth", "residual_norms", "t_sub"):
            assert _rel(getattr(batch, name)[b] if name != "t_sub" else batch.t_sub, getattr(one, name)) < 1e-10, \
                (b, name)
        for name in ("control_step", "control_smooth"):  # costates solved through the ill-conditioned Phi_xp
            assert _rel(getattr(batch, name)[b], getattr(one, name)) < 1e-9, (b, name)
        assert abs(batch.z_smooth[b] / one.z_smooth - 1) < 1e-10
        assert abs(batch.z_step[b] / one.z_step - 1) < 1e-9
    # the burn trial's smoothed control stands out against the noise-only trials
    assert batch.z_smooth[1] > 1.5 * max(batch.z_smooth[0], batch.z_smooth[2], batch.z_smooth[3])


def test_block_integrator_equals_the_full_12x12_oracle_and_trials_are_independent(batch_run, monkeypatch):
    args, fast = batch_run
    ref = ocbe_batch_reference(em, *args, n_sub=5)
    for name in ("x_pred", "x_filt", "P_filt", "x_smooth", "P_smooth", "residual_norms"):
        assert _rel(getattr(fast, name), getattr(ref, name)) < 1e-10, name
    for name in ("control_step", "control_smooth"):
        assert _rel(getattr(fast, name), getattr(ref, name)) < 1e-9, name
    assert np.max(np.abs(fast.z_smooth / ref.z_smooth - 1)) < 1e-10
    assert np.array_equal(fast.t_sub, ref.t_sub)
    t, y, obs, model, Rm, x0, P0, q = args
    alone = batched_ocbe.ocbe_batch(em, t, y[1:2], obs, model, Rm, x0[1:2], P0, q, n_sub=5)
    assert abs(alone.z_smooth[0] / fast.z_smooth[1] - 1) < 1e-12
    monkeypatch.setattr(batched_ocbe, "_LANES", 3)  # the 4 trials in two groups of lanes (3 + 1)
    split = batched_ocbe.ocbe_batch(em, *args, n_sub=5)
    assert np.max(np.abs(split.z_smooth / fast.z_smooth - 1)) < 1e-12
    assert np.max(np.abs(split.x_smooth - fast.x_smooth)) < 1e-12 * np.max(np.abs(fast.x_smooth))


def _two_observers(t, truth, model, rng, Rm):
    """The L2 observer and the DRO observer, with a mask: epoch 2 unseen by both, epochs 1, 4 and 6 by one only."""
    dro = sites.dro_observer_orbit(em)
    obs = np.stack([np.tile(sites.l2_observer_state(em), (t.size, 1)), propagate(em, dro.x0, t).x], axis=1)
    avail = np.ones((t.size, 2), dtype=bool)
    avail[2] = False
    avail[[1, 6], 0] = False
    avail[4, 1] = False
    y = model(obs[None], truth[:, :, None, :]) + rng.standard_normal(truth.shape[:2] + (2, model.dim)) * np.sqrt(
        np.diag(Rm))
    y[:, ~avail] = np.nan  # ignored where unavailable
    return obs, avail, y


@pytest.mark.parametrize("smooth", [True, False])
def test_several_observers_masks_and_filter_only_equal_the_single_trial_filter(smooth):
    t, _, _, model, Rm, x0, P0, q = _trials(3)
    truth = np.repeat(propagate(em, orbits.nrho_9_2(em).x0, t).x[None], 3, axis=0)
    obs, avail, y = _two_observers(t, truth, model, np.random.default_rng(5), Rm)
    batch = batched_ocbe.ocbe_batch(em, t, y, obs, model, Rm, x0, P0, q, n_sub=3, available=avail, smooth=smooth,
                                    on_failure="flag")
    assert not batch.failed.any() and list(batch.failure) == [""] * 3
    for name in ("x_smooth", "P_smooth", "control_step", "control_smooth", "z_step", "z_smooth"):
        assert (getattr(batch, name) is None) == (not smooth), name  # filter only: no smoother, no control
    for b in range(3):
        one = ocbe.ocbe_filter_smoother(em, t, y[b], obs, model, Rm, x0[b], P0, q, n_sub=3, available=avail,
                                        smooth=smooth)
        names = ("x_pred", "x_filt", "P_filt") + (("x_smooth", "P_smooth") if smooth else ())
        for name in names:
            assert _rel(getattr(batch, name)[b], getattr(one, name)) < 1e-10, (b, name)
        assert np.array_equal(batch.residual_norms[b] == 0, one.residual_norms == 0)  # the unseen epoch: no update
        assert _rel(batch.residual_norms[b], one.residual_norms) < 1e-8
        if smooth:
            assert abs(batch.z_step[b] / one.z_step - 1) < 1e-8 and abs(batch.z_smooth[b] / one.z_smooth - 1) < 1e-8
    # the mask matters: with every observer used at every epoch the filter differs
    y_all = model(obs[None], truth[:, :, None, :])
    every = batched_ocbe.ocbe_batch(em, t, y_all, obs, model, Rm, x0, P0, q, n_sub=3, smooth=False)
    assert _rel(every.P_filt[:, 2], batch.P_filt[:, 2]) > 1e-3


def _falling_and_degenerate_trials():
    """Four trials of :func:`_trials`; trial 1 tracks a fall onto the Moon (impact between epochs 2 and 3), trial 3
    starts at the observer (the first measurement update is undefined)."""
    t, y, obs, model, Rm, x0, P0, q = _trials(4)
    moon = em.secondary_position
    above = np.r_[moon + [em.km_to_lu(em.secondary_radius_km + 100.0), 0.0, 0.0],
                  np.array([-2.0, 0.3, 0.0]) / em.velocity_unit_km_s]  # 100 km up, falling at 2 km/s
    x_fall = propagate(em, above, [0.0, -float(em.days_to_tu(5.0 / 24.0))]).x[-1]  # 5 h earlier
    fall = propagate(em, x_fall, t[:3]).x
    y, x0 = y.copy(), x0.copy()
    y[1] = model(obs, np.r_[fall, np.repeat(fall[-1:], t.size - 3, axis=0)])
    x0[1] = x_fall
    x0[3] = sites.l2_observer_state(em)
    return t, y, obs, model, Rm, x0, P0, q


def test_failing_trials_are_flagged_as_the_single_trial_filter_flags_them_and_the_others_go_on():
    args = _falling_and_degenerate_trials()
    t, y, obs, model, Rm, x0, P0, q = args
    batch = batched_ocbe.ocbe_batch(em, *args, n_sub=5, on_failure="flag")
    assert list(batch.failed) == [False, True, False, True]
    for b in range(4):
        try:
            one = ocbe.ocbe_filter_smoother(em, t, y[b], obs, model, Rm, x0[b], P0, q, n_sub=5)
        except ocbe.FilterDivergenceError as exc:
            assert batch.failure_epoch[b] == exc.epoch, b
            assert batch.failure[b].startswith(f"OCBE failed numerically at epoch {exc.epoch} (t = {exc.time:.6g} TU)")
            assert exc.cause.split(":")[0] in batch.failure[b]  # the same kind of error
            for name in ("x_filt", "P_filt", "x_smooth", "control_step", "z_smooth", "residual_norms"):
                assert np.all(np.isnan(getattr(batch, name)[b])), (b, name)
            continue
        assert batch.failure_epoch[b] == -1 and batch.failure[b] == ""
        for name in ("x_filt", "P_filt", "x_smooth", "P_smooth"):
            assert _rel(getattr(batch, name)[b], getattr(one, name)) < 1e-10, (b, name)
    assert list(batch.failure_epoch) == [-1, 3, -1, 0]  # impact during interval 2; undefined first update
    # the same trials alone, and raised without flagging (the first failure stops the batch)
    alone = batched_ocbe.ocbe_batch(em, t, y[[0, 2]], obs, model, Rm, x0[[0, 2]], P0, q, n_sub=5)
    assert _rel(alone.x_smooth, batch.x_smooth[[0, 2]]) < 1e-12
    with pytest.raises(ValueError, match="coincide"):
        batched_ocbe.ocbe_batch(em, *args, n_sub=5)


def test_a_prior_inside_the_moon_is_flagged_at_epoch_1_as_in_the_single_trial_filter():
    t, y, obs, model, Rm, x0, P0, q = _trials(2, n_meas=3)
    x0 = x0.copy()
    x0[1, :3] = em.secondary_position + em.km_to_lu(500.0)
    P0 = np.eye(6) * 1e-20  # the first update keeps the estimate inside
    with pytest.raises(ocbe.FilterDivergenceError) as single:
        ocbe.ocbe_filter_smoother(em, t, y[1], obs, model, Rm, x0[1], P0, q, n_sub=2, smooth=False)
    batch = batched_ocbe.ocbe_batch(em, t, y, obs, model, Rm, x0, P0, q, n_sub=2, smooth=False, on_failure="flag")
    assert list(batch.failure_epoch) == [-1, single.value.epoch] == [-1, 1]
    assert "ImpactError" in batch.failure[1] and "ImpactError" in single.value.cause
    with pytest.raises(ImpactError):  # without flagging, refused at the boundary
        batched_ocbe.ocbe_batch(em, t, y, obs, model, Rm, x0, P0, q, n_sub=2)


def test_every_trial_failing_leaves_nan_and_flags():
    t, y, obs, model, Rm, x0, P0, q = _falling_and_degenerate_trials()
    batch = batched_ocbe.ocbe_batch(em, t, y[[1, 3]], obs, model, Rm, x0[[1, 3]], P0, q, n_sub=5, smooth=False,
                                    on_failure="flag")
    assert list(batch.failure_epoch) == [3, 0]
    assert np.all(np.isnan(batch.x_filt)) and batch.x_smooth is None


def test_batched_ocbe_bad_input():
    t, y, obs, model, Rm, x0, P0, q = _trials(2, n_meas=3)
    with pytest.raises(ValueError, match="y"):
        batched_ocbe.ocbe_batch(em, t, y[:, :2], obs, model, Rm, x0, P0, q)
    with pytest.raises(ValueError, match="P0"):
        batched_ocbe.ocbe_batch(em, t, y, obs, model, Rm, x0, np.stack([P0] * 3), q)
    with pytest.raises(TypeError, match="engine"):
        batched_ocbe.ocbe_batch(em, t, y, obs, model, Rm, x0, P0, q, engine="fast")  # one engine, no choice
    with pytest.raises(validation.ArgumentTypeError, match="available"):
        batched_ocbe.ocbe_batch(em, t, y, obs, model, Rm, x0, P0, q, available=np.ones((3, 1)))
    with pytest.raises(ValueError, match="available"):
        batched_ocbe.ocbe_batch(em, t, y, obs, model, Rm, x0, P0, q, available=np.ones((3, 2), dtype=bool))
    with pytest.raises(ValueError, match="on_failure"):
        batched_ocbe.ocbe_batch(em, t, y, obs, model, Rm, x0, P0, q, on_failure="ignore")
    y_nan = y.copy()
    y_nan[0, 1, 0] = np.nan
    with pytest.raises(ValueError, match="y contains NaN"):
        batched_ocbe.ocbe_batch(em, t, y_nan, obs, model, Rm, x0, P0, q)
    mask = np.array([True, False, True])
    assert batched_ocbe.ocbe_batch(em, t, y_nan, obs, model, Rm, x0, P0, q, available=mask).residual_norms[0, 1] == 0
    with pytest.raises(ValueError, match="y must have 4 dimensions"):  # two observers need (B, N, K, m)
        batched_ocbe.ocbe_batch(em, t, y, np.stack([obs, obs], axis=1), model, Rm, x0, P0, q)


def test_control_integral_is_eq_33_per_trial():
    """Constant ||u|| = c on every interval integrates to c (t_end - t_0); stacked trials are integrated apart."""
    t_sub = np.array([np.linspace(0.0, 0.5, 4), np.linspace(0.5, 2.0, 4)])
    u = np.zeros((3, 2, 4, 3))
    u[..., 0] = np.array([1.0, 2.0, 3.0])[:, None, None]
    z = ocbe._control_integral(t_sub, u)
    assert z.shape == (3,) and np.allclose(z, [2.0, 4.0, 6.0], rtol=1e-15)
    assert ocbe._control_integral(t_sub, u[1]) == z[1]
    u[1, 1, :, 1] = np.linspace(0.0, 1.0, 4)  # a linear ramp on the second interval: trapezoid rule exact
    assert np.isclose(ocbe._control_integral(t_sub, u)[0], 2.0)
    assert not np.isclose(ocbe._control_integral(t_sub, u)[1], 4.0)


# ---------------------------------------------------------------------------------------------------------------
# Filter-side options (issue 23): azimuth wrapping and the fixed-reference (linearised) filter


def test_default_options_are_bit_identical_to_omitting_them():
    t, y, obs, model, Rm, x0, P0, q = _trials(2)
    a = batched_ocbe.ocbe_batch(em, t, y, obs, model, Rm, x0, P0, q, n_sub=2, smooth=False)
    b = batched_ocbe.ocbe_batch(em, t, y, obs, model, Rm, x0, P0, q, n_sub=2, smooth=False, wrap_azimuth=True,
                                relinearize=True)
    assert np.array_equal(a.x_filt, b.x_filt) and np.array_equal(a.P_filt, b.P_filt)


def test_unwrapped_azimuth_agrees_away_from_the_cut_and_mishandles_a_residual_across_it():
    # the 9:2 NRHO seen from L2 starts on the azimuth's +-pi cut (the first azimuth is pi) and leaves it
    t, y, obs, model, Rm, x0, P0, q = _trials(2)
    az = model(obs, orbits.nrho_9_2(em).x0)[0, 0]
    assert abs(abs(az) - np.pi) < 1e-6
    kw = dict(n_sub=2, smooth=False)
    # away from the cut (epochs 1-8: azimuth -3.127 to -3.027 rad, i.e. 1000+ sigma from it): the same filter
    x1 = batched_ocbe.ocbe_batch(em, t, y, obs, model, Rm, x0, P0, q, **kw).x_filt[:, 1]
    P1 = batched_ocbe.ocbe_batch(em, t, y, obs, model, Rm, x0, P0, q, **kw).P_filt[0, 1]
    args = (em, t[1:], y[:, 1:], obs[1:], model, Rm, x1, P1, q[1:])
    wrapped = batched_ocbe.ocbe_batch(*args, **kw)
    unwrapped = batched_ocbe.ocbe_batch(*args, wrap_azimuth=False, **kw)
    assert _rel(unwrapped.x_filt, wrapped.x_filt) < 1e-13
    assert _rel(unwrapped.P_filt, wrapped.P_filt) < 1e-12
    # across the cut: the measured azimuth on the other branch (y - 2 pi) is the same measurement to the wrapped
    # filter; the unwrapped one sees a 2 pi residual (about 6e5 sigma) and its estimate is thrown off
    y_other = y.copy()
    y_other[:, 0, 0] += -2 * np.pi if az > 0 else 2 * np.pi
    base = batched_ocbe.ocbe_batch(em, t, y, obs, model, Rm, x0, P0, q, **kw)
    w2 = batched_ocbe.ocbe_batch(em, t, y_other, obs, model, Rm, x0, P0, q, **kw)
    u2 = batched_ocbe.ocbe_batch(em, t, y_other, obs, model, Rm, x0, P0, q, wrap_azimuth=False, on_failure="flag",
                                 **kw)
    assert _rel(w2.x_filt, base.x_filt) < 1e-12
    assert np.all(u2.failed) or np.nanmax(np.abs(u2.x_filt[:, 0] - base.x_filt[:, 0])) > 1e3 * np.sqrt(P0[0, 0])


def test_fixed_reference_filter_equals_the_relinearised_one_to_second_order_in_the_deviation():
    """On a linear system the two filters are one; here they differ by a term quadratic in the deviation from the
    reference: scaling the prior error (noise-free data of the reference orbit) by 1/10 scales the difference of the
    estimates by 1/100 (a mistake in the deviation bookkeeping, e.g. a dropped H dx or Phi dx, makes it 1/10)."""
    t, _, obs, model, Rm, x0, P0, q = _trials(2)
    nrho = orbits.nrho_9_2(em)
    truth = propagate(em, nrho.x0, t).x
    y = np.repeat(model(obs, truth)[None], 2, axis=0)
    d = x0 - nrho.x0
    diffs = []
    for eps in (1.0, 0.1):
        xe = nrho.x0 + eps * d
        ekf = batched_ocbe.ocbe_batch(em, t, y, obs, model, Rm, xe, P0, q, n_sub=2, smooth=False)
        lkf = batched_ocbe.ocbe_batch(em, t, y, obs, model, Rm, xe, P0, q, n_sub=2, smooth=False, relinearize=False)
        assert np.array_equal(lkf.x_filt[:, 0], ekf.x_filt[:, 0])  # one reference at t[0]: the prior mean
        assert np.max(np.abs(ekf.x_filt - truth)) > 10 * np.max(np.abs(lkf.x_filt - ekf.x_filt))
        diffs.append(np.max(np.abs(lkf.x_filt - ekf.x_filt)))
    assert 70 < diffs[0] / diffs[1] < 130


def test_fixed_reference_filter_is_filter_only_and_options_are_checked():
    t, y, obs, model, Rm, x0, P0, q = _trials(2)
    with pytest.raises(ValueError, match="smooth=False"):
        batched_ocbe.ocbe_batch(em, t, y, obs, model, Rm, x0, P0, q, relinearize=False)
    for kw in ({"relinearize": "no"}, {"wrap_azimuth": 1}):
        with pytest.raises(TypeError, match=next(iter(kw))):
            batched_ocbe.ocbe_batch(em, t, y, obs, model, Rm, x0, P0, q, smooth=False, **kw)


def test_frozen_transition_is_the_integrated_one_to_first_order_and_gives_a_valid_process_noise():
    """The coarse time update (one frozen-Jacobian step): its one-step error against the integrated 12x12 transition
    is O(dt^2) (halving the step quarters it; the relative error of Phi_xp is O(dt^3), the frozen Hessian acting
    on the velocity columns only at second order); its process noise is symmetric positive semi-definite; with q = 0 it
    is exp(A dt) (the costate block is zero)."""
    x = orbits.nrho_9_2(em).x0
    errs = []
    for dt in (0.02, 0.01):
        tr = ocbe.ocbe_transition(em, x, dt, Q_WEIGHT)
        pxx, pxp = batched_ocbe._frozen_transition(em, x, dt, Q_WEIGHT)
        errs.append((np.max(np.abs(pxx - tr.phi_xx[-1])), np.max(np.abs(pxp - tr.phi_xp[-1]))
                     / np.max(np.abs(tr.phi_xp[-1]))))
        Q = -pxp @ pxx.T
        assert np.allclose(Q, Q.T, rtol=0, atol=1e-12 * np.max(np.abs(Q)))
        assert np.min(np.linalg.eigvalsh(0.5 * (Q + Q.T))) > -1e-12 * np.max(np.abs(Q))
    assert 3.5 < errs[0][0] / errs[1][0] < 4.5 and 6.0 < errs[0][1] / errs[1][1] < 10.0
    # the chapter's tiny weight (1e-20 km^2/s^3) over one minute: Phi_xp keeps its relative accuracy
    q_tiny, dt = 1e-20 * em.time_unit_s**3 / em.length_unit_km**2, 1.6e-4  # about one minute
    tr = ocbe.ocbe_transition(em, x, dt, q_tiny)
    pxp = batched_ocbe._frozen_transition(em, x, dt, q_tiny)[1]
    assert np.max(np.abs(pxp - tr.phi_xp[-1])) < 1e-6 * np.max(np.abs(tr.phi_xp[-1]))
    pxx0, pxp0 = batched_ocbe._frozen_transition(em, np.stack([x, x]), 0.1, np.zeros(2))
    from scipy.linalg import expm
    assert np.allclose(pxx0[1], expm(em.jacobian(x) * 0.1), rtol=0, atol=1e-14) and not np.any(pxp0)


def test_coarse_stm_filter_approaches_the_integrated_one_as_the_interval_shrinks():
    t, y, obs, model, Rm, x0, P0, q = _trials(2)
    fine = batched_ocbe.ocbe_batch(em, t, y, obs, model, Rm, x0, P0, q, n_sub=2, smooth=False)
    coarse = batched_ocbe.ocbe_batch(em, t, y, obs, model, Rm, x0, P0, q, n_sub=2, smooth=False, coarse_stm=True)
    assert np.array_equal(coarse.x_filt[:, 0], fine.x_filt[:, 0])
    d_2h = _rel(coarse.P_filt[:, 1:2], fine.P_filt[:, 1:2])
    # the same first interval cut to a quarter: the covariance after it moves to the integrated one
    tq = np.r_[t[0], t[0] + (t[1] - t[0]) / 4]
    yq = model(obs[:2], propagate(em, x0[0], tq).x)[None].repeat(2, axis=0)
    fq = batched_ocbe.ocbe_batch(em, tq, yq, obs[:2], model, Rm, x0, P0, q[:1], n_sub=2, smooth=False)
    cq = batched_ocbe.ocbe_batch(em, tq, yq, obs[:2], model, Rm, x0, P0, q[:1], n_sub=2, smooth=False,
                                 coarse_stm=True)
    assert _rel(cq.P_filt[:, 1], fq.P_filt[:, 1]) < d_2h / 4
    with pytest.raises(ValueError, match="smooth=False"):
        batched_ocbe.ocbe_batch(em, t, y, obs, model, Rm, x0, P0, q, coarse_stm=True)


def test_growing_arcs_from_one_forward_pass_equal_reruns_on_each_arc_bit_for_bit(batch_run):
    """smooth_ends: the z of each arc t[0]..t[e] from the whole track's forward pass and one backward pass per arc is
    the z_smooth of a filter and smoother run on the first e + 1 epochs alone, bit for bit (same kernels, same
    inputs); flagged failures leave NaN; the option is checked."""
    (t, y, obs, model, Rm, x0, P0, q), full = batch_run
    N = t.size
    ends = [1, 3, N - 2, N - 1, 4]  # any order, the whole track included
    res = batched_ocbe.ocbe_batch(em, t, y, obs, model, Rm, x0, P0, q, n_sub=5, smooth_ends=ends)
    assert res.z_smooth_ends.shape == (y.shape[0], len(ends))
    assert np.array_equal(res.z_smooth, full.z_smooth) and np.array_equal(res.x_smooth, full.x_smooth)
    for j, e in enumerate(ends):
        arc = batched_ocbe.ocbe_batch(em, t[:e + 1], y[:, :e + 1], obs[:e + 1], model, Rm, x0, P0, q[:e], n_sub=5)
        assert np.array_equal(res.z_smooth_ends[:, j], arc.z_smooth), e
    # the smoothed z of a short arc differs from the whole track's: the backward pass does start at epoch e
    assert not np.allclose(res.z_smooth_ends[:, 2], full.z_smooth, rtol=1e-6)
    assert full.z_smooth_ends is None
    with pytest.raises(ValueError, match="smooth_ends"):
        batched_ocbe.ocbe_batch(em, t, y, obs, model, Rm, x0, P0, q, n_sub=5, smooth_ends=[0])
    with pytest.raises(ValueError, match="smooth_ends"):
        batched_ocbe.ocbe_batch(em, t, y, obs, model, Rm, x0, P0, q, n_sub=5, smooth_ends=[N])
    with pytest.raises(ValueError, match="smooth_ends"):
        batched_ocbe.ocbe_batch(em, t, y, obs, model, Rm, x0, P0, q, n_sub=5, smooth_ends=[1.5])
    with pytest.raises(ValueError, match="smooth=True"):
        batched_ocbe.ocbe_batch(em, t, y, obs, model, Rm, x0, P0, q, n_sub=5, smooth=False, smooth_ends=[2])


def test_in_place_kernels_are_bit_identical_to_the_previous_lockstep_loop(batch_run, monkeypatch):
    """Today's loop (time-update and smoother arrays assembled in place) against the loop of 2026-11-26c kept in
    reference_lockstep_ocbe.py (generic srif kernels): every output bit for bit with the integrated costate block,
    and to round-off with Phi_pp formed from Phi_xx (78 states, today's default)."""
    from reference_lockstep_ocbe import previous_lockstep

    from cislunar.estimation import srif

    rng = np.random.default_rng(2)
    R = np.triu(rng.standard_normal((5, 6, 6))) + 3 * np.eye(6)
    Phi = np.eye(6) + 0.1 * rng.standard_normal((5, 6, 6))
    Q = np.eye(6) * 1e-3 + (lambda a: a @ np.swapaxes(a, -1, -2))(1e-2 * rng.standard_normal((5, 6, 6)))
    got, ref = batched_ocbe._time_update_identity(R, Phi, Q), srif._time_update(R, np.zeros(6), Phi, np.eye(6), Q)
    assert np.array_equal(got[0], ref[0]) and np.array_equal(got[1], ref[1])
    assert all(np.array_equal(a, b) for a, b in zip(got[2], ref[2]))
    zs = rng.standard_normal((5, 6))
    assert all(np.array_equal(a, b) for a, b in zip(batched_ocbe._smoother_step_identity(R, zs, Phi, got[2]),
                                                    srif._smoother_step(R, zs, Phi, np.eye(6), got[2])))
    args, fast = batch_run
    assert not batched_ocbe._COSTATE_BLOCK
    with previous_lockstep():
        old = batched_ocbe.ocbe_batch(em, *args, n_sub=5)
    monkeypatch.setattr(batched_ocbe, "_COSTATE_BLOCK", True)
    same = batched_ocbe.ocbe_batch(em, *args, n_sub=5)
    monkeypatch.setattr(batched_ocbe, "_LANES", 3)  # the 4 trials in lane groups of 3 + 1
    split = batched_ocbe.ocbe_batch(em, *args, n_sub=5)
    for name in ("x_pred", "x_filt", "P_filt", "x_smooth", "P_smooth", "control_step", "control_smooth", "z_step",
                 "z_smooth", "residual_norms"):
        ref = getattr(old, name)
        assert np.array_equal(getattr(same, name), ref), name
        assert np.max(np.abs(getattr(split, name) - ref)) <= 1e-12 * np.max(np.abs(ref)), name
        assert np.max(np.abs(getattr(fast, name) - ref)) <= 1e-10 * np.max(np.abs(ref)), name
