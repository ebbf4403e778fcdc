"""Maneuver detection: station-keeping policy draws, hypothesis test, batched OCBE and Monte Carlo reproducibility."""

import pickle
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest
from scipy import stats

from cislunar.cr3bp import orbits
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.cr3bp.propagation import propagate
from cislunar.estimation import batched_ocbe, consistency, ocbe
from cislunar.papers.greaves_scheeres_2021 import detection as det
from tests.papers.greaves_scheeres_2021 import reference_detection

# ---------------------------------------------------------------------------------------------------------------
# Station-keeping policy (Eqs. 3-5)
# ---------------------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("policy", [det.ACTIVE_POLICY, det.QUIET_POLICY])
def test_truncated_gaussian_bounds_and_moments(policy):
    rng = np.random.default_rng(1)
    m = policy.sample_magnitude(rng, 40000)
    mu, sd = policy.mean_m_s, policy.sd_m_s
    assert m.min() >= mu - 3 * sd and m.max() <= mu + 3 * sd
    ref = stats.truncnorm(-3, 3, loc=mu, scale=sd)
    assert abs(m.mean() - ref.mean()) < 4 * ref.std() / np.sqrt(m.size)
    assert abs(m.var() / ref.var() - 1) < 0.03
    assert abs(ref.std() / sd - 1) > 0.01  # truncation visibly shrinks the spread (about 1.3 %)
    assert stats.kstest(m, ref.cdf).pvalue > 1e-3
    assert np.isclose(policy.second_moment_m2_s2(), ref.var() + ref.mean() ** 2)
    # the caller's generator drives the draw
    assert np.array_equal(policy.sample_magnitude(np.random.default_rng(5), 7),
                          policy.sample_magnitude(np.random.default_rng(5), 7))


def test_pointing_follows_the_paper_not_a_uniform_sphere():
    rng = np.random.default_rng(2)
    az, el = det.StationKeepingPolicy.sample_pointing(rng, 40000)
    assert az.min() >= -np.pi and az.max() <= np.pi and el.min() >= -np.pi / 2 and el.max() <= np.pi / 2
    assert stats.kstest(az, stats.uniform(-np.pi, 2 * np.pi).cdf).pvalue > 1e-3  # Eq. 3
    assert stats.kstest(el, stats.uniform(-np.pi / 2, np.pi).cdf).pvalue > 1e-3  # Eq. 4
    u = det.pointing_vector(az, el)
    assert np.allclose(np.linalg.norm(u, axis=-1), 1.0)
    # uniform on the sphere would make u_z uniform on [-1, 1]; the paper's rule makes it arcsine distributed
    assert stats.kstest(u[:, 2], stats.uniform(-1, 2).cdf).pvalue < 1e-10
    assert stats.kstest(u[:, 2], stats.arcsine(-1, 2).cdf).pvalue > 1e-3
    assert np.allclose(det.pointing_vector(np.pi / 2, 0.0), [0, 1, 0], atol=1e-15)


def test_policy_bad_input():
    with pytest.raises(ValueError, match="sd_m_s"):
        det.StationKeepingPolicy("x", 1.0, -0.1)
    with pytest.raises(ValueError, match="mean_m_s"):
        det.StationKeepingPolicy("x", 0.1, 0.1)  # mean - 3 sd < 0
    with pytest.raises(ValueError, match="rng"):
        det.ACTIVE_POLICY.sample_magnitude(np.random.RandomState(0))
    with pytest.raises(ValueError, match="window_hours"):
        det.window_control_weight(det.QUIET_POLICY, 0.0)
    # E[m^2] / (3 T): 1 m/s^2-ish over 8 h is ~1.26e-11 km^2/s^3
    assert np.isclose(det.window_control_weight(det.ACTIVE_POLICY, 8.0),
                      det.ACTIVE_POLICY.second_moment_m2_s2() * 1e-6 / (3 * 8 * 3600))


# ---------------------------------------------------------------------------------------------------------------
# Hypothesis test (Eqs. 34-35)
# ---------------------------------------------------------------------------------------------------------------


def _gauss_crossing(m0, s0, m1, s1):
    """Crossing of two normal PDFs between the means (root of the quadratic log-density difference)."""
    a = 1 / (2 * s1**2) - 1 / (2 * s0**2)
    b = m0 / s0**2 - m1 / s1**2
    c = m1**2 / (2 * s1**2) - m0**2 / (2 * s0**2) + np.log(s1 / s0)
    roots = np.roots([a, b, c]) if a != 0 else np.array([-c / b])
    return float(roots[(roots > m0) & (roots < m1)][0])


