"""Informed station keeping on a QPO (Greaves & Scheeres AMOS 2023, Secs. 4-5)."""

from __future__ import annotations

import pickle
from concurrent.futures import ProcessPoolExecutor

import numpy as np
import pytest

from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.cr3bp.orbits import nrho_9_2
from cislunar.cr3bp.propagation import propagate
from cislunar.cr3bp.torus import torus_from_orbit
from cislunar.guidance import ssat
from cislunar.papers.greaves_scheeres_2023 import station_keeping as sk
from cislunar.sensing.measurements import AZIMUTH_ELEVATION

HR = 3600.0 / em.time_unit_s


@pytest.fixture(scope="module")
def torus():
    return torus_from_orbit(nrho_9_2(em), N=15, size_km=100.0)


@pytest.fixture(scope="module")
def surface(torus):
    theta = 2 * np.pi * np.arange(6) / 6 + 0.1
    t_arr = np.array([-6.0, 0.5, 7.0]) * HR
    return sk.station_keeping_surface(em, torus, theta, t_arr, -18 * HR, 12 * HR, progress=False)


def test_two_burn_transfer_reaches_torus_point(torus):
    t_b, t_a = -20 * HR, 3.3 * HR
    xa0 = torus.states([0.0], [t_b])[0, 0]
    theta = np.array([0.7, 2.0, 4.5])
    goal = torus.states(theta, [t_a])[:, 0]
    dv1, dv2, x1 = sk.two_burn_transfer(em, xa0, t_b, t_a, goal)
    # independent check: propagate the burned states with the plain propagator
    x = np.tile(xa0, (3, 1))
    x[:, 3:6] += dv1
    arr = propagate(em, x, np.array([t_b, t_a])).x[:, -1]
    arr[:, 3:6] += dv2
    assert np.max(np.linalg.norm(arr[:, :3] - goal[:, :3], axis=1)) < 1e-9
    assert np.max(np.linalg.norm(arr[:, 3:6] - goal[:, 3:6], axis=1)) < 1e-9
    # after the second burn the agent follows the torus trajectory of its ring angle
    later = propagate(em, arr, np.array([t_a, t_a + 6 * HR])).x[:, -1]
    on = torus.states(theta, [t_a + 6 * HR])[:, 0]
    assert np.max(np.linalg.norm(later - on, axis=1)) < 1e-8
    # the burns are real maneuvers of m/s size for a 100 km torus (not a trivial zero)
    assert np.all(np.linalg.norm(dv1, axis=1) * em.velocity_unit_km_s * 1e3 > 0.1)


def test_newton_converges_quadratically(torus):
    xa0 = torus.states([0.0], [-20 * HR])[0, 0]
    goal = torus.states([3.0], [0.0])[:, 0]
    _, _, hist = sk.position_transfer(em, xa0, -20 * HR, 0.0, goal[:, :3], tol=1e-14)
    h = np.array(hist)
    assert h[-1] <= 1e-14 and len(h) <= 8
    # quadratic: e_{k+1} / e_k^2 bounded while far from round-off
    big = h[h > 1e-11]
    if big.size >= 3:
        ratios = big[2:] / big[1:-1] ** 2
        assert np.all(ratios < 1e6)


def _fail_transfer(_):
    xa0 = nrho_9_2(em).x0
    sk.position_transfer(em, xa0, 0.0, 5 * HR, xa0[:3] + 1e-3, max_iter=1)


def test_transfer_failure_reports_history_and_pickles():
    with pytest.raises(sk.TransferConvergenceError) as info:
        _fail_transfer(None)
    err = info.value
    assert len(err.residuals) == 1 and err.failed == [0] and "residual history" in str(err)
    again = pickle.loads(pickle.dumps(err))
    assert again.residuals == err.residuals and str(again) == str(err)
    with ProcessPoolExecutor(max_workers=1) as pool:
        with pytest.raises(sk.TransferConvergenceError) as info2:
            pool.submit(_fail_transfer, None).result()
    assert info2.value.residuals == err.residuals


