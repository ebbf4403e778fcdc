r"""Time nodes and first-order-hold discretisation for successive convexification (Wolf & Jones, §SCvx).

Sundman-spaced nodes (Eqs. 37-39)
---------------------------------
With the generalised Sundman transformation :math:`dt = r_m^{\sigma}d\tau` (:math:`r_m` the distance to the Moon),
nodes equally spaced in :math:`\tau` crowd where :math:`r_m` is small (perilune) for :math:`\sigma > 0` and are
equally spaced in time for :math:`\sigma = 0`.  The paper integrates :math:`dz/d\tau = r_m^{\sigma}[f; 1]`
(Eq. 38, where the exponent is printed as :math:`\alpha`; it is the :math:`\sigma` of Eq. 37).  Equivalently,
and what is done here, :math:`\tau(t) = \int_0^t r_m^{-\sigma}dt` is integrated alongside the reference
trajectory (heyoka, one extra state) and the node times solve :math:`\tau(t_k) = k\,\tau(t_f)/(N-1)` on the
dense output.

Maximum control per node (Eqs. 40-41)
-------------------------------------
With unequal intervals the thrust bound becomes node dependent: Eq. 40 asks
:math:`(u_{max,k} + u_{max,k+1})/(2\Delta t_k) = a_{max}` on every interval (Eq. 41 in matrix form), an
underdetermined system whose minimum-norm solution is returned (the paper uses a QR factorisation;
``numpy.linalg.lstsq`` gives the same minimum-norm solution).

First-order hold (Eqs. 27-33)
-----------------------------
Between nodes the control (an acceleration, LU/TU^2, added to the CR3BP velocity derivative) is interpolated
linearly, :math:`u(t) = \lambda_k^-(t)u_k + \lambda_k^+(t)u_{k+1}`.  The discrete model
:math:`x_{k+1} = A_kx_k + B_k^-u_k + B_k^+u_{k+1} + r_k + E_k\epsilon_k` (Eqs. 28-31) is obtained here from
heyoka's variational equations with respect to the state *and* the parameters :math:`u_k, u_{k+1}` and a constant
virtual control :math:`\epsilon` entering every state derivative (:math:`E(t) = I`): the sensitivities of
:math:`x_{k+1}` are exactly :math:`A_k = \Phi(t_{k+1},t_k)`, :math:`B_k^\mp = A_k\int\Phi^{-1}B\lambda^\mp d\tau`
and :math:`E_k = A_k\int\Phi^{-1}d\tau`, with no inverse of the STM needed (the paper's Eq. 32 integrates
:math:`\Phi^{-1}` instead).  :math:`r_k` makes the affine model exact at the reference.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from cislunar.cr3bp.dynamics import CR3BP, check_system
from cislunar.cr3bp.propagation import (
    DEFAULT_TOL,
    _check_outcome,
    _check_tol,
    _heyoka,
    thread_local_copy,
)
from cislunar.utils import validation

__all__ = ["sundman_nodes", "max_control_per_node", "FOHModel", "foh_discretize", "propagate_foh"]


@functools.lru_cache(maxsize=4)
def _sundman_template(tol: float):
    hy = _heyoka()
    x, y, z, vx, vy, vz, tau = hy.make_vars("x", "y", "z", "vx", "vy", "vz", "tau")
    mu, sigma = hy.par[0], hy.par[1]
    r1_3 = ((x + mu) ** 2 + y**2 + z**2) ** 1.5
    rm2 = (x - 1.0 + mu) ** 2 + y**2 + z**2
    r2_3 = rm2**1.5
    sys = [(x, vx), (y, vy), (z, vz),
           (vx, 2.0 * vy + x - (1.0 - mu) * (x + mu) / r1_3 - mu * (x - 1.0 + mu) / r2_3),
           (vy, -2.0 * vx + y - (1.0 - mu) * y / r1_3 - mu * y / r2_3),
           (vz, -(1.0 - mu) * z / r1_3 - mu * z / r2_3),
           (tau, rm2 ** (-0.5 * sigma))]
    return hy.taylor_adaptive(sys, [0.8, 0, 0, 0, 0.5, 0, 0], pars=[0.01, 0.0, 0.0, 0.0], tol=tol,
                              compact_mode=True, t_events=_impact_events(hy, x, y, z, mu, hy.par[2], hy.par[3]))


def _impact_events(hy, x, y, z, mu, r_moon, r_earth):
    """Terminal events at the surface of the Moon (event 0) and of the Earth (event 1), entered from outside."""
    return [hy.t_event(((x - 1.0 + mu) ** 2 + y**2 + z**2) - r_moon**2, direction=hy.event_direction.negative),
            hy.t_event(((x + mu) ** 2 + y**2 + z**2) - r_earth**2, direction=hy.event_direction.negative)]


def _check_outside(system: CR3BP, x, name: str):
    """Refuse states inside either primary (an integration from there would run through the body)."""
    x = np.atleast_2d(x)
    rm = np.linalg.norm(x[:, :3] - [1.0 - system.mu, 0.0, 0.0], axis=1)
    re = np.linalg.norm(x[:, :3] - [-system.mu, 0.0, 0.0], axis=1)
    bad = np.flatnonzero((rm <= system.secondary_radius) | (re <= system.primary_radius))
    if bad.size:
        raise ValueError(f"{name} holds a state inside a primary (row {int(bad[0])})")


def sundman_nodes(system: CR3BP, x0, t_final: float, n_nodes: int, sigma: float, *, tol: float = DEFAULT_TOL):
    """Node times equally spaced in the Sundman variable :math:`\\tau` along a ballistic reference.

    Parameters
    ----------
    system : CR3BP
    x0 : array_like, shape (6,)
        Reference state at ``t = 0``.
    t_final : float
        Final time, TU (> 0).
    n_nodes : int
        Number of nodes including both ends (>= 2).
    sigma : float
        Sundman exponent; 0 gives uniform nodes, positive values crowd nodes near perilune.  In [-3, 3].
    tol : float
        Integrator tolerance.

    Returns
    -------
    t_nodes : ndarray, shape (n_nodes,)
        Node times, TU, from 0 to ``t_final``.
    tau_nodes : ndarray, shape (n_nodes,)
        The Sundman variable at the nodes (LU^-sigma TU).

    Raises
    ------
    ValueError
        ``x0`` lies inside a primary.
    RuntimeError
        The ballistic reference hits the surface of the Moon or the Earth before ``t_final`` (terminal event).
    """
    check_system(system, "system")
    x0 = validation.as_state(x0, "x0", batch=False)
    tf = validation.positive(t_final, "t_final")
    n = validation.integer(n_nodes, "n_nodes", minimum=2)
    sigma = validation.in_range(sigma, "sigma", -3.0, 3.0)
    tol = _check_tol(tol)
    ta = thread_local_copy(("sundman", tol), lambda: _sundman_template(tol))
    _check_outside(system, x0, "x0")
    ta.pars[:] = [system.mu, sigma, system.secondary_radius, system.primary_radius]
    ta.time = 0.0
    ta.state[:] = np.r_[x0, 0.0]
    res = ta.propagate_until(tf, c_output=True)
    _check_outcome(res[0], tf, ta.time)
    c_out = res[4]
    tau_f = float(ta.state[6])
    tau_nodes = np.linspace(0.0, tau_f, n)
    t_nodes = np.empty(n)
    t_nodes[0], t_nodes[-1] = 0.0, tf
    lo = 0.0
    for k in range(1, n - 1):
        t_nodes[k] = brentq(lambda s, target=tau_nodes[k]: float(c_out(s)[6]) - target, lo, tf, xtol=1e-14,
                            rtol=1e-14)
        lo = t_nodes[k]
    return t_nodes, tau_nodes


def max_control_per_node(t_nodes, a_max: float) -> np.ndarray:
    r"""Minimum-norm node bounds solving Eq. 41 as printed: :math:`(u_{max,k} + u_{max,k+1})/\Delta t_k = 2a_{max}`.

    Each row is Eq. 40, :math:`(u_{max,k} + u_{max,k+1})/(2\Delta t_k) = a_{max}`: the bounds have the units of
    :math:`a_{max}` times time (an impulse per node).  Read instead as accelerations, the trapezoid rule would give
    :math:`(u_{max,k} + u_{max,k+1})/2 = a_{max}`, solved by the uniform :math:`u_{max,k} = a_{max}`; notebook 04
    shows both readings.

    Parameters
    ----------
    t_nodes : array_like, shape (N,)
        Strictly increasing node times.
    a_max : float
        Maximum acceleration, >= 0.

    Returns
    -------
    ndarray, shape (N,)
        Minimum-norm solution (``numpy.linalg.lstsq``; the paper uses a QR factorisation, same solution).
    """
    t = validation.time_grid(t_nodes, "t_nodes", increasing=True)
    a = validation.positive(a_max, "a_max", allow_zero=True)
    dt = np.diff(t)
    n = t.size
    M = np.zeros((n - 1, n))
    idx = np.arange(n - 1)
    M[idx, idx] = 1.0 / dt
    M[idx, idx + 1] = 1.0 / dt
    return np.linalg.lstsq(M, np.full(n - 1, 2.0 * a), rcond=None)[0]


@functools.lru_cache(maxsize=4)
def _foh_template(tol: float):
    """Variational system of the CR3BP with a first-order-hold acceleration and a constant virtual control.

    Parameters: ``par[0]`` mu, ``par[1:4]`` u_k, ``par[4:7]`` u_{k+1}, ``par[7:13]`` epsilon (added to the six
    state derivatives), ``par[13]`` t_k, ``par[14]`` t_{k+1}, ``par[15:17]`` Moon and Earth radii (LU; terminal
    impact events).
    """
    hy = _heyoka()
    x, y, z, vx, vy, vz = hy.make_vars("x", "y", "z", "vx", "vy", "vz")
    mu = hy.par[0]
    tk, tk1 = hy.par[13], hy.par[14]
    lam_m = (tk1 - hy.time) / (tk1 - tk)
    lam_p = (hy.time - tk) / (tk1 - tk)
    u = [lam_m * hy.par[1 + i] + lam_p * hy.par[4 + i] for i in range(3)]
    eps = [hy.par[7 + i] for i in range(6)]
    r1_3 = ((x + mu) ** 2 + y**2 + z**2) ** 1.5
    r2_3 = ((x - 1.0 + mu) ** 2 + y**2 + z**2) ** 1.5
    rhs = [vx + eps[0], vy + eps[1], vz + eps[2],
           2.0 * vy + x - (1.0 - mu) * (x + mu) / r1_3 - mu * (x - 1.0 + mu) / r2_3 + u[0] + eps[3],
           -2.0 * vx + y - (1.0 - mu) * y / r1_3 - mu * y / r2_3 + u[1] + eps[4],
           -(1.0 - mu) * z / r1_3 - mu * z / r2_3 + u[2] + eps[5]]
    sys = list(zip((x, y, z, vx, vy, vz), rhs))
    args = [x, y, z, vx, vy, vz] + [hy.par[i] for i in range(1, 13)]
    vsys = hy.var_ode_sys(sys, args, order=1)
    ta = hy.taylor_adaptive(vsys, [0.8, 0, 0, 0, 0.5, 0], pars=np.r_[0.01, np.zeros(12), 0.0, 1.0, 0.0, 0.0],
                            tol=tol, compact_mode=True,
                            t_events=_impact_events(hy, x, y, z, mu, hy.par[15], hy.par[16]))
    index = np.zeros((6, 18), dtype=int)
    for k in range(6, len(ta.state)):
        m = ta.get_mindex(k)
        index[m[0], int(np.flatnonzero(np.asarray(m[1:]))[0])] = k
    return ta, index


@dataclass(frozen=True)
class FOHModel:
    """Discrete affine model :math:`x_{k+1} = A_kx_k + B^-_ku_k + B^+_ku_{k+1} + r_k + E_k\\epsilon_k` (Eq. 30b).

    Attributes
    ----------
    t : ndarray, shape (N,)
        Node times, TU.
    A, Bm, Bp, E : ndarray, shapes (N-1, 6, 6), (N-1, 6, 3), (N-1, 6, 3), (N-1, 6, 6)
    r : ndarray, shape (N-1, 6)
    x_next : ndarray, shape (N-1, 6)
        Nonlinear propagation of each reference node with the reference controls (Eq. 35).
    defects : ndarray, shape (N-1, 6)
        :math:`\\delta_k = \\bar x_{k+1} - f_k(\\bar x_k, \\bar u_k, \\bar u_{k+1})` (Eq. 34).
    """

    t: np.ndarray
    A: np.ndarray
    Bm: np.ndarray
    Bp: np.ndarray
    E: np.ndarray
    r: np.ndarray
    x_next: np.ndarray
    defects: np.ndarray

    def predict(self, x_nodes, u_nodes, eps=None) -> np.ndarray:
        """Affine prediction of ``x_{k+1}`` from node states (N, 6), controls (N, 3) and virtual controls (N-1, 6)."""
        x = validation.as_array(x_nodes, "x_nodes", shape=(self.t.size, 6))
        u = validation.as_array(u_nodes, "u_nodes", shape=(self.t.size, 3))
        out = (np.einsum("kij,kj->ki", self.A, x[:-1]) + np.einsum("kij,kj->ki", self.Bm, u[:-1])
               + np.einsum("kij,kj->ki", self.Bp, u[1:]) + self.r)
        if eps is not None:
            out = out + np.einsum("kij,kj->ki", self.E, validation.as_array(eps, "eps", shape=(self.t.size - 1, 6)))
        return out


_FOH_VARIATIONAL_IC = np.concatenate([np.eye(6), np.zeros((6, 12))], axis=1).ravel()  # d x / d (x0, uk, uk1, eps)
_FOH_VARIATIONAL_IC.flags.writeable = False


def _foh_interval(system, x0, uk, uk1, t0, t1, tol):
    ta = thread_local_copy(("foh", tol), lambda: _foh_template(tol)[0])
    _, index = _foh_template(tol)
    pars = ta.pars
    pars[0] = system.mu
    pars[1:4] = uk
    pars[4:7] = uk1
    pars[7:13] = 0.0
    pars[13] = t0
    pars[14] = t1
    pars[15] = system.secondary_radius
    pars[16] = system.primary_radius
    ta.time = t0
    ta.state[:6] = x0
    ta.state[6:] = _FOH_VARIATIONAL_IC
    res = ta.propagate_until(t1)
    _check_outcome(res[0], t1, ta.time)
    return ta.state[:6].copy(), ta.state[index]


def foh_discretize(system: CR3BP, t_nodes, x_nodes, u_nodes, *, tol: float = DEFAULT_TOL) -> FOHModel:
    """Linearise the FOH-controlled CR3BP about reference nodes (Eqs. 28-31, 34-35).

    Parameters
    ----------
    system : CR3BP
    t_nodes : array_like, shape (N,)
        Strictly increasing node times, TU.
    x_nodes : array_like, shape (N, 6)
        Reference states at the nodes (each interval starts from its own node: multiple shooting).
    u_nodes : array_like, shape (N, 3)
        Reference accelerations at the nodes, LU/TU^2 (rotating-frame components).
    tol : float
        Integrator tolerance.

    Raises
    ------
    ValueError
        A reference node lies inside a primary.
    RuntimeError
        An interval's propagation hits the surface of the Moon or the Earth (terminal event) or fails.
    """
    check_system(system, "system")
    t = validation.time_grid(t_nodes, "t_nodes", increasing=True)
    n = t.size
    x = validation.as_array(x_nodes, "x_nodes", shape=(n, 6))
    u = validation.as_array(u_nodes, "u_nodes", shape=(n, 3))
    tol = _check_tol(tol)
    return _foh_discretize(system, t, x, u, tol)


def _foh_discretize(system: CR3BP, t, x, u, tol: float) -> FOHModel:
    """Unchecked kernel of :func:`foh_discretize` (arrays already validated by the caller); the geometric guard
    against reference nodes inside a primary stays, since the nodes of an SCvx iteration are computed."""
    n = t.size
    _check_outside(system, x, "x_nodes")
    A = np.empty((n - 1, 6, 6))
    Bm = np.empty((n - 1, 6, 3))
    Bp = np.empty((n - 1, 6, 3))
    E = np.empty((n - 1, 6, 6))
    xn = np.empty((n - 1, 6))
    for k in range(n - 1):
        xn[k], S = _foh_interval(system, x[k], u[k], u[k + 1], t[k], t[k + 1], tol)
        A[k], Bm[k], Bp[k], E[k] = S[:, :6], S[:, 6:9], S[:, 9:12], S[:, 12:18]
    r = xn - np.einsum("kij,kj->ki", A, x[:-1]) - np.einsum("kij,kj->ki", Bm, u[:-1]) - np.einsum(
        "kij,kj->ki", Bp, u[1:])
    return FOHModel(t, A, Bm, Bp, E, r, xn, x[1:] - xn)


def propagate_foh(system: CR3BP, x0, t_nodes, u_nodes, *, tol: float = DEFAULT_TOL) -> np.ndarray:
    """Nonlinear propagation of ``x0`` through the nodes under the FOH control (single shooting).

    Parameters
    ----------
    system : CR3BP
    x0 : array_like (6,)
        State at ``t_nodes[0]``.
    t_nodes : array_like (N,)
        Strictly increasing node times, TU.
    u_nodes : array_like (N, 3)
        Node accelerations, LU/TU^2 (linear in between).
    tol : float

    Returns
    -------
    ndarray (N, 6)
        States at the nodes.

    Raises
    ------
    RuntimeError
        The trajectory hits the surface of the Moon or the Earth (terminal event), or the integration fails.
    """
    check_system(system, "system")
    t = validation.time_grid(t_nodes, "t_nodes", increasing=True)
    u = validation.as_array(u_nodes, "u_nodes", shape=(t.size, 3))
    x = np.empty((t.size, 6))
    x[0] = validation.as_state(x0, "x0", batch=False)
    tol = _check_tol(tol)
    _check_outside(system, x[0], "x0")
    for k in range(t.size - 1):
        x[k + 1], _ = _foh_interval(system, x[k], u[k], u[k + 1], t[k], t[k + 1], tol)
    return x
