r"""Mutual information of an observation window and its gradient (Wolf & Jones Eqs. 9-23 and 44-52).

The linear-Gaussian measurement sequence
-----------------------------------------
Measurements are taken at :math:`t_0, \dots, t_{N-1}` (the paper indexes them 0..N_meas).  With
:math:`\mathbf x_k = F_{k-1}\mathbf x_{k-1} + \mathbf w_k`, :math:`\mathbf w_k\sim\mathcal N(0, Q_k)`,
:math:`\mathbf x_0\sim\mathcal N(\bar{\mathbf x}_0, P_0)` and :math:`\mathbf y_k = H_k\mathbf x_k + \mathbf v_k`,
:math:`\mathbf v_k\sim\mathcal N(0,R_k)`, the stacked measurement vector is linear in
:math:`[\mathbf x_0; \mathbf w_1; \dots; \mathbf w_{N-1}]`:

* :math:`\tilde P = \mathrm{diag}(P_0, Q_1, \dots, Q_{N-1})` (Eq. 19),
* :math:`\tilde H_{jk} = H_j\Phi(t_j, t_k)` for :math:`k\le j`, 0 otherwise, with
  :math:`\Phi(t_j,t_k) = F_{j-1}\cdots F_k` (Eqs. 20-22),
* :math:`\tilde R = \mathrm{diag}(R_0, \dots, R_{N-1})` (Eq. 23),

and the mutual information (Eq. 18) is :math:`\mathcal I = \tfrac12\ln(|\tilde H\tilde P\tilde H^T + \tilde R| /
|\tilde R|)`.  Arrays here use the convention of :class:`cislunar.sensing.covariance.AugmentedLinearization`:
``F[k]`` maps :math:`t_k \to t_{k+1}` and ``Q[k]`` is the noise added over that interval.

Two evaluations
---------------
* **dense** (:func:`mutual_information_dense`, :func:`mutual_information_gradient_dense`): the stacked matrices
  and Eqs. 18, 47-48 as written; memory :math:`O(N^2)`, time :math:`O(N^3)`.  Kept as the reference.
* **structured** (:func:`mutual_information`, :func:`mutual_information_gradient`): the chain rule of mutual
  information, :math:`\mathcal I(X;Y) = \sum_k \mathcal I(X; \mathbf y_k\,|\,\mathbf y_{0:k-1})`, where each term
  is the information gain of one Kalman measurement update,

  .. math:: \mathcal I_k = \tfrac12\ln\left|I + R_k^{-1/2}H_k\bar P_kH_k^TR_k^{-T/2}\right|,

  with :math:`\bar P_k` the Kalman prior covariance (the determinant identity :math:`|S| = \prod_k |S_k|` of the
  block-LDL factorisation of :math:`\tilde S`).  Cost is linear in N.  The recursion runs in square-root form
  (QR factorisations of pre-arrays): on test case 2's window the posterior covariance has a condition number of
  ~4e9 and the covariance form loses ~5 digits of the MI (1e-5 relative), which made value and finite differences
  disagree; the square-root form keeps ~1e-10.  The gradient is the reverse-mode (adjoint) derivative of the same
  square-root recursion (:func:`_gradient_sqrt_reverse`: one forward sweep storing the triangular factors, one
  backward sweep of two small matrix products per measurement time, the rest batched over the window; cost
  independent of the number of parameters).  Kept for reference: the forward-mode derivative of the square-root
  recursion (``method="sqrt-forward"``, cost proportional to the number of parameters, same accuracy) and the
  reverse-mode derivative of the covariance form (``method="adjoint"``, ~1e-5 relative error on ill-conditioned
  windows).

Gradient (Eqs. 44-52)
---------------------
The derivatives of ``F`` and ``H`` with respect to the observer state at the window start come from the
observer's second-order STT and the measurement Hessians (:func:`cislunar.sensing.covariance.linearize_augmented` with
``derivatives=True``); :math:`\tilde P` and :math:`\tilde R` are held fixed, as in the paper ("this formulation
does not account for the sensitivity of the process noise covariance").  The dense gradient uses Eq. 47-48 in the
equivalent trace form :math:`\partial\mathcal I/\partial\xi = \mathrm{tr}(\tilde S^{-1}\,\partial\tilde H/\partial\xi\,
\tilde P\tilde H^T)` with :math:`\partial\tilde H` assembled block by block as in Eq. 50 (product rule along the
chain of transition matrices).

Range-dependent measurement noise (keyword-only, off by default)
-----------------------------------------------------------------
The linear-Gaussian MI of range-rate measurements grows without bound as the observer nears a target: the
range-rate row of :math:`H` with respect to the relative position is :math:`(\Delta\dot{\mathbf r} -
\dot\rho\hat\rho)^T/\rho`.  :func:`range_noise_scale` gives the row scale of a noise whose standard deviation
grows as the range shrinks, :math:`\sigma(\rho) = \sigma\sqrt{1 + (\rho_c/\rho)^2}` (unchanged far from the
target, :math:`\propto 1/\rho` inside :math:`\rho_c`), for every row of a target; since scaling the noise of a
target's rows by :math:`g` is the same as scaling those rows of :math:`H` by :math:`1/g` (the noise blocks are per
target), :class:`InformationKernel` and :func:`window_information` take it as ``row_scale`` (and its derivative
``d_row_scale`` for the gradient).  With the defaults (``None``) every value is bit-for-bit unchanged.

All logarithms are natural: information in nats.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from scipy.linalg import lapack as _lapack

from cislunar.sensing.covariance import (
    AugmentedLinearization,
    _check_linear_system,
    _check_q_r,
    _cholesky,
    _logdet,
    _spd,
    _sym,
    check_spd,
)
from cislunar.utils import validation

__all__ = [
    "stacked_matrices",
    "stacked_derivative",
    "mutual_information_dense",
    "mutual_information",
    "mutual_information_gradient_dense",
    "mutual_information_gradient",
    "InformationKernel",
    "window_information",
    "range_noise_scale",
    "regularised_range_rate_jacobian",
    "gaussian_kl",
    "monte_carlo_mutual_information",
    "TimingResult",
    "time_evaluations",
]


def _transition_products(F: np.ndarray) -> list:
    """``Phi[j][k] = Phi(t_j, t_k)`` for k <= j (identity on the diagonal)."""
    N = F.shape[0] + 1
    n = F.shape[-1]
    Phi = [[None] * N for _ in range(N)]
    for k in range(N):
        Phi[k][k] = np.eye(n)
        for j in range(k + 1, N):
            Phi[j][k] = F[j - 1] @ Phi[j - 1][k]
    return Phi


def stacked_matrices(P0, F, Q, H, R):
    """The stacked :math:`\\tilde P`, :math:`\\tilde H`, :math:`\\tilde R` of Eqs. 19, 20 and 23.

    Parameters
    ----------
    P0 : array_like (n, n)
        Covariance at ``t_0`` (SPD).
    F : array_like (N-1, n, n)
        Transition matrices ``t_k -> t_{k+1}``.
    Q : array_like (N-1, n, n) or (n, n)
        Process noise over each interval (symmetric PSD).
    H : array_like (N, M, n)
    R : array_like (N, M, M) or (M, M)
        Measurement noise covariances (SPD).

    Returns
    -------
    P_tilde : ndarray (N n, N n)
    H_tilde : ndarray (N M, N n)
    R_tilde : ndarray (N M, N M)
    """
    P0, F, Q, H, R = _check_linear_system(P0, F, Q, H, R)
    return _stacked(P0, F, Q, H, R)


def _stacked(P0, F, Q, H, R):
    N, M, n = H.shape
    Pt = np.zeros((N * n, N * n))
    Pt[:n, :n] = P0
    for k in range(1, N):
        Pt[k * n:(k + 1) * n, k * n:(k + 1) * n] = Q[k - 1]
    Phi = _transition_products(F)
    Ht = np.zeros((N * M, N * n))
    for j in range(N):
        for k in range(j + 1):
            Ht[j * M:(j + 1) * M, k * n:(k + 1) * n] = H[j] @ Phi[j][k]
    Rt = np.zeros((N * M, N * M))
    for j in range(N):
        Rt[j * M:(j + 1) * M, j * M:(j + 1) * M] = R[j]
    return Pt, Ht, Rt


def stacked_derivative(F, H, dF, dH) -> np.ndarray:
    """:math:`\\partial\\tilde H/\\partial\\xi`, shape ``(N M, N n, p)``, from ``dF`` (N-1, n, n, p) and ``dH`` (N, M, n, p).

    Block (j, k) is :math:`\\partial H_j\\,\\Phi(t_j,t_k) + H_j\\,\\partial\\Phi(t_j,t_k)` with
    :math:`\\partial\\Phi(t_j,t_k) = \\partial F_{j-1}\\Phi(t_{j-1},t_k) + F_{j-1}\\partial\\Phi(t_{j-1},t_k)` --
    Eq. 50 extended to every block of Eq. 20.
    """
    H = validation.as_array(H, "H", ndim=(3,), min_size=1)
    N, M, n = H.shape
    F = validation.as_array(F, "F", ndim=(3,))
    if F.shape != (N - 1, n, n):
        raise ValueError(f"F must have shape {(N - 1, n, n)} to match H {H.shape}; got {F.shape}")
    return _stacked_derivative(F, H, *_check_derivatives(F, H, dF, dH))


def _stacked_derivative(F, H, dF, dH) -> np.ndarray:
    """:func:`stacked_derivative` on checked arrays (no argument checks)."""
    N, M, n = H.shape
    p = dH.shape[-1]
    dF_p = np.moveaxis(dF, -1, 1)  # (N-1, p, n, n)
    dH_p = np.moveaxis(dH, -1, 1)  # (N, p, M, n)
    Phi = _transition_products(F)
    out = np.zeros((N * M, N * n, p))
    for k in range(N):
        dphi = np.zeros((p, n, n))
        for j in range(k, N):
            if j > k:
                dphi = dF_p[j - 1] @ Phi[j - 1][k] + F[j - 1] @ dphi
            blk = dH_p[j] @ Phi[j][k] + H[j] @ dphi  # (p, M, n)
            out[j * M:(j + 1) * M, k * n:(k + 1) * n, :] = np.moveaxis(blk, 0, -1)
    return out


def mutual_information_dense(P0, F, Q, H, R) -> float:
    """Eq. 18 from the stacked matrices: :math:`\\tfrac12(\\ln|\\tilde H\\tilde P\\tilde H^T+\\tilde R| - \\ln|\\tilde R|)`, nats.

    Log-determinants from Cholesky factors.  Same arguments as :func:`stacked_matrices`.
    """
    Pt, Ht, Rt = stacked_matrices(P0, F, Q, H, R)
    S = Ht @ Pt @ Ht.T + Rt
    return 0.5 * float(_logdet(0.5 * (S + S.T), "S_tilde") - _logdet(Rt, "R_tilde"))


def mutual_information_gradient_dense(P0, F, Q, H, R, dF, dH):
    """Dense mutual information and its gradient (Eqs. 18, 47-48 with Eq. 50 for every block).

    Parameters
    ----------
    P0, F, Q, H, R
        As in :func:`stacked_matrices`.
    dF : array_like (N-1, n, n, p)
        Derivatives of ``F`` with respect to the p parameters (e.g. the observer state at ``t_0``).
    dH : array_like (N, M, n, p)
        Derivatives of ``H``.

    Returns
    -------
    info : float
        Mutual information, nats.
    grad : ndarray (p,)
        :math:`\\partial\\mathcal I/\\partial\\xi_i = \\tfrac12\\mathrm{tr}(\\tilde S^{-1}(\\partial_i\\tilde H\\tilde P
        \\tilde H^T + \\tilde H\\tilde P\\partial_i\\tilde H^T))` (Eqs. 47-48), per unit of the parameters.
    """
    P0, F, Q, H, R = _check_linear_system(P0, F, Q, H, R)
    dF, dH = _check_derivatives(F, H, dF, dH)
    Pt, Ht, Rt = _stacked(P0, F, Q, H, R)
    dHt = _stacked_derivative(F, H, dF, dH)
    S = Ht @ Pt @ Ht.T + Rt
    S = 0.5 * (S + S.T)
    L = _cholesky(S, "S_tilde")
    info = 0.5 * float(2.0 * np.sum(np.log(np.diag(L))) - _logdet(Rt, "R_tilde"))
    # T_i = S^{-1}(dH_i P H^T + H P dH_i^T);  (1/2) tr T_i = tr(S^{-1} dH_i P H^T)
    PHt = Pt @ Ht.T  # (Nn, NM)
    Sinv = np.linalg.solve(L.T, np.linalg.solve(L, np.eye(S.shape[0])))
    A = PHt @ Sinv  # (Nn, NM)
    grad = np.einsum("abi,ba->i", dHt, A)
    return info, grad


def _check_derivatives(F, H, dF, dH):
    dH = validation.as_array(dH, "dH", ndim=(4,))
    if dH.shape[:3] != H.shape:
        raise ValueError(f"dH must have shape {H.shape} + (p,); got {dH.shape}")
    p = dH.shape[-1]
    if p < 1:
        raise ValueError(f"dH must hold at least one parameter (last axis p >= 1); got shape {dH.shape}")
    dF = validation.as_array(dF, "dF", ndim=(4,))
    if dF.shape[:3] != F.shape:
        raise ValueError(f"dF must have shape {F.shape} + (p,); got {dF.shape}")
    if dF.shape[-1] != p:
        raise ValueError(f"dF and dH must hold the same number of parameters p; got dF {dF.shape}, dH {dH.shape}")
    return dF, dH


def _potrf(S, k):
    """Lower Cholesky factor through LAPACK (low call overhead inside the recursions)."""
    c, info = _lapack.dpotrf(S, lower=1, clean=1)
    if info != 0:
        raise ValueError(f"innovation covariance at measurement {k} is not positive definite")
    return c


def _sqrt_psd(Q):
    """Square roots ``L`` with ``L L^T = Q`` of PSD matrices (..., n, n) (eigen-decomposition; Q may be singular)."""
    w, V = np.linalg.eigh(Q)
    return V * np.sqrt(np.clip(w, 0.0, None))[..., None, :]


def _lower_from_qr(pre_t):
    """Lower-triangular ``L`` with ``L L^T = pre pre^T`` from the R factor of ``pre^T = Q R`` (positive diagonal)."""
    r = _lapack.dgeqrf(pre_t)[0]
    n = pre_t.shape[1]
    L = np.triu(r[:n, :n]).T
    sign = np.where(np.diagonal(L) < 0, -1.0, 1.0)
    return L * sign


_ROOT_CACHE: list = []  # [(Q, LQ)], most recent first: process-noise square roots of the last few windows
_ROOT_CACHE_SIZE = 4
_MASKS: dict = {}


def _noise_roots(Q):
    """:func:`_sqrt_psd` of ``Q`` (N-1, n, n), remembered for the last few ``Q`` (compared entry by entry).

    The eigen-decompositions cost about half as much as the rest of the square-root recursion at test-case-2 size
    (0.19 ms against 0.34 ms), and the callers that evaluate many windows (the SCvx information models, their
    Hessians, the benchmarks) hold ``Q`` fixed.  A hit returns the identical array, so values are bit-for-bit those of an uncached call.
    """
    for key, root in tuple(_ROOT_CACHE):
        if key.shape == Q.shape and np.array_equal(key, Q):
            return root
    root = _sqrt_psd(Q)
    root.flags.writeable = False
    _ROOT_CACHE.insert(0, (Q.copy(), root))
    del _ROOT_CACHE[_ROOT_CACHE_SIZE:]
    return root


def _upper_mask(n):
    """Cached ``(n, n)`` array of ones on and above the diagonal, zeros below."""
    mask = _MASKS.get(n)
    if mask is None:
        mask = _MASKS[n] = np.triu(np.ones((n, n)))
    return mask


def _sqrt_sweep(P0, F, LQ, Hw, *, keep: bool = False):
    """The square-root recursion of :func:`_sqrt_forward` with less overhead, optionally keeping what the reverse
    sweep of :func:`_gradient_sqrt_reverse` needs.

    Same LAPACK calls on the same operands (same memory layouts, hence same BLAS kernels) as
    :func:`_sqrt_forward`, so the information is bit-for-bit the same; the triangular factors are not sign-fixed
    (Householder QR is sign-equivariant, and only :math:`|\\mathrm{diag}|` enters).  ``LQ`` (N-1, n, n): square
    roots of the process noise.

    Returns the per-measurement gains :math:`\\tfrac12\\ln|S_k|` (N,) and, with ``keep``: the time-update pre-arrays
    ``T`` (N, n, 2n) (:math:`T_k = [F_{k-1}V_{k-1},\\ Q_{k-1}^{1/2}]`, :math:`T_0 = [\\mathrm{chol}\\,P_0,\\ 0]`), the
    inverse transposed measurement post-arrays ``Bi`` (N, M+n, M+n) (:math:`B_k^{-T}`, upper triangular) and the
    transposed posterior factors ``Vt`` (N, n, n) (:math:`V_k^T`, upper triangular).
    """
    N, M, n = Hw.shape
    m = M + n
    mask_n = _upper_mask(n)
    dgeqrf = _lapack.dgeqrf
    V = np.linalg.cholesky(P0)
    T = np.empty((N, n, 2 * n))
    T[0, :, :n] = V
    T[0, :, n:] = 0.0
    if N > 1:
        T[1:, :, n:] = LQ
    pre = np.zeros((m, m))
    pre[:M, :M] = np.eye(M)
    diag = np.empty((N, M))
    if keep:
        Bi = np.empty((N, m, m))
        Vt = np.empty((N, n, n))
    U = V
    for k in range(N):
        if k:
            Tk = T[k]
            np.matmul(F[k - 1], V, out=Tk[:, :n])
            U = (dgeqrf(Tk.T)[0][:n] * mask_n).T  # prior factor: upper R of [F V, Q^(1/2)]^T, transposed
        np.matmul(Hw[k], U, out=pre[:M, M:])
        pre[M:, M:] = U
        r = dgeqrf(pre.T)[0]  # upper R = B^T (Householder vectors below the diagonal)
        diag[k] = np.diagonal(r)[:M]
        X = r[M:, M:] * mask_n  # V^T
        V = X.T
        if keep:
            Vt[k] = X
            Bi[k] = _lapack.dtrtri(r, lower=0)[0]
    terms = np.sum(np.log(np.abs(diag)), axis=1)
    if not keep:
        return terms
    Bi *= _upper_mask(m)
    return terms, T, Bi, Vt


def _sqrt_sweep_joint(P0, F, LQ, Hw):
    """One QR factorisation per measurement time: the time and measurement updates of :func:`_sqrt_sweep` as one.

    The post-array :math:`B_k` is the triangular factor of :math:`A'_k = [I, \\hat H_kT_k; 0, T_k]`
    (:math:`T_k = [F_{k-1}V_{k-1},\\ Q_{k-1}^{1/2}]`, :math:`T_0 = [\\mathrm{chol}\\,P_0,\\ 0]`), so one QR of the
    :math:`(M+2n)\\times(M+n)` array :math:`A_k'^T` gives it without the prior factor :math:`U_k` (the docstring of
    :func:`_gradient_sqrt_reverse` derives the reverse sweep on :math:`A'_k`, so it takes these outputs unchanged).
    Same mathematics, different round-off: the information agrees with :func:`_sqrt_sweep` to ~1e-13 relative and
    the reverse-mode gradient to the ~1e-8 floor of any square-root recursion (not bit for bit).  Returns
    ``terms, T, Bi, Vt`` as :func:`_sqrt_sweep` with ``keep=True``.
    """
    N, M, n = Hw.shape
    m = M + n
    dgeqrf, dtrtri = _lapack.dgeqrf, _lapack.dtrtri
    mask_n = _upper_mask(n)
    T = np.empty((N, n, 2 * n))
    T[0, :, :n] = np.linalg.cholesky(P0)
    T[0, :, n:] = 0.0
    if N > 1:
        T[1:, :, n:] = LQ
    pre_t = np.zeros((2 * n + M, m), order="F")  # A'^T = [I 0; (Hw T)^T T^T]
    pre_t[:M, :M] = np.eye(M)
    diag = np.empty((N, M))
    Bi = np.empty((N, m, m))
    Vt = np.empty((N, n, n))
    for k in range(N):
        Tk = T[k]
        if k:
            np.matmul(F[k - 1], Vt[k - 1].T, out=Tk[:, :n])
        pre_t[M:, :M] = (Hw[k] @ Tk).T
        pre_t[M:, M:] = Tk.T
        r = dgeqrf(pre_t)[0][:m]  # upper R = B^T
        diag[k] = np.diagonal(r)[:M]
        Vt[k] = r[M:, M:] * mask_n
        Bi[k] = dtrtri(r, lower=0)[0]
    Bi *= _upper_mask(m)
    return np.sum(np.log(np.abs(diag)), axis=1), T, Bi, Vt


def _sqrt_forward(P0, F, Q, Hw, *, store: bool = False):
    """Square-root covariance Kalman recursion on whitened Jacobians ``Hw`` (measurement noise = identity).

    Time update: :math:`\\bar L\\bar L^T = F\\hat L\\hat L^TF^T + Q` from a QR factorisation of
    :math:`[F\\hat L,\\ Q^{1/2}]^T`.  Measurement update: the lower-triangular QR post-array of

    .. math:: \\begin{bmatrix}I & \\hat H\\bar L\\\\ 0 & \\bar L\\end{bmatrix}\\Theta =
              \\begin{bmatrix}S^{1/2} & 0\\\\ \\bar K & \\hat L\\end{bmatrix},\\qquad S = I + \\hat H\\bar P\\hat H^T,
              \\ \\bar K = \\bar P\\hat H^TS^{-T/2}.

    Orthogonal transformations keep the factors accurate when the measurements are far more precise than the
    prior (test case 2: posterior covariance condition number ~4e9), where the covariance form
    :math:`\\bar P - \\bar P\\hat H^TS^{-1}\\hat H\\bar P` loses about five digits of the information.

    Returns the per-measurement log-determinants :math:`\\tfrac12\\ln|S_k|` and, with ``store``, the priors,
    posteriors, Cholesky factors of :math:`S_k` and :math:`K_k^T` (used by ``method="adjoint"``).  The values use
    :func:`_sqrt_sweep`, the same recursion with less overhead (bit-for-bit equal; this one is its reference).
    """
    N, M, n = Hw.shape
    eye_m = np.eye(M)
    L = np.linalg.cholesky(P0)
    LQ = _sqrt_psd(Q) if N > 1 else None
    terms = np.empty(N)
    if store:
        prior = np.empty((N, n, n))
        post = np.empty((N, n, n))
        chol = np.empty((N, M, M))
        gain_t = np.empty((N, M, n))
    pre = np.zeros((M + n, M + n))
    pre[:M, :M] = eye_m
    for k in range(N):
        if k > 0:
            L = _lower_from_qr(np.concatenate([F[k - 1] @ L, LQ[k - 1]], axis=1).T)
        pre[:M, M:] = Hw[k] @ L
        pre[M:, M:] = L
        post_arr = _lower_from_qr(pre.T)
        Sh = post_arr[:M, :M]
        terms[k] = float(np.sum(np.log(np.diagonal(Sh))))
        if store:
            prior[k] = L @ L.T
            Kbar = post_arr[M:, :M]
            gain_t[k] = _lapack.dtrtrs(Sh, Kbar.T, lower=1, trans=1)[0]  # S^{-T/2} Kbar^T = S^{-1} H P
            chol[k] = Sh
        L = post_arr[M:, M:]
        if store:
            post[k] = L @ L.T
    if store:
        return terms, prior, post, chol, gain_t
    return terms


def mutual_information(P0, F, Q, H, R, *, return_terms: bool = False):
    """Eq. 18 by the chain rule: a Kalman recursion summing per-measurement information gains, O(N).

    .. math:: \\mathcal I = \\sum_k \\tfrac12\\ln|I + \\hat H_k\\bar P_k\\hat H_k^T|,\\qquad \\hat H_k = L_{R_k}^{-1}H_k

    with :math:`\\bar P_k` the Kalman prior covariance, propagated in square-root form (QR factorisations, see
    :func:`_sqrt_forward`) so that the value keeps ~10 significant digits on ill-conditioned windows.

    Parameters
    ----------
    P0, F, Q, H, R
        As in :func:`stacked_matrices`.
    return_terms : bool
        Also return the per-measurement gains :math:`\\mathcal I_k` (nats), shape (N,).

    Returns
    -------
    float, or (float, ndarray)
    """
    P0, F, Q, H, R, LR = _check_linear_system(P0, F, Q, H, R, chol_R=True)
    return_terms = validation.boolean(return_terms, "return_terms")
    Hw = np.linalg.solve(LR, H)
    terms = _sqrt_sweep(P0, F, _noise_roots(Q) if H.shape[0] > 1 else None, Hw)
    total = float(np.sum(terms))
    return (total, terms) if return_terms else total


def _gradient_adjoint(P0, F, Q, H, LR, dF, dH):
    """Structured mutual information and gradient: adjoint (reverse-mode) derivative of the Kalman recursion, O(N).

    Forward pass: the square-root recursion of :func:`mutual_information` on whitened Jacobians
    :math:`\\hat H_k`, storing :math:`\\bar P_k`, :math:`S_k`, :math:`K_k = \\bar P_k\\hat H_k^TS_k^{-1}` and :math:`A_k = I - K_k\\hat H_k`.
    Backward pass (adjoints :math:`\\bar X = \\partial\\mathcal I/\\partial X`; start :math:`\\bar{\\hat P}_{N-1}=0`):

    .. math:: \\bar{\\bar P}_k = A_k^T\\bar{\\hat P}_kA_k + \\tfrac12\\hat H_k^TS_k^{-1}\\hat H_k,\\qquad
              \\bar{\\hat H}_k = S_k^{-1}\\hat H_k\\bar P_k - 2K_k^T\\bar{\\hat P}_kA_k\\bar P_k,

    .. math:: \\bar{\\hat P}_{k-1} = F_{k-1}^T\\bar{\\bar P}_kF_{k-1},\\qquad
              \\bar F_{k-1} = 2\\bar{\\bar P}_kF_{k-1}\\hat P_{k-1},

    where the measurement-update adjoint uses the Joseph form, whose sensitivity to the gain vanishes at the
    optimal gain (:math:`d\\hat P = A\\,d\\bar PA^T - K\\,d\\hat H\\bar PA^T - (\\cdot)^T`); this avoids the
    cancellation in :math:`\\bar P - \\bar P\\hat H^TS^{-1}\\hat H\\bar P` when the measurements are far more
    precise than the prior.  Finally
    :math:`\\partial\\mathcal I/\\partial\\xi_i = \\sum_k\\langle L_{R_k}^{-T}\\bar{\\hat H}_k, \\partial_i H_k\\rangle
    + \\sum_k\\langle\\bar F_k, \\partial_i F_k\\rangle` -- two tensor contractions, so the cost does not grow with
    the number of parameters.  Returns as in :func:`mutual_information_gradient_dense`; arguments checked by
    :func:`mutual_information_gradient` (``LR``: Cholesky factors of R), no checks here.
    """
    LRinv = np.linalg.inv(LR)  # whitening: H_w = L_R^{-1} H; undone on the adjoint at the end
    Hw = LRinv @ H
    N, M, n = H.shape
    p = dH.shape[-1]
    eye_n = np.eye(n)
    matmul = np.matmul
    # forward pass in square-root form (accurate priors, posteriors, gains and innovation factors)
    terms, prior, post, chol, gain_t = _sqrt_forward(P0, F, Q, Hw, store=True)
    info = float(np.sum(terms))
    # S^{-1} H from the Cholesky factors of S (batched triangular solves)
    SiH_all = np.linalg.solve(np.swapaxes(chol, -1, -2), np.linalg.solve(chol, Hw))
    # quantities of the backward sweep that do not depend on the adjoint recursion, batched over k
    half_G = 0.5 * (np.swapaxes(Hw, -1, -2) @ SiH_all)  # (1/2) H^T S^{-1} H
    A_all = eye_n - np.swapaxes(gain_t, -1, -2) @ Hw  # I - K H
    BA_all = np.zeros((N, n, n))
    BF_all = np.empty((N - 1, n, n))
    # backward sweep: adjoints of the Kalman recursion (Pbar_post is zero after the last measurement)
    for k in range(N - 1, 0, -1):
        Pbar_prior = half_G[k] if k == N - 1 else A_all[k].T @ BA_all[k] + half_G[k]
        Fk = F[k - 1]
        BF = matmul(Pbar_prior, Fk, out=BF_all[k - 1])
        matmul(Fk.T @ BF, A_all[k - 1], out=BA_all[k - 1])
    Hbar = gain_t - 2.0 * ((gain_t @ BA_all) @ prior)
    Fbar = 2.0 * (BF_all @ post[:-1])
    # undo the whitening: <Hbar_w, L^{-1} dH> = <L^{-T} Hbar_w, dH>
    Hbar_raw = np.swapaxes(LRinv, -1, -2) @ Hbar
    grad = Hbar_raw.reshape(-1) @ dH.reshape(-1, p) + Fbar.reshape(-1) @ dF.reshape(-1, p)
    return info, grad


def _phi(A):
    """Lower triangle with halved diagonal, batched over leading axes (derivative of a Cholesky factor)."""
    out = np.tril(A)
    d = np.einsum("...ii->...i", out)
    d *= 0.5
    return out


def _tri_solve(L, B):
    """``L^{-1} B`` for lower-triangular L (n, n) and B (p, n, k), one LAPACK call."""
    p, n, k = B.shape
    X = _lapack.dtrtrs(L, np.moveaxis(B, 0, 1).reshape(n, p * k), lower=1)[0]
    return np.moveaxis(X.reshape(n, p, k), 1, 0)


def _gradient_sqrt(P0, F, Q, H, LR, dF, dH):
    """Forward-mode derivative of the square-root recursion of :func:`_sqrt_forward` (p tangent directions).

    ``method="sqrt-forward"``: the default before 2026-11-24, kept as the reference of the reverse mode
    (:func:`_gradient_sqrt_reverse`), which computes the same derivative at a cost independent of p.

    For a lower-triangular factor :math:`LL^T = M`, :math:`dL = L\\,\\Phi(L^{-1}dML^{-T})` with :math:`\\Phi` the
    lower triangle with halved diagonal.  Time update: :math:`M = GG^T + Q`, :math:`G = F\\hat L`, so
    :math:`L^{-1}dML^{-T} = Y + Y^T`, :math:`Y = (L^{-1}dG)(L^{-1}G)^T`.  Measurement update: with the pre-array
    :math:`A` and its triangular post-array :math:`B` (:math:`BB^T = AA^T`), :math:`Y = (B^{-1}dA)(B^{-1}A)^T`
    (:math:`B^{-1}A` is orthogonal), :math:`dB = B\\,\\Phi(Y+Y^T)` and
    :math:`d\\ln|S_k^{1/2}| = \\sum_{i<M}Y_{ii}`.  Every quantity is a factor or an orthogonal matrix, so the
    gradient keeps the accuracy of the value (the covariance-form adjoint loses ~5 digits on test case 2).
    """
    Hw = np.linalg.solve(LR, H)
    N, M, n = H.shape
    p = dH.shape[-1]
    dHw = np.linalg.solve(LR[:, None], np.moveaxis(dH, -1, 1))  # (N, p, M, n)
    dFp = np.moveaxis(dF, -1, 1)  # (N-1, p, n, n)
    L = np.linalg.cholesky(P0)
    dL = np.zeros((p, n, n))
    LQ = _sqrt_psd(Q) if N > 1 else None
    pre = np.zeros((M + n, M + n))
    pre[:M, :M] = np.eye(M)
    dpre = np.zeros((p, M + n, M + n))
    total, grad = 0.0, np.zeros(p)
    for k in range(N):
        if k > 0:
            G = F[k - 1] @ L
            dG = dFp[k - 1] @ L + F[k - 1] @ dL
            L = _lower_from_qr(np.concatenate([G, LQ[k - 1]], axis=1).T)
            W = _lapack.dtrtrs(L, G, lower=1)[0]  # L^{-1} G, norm <= 1
            Y = _tri_solve(L, dG) @ W.T
            dL = L @ _phi(Y + np.swapaxes(Y, -1, -2))
        pre[:M, M:] = Hw[k] @ L
        pre[M:, M:] = L
        B = _lower_from_qr(pre.T)
        dpre[:, :M, M:] = dHw[k] @ L + Hw[k] @ dL
        dpre[:, M:, M:] = dL
        Z = _lapack.dtrtrs(B, pre, lower=1)[0]  # B^{-1} A: orthogonal
        Y = _tri_solve(B, dpre) @ Z.T
        total += float(np.sum(np.log(np.diagonal(B)[:M])))
        grad += np.einsum("pii->p", Y[:, :M, :M])
        dB = B @ _phi(Y + np.swapaxes(Y, -1, -2))
        L = B[M:, M:]
        dL = dB[:, M:, M:]
    return total, grad


def _gradient_sqrt_reverse(P0, F, Q, H, LR, dF, dH, LQ=None, joint: bool = False):
    """Reverse-mode (adjoint) derivative of the square-root recursion: value and gradient, cost independent of p.

    Notation (whitened :math:`\\hat H_k = L_{R_k}^{-1}H_k`): prior and posterior factors :math:`U_k, V_k`,
    time-update pre-array :math:`T_k = [F_{k-1}V_{k-1},\\ Q_{k-1}^{1/2}]` (:math:`U_kU_k^T = T_kT_k^T`;
    :math:`T_0 = [U_0,\\ 0]`, :math:`U_0 = \\mathrm{chol}\\,P_0`), measurement post-array
    :math:`B_k = [S_k^{1/2}, 0; \\bar K_k, V_k]` (lower triangular, :math:`B_kB_k^T = A_kA_k^T`,
    :math:`A_k = [I, \\hat H_kU_k; 0, U_k]`) and
    :math:`\\mathcal I = \\sum_k\\sum_{i<M}\\ln|(B_k)_{ii}|` nats.

    *Reverse rule of a triangular factor.*  If :math:`BB^T = AA^T` then :math:`dB = B\\,\\Phi(Y + Y^T)`,
    :math:`Y = B^{-1}dA\\,Z^T`, :math:`Z = B^{-1}A` (orthonormal rows; :math:`\\Phi` = lower triangle with halved
    diagonal, self-adjoint), so for any adjoint :math:`\\bar B`:
    :math:`\\langle\\bar B, dB\\rangle = \\langle B^{-T}(W + W^T)Z,\\ dA\\rangle`, :math:`W = \\Phi(B^T\\bar B)`.
    Two facts make :math:`W + W^T` explicit: the gain term has :math:`\\bar B = \\mathrm{diag}(1/B_{ii})_{i<M}`,
    giving :math:`W + W^T = \\mathrm{diag}(I_M, 0)`; and everything after :math:`V_k` depends on it only through
    :math:`V_kV_k^T`, so :math:`\\Psi_k = V_k^T\\bar V_k` is symmetric and :math:`\\Phi(\\Psi)+\\Phi(\\Psi)^T = \\Psi`.
    With :math:`\\Omega_k = \\mathrm{diag}(I_M, \\Psi_k)`: :math:`\\bar A_k = B_k^{-T}\\Omega_kZ_k`.

    *One step per measurement time.*  :math:`B_k` is also the triangular factor of
    :math:`A'_k = [I, \\hat H_kT_k; 0, T_k]` (:math:`A'_kA_k'^T = A_kA_k^T`), so time and measurement update
    differentiate as one factorisation: :math:`Z'_k = B_k^{-1}A'_k = [B_k^{-1}[I; 0],\\ \\Gamma_kT_k]` with
    :math:`\\Gamma_k = B_k^{-1}[\\hat H_k; I]` ((M+n) x n).  Writing :math:`G_k = \\Gamma_kF_{k-1}V_{k-1}` (the
    columns of :math:`Z'_k` that :math:`V_{k-1}` enters) with row blocks :math:`G_k^{(1)}` (M) and :math:`G_k^{(2)}`
    (n), :math:`V_{k-1}^T\\bar V_{k-1} = G_k^T\\Omega_kG_k`, hence

    .. math:: \\Psi_{N-1} = 0,\\qquad \\Psi_{k-1} = G_k^{(1)T}G_k^{(1)} + G_k^{(2)T}\\Psi_kG_k^{(2)},

    .. math:: \\frac{\\partial\\mathcal I}{\\partial\\hat H_k} = \\big[B_k^{-T}\\Omega_kZ'_k\\big]_{1:M}T_k^T,
              \\qquad \\frac{\\partial\\mathcal I}{\\partial F_{k-1}} = \\Gamma_k^T\\Omega_kG_kV_{k-1}^T,

    :math:`\\partial\\mathcal I/\\partial H_k = L_{R_k}^{-T}\\partial\\mathcal I/\\partial\\hat H_k`, and
    :math:`\\partial\\mathcal I/\\partial\\xi_i = \\sum_k\\langle\\partial\\mathcal I/\\partial H_k,
    \\partial_iH_k\\rangle + \\sum_k\\langle\\partial\\mathcal I/\\partial F_k, \\partial_iF_k\\rangle`
    (two tensor contractions).

    *Cost and accuracy.*  The forward sweep is :func:`_sqrt_sweep` (two QR factorisations and one triangular
    inverse per time; value bit-for-bit that of :func:`mutual_information`); only the :math:`\\Psi` recursion is
    sequential (two n x n products per time), everything else is batched over the window.  :math:`\\Psi` stays
    :math:`O(N)` (it is built from orthonormal blocks), so the adjoint is carried in square-root coordinates and
    never forms the ill-conditioned covariance adjoint of ``method="adjoint"``.  Measured against a 40-digit
    evaluation on the test-case-2-sized benchmark window: 2.4e-8 relative (max abs), forward mode 1.8e-8; an
    eps-sized perturbation of the posterior factors alone moves the gradient by ~1e-7 there, so ~1e-8 is the
    double-precision floor of any square-root recursion and the two modes agree to ~4e-8 (1e-12 on
    well-conditioned windows).  Returns as in :func:`mutual_information_gradient_dense`; arguments checked by
    :func:`mutual_information_gradient` (``LR``: Cholesky factors of R; ``LQ``: square roots of Q, default
    :func:`_noise_roots`), no checks here.
    """
    Hw = np.linalg.solve(LR, H)
    N, M, n = H.shape
    p = dH.shape[-1]
    if LQ is None and N > 1:
        LQ = _noise_roots(Q)
    terms, T, Bi, Vt = _sqrt_sweep_joint(P0, F, LQ, Hw) if joint else _sqrt_sweep(P0, F, LQ, Hw, keep=True)
    info = float(np.sum(terms))
    swap = np.swapaxes
    Gam = swap(Bi[:, :M], 1, 2) @ Hw  # B^{-1}[Hw; I]: B^{-1} = Bi^T, lower triangular
    Gam += swap(Bi[:, M:], 1, 2)
    Z = Gam @ T  # Z'[:, :, M:] = [G | Gamma Q^(1/2)], (N, M+n, 2n)
    G1 = Z[:, :M, :n]
    C = swap(G1, 1, 2) @ G1
    Psi = np.zeros((N, n, n))
    if N > 1:
        Psi[N - 2] = C[N - 1]
    for k in range(N - 2, 0, -1):  # the only sequential part of the backward sweep
        G2 = Z[k, M:, :n]
        Psi[k - 1] = C[k] + G2.T @ Psi[k] @ G2
    Z[:, M:] = Psi @ Z[:, M:]  # Omega Z'
    Hbar = (Bi[:, :M] @ Z) @ swap(T, 1, 2)
    Hbar = np.linalg.solve(swap(LR, 1, 2), Hbar)  # undo the whitening
    grad = Hbar.reshape(-1) @ dH.reshape(-1, p)
    if N > 1:
        Fbar = (swap(Gam[1:], 1, 2) @ Z[1:, :, :n]) @ Vt[:-1]
        grad += Fbar.reshape(-1) @ dF.reshape(-1, p)
    return info, grad


def mutual_information_gradient(P0, F, Q, H, R, dF, dH, *, method: str = "sqrt"):
    """Structured mutual information and its gradient with respect to parameters of ``F`` and ``H``, O(N).

    Parameters
    ----------
    P0, F, Q, H, R
        As in :func:`stacked_matrices`.
    dF : array_like (N-1, n, n, p)
    dH : array_like (N, M, n, p)
        Derivatives of ``F`` and ``H`` with respect to the p parameters.
    method : {"sqrt", "sqrt-forward", "adjoint"}
        ``"sqrt"`` (default): reverse-mode derivative of the square-root recursion (:func:`_gradient_sqrt_reverse`),
        cost independent of p, ~2e-8 relative on the test-case-2 windows (the double-precision floor of the
        square-root factors).  ``"sqrt-forward"``: forward-mode derivative of the same recursion
        (:func:`_gradient_sqrt`), cost proportional to p, same accuracy, kept as the reference.  ``"adjoint"``:
        reverse-mode derivative of the covariance-form recursion (:func:`_gradient_adjoint`), cost independent of p
        but about 1e-5 relative error on ill-conditioned windows (test case 2).

    Returns
    -------
    info : float
        Mutual information (the square-root value of :func:`mutual_information` in both methods), nats.
    grad : ndarray (p,)
    """
    validation.choice(method, "method", ("sqrt", "sqrt-forward", "adjoint"))
    P0, F, Q, H, R, LR = _check_linear_system(P0, F, Q, H, R, chol_R=True)  # checked once; the kernels do not
    dF, dH = _check_derivatives(F, H, dF, dH)
    kernel = {"sqrt": _gradient_sqrt_reverse, "sqrt-forward": _gradient_sqrt, "adjoint": _gradient_adjoint}[method]
    return kernel(P0, F, Q, H, LR, dF, dH)


class InformationKernel:
    """Mutual information and its gradient for many windows that share ``P0``, ``Q`` and ``R``, checked once.

    An optimiser that moves the observer re-evaluates the same window with new ``F``, ``H`` (and their
    derivatives) and the same noise: here ``P0``, ``Q`` and ``R`` are validated once, the Cholesky factors of R
    and the square roots of Q are computed once, and each evaluation checks only the shapes and finiteness of
    its arrays.  Values and gradients are bit-for-bit those of :func:`mutual_information` and
    :func:`mutual_information_gradient` (``method="sqrt"``, the same kernels on the same checked arrays).

    Parameters
    ----------
    P0 : array_like (n, n)
        Covariance at ``t_0`` (SPD).
    Q : array_like (N-1, n, n) or (n, n)
        Process noise over each interval (symmetric PSD).
    R : array_like (N, M, M) or (M, M)
        Measurement noise covariances (SPD).
    n_times : int
        Number of measurement times N (>= 1).
    one_qr : bool
        ``value_gradient`` by one QR factorisation per measurement time (:func:`_sqrt_sweep_joint`: time and
        measurement updates as one) instead of two; default False.  Faster, same mathematics, but not bit for bit:
        the gradient moves by up to ~4e-8 relative on the test-case-2 window (the square-root recursion's
        double-precision floor), which changes SCvx iterates.  :meth:`value` is unaffected.
    """

    def __init__(self, P0, Q, R, n_times: int, *, one_qr: bool = False):
        N = validation.integer(n_times, "n_times", minimum=1)
        self.one_qr = validation.boolean(one_qr, "one_qr")
        P0 = check_spd(P0, "P0")
        if P0.ndim != 2:
            raise ValueError(f"P0 must be a single (n, n) matrix; got {P0.shape}")
        n = P0.shape[0]
        Rv = validation.as_array(R, "R", ndim=(2, 3), min_size=1)
        M = Rv.shape[-1]
        Q, R, LR = _check_q_r(Q, Rv, N, M, n, f" (N - 1 = {N - 1} intervals, n from P0 {P0.shape})",
                              f" (N = {N} times)")
        self.P0, self.Q, self.R, self.LR = P0, Q, R, LR
        self.LQ = _sqrt_psd(Q) if N > 1 else None
        for a in (self.P0, self.Q, self.R, self.LR) + ((self.LQ,) if N > 1 else ()):
            if a.flags.owndata:
                a.flags.writeable = False
        self.shape = (N, M, n)

    @staticmethod
    def _float(value, name):
        """``value`` as a float array: a float64 array as it is (the hot path: no copy, no scan), anything else through
        the package's array check (text anywhere in a container, objects and ragged lists refused naming ``name``;
        finiteness is checked by the caller)."""
        if isinstance(value, np.ndarray) and value.dtype == np.float64:
            return value
        return validation.as_array(value, name, finite=False)

    def _check(self, F, H):
        N, M, n = self.shape
        F = self._float(F, "F")
        H = self._float(H, "H")
        if F.shape != (N - 1, n, n):
            raise ValueError(f"F must have shape {(N - 1, n, n)}; got {F.shape}")
        if H.shape != (N, M, n):
            raise ValueError(f"H must have shape {(N, M, n)}; got {H.shape}")
        if not np.isfinite(F).all():
            raise ValueError("F must be finite (no NaN or inf)")
        if not np.isfinite(H).all():
            raise ValueError("H must be finite (no NaN or inf)")
        return F, H

    def _row_scale(self, row_scale, name="row_scale"):
        N, M, _ = self.shape
        s = validation.as_array(row_scale, name, shape=(N, M))
        if np.any(s <= 0):
            raise ValueError(f"{name} must be positive (a factor on measurement rows); got min {s.min()}")
        return s

    def value(self, F, H, *, row_scale=None) -> float:
        """:func:`mutual_information` of the window with transitions ``F`` (N-1, n, n) and Jacobians ``H`` (N, M, n),
        nats.  ``row_scale`` (N, M), optional: positive factors on the rows of ``H`` (a noise standard deviation
        divided by them, e.g. :func:`range_noise_scale`; default none: bit-for-bit the unscaled value)."""
        F, H = self._check(F, H)
        if row_scale is not None:
            H = self._row_scale(row_scale)[..., None] * H
        return float(np.sum(_sqrt_sweep(self.P0, F, self.LQ, np.linalg.solve(self.LR, H))))

    def value_gradient(self, F, H, dF, dH, *, row_scale=None, d_row_scale=None):
        """:func:`mutual_information_gradient` (reverse mode): ``(info, grad (p,))`` for derivatives ``dF``
        (N-1, n, n, p) and ``dH`` (N, M, n, p).  ``row_scale`` (N, M) and its derivative ``d_row_scale``
        (N, M, p), optional together: the rows of ``H`` are scaled (as in :meth:`value`) and the product rule
        enters the gradient."""
        F, H = self._check(F, H)
        if (row_scale is None) != (d_row_scale is None):
            raise ValueError("row_scale and d_row_scale must be given together (or neither)")
        dF = self._float(dF, "dF")
        dH = self._float(dH, "dH")
        if dF.ndim != 4 or dF.shape[:3] != F.shape or dF.shape[-1] < 1:
            raise ValueError(f"dF must have shape {F.shape} + (p,) with p >= 1; got {dF.shape}")
        if dH.ndim != 4 or dH.shape[:3] != H.shape or dH.shape[-1] < 1:
            raise ValueError(f"dH must have shape {H.shape} + (p,) with p >= 1; got {dH.shape}")
        if dF.shape[-1] != dH.shape[-1]:
            raise ValueError(f"dF and dH must have the same number p of parameters on their last axis; got dF "
                             f"{dF.shape} (p = {dF.shape[-1]}) and dH {dH.shape} (p = {dH.shape[-1]})")
        if not np.isfinite(dF).all():
            raise ValueError("dF must be finite (no NaN or inf)")
        if not np.isfinite(dH).all():
            raise ValueError("dH must be finite (no NaN or inf)")
        if row_scale is not None:
            sc = self._row_scale(row_scale)
            ds = validation.as_array(d_row_scale, "d_row_scale", shape=sc.shape + (dH.shape[-1],))
            dH = sc[..., None, None] * dH + H[..., None] * ds[:, :, None, :]
            H = sc[..., None] * H
        return _gradient_sqrt_reverse(self.P0, F, self.Q, H, self.LR, dF, dH, self.LQ, joint=self.one_qr)


def range_noise_scale(lin: AugmentedLinearization, range_scale: float, *, derivatives: bool = False):
    r"""Row scale of a range-dependent noise, :math:`1/g(\rho) = \rho/\sqrt{\rho^2 + \rho_c^2}`, for every
    measurement row of each target (the noise standard deviation times :math:`g = \sqrt{1 + (\rho_c/\rho)^2}`).

    Parameters
    ----------
    lin : AugmentedLinearization
        The window (observer and target states at the measurement times; ``observer_stm`` for the derivative).
    range_scale : float
        :math:`\rho_c` (> 0), LU: the noise is :math:`\sqrt2` times larger at this range and grows like
        :math:`\rho_c/\rho` inside it.
    derivatives : bool
        Also return the derivative with respect to the observer state at ``t[0]`` (through ``lin.observer_stm``).

    Returns
    -------
    ndarray (N, M), or (ndarray (N, M), ndarray (N, M, 6))
        Factors in (0, 1) for :meth:`InformationKernel.value` (``row_scale``), and ``d_row_scale`` in 1/LU and
        TU/LU.
    """
    validation.instance(lin, "lin", AugmentedLinearization)
    rc = validation.positive(range_scale, "range_scale")
    derivatives = validation.boolean(derivatives, "derivatives")
    n_t = lin.targets.shape[0]
    m = lin.H.shape[1] // n_t
    rel = lin.observer[None, :, :3] - lin.targets[:, :, :3]  # (N_T, N, 3): observer minus target
    rho = np.linalg.norm(rel, axis=-1)
    s = rho / np.sqrt(rho**2 + rc**2)  # (N_T, N)
    scale = np.repeat(s.T, m, axis=1)  # (N, M): target j's rows j m .. j m + m - 1
    if not derivatives:
        return scale
    # d s / d rho = rc^2 / (rho^2 + rc^2)^1.5; d rho / d x0 = rho_hat^T Phi_S(t_k, t0)[:3, :]
    dsdr = rc**2 / (rho**2 + rc**2) ** 1.5
    drho = np.einsum("jka,kab->jkb", rel / rho[..., None], lin.observer_stm[:, :3, :])  # (N_T, N, 6)
    dscale = np.repeat(np.moveaxis(dsdr[..., None] * drho, 0, 1), m, axis=1)  # (N, M, 6)
    return scale, dscale


def regularised_range_rate_jacobian(lin: AugmentedLinearization, range_scale: float, *, derivatives: bool = False):
    r"""The window's measurement Jacobians with the range-rate row regularised at short range: its position part
    :math:`(\Delta\dot{\mathbf r}-\dot\rho\hat\rho)^T/\rho` becomes
    :math:`(\Delta\dot{\mathbf r}-\dot\rho\hat\rho)^T/\sqrt{\rho^2+\rho_c^2}` (bounded as :math:`\rho\to0`
    instead of growing like :math:`1/\rho`); the range row and the velocity part of the range-rate row are kept.

    The position columns of each target's range-rate row (the observer's and that target's) are multiplied by
    :math:`\rho/\sqrt{\rho^2+\rho_c^2}`, the factor of :func:`range_noise_scale`; the measurement noise is left
    as it is.  Far from the targets (:math:`\rho \gg \rho_c`) the Jacobians are the model's.

    Parameters
    ----------
    lin : AugmentedLinearization
        A range and range-rate window (two rows per target, range first, as
        :data:`cislunar.sensing.measurements.RANGE_RANGE_RATE` gives them); ``derivatives`` needs ``lin.dH``.
    range_scale : float
        :math:`\rho_c` (> 0), LU.
    derivatives : bool
        Also return the derivative of the Jacobians with respect to the observer state at ``t[0]`` (product rule:
        ``lin.dH`` times the factor plus the Jacobian times the factor's derivative).

    Returns
    -------
    ndarray (N, M, n), or (ndarray (N, M, n), ndarray (N, M, n, 6))
        ``H`` (and ``dH``) in the units of ``lin.H`` (``lin.dH``): for :meth:`InformationKernel.value` and
        :meth:`InformationKernel.value_gradient` in place of ``lin.H`` and ``lin.dH``.
    """
    validation.instance(lin, "lin", AugmentedLinearization)
    rc = validation.positive(range_scale, "range_scale")
    derivatives = validation.boolean(derivatives, "derivatives")
    n_t = lin.targets.shape[0]
    M, n = lin.H.shape[1], lin.H.shape[2]
    if M != 2 * n_t:
        raise ValueError(f"lin must be a range and range-rate window (2 rows per target, {2 * n_t} rows); got "
                         f"{M} rows for {n_t} targets")
    if derivatives and lin.dH is None:
        raise ValueError("lin has no dH: linearise with derivatives=True for derivatives=True")
    mask = np.zeros((M, n), dtype=bool)  # the position columns of each target's range-rate row
    for j in range(n_t):
        mask[2 * j + 1, 0:3] = True
        mask[2 * j + 1, 6 * (j + 1):6 * (j + 1) + 3] = True
    if not derivatives:
        s = range_noise_scale(lin, rc)
        return np.where(mask, s[..., None] * lin.H, lin.H)
    s, ds = range_noise_scale(lin, rc, derivatives=True)
    H = np.where(mask, s[..., None] * lin.H, lin.H)
    dH = np.where(mask[..., None], s[..., None, None] * lin.dH + lin.H[..., None] * ds[:, :, None, :], lin.dH)
    return H, dH


def window_information(lin: AugmentedLinearization, *, method: str = "structured", gradient: bool = False,
                       range_scale: float | None = None):
    """Mutual information (and optionally its gradient w.r.t. the observer state at the window start) of a window.

    Parameters
    ----------
    lin : AugmentedLinearization
        From :func:`cislunar.sensing.covariance.linearize_augmented` (``derivatives=True`` for the gradient).
    method : {"structured", "dense"}
    gradient : bool
    range_scale : float, optional
        :math:`\\rho_c` of a range-dependent noise (:func:`range_noise_scale`), LU; default none (the noise of
        ``lin.R``, bit-for-bit the plain value).  Structured method only.

    Returns
    -------
    float, or (float, ndarray (6,))
        Nats; gradient in nats per LU (position) and per LU/TU (velocity).
    """
    validation.instance(lin, "lin", AugmentedLinearization)
    validation.choice(method, "method", ("structured", "dense"))
    if range_scale is not None:
        if method != "structured":
            raise ValueError("range_scale needs method='structured'")
        gradient = validation.boolean(gradient, "gradient")
        if gradient and lin.dF is None:
            raise ValueError("lin has no derivatives: build it with linearize_augmented(..., derivatives=True)")
        kernel = InformationKernel(lin.P0, lin.Q, lin.R, lin.t.size)
        if gradient:
            sc, ds = range_noise_scale(lin, range_scale, derivatives=True)
            return kernel.value_gradient(lin.F, lin.H, lin.dF, lin.dH, row_scale=sc, d_row_scale=ds)
        return kernel.value(lin.F, lin.H, row_scale=range_noise_scale(lin, range_scale))
    if validation.boolean(gradient, "gradient"):
        if lin.dF is None:
            raise ValueError("lin has no derivatives: build it with linearize_augmented(..., derivatives=True)")
        f = mutual_information_gradient if method == "structured" else mutual_information_gradient_dense
        return f(*lin.arrays, lin.dF, lin.dH)
    f = mutual_information if method == "structured" else mutual_information_dense
    return f(*lin.arrays)


def gaussian_kl(mean_p, cov_p, mean_q, cov_q) -> np.ndarray:
    """KL divergence (Eq. 10) between Gaussians, :math:`D_{KL}[\\mathcal N(m_p,\\Sigma_p)\\|\\mathcal N(m_q,\\Sigma_q)]`, nats.

    .. math:: \\tfrac12\\left[\\mathrm{tr}(\\Sigma_q^{-1}\\Sigma_p) + (m_q-m_p)^T\\Sigma_q^{-1}(m_q-m_p) - d
              + \\ln\\frac{|\\Sigma_q|}{|\\Sigma_p|}\\right]

    Means broadcast over leading axes ``(..., d)``; covariances are single ``(d, d)`` SPD matrices.
    """
    cp = _sym(_spd(cov_p, "cov_p"))
    cq = _sym(_spd(cov_q, "cov_q"))
    if cp.ndim != 2 or cp.shape != cq.shape:
        raise ValueError(f"cov_p and cov_q must be (d, d) of the same shape; got {cp.shape} and {cq.shape}")
    d = cp.shape[0]
    mp = validation.as_array(mean_p, "mean_p", last=d, min_size=1)
    mq = validation.as_array(mean_q, "mean_q", last=d, min_size=1)
    Lq = np.linalg.cholesky(cq)
    diff = np.moveaxis(np.asarray(mq - mp), -1, 0).reshape(d, -1)
    z = np.linalg.solve(Lq, diff)
    maha = np.sum(z**2, axis=0).reshape(np.broadcast_shapes(mp.shape, mq.shape)[:-1])
    tr = np.trace(np.linalg.solve(cq, cp))
    return 0.5 * (tr + maha - d + _logdet(cq, "cov_q") - _logdet(cp, "cov_p"))


def monte_carlo_mutual_information(P0, F, Q, H, R, n_samples: int, rng: np.random.Generator):
    """Monte Carlo estimate of :math:`\\mathbb E_X[D_{KL}(p(Y|X)\\|p(Y))]` (Eq. 11, second line), nats.

    Samples :math:`(X, Y)` from the generative model (initial state, process noises, measurement noises, forward
    recursion) and averages :math:`\\ln p(Y|X) - \\ln p(Y)`.  :math:`\\ln p(Y|X)` is the sum of measurement
    log-likelihoods at the sampled true states; :math:`\\ln p(Y)` is the Kalman filter's prediction-error
    decomposition :math:`\\sum_k\\ln\\mathcal N(\\mathbf y_k; H_k\\bar{\\mathbf x}_k, S_k)` run on each sampled Y.
    Neither uses the stacked matrices or the log-determinant formula of Eq. 18.

    Parameters
    ----------
    P0, F, Q, H, R
        As in :func:`stacked_matrices`.
    n_samples : int
        Number of joint samples (>= 2).
    rng : numpy.random.Generator
        Source of randomness (pass a seeded generator for reproducibility).

    Returns
    -------
    estimate : float
    standard_error : float
        Sample standard deviation of the log ratio divided by sqrt(n_samples).
    """
    P0, F, Q, H, R = _check_linear_system(P0, F, Q, H, R)
    rng = validation.rng(rng, "rng")
    ns = validation.integer(n_samples, "n_samples", minimum=2)
    N, M, n = H.shape

    def chol_psd(A):
        w, V = np.linalg.eigh(A)
        return V * np.sqrt(np.clip(w, 0.0, None))

    def logpdf(res, cov):
        L = np.linalg.cholesky(cov)
        z = np.linalg.solve(L, res.T)
        return -0.5 * np.sum(z**2, axis=0) - np.sum(np.log(np.diag(L))) - 0.5 * M * np.log(2 * np.pi)

    x = rng.standard_normal((ns, n)) @ chol_psd(P0).T
    xhat = np.zeros((ns, n))
    P = P0.copy()
    log_ratio = np.zeros(ns)
    for k in range(N):
        if k > 0:
            x = x @ F[k - 1].T + rng.standard_normal((ns, n)) @ chol_psd(Q[k - 1]).T
            xhat = xhat @ F[k - 1].T
            P = F[k - 1] @ P @ F[k - 1].T + Q[k - 1]
        y = x @ H[k].T + rng.standard_normal((ns, M)) @ np.linalg.cholesky(R[k]).T
        S = H[k] @ P @ H[k].T + R[k]
        S = 0.5 * (S + S.T)
        innov = y - xhat @ H[k].T
        log_ratio += logpdf(y - x @ H[k].T, R[k]) - logpdf(innov, S)
        K = np.linalg.solve(S, H[k] @ P).T
        xhat = xhat + innov @ K.T
        IKH = np.eye(n) - K @ H[k]
        P = IKH @ P @ IKH.T + K @ R[k] @ K.T
    return float(np.mean(log_ratio)), float(np.std(log_ratio, ddof=1) / np.sqrt(ns))


@dataclass(frozen=True)
class TimingResult:
    """Best-of-repeats wall time per evaluation, seconds, for value and value+gradient, dense and structured."""

    dense_value: float
    structured_value: float
    dense_gradient: float
    structured_gradient: float

    @property
    def ratio_value(self) -> float:
        return self.dense_value / self.structured_value

    @property
    def ratio_gradient(self) -> float:
        return self.dense_gradient / self.structured_gradient


def _mean_time(fn, min_time: float) -> float:
    """Mean wall time of ``fn`` over as many calls as fit in ``min_time`` seconds."""
    count, t0 = 0, time.perf_counter()
    while True:
        fn()
        count += 1
        el = time.perf_counter() - t0
        if el >= min_time:
            return el / count


def _interleaved_best(fns, repeat: int, min_time: float) -> list:
    """Best-of-``repeat`` mean times of several functions, measured in interleaved rounds.

    Interleaving makes the ratios robust to load that changes during the measurement (a shared machine): each
    round times every function once, and the minimum over rounds is kept for each.
    """
    for fn in fns:
        fn()  # warm-up
    best = [np.inf] * len(fns)
    for _ in range(repeat):
        for i, fn in enumerate(fns):
            best[i] = min(best[i], _mean_time(fn, min_time))
    return best


def time_evaluations(P0, F, Q, H, R, dF, dH, *, repeat: int = 3, min_time: float = 0.05) -> TimingResult:
    """Time dense and structured evaluations of Eq. 18 and of the gradient (best of ``repeat`` runs).

    Each round times every evaluation once (repeating it until ``min_time`` seconds have passed and taking the
    mean); the best round is kept for each, so the ratios are robust to load changing during the measurement.
    """
    rep = validation.integer(repeat, "repeat", minimum=1)
    mt = validation.positive(min_time, "min_time")
    args = (P0, F, Q, H, R)
    times = _interleaved_best([
        lambda: mutual_information_dense(*args),
        lambda: mutual_information(*args),
        lambda: mutual_information_gradient_dense(*args, dF, dH),
        lambda: mutual_information_gradient(*args, dF, dH),
    ], rep, mt)
    return TimingResult(*times)
