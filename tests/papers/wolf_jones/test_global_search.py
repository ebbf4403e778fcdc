"""Multi-start, lower envelope and mesh study of the Wolf & Jones SCvx plans (issue 22, item 1), on small grids."""

from __future__ import annotations

import dataclasses
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cislunar.guidance import discretization as D
from cislunar.guidance import scvx
from cislunar.papers.wolf_jones import global_search as gs
from cislunar.papers.wolf_jones import scenarios as wj

N = 10  # nodes of the test grid (test case 1)
A = 5e-3


@pytest.fixture(scope="module")
def setup():
    sc = wj.test_case_1()
    t, k, _ = sc.node_times(N, 1.0)
    return sc, t, k, wj.ScenarioSolver(sc, t, k, settings=scvx.SCvxSettings())


@pytest.fixture(scope="module")
def ms(setup):
    return gs.multi_start(setup[3], [A], rng=np.random.default_rng(7), n_random=1, neighbours=False)


def _fake(res, cost, x=None):
    return dataclasses.replace(res, cost=cost, x=res.x if x is None else x)


# --------------------------------------------------------------------------------------------------------------
# multi-start
# --------------------------------------------------------------------------------------------------------------
def test_multi_start_is_never_worse_than_its_best_single_start(setup, ms):
    """Each start solved on its own (same guesses, the random one drawn from the same seed): the multi-start's
    best cost is at most the best of them, and it is the lowest cost among its own converged outcomes."""
    sc, t, k, solver = setup
    guesses = {"ballistic": sc.ballistic_guess(t), "+z seed": sc.seeded_guess(t, +1, 0.05),
               "-z seed": sc.seeded_guess(t, -1, 0.05),
               "random 1": gs._random_guess(sc, t, solver.u_max, np.random.default_rng(7), 0.05)}
    single = {}
    for lab, (x, u) in guesses.items():
        try:
            single[lab] = solver(A, x, u).cost
        except scvx.SCvxError:
            pass
    assert single, "no single start converged: the test says nothing"
    (best,) = ms.best
    assert best.cost <= min(single.values())
    conv = [o for o in ms.outcomes if o.converged]
    assert best.cost == min(o.cost for o in conv)
    assert {o.label for o in ms.outcomes} == set(guesses)
    for o in conv:  # each outcome is the same deterministic solve as the single start
        assert o.cost == single[o.label]
    lo, hi = ms.cost_range[0]
    assert lo == best.cost and hi == max(single.values())
    assert ms.n_distinct[0] >= 1 and all(o.optimum >= 0 for o in conv)
    assert next(o for o in ms.outcomes if o.result is best).optimum == 0


def test_a_known_better_plan_is_kept_and_a_known_label_is_not_solved_again(setup, ms):
    sc, t, k, solver = setup
    (b,) = ms.best
    fake = _fake(b, b.cost - 1.0)
    out = gs.multi_start(solver, [A], known={A: [("ballistic", fake)]}, n_random=0, seeds_z=False, neighbours=False)
    assert out.best[0] is fake and out.best_label == ("ballistic",)
    assert len(out.outcomes) == 1  # the ballistic start was known: not solved
    assert out.improvements([b]) == [(A, b.cost, fake.cost, "ballistic")]
    assert out.improvements([fake]) == []


