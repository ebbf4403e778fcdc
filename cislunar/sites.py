r"""Observer sites of the maneuver-detection paper (Greaves & Scheeres 2021, "Measurements" section, Fig. 3).

The paper places optical observers near L2, on a distant retrograde orbit (DRO) and at three lunar-surface
stations, but its table of observer states is missing from the text.  The sites below are this reproduction's
documented choices; notebook 01 checks what the paper *says* about them (the L2 observer's line of sight to
the NRHOs is never blocked; three surface stations are needed to see the whole 9:2 orbit).

* **L2 observer**: at rest at the L2 libration point (an equilibrium of the rotating frame).
* **DRO observer**: on the DRO through the Wolf & Jones target state ``x0 = 0.778008526`` (period about
  16.2 days), a quiescent orbit at lunar distance.
* **Lunar surface stations**: fixed points on the Moon's surface in the rotating frame (the Moon is tidally
  locked).  Selenographic latitude is measured from the Earth-Moon plane towards +z; longitude 0 faces the Earth
  (the -x direction from the Moon's centre) and increases towards -y (the Moon's orbital motion is +y).

Frames: rotating, barycentric origin, LU; a station's horizon is the plane normal to its local vertical.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import _checks
from .dynamics import CR3BP

__all__ = ["SurfaceStation", "surface_station_position", "station_elevation", "line_of_sight_clear",
           "DEFAULT_STATIONS", "l2_observer_state", "dro_observer_orbit", "surface_coverage", "DRO_OBSERVER_X0"]


@dataclass(frozen=True)
class SurfaceStation:
    """A lunar surface station.

    Attributes
    ----------
    name : str
    latitude_deg, longitude_deg : float
        Selenographic latitude and longitude (convention in the module docstring), degrees.
    """

    name: str
    latitude_deg: float
    longitude_deg: float

    def position(self, system: CR3BP) -> np.ndarray:
        """Position in the rotating frame, LU (barycentric origin)."""
        return surface_station_position(system, self.latitude_deg, self.longitude_deg)


#: Three stations chosen so that together they see the whole southern 9:2 NRHO (checked in notebook 01 and the
#: tests): a grid search over layouts "one southern station + a pair mirrored in longitude" maximising the worst
#: elevation of the best-placed station over the orbit (sampled densely through perilune) picked the south pole,
#: under the apolune region, and two stations at 45 deg N, 90 deg E and W, which see the fast perilune passage over
#: the north pole from either side.  The target is always at least 12 deg above some station's horizon, and no
#: pair of the three covers the orbit.
DEFAULT_STATIONS = (
    SurfaceStation("south pole", -90.0, 0.0),
    SurfaceStation("45N 90E", 45.0, 90.0),
    SurfaceStation("45N 90W", 45.0, -90.0),
)


def surface_station_position(system: CR3BP, latitude_deg: float, longitude_deg: float) -> np.ndarray:
    """Rotating-frame position (LU) of a point on the Moon's mean sphere at the given selenographic coordinates."""
    lat = np.deg2rad(_checks.in_range(latitude_deg, "latitude_deg", -90.0, 90.0))
    lon = np.deg2rad(_checks.in_range(longitude_deg, "longitude_deg", -360.0, 360.0))
    up = np.array([-np.cos(lat) * np.cos(lon), -np.cos(lat) * np.sin(lon), np.sin(lat)])
    return system.secondary_position + system.secondary_radius * up


def station_elevation(system: CR3BP, station_position, target_positions) -> np.ndarray:
    """Elevation (rad) of targets ``(..., >=3)`` above a surface station's local horizon."""
    s = _checks.as_array(station_position, "station_position", ndim=(1,))[:3]
    t = _checks.as_array(target_positions, "target_positions")[..., :3]
    up = s - system.secondary_position
    up = up / np.linalg.norm(up)
    rel = t - s
    rng = np.linalg.norm(rel, axis=-1)
    if np.any(rng == 0):
        raise ValueError("target_positions coincide with the station (zero range)")
    return np.arcsin(np.clip(rel @ up / rng, -1.0, 1.0))


def line_of_sight_clear(system: CR3BP, observer_positions, target_positions, *, body: str = "moon") -> np.ndarray:
    """True where the segment observer-target does not pass through the Moon (or Earth) sphere.

    Parameters
    ----------
    observer_positions, target_positions : array_like, shape (..., >=3)
        Broadcastable positions, LU.
    body : {"moon", "earth"}
    """
    if body not in ("moon", "earth"):
        raise ValueError(f"body must be 'moon' or 'earth'; got {body!r}")
    c = system.secondary_position if body == "moon" else system.primary_position
    radius = system.secondary_radius if body == "moon" else system.primary_radius
    o = _checks.as_array(observer_positions, "observer_positions")[..., :3]
    t = _checks.as_array(target_positions, "target_positions")[..., :3]
    d = t - o
    dd = np.sum(d * d, axis=-1)
    if np.any(dd == 0):
        raise ValueError("observer and target positions coincide (zero range)")
    # closest approach of the segment to the body's centre
    s = np.clip(np.sum((c - o) * d, axis=-1) / dd, 0.0, 1.0)
    closest = o + s[..., None] * d
    return np.linalg.norm(closest - c, axis=-1) > radius


def l2_observer_state(system: CR3BP) -> np.ndarray:
    """State of the L2 observer: at rest at L2, shape (6,)."""
    return np.r_[system.libration_points()[1], np.zeros(3)]


#: x-axis crossing of the DRO observer (Wolf & Jones test case 1 target, Table 2), LU.
DRO_OBSERVER_X0 = 0.778008526


def dro_observer_orbit(system: CR3BP):
    """The DRO observer's orbit: the periodic DRO through ``x0 = 0.778008526`` LU (about 16.2 days)."""
    from .orbits import correct_symmetric

    return correct_symmetric(system, [DRO_OBSERVER_X0, 0, 0, 0, 0.556190606, 0], fix="x0", label="DRO observer")


def surface_coverage(system: CR3BP, target_positions, stations=DEFAULT_STATIONS, *, min_elevation_deg: float = 0.0):
    """Visibility of targets ``(m, >=3)`` from each surface station (elevation above ``min_elevation_deg``).

    Returns
    -------
    ndarray of bool, shape (len(stations), m)
    """
    t = _checks.as_array(target_positions, "target_positions", ndim=(2,))
    _checks.in_range(min_elevation_deg, "min_elevation_deg", -90.0, 90.0)
    return np.array([station_elevation(system, s.position(system), t) > np.deg2rad(min_elevation_deg)
                     for s in stations])
