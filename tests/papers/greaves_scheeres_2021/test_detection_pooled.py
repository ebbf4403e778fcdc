"""The detection Monte Carlo's fast path against the path before it: batched draws, vectorised bookkeeping and
the pooled sweeps of several Monte Carlo runs give the same trials (same random streams, same numbers to
round-off), and a truth that meets the Moon is still refused."""

import numpy as np
import pytest

from cislunar.cr3bp import orbits
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.cr3bp.propagation import ImpactError
from cislunar.papers.greaves_scheeres_2021 import detection as det
from cislunar.papers.greaves_scheeres_2021 import detection_studies as dstudies
from cislunar.utils.montecarlo import MonteCarloError
from tests.papers.greaves_scheeres_2021.reference_detection import (
    reference_detection_batches,
    reference_draw_trial,
    reference_monte_carlo,
)

FIELDS = ("z_m_s", "z_step_m_s", "magnitude_m_s", "azimuth", "elevation", "nees_over_fwd", "nees_over_smooth",
          "nees_mean_fwd", "nees_mean_smooth")


@pytest.fixture(scope="module")
def short_setup():
    """A short, coarse track (0.6 period from periapsis, 8-hour cadence) so the filter runs take milliseconds."""
    return det.make_setup(em, orbits.nrho_9_2(em), det.window_control_weight(det.ACTIVE_POLICY), 1e-18,
                          cadence_hours=8.0, window_hours=16.0, periods=0.6)


CASES = [dict(policy=det.QUIET_POLICY), dict(policy=det.ACTIVE_POLICY), dict(policy=None),
         dict(magnitude_m_s=0.5), dict(policy=det.ACTIVE_POLICY, magnitude_m_s=2.0, direction=(0.3, -0.2)),
         dict(magnitude_m_s=1.0, direction=(1.0, 0.4), burn_offset_hours=-5.0)]


@pytest.mark.parametrize("kw", CASES, ids=lambda kw: "-".join(sorted(kw)) + ("-H0" if kw.get("policy", 1) is None
                                                                               else ""))
def test_batched_draws_equal_the_draws_one_at_a_time(short_setup, kw):
    seeds = np.random.default_rng(11).spawn(7)
    ref = [reference_draw_trial(np.random.default_rng(s.bit_generator.seed_seq), short_setup, **kw) for s in seeds]
    new = det.draw_trials([np.random.default_rng(s.bit_generator.seed_seq) for s in seeds], short_setup, **kw)
    one = [det.draw_trial(np.random.default_rng(s.bit_generator.seed_seq), short_setup, **kw) for s in seeds]
    for a, b, c in zip(ref, new, one):
        for f in ("magnitude_m_s", "azimuth", "elevation"):  # the random streams, bit for bit
            assert np.array_equal(getattr(a, f), getattr(b, f), equal_nan=True), f
        assert np.array_equal(a.x0, b.x0) and np.array_equal(a.P0, b.P0)
        # the batched (SIMD) propagation after the burn: the same truth and data to round-off
        assert np.allclose(b.truth, a.truth, rtol=0, atol=1e-13)
        assert np.allclose(b.y, a.y, rtol=1e-12, atol=1e-13)
        for f in ("magnitude_m_s", "azimuth", "elevation", "truth", "y", "x0", "P0"):  # one trial: bit for bit
            assert np.array_equal(getattr(a, f), getattr(c, f), equal_nan=True), f
    # the noise is the trial's own: trials differ, and a second draw from the same generators repeats them
    assert not np.allclose(new[0].y, new[1].y)


def test_batched_draws_keep_the_burn_in_the_truth(short_setup):
    """A mutation check of the shared first arc: the truth is ballistic up to the burn and differs after it."""
    rngs = [np.random.default_rng(k) for k in range(4)]
    burn = det.draw_trials(rngs, short_setup, magnitude_m_s=1.0)
    plain = det.draw_trials([np.random.default_rng(k) for k in range(4)], short_setup)
    k = int(np.searchsorted(short_setup.scenario.t, short_setup.t_maneuver, side="right"))
    for b, p in zip(burn, plain):
        assert np.array_equal(b.truth[:k], p.truth[:k])
        dv = np.linalg.norm(b.truth[k:, 3:] - p.truth[k:, 3:], axis=-1) * em.velocity_unit_km_s * 1e3
        assert 0.3 < dv[0] < 3.0  # about the 1 m/s of the burn one epoch later (dynamics bend it a little)