def test_known_ballistic_plans_are_the_sweeps_cold_starts_only():
    # a two-way sweep (scenarios.sweep_both_ways) names each run's start: a best plan whose converged run in its
    # chain was a cold start was solved from the sweep's guess (the multi-start's ballistic start); a warm one not
    p = {k: object() for k in "abcd"}
    att = [dict(alpha=0.0, direction="up", start="cold", converged=True),
           dict(alpha=0.5, direction="up", start="warm", converged=False),
           dict(alpha=0.5, direction="up", start="cold", converged=True),  # warm failed, retried cold
           dict(alpha=0.7, direction="up", start="warm", converged=True),
           dict(alpha=1.0, direction="up", start="warm", converged=True),
           dict(alpha=1.0, direction="down", start="cold", converged=True),
           dict(alpha=0.7, direction="down", start="cold", converged=True),  # cold, but the best came from up
           dict(alpha=0.5, direction="down", start="warm", converged=True),
           dict(alpha=0.0, direction="down", start="warm", converged=True)]
    sweep = scvx.SweepResult(np.array([0.0, 0.5, 0.7, 1.0]), [p["a"], p["b"], p["c"], p["d"]],
                             ["up", "up", "up", "down"], att)
    assert gs.known_from_sweep(sweep, which="ballistic") == {0.0: [("ballistic", p["a"])], 0.5: [("ballistic", p["b"])],
                                                             1.0: [("ballistic", p["d"])]}
    assert gs.known_from_sweep(sweep, [0.5, 0.7], which="ballistic") == {0.5: [("ballistic", p["b"])]}
    assert gs.known_from_sweep(sweep, [0.7])[0.7] == [("sweep (up)", p["c"])]
    with pytest.raises(ValueError, match="which"):
        gs.known_from_sweep(sweep, which="cold")


def test_multi_start_is_the_same_on_an_executor(setup, ms):
    with ThreadPoolExecutor(max_workers=2) as ex:
        other = gs.multi_start(setup[3], [A], rng=np.random.default_rng(7), n_random=1, neighbours=False,
                               executor=ex)
    assert [(o.label, o.cost, o.optimum) for o in other.outcomes] == [(o.label, o.cost, o.optimum)
                                                                      for o in ms.outcomes]
    assert np.array_equal(other.best[0].x, ms.best[0].x)


def test_distinct_optima_follow_the_stated_tolerances(ms):
    """Same optimum: cost within cost_tol (1 + |J|) and plans (or z-mirrors) within plan_km; else distinct."""
    (b,) = ms.best
    tol_lu = 100.0 / wj.test_case_1().system.length_unit_km
    mirror = b.x * np.array([1, 1, -1, 1, 1, -1.0])
    shifted = b.x.copy()
    shifted[3, 1] += 2 * tol_lu
    near = b.x.copy()
    near[3, 1] += 0.5 * tol_lu
    cases = [_fake(b, b.cost), _fake(b, b.cost * (1 + 1e-8)), _fake(b, b.cost, mirror), _fake(b, b.cost, near),
             _fake(b, b.cost - 1e-3), _fake(b, b.cost, shifted)]
    lab = gs._cluster([cases[0], cases[1], cases[2], cases[3], None], 1e-6, tol_lu)
    assert lab == [0, 0, 0, 0, None]  # equal, round-off cost, z-mirror, 50 km apart: one optimum
    lifted = b.x.copy()
    lifted[:, 2] += 3 * tol_lu  # 300 km out of plane: its z-mirror lies 600 km away, yet is the same optimum
    assert gs._cluster([_fake(b, b.cost, lifted), _fake(b, b.cost, lifted * np.array([1, 1, -1, 1, 1, -1.0]))],
                       1e-6, tol_lu) == [0, 0]
    lab = gs._cluster([cases[0], cases[4]], 1e-6, tol_lu)
    assert lab == [1, 0]  # a lower cost is another optimum, and it comes first
    lab = gs._cluster([cases[0], cases[5]], 1e-6, tol_lu)
    assert lab == [0, 1]  # same cost but 200 km apart: distinct


def test_adopt_takes_the_lower_cost_plan_per_weight_and_keeps_the_sweeps_attempts(setup, ms):
    (b,) = ms.best
    sweep = scvx.SweepResult(np.array([0.0, A]), [None, None], ["", ""], [dict(alpha=A, converged=False)])
    ad = gs.adopt(sweep, ms)
    assert ad.best == [None, b] and ad.attempts is sweep.attempts and ad.source == ["", ms.best_label[0]]
    worse, better = _fake(b, b.cost + 1.0), _fake(b, b.cost - 1.0)
    assert gs.adopt(scvx.SweepResult(np.array([A]), [worse], ["up"], []), ms).best == [b]
    kept = gs.adopt(scvx.SweepResult(np.array([A]), [better], ["up"], []), ms)
    assert kept.best == [better] and kept.source == ["up"]
    with pytest.raises(ValueError, match="weights"):
        gs.adopt(scvx.SweepResult(np.array([0.0]), [None], [""], []), ms)
    assert list(gs.known_from_sweep(kept)) == [A] and gs.known_from_sweep(kept, [0.0]) == {}


