"""Notebook 12's set-ups (cislunar.papers.nychka_bhattacharya.observer_simulation) on a short run."""

import numpy as np
import pytest

from cislunar.papers.nychka_bhattacharya import observer_simulation as obs
from cislunar.papers.nychka_bhattacharya.claims.observer_simulation import CLAIMS
from cislunar.papers.nychka_bhattacharya.scenarios import paper_scenario


@pytest.fixture(scope="module")
def setup():
    sc = paper_scenario(n_samples=300)
    od = obs.observer_designs(sc, 3, np.random.default_rng(0))
    sim = obs.simulate_fig3(sc, od, 0.01, 0.2, 0.1, np.random.default_rng(1))
    return sc, od, sim


def test_first_and_rms_on_a_known_error_history():
    t = np.linspace(0.0, 1.0, 11)
    e = np.array([5.0, 4.0, 3.0, 0.5, 0.5, 2.0, 0.5, 0.5, 0.5, 0.5, 0.5])
    first, rms = obs.first_and_rms(t, e, 1.0, period=10.0)  # 2 % of the period = 0.2 TU after t = 0.3
    assert first == pytest.approx(0.3)
    assert rms == pytest.approx(np.sqrt(np.mean(e[t > 0.5] ** 2)))
    assert obs.first_and_rms(t, e, 0.1, period=10.0) == (np.inf, np.inf)


def test_designs_verified_and_runs_start_from_the_initial_error(setup):
    sc, od, sim = setup
    assert all(v.passed for v in od.verification.values())
    assert sim.initial_error == pytest.approx(0.02 * np.sqrt(2))
    assert set(sim.runs) == {"h2", "hinf", "ekf"} and set(sim.exact) == {"h2", "hinf"}
    for r in sim.runs.values():
        assert r.position_error[-1] < 0.5 * sim.initial_error  # every observer reduces the error


def test_convergence_study_and_line_crossings(setup):
    sc, od, sim = setup
    cv = obs.convergence_study(sc, od, sim, 0.1, e0_scales=(0.01, 1.0))
    # the guarantees follow lpv.guaranteed_error_rms: H2 scales with sqrt(dt)
    assert cv.bound["h2"] > 0 and cv.bound["hinf"] > 0
    assert cv.noise_rms_deg == pytest.approx(0.1, rel=0.3)
    assert all(v > 0 for v in cv.decay.values())
    # a smaller initial error is never slower to reach the bound
    assert cv.first_sweep[0] <= cv.first_sweep[1]
    assert cv.converges("h2", sim.period) == (cv.first["h2"] <= 0.05 * sim.period)
    # the rows' level is the paper's: gamma for H2 at its 0.1 deg, gamma x 0.1/0.08 for Hinf (not the guarantee)
    assert cv.level == pytest.approx({"h2": 0.0013, "hinf": 0.0013 * 1.25})
    # the predicted time to the level follows from the slowest pole
    assert cv.t_pred["h2"] == pytest.approx(np.log(sim.initial_error / 0.0013) / cv.decay["h2"])
    lc = obs.line_crossings(sim, window=0.05)
    assert lc.near.shape == sim.t.shape
    # the running RMS of a constant error is that constant
    assert set(lc.running_rms) == set(sim.runs)
    assert np.all(lc.running_rms["h2"] >= 0)


def test_window_rerun_keeps_the_initial_error(setup):
    sc, od, sim = setup
    ww = obs.window_rerun(sc, od, sim, 0.02, 0.2, 0.1, np.random.default_rng(2))
    assert ww.n == np.arange(0.0, 0.2 * sc.orbit.period, 0.02).size
    assert set(ww.median) == {"h2", "hinf"} and all(m < 0.02 for m in ww.median.values())


def test_claims_of_the_chapter():
    assert CLAIMS["h2_converges"].judge(False, reason="slow").status == "differs"
    assert CLAIMS["hinf_larger"].judge(True).status == "consistent (tuned)"  # one orbit, two intervals
    assert CLAIMS["fig3_233"].judge(False).status == "beyond paper"  # the guarantee with triangulated rho: diagnostic
    assert CLAIMS["h2_converges"].judge(True).status == "reproduced"  # level from the paper's digits, not tuned
    assert CLAIMS["no_range"].judge(False, reason="x").status == "differs"
    assert CLAIMS["no_range"].judge(True).status == "reproduced"  # bound from the paper's words, not tuned
    assert CLAIMS["ordering_dt"].judge(0.36).status == "beyond paper"  # our dt: a record, not a comparison
    assert CLAIMS["dt"].judge(0.004).status == "not in paper"


