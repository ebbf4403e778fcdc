r"""The batched OCBE: the SRI OCBE filter and smoother of :mod:`cislunar.estimation.ocbe` for B trials in lockstep.

All trials share the epochs, observers, measurement model and noise; the transitions of every trial come from one
heyoka batch integrator of the three non-zero 6x6 blocks of the state/costate transition
(:func:`cislunar.estimation.ocbe.block_integrator`), and the square-root-information updates are the stacked kernels
of :mod:`cislunar.estimation.srif` (the same functions the single-trial filter calls, with a leading trial axis).
The result equals the single-trial filter (:func:`cislunar.estimation.ocbe.ocbe_filter_smoother`) to round-off, and
so does the first batched implementation, which integrated the full 12x12 variational system and is kept as a test
oracle in ``tests/estimation/reference_batched_ocbe.py``.

Frames and units: rotating barycentric frame, non-dimensional (LU, TU); controls in LU/TU^2, Eq. 33 in LU/TU.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cislunar.cr3bp.dynamics import CR3BP, check_system
from cislunar.cr3bp.propagation import (
    DEFAULT_TOL,
    ImpactError,
    _check_arcs_outside_primaries,
    _check_tol,
    _inside_primaries,
    check_outside_primaries,
)
from cislunar.estimation import ocbe, srif
from cislunar.utils import validation

__all__ = ["BatchOCBEResult", "ocbe_batch"]


@dataclass(frozen=True)
class BatchOCBEResult:
    """Output of :func:`ocbe_batch`; arrays carry a leading trial axis ``B``.

    Attributes
    ----------
    x_pred, x_filt, x_smooth : ndarray, shape (B, N, 6)
    P_filt, P_smooth : ndarray, shape (B, N, 6, 6)
    t_sub : ndarray, shape (N-1, n_sub)
    control_step, control_smooth : ndarray, shape (B, N-1, n_sub, 3)
        Estimated control (Eq. 32), LU/TU^2.
    z_step, z_smooth : ndarray, shape (B,)
        Eq. 33, LU/TU.
    residual_norms : ndarray, shape (B, N)
    """

    x_pred: np.ndarray
    x_filt: np.ndarray
    P_filt: np.ndarray
    x_smooth: np.ndarray
    P_smooth: np.ndarray
    t_sub: np.ndarray
    control_step: np.ndarray
    control_smooth: np.ndarray
    z_step: np.ndarray
    z_smooth: np.ndarray
    residual_norms: np.ndarray


def ocbe_batch(system: CR3BP, t, y, observer_states, model, meas_cov, x0, P0, control_weight, *, n_sub: int = 9,
               tol: float = DEFAULT_TOL) -> BatchOCBEResult:
    """The extended SRI OCBE filter and full smoother of :func:`cislunar.estimation.ocbe.ocbe_filter_smoother` for B trials.

    Same algorithm, step for step (Eqs. 17, 21-32 and the backward SRI smoother with costates
    :math:`\\mathbf p_{n|N} = \\Phi_{xp}^{-1}\\hat{\\mathbf w}_n`), with all trials sharing the epochs, observers,
    measurement model and noise; the transition blocks of all trials come from heyoka batch integrators
    (:func:`cislunar.estimation.ocbe.block_integrator`, :data:`_LANES` trials each) and the square-root-information
    updates are the stacked kernels of :mod:`cislunar.estimation.srif`.  Each trial's result does not depend on the
    other trials of the batch.

    Parameters
    ----------
    system : CR3BP
    t : array_like, shape (N,)
        Strictly increasing epochs, TU.
    y : array_like, shape (B, N, m)
        Measurements of each trial.
    observer_states : array_like, shape (N, 6)
    model : cislunar.sensing.measurements.MeasurementModel
    meas_cov : array_like, shape (m, m)
        Measurement covariance (shared by all epochs and trials).
    x0 : array_like, shape (B, 6)
        Prior means.
    P0 : array_like, shape (6, 6) or (B, 6, 6)
        Prior covariances.
    control_weight : array_like, shape (N-1,) or (B, N-1) or scalar
        :math:`q_n`, LU^2/TU^3.
    n_sub : int
        Control evaluation points per interval (>= 2).
    tol : float
        Integrator tolerance.
    """
    check_system(system)
    model = ocbe.check_model(model)
    t = validation.time_grid(t, "t", increasing=True)
    N = t.size
    y = validation.as_array(y, "y", ndim=(3,), min_size=1)
    B, m = y.shape[0], model.dim
    if y.shape[1:] != (N, m):
        raise ValueError(f"y must have shape (B, {N}, {m}); got {y.shape}")
    obs = validation.as_array(observer_states, "observer_states", shape=(N, 6))
    R = validation.spd(meas_cov, "meas_cov", n=m)
    x = validation.as_array(x0, "x0", shape=(B, 6)).copy()
    check_outside_primaries(system, x, "x0", t0=t[0])
    P0 = validation.spd(P0, "P0", n=6, batch=True)
    if P0.shape not in ((6, 6), (B, 6, 6)):
        raise ValueError(f"P0 must have shape (6, 6) or ({B}, 6, 6); got {P0.shape}")
    P0 = np.broadcast_to(P0, (B, 6, 6))
    qs = ocbe.control_weights(control_weight, N - 1, batch=B)
    n_sub = validation.integer(n_sub, "n_sub", minimum=2, maximum=10_000)
    tol = _check_tol(tol)
    return _ocbe_batch(system, t, y, obs, model, R, x, P0, qs, n_sub, tol)


#: Trials per heyoka batch integrator (larger lockstep batches are integrated in groups of
#: this size: the Taylor integrator's cost per trial grows again beyond a few SIMD widths).
_LANES = 16


def _check_start_outside(system, x, n, time):
    """Raise :class:`ocbe.FilterDivergenceError` (cause: an ImpactError) if a trial's estimate ``x`` (B, 6) lies
    inside a primary at the start of interval ``n``."""
    try:
        check_outside_primaries(system, x, "the reference", t0=time)
    except ImpactError as exc:
        raise ocbe.FilterDivergenceError(n, time, f"ImpactError: {exc}") from exc


def _ocbe_batch(system, t, y, obs, model, R, x, P0, qs, n_sub, tol) -> BatchOCBEResult:
    """:func:`ocbe_batch` after its argument checks: the loop of the single-trial filter with a trial axis.

    The SRI algebra is that of :func:`cislunar.estimation.ocbe.ocbe_filter_smoother` step for step, on the same
    :mod:`cislunar.estimation.srif` kernels; what the lockstep adds is where the transitions come from (the three
    non-zero 6x6 blocks of every trial from one batch integrator per :data:`_LANES` trials) and bookkeeping: the
    sub-grids and the integrators' initial state are allocated once.
    """
    B, N = y.shape[0], t.size
    lay = ocbe.BLOCK_LAYOUT
    s_xx, s_xp, s_pp = lay["phi_xx"], lay["phi_xp"], lay["phi_pp"]
    lanes = [(a, min(a + _LANES, B)) for a in range(0, B, _LANES)]
    integrators = [ocbe.block_integrator(b - a, tol) for a, b in lanes]
    t_sub = np.array([np.linspace(t[n], t[n + 1], n_sub) for n in range(N - 1)])  # as the single-trial filter
    start = np.zeros((s_pp.stop, B))
    out = np.empty((n_sub, s_pp.stop, B))
    start[s_xx] = start[s_pp] = np.eye(6).ravel()[:, None]
    zero, eye = np.zeros(6), np.eye(6)

    def update(S, x_ref, k):  # Eqs. 24-28 about the reference x_ref (the deviation's prior mean is zero)
        if not np.all(np.isfinite(x_ref)):  # a diverged estimate (was refused by model.evaluate's check)
            raise ValueError("target contains NaN or infinite values")
        val, _, Ht = model._evaluate(obs[k], x_ref)  # arrays checked above: the unchecked kernels
        S_new, b, e = srif._measurement_update(S, zero, Ht, model._residual(y[:, k], val), R)
        return S_new, x_ref + srif._solve_upper(S_new, b), e

    x_pred = np.empty((B, N, 6))
    x_filt = np.empty((B, N, 6))
    S_filt = np.empty((B, N, 6, 6))
    resid = np.empty((B, N))
    phi_xx = np.empty((B, N - 1, 6, 6))
    phi_xp = np.empty((B, N - 1, 6, 6))
    Rw, Rwx, zw = np.empty((B, N - 1, 6, 6)), np.empty((B, N - 1, 6, 6)), np.empty((B, N - 1, 6))  # smoother terms
    phi_pp_sub = np.empty((B, N - 1, n_sub, 6, 6))
    p_step = np.empty((B, N - 1, 6))
    x_pred[:, 0] = x
    S, x, resid[:, 0] = update(srif._sri_of_cov(P0), x, 0)
    x_filt[:, 0], S_filt[:, 0] = x, S
    mu = system.mu
    for n in range(N - 1):
        grid = t_sub[n]
        start[:6] = x.T
        _check_start_outside(system, x, n, float(grid[0]))  # a measurement update may move an estimate inside
        ok = True
        for (a, b), tb in zip(lanes, integrators):  # SIMD-sized groups of trials (one lane each)
            tb.set_time(np.full(b - a, grid[0]))
            tb.state[:] = start[:, a:b]
            tb.pars[0] = mu
            tb.pars[1] = qs[a:b, n]
            out[:, :, a:b] = tb.propagate_grid(np.repeat(grid[:, None], b - a, axis=1))[-1]  # (n_sub, 114, lanes)
            ok = ok and bool(np.all(np.abs(tb.time - grid[-1]) <= 1e-12))
        if not ok or not np.all(np.isfinite(out)):
            raise ocbe.FilterDivergenceError(n, float(grid[0]), "heyoka batch propagation failed (non-finite "
                                             "state)")
        # no impact events in the batch integrator (they would change its steps at round-off level): the sub-grid
        # states and the arcs between them are checked instead (ocbe.ocbe_transition, Notes)
        ref = np.moveaxis(out[:, :6], -1, 1)  # (n_sub, B, 6)
        try:
            if _inside_primaries(system, ref):
                inside = [b for b in range(B) if _inside_primaries(system, ref[:, b])][0]
                check_outside_primaries(system, ref[:, inside], f"the reference of trial {inside}",
                                        t0=float(grid[0]))
            _check_arcs_outside_primaries(system, grid, ref, tol)
        except ImpactError as exc:
            raise ocbe.FilterDivergenceError(n, float(grid[0]), f"ImpactError: {exc}") from exc
        end = out[-1].T  # (B, 114)
        Phi_xx = phi_xx[:, n] = end[:, s_xx].reshape(B, 6, 6)
        phi_xp[:, n] = end[:, s_xp].reshape(B, 6, 6)
        phi_pp_sub[:, n] = np.moveaxis(out[:, s_pp], -1, 0).reshape(B, n_sub, 6, 6)
        Q = ocbe._process_noise(Phi_xx, phi_xp[:, n])  # Eq. 17
        S_bar, _, term = srif._time_update(S, zero, Phi_xx, eye, Q)  # Eq. 23 with Gamma = I, b_x = 0
        Rw[:, n], Rwx[:, n], zw[:, n] = term
        x_prior = end[:, :6]
        x_pred[:, n + 1] = x_prior
        S_new, x_new, resid[:, n + 1] = update(S_bar, x_prior, n + 1)  # Eqs. 24-28
        # single-step smoother (Eqs. 29-30) and costate (Eq. 31)
        S1, b1 = srif._smoother_step(S_new, (S_new @ (x_new - x_prior)[..., None])[..., 0], Phi_xx, eye, term)
        p_step[:, n] = -((np.swapaxes(S, -1, -2) @ S) @ srif._solve_upper(S1, b1)[..., None])[..., 0]
        S, x = S_new, x_new
        x_filt[:, n + 1], S_filt[:, n + 1] = x, S
    control_step = -qs[:, :, None, None] * np.einsum("bnkij,bnj->bnki", phi_pp_sub, p_step)[..., 3:6]  # Eq. 32
    # full SRI smoother (backward)
    x_s = np.empty((B, N, 6))
    P_s = np.empty((B, N, 6, 6))
    Rs, bs = S_filt[:, -1], np.zeros((B, 6))
    x_s[:, -1], P_s[:, -1] = x_filt[:, -1], srif._cov_of_sri(Rs)
    for n in range(N - 2, -1, -1):
        z_next = bs + (Rs @ (x_filt[:, n + 1] - x_pred[:, n + 1])[..., None])[..., 0]
        Rs, bs = srif._smoother_step(Rs, z_next, phi_xx[:, n], eye, (Rw[:, n], Rwx[:, n], zw[:, n]))
        x_s[:, n] = x_filt[:, n] + srif._solve_upper(Rs, bs)
        P_s[:, n] = srif._cov_of_sri(Rs)
    w = (x_s[:, 1:] - x_pred[:, 1:]) - (phi_xx @ (x_s[:, :-1] - x_filt[:, :-1])[..., None])[..., 0]
    p_s = np.linalg.solve(phi_xp, w[..., None])[..., 0]
    control_s = -qs[:, :, None, None] * np.einsum("bnkij,bnj->bnki", phi_pp_sub, p_s)[..., 3:6]
    return BatchOCBEResult(x_pred, x_filt, srif._cov_of_sri(S_filt), x_s, P_s, t_sub, control_step, control_s,
                           ocbe._control_integral(t_sub, control_step), ocbe._control_integral(t_sub, control_s),
                           resid)
