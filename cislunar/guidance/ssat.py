r"""Spacecraft-to-spacecraft absolute tracking (SSAT), range-variance cost and MMD guidance.

Greaves & Scheeres, "Autonomous information gathering guidance for spacecraft-to-spacecraft tracking with optical
sensors" (AMOS 2023), Sections 3-4.  Two vehicles: an *agent* that measures and maneuvers, and a non-cooperative
*target*.  Each has a CR3BP state :math:`\mathbf s = [\mathbf r; \mathbf v]` (LU, LU/TU, rotating frame).

States (Eqs. 1-7)
-----------------
* inertial SSAT state :math:`\mathbf x = [\mathbf s_a; \mathbf s_t]` (Eq. 1; "inertial" is the paper's word for
  the two absolute states side by side, both still in the rotating frame);
* relative SSAT state :math:`\tilde{\mathbf x} = [\mathbf s_\alpha; \mathbf s_\rho] = T\mathbf x` with the mean
  :math:`\mathbf s_\alpha = (\mathbf s_a + \mathbf s_t)/2` and the difference :math:`\mathbf s_\rho = \mathbf s_t -
  \mathbf s_a` (Eqs. 2-6), covariance :math:`\tilde P = TPT^T` (Eq. 7);
* agent-based absolute state :math:`\bar{\mathbf x} = [\mathbf s_a; \mathbf s_\rho] = T_a\mathbf x`,
  :math:`T_a = [[I, 0], [-I, I]]` (the alternative the paper mentions).  Both share the relative partition, so
  the range variance :math:`J_\rho` and every statement about relative information are identical; the
  measurement Jacobian in either coordinate system is :math:`[0\ \ H_\rho]` (angles see only the difference).

Control (Eqs. 13-14): impulses on the agent only, :math:`\mathbf x^+ = \mathbf x^- + B_a\mathbf u`,
:math:`B_a = [0\ I_3\ 0\ 0]^T`.  No execution errors (as in the paper), so an impulse changes the trajectory (and
hence every later STM and Jacobian) but not the covariance directly; the STM across an impulse is the identity.

Covariance analysis (Sections 3.3 and 5)
----------------------------------------
Azimuth/elevation of the target seen from the agent (Eqs. 15-18, :mod:`cislunar.sensing.measurements`) every
``cadence`` along the *true* trajectories, with the root-mean-square angular noise of Eqs. 19-20
(:math:`\sigma_\theta^2 = \sigma_{\theta,min}^2 + D^2/\rho^2`, 10 micro-rad and 4 m), initial 3-sigma
60 km and 60 cm/s per axis for both vehicles, no process noise (the paper mentions none).  Without process noise
the EKF covariance recursion is the batch information filter referred to :math:`t_0`:

.. math:: P(t_k) = \Phi(t_k,t_0)\Big(P_0^{-1} + \sum_{j\le k}\Phi_j^T H_j^T R_j^{-1} H_j\Phi_j\Big)^{-1}
          \Phi(t_k,t_0)^T ,

which :func:`ssat_covariance` evaluates in square-root information form (batched Householder QR over all
trajectories, one measurement epoch at a time), so information is never squared.  The cost (Eqs. 21-22)

.. math:: J_\rho = M_\rho^T\tilde P_f M_\rho,\qquad M_\rho = [\mathbf 0_6^T\ \hat{\boldsymbol\rho}^T\
          \mathbf 0_3^T]^T

is the variance of the range along the final line of sight; :math:`\sqrt{J_\rho}` is the 1-sigma range
uncertainty.  In inertial coordinates :math:`T^TM_\rho = [-\hat{\boldsymbol\rho}; 0; \hat{\boldsymbol\rho}; 0]`.

MMD guidance (Eqs. 23-24)
-------------------------
The maximum-measurement-deviation surrogate maximises :math:`\|H_f\Phi(\tau_f,\tau_0)B_a\mathbf u\|^2` over
:math:`\|\mathbf u\| = \upsilon`: the eigenvector of the largest eigenvalue of
:math:`Q = B_a^T\Phi^TH_f^TH_f\Phi B_a` (3x3, rank at most 2), sign chosen by a quick covariance analysis of
both candidates.  Beyond the paper, :func:`range_sigma_over_directions` evaluates :math:`J_\rho` for arbitrary
burn directions (a dense sphere grid), so MMD can be compared with the true minimiser and with the
"perpendicular to the line of sight" heuristic.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.linalg import _umath_linalg

from cislunar.cr3bp.dynamics import CR3BP, check_system
from cislunar.cr3bp.propagation import propagate_stm
from cislunar.sensing.covariance import covariance_analysis, state_covariance
from cislunar.sensing.measurements import (
    AMOS_RESOLUTION_KM,
    AMOS_SIGMA_MIN_RAD,
    AZIMUTH_ELEVATION,
    angular_sigma,
)
from cislunar.utils import validation

__all__ = [
    "AMOS_SIGMA3_POS_KM",
    "AMOS_SIGMA3_VEL_KM_S",
    "transform_matrix",
    "agent_transform_matrix",
    "to_relative",
    "from_relative",
    "to_agent_based",
    "from_agent_based",
    "relative_covariance",
    "inertial_covariance",
    "agent_based_covariance",
    "control_matrix",
    "apply_impulse",
    "range_projection",
    "range_variance",
    "initial_covariance",
    "ImpulsiveTrajectory",
    "propagate_with_impulses",
    "SSATCovariance",
    "ssat_covariance",
    "ssat_covariance_ekf",
    "mmd_matrix",
    "mmd_direction",
    "mmd_policy",
    "fibonacci_sphere",
    "perpendicular_directions",
    "range_sigma_over_directions",
    "minimize_range_sigma",
    "PolicyComparison",
    "compare_burn_policies",
]

#: AMOS 2023 Sec. 5: initial 3-sigma position uncertainty per axis, both vehicles, km.
AMOS_SIGMA3_POS_KM = 60.0
#: AMOS 2023 Sec. 5: initial 3-sigma velocity uncertainty per axis, both vehicles, km/s (60 cm/s).
AMOS_SIGMA3_VEL_KM_S = 6e-4


# --------------------------------------------------------------------------------------------------------------
# state transformations (Eqs. 1-7)
# --------------------------------------------------------------------------------------------------------------
def transform_matrix(n: int = 6) -> np.ndarray:
    """:math:`T` of Eq. 6, shape (2n, 2n): mean and difference of agent and target states."""
    n = _check_n(n)
    eye = np.eye(n)
    return np.block([[0.5 * eye, 0.5 * eye], [-eye, eye]])


def agent_transform_matrix(n: int = 6) -> np.ndarray:
    """:math:`T_a = [[I, 0], [-I, I]]`, shape (2n, 2n): agent-based absolute state :math:`[\\mathbf s_a; \\mathbf s_\\rho]`."""
    n = _check_n(n)
    eye = np.eye(n)
    return np.block([[eye, np.zeros((n, n))], [-eye, eye]])


def _check_n(n):
    return validation.integer(n, "n (sub-state dimension)", minimum=1)


_COORDINATES = ("inertial", "relative", "agent")


def _noise(sigma_min_rad, resolution_km):
    """Eq. 20 noise parameters, checked by name; both zero would make every measurement exact (infinite weight)."""
    smin = validation.positive(sigma_min_rad, "sigma_min_rad", allow_zero=True)
    dres = validation.positive(resolution_km, "resolution_km", allow_zero=True)
    if smin == 0.0 and dres == 0.0:
        raise ValueError("sigma_min_rad and resolution_km are both zero: the angular noise of Eq. 20 would vanish "
                         "(exact measurements); give at least one a positive value")
    return smin, dres


def _initial_cov(P0, name: str = "P0") -> np.ndarray:
    """A 12x12 SPD covariance of the inertial SSAT state (its symmetric part, as the filters use it)."""
    P = validation.spd(P0, name, n=12)  # one check (it also refuses numerical singularity)
    return 0.5 * (P + P.T)


def _trajectory(value, name: str) -> "ImpulsiveTrajectory":
    return validation.instance(value, name, ImpulsiveTrajectory,
                            "a cislunar.guidance.ssat.ImpulsiveTrajectory (from propagate_with_impulses)")


def _grid_indices(value, name: str) -> np.ndarray:
    """A non-empty 1-D sequence of integer grid indices (integral floats accepted; 2.5 or NaN refused)."""
    a = validation.as_array(value, name, ndim=(1,), min_size=1)
    if not np.all(a == np.round(a)):
        raise ValueError(f"{name} must hold integer grid indices; got {value!r:.80}")
    return a.astype(int)


def _pair(x, name):
    x = validation.as_array(x, name)
    if x.ndim < 1 or x.shape[-1] % 2 or x.shape[-1] == 0:
        raise ValueError(f"{name} must have an even, non-zero last axis (agent then target); got shape {x.shape}")
    return x


def to_relative(x) -> np.ndarray:
    """Relative SSAT state :math:`\\tilde{\\mathbf x} = T\\mathbf x` (Eq. 5) of ``x`` (..., 2n)."""
    x = _pair(x, "x")
    n = x.shape[-1] // 2
    sa, st = x[..., :n], x[..., n:]
    return np.concatenate([0.5 * (sa + st), st - sa], axis=-1)


def from_relative(x_rel) -> np.ndarray:
    """Inertial SSAT state :math:`T^{-1}\\tilde{\\mathbf x}`: :math:`\\mathbf s_a = \\mathbf s_\\alpha - \\mathbf s_\\rho/2`, :math:`\\mathbf s_t = \\mathbf s_\\alpha + \\mathbf s_\\rho/2`."""
    x = _pair(x_rel, "x_rel")
    n = x.shape[-1] // 2
    salpha, srho = x[..., :n], x[..., n:]
    return np.concatenate([salpha - 0.5 * srho, salpha + 0.5 * srho], axis=-1)


def to_agent_based(x) -> np.ndarray:
    """Agent-based SSAT state :math:`[\\mathbf s_a; \\mathbf s_t - \\mathbf s_a]` of ``x`` (..., 2n)."""
    x = _pair(x, "x")
    n = x.shape[-1] // 2
    return np.concatenate([x[..., :n], x[..., n:] - x[..., :n]], axis=-1)


def from_agent_based(x_agent) -> np.ndarray:
    """Inverse of :func:`to_agent_based`: :math:`[\\mathbf s_a; \\mathbf s_a + \\mathbf s_\\rho]`."""
    x = _pair(x_agent, "x_agent")
    n = x.shape[-1] // 2
    return np.concatenate([x[..., :n], x[..., :n] + x[..., n:]], axis=-1)


def _cov(P, name):
    P = validation.as_array(P, name)
    if P.ndim < 2 or P.shape[-1] != P.shape[-2] or P.shape[-1] % 2 or P.shape[-1] == 0:
        raise ValueError(f"{name} must be square with an even size (..., 2n, 2n); got shape {P.shape}")
    return validation.psd(P, name, batch=True)


def relative_covariance(P) -> np.ndarray:
    """:math:`\\tilde P = TPT^T` (Eq. 7) for covariances ``P`` (..., 2n, 2n) of the inertial SSAT state."""
    P = _cov(P, "P")
    T = transform_matrix(P.shape[-1] // 2)
    return T @ P @ T.T


def inertial_covariance(P_rel) -> np.ndarray:
    """:math:`P = T^{-1}\\tilde P T^{-T}`, the inverse map of :func:`relative_covariance`."""
    P = _cov(P_rel, "P_rel")
    Ti = np.linalg.inv(transform_matrix(P.shape[-1] // 2))
    return Ti @ P @ Ti.T


def agent_based_covariance(P) -> np.ndarray:
    """:math:`T_aPT_a^T` for the agent-based state :math:`[\\mathbf s_a; \\mathbf s_\\rho]`."""
    P = _cov(P, "P")
    Ta = agent_transform_matrix(P.shape[-1] // 2)
    return Ta @ P @ Ta.T


def control_matrix(coordinates: str = "inertial") -> np.ndarray:
    """Agent control input matrix (12, 3): :math:`B_a` of Eq. 14, or :math:`TB_a` / :math:`T_aB_a` in the other coordinates.

    Parameters
    ----------
    coordinates : {"inertial", "relative", "agent"}
    """
    validation.choice(coordinates, "coordinates", _COORDINATES)
    B = np.zeros((12, 3))
    B[3:6, :] = np.eye(3)
    if coordinates == "inertial":
        return B
    if coordinates == "relative":
        return transform_matrix(6) @ B
    if coordinates == "agent":
        return agent_transform_matrix(6) @ B
    raise ValueError(f"coordinates must be 'inertial', 'relative' or 'agent'; got {coordinates!r}")


def apply_impulse(x, u) -> np.ndarray:
    """Eq. 13: :math:`\\mathbf x^+ = \\mathbf x^- + B_a\\mathbf u` for SSAT states ``x`` (..., 12) and impulses ``u`` (..., 3) (LU/TU)."""
    x = validation.as_array(x, "x", last=12, min_size=1)
    u = validation.as_array(u, "u", last=3, min_size=1)
    try:
        shape = np.broadcast_shapes(x.shape[:-1], u.shape[:-1])
    except ValueError as exc:
        raise ValueError(f"x and u leading axes do not broadcast: {x.shape} vs {u.shape}") from exc
    out = np.broadcast_to(x, shape + (12,)).copy()
    out[..., 3:6] += u
    return out


def range_projection(x, coordinates: str = "inertial") -> np.ndarray:
    """The vector that projects an SSAT covariance on the range direction (Eq. 22), shape (..., 12).

    ``x`` (..., 12) is the inertial SSAT state at the final time.  ``coordinates="relative"`` gives
    :math:`M_\\rho = [0_6; \\hat{\\boldsymbol\\rho}; 0_3]` (for :math:`\\tilde P`; also valid for the agent-based
    state), ``"inertial"`` gives :math:`T^TM_\\rho = [-\\hat{\\boldsymbol\\rho}; 0_3; \\hat{\\boldsymbol\\rho}; 0_3]`.
    """
    x = validation.as_array(x, "x", last=12, min_size=1)
    validation.choice(coordinates, "coordinates", _COORDINATES)
    rho = x[..., 6:9] - x[..., 0:3]
    norm = np.linalg.norm(rho, axis=-1, keepdims=True)
    if np.any(norm <= 0):
        raise ValueError("x has coincident agent and target positions: the range direction is undefined")
    u = rho / norm
    M = np.zeros(x.shape[:-1] + (12,))
    if coordinates in ("relative", "agent"):
        M[..., 6:9] = u
    elif coordinates == "inertial":
        M[..., 0:3] = -u
        M[..., 6:9] = u
    else:
        raise ValueError(f"coordinates must be 'inertial', 'relative' or 'agent'; got {coordinates!r}")
    return M


def range_variance(P, x, coordinates: str = "inertial") -> np.ndarray:
    """:math:`J_\\rho = M^TPM` (Eq. 21), LU^2, for covariances ``P`` (..., 12, 12) in the given coordinates at state ``x``."""
    P = validation.psd(P, "P", n=12, batch=True)
    M = range_projection(x, coordinates)
    return np.einsum("...i,...ij,...j->...", M, P, M)


def initial_covariance(system: CR3BP, sigma3_pos_km: float = AMOS_SIGMA3_POS_KM,
                       sigma3_vel_km_s: float = AMOS_SIGMA3_VEL_KM_S) -> np.ndarray:
    """Initial SSAT covariance (12, 12), non-dimensional, both vehicles uncorrelated.

    Parameters
    ----------
    system : CR3BP
    sigma3_pos_km, sigma3_vel_km_s : float
        3-sigma per axis (AMOS 2023 Sec. 5: 60 km and 60 cm/s = 6e-4 km/s).
    """
    check_system(system)
    sp = validation.positive(sigma3_pos_km, "sigma3_pos_km") / 3.0
    sv = validation.positive(sigma3_vel_km_s, "sigma3_vel_km_s") / 3.0
    P = state_covariance(sp, sv, system)
    out = np.zeros((12, 12))
    out[:6, :6] = P
    out[6:, 6:] = P
    return out


# --------------------------------------------------------------------------------------------------------------
# trajectories with impulses
# --------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class ImpulsiveTrajectory:
    """States and STMs of a batch of trajectories with impulses.

    Attributes
    ----------
    t : ndarray (N,)
        Output times, TU.
    x : ndarray (n, N, 6)
        States at ``t`` (post-impulse where an impulse falls on a grid time).
    stm : ndarray (n, N, 6, 6)
        :math:`\\Phi(t_k, t_0)` with respect to the (post-impulse) state at ``t[0]``; identity jump across
        impulses (no execution errors).
    """

    t: np.ndarray
    x: np.ndarray
    stm: np.ndarray

    def __post_init__(self):
        t = validation.time_grid(self.t, "t", increasing=True)
        x = validation.as_array(self.x, "x", ndim=(3,), last=6)
        if x.shape[0] < 1 or x.shape[1] != t.size:
            raise ValueError(f"x must have shape (n, N, 6) with n >= 1 and N = t.size = {t.size}; got {x.shape}")
        stm = validation.as_array(self.stm, "stm", ndim=(4,))
        if stm.shape != x.shape[:2] + (6, 6):
            raise ValueError(f"stm must have shape (n, N, 6, 6) = {x.shape[:2] + (6, 6)} to match x; got {stm.shape}")
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "x", x)
        object.__setattr__(self, "stm", stm)


def propagate_with_impulses(system: CR3BP, x0, t, impulses=(), *, threads: int | None = None) -> ImpulsiveTrajectory:
    """Propagate states with impulsive velocity changes, returning states and STMs on a grid (batched).

    Parameters
    ----------
    system : CR3BP
    x0 : array_like (6,) or (n, 6)
        States at ``t[0]`` before any impulse at ``t[0]``.
    t : array_like (N,)
        Strictly increasing output grid, TU.
    impulses : sequence of (time, dv)
        Impulse times (scalars shared by the batch, within ``[t[0], t[-1]]``, TU) and velocity changes
        ``dv`` (3,) or (n, 3), LU/TU.  Times need not be grid points.
    threads : int, optional
        Passed to :func:`cislunar.cr3bp.propagation.propagate_stm`.

    Returns
    -------
    ImpulsiveTrajectory
        With a leading batch axis even for a single ``x0``.

    Raises
    ------
    cislunar.cr3bp.propagation.ImpactError
        A trajectory starts inside or reaches the Earth or the Moon (it is never integrated through a primary).
    ValueError, TypeError
        Bad arguments (named).
    """

    check_system(system)
    x0 = validation.as_state(x0, "x0")
    xs = np.atleast_2d(x0).copy()
    n = xs.shape[0]
    if n == 0:
        raise ValueError("x0 must hold at least one state")
    t = validation.time_grid(t, "t", increasing=True)
    if isinstance(impulses, (str, bytes, dict)):
        raise validation.ArgumentTypeError(f"impulses must be a sequence of (time, dv) pairs; got "
                                        f"{type(impulses).__name__}")
    try:
        items = list(impulses)
    except TypeError:
        raise validation.ArgumentTypeError(f"impulses must be a sequence of (time, dv) pairs; got "
                                        f"{type(impulses).__name__}") from None
    imp = []
    for i, item in enumerate(items):
        if isinstance(item, (str, bytes)):
            raise validation.ArgumentTypeError(f"impulses[{i}] must be a (time, dv) pair; got {type(item).__name__}")
        try:
            tau, dv = item
        except (TypeError, ValueError) as exc:
            raise ValueError(f"impulses[{i}] must be a (time, dv) pair") from exc
        tau = validation.real(tau, f"impulses[{i}] time")
        if not (t[0] <= tau <= t[-1]):
            raise ValueError(f"impulses[{i}] time {tau} must lie within the grid [{t[0]}, {t[-1]}] TU")
        dv = validation.as_array(dv, f"impulses[{i}] dv", last=3)
        if dv.ndim == 1:
            dv = np.broadcast_to(dv, (n, 3))
        if dv.shape != (n, 3):
            raise ValueError(f"impulses[{i}] dv must have shape (3,) or ({n}, 3); got {dv.shape}")
        imp.append((tau, dv))
    imp.sort(key=lambda p: p[0])
    N = t.size
    X = np.empty((n, N, 6))
    S = np.empty((n, N, 6, 6))
    phi = np.broadcast_to(np.eye(6), (n, 6, 6)).copy()
    a = t[0]
    k = 0  # next grid index to fill
    j = 0
    while j < len(imp) and imp[j][0] == a:
        xs[:, 3:6] += imp[j][1]
        j += 1
    bounds = [p[0] for p in imp[j:]] + [t[-1]]
    dvs = [p[1] for p in imp[j:]] + [None]
    for b, dv in zip(bounds, dvs):
        last = dv is None
        inside = t[(t > a) & ((t <= b) if last else (t < b))]
        if b > a:
            grid = np.unique(np.r_[a, inside, b])
            tr = propagate_stm(system, xs, grid, threads=threads)
            xg = tr.x if tr.x.ndim == 3 else tr.x[None]
            sg = tr.stm if tr.stm.ndim == 4 else tr.stm[None]
            # record the segment start if it is a grid time, then the interior (and the final) grid points
            if k < N and t[k] == a:
                X[:, k], S[:, k] = xs, phi
                k += 1
            idx = np.searchsorted(grid, inside)
            X[:, k:k + inside.size] = xg[:, idx]
            S[:, k:k + inside.size] = sg[:, idx] @ phi[:, None]
            k += inside.size
            phi = sg[:, -1] @ phi
            xs = xg[:, -1].copy()
        if not last:
            xs[:, 3:6] += dv
        a = b
    if k == N - 1 and t[-1] == a:  # an impulse exactly at the last grid time: report the post-impulse state
        X[:, k], S[:, k] = xs, phi
        k += 1
    if k != N:  # pragma: no cover - bookkeeping guard
        raise RuntimeError(f"internal error: filled {k} of {N} grid points")
    return ImpulsiveTrajectory(t=t, x=X, stm=S)


# --------------------------------------------------------------------------------------------------------------
# covariance analysis
# --------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class SSATCovariance:
    """Result of :func:`ssat_covariance` for a batch of agent trajectories against one target trajectory.

    Attributes
    ----------
    t : ndarray (N,)
        Measurement times, TU.
    J_rho : ndarray (n, N)
        Range variance :math:`J_\\rho` (LU^2) of the posterior covariance at each measurement time, as if that
        time were the final time :math:`\\tau_f`.
    P_final : ndarray (n, 12, 12)
        Posterior inertial SSAT covariance at ``t[-1]`` (LU, LU/TU).
    range_km : ndarray (n, N)
        True agent-target range, km.
    sigma_theta_rad : ndarray (n, N)
        Angular noise (Eq. 20) of each measurement.
    """

    t: np.ndarray
    J_rho: np.ndarray
    P_final: np.ndarray
    range_km: np.ndarray
    sigma_theta_rad: np.ndarray
    length_unit_km: float

    def __post_init__(self):
        t = validation.time_grid(self.t, "t", increasing=True)
        J = validation.as_array(self.J_rho, "J_rho", ndim=(2,))
        n = J.shape[0]
        if n < 1 or J.shape[1] != t.size:
            raise ValueError(f"J_rho must have shape (n, N) with n >= 1 and N = t.size = {t.size}; got {J.shape}")
        if np.any(J < 0):
            raise ValueError("J_rho must be non-negative (a variance)")
        P = validation.as_array(self.P_final, "P_final", shape=(n, 12, 12))
        fields = {"t": t, "J_rho": J, "P_final": P}
        for name in ("range_km", "sigma_theta_rad"):
            a = validation.as_array(getattr(self, name), name, shape=(n, t.size))
            if np.any(a <= 0):
                raise ValueError(f"{name} must be positive")
            fields[name] = a
        fields["length_unit_km"] = validation.positive(self.length_unit_km, "length_unit_km")
        for name, value in fields.items():
            object.__setattr__(self, name, value)

    @property
    def range_sigma_km(self) -> np.ndarray:
        """:math:`\\sqrt{J_\\rho}`, the 1-sigma range uncertainty, km, shape (n, N)."""
        return np.sqrt(self.J_rho) * self.length_unit_km

    @property
    def final_range_sigma_km(self) -> np.ndarray:
        """:math:`\\sqrt{J_\\rho(\\tau_f)}` at the last measurement time, km, shape (n,)."""
        return self.range_sigma_km[:, -1]


def _measurement_rows(system, xa, xt, sigma_min_rad, resolution_km):
    """Whitened azimuth/elevation Jacobian rows w.r.t. [s_a, s_t] at the given states, plus range and sigma."""
    _, Ha, Ht = AZIMUTH_ELEVATION.evaluate(xa, xt)  # (..., 2, 6)
    rho_km = np.linalg.norm(xt[..., :3] - xa[..., :3], axis=-1) * system.length_unit_km
    sig = angular_sigma(rho_km, sigma_min_rad, resolution_km)
    H = np.concatenate([Ha, Ht], axis=-1) / sig[..., None, None]
    return H, rho_km, sig


def _check_separated(xa, xt, t):
    """Angles (and the range direction) are undefined where agent and target coincide."""
    bad = np.argwhere(np.all(xa[..., :3] == xt[..., :3], axis=-1))
    if bad.size:
        k = int(bad[0, -1])
        which = f" (agent trajectory {int(bad[0, 0])})" if bad.shape[1] > 1 else ""
        raise ValueError(f"agent and target coincide at t[{k}] = {t[k]:.6g} TU{which}: the line of sight and the "
                         "angles are undefined")


def _check_pair_trajectories(agent, target, n_agent_name="agent", n_target_name="target"):
    _trajectory(agent, n_agent_name)
    _trajectory(target, n_target_name)
    if target.x.shape[0] != 1 and target.x.shape[0] != agent.x.shape[0]:
        raise ValueError(f"{n_target_name} must hold one trajectory or as many as {n_agent_name} "
                         f"({agent.x.shape[0]}); got {target.x.shape[0]}")
    if agent.t.shape != target.t.shape or not np.allclose(agent.t, target.t, rtol=0, atol=1e-12):
        raise ValueError(f"{n_agent_name} and {n_target_name} must share the same time grid")


_TRIU_12 = np.triu(np.ones((12, 12), dtype=bool))


def _sri_range_variance(R, A, stm_a, stm_t, M):
    """The measurement loop of :func:`ssat_covariance` (arguments checked there): :math:`J_\\rho` at every epoch
    (n, N) and the final square-root information matrix (n, 12, 12).

    The QR factorisations and triangular-system solves are the very LAPACK calls of ``np.linalg.qr(..., mode="r")``
    and ``np.linalg.solve`` (numpy's own linalg gufuncs, same inputs, same signature), called once per epoch without
    the per-call wrapper work of those functions; the results are bit-identical to them
    (``tests/guidance/test_ssat_kernel.py`` keeps the wrapper form as its oracle).
    """
    n, N = A.shape[:2]
    J = np.empty((n, N))
    # g_k = Phi_k^T m_k (block diagonal STM), every epoch at once
    g = np.concatenate([np.einsum("nkji,nkj->nki", stm_a, M[..., :6]),
                        np.einsum("nkji,nkj->nki", stm_t, M[..., 6:])], axis=-1)[..., None]
    qr_r_raw, solve = _umath_linalg.qr_r_raw, _umath_linalg.solve
    stacked = np.empty((n, 12 + A.shape[-2], 12))
    with np.errstate(invalid="raise", over="ignore", divide="ignore", under="ignore"):
        try:
            for k in range(N):
                stacked[:, :12] = R
                stacked[:, 12:] = A[:, k]
                qr_r_raw(stacked, signature="d->d")  # Householder QR in place (LAPACK dgeqrf), R in the upper part
                R = np.where(_TRIU_12, stacked[:, :12], 0.0)
                w = solve(np.swapaxes(R, -1, -2), g[:, k], signature="dd->d")[..., 0]
                J[:, k] = np.sum(w * w, axis=-1)
        except FloatingPointError as err:  # what np.linalg raises on a failed factorisation or a singular R
            raise np.linalg.LinAlgError(f"square-root information update failed: {err}") from None
    return J, R


def ssat_covariance(system: CR3BP, agent: ImpulsiveTrajectory, target: ImpulsiveTrajectory, P0, *,
                    sigma_min_rad: float = AMOS_SIGMA_MIN_RAD,
                    resolution_km: float = AMOS_RESOLUTION_KM) -> SSATCovariance:
    """Linear covariance analysis of SSAT with angles-only measurements at every grid time (batched).

    Parameters
    ----------
    system : CR3BP
    agent : ImpulsiveTrajectory
        Agent trajectories (n, N) with STMs from :func:`propagate_with_impulses` (true trajectories, impulses
        included).
    target : ImpulsiveTrajectory
        Target trajectory (1 or n of them) on the same grid.
    P0 : array_like (12, 12)
        Inertial SSAT covariance at ``t[0]`` (e.g. :func:`initial_covariance`).
    sigma_min_rad, resolution_km : float
        Eq. 20 noise parameters (defaults 10 micro-rad, 4 m).

    Returns
    -------
    SSATCovariance

    Notes
    -----
    Square-root information filter referred to :math:`t_0` (no process noise): the upper-triangular
    :math:`R` with :math:`R^TR = P_0^{-1} + \\sum_j A_j^TA_j`, :math:`A_j = R_j^{-1/2}H_j\\Phi(t_j,t_0)`, is
    updated by a batched QR per measurement epoch; then
    :math:`J_\\rho(t_k) = \\|R_k^{-T}\\Phi(t_k,t_0)^Tm_k\\|^2` with :math:`m_k` from :func:`range_projection`.
    Equal to the Joseph-form EKF recursion of :func:`ssat_covariance_ekf` (tested).
    """
    check_system(system)
    _check_pair_trajectories(agent, target)
    P0 = _initial_cov(P0)
    smin, dres = _noise(sigma_min_rad, resolution_km)
    n, N = agent.x.shape[0], agent.t.size
    xt = np.broadcast_to(target.x, (n, N, 6))
    st = np.broadcast_to(target.stm, (n, N, 6, 6))
    _check_separated(agent.x, xt, agent.t)
    H, rho_km, sig = _measurement_rows(system, agent.x, xt, smin, dres)  # (n, N, 2, 12)
    # A_k = H_k blockdiag(Phi_a, Phi_t)
    A = np.concatenate([H[..., :6] @ agent.stm, H[..., 6:] @ st], axis=-1)
    R = np.broadcast_to(np.linalg.inv(np.linalg.cholesky(P0)), (n, 12, 12)).copy()  # R^T R = P0^{-1}
    X = np.concatenate([agent.x, xt], axis=-1)
    M = range_projection(X, "inertial")  # (n, N, 12)
    J, R = _sri_range_variance(R, A, agent.stm, st, M)
    Rinv = np.linalg.inv(R)
    Pt0 = Rinv @ np.swapaxes(Rinv, -1, -2)
    Phi = np.zeros((n, 12, 12))
    Phi[:, :6, :6] = agent.stm[:, -1]
    Phi[:, 6:, 6:] = st[:, -1]
    Pf = Phi @ Pt0 @ np.swapaxes(Phi, -1, -2)
    Pf = 0.5 * (Pf + np.swapaxes(Pf, -1, -2))
    return SSATCovariance(t=agent.t, J_rho=J, P_final=Pf, range_km=rho_km, sigma_theta_rad=sig,
                          length_unit_km=system.length_unit_km)


def ssat_covariance_ekf(system: CR3BP, agent: ImpulsiveTrajectory, target: ImpulsiveTrajectory, P0, *,
                        coordinates: str = "inertial", sigma_min_rad: float = AMOS_SIGMA_MIN_RAD,
                        resolution_km: float = AMOS_RESOLUTION_KM):
    """Reference EKF recursion (:func:`cislunar.sensing.covariance.covariance_analysis`) for one agent trajectory.

    Runs the Joseph-form recursion in the chosen coordinates (``"inertial"`` :math:`\\mathbf x`, ``"relative"``
    :math:`T\\mathbf x` or ``"agent"`` :math:`T_a\\mathbf x`) with :math:`F_k = C\\Phi_kC^{-1}`,
    :math:`H_k C^{-1}` and :math:`CP_0C^T`; used to check :func:`ssat_covariance` and the equivalence of the
    three SSAT coordinate systems.

    Returns
    -------
    posterior : ndarray (N, 12, 12)
        Posterior covariances in the chosen coordinates.
    J_rho : ndarray (N,)
        Range variance at each time, LU^2.
    """

    check_system(system)
    _check_pair_trajectories(agent, target)
    if agent.x.shape[0] != 1:
        raise ValueError(f"agent must hold a single trajectory for the reference recursion; got {agent.x.shape[0]}")
    validation.choice(coordinates, "coordinates", _COORDINATES)
    P0 = _initial_cov(P0)
    sigma_min_rad, resolution_km = _noise(sigma_min_rad, resolution_km)
    C = {"inertial": np.eye(12), "relative": transform_matrix(6), "agent": agent_transform_matrix(6)}[coordinates]
    Ci = np.linalg.inv(C)
    xa, xt = agent.x[0], target.x[0]
    _check_separated(xa, xt, agent.t)
    sa, st = agent.stm[0], target.stm[0]
    N = agent.t.size
    Phi = np.zeros((N, 12, 12))
    Phi[:, :6, :6] = sa
    Phi[:, 6:, 6:] = st
    F = np.linalg.solve(np.swapaxes(Phi[:-1], -1, -2), np.swapaxes(Phi[1:], -1, -2))
    F = C @ np.swapaxes(F, -1, -2) @ Ci  # Phi_{k+1} Phi_k^{-1}
    H, _, _ = _measurement_rows(system, xa, xt, sigma_min_rad, resolution_km)
    H = H @ Ci
    P0c = C @ P0 @ C.T
    hist = covariance_analysis(P0c, F, np.zeros((12, 12)), H, np.eye(2))
    X = np.concatenate([xa, xt], axis=-1)
    J = range_variance(hist.posterior, X, coordinates)
    return hist.posterior, J


# --------------------------------------------------------------------------------------------------------------
# MMD guidance (Eqs. 23-24)
# --------------------------------------------------------------------------------------------------------------
def mmd_matrix(agent_stm, H_agent) -> np.ndarray:
    """:math:`Q = B_a^T\\Phi^TH_f^TH_f\\Phi B_a` (Eq. 24), shape (..., 3, 3).

    Parameters
    ----------
    agent_stm : array_like (..., 6, 6)
        Agent STM :math:`\\Phi_a(\\tau_f, \\tau_0)` of the unmaneuvered trajectory.
    H_agent : array_like (..., 2, 6)
        Measurement Jacobian at :math:`\\tau_f` with respect to the agent state (:math:`-\\partial h/\\partial
        \\boldsymbol\\delta`).  Only the agent block of the 12-state :math:`H\\Phi B_a` is non-zero, because
        :math:`B_a` acts on the agent and :math:`\\Phi` is block diagonal.
    """
    S = validation.as_array(agent_stm, "agent_stm", last=6, min_size=1)
    H = validation.as_array(H_agent, "H_agent", last=6, min_size=1)
    if S.shape[-2:] != (6, 6):
        raise ValueError(f"agent_stm must have shape (..., 6, 6); got {S.shape}")
    if H.ndim < 2:
        raise ValueError(f"H_agent must have shape (..., m, 6); got {H.shape}")
    G = H @ S[..., :, 3:6]  # (..., m, 3)
    return np.swapaxes(G, -1, -2) @ G


def mmd_direction(Q) -> np.ndarray:
    """Unit eigenvector of the largest eigenvalue of ``Q`` (..., 3, 3) (Eq. 23), sign fixed (its largest component in absolute value is positive).

    Eq. 23 as printed, :math:`\\mathbf u_y = \\pm\\upsilon\\max(\\mathrm{eig}(Q))`, names the largest eigenvalue (a
    scalar); the policy is its eigenvector, the maximiser of the Rayleigh quotient :math:`\\mathbf u^TQ\\mathbf u`
    on the unit sphere.
    """
    Q = validation.as_array(Q, "Q", min_size=1)
    if Q.shape[-2:] != (3, 3):
        raise ValueError(f"Q must have shape (..., 3, 3); got {Q.shape}")
    Q = validation.psd(Q, "Q", n=3, batch=True)
    w, V = np.linalg.eigh(0.5 * (Q + np.swapaxes(Q, -1, -2)))
    v = V[..., :, -1]
    idx = np.argmax(np.abs(v), axis=-1)
    sgn = np.sign(np.take_along_axis(v, idx[..., None], axis=-1))
    return v * sgn


def _burn_index(burn_index, t, name="burn_index"):
    if isinstance(burn_index, bool) or not isinstance(burn_index, (int, np.integer)):
        raise ValueError(f"{name} must be an integer grid index; got {burn_index!r}")
    b = int(burn_index)
    if not 0 <= b < t.size - 1:
        raise ValueError(f"{name} must index a grid time before the last one (0..{t.size - 2}); got {b}")
    return b


def mmd_policy(system: CR3BP, agent_x0, target_x0, t, dv_magnitude: float, P0, *, burn_index: int = 0,
               sigma_min_rad: float = AMOS_SIGMA_MIN_RAD, resolution_km: float = AMOS_RESOLUTION_KM):
    """MMD impulse at ``t[burn_index]`` for the coast to ``t[-1]``, sign chosen by a quick covariance analysis.

    Measurements cover the whole grid (those before the burn are a tracking arc that ends at the burn).

    Parameters
    ----------
    system : CR3BP
    agent_x0, target_x0 : array_like (6,)
        States at ``t[0]`` (before the burn).
    t : array_like (N,)
        Measurement grid; :math:`\\tau_0 = t_b`, :math:`\\tau_f = t_{N-1}`.
    dv_magnitude : float
        :math:`\\upsilon`, LU/TU.
    P0 : array_like (12, 12)

    Returns
    -------
    u : ndarray (3,)
        Selected impulse :math:`\\pm\\upsilon\\,\\mathbf e_{max}`, LU/TU.
    Q : ndarray (3, 3)
        MMD matrix.
    J_pm : ndarray (2,)
        Final :math:`J_\\rho` of ``+e`` and ``-e`` (LU^2).
    """
    check_system(system)
    v = validation.positive(dv_magnitude, "dv_magnitude")
    t = validation.time_grid(t, "t", increasing=True)
    xa0 = validation.as_state(agent_x0, "agent_x0", batch=False)
    xt0 = validation.as_state(target_x0, "target_x0", batch=False)
    b = _burn_index(burn_index, t)
    _initial_cov(P0)
    _noise(sigma_min_rad, resolution_km)
    nominal = propagate_with_impulses(system, np.vstack([xa0, xt0]), t)
    _, Ha, _ = AZIMUTH_ELEVATION.evaluate(nominal.x[0, -1], nominal.x[1, -1])
    phi_fb = nominal.stm[0, -1] @ np.linalg.inv(nominal.stm[0, b])  # Phi(tau_f, tau_0)
    Q = mmd_matrix(phi_fb, Ha)
    e = mmd_direction(Q)
    target = ImpulsiveTrajectory(t, nominal.x[1:], nominal.stm[1:])
    cand = np.vstack([e, -e]) * v
    ag = propagate_with_impulses(system, np.vstack([xa0, xa0]), t, [(t[b], cand)])
    J = ssat_covariance(system, ag, target, P0, sigma_min_rad=sigma_min_rad, resolution_km=resolution_km).J_rho[:, -1]
    return cand[int(np.argmin(J))], Q, J


# --------------------------------------------------------------------------------------------------------------
# directions: sphere grids, perpendicular circle, true minimiser
# --------------------------------------------------------------------------------------------------------------
def fibonacci_sphere(n: int) -> np.ndarray:
    """``n`` nearly uniform unit vectors (Fibonacci lattice), shape (n, 3); spacing about :math:`\\sqrt{4\\pi/n}` rad."""
    n = validation.integer(n, "n", minimum=2)
    i = np.arange(n) + 0.5
    z = 1.0 - 2.0 * i / n
    phi = np.pi * (1.0 + 5**0.5) * i
    r = np.sqrt(1.0 - z * z)
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1)


def perpendicular_directions(line_of_sight, n: int) -> np.ndarray:
    """``n`` unit vectors evenly spaced on the circle perpendicular to ``line_of_sight`` (3,), shape (n, 3)."""
    los = validation.as_array(line_of_sight, "line_of_sight", shape=(3,))
    nrm = np.linalg.norm(los)
    if nrm == 0:
        raise ValueError("line_of_sight must be non-zero")
    n = validation.integer(n, "n", minimum=1)
    u = los / nrm
    a = np.eye(3)[np.argmin(np.abs(u))]
    e1 = np.cross(u, a)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(u, e1)
    ang = 2 * np.pi * np.arange(n) / n
    return np.cos(ang)[:, None] * e1 + np.sin(ang)[:, None] * e2


def range_sigma_over_directions(system: CR3BP, agent_x0, target_x0, t, dv_magnitude: float, directions, P0, *,
                                burn_index: int = 0, target: ImpulsiveTrajectory | None = None,
                                threads: int | None = None,
                                sigma_min_rad: float = AMOS_SIGMA_MIN_RAD,
                                resolution_km: float = AMOS_RESOLUTION_KM) -> SSATCovariance:
    """Covariance analyses of impulses ``dv_magnitude * directions`` applied at ``t[burn_index]`` (batched).

    ``J_rho[:, k]`` of the result is the cost for the coast :math:`\\tau_f = t_k` (measurements are a prefix of
    the grid), so one call covers every coast time of the grid.  ``directions`` (m, 3) need not be unit vectors
    only if the caller wants other magnitudes; they are normalised here.
    """
    check_system(system)
    v = validation.positive(dv_magnitude, "dv_magnitude", allow_zero=True)
    D = validation.as_array(directions, "directions", ndim=(2,), last=3, min_size=1)
    nrm = np.linalg.norm(D, axis=-1, keepdims=True)
    if np.any(nrm == 0):
        raise ValueError("directions must be non-zero vectors")
    D = D / nrm
    t = validation.time_grid(t, "t", increasing=True)
    xa0 = validation.as_state(agent_x0, "agent_x0", batch=False)
    b = _burn_index(burn_index, t)
    _initial_cov(P0)
    _noise(sigma_min_rad, resolution_km)
    if target is None:
        xt0 = validation.as_state(target_x0, "target_x0", batch=False)
        target = propagate_with_impulses(system, xt0, t)
    else:
        _trajectory(target, "target")
        if target.t.shape != t.shape or not np.allclose(target.t, t, rtol=0, atol=1e-12):
            raise ValueError("target must be given on the grid t")
    ag = propagate_with_impulses(system, np.broadcast_to(xa0, D.shape[:1] + (6,)), t, [(t[b], v * D)],
                                 threads=threads)
    return ssat_covariance(system, ag, target, P0, sigma_min_rad=sigma_min_rad, resolution_km=resolution_km)


def minimize_range_sigma(system: CR3BP, agent_x0, target_x0, t, dv_magnitude: float, P0, *, n_grid: int = 2000,
                         refine: bool = True, burn_index: int = 0, target: ImpulsiveTrajectory | None = None,
                         grid_result: SSATCovariance | None = None, sigma_min_rad: float = AMOS_SIGMA_MIN_RAD,
                         resolution_km: float = AMOS_RESOLUTION_KM):
    """True minimiser of the final :math:`J_\\rho` over burn directions of fixed magnitude.

    A Fibonacci grid of ``n_grid`` directions is evaluated (or ``grid_result`` from
    :func:`range_sigma_over_directions` on that grid is reused), then the best grid direction is refined with
    Nelder-Mead on the two spherical angles.  ``sigma_min_rad`` and ``resolution_km`` (Eq. 20) must be those of
    ``grid_result`` when it is given.

    Returns
    -------
    direction : ndarray (3,)
        Unit minimiser.
    J : float
        Its final :math:`J_\\rho`, LU^2.
    """
    from scipy.optimize import minimize

    check_system(system)
    t = validation.time_grid(t, "t", increasing=True)
    validation.as_state(agent_x0, "agent_x0", batch=False)
    validation.positive(dv_magnitude, "dv_magnitude")
    _initial_cov(P0)
    n_grid = validation.integer(n_grid, "n_grid", minimum=2)
    refine = validation.boolean(refine, "refine")
    _burn_index(burn_index, t)
    if grid_result is not None:
        validation.instance(grid_result, "grid_result", SSATCovariance,
                         "a cislunar.guidance.ssat.SSATCovariance (from range_sigma_over_directions) or None")
    _noise(sigma_min_rad, resolution_km)
    if target is None:
        target = propagate_with_impulses(system, validation.as_state(target_x0, "target_x0", batch=False), t)
    D = fibonacci_sphere(n_grid)
    if grid_result is None:
        grid_result = range_sigma_over_directions(system, agent_x0, None, t, dv_magnitude, D, P0, target=target,
                                                  burn_index=burn_index, sigma_min_rad=sigma_min_rad,
                                                  resolution_km=resolution_km)
    Jg = grid_result.J_rho[:, -1]
    if Jg.size != D.shape[0]:
        raise ValueError(f"grid_result must hold {D.shape[0]} directions (n_grid); got {Jg.size}")
    best = D[int(np.argmin(Jg))]
    Jbest = float(np.min(Jg))
    if not refine:
        return best, Jbest

    def to_vec(p):
        th, ph = p
        return np.array([np.cos(ph) * np.cos(th), np.cos(ph) * np.sin(th), np.sin(ph)])

    p0 = np.array([np.arctan2(best[1], best[0]), np.arcsin(np.clip(best[2], -1, 1))])

    def cost(p):
        r = range_sigma_over_directions(system, agent_x0, None, t, dv_magnitude, to_vec(p)[None], P0, target=target,
                                        burn_index=burn_index, sigma_min_rad=sigma_min_rad,
                                        resolution_km=resolution_km)
        return r.J_rho[0, -1] / Jbest

    step = np.sqrt(4 * np.pi / D.shape[0])
    res = minimize(cost, p0, method="Nelder-Mead",
                   options={"xatol": 1e-4, "fatol": 1e-7, "initial_simplex": [p0, p0 + [step, 0], p0 + [0, step]]})
    if res.fun * Jbest < Jbest:
        return to_vec(res.x), float(res.fun * Jbest)
    return best, Jbest


@dataclass(frozen=True)
class PolicyComparison:
    """Final range uncertainty :math:`\\sqrt{J_\\rho}` (km) of burn policies over several coast times.

    Every array has one entry per coast time.  ``grid_*`` summarise a Fibonacci sphere of directions (the
    distribution of a uniformly random burn direction); ``perp_*`` the circle of directions perpendicular to the
    line of sight at the burn; ``optimum`` the refined minimiser; ``mmd`` the MMD policy with its sign chosen by
    the quick covariance analysis and ``mmd_other`` the rejected sign.

    Attributes
    ----------
    coast_hours : ndarray
    none, mmd, mmd_other, optimum, grid_median, grid_max, perp_best, perp_median, perp_worst : ndarray, km
    mmd_percentile : ndarray
        Percent of sphere-grid directions that do better than MMD (0 = MMD beats every grid direction).
    mmd_direction, optimum_direction : ndarray (m, 3)
        Unit burn directions (rotating frame).
    angle_mmd_optimum_deg : ndarray
        Angle between the MMD axis (either sign) and the optimum, deg.
    optimum_perp_angle_deg : ndarray
        Angle between the optimum and the plane perpendicular to the line of sight, deg (0: in the plane).
    """

    coast_hours: np.ndarray
    none: np.ndarray
    mmd: np.ndarray
    mmd_other: np.ndarray
    optimum: np.ndarray
    grid_median: np.ndarray
    grid_max: np.ndarray
    perp_best: np.ndarray
    perp_median: np.ndarray
    perp_worst: np.ndarray
    mmd_percentile: np.ndarray
    mmd_direction: np.ndarray
    optimum_direction: np.ndarray
    angle_mmd_optimum_deg: np.ndarray
    optimum_perp_angle_deg: np.ndarray

    @property
    def mmd_excess_percent(self) -> np.ndarray:
        """How far MMD is above the optimum, percent of the optimum's :math:`\\sqrt{J_\\rho}`."""
        return 100.0 * (self.mmd / self.optimum - 1.0)

    @property
    def mmd_gain_fraction(self) -> np.ndarray:
        """Fraction of the possible improvement over a median (random) direction that MMD achieves (1 = optimal)."""
        return (self.grid_median - self.mmd) / (self.grid_median - self.optimum)


def compare_burn_policies(system: CR3BP, agent_x0, target_x0, t, coast_indices, dv_magnitude: float, P0, *,
                          n_grid: int = 2000, n_perp: int = 72, refine: bool = True, burn_index: int = 0,
                          sigma_min_rad: float = AMOS_SIGMA_MIN_RAD,
                          resolution_km: float = AMOS_RESOLUTION_KM) -> PolicyComparison:
    """MMD against the true minimiser of :math:`J_\\rho` and the perpendicular heuristic, for several coast times.

    A single impulse of magnitude ``dv_magnitude`` (LU/TU) at ``t[burn_index]``; measurements at every grid time
    up to the end of the coast :math:`\\tau_f = t_k`, ``k`` in ``coast_indices`` (grid times before the burn are a
    tracking arc).  The sphere grid and the perpendicular
    circle are propagated once for the longest coast (the measurement sets of shorter coasts are prefixes).

    Parameters
    ----------
    system : CR3BP
    agent_x0, target_x0 : array_like (6,)
        States at ``t[0]``.
    t : array_like (N,)
        Measurement grid, TU.
    coast_indices : sequence of int
        Grid indices (>= 1) of the coast end times.
    dv_magnitude : float
        :math:`\\upsilon`, LU/TU.
    P0 : array_like (12, 12)
    n_grid, n_perp : int
        Sphere-grid and perpendicular-circle sizes.
    refine : bool
        Refine the grid optimum with Nelder-Mead (:func:`minimize_range_sigma`).
    """
    check_system(system)
    t = validation.time_grid(t, "t", increasing=True)
    ks = _grid_indices(coast_indices, "coast_indices")
    b = _burn_index(burn_index, t)
    if np.any(ks <= b) or np.any(ks >= t.size):
        raise ValueError(f"coast_indices must be grid indices in {b + 1}..{t.size - 1} (after the burn); "
                         f"got {coast_indices!r}")
    xa0 = validation.as_state(agent_x0, "agent_x0", batch=False)
    xt0 = validation.as_state(target_x0, "target_x0", batch=False)
    v = validation.positive(dv_magnitude, "dv_magnitude")
    _initial_cov(P0)
    n_grid = validation.integer(n_grid, "n_grid", minimum=2)
    n_perp = validation.integer(n_perp, "n_perp", minimum=1)
    refine = validation.boolean(refine, "refine")
    _noise(sigma_min_rad, resolution_km)
    kmax = int(ks.max())
    tt = t[:kmax + 1]
    L = system.length_unit_km
    target = propagate_with_impulses(system, xt0, tt)
    nominal = propagate_with_impulses(system, xa0, tt)
    none = ssat_covariance(system, nominal, target, P0, sigma_min_rad=sigma_min_rad, resolution_km=resolution_km)
    D = fibonacci_sphere(n_grid)
    grid = range_sigma_over_directions(system, xa0, None, tt, v, D, P0, target=target, burn_index=b,
                                       sigma_min_rad=sigma_min_rad, resolution_km=resolution_km)
    los = target.x[0, b, :3] - nominal.x[0, b, :3]  # line of sight at the burn
    los = los / np.linalg.norm(los)
    perp = range_sigma_over_directions(system, xa0, None, tt, v, perpendicular_directions(los, n_perp), P0,
                                       target=target, burn_index=b, sigma_min_rad=sigma_min_rad,
                                       resolution_km=resolution_km)
    out = {k: [] for k in ("none", "mmd", "mmd_other", "optimum", "grid_median", "grid_max", "perp_best",
                           "perp_median", "perp_worst", "mmd_percentile", "mmd_direction", "optimum_direction",
                           "angle_mmd_optimum_deg", "optimum_perp_angle_deg")}
    for k in ks:
        tk = tt[:k + 1]
        u, Q, Jpm = mmd_policy(system, xa0, xt0, tk, v, P0, burn_index=b, sigma_min_rad=sigma_min_rad,
                               resolution_km=resolution_km)
        Jg = grid.J_rho[:, k]
        sub = SSATCovariance(tk, grid.J_rho[:, :k + 1], grid.P_final, grid.range_km[:, :k + 1],
                             grid.sigma_theta_rad[:, :k + 1], L)
        tgt_k = ImpulsiveTrajectory(tk, target.x[:, :k + 1], target.stm[:, :k + 1])
        d_opt, J_opt = minimize_range_sigma(system, xa0, None, tk, v, P0, n_grid=n_grid, refine=refine,
                                            burn_index=b, target=tgt_k, grid_result=sub,
                                            sigma_min_rad=sigma_min_rad, resolution_km=resolution_km)
        J_mmd = float(Jpm.min())
        e = u / v
        out["none"].append(np.sqrt(none.J_rho[0, k]) * L)
        out["mmd"].append(np.sqrt(J_mmd) * L)
        out["mmd_other"].append(np.sqrt(Jpm.max()) * L)
        out["optimum"].append(np.sqrt(J_opt) * L)
        out["grid_median"].append(np.sqrt(np.median(Jg)) * L)
        out["grid_max"].append(np.sqrt(Jg.max()) * L)
        Jp = perp.J_rho[:, k]
        out["perp_best"].append(np.sqrt(Jp.min()) * L)
        out["perp_median"].append(np.sqrt(np.median(Jp)) * L)
        out["perp_worst"].append(np.sqrt(Jp.max()) * L)
        out["mmd_percentile"].append(100.0 * np.mean(Jg < J_mmd))
        out["mmd_direction"].append(e)
        out["optimum_direction"].append(d_opt)
        out["angle_mmd_optimum_deg"].append(np.degrees(np.arccos(min(1.0, abs(float(e @ d_opt))))))
        out["optimum_perp_angle_deg"].append(np.degrees(np.arcsin(min(1.0, abs(float(d_opt @ los))))))
    hours = (tt[ks] - tt[b]) * system.time_unit_s / 3600.0
    return PolicyComparison(coast_hours=hours, **{k: np.asarray(v_) for k, v_ in out.items()})