def test_extra_starts_join_the_multi_start_and_replace_its_best_only_when_strictly_lower(setup, ms):
    """with_starts: the extra outcomes follow ms's own, are clustered with its tolerances, and become the best only
    with a strictly lower cost; a failed extra start is recorded as failed; the old outcomes are unchanged."""
    solver = setup[3]
    (b,) = ms.best
    lower, tie = _fake(b, b.cost - 1e-3), _fake(b, b.cost)
    err = scvx.SCvxError("diverged")
    out = gs.with_starts(solver, ms, {A: [("mesh 11 (warm)", lower), ("mesh 12 (cold)", err)]})
    assert out.best == (lower,) and out.best_label == ("mesh 11 (warm)",)
    assert [o.label for o in out.outcomes] == [o.label for o in ms.outcomes] + ["mesh 11 (warm)", "mesh 12 (cold)"]
    assert [o.cost for o in out.outcomes[:len(ms.outcomes)]] == [o.cost for o in ms.outcomes]
    failed = out.outcomes[-1]
    assert not failed.converged and failed.error == "diverged" and failed.optimum == -1
    assert out.n_distinct[0] == ms.n_distinct[0] + 1  # 1e-3 lower: another optimum, and the lowest (index 0)
    assert next(o for o in out.outcomes if o.result is lower).optimum == 0
    assert out.improvements([b]) == [(A, b.cost, lower.cost, "mesh 11 (warm)")]
    same = gs.with_starts(solver, ms, {A: [("mesh 11 (warm)", tie)]})
    assert same.best == ms.best and same.best_label == ms.best_label  # a tie keeps the earlier start
    assert same.n_distinct == ms.n_distinct  # the same optimum: no new one counted
    assert gs.with_starts(solver, ms, {}).outcomes == ms.outcomes
    with pytest.raises(ValueError, match="outside ms.alphas"):
        gs.with_starts(solver, ms, {1e-2: []})
    with pytest.raises(TypeError, match=r"extra\[0.005\]\[0\]"):
        gs.with_starts(solver, ms, {A: [lower]})
    with pytest.raises(ValueError, match="node states"):
        gs.with_starts(solver, ms, {A: [("short", _fake(b, b.cost, b.x[:-1]))]})


def test_multi_start_refuses_bad_arguments(setup):
    solver = setup[3]
    with pytest.raises(ValueError, match="alphas"):
        gs.multi_start(solver, [5e-3, 1e-3])
    with pytest.raises(TypeError, match="rng"):
        gs.multi_start(solver, [5e-3], n_random=1)
    with pytest.raises(ValueError, match="known"):
        gs.multi_start(solver, [5e-3], n_random=0, known={1e-2: []})


# --------------------------------------------------------------------------------------------------------------
# lower envelope
# --------------------------------------------------------------------------------------------------------------
def _dominated(p, q, sense):
    """q dominates p: no worse on both axes, better on one."""
    s = 1 if sense == "min" else -1
    return q[0] <= p[0] and s * q[1] <= s * p[1] and (q[0] < p[0] or s * q[1] < s * p[1])


coords = st.floats(min_value=-5, max_value=5, allow_nan=False).map(lambda v: round(v, 1))  # ties are likely


@settings(max_examples=200, deadline=None)
@given(pts=st.lists(st.tuples(coords, coords), min_size=1, max_size=30), sense=st.sampled_from(["min", "max"]))
def test_the_envelope_is_monotone_and_holds_exactly_the_non_dominated_points(pts, sense):
    x, y = np.array(pts).T
    env = gs.lower_envelope(x, y, sense=sense)
    assert env.monotone
    assert np.array_equal(env.x, x[env.index]) and np.array_equal(env.y, y[env.index])
    kept = {(float(a), float(b)) for a, b in zip(env.x, env.y)}
    assert len(kept) == env.index.size  # duplicates kept once
    for p in pts:
        dominated = any(_dominated(p, q, sense) for q in pts)
        assert (tuple(map(float, p)) in kept) == (not dominated)


