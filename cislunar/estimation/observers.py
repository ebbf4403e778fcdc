r"""Simulation of the LPV observer (Nychka & Bhattacharya 2024, Eq. 3a) and of an EKF on the nonlinear CR3BP.

Frame, units and state are those of :mod:`cislunar.estimation.lpv`: planar rotating-frame state ``[x, y, vx, vy]`` in LU and
LU/TU, time in TU.  The truth is propagated with :func:`cislunar.cr3bp.propagation.propagate` (heyoka); measurements are
the angles :math:`\theta_1` (at the Earth) and :math:`\theta_2` (at the Moon) with additive white Gaussian noise
sampled on the truth grid and held constant between samples (zero-order hold).

LPV observer
------------
.. math:: \dot{\hat x} = (A(\rho) + LC(\rho))\hat x - L y + b(\rho) + L d(\rho),

with :math:`y = [\sin\tilde\theta_1, \cos\tilde\theta_1, \sin\tilde\theta_2, \cos\tilde\theta_2,
\tilde r_{13}^2, \tilde r_{23}^2]` built from the noisy angles (the ranges by triangulation; their gain columns
are zero in the sparse designs) and :math:`\rho` obtained by triangulating the noisy angles
(:meth:`CR3BPLPV.rho_from_angles`), except where :math:`|\sin\theta_3| < 0.04` (spacecraft near the Earth-Moon
line), where :math:`\rho(\hat x)` from the current estimate is used, as in the paper.  Integrated with fixed-step
RK4 (``substeps`` per measurement interval): wherever the three stages of a step are scheduled on measured (not
estimated) :math:`\rho` the observer is linear in :math:`\hat x`, so those steps are precomputed, all at once, as
the affine maps :math:`\hat x \mapsto \Phi\hat x + g` of the RK4 step (the same arithmetic, to rounding), and only the
steps near the Earth-Moon line are integrated one by one.

EKF (beyond the paper)
----------------------
Continuous-discrete extended Kalman filter on the same noisy angles: RK4 propagation of the state and of the
covariance through the planar CR3BP Jacobian (:meth:`CR3BP.jacobian`), process noise
:math:`Q = B_d S_d S_d^T B_d^T\,\Delta t`, measurement :math:`h(x) = [\theta_1, \theta_2]` with wrapped innovations
and Joseph-form update.

Impacts
-------
The truth is an input (propagated by the caller with :func:`cislunar.cr3bp.propagation.propagate`, which refuses
impacts); the fixed-step RK4 loops here integrate *estimates*, not trajectories, so they carry no surface events.
An estimate driven through a primary is a filter failure, not an impact: it shows up in the reported estimation
error, and a non-finite estimate raises ``RuntimeError`` naming the step (both simulators check every step).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cislunar.estimation.lpv import CR3BPLPV
from cislunar.utils import validation

__all__ = ["Measurements", "ObserverRun", "make_measurements", "simulate_ekf", "simulate_lpv_observer"]


@dataclass(frozen=True)
class Measurements:
    """Noisy angle measurements on a time grid.

    Attributes
    ----------
    t : ndarray (m,)
        Times, TU.
    theta1, theta2 : ndarray (m,)
        Noisy angles at the Earth and at the Moon, rad.
    sigma : float
        Noise standard deviation of each angle, rad.
    """

    t: np.ndarray
    theta1: np.ndarray
    theta2: np.ndarray
    sigma: float

    def __post_init__(self):
        t = validation.time_grid(self.t, "t", increasing=True)
        th1 = validation.as_array(self.theta1, "theta1", shape=t.shape)
        th2 = validation.as_array(self.theta2, "theta2", shape=t.shape)
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "theta1", th1)
        object.__setattr__(self, "theta2", th2)
        object.__setattr__(self, "sigma", validation.positive(self.sigma, "sigma", allow_zero=True))


@dataclass(frozen=True)
class ObserverRun:
    """Estimate history of one observer run.

    Attributes
    ----------
    t : ndarray (m,)
        Times, TU.
    x_hat : ndarray (m, 4)
        Estimates, LU and LU/TU.
    error : ndarray (m, 4)
        ``truth - x_hat``.
    position_error : ndarray (m,)
        Euclidean position error, LU.
    rho_from_estimate : ndarray of bool (m,)
        Samples where :math:`|\\sin\\theta_3|` was below the threshold and :math:`\\rho(\\hat x)` was used.
    """

    t: np.ndarray
    x_hat: np.ndarray
    error: np.ndarray
    position_error: np.ndarray
    rho_from_estimate: np.ndarray


def make_measurements(model: CR3BPLPV, t, truth, sigma_deg: float, rng: np.random.Generator) -> Measurements:
    """Angles :math:`\\theta_1, \\theta_2` of planar ``truth`` (m, 4) plus N(0, sigma^2) noise (``sigma_deg`` in deg)."""
    model = validation.instance(model, "model", CR3BPLPV)
    rng = validation.rng(rng, "rng")
    t = validation.time_grid(t, "t", increasing=True)
    x = validation.as_array(truth, "truth", shape=(t.size, 4))
    sigma = np.radians(validation.positive(sigma_deg, "sigma_deg", allow_zero=True))
    t1, t2 = model._angles(x)
    n = rng.standard_normal((2, t.size)) * sigma
    return Measurements(t, t1 + n[0], t2 + n[1], float(sigma))


def _measurement_vector(model: CR3BPLPV, th1, th2, singular):
    """Measurement vector and triangulated rho; NaN where ``singular`` (the caller uses the estimate there)."""
    rho = np.full(th1.shape + (6,), np.nan)
    ok = ~singular
    rho[ok] = model._rho_from_angles(th1[ok], th2[ok])
    r13, r23 = 1.0 / rho[..., 2], 1.0 / rho[..., 3]
    y = np.stack([np.sin(th1), np.cos(th1), np.sin(th2), np.cos(th2), r13**2, r23**2], axis=-1)
    return y, rho


def simulate_lpv_observer(model: CR3BPLPV, L, meas: Measurements, x_hat0, truth, *, sin3_threshold: float = 0.04,
                          substeps: int | None = None, exact_rho: bool = False,
                          hold: str = "noise") -> ObserverRun:
    """Run the LPV observer (Eq. 3a) on noisy measurements.

    Parameters
    ----------
    model : CR3BPLPV
    L : array_like (4, 6)
        Observer gain (paper sign convention).
    meas : Measurements
    x_hat0 : array_like (4,)
        Initial estimate, LU and LU/TU.
    truth : array_like (m, 4)
        True planar states on ``meas.t`` (only used to report errors).
    sin3_threshold : float
        Below this :math:`|\\sin\\theta_3|` the scheduling parameters come from the estimate.
    substeps : int, optional
        RK4 steps per measurement interval; default enough that :math:`h\\,\\|LC\\| \\le 1` with the largest
        measurement matrix on the run (RK4 is stable for :math:`|h\\lambda| < 2.78`), at least 4.
    hold : {"noise", "measurement"}
        ``"noise"`` (default): the sensor is continuous and only its noise is held over each interval, i.e.
        :math:`\\theta(t) = \\theta(x(t)) + n_k` with :math:`x(t)` the cubic Hermite interpolant of ``truth``;
        this is the white-noise model of intensity :math:`\\sigma^2\\Delta t` the H2 conversion assumes.
        ``"measurement"``: the whole measurement is held (a sampled sensor); a high-bandwidth observer then lags
        the truth by about :math:`|\\dot\\theta|\\Delta t`, which acts as extra noise.
    exact_rho : bool
        Diagnostic: schedule on :math:`\\rho` of the true state (held like the measurements) instead of the
        triangulated one, i.e. the situation the LMIs certify.
    """
    model = validation.instance(model, "model", CR3BPLPV)
    meas = validation.instance(meas, "meas", Measurements)
    L = validation.as_array(L, "L", shape=(4, 6))
    xh = validation.as_array(x_hat0, "x_hat0", shape=(4,)).copy()
    truth = validation.as_array(truth, "truth", shape=(meas.t.size, 4))
    thr = validation.in_range(sin3_threshold, "sin3_threshold", 0.0, 1.0)
    exact_rho = validation.boolean(exact_rho, "exact_rho")
    hold = validation.choice(hold, "hold", ("noise", "measurement"))
    if substeps is not None:
        substeps = validation.integer(substeps, "substeps", minimum=1)
    singular = np.abs(np.sin(meas.theta1 + meas.theta2)) < max(thr, 1e-9)
    y_all, rho_all = _measurement_vector(model, meas.theta1, meas.theta2, singular)
    y_singular = singular
    if exact_rho:
        rho_all = model._rho(truth)
        singular = np.zeros_like(singular)
    if substeps is None:
        rho_ok = rho_all[~singular] if np.any(~singular) else model._rho(truth)
        c_max = np.max(np.linalg.norm(model._affine_kernel("C", rho_ok), 2, axis=(-2, -1)))
        rate = np.linalg.norm(L, 2) * c_max + 10.0
        dt_max = float(np.max(np.diff(meas.t))) if meas.t.size > 1 else 0.0
        substeps = max(4, int(np.ceil(dt_max * rate)))
    stage_y, stage_rho, stage_sing = _stages(model, meas, truth, substeps, hold, exact_rho, thr, y_all, rho_all,
                                             y_singular, singular)
    m = meas.t.size
    out = np.empty((m, 4))
    out[0] = xh
    h = np.repeat(np.diff(meas.t) / substeps, substeps)  # (n_steps,)
    Phi = _linear_rk4_maps(model, L, h, stage_y, stage_rho)  # (n_steps, 5, 5); rows of singular steps unused
    step_sing = np.any(stage_sing, axis=1)
    coef = model.affine_coefficients()
    A0, Ai, b0, bi = coef["A"][0], coef["A"][1:], coef["b"][0], coef["b"][1:]
    C0, Ci, d0, di = coef["C"][0], coef["C"][1:], coef["d"][0], coef["d"][1:]
    mu = model.mu

    def rhs(s, y, rho):
        """Observer vector field; ``rho`` NaN: scheduled on the estimate (near the Earth-Moon line)."""
        if np.isnan(rho[0]):
            r13 = np.hypot(s[0] + mu, s[1])
            r23 = np.hypot(s[0] - 1.0 + mu, s[1])
            rho = np.array([r13**-3, r23**-3, 1.0 / r13, 1.0 / r23, s[0], s[1]])
        A = A0 + np.tensordot(rho, Ai, axes=1)
        C = C0 + np.tensordot(rho, Ci, axes=1)
        return (A + L @ C) @ s - L @ y + b0 + rho @ bi + L @ (d0 + rho @ di)

    i = 0
    for k in range(m - 1):
        for _ in range(substeps):
            if step_sing[i]:  # a stage scheduled on the estimate: the step is nonlinear in it
                hi, (ya, yb, yc), (ra, rb, rc) = h[i], stage_y[i], stage_rho[i]
                k1 = rhs(xh, ya, ra)
                k2 = rhs(xh + 0.5 * hi * k1, yb, rb)
                k3 = rhs(xh + 0.5 * hi * k2, yb, rb)
                k4 = rhs(xh + hi * k3, yc, rc)
                xh = xh + hi / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
            else:
                xh = Phi[i, :4, :4] @ xh + Phi[i, :4, 4]
            i += 1
        if not np.all(np.isfinite(xh)):
            raise RuntimeError(f"LPV observer diverged at t = {meas.t[k + 1]:.4f} TU (step {k + 1})")
        out[k + 1] = xh
    err = truth - out
    return ObserverRun(meas.t, out, err, np.hypot(err[:, 0], err[:, 1]), singular)


def _stages(model, meas, truth, substeps, hold, exact_rho, thr, y_all, rho_all, y_singular, singular):
    """Measurement vector, scheduling parameters and singular flag at the three RK4 stage times of every step.

    Returns ``y (n_steps, 3, 6)``, ``rho (n_steps, 3, 6)`` (NaN where the estimate schedules) and ``sing
    (n_steps, 3)``; stages are the start, the midpoint (used by k2 and k3) and the end of each step.
    """
    m = meas.t.size
    n_steps = (m - 1) * substeps
    k = np.repeat(np.arange(m - 1), substeps)
    if hold == "measurement":
        y = np.repeat(np.where(y_singular[:-1, None], np.nan_to_num(y_all[:-1]), y_all[:-1]), substeps, axis=0)
        rho = np.repeat(np.where(singular[:-1, None], np.nan, rho_all[:-1]), substeps, axis=0)
        y, rho = (np.repeat(a[:, None, :], 3, axis=1) for a in (y, rho))
        return y, rho, np.isnan(rho[..., 0])
    t1_true, t2_true = model._angles(truth)
    n1 = np.angle(np.exp(1j * (meas.theta1 - t1_true)))
    n2 = np.angle(np.exp(1j * (meas.theta2 - t2_true)))
    j = np.tile(np.arange(substeps), m - 1)
    hk = (meas.t[1:] - meas.t[:-1])[k]
    u = (j[:, None] + np.array([0.0, 0.5, 1.0])[None, :]) / substeps  # (n_steps, 3) fraction of the interval
    h00, h10, h01, h11 = 2 * u**3 - 3 * u**2 + 1, u**3 - 2 * u**2 + u, -2 * u**3 + 3 * u**2, u**3 - u**2
    pos = (h00[..., None] * truth[k, None, :2] + (h10 * hk[:, None])[..., None] * truth[k, None, 2:]
           + h01[..., None] * truth[k + 1, None, :2] + (h11 * hk[:, None])[..., None] * truth[k + 1, None, 2:])
    a1, a2 = model._angles(pos)
    th1, th2 = a1 + n1[k, None], a2 + n2[k, None]
    y = np.zeros((n_steps, 3, 6))
    y[..., 0], y[..., 1], y[..., 2], y[..., 3] = np.sin(th1), np.cos(th1), np.sin(th2), np.cos(th2)
    if exact_rho:
        return y, model._rho(pos), np.zeros((n_steps, 3), dtype=bool)
    sing = np.abs(np.sin(th1 + th2)) < max(thr, 1e-9)
    rho = np.full((n_steps, 3, 6), np.nan)
    rho[~sing] = model._rho_from_angles(th1[~sing], th2[~sing])
    y[~sing, 4] = 1.0 / rho[~sing, 2] ** 2
    y[~sing, 5] = 1.0 / rho[~sing, 3] ** 2
    return y, rho, sing


def _linear_rk4_maps(model, L, h, y, rho):
    r"""One classical RK4 step of the observer as an affine map, for every step at once.

    With :math:`\rho` and :math:`y` given at the stages the observer is linear, :math:`\dot{\hat x} = M\hat x + c`
    with :math:`M = A(\rho) + LC(\rho)`, :math:`c = b(\rho) + Ld(\rho) - Ly`; the RK4 step is then exactly
    :math:`\hat x \mapsto \Phi\hat x + g`, returned as the augmented ``(n_steps, 5, 5)`` matrices
    ``[[Phi, g], [0, 1]]`` (NaN rows for steps with a stage scheduled on the estimate).
    """
    r = np.nan_to_num(rho)
    M = model._affine_kernel("A", r) + np.einsum("ij,...jk->...ik", L, model._affine_kernel("C", r))
    c = model._affine_kernel("b", r) + np.einsum("ij,...j->...i", L, model._affine_kernel("d", r) - y)
    K = np.zeros(M.shape[:-2] + (5, 5))
    K[..., :4, :4], K[..., :4, 4] = M, c
    eye = np.eye(5)
    hh = h[:, None, None]
    k1 = K[:, 0]
    k2 = K[:, 1] @ (eye + 0.5 * hh * k1)
    k3 = K[:, 1] @ (eye + 0.5 * hh * k2)
    k4 = K[:, 2] @ (eye + hh * k3)
    return eye + hh / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)


def simulate_ekf(model: CR3BPLPV, meas: Measurements, x_hat0, P0, truth, *, sigma_acc: float = 1e-3,
                 substeps: int = 4) -> ObserverRun:
    """Continuous-discrete EKF on the noisy angles (see module notes).

    Parameters
    ----------
    model : CR3BPLPV
    meas : Measurements
    x_hat0 : array_like (4,)
        Initial estimate.
    P0 : array_like (4, 4)
        Initial covariance (LU^2, LU^2/TU, LU^2/TU^2).
    truth : array_like (m, 4)
        True states (for the error report only).
    sigma_acc : float
        Process-noise acceleration intensity, LU/TU^2 per sqrt(TU) (same role as :math:`S_d` in the LMIs).
    substeps : int
        RK4 steps per measurement interval.
    """
    model = validation.instance(model, "model", CR3BPLPV)
    meas = validation.instance(meas, "meas", Measurements)
    xh = validation.as_array(x_hat0, "x_hat0", shape=(4,)).copy()
    P = validation.spd(P0, "P0", n=4).copy()
    truth = validation.as_array(truth, "truth", shape=(meas.t.size, 4))
    q = validation.positive(sigma_acc, "sigma_acc", allow_zero=True)
    substeps = validation.integer(substeps, "substeps", minimum=1)
    R = np.eye(2) * meas.sigma**2
    Qc = np.zeros((4, 4))
    Qc[2, 2] = Qc[3, 3] = q**2
    mu = model.mu
    F = np.zeros((4, 4))
    F[0, 2] = F[1, 3] = 1.0
    F[2, 3], F[3, 2] = 2.0, -2.0

    def deriv(s, P_):
        """Planar CR3BP field and the covariance rate (the planar rows of :meth:`CR3BP.eom`, :meth:`CR3BP.jacobian`)."""
        x, y, vx, vy = s
        dx1, dx2 = x + mu, x - 1.0 + mu
        r1s, r2s = dx1 * dx1 + y * y, dx2 * dx2 + y * y
        c1, c2 = (1.0 - mu) / r1s**1.5, mu / r2s**1.5
        f = np.array([vx, vy, 2.0 * vy + x - c1 * dx1 - c2 * dx2, -2.0 * vx + y - (c1 + c2) * y])
        e1, e2 = 3.0 * c1 / r1s, 3.0 * c2 / r2s
        F[2, 0] = 1.0 - c1 - c2 + e1 * dx1 * dx1 + e2 * dx2 * dx2
        F[3, 1] = 1.0 - c1 - c2 + (e1 + e2) * y * y
        F[2, 1] = F[3, 0] = (e1 * dx1 + e2 * dx2) * y
        FP = F @ P_
        return f, FP + FP.T + Qc

    m = meas.t.size
    out = np.empty((m, 4))

    def update(k, xh, P):
        dx1, dx2 = xh[0] + mu, 1.0 - mu - xh[0]
        y = xh[1]
        r1s, r2s = dx1**2 + y**2, dx2**2 + y**2
        h = np.array([np.arctan2(y, dx1), np.arctan2(y, dx2)])
        H = np.array([[-y / r1s, dx1 / r1s, 0, 0], [y / r2s, dx2 / r2s, 0, 0]])
        nu = np.angle(np.exp(1j * (np.array([meas.theta1[k], meas.theta2[k]]) - h)))
        S = H @ P @ H.T + R
        K = np.linalg.solve(S, H @ P).T
        xh = xh + K @ nu
        IKH = np.eye(4) - K @ H
        P = IKH @ P @ IKH.T + K @ R @ K.T
        return xh, 0.5 * (P + P.T)

    xh, P = update(0, xh, P)
    out[0] = xh
    for k in range(m - 1):
        h = (meas.t[k + 1] - meas.t[k]) / substeps
        for _ in range(substeps):
            f1, p1 = deriv(xh, P)
            f2, p2 = deriv(xh + 0.5 * h * f1, P + 0.5 * h * p1)
            f3, p3 = deriv(xh + 0.5 * h * f2, P + 0.5 * h * p2)
            f4, p4 = deriv(xh + h * f3, P + h * p3)
            xh = xh + h / 6.0 * (f1 + 2 * f2 + 2 * f3 + f4)
            P = P + h / 6.0 * (p1 + 2 * p2 + 2 * p3 + p4)
        xh, P = update(k + 1, xh, P)
        if not np.all(np.isfinite(xh)):
            raise RuntimeError(f"EKF diverged at t = {meas.t[k + 1]:.4f} TU (step {k + 1})")
        out[k + 1] = xh
    err = truth - out
    return ObserverRun(meas.t, out, err, np.hypot(err[:, 0], err[:, 1]), np.zeros(m, dtype=bool))
