r"""The batched OCBE: the SRI OCBE filter and smoother of :mod:`cislunar.estimation.ocbe` for B trials in lockstep.

All trials share the epochs, observers, measurement model and noise; the transitions of every trial come from one
heyoka batch integrator and the square-root-information updates are stacked QR factorisations.  The default engine
integrates only the three non-zero 6x6 blocks of the state/costate transition
(:func:`cislunar.estimation.ocbe.block_integrator`); the ``engine="reference"`` path integrates the full 12x12
variational system and is kept as a test oracle.  Both equal the single-trial filter
(:func:`cislunar.estimation.ocbe.ocbe_filter_smoother`) to round-off.

Frames and units: rotating barycentric frame, non-dimensional (LU, TU); controls in LU/TU^2, Eq. 33 in LU/TU.
"""

from __future__ import annotations

import copy
import functools
from dataclasses import dataclass

import numpy as np

from cislunar.cr3bp.dynamics import CR3BP, check_system
from cislunar.cr3bp.propagation import DEFAULT_TOL, _check_tol, _heyoka
from cislunar.estimation import ocbe
from cislunar.utils import validation

__all__ = ["BatchOCBEResult", "ocbe_batch"]


@functools.lru_cache(maxsize=8)
def _batch_template(tol: float, batch_size: int):
    """heyoka batch integrator of the OCBE variational system (compiled once per process and size)."""
    hy = _heyoka()
    sys, index = ocbe.variational_system(tol)
    tb = hy.taylor_adaptive_batch(sys, np.zeros((len(sys), batch_size)), pars=np.zeros((2, batch_size)),
                                  tol=tol, compact_mode=True)
    return tb, index


def _triangularize(A):
    """Stacked Householder triangularisation with non-negative diagonal (as :func:`srif.householder_triangularize`)."""
    r = np.linalg.qr(A, mode="r")
    d = np.sign(np.diagonal(r, axis1=-2, axis2=-1)).copy()
    d[d == 0] = 1.0
    return r * d[..., :, None]


def _sri_of_cov(C):
    """Stacked upper-triangular W with W^T W = C^{-1}."""
    L = np.linalg.cholesky(0.5 * (C + np.swapaxes(C, -1, -2)))
    return _triangularize(np.linalg.inv(L))


def _solve_upper(R, b):
    return np.linalg.solve(R, b[..., None])[..., 0]


