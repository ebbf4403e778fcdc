r"""The batched OCBE: the SRI OCBE filter and smoother of :mod:`cislunar.estimation.ocbe` for B trials in lockstep.

All trials share the epochs, observers (one or several, with the same availability mask), measurement model and
noise; the transitions of every trial come from one heyoka batch integrator of the three non-zero 6x6 blocks of the
state/costate transition (:func:`cislunar.estimation.ocbe.block_integrator`), and the square-root-information
updates are the stacked kernels of :mod:`cislunar.estimation.srif` (the same functions the single-trial filter
calls, with a leading trial axis).  The result equals the single-trial filter
(:func:`cislunar.estimation.ocbe.ocbe_filter_smoother`) to round-off, and so does the first batched implementation,
which integrated the full 12x12 variational system and is kept as a test oracle in
``tests/estimation/reference_batched_ocbe.py``.

The transitions integrate 78 states per trial: :math:`\Phi_{pp} = \Phi_{xx}^{-\top}` is formed from
:math:`\Phi_{xx}` through the CR3BP's invariant form (``costate_block=False`` of
:func:`cislunar.estimation.ocbe.block_integrator`), equal to the integrated one to round-off.  With ``smooth_ends``
one forward pass gives the smoothed control integral of every growing data arc ``t[0] .. t[e]`` (each arc its own
backward pass), bit for bit what separate calls on each arc give.  The loop before these changes (2026-11-26c: 114
states, the generic SRI kernels) is kept in ``tests/estimation/reference_lockstep_ocbe.py``.

A trial that fails numerically (a diverged filter) either stops the whole batch (``on_failure="raise"``, the
default) or is flagged and dropped while the others go on (``on_failure="flag"``): then each trial ends exactly as
the single-trial filter would, with results or with the :class:`cislunar.estimation.ocbe.FilterDivergenceError`
that filter raises (same epoch).

Frames and units: rotating barycentric frame, non-dimensional (LU, TU); controls in LU/TU^2, Eq. 33 in LU/TU.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm

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

#: What counts as a numerical failure of a filter (the exceptions :func:`cislunar.estimation.ocbe.ocbe_filter_smoother`
#: turns into :class:`cislunar.estimation.ocbe.FilterDivergenceError`).
_DIVERGENCE = (np.linalg.LinAlgError, ValueError, RuntimeError, FloatingPointError)


@dataclass(frozen=True)
class BatchOCBEResult:
    """Output of :func:`ocbe_batch`; arrays carry a leading trial axis ``B``.

    Attributes
    ----------
    x_pred, x_filt, x_smooth : ndarray, shape (B, N, 6)
        ``x_smooth`` and ``P_smooth`` are None in the filter-only mode (``smooth=False``).
    P_filt, P_smooth : ndarray, shape (B, N, 6, 6)
    t_sub : ndarray, shape (N-1, n_sub)
    control_step, control_smooth : ndarray, shape (B, N-1, n_sub, 3)
        Estimated control (Eq. 32), LU/TU^2 (both None in the filter-only mode, ``smooth=False``).
    z_step, z_smooth : ndarray, shape (B,)
        Eq. 33, LU/TU (both None in the filter-only mode).
    residual_norms : ndarray, shape (B, N)
    z_smooth_ends : ndarray, shape (B, E) or None
        With ``smooth_ends`` (E end epochs :math:`e`): column ``j`` is the smoothed Eq. 33 of the arc
        ``t[0] .. t[e_j]`` alone, LU/TU (what ``z_smooth`` of the filter and smoother run on the first
        :math:`e_j + 1` epochs gives), from the one forward pass; None without ``smooth_ends``.
    failure_epoch : ndarray of int, shape (B,)
        Epoch at which each trial failed numerically (``on_failure="flag"``), -1 for a trial that did not; the
        epoch of the :class:`cislunar.estimation.ocbe.FilterDivergenceError` the single-trial filter raises.  A
        failed trial's arrays are NaN.
    failure : ndarray of str, shape (B,)
        The failure's message (``str`` of that error), "" for a trial that did not fail.
    """

    x_pred: np.ndarray
    x_filt: np.ndarray
    P_filt: np.ndarray
    x_smooth: np.ndarray | None
    P_smooth: np.ndarray | None
    t_sub: np.ndarray
    control_step: np.ndarray
    control_smooth: np.ndarray | None
    z_step: np.ndarray
    z_smooth: np.ndarray | None
    residual_norms: np.ndarray
    failure_epoch: np.ndarray | None = None
    failure: np.ndarray | None = None
    z_smooth_ends: np.ndarray | None = None

    @property
    def failed(self) -> np.ndarray:
        """Which trials failed numerically, shape (B,) bool."""
        if self.failure_epoch is None:
            return np.zeros(self.x_filt.shape[0], dtype=bool)
        return self.failure_epoch >= 0


def ocbe_batch(system: CR3BP, t, y, observer_states, model, meas_cov, x0, P0, control_weight, *, n_sub: int = 9,
               tol: float = DEFAULT_TOL, available=None, smooth: bool = True,
               on_failure: str = "raise", wrap_azimuth: bool = True, relinearize: bool = True,
               coarse_stm: bool = False, smooth_ends=None) -> BatchOCBEResult:
    """The extended SRI OCBE filter and full smoother of :func:`cislunar.estimation.ocbe.ocbe_filter_smoother` for B trials.

    Same algorithm, step for step (Eqs. 17, 21-32 and the backward SRI smoother with costates
    :math:`\\mathbf p_{n|N} = \\Phi_{xp}^{-1}\\hat{\\mathbf w}_n`), with all trials sharing the epochs, observers,
    availability, measurement model and noise; the transition blocks of all trials come from heyoka batch integrators
    (:func:`cislunar.estimation.ocbe.block_integrator`, :data:`_LANES` trials each; :math:`\\Phi_{pp}` formed from
    :math:`\\Phi_{xx}` through the CR3BP's invariant form, 78 states per trial) and the square-root-information
    updates are the stacked kernels of :mod:`cislunar.estimation.srif`.  Each trial's result does not depend on the
    other trials of the batch.

    Parameters
    ----------
    system : CR3BP
    t : array_like, shape (N,)
        Strictly increasing epochs, TU.
    y : array_like, shape (B, N, m) or (B, N, K, m)
        Measurements of each trial (angles in rad, rates per TU), from one observer or from K observers; entries
        where an observer is not ``available`` are ignored (NaN allowed there).
    observer_states : array_like, shape (N, 6) or (N, K, 6)
        Observer states at the epochs (shared by all trials).
    model : cislunar.sensing.measurements.MeasurementModel
    meas_cov : array_like, shape (m, m) or (N, m, m)
        Covariance of one observer's measurement (shared by all trials and observers; observers independent).
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
    available : array_like of bool, shape (N, K) or (N,), optional
        Which observers measured at each epoch (shared by all trials; default all).  An epoch without any
        measurement is a pure time update.
    smooth : bool
        Run the single-step and full smoothers and estimate the control (``False``: the filter only, faster; the
        smoothed and control fields are None).
    on_failure : {"raise", "flag"}
        A trial failing numerically raises (:class:`cislunar.estimation.ocbe.FilterDivergenceError` for a failed
        propagation, the numerical error otherwise) or is flagged in ``failure_epoch`` / ``failure`` with the
        epoch and message of the single-trial filter's error, its arrays NaN, while the others go on.
    wrap_azimuth : bool
        Wrap the angle components of the residuals to :math:`[-\\pi, \\pi)` (the default, as
        :meth:`cislunar.sensing.measurements.MeasurementModel.residual`), or use the plain difference
        ``y - h(x)`` (``False``: a filter that mishandles the azimuth's branch cut at :math:`\\pm\\pi`, where a
        residual across the cut is off by :math:`2\\pi`; identical to the default away from the cut).
    relinearize : bool
        Re-linearise about the updated estimate at every epoch (the default: the extended filter), or keep a fixed
        reference trajectory propagated from the prior mean ``x0`` (``False``: a linearised Kalman filter in SRI
        form; the transitions, process noise and measurement Jacobians are those of the reference, the estimated
        deviation is carried by :math:`\\Phi_{xx}` and the measurement residual is
        :math:`\\mathbf y - h(\\mathbf x_{ref}) - H\\,\\delta\\mathbf x^-`).  On a linear system the two are the
        same filter; here they differ at second order in the deviation from the reference.  Filter only
        (``smooth=False``).
    coarse_stm : bool
        Time update with the state/costate transition integrated along the reference (the default), or a coarse
        one (``True``): a single step over each update interval with the Jacobian frozen at the interval's start,
        :math:`\\Phi = \\exp(M\\Delta t)`, :math:`M = [A(\\mathbf x_n),\\ -B\\tilde QB^\\top;\\ 0,\\ -A(\\mathbf x_n)^\\top]`
        (:func:`_frozen_transition`), which ignores how :math:`A` changes through the interval (through perilune at
        long cadences).  The mean is still integrated.  Filter only (``smooth=False``).
    smooth_ends : sequence of int, optional
        End epochs :math:`e` (each in ``1 .. N-1``) of growing data arcs ``t[0] .. t[e]``: the smoothed control
        integral of each arc alone is returned in ``z_smooth_ends`` (with ``smooth=True``).  The forward filter on
        an arc is the first :math:`e + 1` epochs of the forward filter on the whole track, so one forward pass
        serves every arc; each arc gets only its own backward (smoother) pass, with the same kernels on the same
        stored quantities: equal, bit for bit, to ``z_smooth`` of a call on the first :math:`e + 1` epochs
        (``tests/estimation/test_batched_ocbe.py``).
    """
    check_system(system)
    model = ocbe.check_model(model)
    t = validation.time_grid(t, "t", increasing=True)
    N = t.size
    m = model.dim
    obs = validation.as_array(observer_states, "observer_states", ndim=(2, 3), last=6)
    if obs.shape[0] != N:
        raise ValueError(f"observer_states must have {N} epochs (shape ({N}, 6) or ({N}, K, 6)); got {obs.shape}")
    multi = obs.ndim == 3
    obs = obs if multi else obs[:, None, :]
    K = obs.shape[1]
    y = validation.as_array(y, "y", ndim=(4,) if multi else (3,), min_size=1, finite=False)
    B = y.shape[0]
    if y.shape[1:] != ((N, K, m) if multi else (N, m)):
        raise ValueError(f"y must have shape (B, {N}, {f'{K}, ' if multi else ''}{m}) to match observer_states and "
                         f"the model; got {y.shape}")
    y = y if multi else y[:, :, None, :]
    avail = ocbe._availability(available, N, K)
    if not np.all(np.isfinite(y[:, avail])):
        raise ValueError("y contains NaN or infinite values where measurements are available")
    R = validation.as_array(meas_cov, "meas_cov", ndim=(2, 3))
    if R.shape not in ((m, m), (N, m, m)):
        raise ValueError(f"meas_cov must have shape ({m}, {m}) or ({N}, {m}, {m}); got {R.shape}")
    R = validation.spd(R, "meas_cov", n=m, batch=True)
    validation.choice(on_failure, "on_failure", ("raise", "flag"))
    x = validation.as_array(x0, "x0", shape=(B, 6)).copy()
    if on_failure == "raise":  # flagged: a prior mean inside a primary fails its trial at epoch 1, as in ocbe.py
        check_outside_primaries(system, x, "x0", t0=t[0])
    P0 = validation.spd(P0, "P0", n=6, batch=True)
    if P0.shape not in ((6, 6), (B, 6, 6)):
        raise ValueError(f"P0 must have shape (6, 6) or ({B}, 6, 6); got {P0.shape}")
    P0 = np.broadcast_to(P0, (B, 6, 6))
    qs = ocbe.control_weights(control_weight, N - 1, batch=B)
    n_sub = validation.integer(n_sub, "n_sub", minimum=2, maximum=10_000)
    tol = _check_tol(tol)
    smooth = validation.boolean(smooth, "smooth")
    wrap_azimuth = validation.boolean(wrap_azimuth, "wrap_azimuth")
    relinearize = validation.boolean(relinearize, "relinearize")
    coarse_stm = validation.boolean(coarse_stm, "coarse_stm")
    if not relinearize and smooth:
        raise ValueError("relinearize=False (the fixed-reference filter) is filter only: pass smooth=False")
    if coarse_stm and smooth:
        raise ValueError("coarse_stm=True (the frozen-Jacobian time update) is filter only: pass smooth=False")
    if smooth_ends is not None:
        ends = validation.as_array(smooth_ends, "smooth_ends", ndim=(1,), min_size=1)
        if not np.all(ends == np.round(ends)) or np.any(ends < 1) or np.any(ends > N - 1):
            raise ValueError(f"smooth_ends must hold integer epochs in 1..{N - 1}; got {smooth_ends!r:.80}")
        if not smooth:
            raise ValueError("smooth_ends needs the smoother: pass smooth=True")
        smooth_ends = ends.astype(int)
    return _ocbe_batch(system, t, y, obs, avail, model, R, x, P0, qs, n_sub, tol, smooth, on_failure == "flag",
                       wrap_azimuth, relinearize, coarse_stm, smooth_ends)


#: Trials per heyoka batch integrator (larger lockstep batches are integrated in groups of
#: this size: the Taylor integrator's cost per trial grows again beyond a few SIMD widths).  Measured 2026-11-26d on
#: a 128-trial lockstep group (``benchmarks/bench_detection.py``): 32 lanes were about 7 % faster than 16 with the
#: 114-state integrator, 64 slower; with today's 78 states 32 and 16 cost the same (4.58 vs 4.60 ms per trial).
#: Results are bit-identical between 16 and 32 for full lane groups.
_LANES = 16


def _time_update_identity(R, Phi, Q):
    """:func:`cislunar.estimation.srif._time_update` with ``z = 0`` and ``Gamma = I`` (the OCBE's Eq. 23), the
    stacked array assembled in place instead of through :func:`srif._blocks`: the same entries, the same
    triangularisation, bit for bit the same result.  ``R``, ``Phi``, ``Q`` (B, 6, 6); unchecked (inner kernel)."""
    nb = R.shape[0]
    Rt = np.swapaxes(np.linalg.solve(np.swapaxes(Phi, -1, -2), np.swapaxes(R, -1, -2)), -1, -2)  # R Phi^{-1}
    A = np.zeros((nb, 12, 13))
    A[:, :6, :6] = srif._sri_of_cov(Q)
    A[:, 6:, :6] = -Rt @ _EYE6
    A[:, 6:, 6:12] = Rt
    U = srif._triangularize(A)
    return U[..., 6:, 6:12], U[..., 6:, 12], (U[..., :6, :6], U[..., :6, 6:12], U[..., :6, 12])


def _smoother_step_identity(Rs_next, zs_next, Phi, smoother_terms):
    """:func:`cislunar.estimation.srif._smoother_step` with ``Gamma = I``, assembled in place (bit for bit the
    same result).  Shapes (B, 6, 6) and (B, 6); unchecked (inner kernel)."""
    Rw, Rwx, zw = smoother_terms
    A = np.empty((Rs_next.shape[0], 12, 13))
    A[:, :6, :6] = Rw + Rwx @ _EYE6
    A[:, :6, 6:12] = Rwx @ Phi
    A[:, :6, 12] = zw
    A[:, 6:, :6] = Rs_next @ _EYE6
    A[:, 6:, 6:12] = Rs_next @ Phi
    A[:, 6:, 12] = zs_next
    U = srif._triangularize(A)
    return U[..., 6:12, 6:12], U[..., 6:12, 12]


_EYE6 = np.eye(6)

#: Integrate the costate block :math:`\Phi_{pp}` (114 states per trial) or form it from :math:`\Phi_{xx}` (78
#: states, ``costate_block=False`` of :func:`cislunar.estimation.ocbe.block_integrator`, about 1.2x faster
#: integration; equal to round-off, not bit for bit).  A switch for the benchmarks and tests, not an option.
_COSTATE_BLOCK = False


def _check_start_outside(system, x, n, time):
    """Raise :class:`ocbe.FilterDivergenceError` (cause: an ImpactError) if a trial's estimate ``x`` (B, 6) lies
    inside a primary at the start of interval ``n`` (ValueError if it is not finite)."""
    if np.all(np.isfinite(x)) and not _inside_primaries(system, x):  # the common case, without the checks' cost
        return
    try:
        check_outside_primaries(system, x, "the reference", t0=time)
    except ImpactError as exc:
        raise ocbe.FilterDivergenceError(n, time, f"ImpactError: {exc}") from exc


def _process_noise_per_trial(phi_xx, phi_xp):
    """:func:`ocbe._process_noise` with its symmetry check made trial by trial (each against its own scale)."""
    Q = -phi_xp @ np.swapaxes(phi_xx, -1, -2)
    asym = np.max(np.abs(Q - np.swapaxes(Q, -1, -2)), axis=(-2, -1))
    if np.any(asym > 1e-8 * np.maximum(np.max(np.abs(Q), axis=(-2, -1)), 1e-300)):
        raise ValueError(f"phi is not an OCBE transition matrix: -Phi_xp Phi_xx^T is not symmetric "
                         f"({np.max(asym):.2e})")
    return 0.5 * (Q + np.swapaxes(Q, -1, -2))


def _frozen_transition(system, x, dt, q):
    """The coarse OCBE transition of one step (``coarse_stm=True`` of :func:`ocbe_batch`): :math:`\\Phi_{xx}` and
    :math:`\\Phi_{xp}` of :math:`\\exp(M\\Delta t)` with :math:`M = [A(\\mathbf x),\\ -B\\tilde QB^\\top;\\ 0,\\
    -A(\\mathbf x)^\\top]`, the OCBE's 12x12 system with the Jacobian frozen at ``x`` (exact when :math:`A` is
    constant; otherwise its one-step error is :math:`O(\\Delta t^2)`).

    ``x`` (..., 6) in LU, LU/TU (rotating frame), ``dt`` in TU, ``q`` (...) or scalar in LU^2/TU^3 (unchecked: the
    batched filter's inner kernel).  Returns ``(phi_xx, phi_xp)``, each (..., 6, 6).
    """
    A = system.jacobian(x)
    M = np.zeros(A.shape[:-2] + (12, 12))
    M[..., :6, :6] = A
    M[..., 6:, 6:] = -np.swapaxes(A, -1, -2)
    M[..., 3:6, 9:12] = -np.asarray(q, dtype=float)[..., None, None] * np.eye(3)
    E = expm(M * dt)
    return np.array(E[..., :6, :6]), np.array(E[..., :6, 6:])


class _Failures:
    """The flagged trials of a batch: the epoch and message of each failure, and which trial each slot computes
    (a failed trial's slot repeats a live trial, so that the lockstep keeps its size and its compiled integrators)."""

    def __init__(self, t, B):
        self.t = t
        self.epoch = np.full(B, -1)
        self.message = [""] * B
        self.src = np.arange(B)

    @property
    def alive(self) -> np.ndarray:
        return np.flatnonzero(self.epoch < 0)

    def flag(self, b, epoch, exc):
        """Trial ``b`` failed at ``epoch`` with ``exc``: recorded as the single-trial filter's error would be."""
        cause = exc.cause if isinstance(exc, ocbe.FilterDivergenceError) else f"{type(exc).__name__}: {exc}"
        self.epoch[b] = epoch
        self.message[b] = str(ocbe.FilterDivergenceError(epoch, float(self.t[epoch]), cause))

    def donate(self):
        """Point every failed trial's slot at the first live trial; returns the live trials (None: none left)."""
        alive = self.alive
        if alive.size == 0:
            return None
        self.src = np.arange(self.epoch.size)
        self.src[self.epoch >= 0] = alive[0]
        return alive


def _per_trial(fn, B, failures, epoch, *, replicate):
    """After a batch call ``fn(failures.src)`` raised: run each live trial alone, flag those that fail.

    ``fn(idx)`` computes the trials ``idx`` (indices into the batch) and returns a tuple of arrays (or None) with
    that leading axis.  ``replicate``: the trial fills all ``B`` slots and its own slot's values are kept (the heyoka
    integrators are compiled per group size, so the lanes stay those of the batch); else it runs as a batch of one.
    Returns the tuple for all ``B`` slots (a failed trial's slot repeats a live trial), None if every trial failed.
    """
    parts = {}
    for b in failures.alive:
        idx = np.full(B, b) if replicate else np.array([b])
        try:
            out = fn(idx)
        except _DIVERGENCE as exc:
            failures.flag(b, epoch, exc)
            continue
        k = b if replicate else 0
        parts[b] = [None if o is None else np.array(o[k]) for o in out]
    alive = failures.donate()
    if alive is None:
        return None
    first = parts[alive[0]]
    return tuple(None if first[i] is None else np.stack([parts[failures.src[b]][i] for b in range(B)])
                 for i in range(len(first)))


def _ocbe_batch(system, t, y, obs, avail, model, R, x, P0, qs, n_sub, tol, smooth, flag, wrap_azimuth=True,
                relinearize=True, coarse_stm=False, ends=None) -> BatchOCBEResult:
    """:func:`ocbe_batch` after its argument checks: the loop of the single-trial filter with a trial axis.

    The SRI algebra is that of :func:`cislunar.estimation.ocbe.ocbe_filter_smoother` step for step, on the same
    :mod:`cislunar.estimation.srif` kernels; what the lockstep adds is where the transitions come from (the three
    non-zero 6x6 blocks of every trial from one batch integrator per :data:`_LANES` trials) and bookkeeping: the
    sub-grids and the integrators' initial state are allocated once.  Each stage (the first update, each interval,
    the closing smoother) is a function of the trials it computes; with ``flag``, a stage that raises is rerun
    trial by trial (:func:`_per_trial`) so that only the failing trials are dropped, at the epoch where the
    single-trial filter would have raised (0 for the first update, n+1 for interval n, N-1 for the smoother).
    ``wrap_azimuth``, ``relinearize`` and ``coarse_stm``: see :func:`ocbe_batch` (with ``relinearize=False`` the reference of each
    trial is carried beside its estimate; the deviation is their difference).  ``ends``: the ``smooth_ends`` of
    :func:`ocbe_batch` (checked), each arc's backward pass in :func:`_arc_z_smooth`.
    """
    B, N = y.shape[0], t.size
    lay = ocbe.BLOCK_LAYOUT
    s_xx, s_xp, s_pp = lay["phi_xx"], lay["phi_xp"], lay["phi_pp"]
    lanes = [(a, min(a + _LANES, B)) for a in range(0, B, _LANES)]
    costate_block = _COSTATE_BLOCK
    integrators = [ocbe.block_integrator(b - a, tol, costate_block=costate_block) for a, b in lanes]
    n_state = s_pp.stop if costate_block else s_xp.stop
    t_sub = np.array([np.linspace(t[n], t[n + 1], n_sub) for n in range(N - 1)])  # as the single-trial filter
    start = np.zeros((n_state, B))
    out = np.empty((n_sub, n_state, B))
    start[s_xx] = np.eye(6).ravel()[:, None]
    if costate_block:
        start[s_pp] = np.eye(6).ravel()[:, None]
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
        S_bar, _, term = _time_update_identity(S, Phi_xx, Q)  # Eq. 23 with Gamma = I, b_x = 0
        x_prior = np.array(end[:, :6])
        if not relinearize:  # the deviation from the fixed reference, carried by Phi_xx
            dx = (Phi_xx @ (x_cur[idx] - xs)[..., None])[..., 0]
            S_new, x_new, e = update(S_bar, x_prior, n + 1, y[idx, n + 1], dx)
            return x_prior + dx, S_new, x_new, e, x_prior
        S_new, x_new, e = update(S_bar, x_prior, n + 1, y[idx, n + 1])  # Eqs. 24-28
        if not smooth:  # filter only: no single-step smoother, no control estimate
            return x_prior, S_new, x_new, e
        if costate_block:
            pp_sub = np.moveaxis(out[:, s_pp], -1, 0).reshape(B, n_sub, 6, 6)  # a copy (not a view of out)
        else:  # Phi_pp = K Phi_xx K^-1 at the sub-grid points (ocbe.block_integrator, costate_block)
            pp_sub = ocbe._costate_block(np.moveaxis(out[:, s_xx], -1, 0).reshape(B, n_sub, 6, 6))
        # single-step smoother (Eqs. 29-30) and costate (Eq. 31)
        S1, b1 = _smoother_step_identity(S_new, (S_new @ (x_new - x_prior)[..., None])[..., 0], Phi_xx, term)
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
            return P_f, None, None, None, None, None, None, None
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
            Rs, bs = _smoother_step_identity(Rs, z_next, pxx[:, n], (Rw[idx, n], Rwx[idx, n], zw[idx, n]))
            x_s[:, n] = xf[:, n] + srif._solve_upper(Rs, bs)
            P_s[:, n] = srif._cov_of_sri(Rs)
        w = (x_s[:, 1:] - xp[:, 1:]) - (pxx @ (x_s[:, :-1] - xf[:, :-1])[..., None])[..., 0]
        p_s = np.linalg.solve(phi_xp[idx], w[..., None])[..., 0]
        pps = phi_pp_sub[idx]
        control_s = -q[:, :, None, None] * np.einsum("bnkij,bnj->bnki", pps, p_s)[..., 3:6]
        z_s = ocbe._control_integral(t_sub, control_s)
        if ends is None:
            return P_f, control_step, z_step, x_s, P_s, control_s, z_s, None
        z_ends = np.stack([z_s if e == N - 1 else
                           _arc_z_smooth(e, t_sub, q, S_filt[idx, e], xf, xp, pxx, Rw[idx], Rwx[idx], zw[idx],
                                         phi_xp[idx], pps) for e in ends], axis=-1)
        return P_f, control_step, z_step, x_s, P_s, control_s, z_s, z_ends

    done = stage(closing, N - 1, False) if res is not None else None
    if done is None:  # every trial failed
        full = (np.full((B, N, 6, 6), nan), np.full((B, N - 1, n_sub, 3), nan), np.full(B, nan))
        done = (full + (np.full((B, N, 6), nan),) + full) if smooth else (full[0],) + (None,) * 6
        done += (None if ends is None else np.full((B, ends.size), nan),)
    P_f, control_step, z_step, x_s, P_s, control_s, z_s, z_ends = done
    dead = failures.epoch >= 0
    if dead.any():
        for arr in (x_pred, x_filt, resid, P_f, control_step, z_step, x_s, P_s, control_s, z_s, z_ends):
            if arr is not None:
                arr[dead] = nan
    return BatchOCBEResult(x_pred, x_filt, P_f, x_s, P_s, t_sub, control_step, control_s, z_step, z_s, resid,
                           failures.epoch.copy(), np.array(failures.message, dtype=str), z_ends)


def _arc_z_smooth(e, t_sub, q, S_e, xf, xp, pxx, Rw, Rwx, zw, phi_xp, phi_pp_sub):
    """The smoothed Eq. 33 of the arc ``t[0] .. t[e]`` alone (LU/TU, shape (B,)) from the whole track's forward
    pass: the backward SRI smoother of ``closing`` in :func:`_ocbe_batch` started at epoch ``e`` (``S_e`` the
    filtered SRI matrix there, (B, 6, 6)), then the costates and controls of the arc's intervals.

    The arrays are the forward pass's stored quantities of the trials (``xf``, ``xp`` (B, N, 6); ``pxx``,
    ``phi_xp``, ``Rw``, ``Rwx`` (B, N-1, 6, 6); ``zw`` (B, N-1, 6); ``phi_pp_sub`` (B, N-1, n_sub, 6, 6); ``q``
    (B, N-1)).  Every kernel gets the arc's slice in the layout a call on the first ``e + 1`` epochs gives it
    (contiguous copies where that call's arrays are contiguous), so the result is that call's ``z_smooth`` bit for
    bit.  Covariances are not formed (z does not need them).  Unchecked (inner kernel).
    """
    nb = xf.shape[0]
    x_s = np.empty((nb, e + 1, 6))
    Rs, bs = S_e, np.zeros((nb, 6))
    x_s[:, -1] = xf[:, e]
    for n in range(e - 1, -1, -1):
        z_next = bs + (Rs @ (xf[:, n + 1] - xp[:, n + 1])[..., None])[..., 0]
        Rs, bs = _smoother_step_identity(Rs, z_next, pxx[:, n], (Rw[:, n], Rwx[:, n], zw[:, n]))
        x_s[:, n] = xf[:, n] + srif._solve_upper(Rs, bs)
    pxx_e = np.ascontiguousarray(pxx[:, :e])
    w = (x_s[:, 1:] - xp[:, 1:e + 1]) - (pxx_e @ (x_s[:, :-1] - xf[:, :e])[..., None])[..., 0]
    p_s = np.linalg.solve(np.ascontiguousarray(phi_xp[:, :e]), w[..., None])[..., 0]
    q_e = np.ascontiguousarray(q[:, :e])
    control_s = -q_e[:, :, None, None] * np.einsum("bnkij,bnj->bnki", np.ascontiguousarray(phi_pp_sub[:, :e]),
                                                   p_s)[..., 3:6]
    return ocbe._control_integral(t_sub[:e], control_s)
