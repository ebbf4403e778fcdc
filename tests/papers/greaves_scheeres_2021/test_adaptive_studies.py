"""Studies of notebook 09b on small sizes: outcome bookkeeping, the reset-rule summaries, the null metric law and
the closing rows judged by the declared claims."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from cislunar.cr3bp import orbits
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.estimation import adaptive_ocbe as ad
from cislunar.papers.greaves_scheeres_2021 import adaptive_studies as ads
from cislunar.papers.greaves_scheeres_2021 import detection as det
from cislunar.papers.greaves_scheeres_2021.claims.adaptive_ocbe import CLAIMS


@pytest.fixture(scope="module")
def nrho():
    return orbits.nrho_9_2(em)


@pytest.fixture(scope="module")
def setup(nrho):
    return det.make_setup(em, nrho, 1e-18, 1e-18)


def test_first_seen_epoch_is_the_first_epoch_after_the_burn(setup):
    k = ads.first_seen_epoch(setup)
    t = setup.scenario.t
    assert t[k - 1] <= setup.t_maneuver < t[k]


def test_delay_outcomes_partition_the_runs(setup, nrho):
    k = ads.first_seen_epoch(setup)
    t = setup.scenario.t
    late_from = setup.t_maneuver + 0.75 * (nrho.period - setup.t_maneuver)
    k_late = int(np.searchsorted(t, late_from))
    # prompt (on time, one early, two late), late, nearly periapsis, not detected, false alarm
    epochs = [k, k - 1, k + 2, k + 5, k_late, -1, 3]
    o = ads.delay_outcome(setup, epochs, late_from)
    assert o.n == 7
    assert o.prompt == pytest.approx(3 / 7) and o.late == pytest.approx(1 / 7)
    assert o.near == pytest.approx(1 / 7) and o.undetected == pytest.approx(1 / 7)
    assert o.false_alarms == 1 and o.early_by_chance == 1
    # every run is in exactly one outcome or a false alarm
    assert o.prompt + o.late + o.near + o.undetected + o.false_alarms / o.n == pytest.approx(1.0)
    assert sorted(o.delays_h) == sorted(np.array([0, -1, 2, 5, k_late - k]) * setup.scenario.cadence_hours)
    assert o.median_h == pytest.approx(2 * setup.scenario.cadence_hours)
    assert [o.fraction(x) for x in ads.OUTCOMES] == [o.prompt, o.late, o.near, o.undetected]


def test_reset_rule_summary_counts_chains_and_reconvergence():
    runs = ((0.05, "mean", True, 0.5, True, 3, False), (0.05, "mean", False, 1.0, True, 0, False),
            (0.05, "likelihood", True, 0.0, False, 1, True), (0.05, "likelihood", False, 1.0, True, 0, False),
            (3.0, "mean", True, 0.0, False, 1, True), (3.0, "likelihood", True, 0.0, False, 1, True))
    study = ads.ResetRuleStudy(runs, (0.05, 3.0), ("mean", "likelihood"))
    s = study.summary(0.05, "mean")
    assert s["n"] == 2 and s["n_detected"] == 1 and s["inconsistent"] == 1.0 and s["chains"] == 1
    assert s["final_ok"] == 0.0 and s["resets"] == 1.5
    assert study.summary(0.05, "likelihood")["final_ok"] == 1.0
    assert study.chains("mean") == (1, 2) and study.chains("likelihood") == (0, 2)
    assert study.pooled_inconsistent((0.05, 3.0), "mean") == (pytest.approx(2 / 3), 3)
    assert "agree at 3000 mm/s" in study.report()
    with pytest.raises(ValueError, match="no runs"):
        study.summary(1.0, "mean")


def test_null_metric_has_the_chi2_mean_and_no_false_resets(setup):
    null = ads.null_metric_study(setup, 2, np.random.default_rng(0))
    assert null.dof == 4 and null.n_runs == 2 and null.n_resets == 0
    # chi2_4: mean 4, within 4 standard errors
    assert abs(null.metric.mean() - 4.0) < 4 * null.standard_error
    assert null.exceed_fraction < 0.05
    spread = ads.measurement_spread(setup, null.first.P0)
    assert spread.shape == (4,) and np.all(spread > 0)
    assert spread[2:].max() < 1e-2 < spread[:2].min()  # rates carry almost no state information here


def test_large_burn_run_and_closing_rows_are_judged_by_every_claim(setup, nrho):
    rng = np.random.default_rng(1)
    big = ads.adaptive_run(setup, det.draw_trial(rng, setup, magnitude_m_s=3.0))
    assert big.detections and big.delay_epochs is not None and abs(big.delay_epochs) <= ad.CONSECUTIVE_EPOCHS - 1
    assert big.panels is not None and 0.0 <= big.nees_f_after <= 1.0
    null = ads.NullMetricStudy(np.full(10, 4.0), 4, 0.5, 0.0, 0, np.full((1, 5), 6.0), big.inputs)
    k = ads.first_seen_epoch(setup)
    delays = ads.DelayStudy({0.05: ads.delay_outcome(setup, [-1, k + 20], 0.0),
                             3.0: ads.delay_outcome(setup, [k, k], 0.0)},
                            {10: ads.delay_outcome(setup, [-1, k + 20], 0.0)}, 90.0, 70.0, 2)
    rules = ads.ResetRuleStudy(((0.05, "mean", False, 1.0, True, 0, False), (0.05, "likelihood", False, 1.0, True, 0,
                                                                             False),
                                (3.0, "mean", True, 0.0, False, 1, True), (3.0, "likelihood", True, 0.0, False, 1, True)),
                               (0.05, 3.0), ("mean", "likelihood"))
    rows = ads.closing_rows(null, big, delays, rules, 1e-18)
    assert set(rows) == set(CLAIMS) - set(ads.VARIANT_ROW_KEYS)  # variant_rows measures the others
    status = {key: CLAIMS[key].judge(**row).status for key, row in rows.items()}
    assert status["3 m/s prompt"] == "reproduced" and status["large prompt"] == "reproduced"
    assert status["large consistent"] == "reproduced" and status["no false resets"] == "derived"
    assert status["small late"] == "reproduced"  # no prompt run
    assert status["small re-converges"] == "differs"  # no detected run counts as 0
    assert status["base weight"] == "not in paper"
    # the one-run figures are judged as plausible draws among the studies' runs, not on our one draw: half of the
    # 50 mm/s runs detected nearly at periapsis (late_from 0 puts every detection there) is a plausible draw
    assert rows["small nearly periapsis"]["measured"] == 0.5
    assert status["small nearly periapsis"] == "consistent (tuned)"
    assert status["3 m/s consistent"] == "consistent (tuned)" and big.nees_f_after <= 0.05
    # the same favourable draw with every 3 m/s run of the studies late and inconsistent, and the 50 mm/s runs
    # detected before the 'nearly periapsis' stretch, differs
    never = float(setup.scenario.t[-1]) + 1.0
    late = dataclasses.replace(delays, by_size={0.05: ads.delay_outcome(setup, [-1, k + 20], never),
                                                3.0: ads.delay_outcome(setup, [k + 10, k + 10], 0.0)})
    bad = ads.ResetRuleStudy(rules.runs[:2] + ((3.0, "mean", True, 0.0, True, 1, True),) + rules.runs[3:],
                             rules.magnitudes_m_s, rules.rules)
    rows = ads.closing_rows(null, big, late, bad, 1e-18)
    assert CLAIMS["3 m/s consistent"].judge(**rows["3 m/s consistent"]).status == "differs"
    assert CLAIMS["3 m/s prompt"].judge(**rows["3 m/s prompt"]).status == "differs"
    assert rows["small nearly periapsis"]["measured"] == 0.0
    assert CLAIMS["small nearly periapsis"].judge(**rows["small nearly periapsis"]).status == "differs"
    assert "the Fig. 6 draw: 0 % of its epochs" in rows["3 m/s consistent"]["shown"]


def test_one_run_figures_are_plausible_draws_at_one_run_in_ten(setup, nrho):
    """The re-convergence row counts the detected 50 mm/s runs of the reset-rule study that end consistent: one of
    ten passes the 10 % floor (not typical), none of ten fails; likewise the Fig. 6 consistency row."""
    k = ads.first_seen_epoch(setup)
    big = ads.adaptive_run(setup, det.draw_trial(np.random.default_rng(1), setup, magnitude_m_s=3.0))
    null = ads.NullMetricStudy(np.full(10, 4.0), 4, 0.5, 0.0, 0, np.full((1, 5), 6.0), big.inputs)
    delays = ads.DelayStudy({0.05: ads.delay_outcome(setup, [-1, k + 20], 0.0),
                             3.0: ads.delay_outcome(setup, [k, k], 0.0)},
                            {10: ads.delay_outcome(setup, [-1, k + 20], 0.0)}, 90.0, 70.0, 2)

    def study(n_ok):
        small = [(0.05, rule, True, 1.0, True, 1, i < n_ok) for i in range(10) for rule in ("mean", "likelihood")]
        top = [(3.0, rule, True, 0.0, i >= n_ok, 1, True) for i in range(10) for rule in ("mean", "likelihood")]
        return ads.ResetRuleStudy(tuple(small + top), (0.05, 3.0), ("mean", "likelihood"))

    for n_ok, want in ((1, "consistent (tuned)"), (0, "differs")):
        rows = ads.closing_rows(null, big, delays, study(n_ok), 1e-18)
        assert rows["small re-converges"]["measured"] == pytest.approx(n_ok / 10)
        assert rows["3 m/s consistent"]["measured"] == pytest.approx(n_ok / 10)
        for key in ("small re-converges", "3 m/s consistent"):
            assert CLAIMS[key].judge(**rows[key]).status == want
    assert "not typical" in rows["small re-converges"]["shown"]
    rows = ads.closing_rows(null, big, delays, study(6), 1e-18)
    assert "(typical;" in rows["small re-converges"]["shown"]


def test_delay_study_draws_first_and_gives_the_same_outcomes_on_any_executor(setup, nrho):
    from concurrent.futures import ThreadPoolExecutor  # noqa: PLC0415 - a thread pool is enough to check the order

    mags, noise = (0.05, 3.0), (5.0, 10.0)
    serial = ads.delay_study(setup, nrho, mags, noise, 3, np.random.default_rng(4))
    with ThreadPoolExecutor(2) as pool:
        pooled = ads.delay_study(setup, nrho, mags, noise, 3, np.random.default_rng(4), executor=pool)
    # the draws are the sequential ones of the study before it had an executor: sizes first, then noise levels
    rng = np.random.default_rng(4)
    ep = [ads.first_detection_epochs(setup, m, 3, rng) for m in mags]
    s5 = det.make_setup(em, nrho, 1e-18, 1e-18, sigma_angle_rad=5e-6)
    ep5 = ads.first_detection_epochs(s5, 0.05, 3, rng)
    late_from = setup.t_maneuver + 0.75 * (nrho.period - setup.t_maneuver)
    for study in (serial, pooled):
        for m, e in zip(mags, ep):
            want = ads.delay_outcome(setup, e, late_from)
            got = study.by_size[m]
            assert (got.prompt, got.late, got.near, got.undetected) == (want.prompt, want.late, want.near,
                                                                        want.undetected)
            np.testing.assert_array_equal(got.delays_h, want.delays_h)
        np.testing.assert_array_equal(study.by_noise[5.0].delays_h, ads.delay_outcome(s5, ep5, late_from).delays_h)
        assert study.by_noise[10.0] is study.by_size[0.05]  # the default noise reuses the size sweep's runs
        assert study.by_size[3.0].prompt == 1.0


def test_reset_rule_study_is_the_same_on_any_executor(setup):
    from concurrent.futures import ThreadPoolExecutor  # noqa: PLC0415

    serial = ads.reset_rule_study(setup, (3.0,), 2, np.random.default_rng(5))
    with ThreadPoolExecutor(2) as pool:
        pooled = ads.reset_rule_study(setup, (3.0,), 2, np.random.default_rng(5), executor=pool)
    assert serial.runs == pooled.runs and len(serial.runs) == 2 * len(ad.RESET_RULES)
    # rows in the order of the draws, every rule on each drawn run
    assert [r[1] for r in serial.runs] == list(ad.RESET_RULES) * 2
    with pytest.raises(ValueError, match="max_resets"):
        ads.reset_rule_study(setup, (3.0,), 1, np.random.default_rng(5), max_resets=0)


def test_study_arguments_are_refused_by_name_before_any_run(setup, nrho):
    rng = np.random.default_rng(0)
    k = ads.first_seen_epoch(setup)
    with pytest.raises(ValueError, match="epochs"):
        ads.delay_outcome(setup, [k + 0.5], 0.0)  # an epoch index is an integer
    with pytest.raises(ValueError, match="epochs"):
        ads.delay_outcome(setup, [], 0.0)  # no run: the fractions would be NaN
    with pytest.raises(ValueError, match="epochs"):
        ads.delay_outcome(setup, [-2], 0.0)  # -1 is the only "none"
    inputs = det.draw_trial(np.random.default_rng(1), setup, magnitude_m_s=3.0)
    for kw, name in ((dict(reset="median"), "reset"), (dict(smooth="yes"), "smooth"), (dict(max_resets=-1),
                                                                                         "max_resets")):
        with pytest.raises(ValueError, match=name):
            ads.adaptive_run(setup, inputs, **kw)
    for args, name in (((nrho, [0.05, -1.0], (10.0,)), "magnitudes_m_s"), ((nrho, [], (10.0,)), "magnitudes_m_s"),
                       ((nrho, [0.05], ()), "noise_urad"), ((nrho, [0.05], (0.0,)), "noise_urad"),
                       (("nrho", [0.05], (10.0,)), "orbit")):
        with pytest.raises(ValueError, match=name):
            ads.delay_study(setup, *args, 1, rng)
    with pytest.raises(TypeError, match="executor"):
        ads.delay_study(setup, nrho, [0.05], (10.0,), 1, rng, executor=object())
    with pytest.raises(TypeError, match="executor"):
        ads.reset_rule_study(setup, (3.0,), 1, rng, executor="pool")
    with pytest.raises(ValueError, match="n_runs"):
        ads.first_detection_epochs(setup, 0.05, 0, rng)
    with pytest.raises(ValueError, match="magnitude_m_s"):
        ads.first_detection_epochs(setup, -0.05, 1, rng)
    # none of these drew from the generator: the checks come before the draws
    assert rng.bit_generator.state == np.random.default_rng(0).bit_generator.state


def test_batched_reset_rule_rows_equal_the_single_trial_rows(setup):
    """The reset-rule study's batched task gives, run by run and rule by rule, the row of the single-trial adaptive
    filter (its reference), including a run that fails (more resets than allowed)."""
    rng = np.random.default_rng(3)
    runs = [(m, det.draw_trial(rng, setup, magnitude_m_s=m)) for m in (3.0, 3.0, 0.3, 0.05)]
    for max_resets in (0, 5):  # 0: every detected run fails its first reset (a failed row)
        batched = ads._reset_rule_batch((setup, runs, max_resets))
        single = [row for m, d in runs for row in ads._reset_rule_runs((setup, m, d, max_resets))]
        assert batched == single
        assert [r[:2] for r in batched] == [(m, rule) for m, _ in runs for rule in ad.RESET_RULES]
        assert sum(r[5] == max_resets + 1 for r in batched) == (6 if max_resets == 0 else 0)
        assert any(not r[2] for r in batched)  # the 50 mm/s run is not detected


# ---------------------------------------------------------------------------------------------------------------
# Measurement sets, the state-covariance reset and the e^-2 prediction run by run
# ---------------------------------------------------------------------------------------------------------------
def test_measurement_sets_share_the_truth_and_the_noise_draws(setup):
    """Angles only drops the rates; 1-TU rates keep the rates' standard-normal draws, rescaled to sqrt(2) sigma per
    TU (a factor TU_s smaller than the 1-s rates' noise); the rate-noise floor is the squared whitened 1-s rate
    noise (a chi2_2 draw: mean 2 over many epochs)."""
    inp = det.draw_trial(np.random.default_rng(2), setup, magnitude_m_s=0.3)
    sc = setup.scenario
    h = sc.model(setup.observer_states, inp.truth)
    ang = ads.variant_data(setup, inp, "angles only")
    np.testing.assert_array_equal(ang, inp.y[:, :2])
    assert ads.variant_setup(setup, "angles only").scenario.model.dim == 2
    tu = ads.variant_setup(setup, "rates 1 TU")
    R1, R = np.diag(tu.scenario.meas_cov), np.diag(sc.meas_cov)
    np.testing.assert_allclose(R1[2:] * em.time_unit_s**2, R[2:], rtol=1e-12)
    np.testing.assert_allclose(R1[2:], 2 * R[0], rtol=1e-12)
    y1 = ads.variant_data(setup, inp, "rates 1 TU")
    np.testing.assert_array_equal(y1[:, :2], inp.y[:, :2])
    np.testing.assert_allclose((y1[:, 2:] - h[:, 2:]) / np.sqrt(R1[2:]), (inp.y[:, 2:] - h[:, 2:]) / np.sqrt(R[2:]),
                               rtol=1e-6)
    floors = np.array([ads.rate_noise_floor(setup, inp, k) for k in range(sc.t.size)])
    z = (inp.y[:, 2:] - h[:, 2:]) / np.sqrt(R[2:])
    np.testing.assert_allclose(floors, np.sum(z**2, axis=1), rtol=1e-12)
    assert abs(floors.mean() - 2.0) < 4 * np.sqrt(4.0 / floors.size)
    assert ads.variant_setup(setup, "rates 1 s") is setup
    with pytest.raises(ValueError, match="measurement_set"):
        ads.variant_setup(setup, "rates 1 min")
    with pytest.raises(ValueError, match="epoch"):
        ads.rate_noise_floor(setup, inp, sc.t.size)


def _vr(ms, rule, first, resets, floor=np.nan, mag=3.0, inconsistent=False, final_ok=True):
    return ads.VariantRun(ms, mag, rule, first, resets, inconsistent, final_ok, False, floor)


def test_variant_summaries_and_the_e2_test_count_runs_by_hand():
    """Hand-made runs: the chain rate, delays and the run-by-run agreement of 'rate noise above 4' with 'chain'."""
    runs = (_vr("rates 1 s", "mean", 40, 1, 1.0), _vr("rates 1 s", "mean", 40, 3, 6.0),
            _vr("rates 1 s", "mean", 41, 2, 3.0, final_ok=False), _vr("rates 1 s", "mean", -1, 0),
            _vr("angles only", "mean", 42, 1, inconsistent=True))
    v = ads.VariantStudy(runs, (3.0,), 40, 2.0)
    s = v.summary("rates 1 s", "mean")
    assert (s["n"], s["n_detected"]) == (4, 3)
    assert s["resets_per_detection"] == pytest.approx(2.0) and s["chain"] == pytest.approx(2 / 3)
    assert s["median_delay_h"] == 0.0 and s["prompt"] == pytest.approx(0.75)
    assert s["reconverged"] == pytest.approx(2 / 3)
    assert v.summary("angles only", "mean")["median_delay_h"] == 4.0
    e2 = v.e2_test()
    assert (e2["n"], e2["n_over"], e2["n_chain"]) == (3, 1, 2)
    assert e2["agreement"] == pytest.approx(2 / 3)  # the floor-3 chain is the one disagreement
    assert e2["chain_given_over"] == 1.0 and e2["chain_given_under"] == pytest.approx(0.5)
    with pytest.raises(ValueError, match="no runs"):
        v.summary("rates 1 TU", "mean")


def test_variant_study_is_the_same_on_any_executor_and_its_rows_are_judged(setup):
    from concurrent.futures import ThreadPoolExecutor  # noqa: PLC0415

    serial = ads.variant_study(setup, (3.0,), 1, np.random.default_rng(5))
    with ThreadPoolExecutor(2) as pool:
        pooled = ads.variant_study(setup, (3.0,), 1, np.random.default_rng(5), executor=pool)
    same = (lambda x, y: x == y or (isinstance(x, float) and np.isnan(x) and np.isnan(y)))  # noqa: E731
    assert len(serial.runs) == len(pooled.runs) == len(ads.MEASUREMENT_SETS) * len(ads.VARIANT_RULES)
    for a, b in zip(serial.runs, pooled.runs):
        assert all(same(x, y) for x, y in zip(dataclasses.astuple(a), dataclasses.astuple(b)))
    assert [(r.measurement_set, r.rule) for r in serial.runs] == [
        (ms, rule) for ms in ads.MEASUREMENT_SETS for rule in ads.VARIANT_RULES]
    assert all(r.detected for r in serial.runs)  # a 3 m/s burn is seen by every measurement set
    assert len({r.first_epoch for r in serial.runs if r.measurement_set != "rates 1 TU"}) == 1
    inp = det.draw_trial(np.random.default_rng(11), setup, magnitude_m_s=0.05)
    fig8 = ads.fig8_variants(setup, inp)
    assert [(v.measurement_set, v.rule) for v in fig8] == [
        (ms, rule) for ms in ads.MEASUREMENT_SETS for rule in ad.ALL_RESET_RULES]
    assert len(ads.fig8_report(fig8).splitlines()) == len(fig8)
    rows = ads.variant_rows(serial, fig8)
    assert tuple(rows) == ads.VARIANT_ROW_KEYS
    for key, row in rows.items():
        assert CLAIMS[key].judge(**row).status
    with pytest.raises(TypeError, match="fig8"):
        ads.variant_rows(serial, [object()])
    with pytest.raises(TypeError, match="executor"):
        ads.variant_study(setup, (3.0,), 1, np.random.default_rng(5), executor="pool")