def _cov_of_sri(R):
    Rinv = np.linalg.inv(R)
    return Rinv @ np.swapaxes(Rinv, -1, -2)


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
               tol: float = DEFAULT_TOL, engine: str = "fast") -> BatchOCBEResult:
    """The extended SRI OCBE filter and full smoother of :func:`cislunar.estimation.ocbe.ocbe_filter_smoother` for B trials.

    Same algorithm, step for step (Eqs. 17, 21-32 and the backward SRI smoother with costates
    :math:`\\mathbf p_{n|N} = \\Phi_{xp}^{-1}\\hat{\\mathbf w}_n`), with all trials sharing the epochs, observers,
    measurement model and noise; the 12x12 transitions of all trials come from one heyoka batch integrator and the
    square-root-information updates are stacked QR factorisations.

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
    engine : {"fast", "reference"}
        ``"fast"`` (default): the transition blocks from :func:`cislunar.estimation.ocbe.block_integrator` (the same
        variational equations without the identically zero block, about four times cheaper to integrate) and the
        square-root-information algebra with fewer temporaries.  ``"reference"``: the first batched
        implementation, integrating the full 12x12 variational system of
        :func:`cislunar.estimation.ocbe.variational_system`; kept to check the fast engine against
        (``tests/papers/greaves_scheeres_2021/test_detection.py``: states and covariances agree to ~1e-14 relative, controls and z to
        ~1e-10, the same round-off level as between either engine and the single-trial filter) and to benchmark
        it (``benchmarks/bench_detection.py``).
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
    P0 = validation.spd(P0, "P0", n=6, batch=True)
    if P0.shape not in ((6, 6), (B, 6, 6)):
        raise ValueError(f"P0 must have shape (6, 6) or ({B}, 6, 6); got {P0.shape}")
    P0 = np.broadcast_to(P0, (B, 6, 6))
    qs = ocbe.control_weights(control_weight, N - 1, batch=B)
    n_sub = validation.integer(n_sub, "n_sub", minimum=2)
    tol = _check_tol(tol)
    engine = validation.choice(engine, "engine", ("fast", "reference"))
    run = _ocbe_batch_fast if engine == "fast" else _ocbe_batch_reference
    return run(system, t, y, obs, model, R, x, P0, qs, n_sub, tol)


def _ocbe_batch_reference(system, t, y, obs, model, R, x, P0, qs, n_sub, tol) -> BatchOCBEResult:
    """The first batched OCBE (full 12x12 variational system); arguments checked by :func:`ocbe_batch`."""
    B, N = y.shape[0], t.size
    template, index = _batch_template(tol, B)
    tb = copy.deepcopy(template)
    W = _sri_of_cov(R)
    bidx = np.arange(B)

    def update(S, x_ref, k):
        val, _, Ht = model.evaluate(obs[k], x_ref)
        dy = model.residual(y[:, k], val)
        A = np.concatenate([np.concatenate([S, np.zeros((B, 6, 1))], axis=2),
                            np.concatenate([W @ Ht, (W @ dy[..., None])], axis=2)], axis=1)
        U = _triangularize(A)
        S_new, b = U[:, :6, :6], U[:, :6, 6]
        return S_new, x_ref + _solve_upper(S_new, b), np.abs(U[:, 6, 6])

    S = _sri_of_cov(P0)
    x_pred = np.empty((B, N, 6))
    x_filt = np.empty((B, N, 6))
    S_filt = np.empty((B, N, 6, 6))
    resid = np.empty((B, N))
    phis = np.empty((B, N - 1, 12, 12))
    terms = np.empty((B, N - 1, 6, 13))  # [Rw | Rwx | zw] of each time update
    phi_pp_sub = np.empty((B, N - 1, n_sub, 6, 6))
    p_step = np.empty((B, N - 1, 6))
    t_sub = np.empty((N - 1, n_sub))
    x_pred[:, 0] = x
    S, x, resid[:, 0] = update(S, x, 0)
    x_filt[:, 0], S_filt[:, 0] = x, S
    eye12 = np.eye(12).ravel()
    for n in range(N - 1):
        grid = np.linspace(t[n], t[n + 1], n_sub)
        t_sub[n] = grid
        tb.set_time(np.full(B, grid[0]))
        tb.state[:12] = np.concatenate([x, np.zeros((B, 6))], axis=1).T
        tb.state[12:] = eye12[:, None]
        tb.pars[0] = system.mu
        tb.pars[1] = qs[:, n]
        out = tb.propagate_grid(np.repeat(grid[:, None], B, axis=1))[-1]  # (n_sub, 156, B)
        if not np.allclose(tb.time, grid[-1], rtol=0, atol=1e-12) or not np.all(np.isfinite(out)):
            raise ocbe.FilterDivergenceError(n, float(grid[0]), "heyoka batch propagation failed (non-finite "
                                             "state)")
        # no impact events in the batch integrator (see ocbe.ocbe_transition): check every sub-grid state
        r1, r2 = system.distances(np.moveaxis(out[:, :3], -1, 1))
        if np.any(r2 <= system.secondary_radius) or np.any(r1 <= system.primary_radius):
            member = int(np.flatnonzero(np.any((r2 <= system.secondary_radius) | (r1 <= system.primary_radius),
                                               axis=0))[0])
            raise ocbe.FilterDivergenceError(n, float(grid[0]), f"the reference of trial {member} of the batch "
                                             "entered a primary")
        phi_all = np.moveaxis(out, -1, 0)[:, :, index]  # (B, n_sub, 12, 12)
        Phi = phi_all[:, -1]
        Phi_xx, Phi_xp = Phi[:, :6, :6], Phi[:, :6, 6:]
        Q = ocbe.ocbe_process_noise(Phi)
        # Eq. 23: time update with Gamma = I, b_x = 0
        Rt = np.swapaxes(np.linalg.solve(np.swapaxes(Phi_xx, -1, -2), np.swapaxes(S, -1, -2)), -1, -2)
        A = np.zeros((B, 12, 13))
        A[:, :6, :6] = _sri_of_cov(Q)
        A[:, 6:, :6] = -Rt
        A[:, 6:, 6:12] = Rt
        U = _triangularize(A)
        S_bar, term = U[:, 6:12, 6:12], U[:, :6, :]
        x_prior = np.moveaxis(out[-1, :6], -1, 0)
        x_pred[:, n + 1] = x_prior
        S_new, x_new, resid[:, n + 1] = update(S_bar, x_prior, n + 1)  # Eqs. 24-28
        # single-step smoother (Eqs. 29-30) and costate (Eq. 31)
        S1, b1 = _smoother_step(S_new, (S_new @ (x_new - x_prior)[..., None])[..., 0], Phi_xx, term)
        p_step[:, n] = -((np.swapaxes(S, -1, -2) @ S) @ _solve_upper(S1, b1)[..., None])[..., 0]
        phis[:, n], terms[:, n], phi_pp_sub[:, n] = Phi, term, phi_all[:, :, 6:, 6:]
        S, x = S_new, x_new
        x_filt[:, n + 1], S_filt[:, n + 1] = x, S
    control_step = -qs[:, :, None, None] * np.einsum("bnkij,bnj->bnki", phi_pp_sub, p_step)[..., 3:6]
    # full SRI smoother (backward)
    x_s = np.empty((B, N, 6))
    P_s = np.empty((B, N, 6, 6))
    Rs, bs = S_filt[:, -1], np.zeros((B, 6))
    x_s[:, -1], P_s[:, -1] = x_filt[:, -1], _cov_of_sri(Rs)
    for n in range(N - 2, -1, -1):
        z_next = bs + (Rs @ (x_filt[:, n + 1] - x_pred[:, n + 1])[..., None])[..., 0]
        Rs, bs = _smoother_step(Rs, z_next, phis[:, n, :6, :6], terms[:, n])
        x_s[:, n] = x_filt[:, n] + _solve_upper(Rs, bs)
        P_s[:, n] = _cov_of_sri(Rs)
    w = (x_s[:, 1:] - x_pred[:, 1:]) - (phis[:, :, :6, :6] @ (x_s[:, :-1] - x_filt[:, :-1])[..., None])[..., 0]
    p_s = np.linalg.solve(phis[:, :, :6, 6:], w[..., None])[..., 0]
    control_s = -qs[:, :, None, None] * np.einsum("bnkij,bnj->bnki", phi_pp_sub, p_s)[..., 3:6]
    P_filt = _cov_of_sri(S_filt)
    return BatchOCBEResult(x_pred, x_filt, P_filt, x_s, P_s, t_sub, control_step, control_s,
                           _control_integral(t_sub, control_step), _control_integral(t_sub, control_s), resid)


#: Trials per heyoka batch integrator in the fast engine (larger lockstep batches are integrated in groups of
#: this size: the Taylor integrator's cost per trial grows again beyond a few SIMD widths).
_LANES = 16


def _ocbe_batch_fast(system, t, y, obs, model, R, x, P0, qs, n_sub, tol) -> BatchOCBEResult:
    """:func:`ocbe_batch` on the block integrator (:func:`cislunar.estimation.ocbe.block_integrator`); arguments checked.

    The algebra is that of :func:`_ocbe_batch_reference` step for step; what changes is where the transition
    comes from (the three non-zero 6x6 blocks instead of the full 12x12 matrix) and bookkeeping: the sub-grids,
    the integrator's initial state and the measurement-update matrix are allocated once, quantities shared by all
    trials (whitened measurement noise, epochs) are computed once.
    """
    B, N = y.shape[0], t.size
    lay = ocbe.BLOCK_LAYOUT
    s_xx, s_xp, s_pp = lay["phi_xx"], lay["phi_xp"], lay["phi_pp"]
    lanes = [(a, min(a + _LANES, B)) for a in range(0, B, _LANES)]
    integrators = [ocbe.block_integrator(b - a, tol) for a, b in lanes]
    W = _sri_of_cov(R)
    m = W.shape[0]
    t_sub = np.array([np.linspace(t[n], t[n + 1], n_sub) for n in range(N - 1)])  # as the reference, per interval
    start = np.zeros((s_pp.stop, B))
    out = np.empty((n_sub, s_pp.stop, B))
    start[s_xx] = start[s_pp] = np.eye(6).ravel()[:, None]
    A_meas = np.zeros((B, 6 + m, 7))  # [S 0; W H  W dy]

    def update(S, x_ref, k):
        val, _, Ht = model.evaluate(obs[k], x_ref)
        dy = model.residual(y[:, k], val)
        A_meas[:, :6, :6] = S
        A_meas[:, 6:, :6] = W @ Ht
        A_meas[:, 6:, 6] = (W @ dy[..., None])[..., 0]
        U = _triangularize(A_meas)
        S_new, b = U[:, :6, :6], U[:, :6, 6]
        return S_new, x_ref + _solve_upper(S_new, b), np.abs(U[:, 6, 6])

    S = _sri_of_cov(P0)
    x_pred = np.empty((B, N, 6))
    x_filt = np.empty((B, N, 6))
    S_filt = np.empty((B, N, 6, 6))
    resid = np.empty((B, N))
    phi_xx = np.empty((B, N - 1, 6, 6))
    phi_xp = np.empty((B, N - 1, 6, 6))
    terms = np.empty((B, N - 1, 6, 13))  # [Rw | Rwx | zw] of each time update
    phi_pp_sub = np.empty((B, N - 1, n_sub, 6, 6))
    p_step = np.empty((B, N - 1, 6))
    A_time = np.zeros((B, 12, 13))
    x_pred[:, 0] = x
    S, x, resid[:, 0] = update(S, x, 0)
    x_filt[:, 0], S_filt[:, 0] = x, S
    mu = system.mu
    for n in range(N - 1):
        grid = t_sub[n]
        start[:6] = x.T
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
        # no impact events in the batch integrator (see ocbe.ocbe_transition): check every sub-grid state
        r1, r2 = system.distances(np.moveaxis(out[:, :3], -1, 1))
        if np.any(r2 <= system.secondary_radius) or np.any(r1 <= system.primary_radius):
            member = int(np.flatnonzero(np.any((r2 <= system.secondary_radius) | (r1 <= system.primary_radius),
                                               axis=0))[0])
            raise ocbe.FilterDivergenceError(n, float(grid[0]), f"the reference of trial {member} of the batch "
                                             "entered a primary")
        end = out[-1].T  # (B, 114)
        Phi_xx = phi_xx[:, n] = end[:, s_xx].reshape(B, 6, 6)
        phi_xp[:, n] = end[:, s_xp].reshape(B, 6, 6)
        phi_pp_sub[:, n] = np.moveaxis(out[:, s_pp], -1, 0).reshape(B, n_sub, 6, 6)
        Q = ocbe._process_noise(Phi_xx, phi_xp[:, n])
        # Eq. 23: time update with Gamma = I, b_x = 0
        Rt = np.swapaxes(np.linalg.solve(np.swapaxes(Phi_xx, -1, -2), np.swapaxes(S, -1, -2)), -1, -2)
        A_time[:, :6, :6] = _sri_of_cov(Q)
        A_time[:, 6:, :6] = -Rt
        A_time[:, 6:, 6:12] = Rt
        U = _triangularize(A_time)
        S_bar, term = U[:, 6:12, 6:12], U[:, :6, :]
        x_prior = end[:, :6]
        x_pred[:, n + 1] = x_prior
        S_new, x_new, resid[:, n + 1] = update(S_bar, x_prior, n + 1)  # Eqs. 24-28
        # single-step smoother (Eqs. 29-30) and costate (Eq. 31)
        S1, b1 = _smoother_step(S_new, (S_new @ (x_new - x_prior)[..., None])[..., 0], Phi_xx, term)
        p_step[:, n] = -((np.swapaxes(S, -1, -2) @ S) @ _solve_upper(S1, b1)[..., None])[..., 0]
        terms[:, n] = term
        S, x = S_new, x_new
        x_filt[:, n + 1], S_filt[:, n + 1] = x, S
    control_step = -qs[:, :, None, None] * np.einsum("bnkij,bnj->bnki", phi_pp_sub, p_step)[..., 3:6]
    # full SRI smoother (backward)
    x_s = np.empty((B, N, 6))
    P_s = np.empty((B, N, 6, 6))
    Rs, bs = S_filt[:, -1], np.zeros((B, 6))
    x_s[:, -1], P_s[:, -1] = x_filt[:, -1], _cov_of_sri(Rs)
    for n in range(N - 2, -1, -1):
        z_next = bs + (Rs @ (x_filt[:, n + 1] - x_pred[:, n + 1])[..., None])[..., 0]
        Rs, bs = _smoother_step(Rs, z_next, phi_xx[:, n], terms[:, n])
        x_s[:, n] = x_filt[:, n] + _solve_upper(Rs, bs)
        P_s[:, n] = _cov_of_sri(Rs)
    w = (x_s[:, 1:] - x_pred[:, 1:]) - (phi_xx @ (x_s[:, :-1] - x_filt[:, :-1])[..., None])[..., 0]
    p_s = np.linalg.solve(phi_xp, w[..., None])[..., 0]
    control_s = -qs[:, :, None, None] * np.einsum("bnkij,bnj->bnki", phi_pp_sub, p_s)[..., 3:6]
    P_filt = _cov_of_sri(S_filt)
    return BatchOCBEResult(x_pred, x_filt, P_filt, x_s, P_s, t_sub, control_step, control_s,
                           _control_integral(t_sub, control_step), _control_integral(t_sub, control_s), resid)


def _smoother_step(Rs_next, zs_next, Phi, term):
    """Stacked :func:`cislunar.estimation.srif.smoother_step` with Gamma = I; ``term`` = [Rw | Rwx | zw] (B, 6, 13)."""
    Rw, Rwx, zw = term[:, :, :6], term[:, :, 6:12], term[:, :, 12]
    B = Rs_next.shape[0]
    A = np.empty((B, 12, 13))
    A[:, :6, :6] = Rw + Rwx
    A[:, :6, 6:12] = Rwx @ Phi
    A[:, :6, 12] = zw
    A[:, 6:, :6] = Rs_next
    A[:, 6:, 6:12] = Rs_next @ Phi
    A[:, 6:, 12] = zs_next
    U = _triangularize(A)
    return U[:, 6:12, 6:12], U[:, 6:12, 12]


def _control_integral(t_sub, control) -> np.ndarray:
    """Eq. 33 per trial: trapezoid rule of ||u|| on each interval's sub-grid, summed over intervals."""
    mag = np.linalg.norm(control, axis=-1)  # (B, N-1, n_sub)
    return np.sum(np.trapezoid(mag, t_sub[None], axis=-1), axis=-1)