def test_the_envelope_of_a_front_with_a_dominated_point_drops_it():
    env = gs.lower_envelope([1.0, 2.0, 3.0, 4.0], [10.0, 5.0, 6.0, 1.0])
    assert env.index.tolist() == [0, 1, 3]
    env = gs.lower_envelope([1.0, 2.0, 3.0], [1.0, 3.0, 2.0], sense="max")
    assert env.index.tolist() == [0, 1]


def test_front_points_evaluate_every_distinct_optimum(setup, ms):
    sc, t, k, _ = setup
    fp = gs.front_points(ms, sc, k)
    assert len(fp.alpha) == ms.n_distinct[0]
    c = wj.evaluate_crlb(sc, ms.best[0].x[k]).terminal_rms_km
    assert fp.rms_obs[0] == pytest.approx(c[0]) and fp.rms_tgt[0] == pytest.approx(c[1])
    assert fp.envelope("mi").monotone and fp.envelope().monotone


# --------------------------------------------------------------------------------------------------------------
# mesh
# --------------------------------------------------------------------------------------------------------------
def test_a_nested_refinement_flies_the_same_plan_and_re_converges_no_worse(setup, ms):
    """Nodes added at the midpoints: the plan interpolated onto them is the same FOH control, so it flies the same
    trajectory (every old node reached to 1e-9), spends no more impulse (|u| is convex along each segment), and the
    refined solve from it converges to a cost no higher than the coarse plan's (within 1e-6 (1 + |J|)) and within
    5 % of it."""
    sc, t, k, solver = setup
    (b,) = ms.best
    tf = np.union1d(t, 0.5 * (t[1:] + t[:-1]))
    kf = int(np.flatnonzero(tf == t[k])[0])
    xf, uf = gs._interpolate_plan(t, b.x, b.u, tf)
    flown = D.propagate_foh(sc.system, sc.observer_x0, tf, uf)
    assert np.max(np.abs(flown[::2] - D.propagate_foh(sc.system, sc.observer_x0, t, b.u))) < 1e-9
    assert np.max(np.abs(xf[::2] - b.x)) == 0.0
    assert scvx.impulse(tf, uf) <= b.impulse * (1 + 1e-12)
    fine = wj.ScenarioSolver(sc, tf, kf, information=solver.information, settings=solver.settings)(A, xf, uf)
    assert fine.cost <= b.cost + 1e-6 * (1 + abs(b.cost))
    assert abs(fine.cost - b.cost) <= 0.05 * abs(b.cost)


