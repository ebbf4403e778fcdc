"""Tracking scenarios: truth with impulses, measurement noise, tuning windows."""

import numpy as np
import pytest

from cislunar.cr3bp import orbits
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.cr3bp.propagation import propagate
from cislunar.estimation import batched_ocbe, consistency
from cislunar.papers.greaves_scheeres_2021 import tracking
from cislunar.utils.montecarlo import spawn_rngs


@pytest.fixture(scope="module")
def scenario():
    return tracking.make_scenario(em, orbits.nrho_9_2(em), 2.0)


def test_scenario_layout(scenario):
    sc = scenario
    assert abs(sc.cadence_hours - 2.0) < 1e-12
    assert sc.t[-1] <= sc.orbit.period + 1e-9 and sc.t.size == int(np.floor(sc.orbit.period / sc.t[1])) + 1
    # starts at periapsis: radial velocity w.r.t. the Moon vanishes
    r = sc.x_start[:3] - em.secondary_position
    assert abs(r @ sc.x_start[3:]) < 1e-10
    assert sc.t_apoapsis.size == 1 and abs(sc.t_apoapsis[0] - sc.orbit.period / 2) < 1e-8
    # Eq. 13: rate sigma = sqrt(2) sigma / 1 s
    s = np.sqrt(np.diag(sc.meas_cov))
    assert np.isclose(s[2], np.sqrt(2) * s[0] * em.time_unit_s)


def test_truth_with_impulse_matches_piecewise_propagation(scenario):
    sc = scenario
    tm = 0.5 * (sc.t[10] + sc.t[11])
    dv = np.array([1e-3, -2e-3, 5e-4])
    truth = tracking.simulate_truth(em, sc.x_start, sc.t[:20], [(tm, dv)])
    plain = propagate(em, sc.x_start, sc.t[:20]).x
    assert np.array_equal(truth[:11], plain[:11])
    x_m = propagate(em, sc.x_start, [0.0, tm]).x[-1] + np.r_[0, 0, 0, dv]
    after = propagate(em, x_m, np.r_[tm, sc.t[11:20]]).x[1:]
    assert np.max(np.abs(truth[11:] - after)) < 1e-12
    with pytest.raises(ValueError, match="precede"):
        tracking.simulate_truth(em, sc.x_start, sc.t[:5], [(-1.0, dv)])


def test_measurement_noise_statistics(scenario):
    sc = scenario
    truth = propagate(em, sc.x_start, sc.t).x
    rng = np.random.default_rng(0)
    res = np.array([sc.model.residual(tracking.simulate_measurements(sc, truth, rng)[:, 0],
                                      sc.model(sc.observers[:, 0], truth)) for _ in range(40)]).reshape(-1, 4)
    z = res / np.sqrt(np.diag(sc.meas_cov))
    assert np.all(np.abs(z.mean(axis=0)) < 0.05) and np.all(np.abs(z.std(axis=0) - 1) < 0.05)


def test_apoapsis_window(scenario):
    sc = scenario
    q = tracking.apoapsis_window_weights(sc.t, sc.t_apoapsis, 1.0, 50.0, 8.0, em)
    hot = np.flatnonzero(q == 50.0)
    assert hot.size in (4, 5)  # 8 hours at a 2-hour cadence: four intervals, five if apoapsis falls mid-interval
    mid = 0.5 * (sc.t[hot[0]] + sc.t[hot[-1] + 1])
    assert abs(mid - sc.t_apoapsis[0]) < sc.t[1]


def test_five_observer_scenario_visibility():
    sc = tracking.make_scenario(em, orbits.nrho_9_2(em), 1.0, observers="all", rates=False)
    assert sc.observers.shape == (sc.t.size, 5, 6) and sc.available.shape == (sc.t.size, 5)
    assert sc.available[:, 0].all()  # L2 never occulted
    assert sc.available[:, 2:].any(axis=1).all()  # the three stations together see the whole orbit
    y = tracking.simulate_measurements(sc, propagate(em, sc.x_start, sc.t).x, np.random.default_rng(1))
    assert np.isnan(y[~sc.available]).all() and np.isfinite(y[sc.available]).all()


