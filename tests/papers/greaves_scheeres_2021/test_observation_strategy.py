"""Chapter 09 studies: Monte Carlo aggregation, seeding, the regime-map analysis and the stable-candidate
comparison (small sizes and synthetic cells; invariants, not snapshots)."""

import dataclasses
from concurrent.futures import ThreadPoolExecutor

import matplotlib.pyplot as plt
import numpy as np
import pytest

from cislunar.cr3bp import orbits
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.estimation import ocbe
from cislunar.papers.greaves_scheeres_2021 import observation_strategy as obs
from cislunar.papers.greaves_scheeres_2021 import tracking
from cislunar.papers.greaves_scheeres_2021.claims.observation_strategy import CLAIMS
from cislunar.publish import plotting
from cislunar.utils.montecarlo import trial_rng

Q = 1e-20 * em.time_unit_s**3 / em.length_unit_km**2


def _summary(diverged, sigma_pos=1.0, nees=6.0):
    return tracking.TrialSummary(sigma_pos, 1e-3, 0.1, 1e-4, 1.0, nees, 0.2 if diverged else 0.0, diverged)


def same_run(a, b, rtol=1e-7):
    """Two TrialSummary of the same draws (lockstep and single-trial path): flags, counts and epochs identical,
    numbers equal to round-off."""
    assert (a.diverged, a.first_inconsistent_epoch, a.inconsistent_fraction, a.failure == "") == \
        (b.diverged, b.first_inconsistent_epoch, b.inconsistent_fraction, b.failure == "")
    for name in ("final_sigma_pos_km", "final_sigma_vel_m_s", "final_error_pos_km", "max_error_pos_km", "nees_mean"):
        assert abs(getattr(a, name) / getattr(b, name) - 1) < rtol, name


@pytest.fixture(scope="module")
def nrho():
    return orbits.nrho_9_2(em)


def test_labels_and_flags():
    assert obs.cadence_label(1 / 60) == "1 min" and obs.cadence_label(10 / 60) == "10 min"
    assert obs.cadence_label(12.0) == "12 h"
    assert obs.pct_span([0.1, 0.1]) == "10 %" and obs.pct_span([0.0, 0.5]) == "0-50 %"
    rows = [("a", 2.0, 0.1, 0, 0, 0, 10), ("b", 2.0, 0.15, 0, 0, 0, 10)]
    assert obs.flagged_cells(rows) == [("b", 2.0, 0.15)]  # the 10 % flag is "more than"


def test_study_rows_are_fractions_and_medians():
    runs = {("x", 2.0): (_summary(True, 1.0, 50.0), _summary(False, 3.0, 5.0), _summary(False, 2.0, 6.0), _summary(
        False, 4.0, 7.0)), ("x", 12.0): (_summary(True, 5.0), _summary(True, 7.0))}
    st = obs.StrategyStudy(runs, rates=True)
    r2, r12 = st.by_cadence("x")[2.0], st.by_cadence("x")[12.0]
    assert r2[2] == 0.25 and r2[3] == pytest.approx(6.5) and r2[4] == pytest.approx(3 * 2.5) and r2[6] == 4
    assert r12[2] == 1.0 and st.diverged_cells() == [("x", 12.0)]
    assert st.diverged_fraction("x", [2.0, 12.0]) == pytest.approx(3 / 6)
    assert "cadence [h]" in st.report("label")


def test_strategy_study_seeds_each_cell_independently_of_the_executor(nrho):
    st = obs.strategy_study(em, {"9:2 NRHO": nrho}, [12.0], Q, rates=True, n_runs=2, seed=3)
    scn = tracking.make_scenario(em, nrho, 12.0, start="apoapsis", rates=True)
    direct = tracking.filter_trial(trial_rng((3, 0, 0, 1), 1), scn, Q)  # the single-trial path
    same_run(st.runs["9:2 NRHO", 12.0][1], direct)
    assert len(st.rows) == 1 and st.rows[0][6] == 2
    with ThreadPoolExecutor(2) as pool:  # the lockstep tasks through an executor: the same numbers
        pooled = obs.strategy_study(em, {"9:2 NRHO": nrho}, [12.0], Q, rates=True, n_runs=2, seed=3, executor=pool)
    assert pooled.runs == st.runs
    with pytest.raises(ValueError, match="n_runs"):
        obs.strategy_study(em, {"9:2 NRHO": nrho}, [12.0], Q, rates=True, n_runs=0, seed=3)


