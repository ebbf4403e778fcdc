"""The worked solutions of the exercises of notebooks 07 and 08 say what their answers claim."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from cislunar.papers.greaves_scheeres_2023 import exercises as ex


def _frozen_with_answer(result):
    assert dataclasses.is_dataclass(result)
    with pytest.raises(dataclasses.FrozenInstanceError):
        result.answer = "changed"
    assert isinstance(result.answer, str) and len(result.answer) > 200


# ---------------------------------------------------------------------------------------------------------------
# Notebook 07
# ---------------------------------------------------------------------------------------------------------------
def test_07_burn_magnitude_moves_the_gain_not_the_axis():
    r = ex.exercise_07_burn_magnitude(dv_m_s=(0.1, 1.0, 2.0), coast_hours=12)
    _frozen_with_answer(r)
    # Eq. 24 has no upsilon: the same axis (up to sign) for every burn size
    assert np.all(r.axis_angle_deg < 1e-6)
    # the MMD burn helps, and more with a bigger burn
    assert np.all(r.mmd_km < r.none_km)
    assert np.all(np.diff(r.gain_percent) > 0)
    # roughly in proportion to the burn: doubling 1 -> 2 m/s roughly doubles the gain
    assert 1.5 < r.gain_percent[2] / r.gain_percent[1] < 2.5
    assert f"{r.none_km:.2f}" in r.answer


def test_07_burn_magnitude_refuses_bad_sizes():
    with pytest.raises(ValueError, match="dv_m_s"):
        ex.exercise_07_burn_magnitude(dv_m_s=(1.0, 0.1))


def test_07_tracking_arc_makes_mmd_nearly_optimal():
    r = ex.exercise_07_tracking_arc(arc_hours=24, coast_hours=(1, 4), n_grid=150)
    _frozen_with_answer(r)
    # MMD never beats the true minimiser (up to the minimiser's own tolerance)
    assert np.all(r.excess_start_percent > -0.5) and np.all(r.excess_arc_percent > -0.5)
    # at the start of tracking it misses the 5 % of the closing table; after a tracked arc it meets it
    assert r.excess_start_percent.max() > 5.0
    assert r.excess_arc_percent.max() < 5.0
    assert np.all(r.excess_arc_percent < r.excess_start_percent)
    # the kink of a burn inside a tracked arc is worth far more than the burn at the start
    assert np.all(r.optimum_arc_km < 0.1 * r.none_arc_km)
    assert np.all(r.optimum_start_km > 0.5 * r.none_start_km)


# ---------------------------------------------------------------------------------------------------------------
# Notebook 08
# ---------------------------------------------------------------------------------------------------------------
def test_07_sphere_resolution_moves_the_grid_numbers_not_the_minimiser():
    r = ex.exercise_07_sphere_resolution(n_grid=(100, 400), coast_hours=12)
    _frozen_with_answer(r)
    # Nelder-Mead makes the minimiser independent of the sphere (to 0.5 %), and never worse than the grid's best
    assert np.ptp(r.optimum_km) / r.optimum_km.min() < 0.005
    assert np.all(r.optimum_km <= r.grid_best_km + 1e-9)
    # the grid's spacing halves when the size quadruples; the surrogate check holds at both resolutions
    assert r.spacing_deg[1] == pytest.approx(r.spacing_deg[0] / 2)
    assert all(r.within_grid) and np.all(r.surrogate_angle_deg <= r.spacing_deg)


def test_08_ring_grid_moves_the_angle_reading_only():
    r = ex.exercise_08_ring_grid(n_ring=(10, 20, 40), arrival_hours=(0.0,))
    _frozen_with_answer(r)
    # angle reading: smaller burns and larger range uncertainty with every refinement
    assert np.all(np.diff(r.angle_fuel_m_s) < 0)
    assert np.all(np.diff(r.angle_sigma_m) > 0)
    assert r.angle_sigma_m[-1] > 3 * r.angle_sigma_m[0]
    # projection reading: settles (within 10 %) near the slice's best maneuver
    assert np.ptp(r.projection_sigma_m) / r.projection_sigma_m.min() < 0.10
    assert np.all(r.projection_sigma_m <= 1.2 * r.best_m)


def test_08_ring_grid_refuses_a_single_count():
    with pytest.raises(ValueError, match="n_ring"):
        ex.exercise_08_ring_grid(n_ring=(10,))


def test_08_execution_errors_set_the_range_error():
    r = ex.exercise_08_execution_errors(scales=(0.0, 0.1, 1.0, 10.0), n_trials=4)
    _frozen_with_answer(r)
    # perfect burns: the filter reaches the covariance analysis' level (within a factor 2 over 4 runs)
    assert 0.3 * r.predicted_m < r.rms_m[0] < 2.0 * r.predicted_m
    # the error grows with the execution error, about tenfold per decade once it dominates
    assert np.all(np.diff(r.rms_m) > 0)
    assert 4.0 < r.rms_m[2] / r.rms_m[1] < 25.0
    assert r.rms_m[1] > 5 * r.rms_m[0]
    # honest in range up to the nominal errors, overconfident at ten times them (error well above its sigma)
    ratio = r.rms_m / r.sigma_m
    assert np.all((ratio[:3] > 0.5) & (ratio[:3] < 1.5))
    assert ratio[3] > 1.8
    lo, hi = r.band
    assert 0 < lo < 12 < hi


def test_08_agent_phase_moves_the_projection_reading_out_of_the_valley():
    r = ex.exercise_08_agent_phase(agent_phases=(0.0, 0.25), n_ring=14, n_arrival=3)
    _frozen_with_answer(r)
    assert r.projection_percentile[0] < 25.0  # the valley (best quartile) for the baseline agent
    assert r.projection_percentile[1] >= 25.0  # out of it a quarter turn away
    assert np.all((0 <= r.angle_percentile) & (r.angle_percentile <= 100))


def test_exercises_refuse_bad_parameters_before_any_work():
    """Each parameter is checked up front (no torus or pair is built for a malformed request)."""
    with pytest.raises(ValueError, match="scales"):
        ex.exercise_08_execution_errors(scales=(0.0, 1.0))  # the answer compares the 2nd and 3rd scales
    with pytest.raises(ValueError, match="coast_hours"):
        ex.exercise_07_tracking_arc(coast_hours=(1, 100))  # beyond the pair's 72 h
    with pytest.raises(TypeError, match="n_grid"):
        ex.exercise_07_sphere_resolution(n_grid=None)
    with pytest.raises(ValueError, match="arrival_hours"):
        ex.exercise_08_ring_grid(arrival_hours=[np.nan])
