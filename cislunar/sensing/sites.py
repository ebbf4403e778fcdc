r"""Observer sites of the maneuver-detection paper (Greaves & Scheeres 2021, "Measurements" section, Fig. 3).

The paper places optical observers near L2, on a distant retrograde orbit (DRO) and at three lunar-surface
stations, and shows them only in its Fig. 3, which is not in the text: no observer state is given.  The sites
below are this reproduction's documented choices; notebook 01 checks what the paper *says* about them (the L2 observer's line of sight to
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

from cislunar.cr3bp.dynamics import CR3BP, check_system
from cislunar.cr3bp.orbits import PeriodicOrbit, correct_symmetric
from cislunar.utils import validation

__all__ = ["SurfaceStation", "surface_station_position", "station_elevation", "line_of_sight_clear",
           "DEFAULT_STATIONS", "l2_observer_state", "dro_observer_orbit", "surface_coverage", "DRO_OBSERVER_X0",
           "site_grid", "PairCoverage", "pair_coverage", "OutageStatistics", "occultation_outages"]


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
            raise validation.ArgumentTypeError(f"name must be a str; got {type(self.name).__name__}")
        validation.in_range(self.latitude_deg, "latitude_deg", -90.0, 90.0)
        validation.in_range(self.longitude_deg, "longitude_deg", -360.0, 360.0)

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
    check_system(system)
    lat = np.deg2rad(validation.in_range(latitude_deg, "latitude_deg", -90.0, 90.0))
    lon = np.deg2rad(validation.in_range(longitude_deg, "longitude_deg", -360.0, 360.0))
    up = np.array([-np.cos(lat) * np.cos(lon), -np.cos(lat) * np.sin(lon), np.sin(lat)])
    return system.secondary_position + system.secondary_radius * up


def station_elevation(system: CR3BP, station_position, target_positions) -> np.ndarray:
    """Elevation (rad) of targets ``(..., >=3)`` above a surface station's local horizon."""
    check_system(system)
    s = validation.as_array(station_position, "station_position", ndim=(1,))
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
    a = validation.as_array(value, name)
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
    check_system(system)
    validation.choice(body, "body", ("moon", "earth"))
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
    check_system(system)
    return np.r_[system.libration_points()[1], np.zeros(3)]


#: x-axis crossing of the DRO observer (Wolf & Jones test case 1 target, Table 2), LU.
DRO_OBSERVER_X0 = 0.778008526


def dro_observer_orbit(system: CR3BP):
    """The DRO observer's orbit: the periodic DRO through ``x0 = 0.778008526`` LU (about 16.2 days)."""

    check_system(system)
    return correct_symmetric(system, [DRO_OBSERVER_X0, 0, 0, 0, 0.556190606, 0], fix="x0", label="DRO observer")


def surface_coverage(system: CR3BP, target_positions, stations=DEFAULT_STATIONS, *, min_elevation_deg: float = 0.0):
    """Visibility of targets ``(m, >=3)`` from each surface station (elevation above ``min_elevation_deg``).

    Returns
    -------
    ndarray of bool, shape (len(stations), m)
    """
    check_system(system)
    t = validation.as_array(target_positions, "target_positions", ndim=(2,))
    _position_stack(t, "target_positions")
    validation.in_range(min_elevation_deg, "min_elevation_deg", -90.0, 90.0)
    stations = validation.one_or_many(stations, "stations", SurfaceStation, "SurfaceStation")
    for st in stations:
        validation.instance(st, "stations", SurfaceStation, "a sequence of cislunar.sensing.sites.SurfaceStation")
    return np.array([station_elevation(system, s.position(system), t) > np.deg2rad(min_elevation_deg)
                     for s in stations])


def site_grid(lat_step_deg: float, lon_step_deg: float) -> tuple:
    """Surface stations on a regular latitude-longitude grid covering the whole Moon.

    Latitudes run from -90 to +90 deg in steps of ``lat_step_deg``; each non-polar latitude carries stations at
    longitudes -180, -180 + ``lon_step_deg``, ... (< 180); each pole carries a single station (longitude 0).

    Parameters
    ----------
    lat_step_deg : float
        Latitude spacing, degrees; must divide 180 exactly.
    lon_step_deg : float
        Longitude spacing, degrees; must divide 360 exactly.

    Returns
    -------
    tuple of SurfaceStation
        Named ``"<lat>,<lon>"`` (degrees), south to north, west to east.
    """
    dlat = validation.positive(lat_step_deg, "lat_step_deg")
    dlon = validation.positive(lon_step_deg, "lon_step_deg")
    for v, total, name in ((dlat, 180.0, "lat_step_deg"), (dlon, 360.0, "lon_step_deg")):
        k = total / v
        if k < 1.0 - 1e-9:
            raise ValueError(f"{name} must be at most {total:g} deg; got {v!r}")
        if abs(k - round(k)) > 1e-9:
            raise ValueError(f"{name} must divide {total:g} deg exactly; got {v!r}")
    validation.work_size((180.0 / dlat + 1.0) * (360.0 / dlon), "lat_step_deg, lon_step_deg", 1e6, "sites")
    lats = np.linspace(-90.0, 90.0, int(round(180.0 / dlat)) + 1)
    lons = np.linspace(-180.0, 180.0, int(round(360.0 / dlon)) + 1)[:-1]
    out = []
    for la in lats:
        for lo in ((0.0,) if abs(la) == 90.0 else lons):
            out.append(SurfaceStation(f"{la:+g},{lo:+g}", float(la), float(lo)))
    return tuple(out)


