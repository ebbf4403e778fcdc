r"""Test oracle: the first batched OCBE, on the full 12x12 OCBE variational system (not part of the package).

:func:`cislunar.estimation.batched_ocbe.ocbe_batch` integrates only the three non-zero 6x6 blocks of the
state/costate transition (:func:`cislunar.estimation.ocbe.block_integrator`).  This module keeps the implementation
it replaced, which integrates the whole 12x12 matrix of :func:`cislunar.estimation.ocbe.variational_system` in one
heyoka batch integrator for all B trials, so the tests can check the two integrations (and the lockstep split into
groups of lanes) against each other.  The square-root-information algebra is the stacked kernels of
:mod:`cislunar.estimation.srif` that both filters share.

Imported by ``tests/estimation/test_batched_ocbe.py`` (pytest puts this folder on ``sys.path``) and by
``benchmarks/bench_detection.py`` (which adds ``tests/estimation`` to ``sys.path``).

Frames and units: rotating barycentric frame, non-dimensional (LU, TU); controls in LU/TU^2, Eq. 33 in LU/TU.
"""

from __future__ import annotations

import copy
import functools

import numpy as np

from cislunar.cr3bp.propagation import DEFAULT_TOL, _heyoka
from cislunar.estimation import ocbe, srif
from cislunar.estimation.batched_ocbe import BatchOCBEResult

__all__ = ["ocbe_batch_reference"]


@functools.lru_cache(maxsize=8)
def _batch_template(tol: float, batch_size: int):
    """heyoka batch integrator of the full OCBE variational system (compiled once per process and size)."""
    hy = _heyoka()
    sys, index = ocbe.variational_system(tol)
    tb = hy.taylor_adaptive_batch(sys, np.zeros((len(sys), batch_size)), pars=np.zeros((2, batch_size)),
                                  tol=tol, compact_mode=True)
    return tb, index


def ocbe_batch_reference(system, t, y, observer_states, model, meas_cov, x0, P0, control_weight, *, n_sub: int = 9,
                         tol: float = DEFAULT_TOL) -> BatchOCBEResult:
    """The batched OCBE on the full 12x12 transition; arguments as :func:`cislunar.estimation.batched_ocbe.ocbe_batch`.

    Arguments are converted but not checked (an oracle for valid inputs).
    """
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    obs = np.asarray(observer_states, dtype=float)
    R = np.asarray(meas_cov, dtype=float)
    x = np.array(x0, dtype=float)
    B, N = y.shape[0], t.size
    P0 = np.broadcast_to(np.asarray(P0, dtype=float), (B, 6, 6))
    qs = ocbe.control_weights(control_weight, N - 1, batch=B)
    template, index = _batch_template(tol, B)
    tb = copy.deepcopy(template)
    zero, eye = np.zeros(6), np.eye(6)

    def update(S, x_ref, k):
        val, _, Ht = model.evaluate(obs[k], x_ref)
        S_new, b, e = srif._measurement_update(S, zero, Ht, model.residual(y[:, k], val), R)
        return S_new, x_ref + srif._solve_upper(S_new, b), e

    x_pred = np.empty((B, N, 6))
    x_filt = np.empty((B, N, 6))
    S_filt = np.empty((B, N, 6, 6))
    resid = np.empty((B, N))
    phis = np.empty((B, N - 1, 12, 12))
    terms = []
    phi_pp_sub = np.empty((B, N - 1, n_sub, 6, 6))
    p_step = np.empty((B, N - 1, 6))
    t_sub = np.empty((N - 1, n_sub))
    x_pred[:, 0] = x
    S, x, resid[:, 0] = update(srif._sri_of_cov(P0), x, 0)
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
        assert np.allclose(tb.time, grid[-1], rtol=0, atol=1e-12) and np.all(np.isfinite(out))
        phi_all = np.moveaxis(out, -1, 0)[:, :, index]  # (B, n_sub, 12, 12)
        Phi = phi_all[:, -1]
        Phi_xx = Phi[:, :6, :6]
        Q = ocbe.ocbe_process_noise(Phi)  # Eq. 17
        S_bar, _, term = srif._time_update(S, zero, Phi_xx, eye, Q)  # Eq. 23
        x_prior = np.moveaxis(out[-1, :6], -1, 0)
        x_pred[:, n + 1] = x_prior
        S_new, x_new, resid[:, n + 1] = update(S_bar, x_prior, n + 1)  # Eqs. 24-28
        S1, b1 = srif._smoother_step(S_new, (S_new @ (x_new - x_prior)[..., None])[..., 0], Phi_xx, eye, term)
        p_step[:, n] = -((np.swapaxes(S, -1, -2) @ S) @ srif._solve_upper(S1, b1)[..., None])[..., 0]  # Eq. 31
        phis[:, n], phi_pp_sub[:, n] = Phi, phi_all[:, :, 6:, 6:]
        terms.append(term)
        S, x = S_new, x_new
        x_filt[:, n + 1], S_filt[:, n + 1] = x, S
    control_step = -qs[:, :, None, None] * np.einsum("bnkij,bnj->bnki", phi_pp_sub, p_step)[..., 3:6]
    x_s = np.empty((B, N, 6))
    P_s = np.empty((B, N, 6, 6))
    Rs, bs = S_filt[:, -1], np.zeros((B, 6))
    x_s[:, -1], P_s[:, -1] = x_filt[:, -1], srif._cov_of_sri(Rs)
    for n in range(N - 2, -1, -1):
        z_next = bs + (Rs @ (x_filt[:, n + 1] - x_pred[:, n + 1])[..., None])[..., 0]
        Rs, bs = srif._smoother_step(Rs, z_next, phis[:, n, :6, :6], eye, terms[n])
        x_s[:, n] = x_filt[:, n] + srif._solve_upper(Rs, bs)
        P_s[:, n] = srif._cov_of_sri(Rs)
    w = (x_s[:, 1:] - x_pred[:, 1:]) - (phis[:, :, :6, :6] @ (x_s[:, :-1] - x_filt[:, :-1])[..., None])[..., 0]
    p_s = np.linalg.solve(phis[:, :, :6, 6:], w[..., None])[..., 0]
    control_s = -qs[:, :, None, None] * np.einsum("bnkij,bnj->bnki", phi_pp_sub, p_s)[..., 3:6]
    return BatchOCBEResult(x_pred, x_filt, srif._cov_of_sri(S_filt), x_s, P_s, t_sub, control_step, control_s,
                           ocbe._control_integral(t_sub, control_step), ocbe._control_integral(t_sub, control_s),
                           resid)
