r"""Test oracle: the lockstep OCBE as it was before 2026-11-26d (not part of the package).

:func:`cislunar.estimation.batched_ocbe.ocbe_batch` now assembles the time-update and smoother arrays in place
(``_time_update_identity``, ``_smoother_step_identity``), forms :math:`\Phi_{pp}` from :math:`\Phi_{xx}` instead of
integrating it (78 states per trial instead of 114; ``batched_ocbe._COSTATE_BLOCK``) and can return the smoothed
control integral of growing arcs (``smooth_ends``).  This module keeps the loop it replaced (``_ocbe_batch`` of
2026-11-26c: 114 states, 16 lanes, the generic :mod:`cislunar.estimation.srif` kernels) so that
``benchmarks/bench_detection.py`` can time the two side by side and the tests can check that today's loop with the
integrated :math:`\Phi_{pp}` gives bit for bit the same results: :func:`previous_lockstep` patches it into
``ocbe_batch`` within a block.

Frames and units: rotating barycentric frame, non-dimensional (LU, TU); controls in LU/TU^2, Eq. 33 in LU/TU.
"""

from __future__ import annotations

import contextlib

import numpy as np

from cislunar.cr3bp.propagation import (
    ImpactError,
    _check_arcs_outside_primaries,
    _inside_primaries,
    check_outside_primaries,
)
from cislunar.estimation import batched_ocbe, ocbe, srif
from cislunar.estimation.batched_ocbe import (
    _DIVERGENCE,
    BatchOCBEResult,
    _check_start_outside,
    _Failures,
    _frozen_transition,
    _per_trial,
    _process_noise_per_trial,
)

__all__ = ["previous_lockstep"]

_LANES = 16


@contextlib.contextmanager
def previous_lockstep():
    """Within the block, :func:`cislunar.estimation.batched_ocbe.ocbe_batch` runs the loop of 2026-11-26c (not
    thread-safe: it patches a module; ``smooth_ends`` is refused)."""
    today = batched_ocbe._ocbe_batch
    batched_ocbe._ocbe_batch = _previous_ocbe_batch
    try:
        yield
    finally:
        batched_ocbe._ocbe_batch = today


def _previous_ocbe_batch(*args, **kwargs):
    ends = args[17] if len(args) > 17 else kwargs.pop("ends", None)
    if ends is not None:
        raise ValueError("the previous lockstep OCBE has no smooth_ends")
    return _ocbe_batch(*args[:17], **kwargs)


