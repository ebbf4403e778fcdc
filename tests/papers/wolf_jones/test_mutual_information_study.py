"""Notebook 02's studies: the scalar worked example against its closed form, the stacked toy window, the CRLB
decomposition and the gradient on a short test-case-2 window, the baseline summaries and the timing crossover."""

import numpy as np
import pytest

from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.papers.wolf_jones import mutual_information_study as S
from cislunar.papers.wolf_jones import scenarios as wj
from cislunar.sensing import information as info


def test_scalar_example_agrees_with_its_closed_form():
    ex = S.scalar_worked_example(4000, np.random.default_rng(1), p=2.0, h=0.5, r=0.3)
    assert ex.closed == pytest.approx(0.5 * np.log(1 + 0.25 * 2.0 / 0.3))
    assert abs(ex.kl_mean - ex.closed) < 4 * ex.kl_se
    assert abs(ex.monte_carlo - ex.closed) < 4 * ex.monte_carlo_se
    assert ex.std_ratio == pytest.approx(np.exp(-ex.closed))  # posterior/prior std = exp(-I) for a scalar
    with pytest.raises(ValueError):
        S.scalar_worked_example(1, np.random.default_rng(0))


def test_toy_window_dense_equals_chain_rule():
    toy = S.constant_velocity_toy(dt=0.5, n_times=4)
    assert toy.F.shape == (3, 2, 2) and toy.H.shape == (4, 1, 2)
    assert np.all(np.linalg.eigvalsh(toy.Q[0]) > 0)
    total, terms = info.mutual_information(*toy.arrays, return_terms=True)
    assert info.mutual_information_dense(*toy.arrays) == pytest.approx(total, rel=1e-10)
    assert np.sum(terms) == pytest.approx(total) and terms[0] == max(terms)


@pytest.fixture(scope="module")
def short_window():
    P = S.reference_period(em)
    return S.case_2_window(em, t=P + np.arange(4) * float(em.days_to_tu(1.0)))


def test_the_window_is_notebook_06s(short_window):
    """Notebook 02's window is notebook 06's: the same P_ref (the corrected observer_t0 DRO, not observer_tf), the
    same measurement times, the observer at 06's ballistic window start, and Eq. 18 equal to 06's information model
    there (same P0, R, Q)."""
    sc = wj.test_case_2(em)
    assert S.reference_period(em) == sc.period
    assert em.tu_to_days(sc.period) - em.tu_to_days(S._period(em, S.OBSERVER_TF_X0)) > 0.1  # the old P_ref differed
    w = S.case_2_window(em)
    assert w.P_ref == sc.period and w.t[0] == pytest.approx(sc.window[0], abs=1e-12)
    np.testing.assert_allclose(w.t, sc.measurement_times, rtol=0, atol=1e-12)
    x_ws = sc.ballistic_guess(np.array([0.0, sc.window[0]]))[0][-1]
    np.testing.assert_allclose(w.start[0], x_ws, rtol=0, atol=1e-10)
    np.testing.assert_allclose(w.start[1:], sc.targets_at([sc.window[0]])[:, 0], rtol=0, atol=1e-10)
    mi_02 = info.mutual_information(*w.lin.arrays)
    assert mi_02 == pytest.approx(float(sc.information_model()(x_ws)), rel=1e-8)


def test_window_crlb_decomposes_and_matches_eq18(short_window):
    w = short_window
    assert w.start.shape == (4, 6) and w.lin.P0.shape == (24, 24) and len(w.target_periods_d) == 3
    assert w.days[0] == pytest.approx(em.tu_to_days(w.P_ref))
    c = S.window_crlb(w)
    assert c.total.shape == (4, 4)
    assert c.relative_difference < 1e-6 and np.sum(c.gains) == pytest.approx(c.mi_chain)
    # position variance = in-plane + out-of-plane variance, and the update never raises the variance
    assert np.allclose(c.total**2, c.in_plane**2 + c.out_of_plane**2)
    assert np.all(c.total <= c.prior * (1 + 1e-12))
    # planar DROs: range and range rate do not see z
    assert c.largest_z_jacobian < 1e-12 and 0 < c.out_of_plane_share <= 1


def test_gradient_matches_finite_differences(short_window):
    g = S.gradient_check(short_window, step=1e-6)
    assert g.error < 1e-5
    assert g.value == pytest.approx(S.observer_information(short_window, short_window.start[0]), rel=1e-9)
    lc = S.linearisation_check(short_window, g, steps_km=[1.0, 100.0])
    # Eq. 44 is first order: the error grows faster than the step
    assert lc.error[1] / lc.error[0] > 100.0
    assert np.allclose(np.linalg.norm(lc.dx, axis=1), em.km_to_lu(np.array([1.0, 100.0])))