def test_regime_map_runs_each_cell_with_its_own_seed_and_handoff(nrho, monkeypatch):
    """Hand-offs share a lockstep task, yet each cell's runs are those of its own seed and hand-off; tasks are cut
    at LOCKSTEP_TRIALS runs without changing them."""
    args = (em, {"9:2 NRHO": nrho}, [12.0], [10e-6], [1.0, 1000.0], {"angles + rates (1 s)": 1.0}, Q)
    rm = obs.regime_map(*args, n_runs=2, seed=4)
    scn = tracking.make_scenario(em, nrho, 12.0, start="apoapsis", rates=False)
    for ih, h in enumerate((1.0, 1000.0)):
        runs = [tracking.filter_trial(trial_rng((4, 77, 0, 0, 0, 0, ih), i), scn, Q, handoff_scale=h) for i in range(2)]
        assert rm["9:2 NRHO", 12.0, 10e-6, "angles", h] == np.mean([r.diverged for r in runs])
    assert rm["9:2 NRHO", 12.0, 10e-6, "angles", 1000.0] == 1.0 and rm["9:2 NRHO", 12.0, 10e-6, "angles", 1.0] == 0.0
    monkeypatch.setattr(obs, "LOCKSTEP_TRIALS", 3)
    cut = obs.regime_map(*args, n_runs=2, seed=4)
    assert cut.cells == rm.cells and cut.onsets == rm.onsets


def test_divergence_example_picks_the_worst_diverged_draw(nrho):
    rm = obs.RegimeMap({("9:2 NRHO", 12.0, 10e-6, "angles", 1000.0): 1.0}, {}, ("angles",), ("9:2 NRHO",), (12.0,),
                       (10e-6,), (1000.0,), 2)
    ex = obs.divergence_example(em, nrho, rm, ("9:2 NRHO", 12.0, 10e-6, "angles", 1000.0), Q, seed=0, n_draws=3)
    scn, truth = ex.scenario, ex.truth
    nees = []
    for k in range(3):  # the single-trial path, draw by draw
        rng = np.random.default_rng([0, 404, k])
        y = tracking.simulate_measurements(scn, truth, rng)
        x0, P0 = tracking.initial_estimate(em, scn.x_start, rng, scale=1000.0)
        run = ocbe.ocbe_filter_smoother(em, scn.t, y, scn.observers, scn.model, scn.meas_cov, x0, P0, Q,
                                        available=scn.available, smooth=False)
        nees.append(tracking.summarize(em, run.x_filt, run.P_filt, truth))
    assert all(s.diverged for s in nees) and ex.draw == int(np.argmax([s.nees_mean for s in nees]))
    assert ex.summary == nees[ex.draw]  # the chosen draw rerun with the single-trial filter


def _synthetic_map():
    models = ("angles", "angles + rates (1 s)", "angles + rates (dt = 1 TU)")
    orbit_names, handoffs = ("9:2 NRHO", "other"), (1.0, 10.0, 100.0)
    cells = {}
    for o in orbit_names:
        for h in handoffs:
            cells[o, 12.0, 1e-5, "angles", h] = 0.0 if h < 100 else 0.8
            cells[o, 12.0, 1e-5, models[1], h] = 0.0 if h < 100 else 0.7
            cells[o, 12.0, 1e-5, models[2], h] = 0.0 if (h < 100 or o == "other") else 0.9
    cells["other", 12.0, 1e-5, "angles", 1.0] = 0.6  # diverges at the paper's hand-off
    onsets = {k: ["first update"] * int(10 * v) for k, v in cells.items()}
    return obs.RegimeMap(cells, onsets, models, orbit_names, (12.0,), (1e-5,), handoffs, 10)


def test_regime_map_analysis_on_synthetic_cells():
    rm = _synthetic_map()
    assert len(rm.map_cells) == 6 and rm.rates_paper == "angles + rates (1 s)"
    # contrast: angles > 50 % and rates <= 10 %: only "other" at 100 with the dt = 1 TU model, and "other" at 1.0
    # with both models (its rates fractions there are 0)
    assert rm.contrast["angles + rates (dt = 1 TU)"] == [("other", 12.0, 1e-5, 1.0), ("other", 12.0, 1e-5, 100.0)]
    assert rm.contrast["angles + rates (1 s)"] == [("other", 12.0, 1e-5, 1.0)]
    assert rm.onset_km("9:2 NRHO") == 1000.0 and rm.onset_km("other") == 10.0
    assert rm.at_paper_handoff("other") == [0.6]
    cell_92, cell_paper = rm.divergence_cells()
    assert cell_92 == ("9:2 NRHO", 12.0, 1e-5, "angles", 100.0)
    assert cell_paper == ("other", 12.0, 1e-5, "angles", 1.0)
    text = rm.analysis_report()
    assert "verdict: the paper's contrast appears in 3" in text and rm.table_report().count("\n") == 6