def test_surface_batched_equals_loop_and_transfers_hit(torus, surface):
    loop = sk.station_keeping_surface(em, torus, surface.theta, surface.t_arrival, surface.t_burn, surface.t[-1],
                                      batched=False, progress=False)
    assert np.allclose(loop.dv1, surface.dv1, rtol=1e-9, atol=1e-14)
    assert np.allclose(loop.range_sigma_km, surface.range_sigma_km, rtol=1e-8)
    assert surface.transfer_miss.max() < 1e-9
    assert surface.range_sigma_km.shape == (3, 6)
    assert np.all(surface.fuel_m_s > 0)


def test_informed_selection_follows_eq25(torus, surface):
    s = surface
    for j in range(s.t_arrival.size):
        cosu = [s.dv1[j, i] @ s.u_y[j] / np.linalg.norm(s.dv1[j, i]) for i in range(s.theta.size)]
        assert np.allclose(s.alignment[j], cosu)
        assert s.candidates[j, 0] == int(np.argmax(cosu)) and s.candidates[j, 1] == int(np.argmin(cosu))
        assert s.informed[j] in s.candidates[j]
        assert s.range_sigma_km[j, s.informed[j]] == min(s.range_sigma_km[j, s.candidates[j]])
    # u_y is the MMD axis of the unmaneuvered coast burn -> arrival
    j = 1
    t = np.array([s.t_burn, s.t_arrival[j]])
    tgt0 = propagate(em, torus.orbit.x0, np.array([0.0, s.t_burn])).x[-1]
    nom = ssat.propagate_with_impulses(em, np.vstack([s.agent_x0, tgt0]), t)
    _, Ha, _ = AZIMUTH_ELEVATION.evaluate(nom.x[0, -1], nom.x[1, -1])
    e = ssat.mmd_direction(ssat.mmd_matrix(nom.stm[0, -1], Ha))
    assert abs(abs(e @ s.u_y[j]) - 1) < 1e-10
    assert np.all(s.informed_percentile >= 0) and np.all(s.informed_percentile <= 100)


def test_informed_choice_brute_force():
    """Eq. 25 on synthetic burns: both signs of u_y are candidates and the covariance analysis decides."""
    rng = np.random.default_rng(4)
    dv1 = rng.standard_normal((5, 30, 3))
    u_y = rng.standard_normal((5, 3)) * 7.0
    cost = rng.random((5, 30))
    align, cand, pick = sk.informed_choice(dv1, u_y, cost)
    for j in range(5):
        ang = [np.arccos(np.clip(d @ u_y[j] / np.linalg.norm(d) / np.linalg.norm(u_y[j]), -1, 1)) for d in dv1[j]]
        assert cand[j, 0] == int(np.argmin(ang)) and cand[j, 1] == int(np.argmax(ang))
        assert pick[j] == cand[j, int(np.argmin(cost[j, cand[j]]))]
    # make the minus candidate win in row 0 and the plus candidate in row 1
    cost[0, cand[0, 1]], cost[0, cand[0, 0]] = 0.0, 1.0
    cost[1, cand[1, 0]], cost[1, cand[1, 1]] = 0.0, 1.0
    _, _, pick = sk.informed_choice(dv1, u_y, cost)
    assert pick[0] == cand[0, 1] and pick[1] == cand[1, 0]
    with pytest.raises(ValueError, match="u_y"):
        sk.informed_choice(dv1, np.zeros((5, 3)), cost)


