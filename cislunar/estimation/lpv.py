r"""Planar CR3BP in affine parameter-varying (LPV) form and optimal sensing-precision LMIs.

Follows E. Nychka, R. Bhattacharya, "Optimal Sensing Precision for Celestial Navigation Systems in Cislunar Space
using LPV Framework" (arXiv 2410.02013, 2024), Sections III-IV, with the method of V. M. Deshpande,
R. Bhattacharya, IEEE Control Systems Letters 5(2), 2021.

Frame, units, state
-------------------
Barycentric rotating (synodic) frame of :mod:`cislunar.cr3bp.dynamics`, non-dimensional units (LU, TU).  The planar
state is :math:`\mathbf x = [x, y, \dot x, \dot y]` (LU, LU/TU); the Earth sits at :math:`(-\mu, 0)` and the Moon
at :math:`(1-\mu, 0)`, :math:`\mu = \pi_2` in the paper's notation.

LPV form (paper Eqs. 20-21, 23; derived and checked here)
----------------------------------------------------------
With :math:`r_{13} = \sqrt{(x+\mu)^2 + y^2}` (spacecraft-Earth) and :math:`r_{23} = \sqrt{(x-1+\mu)^2+y^2}`
(spacecraft-Moon), the scheduling vector is

.. math:: \rho = [1/r_{13}^3,\ 1/r_{23}^3,\ 1/r_{13},\ 1/r_{23},\ x,\ y]

(:math:`\rho_5 = x`, :math:`\rho_6 = y` are not defined in the paper; they are what its Eq. 22 needs).  The planar
equations of motion become exactly

.. math:: \dot{\mathbf x} = A(\rho)\mathbf x + b(\rho), \quad
   A = \begin{bmatrix}0&0&1&0\\0&0&0&1\\a&0&0&2\\0&a&-2&0\end{bmatrix},\quad
   a = 1 - (1-\mu)\rho_1 - \mu\rho_2,\quad b = [0, 0, \mu(1-\mu)(\rho_2-\rho_1), 0]^T,

which agrees with the paper's Eqs. 21 and 23 (:math:`a_{31} = a_{42}`, :math:`b_3 = \pi_2(\rho_1-\rho_2)(\pi_2-1)`).

Sensor model (paper Eq. 22; Eq. 23's :math:`d(\rho)` disagrees with it and with geometry)
-------------------------------------------------------------------------------------------
:math:`\theta_1` is the angle at the Earth between the Earth-Moon line and the Earth-spacecraft line,
:math:`\theta_2` the angle at the Moon between the Moon-Earth line and the Moon-spacecraft line (signed with
:math:`y`), so :math:`\theta_3 = \pi - \theta_1 - \theta_2` is the angle at the spacecraft.  Then exactly

.. math:: y_m = [\sin\theta_1, \cos\theta_1, \sin\theta_2, \cos\theta_2, r_{13}^2, r_{23}^2]^T
              = C(\rho) [x, y]^T + d(\rho),

.. math:: C = \begin{bmatrix}0&\rho_3\\ \rho_3&0\\ 0&\rho_4\\ -\rho_4&0\\ \rho_5+2\mu&\rho_6\\
          \rho_5+2\mu-2&\rho_6\end{bmatrix},\quad
          d = [0,\ \mu\rho_3,\ 0,\ (1-\mu)\rho_4,\ \mu^2,\ (1-\mu)^2]^T .

Eq. 22 prints exactly this :math:`d`; Eq. 23 prints :math:`d = [0, \rho_3, 0, -\rho_4, \rho_5+2\pi_2,
\rho_5+2\pi_2-2]` (it repeats a column of :math:`C` and drops the :math:`\pi_2` factors), which does not
reproduce the measurements; the tests show Eq. 22 is exact to 1e-12 and Eq. 23 is not.

Observer and LMIs
-----------------
See :func:`design_observer` and :class:`PrecisionLMI` for Theorems 1 and 2 as derived (with the paper's
inconsistencies resolved) and :func:`verify_observer` for the checks that do not trust the solver.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, field
from itertools import product

import clarabel
import numpy as np
from scipy import sparse

from cislunar.cr3bp.dynamics import CR3BP, EARTH_MOON, check_system
from cislunar.cr3bp.orbits import correct_symmetric
from cislunar.cr3bp.propagation import propagate
from cislunar.utils import validation

__all__ = [
    "CR3BPLPV",
    "DISTURBANCE_STRUCTURES",
    "RHO_NAMES",
    "SENSOR_NAMES",
    "SIN_THETA3_MIN",
    "InfeasibleLMIError",
    "ObserverDesign",
    "ParameterBox",
    "PrecisionLMI",
    "ResonantOrbit",
    "Verification",
    "default_disturbance",
    "design_observer",
    "disturbance_model",
    "error_system",
    "gamma_sweep",
    "guaranteed_error_rms",
    "h2_norm",
    "hinf_norm",
    "noise_deg_to_precision",
    "precision_to_noise_deg",
    "resonant_orbit",
    "verify_observer",
]

#: Names of the scheduling parameters rho_1..rho_6.
RHO_NAMES = ("1/r13^3", "1/r23^3", "1/r13", "1/r23", "x", "y")
#: Smallest :math:`|\\sin\\theta_3|` accepted by :meth:`CR3BPLPV.rho_from_angles` (float pi is not exact).
SIN_THETA3_MIN = 1e-12
#: Names of the six sensors of Eq. 22.
SENSOR_NAMES = ("sin th1", "cos th1", "sin th2", "cos th2", "r13^2", "r23^2")


# ---------------------------------------------------------------------------------------------------- model
@dataclass(frozen=True)
class CR3BPLPV:
    r"""Planar CR3BP as the affine parameter-varying system :math:`\dot x = A(\rho)x + b(\rho)`,
    :math:`y = C(\rho)x + d(\rho)`.

    Parameters
    ----------
    system : CR3BP
        Earth-Moon system (only ``mu`` is used; all quantities non-dimensional, rotating frame).

    Notes
    -----
    Every matrix function is affine in :math:`\rho`:  ``A(rho) = A0 + sum_i rho_i A_i`` with the coefficient
    arrays returned by :meth:`affine_coefficients`.  All methods broadcast over leading axes.
    """

    system: CR3BP = field(default=EARTH_MOON)

    def __post_init__(self):
        if not isinstance(self.system, CR3BP):
            raise ValueError(f"system must be a cislunar.cr3bp.dynamics.CR3BP; got {type(self.system).__name__}")

    @property
    def mu(self) -> float:
        """Mass parameter :math:`\\mu = \\pi_2`."""
        return self.system.mu

    n_x = 4
    n_y = 6
    n_rho = 6

    # ------------------------------------------------------------- states
    @staticmethod
    def planar(state6) -> np.ndarray:
        """``[x, y, z, vx, vy, vz]`` (..., 6) -> planar ``[x, y, vx, vy]`` (..., 4); rejects non-planar states."""
        s = validation.as_array(state6, "state6", last=6, min_size=1)
        if np.any(np.abs(s[..., [2, 5]]) > 1e-12):
            raise ValueError("state6 must be planar (z = vz = 0)")
        return s[..., [0, 1, 3, 4]]

    @staticmethod
    def spatial(state4) -> np.ndarray:
        """Planar ``[x, y, vx, vy]`` (..., 4) -> ``[x, y, 0, vx, vy, 0]`` (..., 6)."""
        s = validation.as_array(state4, "state4", last=4, min_size=1)
        out = np.zeros(s.shape[:-1] + (6,))
        out[..., [0, 1, 3, 4]] = s
        return out

    @staticmethod
    def _planar_input(state, name: str = "state") -> np.ndarray:
        """Planar states (..., 4) or positions (..., 2), finite, at least one."""
        s = validation.as_array(state, name, ndim=(1, 2, 3), min_size=1)
        if s.shape[-1] not in (2, 4):
            raise ValueError(f"{name} must have last axis 2 (position) or 4 (planar state); got shape {s.shape}")
        return s

    def _distances(self, s):
        mu = self.mu
        r13 = np.hypot(s[..., 0] + mu, s[..., 1])
        r23 = np.hypot(s[..., 0] - 1.0 + mu, s[..., 1])
        return r13, r23

    # ---------------------------------------------------------- scheduling
    def rho(self, state) -> np.ndarray:
        """Scheduling parameters :math:`\\rho` (..., 6) of planar states (..., 4) or positions (..., 2).

        ``[1/r13^3 (LU^-3), 1/r23^3 (LU^-3), 1/r13 (LU^-1), 1/r23 (LU^-1), x (LU), y (LU)]``.
        """
        s = self._planar_input(state)
        r13, r23 = self._distances(s)
        if np.any(r13 == 0) or np.any(r23 == 0):
            raise ValueError("state coincides with a primary (r13 or r23 is zero)")
        return self._rho(s, r13, r23)

    def _rho(self, s, r13=None, r23=None):
        """Kernel of :meth:`rho` (unchecked): ``s`` a float array (..., 2 or 4) off the primaries."""
        if r13 is None:
            r13, r23 = self._distances(s)
        return np.stack([r13**-3, r23**-3, 1.0 / r13, 1.0 / r23, s[..., 0], s[..., 1]], axis=-1)

    def angles(self, state):
        r"""Angles :math:`\theta_1` (at the Earth) and :math:`\theta_2` (at the Moon), rad, signed like ``y``.

        :math:`\theta_1 = \operatorname{atan2}(y, x+\mu)`, :math:`\theta_2 = \operatorname{atan2}(y, 1-\mu-x)`.
        """
        return self._angles(self._planar_input(state))

    def _angles(self, s):
        """Kernel of :meth:`angles` (unchecked)."""
        mu = self.mu
        return np.arctan2(s[..., 1], s[..., 0] + mu), np.arctan2(s[..., 1], 1.0 - mu - s[..., 0])

    def rho_from_angles(self, theta1, theta2) -> np.ndarray:
        r"""Scheduling parameters from the two angles by triangulation on the Earth-Moon baseline (1 LU).

        Law of sines with :math:`\theta_3 = \pi - \theta_1 - \theta_2`:
        :math:`r_{13} = \sin\theta_2/\sin\theta_3`, :math:`r_{23} = \sin\theta_1/\sin\theta_3`,
        :math:`x = -\mu + r_{13}\cos\theta_1`, :math:`y = r_{13}\sin\theta_1`.  Singular where
        :math:`\sin\theta_3 \to 0` (spacecraft on the Earth-Moon line).
        """
        t1 = validation.as_array(theta1, "theta1")
        t2 = validation.as_array(theta2, "theta2")
        if t1.shape != t2.shape:
            raise ValueError(f"theta1 and theta2 must have the same shape; got {t1.shape} and {t2.shape}")
        s3 = np.sin(t1 + t2)  # sin(pi - t1 - t2)
        if np.any(np.abs(s3) < SIN_THETA3_MIN):
            raise ValueError(f"theta1 + theta2 is a multiple of pi (|sin theta3| < {SIN_THETA3_MIN:g}): the "
                             "triangulation is singular (spacecraft on the Earth-Moon line)")
        return self._rho_from_angles(t1, t2, s3)

    def _rho_from_angles(self, t1, t2, s3=None):
        """Kernel of :meth:`rho_from_angles` (unchecked: the caller keeps away from :math:`\\sin\\theta_3 = 0`)."""
        if s3 is None:
            s3 = np.sin(t1 + t2)
        r13 = np.sin(t2) / s3
        r23 = np.sin(t1) / s3
        x = -self.mu + r13 * np.cos(t1)
        y = r13 * np.sin(t1)
        return np.stack([np.abs(r13) ** -3, np.abs(r23) ** -3, 1.0 / np.abs(r13), 1.0 / np.abs(r23), x, y],
                        axis=-1)

    # ------------------------------------------------------- vector fields
    def f(self, state) -> np.ndarray:
        """Nonlinear planar CR3BP vector field (..., 4), from :meth:`CR3BP.eom` (LU/TU, LU/TU^2)."""
        s = validation.as_array(state, "state", last=4, min_size=1)
        s6 = np.zeros(s.shape[:-1] + (6,))
        s6[..., [0, 1, 3, 4]] = s
        return self.system.eom(s6)[..., [0, 1, 3, 4]]

    def measure(self, state) -> np.ndarray:
        """Nonlinear sensor model (..., 6): ``[sin th1, cos th1, sin th2, cos th2, r13^2, r23^2]`` from geometry."""
        s = self._planar_input(state)
        t1, t2 = self._angles(s)
        r13, r23 = self._distances(s)
        return np.stack([np.sin(t1), np.cos(t1), np.sin(t2), np.cos(t2), r13**2, r23**2], axis=-1)

    def affine_coefficients(self):
        r"""Coefficient arrays of the affine maps :math:`M(\rho) = M_0 + \sum_i \rho_i M_i`.

        Returns
        -------
        dict
            ``"A": (7, 4, 4)``, ``"b": (7, 4)``, ``"C": (7, 6, 4)``, ``"d": (7, 6)``; index 0 is the constant
            term and index i the coefficient of :math:`\rho_i`.  :math:`C` acts on the full state (velocity
            columns zero).
        """
        mu = self.mu
        A = np.zeros((7, 4, 4))
        A[0, 0, 2] = A[0, 1, 3] = 1.0
        A[0, 2, 3], A[0, 3, 2] = 2.0, -2.0
        A[0, 2, 0] = A[0, 3, 1] = 1.0
        A[1, 2, 0] = A[1, 3, 1] = -(1.0 - mu)
        A[2, 2, 0] = A[2, 3, 1] = -mu
        b = np.zeros((7, 4))
        b[1, 2] = -mu * (1.0 - mu)
        b[2, 2] = mu * (1.0 - mu)
        C = np.zeros((7, 6, 4))
        C[3, 0, 1] = C[3, 1, 0] = 1.0
        C[4, 2, 1], C[4, 3, 0] = 1.0, -1.0
        C[0, 4, 0], C[0, 5, 0] = 2.0 * mu, 2.0 * mu - 2.0
        C[5, 4, 0] = C[5, 5, 0] = 1.0
        C[6, 4, 1] = C[6, 5, 1] = 1.0
        d = np.zeros((7, 6))
        d[3, 1] = mu
        d[4, 3] = 1.0 - mu
        d[0, 4], d[0, 5] = mu**2, (1.0 - mu) ** 2
        return {"A": A, "b": b, "C": C, "d": d}

    def _affine(self, key, rho):
        return self._affine_kernel(key, validation.as_array(rho, "rho", last=6, min_size=1))

    def _affine_kernel(self, key, r):
        """Unchecked :math:`M(\\rho) = M_0 + \\sum_i \\rho_i M_i` for ``r`` a float array (..., 6)."""
        coef = self.affine_coefficients()[key]
        return coef[0] + np.tensordot(r, coef[1:], axes=(-1, 0))

    def A(self, rho) -> np.ndarray:
        """:math:`A(\\rho)` (..., 4, 4) of paper Eq. 23 (1/TU, 1/TU^2)."""
        return self._affine("A", rho)

    def b(self, rho) -> np.ndarray:
        """:math:`b(\\rho)` (..., 4) of Eq. 23, LU/TU^2."""
        return self._affine("b", rho)

    def C(self, rho) -> np.ndarray:
        """:math:`C_y(\\rho)` (..., 6, 4) of Eq. 22 acting on the planar state."""
        return self._affine("C", rho)

    def d(self, rho) -> np.ndarray:
        """:math:`d(\\rho)` (..., 6) as in Eq. 22 (not Eq. 23, see module notes)."""
        return self._affine("d", rho)

    def d_as_printed_eq23(self, rho) -> np.ndarray:
        """The paper's Eq. 23 :math:`d(\\rho)` as printed, kept only to show (in tests) that it is inconsistent."""
        r = validation.as_array(rho, "rho", last=6, min_size=1)
        mu = self.mu
        z = np.zeros(r.shape[:-1])
        return np.stack([z, r[..., 2], z, -r[..., 3], r[..., 4] + 2 * mu, r[..., 4] + 2 * mu - 2], axis=-1)

    def lpv_rhs(self, state, rho=None) -> np.ndarray:
        """:math:`A(\\rho)x + b(\\rho)` (..., 4) with :math:`\\rho` from ``state`` unless given."""
        s = validation.as_array(state, "state", last=4, min_size=1)
        r = self.rho(s) if rho is None else validation.as_array(rho, "rho", last=6, min_size=1)
        return np.einsum("...ij,...j->...i", self._affine_kernel("A", r), s) + self._affine_kernel("b", r)

    def lpv_measure(self, state, rho=None) -> np.ndarray:
        """:math:`C(\\rho)x + d(\\rho)` (..., 6) with :math:`\\rho` from ``state`` unless given."""
        s = validation.as_array(state, "state", last=4, min_size=1)
        r = self.rho(s) if rho is None else validation.as_array(rho, "rho", last=6, min_size=1)
        return np.einsum("...ij,...j->...i", self._affine_kernel("C", r), s) + self._affine_kernel("d", r)