def test_mesh_study_re_converges_on_other_sundman_grids(setup, ms):
    sc, t, k, solver = setup
    m = gs.mesh_study(solver, {A: ms.best[0]}, [9, 11], cold=False)
    assert m.n_nodes == (9, N, 11) and m.figure_nodes == N
    rows = m.table(A)
    assert [r.n_nodes for r in rows] == [9, N, 11] and all(r.converged for r in rows)
    assert rows[1].start == "figures" and rows[1].result is ms.best[0]
    for r in (rows[0], rows[2]):  # impulse within 10 % of the figures' plan on a grid one node apart
        assert r.start == "warm" and abs(r.impulse_mps / rows[1].impulse_mps - 1) <= 0.10
    # every solve is recorded, and each row is the best converged start of its grid
    assert sorted((n, s) for n, a, s, *_ in m.attempts) == [(9, "warm"), (11, "warm")]
    for r in (rows[0], rows[2]):
        st = m.starts(A, r.n_nodes)
        assert st["warm"] == (r.cost, r.impulse_mps)
    # the finest other grid's plan moved back onto the figures' grid re-converges to the figures' optimum
    back = gs.back_to_grid(solver, m)
    n_back, start, res, gain = back[A]
    assert (n_back, start) == (11, "warm") and not isinstance(res, Exception)
    assert abs(res.cost - rows[1].cost) <= 1e-6 * (1 + abs(rows[1].cost))
    assert gain == (rows[1].cost - res.cost) / (1 + abs(rows[1].cost))
    assert res.cost <= rows[2].cost + 0.05 * abs(rows[2].cost)
    with pytest.raises(ValueError, match="mesh study of solver's grid"):
        gs.back_to_grid(wj.ScenarioSolver(sc, *sc.node_times(9)[:2], information=solver.information,
                                          settings=solver.settings), m)
    ch = m.changes(A)
    assert ch["impulse_mps"][1] == pytest.approx(abs(rows[2].impulse_mps - rows[1].impulse_mps) / rows[1].impulse_mps)
    assert m.converged(A) == all(c[-1] <= m.rtol for c in ch.values())
    # adopting the moved-back plans: the figures' row is replaced only by a strictly lower cost, every moved-back
    # solve is recorded, the other grids are untouched
    kept = gs.with_moved_back(solver, m, back)
    assert kept.attempts[:-1] == m.attempts and kept.attempts[-1][:3] == (N, A, "back 11")
    assert kept.attempts[-1][3] == res.cost
    assert kept.table(A)[1].start == ("back 11" if res.cost < rows[1].cost else "figures")
    lower = _fake(res, rows[1].cost - 1e-3)
    swapped = gs.with_moved_back(solver, m, {A: (11, "warm", lower, 1e-3)})
    new_row = swapped.table(A)[1]
    assert (new_row.start, new_row.cost, new_row.result) == ("back 11", lower.cost, lower)
    assert new_row.rms_km == pytest.approx(wj.evaluate_crlb(sc, lower.x[k]).terminal_rms_km[0])
    assert swapped.table(A)[0] == rows[0] and swapped.table(A)[2] == rows[2]
    failed = gs.with_moved_back(solver, m, {A: (11, "warm", scvx.SCvxError("x"), np.nan)})
    assert failed.rows == m.rows and np.isnan(failed.attempts[-1][3])
    with pytest.raises(ValueError, match="outside the study"):
        gs.with_moved_back(solver, m, {1e-2: (11, "warm", lower, 0.0)})
    with pytest.raises(TypeError, match="back"):
        gs.with_moved_back(solver, m, {A: lower})


def test_mesh_starts_is_the_composition_of_its_steps(setup, ms):
    """mesh_starts = adopt -> mesh_study -> back_to_grid -> with_starts / with_moved_back, the same numbers as the
    steps called by hand; its summary names every moved-back solve; bad weights are refused by name."""
    sc, t, k, solver = setup
    (b,) = ms.best
    sweep = scvx.SweepResult(np.array([A]), [_fake(b, b.cost + 1.0)], ["up"], [])  # the multi-start's plan wins
    out = gs.mesh_starts(solver, sweep, ms, [A], [11], cold=False)
    assert out.before == {A: b}
    m = gs.mesh_study(solver, {A: b}, [11], cold=False)
    back = gs.back_to_grid(solver, m)
    assert [(r.n_nodes, r.start, r.cost) for r in out.study.rows] == [
        (r.n_nodes, r.start, r.cost) for r in gs.with_moved_back(solver, m, back).rows]
    assert out.back[A][:2] == back[A][:2] and out.back[A][3] == back[A][3]
    hand = gs.with_starts(solver, ms, {A: [("mesh 11", back[A][2])]})
    assert [(o.label, o.cost, o.optimum) for o in out.multi.outcomes] == [(o.label, o.cost, o.optimum)
                                                                          for o in hand.outcomes]
    assert out.gains == {A: back[A][3]} and out.changed == ([A] if back[A][3] > 0 else [])
    row = out.back_measurement()  # the closing row of notebooks 05/06: the largest gain, each weight's shown
    assert row["measured"] == back[A][3] and row["shown"] == f"alpha_h {A:g}: gain {back[A][3]:+.1e}"
    assert "adopted" in row["note"]
    assert dataclasses.replace(out, back={}).back_measurement() is None  # nothing moved back: not judged
    text = out.summary(sc.system.velocity_unit_km_s * 1e3)
    assert "the 11-node plan (warm start) moved back to 10 nodes" in text and "mesh study:" in text
    with pytest.raises(ValueError, match="alphas"):
        gs.mesh_starts(solver, sweep, ms, [0.5], [11], cold=False)
