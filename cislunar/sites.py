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
           "DEFAULT_STATIONS", "l2_observer_state"]


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


#: Three stations chosen so that together they see the whole southern 9:2 NRHO (checked in notebook 01):
#: one at the north pole (under perilune), one on the far side at the equator (facing L2 and the apolune region)
#: and one at 60 deg south on the far side.
DEFAULT_STATIONS = (
    SurfaceStation("north pole", 90.0, 0.0),
    SurfaceStation("far-side equator", 0.0, 180.0),
    SurfaceStation("far-side south", -60.0, 180.0),
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