def test_filter_trial_is_consistent_for_the_papers_strategy(scenario):
    q = 1e-20 * em.time_unit_s**3 / em.length_unit_km**2  # truth and filter share the model: negligible q
    out = [tracking.filter_trial(np.random.default_rng(s), scenario, q) for s in range(6)]
    nees_mean = np.mean([o.nees_mean for o in out])
    assert not any(o.diverged for o in out)
    # chi-square with 6 dof has mean 6; epochs within a run are correlated, so only 6 independent runs count:
    # two-sided bound at about three standard errors of a mean of 6 chi-square(6) draws (sd sqrt(12/6) = 1.4)
    assert 6.0 - 4.3 < nees_mean < 6.0 + 4.3
    assert all(o.final_error_pos_km < 4 * o.final_sigma_pos_km for o in out)


def test_nees_of_exact_draws_has_the_chi_square_mean():
    rng = np.random.default_rng(2)
    A = rng.standard_normal((6, 6))
    P = A @ A.T + np.eye(6)
    e = rng.multivariate_normal(np.zeros(6), P, size=4000)
    n = consistency.nees(e, np.broadcast_to(P, (4000, 6, 6)), np.zeros((4000, 6)))
    assert abs(n.mean() - 6.0) < 3 * np.sqrt(12.0 / 4000)


def test_summary_counts_inconsistent_epochs_and_dates_the_first():
    """Errors of 1 sigma are consistent; one of 10 sigma (NEES 100 > 22.5) at epochs 3 and 7 only."""
    N = 10
    P = np.broadcast_to(np.diag([1e-10] * 3 + [1e-12] * 3), (N, 6, 6)).copy()
    truth = np.zeros((N, 6))
    x = np.tile(np.sqrt(np.diag(P[0])) / np.sqrt(6), (N, 1))  # NEES 1 at every epoch
    x[[3, 7], 0] = 10 * np.sqrt(P[0, 0, 0])
    s = tracking.summarize(em, x, P, truth)
    assert s.first_inconsistent_epoch == 3 and s.inconsistent_fraction == pytest.approx(0.2) and s.diverged
    s0 = tracking.summarize(em, np.tile(x[0], (N, 1)), P, truth)
    assert s0.first_inconsistent_epoch == -1 and s0.inconsistent_fraction == 0 and not s0.diverged
    assert s0.nees_mean == pytest.approx(1.0, rel=1e-12)


def same_run(a, b, rtol=1e-7):
    """Two TrialSummary of the same draws: flags, counts and epochs identical, numbers equal to round-off."""
    assert (a.diverged, a.first_inconsistent_epoch, a.inconsistent_fraction, a.failure == "") == \
        (b.diverged, b.first_inconsistent_epoch, b.inconsistent_fraction, b.failure == "")
    for name in ("final_sigma_pos_km", "final_sigma_vel_m_s", "final_error_pos_km", "final_error_vel_m_s",
                 "max_error_pos_km", "nees_mean"):
        x, y = getattr(a, name), getattr(b, name)
        assert (np.isnan(x) and np.isnan(y)) or abs(x / y - 1) < rtol, (name, x, y)


def test_filter_trials_equal_filter_trial_draw_by_draw_with_five_observers_and_mixed_handoffs():
    """The lockstep path against the single-trial path on the same generators: five observers with their
    visibility mask (surface stations come and go), angles only, hand-offs 10 km to 10,000 km (the large ones
    diverge)."""
    sc = tracking.make_scenario(em, orbits.nrho_9_2(em), 6.0, start="apoapsis", rates=False, observers="all")
    assert not sc.available.all()
    q = 1e-20 * em.time_unit_s**3 / em.length_unit_km**2
    scales = [1.0, 1000.0, 0.1, 1000.0, 1.0]
    single = [tracking.filter_trial(r, sc, q, handoff_scale=h) for r, h in zip(spawn_rngs(11, 5), scales)]
    batch = tracking.filter_trials(spawn_rngs(11, 5), sc, q, handoff_scale=scales)
    for a, b in zip(single, batch):
        same_run(a, b)
    assert [r.diverged for r in batch] == [False, True, False, True, False]
    one_scale = tracking.filter_trials(spawn_rngs(11, 5)[2:3], sc, q, handoff_scale=0.1)
    same_run(one_scale[0], batch[2])