@dataclass(frozen=True)
class PairCoverage:
    """Coverage of a sampled trajectory by every pair of surface stations (:func:`pair_coverage`).

    Attributes
    ----------
    stations : tuple of SurfaceStation
        The candidate sites, in the order of the matrix indices.
    fraction : ndarray, shape (n, n)
        ``fraction[i, j]``: fraction of the target samples above the horizon mask of station i or station j
        (the diagonal holds single-station coverage).  With samples uniform in time it is a fraction of time.
    n_samples : int
        Number of target samples.
    """

    stations: tuple
    fraction: np.ndarray
    n_samples: int

    @property
    def full(self) -> np.ndarray:
        """Bool (n, n): the pair sees every sample (exact integer count, not a rounded fraction)."""
        return np.rint(self.fraction * self.n_samples).astype(np.int64) == self.n_samples

    @property
    def n_full_pairs(self) -> int:
        """Number of pairs ``i < j`` of distinct stations that see every sample."""
        return int(np.triu(self.full, k=1).sum())

    @property
    def best_pair(self) -> tuple:
        """Indices ``(i, j)``, ``i < j``, of the pair with the largest coverage (first one in row order on ties)."""
        f = np.where(np.triu(np.ones(self.fraction.shape, bool), k=1), self.fraction, -1.0)
        i, j = np.unravel_index(int(np.argmax(f)), f.shape)
        return int(i), int(j)

    @property
    def best_fraction(self) -> float:
        """Coverage of :attr:`best_pair`."""
        return float(self.fraction[self.best_pair])


def pair_coverage(system: CR3BP, target_positions, stations, *, min_elevation_deg: float = 0.0,
                  chunk: int = 256) -> PairCoverage:
    """Fraction of target samples seen by each pair of lunar surface stations (all pairs at once).

    A station sees a sample when the sample's elevation above the station's local horizon exceeds
    ``min_elevation_deg`` (the same rule as :func:`surface_coverage`).  The per-station visibility matrix ``V``
    (n stations x m samples) is built in Moon-centred coordinates without forming the n x m x 3 difference array:
    for a station at ``R u`` (unit vertical ``u``) and a target at Moon-centred ``t``,
    ``sin(el) = (t.u - R) / |t - R u|`` with ``|t - R u|^2 = |t|^2 + R^2 - 2 R t.u``.  The number of samples seen
    by ``i`` or ``j`` is ``|V_i| + |V_j| - (V V^T)_ij``, one matrix product (exact in float32 for m < 2^24).

    Parameters
    ----------
    system : CR3BP
    target_positions : array_like, shape (m, 3) or (m, 6)
        Target positions (or states), rotating frame, barycentric origin, LU.
    stations : sequence of SurfaceStation
        Candidate sites (e.g. :func:`site_grid`); at least two.
    min_elevation_deg : float
        Horizon mask, degrees, in [-90, 90).
    chunk : int
        Stations processed per block (memory: about 3 x chunk x m doubles).

    Returns
    -------
    PairCoverage
    """
    check_system(system)
    t = validation.as_array(target_positions, "target_positions", ndim=(2,))
    t = _position_stack(t, "target_positions")
    if t.shape[0] < 1:
        raise ValueError("target_positions must hold at least one sample")
    if t.shape[0] >= 2 ** 24:
        raise ValueError(f"target_positions: at most 2**24 - 1 samples (float32 counts); got {t.shape[0]}")
    mask = np.deg2rad(validation.in_range(min_elevation_deg, "min_elevation_deg", -90.0, 90.0))
    chunk = validation.integer(chunk, "chunk", minimum=1)
    stations = tuple(validation.sequence_of(stations, "stations", SurfaceStation, "SurfaceStation"))
    if len(stations) < 2:
        raise ValueError(f"stations must hold at least two SurfaceStation; got {len(stations)}")
    R = system.secondary_radius
    tc = t - system.secondary_position  # Moon-centred, LU
    if np.any(np.linalg.norm(tc, axis=1) <= R):
        raise ValueError("target_positions must lie outside the Moon's sphere")
    up = np.array([(s.position(system) - system.secondary_position) / R for s in stations])  # (n, 3) unit
    t2 = np.sum(tc * tc, axis=1)
    vis = np.empty((len(stations), t.shape[0]), dtype=np.float32)
    sin_mask = np.sin(mask)
    for a in range(0, len(stations), chunk):
        tu = up[a:a + chunk] @ tc.T  # (c, m)
        rng = np.sqrt(np.maximum(t2[None, :] + R * R - 2.0 * R * tu, 0.0))
        vis[a:a + chunk] = (tu - R) > sin_mask * rng
    single = vis.sum(axis=1, dtype=np.float64)
    both = (vis @ vis.T).astype(np.float64)
    union = single[:, None] + single[None, :] - both
    return PairCoverage(stations, union / t.shape[0], int(t.shape[0]))


