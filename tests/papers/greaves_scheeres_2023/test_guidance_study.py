"""Studies of notebook 07 (SSAT and MMD guidance) on small sizes: identities, invariants and consistency."""

from __future__ import annotations

import numpy as np
import pytest

from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.cr3bp.orbits import nrho_9_2
from cislunar.cr3bp.torus import torus_from_orbit
from cislunar.papers.greaves_scheeres_2023 import guidance_study as gs


@pytest.fixture(scope="module")
def pair():
    return gs.demonstration_pair(em, nrho_9_2(em), lead_days=1.0, apolune_range_km=215.0, days=1)


@pytest.fixture(scope="module")
def study(pair):
    return gs.policy_study(em, pair, [1, 3], [1.0], n_grid=60, n_perp=8)


def test_leading_hours():
    h = np.array([1.0, 2.0, 4.0, 8.0])
    assert gs.leading_hours(h, [True, True, False, True]) == 2.0
    assert gs.leading_hours(h, [True] * 4) == 8.0
    assert gs.leading_hours(h, [False, True, True, True]) == 0.0
    with pytest.raises(ValueError, match="shape"):
        gs.leading_hours(h, [True])


def test_coordinate_identities_hold_to_round_off():
    c = gs.coordinate_checks(np.random.default_rng(3))
    assert c.state_round_trip < 1e-12 and c.covariance_round_trip < 1e-12
    assert c.relative_block < 1e-12 and c.range_variance_spread < 1e-12


def test_demonstration_pair_geometry(pair):
    # 24 h after the burn epoch the target is at apolune, where the pair is 215 km apart
    assert pair.baseline.range_km[0, 24] == pytest.approx(215.0, abs=1e-6)
    assert pair.hours[24] == pytest.approx(24.0)
    # a pair of angles knows nothing about range: the prior of both vehicles, sqrt(2) x 20 km
    assert pair.baseline.range_sigma_km[0, 0] == pytest.approx(20.0 * np.sqrt(2.0), rel=1e-9)
    assert 0 < pair.first_hour_drop_percent < 100
    assert max(pair.ekf_difference.values()) < 1e-6
    assert 0.05 < pair.lag_hours < 2.0


def test_equations_as_printed_match_the_package(pair):
    eq = gs.equation_checks(em, pair.agent_x0, pair.target_x0)
    assert eq.eq11 < 1e-12 and eq.eq18 < 1e-10


def test_surrogate_is_the_top_eigenvector(pair):
    s = gs.surrogate_check(em, pair, coast_hours=3, n_grid=400)
    assert s.eigenvalues[0] <= 1e-9 * s.eigenvalues[-1]  # rank 2: two angles
    assert np.linalg.norm(s.direction) == pytest.approx(1.0)
    assert np.allclose(s.Q @ s.direction, s.eigenvalues[-1] * s.direction, rtol=1e-8, atol=1e-12 * s.eigenvalues[-1])
    assert s.within_grid and s.spacing_deg == pytest.approx(np.degrees(np.sqrt(4 * np.pi / 400)))


def test_policy_study_orders_the_policies(study):
    r = study.results[1.0]
    assert r.coast_hours == pytest.approx([1.0, 3.0]) and study.coast_indices == (1, 3)
    assert np.all(r.optimum <= r.mmd + 1e-12) and np.all(r.optimum <= r.grid_median)
    assert np.all(study.sign_percent(1.0) >= 0)  # the selected sign is the better one
    ok = r.perp_best <= 1.02 * r.optimum
    assert study.perpendicular_hours(1.0) == gs.leading_hours(r.coast_hours, ok)


def test_direction_map(pair, study):
    d = gs.direction_map(em, pair, study, coast_hours=3, n_grid=60)
    assert d.range_sigma_km.shape == (60,) and np.linalg.norm(d.line_of_sight) == pytest.approx(1.0)
    # the refined optimum is no worse than the best direction of the same sphere
    assert study.results[1.0].optimum[1] <= d.range_sigma_km.min() + 1e-12
    assert d.los_angle_deg == pytest.approx(90.0 - d.optimum_perp_angle_deg)


def test_tracking_arc_study_runs_and_counts(pair):
    arcs = gs.tracking_arc_study(em, pair, [2], [1, 2], 1.0, n_grid=40, n_perp=6)
    r = arcs.results[2]
    n = arcs.leading_run(2)
    assert 0 <= n <= 2 and np.all(r.mmd_excess_percent[:n] <= 5.0)
    assert arcs.within_hours(2) == (r.coast_hours[n - 1] if n else 0.0)
    assert arcs.worst_excess_percent[0] == pytest.approx(r.mmd_excess_percent.max())