def test_crossing_of_known_gaussians():
    for m0, s0, m1, s1 in ((0.0, 1.0, 3.0, 1.0), (0.2, 0.05, 1.0, 0.3)):
        d0, d1 = stats.norm(m0, s0), stats.norm(m1, s1)
        c = det.pdf_crossings(d0, d1, m0, m1)
        assert c.size == 1 and abs(c[0] - _gauss_crossing(m0, s0, m1, s1)) < 1e-10
        fp, md = det.error_rates(c[0], d0, d1)
        assert np.isclose(fp, stats.norm.sf((c[0] - m0) / s0), rtol=1e-12)
        assert np.isclose(md, stats.norm.cdf((c[0] - m1) / s1), rtol=1e-12)


def test_ml_threshold_from_samples_lands_on_the_kde_crossing():
    rng = np.random.default_rng(3)
    m0, s0, m1, s1 = 0.2, 0.05, 1.0, 0.3
    th = det.ml_threshold(rng.normal(m0, s0, 4000), rng.normal(m1, s1, 4000))
    assert abs(th.pdf0(th.z_lim)[0] - th.pdf1(th.z_lim)[0]) < 1e-8  # on the KDE crossing
    assert abs(th.z_lim - _gauss_crossing(m0, s0, m1, s1)) < 0.02  # and close to the true one
    fp, md = det.error_rates(_gauss_crossing(m0, s0, m1, s1), stats.norm(m0, s0), stats.norm(m1, s1))
    assert abs(th.false_positive - fp) < 0.01 and abs(th.missed_detection - md) < 0.01
    # the ML threshold minimises the total error over nearby thresholds
    for dz in (-0.02, 0.02):
        assert sum(det.error_rates(th.z_lim + dz, th.pdf0, th.pdf1)) >= th.total_error


def test_decisions_and_accuracy():
    score = det.detection_accuracy([0.1, 0.2, 0.5], [0.3, 0.6, 0.9, 1.2], 0.4)
    assert (score.true_negative, score.false_positive, score.true_positive, score.missed_detection) == (2, 1, 3, 1)
    assert np.isclose(score.accuracy, 5 / 7)
    assert det.decide(0.4, 0.4) == np.False_  # Eq. 35: z <= z_lim is H0


def test_hypothesis_test_bad_input():
    with pytest.raises(ValueError, match="samples"):
        det.fit_pdf([1.0])
    with pytest.raises(ValueError, match="bandwidth"):
        det.fit_pdf([1.0, 2.0, 3.0], bandwidth="nope")
    with pytest.raises(ValueError, match="lo and hi"):
        det.pdf_crossings(stats.norm(), stats.norm(1), 1.0, 0.0)
    with pytest.raises(ValueError, match="z_h1"):
        det.ml_threshold([0.1, 0.2, 0.3], [[1.0]])
    with pytest.raises(ValueError, match="coincide"):
        det.ml_threshold([0.0, 0.1, 0.2], [0.0, 0.1, 0.2])
    with pytest.raises(ValueError, match="z_test_h0"):
        det.detection_accuracy([np.nan], [1.0], 0.5)


# ---------------------------------------------------------------------------------------------------------------
# Trials, batched OCBE and the Monte Carlo
# ---------------------------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def short_setup():
    """A short, coarse track (0.6 period from periapsis, 8-hour cadence) so the filter runs take milliseconds."""
    return det.make_setup(em, orbits.nrho_9_2(em), det.window_control_weight(det.ACTIVE_POLICY), 1e-18,
                          cadence_hours=8.0, window_hours=16.0, periods=0.6)


def test_trial_draws_maneuver_at_apoapsis(short_setup):
    s = short_setup
    inp = det.draw_trial(np.random.default_rng(4), s, magnitude_m_s=1.0, direction=(np.pi / 2, 0.0))
    plain = det.draw_trial(np.random.default_rng(4), s)
    k = int(np.searchsorted(s.scenario.t, s.t_maneuver))
    assert np.array_equal(inp.truth[:k], plain.truth[:k]) and not np.allclose(inp.truth[k:], plain.truth[k:])
    assert inp.magnitude_m_s == 1.0 and np.isnan(plain.azimuth)
    assert np.count_nonzero(s.control_weight > s.control_weight.min()) >= 1
    with pytest.raises(ValueError, match="magnitude_m_s"):
        det.draw_trial(np.random.default_rng(0), s, magnitude_m_s=-1.0)
    with pytest.raises(ValueError, match="q_window_km2_s3"):
        det.make_setup(em, s.scenario.orbit, 0.0, 1e-18)