# ------------------------------------------------------------------------------------------- polytope
@dataclass(frozen=True)
class ParameterBox:
    """Axis-aligned box (a convex polytope) bounding the scheduling parameters.

    Parameters
    ----------
    lower, upper : array_like, shape (k,)
        Bounds of each parameter (same units as :meth:`CR3BPLPV.rho`), ``lower <= upper``.
    names : tuple of str
        Parameter names (default :data:`RHO_NAMES`).
    source : str
        Where the bounds come from (e.g. the trajectory they were taken from).
    """

    lower: np.ndarray
    upper: np.ndarray
    names: tuple = RHO_NAMES
    source: str = ""

    def __post_init__(self):
        lo = validation.as_array(self.lower, "lower", ndim=(1,), min_size=1)
        hi = validation.as_array(self.upper, "upper", ndim=(1,))
        if hi.shape != lo.shape:
            raise ValueError(f"lower and upper must have the same shape; got lower {lo.shape}, upper {hi.shape}")
        if np.any(hi < lo):
            raise ValueError(f"upper must be >= lower componentwise; got lower={lo}, upper={hi}")
        if not isinstance(self.names, (tuple, list)) or not all(isinstance(n, str) for n in self.names):
            raise validation.ArgumentTypeError(f"names must be a tuple of str (one per parameter); got "
                                            f"{type(self.names).__name__}")
        if len(self.names) != lo.size:
            raise ValueError(f"names must have one entry per parameter of lower ({lo.size}); got {len(self.names)}")
        validation.instance(self.source, "source", str)
        object.__setattr__(self, "lower", lo)
        object.__setattr__(self, "upper", hi)

    @classmethod
    def from_samples(cls, rho, *, margin: float = 0.0, source: str = "") -> ParameterBox:
        """Smallest box containing the samples ``rho`` (n, k), widened by ``margin`` times each range."""
        r = validation.as_array(rho, "rho", ndim=(2,))
        if r.shape[0] < 1:
            raise ValueError("rho must hold at least one sample")
        margin = validation.positive(margin, "margin", allow_zero=True)
        validation.instance(source, "source", str)
        lo, hi = r.min(axis=0), r.max(axis=0)
        w = (hi - lo) * margin
        names = RHO_NAMES if r.shape[1] == len(RHO_NAMES) else tuple(f"rho_{i + 1}" for i in range(r.shape[1]))
        return cls(lo - w, hi + w, names=names, source=source)

    @property
    def dim(self) -> int:
        """Number of parameters."""
        return self.lower.size

    @property
    def centre(self) -> np.ndarray:
        """Box centre."""
        return 0.5 * (self.lower + self.upper)

    def vertices(self, free=None) -> np.ndarray:
        """Polytope vertices, shape (2^k, dim).

        Parameters
        ----------
        free : sequence of int, optional
            Indices of the parameters allowed to vary (default: all with ``upper > lower``); the others are
            held at the box centre (used by the benchmark to scale the number of vertices).
        """
        if free is None:
            free = [i for i in range(self.dim) if self.upper[i] > self.lower[i]]
        try:
            items = list(free)
        except TypeError:
            raise validation.ArgumentTypeError(f"free must be a sequence of parameter indices; got "
                                            f"{type(free).__name__}") from None
        free = [validation.integer(i, "free") for i in items]
        if any(i < 0 or i >= self.dim for i in free) or len(set(free)) != len(free):
            raise ValueError(f"free must hold distinct indices in [0, {self.dim}); got {free}")
        out = np.tile(self.centre, (2 ** len(free), 1))
        for row, corner in enumerate(product((0, 1), repeat=len(free))):
            for i, c in zip(free, corner):
                out[row, i] = self.upper[i] if c else self.lower[i]
        return out

    def sample(self, n: int, rng: np.random.Generator) -> np.ndarray:
        """``n`` points drawn uniformly in the box (n, dim), with the generator ``rng``."""
        rng = validation.rng(rng, "rng")
        n = validation.integer(n, "n", minimum=1)
        return self.lower + (self.upper - self.lower) * rng.random((n, self.dim))

    def contains(self, rho, *, rtol: float = 1e-12) -> np.ndarray:
        """Whether points (..., dim) lie in the box (with a relative tolerance)."""
        r = validation.as_array(rho, "rho", last=self.dim)
        rtol = validation.positive(rtol, "rtol", allow_zero=True)
        tol = rtol * np.maximum(np.abs(self.lower), np.abs(self.upper))
        return np.all((r >= self.lower - tol) & (r <= self.upper + tol), axis=-1)