def test_stable_candidates_compare_medians_and_long_cadence_fractions():
    runs = {}
    for name, pos, div in (("ref", 2.0, False), ("a", 1.0, False), ("b", 3.0, True)):
        for c in (2.0, 12.0):
            runs[name, c] = (_summary(div, pos), _summary(False, pos))
    cand = obs.compare_stable_candidates(obs.StrategyStudy(runs, True), "ref", ("a", "b"), (2.0, 12.0))
    assert cand.better == {"a": 1.0, "b": 0.0} and cand.ratio["a"] == [0.5, 0.5]
    assert cand.long_cadences == (12.0,) and cand.inconsistent == {"ref": 0.0, "a": 0.0, "b": 0.5}
    assert cand.supports("a") and not cand.supports("b")


def test_measurement_demo_rate_noise_is_eq_13(nrho):
    demo = obs.measurement_demo(em, nrho, 12.0)
    assert demo.sigma_rate_urad_s == pytest.approx(np.sqrt(2) * 10.0)
    assert demo.y.shape == (demo.days.size, 4) and demo.days[0] == 0.0
    # the noise follows the angle noise given (Eq. 13: the rate noise is sqrt(2) sigma over the 1-s baseline)
    noisy = obs.measurement_demo(em, nrho, 12.0, sigma_angle_rad=30e-6)
    assert noisy.sigma_rate_urad_s == pytest.approx(np.sqrt(2) * 30.0)
    assert noisy.sigma[0] == pytest.approx(30e-6) and np.array_equal(noisy.y, demo.y)  # noise-free measurements
    with pytest.raises(ValueError, match="sigma_angle_rad"):
        obs.measurement_demo(em, nrho, 12.0, sigma_angle_rad=-1.0)


def test_typical_run_uses_the_angle_noise_given(nrho):
    quiet = obs.typical_run(em, nrho, 12.0, 1e-20 * em.time_unit_s**3 / em.length_unit_km**2,
                            np.random.default_rng(0), sigma_angle_rad=10e-6)
    noisy = obs.typical_run(em, nrho, 12.0, 1e-20 * em.time_unit_s**3 / em.length_unit_km**2,
                            np.random.default_rng(0), sigma_angle_rad=100e-6)
    assert np.sqrt(noisy.scenario.meas_cov[0, 0]) == pytest.approx(100e-6)
    # ten times the noise: a final position uncertainty several times larger
    final = [r.forward.final_sigma_pos_km for r in (quiet, noisy)]
    assert 3 < final[1] / final[0] <= 10.5


def test_claims_read_diverges_and_consistent_as_declared():
    assert CLAIMS["inner_consistent_long"].judge(0.10).status == "reproduced"
    assert CLAIMS["inner_consistent_long"].judge(0.15).status == "differs"
    assert CLAIMS["outer_better"].judge(1.0).status == "consistent (tuned)"
    assert obs.filled(CLAIMS["table4"], cadence="2 h").judge(1.0, note="median").status == "not in paper"
    row = obs.filled(CLAIMS["angles_only_noise"], noise="100").judge(False, shown="0% diverged")
    assert row.quantity == "angles only, 9:2 NRHO, 12 h, 100 urad" and row.status == "differs"
    assert CLAIMS["angles_only_noise"].quantity.endswith("{noise} urad")  # the declaration itself is untouched


