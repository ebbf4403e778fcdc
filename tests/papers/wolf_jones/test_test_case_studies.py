"""Studies of Wolf & Jones test cases 1 and 2 on small sizes: invariants of the sweeps, CRLB, front and mirror."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from types import SimpleNamespace

import numpy as np
import pytest

from cislunar.guidance import scvx
from cislunar.guidance.scvx import SCvxError
from cislunar.papers.wolf_jones import global_search
from cislunar.papers.wolf_jones import scenarios as wj
from cislunar.papers.wolf_jones import test_case_studies as S
from cislunar.papers.wolf_jones.case_2_closing import Departures


@pytest.fixture(scope="module")
def case1():
    sc = wj.test_case_1()
    return S.sweep_test_case_1(sc, 12, [0.0, 5e-3], forward_hessian=True)


def test_table2_slip_prefers_the_x0_held_reading_and_the_printed_state_crashes():
    sc = wj.test_case_1()
    slip = S.table2_slip(sc, wj.test_case_2(), 10)
    assert slip.x0_wins and slip.n_other_rows == 6
    assert "Moon" in slip.printed_fate
    # the windows follow from the period: [3P/4, 3P/2] (case 1) and [P, 2P] (case 2)
    pd = sc.system.tu_to_days(sc.period)
    (w1, w2) = slip.windows_days[slip.ADOPTED]
    assert w1 == pytest.approx((0.75 * pd, 1.5 * pd)) and w2 == pytest.approx((pd, 2 * pd))
    assert slip.miss23_days[slip.ADOPTED] == pytest.approx(abs(1.5 * pd - 23.0))
    # a transfer from the printed state costs about the velocity slip (tens of m/s), far above the DRO's
    assert slip.printed_transfer_mps > 10.0


def test_case1_sweep_front_reflight_and_crlb(case1):
    assert case1.monotone and len(case1.best) == 2
    assert case1.mi[1] > case1.mi[0] and case1.impulse_mps[1] > case1.impulse_mps[0]
    fl = S.reflight(case1)
    assert max(fl.window_thrust) <= 1e-12  # the window is a coast, imposed
    assert max(fl.miss_km) < 1.0  # the plans fly
    assert all(0 < r <= 1 + 1e-9 for r in fl.max_ratio)
    cr = S.crlb_study(case1)
    assert cr.transient and cr.bounded
    # more information, lower terminal RMS; the literal (much larger) process noise gives larger errors
    assert cr.term_obs[1] < cr.term_obs[0]
    assert all(c.terminal_rms_km[0] > cr.term_obs[i] for c, i in zip(cr.literal, (0, -1)))
    assert cr.spearman(case1.mi)[0] == pytest.approx(-1.0)
    rel, dep = S.departures_km(case1, 50)
    assert np.linalg.norm(rel[0][0]) < 1e-6  # both start on the DRO
    assert dep[1] > dep[0]


def test_case1_budget_is_met_within_its_tolerance(case1):
    cr = S.crlb_study(case1)
    rows, msgs = S.budget_study(case1, cr.term_obs, [2.0, 1e4], rtol=0.02)
    assert len(msgs) == 2 and "beyond" in msgs[1]
    (r,) = rows
    assert r.impulse == pytest.approx(r.budget, rel=0.02)
    assert 0 < r.alpha < 5e-3 and r.rms_obs < cr.term_obs[0]


def _row(alpha, dv, rms):
    crlb = SimpleNamespace(terminal_rms_km=np.array([rms, rms, rms, rms]))
    return S.PlanRow(alpha, None, "up", crlb, dv, 100 + alpha, 0.0, 500.0, 0.0, 0.1, 0.0)


def test_front_finds_dominated_plans_and_monotonicity():
    fr = S.front([_row(0.0, 1.0, 100.0), _row(1e-3, 5.0, 20.0), _row(2e-3, 9.0, 30.0)])
    assert fr.dominated == [(2e-3, 2, 1e-3, 1)] and fr.mono_dv and fr.mono_mi
    assert S.front([_row(0.0, 1.0, 100.0), _row(1e-3, 5.0, 20.0)]).dominated == []
    assert S.front([_row(0.0, 1.0, 100.0), _row(1e-3, 0.5, 20.0)]).mono_dv is False


def test_mirror_pair_measures_the_reflection_across_z():
    rng = np.random.default_rng(1)
    x = rng.normal(size=(5, 6))
    a = SimpleNamespace(x=x, u=rng.normal(size=(5, 3)))
    xm, um = S.mirrored(a)
    assert np.allclose(xm[:, [2, 5]], -x[:, [2, 5]]) and np.allclose(um[:, 2], -a.u[:, 2])
    em = wj.test_case_2().system
    mp = S.mirror_pair(a, SimpleNamespace(x=xm), 3, em)
    assert mp.d_mirror_km == pytest.approx(0.0, abs=1e-9)
    assert mp.d_same_km == pytest.approx(np.max(np.linalg.norm(2 * x[:, :3] * [0, 0, 1], axis=1)) * em.length_unit_km)


def test_relative_rms_agrees_with_the_crlb_and_splits_absolute_from_relative():
    sc = wj.test_case_2()
    t, k, _ = sc.node_times(12)
    x_ws = sc.ballistic_guess(t)[0][k]
    ab, rel, common = S.relative_rms_km(sc, x_ws)
    assert ab == pytest.approx(wj.evaluate_crlb(sc, x_ws).terminal_rms_km, rel=1e-10)
    # the mean position of four objects cannot be worse known than the worst of them
    assert common <= ab.max() * (1 + 1e-12) and rel.shape == (3,)


def test_gradient_check_and_keep_out_scan_on_test_case_2():
    sc = wj.test_case_2()
    t, k, _ = sc.node_times(12)
    info = sc.information_model()
    x_ws = sc.ballistic_guess(t)[0][k]
    gc = S.gradient_check(info, x_ws, sc.system)
    assert gc.relative_error < 1e-5 and gc.value == pytest.approx(gc.value_order1)
    assert abs(gc.gradient[2]) < 1e-8 and gc.mi_vz_up > 0 and gc.mi_vz_down > 0  # planar: a saddle in z
    scan = S.keep_out_scan(sc, info, x_ws, 3)
    assert scan.gain[0] > scan.gain[-1]  # flying through target 1 pays in MI
    assert scan.gain_at(scan.d_km[1]) == pytest.approx(scan.gain[1])


def test_noise_reading_spread_uses_only_the_small_readings():
    nr = S.NoiseReadings([("big", 1e-11, 9e4, 9e4, 1.0, 1.0), ("a", 1e-17, 10.0, 20.0, 1.0, 4.0),
                          ("b", 1e-22, 2.0, 20.0, 1.0, 1.0)], [])
    assert nr.spread == (5.0, 4.0)


def _radius(d, mi, rms, closest, binds):
    return S.RadiusRow(d, "cold", 40.0, mi, rms, closest, np.zeros((3, 6)), 0.0, binds, 0.0)


def test_keep_out_study_aggregates_radii_and_the_free_run():
    err = SCvxError("no convergence", [{"accepted": True, "new_cost": -1.0}, {"accepted": False, "new_cost": -9.0},
                                       {"accepted": True, "new_cost": -2.0}])
    free = S.FreeRun(err, np.array([3000.0, 50.0]))
    assert free.failed and free.best_cost == -2.0  # only accepted steps count
    rows = [_radius(10.0, 3.0, 30.0, 10.0, True), _radius(424.0, 2.0, 20.0, 500.0, False),
            _radius(1500.0, 1.0, 10.0, 1500.0, True)]
    ko = S.KeepOutStudy(1e-2, free, np.nan, rows, {}, [], {})
    assert ko.rank_radii == pytest.approx(1.0) and ko.rms_span == pytest.approx(3.0)
    assert "+1.00 across keep-out radii" in ko.radii_text
    assert S.KeepOutStudy(1e-2, free, np.nan, rows[:2], {}, [], {}).rank_radii is None


def test_mirror_study_flags_seeds_that_are_mirror_images():
    base = dict(pair=None, pair_alphas=(5e-3, 5e-3), alpha=5e-3, optimum=None, twin=None, seeded={})
    good = S.MirrorStudy(**base, twin_dcost=1e-9, twin_km=0.1, rows=[(5e-3, 1.0, -1.0, 1e-9, 0.3, -1.0, -1.1)])
    assert good.twin_is_optimum and good.seeds_mirror
    bad = S.MirrorStudy(**base, twin_dcost=1e-3, twin_km=0.1, rows=[(5e-3, 1.0, 1.0, 1e-9, 2.0, -1.0, -1.1)])
    assert not bad.twin_is_optimum and not bad.seeds_mirror


def test_departures_count_the_grids_above_the_threshold():
    assert Departures([1.0], 0.5, {16: 0.5, 14: 1.0, 24: 0.81}, []).dep_pass == 2


# ---------------------------------------------------------------------------------------------------------------
# The executor paths (round 2): queued runs give the serial results, whatever runs them
# ---------------------------------------------------------------------------------------------------------------


def test_penalty_study_reuses_the_multi_start_ballistic_run_bit_for_bit(case1):
    # notebook 05 hands the multi-start's ballistic start at 5e-3 to the penalty study as its cold run: the same plan
    # as the study's own solve, bit for bit, and used as given
    own = S.penalty_study(case1, [1e1], 1, 2)
    ms = global_search.multi_start(case1.solver, [5e-3], n_random=0, seeds_z=False, neighbours=False)
    start = next(o.result for o in ms.at(5e-3) if o.label == "ballistic")
    assert np.array_equal(start.x, own.cold.x) and np.array_equal(start.u, own.cold.u)
    assert (start.cost, start.information, start.iterations) == (own.cold.cost, own.cold.information,
                                                                 own.cold.iterations)
    given = S.penalty_study(case1, [1e1], 1, 2, cold=start)
    assert given.cold is start and [r["outcome"] for r in given.runs] == [r["outcome"] for r in own.runs]
    with pytest.raises(ValueError, match="cold"):
        S.penalty_study(case1, [1e1], 1, 2, alpha=0.0, cold=start)


def test_the_upward_sweeps_first_plan_stands_for_the_multi_start_ballistic_start(case1):
    # notebook 05 hands the upward sweep's first plan (alpha_h = 0 from the ballistic DRO) to the multi-start as its
    # ballistic start there: the outcomes are those of solving it, bit for bit (labels, order, costs, optima)
    assert case1.sweep.source[0] == "up"
    gs_known = global_search.known_from_sweep(case1.sweep, [0.0])
    solved = global_search.multi_start(case1.solver, [0.0], n_random=0, seeds_z=False, known=gs_known)
    known = {0.0: gs_known[0.0] + [("ballistic", case1.best[0])]}
    reused = global_search.multi_start(case1.solver, [0.0], n_random=0, seeds_z=False, known=known)
    fields = ("alpha", "label", "converged", "cost", "impulse_mps", "mi", "iterations", "optimum")
    assert [tuple(getattr(o, f) for f in fields) for o in solved.outcomes] == [
        tuple(getattr(o, f) for f in fields) for o in reused.outcomes]
    assert [o.label for o in reused.outcomes] == ["sweep (up)", "ballistic"]
    b_solved, b_reused = solved.outcomes[1].result, reused.outcomes[1].result
    assert np.array_equal(b_solved.x, b_reused.x) and np.array_equal(b_solved.u, b_reused.u)


def test_penalty_study_is_the_same_with_an_executor(case1):
    serial = S.penalty_study(case1, [1e1, 1e3], 2, 3)
    with ThreadPoolExecutor(max_workers=2) as ex:
        queued = S.penalty_study(case1, [1e1, 1e3], 2, 3, executor=ex)
    # the gamma sweep, then gamma 1e3 with the long limit; the hybrid apart with the quadratic model
    assert [(r["gamma"], r["max_iter"], r["model"]) for r in serial.runs] == [(1e1, 2, "linear"), (1e3, 2, "linear"),
                                                                              (1e3, 3, "linear")]
    assert serial.hybrid["model"] == "quadratic" and serial.long_run["max_iter"] == 3
    assert serial.printed is serial.runs[1]
    for a, b in zip(serial.runs + [serial.hybrid], queued.runs + [queued.hybrid]):
        assert a["converged"] == b["converged"] and a["outcome"] == b["outcome"]
        assert np.array_equal(a["best"], b["best"], equal_nan=True)  # NaN: no step accepted yet
        assert len(a["history"]) == len(b["history"]) <= a["max_iter"]
    assert serial.cold.cost == queued.cold.cost and serial.cold.max_defect <= 1e-9  # our solver converges


@pytest.fixture(scope="module")
def case2_small():
    sc = wj.test_case_2()
    t, k_ws, k_we = sc.node_times(10)
    solver = wj.ScenarioSolver(sc, t, k_ws, keep_out=True, settings=scvx.SCvxSettings(max_iter=60))
    x_ball, u_ball = sc.ballistic_guess(t)
    return sc, solver, k_ws, k_we, x_ball, u_ball


def test_case2_runs_serial_and_queued_agree_and_an_alt_grid_equal_to_the_main_one_repeats_it(case2_small):
    sc, solver, k_ws, k_we, x_ball, u_ball = case2_small
    serial = S.case2_runs(sc, solver, [0.0], x_ball, u_ball, seed_alphas=[0.0], alt_nodes=[10])
    with ThreadPoolExecutor(max_workers=2) as ex:
        queued = S.case2_runs(sc, solver, [0.0], x_ball, u_ball, seed_alphas=[0.0], alt_nodes=[10], executor=ex)
    for r in (serial, queued):
        assert set(r.seeded) == {(0.0, 1), (0.0, -1)} and set(r.alt) == {10}
        t_alt, k_alt, sw = r.alt[10]
        assert np.array_equal(t_alt, solver.t) and k_alt == k_ws  # the same grid: the same sweep
        assert sw.best[0].cost == r.sweep.best[0].cost
    assert queued.sweep.best[0].cost == serial.sweep.best[0].cost
    for key, res in serial.seeded.items():
        other = queued.seeded[key]
        assert type(res) is type(other)
        if not isinstance(res, SCvxError):
            assert res.cost == other.cost
    # the +z and -z seeds are mirror images and so is the problem (z -> -z): equal costs when both converge
    p, m = serial.seeded[(0.0, 1)], serial.seeded[(0.0, -1)]
    if not isinstance(p, SCvxError) and not isinstance(m, SCvxError):
        assert p.cost == pytest.approx(m.cost, rel=1e-6)
    with pytest.raises(ValueError):
        S.case2_runs(sc, solver, [0.0], x_ball, u_ball, alt_nodes=[2])
    with pytest.raises(ValueError, match="alt_directions"):
        S.case2_runs(sc, solver, [0.0], x_ball, u_ball, alt_nodes=[10], alt_directions=["across"])


def test_case2_runs_one_way_alt_grid_runs_only_that_chain(case2_small):
    """``alt_directions`` reaches the other grids only: the main sweep stays two-way, the alt grid runs the
    downward chain alone, whose plan is that chain's plan of the two-way sweep on the same grid (same cost)."""
    sc, solver, k_ws, k_we, x_ball, u_ball = case2_small
    r = S.case2_runs(sc, solver, [0.0, 1e-2], x_ball, u_ball, alt_nodes=[10], alt_directions=("down",))
    assert {a["direction"] for a in r.sweep.attempts} == {"up", "down"}
    _, _, sw = r.alt[10]
    assert {a["direction"] for a in sw.attempts} == {"down"} and set(sw.source) <= {"down", ""}  # "": failed
    two_way_down = [a for a in r.sweep.attempts if a["direction"] == "down"]
    assert [(a["alpha"], a["start"], a["converged"]) for a in sw.attempts] == [
        (a["alpha"], a["start"], a["converged"]) for a in two_way_down]
    np.testing.assert_array_equal([a["cost"] for a in sw.attempts], [a["cost"] for a in two_way_down])


