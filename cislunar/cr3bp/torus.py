r"""Two-dimensional quasi-periodic invariant tori of the CR3BP by the invariant-circle (GMOS) method.

A quasi-periodic orbit (QPO) near a periodic orbit of period :math:`T_0` fills a 2-D torus.  Cut the torus with
the *stroboscopic map* :math:`\varphi_T` (the flow over a fixed time :math:`T`): the cut is an **invariant
circle** :math:`u(\theta)`, :math:`\theta\in[0, 2\pi)`, that the map sends onto itself with a rigid rotation
(Gomez & Mondelo 2001; Olikara & Scheeres 2012; Baresi, Olikara & Scheeres 2018),

.. math:: \varphi_T\bigl(u(\theta)\bigr) = u(\theta + \rho).

Rotation-number convention
--------------------------
``rho`` is in radians per stroboscopic period, reduced to :math:`[0, 2\pi)`.  The orientation of :math:`\theta`
is chosen at the seed so that, as the torus shrinks to the base orbit, ``rho`` tends to the argument
:math:`\alpha\in(0,\pi)` of the centre eigenvalue :math:`\lambda = e^{i\alpha}` of the monodromy matrix with positive
imaginary part.  The trajectory that starts at :math:`u(\theta_0)` at :math:`t = 0` is at time :math:`t` at the
torus angles :math:`(\theta_1, \theta_2) = (2\pi t/T,\ \theta_0 + \rho t / T)`: longitudinal frequency
:math:`\omega_1 = 2\pi/T`, latitudinal frequency :math:`\omega_2 = \rho/T` (rad/TU).  The stroboscopic time
:math:`T` is the base orbit's period unless the torus is solved with ``free_period=True``.

Discretisation
--------------
The circle is stored at :math:`N` (odd) equally spaced angles :math:`\theta_j = 2\pi j/N`, i.e. as a truncated
Fourier series with modes :math:`|k| \le (N-1)/2` (odd :math:`N` has no ambiguous Nyquist mode, so the rotation
operator is exact on the representation).  Trigonometric interpolation (the Dirichlet kernel)

.. math:: u(\theta) = \sum_l u_l\, w_l(\theta),\qquad
          w_l(\theta) = \frac1N\Bigl[1 + 2\sum_{k=1}^{(N-1)/2}\cos k(\theta-\theta_l)\Bigr]

evaluates the circle anywhere.  The invariance equations at the grid are

.. math:: G_j(U,\rho,T) = \sum_l w_l(\theta_j - \rho)\,\varphi_T(u_l) - u_j = 0,\qquad j = 0..N-1,

(:math:`6N` equations), with Jacobian blocks :math:`w_l(\theta_j-\rho)\,\Phi_T(u_l) - \delta_{jl}I` from the state
transition matrices of all :math:`N` points, propagated in one heyoka batch.  The circle family has three
continuous symmetries or parameters that the equations leave free: the latitudinal phase (:math:`\theta \to
\theta + \alpha`), the longitudinal phase (the circle flowed for a time :math:`s`) and the family parameter.  We add

* a **latitudinal phase constraint**: the first Fourier harmonic of one position component (``phase_component``,
  the one with the largest amplitude at the seed) is real, :math:`\sum_j u_{j,c}\sin\theta_j = 0`, so
  :math:`\theta = 0` is where that harmonic peaks;
* a **longitudinal phase constraint**: the circle's mean position lies in the plane through the base orbit's
  initial position :math:`r_0` normal to its velocity :math:`v_0`, :math:`\frac1N\sum_j (r_j - r_0)\cdot
  \hat v_0 = 0`.  For :func:`cislunar.cr3bp.orbits.nrho_9_2`, whose ``x0`` is the apolune x-z plane crossing, this puts
  the ring at apolune (:math:`\bar y = 0`);
* one **member-selecting constraint** (two with ``free_period``): ring size, Jacobi constant, rotation number or
  period.

The system has :math:`6N+3` equations in :math:`6N+1` unknowns (:math:`U, \rho`; plus :math:`T` if free).  The
:math:`6N` invariance equations alone have rank :math:`6N-2`: their Jacobian annihilates the two phase directions
:math:`(\partial u/\partial\theta, 0)` and :math:`(f(u), 0)` and the family tangent, and two rows are dependent
(the Jacobi constant is conserved by :math:`\varphi_T`; this is the deficiency that an unfolding parameter would
remove).  With the three constraints the Jacobian has full column rank (checked in the tests), and instead of
unfolding we take Gauss-Newton steps with the minimum-norm least-squares solution, which converges quadratically on
this consistent over-determined system.

Sizes
-----
``size`` is the RMS distance of the ring's positions from their centroid (by Parseval, the norm of the non-constant
Fourier modes of the position), LU; ``size_km`` in km; ``velocity_size_mps`` the same for velocities in m/s.

States are in LU and LU/TU in the barycentric rotating frame, times in TU, angles in rad (see
:mod:`cislunar.cr3bp.dynamics`).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field, replace

import numpy as np

from cislunar.cr3bp.dynamics import CR3BP
from cislunar.cr3bp.orbits import ConvergenceError, PeriodicOrbit
from cislunar.cr3bp.propagation import (
    DEFAULT_TOL,
    ImpactError,
    PropagationError,
    propagate,
    propagate_stm,
)
from cislunar.utils import validation
from cislunar.utils.progress import progress as _progress

__all__ = [
    "InvariantTorus",
    "TorusConvergenceError",
    "UnderResolvedWarning",
    "RangeStats",
    "centre_eigenpair",
    "torus_seed",
    "solve_torus",
    "torus_from_orbit",
    "continue_tori",
    "mean_range",
    "qpo_for_mean_range",
    "fourier_weights",
]

_FIX_KINDS = ("size_km", "size", "jacobi", "rho", "period")


class TorusConvergenceError(ConvergenceError):
    """The invariant-circle corrector did not converge.

    Attributes
    ----------
    message : str
        What went wrong (without the residual history).
    residuals : list of float
        Max-norm of the constraint vector at each Gauss-Newton iteration.
    last_guess : ndarray
        Unknown vector ``[U.ravel(), rho(, T)]`` at the last iteration.
    reason : str
        ``"max_iter"``, ``"diverged"``, ``"non_finite"``, ``"impact"`` (an iterate's trajectory reaches a
        primary), ``"propagation"`` (the integrator stopped) or ``"other"``.

    Notes
    -----
    Survives pickling (process pools): ``__reduce__`` rebuilds it from the raw message and the history.
    """

    def __init__(self, message: str, residuals=(), last_guess=(), reason: str = "other"):
        super().__init__(message, residuals, last_guess, reason)

    def __reduce__(self):
        return (type(self), (self.message, list(self.residuals), np.asarray(self.last_guess), self.reason))


class UnderResolvedWarning(UserWarning):
    """A torus solved on its grid is not invariant between grid points: too few circle points N."""


#: Smallest RMS ring size (LU, about 4 micrometres) of a circle that is a torus and not the base periodic orbit.
_MIN_SIZE_LU = 1e-11


# ----------------------------------------------------------------------------------------------------------
# argument checks (private helpers on top of cislunar.utils.validation)
# ----------------------------------------------------------------------------------------------------------
def _heyoka_tol(tol, name: str = "tol") -> float:
    """An integrator tolerance, checked under the caller's name (heyoka accepts [1e-16, 1e-3])."""
    return validation.in_range(tol, name, 1e-16, 1e-3)


