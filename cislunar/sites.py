r"""Observer sites of the maneuver-detection paper (Greaves & Scheeres 2021, "Measurements" section, Fig. 3).

The paper places optical observers near L2, on a distant retrograde orbit (DRO) and at three lunar-surface
stations, and shows them only in its Fig. 3, which is not in the text: no observer state is given.  The sites below are this reproduction's
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

    def __post_init__(self):
        if not isinstance(self.name, str):
            raise _checks.ArgumentTypeError(f"name must be a str; got {type(self.name).__name__}")
        _checks.in_range(self.latitude_deg, "latitude_deg", -90.0, 90.0)
        _checks.in_range(self.longitude_deg, "longitude_deg", -360.0, 360.0)

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
    _checks.system(system)
    lat = np.deg2rad(_checks.in_range(latitude_deg, "latitude_deg", -90.0, 90.0))
    lon = np.deg2rad(_checks.in_range(longitude_deg, "longitude_deg", -360.0, 360.0))
    up = np.array([-np.cos(lat) * np.cos(lon), -np.cos(lat) * np.sin(lon), np.sin(lat)])
    return system.secondary_position + system.secondary_radius * up


def station_elevation(system: CR3BP, station_position, target_positions) -> np.ndarray:
    """Elevation (rad) of targets ``(..., >=3)`` above a surface station's local horizon."""
    _checks.system(system)
    s = _checks.as_array(station_position, "station_position", ndim=(1,))
    if s.size not in (3, 6):
        raise ValueError(f"station_position must be a position (3,) or a state (6,); got shape {s.shape}")
    s = s[:3]
    t = _position_stack(target_positions, "target_positions")
    up = s - system.secondary_position
    if abs(np.linalg.norm(up) - system.secondary_radius) > 1e-6 * system.secondary_radius:
        raise ValueError("station_position must lie on the Moon's surface (use surface_station_position)")
    up = up / np.linalg.norm(up)
    rel = t - s
    rng = np.linalg.norm(rel, axis=-1)
    if np.any(rng == 0):
        raise ValueError("target_positions coincide with the station (zero range)")
    return np.arcsin(np.clip(rel @ up / rng, -1.0, 1.0))


def _position_stack(value, name):
    a = _checks.as_array(value, name)
    if a.ndim == 0 or a.shape[-1] not in (3, 6):
        raise ValueError(f"{name} must have positions (..., 3) or states (..., 6) on its last axis; got shape "
                         f"{a.shape}")
    return a[..., :3]


def line_of_sight_clear(system: CR3BP, observer_positions, target_positions, *, body: str = "moon") -> np.ndarray:
    """True where the segment observer-target does not pass through the Moon (or Earth) sphere.

    Parameters
    ----------
    observer_positions, target_positions : array_like, shape (..., >=3)
        Broadcastable positions, LU.
    body : {"moon", "earth"}
    """
    _checks.system(system)
    _checks.choice(body, "body", ("moon", "earth"))
    c = system.secondary_position if body == "moon" else system.primary_position
    radius = system.secondary_radius if body == "moon" else system.primary_radius
    o = _position_stack(observer_positions, "observer_positions")
    t = _position_stack(target_positions, "target_positions")
    try:
        np.broadcast_shapes(o.shape, t.shape)
    except ValueError:
        raise ValueError(f"observer_positions and target_positions do not broadcast: {o.shape} vs {t.shape}") from None
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
    _checks.system(system)
    return np.r_[system.libration_points()[1], np.zeros(3)]


#: x-axis crossing of the DRO observer (Wolf & Jones test case 1 target, Table 2), LU.
DRO_OBSERVER_X0 = 0.778008526


def dro_observer_orbit(system: CR3BP):
    """The DRO observer's orbit: the periodic DRO through ``x0 = 0.778008526`` LU (about 16.2 days)."""
    from .orbits import correct_symmetric

    _checks.system(system)
    return correct_symmetric(system, [DRO_OBSERVER_X0, 0, 0, 0, 0.556190606, 0], fix="x0", label="DRO observer")


def surface_coverage(system: CR3BP, target_positions, stations=DEFAULT_STATIONS, *, min_elevation_deg: float = 0.0):
    """Visibility of targets ``(m, >=3)`` from each surface station (elevation above ``min_elevation_deg``).

    Returns
    -------
    ndarray of bool, shape (len(stations), m)
    """
    _checks.system(system)
    t = _checks.as_array(target_positions, "target_positions", ndim=(2,))
    _position_stack(t, "target_positions")
    _checks.in_range(min_elevation_deg, "min_elevation_deg", -90.0, 90.0)
    stations = _checks.one_or_many(stations, "stations", SurfaceStation, "SurfaceStation")
    for st in stations:
        _checks.instance(st, "stations", SurfaceStation, "a sequence of cislunar.sites.SurfaceStation")
    return np.array([station_elevation(system, s.position(system), t) > np.deg2rad(min_elevation_deg)
                     for s in stations])