@dataclass(frozen=True)
class OutageStatistics:
    """Lunar occultations of an observer-target line of sight over a long span (:func:`occultation_outages`).

    Attributes
    ----------
    span_days : float
        Length of the sampled span, days.
    step_s : float
        Sampling step, seconds.
    clear_fraction : float
        Fraction of samples with a clear line of sight.
    durations_h : ndarray
        Duration of each outage (maximal run of blocked samples, counted as samples x step), hours, in time order.
        A run cut by either end of the span is counted as one (partial) outage.
    """

    span_days: float
    step_s: float
    clear_fraction: float
    durations_h: np.ndarray

    @property
    def count(self) -> int:
        """Number of outages."""
        return int(self.durations_h.size)

    @property
    def longest_h(self) -> float:
        """Longest outage, hours (0 if none)."""
        return float(self.durations_h.max()) if self.count else 0.0

    @property
    def mean_interval_days(self) -> float:
        """Span divided by the number of outages, days (``inf`` if none)."""
        return self.span_days / self.count if self.count else float("inf")


def _periodic_positions(orbit, tq, n_table):
    """Positions (LU) on a periodic orbit at times ``tq`` (TU) by phase, cubic Hermite on a one-period table."""
    from scipy.interpolate import CubicHermiteSpline

    tt, xs = orbit.sample(n_table + 1)
    return CubicHermiteSpline(tt, xs[:, :3], xs[:, 3:], axis=0)(np.mod(tq, orbit.period))


def occultation_outages(system: CR3BP, observer, target, span_days: float, step_s: float = 60.0, *,
                        body: str = "moon", table_points: int = 4000) -> OutageStatistics:
    """Count and time the occultations of the observer-target line of sight over a long span.

    Each body moves on its periodic orbit indefinitely (its state at time t is the orbit's state at phase
    ``t mod T``, both starting at their :attr:`x0` at t = 0), so a span of a year or more is sampled without the
    numerical divergence of propagating an unstable orbit for many periods.  Positions are interpolated from a
    one-period table of ``table_points`` states by cubic Hermite interpolation in position and velocity.  The line
    of sight is tested with :func:`line_of_sight_clear` at times ``0, step, 2 step, ...`` up to ``span_days``.

    Parameters
    ----------
    system : CR3BP
    observer, target : cislunar.cr3bp.orbits.PeriodicOrbit or array_like, shape (3,) or (6,)
        A periodic orbit, or a point fixed in the rotating frame (position or state, LU, barycentric), e.g.
        :func:`l2_observer_state`.
    span_days : float
        Length of the span, days (positive).
    step_s : float
        Sampling step, seconds (positive, at most the span).
    body : {"moon", "earth"}
        Occulting body.
    table_points : int
        Intervals of the one-period interpolation table (>= 16).

    Returns
    -------
    OutageStatistics
    """

    check_system(system)
    span = validation.positive(span_days, "span_days")
    step = validation.positive(step_s, "step_s")
    if step > span * 86400.0:
        raise ValueError(f"step_s must not exceed the span ({span * 86400.0:g} s); got {step_s!r}")
    validation.choice(body, "body", ("moon", "earth"))
    n_table = validation.integer(table_points, "table_points", minimum=16)
    validation.work_size(span * 86400.0 / step + 1.0, "step_s", 5e6, "samples over span_days")
    tq = np.arange(0.0, span * 86400.0 + 0.5 * step, step) / system.time_unit_s  # TU

    def positions(value, name):
        if isinstance(value, PeriodicOrbit):
            if value.system != system:
                raise ValueError(f"{name} belongs to a different CR3BP system")
            return _periodic_positions(value, tq, n_table)
        a = validation.as_array(value, name, ndim=(1,))
        if a.size not in (3, 6):
            raise ValueError(f"{name} must be a PeriodicOrbit or a fixed position (3,) / state (6,); got shape "
                             f"{a.shape}")
        return a[:3]

    clear = line_of_sight_clear(system, positions(observer, "observer"), positions(target, "target"), body=body)
    clear = np.broadcast_to(clear, tq.shape)
    edges = np.flatnonzero(np.diff(np.r_[0, (~clear).astype(np.int8), 0]))
    runs = edges[1::2] - edges[::2]
    return OutageStatistics(span, step, float(clear.mean()), runs * step / 3600.0)