def _orbit(orbit, name: str = "orbit") -> PeriodicOrbit:
    return validation.instance(orbit, name, PeriodicOrbit, "a cislunar.cr3bp.orbits.PeriodicOrbit (e.g. orbits.nrho_9_2)")


def _torus(torus, name: str = "torus") -> "InvariantTorus":
    return validation.instance(torus, name, InvariantTorus, "a cislunar.cr3bp.torus.InvariantTorus")


def _check_circle_outside_primaries(system: CR3BP, circle: np.ndarray, name: str = "circle") -> None:
    """A ring point on or inside the Earth or the Moon is not a torus of the CR3BP (ValueError naming ``name``)."""
    r1, r2 = system.distances(circle)
    for body, r, radius in (("Moon", r2, system.secondary_radius), ("Earth", r1, system.primary_radius)):
        inside = np.flatnonzero(r <= radius)
        if inside.size:
            k = int(inside[0])
            raise ValueError(f"{name} point {k} lies inside the {body} ({r[k] * system.length_unit_km:.6g} km from "
                             f"its centre, radius {radius * system.length_unit_km:.6g} km): not a torus of the "
                             "CR3BP")


# ----------------------------------------------------------------------------------------------------------
# Fourier interpolation on the circle
# ----------------------------------------------------------------------------------------------------------
#: Largest number of points on the invariant circle (the Newton systems are dense, 6N x 6N).
_MAX_N = 1001
#: Largest number of continuation steps or of grid samples a single call may request.
_MAX_STEPS = 1_000
_MAX_SAMPLES = 5e6


def _check_n(n, name: str = "N") -> int:
    if isinstance(n, (bool, np.bool_)) or not isinstance(n, (int, np.integer)):
        raise validation.ArgumentTypeError(f"{name} must be an odd integer >= 5; got {type(n).__name__} {n!r:.60}")
    n = int(n)
    if n < 5 or n % 2 == 0:
        raise ValueError(f"{name} must be an odd integer >= 5 (odd: no ambiguous Nyquist mode); got {n}")
    validation.work_size(n, name, _MAX_N, "points on the invariant circle (dense 6N x 6N Newton systems)")
    return n