def _ocbe_batch(system, t, y, obs, avail, model, R, x, P0, qs, n_sub, tol, smooth, flag, wrap_azimuth=True,
                relinearize=True, coarse_stm=False) -> BatchOCBEResult:
    """:func:`ocbe_batch` after its argument checks: the loop of the single-trial filter with a trial axis.

    The SRI algebra is that of :func:`cislunar.estimation.ocbe.ocbe_filter_smoother` step for step, on the same
    :mod:`cislunar.estimation.srif` kernels; what the lockstep adds is where the transitions come from (the three
    non-zero 6x6 blocks of every trial from one batch integrator per :data:`_LANES` trials) and bookkeeping: the
    sub-grids and the integrators' initial state are allocated once.  Each stage (the first update, each interval,
    the closing smoother) is a function of the trials it computes; with ``flag``, a stage that raises is rerun
    trial by trial (:func:`_per_trial`) so that only the failing trials are dropped, at the epoch where the
    single-trial filter would have raised (0 for the first update, n+1 for interval n, N-1 for the smoother).
    ``wrap_azimuth``, ``relinearize`` and ``coarse_stm``: see :func:`ocbe_batch` (with ``relinearize=False`` the reference of each
    trial is carried beside its estimate; the deviation is their difference).
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
    visible = [np.flatnonzero(avail[k]) for k in range(N)]
    process_noise = _process_noise_per_trial if flag else ocbe._process_noise
    mu = system.mu

    whiten = {}

    def whitening(k, n_vis):  # S_y of the stacked observers' covariance (independent observers), Eq. 26
        key = (k if R.ndim == 3 else -1, n_vis)
        if key not in whiten:
            Rk = R[k] if R.ndim == 3 else R
            whiten[key] = srif._sri_of_cov(Rk if n_vis == 1 else np.kron(np.eye(n_vis), Rk))
        return whiten[key]

    def update(S, x_ref, k, yk, dx=None):  # Eqs. 24-28 about the reference x_ref (the deviation's prior mean is
        # zero; with dx, the prior deviation of a fixed reference: the residual is y - h(x_ref) - H dx)
        vis = visible[k]
        if vis.size == 0:  # no measurement: a pure time update
            return S, x_ref.copy() if dx is None else x_ref + dx, np.zeros(x_ref.shape[0])
        if not np.all(np.isfinite(x_ref)):  # a diverged estimate (was refused by model.evaluate's check)
            raise ValueError("target contains NaN or infinite values")
        val, _, Ht = model._evaluate(obs[k, vis], x_ref[:, None, :])  # arrays checked above: the unchecked kernels
        nb = x_ref.shape[0]
        dy = (model._residual(yk[:, vis], val) if wrap_azimuth else yk[:, vis] - val).reshape(nb, -1)
        if dx is not None:
            dy = dy - (Ht.reshape(nb, -1, 6) @ dx[..., None])[..., 0]
            x_ref = x_ref + dx
        # srif._measurement_update with the whitening computed once: triangularise [S 0; W H  W dy]
        W = whitening(k, vis.size)
        U = srif._triangularize(np.concatenate([np.concatenate([S, np.zeros((nb, 6, 1))], axis=-1),
                                                np.concatenate([W @ Ht.reshape(nb, -1, 6), (W @ dy[..., None])],
                                                               axis=-1)], axis=-2))
        S_new, b = U[..., :6, :6], U[..., :6, 6]
        return S_new, x_ref + srif._solve_upper(S_new, b), np.abs(U[..., 6, 6])

    nan = np.nan
    x_pred = np.full((B, N, 6), nan)
    x_filt = np.full((B, N, 6), nan)
    S_filt = np.full((B, N, 6, 6), nan)
    resid = np.full((B, N), nan)
    if smooth:  # what the single-step and full smoothers need
        phi_xx = np.full((B, N - 1, 6, 6), nan)
        phi_xp = np.full((B, N - 1, 6, 6), nan)
        Rw, Rwx, zw = np.full((B, N - 1, 6, 6), nan), np.full((B, N - 1, 6, 6), nan), np.full((B, N - 1, 6), nan)
        phi_pp_sub = np.full((B, N - 1, n_sub, 6, 6), nan)
        p_step = np.full((B, N - 1, 6), nan)
    failures = _Failures(t, B)
    x_cur, S_cur = x, None
    x_ref = x.copy()  # the fixed reference (relinearize=False): at t[0], the prior mean

    def stage(fn, epoch, replicate):
        if not flag:
            return fn(failures.src)
        try:
            return fn(failures.src)
        except _DIVERGENCE:
            return _per_trial(fn, B, failures, epoch, replicate=replicate)

    def first(idx):
        return update(srif._sri_of_cov(P0[idx]), x[idx], 0, y[idx, 0])

    def interval(idx, n):
        xs, S = (x_cur[idx], S_cur[idx]) if relinearize else (x_ref[idx], S_cur[idx])
        grid = t_sub[n]
        start[:6] = xs.T
        _check_start_outside(system, xs, n, float(grid[0]))  # a measurement update may move an estimate inside
        ok = True
        for (a, b), tb in zip(lanes, integrators):  # SIMD-sized groups of trials (one lane each)
            tb.set_time(np.full(b - a, grid[0]))
            tb.state[:] = start[:, a:b]
            tb.pars[0] = mu
            tb.pars[1] = qs[idx[a:b], n]
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
                check_outside_primaries(system, ref[:, inside], f"the reference of trial {idx[inside]}",
                                        t0=float(grid[0]))
            _check_arcs_outside_primaries(system, grid, ref, tol)
        except ImpactError as exc:
            raise ocbe.FilterDivergenceError(n, float(grid[0]), f"ImpactError: {exc}") from exc
        end = out[-1].T  # (B, 114)
        Phi_xx = np.array(end[:, s_xx].reshape(B, 6, 6))
        Phi_xp = np.array(end[:, s_xp].reshape(B, 6, 6))
        if coarse_stm:  # one frozen-Jacobian step over the interval instead of the integrated transition
            Phi_xx, Phi_xp = _frozen_transition(system, xs, float(grid[-1] - grid[0]), qs[idx, n])
        Q = process_noise(Phi_xx, Phi_xp)  # Eq. 17
        S_bar, _, term = srif._time_update(S, zero, Phi_xx, eye, Q)  # Eq. 23 with Gamma = I, b_x = 0
        x_prior = np.array(end[:, :6])
        if not relinearize:  # the deviation from the fixed reference, carried by Phi_xx
            dx = (Phi_xx @ (x_cur[idx] - xs)[..., None])[..., 0]
            S_new, x_new, e = update(S_bar, x_prior, n + 1, y[idx, n + 1], dx)
            return x_prior + dx, S_new, x_new, e, x_prior
        S_new, x_new, e = update(S_bar, x_prior, n + 1, y[idx, n + 1])  # Eqs. 24-28
        if not smooth:  # filter only: no single-step smoother, no control estimate
            return x_prior, S_new, x_new, e
        pp_sub = np.moveaxis(out[:, s_pp], -1, 0).reshape(B, n_sub, 6, 6)  # a copy (not a view of out)
        # single-step smoother (Eqs. 29-30) and costate (Eq. 31)
        S1, b1 = srif._smoother_step(S_new, (S_new @ (x_new - x_prior)[..., None])[..., 0], Phi_xx, eye, term)
        p = -((np.swapaxes(S, -1, -2) @ S) @ srif._solve_upper(S1, b1)[..., None])[..., 0]
        return (x_prior, S_new, x_new, e, Phi_xx, Phi_xp, pp_sub, *term, p)

    res = stage(first, 0, False)
    if res is not None:
        S_cur, x_cur, resid[:, 0] = res
        x_pred[:, 0], x_filt[:, 0], S_filt[:, 0] = x, x_cur, S_cur
        for n in range(N - 1):
            res = stage(lambda idx: interval(idx, n), n + 1, True)  # noqa: B023 - called at once
            if res is None:
                break
            x_pred[:, n + 1], S_cur, x_cur, resid[:, n + 1] = res[:4]
            if not relinearize:
                x_ref = res[4]
            x_filt[:, n + 1], S_filt[:, n + 1] = x_cur, S_cur
            if smooth:
                phi_xx[:, n], phi_xp[:, n], phi_pp_sub[:, n], Rw[:, n], Rwx[:, n], zw[:, n], p_step[:, n] = res[4:]

    def closing(idx):  # covariances, controls (Eq. 32) and the full SRI smoother (backward) of the trials idx
        nb = idx.size
        P_f = srif._cov_of_sri(S_filt[idx])
        if not smooth:
            return P_f, None, None, None, None, None, None
        q = qs[idx]
        control_step = -q[:, :, None, None] * np.einsum("bnkij,bnj->bnki", phi_pp_sub[idx], p_step[idx])[..., 3:6]
        z_step = ocbe._control_integral(t_sub, control_step)
        xf, xp, pxx = x_filt[idx], x_pred[idx], phi_xx[idx]
        x_s = np.empty((nb, N, 6))
        P_s = np.empty((nb, N, 6, 6))
        Rs, bs = S_filt[idx, -1], np.zeros((nb, 6))
        x_s[:, -1], P_s[:, -1] = xf[:, -1], P_f[:, -1]
        for n in range(N - 2, -1, -1):
            z_next = bs + (Rs @ (xf[:, n + 1] - xp[:, n + 1])[..., None])[..., 0]
            Rs, bs = srif._smoother_step(Rs, z_next, pxx[:, n], eye, (Rw[idx, n], Rwx[idx, n], zw[idx, n]))
            x_s[:, n] = xf[:, n] + srif._solve_upper(Rs, bs)
            P_s[:, n] = srif._cov_of_sri(Rs)
        w = (x_s[:, 1:] - xp[:, 1:]) - (pxx @ (x_s[:, :-1] - xf[:, :-1])[..., None])[..., 0]
        p_s = np.linalg.solve(phi_xp[idx], w[..., None])[..., 0]
        control_s = -q[:, :, None, None] * np.einsum("bnkij,bnj->bnki", phi_pp_sub[idx], p_s)[..., 3:6]
        return P_f, control_step, z_step, x_s, P_s, control_s, ocbe._control_integral(t_sub, control_s)

    done = stage(closing, N - 1, False) if res is not None else None
    if done is None:  # every trial failed
        full = (np.full((B, N, 6, 6), nan), np.full((B, N - 1, n_sub, 3), nan), np.full(B, nan))
        done = (full + (np.full((B, N, 6), nan),) + full) if smooth else (full[0],) + (None,) * 6
    P_f, control_step, z_step, x_s, P_s, control_s, z_s = done
    dead = failures.epoch >= 0
    if dead.any():
        for arr in (x_pred, x_filt, resid, P_f, control_step, z_step, x_s, P_s, control_s, z_s):
            if arr is not None:
                arr[dead] = nan
    return BatchOCBEResult(x_pred, x_filt, P_f, x_s, P_s, t_sub, control_step, control_s, z_step, z_s, resid,
                           failures.epoch.copy(), np.array(failures.message, dtype=str))
