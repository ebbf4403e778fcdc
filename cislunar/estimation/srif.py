r"""Square-root information filtering and smoothing (Tapley, Schutz & Born 2004, ch. 5; Bierman 1977).

The state estimate is carried as a square-root information pair :math:`(R, z)`: :math:`R` is upper triangular
with :math:`R^\top R = P^{-1}` and :math:`R\,\hat x = z`.  Every update is an orthogonal (Householder)
triangularisation of a stacked array, so information is never squared and the covariance
:math:`P = R^{-1}R^{-\top}` stays symmetric positive definite by construction.  This is the numerical core that
the OCBE of the maneuver-detection paper (Greaves & Scheeres 2021, §State Estimation) is written in.

Model, for ``k = 0 .. N-1``::

    x_{k+1} = Phi_k x_k + Gamma_k w_k,   w_k ~ N(0, Q_k)        (time update)
    y_k     = H_k x_k + v_k,              v_k ~ N(0, R_k)        (measurement update)

Units are whatever the caller's state uses; all arrays are plain ``numpy`` arrays.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cislunar.utils import validation

__all__ = [
    "householder_triangularize",
    "sri_from_covariance",
    "covariance_from_sri",
    "measurement_update",
    "time_update",
    "smoother_step",
    "SRIResult",
    "filter_smoother",
    "filter_many",
    "factor_process_noise",
]


def householder_triangularize(A) -> np.ndarray:
    """Orthogonal triangularisation :math:`T A = [U; 0]` (LAPACK Householder QR); returns the ``min(m, n)`` rows of U.

    Row signs are normalised so that the diagonal is non-negative (the factor is then unique for full rank).
    """
    return _triangularize(validation.as_array(A, "A", ndim=(2,)))


# Unchecked kernels, written once in stacked form: every array may carry leading batch axes (B, ...) that broadcast
# against each other, and a single matrix is the case without them.  The public functions below validate their
# arguments and call these; the filters built on this module (the single-trial OCBE of cislunar.estimation.ocbe and
# the B-trial lockstep OCBE of cislunar.estimation.batched_ocbe) validate once at their own boundary and call the
# kernels in their inner loops.
def _triangularize(A):
    """Householder QR of A (..., m, n): the min(m, n) rows of U, with non-negative diagonal."""
    r = np.linalg.qr(A, mode="r")
    d = np.sign(np.diagonal(r, axis1=-2, axis2=-1)).copy()
    d[d == 0] = 1.0
    return r * d[..., :, None]


def _blocks(rows):
    """:func:`numpy.block` for stacks: a list of block rows whose blocks share (broadcast) leading axes."""
    lead = np.broadcast_shapes(*(b.shape[:-2] for row in rows for b in row))
    return np.concatenate([np.concatenate([np.broadcast_to(b, lead + b.shape[-2:]) for b in row], axis=-1)
                           for row in rows], axis=-2)


def _sri_of_cov(C):
    """W upper triangular with W^T W = C^{-1} (..., n, n); raises LinAlgError if C is not positive definite."""
    L = np.linalg.cholesky(0.5 * (C + np.swapaxes(C, -1, -2)))
    return _triangularize(np.linalg.inv(L))  # C = L L^T -> C^{-1} = L^{-T} L^{-1}; W = L^{-1} re-triangularised


def _solve_upper(R, b):
    """x with R x = b for stacks of upper-triangular R (..., n, n) and b (..., n)."""
    return np.linalg.solve(R, b[..., None])[..., 0]


def _cov_of_sri(R, z=None):
    """Covariance R^{-1}R^{-T} (..., n, n), and the mean R^{-1}z first if ``z`` (..., n) is given."""
    Rinv = np.linalg.inv(R)
    P = Rinv @ np.swapaxes(Rinv, -1, -2)
    return P if z is None else ((Rinv @ z[..., None])[..., 0], P)


def _measurement_update(R, z, H, y, meas_cov):
    """Stacked :func:`measurement_update`: R (..., n, n), z (..., n), H (..., m, n), y (..., m), meas_cov (..., m, m).

    Returns ``R_new, z_new, residual_norm`` (the last of shape (...)).
    """
    n = R.shape[-1]
    W = _sri_of_cov(meas_cov)
    U = _triangularize(_blocks([[R, z[..., None]], [W @ H, W @ y[..., None]]]))
    return U[..., :n, :n], U[..., :n, n], np.abs(U[..., n, n])


def _time_update(R, z, Phi, Gamma, Q):
    """Stacked :func:`time_update` with process noise (Gamma (..., n, r), Q (..., r, r))."""
    n, r = R.shape[-1], Gamma.shape[-1]
    Rt = np.swapaxes(np.linalg.solve(np.swapaxes(Phi, -1, -2), np.swapaxes(R, -1, -2)), -1, -2)  # R Phi^{-1}
    A = _blocks([[_sri_of_cov(Q), np.zeros((r, n)), np.zeros((r, 1))], [-Rt @ Gamma, Rt, z[..., None]]])
    U = _triangularize(A)
    return U[..., r:, r:r + n], U[..., r:, r + n], (U[..., :r, :r], U[..., :r, r:r + n], U[..., :r, r + n])


def _smoother_step(Rs_next, zs_next, Phi, Gamma, smoother_terms):
    """Stacked :func:`smoother_step`; ``smoother_terms`` is the (Rw, Rwx, zw) triple of :func:`_time_update`."""
    Rw, Rwx, zw = smoother_terms
    r, n = Rw.shape[-2], Rs_next.shape[-1]
    A = _blocks([[Rw + Rwx @ Gamma, Rwx @ Phi, zw[..., None]], [Rs_next @ Gamma, Rs_next @ Phi, zs_next[..., None]]])
    U = _triangularize(A)
    return U[..., r:r + n, r:r + n], U[..., r:r + n, r + n]


def _chol_upper_inverse(C, name):
    """Upper-triangular W with W^T W = C^{-1} (i.e. the square-root information matrix of covariance C)."""
    C = validation.square(C, name)
    if C.shape[0] == 0:
        raise ValueError(f"{name} must not be empty")
    if not np.allclose(C, C.T, rtol=1e-10, atol=1e-14 * max(1.0, np.max(np.abs(C)))):
        raise ValueError(f"{name} must be symmetric")
    validation.spd(C, name)  # also refuses numerically singular covariances (validation.SPD_RCOND)
    try:
        return _sri_of_cov(C)
    except np.linalg.LinAlgError:
        raise ValueError(f"{name} must be symmetric positive definite") from None


def sri_from_covariance(x, P, *, name: str = "P") -> tuple[np.ndarray, np.ndarray]:
    """Square-root information pair ``(R, z)`` of a mean ``x`` (n,) and covariance ``P`` (n, n).

    ``name`` is the caller's name for ``P`` in error messages (e.g. ``"P0"``).
    """
    x = validation.as_array(x, "x", ndim=(1,))
    R = _chol_upper_inverse(P, name)
    if R.shape[0] != x.size:
        raise ValueError(f"x has length {x.size} but P is {P.shape}")
    return R, R @ x


def covariance_from_sri(R, z=None):
    """Covariance :math:`R^{-1}R^{-\\top}` (and mean :math:`R^{-1}z` if ``z`` is given) of an SRI pair."""
    R = validation.upper_triangular(R, "R")
    if z is None:
        return _cov_of_sri(R)
    return _cov_of_sri(R, validation.as_array(z, "z", shape=(R.shape[0],)))


def measurement_update(R, z, H, y, meas_cov):
    """Fold a measurement ``y = H x + v``, ``v ~ N(0, meas_cov)`` into the SRI pair.

    Whitening with :math:`W^\\top W = R_v^{-1}` gives :math:`W y = W H x + \\tilde v` with unit noise; the stack
    :math:`[R\\ z;\\ WH\\ Wy]` is triangularised.

    Returns
    -------
    R_new, z_new : ndarray
    residual_norm : float
        Norm of the whitened residual that this update adds to the least-squares cost (the one non-zero entry
        below ``z_new`` after triangularisation).
    """
    R = validation.upper_triangular(R, "R", nonsingular=False)
    n = R.shape[0]
    z = validation.as_array(z, "z", shape=(n,))
    H = validation.as_array(H, "H", ndim=(2,))
    if H.shape[1] != n:
        raise ValueError(f"H must have {n} columns to match R; got shape {H.shape}")
    y = validation.as_array(y, "y", shape=(H.shape[0],))
    W = _chol_upper_inverse(meas_cov, "meas_cov")
    if W.shape[0] != H.shape[0]:
        raise ValueError(f"meas_cov must be {H.shape[0]}x{H.shape[0]}; got {np.shape(meas_cov)}")
    R_new, z_new, e = _measurement_update(R, z, H, y, meas_cov)  # triangularised [R_new z_new; 0 e]
    return R_new, z_new, float(e)


def factor_process_noise(Q, *, rtol: float = 1e-12):
    """Factor a symmetric positive semi-definite ``Q`` (n, n) as :math:`\\Gamma\\Gamma^\\top` with Gamma (n, r).

    ``r`` is the numerical rank (eigenvalues above ``rtol`` times the largest).  With unit-covariance noise
    :math:`w\\sim N(0, I_r)`, :math:`\\Gamma w` has covariance Q; this is how a possibly singular process-noise
    matrix (e.g. the OCBE's :math:`-\\Phi_{xp}\\Phi_{xx}^\\top`) enters the SRI time update.
    """
    Q = validation.as_array(Q, "Q", ndim=(2,))
    if Q.shape[0] != Q.shape[1]:
        raise ValueError(f"Q must be square; got shape {Q.shape}")
    scale = max(np.max(np.abs(Q)), 1e-300)
    if not np.allclose(Q, Q.T, rtol=1e-8, atol=1e-12 * scale):
        raise ValueError("Q must be symmetric")
    lam, V = np.linalg.eigh(0.5 * (Q + Q.T))
    if lam.min() < -1e-8 * max(lam.max(), 0.0) - 1e-300:
        raise ValueError(f"Q must be positive semi-definite; smallest eigenvalue {lam.min():.3e}")
    keep = lam > rtol * max(lam.max(), 0.0)
    return V[:, keep] * np.sqrt(lam[keep])


def time_update(R, z, Phi, Gamma=None, Q=None):
    """Propagate an SRI pair through ``x+ = Phi x + Gamma w``, ``w ~ N(0, Q)``.

    Without process noise: :math:`\\bar R = R\\Phi^{-1}` (re-triangularised), :math:`\\bar z = z`.  With process
    noise the stack :math:`[R_w\\ 0\\ 0;\\ -\\tilde R\\Gamma\\ \\tilde R\\ z]`, :math:`\\tilde R = R\\Phi^{-1}`, is
    triangularised in the variables :math:`(w, x_+)` (Tapley et al. §5.7).

    Returns
    -------
    R_next, z_next : ndarray
    smoother_terms : tuple or None
        ``(Rw_bar, Rwx_bar, zw_bar)``: the first block row, kept for :func:`smoother_step`.
    """
    R = validation.upper_triangular(R, "R", nonsingular=False)
    n = R.shape[0]
    z = validation.as_array(z, "z", shape=(n,))
    Phi = validation.as_array(Phi, "Phi", shape=(n, n))
    try:
        Rt = np.linalg.solve(Phi.T, R.T).T  # R Phi^{-1}
    except np.linalg.LinAlgError:
        raise ValueError("Phi must be an invertible transition matrix; it is singular") from None
    if not np.all(np.isfinite(Rt)):
        raise ValueError("Phi must be an invertible transition matrix; it is numerically singular")
    if Gamma is None and Q is None:
        U = _triangularize(np.hstack([Rt, z[:, None]]))
        return U[:, :n], U[:, n], None
    if Gamma is None or Q is None:
        raise ValueError("Gamma and Q must be given together (or both omitted for no process noise)")
    Gamma = validation.as_array(Gamma, "Gamma", ndim=(2,))
    if Gamma.shape[0] != n:
        raise ValueError(f"Gamma must have {n} rows; got shape {Gamma.shape}")
    r = Gamma.shape[1]
    if _chol_upper_inverse(Q, "Q").shape[0] != r:
        raise ValueError(f"Q must be {r}x{r} to match Gamma; got {np.shape(Q)}")
    return _time_update(R, z, Phi, Gamma, np.asarray(Q, dtype=float))


def smoother_step(Rs_next, zs_next, Phi, Gamma, smoother_terms):
    """One backward step of the SRI smoother (Tapley et al. §5.8; Bierman's SRIS).

    Given the smoothed pair at ``k+1`` and the terms stored by the time update ``k -> k+1``, substitute
    :math:`x_{k+1} = \\Phi x_k + \\Gamma w_k` into both information equations and triangularise in
    :math:`(w_k, x_k)`; the lower block is the smoothed pair at ``k``.
    """
    Rs_next = validation.upper_triangular(Rs_next, "Rs_next", nonsingular=False)
    n = Rs_next.shape[0]
    zs_next = validation.as_array(zs_next, "zs_next", shape=(n,))
    Phi = validation.as_array(Phi, "Phi", shape=(n, n))
    Gamma = validation.as_array(Gamma, "Gamma", ndim=(2,))
    if Gamma.shape[0] != n:
        raise ValueError(f"Gamma must have {n} rows; got shape {Gamma.shape}")
    if not isinstance(smoother_terms, (tuple, list)) or len(smoother_terms) != 3:
        raise validation.ArgumentTypeError("smoother_terms must be the (Rw_bar, Rwx_bar, zw_bar) tuple returned by "
                                        "time_update with process noise")
    Rw = validation.as_array(smoother_terms[0], "smoother_terms[0]", ndim=(2,))
    r = Rw.shape[0]
    Rwx = validation.as_array(smoother_terms[1], "smoother_terms[1]", shape=(r, n))
    zw = validation.as_array(smoother_terms[2], "smoother_terms[2]", shape=(r,))
    if Gamma.shape[1] != r:
        raise ValueError(f"Gamma must have {r} columns to match smoother_terms; got shape {Gamma.shape}")
    return _smoother_step(Rs_next, zs_next, Phi, Gamma, (Rw, Rwx, zw))


@dataclass(frozen=True)
class SRIResult:
    """Filtered and smoothed estimates at every measurement epoch.

    Attributes
    ----------
    x_filt, P_filt : ndarray, shapes (N, n), (N, n, n)
        Measurement-updated means and covariances.
    x_pred, P_pred : ndarray
        Time-updated (a priori) means and covariances; entry 0 is the initial prior.
    x_smooth, P_smooth : ndarray or None
        Smoothed means and covariances (when process noise is present at every step, or N == 1).
    R_filt : ndarray, shape (N, n, n)
        Filtered square-root information matrices.
    residuals : ndarray, shape (N,)
        Whitened residual norm added by each measurement update (0 where there was no measurement).
    """

    x_filt: np.ndarray
    P_filt: np.ndarray
    x_pred: np.ndarray
    P_pred: np.ndarray
    x_smooth: np.ndarray | None
    P_smooth: np.ndarray | None
    R_filt: np.ndarray
    residuals: np.ndarray


def filter_smoother(x0, P0, Phis, Hs, ys, meas_covs, Gammas=None, Qs=None, *, smooth: bool = True) -> SRIResult:
    """Run the SRI filter over ``N`` epochs, then (optionally) the SRI smoother backwards.

    Parameters
    ----------
    x0, P0 : array_like
        Prior mean (n,) and covariance (n, n) at epoch 0.
    Phis : array_like, shape (N-1, n, n)
        Transition matrices from epoch k to k+1.
    Hs, ys, meas_covs : sequences of length N
        Measurement matrices (m_k, n), measurements (m_k,) and noise covariances (m_k, m_k); an epoch without a
        measurement has ``H`` of shape (0, n).
    Gammas, Qs : sequences of length N-1, optional
        Process-noise maps (n, r_k) and covariances (r_k, r_k).  Smoothing needs them.
    smooth : bool
        Run the backward pass.
    """
    x0 = validation.as_array(x0, "x0", ndim=(1,), min_size=1)
    n = x0.size
    if np.shape(P0) != (n, n):
        raise ValueError(f"P0 must be {n}x{n} to match x0 (length {n}); got shape {np.shape(P0)}")
    validation.spd(P0, "P0", n=n)
    smooth = validation.boolean(smooth, "smooth")
    for name, seq in (("Phis", Phis), ("Hs", Hs), ("ys", ys), ("meas_covs", meas_covs), ("Gammas", Gammas),
                      ("Qs", Qs)):
        if seq is None and name in ("Gammas", "Qs"):
            continue
        try:
            len(seq)
            ok = not isinstance(seq, (str, bytes))
        except TypeError:
            ok = False
        if not ok:
            raise validation.ArgumentTypeError(f"{name} must be a sequence (one entry per epoch); got "
                                            f"{type(seq).__name__} {seq!r:.40}")
    Phis = validation.as_array(Phis, "Phis", ndim=(3,)) if len(Phis) else np.zeros((0, n, n))
    N = Phis.shape[0] + 1
    if Phis.shape[1:] != (n, n):
        raise ValueError(f"Phis must have shape (N-1, {n}, {n}); got {Phis.shape}")
    for name, seq in (("Hs", Hs), ("ys", ys), ("meas_covs", meas_covs)):
        if len(seq) != N:
            raise ValueError(f"{name} must have {N} entries (one per epoch); got {len(seq)}")
    noise = Gammas is not None
    if noise and (Qs is None or len(Gammas) != N - 1 or len(Qs) != N - 1):
        raise ValueError(f"Gammas and Qs must both have {N - 1} entries")
    R, z = sri_from_covariance(x0, P0, name="P0")
    xf, Pf, xp, Pp, Rf, res, terms = [], [], [], [], [], [], []
    for k in range(N):
        m, P = covariance_from_sri(R, z)
        xp.append(m)
        Pp.append(P)
        H = validation.as_array(Hs[k], f"Hs[{k}]").reshape(-1, n) if np.size(Hs[k]) else np.zeros((0, n))
        if H.shape[0]:
            R, z, e = measurement_update(R, z, H, ys[k], meas_covs[k])
        else:
            e = 0.0
        res.append(e)
        m, P = covariance_from_sri(R, z)
        xf.append(m)
        Pf.append(P)
        Rf.append(R)
        if k < N - 1:
            if noise:
                R, z, t = time_update(R, z, Phis[k], Gammas[k], Qs[k])
            else:
                R, z, t = time_update(R, z, Phis[k])
            terms.append(t)
    xs = Ps = None
    if smooth and (noise or N == 1):
        Rs, zs = R, z
        xs_list, Ps_list = [None] * N, [None] * N
        xs_list[-1], Ps_list[-1] = covariance_from_sri(Rs, zs)
        for k in range(N - 2, -1, -1):
            Rs, zs = smoother_step(Rs, zs, Phis[k], np.asarray(Gammas[k], float), terms[k])
            xs_list[k], Ps_list[k] = covariance_from_sri(Rs, zs)
        xs, Ps = np.array(xs_list), np.array(Ps_list)
    return SRIResult(np.array(xf), np.array(Pf), np.array(xp), np.array(Pp), xs, Ps, np.array(Rf), np.array(res))


def filter_many(x0s, P0, Phis, Hs, ys, meas_covs, Gammas=None, Qs=None):
    """The SRI filter of :func:`filter_smoother` (forward pass) for M measurement sets of the same model at once.

    The square-root information matrix does not depend on the measurements, so one triangularisation per update
    carries every set as an extra right-hand-side column of the information vector (Bierman 1977, ch. V): each
    set's estimate equals :func:`filter_smoother`'s for that set to round-off, at the cost of about one filter.

    Parameters
    ----------
    x0s : array_like, shape (M, n)
        Prior means, one per set (the prior covariance ``P0`` (n, n) is shared).
    Phis, Hs, meas_covs, Gammas, Qs
        As in :func:`filter_smoother` (shared by all sets); an epoch without a measurement has ``H`` of shape
        (0, n).
    ys : array_like, shape (M, N, m) or sequence of length N of arrays (M, m_k)
        The measurements of each set at each epoch (``(M, 0)`` or anything empty where ``H`` is empty).

    Returns
    -------
    x_filt : ndarray, shape (M, N, n)
    P_filt : ndarray, shape (N, n, n)
        :math:`R^{-1}R^{-\\top}` (shared).
    R_filt : ndarray, shape (N, n, n)
        Square-root information matrices after each update (shared).
    """
    x0s = validation.as_array(x0s, "x0s", ndim=(2,), min_size=1)
    M, n = x0s.shape
    if np.shape(P0) != (n, n):
        raise ValueError(f"P0 must be {n}x{n} to match x0s (shape {x0s.shape}); got shape {np.shape(P0)}")
    empty = isinstance(Phis, (list, tuple)) and len(Phis) == 0
    Phis = np.zeros((0, n, n)) if empty else validation.as_array(Phis, "Phis", ndim=(3,))
    if Phis.shape[1:] != (n, n):
        raise ValueError(f"Phis must have shape (N-1, {n}, {n}); got {Phis.shape}")
    N = Phis.shape[0] + 1
    for name, seq in (("Hs", Hs), ("meas_covs", meas_covs), ("Gammas", Gammas), ("Qs", Qs)):
        if seq is None and name in ("Gammas", "Qs"):
            continue
        if isinstance(seq, (str, bytes)) or not hasattr(seq, "__len__"):
            raise validation.ArgumentTypeError(f"{name} must be a sequence (one entry per epoch); got "
                                               f"{type(seq).__name__}")
    for name, seq in (("Hs", Hs), ("meas_covs", meas_covs)):
        if len(seq) != N:
            raise ValueError(f"{name} must have {N} entries (one per epoch); got {len(seq)}")
    if isinstance(ys, (str, bytes)) or not hasattr(ys, "__len__"):
        raise validation.ArgumentTypeError(f"ys must be an array (M, N, m) or a sequence of N arrays; got "
                                           f"{type(ys).__name__}")
    if isinstance(ys, np.ndarray) and ys.ndim == 3:
        if ys.shape[:2] != (M, N):
            raise ValueError(f"ys must have shape ({M}, {N}, m) to match x0s and Phis; got {ys.shape}")

        def y_of(k):
            return ys[:, k]
    else:
        if len(ys) != N:
            raise ValueError(f"ys must have {N} entries (one per epoch); got {len(ys)}")

        def y_of(k):
            return np.asarray(ys[k], dtype=float)
    noise = Gammas is not None
    if noise and (Qs is None or len(Gammas) != N - 1 or len(Qs) != N - 1):
        raise ValueError(f"Gammas and Qs must both have {N - 1} entries")
    R = _chol_upper_inverse(P0, "P0")
    Z = R @ x0s.T  # (n, M): one information vector per set
    xf, Rf = np.empty((M, N, n)), np.empty((N, n, n))
    for k in range(N):
        H = validation.as_array(Hs[k], f"Hs[{k}]").reshape(-1, n) if np.size(Hs[k]) else np.zeros((0, n))
        if H.shape[0]:
            Y = validation.as_array(y_of(k), f"ys at epoch {k}", shape=(M, H.shape[0]))
            W = _chol_upper_inverse(meas_covs[k], f"meas_covs[{k}]")
            if W.shape[0] != H.shape[0]:
                raise ValueError(f"meas_covs[{k}] must be {H.shape[0]}x{H.shape[0]}")
            U = _triangularize(np.block([[R, Z], [W @ H, W @ Y.T]]))
            R, Z = U[:n, :n], U[:n, n:]
        xf[:, k] = np.linalg.solve(R, Z).T
        Rf[k] = R
        if k < N - 1:
            Phi = Phis[k]
            Rt = np.linalg.solve(Phi.T, R.T).T  # R Phi^{-1}
            if noise:
                G = validation.as_array(Gammas[k], f"Gammas[{k}]", ndim=(2,))
                Rw = _chol_upper_inverse(Qs[k], f"Qs[{k}]")
                r = Rw.shape[0]
                U = _triangularize(np.block([[Rw, np.zeros((r, n)), np.zeros((r, M))], [-Rt @ G, Rt, Z]]))
                R, Z = U[r:r + n, r:r + n], U[r:r + n, r + n:]
            else:
                U = _triangularize(np.hstack([Rt, Z]))
                R, Z = U[:n, :n], U[:n, n:]
    return xf, _cov_of_sri(Rf), Rf