def fourier_weights(theta, n: int, derivative: bool = False) -> np.ndarray:
    r"""Trigonometric-interpolation weights :math:`w_l(\theta)` (or :math:`w_l'(\theta)`) for an ``n``-point circle.

    Parameters
    ----------
    theta : array_like, shape (m,)
        Angles at which the circle is evaluated, rad.
    n : int
        Number of circle points (odd).
    derivative : bool
        Return :math:`dw_l/d\theta` instead.

    Returns
    -------
    ndarray, shape (m, n)
        ``W @ circle`` is the interpolated circle (or its :math:`\theta`-derivative) at ``theta``.
    """
    n = _check_n(n, "n")
    theta = validation.as_array(theta, "theta", ndim=(0, 1)).reshape(-1)
    derivative = validation.boolean(derivative, "derivative")
    grid = 2.0 * np.pi * np.arange(n) / n
    d = theta[:, None] - grid[None, :]
    k = np.arange(1, (n - 1) // 2 + 1)
    kd = k[None, None, :] * d[:, :, None]
    if derivative:
        return -2.0 * np.sum(k * np.sin(kd), axis=-1) / n
    return (1.0 + 2.0 * np.sum(np.cos(kd), axis=-1)) / n


# ----------------------------------------------------------------------------------------------------------
# The torus
# ----------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class InvariantTorus:
    r"""A 2-D invariant torus represented by its invariant circle at stroboscopic time 0.

    Attributes
    ----------
    orbit : PeriodicOrbit
        Base periodic orbit; its ``x0`` fixes the longitudinal phase (the ring is centred on the plane through
        ``x0``'s position normal to its velocity).
    circle : ndarray, shape (N, 6)
        :math:`u(\theta_j)`, :math:`\theta_j = 2\pi j/N`, LU and LU/TU, rotating frame.
    period : float
        Stroboscopic time :math:`T`, TU.
    rho : float
        Rotation number, rad per stroboscopic period, in :math:`[0, 2\pi)`:
        :math:`\varphi_T(u(\theta)) = u(\theta+\rho)`.
    residuals : tuple of float
        Gauss-Newton residual history (empty for an unsolved seed).
    phase_component : int
        Position component (0, 1, 2) whose first Fourier harmonic is real (latitudinal phase).
    label : str
        Free-form name.
    """

    orbit: PeriodicOrbit
    circle: np.ndarray = field(repr=False)
    period: float
    rho: float
    residuals: tuple = field(default=(), repr=False)
    phase_component: int = 0
    label: str = ""

    def __post_init__(self):
        _orbit(self.orbit, "orbit")
        circle = validation.as_array(self.circle, "circle", ndim=(2,), last=6)
        _check_n(circle.shape[0], "circle.shape[0] (N)")
        _check_circle_outside_primaries(self.orbit.system, circle, "circle")
        if _rms_about_mean(circle[:, :3]) < _MIN_SIZE_LU:
            raise ValueError(f"circle is degenerate: its {circle.shape[0]} points coincide (RMS ring size "
                             f"{_rms_about_mean(circle[:, :3]):.2e} LU); a zero-size torus is the base periodic orbit")
        object.__setattr__(self, "circle", circle)
        object.__setattr__(self, "period", validation.positive(self.period, "period"))
        rho = validation.as_array(self.rho, "rho", ndim=(0,))
        object.__setattr__(self, "rho", float(np.mod(rho, 2.0 * np.pi)))
        res = validation.as_array(self.residuals, "residuals", ndim=(1,), finite=False)
        if np.any(np.isnan(res)) or np.any(res < 0):
            raise ValueError("residuals must be a sequence of non-negative residual norms")
        object.__setattr__(self, "residuals", tuple(float(r) for r in res))
        object.__setattr__(self, "phase_component", validation.integer(self.phase_component, "phase_component",
                                                                    minimum=0, maximum=2))
        validation.instance(self.label, "label", str)

    # ---------------------------------------------------------------------------------------- basic numbers
    @property
    def system(self) -> CR3BP:
        """The dynamical system of the base orbit."""
        return self.orbit.system

    @property
    def N(self) -> int:  # noqa: N802 - the conventional name
        """Number of circle points."""
        return int(self.circle.shape[0])

    @property
    def thetas(self) -> np.ndarray:
        """Grid angles :math:`\\theta_j = 2\\pi j/N`, rad."""
        return 2.0 * np.pi * np.arange(self.N) / self.N

    @property
    def jacobi(self) -> float:
        """Mean Jacobi constant of the circle points (constant on an invariant torus)."""
        return float(np.mean(self.system.jacobi(self.circle)))

    @property
    def jacobi_spread(self) -> float:
        """Max minus min Jacobi constant over the circle points (zero up to the solve tolerance)."""
        c = self.system.jacobi(self.circle)
        return float(np.max(c) - np.min(c))

    @property
    def size(self) -> float:
        """RMS distance of the ring's positions from their centroid, LU."""
        return _rms_about_mean(self.circle[:, :3])

    @property
    def size_km(self) -> float:
        """:attr:`size` in km."""
        return self.size * self.system.length_unit_km

    @property
    def velocity_size_mps(self) -> float:
        """RMS distance of the ring's velocities from their mean, m/s."""
        return _rms_about_mean(self.circle[:, 3:]) * self.system.velocity_unit_km_s * 1e3

    @property
    def semi_axes_km(self) -> np.ndarray:
        """Semi-axes of the ring's position ellipse, km, largest first: :math:`\\sqrt{2\\lambda_i}` of the covariance
        of the ring positions over :math:`\\theta` (exact for a planar ellipse; the third is ~0 for a flat ring)."""
        r = self.circle[:, :3] - self.circle[:, :3].mean(axis=0)
        lam = np.linalg.eigvalsh(r.T @ r / self.N)[::-1]
        return np.sqrt(2.0 * np.clip(lam, 0.0, None)) * self.system.length_unit_km

    def _dense_circle(self, n: int = 1440) -> np.ndarray:
        return self.circle_at(2.0 * np.pi * np.arange(n) / n)

    @property
    def max_offset_km(self) -> float:
        """Largest distance of the ring (interpolated at 1440 angles) from the base orbit's initial position, km."""
        d = np.linalg.norm(self._dense_circle()[:, :3] - self.orbit.x0[:3], axis=1)
        return float(d.max() * self.system.length_unit_km)

    @property
    def max_velocity_offset_mps(self) -> float:
        """Largest velocity difference between the ring (1440 angles) and the base orbit's initial state, m/s."""
        d = np.linalg.norm(self._dense_circle()[:, 3:] - self.orbit.x0[3:], axis=1)
        return float(d.max() * self.system.velocity_unit_km_s * 1e3)

    @property
    def frequencies(self) -> tuple[float, float]:
        """``(omega_1, omega_2) = (2 pi / T, rho / T)``, longitudinal and latitudinal frequencies, rad/TU."""
        return 2.0 * np.pi / self.period, self.rho / self.period

    @property
    def fourier_amplitudes(self) -> np.ndarray:
        """Norm over the 6 components of each Fourier mode ``k = 0..(N-1)/2`` of the circle (decay check)."""
        c = np.fft.rfft(self.circle, axis=0) / self.N
        return np.linalg.norm(c, axis=1)[: (self.N - 1) // 2 + 1]

    # ---------------------------------------------------------------------------------------- evaluation
    def circle_at(self, theta) -> np.ndarray:
        """States on the invariant circle at angles ``theta`` (rad) by Fourier interpolation, shape ``(m, 6)``."""
        return fourier_weights(theta, self.N) @ self.circle

    def states(self, theta0, t, *, tol: float = DEFAULT_TOL) -> np.ndarray:
        """States on the torus: the trajectory starting at :math:`u(\\theta_0)` at time 0, evaluated at times ``t``.

        For :math:`t = kT + s` with :math:`0 \\le s < T` the state is :math:`\\varphi_s(u(\\theta_0 + k\\rho))`:
        only one stroboscopic period is ever propagated, so the result stays on the torus for any ``t`` (the base
        orbit is unstable, and direct long propagation would drift off it).

        Parameters
        ----------
        theta0 : float or array_like, shape (n,)
            Initial ring angles, rad.
        t : float or array_like, shape (m,)
            Times from the ring (any sign, any order), TU.
        tol : float
            heyoka tolerance.

        Returns
        -------
        ndarray, shape (n, m, 6)
            LU and LU/TU, rotating frame.

        Raises
        ------
        cislunar.cr3bp.propagation.ImpactError
            A torus trajectory reaches the Earth or the Moon (impact detection is on for every propagation here).
        """
        theta0 = validation.as_array(theta0, "theta0", ndim=(0, 1)).reshape(-1)
        t = validation.as_array(t, "t", ndim=(0, 1)).reshape(-1)
        tol = _heyoka_tol(tol)
        if theta0.size == 0 or t.size == 0:
            raise ValueError("theta0 and t must hold at least one value each")
        T = self.period
        k = np.floor(t / T)
        s = t - k * T
        k = np.where(s >= T, k + 1, k)  # rounding
        s = np.clip(np.where(s >= T, 0.0, s), 0.0, None)
        out = np.empty((theta0.size, t.size, 6))
        for kk in np.unique(k):
            idx = np.nonzero(k == kk)[0]
            x0 = self.circle_at(theta0 + kk * self.rho)
            grid = np.unique(np.concatenate([[0.0], s[idx]]))
            if grid.size == 1:
                x = x0[:, None, :]
            else:
                x = propagate(self.system, x0, grid, tol=tol).x
                x = x.reshape(theta0.size, grid.size, 6)
            out[:, idx] = x[:, np.searchsorted(grid, s[idx])]
        return out

    def ring(self, t: float = 0.0, n_theta: int | None = None) -> np.ndarray:
        """The invariant ring at time ``t`` (TU) at ``n_theta`` equally spaced initial angles, ``(n_theta, 6)``."""
        n_theta = self.N if n_theta is None else validation.integer(n_theta, "n_theta", minimum=1)
        t = validation.real(t, "t")
        th = 2.0 * np.pi * np.arange(n_theta) / n_theta
        return self.states(th, [t])[:, 0]

    def invariance_error(self, theta=None, *, tol: float = DEFAULT_TOL) -> float:
        """Max-norm (over angles) of :math:`\\|\\varphi_T(u(\\theta)) - u(\\theta+\\rho)\\|_2` (6-D, non-dimensional).

        ``theta`` defaults to the midpoints :math:`\\theta_j + \\pi/N` between grid points, where interpolation
        error is largest.
        """
        theta = (self.thetas + np.pi / self.N) if theta is None else validation.as_array(theta, "theta", ndim=(0, 1))
        theta = np.atleast_1d(theta)
        if theta.size == 0:
            raise ValueError("theta must hold at least one angle")
        tol = _heyoka_tol(tol)
        x = propagate(self.system, self.circle_at(theta), self.period, tol=tol).x
        x = x.reshape(theta.size, 2, 6)[:, -1]
        return float(np.max(np.linalg.norm(x - self.circle_at(theta + self.rho), axis=1)))

    def distance_to_ring(self, x, t: float = 0.0, *, n_search: int = 720) -> np.ndarray:
        """Distance (6-D, non-dimensional) of states ``x`` from the invariant ring at time ``t``.

        The ring at time ``t`` is the circle's :math:`N` points flowed for ``t`` and Fourier-interpolated; the
        distance is minimised over :math:`\\theta` by a dense search refined with Brent's method.

        Parameters
        ----------
        x : array_like, shape (6,) or (m, 6)
            States, LU and LU/TU.
        t : float
            Time of the ring, TU.
        n_search : int
            Angles of the initial dense search.

        Returns
        -------
        ndarray, shape (m,)
        """
        from scipy.optimize import minimize_scalar

        x = np.atleast_2d(validation.as_state(x, "x"))
        if x.shape[0] == 0:
            raise ValueError("x must hold at least one state")
        t = validation.real(t, "t")
        n_search = validation.integer(n_search, "n_search", minimum=8)
        ring = self.ring(t) if t != 0.0 else self.circle
        th = 2.0 * np.pi * np.arange(n_search) / n_search
        dense = fourier_weights(th, self.N) @ ring
        out = np.empty(x.shape[0])
        for i, xi in enumerate(x):
            j = int(np.argmin(np.linalg.norm(dense - xi, axis=1)))

            def f(a, xi=xi):
                return float(np.linalg.norm(fourier_weights([a], self.N) @ ring - xi))

            h = 2.0 * np.pi / n_search
            try:
                res = minimize_scalar(f, bracket=(th[j] - h, th[j], th[j] + h), tol=1e-12)
            except ValueError:  # flat neighbourhood (equal distances): the grid point is the answer
                out[i] = f(th[j])
                continue
            out[i] = min(res.fun, f(th[j]))
        return out


    def stability_multipliers(self, *, tol: float = DEFAULT_TOL) -> np.ndarray:
        """Eigenvalues of the linearised invariant-circle map, sorted by decreasing modulus.

        A perturbation :math:`\\delta u(\\theta)` of the circle maps to :math:`\\Phi_T(u(\\theta))\\,\\delta
        u(\\theta)`, which belongs to the angle :math:`\\theta+\\rho`; rotating it back gives the :math:`6N\\times6N`
        operator :math:`(W(\\theta_j-\\rho)\\otimes I)\\,\\mathrm{diag}(\\Phi_T(u_l))` (Olikara & Scheeres 2012),
        whose eigenvalues come in sets :math:`\\lambda_i e^{ik\\rho}` of equal modulus.  Their largest modulus is the
        per-period growth factor of deviations from the torus (the 9:2 NRHO's hyperbolic pair gives about 2.19).

        Returns
        -------
        ndarray, shape (6N,), complex
        """
        n = self.N
        tol = _heyoka_tol(tol)
        stm = propagate_stm(self.system, self.circle, self.period, tol=tol).stm.reshape(n, 2, 6, 6)[:, -1]
        W = fourier_weights(self.thetas - self.rho, n)
        A = np.einsum("jl,lab->jalb", W, stm).reshape(6 * n, 6 * n)
        lam = np.linalg.eigvals(A)
        return lam[np.argsort(-np.abs(lam))]

    def closest_approach(self, body: str = "Moon", *, n_theta: int = 32, n_t: int = 1601,
                         tol: float = DEFAULT_TOL) -> tuple[float, tuple[float, float]]:
        """Smallest distance of the torus from a primary's centre, km, and where it occurs.

        A grid over initial ring angles and one stroboscopic period, refined by Nelder-Mead.

        Parameters
        ----------
        body : {"Moon", "Earth"}
        n_theta, n_t : int
            Grid sizes (angles, times per period).
        tol : float
            heyoka tolerance.

        Returns
        -------
        distance_km : float
        (theta0, t) : tuple of float
            Initial ring angle (rad) and time (TU) of the closest approach.
        """
        validation.choice(body, "body", ("Moon", "Earth"))
        n_theta = validation.integer(n_theta, "n_theta", minimum=4)
        n_t = validation.integer(n_t, "n_t", minimum=11)
        tol = _heyoka_tol(tol)
        centre = self.system.secondary_position if body == "Moon" else self.system.primary_position
        km = self.system.length_unit_km
        th = 2.0 * np.pi * np.arange(n_theta) / n_theta
        t = np.linspace(0.0, self.period, n_t)
        d = np.linalg.norm(self.states(th, t, tol=tol)[..., :3] - centre, axis=-1) * km

        def point(a, b):
            return float(np.linalg.norm(self.states([a], [b], tol=tol)[0, 0, :3] - centre) * km)

        return _refine_extremum(self, th, t, d, +1.0, tol, point)


def _rms_about_mean(a: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.sum((a - a.mean(axis=0)) ** 2, axis=1))))