def test_fast_batches_equal_the_old_path(short_setup):
    # a window weight a hundred times too small for the active burns: the forward filter is inconsistent after
    # the burn, the smoothed one less so (the bookkeeping of both NEES counts is tested)
    low = det.make_setup(em, orbits.nrho_9_2(em), 0.01 * det.window_control_weight(det.ACTIVE_POLICY), 1e-18,
                         cadence_hours=8.0, window_hours=16.0, periods=0.6)
    rngs = [np.random.default_rng([5, k]) for k in range(3)]
    ref = reference_detection_batches(rngs, low, det.ACTIVE_POLICY, 4)
    new = det._detection_batches([np.random.default_rng([5, k]) for k in range(3)], low, det.ACTIVE_POLICY, 4)
    a = np.array([[getattr(r, f) for f in FIELDS] for batch in ref for r in batch])
    b = np.array([[getattr(r, f) for f in FIELDS] for batch in new for r in batch])
    assert a.shape == b.shape == (12, len(FIELDS))
    assert np.array_equal(a[:, 2:5], b[:, 2:5], equal_nan=True)  # the maneuvers, bit for bit
    assert np.allclose(b[:, :2], a[:, :2], rtol=1e-9, atol=0)  # z, smoothed and forward
    assert np.array_equal(a[:, 5:7], b[:, 5:7])  # fractions of epochs over the NEES limit
    assert np.any(a[:, 5] != a[:, 6]) and np.any(a[:, 7] != a[:, 8])
    assert np.allclose(b[:, 7:], a[:, 7:], rtol=1e-8)


def _as_array(sample):
    return np.array([sample.z, sample.z_step, sample.magnitude, sample.azimuth, sample.elevation,
                     sample.nees_over_fwd, sample.nees_over_smooth, sample.nees_mean_fwd, sample.nees_mean_smooth])


def test_pooled_monte_carlo_equals_separate_runs_and_the_old_path(short_setup, monkeypatch):
    monkeypatch.setattr(det, "LOCKSTEP_TRIALS", 8)  # several lockstep groups per job, shared between jobs
    s2 = det.make_setup(em, orbits.nrho_9_2(em), 0.3 * det.window_control_weight(det.QUIET_POLICY), 1e-18,
                        cadence_hours=8.0, window_hours=16.0, periods=0.6)
    jobs = [(short_setup, det.ACTIVE_POLICY, 13, [0, 1]), (s2, None, 6, [0, 2]), (s2, det.QUIET_POLICY, 9, 7),
            (short_setup, None, 3, np.random.SeedSequence([4, 4]))]
    pooled = det.run_detection_monte_carlos(jobs, batch_size=4)
    for job, got in zip(jobs, pooled):
        alone = det.run_detection_monte_carlo(*job, batch_size=4, progress=False)
        assert len(got) == job[2]
        assert np.array_equal(_as_array(got), _as_array(alone), equal_nan=True)  # bit for bit
    old = np.array([[getattr(r, f) for f in FIELDS] for r in reference_monte_carlo(*jobs[0], batch_size=4)]).T
    assert np.array_equal(old[2:5], _as_array(pooled[0])[2:5], equal_nan=True)
    assert np.allclose(_as_array(pooled[0])[:2], old[:2], rtol=1e-9, atol=0)


def test_jobs_of_different_tunings_share_lockstep_groups_and_keep_their_own_weight(short_setup, monkeypatch):
    """Two tunings of the same track are filtered in one lockstep call, each trial with its own control weight:
    a mix-up of the weights (e.g. the first setup's for every trial) changes the second job's z."""
    s2 = det.make_setup(em, orbits.nrho_9_2(em), 0.01 * det.window_control_weight(det.ACTIVE_POLICY), 1e-18,
                        cadence_hours=8.0, window_hours=16.0, periods=0.6)
    calls = []
    real = det.ocbe_batch

    def counting(*args, **kwargs):
        calls.append(args[2].shape[0])
        return real(*args, **kwargs)

    monkeypatch.setattr(det, "ocbe_batch", counting)
    jobs = [(short_setup, det.ACTIVE_POLICY, 8, [9]), (s2, det.ACTIVE_POLICY, 8, [9])]
    a, b = det.run_detection_monte_carlos(jobs, batch_size=4)
    assert calls == [16]  # one lockstep call for both jobs
    monkeypatch.setattr(det, "ocbe_batch", real)
    alone = [det.run_detection_monte_carlo(*job, batch_size=4, progress=False) for job in jobs]
    assert np.array_equal(_as_array(a), _as_array(alone[0]), equal_nan=True)
    assert np.array_equal(_as_array(b), _as_array(alone[1]), equal_nan=True)
    assert np.array_equal(a.magnitude, b.magnitude) and not np.allclose(a.z, b.z, rtol=1e-3)  # same burns