def test_informed_choice_projection_reading_brute_force():
    """The projection reading ranks by the burn component along u_y: independent of |u_y|, and unlike the angle
    reading it prefers the larger of two parallel burns."""
    rng = np.random.default_rng(5)
    dv1 = rng.standard_normal((4, 25, 3))
    u_y = rng.standard_normal((4, 3))
    cost = rng.random((4, 25))
    align, cand, pick = sk.informed_choice(dv1, u_y, cost, criterion="projection")
    for j in range(4):
        comp = [d @ u_y[j] / np.linalg.norm(u_y[j]) for d in dv1[j]]
        assert np.allclose(align[j], comp, rtol=1e-14, atol=1e-15)
        assert cand[j, 0] == int(np.argmax(comp)) and cand[j, 1] == int(np.argmin(comp))
        assert pick[j] == cand[j, int(np.argmin(cost[j, cand[j]]))]
    a2, c2, _ = sk.informed_choice(dv1, 3.0 * u_y, cost, criterion="projection")
    assert np.allclose(a2, align, rtol=1e-14, atol=1e-15) and np.array_equal(c2, cand)
    # two burns along +u_y, one ten times the other: same angle, the projection picks the larger
    e = u_y[0] / np.linalg.norm(u_y[0])
    two = np.stack([0.1 * e, 1.0 * e, -0.5 * e])[None]
    one_cost = np.ones((1, 3))
    a_angle, _, _ = sk.informed_choice(two, u_y[:1], one_cost)
    a_proj, c_proj, _ = sk.informed_choice(two, u_y[:1], one_cost, criterion="projection")
    assert np.allclose(a_angle[0], [1.0, 1.0, -1.0], rtol=0, atol=1e-15)  # the angle cannot tell 0.1 from 1
    assert np.allclose(a_proj[0], [0.1, 1.0, -0.5], rtol=1e-15) and c_proj[0, 0] == 1 and c_proj[0, 1] == 2
    with pytest.raises(ValueError, match="criterion"):
        sk.informed_choice(dv1, u_y, cost, criterion="dot")


def test_reselect_matches_informed_choice(surface):
    """StationKeepingSurface.reselect re-runs Eq. 25 on the stored burns; 'angle' gives back the surface's own u*."""
    same = surface.reselect("angle")
    assert np.array_equal(same.informed, surface.informed) and np.array_equal(same.alignment, surface.alignment)
    proj = surface.reselect("projection")
    _, cand, pick = sk.informed_choice(surface.dv1, surface.u_y, surface.range_sigma_km, criterion="projection")
    assert np.array_equal(proj.informed, pick) and np.array_equal(proj.candidates, cand)
    assert np.array_equal(proj.range_sigma_km, surface.range_sigma_km)
    # candidates: the largest component along +u_y and along -u_y; u* is one of them
    rows = np.arange(surface.t_arrival.size)
    assert np.all(proj.alignment[rows, proj.candidates[:, 0]] == proj.alignment.max(axis=1))
    assert np.all(proj.alignment[rows, proj.candidates[:, 1]] == proj.alignment.min(axis=1))
    assert np.all((proj.informed == proj.candidates[:, 0]) | (proj.informed == proj.candidates[:, 1]))
    speed = np.linalg.norm(surface.dv1, axis=-1)
    assert np.allclose(np.abs(proj.alignment) <= speed * (1 + 1e-12), True)


def test_zero_maneuver_point_is_natural_motion(torus):
    theta = np.array([0.0, 1.0])
    s = sk.station_keeping_surface(em, torus, theta, np.array([-2 * HR]), -14 * HR, 6 * HR, agent_theta=0.0,
                                   progress=False)
    assert np.max(np.abs(s.dv1[0, 0])) < 1e-12 and np.max(np.abs(s.dv2[0, 0])) < 1e-12
    tgt = sk.target_trajectory(em, torus.orbit.x0, s.t)
    nat = ssat.propagate_with_impulses(em, s.agent_x0, s.t)
    ref = ssat.ssat_covariance(em, nat, tgt, ssat.initial_covariance(em))
    assert np.isclose(ref.final_range_sigma_km[0], s.range_sigma_km[0, 0], rtol=1e-6)
    # a maneuver buys range information in the linear analysis (no execution errors)
    assert s.range_sigma_km[0, 1] < s.range_sigma_km[0, 0]


def test_tracking_arc_before_the_burn(torus):
    theta = np.array([0.0, 1.0, 2.5])
    kw = dict(agent_theta=0.0, progress=False)
    late = sk.station_keeping_surface(em, torus, theta, np.array([-2 * HR]), -14 * HR, 6 * HR, **kw)
    early = sk.station_keeping_surface(em, torus, theta, np.array([-2 * HR]), -14 * HR, 6 * HR,
                                       t_track_start=-20 * HR, **kw)
    assert np.isclose(early.t[0], -20 * HR) and np.isclose(early.t[-1], 6 * HR)
    assert np.allclose(early.agent_x0, torus.states([0.0], [-20 * HR])[0, 0])
    # same maneuvers (the agent coasts on the torus until the burn), more tracking -> no worse range knowledge
    assert np.allclose(early.dv1, late.dv1, atol=1e-11)
    assert early.transfer_miss.max() < 1e-9
    assert np.all(early.range_sigma_km <= late.range_sigma_km * (1 + 1e-9))
    with pytest.raises(ValueError, match="t_track_start"):
        sk.station_keeping_surface(em, torus, theta, np.array([-2 * HR]), -14 * HR, 6 * HR, t_track_start=-10 * HR)