# ----------------------------------------------------------------------------------------------------------
# Seed from the centre eigenvector
# ----------------------------------------------------------------------------------------------------------
def centre_eigenpair(orbit: PeriodicOrbit, *, unit_tol: float = 1e-6, trivial_tol: float = 1e-3):
    """The centre eigenvalue :math:`e^{i\\alpha}`, :math:`0<\\alpha<\\pi`, of the monodromy matrix and its eigenvector.

    Parameters
    ----------
    orbit : PeriodicOrbit
    unit_tol : float
        Eigenvalues with :math:`||\\lambda| - 1|` below this are on the unit circle.
    trivial_tol : float
        Eigenvalues within this of 1 are the trivial pair and skipped.

    Returns
    -------
    lam : complex
        The centre eigenvalue with positive imaginary part (the one farthest from 1 if there are two).
    v : ndarray, shape (6,), complex
        Its eigenvector.

    Raises
    ------
    ValueError
        If the orbit has no centre eigenvalue pair (no family of tori about it).
    """
    _orbit(orbit)
    unit_tol = validation.positive(unit_tol, "unit_tol")
    trivial_tol = validation.positive(trivial_tol, "trivial_tol")
    if unit_tol >= 1.0:
        raise ValueError(f"unit_tol must be below 1 (a distance from the unit circle); got {unit_tol!r}")
    if trivial_tol >= 2.0:
        raise ValueError(f"trivial_tol must be below 2 (every unit-circle eigenvalue is within 2 of 1); got "
                         f"{trivial_tol!r}")
    lam, vec = np.linalg.eig(orbit.monodromy)
    ok = (np.abs(np.abs(lam) - 1.0) < unit_tol) & (np.abs(lam - 1.0) > trivial_tol) & (lam.imag > 0)
    if not np.any(ok):
        raise ValueError(f"orbit has no centre eigenvalue pair (eigenvalues {np.round(lam, 6)}); no tori about it")
    cand = np.nonzero(ok)[0]
    i = cand[np.argmax(np.abs(lam[cand] - 1.0))]
    return complex(lam[i]), vec[:, i]


def torus_seed(orbit: PeriodicOrbit, N: int = 25, size_km: float = 1.0) -> InvariantTorus:  # noqa: N803
    r"""Linear torus: :math:`u(\theta) = x_0 + \varepsilon\,\mathrm{Re}(v e^{i\theta})`, :math:`\rho = \arg\lambda`.

    ``v`` is the centre eigenvector of the monodromy, scaled so the ring's RMS position radius is ``size_km`` and
    rotated so its largest position component is real (the latitudinal phase convention).  Not solved.

    Parameters
    ----------
    orbit : PeriodicOrbit
        Base orbit (its ``x0`` is where the ring sits).
    N : int
        Number of circle points, odd, >= 5.
    size_km : float
        RMS position radius of the ring, km, > 0.
    """
    _orbit(orbit)
    N = _check_n(N)
    size_km = validation.positive(size_km, "size_km")
    lam, v = centre_eigenpair(orbit)
    v = v / np.sqrt(np.sum(np.abs(v[:3]) ** 2) / 2.0)
    c = int(np.argmax(np.abs(v[:3])))
    v = v * np.conj(v[c]) / np.abs(v[c])
    eps = size_km / orbit.system.length_unit_km
    if eps < 100 * _MIN_SIZE_LU:
        raise ValueError(f"size_km must be at least {100 * _MIN_SIZE_LU * orbit.system.length_unit_km:.1e} km (a "
                         f"smaller ring is numerically the base periodic orbit); got {size_km!r}")
    th = 2.0 * np.pi * np.arange(N) / N
    circle = orbit.x0[None, :] + eps * np.real(v[None, :] * np.exp(1j * th)[:, None])
    return InvariantTorus(orbit=orbit, circle=circle, period=orbit.period, rho=float(np.angle(lam)),
                          phase_component=c, label=f"seed {size_km:g} km")