def test_batched_ocbe_equals_single_trial_filter(short_setup):
    s = short_setup
    B = 3
    res = det.detection_trial_batch(np.random.default_rng(5), s, det.ACTIVE_POLICY, B)
    kids = np.random.default_rng(5).spawn(B)
    inputs = [det.draw_trial(k, s, det.ACTIVE_POLICY) for k in kids]
    sc = s.scenario
    batch = batched_ocbe.ocbe_batch(em, sc.t, np.array([i.y for i in inputs]), s.observer_states, sc.model, sc.meas_cov,
                           np.array([i.x0 for i in inputs]), inputs[0].P0, s.control_weight, n_sub=s.n_sub)
    for b, inp in enumerate(inputs):
        one = det.run_trial_filter(s, inp)
        rel = lambda a, ref: np.max(np.abs(a - ref)) / np.max(np.abs(ref))  # noqa: E731
        assert rel(batch.x_filt[b], one.x_filt) < 1e-10
        assert rel(batch.x_smooth[b], one.x_smooth) < 1e-10
        assert rel(batch.P_filt[b], one.P_filt) < 1e-10
        assert rel(batch.P_smooth[b], one.P_smooth) < 1e-10
        assert rel(batch.control_step[b], one.control_step) < 1e-10
        assert rel(batch.control_smooth[b], one.control_smooth) < 1e-10
        assert abs(batch.z_smooth[b] / one.z_smooth - 1) < 1e-10
        assert abs(res[b].z_m_s / (one.z_smooth * em.velocity_unit_km_s * 1e3) - 1) < 1e-10
        assert res[b].magnitude_m_s == inp.magnitude_m_s
    with pytest.raises(ValueError, match="y"):
        batched_ocbe.ocbe_batch(em, sc.t, np.zeros((2, 3, 4)), s.observer_states, sc.model, sc.meas_cov, np.zeros((2, 6)),
                       inputs[0].P0, s.control_weight)


def test_monte_carlo_reproducible_and_executor_agnostic(short_setup):
    s = short_setup
    a = det.run_detection_monte_carlo(s, det.QUIET_POLICY, 5, 11, batch_size=2, progress=False)
    b = det.run_detection_monte_carlo(s, det.QUIET_POLICY, 5, 11, batch_size=2, progress=False)
    with ThreadPoolExecutor(2) as ex:
        c = det.run_detection_monte_carlo(s, det.QUIET_POLICY, 5, 11, batch_size=2, executor=ex, progress=False)
    assert len(a) == 5
    for name in ("z", "z_step", "magnitude", "azimuth", "elevation"):
        assert np.array_equal(getattr(a, name), getattr(b, name))
        assert np.array_equal(getattr(a, name), getattr(c, name))
    d = det.run_detection_monte_carlo(s, det.QUIET_POLICY, 5, 12, batch_size=2, progress=False)
    assert not np.array_equal(a.z, d.z)
    h0 = det.run_detection_monte_carlo(s, None, 2, 11, batch_size=0, progress=False)  # single-trial path
    assert np.all(h0.magnitude == 0) and np.all(h0.z > 0)
    # what a process pool needs
    for obj in (det.detection_trial, det.detection_trial_batch, s, det.QUIET_POLICY):
        pickle.loads(pickle.dumps(obj))
    with pytest.raises(ValueError, match="n_trials"):
        det.run_detection_monte_carlo(s, None, 0, 1)
    with pytest.raises(ValueError, match="batch_size"):
        det.run_detection_monte_carlo(s, None, 2, 1, batch_size=-1)