def test_convergence_sweep_same_result_through_an_executor(setup):
    from concurrent.futures import ThreadPoolExecutor

    sc, od, sim = setup
    serial = obs.convergence_study(sc, od, sim, 0.1, e0_scales=(0.1, 1.0))
    with ThreadPoolExecutor(2) as executor:
        threaded = obs.convergence_study(sc, od, sim, 0.1, e0_scales=(0.1, 1.0), executor=executor)
    assert np.array_equal(serial.first_sweep, threaded.first_sweep)
    # the sweep's full-scale run is the noisy H2 run of the simulation itself, against the rows' level
    acc = obs.Fig3Accuracy.measure({"x": (sim.t, {"h2": sim.runs["h2"].position_error})}, serial.level, sim.period)
    assert serial.first_sweep[1] == acc.first[("x", "h2")]
    assert serial.early_sweep[1] == acc.early_rms[("x", "h2")]


def test_e0_max_ok_needs_both_parts_of_rapidly():
    """The regime of the H2 row's 5 % part: the largest start whose error is first below the level within 5 % of
    the period AND whose RMS over 5-10 % of it is at most the level."""
    cv = obs.Convergence(0.1, {}, {}, {}, {}, {"h2": 1.0, "hinf": 1.25}, {}, {}, 0.0, np.array([0.1, 0.5, 1.0]),
                         np.array([0.1, 0.4, 2.0]), np.array([0.5, 3.0, 0.5]))
    # period 10: 5 % = 0.5 TU.  Scale 0.1 settles; 0.5 dips below in time but swings back (RMS 3); 1.0 too late
    assert cv.e0_max_ok(100.0, 10.0) == pytest.approx(10.0)
    assert np.isnan(cv.e0_max_ok(100.0, 1.0))  # 5 % of 1 TU = 0.05: none in time


def test_simulate_fig3_honours_the_initial_error(setup):
    sc, od, _ = setup
    sim = obs.simulate_fig3(sc, od, 0.01, 0.05, 0.1, np.random.default_rng(1), initial_error=0.5 * obs.INITIAL_ERROR)
    assert sim.initial_error == pytest.approx(0.01 * np.sqrt(2))
    with pytest.raises(ValueError):
        obs.simulate_fig3(sc, od, 0.01, 0.05, 0.1, np.random.default_rng(1), initial_error=[0.1, 0.1])


def test_allowance_at_follows_eq24_per_sample(setup):
    _, od, _ = setup
    a1, a4 = obs.allowance_at(od, 0.001), obs.allowance_at(od, 0.004)
    k = od.designs["h2"].kappa[0]
    assert a1.h2_per_sample_deg == pytest.approx(np.degrees(np.arcsin(1.0 / (k * np.sqrt(0.001)))))
    assert a1.h2_per_sample_deg > a4.h2_per_sample_deg  # a longer interval allows less per sample
    assert a1.hinf_deg == a4.hinf_deg and a1.dt_01 == a4.dt_01
    # at dt_01 the H2 design allows exactly 0.1 deg per sample
    assert obs.allowance_at(od, a1.dt_01).h2_per_sample_deg == pytest.approx(0.1, rel=1e-9)


# ------------------------------------------------------------------ the range-free row (obs.RangeFree)
def _designs(range_gain=0.0, range_used=False):
    """Two stand-in designs with the interface RangeFree reads (gain(), used), range columns set as asked."""
    from types import SimpleNamespace

    g = np.zeros((4, 6))
    g[2:, :2] = -3.0  # theta1 channels
    g[3, 5] = range_gain
    used = np.array([True, True, False, False, False, range_used])
    d = SimpleNamespace(gain=lambda: g, used=used)
    return obs.ObserverDesigns({"h2": d, "hinf": d}, {})


T21 = np.linspace(0.0, 2.0, 21)  # settling window: t > 0.2


def _history(**spikes):
    e = np.full(T21.size, 1.0)
    e[0] = 10.0
    for i, v in spikes.items():
        e[int(i[1:])] = v
    return e


