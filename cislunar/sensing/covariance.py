r"""Augmented observer/target covariances: SPD helpers, process noise, EKF covariance analysis (CRLB).

Augmented state (Wolf & Jones Eq. 7)
------------------------------------
:math:`\mathbf x_{\mathcal A} = [\mathbf x_{\mathcal S}; \mathbf x^{(1)}_{\mathcal T}; \dots;
\mathbf x^{(N_{\mathcal T})}_{\mathcal T}]`, 6 (N_T + 1) components, each a CR3BP state in LU, LU/TU (rotating
frame).  Objects are uncorrelated a priori and move independently, so the initial covariance, the transition
matrix :math:`\Phi_{\mathcal A}` (Eq. 22) and the process noise :math:`Q_{\mathcal A}` are block diagonal.  The
augmented measurement Jacobian :math:`H_{\mathcal A}` (Eq. 21) couples the observer to each target.

Process noise
-------------
A continuous white-noise acceleration :math:`\mathbf w(t)` with power spectral density (PSD) :math:`q` per axis
enters as :math:`\dot{\delta\mathbf x} = A(t)\delta\mathbf x + G\mathbf w`, :math:`G = [0; I_3]`.  Its exact
discretisation along the reference trajectory between :math:`t_k` and :math:`t_{k+1}` is

.. math:: Q_k = \int_{t_k}^{t_{k+1}} \Phi(t_{k+1},\tau)\,G\,q\,G^T\,\Phi(t_{k+1},\tau)^T\,d\tau ,

the time-varying generalisation of Van Loan's formula (it solves the Lyapunov differential equation
:math:`\dot Q = AQ + QA^T + qGG^T`, :math:`Q(t_k)=0`).  :func:`process_noise` evaluates the integral by
Gauss-Legendre quadrature with STMs from heyoka (:math:`\Phi(t_{k+1},\tau) = \Phi(t_{k+1},t_k)
\Phi(\tau,t_k)^{-1}`, both propagated from :math:`t_k` so the inverse is of a short-arc STM);
:func:`process_noise_lyapunov` integrates the Lyapunov equation with scipy (independent check) and
:func:`van_loan` is the classical matrix-exponential form for a constant :math:`A`.

Units of the PSD.  The PSD of an acceleration has units (km/s^2)^2 / Hz = km^2/s^3.  Wolf & Jones print
"Q [km/s^3] = 1e-11" (Tables 3 and 5).  Read literally with the square restored (1e-11 km^2/s^3, a one-day
velocity random walk of 0.93 m/s) the CRLB of their test case 1 grows without bound over the window, against their
text; the adopted reading is the same number in normalised units, :math:`q = 10^{-11}` LU^2/TU^3
= 2.80e-17 km^2/s^3 (:data:`WOLF_JONES_PSD_KM2_S3`; the evidence and the other readings are in
:mod:`cislunar.papers.wolf_jones.scenarios` and notebook 06).  :func:`psd_to_nondimensional` converts km^2/s^3 to LU^2/TU^3:
:math:`q_{nd} = q\,T^3/L^2`.

EKF covariance analysis (Performance Evaluation section)
--------------------------------------------------------
The CRLB of a nonlinear system with Gaussian noise is obtained from the EKF covariance recursion linearised about
the *true* trajectory (Taylor 1978):

.. math:: \bar P_{k+1} = \Phi_k\hat P_k\Phi_k^T + Q_k,\quad K_k = \bar P_k H_k^T(H_k\bar P_kH_k^T + R_k)^{-1},\quad
          \hat P_k = (I-K_kH_k)\bar P_k(I-K_kH_k)^T + K_kR_kK_k^T

(the Joseph form, algebraically equal to the paper's :math:`(I-KH)\bar P` and better conditioned; identical to
``filterpy.kalman.KalmanFilter.predict/update``, checked in the tests).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
from scipy.integrate import solve_ivp

from cislunar.cr3bp.dynamics import CR3BP, check_system
from cislunar.cr3bp.propagation import (
    check_outside_primaries,
    propagate,
    propagate_stm,
    propagate_stt,
    raise_scipy_impact,
    scipy_impact_events,
)
from cislunar.sensing.measurements import MeasurementModel
from cislunar.utils import validation

__all__ = [
    "WOLF_JONES_SIGMA_POS_KM",
    "WOLF_JONES_SIGMA_VEL_KM_S",
    "WOLF_JONES_PSD_KM2_S3",
    "symmetrize",
    "check_spd",
    "check_psd",
    "cholesky_spd",
    "logdet_spd",
    "block_diag",
    "WindowAssembler",
    "state_covariance",
    "augment_states",
    "augmented_covariance",
    "psd_to_nondimensional",
    "van_loan",
    "process_noise",
    "process_noise_lyapunov",
    "ekf_predict",
    "ekf_update",
    "CovarianceHistory",
    "covariance_analysis",
    "position_sigma_km",
    "AugmentedLinearization",
    "ObjectArcs",
    "propagate_arcs",
    "assemble_augmented",
    "linearize_augmented",
]

#: Wolf & Jones Tables 3 and 5: initial 1-sigma position per axis, km.
WOLF_JONES_SIGMA_POS_KM = 100.0
#: Wolf & Jones Tables 3 and 5: initial 1-sigma velocity per axis, km/s.
WOLF_JONES_SIGMA_VEL_KM_S = 1e-2
#: Wolf & Jones Tables 3 and 5: process-noise PSD in km^2/s^3, the adopted reading of the printed "1e-11 km/s^3"
#: (1e-11 LU^2/TU^3 in the classical Earth-Moon units, 2.80e-17 km^2/s^3; see :mod:`cislunar.papers.wolf_jones.scenarios`).
WOLF_JONES_PSD_KM2_S3 = 1e-11 * 384400.0**2 / 375190.25852**3


# --------------------------------------------------------------------------------------------------------------
# SPD helpers
# --------------------------------------------------------------------------------------------------------------
def symmetrize(P, name: str = "P") -> np.ndarray:
    """Symmetric part :math:`(P + P^T)/2` of square matrices ``(..., n, n)``.

    Raises ``ValueError`` naming ``name`` for a non-square or non-finite input.
    """
    P = _square(P, name)
    return 0.5 * (P + np.swapaxes(P, -1, -2))


def _name(name) -> str:
    """The ``name`` argument of the SPD helpers (a string used in their messages)."""
    return validation.instance(name, "name", str, "a str (the argument name used in messages)")


def _rtol(rtol) -> float:
    return validation.positive(rtol, "rtol", allow_zero=True)


def _square(P, name):
    _name(name)
    P = validation.as_array(P, name, min_size=1)
    if P.ndim < 2 or P.shape[-1] != P.shape[-2]:
        raise ValueError(f"{name} must be a square matrix (..., n, n); got shape {P.shape}")
    return P


def cholesky_spd(P, name: str = "P", *, rtol: float = 1e-8) -> np.ndarray:
    """Lower Cholesky factor of symmetric positive-definite matrices ``(..., n, n)``.

    Parameters
    ----------
    P : array_like, shape (..., n, n)
    name : str
        Argument name for error messages.
    rtol : float
        Allowed asymmetry :math:`\\max|P-P^T|` relative to :math:`\\max|P|`.

    Raises
    ------
    ValueError
        Not square, NaN, asymmetric beyond ``rtol``, not positive definite or numerically singular (correlation-matrix
        eigenvalue ratio at most :data:`cislunar.utils.validation.SPD_RCOND`, see :func:`cislunar.utils.validation.spd`)
        (names ``name``).
    """
    return _cholesky(_spd(P, name, rtol))


def _spd(P, name, rtol=1e-8):
    """The checks of :func:`check_spd` (one pass of :func:`cislunar.utils.validation.spd`); returns the float array."""
    P = _square(P, name)
    rtol = _rtol(rtol)
    if not np.any(P):
        raise ValueError(f"{name} must be positive definite; got a zero matrix")
    return validation.spd(P, name, batch=True, rtol=rtol)


def _cholesky(P, name: str = "P"):
    """Lower Cholesky factor of the symmetric part of checked (or computed) SPD matrices, no argument checks.

    The inner kernel of :func:`cholesky_spd`; a failed factorisation (a computed matrix that lost definiteness)
    still raises a ``ValueError`` naming ``name``.
    """
    try:
        return np.linalg.cholesky(_sym(P))
    except np.linalg.LinAlgError as exc:
        raise ValueError(f"{name} must be positive definite (Cholesky factorisation failed)") from exc


def _logdet(P, name: str = "P"):
    """:func:`logdet_spd` of checked (or computed) SPD matrices, no argument checks."""
    return 2.0 * np.sum(np.log(np.diagonal(_cholesky(P, name), axis1=-2, axis2=-1)), axis=-1)


def check_spd(P, name: str = "P", *, rtol: float = 1e-8) -> np.ndarray:
    """Check that ``P`` (..., n, n) is symmetric positive definite; return its symmetric part.

    Raises ``ValueError`` naming ``name`` otherwise (see :func:`cholesky_spd`), also for a numerically singular
    matrix (correlation-matrix eigenvalue ratio at most :data:`cislunar.utils.validation.SPD_RCOND`, see
    :func:`cislunar.utils.validation.spd`).
    """
    return _sym(_spd(P, name, rtol))


def check_psd(Q, name: str = "Q", *, rtol: float = 1e-8) -> np.ndarray:
    """Check that ``Q`` (..., n, n) is symmetric positive *semi*-definite; return its symmetric part.

    Zero matrices are allowed (no process noise).  The smallest eigenvalue may be negative by at most ``rtol``
    times the largest absolute entry (round-off of a computed covariance).

    Raises
    ------
    ValueError
        Not square, NaN, asymmetric beyond ``rtol`` or with a negative eigenvalue (names ``name``).
    """
    Q = _square(Q, name)
    rtol = _rtol(rtol)
    scale = float(np.max(np.abs(Q))) if Q.size else 0.0
    if scale == 0.0:
        return symmetrize(Q, name)
    asym = float(np.max(np.abs(Q - np.swapaxes(Q, -1, -2))))
    if asym > rtol * scale:
        raise ValueError(f"{name} must be symmetric (max asymmetry {asym:.3g})")
    Qs = symmetrize(Q, name)
    lam = float(np.min(np.linalg.eigvalsh(Qs)))
    if lam < -rtol * scale:
        raise ValueError(f"{name} must be positive semi-definite (smallest eigenvalue {lam:.3g})")
    return Qs


def logdet_spd(P, name: str = "P") -> np.ndarray:
    """:math:`\\ln|P|` of SPD matrices ``(..., n, n)`` from the Cholesky factor, :math:`2\\sum_i \\ln L_{ii}`."""
    return _logdet(_spd(P, name), name)


def block_diag(blocks) -> np.ndarray:
    """Block-diagonal matrix from a sequence of square blocks, or from an array ``(..., k, n, n)`` (per leading index).

    With an array input the leading axes are kept: ``(..., k, n, n) -> (..., k n, k n)``.
    """
    if isinstance(blocks, np.ndarray) and blocks.ndim >= 3:
        return _block_diag(validation.square(blocks, "blocks", batch=True))
    items = validation.one_or_many(blocks, "blocks", np.ndarray, "square matrix")
    mats = [validation.square(np.atleast_2d(validation.as_array(b, f"blocks[{i}]")), f"blocks[{i}]")
            for i, b in enumerate(items)]
    return scipy.linalg.block_diag(*mats)


def _block_diag(blocks: np.ndarray) -> np.ndarray:
    """:func:`block_diag` of a checked float array ``(..., k, n, n)`` (no argument checks)."""
    k, n = blocks.shape[-3], blocks.shape[-1]
    out = np.zeros(blocks.shape[:-3] + (k * n, k * n))
    for i in range(k):
        out[..., i * n:(i + 1) * n, i * n:(i + 1) * n] = blocks[..., i, :, :]
    return out


# --------------------------------------------------------------------------------------------------------------
# augmented state and initial covariances
# --------------------------------------------------------------------------------------------------------------
def _check_system(system):
    return check_system(system, "system")


def state_covariance(sigma_pos_km: float, sigma_vel_km_s: float, system: CR3BP) -> np.ndarray:
    """Diagonal 6x6 covariance in LU^2 and (LU/TU)^2 from 1-sigma position (km) and velocity (km/s) per axis.

    Wolf & Jones Tables 3 and 5: 100 km and 1e-2 km/s for every object.
    """
    sp = validation.positive(sigma_pos_km, "sigma_pos_km")
    sv = validation.positive(sigma_vel_km_s, "sigma_vel_km_s")
    _check_system(system)
    d = np.r_[np.full(3, sp / system.length_unit_km), np.full(3, sv / system.velocity_unit_km_s)]
    return np.diag(d**2)


def augment_states(observer, targets) -> np.ndarray:
    """Augmented state of Eq. 7: ``observer`` (..., 6) and ``targets`` (N_T, ..., 6) -> (..., 6 (N_T+1))."""
    xs = validation.as_array(observer, "observer", last=6)
    xt = validation.as_array(targets, "targets", last=6)
    if xt.ndim != xs.ndim + 1:
        raise ValueError(f"targets must have shape (N_T,) + observer.shape; got {xt.shape} for observer {xs.shape}")
    return np.concatenate([xs] + [xt[i] for i in range(xt.shape[0])], axis=-1)


def augmented_covariance(P_observer, P_targets) -> np.ndarray:
    """Block-diagonal :math:`P_{\\mathcal A,0} = \\mathrm{diag}(P_{\\mathcal S}, P^{(1)}_{\\mathcal T}, \\dots)`.

    ``P_observer`` (6, 6); ``P_targets`` (N_T, 6, 6), or (6, 6) for a single target.  Each block must be SPD
    (``ValueError`` names the argument).
    """
    Ps = check_spd(validation.as_array(P_observer, "P_observer", shape=(6, 6)), "P_observer")
    Pt = validation.as_array(P_targets, "P_targets")
    if Pt.ndim == 2:
        Pt = Pt[None]
    if Pt.ndim != 3 or Pt.shape[1:] != (6, 6):
        raise ValueError(f"P_targets must have shape (N_T, 6, 6) or (6, 6); got {Pt.shape}")
    Pt = check_spd(Pt, "P_targets")
    return block_diag(np.concatenate([Ps[None], Pt], axis=0))


# --------------------------------------------------------------------------------------------------------------
# process noise
# --------------------------------------------------------------------------------------------------------------
def psd_to_nondimensional(q_km2_s3: float, system: CR3BP) -> float:
    """Convert an acceleration PSD from km^2/s^3 to LU^2/TU^3: :math:`q_{nd} = q\\,T^3/L^2`.

    Raises ``ValueError`` for a negative or non-finite ``q_km2_s3`` (zero is allowed: no process noise).
    """
    q = validation.positive(q_km2_s3, "q_km2_s3", allow_zero=True)
    _check_system(system)
    return q * system.time_unit_s**3 / system.length_unit_km**2


def van_loan(A, q: float, dt: float):
    """Van Loan discretisation for a constant ``A`` (6x6) and white acceleration noise of PSD ``q`` on :math:`G=[0;I_3]`.

    .. math:: \\exp\\left(\\begin{bmatrix}-A & GqG^T\\\\ 0 & A^T\\end{bmatrix}\\Delta t\\right)
              = \\begin{bmatrix}\\cdot & \\Phi^{-1}Q\\\\ 0 & \\Phi^T\\end{bmatrix}

    Returns
    -------
    Phi : ndarray (6, 6)
    Q : ndarray (6, 6)
    """
    A = validation.as_array(A, "A", shape=(6, 6))
    q = validation.positive(q, "q", allow_zero=True)
    dt = validation.positive(dt, "dt")
    W = np.zeros((6, 6))
    W[3:, 3:] = q * np.eye(3)
    M = np.zeros((12, 12))
    M[:6, :6] = -A
    M[:6, 6:] = W
    M[6:, 6:] = A.T
    E = scipy.linalg.expm(M * dt)
    Phi = E[6:, 6:].T
    return Phi, symmetrize(Phi @ E[:6, 6:])


def _lane_order(system: CR3BP, starts: np.ndarray, ends: np.ndarray | None, dts: np.ndarray) -> np.ndarray:
    r"""Order in which to hand the intervals ``starts`` (K, 6) to heyoka's batch integrator: by an estimate of their
    number of Taylor steps, fewest first (stable argsort; a permutation of ``range(K)``).

    A batch of SIMD lanes steps until its slowest lane has finished, so lanes with equal step counts should share a
    batch.  The estimate is :math:`|\Delta t|\,\max |\mathbf v| / \min(r_1, r_2)` over the interval's start and
    (when given) end states ``ends`` (K, 6): Taylor step sizes scale with the distance to the nearest primary over
    the speed.  Intervals of perturbed copies of one arc (the Hessian's 12 observers) get nearly equal estimates and
    share batches (lanes = perturbations).  Each lane has its own step sizes, so the order changes only the time,
    not a bit of the results (compared in ``tests/sensing/test_covariance_lanes.py``).  Unchecked (inner kernel).
    """
    def rate(x):
        r1, r2 = system.distances(x)
        return np.sqrt(np.einsum("ki,ki->k", x[:, 3:], x[:, 3:])) / np.minimum(r1, r2)

    est = rate(starts) if ends is None else np.maximum(rate(starts), rate(ends))
    return np.argsort(np.abs(dts) * est, kind="stable")


def _interval_transitions(system: CR3BP, starts: np.ndarray, dts: np.ndarray, q: float | None, n_nodes: int,
                          order: int, ends: np.ndarray | None = None, sort_lanes: bool = True):
    """Per-interval STM (and STT) over ``dts`` from ``starts`` (K, 6), and the process noise by quadrature.

    ``sort_lanes=True`` (default since 2026-11-26d) hands the intervals to heyoka's batch integrator in the order
    of :func:`_lane_order` (``ends`` (K, 6), optional: the states at the ends of the intervals, used only for that
    order); False keeps the given order (the path before).  Each lane of a heyoka batch has its own steps, so the
    order moves no result (compared bit for bit in ``tests/sensing/test_covariance_lanes.py``); the group's
    interval length stays its first interval's in the given order (lengths equal to 12 digits are grouped, and may
    differ in the last bits).
    """

    K = starts.shape[0]
    F = np.empty((K, 6, 6))
    Qd = np.empty((K, 6, 6)) if q is not None else None
    Psi = np.empty((K, 6, 6, 6)) if order == 2 else None
    nodes, weights = np.polynomial.legendre.leggauss(n_nodes)
    # group equal interval lengths so that each group is one batch propagation on a shared grid
    keys = np.round(dts / np.max(np.abs(dts)), 12)
    for key in np.unique(keys):
        idx = np.flatnonzero(keys == key)
        dt = float(dts[idx[0]])  # the group's length: its first interval's in the given order (whatever the lanes')
        if sort_lanes and idx.size > 1:
            idx = idx[_lane_order(system, starts[idx], None if ends is None else ends[idx], dts[idx])]
        taus = 0.5 * dt * (nodes + 1.0)
        grid = np.r_[0.0, taus, dt] if q is not None else np.array([0.0, dt])
        prop = propagate_stt if order == 2 else propagate_stm
        tr = prop(system, starts[idx], grid)
        stm = tr.stm if tr.stm.ndim == 4 else tr.stm[None]
        F[idx] = stm[:, -1]
        if order == 2:
            stt = tr.stt if tr.stt.ndim == 5 else tr.stt[None]
            Psi[idx] = stt[:, -1]
        if q is not None:
            phi_end = stm[:, -1]  # (k, 6, 6)
            phi_nodes = stm[:, 1:-1]  # (k, n_nodes, 6, 6)
            # Phi(t_end, tau) = Phi(t_end, t_k) Phi(tau, t_k)^{-1}; only its last three columns are needed
            M = np.linalg.solve(np.swapaxes(phi_nodes, -1, -2), np.swapaxes(phi_end, -1, -2)[:, None])
            M = np.swapaxes(M, -1, -2)[..., :, 3:6]  # (k, n_nodes, 6, 3)
            integrand = M @ np.swapaxes(M, -1, -2)
            Qd[idx] = symmetrize(q * 0.5 * dt * np.einsum("j,kjab->kab", weights, integrand))
    return F, Qd, Psi


def process_noise(system: CR3BP, x, t, q: float, *, n_nodes: int = 12) -> np.ndarray:
    """Exact discrete process noise :math:`Q_k` between consecutive grid times along reference trajectories.

    Parameters
    ----------
    system : CR3BP
    x : array_like, shape (m, 6) or (n, m, 6)
        Reference states at the grid times ``t`` (LU, LU/TU), e.g. ``propagate(...).x``.
    t : array_like, shape (m,)
        Strictly increasing times, TU.
    q : float
        Acceleration PSD per axis in LU^2/TU^3 (see :func:`psd_to_nondimensional`).
    n_nodes : int
        Gauss-Legendre nodes per interval (12 reaches ~1e-14 relative accuracy for one-day arcs in cislunar
        space; compare :func:`process_noise_lyapunov`).

    Returns
    -------
    ndarray, shape (m-1, 6, 6) or (n, m-1, 6, 6)
        :math:`Q_k` in LU^2, LU^2/TU, (LU/TU)^2 blocks.
    """
    _check_system(system)
    x = validation.as_array(x, "x", ndim=(2, 3), last=6)
    t = validation.time_grid(t, "t", increasing=True)
    if x.shape[-2] != t.size:
        raise ValueError(f"x must hold one state per time of t ({t.size}); got shape {x.shape}")
    q = validation.positive(q, "q", allow_zero=True)
    n_nodes = validation.integer(n_nodes, "n_nodes", minimum=2)
    single = x.ndim == 2
    xs = x[None] if single else x
    n, m = xs.shape[0], xs.shape[1]
    starts = xs[:, :-1].reshape(-1, 6)
    dts = np.tile(np.diff(t), n)
    _, Qd, _ = _interval_transitions(system, starts, dts, q, int(n_nodes), 1, xs[:, 1:].reshape(-1, 6))
    Qd = Qd.reshape(n, m - 1, 6, 6)
    return Qd[0] if single else Qd


def process_noise_lyapunov(system: CR3BP, x0, dt: float, q: float, *, rtol: float = 1e-12,
                           atol: float = 1e-16) -> np.ndarray:
    """Reference :math:`Q` over one interval by integrating :math:`\\dot Q = A(t)Q + QA(t)^T + qGG^T` with scipy.

    ``x0`` (6,) is the reference state at the start, ``dt`` (TU) the interval, ``q`` the PSD in LU^2/TU^3.
    Independent of heyoka: DOP853 on the state and the full 6x6 Q (42 equations).  A start inside a primary or a
    reference trajectory that reaches the surface of the Moon or the Earth raises
    :class:`cislunar.cr3bp.propagation.ImpactError` (terminal ``solve_ivp`` events on the squared distances).
    """

    _check_system(system)
    x0 = validation.as_state(x0, "x0", batch=False)
    dt = validation.positive(dt, "dt")
    q = validation.positive(q, "q", allow_zero=True)
    rtol = validation.in_range(rtol, "rtol", 1e-16, 1e-2)
    atol = validation.in_range(atol, "atol", 1e-20, 1e-2)
    check_outside_primaries(system, x0, "x0")
    W = np.zeros((6, 6))
    W[3:, 3:] = q * np.eye(3)

    def rhs(_t, y):
        xs = y[:6]
        Q = y[6:].reshape(6, 6)
        A = system.jacobian(xs)
        return np.concatenate([system.eom(xs), (A @ Q + Q @ A.T + W).ravel()])

    sol = solve_ivp(rhs, (0.0, dt), np.r_[x0, np.zeros(36)], method="DOP853", rtol=rtol, atol=atol,
                    events=scipy_impact_events(system))
    raise_scipy_impact(sol)
    if not sol.success:  # pragma: no cover
        raise RuntimeError(f"solve_ivp failed: {sol.message}")
    return symmetrize(sol.y[6:, -1].reshape(6, 6))


# --------------------------------------------------------------------------------------------------------------
# EKF covariance recursion
# --------------------------------------------------------------------------------------------------------------
def ekf_predict(P, F, Q) -> np.ndarray:
    """Covariance time update :math:`\\bar P = F P F^T + Q` (broadcast over leading axes).

    Raises ``ValueError`` naming the argument when ``P`` is not symmetric positive definite, ``Q`` not symmetric
    positive semi-definite, or the shapes do not match.
    """
    P = check_spd(P, "P")
    F = validation.as_array(F, "F", min_size=1)
    Q = check_psd(Q, "Q")
    n = P.shape[-1]
    if F.ndim < 2 or F.shape[-2:] != (n, n) or Q.shape[-1] != n:
        raise ValueError(f"F and Q must be ({n}, {n}) to match P; got F {F.shape}, Q {Q.shape}")
    return _ekf_predict(P, F, Q)


def _sym(A):
    """Symmetric part of (..., n, n) arrays (unchecked :func:`symmetrize`)."""
    return 0.5 * (A + np.swapaxes(A, -1, -2))


def _ekf_predict(P, F, Q):
    """:func:`ekf_predict` on checked arrays (the recursion's inner loop)."""
    return _sym(F @ P @ np.swapaxes(F, -1, -2) + Q)


def ekf_update(P, H, R):
    """Joseph-form covariance measurement update.

    Parameters
    ----------
    P : array_like, shape (..., n, n)
        Prior covariance (SPD).
    H : array_like, shape (..., m, n)
        Measurement Jacobian.
    R : array_like, shape (..., m, m)
        Measurement noise covariance (SPD).

    Returns
    -------
    P_post : ndarray (..., n, n)
        :math:`(I-KH)P(I-KH)^T + KRK^T`.
    K : ndarray (..., n, m)
        Kalman gain :math:`PH^TS^{-1}`.
    S : ndarray (..., m, m)
        Innovation covariance :math:`HPH^T + R`.
    """
    P = check_spd(P, "P")
    H = validation.as_array(H, "H", min_size=1)
    R = _square(R, "R")
    n = P.shape[-1]
    if H.ndim < 2 or H.shape[-1] != n:
        raise ValueError(f"H must have shape (..., m, {n}) to match P; got {H.shape}")
    m = H.shape[-2]
    if R.shape[-1] != m:
        raise ValueError(f"R must be ({m}, {m}) to match H; got {R.shape}")
    _spd(R, "R")
    return _ekf_update(P, H, R)


def _ekf_update(P, H, R):
    """:func:`ekf_update` on checked arrays (the recursion's inner loop); raises ValueError if S is not SPD."""
    n = P.shape[-1]
    HT = np.swapaxes(H, -1, -2)
    S = _sym(H @ P @ HT + R)
    L = _cholesky(S, "S (innovation covariance)")
    # K^T = S^{-1} H P via two triangular solves
    HP = H @ P
    KT = np.linalg.solve(np.swapaxes(L, -1, -2), np.linalg.solve(L, HP))
    K = np.swapaxes(KT, -1, -2)
    IKH = np.eye(n) - K @ H
    P_post = _sym(IKH @ P @ np.swapaxes(IKH, -1, -2) + K @ R @ np.swapaxes(K, -1, -2))
    return P_post, K, S


@dataclass(frozen=True)
class CovarianceHistory:
    """Output of :func:`covariance_analysis`.

    Attributes
    ----------
    prior : ndarray (N, n, n)
        :math:`\\bar P_k` before the measurement at :math:`t_k` (``prior[0]`` is the initial covariance).
    posterior : ndarray (N, n, n)
        :math:`\\hat P_k` after it: the CRLB of the augmented state at :math:`t_k`.
    innovation : ndarray (N, M, M)
        :math:`S_k = H_k\\bar P_kH_k^T + R_k`.
    """

    prior: np.ndarray
    posterior: np.ndarray
    innovation: np.ndarray


def _as_sequence(arr, name, count, shape, context: str = ""):
    a = validation.as_array(arr, name)
    if a.shape == shape:
        return np.broadcast_to(a, (count,) + shape)
    if a.shape != (count,) + shape:
        raise ValueError(f"{name} must have shape {(count,) + shape} or {shape}{context}; got {a.shape}")
    return a


def covariance_analysis(P0, F, Q, H, R) -> CovarianceHistory:
    """EKF covariance recursion (CRLB along a given linearisation), measurements at every time ``t_0..t_{N-1}``.

    Parameters
    ----------
    P0 : array_like (n, n)
        Covariance at the first measurement time (SPD).
    F : array_like (N-1, n, n)
        Transition matrices :math:`\\Phi(t_{k+1}, t_k)`.
    Q : array_like (N-1, n, n) or (n, n)
        Process noise over each interval (symmetric positive semi-definite).
    H : array_like (N, M, n)
        Measurement Jacobians.
    R : array_like (N, M, M) or (M, M)
        Measurement noise covariances (SPD).

    Returns
    -------
    CovarianceHistory
    """
    P0, F, Q, H, R = _check_linear_system(P0, F, Q, H, R)  # checked once here; the loop calls the kernels
    N = H.shape[0]
    prior = np.empty((N,) + P0.shape)
    post = np.empty_like(prior)
    S = np.empty((N, H.shape[1], H.shape[1]))
    P = P0
    for k in range(N):
        if k > 0:
            P = _ekf_predict(P, F[k - 1], Q[k - 1])
        prior[k] = P
        P, _, S[k] = _ekf_update(P, H[k], R[k])
        post[k] = P
    return CovarianceHistory(prior, post, S)


#: The last few checked ``(P0, Q, R)`` of :func:`_check_linear_system`: ``((N, M), inputs, outputs)``, most recent
#: first.  Callers that evaluate many windows (the SCvx information models, their Hessians) hold them fixed and
#: change only F and H, so the SPD / PSD checks and R's Cholesky factors run once per window.
_CHECKED_NOISE: list = []
_CHECKED_NOISE_SIZE = 4


def _same_array(a, b) -> bool:
    return type(a) is np.ndarray and a.dtype == b.dtype and a.shape == b.shape and np.array_equal(a, b)


def _checked_noise(P0, Q, R, H):
    """Cached checked ``(P0, Q, R, LR)`` for inputs equal entry by entry to ones checked before (else None)."""
    if type(H) is not np.ndarray or H.ndim != 3:
        return None
    key = H.shape[:2]
    for k, raw, out in _CHECKED_NOISE:
        if k == key and all(_same_array(a, b) for a, b in zip((P0, Q, R), raw)):
            return out
    return None


def _check_linear_system(P0, F, Q, H, R, *, chol_R: bool = False):
    """Validate the matrices of a linear-Gaussian measurement sequence (shared with :mod:`cislunar.sensing.information`).

    Returns ``(P0, F, Q, H, R)`` as float arrays (Q, R broadcast to sequences), plus the Cholesky factors of R
    when ``chol_R``.  ``P0``, ``Q`` and ``R`` equal (entry by entry) to ones checked in one of the last few calls
    are not checked again: the same read-only arrays are returned, so values are bit-for-bit those of a full check.
    """
    hit = _checked_noise(P0, Q, R, H)
    if hit is not None:
        P0c, Qc, Rc, LRc = hit
        H = validation.as_array(H, "H", ndim=(3,))
        if H.shape[-1] != P0c.shape[0]:
            raise ValueError(f"H must have shape (N, M, {P0c.shape[0]}) to match P0; got {H.shape}")
        N, n = H.shape[0], P0c.shape[0]
        F = validation.as_array(F, "F")
        if N == 1 and F.size == 0:
            F = np.zeros((0, n, n))
        F = _as_sequence(F, "F", N - 1, (n, n), f" (N - 1 intervals from H {H.shape}, n from P0 {P0c.shape})")
        return (P0c, F, Qc, H, Rc, LRc) if chol_R else (P0c, F, Qc, H, Rc)
    raw = tuple(np.array(a, copy=True) if type(a) is np.ndarray else None for a in (P0, Q, R))
    P0 = check_spd(P0, "P0")
    if P0.ndim != 2:
        raise ValueError(f"P0 must be a single (n, n) matrix; got {P0.shape}")
    n = P0.shape[0]
    H = validation.as_array(H, "H", ndim=(3,))
    if H.shape[-1] != n:
        raise ValueError(f"H must have shape (N, M, {n}) to match P0; got {H.shape}")
    N, M = H.shape[0], H.shape[1]
    if N < 1 or M < 1:
        raise ValueError(f"H must hold at least one measurement time and component (N, M >= 1); got {H.shape}")
    ctx = f" (N - 1 intervals from H {H.shape}, n from P0 {P0.shape})"
    F = validation.as_array(F, "F")
    if N == 1 and F.size == 0:
        F = np.zeros((0, n, n))
    F = _as_sequence(F, "F", N - 1, (n, n), ctx)
    Q, R, LR = _check_q_r(Q, R, N, M, n, ctx, f" (N, M from H {H.shape})")
    if all(a is not None for a in raw):
        out = (P0, np.array(Q, copy=True), R, LR)
        for a in out:
            a.flags.writeable = False
        _CHECKED_NOISE.insert(0, ((N, M), raw, out))
        del _CHECKED_NOISE[_CHECKED_NOISE_SIZE:]
        P0, Q, R, LR = out
    return (P0, F, Q, H, R, LR) if chol_R else (P0, F, Q, H, R)


def _check_q_r(Q, R, N: int, M: int, n: int, ctx_q: str = "", ctx_r: str = ""):
    """The process- and measurement-noise checks of :func:`_check_linear_system` for N times, M measurements and n
    states: ``Q`` (N-1, n, n) or (n, n) symmetric PSD, ``R`` (N, M, M) or (M, M) SPD.  Returns ``(Q, R, LR)``
    (symmetric parts as sequences, LR the lower Cholesky factors of R)."""
    Q = _as_sequence(Q, "Q", N - 1, (n, n), ctx_q) if np.size(Q) else np.zeros((0, n, n))
    if N > 1:
        Qs = _sym(Q)
        if np.max(np.abs(Q - Qs)) > 1e-8 * max(np.max(np.abs(Q)), 1e-300):
            raise ValueError("Q must be symmetric")
        # PSD test: Q + jitter I must admit a Cholesky factor (jitter 1e-10 of the largest diagonal entry)
        d = np.diagonal(Qs, axis1=-2, axis2=-1)
        if np.any(d < 0):
            raise ValueError("Q must be positive semi-definite (negative diagonal entry)")
        jitter = 1e-10 * np.maximum(np.max(d, axis=-1), 1e-300)
        try:
            np.linalg.cholesky(Qs + jitter[:, None, None] * np.eye(n))
        except np.linalg.LinAlgError as exc:
            raise ValueError("Q must be positive semi-definite") from exc
        Q = Qs
    R = _as_sequence(R, "R", N, (M, M), ctx_r)
    _spd(R[0] if R.strides[0] == 0 else R, "R")  # a broadcast (M, M) R is checked once
    R = _sym(R)
    LR = _cholesky(R, "R")
    return Q, R, LR


def position_sigma_km(P, index: int, system: CR3BP, *, axes=(0, 1, 2)) -> np.ndarray:
    """RMS position error :math:`\\sqrt{\\sum_a P_{aa}}` (km) of object ``index`` (0 = observer) in augmented
    covariances ``(..., n, n)``, summed over the rotating-frame position ``axes`` (default all three: the trace of
    :math:`P_{rr}`; ``(0, 1)`` gives the in-plane RMS, ``(2,)`` the out-of-plane sigma)."""
    P = validation.psd(P, "P", batch=True)  # a negative covariance would give NaN (round-off negatives pass)
    _check_system(system)
    i = validation.integer(index, "index", minimum=0)
    if 6 * (i + 1) > P.shape[-1]:
        raise ValueError(f"index must select an object in 0..{P.shape[-1] // 6 - 1}; got {index}")
    if isinstance(axes, (str, bytes)) or not hasattr(axes, "__iter__"):
        raise validation.ArgumentTypeError(f"axes must be a sequence of position axes (0, 1, 2); got {axes!r}")
    ax = [validation.integer(a, "axes", minimum=0, maximum=2) for a in axes]
    if not ax or len(set(ax)) != len(ax):
        raise ValueError(f"axes must hold distinct position axes among 0, 1, 2; got {axes!r}")
    idx = [6 * i + a for a in ax]
    return np.sqrt(np.sum(P[..., idx, idx], axis=-1)) * system.length_unit_km


# --------------------------------------------------------------------------------------------------------------
# linearisation of an observer / N-target measurement sequence along true trajectories
# --------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class AugmentedLinearization:
    """Linear-Gaussian description of an observation window (Wolf & Jones Eqs. 19-23 ingredients).

    Measurements of every target are taken at every time ``t[k]``, k = 0..N-1 (``t[0]`` is the start of the
    observation window, where ``P0`` applies).

    Attributes
    ----------
    t : ndarray (N,)
        Measurement times, TU.
    observer : ndarray (N, 6)
        Observer states at ``t``.
    targets : ndarray (N_T, N, 6)
        Target states at ``t``.
    P0 : ndarray (n, n)
        Augmented covariance at ``t[0]``, n = 6 (N_T + 1).
    F : ndarray (N-1, n, n)
        :math:`\\Phi_{\\mathcal A}(t_{k+1}, t_k)` (block diagonal, Eq. 22).
    Q : ndarray (N-1, n, n)
        :math:`Q_{\\mathcal A,k+1}` (block diagonal).
    H : ndarray (N, M, n)
        :math:`H_{\\mathcal A,k}` (Eq. 21), M = m N_T.
    R : ndarray (N, M, M)
        :math:`R_{\\mathcal A,k}` (block diagonal).
    dF : ndarray (N-1, n, n, 6) or None
        :math:`\\partial F_k/\\partial\\mathbf x_{\\mathcal S}(t_0)` (from the observer's second-order STT).
    dH : ndarray (N, M, n, 6) or None
        :math:`\\partial H_k/\\partial\\mathbf x_{\\mathcal S}(t_0)` (measurement Hessians times the STM).
    observer_stm : ndarray (N, 6, 6)
        :math:`\\Phi_{\\mathcal S}(t_k, t_0)`.
    """

    t: np.ndarray
    observer: np.ndarray
    targets: np.ndarray
    P0: np.ndarray
    F: np.ndarray
    Q: np.ndarray
    H: np.ndarray
    R: np.ndarray
    dF: np.ndarray | None
    dH: np.ndarray | None
    observer_stm: np.ndarray

    @property
    def n_targets(self) -> int:
        return self.targets.shape[0]

    @property
    def arrays(self):
        """``(P0, F, Q, H, R)`` for the functions of :mod:`cislunar.sensing.information`."""
        return self.P0, self.F, self.Q, self.H, self.R


@dataclass(frozen=True)
class ObjectArcs:
    """Ballistic arcs of K objects on a common grid, with per-interval transitions (building block of
    :func:`linearize_augmented`; lets a caller propagate fixed targets once and re-linearise only the observer).

    Attributes
    ----------
    t : ndarray (N,)
        Grid times, TU.
    x : ndarray (K, N, 6)
        States at ``t``.
    F : ndarray (K, N-1, 6, 6)
        :math:`\\Phi(t_{k+1}, t_k)` of each object.
    Q : ndarray (K, N-1, 6, 6) or None
        Process noise over each interval (when a PSD was given).
    stt : ndarray (K, N-1, 6, 6, 6) or None
        Second-order STT of each interval with respect to the interval's start state (``order=2``).
    """

    t: np.ndarray
    x: np.ndarray
    F: np.ndarray
    Q: np.ndarray | None
    stt: np.ndarray | None

    @property
    def stm_from_start(self) -> np.ndarray:
        """:math:`\\Phi(t_k, t_0)` of each object, (K, N, 6, 6): running product of the interval STMs."""
        K, N = self.x.shape[0], self.t.size
        out = np.empty((K, N, 6, 6))
        out[:, 0] = np.eye(6)
        for k in range(1, N):
            out[:, k] = self.F[:, k - 1] @ out[:, k - 1]
        return out


def propagate_arcs(system: CR3BP, x0, t, *, q: float | None = None, order: int = 1,
                   n_nodes: int = 12) -> ObjectArcs:
    """Propagate K objects from ``t[0]`` over the grid ``t``; interval STMs (order 1) or STMs and STTs (order 2).

    Parameters
    ----------
    system : CR3BP
    x0 : array_like (K, 6) or (6,)
        States at ``t[0]``.
    t : array_like (N,)
        Strictly increasing times, TU (N >= 2).
    q : float, optional
        Acceleration PSD (LU^2/TU^3); if given the exact process noise of every interval is computed too.
    order : {1, 2}
    n_nodes : int
        Quadrature nodes per interval for the process noise.
    """

    _check_system(system)
    x0 = validation.as_array(x0, "x0", last=6)
    if x0.ndim == 1:
        x0 = x0[None]
    if x0.ndim != 2:
        raise ValueError(f"x0 must have shape (K, 6) or (6,); got {x0.shape}")
    t = validation.time_grid(t, "t", increasing=True)
    order = validation.integer(order, "order", minimum=1, maximum=2)
    qq = None if q is None else validation.positive(q, "q", allow_zero=True)
    n_nodes = validation.integer(n_nodes, "n_nodes", minimum=2)
    return _propagate_arcs(system, x0, t, qq, order, n_nodes)


def _propagate_arcs(system, x0, t, qq, order, n_nodes) -> ObjectArcs:
    """:func:`propagate_arcs` on checked arguments (``x0`` (K, 6), ``t`` increasing, ``qq`` float or None)."""
    K, N = x0.shape[0], t.size
    X = propagate(system, x0, t).x
    X = X if X.ndim == 3 else X[None]
    starts = X[:, :-1].reshape(-1, 6)
    dts = np.tile(np.diff(t), K)
    # batch lanes sorted by step count (the SCvx Hessian's 12 perturbed observers: lanes = perturbations); the
    # results are bit-identical to the given order's
    F, Qd, Psi = _interval_transitions(system, starts, dts, qq, int(n_nodes), order, X[:, 1:].reshape(-1, 6))
    return ObjectArcs(t=t, x=X, F=F.reshape(K, N - 1, 6, 6),
                      Q=None if Qd is None else Qd.reshape(K, N - 1, 6, 6),
                      stt=None if Psi is None else Psi.reshape(K, N - 1, 6, 6, 6))


def assemble_augmented(model: MeasurementModel, noise, P0, observer: ObjectArcs, targets: ObjectArcs, *,
                       Q=None, index: int = 0) -> AugmentedLinearization:
    """Augmented linearisation (Eqs. 19-23 ingredients) from already propagated observer and target arcs.

    Parameters
    ----------
    model : MeasurementModel
    noise : array_like (m, m) or callable
        As in :func:`linearize_augmented`.
    P0 : array_like (n, n)
        Augmented covariance at ``t[0]``.
    observer : ObjectArcs
        Arcs of one or more observer candidates; ``index`` selects one.  With ``stt`` present, the derivatives
        ``dF``, ``dH`` with respect to the observer state at ``t[0]`` are filled in.
    targets : ObjectArcs
        Arcs of the N_T targets on the same grid.
    Q : array_like (N-1, n, n), optional
        Fixed augmented process noise; default: block diagonal of the arcs' own ``Q``.
    index : int
        Which observer arc to use.
    """
    validation.instance(model, "model", MeasurementModel)
    validation.instance(observer, "observer", ObjectArcs)
    validation.instance(targets, "targets", ObjectArcs)
    if observer.t.shape != targets.t.shape or not np.array_equal(observer.t, targets.t):
        raise ValueError("observer and targets arcs must share the same time grid")
    t = observer.t
    NT, N, m = targets.x.shape[0], t.size, model.dim
    n = 6 * (NT + 1)
    P0 = check_spd(validation.as_array(P0, "P0", shape=(n, n)), "P0")
    i = validation.integer(index, "index", minimum=0, maximum=observer.x.shape[0] - 1)
    if Q is not None:
        Q = _as_sequence(Q, "Q", N - 1, (n, n))
        check_psd(Q, "Q")
    if not callable(noise):
        noise = _spd(validation.as_array(noise, "noise", shape=(m, m)), "noise")
    return _assemble(model, noise, P0, observer, targets, Q, i)


class WindowAssembler:
    """:func:`assemble_augmented` for many observer candidates of one window, the fixed ingredients checked once.

    An optimiser that moves only the observer (the SCvx information models of Wolf & Jones) re-linearises the same
    window many times with the same measurement model, noise, prior, target arcs and fixed process noise; here
    those are validated once, at construction, and each call checks only the observer arcs.  Calls return exactly
    (bit for bit) what :func:`assemble_augmented` returns for the same arguments.

    Parameters
    ----------
    model : MeasurementModel
    noise : array_like (m, m) or callable
        As in :func:`assemble_augmented` (a callable's output is checked on every call).
    P0 : array_like (n, n)
        Augmented covariance at ``t[0]`` (SPD), n = 6 (N_T + 1).
    targets : ObjectArcs
        Arcs of the N_T targets (their grid is the window's).
    Q : array_like (N-1, n, n) or (n, n), optional
        Fixed augmented process noise (symmetric PSD); default: block diagonal of the arcs' own ``Q``.
    """

    def __init__(self, model: MeasurementModel, noise, P0, targets: ObjectArcs, *, Q=None):
        self.model = validation.instance(model, "model", MeasurementModel)
        self.targets = validation.instance(targets, "targets", ObjectArcs)
        NT, N, m = targets.x.shape[0], targets.t.size, model.dim
        n = 6 * (NT + 1)
        self.P0 = check_spd(validation.as_array(P0, "P0", shape=(n, n)), "P0")
        self.P0.flags.writeable = False  # shared by every linearisation
        if Q is not None:
            Q = _as_sequence(Q, "Q", N - 1, (n, n))
            check_psd(Q, "Q")
        self.Q = Q
        self.noise = noise if callable(noise) else _spd(validation.as_array(noise, "noise", shape=(m, m)), "noise")

    def __call__(self, observer: ObjectArcs, index: int = 0) -> AugmentedLinearization:
        """The :class:`AugmentedLinearization` of observer arc ``index`` of ``observer`` (on the targets' grid)."""
        validation.instance(observer, "observer", ObjectArcs)
        t = self.targets.t
        if observer.t.shape != t.shape or not np.array_equal(observer.t, t):
            raise ValueError("observer and targets arcs must share the same time grid")
        i = validation.integer(index, "index", minimum=0, maximum=observer.x.shape[0] - 1)
        return _assemble(self.model, self.noise, self.P0, observer, self.targets, self.Q, i)


def _assemble(model, noise, P0, observer, targets, Q, i) -> AugmentedLinearization:
    """:func:`assemble_augmented` on checked arguments (``P0`` symmetrised, ``noise`` a checked (m, m) array or a
    callable whose output is checked here, ``Q`` a checked sequence or None, ``i`` the observer index)."""
    t = observer.t
    NT, N, m = targets.x.shape[0], t.size, model.dim
    n = 6 * (NT + 1)
    obs = observer.x[i]
    tgts = targets.x
    Fo = observer.F[i]
    F = _block_diag(np.moveaxis(np.concatenate([Fo[None], targets.F], axis=0), 0, 1))
    if Q is None:
        if observer.Q is None or targets.Q is None:
            raise ValueError("give Q, or arcs propagated with a process-noise PSD q")
        Qa = _block_diag(np.moveaxis(np.concatenate([observer.Q[i][None], targets.Q], axis=0), 0, 1))
    else:
        Qa = Q
    stm = np.empty((N, 6, 6))
    stm[0] = np.eye(6)
    for k in range(1, N):
        stm[k] = Fo[k - 1] @ stm[k - 1]
    _, Hs, Ht = model._evaluate(obs[None], tgts)  # (NT, N, m, 6)
    H = np.zeros((N, NT * m, n))
    for j in range(NT):
        H[:, j * m:(j + 1) * m, 0:6] = Hs[j]
        H[:, j * m:(j + 1) * m, 6 * (j + 1):6 * (j + 2)] = Ht[j]
    if callable(noise):  # a user's function: its output is checked on every call
        Rt = validation.as_array(noise(obs[None], tgts), "noise(observer, target)", shape=(NT, N, m, m))
        R = _block_diag(np.moveaxis(Rt, 0, 1))
        check_spd(R, "noise")
    else:  # checked by the caller (identical blocks: their block diagonal is SPD exactly when the block is)
        R = _block_diag(np.moveaxis(np.broadcast_to(noise, (NT, N, m, m)), 0, 1))
    dF = dH = None
    if observer.stt is not None:
        Psi = observer.stt[i]
        dF = np.zeros((N - 1, n, n, 6))
        dF[:, 0:6, 0:6, :] = np.einsum("kabd,kdc->kabc", Psi, stm[:-1])
        hess = model._hessian(obs[None], tgts)  # (NT, N, m, 6, 6): d2h/ddelta2
        # dH_obs/dx_S = +hess, dH_tgt/dx_S = -hess (delta = x_T - x_S); chain with Phi_S(t_k, t_0)
        dhx = np.einsum("ikabd,kdc->ikabc", hess, stm)
        dH = np.zeros((N, NT * m, n, 6))
        for j in range(NT):
            dH[:, j * m:(j + 1) * m, 0:6, :] = dhx[j]
            dH[:, j * m:(j + 1) * m, 6 * (j + 1):6 * (j + 2), :] = -dhx[j]
    return AugmentedLinearization(t=t, observer=obs, targets=tgts, P0=P0, F=F, Q=Qa, H=H, R=R, dF=dF, dH=dH,
                                  observer_stm=stm)


def linearize_augmented(system: CR3BP, observer_x0, targets_x0, t, model: MeasurementModel, noise, P0, *,
                        q: float | None = None, Q=None, derivatives: bool = False,
                        n_nodes: int = 12) -> AugmentedLinearization:
    """Propagate observer and targets from ``t[0]`` and linearise the measurement sequence along them.

    Parameters
    ----------
    system : CR3BP
    observer_x0 : array_like (6,)
        Observer state at ``t[0]`` (the start of the observation window), LU, LU/TU.
    targets_x0 : array_like (N_T, 6)
        Target states at ``t[0]``.
    t : array_like (N,)
        Strictly increasing measurement times, TU (N >= 2).
    model : MeasurementModel
        Measurement taken by the observer of each target at every time.
    noise : array_like (m, m) or callable
        Noise covariance of one measurement (non-dimensional), or ``noise(observer, target) -> (..., m, m)``
        (e.g. a range-dependent angular model built on :func:`cislunar.sensing.measurements.angles_noise`).
    P0 : array_like (n, n)
        Augmented covariance at ``t[0]``.
    q : float, optional
        Acceleration PSD (LU^2/TU^3) of every object; :math:`Q_{\\mathcal A}` is computed along the trajectories
        with :func:`process_noise`.  Exclusive with ``Q``.
    Q : array_like (N-1, n, n), optional
        Given augmented process noise (held fixed, e.g. when differentiating with respect to the observer, as in
        Wolf & Jones who neglect the sensitivity of :math:`\\tilde P` to the observer state).
    derivatives : bool
        Also compute ``dF`` and ``dH`` with respect to the observer state at ``t[0]`` (second-order STT).
    n_nodes : int
        Quadrature nodes per interval for the process noise.

    Returns
    -------
    AugmentedLinearization

    Notes
    -----
    Transition matrices are propagated interval by interval from the reference states (no inversion of long-arc
    STMs); :math:`\\Phi_{\\mathcal S}(t_k, t_0)` is their running product.  The noise covariance is treated as
    independent of the states in ``dH`` (exact for constant noise; for range-dependent angular noise the
    sensitivity of R is neglected, like that of :math:`\\tilde P` in the paper).  Built from
    :func:`propagate_arcs` and :func:`assemble_augmented`.
    """
    _check_system(system)
    validation.instance(model, "model", MeasurementModel)
    xs0 = validation.as_state(observer_x0, "observer_x0", batch=False)
    xt0 = validation.as_array(targets_x0, "targets_x0", last=6)
    if xt0.ndim == 1:
        xt0 = xt0[None]
    if xt0.ndim != 2 or xt0.shape[0] < 1:
        raise ValueError(f"targets_x0 must have shape (N_T, 6); got {xt0.shape}")
    t = validation.time_grid(t, "t", increasing=True)
    n = 6 * (xt0.shape[0] + 1)
    P0 = check_spd(validation.as_array(P0, "P0", shape=(n, n)), "P0")
    if q is not None:
        q = validation.positive(q, "q", allow_zero=True)
    if Q is not None:
        Q = _as_sequence(Q, "Q", t.size - 1, (n, n))
        check_psd(Q, "Q")
    if (q is None) == (Q is None):
        raise ValueError("give exactly one of q (process-noise PSD) and Q (discrete process noise)")
    derivatives = validation.boolean(derivatives, "derivatives")
    n_nodes = validation.integer(n_nodes, "n_nodes", minimum=2)
    if not callable(noise):
        noise = _spd(validation.as_array(noise, "noise", shape=(model.dim, model.dim)), "noise")
    obs = _propagate_arcs(system, xs0[None], t, q, 2 if derivatives else 1, n_nodes)
    tgt = _propagate_arcs(system, xt0, t, q, 1, n_nodes)
    return _assemble(model, noise, P0, obs, tgt, Q, 0)