def test_batched_trials_are_independent_of_the_batch_and_of_the_lane_groups(short_setup, monkeypatch):
    """A trial's result does not depend on the other trials of its batch, nor on how the integrator groups them in
    lanes.  (The block integrator against the full 12x12 oracle is tests/estimation/test_batched_ocbe.py's.)"""
    s = short_setup
    sc = s.scenario
    inputs = [det.draw_trial(k, s, det.ACTIVE_POLICY if j % 2 else None)
              for j, k in enumerate(np.random.default_rng(8).spawn(4))]
    args = (em, sc.t, np.array([i.y for i in inputs]), s.observer_states, sc.model, sc.meas_cov,
            np.array([i.x0 for i in inputs]), np.array([i.P0 for i in inputs]), s.control_weight)
    fast = batched_ocbe.ocbe_batch(*args, n_sub=s.n_sub)
    alone = batched_ocbe.ocbe_batch(em, sc.t, args[2][1:2], s.observer_states, sc.model, sc.meas_cov, args[6][1:2],
                                    args[7][1], s.control_weight, n_sub=s.n_sub)
    assert abs(alone.z_smooth[0] / fast.z_smooth[1] - 1) < 1e-12
    monkeypatch.setattr(batched_ocbe, "_LANES", 3)  # integrate the 4 trials in two groups of lanes (3 + 1)
    split = batched_ocbe.ocbe_batch(*args, n_sub=s.n_sub)
    assert np.max(np.abs(split.z_smooth / fast.z_smooth - 1)) < 1e-12
    assert np.max(np.abs(split.x_smooth - fast.x_smooth)) < 1e-12 * np.max(np.abs(fast.x_smooth))