def test_public_boundary_names_the_bad_argument(nrho):
    """Configuration errors are refused by name before any Monte Carlo run (not as a failed trial)."""
    orbits_ = {"9:2 NRHO": nrho}
    for kwargs, name in ((dict(control_weight=-1.0), "control_weight"), (dict(cadences=[]), "cadences"),
                         (dict(cadences=[2.0, -1.0]), "cadences"), (dict(handoff_scale=0.0), "handoff_scale"),
                         (dict(executor="pool"), "executor"), (dict(observers="moon"), "observers")):
        args = dict(cadences=[12.0], control_weight=Q) | kwargs
        with pytest.raises((ValueError, TypeError), match=name):
            obs.strategy_study(em, orbits_, args["cadences"], args["control_weight"], rates=False, n_runs=1,
                               seed=0, **{k: v for k, v in kwargs.items() if k not in ("cadences", "control_weight")})
    with pytest.raises(TypeError, match="orbits_"):
        obs.strategy_study(em, [nrho], [12.0], Q, rates=False, n_runs=1, seed=0)
    with pytest.raises(TypeError, match="rate_models"):
        obs.regime_map(em, orbits_, [12.0], [1e-5], [1.0], {"rates": "1 s"}, Q, n_runs=1, seed=0)
    runs = {(name, cad): (_summary(False),) for name in ("ref", "a") for cad in (2.0, 12.0)}
    study = obs.StrategyStudy(runs, True)
    with pytest.raises(ValueError, match="reference"):
        obs.compare_stable_candidates(study, "9:2", ("a",), (2.0, 12.0))
    with pytest.raises(TypeError, match="candidates"):
        obs.compare_stable_candidates(study, "ref", "a", (2.0, 12.0))  # one name, not its letters
    with pytest.raises(ValueError, match="cadences"):
        obs.compare_stable_candidates(study, "ref", ("a",), (6.0,))  # not a cadence of the study
    with pytest.raises(TypeError, match="rows"):
        obs.flagged_cells("abc")
    with pytest.raises(ValueError, match="fields"):
        obs.filled(CLAIMS["table4"])  # its quantity has a {cadence} field to fill
    with pytest.raises(ValueError, match="values"):
        obs.pct_span([])
    with pytest.raises(ValueError, match="cadence_h"):
        obs.cadence_label(0.0)


def test_filter_axes_study_filters_the_same_draws_with_each_axis_options_and_weight(nrho, monkeypatch):
    """Every axis sees the same draws (the cell's seed), its own filter options and its factor on the weight; the
    cells are the diverged fractions of exactly those runs (checked against tracking.filter_trials called directly)."""
    axes = {"baseline": ({}, 1.0), "fixed reference": ({"relinearize": False}, 1.0), "weight x100": ({}, 100.0)}
    st = obs.filter_axes_study(em, {"9:2 NRHO": nrho}, [12.0], Q, n_runs=2, seed=5, axes=axes, handoff_scale=300.0,
                               progress=False)
    assert st.axes == tuple(axes) and set(st.cells) == {(a, "9:2 NRHO", 12.0, m) for a in axes
                                                        for m in ("angles", "angles+rates")}
    for im, rates in enumerate((False, True)):
        scn = tracking.make_scenario(em, nrho, 12.0, start="apoapsis", rates=rates)
        for a, (options, factor) in axes.items():
            runs = tracking.filter_trials([trial_rng((5, 23, 0, 0, im), i) for i in range(2)], scn, Q * factor,
                                          handoff_scale=300.0, **options)
            assert st.cells[a, "9:2 NRHO", 12.0, st.MODELS[im]] == np.mean([r.diverged for r in runs])
            assert len(st.onsets[a, "9:2 NRHO", 12.0, st.MODELS[im]]) == sum(r.diverged for r in runs)
    calls = []
    real = tracking.filter_trials

    def spy(rngs, scenario, control_weight, **kw):
        calls.append((control_weight, kw.get("relinearize", True), tuple(r.bit_generator.state["state"]["state"]
                                                                          for r in rngs)))
        return real(rngs, scenario, control_weight, **kw)

    monkeypatch.setattr(tracking, "filter_trials", spy)
    monkeypatch.setattr(obs, "LOCKSTEP_TRIALS", 1)  # one run per task: same cells
    cut = obs.filter_axes_study(em, {"9:2 NRHO": nrho}, [12.0], Q, n_runs=2, seed=5, axes=axes, handoff_scale=300.0,
                                progress=False)
    assert cut.cells == st.cells and len(calls) == 2 * 3 * 2
    angles_calls = calls[:6]  # the angles-only cell: three axes, two one-run tasks each
    assert [c[2] for c in angles_calls[0:2]] == [c[2] for c in angles_calls[2:4]] == [c[2] for c in angles_calls[4:6]]
    assert [(c[0] / Q, c[1]) for c in angles_calls[::2]] == [(1.0, True), (1.0, False), (100.0, True)]


