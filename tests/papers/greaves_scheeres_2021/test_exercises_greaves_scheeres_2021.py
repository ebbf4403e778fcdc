"""The worked solutions of the exercises of the Greaves & Scheeres (JAS 2021) notebooks say what their answers
claim.  One section per notebook group."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from cislunar.papers.greaves_scheeres_2021 import exercises as ex


def _frozen_with_answer_0910(result):
    assert dataclasses.is_dataclass(result)
    with pytest.raises(dataclasses.FrozenInstanceError):
        result.answer = "changed"
    assert isinstance(result.answer, str) and len(result.answer) > 200


# ---------------------------------------------------------------------------------------------------------------
# Notebooks 09b-10 (section of the 09b/10 helper)
# ---------------------------------------------------------------------------------------------------------------
def test_09b_burn_size_larger_burns_are_detected_sooner():
    r = ex.exercise_09b_burn_size(magnitudes_m_s=(0.05, 0.3, 3.0), n_runs=6)
    _frozen_with_answer_0910(r)
    assert np.all(np.diff(r.mean_delay_h) < 0)  # the delay falls as the burn grows
    assert r.prompt[-1] == 1.0 and r.prompt[0] < 0.5  # 3 m/s at once, 50 mm/s mostly not
    assert np.all(r.mean_delay_h <= r.coast_h) and np.all((0 <= r.undetected) & (r.undetected <= 1))
    assert f"{r.mean_delay_h[0]:.0f} h at 0.05 m/s" in r.answer
    with pytest.raises(ValueError, match="magnitudes_m_s"):
        ex.exercise_09b_burn_size(magnitudes_m_s=(3.0, 0.05))


def test_09b_base_weight_lowers_the_metric_and_hides_the_burn():
    r = ex.exercise_09b_base_weight(q_km2_s3=(1e-18, 1e-12), n_null=3, n_runs=4)
    _frozen_with_answer_0910(r)
    # the ballistic tuning matches the truth: chi2_4 mean within 3 standard errors of 4
    assert abs(r.metric_mean[0] - 4.0) < 3 * r.metric_standard_error[0]
    # the raised weight over-predicts the innovation: the mean falls well below 4
    assert r.metric_mean[1] < 4.0 - 3 * r.metric_standard_error[1]
    assert r.detected[1] < r.detected[0]
    with pytest.raises(ValueError, match="q_km2_s3"):
        ex.exercise_09b_base_weight(q_km2_s3=(1e-12,))


def test_10_window_factor_raises_z_without_a_burn_and_the_threshold():
    r = ex.exercise_10_window_factor(f=(0.03, 0.3, 1.0), n_runs=6)
    _frozen_with_answer_0910(r)
    assert np.all(np.diff(r.z_h0_mm_s) > 0) and np.all(np.diff(r.z_lim_mm_s) > 0)
    # a burn still lifts z above the no-burn runs, and the threshold lies between the two means
    assert np.all(r.z_h1_mm_s > r.z_h0_mm_s)
    assert np.all((r.z_h0_mm_s < r.z_lim_mm_s) & (r.z_lim_mm_s < r.z_h1_mm_s))
    # H1 grows less than H0 (a burn cannot add more than its size): the two move closer in ratio
    assert r.z_h1_mm_s[-1] / r.z_h0_mm_s[-1] < r.z_h1_mm_s[0] / r.z_h0_mm_s[0]
    with pytest.raises(ValueError, match="f must"):
        ex.exercise_10_window_factor(f=(0.3, 0.1))


def test_10_pm_j_pattern_needs_noisy_angles():
    r = ex.exercise_10_pm_j_noise(noise_urad=(10.0, 1000.0))
    _frozen_with_answer_0910(r)
    assert abs(r.contrast[0] - 1.0) < 0.1  # every direction is seen at our noise
    assert r.contrast[1] > 1.3  # +-j stands out when the angles see the burn poorly
    assert np.all(np.abs(r.z_m_s[0] - 1.0) < 0.2)  # z recovers the 1 m/s burn at our noise ...
    assert r.z_m_s[1].max() < 0.7  # ... and falls short of it with noisy angles
    assert f"{r.contrast[1]:.2f}" in r.answer


# ---------------------------------------------------------------------------------------------------------------
# Notebooks 01 and 09 (section of the 01/09 helper)
# ---------------------------------------------------------------------------------------------------------------
def _frozen_with_answer_0109(result):
    assert dataclasses.is_dataclass(result)
    with pytest.raises(dataclasses.FrozenInstanceError):
        result.answer = "changed"
    assert isinstance(result.answer, str) and len(result.answer) > 200


def test_01_halo_step_resolves_the_band_but_keeps_the_orbits():
    r = ex.exercise_01_halo_step(steps=(0.03, 0.015))
    _frozen_with_answer_0109(r)
    # halving the step about doubles the members, in the family and in the outer band
    assert 1.6 < r.n_members[1] / r.n_members[0] < 2.4 and r.n_band[1] > r.n_band[0] >= 1
    assert np.all(r.band_km[:, 0] <= r.band_km[:, 1])
    # the finer walk's band reaches at least as far: its listed span is not narrower (to 1 km)
    assert r.band_km[1, 0] <= r.band_km[0, 0] + 1 and r.band_km[1, 1] >= r.band_km[0, 1] - 1
    # the orbits used downstream are found by root finding: independent of the step, and inside the band
    assert np.ptp(r.outer_perilune_km) < 1e-6 and np.ptp(r.stable_perilune_km) < 1e-6
    assert r.band_km[1, 0] < r.outer_perilune_km[1] < r.band_km[1, 1]
    with pytest.raises(ValueError, match="steps"):
        ex.exercise_01_halo_step(steps=(0.03,))


def test_01_site_grid_finer_grids_never_do_worse_and_never_suffice():
    r = ex.exercise_01_site_grid(grids_deg=((20.0, 40.0), (10.0, 20.0)), samples=400)
    _frozen_with_answer_0109(r)
    assert r.n_sites[1] > r.n_sites[0]
    # nested grids: the finer grid holds every coarse pair, so its best pair is at least as good
    assert r.best_fraction[1] >= r.best_fraction[0] - 1e-12
    assert np.all(r.best_fine_fraction >= r.best_fraction - 1e-12)  # the refinement contains the best pair too
    assert np.all(r.n_full_pairs == 0) and np.all(r.best_fine_fraction < 1)
    with pytest.raises(ValueError, match="grids_deg"):
        ex.exercise_01_site_grid(grids_deg=((10.0, 20.0), (20.0, 40.0)))


def test_09_angle_noise_scales_the_final_uncertainty():
    r = ex.exercise_09_angle_noise(noise_urad=(10.0, 100.0), n_runs=3)
    _frozen_with_answer_0109(r)
    ratio = r.final_3sigma_km[1] / r.final_3sigma_km[0]
    assert 0.6 * 10 < ratio <= 10 * 1.05  # nearly proportional to the noise, not more
    assert np.all(r.diverged <= 0.5)  # noise alone does not make the filter diverge


def test_09_cadence_denser_tracking_shrinks_the_uncertainty_with_diminishing_returns():
    r = ex.exercise_09_cadence(cadences_h=(12.0, 2.0), n_runs=3)
    _frozen_with_answer_0109(r)
    assert r.n_measurements[1] > 5 * r.n_measurements[0] - 5
    gain = r.final_3sigma_km[0] / r.final_3sigma_km[1]
    assert 1.2 < gain <= np.sqrt(r.n_measurements[1] / r.n_measurements[0]) * 1.05


def test_09_handoff_wide_priors_diverge_while_the_covariance_forgets_them():
    r = ex.exercise_09_handoff(scales=(1.0, 300.0), n_runs=4)
    _frozen_with_answer_0109(r)
    assert r.diverged[0] <= 0.25 and r.diverged[1] >= 0.5
    assert abs(r.final_3sigma_km[1] / r.final_3sigma_km[0] - 1) < 0.1


def test_exercise_parameters_are_refused_by_name():
    """Every exercise checks its parameters before any run."""
    for fn, kwargs, name in ((ex.exercise_09b_burn_size, dict(seed=-1), "seed"),
                             (ex.exercise_09b_base_weight, dict(seed="a"), "seed"),
                             (ex.exercise_10_window_factor, dict(seed=1.5), "seed"),
                             (ex.exercise_10_pm_j_noise, dict(seed=None), "seed"),
                             (ex.exercise_09_angle_noise, dict(seed=True), "seed"),
                             (ex.exercise_09_cadence, dict(cadences_h=None), "cadences_h"),
                             (ex.exercise_09_cadence, dict(cadences_h=(2.0, 12.0)), "cadences_h"),  # sparse first
                             (ex.exercise_09_handoff, dict(scales=(300.0, 1.0)), "scales"),
                             (ex.exercise_01_halo_step, dict(steps=None), "steps"),
                             (ex.exercise_01_halo_step, dict(steps=(0.015, 0.03)), "steps"),  # coarse first
                             (ex.exercise_01_site_grid, dict(grids_deg=((40.0, 80.0), (30.0, 60.0))), "grids_deg"),
                             (ex.exercise_01_site_grid, dict(grids_deg=(20.0, 40.0)), "grids_deg")):
        with pytest.raises((ValueError, TypeError), match=name):
            fn(**kwargs)