def test_lockstep_groups_equal_separate_batches_and_any_executor(short_setup):
    """run_detection_monte_carlo runs several batches per lockstep call; results equal one call per batch."""
    from concurrent.futures import ProcessPoolExecutor

    from cislunar.utils.montecarlo import trial_rng

    s = short_setup
    n, B = 13, 2  # 7 batches (the last trimmed): lockstep groups of 2 batches
    mc = det.run_detection_monte_carlo(s, det.QUIET_POLICY, n, 21, batch_size=B, progress=False)
    one = [r for k in range(-(-n // B)) for r in det.detection_trial_batch(trial_rng(21, k), s, det.QUIET_POLICY, B)]
    one = det.MonteCarloSample.from_results(one[:n])
    assert np.array_equal(mc.magnitude, one.magnitude) and np.array_equal(mc.azimuth, one.azimuth)
    assert np.max(np.abs(mc.z / one.z - 1)) < 1e-12 and np.max(np.abs(mc.z_step / one.z_step - 1)) < 1e-12
    with ProcessPoolExecutor(2) as ex:
        procs = det.run_detection_monte_carlo(s, det.QUIET_POLICY, n, 21, batch_size=B, executor=ex, progress=False)
    for name in ("z", "z_step", "magnitude", "azimuth", "elevation"):
        assert np.array_equal(getattr(mc, name), getattr(procs, name), equal_nan=True), name


def _moon_dipping_prior(s):
    """A prior mean at ``t[0]`` whose fast (3.5 km/s) ballistic arc passes 300 km below the lunar surface a tenth of
    the way to the next sub-grid point (every sub-grid state outside both primaries).  Off-centre, so that the
    farther end of that sub-interval lies beyond ``R + h v_max / 2`` of the Moon: only the screen's stray bound
    keeps the interval for the 17-point test."""
    r = em.km_to_lu(em.secondary_radius_km - 300.0)
    v = 3.5 / em.velocity_unit_km_s
    peri = np.array([1 - em.mu + r, 0, 0, 0, v * np.cos(0.3), v * np.sin(0.3)])
    tenth = 0.1 * (s.scenario.t[1] - s.scenario.t[0]) / (s.n_sub - 1)
    x0 = propagate(em, peri, [0.0, -tenth], impact=False).x[-1]
    sub = propagate(em, x0, np.linspace(0.0, s.scenario.t[1] - s.scenario.t[0], s.n_sub), impact=False).x
    assert np.all(em.distances(sub)[1] > em.secondary_radius) and np.all(em.distances(sub)[0] > em.primary_radius)
    return x0


def test_screened_arc_check_leaves_the_filter_bit_identical_and_still_stops_a_trial_that_dips_into_the_moon(
        short_setup):
    """The screen of the arc impact check (propagation._check_arcs_outside_primaries) against the unscreened check
    (the path before it): the same filter output bit for bit on ordinary trials, and the same failure, named as an
    impact between grid points, for a trial whose reference dips below the Moon's surface between sub-grid points."""
    s = short_setup
    sc = s.scenario
    inputs = [det.draw_trial(k, s, det.QUIET_POLICY if j % 2 else None)
              for j, k in enumerate(np.random.default_rng(31).spawn(4))]
    x_dip = _moon_dipping_prior(s)
    y_dip = inputs[0].y.copy()
    y_dip[0] = sc.model(s.observer_states[0], x_dip)
    y = np.array([i.y for i in inputs] + [y_dip])
    x0 = np.array([i.x0 for i in inputs] + [x_dip])
    P0 = np.array([i.P0 for i in inputs] + [inputs[0].P0])
    args = (em, sc.t, y, s.observer_states, sc.model, sc.meas_cov, x0, P0, s.control_weight)

    def run():
        flagged = batched_ocbe.ocbe_batch(*args, n_sub=s.n_sub, tol=s.tol, on_failure="flag")
        with pytest.raises(ocbe.FilterDivergenceError) as stop:
            batched_ocbe.ocbe_batch(*args, n_sub=s.n_sub, tol=s.tol)
        return flagged, str(stop.value), det.run_detection_monte_carlo(s, det.QUIET_POLICY, 6, 3, batch_size=2,
                                                                        progress=False)

    new, stop_new, mc_new = run()
    with reference_detection.unscreened_arc_check():
        old, stop_old, mc_old = run()
    assert list(new.failure_epoch) == [-1, -1, -1, -1, 1]
    assert "ImpactError" in new.failure[4] and "Moon" in new.failure[4] and "between grid points" in new.failure[4]
    assert stop_new == stop_old and "between grid points" in stop_new
    assert list(new.failure) == list(old.failure)
    for name in ("x_pred", "x_filt", "P_filt", "x_smooth", "P_smooth", "control_smooth", "z_step", "z_smooth"):
        assert np.array_equal(getattr(new, name), getattr(old, name), equal_nan=True), name
    assert np.all(np.isfinite(new.z_smooth[:4]))
    for name in ("z", "z_step", "nees_mean_fwd", "nees_mean_smooth"):
        assert np.array_equal(getattr(mc_new, name), getattr(mc_old, name)), name


# ---------------------------------------------------------------------------------------------------------------
# Consistency readout, burn timing, filtering given trials, direction response, health-metric race
# ---------------------------------------------------------------------------------------------------------------


def test_trial_nees_equals_the_nees_of_the_filter_output(short_setup):
    """The NEES fields of a Monte Carlo trial are those of consistency.nees on the single-trial filter's estimates."""
    s = short_setup
    lim = stats.chi2.ppf(consistency.NEES_PROBABILITY, 6)
    batch = det.detection_trial_batch(np.random.default_rng(31), s, det.QUIET_POLICY, 2)
    for res, kid in zip(batch, np.random.default_rng(31).spawn(2)):
        inp = det.draw_trial(kid, s, det.QUIET_POLICY)
        one = det.run_trial_filter(s, inp)
        nf = consistency.nees(one.x_filt, one.P_filt, inp.truth)
        ns = consistency.nees(one.x_smooth, one.P_smooth, inp.truth)
        assert np.isclose(res.nees_mean_fwd, nf.mean(), rtol=1e-8)
        assert np.isclose(res.nees_mean_smooth, ns.mean(), rtol=1e-8)
        assert res.nees_over_fwd == np.mean(nf > lim) and res.nees_over_smooth == np.mean(ns > lim)
    single = det.detection_trial(np.random.default_rng(32), s, None)
    inp = det.draw_trial(np.random.default_rng(32), s, None)
    one = det.run_trial_filter(s, inp)
    assert np.isclose(single.nees_mean_smooth, consistency.nees(one.x_smooth, one.P_smooth, inp.truth).mean(), rtol=1e-12)
    # a run is inconsistent when more than 5 % of its epochs are above the quantile (strictly)
    r = [det.TrialResult(1.0, 1.0, 0.0, np.nan, np.nan, f, g, 6.0, 6.0)
         for f, g in ((0.0, 0.0), (0.05, 0.2), (0.06, 0.0), (0.5, 0.051))]
    mc = det.MonteCarloSample.from_results(r)
    assert mc.inconsistent_runs == (0.5, 0.5)


def test_burn_offset_moves_the_impulse_and_nothing_else(short_setup):
    from cislunar.cr3bp import propagation
    s = short_setup
    sc = s.scenario
    dv_m_s, direction = 2.0, (0.3, -0.4)
    plain = det.draw_trial(np.random.default_rng(6), s)
    at_apoapsis = det.draw_trial(np.random.default_rng(6), s, magnitude_m_s=dv_m_s, direction=direction)
    k = int(np.searchsorted(sc.t, s.t_maneuver, side="right"))  # first epoch after the apoapsis
    lag_h = (sc.t[k] - s.t_maneuver) * em.time_unit_s / 3600
    for offset in (-3.0, 0.0, lag_h / 2):
        inp = det.draw_trial(np.random.default_rng(6), s, magnitude_m_s=dv_m_s, direction=direction,
                             burn_offset_hours=offset)
        t_b = s.t_maneuver + offset * 3600 / em.time_unit_s
        kb = int(np.searchsorted(sc.t, t_b, side="right"))
        assert np.array_equal(inp.truth[:kb], plain.truth[:kb]) and np.array_equal(inp.x0, at_apoapsis.x0)
        # back-propagated from the next epoch to the burn time, the truth differs from the no-burn state by dv only
        before = propagation.propagate(em, plain.truth[kb], [sc.t[kb], t_b]).x[-1]
        after = propagation.propagate(em, inp.truth[kb], [sc.t[kb], t_b]).x[-1]
        dv = det.pointing_vector(*direction) * dv_m_s * 1e-3 / em.velocity_unit_km_s
        assert np.allclose(after - before, np.r_[np.zeros(3), dv], rtol=0, atol=1e-9 * np.abs(dv).max())
    late = det.draw_trial(np.random.default_rng(6), s, magnitude_m_s=dv_m_s, direction=direction,
                          burn_offset_hours=lag_h + 1.0)  # after the first post-apoapsis epoch
    assert np.array_equal(late.truth[:k + 1], plain.truth[:k + 1])
    with pytest.raises(ValueError, match="burn_offset_hours"):
        det.draw_trial(np.random.default_rng(6), s, magnitude_m_s=1.0, burn_offset_hours=1e4)


def test_filter_trials_equals_ocbe_batch_on_the_whole_and_on_a_truncated_arc(short_setup, monkeypatch):
    s = short_setup
    sc = s.scenario
    inputs = [det.draw_trial(k, s, det.ACTIVE_POLICY) for k in np.random.default_rng(9).spawn(3)]

    def direct(n):
        return batched_ocbe.ocbe_batch(em, sc.t[:n], np.array([i.y[:n] for i in inputs]), s.observer_states[:n], sc.model,
                              sc.meas_cov, np.array([i.x0 for i in inputs]), inputs[0].P0, s.control_weight[:n - 1],
                              n_sub=s.n_sub, tol=s.tol)

    monkeypatch.setattr(det, "LOCKSTEP_TRIALS", 2)  # 3 trials in two lockstep groups, concatenated
    for n in (None, sc.t.size, 5):
        got, ref = det.filter_trials(s, inputs, n_epochs=n), direct(sc.t.size if n is None else n)
        assert got.x_smooth.shape == ref.x_smooth.shape and np.array_equal(got.t_sub, ref.t_sub)
        # z is ~1e-9 LU/TU here; lockstep groups of other sizes take other SIMD lanes in heyoka, which moves the
        # smoothed control's round-off by up to ~1e-10 relative on some CPUs (8e-11 seen)
        assert np.max(np.abs(got.z_smooth / ref.z_smooth - 1)) < 1e-9
        assert np.max(np.abs(got.P_smooth - ref.P_smooth)) <= 1e-12 * np.max(np.abs(ref.P_smooth))
    # the forward pass does not look ahead: a truncated arc has the same filtered states on its epochs
    short = det.filter_trials(s, inputs, n_epochs=5)
    full = det.filter_trials(s, inputs)
    assert np.allclose(short.x_filt, full.x_filt[:, :5], rtol=0, atol=1e-12)
    with pytest.raises(ValueError, match="n_epochs"):
        det.filter_trials(s, inputs, n_epochs=1)
    with pytest.raises(ValueError, match="inputs"):
        det.filter_trials(s, [])
    with pytest.raises(TypeError, match="inputs"):
        det.filter_trials(s, inputs[0])


def test_direction_response_pairs_the_noise_across_directions(short_setup):
    s = short_setup
    dirs = np.array([[0.0, 0.0], [np.pi / 2, 0.0], [0.0, 0.0]])
    z = det.direction_response(s, dirs, 1.0, 2, [4, 1])
    assert z.shape == (2, 3) and np.allclose(z[:, 0], z[:, 2], rtol=1e-12)  # same direction, same noise
    assert not np.isclose(z[0, 0], z[1, 0])  # repeats have different noise
    one = det.draw_trial(np.random.default_rng([4, 1, 1]), s, magnitude_m_s=1.0, direction=dirs[1])
    ref = det.run_trial_filter(s, one).z_smooth * em.velocity_unit_km_s * 1e3
    assert abs(z[1, 1] / ref - 1) < 1e-9
    with pytest.raises(ValueError, match="magnitude_m_s"):
        det.direction_response(s, dirs, 0.0, 1, 0)
    with pytest.raises(ValueError, match="directions"):
        det.direction_response(s, np.zeros(3), 1.0, 1, 0)


def test_health_lead_study_outcomes_partition_and_a_large_burn_is_seen_at_once():
    s = det.make_setup(em, orbits.nrho_9_2(em), 0.1 * det.window_control_weight(det.QUIET_POLICY, 16.0), 1e-18,
                       cadence_hours=8.0, window_hours=16.0, periods=0.8)
    h = det.health_lead_study(s, [0.02, 5.0], 10, 4, 2, horizon_hours=20.0)
    sc = s.scenario
    k0 = int(np.searchsorted(sc.t, s.t_maneuver, side="right"))
    assert np.allclose(h.delay_hours, (sc.t[k0:k0 + h.delay_hours.size] - s.t_maneuver) * em.time_unit_s / 3600)
    assert h.delay_hours[0] > 0 and h.delay_hours[-1] <= 20.0
    fr = h.outcome_fractions()
    assert np.allclose(sum(fr.values()), 1.0)  # every run falls in exactly one outcome
    # a 5 m/s burn, a hundred times the quiet policy's, trips both tests at the first epoch after it
    assert np.all(h.control_epoch[1] == 0) and np.all(h.residual_epoch[1] == 0)
    assert fr["same epoch"][1] == 1.0 and np.allclose(h.median_delay_hours("control")[1], h.delay_hours[0])
    assert h.z_final_m_s[1].min() > h.z_h0_final_m_s.max()
    assert 0 <= h.false_alarm_control <= 1 and h.tail_probability == pytest.approx(stats.norm.sf(3.0))
    with pytest.raises(ValueError, match="horizon_hours"):
        det.health_lead_study(s, [0.1], 10, 2, 0, horizon_hours=1e4)
    with pytest.raises(ValueError, match="magnitudes_m_s"):
        det.health_lead_study(s, [-0.1], 10, 2, 0)
    with pytest.raises(ValueError, match="test"):
        h.median_delay_hours("metric")


def test_health_lead_study_one_forward_pass_equals_the_filter_rerun_on_every_arc_whatever_the_executor(monkeypatch):
    """The race's growing arcs from one forward pass and a backward pass per arc (smooth_ends) equal the filter and
    smoother rerun on each arc (the path before 2026-11-26d, reference_detection.reference_arc_statistics) bit for
    bit, whether the runs go in one lockstep group or several, serially or through an executor."""
    s = det.make_setup(em, orbits.nrho_9_2(em), 0.1 * det.window_control_weight(det.QUIET_POLICY, 16.0), 1e-18,
                       cadence_hours=8.0, window_hours=16.0, periods=0.8)
    args = (s, [0.02, 5.0], 10, 3, 2)
    one = det.health_lead_study(*args, horizon_hours=20.0)  # 26 runs: one lockstep group
    monkeypatch.setattr(batched_ocbe, "_LANES", 2)  # lane groups of 2: groups of 8 runs, four tasks
    tasks, today = [], det._arc_statistics

    def spy(task):
        tasks.append(task)
        return today(task)

    monkeypatch.setattr(det, "_arc_statistics", spy)
    serial = det.health_lead_study(*args, horizon_hours=20.0)
    assert len(tasks) == 4 and [len(t[1]) for t in tasks] == [8, 8, 8, 2]
    monkeypatch.setattr(det, "_arc_statistics", today)
    with ThreadPoolExecutor(2) as ex:
        split = det.health_lead_study(*args, horizon_hours=20.0, executor=ex)
    monkeypatch.setattr(det, "_arc_statistics", reference_detection.reference_arc_statistics)
    rerun = det.health_lead_study(*args, horizon_hours=20.0)
    for f in one.__dataclass_fields__:
        assert np.array_equal(getattr(split, f), getattr(one, f)), f
        assert np.array_equal(getattr(serial, f), getattr(one, f)), f
        assert np.array_equal(getattr(rerun, f), getattr(one, f)), f
    # the statistics themselves: every run at once through the rerun path against the groups of one forward pass
    everything = [i for t in tasks for i in t[1]]
    ks = tasks[0][2]
    old = reference_detection.reference_arc_statistics((s, everything, ks))
    new = [np.concatenate(parts) for parts in zip(*(today(t) for t in tasks))]
    for a, b in zip(old, new):
        assert np.array_equal(a, b)
    assert old[0].shape == (26, ks.size) and np.all(np.diff(old[0], axis=1) != 0)


def test_control_spike_contrast_of_a_known_spike(short_setup):
    s = short_setup
    N = s.scenario.t.size
    t_sub = np.array([np.linspace(s.scenario.t[n], s.scenario.t[n + 1], 5) for n in range(N - 1)])
    near = np.abs(t_sub - s.t_maneuver) <= 6 * 3600 / em.time_unit_s
    u = np.zeros((2, N - 1, 5, 3))
    u[..., 0] = 1.0  # unit norm everywhere ...
    u[0, near, 1] = np.sqrt(99.0)  # ... norm 10 near the burn in trial 0
    z = np.zeros(2)
    res = batched_ocbe.BatchOCBEResult(*(np.zeros((2, N, 6)),) * 2, np.zeros((2, N, 6, 6)), np.zeros((2, N, 6)),
                              np.zeros((2, N, 6, 6)), t_sub, np.full_like(u, 0.5), u, z, z, np.zeros((2, N)))
    c = det.control_spike_contrast(s, res)
    assert np.allclose(c[:, 1], [10.0, 1.0]) and np.allclose(c[:, 0], [1.0, 1.0])
    with pytest.raises(ValueError, match="half_width_hours"):
        det.control_spike_contrast(s, res, half_width_hours=1e5)
    with pytest.raises(TypeError, match="result"):
        det.control_spike_contrast(s, object())


def test_threshold_bootstrap_matches_the_spread_over_independent_samples():
    """The bootstrap standard error of z_lim agrees with the spread of z_lim over independent training sets.

    The crossing sits in the tail of the H0 sample, so one data set's bootstrap error scatters by tens of per cent;
    the average over a few data sets is compared.
    """
    m0, s0, m1, s1, n0, n1 = 0.2, 0.05, 1.0, 0.3, 200, 400
    rng = np.random.default_rng(12)
    indep = np.array([det.ml_threshold(rng.normal(m0, s0, n0), rng.normal(m1, s1, n1), n_grid=1001).z_lim
                      for _ in range(60)])
    boots = [det.threshold_bootstrap(rng.normal(m0, s0, n0), rng.normal(m1, s1, n1), 25, np.random.default_rng(k))
             for k in range(4)]
    assert boots[0].shape == (25, 2)
    se = np.mean([b[:, 0].std(ddof=1) for b in boots])
    assert 0.6 < se / indep.std(ddof=1) < 1.6
    assert abs(np.median(boots[0][:, 0]) - _gauss_crossing(m0, s0, m1, s1)) < 4 * indep.std()
    assert np.all((boots[0][:, 1] > 0) & (boots[0][:, 1] < 1))
    with pytest.raises(ValueError, match="n_resamples"):
        det.threshold_bootstrap([0.1, 0.2], [1.0, 2.0], 1, rng)


def test_azimuth_contrast_of_a_known_pattern():
    az = np.radians([90.0, -90.0, 0.0, 180.0, 45.0, 90.0])
    el = np.radians([0.0, 10.0, -20.0, 5.0, 0.0, 80.0])
    mag = np.array([1.0, 2.0, 1.0, 0.5, 1.0, 1.0])
    ratio = np.array([2.0, 2.0, 1.0, 1.0, 7.0, 9.0])  # z / |dv|: the 45 deg and the high-elevation runs are ignored
    n = az.size
    s = det.MonteCarloSample(ratio * mag, ratio * mag, mag, az, el, *(np.zeros(n),) * 4)
    assert det.azimuth_contrast(s) == pytest.approx(2.0)
    assert np.isnan(det.azimuth_contrast(s, half_width_deg=5.0, max_elevation_deg=1.0))  # a sector is empty
    with pytest.raises(ValueError, match="sample"):
        det.azimuth_contrast(det.MonteCarloSample(*(np.zeros(2),) * 9))