def test_pooled_policy_studies_equal_one_study_at_a_time(short_setup):
    jobs = [(short_setup, det.ACTIVE_POLICY, 8, 12, 4, [3]), (short_setup, det.QUIET_POLICY, 8, 8, 0, [3, 1])]
    for job, got in zip(jobs, det.run_policy_studies(jobs, batch_size=4)):
        alone = det.run_policy_study(*job, batch_size=4, progress=False)
        assert np.array_equal(_as_array(got.h0), _as_array(alone.h0), equal_nan=True)
        assert np.array_equal(_as_array(got.h1), _as_array(alone.h1), equal_nan=True)
        assert got.threshold.z_lim == alone.threshold.z_lim
        assert got.score == alone.score
        assert (got.test_h0 is None) == (job[4] == 0)


def _moon_burn(setup):
    """A burn 2 h after the periapsis hand-off that cancels the velocity: the truth falls onto the Moon."""
    t_burn = setup.scenario.t[0] + 2 * 3600.0 / em.time_unit_s
    from cislunar.cr3bp.propagation import propagate
    v = propagate(em, setup.scenario.x_start, [setup.scenario.t[0], t_burn]).x[-1, 3:]
    d = -v / np.linalg.norm(v)
    az, el = np.arctan2(d[1], d[0]), np.arcsin(d[2])
    offset_h = (t_burn - setup.t_maneuver) * em.time_unit_s / 3600.0
    return np.linalg.norm(v) * em.velocity_unit_km_s * 1e3, (az, el), offset_h


def test_a_truth_through_the_moon_is_refused(short_setup):
    mag, direction, offset = _moon_burn(short_setup)
    rngs = [np.random.default_rng(k) for k in range(3)]
    with pytest.raises(ImpactError, match="Moon"):
        det.draw_trials(rngs, short_setup, magnitude_m_s=mag, direction=direction, burn_offset_hours=offset)
    with pytest.raises(ImpactError, match="Moon"):
        det.draw_trial(rngs[0], short_setup, magnitude_m_s=mag, direction=direction, burn_offset_hours=offset)
    # a small burn in the same direction and at the same time is flown
    det.draw_trials(rngs, short_setup, magnitude_m_s=1.0, direction=direction, burn_offset_hours=offset)


def test_pooled_failure_names_the_trial(short_setup, monkeypatch):
    def broken(*args, **kwargs):
        raise RuntimeError("broken filter")

    monkeypatch.setattr(det, "ocbe_batch", broken)
    with pytest.raises(MonteCarloError, match="broken filter") as info:
        det.run_detection_monte_carlos([(short_setup, None, 5, [1]), (short_setup, None, 5, [2])], batch_size=4)
    assert info.value.trial_index == 0 and "trials 0-3" in info.value.seed


def test_pooled_bad_input(short_setup):
    with pytest.raises(ValueError, match=r"jobs\[0\]"):
        det.run_detection_monte_carlos([(short_setup, None, 5)], batch_size=4)
    with pytest.raises(ValueError, match=r"jobs\[1\] n_trials"):
        det.run_detection_monte_carlos([(short_setup, None, 5, 1), (short_setup, None, 0, 1)])
    with pytest.raises(TypeError, match=r"jobs\[0\] setup"):
        det.run_detection_monte_carlos([("setup", None, 5, 1)])
    with pytest.raises(ValueError, match="batch_size"):
        det.run_detection_monte_carlos([(short_setup, None, 5, 1)], batch_size=0)
    with pytest.raises(ValueError, match=r"jobs\[0\] n_h1"):
        det.run_policy_studies([(short_setup, det.QUIET_POLICY, 4, 1, 0, 1)])
    with pytest.raises(TypeError, match="rngs"):
        det.draw_trials([np.random.RandomState(0)], short_setup)
    with pytest.raises(ValueError, match="rngs"):
        det.draw_trials([], short_setup)