# ----------------------------------------------------------------------------------------------------------
# Gauss-Newton corrector
# ----------------------------------------------------------------------------------------------------------
def _grad_jacobi(system: CR3BP, u: np.ndarray) -> np.ndarray:
    """Gradient of the Jacobi constant, shape (n, 6)."""
    mu = system.mu
    r = u[:, :3]
    d1 = r - system.primary_position
    d2 = r - system.secondary_position
    r1 = np.linalg.norm(d1, axis=1)[:, None]
    r2 = np.linalg.norm(d2, axis=1)[:, None]
    grad_u = r * np.array([1.0, 1.0, 0.0]) - (1.0 - mu) * d1 / r1**3 - mu * d2 / r2**3
    return np.hstack([2.0 * grad_u, -2.0 * u[:, 3:]])


def _parse_fix(fix, free_period: bool, system: CR3BP) -> list[tuple[str, float]]:
    if not isinstance(fix, dict) or not fix:
        raise TypeError(f"fix must be a non-empty dict such as {{'size_km': 50.0}}; got {fix!r}")
    want = 2 if free_period else 1
    if len(fix) != want:
        raise ValueError(f"fix must hold {want} constraint(s) {'(free_period=True)' if free_period else ''}; "
                         f"got {sorted(fix)}")
    out = []
    for kind, value in fix.items():
        if kind not in _FIX_KINDS:
            raise ValueError(f"fix keys must be among {_FIX_KINDS}; got {kind!r}")
        if kind == "period" and not free_period:
            raise ValueError("fix['period'] requires free_period=True")
        if kind in ("size_km", "size", "period"):
            v = validation.positive(value, f"fix[{kind!r}]")
        else:
            v = float(validation.as_array(value, f"fix[{kind!r}]", ndim=(0,)))
        key = kind
        if kind == "size_km":
            kind, v = "size", v / system.length_unit_km
        if kind == "size" and v < 100 * _MIN_SIZE_LU:
            raise ValueError(f"fix[{key!r}] asks for a ring of {v:.2e} LU: below {100 * _MIN_SIZE_LU:.0e} LU a ring is "
                             "numerically the base periodic orbit, not a torus")
        out.append((kind, v))
    return out


class _Problem:
    """Residual and Jacobian of the invariant-circle equations for one torus set-up."""

    def __init__(self, orbit, n, fix, free_period, phase_component, int_tol, period):
        self.orbit = orbit
        self.period = period
        self.system = orbit.system
        self.n = n
        self.fix = fix
        self.free = free_period
        self.c = phase_component
        self.int_tol = int_tol
        self.th = 2.0 * np.pi * np.arange(n) / n
        v0 = orbit.x0[3:]
        self.r0 = orbit.x0[:3]
        self.v0hat = v0 / np.linalg.norm(v0)

    def pack(self, U, rho, T):
        x = [U.ravel(), [rho]]
        if self.free:
            x.append([T])
        return np.concatenate(x)

    def unpack(self, X):
        n = self.n
        U = X[: 6 * n].reshape(n, 6)
        rho = X[6 * n]
        T = X[6 * n + 1] if self.free else self.period
        return U, rho, T

    def evaluate(self, X, jac: bool = True):
        n = self.n
        U, rho, T = self.unpack(X)
        traj = (propagate_stm if jac else propagate)(self.system, U, T, tol=self.int_tol)
        phi = traj.x.reshape(n, 2, 6)[:, -1]
        W = fourier_weights(self.th - rho, n)
        G = W @ phi - U
        rows = [G.ravel()]
        # latitudinal phase: first harmonic of component c is real
        rows.append([np.sum(U[:, self.c] * np.sin(self.th)) / n])
        # longitudinal phase: mean position on the plane through r0 normal to v0
        rows.append([np.mean((U[:, :3] - self.r0) @ self.v0hat)])
        for kind, value in self.fix:
            if kind == "size":
                rows.append([_rms_about_mean(U[:, :3]) - value])
            elif kind == "jacobi":
                rows.append([np.mean(self.system.jacobi(U)) - value])
            elif kind == "rho":
                rows.append([rho - value])
            else:  # period
                rows.append([T - value])
        F = np.concatenate([np.asarray(r, dtype=float) for r in rows])
        if not jac:
            return F, None
        m = 6 * n + 1 + int(self.free)
        J = np.zeros((F.size, m))
        stm = traj.stm.reshape(n, 2, 6, 6)[:, -1]
        J[: 6 * n, : 6 * n] = np.einsum("jl,lab->jalb", W, stm).reshape(6 * n, 6 * n) - np.eye(6 * n)
        Wd = fourier_weights(self.th - rho, n, derivative=True)
        J[: 6 * n, 6 * n] = -(Wd @ phi).ravel()
        if self.free:
            J[: 6 * n, 6 * n + 1] = (W @ self.system.eom(phi)).ravel()
        r = 6 * n
        J[r, np.arange(n) * 6 + self.c] = np.sin(self.th) / n
        for a in range(3):
            J[r + 1, np.arange(n) * 6 + a] = self.v0hat[a] / n
        for i, (kind, _) in enumerate(self.fix):
            row = r + 2 + i
            if kind == "size":
                dev = U[:, :3] - U[:, :3].mean(axis=0)
                s = _rms_about_mean(U[:, :3])
                for a in range(3):
                    J[row, np.arange(n) * 6 + a] = dev[:, a] / (n * max(s, 1e-300))
            elif kind == "jacobi":
                J[row, : 6 * n] = (_grad_jacobi(self.system, U) / n).ravel()
            elif kind == "rho":
                J[row, 6 * n] = 1.0
            else:
                J[row, 6 * n + 1] = 1.0
        return F, J