def test_an_appended_cadence_leaves_the_earlier_cells_draws_and_the_study_lists_cadences_increasing(nrho, monkeypatch):
    """A cell's draws follow its cadence's place in the caller's list (notebook 09 appends the minute cadences so
    that the hour cells keep theirs); the study lists its cadences increasing, whatever the caller's order."""
    calls = []
    real = tracking.filter_trials

    def spy(rngs, scenario, control_weight, **kw):
        calls.append(tuple(r.bit_generator.state["state"]["state"] for r in rngs))
        return real(rngs, scenario, control_weight, **kw)

    monkeypatch.setattr(tracking, "filter_trials", spy)
    axes = {"baseline": ({}, 1.0)}

    def study(cadences):
        calls.clear()
        st = obs.filter_axes_study(em, {"9:2 NRHO": nrho}, cadences, Q, n_runs=2, n_runs_one_minute=1, seed=5,
                                   axes=axes, handoff_scale=300.0, progress=False)
        return st, list(calls)

    one, one_calls = study([12.0])
    two, two_calls = study([12.0, 24.0])
    assert two.cadences == (12.0, 24.0) and two_calls[:2] == one_calls  # the 12-h cells: the same draws
    assert all(two.cells[k] == one.cells[k] for k in one.cells)
    swapped, swapped_calls = study([24.0, 12.0])
    assert swapped.cadences == (12.0, 24.0)  # listed increasing
    assert swapped_calls[2:] != one_calls  # the 12-h cell moved to index 1: other draws (why the notebook appends)


def test_filter_axes_run_counts_and_the_cadence_ticks_by_name():
    cells = {(a, "9:2 NRHO", c, m): 0.0 for a in ("baseline", "x") for c in (1 / 60, 2.0)
             for m in ("angles", "angles+rates")}
    st = obs.FilterAxesStudy(cells, {k: [] for k in cells}, ("baseline", "x"), ("9:2 NRHO",), (1 / 60, 2.0), 10, 4,
                             1.0, 1e-5)
    assert (st.runs_at(1 / 60), st.runs_at(0.1), st.runs_at(2.0)) == (4, 10, 10)
    st.cells["x", "9:2 NRHO", 2.0, "angles+rates"] = 0.3
    assert st.worst_cadence("x", "9:2 NRHO", "angles+rates") == 2.0
    assert st.worst_cadence("baseline", "9:2 NRHO", "angles+rates") == 1 / 60  # a tie: the shortest cadence
    assert st.total_runs == 2 * 1 * 2 * (4 + 10)
    fig = obs.figure_filter_axes(st)
    ax = next(a for a in fig.axes if a.lines)
    assert [t.get_text() for t in ax.get_xticklabels()] == ["1 min", "2 h"]
    assert list(ax.get_xticks()) == [1 / 60, 2.0]
    assert plotting.axis_label_problems(fig) == []  # save_figure's rule: the x label still carries a unit
    plt.close(fig)


def test_filter_axes_contrast_and_claim_on_synthetic_cells():
    cells = {}
    for a, (ang, rat) in {"baseline": ((0.0, 0.0), (0.0, 0.0)), "x": ((0.6, 0.9), (0.1, 0.0)),
                          "y": ((0.6, 0.5), (0.1, 0.1))}.items():
        for c, va, vr in zip((2.0, 12.0), ang, rat):
            cells[a, "9:2 NRHO", c, "angles"] = va
            cells[a, "9:2 NRHO", c, "angles+rates"] = vr
    st = obs.FilterAxesStudy(cells, {k: [] for k in cells}, ("baseline", "x", "y"), ("9:2 NRHO",), (2.0, 12.0), 10,
                             10, 1.0, 1e-5)
    # contrast: angles > 50 % and rates <= 10 % (0.5 is not "most")
    assert st.contrast == {"baseline": [], "x": [("9:2 NRHO", 2.0), ("9:2 NRHO", 12.0)], "y": [("9:2 NRHO", 2.0)]}
    assert st.axes_with_full_contrast == ["x"]
    assert "contrast with x: 2 of 2 cells" in st.report()
    claim = obs.filled(CLAIMS["filter_axes_contrast"], axes="baseline, x, y", cadences="2 h, 12 h")
    assert claim.judge(bool(st.axes_with_full_contrast)).status == "reproduced"
    assert claim.judge(False).status == "differs"
    fig = obs.figure_filter_axes(st)
    panels = [ax for ax in fig.axes if ax.lines]
    assert len(panels) == 2 and [list(ln.get_ydata()) for ln in panels[0].lines[:3]] == [[0.0, 0.0], [60.0, 90.0],
                                                                                         [60.0, 50.0]]
    plt.close(fig)