def test_baseline_curve_summaries():
    c = S.BaselineCurve("x", np.array([1.0, 2.0, 3.0]), np.array([1.0, 3.0, 2.0]), np.array([5.0, 2.0, 4.0]),
                        np.array([5.0, 2.0, 3.0]), np.array([3.0, 1.0, 2.0]), np.array([4.0, 1.0, 3.0]),
                        np.array([4.0, 1.0, 3.0]), 10.0)
    assert c.gain == 2.0 and c.peak_km == 20.0 and c.best == 1 and c.same_peak
    assert c.rms_drop == 4.0 and c.rebound == 3.0 and c.mi_drop == 1.0
    assert c.observer_above_target_km == ["30"]
    # the MI rises then falls, the RMS falls then rises: the first step improves, the second does not
    assert c.step_improves.tolist() == [True, False] and c.improving_until == 1 and c.end_to_end_drop == pytest.approx(4 / 3)
    assert not c.improves_throughout(1.5)


def _curve(mi, obs_xy):
    n = len(mi)
    ones = np.ones(n)
    return S.BaselineCurve("x", np.arange(1.0, n + 1), np.array(mi, float), ones, ones, ones,
                           np.array(obs_xy, float), ones, 1.0)


def test_baseline_judged_over_the_whole_range():
    """Every step must raise the MI and lower the in-plane RMS; a turn at the longest baseline fails however small
    (the old test judged the MI up to its peak and allowed a rebound), and the end-to-end drop must exceed min_drop."""
    up = _curve([1.0, 2.0, 3.0, 4.0], [8.0, 4.0, 2.0, 1.0])
    assert up.improves_throughout(1.5) and up.improving_until == 3 and up.end_to_end_drop == 8.0
    assert not up.improves_throughout(10.0)  # improves at every step, but by less than asked end to end
    mi_turns = _curve([1.0, 2.0, 3.0, 2.99], [8.0, 4.0, 2.0, 1.0])  # the MI alone falls at the last step
    assert not mi_turns.improves_throughout(1.5) and mi_turns.improving_until == 2
    rms_turns = _curve([1.0, 2.0, 3.0, 4.0], [8.0, 4.0, 2.0, 2.1])  # the RMS alone rises (1.05x) at the last step
    assert not rms_turns.improves_throughout(1.5) and rms_turns.improving_until == 2
    flat = _curve([1.0, 2.0, 2.0, 4.0], [8.0, 4.0, 2.0, 1.0])  # no gain in one step is no improvement
    assert not flat.improves_throughout(1.5) and flat.improving_until == 1


def test_crossover_interpolates_on_log_axes():
    assert S.crossover([4, 16], [0.5, 2.0]) == "N = 8 (between 4 and 16)"
    assert S.crossover([4, 16], [1.2, 2.0]) == "at or below N = 4"
    assert S.crossover([4, 16], [0.2, 0.5]) == "above N = 16 (not reached)"
    with pytest.raises(ValueError):
        S.crossover([4], [0.5, 2.0])
    t = S.TimingStudy((4, 16), (info.TimingResult(1.0, 2.0, 1.0, 1.0), info.TimingResult(4.0, 2.0, 3.0, 1.0)))
    assert t.at(16).ratio_value == 2.0 and t.crossover_value == "N = 8 (between 4 and 16)"
    assert t.crossover_gradient == "at or below N = 4"


def test_range_noise_enters_the_window(short_window):
    w = S.case_2_window(em, t=short_window.t, range_sigma_km=0.05)
    assert w.R[0, 0] == pytest.approx(0.25 * short_window.R[0, 0]) and w.R[1, 1] == short_window.R[1, 1]
    assert info.window_information(w.lin) > info.window_information(short_window.lin)  # less noise, more MI
    with pytest.raises(ValueError):
        S.case_2_window(em, t=short_window.t, range_sigma_km=0.0)