def solve_torus(guess: InvariantTorus, *, fix: dict, free_period: bool = False, tol: float = 1e-11,
                max_iter: int = 15, int_tol: float = DEFAULT_TOL, label: str = "",
                check_midpoints: bool = True) -> InvariantTorus:
    r"""Correct an approximate invariant circle to an invariant torus by Gauss-Newton (minimum-norm steps).

    Parameters
    ----------
    guess : InvariantTorus
        Initial circle, rotation number and stroboscopic time (e.g. :func:`torus_seed` or a continuation
        predictor).  Its ``phase_component`` fixes the latitudinal phase convention.
    fix : dict
        Member-selecting constraint(s): one of ``{"size_km": km}``, ``{"size": LU}``, ``{"jacobi": C}``,
        ``{"rho": rad}``; with ``free_period=True`` two of them (``"period"`` in TU also allowed).
    free_period : bool
        Solve for the stroboscopic time too (default: held at ``guess.period``).
    tol : float
        Convergence threshold on the max-norm of all constraints (non-dimensional).
    max_iter : int
        Maximum Gauss-Newton iterations.
    int_tol : float
        heyoka tolerance.
    label : str
        Name of the result.
    check_midpoints : bool
        After convergence, evaluate the invariance error between grid points (one more propagation of N states)
        and warn with :class:`UnderResolvedWarning` if it exceeds ``1e3 * tol``.

    Returns
    -------
    InvariantTorus
        With ``residuals`` the max-norm history.

    Raises
    ------
    TorusConvergenceError
        No convergence within ``max_iter`` iterations, divergence, or an iterate that hits a primary; carries the
        residual history and survives pickling.
    ValueError, TypeError
        Bad arguments (named).
    """
    _torus(guess, "guess")
    free_period = validation.boolean(free_period, "free_period")
    fixes = _parse_fix(fix, free_period, guess.system)
    tol = validation.in_range(tol, "tol", 1e-15, 1e-3)
    max_iter = validation.integer(max_iter, "max_iter", minimum=1)
    int_tol = _heyoka_tol(int_tol, "int_tol")
    validation.instance(label, "label", str)
    check_midpoints = validation.boolean(check_midpoints, "check_midpoints")
    prob = _Problem(guess.orbit, guess.N, fixes, bool(free_period), guess.phase_component, int_tol, guess.period)
    X = prob.pack(guess.circle, guess.rho, guess.period)
    history: list[float] = []
    try:
        F, J = prob.evaluate(X)
        for _ in range(max_iter + 1):
            err = float(np.max(np.abs(F)))
            history.append(err)
            if not np.isfinite(err):
                break
            if err < tol:
                U, rho, T = prob.unpack(X)
                size = _rms_about_mean(U[:, :3])
                if size < _MIN_SIZE_LU:
                    raise TorusConvergenceError(
                        f"torus solve converged to a degenerate circle (RMS ring size {size:.2e} LU): the base "
                        f"periodic orbit, not a torus (fix={dict(fix)}, N={guess.N})", history, X, "degenerate")
                torus = InvariantTorus(orbit=guess.orbit, circle=U.copy(), period=float(T), rho=float(rho),
                                       residuals=tuple(history), phase_component=guess.phase_component,
                                       label=label or guess.label)
                if check_midpoints:
                    mid = torus.invariance_error(tol=int_tol)
                    if mid > 1e3 * tol:
                        warnings.warn(UnderResolvedWarning(
                            f"torus solved on its {torus.N}-point grid but its invariance error between grid points "
                            f"is {mid:.2e}: the circle is under-resolved, increase N"), stacklevel=2)
                return torus
            if len(history) > max_iter:
                break
            if len(history) >= 3 and err > 1e3 * min(history):
                break
            dX = np.linalg.lstsq(J, -F, rcond=None)[0]
            # backtracking: accept the full step unless the residual grows
            step = 1.0
            for _ in range(6):
                Xn = X + step * dX
                Fn, Jn = prob.evaluate(Xn)
                if np.max(np.abs(Fn)) < err or step < 0.05:
                    break
                step *= 0.5
            X, F, J = Xn, Fn, Jn
    except (ImpactError, PropagationError) as exc:  # an iterate reached a primary or the integrator stopped
        reason = "impact" if isinstance(exc, ImpactError) else "propagation"
        raise TorusConvergenceError(f"torus solve failed (fix={dict(fix)}, N={guess.N}): {exc}", history, X,
                                    reason) from None
    if history and not np.isfinite(history[-1]):
        reason, what = "non_finite", "produced a non-finite residual"
    elif len(history) <= max_iter:
        reason, what = "diverged", "diverged"
    else:
        reason, what = "max_iter", f"did not converge to tol={tol:g} in {max_iter} iterations"
    raise TorusConvergenceError(f"torus solve {what} (fix={dict(fix)}, N={guess.N})", history, X, reason)


def torus_from_orbit(orbit: PeriodicOrbit, N: int = 25, size_km: float = 10.0, *,  # noqa: N803
                     start_km: float = 2.0, step_km: float = 25.0, progress: bool = False,
                     **solve_kw) -> InvariantTorus:
    """Solve the torus of ring size ``size_km`` about ``orbit``: seed at ``start_km``, then continue in size.

    Parameters
    ----------
    orbit : PeriodicOrbit
    N : int
        Circle points (odd, >= 5).
    size_km : float
        Target RMS ring radius, km.
    start_km : float
        Size of the first (seeded) solve, km; the linear seed is accurate to second order in the size.
    step_km : float
        Largest continuation step, km.
    progress : bool
        Show a progress bar.
    **solve_kw
        Passed to :func:`solve_torus` (``tol``, ``max_iter``, ``int_tol``).
    """
    _orbit(orbit)
    N = _check_n(N)
    size_km = validation.positive(size_km, "size_km")
    start_km = min(validation.positive(start_km, "start_km"), size_km)
    step_km = validation.positive(step_km, "step_km")
    progress = validation.boolean(progress, "progress")
    torus = solve_torus(torus_seed(orbit, N, start_km), fix={"size_km": start_km}, label=f"torus size_km={start_km:g}",
                        **solve_kw)
    if size_km == start_km:
        return torus
    n_steps = validation.work_size(np.ceil((size_km - start_km) / step_km), "step_km", _MAX_STEPS,
                                   "continuation steps")
    values = np.linspace(start_km, size_km, n_steps + 1)[1:]
    return continue_tori(torus, values, parameter="size_km", progress=progress, **solve_kw)[-1]


def _predict(prev: InvariantTorus | None, cur: InvariantTorus, p_prev, p_cur, p_new) -> InvariantTorus:
    """Secant predictor in the unknowns (circle, rho, period) along the family parameter."""
    if prev is None or p_cur == p_prev:
        return cur
    a = (p_new - p_cur) / (p_cur - p_prev)
    return replace(cur, circle=cur.circle + a * (cur.circle - prev.circle), rho=cur.rho + a * _wrap(cur.rho - prev.rho),
                   period=cur.period + a * (cur.period - prev.period), residuals=())


def _wrap(a):
    return (a + np.pi) % (2.0 * np.pi) - np.pi


def _parameter_value(torus: InvariantTorus, parameter: str) -> float:
    return {"size_km": torus.size_km, "size": torus.size, "jacobi": torus.jacobi, "rho": torus.rho}[parameter]