def test_range_free_bounded_run_passes_and_an_excursion_fails():
    ok = obs.RangeFree.measure(_designs(), {"a": (T21, {"h2": _history(), "hinf": _history(i1=30.0)})})
    # the early transient (t = 0.1, inside the first 10 % of the run) is not judged
    assert ok.peak[("a", "hinf")] == 1.0 and ok.initial_error[("a", "hinf")] == 10.0
    assert ok.no_range_channel and ok.holds
    late = obs.RangeFree.measure(_designs(), {"a": (T21, {"h2": _history(), "hinf": _history(i15=10.5)})})
    assert late.bounded("a", "h2") and not late.bounded("a", "hinf") and not late.holds
    assert late.peak_time[("a", "hinf")] == pytest.approx(1.5)
    assert late.why(1.0).startswith("hinf at a back to 10 km = 1.05x") and ok.why(1.0) == ""
    at_start = obs.RangeFree.measure(_designs(), {"a": (T21, {"h2": _history(i20=10.0)})})
    assert not at_start.holds  # back to the initial error exactly: not below it
    blown = obs.RangeFree.measure(_designs(), {"a": (T21, {"h2": _history(i18=np.inf)})})
    assert blown.peak[("a", "h2")] == np.inf and not blown.holds
    lost = obs.RangeFree.measure(_designs(), {"a": (T21, {"h2": _history(i18=np.nan)})})
    assert lost.peak[("a", "h2")] == np.inf and not lost.holds  # a NaN estimate is unbounded, not a NaN peak


def test_range_free_every_interval_is_judged_and_the_reference_is_context():
    two = {"a": (T21, {"h2": _history()}), "b": (T21[:11], {"h2": _history(i3=11.0)[:11]})}
    rf = obs.RangeFree.measure(_designs(), two, reference={"a": (T21, {"h2": _history(i5=50.0)})})
    assert rf.bounded("a", "h2") and not rf.bounded("b", "h2") and not rf.holds
    assert rf.reference_peak == {("a", "h2"): 50.0}
    assert "H2 0.10 (a)" in rf.shown() and "H2 1.10 (b)" in rf.shown()
    with pytest.raises(ValueError):
        rf.bounded("c", "h2")


def test_range_free_a_range_channel_fails_by_gain_or_by_use():
    runs = {"a": (T21, {"h2": _history()})}
    assert obs.RangeFree.measure(_designs(), runs).holds
    assert not obs.RangeFree.measure(_designs(range_gain=1e-3), runs).holds  # a non-zero r23^2 column
    assert not obs.RangeFree.measure(_designs(range_used=True), runs).holds  # a range sensor kept


def test_range_free_refuses_malformed_runs():
    with pytest.raises(ValueError):
        obs.RangeFree.measure(_designs(), {})
    with pytest.raises(TypeError):
        obs.RangeFree.measure(_designs(), {"a": T21})
    with pytest.raises(ValueError):
        obs.RangeFree.measure(_designs(), {"a": (T21, {"h2": _history()[:5]})})
    with pytest.raises(ValueError):
        obs.RangeFree.measure(_designs(), {"a": (T21, {"h2": -_history()})})


def test_range_free_on_the_paper_designs(setup):
    _, od, sim = setup
    rf = obs.RangeFree.measure(od, {"x": (sim.t, {n: sim.runs[n].position_error for n in od.designs})})
    assert rf.no_range_channel  # theta1-only designs: r13^2, r23^2 columns exactly zero
    assert rf.initial_error[("x", "h2")] == pytest.approx(sim.initial_error)


# ------------------------------------------------------ the "converges rapidly and stays accurate" rows (Fig3Accuracy)
def _decay(t, e0, rate, floor):
    """An error history decaying from ``e0`` at ``rate`` (1/TU) onto ``floor``."""
    return floor + (e0 - floor) * np.exp(-rate * t)


def test_paper_level_is_gamma_at_the_papers_allowances():
    lv = obs.Fig3Accuracy.paper_level(0.0013, 0.1)
    assert lv["h2"] == pytest.approx(0.0013) and lv["hinf"] == pytest.approx(0.0013 * 0.1 / 0.08)
    assert obs.Fig3Accuracy.paper_level(0.0013, 0.2)["h2"] == pytest.approx(0.0026)  # linear in the noise
    with pytest.raises(ValueError, match="sigma_deg"):
        obs.Fig3Accuracy.paper_level(0.0013, 0.0)


