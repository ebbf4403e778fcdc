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
:math:`\tilde Q` (checked in ``tests/test_ocbe.py`` against :func:`cislunar.covariance.process_noise`).

The 12x12 matrix is computed with heyoka's variational equations of the Hamiltonian system
:math:`\dot{\mathbf x} = f(\mathbf x) - B\tilde QB^\top\mathbf p`, :math:`\dot{\mathbf p} =
-(\partial f/\partial\mathbf x)^\top\mathbf p` started with :math:`\mathbf p = 0`: its first-order sensitivities
are exactly the block matrix above.  ``control_weight`` is :math:`\tilde Q = q I_3` in LU^2/TU^3 (an acceleration
PSD); times in TU, states in LU and LU/TU, rotating frame.
"""

from __future__ import annotations

import copy
import functools
from dataclasses import dataclass

import numpy as np

from . import _checks
from .dynamics import CR3BP
from .propagation import DEFAULT_TOL, _check_outcome, _check_tol, _grid_from, _heyoka

__all__ = ["OCBETransition", "ocbe_transition", "ocbe_process_noise", "estimated_control"]


@functools.lru_cache(maxsize=4)
def _ocbe_template(tol: float):
    """Compile (once per process) the variational system of the OCBE Hamiltonian dynamics."""
    hy = _heyoka()
    x, y, z, vx, vy, vz = hy.make_vars("x", "y", "z", "vx", "vy", "vz")
    p = hy.make_vars("px", "py", "pz", "pvx", "pvy", "pvz")
    mu, q = hy.par[0], hy.par[1]
    r1 = ((x + mu) ** 2 + y**2 + z**2) ** 0.5
    r2 = ((x - 1.0 + mu) ** 2 + y**2 + z**2) ** 0.5
    U = 0.5 * (x**2 + y**2) + (1.0 - mu) / r1 + mu / r2
    pos = (x, y, z)
    grad = [hy.diff(U, v) for v in pos]
    hess = [[hy.diff(g, v) for v in pos] for g in grad]
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
        Final time or monotonic grid (TU), as in :func:`cislunar.propagation.propagate`.
    control_weight : float
        :math:`q > 0` of :math:`\\tilde Q = qI_3`, LU^2/TU^3.
    tol : float
        Integrator tolerance.
    """
    x0 = _checks.as_state(x0, "x0", batch=False)
    grid = _grid_from(t)
    q = _checks.positive(control_weight, "control_weight")
    tol = _check_tol(tol)
    template, index = _ocbe_template(tol)
    ta = copy.copy(template)
    ta.pars[:] = [system.mu, q]
    ta.time = grid[0]
    ta.state[:12] = np.r_[x0, np.zeros(6)]
    ta.state[12:] = np.eye(12).ravel()
    res = ta.propagate_grid(grid)
    _check_outcome(res[0], grid[-1], ta.time)
    out = res[-1]
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
    phi = _checks.as_array(phi, "phi")
    if phi.shape[-2:] != (12, 12):
        raise ValueError(f"phi must have shape (..., 12, 12); got {phi.shape}")
    Q = -phi[..., :6, 6:] @ np.swapaxes(phi[..., :6, :6], -1, -2)
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
    q = _checks.positive(control_weight, "control_weight")
    phi_pp = _checks.as_array(phi_pp, "phi_pp")
    if phi_pp.shape[-2:] != (6, 6):
        raise ValueError(f"phi_pp must have shape (..., 6, 6); got {phi_pp.shape}")
    p = _checks.as_array(p, "p", shape=(6,))
    return -q * (phi_pp @ p)[..., 3:6]
