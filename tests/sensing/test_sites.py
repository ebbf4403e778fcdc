"""Observer sites: station geometry, horizon and occultation tests, coverage of the 9:2 NRHO."""

import numpy as np
import pytest

from cislunar.cr3bp import orbits
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.cr3bp.propagation import propagate
from cislunar.sensing import sites


def test_station_positions_lie_on_the_lunar_sphere():
    for lat in (-90, -30, 0, 45, 90):
        for lon in (-120, 0, 60, 180):
            p = sites.surface_station_position(em, lat, lon)
            assert abs(np.linalg.norm(p - em.secondary_position) - em.secondary_radius) < 1e-15
    # longitude 0 on the equator faces the Earth
    p = sites.surface_station_position(em, 0, 0)
    assert np.allclose((p - em.secondary_position) / em.secondary_radius, [-1, 0, 0])


def test_elevation_zenith_and_horizon():
    s = sites.surface_station_position(em, 90, 0)
    up = np.array([0, 0, 1.0])
    assert abs(sites.station_elevation(em, s, s + 0.1 * up) - np.pi / 2) < 1e-12
    assert abs(sites.station_elevation(em, s, s + 0.1 * np.array([1.0, 0, 0]))) < 1e-12
    assert sites.station_elevation(em, s, s - 0.1 * up) < 0
    with pytest.raises(ValueError, match="zero range"):
        sites.station_elevation(em, s, s)


def test_line_of_sight_through_the_moon_is_blocked():
    m = em.secondary_position
    a = m + [-0.1, 0, 0]
    b = m + [0.1, 0, 0]
    assert not sites.line_of_sight_clear(em, a, b)
    assert sites.line_of_sight_clear(em, a, b + [0, 0.05, 0])
    assert sites.line_of_sight_clear(em, a, a + [0, 0.05, 0])  # segment ends before the Moon
    with pytest.raises(ValueError, match="body"):
        sites.line_of_sight_clear(em, a, b, body="sun")


def test_three_default_stations_see_the_whole_9_2_nrho_and_no_pair_does():
    nrho = orbits.nrho_9_2(em)
    t = np.unique(np.r_[np.linspace(0, nrho.period, 3000), nrho.period / 2 + np.linspace(-0.05, 0.05, 501)])
    x = propagate(em, nrho.x0, t, impact=False).x  # dense through perilune, where the pass is fastest
    el = np.array([sites.station_elevation(em, s.position(em), x) for s in sites.DEFAULT_STATIONS])
    assert np.degrees(el.max(axis=0).min()) > 10.0  # always at least 10 deg above some station's horizon
    cov = sites.surface_coverage(em, x)
    assert cov.any(axis=0).all()
    for i in range(3):
        assert not cov[[j for j in range(3) if j != i]].any(axis=0).all()


def test_bad_station_arguments():
    with pytest.raises(ValueError, match="latitude_deg"):
        sites.surface_station_position(em, 95, 0)


def test_site_grid_counts_and_poles():
    g = sites.site_grid(30, 90)
    assert len(g) == 2 + 5 * 4  # one station per pole, four longitudes on each of the five inner latitudes
    assert [s.latitude_deg for s in g if abs(s.latitude_deg) == 90] == [-90.0, 90.0]
    assert sorted({s.longitude_deg for s in g if abs(s.latitude_deg) < 90}) == [-180.0, -90.0, 0.0, 90.0]
    with pytest.raises(ValueError, match="lat_step_deg"):
        sites.site_grid(7, 10)
    with pytest.raises(ValueError, match="lon_step_deg"):
        sites.site_grid(10, -10)
    with pytest.raises(TypeError, match="lon_step_deg"):
        sites.site_grid(10, "10")


def test_pair_coverage_known_geometry_target_over_the_north_pole():
    # A target on the +z axis at Moon-centred distance d is above the horizon of a station at latitude phi
    # exactly when sin(phi) > R / d (the local vertical's component along the target direction exceeds R/d).
    d = 4 * em.secondary_radius
    target = em.secondary_position + [0, 0, d]
    g = sites.site_grid(5, 30)
    pc = sites.pair_coverage(em, np.array([target, target]), g)
    expect = np.array([np.sin(np.radians(s.latitude_deg)) > 0.25 for s in g])
    assert np.array_equal(np.diag(pc.fraction) == 1.0, expect)
    assert np.array_equal(pc.full, expect[:, None] | expect[None, :])