# ------------------------------------------------------------------------------------- resonant orbit
@dataclass(frozen=True)
class ResonantOrbit:
    """A planar Earth-Moon p:q resonant periodic orbit (x-axis symmetric).

    Attributes
    ----------
    p, q : int
        The spacecraft makes about ``p`` revolutions about the Earth while the Moon makes ``q``.
    x0 : ndarray, shape (6,)
        State at the perpendicular x-axis crossing on the far side of the Earth (LU, LU/TU, rotating frame).
    period : float
        Period in the rotating frame, TU (close to :math:`2\\pi q`).
    perigee_radius : float
        Distance from the Earth at ``x0``, LU (the requested design value).
    """

    system: CR3BP
    p: int
    q: int
    x0: np.ndarray
    period: float
    perigee_radius: float

    def sample(self, n: int, periods: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
        """Times (n,) and states (n, 6) over ``periods`` periods, propagated with :func:`propagate`."""

        n = validation.integer(n, "n", minimum=2)
        t = np.linspace(0.0, validation.positive(periods, "periods") * self.period, max(n, 2))
        return t, propagate(self.system, self.x0, t).x


def resonant_orbit(system: CR3BP = EARTH_MOON, p: int = 3, q: int = 1, perigee_radius: float = 0.2) -> ResonantOrbit:
    r"""Planar p:q Earth-Moon resonant orbit by single shooting from a Keplerian guess.

    The guess is the Earth-centred Keplerian ellipse of semi-major axis :math:`a = (q/p)^{2/3}` LU (mean motion
    p/q times the Moon's) with perigee ``perigee_radius`` on the far side of the Earth, converted to the rotating
    frame (:math:`v_y = -(v_p - r_p)`); the CR3BP orbit is then corrected at fixed :math:`x_0` with free
    :math:`(\dot y_0, T/2)` (half-period guess :math:`\pi q`).  The planar resonant orbits are the
    surveillance orbits of Frueh et al. (2021) cited in the paper's introduction; p, q and the perigee radius
    are this reproduction's choice (the paper does not state its orbit).

    Parameters
    ----------
    system : CR3BP
    p, q : int
        Resonance (positive, ``p > q``).
    perigee_radius : float
        Distance from the Earth of the initial x-axis crossing, LU, in (0.05, 0.9).

    Returns
    -------
    ResonantOrbit
    """
    system = check_system(system, "system")
    p = validation.integer(p, "p", minimum=2)
    q = validation.integer(q, "q", minimum=1)
    if p <= q:
        raise ValueError(f"p and q must be positive integers with p > q; got p={p}, q={q}")
    rp = validation.in_range(perigee_radius, "perigee_radius", 0.05, 0.9)
    mu = system.mu
    a = (q / p) ** (2.0 / 3.0)
    if rp >= 2 * a:
        raise ValueError(f"perigee_radius must be below 2a = {2 * a:.3f} LU for a {p}:{q} resonance; got {rp}")
    vp = np.sqrt((1.0 - mu) * (2.0 / rp - 1.0 / a))
    guess = np.array([-mu - rp, 0.0, 0.0, 0.0, -(vp - rp), 0.0])
    orbit = correct_symmetric(system, guess, np.pi * q, fix="x0", label=f"{p}:{q} resonant")
    x0, period = orbit.x0, orbit.period
    return ResonantOrbit(system, int(p), int(q), np.asarray(x0, dtype=float), float(period), rp)


# ----------------------------------------------------------------------------------------- precisions
def precision_to_noise_deg(kappa) -> np.ndarray:
    r"""Allowable angle noise (deg) from the precision of a sine or cosine sensor, paper Eq. 24:
    :math:`\delta\theta = \sin^{-1}(1/\kappa)` (equivalently :math:`\pi/2 - \cos^{-1}(1/\kappa)`).

    For :math:`\kappa \le 1` the sine/cosine noise may exceed 1 and the angle is unconstrained: 90 deg.
    """
    k = validation.as_array(kappa, "kappa", finite=False)
    if np.any(np.isnan(k)) or np.any(k < 0):
        raise ValueError("kappa must be non-negative")
    return _precision_to_noise_deg(k)


def _precision_to_noise_deg(k):
    """Kernel of :func:`precision_to_noise_deg` (unchecked: ``k`` a float array >= 0, inf allowed)."""
    with np.errstate(divide="ignore"):
        inv = np.where(k > 0, 1.0 / np.where(k > 0, k, 1.0), np.inf)
    return np.degrees(np.arcsin(np.minimum(inv, 1.0)))


def noise_deg_to_precision(noise_deg) -> np.ndarray:
    """Inverse of :func:`precision_to_noise_deg`: :math:`\\kappa = 1/\\sin(\\delta\\theta)`, noise in (0, 90] deg."""
    n = validation.as_array(noise_deg, "noise_deg")
    if np.any(n <= 0) or np.any(n > 90):
        raise ValueError("noise_deg must lie in (0, 90] degrees")
    return 1.0 / np.sin(np.radians(n))


#: Disturbance structures offered by :func:`disturbance_model` (the paper never states :math:`B_d, S_d, D_d`).
DISTURBANCE_STRUCTURES = ("acceleration", "state")


def disturbance_model(structure: str = "acceleration", level: float = 1e-3):
    r"""Disturbance channel :math:`(B_d, S_d, D_d)` of Eq. 5 (the paper states none of them).

    Parameters
    ----------
    structure : {"acceleration", "state"}
        ``"acceleration"``: unmodelled accelerations on both velocity components, :math:`B_d = [0; I_2]`
        (:math:`n_d = 2`).  ``"state"``: independent perturbations of every state component, :math:`B_d = I_4`
        (:math:`n_d = 4`; position entries in LU/TU per unit input, velocity entries in LU/TU^2).
        In both the disturbance does not enter the sensors, :math:`D_d = 0`.
    level : float
        :math:`S_d = \mathrm{level}\,I` (>= 0; 0 switches the disturbance off).

    Returns
    -------
    tuple of ndarray
        ``(Bd (4, nd), Sd (nd, nd), Dd (6, nd))``.
    """
    structure = validation.choice(structure, "structure", DISTURBANCE_STRUCTURES)
    return _disturbance_model(structure, validation.positive(level, "level", allow_zero=True))


def _disturbance_model(structure, s):
    """Kernel of :func:`disturbance_model` (unchecked)."""
    Bd = np.vstack([np.zeros((2, 2)), np.eye(2)]) if structure == "acceleration" else np.eye(4)
    nd = Bd.shape[1]
    return Bd, s * np.eye(nd), np.zeros((6, nd))


def default_disturbance(sigma_acc: float = 1e-3):
    r"""Disturbance channel used in this reproduction: ``disturbance_model("acceleration", sigma_acc)``.

    Unmodelled accelerations of size ``sigma_acc`` (LU/TU^2 per unit normalised input; 1e-3 LU/TU^2 is about
    2.7e-9 km/s^2, three to ten times below the solar tide the CR3BP ignores, :math:`2GM_\odot r/d^3 \approx`
    0.9-3e-8 km/s^2 = 0.003-0.011 LU/TU^2 at r = 0.3-1 LU from the Earth) on both velocity components:
    :math:`B_d = [0; I_2]`, :math:`S_d = \sigma_{acc} I_2`, :math:`D_d = 0`.

    Returns
    -------
    tuple of ndarray
        ``(Bd (4, 2), Sd (2, 2), Dd (6, 2))``.
    """
    return _disturbance_model("acceleration", validation.positive(sigma_acc, "sigma_acc", allow_zero=True))


class InfeasibleLMIError(RuntimeError):
    """The precision LMI has no solution (or the solver failed); the message names gamma and the status.

    Attributes ``gamma`` (LU) and ``status`` (solver status) survive pickling (process pools).
    """

    def __init__(self, message: str, gamma: float = float("nan"), status: str = "unknown"):
        super().__init__(message)
        self.message = str(message)
        self.gamma = gamma
        self.status = status

    def __reduce__(self):
        return (type(self), (self.message, self.gamma, self.status))


@dataclass(frozen=True)
class ObserverDesign:
    """Result of :class:`PrecisionLMI` (Theorem 1 or 2).

    Attributes
    ----------
    norm : str
        ``"h2"`` or ``"hinf"``.
    gamma : float
        Performance bound on the position error, LU.
    L : ndarray (4, 6)
        Observer gain :math:`L = X^{-1}Y` of Eq. 3a (sign convention of the paper: the observer is
        :math:`\\dot{\\hat x} = (A + LC)\\hat x - Ly + b + Ld`).
    X : ndarray (4, 4)
        Lyapunov matrix of the scaled problem (H2: :math:`\\gamma^2 P^{-1}`; H-infinity: the :math:`X` of Eq. 19,
        unscaled; see :class:`PrecisionLMI`).
    beta : ndarray (6,)
        :math:`\\beta_i = \\kappa_i^2`.
    kappa : ndarray (6,)
        Precision of each sensor (inverse of its admissible noise, :math:`\\kappa_i = \\sqrt{\\beta_i}`).
        For H2 the admissible noise :math:`1/\\kappa_i` is a white-noise intensity (units of the sensor times
        TU^1/2); for H-infinity an energy (L2) bound.
    noise_deg : ndarray (6,)
        Eq. 24 applied to each :math:`\\kappa_i` (meaningful for the four angle sensors), deg.
    used : ndarray of bool (6,)
        Sensors whose :math:`\\beta_i` exceeds ``sparsity_tol`` times the largest (the others can be removed).
    status, solver : str
        Solver status and name.
    solve_time : float
        Wall-clock seconds of the solve (with ``backend="cvxpy"`` or SCS, including canonicalisation on the first
        call).
    objective : float
        Optimal :math:`\\|\\beta\\|_p`.
    Bw, Dd : ndarray
        :math:`B_dS_d` (4, nd) and :math:`D_dS_d` (6, nd) of the error system, with the disturbance level used.
    pole_radius : float or None
        Bandwidth bound imposed (:math:`|\\lambda(A+LC)| < R`, 1/TU), ``None`` if none.
    variable_scale : float
        Magnitude of the scaled Lyapunov variables with which the solver ended (see :class:`PrecisionLMI`).
    """

    norm: str
    gamma: float
    L: np.ndarray
    X: np.ndarray
    beta: np.ndarray
    kappa: np.ndarray
    noise_deg: np.ndarray
    used: np.ndarray
    status: str
    solver: str
    solve_time: float
    objective: float
    Bw: np.ndarray = None
    Dd: np.ndarray = None
    pole_radius: float | None = None
    variable_scale: float = 1.0

    @property
    def gain_norm(self) -> float:
        """Spectral norm of the full observer gain :math:`\\|L\\|_2` (mixed units, LU and LU/TU per sensor unit)."""
        return float(np.linalg.norm(self.L, 2))

    @property
    def optimal(self) -> bool:
        """The solver reported ``optimal`` (not ``optimal_inaccurate``)."""
        return self.status == "optimal"

    def noise_std(self) -> np.ndarray:
        """Admissible noise level of each sensor :math:`1/\\kappa_i` (inf for removed sensors)."""
        with np.errstate(divide="ignore"):
            return np.where(self.used, 1.0 / self.kappa, np.inf)

    def noise_per_sample_deg(self, dt: float) -> np.ndarray:
        r"""H2 only: admissible per-sample angle noise (deg) of a sensor sampled every ``dt`` TU.

        A white-noise intensity :math:`1/\kappa^2` equals the variance :math:`\sigma^2 = 1/(\kappa^2\Delta t)` of
        independent samples held over :math:`\Delta t` (the standard continuous/discrete equivalence), so Eq. 24
        becomes :math:`\delta\theta = \sin^{-1}(1/(\kappa\sqrt{\Delta t}))`.
        """
        if self.norm != "h2":
            raise ValueError("noise_per_sample_deg applies to H2 designs (an intensity); this design is "
                             f"{self.norm!r}")
        dt = validation.positive(dt, "dt")
        return _precision_to_noise_deg(self.kappa * np.sqrt(dt))

    def gain(self, *, drop_unused: bool = True) -> np.ndarray:
        """Observer gain (4, 6); with ``drop_unused`` the columns of removed sensors are set to zero."""
        L = self.L.copy()
        if validation.boolean(drop_unused, "drop_unused"):
            L[:, ~self.used] = 0.0
        return L


_SOLVERS = ("CLARABEL", "SCS")
#: Scalings (variable magnitude, velocity-balanced state scale?) tried in turn by :meth:`PrecisionLMI.solve`
#: until the solver reports ``optimal``; all describe the same problem.
RETRY_SCALINGS = ((100.0, True), (1.0, False), (10.0, False), (100.0, False), (30.0, True), (3.0, False),
                  (0.3, False))
_NORMS = ("h2", "hinf")
_OBJECTIVES = {"l1": 1, "l2": 2, "linf": np.inf}
#: How :class:`PrecisionLMI` reaches Clarabel: its conic data built directly in numpy ("direct", the default) or
#: through cvxpy's canonicalisation ("cvxpy", the older path; SCS always goes through cvxpy).
_BACKENDS = ("direct", "cvxpy")
#: Clarabel status -> the cvxpy status name cvxpy's Clarabel interface reports for it.
_CLARABEL_STATUS = {"Solved": "optimal", "AlmostSolved": "optimal_inaccurate", "PrimalInfeasible": "infeasible",
                    "AlmostPrimalInfeasible": "infeasible_inaccurate", "DualInfeasible": "unbounded",
                    "AlmostDualInfeasible": "unbounded_inaccurate", "MaxIterations": "user_limit",
                    "MaxTime": "user_limit"}


#: Clarabel cone constructors by the kind names of :meth:`PrecisionLMI._conic_data`.
_CLARABEL_CONES = {"nonneg": clarabel.NonnegativeConeT, "soc": clarabel.SecondOrderConeT,
                   "psd": clarabel.PSDTriangleConeT}


def _svec_indices(k):
    """Row and column indices of the upper triangle of a k x k matrix, by columns (Clarabel's PSD triangle)."""
    a, b = np.tril_indices(k)  # a >= b, ordered by a: as (row b, column a) the upper triangle column by column
    return b, a


class PrecisionLMI:
    r"""Theorem 1 (H2) or Theorem 2 (H-infinity) of the paper as a conic program, built once.

    Decision variables :math:`X = X^T \succ 0` (4x4), :math:`Y` (4x6), :math:`\beta \ge 0` (6) and, for H2,
    :math:`Q = Q^T` (2x2).  At every vertex :math:`\rho_v` of the parameter polytope (the LMIs are affine in
    :math:`\rho` because :math:`A, C` are and :math:`X, Y` are constant, so the vertices suffice):

    H2 (Eq. 12-13, derived from the Gramian form :math:`(A+LC)P + P(A+LC)^T + (B_{\bar w}+LD_{\bar w})
    (B_{\bar w}+LD_{\bar w})^T \prec 0`, the noise entering through :math:`LD_{\bar w}`,
    :math:`\mathrm{tr}(C_z P C_z^T) < \gamma^2`, with :math:`X = P^{-1}, Y = XL`):

    .. math:: \begin{bmatrix} \mathrm{sym}(XA_v + YC_v) & (XB_d + YD_d)S_d & Y\\ \star & -I & 0\\
              \star & 0 & -\mathrm{diag}(\beta)\end{bmatrix} \prec 0,\quad
              \begin{bmatrix} -Q & C_z\\ C_z^T & -X\end{bmatrix} \prec 0,\quad \mathrm{tr}\,Q < \gamma^2 .

    H-infinity (Eq. 14/19, from the bounded-real lemma
    :math:`\mathrm{sym}(X(A+LC)) + C_z^TC_z + \gamma^{-2}X(B_{\bar w}+LD_{\bar w})(B_{\bar w}+LD_{\bar w})^TX
    \prec 0`):

    .. math:: \begin{bmatrix} \mathrm{sym}(XA_v + YC_v) & (XB_d + YD_d)S_d & C_z^T & Y\\ \star & -\gamma^2 I & 0 & 0\\
              \star & 0 & -I & 0\\ \star & 0 & 0 & -\gamma^2\mathrm{diag}(\beta)\end{bmatrix} \prec 0 ,

    Scaling (three congruences that leave the solution set unchanged).

    1. :math:`\gamma`.  With :math:`\gamma = 0.0013` the printed forms mix :math:`\gamma^2 \sim 10^{-6}` and
       :math:`\beta \sim 10^{6}`.  H2 is solved in :math:`\tilde X = \gamma^2 X`,
       :math:`\tilde Y = \gamma^2 Y` (same :math:`L`), :math:`\tilde\beta = \gamma^2\beta`, :math:`\tilde Q =
       Q/\gamma^2`, with :math:`\mathrm{tr}\,\tilde Q < 1`.  H-infinity is solved after the congruence
       :math:`\mathrm{diag}(I, I/\gamma, I, I)` of Eq. 19: :math:`X` and :math:`Y` unchanged, the disturbance block
       :math:`(XB_d+YD_d)S_d/\gamma` against :math:`-I`, and :math:`\tilde\beta = \gamma^2\beta`.  In both,
       :math:`\gamma` only scales the disturbance, :math:`S_d \to S_d/\gamma`.  The ratio ``disturbance_scale / gamma`` enters the solver's data
       affinely (and as one ``cp.Parameter`` on the cvxpy path), so sweeps over gamma and over the disturbance
       level re-use the built problem.
    2. State coordinates (optional).  The error may be written :math:`e = T\hat e` with :math:`T =
       \mathrm{diag}(\mathrm{state\_scale})`; default :math:`T = I`.  :meth:`for_cr3bp` also records the
       velocity-balanced :math:`T = \mathrm{diag}(1, 1, v, v)`, :math:`v = 1/\sqrt{\max|a(\rho)|}` (inverse
       of the fastest frozen frequency), one of the scalings :meth:`solve` retries with.
    3. Variable magnitude.  :math:`\tilde X = s\hat X`, :math:`\tilde Y = s\hat Y` with ``variable_scale`` s
       (default 10 with a pole radius, else 1), so that the bandwidth-bounded problems, whose :math:`\tilde X`
       is of order :math:`10^{-4}`-:math:`10^{-2}`, end ``optimal`` in Clarabel.

    Caution, found while building this: the strictness margin :math:`\hat X \succeq \epsilon I` is a bound on
    :math:`X` and thus on the gain; a scaling that makes it bind (e.g. a velocity scaling with a large s) returns
    an ``optimal`` but different answer.  The tests therefore check that the precisions do not move when
    ``eps`` changes tenfold, when the tolerance is tightened and when SCS is used.

    Well-posedness.  The H-infinity infimum is approached only as the gain grows without bound (the observer
    then inverts the :math:`\theta_1` measurement, and the least precision tends to :math:`\max r_{13}/\gamma`):
    without a bound on the gain the minimum is not attained and solvers stop "inaccurate" with a gain that
    depends on the strictness margin.  ``pole_radius`` R (beyond the paper) adds at each vertex
    :math:`\begin{bmatrix}-\hat X & \hat X\hat A_{cl}/R\\ \star & -\hat X\end{bmatrix} \prec 0`, i.e. the
    eigenvalues of :math:`A+LC` inside the disc :math:`|\lambda| < R` with the same Lyapunov matrix: an observer
    bandwidth bound that makes the minimum attained and the gain finite.  The precision then tends to the
    unbounded-gain limit as R grows (shown in notebook 11).  H2 needs no such bound (its optimum has a moderate
    gain).

    In both, the noise enters through :math:`S_n = \mathrm{diag}(1/\kappa_i)` (the scaling from the normalised
    to the physical noise; the paper's text writes :math:`S_n = \mathrm{diag}(\kappa_i)`, which contradicts its
    own definition :math:`\kappa_i = 1/\|n_i\|`) so :math:`(S_nS_n^T)^{-1} = \mathrm{diag}(\beta)` and the
    precision is :math:`\kappa_i = \sqrt{\beta_i}` for *both* theorems (the printed H-infinity formula
    :math:`\sqrt{\beta_i/\gamma}` does not follow from Eq. 18-19).  Strict inequalities are imposed with a margin
    ``eps`` (:math:`\preceq -\epsilon I` in the scaled variables).  Vertices with identical
    :math:`(A_v, C_v)` restricted to the offered sensors give identical LMIs and are imposed once.

    Parameters
    ----------
    A_vertices : array_like (n_v, nx, nx)
        :math:`A(\rho_v)` at the polytope vertices (use :meth:`for_cr3bp` for the CR3BP model).
    C_vertices : array_like (n_v, ny, nx)
        :math:`C_y(\rho_v)`.
    norm : {"h2", "hinf"}
    disturbance : tuple
        ``(Bd (nx, nd), Sd (nd, nd), Dd (ny, nd))``; see :func:`disturbance_model`.  ``solve`` may scale
        :math:`S_d` by ``disturbance_scale``.
    Cz : array_like (nz, nx), optional
        Performance output; default the first two states (position ``[I2 0]`` for the CR3BP).
    objective : {"l1", "l2", "linf"}
        Norm of :math:`\beta` minimised (``"l1"`` promotes sparse sensor selection).
    eps : float
        Margin for the strict LMIs (scaled variables).
    sensors : sequence of int, optional
        Subset of sensors offered to the design (others get zero gain); default all six.
    pole_radius : float, optional
        Bound R on the closed-loop eigenvalue moduli, 1/TU (see Well-posedness).
    state_scale : array_like (nx,), optional
        Diagonal of the coordinate scaling T (default ones; :meth:`for_cr3bp` balances it).
    variable_scale : float, optional
        Magnitude s of the scaled Lyapunov variables (default ``max(1, R/10)`` or 1).
    backend : {"direct", "cvxpy"}
        How the problem reaches Clarabel.  ``"direct"`` (default): the conic data (the LMI matrices' upper
        triangles, column by column with off-diagonals times :math:`\sqrt2`, Clarabel's PSD triangle) are read off
        in numpy by evaluating the affine LMI maps at the unit vectors of the decision variables, once per
        problem, and handed to Clarabel; no cvxpy canonicalisation (measured 3.6x less CPU on notebook 11's
        problems, ``benchmarks/bench_lpv.py``).  ``"cvxpy"``: the older path through cvxpy.  Both describe the
        same problem and agree to solver tolerance (tests: precisions within 1e-5 relative); SCS always goes
        through cvxpy.
    """

    def __init__(self, A_vertices, C_vertices, norm: str = "h2", *, disturbance, Cz=None,
                 objective: str = "l1", eps: float = 1e-8, sensors=None, pole_radius: float | None = None,
                 state_scale=None, variable_scale: float | None = None, backend: str = "direct"):
        self._init = {"A_vertices": A_vertices, "C_vertices": C_vertices, "norm": norm, "disturbance": disturbance, "Cz": Cz,
                          "objective": objective, "eps": eps, "sensors": sensors, "pole_radius": pole_radius,
                          "state_scale": state_scale, "backend": backend}
        self.backend = validation.choice(backend, "backend", _BACKENDS)
        self._rescaled = {}
        A_v = validation.as_array(A_vertices, "A_vertices", ndim=(3,))
        nx = A_v.shape[1]
        if A_v.shape[0] < 1 or A_v.shape[2] != nx:
            raise ValueError(f"A_vertices must have shape (n_v >= 1, nx, nx); got {A_v.shape}")
        C_all = validation.as_array(C_vertices, "C_vertices", ndim=(3,))
        if C_all.shape[0] != A_v.shape[0] or C_all.shape[2] != nx:
            raise ValueError(f"C_vertices must have shape ({A_v.shape[0]}, ny, {nx}) to match A_vertices "
                             f"{A_v.shape}; got {C_all.shape}")
        ny = C_all.shape[1]
        norm = validation.choice(norm, "norm", _NORMS)
        objective = validation.choice(objective, "objective", tuple(_OBJECTIVES))
        self.eps = validation.positive(eps, "eps")
        self.pole_radius = None if pole_radius is None else validation.positive(pole_radius, "pole_radius")
        if not isinstance(disturbance, tuple) or len(disturbance) != 3:
            raise ValueError("disturbance must be a tuple (Bd, Sd, Dd)")
        Bd, Sd, Dd = disturbance
        Bd = validation.as_array(Bd, "disturbance Bd", ndim=(2,))
        nd = Bd.shape[1]
        if Bd.shape[0] != nx:
            raise ValueError(f"disturbance Bd must have {nx} rows (nx of A_vertices {A_v.shape}); got shape "
                             f"{Bd.shape}")
        Sd = validation.as_array(Sd, "disturbance Sd", shape=(nd, nd))
        Dd = validation.as_array(Dd, "disturbance Dd", ndim=(2,))
        if Dd.shape != (ny, nd):
            raise ValueError(f"disturbance Dd must have shape ({ny}, {nd}) (ny from C_vertices {C_all.shape}, nd from "
                             f"Bd {Bd.shape}); got {Dd.shape}")
        Cz = np.eye(min(2, nx), nx) if Cz is None else validation.as_array(Cz, "Cz", ndim=(2,), last=nx)
        if sensors is None:
            sensors = list(range(ny))
        else:
            try:
                sensors = sorted(validation.integer(i, "sensors") for i in sensors)
            except TypeError as exc:
                raise validation.ArgumentTypeError(f"sensors must be a sequence of sensor indices; got "
                                                f"{type(sensors).__name__}") from exc
        if not sensors or any(i < 0 or i >= ny for i in sensors) or len(set(sensors)) != len(sensors):
            raise ValueError(f"sensors must be distinct indices in [0, {ny}); got {sensors}")
        tvec = np.ones(nx) if state_scale is None else validation.as_array(state_scale, "state_scale", shape=(nx,))
        if np.any(tvec <= 0):
            raise ValueError(f"state_scale must be positive; got {tvec}")
        if variable_scale is None:
            variable_scale = 10.0 if self.pole_radius else 1.0
        xs = validation.positive(variable_scale, "variable_scale")
        self.n_x, self.n_y = nx, ny
        self.A_vertices, self.C_vertices, self.norm, self.objective = A_v, C_all, norm, objective
        self.Bd, self.Sd, self.Dd, self.Cz, self.sensors = Bd, Sd, Dd, Cz, sensors
        self.state_scale, self.variable_scale = tvec, xs
        # exact de-duplication: vertices that differ only in parameters the offered sensors do not see
        flat = np.concatenate([A_v.reshape(A_v.shape[0], -1), C_all[:, sensors, :].reshape(A_v.shape[0], -1)], 1)
        _, keep = np.unique(flat, axis=0, return_index=True)
        keep = np.sort(keep)
        self.n_unique_vertices = keep.size
        T, Ti = np.diag(tvec), np.diag(1.0 / tvec)
        A_h = Ti @ A_v[keep] @ T
        C_h = C_all[keep][:, sensors, :] @ T
        Bd_h, Cz_h, Dd_s = Ti @ Bd, Cz @ T, Dd[sensors]

        self._data = (A_h, C_h, Bd_h, Cz_h, Dd_s, Sd)
        self._cvx = None
        self._conic = self._conic_data()

    def _blocks(self, Xh, Yh, beta, Q, dog):
        """``(psd, lin)``: the constraint matrices of the problem (each must be PSD) and its linear inequality rows
        (each >= 0: beta, and for H2 1 - tr Q), evaluated in numpy on the same expressions as
        :meth:`_cvxpy_problem` for decision variables batched on a leading axis (the objective's cone rows are
        added by :meth:`_conic_data`)."""
        A_h, C_h, Bd_h, Cz_h, Dd_s, Sd = self._data
        nx, ns, nd, nz = self.n_x, len(self.sensors), Sd.shape[0], Cz_h.shape[0]
        nb, eps, xs = Xh.shape[0], self.eps, self.variable_scale
        X, Y = xs * Xh, xs * Yh
        XAcl = np.einsum("bij,vjk->bvik", X, A_h) + np.einsum("bij,vjk->bvik", Y, C_h)
        M11 = XAcl + np.swapaxes(XAcl, -1, -2)
        M12 = dog * ((X @ Bd_h + Y @ Dd_s) @ Sd)
        nv = A_h.shape[0]
        if self.norm == "h2":
            k = nx + nd + ns
            blk = np.zeros((nb, nv, k, k))
            o = nx + nd
        else:
            k = nx + nd + nz + ns
            blk = np.zeros((nb, nv, k, k))
            o = nx + nd + nz
            blk[:, :, :nx, nx + nd:o] = Cz_h.T
            blk[:, :, nx + nd:o, :nx] = Cz_h
            blk[:, :, nx + nd:o, nx + nd:o] = -np.eye(nz)
        blk[:, :, :nx, :nx] = M11
        blk[:, :, :nx, nx:nx + nd] = M12[:, None]
        blk[:, :, nx:nx + nd, :nx] = np.swapaxes(M12, -1, -2)[:, None]
        blk[:, :, nx:nx + nd, nx:nx + nd] = -np.eye(nd)
        blk[:, :, :nx, o:] = Y[:, None]
        blk[:, :, o:, :nx] = np.swapaxes(Y, -1, -2)[:, None]
        idx = np.arange(ns)
        blk[:, :, o + idx, o + idx] = -beta[:, None, :]
        psd = [Xh - eps * np.eye(nx), -0.5 * (blk + np.swapaxes(blk, -1, -2)) - eps * np.eye(k)]
        if self.pole_radius is not None:
            R = self.pole_radius
            disk = np.zeros((nb, nv, 2 * nx, 2 * nx))
            disk[:, :, :nx, :nx] = -X[:, None]
            disk[:, :, nx:, nx:] = -X[:, None]
            disk[:, :, :nx, nx:] = XAcl / R
            disk[:, :, nx:, :nx] = np.swapaxes(XAcl, -1, -2) / R
            psd.append(-0.5 * (disk + np.swapaxes(disk, -1, -2)) - eps * np.eye(2 * nx))
        lin = [beta]
        if self.norm == "h2":
            qb = np.zeros((nb, nz + nx, nz + nx))
            qb[:, :nz, :nz] = Q
            qb[:, :nz, nz:] = Cz_h
            qb[:, nz:, :nz] = Cz_h.T
            qb[:, nz:, nz:] = X
            psd.append(qb - eps * np.eye(nz + nx))
            lin.append(1.0 - np.trace(Q, axis1=-2, axis2=-1)[:, None])
        return psd, lin

    def _layout(self):
        """Positions of the decision variables in the solver's vector: (X upper triangle, Y, beta, Q, t)."""
        nx, ns, nz = self.n_x, len(self.sensors), self.Cz.shape[0]
        iu = np.triu_indices(nx)
        sizes = {"X": iu[0].size, "Y": nx * ns, "beta": ns, "Q": nz * (nz + 1) // 2 if self.norm == "h2" else 0,
                 "t": 0 if self.objective == "l1" else 1}
        out, at = {}, 0
        for key, n in sizes.items():
            out[key] = slice(at, at + n)
            at += n
        return out, at

    def _unpack(self, z):
        """Decision variables from the solver vector(s) ``z`` (..., n): Xh, Yh, beta, Q (scaled variables)."""
        nx, ns, nz = self.n_x, len(self.sensors), self.Cz.shape[0]
        lay, _ = self._layout()
        z = np.atleast_2d(z)
        Xh = np.zeros((z.shape[0], nx, nx))
        iu = np.triu_indices(nx)
        Xh[:, iu[0], iu[1]] = z[:, lay["X"]]
        Xh[:, iu[1], iu[0]] = z[:, lay["X"]]
        Yh = z[:, lay["Y"]].reshape(-1, nx, ns)
        beta = z[:, lay["beta"]]
        Q = np.zeros((z.shape[0], nz, nz))
        if self.norm == "h2":
            iq = np.triu_indices(nz)
            Q[:, iq[0], iq[1]] = z[:, lay["Q"]]
            Q[:, iq[1], iq[0]] = z[:, lay["Q"]]
        return Xh, Yh, beta, Q

    def _conic_data(self):
        """The problem in Clarabel's form, min q'z s.t. A z + s = b, s in K, with A and b affine in the
        ``disturbance / gamma`` ratio: ``(q, (A0, b0), (A1, b1), cones)`` with A = A0 + r A1, b = b0 + r b1 and
        ``cones`` a list of ``(kind, dimension)``, kind "nonneg", "soc" or "psd" (plain tuples: the problem pickles).

        The constraint maps are read off by evaluating :meth:`_blocks` at z = 0 and at each unit vector (they are
        affine in z); a PSD block enters as the upper triangle by columns with off-diagonals times sqrt(2)
        (Clarabel's ``PSDTriangleConeT``)."""
        lay, n = self._layout()
        basis = np.vstack([np.zeros(n), np.eye(n)])
        parts = {}
        for dog in (0.0, 1.0):
            psd, lin = self._blocks(*self._unpack(basis), dog)
            rows, cones = [], []
            lin_rows = np.concatenate([v.reshape(n + 1, -1) for v in lin], axis=1)
            if self.objective == "linf":  # t - beta_i >= 0
                t = basis[:, lay["t"]]
                lin_rows = np.concatenate([lin_rows, t - basis[:, lay["beta"]]], axis=1)
            rows.append(lin_rows)
            cones.append(("nonneg", lin_rows.shape[1]))
            if self.objective == "l2":  # (t, beta) in the second-order cone
                soc = np.concatenate([basis[:, lay["t"]], basis[:, lay["beta"]]], axis=1)
                rows.append(soc)
                cones.append(("soc", soc.shape[1]))
            for M in psd:
                k = M.shape[-1]
                iu = _svec_indices(k)
                w = np.where(iu[0] == iu[1], 1.0, np.sqrt(2.0))
                S = M[..., iu[0], iu[1]] * w
                S = S.reshape(n + 1, -1, iu[0].size)
                rows.append(S.reshape(n + 1, -1))
                cones.extend(("psd", k) for _ in range(S.shape[1]))
            F = np.concatenate(rows, axis=1)  # (1 + n, m): s(z) = F[0] + sum_i z_i (F[i] - F[0])
            parts[dog] = (-(F[1:] - F[0]).T, F[0].copy())
        (A0, b0), (A1_, b1_) = parts[0.0], parts[1.0]
        q = np.zeros(n)
        q[lay["beta"] if self.objective == "l1" else lay["t"]] = 1.0
        return q, (A0, b0), (A1_ - A0, b1_ - b0), cones

    def _cvxpy_problem(self):
        """The same problem as a cvxpy ``Problem`` (built on first use: the SCS path and ``backend="cvxpy"``);
        returns ``(problem, X, Y, beta, disturbance_over_gamma)``."""
        import cvxpy as cp

        if self._cvx is not None:
            return self._cvx
        A_h, C_h, Bd_h, Cz_h, Dd_s, Sd = self._data
        nx, ns, nd, nz = self.n_x, len(self.sensors), Sd.shape[0], Cz_h.shape[0]
        norm, xs = self.norm, self.variable_scale
        Xh = cp.Variable((nx, nx), symmetric=True, name="X_hat")
        Yh = cp.Variable((nx, ns), name="Y_hat")
        beta = cp.Variable(ns, nonneg=True, name="beta_scaled")
        dist_over_gamma = cp.Parameter(nonneg=True, name="disturbance_over_gamma", value=1.0)
        X, Y = xs * Xh, xs * Yh
        eps = self.eps
        cons = [Xh >> eps * np.eye(nx)]
        Ind = np.eye(nd)
        for Av, Cv in zip(A_h, C_h):
            XAcl = X @ Av + Y @ Cv
            M11 = XAcl + XAcl.T
            M12 = dist_over_gamma * ((X @ Bd_h + Y @ Dd_s) @ Sd)
            if norm == "h2":
                blk = cp.bmat([[M11, M12, Y],
                               [M12.T, -Ind, np.zeros((nd, ns))],
                               [Y.T, np.zeros((ns, nd)), -cp.diag(beta)]])
            else:
                blk = cp.bmat([[M11, M12, Cz_h.T, Y],
                               [M12.T, -Ind, np.zeros((nd, nz)), np.zeros((nd, ns))],
                               [Cz_h, np.zeros((nz, nd)), -np.eye(nz), np.zeros((nz, ns))],
                               [Y.T, np.zeros((ns, nd)), np.zeros((ns, nz)), -cp.diag(beta)]])
            size = blk.shape[0]
            cons.append(0.5 * (blk + blk.T) << -eps * np.eye(size))
            if self.pole_radius is not None:
                R = self.pole_radius
                disk = cp.bmat([[-X, XAcl / R], [XAcl.T / R, -X]])
                cons.append(0.5 * (disk + disk.T) << -eps * np.eye(2 * nx))
        if norm == "h2":
            Q = cp.Variable((nz, nz), symmetric=True, name="Q_scaled")
            cons.append(cp.bmat([[Q, Cz_h], [Cz_h.T, X]]) >> eps * np.eye(nz + nx))
            cons.append(cp.trace(Q) <= 1.0)
        problem = cp.Problem(cp.Minimize(cp.norm(beta, _OBJECTIVES[self.objective])), cons)
        self._cvx = (problem, X, Y, beta, dist_over_gamma)
        return self._cvx

    @classmethod
    def for_cr3bp(cls, model: CR3BPLPV, vertices, norm: str = "h2", *, disturbance=None, **kwargs) -> PrecisionLMI:
        """The LMI for the planar CR3BP LPV model at the polytope ``vertices`` (n_v, 6) of :math:`\\rho`.

        ``disturbance`` defaults to :func:`default_disturbance`; other keywords go to the constructor.
        """
        model = validation.instance(model, "model", CR3BPLPV)
        V = validation.as_array(vertices, "vertices", ndim=(2,), last=model.n_rho)
        if V.shape[0] < 1:
            raise ValueError("vertices must hold at least one vertex")
        A = model.A(V)
        lmi = cls(A, model.C(V), norm, disturbance=default_disturbance() if disturbance is None
                  else disturbance, **kwargs)
        lmi.vertices = V
        v = 1.0 / np.sqrt(max(1.0, float(np.max(np.abs(A[:, 2, 0])))))  # inverse of the fastest frozen frequency
        lmi.balanced_state_scale = np.array([1.0, 1.0, v, v])
        return lmi

    def rescaled(self, variable_scale: float, state_scale=None) -> PrecisionLMI:
        """The same problem built with another ``variable_scale`` and ``state_scale`` (cached)."""
        xs = validation.positive(variable_scale, "variable_scale")
        ss = self.state_scale if state_scale is None else validation.as_array(state_scale, "state_scale",
                                                                             shape=(self.n_x,))
        return self._rescaled_kernel(xs, ss)

    def _rescaled_kernel(self, xs, ss):
        if xs == self.variable_scale and np.array_equal(ss, self.state_scale):
            return self
        key = (xs, tuple(ss))
        if key not in self._rescaled:
            other = PrecisionLMI(**{**self._init, "state_scale": ss}, variable_scale=xs)
            for attr in ("vertices", "balanced_state_scale"):
                if hasattr(self, attr):
                    setattr(other, attr, getattr(self, attr))
            self._rescaled[key] = other
        return self._rescaled[key]

    def solve(self, gamma: float, *, solver: str = "CLARABEL", disturbance_scale: float = 1.0,
              tol: float | None = None, sparsity_tol: float = 1e-4, retry: bool = True,
              **solver_options) -> ObserverDesign:
        """Solve for the bound ``gamma`` (LU); if the solver does not end ``optimal`` and ``retry``, re-solve the
        same problem built with the scalings of :data:`RETRY_SCALINGS` (variable magnitude, and for
        :meth:`for_cr3bp` problems the velocity-balanced state scale) until one does.

        If the problem's own scaling ends ``optimal``, that design is returned.  Otherwise every retry scaling is
        solved and, among those ending ``optimal``, the design with the smallest objective is returned: a scaling
        can make the strictness margin bind and end ``optimal`` at a worse objective (found in notebook 11: a first
        retry 9.6 % worse than the problem's own optimum), so the first ``optimal`` retry is not trusted on its
        own.  If none is ``optimal``, the first solution (``optimal_inaccurate``, with a warning) or, if every
        attempt failed, :class:`InfeasibleLMIError`.  Parameters: see :meth:`solve_once`.
        """
        retry = validation.boolean(retry, "retry")
        gamma, solver, disturbance_scale, tol, sparsity_tol, solver_options = self._solve_arguments(
            gamma, solver, disturbance_scale, tol, sparsity_tol, solver_options)
        balanced = getattr(self, "balanced_state_scale", None)
        configs = [(self.variable_scale, None)]
        if retry:
            for xs, bal in RETRY_SCALINGS:
                if bal and balanced is None:
                    continue
                configs.append((xs, balanced if bal else np.ones(self.n_x)))
        first, first_exc, tried, optimal = None, None, [], []
        for xs, ss in configs:
            lmi = self._rescaled_kernel(xs, self.state_scale if ss is None else ss)
            if lmi in tried:
                continue
            tried.append(lmi)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                try:
                    d = lmi._solve_once(gamma, solver, disturbance_scale, sparsity_tol, solver_options)
                except InfeasibleLMIError as exc:
                    if exc.status == "infeasible":  # a certificate, not a numerical accident
                        raise
                    first_exc = first_exc or exc
                    continue
            if d.optimal:
                if len(tried) == 1:  # the problem's own scaling
                    return d
                optimal.append(d)
                continue
            first = first or d
        if optimal:
            return min(optimal, key=lambda design: design.objective)  # the first of equal objectives
        if first is None:
            raise first_exc
        warnings.warn(f"{self.norm} precision LMI at gamma = {first.gamma:g}: none of {len(tried)} scalings gave "
                      f"'optimal'; returning the {first.status!r} solution (verify it with verify_observer)",
                      stacklevel=2)
        return first

    def solve_once(self, gamma: float, *, solver: str = "CLARABEL", disturbance_scale: float = 1.0,
                   tol: float | None = None, sparsity_tol: float = 1e-4, **solver_options) -> ObserverDesign:
        """Solve for the bound ``gamma`` (LU) and return the design.

        Parameters
        ----------
        gamma : float
            Bound on the H2 or H-infinity norm from the normalised exogenous input to the position error, LU.
        solver : {"CLARABEL", "SCS"}
        disturbance_scale : float
            Multiplies the constructor's :math:`S_d` (>= 0) without rebuilding the problem.
        tol : float, optional
            Solver tolerance (Clarabel ``tol_gap_abs``, ``tol_gap_rel``, ``tol_feas``; SCS ``eps_abs``,
            ``eps_rel``); default the solver's (Clarabel 1e-8) or 1e-9 for SCS.
        sparsity_tol : float
            A sensor is reported unused when its :math:`\\beta_i` is below this fraction of the largest.
        **solver_options
            Passed to ``cvxpy.Problem.solve``.

        Raises
        ------
        ValueError
            Non-positive gamma or unknown solver.
        InfeasibleLMIError
            The solver reports infeasibility or fails; the message names gamma and the status.
        """
        gamma, solver, dscale, _, sparsity_tol, solver_options = self._solve_arguments(
            gamma, solver, disturbance_scale, tol, sparsity_tol, solver_options)
        return self._solve_once(gamma, solver, dscale, sparsity_tol, solver_options)

    @staticmethod
    def _solve_arguments(gamma, solver, disturbance_scale, tol, sparsity_tol, solver_options):
        """The checks of :meth:`solve` / :meth:`solve_once`, done once; the tolerance folded into the options."""
        gamma = validation.positive(gamma, "gamma")
        solver = validation.choice(str(solver).upper() if isinstance(solver, str) else solver, "solver", _SOLVERS)
        dscale = validation.positive(disturbance_scale, "disturbance_scale", allow_zero=True)
        sparsity_tol = validation.in_range(sparsity_tol, "sparsity_tol", 0.0, 1.0)
        if tol is not None:
            tol = validation.positive(tol, "tol")
        if solver == "SCS":
            t = 1e-9 if tol is None else tol
            solver_options = {"eps_abs": t, "eps_rel": t, "max_iters": 200000, **solver_options}
        elif tol is not None:
            solver_options = {"tol_gap_abs": tol, "tol_gap_rel": tol, "tol_feas": tol, "max_iter": 400,
                              **solver_options}
        return gamma, solver, dscale, tol, sparsity_tol, solver_options

    def _solve_once(self, gamma, solver, dscale, sparsity_tol, solver_options) -> ObserverDesign:
        """Kernel of :meth:`solve_once` (arguments already checked by :meth:`_solve_arguments`)."""
        t0 = time.perf_counter()
        if solver == "CLARABEL" and self.backend == "direct":
            status, Xv, Yv, bv, value = self._solve_direct(gamma, dscale / gamma, solver_options)
        else:
            status, Xv, Yv, bv, value = self._solve_cvxpy(gamma, solver, dscale / gamma, solver_options)
        elapsed = time.perf_counter() - t0
        if status not in ("optimal", "optimal_inaccurate") or Xv is None:
            raise InfeasibleLMIError(
                f"{self.norm} precision LMI infeasible or unsolved at gamma = {gamma:g}: solver {solver} status "
                f"{status!r} ({self.n_unique_vertices} distinct vertices)", gamma, str(status))
        if status == "optimal_inaccurate":
            warnings.warn(f"{self.norm} precision LMI at gamma = {gamma:g}: solver {solver} returned "
                          "optimal_inaccurate; verify the design (verify_observer) before trusting it", stacklevel=2)
        return self._design(gamma, dscale, sparsity_tol, solver, status, elapsed, Xv, Yv, bv, value)

    def _solve_direct(self, gamma, ratio, solver_options):
        """Clarabel on the data of :meth:`_conic_data`; returns ``(status, X, Y, beta, objective)`` as cvxpy would
        (status names of cvxpy; a solver failure raises :class:`InfeasibleLMIError` with status "solver_error")."""
        q, (A0, b0), (A1, b1), cones = self._conic
        A = sparse.csc_matrix(A0 + ratio * A1)
        n = q.size
        settings = clarabel.DefaultSettings()
        settings.verbose = False
        for key, val in solver_options.items():
            try:
                setattr(settings, key, val)
            except (AttributeError, TypeError) as exc:
                raise ValueError(f"solver_options: Clarabel has no setting {key!r} of that type ({exc})") from exc
        cones = [_CLARABEL_CONES[kind](dim) for kind, dim in cones]
        sol = clarabel.DefaultSolver(sparse.csc_matrix((n, n)), q, A, b0 + ratio * b1, cones, settings).solve()
        status = _CLARABEL_STATUS.get(str(sol.status), "solver_error")
        if status == "solver_error":
            raise InfeasibleLMIError(f"{self.norm} precision LMI: solver CLARABEL failed at gamma = {gamma:g} "
                                     f"(status {sol.status})", gamma, "solver_error")
        if status not in ("optimal", "optimal_inaccurate"):
            return status, None, None, None, None
        Xh, Yh, beta, _ = self._unpack(np.asarray(sol.x))
        xs = self.variable_scale
        return status, xs * Xh[0], xs * Yh[0], beta[0], float(sol.obj_val)

    def _solve_cvxpy(self, gamma, solver, ratio, solver_options):
        """The same through cvxpy (SCS, or ``backend="cvxpy"``)."""
        import cvxpy as cp

        problem, X, Y, beta, dog = self._cvxpy_problem()
        dog.value = ratio
        try:
            problem.solve(solver=solver, **solver_options)
        except cp.error.SolverError as exc:
            raise InfeasibleLMIError(f"{self.norm} precision LMI: solver {solver} failed at gamma = {gamma:g} "
                                     f"({exc})", gamma, "solver_error") from exc
        if problem.status not in (cp.OPTIMAL, cp.OPTIMAL_INACCURATE) or X.value is None:
            return str(problem.status), None, None, None, None
        return str(problem.status), X.value, Y.value, beta.value, float(problem.value)

    def _design(self, gamma, dscale, sparsity_tol, solver, status, elapsed, Xval, Yval, beta_val, value):
        """The :class:`ObserverDesign` from the scaled solution."""
        T = np.diag(self.state_scale)
        Xh = 0.5 * (Xval + Xval.T)
        Ls = T @ np.linalg.solve(Xh, Yval)
        Xv = np.diag(1.0 / self.state_scale) @ Xh @ np.diag(1.0 / self.state_scale)
        L = np.zeros((self.n_x, self.n_y))
        L[:, self.sensors] = Ls
        beta = np.zeros(self.n_y)
        beta[self.sensors] = np.maximum(beta_val, 0.0) / gamma**2
        kappa = np.sqrt(beta)
        used = np.zeros(self.n_y, dtype=bool)
        used[self.sensors] = beta[self.sensors] > sparsity_tol * beta.max()
        Sd = dscale * self.Sd
        return ObserverDesign(norm=self.norm, gamma=gamma, L=L, X=Xv, beta=beta, kappa=kappa,
                              noise_deg=_precision_to_noise_deg(kappa), used=used, status=str(status),
                              solver=solver, solve_time=elapsed, objective=value / gamma**2,
                              Bw=self.Bd @ Sd, Dd=self.Dd @ Sd, pole_radius=self.pole_radius,
                              variable_scale=self.variable_scale)


def design_observer(model: CR3BPLPV, vertices, gamma: float, norm: str = "h2", *, solver: str = "CLARABEL",
                    **kwargs) -> ObserverDesign:
    """One-shot :class:`PrecisionLMI` build and solve (keyword arguments go to the constructor).

    Returns
    -------
    ObserverDesign
    """
    return PrecisionLMI.for_cr3bp(model, vertices, norm, **kwargs).solve(gamma, solver=solver)


def gamma_sweep(lmi: PrecisionLMI, gammas, *, solver: str = "CLARABEL") -> list:
    """Solve ``lmi`` for each gamma (re-using the built problem); infeasible points give ``None``."""
    lmi = validation.instance(lmi, "lmi", PrecisionLMI)
    g = validation.as_array(gammas, "gammas", ndim=(1,), min_size=1)
    out = []
    for gamma in g:
        try:
            out.append(lmi.solve(float(gamma), solver=solver))
        except InfeasibleLMIError:
            out.append(None)
    return out


# ------------------------------------------------------------------------------------------ verification
def _check_abc(A, B, C):
    A = validation.square(A, "A")
    n = A.shape[0]
    if n == 0:
        raise ValueError("A must be a non-empty square matrix; got shape (0, 0)")
    B = validation.as_array(B, "B", ndim=(2,), min_size=1)
    C = validation.as_array(C, "C", ndim=(2,), min_size=1)
    if B.shape[0] != n:
        raise ValueError(f"B must have {n} rows (the order of A); got shape {B.shape}")
    if C.shape[1] != n:
        raise ValueError(f"C must have {n} columns (the order of A); got shape {C.shape}")
    return A, B, C


def h2_norm(A, B, C) -> float:
    r"""H2 norm of :math:`C(sI-A)^{-1}B` from the controllability Gramian (Lyapunov equation).

    :math:`AP + PA^T + BB^T = 0`, :math:`\|G\|_2 = \sqrt{\mathrm{tr}(CPC^T)}`; ``inf`` if A is not Hurwitz.
    """
    return _h2_norm(*_check_abc(A, B, C))


def _h2_norm(A, B, C) -> float:
    """Kernel of :func:`h2_norm` (unchecked)."""
    from scipy.linalg import solve_continuous_lyapunov

    if np.max(np.linalg.eigvals(A).real) >= 0:
        return np.inf
    P = solve_continuous_lyapunov(A, -B @ B.T)
    return float(np.sqrt(max(np.trace(C @ P @ C.T), 0.0)))


def _sigma_max(A, B, C, w):
    n = A.shape[0]
    G = C @ np.linalg.solve(1j * w * np.eye(n) - A, B)
    return np.linalg.norm(G, 2)


def _sigma_max_many(A, B, C, w):
    """:func:`_sigma_max` at every frequency of ``w`` (k,) in one batched call (the same LAPACK calls per
    frequency, so the same values); returns (k,)."""
    n = A.shape[0]
    M = 1j * np.asarray(w, dtype=float)[:, None, None] * np.eye(n) - A
    G = C @ np.linalg.solve(M, np.broadcast_to(B, (M.shape[0],) + B.shape))
    return np.linalg.svd(G, compute_uv=False)[:, 0]


def hinf_norm(A, B, C, *, rtol: float = 1e-9, max_iter: int = 50) -> float:
    r"""H-infinity norm of :math:`C(sI-A)^{-1}B` (no feedthrough) by the Hamiltonian level-set iteration.

    Boyd-Balakrishnan / Bruinsma-Steinbuch: starting from a lower bound (largest singular value over a
    frequency grid and the modal frequencies), the level :math:`\gamma(1+2\,\mathrm{rtol})` is tested with
    :math:`H = [[A, BB^T/\gamma^2], [-C^TC, -A^T]]`; its imaginary eigenvalues :math:`j\omega_i` bracket the
    frequencies where :math:`\sigma_{max} > \gamma`, whose midpoints give the next lower bound.  Returns
    ``inf`` if A is not Hurwitz.
    """
    A, B, C = _check_abc(A, B, C)
    rtol = validation.positive(rtol, "rtol")
    max_iter = validation.integer(max_iter, "max_iter", minimum=1)
    return _hinf_norm(A, B, C, rtol, max_iter)


def _hinf_norm(A, B, C, rtol: float = 1e-9, max_iter: int = 50) -> float:
    """Kernel of :func:`hinf_norm` (unchecked)."""
    eig = np.linalg.eigvals(A)
    if np.max(eig.real) >= 0:
        return np.inf
    scale = max(np.max(np.abs(eig)), 1e-12)
    freqs = np.concatenate([[0.0], np.abs(eig.imag), scale * np.logspace(-4, 2, 60)])
    lb = float(np.max(_sigma_max_many(A, B, C, freqs)))
    if lb == 0:
        return 0.0
    BB, CC = B @ B.T, C.T @ C
    for _ in range(max_iter):
        g = lb * (1.0 + 2.0 * rtol)
        H = np.block([[A, BB / g**2], [-CC, -A.T]])
        ev = np.linalg.eigvals(H)
        tol_im = 1e-8 * max(np.max(np.abs(ev)), 1.0)
        w = np.sort(np.abs(ev[np.abs(ev.real) < tol_im].imag))
        w = np.unique(np.round(w / tol_im) * tol_im)
        if w.size == 0:
            return float(lb)
        if w.size == 1:
            cand = [w[0]]
        else:
            cand = 0.5 * (w[:-1] + w[1:])
        new = float(np.max(_sigma_max_many(A, B, C, cand)))
        if new <= lb * (1.0 + rtol):
            return float(lb)
        lb = new
    return float(lb)  # pragma: no cover


@dataclass(frozen=True)
class Verification:
    """Independent check of an observer gain over the parameter polytope.

    Attributes
    ----------
    n_vertices, n_samples : int
        Frozen parameter values checked (vertices and uniform random interior samples).
    max_real_eig : float
        Largest real part of the eigenvalues of :math:`A(\\rho)+LC(\\rho)` over all checked points, 1/TU.
    worst_h2, worst_hinf : float
        Largest frozen-parameter H2 and H-infinity norms from the normalised input to the position error, LU.
    worst_rho_h2, worst_rho_hinf : ndarray (6,)
        Parameter values where the worst norms occur.
    gamma : float
        Design bound.
    norm : str
        Norm the design bounds (``"h2"`` or ``"hinf"``).
    """

    n_vertices: int
    n_samples: int
    max_real_eig: float
    worst_h2: float
    worst_hinf: float
    worst_rho_h2: np.ndarray
    worst_rho_hinf: np.ndarray
    gamma: float
    norm: str

    @property
    def hurwitz(self) -> bool:
        """A+LC Hurwitz at every checked point."""
        return bool(self.max_real_eig < 0)

    @property
    def worst(self) -> float:
        """Worst norm of the designed kind."""
        return self.worst_h2 if self.norm == "h2" else self.worst_hinf

    @property
    def passed(self) -> bool:
        """Hurwitz everywhere and the designed norm below gamma everywhere."""
        return self.hurwitz and self.worst < self.gamma


def error_system(model: CR3BPLPV, design: ObserverDesign, rho, *, L=None):
    r"""Frozen-parameter error system :math:`(A+LC,\ [B_dS_d + LD_dS_d,\ LS_n],\ C_z)` at ``rho`` (6,).

    :math:`S_n = \mathrm{diag}(1/\kappa_i)` (zero for sensors whose gain column is zero).
    """
    model = validation.instance(model, "model", CR3BPLPV)
    design = validation.instance(design, "design", ObserverDesign)
    r = validation.as_array(rho, "rho", shape=(model.n_rho,))
    L = design.gain() if L is None else validation.as_array(L, "L", shape=(model.n_x, model.n_y))
    return _error_system(model, design, r, L)


def _error_system(model, design, r, L):
    """Kernel of :func:`error_system` (unchecked: ``r`` (6,), ``L`` (4, 6) float arrays)."""
    with np.errstate(divide="ignore"):
        sn = np.where(design.kappa > 0, 1.0 / np.where(design.kappa > 0, design.kappa, 1.0), 0.0)
    sn = np.where(np.any(L != 0, axis=0), sn, 0.0)
    Acl = model._affine_kernel("A", r) + L @ model._affine_kernel("C", r)
    B = np.hstack([design.Bw + L @ design.Dd, L * sn[None, :]])
    Cz = np.hstack([np.eye(2), np.zeros((2, 2))])
    return Acl, B, Cz


def verify_observer(model: CR3BPLPV, design: ObserverDesign, box: ParameterBox, n_samples: int,
                    rng: np.random.Generator, *, L=None) -> Verification:
    """Check a design without trusting the solver: Hurwitz and frozen-parameter H2 / H-infinity norms at every
    vertex of ``box`` and at ``n_samples`` uniform random points inside it.

    Parameters
    ----------
    model : CR3BPLPV
    design : ObserverDesign
    box : ParameterBox
    n_samples : int
        Interior samples (>= 1).
    rng : numpy.random.Generator
    L : array_like (4, 6), optional
        Gain to check (default ``design.gain()``, unused sensors removed).

    Returns
    -------
    Verification
    """
    model = validation.instance(model, "model", CR3BPLPV)
    design = validation.instance(design, "design", ObserverDesign)
    box = validation.instance(box, "box", ParameterBox)
    n_samples = validation.integer(n_samples, "n_samples", minimum=1)
    rng = validation.rng(rng, "rng")
    if box.dim != model.n_rho:
        raise ValueError(f"box must bound the {model.n_rho} scheduling parameters; got dim {box.dim}")
    L = design.gain() if L is None else validation.as_array(L, "L", shape=(model.n_x, model.n_y))
    V = box.vertices()
    S = box.sample(n_samples, rng)
    pts = np.vstack([V, S])
    max_eig, worst2, worstinf = -np.inf, -np.inf, -np.inf
    r2 = rinf = pts[0]
    for r in pts:
        Acl, B, Cz = _error_system(model, design, r, L)
        max_eig = max(max_eig, float(np.max(np.linalg.eigvals(Acl).real)))
        h2 = _h2_norm(Acl, B, Cz)
        hi = _hinf_norm(Acl, B, Cz)
        if h2 > worst2:
            worst2, r2 = h2, r
        if hi > worstinf:
            worstinf, rinf = hi, r
    return Verification(V.shape[0], S.shape[0], max_eig, worst2, worstinf, r2.copy(), rinf.copy(),
                        design.gamma, design.norm)


# ------------------------------------------------------------------------------------ Fig. 3 criterion
def guaranteed_error_rms(design: ObserverDesign, noise_rms_deg: float, dt: float | None = None) -> float:
    r"""Position-error RMS (LU) that the LMI certifies for angle noise of RMS ``noise_rms_deg`` on :math:`\theta_1`.

    The error system is linear in the normalised input :math:`\bar w_i = \kappa_i n_i`.  An angle error
    :math:`\delta\theta` gives :math:`n_{\sin} = \cos\theta\,\delta\theta`, :math:`n_{\cos} = -\sin\theta\,
    \delta\theta`, so :math:`|\bar w| \le \kappa_{max}|\delta\theta|` with :math:`\kappa_{max}` the largest
    precision of the used :math:`\theta_1` channels.  Hence, with :math:`\rho` known exactly:

    * H2 (Theorem 1): white noise of intensity :math:`\sigma^2\Delta t` (samples of variance :math:`\sigma^2` held
      over :math:`\Delta t`) gives a steady-state :math:`E|\epsilon|^2 \le \gamma^2\kappa_{max}^2\sigma^2\Delta t`
      (the common Lyapunov matrix bounds the error covariance of the LPV system);
    * H-infinity (Theorem 2): :math:`\|\epsilon\|_{L_2} \le \gamma\|\bar w\|_{L_2}`, so over a long window the
      time-RMS error is at most :math:`\gamma\kappa_{max}\,\mathrm{RMS}(\delta\theta)` (plus a transient term
      from the initial error, negligible after settling).

    Parameters
    ----------
    design : ObserverDesign
    noise_rms_deg : float
        RMS of the angle noise, deg (per sample for H2).
    dt : float, optional
        Sampling interval, TU (required for H2).

    Returns
    -------
    float
        Bound on the RMS position error, LU.
    """
    design = validation.instance(design, "design", ObserverDesign)
    sig = np.radians(validation.positive(noise_rms_deg, "noise_rms_deg", allow_zero=True))
    if dt is not None:
        dt = validation.positive(dt, "dt")
    used = design.used[:2]
    if not used.any():
        raise ValueError("design must use a theta1 sensor (sin th1 or cos th1)")
    kmax = float(np.max(design.kappa[:2][used]))
    if design.norm == "h2":
        if dt is None:
            raise ValueError("dt (the sampling interval, TU) is required for an H2 design")
        return design.gamma * kmax * sig * np.sqrt(dt)
    return design.gamma * kmax * sig