def test_fig3_accuracy_fast_accurate_run_passes_and_each_part_can_fail():
    t, period = np.linspace(0.0, 10.0, 1001), 10.0  # 5 % of the period: t <= 0.5; settled: t > 1.0
    level = {"h2": 1.0, "hinf": 1.0}
    fast = _decay(t, 100.0, 20.0, 0.5)  # below 1 at t = ln(99/0.5)/20 = 0.26
    slow = _decay(t, 100.0, 3.0, 0.5)  # below 1 at t = 1.76: accurate afterwards, not rapid
    noisy = _decay(t, 100.0, 20.0, 1.2)  # settles at 1.2, above the level: never below it
    high = fast.copy()
    high[t > 5.0] = 1.5  # rapid, then RMS after 10 % above the level
    acc = obs.Fig3Accuracy.measure({"a": (t, {"h2": fast, "hinf": slow})}, level, period)
    assert acc.first[("a", "h2")] == pytest.approx(np.log(99.0 / 0.5) / 20.0, abs=0.011)
    assert acc.rapid("a", "h2") and acc.accurate("a", "h2") and acc.holds("h2")
    assert not acc.rapid("a", "hinf") and acc.accurate("a", "hinf") and not acc.holds("hinf")
    # the settled RMS is over t > 10 % of the run only: the transient before it does not count
    assert acc.rms[("a", "h2")] == pytest.approx(np.sqrt(np.mean(fast[t > 1.0] ** 2)))
    bad = obs.Fig3Accuracy.measure({"a": (t, {"h2": high, "hinf": noisy})}, level, period)
    assert bad.rapid("a", "h2") and not bad.accurate("a", "h2") and not bad.holds("h2")
    assert bad.first[("a", "hinf")] == np.inf and not bad.holds("hinf")
    assert "RMS above 1 km" in bad.why("h2", 1.0) and acc.why("h2", 1.0) == ""
    # a dip below the level on the way down is not convergence: above it again over 5-10 % of the period
    dip = slow.copy()
    dip[(t > 0.2) & (t < 0.3)] = 0.5
    swung = obs.Fig3Accuracy.measure({"a": (t, {"h2": dip})}, level, period)
    assert swung.first[("a", "h2")] <= 0.5 and swung.early_rms[("a", "h2")] > 1.0 and not swung.rapid("a", "h2")
    assert swung.early_rms[("a", "h2")] == pytest.approx(np.sqrt(np.mean(dip[(t > 0.5) & (t <= 1.0)] ** 2)))
    assert "not settled below 1 km within 5 % of the period" in acc.why("hinf", 1.0)


def test_fig3_accuracy_every_interval_must_hold_and_levels_are_per_observer():
    t = np.linspace(0.0, 10.0, 1001)
    ok, late = _decay(t, 100.0, 20.0, 0.5), _decay(t, 100.0, 3.0, 0.5)
    two = obs.Fig3Accuracy.measure({"a": (t, {"h2": ok}), "b": (t[::10], {"h2": late[::10]})}, {"h2": 1.0}, 10.0,
                                   reference={"b": (t[::10], {"h2": ok[::10]})})
    assert two.rapid("a", "h2") and not two.rapid("b", "h2") and not two.holds("h2")
    assert two.why("h2", 1.0) == "at b not settled below 1 km within 5 % of the period"  # accurate: no true-rho RMS
    high = obs.Fig3Accuracy.measure({"b": (t, {"h2": ok + 2.0})}, {"h2": 1.0}, 10.0,
                                    reference={"b": (t, {"h2": ok + 0.2})})  # settles at 0.7
    assert high.why("h2", 1.0).endswith("RMS above 1 km (on the true rho: RMS 1 km)")
    # a larger level for one observer (Hinf's 1.25 gamma) is that observer's alone
    both = obs.Fig3Accuracy.measure({"a": (t, {"h2": 1.1 * ok, "hinf": 1.1 * ok})}, {"h2": 0.5, "hinf": 1.0}, 10.0)
    assert not both.accurate("a", "h2") and both.accurate("a", "hinf")
    # a run that blew up after the start is inaccurate, not an error
    blown = ok.copy()
    blown[500] = np.nan
    assert obs.Fig3Accuracy.measure({"a": (t, {"h2": blown})}, {"h2": 1.0}, 10.0).rms[("a", "h2")] == np.inf
    with pytest.raises(ValueError):
        two.holds("hinf")
    with pytest.raises(ValueError):
        obs.Fig3Accuracy.measure({}, {"h2": 1.0}, 10.0)
    with pytest.raises(ValueError, match="no level"):
        obs.Fig3Accuracy.measure({"a": (t, {"ekf": ok})}, {"h2": 1.0}, 10.0)
    with pytest.raises(ValueError, match="level"):
        obs.Fig3Accuracy.measure({"a": (t, {"h2": ok})}, {"h2": 0.0}, 10.0)
    with pytest.raises(TypeError):
        obs.Fig3Accuracy.measure({"a": t}, {"h2": 1.0}, 10.0)
