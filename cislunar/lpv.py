r"""Planar CR3BP in affine parameter-varying (LPV) form and optimal sensing-precision LMIs.

Follows E. Nychka, R. Bhattacharya, "Optimal Sensing Precision for Celestial Navigation Systems in Cislunar Space
using LPV Framework" (arXiv 2410.02013, 2024), Sections III-IV, with the method of V. M. Deshpande,
R. Bhattacharya, IEEE Control Systems Letters 5(2), 2021.

Frame, units, state
-------------------
Barycentric rotating (synodic) frame of :mod:`cislunar.dynamics`, non-dimensional units (LU, TU).  The planar
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
from dataclasses import dataclass, field
from itertools import product

import numpy as np

from . import _checks
from .dynamics import CR3BP, EARTH_MOON

__all__ = [
    "RHO_NAMES",
    "SENSOR_NAMES",
    "CR3BPLPV",
    "ParameterBox",
    "resonant_orbit",
    "PrecisionLMI",
    "ObserverDesign",
    "InfeasibleLMIError",
    "design_observer",
    "precision_to_noise_deg",
    "noise_deg_to_precision",
    "h2_norm",
    "hinf_norm",
    "Verification",
    "verify_observer",
    "gamma_sweep",
    "default_disturbance",
]

#: Names of the scheduling parameters rho_1..rho_6.
RHO_NAMES = ("1/r13^3", "1/r23^3", "1/r13", "1/r23", "x", "y")
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
            raise ValueError(f"system must be a cislunar.dynamics.CR3BP; got {type(self.system).__name__}")

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
        s = _checks.as_array(state6, "state6", last=6)
        if np.any(np.abs(s[..., [2, 5]]) > 1e-12):
            raise ValueError("state6 must be planar (z = vz = 0)")
        return s[..., [0, 1, 3, 4]]

    @staticmethod
    def spatial(state4) -> np.ndarray:
        """Planar ``[x, y, vx, vy]`` (..., 4) -> ``[x, y, 0, vx, vy, 0]`` (..., 6)."""
        s = _checks.as_array(state4, "state4", last=4)
        out = np.zeros(s.shape[:-1] + (6,))
        out[..., [0, 1, 3, 4]] = s
        return out

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
        s = _checks.as_array(state, "state", ndim=(1, 2, 3))
        if s.shape[-1] not in (2, 4):
            raise ValueError(f"state must have last axis 2 (position) or 4 (planar state); got shape {s.shape}")
        r13, r23 = self._distances(s)
        if np.any(r13 == 0) or np.any(r23 == 0):
            raise ValueError("state coincides with a primary (r13 or r23 is zero)")
        return np.stack([r13**-3, r23**-3, 1.0 / r13, 1.0 / r23, s[..., 0], s[..., 1]], axis=-1)

    def angles(self, state):
        r"""Angles :math:`\theta_1` (at the Earth) and :math:`\theta_2` (at the Moon), rad, signed like ``y``.

        :math:`\theta_1 = \operatorname{atan2}(y, x+\mu)`, :math:`\theta_2 = \operatorname{atan2}(y, 1-\mu-x)`.
        """
        s = _checks.as_array(state, "state", ndim=(1, 2, 3))
        mu = self.mu
        return np.arctan2(s[..., 1], s[..., 0] + mu), np.arctan2(s[..., 1], 1.0 - mu - s[..., 0])

    def rho_from_angles(self, theta1, theta2) -> np.ndarray:
        r"""Scheduling parameters from the two angles by triangulation on the Earth-Moon baseline (1 LU).

        Law of sines with :math:`\theta_3 = \pi - \theta_1 - \theta_2`:
        :math:`r_{13} = \sin\theta_2/\sin\theta_3`, :math:`r_{23} = \sin\theta_1/\sin\theta_3`,
        :math:`x = -\mu + r_{13}\cos\theta_1`, :math:`y = r_{13}\sin\theta_1`.  Singular where
        :math:`\sin\theta_3 \to 0` (spacecraft on the Earth-Moon line).
        """
        t1 = _checks.as_array(theta1, "theta1")
        t2 = _checks.as_array(theta2, "theta2")
        s3 = np.sin(t1 + t2)  # sin(pi - t1 - t2)
        if np.any(s3 == 0):
            raise ValueError("theta1 + theta2 is a multiple of pi: triangulation is singular")
        r13 = np.sin(t2) / s3
        r23 = np.sin(t1) / s3
        x = -self.mu + r13 * np.cos(t1)
        y = r13 * np.sin(t1)
        return np.stack([np.abs(r13) ** -3, np.abs(r23) ** -3, 1.0 / np.abs(r13), 1.0 / np.abs(r23), x, y],
                        axis=-1)

    # ------------------------------------------------------- vector fields
    def f(self, state) -> np.ndarray:
        """Nonlinear planar CR3BP vector field (..., 4), from :meth:`CR3BP.eom` (LU/TU, LU/TU^2)."""
        s = _checks.as_array(state, "state", last=4)
        d = self.system.eom(self.spatial(s))
        return d[..., [0, 1, 3, 4]]

    def measure(self, state) -> np.ndarray:
        """Nonlinear sensor model (..., 6): ``[sin th1, cos th1, sin th2, cos th2, r13^2, r23^2]`` from geometry."""
        s = _checks.as_array(state, "state", ndim=(1, 2, 3))
        t1, t2 = self.angles(s)
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
        r = _checks.as_array(rho, "rho", last=6)
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
        r = _checks.as_array(rho, "rho", last=6)
        mu = self.mu
        z = np.zeros(r.shape[:-1])
        return np.stack([z, r[..., 2], z, -r[..., 3], r[..., 4] + 2 * mu, r[..., 4] + 2 * mu - 2], axis=-1)

    def lpv_rhs(self, state, rho=None) -> np.ndarray:
        """:math:`A(\\rho)x + b(\\rho)` (..., 4) with :math:`\\rho` from ``state`` unless given."""
        s = _checks.as_array(state, "state", last=4)
        r = self.rho(s) if rho is None else rho
        return np.einsum("...ij,...j->...i", self.A(r), s) + self.b(r)

    def lpv_measure(self, state, rho=None) -> np.ndarray:
        """:math:`C(\\rho)x + d(\\rho)` (..., 6) with :math:`\\rho` from ``state`` unless given."""
        s = _checks.as_array(state, "state", last=4)
        r = self.rho(s) if rho is None else rho
        return np.einsum("...ij,...j->...i", self.C(r), s) + self.d(r)
