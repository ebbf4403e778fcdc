"""The worked solutions of notebooks 11 and 12: each checks the claim its answer makes."""

import numpy as np
import pytest

from cislunar.papers.nychka_bhattacharya import exercises as ex


def test_exercise_11_gamma_kappa_scales_like_one_over_gamma():
    r = ex.exercise_11_gamma(factor=2.0)
    assert r.gammas == pytest.approx((0.0013, 0.0026))
    for n in ("h2", "hinf"):
        # kappa * gamma nearly constant (slope -1 of the trade curve); the allowance grows with gamma
        assert r.kappa_ratio[n] == pytest.approx(0.5, rel=0.05)
        assert r.noise_deg[n][1] > 1.9 * r.noise_deg[n][0]
    assert "1/2" in r.answer
    with pytest.raises(ValueError):
        ex.exercise_11_gamma(factor=-1.0)


def test_exercise_11_orbit_allowance_follows_the_apogee():
    r = ex.exercise_11_orbit((3, 1, 0.3))
    # a smaller apogee allows more noise; each allowance sits just below asin(gamma / max r13)
    assert r.r13_max[1] < r.r13_max[0]
    assert r.hinf_deg[1] > r.hinf_deg[0]
    for a, lim in zip(r.hinf_deg, r.limit_deg):
        assert 0.95 * lim < a <= lim * (1 + 1e-6)
    assert np.degrees(np.arcsin(0.0013 / r.r13_max[1])) == pytest.approx(r.limit_deg[1])
    assert "smaller apogee relaxes" in r.answer


def test_exercise_11_bandwidth_lower_bound_costs_precision():
    r = ex.exercise_11_bandwidth(200.0)
    assert r.radii == (1000.0, 200.0)
    assert r.gain_norm[1] < r.gain_norm[0]
    assert r.hinf_deg[1] < r.hinf_deg[0] <= r.limit_deg * (1 + 1e-6)


def test_exercise_12_noise_error_scales_with_the_noise():
    r = ex.exercise_12_noise(factor=2.0)
    assert r.bound_km[1] == pytest.approx(2.0 * r.bound_km[0], rel=1e-9)  # linear guarantee
    assert r.ratio == pytest.approx(2.0, rel=0.15)
    assert r.rms_km[1] > r.rms_km[0]


def test_exercise_12_initial_error_smaller_start_converges_sooner():
    r = ex.exercise_12_initial_error(scale=0.1)
    assert r.initial_error_km[1] == pytest.approx(0.1 * r.initial_error_km[0], rel=1e-9)
    assert np.all(np.isfinite(r.first))
    assert r.first[1] < r.first[0]
    assert r.decay > 0 and r.predicted_shift == pytest.approx(np.log(10.0) / r.decay)
    with pytest.raises(ValueError):
        ex.exercise_12_initial_error(scale=1.5)


def test_exercise_12_interval_h2_per_sample_grows_hinf_unchanged():
    r = ex.exercise_12_interval(factor=0.5)
    assert r.dt == pytest.approx((0.004, 0.002))
    assert r.h2_per_sample_deg[1] / r.h2_per_sample_deg[0] == pytest.approx(np.sqrt(2.0), rel=0.01)
    assert r.h2_bound_km[1] / r.h2_bound_km[0] == pytest.approx(1 / np.sqrt(2.0), rel=1e-9)
    assert r.hinf_deg[0] == r.hinf_deg[1]