def test_surface_validation(torus):
    th = np.array([0.0, 1.0])
    with pytest.raises(ValueError, match="t_arrival must be later than t_burn"):
        sk.station_keeping_surface(em, torus, th, np.array([-5.0]) * HR, -4 * HR, 0.0, progress=False)
    with pytest.raises(ValueError, match="t_final"):
        sk.station_keeping_surface(em, torus, th, np.array([1.0]) * HR, -4 * HR, 0.0, progress=False)
    with pytest.raises(ValueError, match="t_arrival"):
        sk.station_keeping_surface(em, torus, th, np.array([1.0, 0.5]) * HR, -4 * HR, 2 * HR, progress=False)
    with pytest.raises(ValueError, match="torus must provide"):
        sk.station_keeping_surface(em, object(), th, np.array([1.0]) * HR, -4 * HR, 2 * HR, progress=False)
    with pytest.raises(ValueError, match="theta"):
        sk.station_keeping_surface(em, torus, np.array([np.nan]), np.array([1.0]) * HR, -4 * HR, 2 * HR,
                                   progress=False)
    with pytest.raises(ValueError, match="t1 must be"):
        sk.position_transfer(em, torus.orbit.x0, 1.0, 0.5, np.zeros(3))


def test_execution_sigma():
    dv = np.array([3.0, 4.0, 0.0])
    assert np.isclose(sk.execution_sigma(dv, 0.1, 0.02), np.sqrt(0.01 + 0.01))
    # a burn that is not made has no execution error; a tiny one has at least the absolute term
    both = sk.execution_sigma(np.array([[0.0, 0.0, 0.0], [1e-12, 0.0, 0.0]]), 0.1, 0.02)
    assert both[0] == 0.0 and abs(both[1] - 0.1) < 1e-15
    with pytest.raises(ValueError, match="sigma_rel"):
        sk.execution_sigma(dv, 0.1, -1)


def test_filter_trial_is_consistent(torus, surface):
    """Mean NEES of a short EKF Monte Carlo lies inside the two-sided 99% chi-square band of 12 N_trials dof."""
    from scipy.stats import chi2

    from cislunar.utils.montecarlo import run_monte_carlo

    tgt0 = propagate(em, torus.orbit.x0, np.array([0.0, surface.t_burn])).x[-1]
    sc = sk.filter_scenario(surface, 1, 2, tgt0, em, exec_sigma_abs_m_s=1e-3, exec_sigma_rel=0.01)
    n = 24
    res = run_monte_carlo(sk.filter_trial, n, 7, args=(sc,), progress=False)
    assert all(r.failure == "" for r in res)
    nees = np.array([r.nees for r in res])
    mean_last = nees[:, -1].mean()
    lo, hi = chi2.ppf([0.005, 0.995], 12 * n) / n
    assert lo < mean_last < hi
    # the filter's range sigma matches the scatter of the achieved range errors within sampling error
    err = np.array([r.range_error_km[-1] for r in res])
    sig = np.mean([r.range_sigma_km[-1] for r in res])
    assert 0.5 * sig < np.sqrt(np.mean(err**2)) < 1.6 * sig


def test_mmd_horizon_final(torus, surface):
    """mmd_horizon="final": one u_y for every row, the MMD axis of the coast t_burn -> t_final; same maneuvers and costs."""
    s = sk.station_keeping_surface(em, torus, surface.theta, surface.t_arrival, surface.t_burn, surface.t[-1],
                                   mmd_horizon="final", progress=False)
    assert np.allclose(s.dv1, surface.dv1) and np.allclose(s.range_sigma_km, surface.range_sigma_km)
    t = np.array([s.t_burn, s.t[-1]])
    tgt0 = propagate(em, torus.orbit.x0, np.array([0.0, s.t_burn])).x[-1]
    nom = ssat.propagate_with_impulses(em, np.vstack([s.agent_x0, tgt0]), t)
    _, Ha, _ = AZIMUTH_ELEVATION.evaluate(nom.x[0, -1], nom.x[1, -1])
    e = ssat.mmd_direction(ssat.mmd_matrix(nom.stm[0, -1], Ha))
    assert np.allclose(np.abs(s.u_y @ e), 1.0, atol=1e-10)
    assert not np.allclose(np.abs(surface.u_y @ e), 1.0, atol=1e-3)  # the arrival horizon differs
    with pytest.raises(ValueError, match="mmd_horizon"):
        sk.station_keeping_surface(em, torus, surface.theta, surface.t_arrival, surface.t_burn, surface.t[-1],
                                   mmd_horizon="tf", progress=False)