def test_qpo_pair_study_needs_ring_angle_zero(pair):
    torus = torus_from_orbit(nrho_9_2(em), N=15, size_km=100.0)
    with pytest.raises(ValueError, match="include 0"):
        gs.qpo_pair_study(em, torus, pair, [45.0], [1], n_grid=20, n_perp=4)
    q = gs.qpo_pair_study(em, torus, pair, [0.0], [1], n_grid=20, n_perp=4)
    assert q.excess_percent.shape == (1,) and q.percentile.shape == (1,)
    opt, mmd, pct = q.antipode_differences()
    assert opt >= 0 and mmd >= 0 and pct >= 0 and q.mirror_ratio >= 0


def test_optimum_at_and_coast_range(pair, study):
    r = study.results[1.0]
    assert study.optimum_at(1.0, 3) == pytest.approx(r.optimum[1])
    assert np.isnan(study.optimum_at(1.0, 2))
    with pytest.raises(ValueError, match="coast_hours"):
        gs.policy_study(em, pair, [1, 30], [1.0], n_grid=20, n_perp=4)  # the 1-day pair has 24 h of grid


def _same_comparison(a, b):
    for f in ("none", "mmd", "mmd_other", "optimum", "perp_best", "perp_worst", "mmd_percentile", "coast_hours"):
        np.testing.assert_array_equal(getattr(a, f), getattr(b, f), err_msg=f)


def test_sweeps_on_an_executor_match_the_serial_run(pair):
    from concurrent.futures import ThreadPoolExecutor

    torus = torus_from_orbit(nrho_9_2(em), N=15, size_km=100.0)
    kw = {"n_grid": 20, "n_perp": 4}
    serial = gs.policy_study(em, pair, [1, 2], [0.5, 1.0], **kw)
    arcs = gs.tracking_arc_study(em, pair, [1, 2], [1], 1.0, **kw)
    qpo = gs.qpo_pair_study(em, torus, pair, [0.0, 90.0], [1], **kw)
    with ThreadPoolExecutor(2) as ex:
        par = gs.policy_study(em, pair, [1, 2], [0.5, 1.0], executor=ex, **kw)
        arcs_p = gs.tracking_arc_study(em, pair, [1, 2], [1], 1.0, executor=ex, **kw)
        qpo_p = gs.qpo_pair_study(em, torus, pair, [0.0, 90.0], [1], executor=ex, **kw)
    assert list(par.results) == [0.5, 1.0] and list(arcs_p.results) == [1, 2] and list(qpo_p.results) == [0.0, 90.0]
    for dv in (0.5, 1.0):
        _same_comparison(serial.results[dv], par.results[dv])
    for h in (1, 2):
        _same_comparison(arcs.results[h], arcs_p.results[h])
    for a in (0.0, 90.0):
        _same_comparison(qpo.results[a], qpo_p.results[a])
    _same_comparison(qpo.antipode, qpo_p.antipode)
    # the burn sizes are not mixed up: a bigger burn moves the cost further from doing nothing
    r0, r1 = par.results[0.5], par.results[1.0]
    assert np.all(np.abs(r1.optimum - r1.none) > np.abs(r0.optimum - r0.none))


def test_result_methods_and_sweeps_refuse_bad_arguments_by_name(pair, study):
    with pytest.raises(ValueError, match="dv_m_s"):
        study.sign_percent(2.0)  # a burn magnitude the study did not run
    with pytest.raises(ValueError, match="dv_m_s"):
        gs.direction_map(em, pair, study, coast_hours=3, dv_m_s=0.5, n_grid=20)
    with pytest.raises(TypeError, match="ok"):
        gs.leading_hours([1.0, 2.0], [1, 0])  # integers are not booleans
    with pytest.raises(ValueError, match="dv_m_s"):
        gs.policy_study(em, pair, [1], [-1.0], n_grid=20, n_perp=4)
    with pytest.raises(TypeError, match="n_grid"):
        gs.policy_study(em, pair, [1], [1.0], n_grid=2.5)
    with pytest.raises(ValueError, match="arc_hours"):
        gs.tracking_arc_study(em, pair, [-2], [1])
    with pytest.raises(TypeError, match="torus"):
        gs.qpo_pair_study(em, None, pair, [0.0], [1])
    with pytest.raises(ValueError, match="coast_hours"):
        gs.qpo_pair_study(em, torus_from_orbit(nrho_9_2(em), 5, 10.0), pair, [0.0], [30])  # beyond the 24-h grid