def test_filter_trial_sets_equal_filter_trials_per_set(short_setup, monkeypatch):
    monkeypatch.setattr(det, "LOCKSTEP_TRIALS", 5)  # sets split over groups and groups shared between sets
    s2 = det.make_setup(em, orbits.nrho_9_2(em), 0.05 * det.window_control_weight(det.ACTIVE_POLICY), 1e-18,
                        cadence_hours=8.0, window_hours=16.0, periods=0.6)
    runs = det.draw_trials(np.random.default_rng(8).spawn(7), short_setup, det.ACTIVE_POLICY)
    other = det.draw_trials(np.random.default_rng(9).spawn(3), short_setup)
    sets = [(short_setup, runs), (s2, runs), (s2, other)]
    got = det.filter_trial_sets(sets)
    for (setup, inputs), res in zip(sets, got):
        alone = det.filter_trials(setup, inputs)
        for f in ("x_filt", "P_smooth", "control_smooth", "z_smooth", "z_step", "residual_norms", "t_sub"):
            assert np.array_equal(getattr(res, f), getattr(alone, f)), f
    assert not np.allclose(got[0].z_smooth, got[1].z_smooth, rtol=1e-3)  # each set keeps its own tuning
    with pytest.raises(ValueError, match=r"sets\[0\] inputs"):
        det.filter_trial_sets([(short_setup, [])])


def test_direction_trials_are_those_of_direction_response(short_setup):
    dirs = np.radians([[0.0, 0.0], [90.0, 0.0], [0.0, 90.0]])
    inputs = det.direction_trials(short_setup, dirs, 1.0, 2, [4], burn_offset_hours=1.0)
    z = det.filter_trials(short_setup, inputs).z_smooth * em.velocity_unit_km_s * 1e3
    assert np.array_equal(z.reshape(2, 3), det.direction_response(short_setup, dirs, 1.0, 2, [4],
                                                                  burn_offset_hours=1.0))
    # repeat k shares its noise across directions; the repeats differ
    assert np.array_equal(inputs[0].x0, inputs[2].x0) and not np.array_equal(inputs[0].x0, inputs[3].x0)
    assert [i.azimuth for i in inputs[:3]] == list(dirs[:, 0]) and np.array_equal(inputs[1].y[0], inputs[0].y[0])
    ref = reference_draw_trial(np.random.default_rng([4, 1]), short_setup, magnitude_m_s=1.0, direction=dirs[2],
                               burn_offset_hours=1.0)
    assert np.array_equal(ref.y, inputs[5].y) or np.allclose(ref.y, inputs[5].y, rtol=1e-12, atol=1e-13)


def test_studies_build_one_scenario_per_track_and_the_same_setups_as_make_setup():
    """The studies' setup maker (one scenario per orbit and angle noise, retuned for each weight and window) gives,
    field by field and bit for bit, the setup that make_setup builds from scratch; a swap of the window and base
    weights, or a window length left at the first call's, changes the control weights."""
    nrho = orbits.nrho_9_2(em)
    make = dstudies._setup_maker(em)
    cases = [(3e-15, 1e-18, 8.0, 10e-6), (3e-14, 1e-18, 8.0, 10e-6), (3e-15, 1e-16, 4.0, 10e-6),
             (1e-13, 1e-18, 12.0, 10e-6), (3e-15, 1e-18, 8.0, 20e-6), (5e-15, 1e-17, 6.0, 20e-6)]
    got = [make(nrho, qw, qb, window_hours=wh, sigma_angle_rad=s) for qw, qb, wh, s in cases]
    for (qw, qb, wh, s), a in zip(cases, got):
        b = det.make_setup(em, nrho, qw, qb, window_hours=wh, sigma_angle_rad=s)
        assert np.array_equal(a.control_weight, b.control_weight)
        nd = em.time_unit_s**3 / em.length_unit_km**2  # km^2/s^3 -> LU^2/TU^3, independently of the module
        assert np.isclose(a.control_weight.max(), qw * nd, rtol=1e-12) and np.isclose(a.control_weight.min(), qb * nd,
                                                                                        rtol=1e-12)
        assert (a.q_window_km2_s3, a.q_base_km2_s3, a.window_hours) == (qw, qb, wh)
        assert (a.t_maneuver, a.q_window_km2_s3, a.q_base_km2_s3, a.window_hours, a.n_sub, a.tol) == (
            b.t_maneuver, b.q_window_km2_s3, b.q_base_km2_s3, b.window_hours, b.n_sub, b.tol)
        assert np.array_equal(a.scenario.t, b.scenario.t) and np.array_equal(a.scenario.meas_cov, b.scenario.meas_cov)
        assert np.array_equal(a.observer_states, b.observer_states) and np.array_equal(a.scenario.x_start,
                                                                                        b.scenario.x_start)
    assert got[1].scenario is got[0].scenario and got[3].scenario is got[0].scenario  # one track per noise
    assert got[5].scenario is got[4].scenario and got[4].scenario is not got[0].scenario
    assert len({g.control_weight.tobytes() for g in got[:4]}) == 4  # the tunings differ where they should
    with pytest.raises(ValueError, match="q_window_km2_s3"):
        make(nrho, -1.0, 1e-18, window_hours=8.0, sigma_angle_rad=10e-6)