def test_filter_axes_study_bad_input(nrho):
    orbits_ = {"9:2 NRHO": nrho}
    with pytest.raises(ValueError, match="axes"):
        obs.filter_axes_study(em, orbits_, [12.0], Q, n_runs=1, seed=0, axes={"a": ({"n_sub": 3}, 1.0)})
    with pytest.raises(TypeError, match="axes"):
        obs.filter_axes_study(em, orbits_, [12.0], Q, n_runs=1, seed=0, axes={"a": {"relinearize": False}})
    with pytest.raises(ValueError, match="factor"):
        obs.filter_axes_study(em, orbits_, [12.0], Q, n_runs=1, seed=0, axes={"a": ({}, 0.0)})
    with pytest.raises(ValueError, match="n_runs"):
        obs.filter_axes_study(em, orbits_, [12.0], Q, n_runs=0, seed=0)


def _early(diverged, first_epoch):
    return dataclasses.replace(_summary(diverged), first_inconsistent_epoch=first_epoch)


def test_divergence_before_perilune_counts_only_early_onsets():
    """The angles-only L2 row: most runs of a cell diverge *before* the orbit's perilune, at every cadence."""
    limit = {"a": 10.0, "b": 10.0}  # hours after the start
    runs = {("a", 2.0): (_early(True, 4), _early(True, 0), _early(False, -1)),  # 8 h, 0 h: 2 of 3 early
            ("a", 6.0): (_early(True, 1), _early(True, -1), _early(True, 2)),  # 6 h, failure, 12 h: 2 of 3 early
            ("b", 2.0): (_early(True, 5), _early(True, 6), _early(True, 0)),  # 10 h is not before 10 h: 1 of 3
            ("b", 6.0): (_early(True, 0), _early(True, 0), _early(False, -1))}
    st = obs.StrategyStudy(runs, rates=False)
    assert st.cells_diverged_before(limit) == [("a", 2.0), ("a", 6.0), ("b", 6.0)]
    assert st.orbits_diverging_before(limit) == ["a"]  # b fails at 2 h though every run there diverged
    assert st.diverged_cells() == list(runs)  # by the plain rule every cell diverged
    assert st.orbits_diverging_before({"a": 100.0, "b": 100.0}) == ["a", "b"]
    assert st.cells_diverged_before({"a": 1.0, "b": 1.0}) == [("b", 6.0)]  # only b at 6 h has two 0-h onsets
    assert st.orbits_diverging_before({"a": 1.0, "b": 1.0}) == []
    half = obs.StrategyStudy({("c", 2.0): (_early(True, 0), _early(False, -1))}, rates=False)
    assert half.cells_diverged_before({"c": 10.0}) == [] and half.orbits_diverging_before({"c": 10.0}) == []


def test_noise_readings_ask_for_every_cadence_at_one_noise():
    """The hand-off rows: some noise of the map makes most angles-only runs diverge at every cadence at the paper's
    hand-off; divergence at different cadences under different noises does not count."""
    cells = {}
    for c in (2.0, 12.0):
        for sg in (1e-6, 1e-5):
            for h in (1.0, 100.0):
                cells["o", c, sg, "angles", h] = 1.0 if h == 100.0 else 0.0
    cells["o", 12.0, 1e-6, "angles", 1.0] = 0.8  # 12 h diverges at 1 urad, 2 h at 10 urad: never both
    cells["o", 2.0, 1e-5, "angles", 1.0] = 0.9
    rm = obs.RegimeMap(cells, {}, ("angles",), ("o",), (2.0, 12.0), (1e-6, 1e-5), (1.0, 100.0), 10)
    assert rm.noise_readings("o") == {1e-6: [0.0, 0.8], 1e-5: [0.9, 0.0]}
    assert rm.diverging_noises("o") == []
    cells["o", 2.0, 1e-6, "angles", 1.0] = 0.6  # now 1 urad diverges at both cadences
    assert rm.diverging_noises("o") == [1e-6]
    cells["o", 2.0, 1e-6, "angles", 1.0] = 0.5  # exactly half is not "most"
    assert rm.diverging_noises("o") == []