def test_baseline_study_is_the_same_through_an_executor(short_window):
    from concurrent.futures import ThreadPoolExecutor

    serial = S.baseline_study(short_window, 2, min_phase=0.01, max_phase=0.1)
    with ThreadPoolExecutor(2) as pool:
        pooled = S.baseline_study(short_window, 2, min_phase=0.01, max_phase=0.1, executor=pool)
    assert [c.name for c in serial] == ["relative position (100 m)", "range + range rate"]
    for a, b in zip(serial, pooled):
        assert np.array_equal(a.mi, b.mi) and np.array_equal(a.obs_xy, b.obs_xy)
        assert a.baseline[1] > a.baseline[0] > 0  # a longer lead, a longer baseline
        # the in-plane and out-of-plane parts make up the observer's total terminal RMS
        assert np.all(a.obs_xy <= a.obs * (1 + 1e-12)) and np.all(a.obs_z <= a.obs * (1 + 1e-12))
    with pytest.raises(ValueError):
        S.baseline_study(short_window, 2, min_phase=0.2, max_phase=0.1)


def test_eq18_precision_passes_the_chain_rule_and_fails_a_wrong_recursion():
    """The chain rule agrees with Eq. 18 in extended precision within the dense form's round-off scale; a recursion
    with the process noise doubled, or one measurement dropped, misses it by far more."""
    toy = S.constant_velocity_toy(dt=0.5, n_times=4)
    P0, F, Q, H, R = toy.arrays
    ref = S.Eq18Precision.of(P0, F, Q, H, R)
    assert ref.size == 4 and ref.condition >= 1 and ref.extended_eps <= np.finfo(float).eps
    eps = np.finfo(float).eps
    assert ref.bound == pytest.approx(0.5 * ref.size * (eps / 2) * np.linalg.cond(
        (lambda Pt, Ht, Rt: Ht @ Pt @ Ht.T + Rt)(*info.stacked_matrices(P0, F, Q, H, R))), rel=1e-6)
    assert ref.reference == pytest.approx(info.mutual_information_dense(P0, F, Q, H, R), rel=1e-12)
    assert ref.ratio(info.mutual_information(P0, F, Q, H, R)) <= 1.0  # passes
    assert ref.ratio(info.mutual_information(P0, F, 2 * Q, H, R)) > 1.0  # wrong process noise fails
    assert ref.ratio(info.mutual_information(P0, F[:-1], Q[:-1], H[:-1], R[:-1])) > 1.0  # a dropped measurement
    with pytest.raises(TypeError):
        ref.ratio("1.0")


def test_eq18_precision_bounds_the_dense_round_off_on_an_ill_conditioned_window():
    """Measurements far more precise than the prior make S~ ill-conditioned: the float64 dense form then drifts
    from the extended-precision reference, within the stated round-off scale, while the chain rule stays closer."""
    toy = S.constant_velocity_toy(dt=1.0, n_times=6, psd=1e-6, r=1e-14)
    P0, F, Q, H, R = toy.arrays
    P0 = P0 * 1e6
    ref = S.Eq18Precision.of(P0, F, Q, H, R)
    assert ref.condition > 1e12
    if np.finfo(np.longdouble).eps < np.finfo(float).eps:  # a real extended precision on this platform
        chain = info.mutual_information(P0, F, Q, H, R)
        assert ref.ratio(ref.dense) <= 1.0 and ref.ratio(chain) <= 1.0
        assert abs(ref.dense - ref.reference) > 10 * abs(chain - ref.reference)  # the dense form is the one off


def test_case1_readings_growth_judges_the_fig4_statement():
    """Window end over the 2nd measurement, largest over the objects: at most 1 is bounded."""
    assert S.Case1Readings.growth_of([[100.0, 50.0, 40.0], [90.0, 60.0, 30.0]]) == pytest.approx(0.8)  # bounded
    assert S.Case1Readings.growth_of([[100.0, 50.0, 40.0], [90.0, 60.0, 66.0]]) == pytest.approx(1.1)  # one grows
    with pytest.raises(ValueError):
        S.Case1Readings.growth_of([[1.0], [2.0]])
    r = S.Case1Readings.of(em)
    assert r.rms_km.shape[:2] == (len(wj.PROCESS_NOISE_READINGS_KM2_S3), 2) and "adopted" in r.labels[r.adopted]
    from cislunar.sensing import covariance as cov
    assert cov.psd_to_nondimensional(r.q_km2_s3[r.adopted], em) == pytest.approx(wj.PROCESS_NOISE_PSD_ND, rel=1e-12)
    literal = r.labels.index(next(k for k in r.labels if r.q_km2_s3[r.labels.index(k)] == 1e-11))
    assert r.growth[literal] > 1.0 >= r.growth[r.adopted]  # the literal reading grows, the adopted one is bounded
    # more process noise, more growth: the readings in order of q give growths in the same order
    order = np.argsort(r.q_km2_s3)
    assert np.all(np.diff(r.growth[order]) > 0)
