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
