"""Observer sites: station geometry, horizon and occultation tests, coverage of the 9:2 NRHO."""

import numpy as np
import pytest

from cislunar import orbits, sites
from cislunar.dynamics import EARTH_MOON as em
from cislunar.propagation import propagate


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