def test_slice_statistics_by_hand(surface):
    """Percentiles and fuel of the informed maneuver recomputed from the raw arrays (a factor or an off-by-one fails)."""
    s = surface
    V = em.velocity_unit_km_s * 1e3
    fuel = (np.linalg.norm(s.dv1, axis=-1) + np.linalg.norm(s.dv2, axis=-1)) * V
    assert np.allclose(s.fuel_m_s, fuel)
    for j in range(s.t_arrival.size):
        i = s.informed[j]
        assert np.isclose(s.informed_percentile[j], 100 * np.sum(s.range_sigma_km[j] < s.range_sigma_km[j, i]) / s.theta.size)
        assert np.isclose(s.informed_fuel_percentile[j], 100 * np.sum(fuel[j] > fuel[j, i]) / s.theta.size)
    assert np.allclose(s.t_arrival_hours, [-6.0, 0.5, 7.0])
    assert np.allclose(s.phase, s.theta / (2 * np.pi))


def test_slice_best_is_the_valley(surface):
    """The best maneuver of each slice: nothing in its slice is smaller, and its own percentile would be 0."""
    s = surface
    for j in range(s.t_arrival.size):
        row = s.range_sigma_km[j]
        assert s.best_range_sigma_km[j] == row[s.best[j]]
        assert np.all(row >= s.best_range_sigma_km[j])
        assert np.sum(row < row[s.best[j]]) == 0
    # u* cannot beat the slice best; where u* is the best, its percentile is 0
    assert np.all(s.informed_range_sigma_km >= s.best_range_sigma_km)
    same = s.informed == s.best
    assert np.all(s.informed_percentile[same] == 0) and np.all(s.informed_percentile[~same] > 0)


def test_first_burn_only_identities(torus):
    """At the agent's own ring angle both burns are zero, so flying the first burn only changes nothing (identity);
    elsewhere dropping a non-zero second burn changes sqrt(J_rho)."""
    from dataclasses import replace

    theta = np.array([0.0, 2.0, 4.0])
    t_arr = np.array([-4.0, 3.0]) * HR
    s = sk.station_keeping_surface(em, torus, theta, t_arr, -16 * HR, 8 * HR, progress=False)
    # zero up to the transfer solver's round-off (about 1e-9 m/s on some CPUs; a real burn is >= 1e-3 m/s here)
    assert np.all(s.fuel_m_s[:, 0] < 1e-7)
    at_agent = replace(s, informed=np.zeros(2, dtype=int))
    only = sk.first_burn_only_range_sigma_km(em, at_agent, torus.orbit.x0)
    assert np.allclose(only, s.range_sigma_km[:, 0], rtol=1e-7, atol=0)  # integration grids differ slightly
    same = sk.first_burn_only_range_sigma_km(em, s, torus.orbit.x0, informed=np.zeros(2))
    assert np.array_equal(same, only)
    moved = sk.first_burn_only_range_sigma_km(em, s, torus.orbit.x0, informed=np.array([1, 2]))
    full = s.range_sigma_km[[0, 1], [1, 2]]
    assert np.all(s.dv2_m_s[[0, 1], [1, 2]] > 1e-3)
    assert np.all(np.abs(moved / full - 1) > 1e-3)
    with pytest.raises(ValueError, match="informed"):
        sk.first_burn_only_range_sigma_km(em, s, torus.orbit.x0, informed=np.array([0, 3]))
    with pytest.raises(TypeError, match="surface"):
        sk.first_burn_only_range_sigma_km(em, "surface", torus.orbit.x0)
