r"""Spacecraft-to-spacecraft measurement models with analytic Jacobians and noise models.

Every model is a function of the *relative state* of a target with respect to an observer,

.. math:: \boldsymbol\delta = \mathbf x_{\mathcal T} - \mathbf x_{\mathcal S}
          = [\boldsymbol\rho;\ \dot{\boldsymbol\rho}],

(Wolf & Jones test case 2: :math:`\Delta x = x_{\mathcal T} - x_{\mathcal S}`; Greaves & Scheeres 2021 Eqs. 6 and 9:
:math:`\boldsymbol\rho = \mathbf r - \mathbf r_{obs}`), so the Jacobians with respect to the two 6-dimensional
CR3BP states are :math:`H_{\mathcal T} = \partial h/\partial\boldsymbol\delta` and
:math:`H_{\mathcal S} = -\partial h/\partial\boldsymbol\delta`.

Frames and units
----------------
States are in the rotating (synodic) frame of :mod:`cislunar.cr3bp.dynamics`; any consistent units work (the models do
not scale), normally LU and LU/TU, in which case ranges are in LU, range rates in LU/TU, angles in rad and
angle rates in rad/TU.  Angles are measured in the rotating frame axes, as assumed by Greaves & Scheeres (the
image processing delivers angles "in the CR3BP frame").  The noise helpers take physical values (km, km/s, rad,
s) and a :class:`~cislunar.cr3bp.dynamics.CR3BP` to return covariances in non-dimensional units.

Models
------
``relative_position``
    :math:`h = \boldsymbol\rho` (Wolf & Jones test case 1), 3 components.
``range_range_rate``
    :math:`[\rho,\ \dot\rho] = [\|\boldsymbol\rho\|,\ \boldsymbol\rho\cdot\dot{\boldsymbol\rho}/\rho]`
    (Wolf & Jones test case 2).
``azimuth_elevation``
    :math:`[\theta, \psi] = [\operatorname{atan2}(\rho_y, \rho_x),\ \arcsin(\rho_z/\rho)]`
    (Greaves & Scheeres 2021 Eqs. 7-8; AMOS 2023 Eqs. 15-17; Jacobian AMOS Eq. 18).
``angle_rates``
    :math:`[\dot\theta, \dot\psi]` of Greaves & Scheeres 2021 Eqs. 10-11.
``angles_and_rates``
    the four of them stacked, as filtered by Greaves & Scheeres 2021.

Degenerate geometry (documented behaviour, tested)
--------------------------------------------------
* **Zero range.**  When observer and target positions coincide (range below ``MIN_RANGE`` = 1e-12 in the state's
  length unit) the range rate, the angles, their rates and every Jacobian except that of ``relative_position`` are
  undefined: a ``ValueError`` is raised (also by :func:`range_range_rate`, whose range rate has no direction
  to project on).  ``relative_position`` stays defined.
* **Elevation at +-90 deg.**  When the line of sight is along the +-z axis (horizontal component
  :math:`\sqrt{\rho_x^2+\rho_y^2} \le 10^{-12}\rho`) the azimuth, its rate and the elevation Jacobian are undefined
  (AMOS Eq. 18 divides by :math:`\sqrt{\rho_x^2+\rho_y^2}`): a ``ValueError`` is raised.  The elevation value is
  computed as :math:`\operatorname{atan2}(\rho_z, \sqrt{\rho_x^2+\rho_y^2})`, equal to Eq. 8 but well conditioned
  near the poles.
* **Azimuth wrap.**  Azimuths are returned in :math:`(-\pi, \pi]` (``numpy.arctan2``).  The Jacobian is smooth
  across the branch cut at :math:`\pm\pi`; residuals must be wrapped, which :meth:`MeasurementModel.residual` and
  :func:`wrap_angle` do (result in :math:`[-\pi, \pi)`).

Second derivatives
------------------
The gradient of the mutual information (Wolf & Jones Eq. 50) needs :math:`\partial H/\partial\mathbf x`, i.e. the
Hessian of each measurement component with respect to the relative state.  :meth:`MeasurementModel.hessian`
evaluates it exactly by second-order forward-mode differentiation (value, gradient and Hessian carried through
every arithmetic operation of the same formulas, :class:`_Jet`), so no hand-derived second-derivative tensors
are needed; the closed-form first derivatives are cross-checked against it and against finite differences in
``tests/sensing/test_measurements.py``.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Callable

import numpy as np

from cislunar.cr3bp.dynamics import CR3BP, check_system
from cislunar.utils import validation

__all__ = [
    "MIN_RANGE",
    "MeasurementModel",
    "RELATIVE_POSITION",
    "RANGE_RANGE_RATE",
    "AZIMUTH_ELEVATION",
    "ANGLE_RATES",
    "ANGLES_AND_RATES",
    "MODELS",
    "relative_state",
    "relative_position",
    "range_range_rate",
    "azimuth_elevation",
    "angle_rates",
    "angles_and_rates",
    "wrap_angle",
    "diagonal_covariance",
    "relative_position_noise",
    "range_range_rate_noise",
    "angular_sigma",
    "angle_rate_sigma",
    "angles_noise",
    "WOLF_JONES_RELPOS_SIGMA_KM",
    "WOLF_JONES_RANGE_SIGMA_KM",
    "WOLF_JONES_RANGE_RATE_SIGMA_KM_S",
    "AMOS_SIGMA_MIN_RAD",
    "AMOS_RESOLUTION_KM",
]

#: Smallest range (state length unit) for which range rate, angles and Jacobians are defined.
MIN_RANGE = 1e-12
#: Relative size of the horizontal line-of-sight component below which azimuth is undefined.
_MIN_HORIZONTAL = 1e-12
#: Below this horizontal/range ratio the azimuth Jacobians (1/ratio) are ill conditioned: a RuntimeWarning is issued.
ILL_CONDITIONED_HORIZONTAL = 1e-6

#: Wolf & Jones test case 1: relative position noise, 100 m per axis (Table 3).
WOLF_JONES_RELPOS_SIGMA_KM = 0.1
#: Wolf & Jones test case 2: range noise 100 m (Table 5).
WOLF_JONES_RANGE_SIGMA_KM = 0.1
#: Wolf & Jones test case 2: range-rate noise 10 m/s as printed (Table 5).
WOLF_JONES_RANGE_RATE_SIGMA_KM_S = 0.01
#: Greaves & Scheeres AMOS 2023: minimum angular uncertainty 10 micro-rad (Sec. 3.3).
AMOS_SIGMA_MIN_RAD = 10e-6
#: Greaves & Scheeres AMOS 2023: resolution uncertainty D = 4 m (Sec. 3.3).
AMOS_RESOLUTION_KM = 4e-3


# --------------------------------------------------------------------------------------------------------------
# second-order forward-mode differentiation ("jets") used for exact measurement Hessians
# --------------------------------------------------------------------------------------------------------------
class _Jet:
    """A scalar field carrying value ``v`` (...), gradient ``g`` (..., n) and Hessian ``h`` (..., n, n)."""

    __slots__ = ("v", "g", "h")

    def __init__(self, v, g, h):
        self.v, self.g, self.h = v, g, h

    @staticmethod
    def variables(values):
        """Independent variables from an array ``(..., n)``."""
        n = values.shape[-1]
        eye = np.broadcast_to(np.eye(n), values.shape + (n,))
        zero = np.zeros(values.shape[:-1] + (n, n))
        return [_Jet(values[..., i], eye[..., i, :], zero) for i in range(n)]

    def _unary(self, f, d1, d2):
        g = d1[..., None] * self.g
        h = d1[..., None, None] * self.h + d2[..., None, None] * self.g[..., :, None] * self.g[..., None, :]
        return _Jet(f, g, h)

    def __add__(self, other):
        if isinstance(other, _Jet):
            return _Jet(self.v + other.v, self.g + other.g, self.h + other.h)
        return _Jet(self.v + other, self.g, self.h)

    __radd__ = __add__

    def __neg__(self):
        return _Jet(-self.v, -self.g, -self.h)

    def __sub__(self, other):
        return self + (-other)

    def __rsub__(self, other):
        return (-self) + other

    def __mul__(self, other):
        if isinstance(other, _Jet):
            a, b = self, other
            outer = a.g[..., :, None] * b.g[..., None, :]
            return _Jet(a.v * b.v, a.v[..., None] * b.g + b.v[..., None] * a.g,
                        a.v[..., None, None] * b.h + b.v[..., None, None] * a.h + outer + np.swapaxes(outer, -1, -2))
        c = np.asarray(other, dtype=float)
        return _Jet(self.v * c, self.g * c[..., None], self.h * c[..., None, None])

    __rmul__ = __mul__

    def reciprocal(self):
        return self._unary(1.0 / self.v, -1.0 / self.v**2, 2.0 / self.v**3)

    def __truediv__(self, other):
        if isinstance(other, _Jet):
            return self * other.reciprocal()
        return self * (1.0 / np.asarray(other, dtype=float))

    def __rtruediv__(self, other):
        return self.reciprocal() * other


def _sqrt(u):
    if isinstance(u, _Jet):
        s = np.sqrt(u.v)
        return u._unary(s, 0.5 / s, -0.25 / s**3)
    return np.sqrt(u)


def _atan2(y, x):
    if not isinstance(y, _Jet) and not isinstance(x, _Jet):
        return np.arctan2(y, x)
    r2 = x.v**2 + y.v**2
    tx, ty = -y.v / r2, x.v / r2
    txx, tyy, txy = 2 * x.v * y.v / r2**2, -2 * x.v * y.v / r2**2, (y.v**2 - x.v**2) / r2**2
    gx, gy = x.g, y.g
    oxy = gx[..., :, None] * gy[..., None, :]
    h = (tx[..., None, None] * x.h + ty[..., None, None] * y.h
         + txx[..., None, None] * gx[..., :, None] * gx[..., None, :]
         + tyy[..., None, None] * gy[..., :, None] * gy[..., None, :]
         + txy[..., None, None] * (oxy + np.swapaxes(oxy, -1, -2)))
    return _Jet(np.arctan2(y.v, x.v), tx[..., None] * gx + ty[..., None] * gy, h)


# --------------------------------------------------------------------------------------------------------------
# generic formulas (work on arrays and on jets); d = [rx, ry, rz, vx, vy, vz] of the relative state
# --------------------------------------------------------------------------------------------------------------
def _f_relpos(d):
    return [d[0], d[1], d[2]]


def _f_range_rr(d):
    rho = _sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
    return [rho, (d[0] * d[3] + d[1] * d[4] + d[2] * d[5]) / rho]


def _f_azel(d):
    horiz = _sqrt(d[0] * d[0] + d[1] * d[1])
    return [_atan2(d[1], d[0]), _atan2(d[2], horiz)]


def _f_rates(d):
    s = d[0] * d[0] + d[1] * d[1]
    q = d[0] * d[3] + d[1] * d[4]
    rho2 = s + d[2] * d[2]
    az_rate = (d[0] * d[4] - d[1] * d[3]) / s  # Greaves & Scheeres 2021 Eq. 10 (second line)
    el_rate = (d[5] * s - d[2] * q) / (rho2 * _sqrt(s))  # Eq. 11 (third line), rewritten with rho^2 - rho_z^2 = s
    return [az_rate, el_rate]


def _f_angles_rates(d):
    return _f_azel(d) + _f_rates(d)


# --------------------------------------------------------------------------------------------------------------
# closed-form values and Jacobians with respect to the relative state, shape (..., m) and (..., m, 6)
# --------------------------------------------------------------------------------------------------------------
def _check_range(rel, what):
    rho = np.linalg.norm(rel[..., 0:3], axis=-1)
    if np.any(rho <= MIN_RANGE):
        raise ValueError(f"observer and target positions coincide (range <= {MIN_RANGE:g}): {what} and its "
                         "Jacobian are undefined at zero range")
    return rho


def _check_horizontal(rel, rho, what):
    s = np.sqrt(rel[..., 0] ** 2 + rel[..., 1] ** 2)
    if np.any(s <= _MIN_HORIZONTAL * rho):
        raise ValueError(f"line of sight along the +-z axis (elevation +-90 deg): {what} and its Jacobian are "
                         "undefined there (azimuth has no meaning at the poles)")
    ratio = float(np.min(s / rho)) if np.size(s) else 1.0
    if ratio < ILL_CONDITIONED_HORIZONTAL:
        warnings.warn(f"line of sight within {np.degrees(ratio):.2e} deg of the +-z axis: the {what} Jacobian "
                      f"scales as 1/(horizontal range) and is ill conditioned (horizontal/range = {ratio:.1e})",
                      RuntimeWarning, stacklevel=4)
    return s


def _relpos_rel(rel):
    jac = np.zeros(rel.shape[:-1] + (3, 6))
    jac[..., [0, 1, 2], [0, 1, 2]] = 1.0
    return rel[..., 0:3].copy(), jac


def _range_rr_rel(rel):
    rho = _check_range(rel, "range rate")
    r, v = rel[..., 0:3], rel[..., 3:6]
    u = r / rho[..., None]
    rdot = np.sum(u * v, axis=-1)
    jac = np.zeros(rel.shape[:-1] + (2, 6))
    jac[..., 0, 0:3] = u
    jac[..., 1, 0:3] = (v - rdot[..., None] * u) / rho[..., None]
    jac[..., 1, 3:6] = u
    return np.stack([rho, rdot], axis=-1), jac


def _azel_rel(rel):
    rho = _check_range(rel, "azimuth/elevation")
    sq = _check_horizontal(rel, rho, "azimuth")
    x, y, z = rel[..., 0], rel[..., 1], rel[..., 2]
    s = sq**2
    rho2 = rho**2
    jac = np.zeros(rel.shape[:-1] + (2, 6))
    # AMOS 2023 Eq. 18
    jac[..., 0, 0] = -y / s
    jac[..., 0, 1] = x / s
    jac[..., 1, 0] = -x * z / (rho2 * sq)
    jac[..., 1, 1] = -y * z / (rho2 * sq)
    jac[..., 1, 2] = sq / rho2
    return np.stack([np.arctan2(y, x), np.arctan2(z, sq)], axis=-1), jac


def _rates_rel(rel):
    rho = _check_range(rel, "angle rates")
    sq = _check_horizontal(rel, rho, "azimuth rate")
    x, y, z, vx, vy, vz = np.moveaxis(rel, -1, 0)
    s = sq**2
    rho2 = rho**2
    n_az = x * vy - y * vx
    az_rate = n_az / s
    q = x * vx + y * vy
    num = vz * s - z * q
    den = rho2 * sq
    el_rate = num / den
    jac = np.zeros(rel.shape[:-1] + (2, 6))
    jac[..., 0, 0] = vy / s - 2 * x * n_az / s**2
    jac[..., 0, 1] = -vx / s - 2 * y * n_az / s**2
    jac[..., 0, 3] = -y / s
    jac[..., 0, 4] = x / s
    dnum = np.stack([2 * x * vz - z * vx, 2 * y * vz - z * vy, -q, -z * x, -z * y, s], axis=-1)
    dden = np.zeros(rel.shape)
    dden[..., 0] = 2 * x * sq + rho2 * x / sq
    dden[..., 1] = 2 * y * sq + rho2 * y / sq
    dden[..., 2] = 2 * z * sq
    jac[..., 1, :] = (dnum * den[..., None] - num[..., None] * dden) / den[..., None] ** 2
    return np.stack([az_rate, el_rate], axis=-1), jac


def _angles_rates_rel(rel):
    v1, j1 = _azel_rel(rel)
    v2, j2 = _rates_rel(rel)
    return np.concatenate([v1, v2], axis=-1), np.concatenate([j1, j2], axis=-2)


# --------------------------------------------------------------------------------------------------------------
# public API
# --------------------------------------------------------------------------------------------------------------
def relative_state(observer, target) -> np.ndarray:
    """Relative state :math:`\\boldsymbol\\delta = \\mathbf x_{\\mathcal T} - \\mathbf x_{\\mathcal S}`, shape ``(..., 6)``.

    Parameters
    ----------
    observer, target : array_like, shape (..., 6)
        Observer and target states (rotating frame; LU, LU/TU or any consistent units); leading axes broadcast.

    Raises
    ------
    ValueError
        Wrong last axis, NaN, or leading axes that do not broadcast.
    """
    xs, xt = _checked_pair(observer, target)
    return xt - xs


def _checked_pair(observer, target):
    """The checks of :func:`relative_state`: both states as float arrays ``(..., 6)`` with broadcasting leading axes."""
    xs = validation.as_array(observer, "observer", last=6)
    xt = validation.as_array(target, "target", last=6)
    try:
        np.broadcast_shapes(xs.shape, xt.shape)
    except ValueError as exc:
        raise ValueError(f"observer and target leading axes do not broadcast: {xs.shape} vs {xt.shape}") from exc
    return xs, xt


@dataclass(frozen=True)
class MeasurementModel:
    """A measurement :math:`\\mathbf y = h(\\mathbf x_{\\mathcal T} - \\mathbf x_{\\mathcal S})` with derivatives.

    Attributes
    ----------
    name : str
        Short identifier.
    labels : tuple of str
        Component names with units in parentheses.
    angles : tuple of bool
        Which components are angles (wrapped to :math:`[-\\pi, \\pi)` in residuals).
    """

    name: str
    labels: tuple
    angles: tuple
    _closed_form: Callable
    _generic: Callable

    @property
    def dim(self) -> int:
        """Number of measurement components per observer/target pair."""
        return len(self.labels)

    def __call__(self, observer, target) -> np.ndarray:
        """Measurement value, shape ``(..., dim)``."""
        return self._closed_form(relative_state(observer, target))[0]

    def evaluate(self, observer, target):
        """Value and Jacobians with respect to observer and target states.

        Returns
        -------
        value : ndarray, shape (..., dim)
        H_observer : ndarray, shape (..., dim, 6)
            :math:`\\partial h/\\partial \\mathbf x_{\\mathcal S} = -\\partial h/\\partial\\boldsymbol\\delta`.
        H_target : ndarray, shape (..., dim, 6)
            :math:`\\partial h/\\partial \\mathbf x_{\\mathcal T} = \\partial h/\\partial\\boldsymbol\\delta`.
        """
        return self._evaluate(*_checked_pair(observer, target))

    def _evaluate(self, observer, target):
        """:meth:`evaluate` on checked float arrays (no argument checks: the inner loops of the filters and of the
        linearisations, whose public entry points checked the states once)."""
        val, jac = self._closed_form(target - observer)
        return val, -jac, jac

    def jacobians(self, observer, target):
        """``(H_observer, H_target)``, each ``(..., dim, 6)``; see :meth:`evaluate`."""
        return self.evaluate(observer, target)[1:]

    def hessian(self, observer, target) -> np.ndarray:
        """Second derivatives :math:`\\partial^2 h_i/\\partial\\boldsymbol\\delta\\partial\\boldsymbol\\delta`, ``(..., dim, 6, 6)``.

        With respect to the absolute states: :math:`\\partial^2 h/\\partial\\mathbf x_{\\mathcal S}^2 =
        \\partial^2 h/\\partial\\mathbf x_{\\mathcal T}^2 = -\\partial^2 h/\\partial\\mathbf x_{\\mathcal S}
        \\partial\\mathbf x_{\\mathcal T}` equal this tensor.  Exact (forward-mode second-order differentiation of
        the same formulas); degenerate geometry raises as in :meth:`evaluate`.
        """
        return self._hessian(*_checked_pair(observer, target))

    def _hessian(self, observer, target) -> np.ndarray:
        """:meth:`hessian` on checked float arrays (no argument checks)."""
        rel = target - observer
        self._closed_form(rel)  # geometry checks
        comps = self._generic(_Jet.variables(rel))
        out = np.zeros(rel.shape[:-1] + (self.dim, 6, 6))
        for i, c in enumerate(comps):
            if isinstance(c, _Jet):
                out[..., i, :, :] = c.h
        return out

    def residual(self, y, y_predicted) -> np.ndarray:
        """``y - y_predicted`` with angle components wrapped to :math:`[-\\pi, \\pi)`."""
        return self._residual(validation.as_array(y, "y", last=self.dim),
                              validation.as_array(y_predicted, "y_predicted", last=self.dim))

    def _residual(self, y, y_predicted) -> np.ndarray:
        """:meth:`residual` on checked float arrays (no argument checks)."""
        r = y - y_predicted
        mask = np.asarray(self.angles, dtype=bool)
        r[..., mask] = wrap_angle(r[..., mask])
        return r


RELATIVE_POSITION = MeasurementModel("relative_position", ("rho_x (LU)", "rho_y (LU)", "rho_z (LU)"),
                                     (False, False, False), _relpos_rel, _f_relpos)
RANGE_RANGE_RATE = MeasurementModel("range_range_rate", ("range (LU)", "range rate (LU/TU)"), (False, False),
                                    _range_rr_rel, _f_range_rr)
AZIMUTH_ELEVATION = MeasurementModel("azimuth_elevation", ("azimuth (rad)", "elevation (rad)"), (True, False),
                                     _azel_rel, _f_azel)
ANGLE_RATES = MeasurementModel("angle_rates", ("azimuth rate (rad/TU)", "elevation rate (rad/TU)"),
                               (False, False), _rates_rel, _f_rates)
ANGLES_AND_RATES = MeasurementModel(
    "angles_and_rates", ("azimuth (rad)", "elevation (rad)", "azimuth rate (rad/TU)", "elevation rate (rad/TU)"),
    (True, False, False, False), _angles_rates_rel, _f_angles_rates)
#: All models by name.
MODELS = {m.name: m for m in (RELATIVE_POSITION, RANGE_RANGE_RATE, AZIMUTH_ELEVATION, ANGLE_RATES, ANGLES_AND_RATES)}


def _apply(model: MeasurementModel, observer, target, jacobian: bool):
    if not isinstance(jacobian, (bool, np.bool_)):
        raise validation.ArgumentTypeError(f"jacobian must be True or False; got {type(jacobian).__name__}")
    if jacobian:
        return model.evaluate(observer, target)
    return model(observer, target)


def relative_position(observer, target, *, jacobian: bool = False):
    """Relative position :math:`\\boldsymbol\\rho = \\mathbf r_{\\mathcal T} - \\mathbf r_{\\mathcal S}` (Wolf & Jones test case 1).

    Parameters
    ----------
    observer, target : array_like, shape (..., 6)
        States in the rotating frame (LU, LU/TU).
    jacobian : bool
        Also return ``(H_observer, H_target)``, each ``(..., 3, 6)``: :math:`\\mp[I_3\\ 0]`.

    Returns
    -------
    ndarray (..., 3) in LU, or the tuple ``(value, H_observer, H_target)``.
    """
    return _apply(RELATIVE_POSITION, observer, target, jacobian)


def range_range_rate(observer, target, *, jacobian: bool = False):
    """Range and range rate (Wolf & Jones test case 2).

    .. math:: \\rho = \\|\\boldsymbol\\rho\\|,\\qquad \\dot\\rho = \\boldsymbol\\rho\\cdot\\dot{\\boldsymbol\\rho}/\\rho,
    .. math:: \\frac{\\partial\\rho}{\\partial\\boldsymbol\\delta} = [\\hat{\\boldsymbol\\rho}^T\\ 0],\\qquad
              \\frac{\\partial\\dot\\rho}{\\partial\\boldsymbol\\delta} =
              [(\\dot{\\boldsymbol\\rho} - \\dot\\rho\\hat{\\boldsymbol\\rho})^T/\\rho\\ \\ \\hat{\\boldsymbol\\rho}^T].

    Parameters
    ----------
    observer, target : array_like, shape (..., 6)
    jacobian : bool
        Also return ``(H_observer, H_target)``, each ``(..., 2, 6)``.

    Returns
    -------
    ndarray (..., 2): range (LU) and range rate (LU/TU), or ``(value, H_observer, H_target)``.

    Raises
    ------
    ValueError
        Zero range (range rate undefined).
    """
    return _apply(RANGE_RANGE_RATE, observer, target, jacobian)


def azimuth_elevation(observer, target, *, jacobian: bool = False):
    """Azimuth and elevation of the line of sight in the rotating frame (G&S 2021 Eqs. 7-8, AMOS Eqs. 15-18).

    Azimuth :math:`\\theta = \\operatorname{atan2}(\\rho_y, \\rho_x) \\in (-\\pi, \\pi]`, elevation
    :math:`\\psi = \\arcsin(\\rho_z/\\rho) \\in [-\\pi/2, \\pi/2]`, both rad.

    Raises
    ------
    ValueError
        Zero range, or line of sight along +-z (azimuth undefined); see the module notes.
    """
    return _apply(AZIMUTH_ELEVATION, observer, target, jacobian)


def angle_rates(observer, target, *, jacobian: bool = False):
    """Azimuth and elevation rates (Greaves & Scheeres 2021 Eqs. 10-11), rad per time unit of the states.

    .. math:: \\dot\\theta = \\frac{\\rho_x\\dot\\rho_y - \\rho_y\\dot\\rho_x}{\\rho_x^2+\\rho_y^2},\\qquad
              \\dot\\psi = \\frac{\\dot\\rho_z\\rho^2 - \\rho_z(\\boldsymbol\\rho\\cdot\\dot{\\boldsymbol\\rho})}
              {\\rho^2\\sqrt{\\rho^2-\\rho_z^2}}.

    Raises
    ------
    ValueError
        Zero range, or line of sight along +-z.
    """
    return _apply(ANGLE_RATES, observer, target, jacobian)


def angles_and_rates(observer, target, *, jacobian: bool = False):
    """``[azimuth, elevation, azimuth rate, elevation rate]`` (Greaves & Scheeres 2021 measurement set)."""
    return _apply(ANGLES_AND_RATES, observer, target, jacobian)


def wrap_angle(angle) -> np.ndarray:
    """Wrap angles (rad) to :math:`[-\\pi, \\pi)`."""
    a = validation.as_array(angle, "angle")
    return (a + np.pi) % (2.0 * np.pi) - np.pi


# --------------------------------------------------------------------------------------------------------------
# noise models
# --------------------------------------------------------------------------------------------------------------
def _check_system(system):
    return check_system(system)


def diagonal_covariance(sigmas) -> np.ndarray:
    """Diagonal covariance ``diag(sigmas**2)``; ``sigmas`` (..., m) must be non-negative (else ``ValueError``)."""
    s = validation.as_array(sigmas, "sigmas", ndim=None)
    s = np.atleast_1d(s)
    if s.shape[-1] == 0:
        raise ValueError("sigmas must hold at least one standard deviation")
    if np.any(s < 0):
        raise ValueError(f"sigmas must be non-negative; got {s}")
    out = np.zeros(s.shape + (s.shape[-1],))
    idx = np.arange(s.shape[-1])
    out[..., idx, idx] = s**2
    return out


def relative_position_noise(sigma_km: float, system: CR3BP) -> np.ndarray:
    """Relative-position noise covariance (3, 3) in LU^2 for a 1-sigma ``sigma_km`` per axis (km).

    Wolf & Jones test case 1 uses 100 m (:data:`WOLF_JONES_RELPOS_SIGMA_KM`).
    """
    sigma = validation.positive(sigma_km, "sigma_km")
    _check_system(system)
    return diagonal_covariance(np.full(3, sigma / system.length_unit_km))


def range_range_rate_noise(sigma_range_km: float, sigma_range_rate_km_s: float, system: CR3BP) -> np.ndarray:
    """Range / range-rate noise covariance (2, 2) in LU^2 and (LU/TU)^2.

    Parameters
    ----------
    sigma_range_km : float
        1-sigma range noise, km (Wolf & Jones: 0.1 km).
    sigma_range_rate_km_s : float
        1-sigma range-rate noise, km/s (Wolf & Jones Table 5 prints 10 m/s = 0.01 km/s).
    system : CR3BP
        Provides the length and velocity units.
    """
    sr = validation.positive(sigma_range_km, "sigma_range_km")
    srr = validation.positive(sigma_range_rate_km_s, "sigma_range_rate_km_s")
    _check_system(system)
    return diagonal_covariance([sr / system.length_unit_km, srr / system.velocity_unit_km_s])


def angular_sigma(range_, sigma_min: float, resolution: float) -> np.ndarray:
    """RMS angular noise model of Greaves & Scheeres, AMOS 2023 Eqs. 19-20.

    .. math:: \\sigma_\\theta = \\sqrt{\\sigma_{\\theta,min}^2 + D^2/\\rho^2}

    Parameters
    ----------
    range_ : array_like, shape (...)
        Observer-target range :math:`\\rho`, in the same length unit as ``resolution``; must be positive.
    sigma_min : float
        Minimum angular uncertainty, rad (AMOS: 10 micro-rad, :data:`AMOS_SIGMA_MIN_RAD`); non-negative.
    resolution : float
        Resolution uncertainty :math:`D` (AMOS: 4 m, :data:`AMOS_RESOLUTION_KM`); non-negative.

    Returns
    -------
    ndarray, shape (...)
        1-sigma angle noise, rad.
    """
    rho = validation.as_array(range_, "range_")
    if np.any(rho <= 0):
        raise ValueError("range_ must be positive (the resolution term D/rho diverges at zero range)")
    smin = validation.positive(sigma_min, "sigma_min", allow_zero=True)
    d = validation.positive(resolution, "resolution", allow_zero=True)
    if smin == 0 and d == 0:
        raise ValueError("sigma_min and resolution cannot both be zero (noise-free angles)")
    return np.sqrt(smin**2 + (d / rho) ** 2)


def angle_rate_sigma(sigma_angle, dt: float) -> np.ndarray:
    """Noise of an angle rate formed by differencing two angles ``dt`` apart (Greaves & Scheeres 2021 Eqs. 12-13).

    .. math:: \\sigma_{\\dot\\theta} = \\sqrt{2}\\,\\sigma_\\theta/\\Delta t

    Units: ``sigma_angle`` in rad, ``dt`` in the time unit wanted for the rate (e.g. TU gives rad/TU).
    """
    s = validation.as_array(sigma_angle, "sigma_angle")
    if np.any(s < 0):
        raise ValueError("sigma_angle must be non-negative")
    dt = validation.positive(dt, "dt")
    return np.sqrt(2.0) * s / dt


def angles_noise(observer, target, system: CR3BP, *, sigma_min_rad: float = AMOS_SIGMA_MIN_RAD,
                 resolution_km: float = AMOS_RESOLUTION_KM, rate_dt_s: float | None = None) -> np.ndarray:
    """Range-dependent covariance of azimuth/elevation (and optionally their rates), non-dimensional units.

    Both angles get :math:`\\sigma_\\theta` of :func:`angular_sigma` (the papers use one angular sigma for the pair;
    no :math:`1/\\cos\\psi` inflation of the azimuth).  With ``rate_dt_s`` the rates get
    :math:`\\sqrt2\\sigma_\\theta/\\Delta t` (G&S 2021 Eq. 13; they use 1 s) converted to rad/TU, uncorrelated with
    the angles as assumed there.

    Parameters
    ----------
    observer, target : array_like, shape (..., 6)
        States in LU, LU/TU.
    system : CR3BP
    sigma_min_rad, resolution_km : float
        AMOS Eq. 20 parameters (defaults: AMOS 2023 values).
    rate_dt_s : float, optional
        Differencing interval of the rates, s.

    Returns
    -------
    ndarray, shape (..., 2, 2) or (..., 4, 4)
        Covariance in rad^2 (and (rad/TU)^2).
    """
    _check_system(system)
    validation.positive(sigma_min_rad, "sigma_min_rad", allow_zero=True)
    validation.positive(resolution_km, "resolution_km", allow_zero=True)
    if rate_dt_s is not None:
        validation.positive(rate_dt_s, "rate_dt_s")
    rel = relative_state(observer, target)
    rho_km = np.linalg.norm(rel[..., 0:3], axis=-1) * system.length_unit_km
    sig = angular_sigma(rho_km, sigma_min_rad, resolution_km)
    if rate_dt_s is None:
        return diagonal_covariance(np.stack([sig, sig], axis=-1))
    dt_tu = validation.positive(rate_dt_s, "rate_dt_s") / system.time_unit_s
    srate = angle_rate_sigma(sig, dt_tu)
    return diagonal_covariance(np.stack([sig, sig, srate, srate], axis=-1))