def continue_tori(torus: InvariantTorus, values, *, parameter: str = "size_km", progress: bool = True,
                  max_halvings: int = 4, free_period: bool = False, hold: dict | None = None,
                  **solve_kw) -> list:
    """Natural-parameter continuation of a torus family with a secant predictor and step halving.

    Parameters
    ----------
    torus : InvariantTorus
        A solved member (the starting point, not repeated in the output).
    values : array_like, shape (m,)
        Successive values of the continuation parameter.
    parameter : {"size_km", "size", "jacobi", "rho"}
        Which member-selecting constraint is continued.
    progress : bool
        Progress bar (:func:`cislunar.utils.progress.progress`).
    max_halvings : int
        A failed step is retried with intermediate values up to this many halvings.
    free_period : bool
        Let the stroboscopic time vary; then ``hold`` must fix one more quantity.
    hold : dict, optional
        Constraints held fixed along the branch (e.g. ``{"jacobi": C}`` or ``{"period": T}`` with
        ``free_period=True``), in the form of :func:`solve_torus`'s ``fix``.
    **solve_kw
        Passed to :func:`solve_torus`.

    Returns
    -------
    list of InvariantTorus
        One member per entry of ``values``.

    Raises
    ------
    TorusConvergenceError
        A step fails even after ``max_halvings`` halvings.
    """
    _torus(torus)
    validation.choice(parameter, "parameter", ("size_km", "size", "jacobi", "rho"))
    progress = validation.boolean(progress, "progress")
    max_halvings = validation.integer(max_halvings, "max_halvings", minimum=0)
    free_period = validation.boolean(free_period, "free_period")
    hold = {} if hold is None else hold
    if not isinstance(hold, dict):
        raise validation.ArgumentTypeError(f"hold must be a dict of constraints (or None); got {type(hold).__name__}")
    if parameter in hold:
        raise ValueError(f"hold must be a dict of constraints other than {parameter!r}; got {hold!r}")
    if len(hold) != int(free_period):
        raise ValueError(f"hold must fix {int(free_period)} constraint(s) with free_period={free_period}; got "
                         f"{sorted(hold)}")
    values = validation.as_array(values, "values", ndim=(0, 1), min_size=1).reshape(-1)
    if parameter in ("size_km", "size") and np.any(values <= 0):
        raise ValueError("values must be positive sizes")
    out = []
    prev, cur = None, torus
    p_prev, p_cur = None, _parameter_value(torus, parameter)
    for target in _progress(values, desc=f"torus continuation ({parameter})", enabled=progress):
        p_new = float(target)
        halvings = 0
        while True:
            try:
                guess = _predict(prev, cur, p_prev, p_cur, p_new)
                nxt = solve_torus(guess, fix={parameter: p_new, **hold}, free_period=free_period,
                                  label=f"torus {parameter}={p_new:g}", **solve_kw)
            except TorusConvergenceError as exc:
                if halvings >= max_halvings:
                    raise TorusConvergenceError(
                        f"continuation in {parameter} failed from {p_cur:.10g} towards {float(target):.10g} after "
                        f"{max_halvings} step halvings (last try {p_new:.10g}): {exc.message}",
                        exc.residuals, exc.last_guess, exc.reason) from None
                halvings += 1
                p_new = 0.5 * (p_cur + p_new)
                continue
            prev, cur, p_prev, p_cur = cur, nxt, p_cur, p_new
            if p_new == float(target):
                break
            p_new = float(target)
        out.append(cur)
    return out


# ----------------------------------------------------------------------------------------------------------
# Agent-target range for the paper's QPO
# ----------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class RangeStats:
    """Range between an agent on the torus and a target on the base orbit.

    Attributes
    ----------
    mean_km, rms_km : float
        Mean and RMS range (quadrature over the grid), km.
    min_km, max_km : float
        Smallest and largest range, km: grid extremes refined by a Nelder-Mead search over
        :math:`(\theta_0, t)`.
    ring_mean_km : float
        Mean range over the ring at t = 0 (agent on the initial ring, target at the base orbit's ``x0``), km.
    theta0 : ndarray, shape (n_theta,)
        Initial ring angles, rad.
    t : ndarray, shape (n_t,)
        Times from the ring (apolune), TU.
    range_km : ndarray, shape (n_theta, n_t)
        Range for each initial angle and time, km.
    min_at, max_at : tuple of float
        ``(theta0, t)`` (rad, TU) of the refined minimum and maximum.
    """

    mean_km: float
    min_km: float
    max_km: float
    rms_km: float
    ring_mean_km: float
    theta0: np.ndarray = field(repr=False)
    t: np.ndarray = field(repr=False)
    range_km: np.ndarray = field(repr=False)
    min_at: tuple = (np.nan, np.nan)
    max_at: tuple = (np.nan, np.nan)

    @property
    def per_theta_mean_km(self) -> np.ndarray:
        """Mean range over the time window for each initial ring angle (one agent trajectory each), km.

        Their spread shows how much a finite-window average of a single trajectory can differ from the torus
        average :attr:`mean_km` (which is their mean).
        """
        w = np.full(self.t.size, 1.0)
        w[0] = w[-1] = 0.5
        return self.range_km @ (w / w.sum())


def mean_range(torus: InvariantTorus, *, n_theta: int = 48, n_t: int = 1201, periods: int = 1,
               tol: float = DEFAULT_TOL) -> RangeStats:
    r"""Mean agent-target range of natural motion: agent on the torus, target on the base orbit.

    Definition
    ----------
    The target is on the base orbit, :math:`x_p(t) = \varphi_t(x_0)` (for the 9:2 NRHO, :math:`x_0` is apolune),
    the agent on the trajectory from the ring point :math:`u(\theta_0)`, :math:`x_a(t) = \varphi_t(u(\theta_0))`;
    both start at the ring/apolune epoch, so they share the base frequency.  The mean range is

    .. math:: \bar\rho = \frac{1}{2\pi\,kT}\int_0^{2\pi}\!\!\int_0^{kT} \|r_a(t;\theta_0) - r_p(t)\|\,dt\,d\theta_0,

    uniform over all initial ring angles and over time.  It does not depend on the whole number of periods
    :math:`k` (the stroboscopic map only rotates the ring), and for an irrational :math:`\rho/2\pi` it equals the
    long-time average along any single agent trajectory: the "average range between the natural trajectories".
    The :math:`\theta_0` integral uses the rectangle rule (spectrally accurate for periodic integrands), the time
    integral the trapezoidal rule on ``n_t`` points per period.

    Parameters
    ----------
    torus : InvariantTorus
    n_theta : int
        Initial ring angles (>= 4).
    n_t : int
        Time samples per stroboscopic period (>= 11).
    periods : int
        Whole number of periods :math:`k` (>= 1).
    tol : float
        heyoka tolerance.

    Returns
    -------
    RangeStats
    """
    _torus(torus)
    n_theta = validation.integer(n_theta, "n_theta", minimum=4)
    n_t = validation.integer(n_t, "n_t", minimum=11)
    periods = validation.integer(periods, "periods", minimum=1)
    validation.work_size(float(n_theta) * periods * n_t, "n_theta * n_t * periods", _MAX_SAMPLES, "torus samples")
    tol = _heyoka_tol(tol)
    return _range_stats(torus, n_theta, n_t, periods, tol).finish()


