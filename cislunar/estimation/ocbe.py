r"""Optimal-control-based estimator (OCBE) dynamics: the state/costate transition matrix and its process noise.

Greaves & Scheeres (2021, §State Estimation, Eqs. 14-17 and 32), after Lubey & Scheeres (JGCD 2014) and
Lubey's thesis (2015), model unknown accelerations as an optimal control :math:`\mathbf u = -\tilde Q B^\top
\mathbf p` with costate :math:`\mathbf p` and :math:`B = [0;\ I_3]`.  About a ballistic reference
(:math:`\mathbf p = 0`) the deviations obey

.. math::

    \frac{d}{dt}\begin{bmatrix}\delta\mathbf x\\ \mathbf p\end{bmatrix} =
    \begin{bmatrix} A(t) & -B\tilde QB^\top \\ 0 & -A(t)^\top\end{bmatrix}
    \begin{bmatrix}\delta\mathbf x\\ \mathbf p\end{bmatrix},

so the 12x12 transition matrix has :math:`\Phi_{px} = 0`, :math:`\Phi_{pp} = \Phi_{xx}^{-\top}` and
:math:`\Phi_{xp}\Phi_{xx}^\top` symmetric negative semi-definite.  The OCBE's process-noise-like term (Eq. 17) is

.. math:: Q = -\Phi_{xp}\Phi_{xx}^\top = \int_{t_n}^{t_{n+1}} \Phi_{xx}(t_{n+1},\tau)B\tilde QB^\top
          \Phi_{xx}(t_{n+1},\tau)^\top d\tau,

the same matrix as the exact discretisation of continuous white-noise acceleration with power spectral density
:math:`\tilde Q` (checked in ``tests/estimation/test_ocbe.py`` against :func:`cislunar.sensing.covariance.process_noise`).

The 12x12 matrix is computed with heyoka's variational equations of the Hamiltonian system
:math:`\dot{\mathbf x} = f(\mathbf x) - B\tilde QB^\top\mathbf p`, :math:`\dot{\mathbf p} =
-(\partial f/\partial\mathbf x)^\top\mathbf p` started with :math:`\mathbf p = 0`: its first-order sensitivities
are exactly the block matrix above.  ``control_weight`` is :math:`\tilde Q = q I_3` in LU^2/TU^3 (an acceleration
PSD); times in TU, states in LU and LU/TU, rotating frame.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from cislunar.cr3bp.dynamics import CR3BP, check_system
from cislunar.cr3bp.propagation import (
    DEFAULT_TOL,
    _check_arcs_outside_primaries,
    _check_outcome,
    _check_tol,
    _grid_from,
    _heyoka,
    _inside_primaries,
    check_outside_primaries,
    thread_local_copy,
)
from cislunar.estimation import srif
from cislunar.sensing.measurements import MeasurementModel
from cislunar.utils import validation

__all__ = ["OCBETransition", "ocbe_transition", "ocbe_process_noise", "estimated_control", "spike_contrast",
           "OCBEResult",
           "ocbe_filter_smoother", "variational_system", "block_integrator", "BLOCK_LAYOUT",
           "FilterDivergenceError"]


class FilterDivergenceError(RuntimeError):
    """The OCBE failed numerically while filtering (a diverged filter, not a configuration error).

    Attributes
    ----------
    epoch : int
        Index of the epoch being processed when the failure occurred.
    time : float
        Its time, TU.
    cause : str
        Type and message of the underlying numerical error.
    """

    def __init__(self, epoch: int, time: float, cause: str):
        super().__init__(f"OCBE failed numerically at epoch {epoch} (t = {time:.6g} TU): {cause}")
        self.epoch, self.time, self.cause = int(epoch), float(time), str(cause)

    def __reduce__(self):
        return (type(self), (self.epoch, self.time, self.cause))


def _availability(available, N: int, K: int) -> np.ndarray:
    """The (N, K) bool mask of which observer sees the target at which epoch (``None``: all, always).

    A (N,) mask is accepted for one observer.  Shared by the single-trial and the batched OCBE.
    """
    if available is None:
        return np.ones((N, K), dtype=bool)
    avail = np.asarray(available)
    if avail.dtype != bool:
        raise validation.ArgumentTypeError(f"available must be an array of bool; got dtype {avail.dtype}")
    if avail.shape != (N, K) and not (K == 1 and avail.shape == (N,)):
        raise ValueError(f"available must have shape ({N}, {K}); got {avail.shape}")
    return avail.reshape(N, K)

def check_model(model, name: str = "model"):
    """A :class:`cislunar.sensing.measurements.MeasurementModel` (e.g. ``measurements.ANGLES_AND_RATES``)."""

    return validation.instance(model, name, MeasurementModel,
                            "a cislunar.sensing.measurements.MeasurementModel (e.g. measurements.ANGLES_AND_RATES)")


def control_weights(control_weight, n_intervals: int, name: str = "control_weight", *, batch: int | None = None):
    """Per-interval control weights: a positive scalar or an array of shape ``(n_intervals,)`` (or ``(B, n)``)."""
    q = validation.as_array(control_weight, name)
    shapes = [(), (n_intervals,)] + ([] if batch is None else [(batch, n_intervals)])
    if q.shape not in shapes:
        raise ValueError(f"{name} must be a scalar or have shape {' or '.join(map(str, shapes[1:]))}; got {q.shape}")
    if np.any(q <= 0):
        raise ValueError(f"{name} must be positive on every interval")
    target = (n_intervals,) if batch is None else (batch, n_intervals)
    return np.broadcast_to(q, target).astype(float)


def _potential_expressions(hy):
    """heyoka state variables, the control-weight parameter and the CR3BP effective potential's derivatives.

    Returns ``(x, y, z, vx, vy, vz), q, grad, hess`` with parameters ``par[0] = mu``, ``par[1] = q`` and
    :math:`U = (x^2 + y^2)/2 + (1-\\mu)/r_1 + \\mu/r_2` (rotating frame, LU/TU): ``grad[i]`` is
    :math:`\\partial U/\\partial r_i`, ``hess[i][j]`` :math:`\\partial^2 U/\\partial r_i\\partial r_j`.
    """
    state = hy.make_vars("x", "y", "z", "vx", "vy", "vz")
    x, y, z = state[:3]
    mu, q = hy.par[0], hy.par[1]
    r1 = ((x + mu) ** 2 + y**2 + z**2) ** 0.5
    r2 = ((x - 1.0 + mu) ** 2 + y**2 + z**2) ** 0.5
    U = 0.5 * (x**2 + y**2) + (1.0 - mu) / r1 + mu / r2
    grad = [hy.diff(U, v) for v in (x, y, z)]
    hess = [[hy.diff(g, v) for v in (x, y, z)] for g in grad]
    return state, q, grad, hess


@functools.lru_cache(maxsize=4)
def _ocbe_template(tol: float):
    """Compile (once per process) the variational system of the OCBE Hamiltonian dynamics."""
    hy = _heyoka()
    (x, y, z, vx, vy, vz), q, grad, hess = _potential_expressions(hy)
    p = hy.make_vars("px", "py", "pz", "pvx", "pvy", "pvz")
    px, py, pz, pvx, pvy, pvz = p
    # u = -q B^T p = -q p_v ; f(x) = [v; grad U + 2 Omega v] with Omega v = (vy, -vx, 0)
    ax = grad[0] + 2.0 * vy - q * pvx
    ay = grad[1] - 2.0 * vx - q * pvy
    az = grad[2] - q * pvz
    # p' = -A^T p with A = [[0, I], [U_rr, 2 Omega]] -> p_r' = -U_rr p_v, p_v' = -p_r - (2 Omega)^T p_v
    dpr = [-(hess[i][0] * pvx + hess[i][1] * pvy + hess[i][2] * pvz) for i in range(3)]
    dpv = [-px + 2.0 * pvy, -py - 2.0 * pvx, -pz]
    sys = [(x, vx), (y, vy), (z, vz), (vx, ax), (vy, ay), (vz, az),
           (px, dpr[0]), (py, dpr[1]), (pz, dpr[2]), (pvx, dpv[0]), (pvy, dpv[1]), (pvz, dpv[2])]
    vsys = hy.var_ode_sys(sys, hy.var_args.vars, order=1)
    ta = hy.taylor_adaptive(vsys, [0.5, 0, 0, 0, 0.5, 0] + [0.0] * 6, pars=[0.01, 1.0], tol=tol, compact_mode=True)
    index = np.zeros((12, 12), dtype=int)
    for k in range(12, len(ta.state)):
        m = ta.get_mindex(k)
        index[m[0], int(np.flatnonzero(np.asarray(m[1:]))[0])] = k
    return ta, index


def variational_system(tol: float = DEFAULT_TOL):
    """The OCBE variational ODE system (heyoka expressions) and the state index of each 12x12 STM entry.

    For callers that build their own integrators from it (e.g. the heyoka batch integrator of the full-12x12 test
    oracle of the batched OCBE, ``tests/estimation/reference_batched_ocbe.py``; the package's batched OCBE integrates
    the three non-zero blocks, :func:`block_integrator`).  Returns ``(sys, index)``: ``sys`` is the list of
    (variable, expression) pairs, ``index[i, j]`` the position of entry (i, j) of the 12x12 STM in the integrator
    state; parameters are ``[mu, q]``.
    """
    ta, index = _ocbe_template(_check_tol(tol))
    return ta.sys, index.copy()


#: Positions of the reference state and of the three non-zero 6x6 blocks (row-major) in the state of
#: :func:`block_variational_system`.
BLOCK_LAYOUT = {"x": slice(0, 6), "phi_xx": slice(6, 42), "phi_xp": slice(42, 78), "phi_pp": slice(78, 114)}


#: :math:`K = T^\top JT` with :math:`T = [I,\ 0;\ W,\ I]` (the canonical momenta :math:`\mathbf v + \hat{\mathbf z}\times
#: \mathbf r`, :math:`W\mathbf r = \hat{\mathbf z}\times\mathbf r`) and :math:`J = [0,\ I;\ -I,\ 0]`:
#: :math:`K = [2W,\ I;\ -I,\ 0]`.  The CR3BP's state transition preserves it, :math:`\Phi^\top K\Phi = K`
#: (:math:`A^\top K + KA = 0` for :math:`A = [0,\ I;\ U_{rr},\ -2W]`), so the costate block of the OCBE
#: transition is :math:`\Phi_{pp} = \Phi_{xx}^{-\top} = K\Phi_{xx}K^{-1}`, linear in :math:`\Phi_{xx}`.
_K = np.block([[2.0 * np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 0.0]]), np.eye(3)],
               [-np.eye(3), np.zeros((3, 3))]])
_K_INV = np.block([[np.zeros((3, 3)), -np.eye(3)], [np.eye(3), 2.0 * np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0],
                                                                             [0.0, 0.0, 0.0]])]])


def _costate_block(phi_xx):
    """:math:`\\Phi_{pp} = K\\Phi_{xx}K^{-1}` (= :math:`\\Phi_{xx}^{-\\top}`, :data:`_K`) of stacked ballistic state
    transitions ``phi_xx`` (..., 6, 6) of the CR3BP (rotating frame, LU, LU/TU); unchecked (inner kernel)."""
    return _K @ phi_xx @ _K_INV


@functools.lru_cache(maxsize=2)
def _block_system(costate_block: bool = True):
    """Expressions of :func:`block_variational_system` (built once per process); without ``costate_block`` the
    :math:`\\Phi_{pp}` rows that drive :math:`\\Phi_{xp}` are the linear expressions of :func:`_costate_block`
    instead of integrated states (78 states instead of 114)."""
    hy = _heyoka()
    (x, y, z, vx, vy, vz), q, grad, hess = _potential_expressions(hy)

    def a_col(i, c):
        """Row i of A c for a column c (6 expressions); A = [[0, I], [U_rr, 2 Omega]], 2 Omega v = (2vy, -2vx, 0)."""
        if i < 3:
            return c[i + 3]
        k = i - 3
        e = hess[k][0] * c[0] + hess[k][1] * c[1] + hess[k][2] * c[2]
        return e + 2.0 * c[4] if k == 0 else e - 2.0 * c[3] if k == 1 else e

    def at_col(i, c):
        """Row i of A^T c: A^T = [[0, U_rr], [I, (2 Omega)^T]] (U_rr symmetric)."""
        if i < 3:
            return hess[i][0] * c[3] + hess[i][1] * c[4] + hess[i][2] * c[5]
        k = i - 3
        return c[k] - 2.0 * c[4] if k == 0 else c[k] + 2.0 * c[3] if k == 1 else c[k]

    blocks = {b: [[hy.make_vars(f"{b}_{i}{j}") for j in range(6)] for i in range(6)] for b in ("xx", "xp", "pp")}
    F, X, P = blocks["xx"], blocks["xp"], blocks["pp"]
    col = lambda M, j: [M[k][j] for k in range(6)]  # noqa: E731
    sys = [(x, vx), (y, vy), (z, vz), (vx, grad[0] + 2.0 * vy), (vy, grad[1] - 2.0 * vx), (vz, grad[2])]
    sys += [(F[i][j], a_col(i, col(F, j))) for i in range(6) for j in range(6)]
    if not costate_block:  # rows 3-5 of K Phi_xx K^-1: [-Phi_rv, Phi_rr - 2 Phi_rv W]
        P = [None] * 3 + [[-F[i][3], -F[i][4], -F[i][5], F[i][0] - 2.0 * F[i][4], F[i][1] + 2.0 * F[i][3], F[i][2]]
                          for i in range(3)]
    sys += [(X[i][j], a_col(i, col(X, j)) - q * P[i][j] if i >= 3 else a_col(i, col(X, j)))
            for i in range(6) for j in range(6)]
    if costate_block:
        sys += [(P[i][j], -at_col(i, col(P, j))) for i in range(6) for j in range(6)]
    return sys


@functools.lru_cache(maxsize=8)
def _block_template(tol: float, batch_size: int, costate_block: bool = True):
    """Compile (once per process, tolerance, batch size and layout) the batch integrator of
    :func:`block_integrator`."""
    hy = _heyoka()
    sys = _block_system(costate_block)
    return hy.taylor_adaptive_batch(sys, np.zeros((len(sys), batch_size)), pars=np.zeros((2, batch_size)), tol=tol,
                                    compact_mode=True)


def block_integrator(batch_size: int, tol: float = DEFAULT_TOL, *, costate_block: bool = True):
    """heyoka batch integrator of the OCBE transition blocks for ``batch_size`` references at once.

    About the ballistic reference of the filters (:math:`\\mathbf p \\equiv 0`) the variational equations of
    :func:`variational_system` reduce to

    .. math::

        \\dot\\Phi_{xx} = A\\Phi_{xx},\\qquad \\dot\\Phi_{xp} = A\\Phi_{xp} - B\\tilde QB^\\top\\Phi_{pp},\\qquad
        \\dot\\Phi_{pp} = -A^\\top\\Phi_{pp},\\qquad \\Phi_{px}\\equiv 0,

    with :math:`A = \\partial f/\\partial\\mathbf x`: every term of the full system that multiplies :math:`\\mathbf p`
    vanishes exactly and :math:`\\Phi_{px}` stays exactly zero.  Dropping the zero block and the vanishing
    third-derivative terms cuts the Taylor decomposition about six-fold (114 instead of 156 states, 836 instead of
    5260 elementary operations); the kept entries obey the same differential equations, so the two integrators
    agree to round-off (``tests/estimation/test_ocbe.py``).  Used by the batched OCBE of :mod:`cislunar.estimation.batched_ocbe`.

    Parameters
    ----------
    batch_size : int
        Number of references integrated in lockstep (one SIMD lane each).
    tol : float
        Integrator tolerance.
    costate_block : bool
        Integrate :math:`\\Phi_{pp}` (the default, 114 states), or not (``False``, 78 states: the first 78 rows of
        :data:`BLOCK_LAYOUT`).  The CR3BP's state transition preserves the form :math:`K = [2W,\\ I;\\ -I,\\ 0]`
        (:math:`W\\mathbf r = \\hat{\\mathbf z}\\times\\mathbf r`, the rotating frame's canonical momenta), so
        :math:`\\Phi_{pp} = \\Phi_{xx}^{-\\top} = K\\Phi_{xx}K^{-1}` is linear in :math:`\\Phi_{xx}`: its rows in
        the :math:`\\Phi_{xp}` equation become those linear expressions, and callers form :math:`\\Phi_{pp}` from
        :math:`\\Phi_{xx}` the same way.  Equal to the 114-state integration to round-off (step sizes, and so the
        last bits, may differ: heyoka's step control sees all states); about 1.2x faster.

    Returns
    -------
    heyoka.taylor_adaptive_batch
        This thread's working copy (compiled once per process, copied once per thread; callers reset time, state
        and parameters).  State layout (114 rows, one column per reference): :data:`BLOCK_LAYOUT`, blocks
        row-major; start each interval with ``x`` the reference, ``phi_xx = phi_pp = I``, ``phi_xp = 0``.
        Parameters ``[mu, q]`` with ``q`` the control weight (LU^2/TU^3) as in :func:`variational_system`.
    """
    B = validation.integer(batch_size, "batch_size", minimum=1)
    tol = _check_tol(tol)
    costate_block = validation.boolean(costate_block, "costate_block")
    return thread_local_copy(("ocbe_block", tol, B, costate_block), lambda: _block_template(tol, B, costate_block))


def _ocbe_integrator(tol: float):
    """This thread's working copy of the compiled OCBE integrator."""
    return thread_local_copy(("ocbe", tol), lambda: _ocbe_template(tol)[0])


@dataclass(frozen=True)
class OCBETransition:
    """Reference trajectory and OCBE transition matrices on a time grid.

    Attributes
    ----------
    t : ndarray, shape (m,)
        Times, TU.
    x : ndarray, shape (m, 6)
        Ballistic reference states.
    phi : ndarray, shape (m, 12, 12)
        :math:`\\Phi(t_k, t_0)` of the state/costate deviations.
    control_weight : float
        :math:`q` in :math:`\\tilde Q = qI_3`, LU^2/TU^3.
    """

    t: np.ndarray
    x: np.ndarray
    phi: np.ndarray
    control_weight: float

    @property
    def phi_xx(self):
        return self.phi[..., :6, :6]

    @property
    def phi_xp(self):
        return self.phi[..., :6, 6:]

    @property
    def phi_px(self):
        return self.phi[..., 6:, :6]

    @property
    def phi_pp(self):
        return self.phi[..., 6:, 6:]


def ocbe_transition(system: CR3BP, x0, t, control_weight: float, *, tol: float = DEFAULT_TOL) -> OCBETransition:
    """Propagate a ballistic reference and the 12x12 OCBE transition matrix.

    Parameters
    ----------
    system : CR3BP
    x0 : array_like, shape (6,)
        Reference state at ``t[0]``.
    t : float or array_like
        Final time or monotonic grid (TU), as in :func:`cislunar.cr3bp.propagation.propagate`.
    control_weight : float
        :math:`q > 0` of :math:`\\tilde Q = qI_3`, LU^2/TU^3.
    tol : float
        Integrator tolerance.

    Notes
    -----
    The OCBE integrator carries no impact events (its reference is the filter's current estimate of a spacecraft
    in orbit, re-linearised every interval): impact events change its steps at round-off level.  A start inside a
    primary raises :class:`cislunar.cr3bp.propagation.ImpactError`, and so does any grid state inside a primary or
    an arc between two grid points that dips below a surface: every grid interval that a fall-time bound from
    Jacobi's integral cannot clear is re-propagated with the impact events of
    :func:`cislunar.cr3bp.propagation.propagate` (a sufficient condition: no interval through a primary is missed,
    whatever its length).
    """
    check_system(system)
    x0 = validation.as_state(x0, "x0", batch=False)
    grid = _grid_from(t)
    check_outside_primaries(system, x0, "x0", t0=grid[0])
    q = validation.positive(control_weight, "control_weight")
    tol = _check_tol(tol)
    return _transition(system, x0, grid, q, tol)


def _transition(system, x0, grid, q, tol) -> OCBETransition:
    """:func:`ocbe_transition` without argument checks (the filters' inner loop)."""
    _, index = _ocbe_template(tol)
    ta = _ocbe_integrator(tol)
    ta.pars[:] = [system.mu, q]
    ta.time = grid[0]
    ta.state[:12] = np.r_[x0, np.zeros(6)]
    ta.state[12:] = np.eye(12).ravel()
    res = ta.propagate_grid(grid)
    _check_outcome(res[0], grid[-1], ta.time, None, np.array(ta.state[:6]))
    out = res[-1]
    if _inside_primaries(system, out[:, :3]):
        check_outside_primaries(system, out[:, :6], "reference trajectory", t0=grid[0])
    _check_arcs_outside_primaries(system, grid, out[:, :6], tol)
    return OCBETransition(t=grid, x=out[:, :6], phi=out[:, index], control_weight=q)


def ocbe_process_noise(phi) -> np.ndarray:
    """OCBE process-noise-like term :math:`Q = -\\Phi_{xp}\\Phi_{xx}^\\top` (Greaves & Scheeres Eq. 17).

    Parameters
    ----------
    phi : array_like, shape (..., 12, 12)
        OCBE transition matrix over one interval.

    Returns
    -------
    ndarray, shape (..., 6, 6)
        Symmetric positive semi-definite (symmetrised; the asymmetry before symmetrising is checked).
    """
    phi = validation.as_array(phi, "phi")
    if phi.shape[-2:] != (12, 12):
        raise ValueError(f"phi must have shape (..., 12, 12); got {phi.shape}")
    return _process_noise(phi[..., :6, :6], phi[..., :6, 6:])


def _process_noise(phi_xx, phi_xp) -> np.ndarray:
    """:func:`ocbe_process_noise` from the two blocks (no argument checks; the batched filter's inner loop)."""
    Q = -phi_xp @ np.swapaxes(phi_xx, -1, -2)
    asym = np.max(np.abs(Q - np.swapaxes(Q, -1, -2)))
    if asym > 1e-8 * max(np.max(np.abs(Q)), 1e-300):
        raise ValueError(f"phi is not an OCBE transition matrix: -Phi_xp Phi_xx^T is not symmetric ({asym:.2e})")
    return 0.5 * (Q + np.swapaxes(Q, -1, -2))


def estimated_control(control_weight: float, phi_pp, p) -> np.ndarray:
    """Estimated control :math:`\\hat u(t) = -\\tilde QB^\\top\\Phi_{pp}(t, t_n)\\mathbf p_n` (Eq. 32), LU/TU^2.

    Parameters
    ----------
    control_weight : float
        :math:`q` of :math:`\\tilde Q = qI_3`.
    phi_pp : array_like, shape (..., 6, 6)
        Costate transition from :math:`t_n` to each time.
    p : array_like, shape (6,)
        Costate at :math:`t_n`.
    """
    q = validation.positive(control_weight, "control_weight")
    phi_pp = validation.as_array(phi_pp, "phi_pp")
    if phi_pp.shape[-2:] != (6, 6):
        raise ValueError(f"phi_pp must have shape (..., 6, 6); got {phi_pp.shape}")
    p = validation.as_array(p, "p", shape=(6,))
    return -q * (phi_pp @ p)[..., 3:6]


def spike_contrast(t, control_norm, t_centre: float, half_width: float) -> np.ndarray:
    """How much an estimated control stands out near ``t_centre``: mean norm within ``half_width`` over the mean
    farther away (1: no spike; the measure of the paper's Figs. 11 and 13).

    Means, not maxima or medians: the forward (single-step) control is a saw-tooth that restarts every interval and
    the smoothed one spreads a burn over the raised-uncertainty intervals, so the average level is what
    distinguishes a spike.

    Parameters
    ----------
    t : array_like, shape S
        Times of the control samples, e.g. the (N-1, n_sub) sub-grid of a run (any unit, the same as
        ``t_centre`` and ``half_width``).
    control_norm : array_like, shape (...,) + S
        Control norms at those times (any unit; leading axes are e.g. trials or forward/smoothed).
    t_centre, half_width : float
        Centre and half width of the window that should hold the spike.

    Returns
    -------
    ndarray, shape (...)
    """
    t = validation.as_array(t, "t")
    u = validation.as_array(control_norm, "control_norm")
    if t.ndim < 1 or u.shape[u.ndim - t.ndim:] != t.shape or u.ndim < t.ndim:
        raise ValueError(f"control_norm must have shape (..., {', '.join(map(str, t.shape))}) to match t; "
                         f"got {u.shape}")
    if np.any(u < 0):
        raise ValueError("control_norm must hold norms (>= 0)")
    t0 = validation.real(t_centre, "t_centre")
    hw = validation.positive(half_width, "half_width")
    near = np.abs(t - t0) <= hw
    if not near.any() or near.all():
        raise ValueError(f"t_centre +- half_width must cover some but not all of t; got {t0} +- {hw}")
    u = u.reshape(u.shape[:u.ndim - t.ndim] + (-1,))
    near = near.ravel()
    return u[..., near].mean(axis=-1) / u[..., ~near].mean(axis=-1)


# ----------------------------------------------------------------------------------------------------------
# The extended square-root-information OCBE with single-step and full smoothing (Eqs. 21-33)
# ----------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class OCBEResult:
    """Output of :func:`ocbe_filter_smoother`.

    Attributes
    ----------
    t : ndarray, shape (N,)
        Measurement times, TU.
    x_pred, P_pred : ndarray, shapes (N, 6), (N, 6, 6)
        Time-updated estimates (entry 0: the prior).
    x_filt, P_filt : ndarray
        Measurement-updated estimates (Eq. 28).
    x_smooth, P_smooth : ndarray or None
        Full SRI smoother.
    costate_step : ndarray, shape (N-1, 6)
        Single-step smoothed costates :math:`\\mathbf p_{n|n+1}` (Eq. 31).
    costate_smooth : ndarray or None, shape (N-1, 6)
        Costates consistent with the full smoother.
    t_sub : ndarray, shape (N-1, n_sub)
        Sub-grid of each interval on which the control is evaluated, TU.
    control_step, control_smooth : ndarray, shape (N-1, n_sub, 3)
        Estimated control (Eq. 32) from the single-step and the full smoother, LU/TU^2.
    z_step, z_smooth : float
        Control-policy integrals :math:`z = \\int\\|\\mathbf u\\|dt` (Eq. 33), LU/TU (multiply by the velocity
        unit for km/s).
    residual_norms : ndarray, shape (N,)
        Whitened residual norms of the measurement updates.
    """

    t: np.ndarray
    x_pred: np.ndarray
    P_pred: np.ndarray
    x_filt: np.ndarray
    P_filt: np.ndarray
    x_smooth: np.ndarray | None
    P_smooth: np.ndarray | None
    costate_step: np.ndarray
    costate_smooth: np.ndarray | None
    t_sub: np.ndarray
    control_step: np.ndarray
    control_smooth: np.ndarray | None
    z_step: float
    z_smooth: float | None
    residual_norms: np.ndarray


def _control_integral(t_sub, control) -> np.ndarray:
    """Eq. 33, :math:`\\sum_n\\int_{t_n}^{t_{n+1}}\\|u\\|dt`, by the trapezoid rule on each interval's sub-grid.

    ``t_sub`` (N-1, n_sub) in TU, ``control`` (..., N-1, n_sub, 3) in LU/TU^2 with optional leading trial axes (the
    batched filter of :mod:`cislunar.estimation.batched_ocbe`); returns shape (...), LU/TU.
    """
    mag = np.linalg.norm(control, axis=-1)
    return np.sum(np.trapezoid(mag, t_sub, axis=-1), axis=-1)


def ocbe_filter_smoother(system: CR3BP, t, y, observer_states, model, meas_cov, x0, P0, control_weight, *,
                         available=None, n_sub: int = 9, smooth: bool = True, tol: float = DEFAULT_TOL) -> OCBEResult:
    """Extended SRI OCBE of Greaves & Scheeres (2021, Eqs. 21-32) with single-step and full smoothing.

    At each interval the reference is re-linearised about the current estimate (EKF style): the 12x12 OCBE
    transition gives :math:`Q = -\\Phi_{xp}\\Phi_{xx}^\\top` (Eq. 17), the SRI time update with
    :math:`\\Gamma = I` (Eq. 23), the SRI measurement update (Eqs. 24-28), the single-step smoother and costate
    (Eqs. 29-31) and the estimated control (Eq. 32).  A backward SRI pass gives the full smoother; its costates
    are :math:`\\mathbf p_{n|N} = \\Phi_{xp}^{-1}\\hat{\\mathbf w}_n` with :math:`\\hat{\\mathbf w}_n` the smoothed
    deviation not explained by :math:`\\Phi_{xx}` (equal to Eq. 31 for the last step).

    Parameters
    ----------
    system : CR3BP
    t : array_like, shape (N,)
        Strictly increasing measurement times, TU; the prior refers to ``t[0]``.
    y : array_like, shape (N, m) or (N, K, m)
        Measurements of ``model`` (angles in rad, rates per TU), from one observer or from K observers.
    observer_states : array_like, shape (N, 6) or (N, K, 6)
        Observer states at the measurement times (deterministic, as in the paper).
    model : cislunar.sensing.measurements.MeasurementModel
    meas_cov : array_like, shape (m, m) or (N, m, m)
        Measurement noise covariance(s) of one observer's measurement, non-dimensional (the same for every
        observer; measurements of different observers are independent).
    available : array_like of bool, shape (N, K), optional
        Which observers measured at each epoch (line of sight, horizon); default all.  An epoch without any
        measurement is a pure time update.
    x0, P0 : array_like
        Prior mean (6,) and covariance (6, 6) at ``t[0]``.
    control_weight : float or array_like, shape (N-1,)
        :math:`q_n` of :math:`\\tilde Q = q_nI_3` on each interval, LU^2/TU^3 (the paper raises it in an 8-hour
        window around apoapsis).
    n_sub : int
        Points per interval for the control evaluation (>= 2).
    smooth : bool
        Run the full backward smoother.
    tol : float
        Integrator tolerance.
    """
    check_system(system)
    model = check_model(model)
    t = validation.time_grid(t, "t", increasing=True)
    N = t.size
    obs = validation.as_array(observer_states, "observer_states", ndim=(2, 3), last=6)
    obs = obs[:, None, :] if obs.ndim == 2 else obs
    K = obs.shape[1]
    if obs.shape[0] != N:
        raise ValueError(f"observer_states must have {N} epochs; got shape {obs.shape}")
    y = validation.as_array(y, "y", ndim=(2, 3), finite=False)
    y = y[:, None, :] if y.ndim == 2 else y
    if y.shape != (N, K, model.dim):
        raise ValueError(f"y must have shape ({N}, {model.dim}) or ({N}, {K}, {model.dim}); got {y.shape}")
    avail = _availability(available, N, K)
    if not np.all(np.isfinite(y[avail])):
        raise ValueError("y contains NaN or infinite values where measurements are available")
    R = validation.as_array(meas_cov, "meas_cov")
    R = np.broadcast_to(R, (N, model.dim, model.dim)) if R.shape == (model.dim, model.dim) else R
    if R.shape != (N, model.dim, model.dim):
        raise ValueError(f"meas_cov must have shape ({model.dim}, {model.dim}) or ({N}, {model.dim}, {model.dim})")
    validation.spd(R, "meas_cov", batch=True)
    qs = control_weights(control_weight, N - 1)
    n_sub = validation.integer(n_sub, "n_sub", minimum=2, maximum=10_000)
    smooth = validation.boolean(smooth, "smooth")
    tol = _check_tol(tol)
    x = validation.as_state(x0, "x0", batch=False).copy()
    P0 = validation.spd(P0, "P0", n=6)
    S, _ = srif.sri_from_covariance(np.zeros(6), P0)
    eye6 = np.eye(6)

    def update(S, x_ref, k):
        vis = np.flatnonzero(avail[k])
        if vis.size == 0:
            return S, x_ref.copy(), 0.0
        if not np.all(np.isfinite(x_ref)):  # a diverged estimate (was refused by model.evaluate's check)
            raise ValueError("target contains NaN or infinite values")
        val, _, Ht = model._evaluate(obs[k, vis], x_ref)  # arrays checked above: the unchecked kernels
        dy = model._residual(y[k, vis], val).reshape(-1)
        Rk = np.kron(np.eye(vis.size), R[k])
        S_new, b, e = srif._measurement_update(S, np.zeros(6), Ht.reshape(-1, 6), dy, Rk)
        return S_new, x_ref + srif._cov_of_sri(S_new, b)[0], e

    epoch = [0]

    def run(S, x):
        x_pred, P_pred, x_filt, P_filt, S_filt, resid = [], [], [], [], [], []
        phis, terms, Qs, t_sub, phi_pp_sub, p_step = [], [], [], [], [], []
        x_pred.append(x.copy())
        P_pred.append(srif._cov_of_sri(S))
        S, x, e = update(S, x, 0)
        x_filt.append(x.copy())
        P_filt.append(srif._cov_of_sri(S))
        S_filt.append(S)
        resid.append(e)
        for n in range(N - 1):
            epoch[0] = n + 1
            grid = np.linspace(t[n], t[n + 1], n_sub)
            tr = _transition(system, x, grid, qs[n], tol)
            Phi = tr.phi[-1]
            Phi_xx, Phi_xp = Phi[:6, :6], Phi[:6, 6:]
            Q = _process_noise(Phi_xx, Phi_xp)
            S_bar, _, term = srif._time_update(S, np.zeros(6), Phi_xx, eye6, Q)  # Eq. 23 (b_x,n|n = 0)
            x_prior = tr.x[-1]
            x_pred.append(x_prior.copy())
            P_pred.append(srif._cov_of_sri(S_bar))
            S_new, x_new, e = update(S_bar, x_prior, n + 1)  # Eqs. 24-28
            # single-step smoother (Eqs. 29-30) and costate (Eq. 31)
            S1, b1 = srif._smoother_step(S_new, S_new @ (x_new - x_prior), Phi_xx, eye6, term)
            dx_n = srif._cov_of_sri(S1, b1)[0]
            p_step.append(-(S.T @ S) @ dx_n)
            phis.append(Phi)
            terms.append(term)
            Qs.append(Q)
            t_sub.append(grid)
            phi_pp_sub.append(tr.phi_pp)
            S, x = S_new, x_new
            x_filt.append(x.copy())
            P_filt.append(srif._cov_of_sri(S))
            S_filt.append(S)
            resid.append(e)
        p_step = np.array(p_step)
        t_sub = np.array(t_sub)
        phi_pp_sub = np.array(phi_pp_sub)
        control_step = -qs[:, None, None] * np.einsum("nkij,nj->nki", phi_pp_sub, p_step)[..., 3:6]
        z_step = float(_control_integral(t_sub, control_step))
        x_s = P_s = p_s = control_s = z_s = None
        if smooth:
            xs, Ps = [None] * N, [None] * N
            Rs, bs = S_filt[-1], np.zeros(6)
            xs[-1], Ps[-1] = x_filt[-1], P_filt[-1]
            for n in range(N - 2, -1, -1):
                Phi_xx = phis[n][:6, :6]
                z_next = bs + Rs @ (x_filt[n + 1] - x_pred[n + 1])  # info about the deviation from x_{n+1|n}
                Rs, bs = srif._smoother_step(Rs, z_next, Phi_xx, eye6, terms[n])
                dx, Ps[n] = srif._cov_of_sri(Rs, bs)
                xs[n] = x_filt[n] + dx
            x_s, P_s = np.array(xs), np.array(Ps)
            p_s = np.empty((N - 1, 6))
            for n in range(N - 1):
                Phi_xx, Phi_xp = phis[n][:6, :6], phis[n][:6, 6:]
                w = (x_s[n + 1] - x_pred[n + 1]) - Phi_xx @ (x_s[n] - x_filt[n])
                p_s[n] = np.linalg.solve(Phi_xp, w)
            control_s = -qs[:, None, None] * np.einsum("nkij,nj->nki", phi_pp_sub, p_s)[..., 3:6]
            z_s = float(_control_integral(t_sub, control_s))
        return OCBEResult(t, np.array(x_pred), np.array(P_pred), np.array(x_filt), np.array(P_filt), x_s, P_s, p_step,
                          p_s, t_sub, control_step, control_s, z_step, z_s, np.array(resid))

    try:
        return run(S, x)
    except (np.linalg.LinAlgError, ValueError, RuntimeError, FloatingPointError) as exc:
        raise FilterDivergenceError(epoch[0], float(t[epoch[0]]), f"{type(exc).__name__}: {exc}") from exc
