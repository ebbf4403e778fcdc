r"""Circular restricted three-body problem (CR3BP) in the rotating (synodic) frame.

Frame and units
---------------
All states are expressed in the barycentric rotating frame: the x axis points from the Earth to the Moon,
z along the orbital angular momentum of the primaries, y completes the right-handed triad.  Quantities are
non-dimensional: the length unit (LU) is the Earth-Moon distance, the time unit (TU) is the inverse of the
mean motion of the primaries, so that the primaries' period is :math:`2\pi` TU.  The Earth sits at
:math:`(-\mu, 0, 0)` and the Moon at :math:`(1-\mu, 0, 0)`.

The equations of motion in velocity form are

.. math::

    \ddot x - 2\dot y = \partial U/\partial x, \quad
    \ddot y + 2\dot x = \partial U/\partial y, \quad
    \ddot z = \partial U/\partial z,

with the pseudo-potential :math:`U = (x^2+y^2)/2 + (1-\mu)/r_1 + \mu/r_2` and the Jacobi constant
:math:`C = 2U - v^2`.

Sources of the constants
------------------------
* ``mu = 0.012150585609624``: Earth-Moon mass ratio used in the Wolf & Jones DRO tables (their states close to
  about 1e-9 with it; checked in ``tests/cr3bp/test_orbits.py``) and in JPL's three-body periodic-orbit database
  (``1.215058560962404e-2``).
* Length unit 384400 km (mean Earth-Moon distance) and time unit
  :math:`\sqrt{L^3 / G(M_E+M_M)} = 375190.25852` s (about 4.3425 days), the "classical" units collected in
  ``book/sources.md``.  JPL's database uses other units (389703.2648 km, 382981.2891 s); the two
  conventions must not be mixed.
* Lunar mean radius 1737.4 km, Earth mean radius 6371 km, synodic month 29.530589 days.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import brentq

from cislunar.utils import validation

__all__ = [
    "check_system",
    "CR3BP",
    "EARTH_MOON",
    "SYNODIC_MONTH_DAYS",
    "MOON_RADIUS_KM",
    "EARTH_RADIUS_KM",
    "SECONDS_PER_DAY",
]

SECONDS_PER_DAY = 86400.0
#: Mean synodic month (new moon to new moon), days.
SYNODIC_MONTH_DAYS = 29.530589
#: Lunar mean radius, km.
MOON_RADIUS_KM = 1737.4
#: Earth mean radius, km.
EARTH_RADIUS_KM = 6371.0


#: Smallest mass parameter: ``1 - mu`` must differ from 1 in double precision (the Moon sits at ``1 - mu``).
_MU_MIN = np.finfo(float).eps / 2.0
#: Allowed range of the length and time units (km, s): their ratios (LU/TU, LU/TU^2) stay finite and non-zero.
_UNIT_RANGE = (1e-6, 1e15)


@dataclass(frozen=True)
class CR3BP:
    """A circular restricted three-body system with its units.

    Parameters
    ----------
    mu : float
        Mass parameter :math:`m_2/(m_1+m_2)`, in (0, 0.5] and at least ``eps/2`` (1.1e-16) so that ``1 - mu``
        differs from 1.
    length_unit_km : float
        Length unit (distance between the primaries), km, in [1e-6, 1e15].
    time_unit_s : float
        Time unit (inverse mean motion of the primaries), s, in [1e-6, 1e15].
    primary_radius_km, secondary_radius_km : float
        Mean radii of the primaries, km (used for plots, visibility and impact checks).
    name : str
        Label for plots and reports.

    Notes
    -----
    All methods accept a single state of shape ``(6,)`` or a stack ``(..., 6)`` and broadcast over the
    leading axes.  States are ``[x, y, z, vx, vy, vz]`` in LU and LU/TU in the rotating frame.
    """

    mu: float
    length_unit_km: float
    time_unit_s: float
    primary_radius_km: float = EARTH_RADIUS_KM
    secondary_radius_km: float = MOON_RADIUS_KM
    name: str = field(default="CR3BP")

    def __post_init__(self):
        validation.in_range(self.mu, "mu", 0.0, 0.5, closed=True)
        if not float(self.mu) >= _MU_MIN:  # also 0: the primaries at -mu and 1 - mu would not resolve a smaller mu
            raise ValueError(f"mu must lie in (0, 0.5] and be resolvable next to 1 (mu >= {_MU_MIN:.1e}); got "
                             f"{self.mu!r}")
        validation.positive(self.length_unit_km, "length_unit_km")
        validation.positive(self.time_unit_s, "time_unit_s")
        for attr in ("length_unit_km", "time_unit_s"):
            if not _UNIT_RANGE[0] <= float(getattr(self, attr)) <= _UNIT_RANGE[1]:
                raise ValueError(f"{attr} must lie in [{_UNIT_RANGE[0]:g}, {_UNIT_RANGE[1]:g}] (derived velocity "
                                 f"and acceleration units must stay finite and non-zero); got {getattr(self, attr)!r}")
        # radii drive impact detection: NaN, negative or non-numeric radii would silently switch it off
        validation.positive(self.primary_radius_km, "primary_radius_km")
        validation.positive(self.secondary_radius_km, "secondary_radius_km")
        if not isinstance(self.name, str):
            raise validation.ArgumentTypeError(f"name must be a str; got {type(self.name).__name__}")
        d = self.length_unit_km
        if self.primary_radius_km + self.secondary_radius_km >= d:
            raise ValueError(f"primary_radius_km + secondary_radius_km must be smaller than length_unit_km = {d} km "
                             "(the primaries would overlap)")
        for attr in ("mu", "length_unit_km", "time_unit_s", "primary_radius_km", "secondary_radius_km"):
            object.__setattr__(self, attr, float(getattr(self, attr)))

    # ------------------------------------------------------------------ units
    @property
    def velocity_unit_km_s(self) -> float:
        """Velocity unit LU/TU expressed in km/s."""
        return self.length_unit_km / self.time_unit_s

    @property
    def acceleration_unit_km_s2(self) -> float:
        """Acceleration unit LU/TU^2 expressed in km/s^2."""
        return self.length_unit_km / self.time_unit_s**2

    @property
    def time_unit_days(self) -> float:
        """Time unit in days."""
        return self.time_unit_s / SECONDS_PER_DAY

    def days_to_tu(self, days):
        """Convert a duration in days to TU."""
        return validation.as_array(days, "days", finite=False) / self.time_unit_days

    def tu_to_days(self, tu):
        """Convert a duration in TU to days."""
        return validation.as_array(tu, "tu", finite=False) * self.time_unit_days

    def km_to_lu(self, km):
        """Convert a length in km to LU."""
        return validation.as_array(km, "km", finite=False) / self.length_unit_km

    def lu_to_km(self, lu):
        """Convert a length in LU to km."""
        return validation.as_array(lu, "lu", finite=False) * self.length_unit_km

    def state_to_km(self, state):
        """Convert non-dimensional states ``(..., 6)`` to km and km/s (same frame and origin)."""
        s = validation.as_array(state, "state", last=6)
        scale = np.r_[np.full(3, self.length_unit_km), np.full(3, self.velocity_unit_km_s)]
        return s * scale

    def state_from_km(self, state_km):
        """Convert states ``(..., 6)`` in km and km/s to non-dimensional units."""
        s = validation.as_array(state_km, "state_km", last=6)
        scale = np.r_[np.full(3, self.length_unit_km), np.full(3, self.velocity_unit_km_s)]
        return s / scale

    # -------------------------------------------------------------- geometry
    @property
    def primary_position(self) -> np.ndarray:
        """Position of the larger primary (Earth), LU."""
        return np.array([-self.mu, 0.0, 0.0])

    @property
    def secondary_position(self) -> np.ndarray:
        """Position of the smaller primary (Moon), LU."""
        return np.array([1.0 - self.mu, 0.0, 0.0])

    @property
    def secondary_radius(self) -> float:
        """Radius of the secondary (Moon), LU."""
        return self.secondary_radius_km / self.length_unit_km

    @property
    def primary_radius(self) -> float:
        """Radius of the primary (Earth), LU."""
        return self.primary_radius_km / self.length_unit_km

    def distances(self, state):
        """Distances ``(r1, r2)`` to the primary and the secondary, LU, for positions ``(..., >=3)``."""
        s = validation.as_array(state, "state", finite=False)
        if s.ndim == 0 or s.shape[-1] < 3:
            raise ValueError(f"state must have at least 3 components on its last axis; got shape {s.shape}")
        x, y, z = s[..., 0], s[..., 1], s[..., 2]
        r1 = np.sqrt((x + self.mu) ** 2 + y**2 + z**2)
        r2 = np.sqrt((x - 1.0 + self.mu) ** 2 + y**2 + z**2)
        return r1, r2

    # -------------------------------------------------------------- dynamics
    def pseudo_potential(self, state):
        """Pseudo-potential :math:`U = (x^2+y^2)/2 + (1-\\mu)/r_1 + \\mu/r_2` (LU^2/TU^2)."""
        s = validation.as_array(state, "state")
        if s.shape[-1] < 3:
            raise ValueError(f"state must have at least 3 components on its last axis; got shape {s.shape}")
        r1, r2 = self.distances(s)
        return 0.5 * (s[..., 0] ** 2 + s[..., 1] ** 2) + (1.0 - self.mu) / r1 + self.mu / r2

    def jacobi(self, state):
        """Jacobi constant :math:`C = 2U - v^2` of states ``(..., 6)``."""
        s = validation.as_array(state, "state", last=6)
        v2 = np.sum(s[..., 3:6] ** 2, axis=-1)
        return 2.0 * self.pseudo_potential(s) - v2

    def eom(self, state, t: float = 0.0):
        """Time derivative of states ``(..., 6)`` (the CR3BP vector field; autonomous, ``t`` unused).

        At a primary's centre the field is singular: the result holds infinities there (no error is raised, so
        that integrators can detect it).
        """
        s = validation.as_array(state, "state", last=6)
        mu = self.mu
        x, y, z, vx, vy, vz = np.moveaxis(s, -1, 0)
        r1, r2 = self.distances(s)
        c1 = (1.0 - mu) / r1**3
        c2 = mu / r2**3
        ax = 2.0 * vy + x - c1 * (x + mu) - c2 * (x - 1.0 + mu)
        ay = -2.0 * vx + y - c1 * y - c2 * y
        az = -c1 * z - c2 * z
        return np.stack([vx, vy, vz, ax, ay, az], axis=-1)

    def jacobian(self, state):
        """Jacobian :math:`A = \\partial f/\\partial x` of the vector field, shape ``(..., 6, 6)``.

        .. math:: A = \\begin{bmatrix} 0 & I \\\\ U_{rr} & 2\\Omega \\end{bmatrix},\\quad
                  \\Omega = \\begin{bmatrix} 0 & 1 & 0\\\\ -1 & 0 & 0 \\\\ 0&0&0\\end{bmatrix}
        """
        s = validation.as_array(state, "state", last=6)
        A = np.zeros(s.shape[:-1] + (6, 6))
        A[..., 0:3, 3:6] = np.eye(3)
        A[..., 3:6, 0:3] = self.potential_hessian(s)
        A[..., 3, 4] = 2.0
        A[..., 4, 3] = -2.0
        return A

    def potential_hessian(self, state):
        """Hessian :math:`U_{rr}` of the pseudo-potential, shape ``(..., 3, 3)``."""
        s = validation.as_array(state, "state")
        if s.ndim == 0 or s.shape[-1] < 3:
            raise ValueError(f"state must have at least 3 components on its last axis; got shape {s.shape}")
        mu = self.mu
        r = s[..., 0:3]
        d1 = r - self.primary_position
        d2 = r - self.secondary_position
        r1 = np.linalg.norm(d1, axis=-1)[..., None, None]
        r2 = np.linalg.norm(d2, axis=-1)[..., None, None]
        eye = np.eye(3)
        H = ((1.0 - mu) * (3.0 * d1[..., :, None] * d1[..., None, :] / r1**5 - eye / r1**3)
             + mu * (3.0 * d2[..., :, None] * d2[..., None, :] / r2**5 - eye / r2**3))
        H = H + np.diag([1.0, 1.0, 0.0])
        return H

    def libration_points(self) -> np.ndarray:
        """Positions of L1..L5, shape ``(5, 3)``, LU.

        The collinear points solve :math:`\\partial U/\\partial x = 0` on the x axis in the three intervals
        separated by the primaries (root bracketing with ``brentq`` to machine precision).
        """
        mu = self.mu

        def dUdx(x):
            r1 = abs(x + mu)
            r2 = abs(x - 1 + mu)
            return x - (1 - mu) * (x + mu) / r1**3 - mu * (x - 1 + mu) / r2**3

        eps = 1e-9
        l1 = brentq(dUdx, -mu + eps, 1 - mu - eps, xtol=1e-15, rtol=1e-15)
        l2 = brentq(dUdx, 1 - mu + eps, 2.0, xtol=1e-15, rtol=1e-15)
        l3 = brentq(dUdx, -2.0, -mu - eps, xtol=1e-15, rtol=1e-15)
        h = np.sqrt(3.0) / 2.0
        return np.array([[l1, 0, 0], [l2, 0, 0], [l3, 0, 0], [0.5 - mu, h, 0], [0.5 - mu, -h, 0]])

    def moon_centred(self, state):
        """Shift positions ``(..., >=3)`` to a Moon-centred origin (same rotating axes), LU."""
        s = np.array(validation.as_array(state, "state", finite=False), copy=True)
        if s.ndim == 0 or s.shape[-1] < 3:
            raise ValueError(f"state must have at least 3 components on its last axis; got shape {s.shape}")
        s[..., 0] -= 1.0 - self.mu
        return s

    def synodic_month_tu(self) -> float:
        """Mean synodic month (29.530589 d) in TU; the 9:2 NRHO period is 2/9 of it."""
        return float(self.days_to_tu(SYNODIC_MONTH_DAYS))


#: Earth-Moon system with the constants listed in the module docstring.

def check_system(value, name: str = "system") -> "CR3BP":
    """Validate a :class:`CR3BP` argument at a public boundary (e.g. ``cislunar.EARTH_MOON``).

    Raises
    ------
    cislunar.utils.validation.ArgumentTypeError
        Naming ``name`` when ``value`` is not a :class:`CR3BP`.
    """
    return validation.instance(value, name, CR3BP, "a cislunar.cr3bp.dynamics.CR3BP (e.g. cislunar.EARTH_MOON)")

EARTH_MOON = CR3BP(mu=0.012150585609624, length_unit_km=384400.0, time_unit_s=375190.25852, name="Earth-Moon")