def test_pair_coverage_matches_a_brute_force_loop_and_the_default_stations():
    nrho = orbits.nrho_9_2(em)
    x = nrho.sample(500)[1]
    g = sites.site_grid(30, 60) + sites.DEFAULT_STATIONS
    for mask in (0.0, 10.0):
        pc = sites.pair_coverage(em, x, g, min_elevation_deg=mask, chunk=7)
        cov = sites.surface_coverage(em, x, g, min_elevation_deg=mask)
        brute = np.array([[(cov[i] | cov[j]).mean() for j in range(len(g))] for i in range(len(g))])
        assert np.array_equal(pc.fraction, brute)
        full = [(i, j) for i in range(len(g)) for j in range(i + 1, len(g)) if (cov[i] | cov[j]).all()]
        assert pc.n_full_pairs == len(full)
        i, j = pc.best_pair
        assert i < j and pc.best_fraction == brute[np.triu_indices(len(g), 1)].max()
    with pytest.raises(ValueError, match="stations"):
        sites.pair_coverage(em, x, g[:1])
    with pytest.raises(TypeError, match="stations"):
        sites.pair_coverage(em, x, [g[0], "south pole"])
    with pytest.raises(ValueError, match="target_positions"):
        sites.pair_coverage(em, x[:, :2], g)
    with pytest.raises(ValueError, match="target_positions"):
        sites.pair_coverage(em, np.array([em.secondary_position, em.secondary_position]), g)
    with pytest.raises(ValueError, match="min_elevation_deg"):
        sites.pair_coverage(em, x, g, min_elevation_deg=95)


def test_occultation_outages_match_direct_propagation_and_a_loop():
    nrho = orbits.nrho_9_2(em)
    dro = sites.dro_observer_orbit(em)
    span_days, step_s = 40.0, 600.0
    st = sites.occultation_outages(em, dro, nrho, span_days, step_s)
    t = np.arange(0.0, span_days * 86400.0 + 0.5 * step_s, step_s) / em.time_unit_s

    def exact(orb):  # each sample propagated from x0 over its phase (no interpolation)
        ph, inverse = np.unique(np.mod(t, orb.period), return_inverse=True)
        grid = np.r_[0.0, ph] if ph[0] > 0 else ph
        xs = propagate(em, orb.x0, grid, impact=False).x[-ph.size:]
        return xs[inverse]

    clear = sites.line_of_sight_clear(em, exact(dro), exact(nrho))
    runs, n = [], 0
    for c in clear:  # brute-force run counting
        if not c:
            n += 1
        elif n:
            runs.append(n)
            n = 0
    if n:
        runs.append(n)
    assert len(runs) >= 1  # one outage about every 24 days
    assert st.count == len(runs)
    assert np.allclose(st.durations_h, np.array(runs) * step_s / 3600.0)
    assert st.clear_fraction == clear.mean()
    assert st.mean_interval_days == span_days / len(runs)
    # a fixed observer at L2 never loses the 9:2 NRHO; a target behind the Moon from a fixed point is always hidden
    l2 = sites.occultation_outages(em, sites.l2_observer_state(em), nrho, 20.0, 600.0)
    assert l2.count == 0 and l2.clear_fraction == 1.0 and l2.mean_interval_days == np.inf
    m = em.secondary_position
    hidden = sites.occultation_outages(em, m - [0.1, 0, 0], m + [0.1, 0, 0], 1.0, 3600.0)
    assert hidden.count == 1 and hidden.clear_fraction == 0.0 and hidden.longest_h == 25.0
    with pytest.raises(ValueError, match="span_days"):
        sites.occultation_outages(em, dro, nrho, -1.0)
    with pytest.raises(ValueError, match="step_s"):
        sites.occultation_outages(em, dro, nrho, 1.0, 2 * 86400.0)
    with pytest.raises(ValueError, match="observer"):
        sites.occultation_outages(em, [1.0, 2.0], nrho, 1.0)
    with pytest.raises(TypeError, match="table_points"):
        sites.occultation_outages(em, dro, nrho, 1.0, table_points=100.5)
