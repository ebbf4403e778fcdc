"""The batched OCBE: equal to the single-trial filter, to the full-12x12 oracle, and independent of the lockstep split."""

import numpy as np
import pytest
from reference_batched_ocbe import ocbe_batch_reference

from cislunar.cr3bp import orbits
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.cr3bp.propagation import propagate
from cislunar.estimation import batched_ocbe, ocbe
from cislunar.sensing import measurements, sites

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


def test_batched_ocbe_bad_input():
    t, y, obs, model, Rm, x0, P0, q = _trials(2, n_meas=3)
    with pytest.raises(ValueError, match="y"):
        batched_ocbe.ocbe_batch(em, t, y[:, :2], obs, model, Rm, x0, P0, q)
    with pytest.raises(ValueError, match="P0"):
        batched_ocbe.ocbe_batch(em, t, y, obs, model, Rm, x0, np.stack([P0] * 3), q)
    with pytest.raises(TypeError, match="engine"):
        batched_ocbe.ocbe_batch(em, t, y, obs, model, Rm, x0, P0, q, engine="fast")  # one engine, no choice


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