def test_filter_trials_reports_a_flagged_trial_as_filter_trial_reports_a_failure(scenario, monkeypatch):
    real = batched_ocbe.ocbe_batch

    def flag_second(*args, **kwargs):
        res = real(*args, **kwargs)
        epoch, text = res.failure_epoch.copy(), res.failure.astype(object)
        epoch[1], text[1] = 4, "OCBE failed numerically at epoch 4 (t = 0.2 TU): LinAlgError: x" + "y" * 300
        return batched_ocbe.BatchOCBEResult(**{**res.__dict__, "failure_epoch": epoch, "failure": text})

    monkeypatch.setattr(tracking, "ocbe_batch", flag_second)
    out = tracking.filter_trials(spawn_rngs(0, 3), scenario, 1e-8)
    assert out[1].diverged and out[1].inconsistent_fraction == 1.0 and np.isnan(out[1].nees_mean)
    assert out[1].first_inconsistent_epoch == -1 and out[1].failure.startswith("OCBE failed numerically at epoch 4")
    assert len(out[1].failure) == 200 and not out[0].failure and not out[2].failure


def test_filter_trials_bad_input(scenario):
    with pytest.raises(TypeError, match="rngs"):
        tracking.filter_trials(np.random.default_rng(0), scenario, 1e-8)
    with pytest.raises(ValueError, match="rngs"):
        tracking.filter_trials([], scenario, 1e-8)
    with pytest.raises(TypeError, match=r"rngs\[1\]"):
        tracking.filter_trials([np.random.default_rng(0), 3], scenario, 1e-8)
    with pytest.raises(ValueError, match="handoff_scale"):
        tracking.filter_trials(spawn_rngs(0, 2), scenario, 1e-8, handoff_scale=[1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="handoff_scale"):
        tracking.filter_trials(spawn_rngs(0, 2), scenario, 1e-8, handoff_scale=[1.0, -2.0])
    with pytest.raises(ValueError, match="control_weight"):
        tracking.filter_trials(spawn_rngs(0, 2), scenario, -1.0)


@pytest.mark.parametrize("options", [{"wrap_azimuth": False}, {"relinearize": False}, {"coarse_stm": True}])
def test_filter_trials_pass_the_filter_options_on_and_draw_the_same_data(scenario, options):
    """A filter-side option changes the filter only: the summaries are those of ocbe_batch with that option on the
    draws of filter_trial (same generators), and the default options give the default summaries bit for bit."""
    q = 1e-20 * em.time_unit_s**3 / em.length_unit_km**2
    sc = tracking.make_scenario(em, orbits.nrho_9_2(em), 12.0, start="apoapsis")
    truth = tracking.simulate_truth(em, sc.x_start, sc.t)
    y, x0 = [], []
    for r in spawn_rngs(2, 2):
        y.append(tracking.simulate_measurements(sc, truth, r))
        x0.append(tracking.initial_estimate(em, sc.x_start, r, scale=30.0)[0])
    P0 = tracking.initial_estimate(em, sc.x_start, np.random.default_rng(0), scale=30.0)[1]
    res = batched_ocbe.ocbe_batch(em, sc.t, np.array(y), sc.observers, sc.model, sc.meas_cov, np.array(x0), P0, q,
                                  available=sc.available, smooth=False, n_sub=2, tol=1e-13, on_failure="flag",
                                  **options)
    out = tracking.filter_trials(spawn_rngs(2, 2), sc, q, handoff_scale=30.0, **options)
    for b in range(2):
        assert out[b] == tracking.summarize(em, res.x_filt[b], res.P_filt[b], truth)
    default = tracking.filter_trials(spawn_rngs(2, 2), sc, q, handoff_scale=30.0)
    assert default == tracking.filter_trials(spawn_rngs(2, 2), sc, q, handoff_scale=30.0, wrap_azimuth=True,
                                             relinearize=True, coarse_stm=False)
    if "wrap_azimuth" not in options:  # whether a draw's azimuths straddle the cut is chance (tests/estimation)
        assert default != out  # the option did change the filter
    with pytest.raises(TypeError, match=next(iter(options))):
        tracking.filter_trials(spawn_rngs(2, 2), sc, q, **{k: "yes" for k in options})