@dataclass(frozen=True)
class _RangeSamples:
    """The sampled ranges of :func:`mean_range` before the (costly) refinement of their extrema."""

    torus: InvariantTorus
    th: np.ndarray
    t: np.ndarray
    rng: np.ndarray
    tol: float
    mean_km: float
    rms_km: float
    ring_mean_km: float

    def finish(self) -> RangeStats:
        """Refine the minimum and maximum range (Nelder-Mead from the grid extrema) and return the statistics."""
        lo = _refine_extremum(self.torus, self.th, self.t, self.rng, +1.0, self.tol)
        hi = _refine_extremum(self.torus, self.th, self.t, self.rng, -1.0, self.tol)
        return RangeStats(mean_km=self.mean_km, min_km=lo[0], max_km=hi[0], rms_km=self.rms_km,
                          ring_mean_km=self.ring_mean_km, theta0=self.th, t=self.t, range_km=self.rng,
                          min_at=lo[1], max_at=hi[1])


def _range_stats(torus, n_theta, n_t, periods, tol) -> _RangeSamples:
    """Sampled ranges and their averages (the kernel of :func:`mean_range`; arguments already checked)."""
    T = torus.period
    th = 2.0 * np.pi * np.arange(n_theta) / n_theta
    t = np.linspace(0.0, periods * T, periods * (n_t - 1) + 1)
    agent = torus.states(th, t, tol=tol)
    target = propagate(torus.system, torus.orbit.x0, t, tol=tol).x
    rng = np.linalg.norm(agent[..., :3] - target[None, :, :3], axis=-1) * torus.system.length_unit_km
    w = np.full(t.size, 1.0)
    w[0] = w[-1] = 0.5
    w /= w.sum()
    per_theta = rng @ w
    return _RangeSamples(torus=torus, th=th, t=t, rng=rng, tol=tol, mean_km=float(per_theta.mean()),
                         rms_km=float(np.sqrt(np.mean((rng**2) @ w))), ring_mean_km=float(rng[:, 0].mean()))


def _range_at(torus: InvariantTorus, theta0: float, t: float, tol: float) -> float:
    """Agent-target range at one (theta0, t), km."""
    agent = torus.states([theta0], [t], tol=tol)[0, 0]
    target = torus.orbit.x0 if t == 0.0 else propagate(torus.system, torus.orbit.x0, t, tol=tol).x[-1]
    return float(np.linalg.norm(agent[:3] - target[:3]) * torus.system.length_unit_km)


def _refine_extremum(torus, th, t, values, sign, tol, point=None):
    """Refine the grid minimum (sign=+1) or maximum (sign=-1) of ``values`` over (theta0, t) by Nelder-Mead.

    ``point(theta0, t)`` evaluates the quantity at one point (default: the agent-target range, km).
    """
    from scipy.optimize import minimize

    point = (lambda a, b: _range_at(torus, a, b, tol)) if point is None else point
    i, j = np.unravel_index(np.argmin(sign * values), values.shape)
    t_lo, t_hi = t[0], t[-1]

    def f(p):
        return sign * point(float(p[0]), float(np.clip(p[1], t_lo, t_hi)))

    dth, dt = th[1] - th[0], t[1] - t[0]
    simplex = np.array([[th[i], t[j]], [th[i] + dth, t[j]], [th[i], t[j] + dt]])
    res = minimize(f, simplex[0], method="Nelder-Mead",
                   options={"initial_simplex": simplex, "xatol": 1e-9, "fatol": 1e-9, "maxiter": 400})
    if res.fun <= sign * values[i, j]:
        return float(sign * res.fun), (float(np.mod(res.x[0], 2 * np.pi)), float(np.clip(res.x[1], t_lo, t_hi)))
    return float(values[i, j]), (float(th[i]), float(t[j]))


def qpo_for_mean_range(orbit: PeriodicOrbit, target_km: float = 215.0, N: int = 25, *,  # noqa: N803
                       statistic: str = "mean_km", rtol: float = 1e-5, n_theta: int = 48, n_t: int = 1201,
                       progress: bool = False, max_iter: int = 12, **solve_kw) -> tuple[InvariantTorus, RangeStats]:
    """The member of the torus family (stroboscopic time = the orbit's period) with a given mean range.

    The family is continued in ring size from a small torus; a secant iteration on the size then matches
    :func:`mean_range` to ``target_km``.

    Parameters
    ----------
    orbit : PeriodicOrbit
        Base orbit (target's orbit), e.g. :func:`cislunar.cr3bp.orbits.nrho_9_2`.
    target_km : float
        Wanted mean agent-target range, km (the paper: 215 km).
    N : int
        Circle points.
    statistic : {"mean_km", "ring_mean_km", "rms_km"}
        Which :class:`RangeStats` reading is matched: the torus average of :func:`mean_range` (default, the
        long-time mean along natural trajectories), the mean over the initial ring at apolune only, or the RMS
        range.  The alternatives exist to show how much the member depends on the reading of "average range".
    rtol : float
        Relative tolerance on the mean range.
    n_theta, n_t : int
        Quadrature of :func:`mean_range`.
    progress : bool
        Progress bar for the continuation.
    max_iter : int
        Secant iterations.
    **solve_kw
        Passed to :func:`solve_torus`.

    Returns
    -------
    (InvariantTorus, RangeStats)

    Raises
    ------
    TorusConvergenceError
        If the secant iteration does not reach ``rtol``.
    """
    _orbit(orbit)
    target_km = validation.positive(target_km, "target_km")
    validation.choice(statistic, "statistic", ("mean_km", "ring_mean_km", "rms_km"))
    rtol = validation.in_range(rtol, "rtol", 1e-12, 0.1)
    N = _check_n(N)
    n_theta = validation.integer(n_theta, "n_theta", minimum=4)
    n_t = validation.integer(n_t, "n_t", minimum=11)
    progress = validation.boolean(progress, "progress")
    max_iter = validation.integer(max_iter, "max_iter", minimum=1)
    small = torus_from_orbit(orbit, N, min(5.0, target_km / 10.0), **solve_kw)
    # the range extrema (a Nelder-Mead each) are refined for the accepted member only: they do not enter the match
    tol = _heyoka_tol(DEFAULT_TOL)
    stats = _range_stats(small, n_theta, n_t, 1, tol)
    sizes, means = [small.size_km], [getattr(stats, statistic)]
    guess_km = small.size_km * target_km / means[0]
    torus = small
    history = []
    for _ in range(max_iter):
        n_steps = max(1, int(np.ceil(abs(guess_km - torus.size_km) / 25.0)))
        values = np.linspace(torus.size_km, guess_km, n_steps + 1)[1:]
        torus = continue_tori(torus, values, parameter="size_km", progress=progress, **solve_kw)[-1]
        stats = _range_stats(torus, n_theta, n_t, 1, tol)
        value = getattr(stats, statistic)
        history.append(value - target_km)
        if abs(value - target_km) <= rtol * target_km:
            return torus, stats.finish()
        sizes.append(torus.size_km)
        means.append(value)
        slope = (means[-1] - means[-2]) / (sizes[-1] - sizes[-2])
        guess_km = sizes[-1] + (target_km - means[-1]) / slope
        if guess_km <= 0:
            break
    raise TorusConvergenceError(f"no torus member with {statistic} = {target_km} km found", history,
                                np.array(sizes), "max_iter")