def test_queued_keep_out_runs_respect_their_radius(case2_small):
    sc, solver, k_ws, k_we, x_ball, u_ball = case2_small
    sweep = wj.sweep_both_ways(solver, [0.0], x_ball, u_ball)
    case = S.case2_rows(sc, solver, k_ws, k_we, sweep)
    row = case.ok[0]
    with pytest.raises(ValueError):
        S.queue_keep_out_runs(case, row, [1500.0], warm=False)
    with ThreadPoolExecutor(max_workers=2) as ex:
        jobs = S.queue_keep_out_runs(case, row, [1500.0], warm=True, executor=ex)
        free = S.free_run(sc, solver.t, k_ws, solver.information, 0.0, x_ball, u_ball, 2)
        ko = jobs.collect(free)
    serial = S.queue_keep_out_runs(case, row, [1500.0], warm=True).collect(free)
    assert [r.d for r in ko.radius_rows] == [sc.keep_out_km, 1500.0] and ko.radius_rows[1].src == "warm"
    r15 = ko.radius_rows[1]
    assert r15.closest >= 1500.0 * (1 - 1e-3)  # the keep-out holds at every measurement
    assert r15.dv == serial.radius_rows[1].dv
    # one solve per other a_max reading of Table 5, same labels serial or queued
    assert len(ko.amax_rows) + len(ko.amax_failed) == len(wj.A_MAX_READINGS_CASE2_KM_S2) - 1
    assert [a[0] for a in ko.amax_rows] == [a[0] for a in serial.amax_rows]
