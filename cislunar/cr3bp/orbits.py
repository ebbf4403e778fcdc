r"""Periodic orbits of the CR3BP symmetric about the x-z plane: shooting, continuation, stability.

Symmetric periodic orbits cross the x-z plane perpendicularly twice per period.  Starting at such a crossing,

.. math:: \mathbf x_0 = [x_0,\ 0,\ z_0,\ 0,\ \dot y_0,\ 0],

the orbit is periodic if after the half period :math:`\tau = T/2` the trajectory crosses y = 0 again with
:math:`\dot x = \dot z = 0`.  We solve the fixed-time formulation

.. math:: G(X) = [y(\tau),\ \dot x(\tau),\ \dot z(\tau)] = 0, \qquad X = [x_0, z_0, \dot y_0, \tau],

(planar orbits drop :math:`z_0` and :math:`\dot z`) with Newton's method, whose Jacobian comes from the STM:
:math:`\partial G/\partial X = [\Phi_{c,\{x,z,\dot y\}}(\tau),\ f_c(\mathbf x(\tau))]`, :math:`c = \{y, \dot x,
\dot z\}`.  Three equations in four unknowns leave a one-parameter family: fixing one unknown (natural-parameter
continuation, or the period for a resonant orbit such as the 9:2 NRHO) gives a square system; pseudo-arclength
continuation adds :math:`(X - X_{k})\cdot t_k = \Delta s` with :math:`t_k` the null vector of
:math:`\partial G/\partial X`.

Stability
---------
The monodromy matrix :math:`M = \Phi(T, 0)` is symplectic-like: its eigenvalues come in reciprocal pairs
:math:`(\lambda, 1/\lambda)`, with one trivial pair at 1.  Two quantities are reported:

* the stability index of Greaves & Scheeres and Zimovan et al.,
  :math:`\nu = (|\lambda_{max}| + 1/|\lambda_{max}|)/2` (``nu = 1`` means linearly stable), and
* the signed Broucke indices :math:`\nu_{a,b} = (\lambda + 1/\lambda)/2` of the two non-trivial pairs, computed
  from the trace invariants of :math:`M` without pairing eigenvectors (robust at bifurcations).

Times in TU, states in LU and LU/TU, rotating frame (see :mod:`cislunar.cr3bp.dynamics`).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np

from cislunar.cr3bp.dynamics import CR3BP, check_system
from cislunar.cr3bp.propagation import (
    DEFAULT_TOL,
    ImpactError,
    PropagationError,
    check_outside_primaries,
    find_events,
    propagate,
    propagate_stm,
)
from cislunar.utils import validation
from cislunar.utils.progress import progress as _bar

__all__ = [
    "ConvergenceError",
    "PeriodicOrbit",
    "correct_symmetric",
    "continue_family",
    "broucke_indices",
    "stability_index",
    "half_period_guess",
]

_FREE_NAMES = ("x0", "z0", "vy0", "half_period")


class ConvergenceError(RuntimeError):
    """A differential corrector did not converge, or converged to a degenerate solution.

    Attributes
    ----------
    message : str
        What went wrong (without the residual history).
    residuals : list of float
        Norm of the constraint vector at each Newton iteration.
    last_guess : ndarray
        Free-variable vector at the last iteration.
    reason : str
        ``"max_iter"`` (no convergence), ``"non_finite"``, ``"bad_iterate"`` (e.g. a non-positive half period),
        ``"equilibrium"`` (converged to an equilibrium point, not an orbit), ``"impact"`` (the orbit passes
        through a primary) or ``"other"``.

    Survives pickling with all attributes (it travels through process pools).
    """

    def __init__(self, message: str, residuals=(), last_guess=(), reason: str = "other"):
        self.message = str(message)
        self.residuals = [float(r) for r in residuals]
        self.last_guess = np.asarray(last_guess, dtype=float)
        self.reason = str(reason)
        history = ", ".join(f"{r:.3e}" for r in self.residuals)
        super().__init__(f"{self.message}; residual history: [{history}]")

    def __reduce__(self):
        return (type(self), (self.message, self.residuals, self.last_guess, self.reason))


def broucke_indices(monodromy) -> np.ndarray:
    """Signed stability indices :math:`(\\lambda + 1/\\lambda)/2` of the two non-trivial eigenvalue pairs.

    With the characteristic polynomial :math:`(\\lambda-1)^2(\\lambda^2 - s_a\\lambda + 1)(\\lambda^2 - s_b\\lambda
    + 1)` the sums :math:`s_{a,b}` follow from :math:`e_1 = \\mathrm{tr} M` and
    :math:`e_2 = (\\mathrm{tr}(M)^2 - \\mathrm{tr}(M^2))/2`: :math:`s_a + s_b = e_1 - 2`,
    :math:`s_a s_b = e_2 - 3 - 2(e_1 - 2)`.

    Parameters
    ----------
    monodromy : array_like, shape (6, 6)

    Returns
    -------
    ndarray, shape (2,)
        :math:`\\nu_a \\ge \\nu_b` (complex conjugates under complex instability).  A pair is elliptic (stable)
        when :math:`|\\nu| \\le 1` and real.
    """
    M = validation.as_array(monodromy, "monodromy", shape=(6, 6))
    e1 = np.trace(M)
    e2 = 0.5 * (e1**2 - np.trace(M @ M))
    p = e1 - 2.0
    q = e2 - 3.0 - 2.0 * p
    disc = p * p - 4.0 * q
    root = np.sqrt(disc + 0j)
    s = np.array([(p + root) / 2.0, (p - root) / 2.0])
    nu = s / 2.0
    if abs(disc) >= 0 and np.all(np.abs(nu.imag) < 1e-12 * max(1.0, np.max(np.abs(nu)))):
        return np.sort(nu.real)[::-1]
    return nu


def stability_index(monodromy) -> float:
    """Stability index :math:`\\nu = (|\\lambda_{max}| + 1/|\\lambda_{max}|)/2` of a monodromy matrix (``1`` if stable)."""
    M = validation.as_array(monodromy, "monodromy", shape=(6, 6))
    lam = np.max(np.abs(np.linalg.eigvals(M)))
    return float(0.5 * (lam + 1.0 / lam))


@dataclass(frozen=True)
class PeriodicOrbit:
    """A corrected x-z symmetric periodic orbit.

    Attributes
    ----------
    system : CR3BP
    x0 : ndarray, shape (6,)
        State at the perpendicular x-z plane crossing used for shooting, LU and LU/TU.
    period : float
        Period, TU.
    monodromy : ndarray, shape (6, 6)
        :math:`\\Phi(T, 0)`.
    closure : float
        :math:`\\|\\mathbf x(T) - \\mathbf x_0\\|` after one full period (position and velocity, non-dimensional).
    residuals : tuple of float
        Newton residual history of the half-period constraints.
    label : str
        Free-form name.
    """

    system: CR3BP
    x0: np.ndarray
    period: float
    monodromy: np.ndarray = field(repr=False)
    closure: float
    residuals: tuple = field(default=(), repr=False)
    label: str = ""

    def __post_init__(self):
        """Validate on construction: a finite state outside both primaries, a positive period, a 6x6 monodromy."""
        check_system(self.system, "system")
        x0 = validation.as_state(self.x0, "x0", batch=False)
        check_outside_primaries(self.system, x0, "x0")
        object.__setattr__(self, "x0", x0)
        validation.positive(self.period, "period")
        object.__setattr__(self, "monodromy", validation.square(self.monodromy, "monodromy", n=6))
        if not isinstance(self.label, str):
            raise validation.ArgumentTypeError(f"label must be a str; got {type(self.label).__name__}")

    @property
    def jacobi(self) -> float:
        """Jacobi constant."""
        return float(self.system.jacobi(self.x0))

    @property
    def period_days(self) -> float:
        """Period in days."""
        return float(self.system.tu_to_days(self.period))

    @cached_property
    def eigenvalues(self) -> np.ndarray:
        """Monodromy eigenvalues sorted by decreasing modulus."""
        lam = np.linalg.eigvals(self.monodromy)
        return lam[np.argsort(-np.abs(lam))]

    @property
    def stability_index(self) -> float:
        """:math:`(|\\lambda_{max}| + 1/|\\lambda_{max}|)/2`."""
        return stability_index(self.monodromy)

    @property
    def broucke_indices(self) -> np.ndarray:
        """Signed indices of the two non-trivial pairs (see :func:`broucke_indices`)."""
        return broucke_indices(self.monodromy)

    @property
    def is_planar(self) -> bool:
        """True if the orbit lies in the x-y plane."""
        return bool(self.x0[2] == 0.0 and self.x0[5] == 0.0)

    def sample(self, n: int = 400, periods: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
        """Times (TU) and states ``(n, 6)`` on a uniform grid over ``periods`` periods.

        Impact detection is off here (and in :attr:`apses`): a corrected orbit was already propagated over its
        period with impact detection on (orbits through a primary are refused by the corrector).
        """
        n = validation.integer(n, "n", minimum=2)
        periods = validation.positive(periods, "periods")
        t = np.linspace(0.0, periods * self.period, n)
        return t, propagate(self.system, self.x0, t, impact=False).x

    @cached_property
    def apses(self):
        """Moon-relative periapsis/apoapsis passages over one period (:class:`cislunar.cr3bp.propagation.EventRecord`)."""
        return find_events(self.system, self.x0, self.period * (1.0 + 1e-9), ("apse",), impact=False)

    @cached_property
    def _apse_radii_km(self) -> np.ndarray:
        """Distances to the Moon's centre at the initial point and at every apse over one period, km."""
        points = np.vstack([self.x0[None, :3], self.apses.x[:, :3]])
        return np.linalg.norm(points - self.system.secondary_position, axis=1) * self.system.length_unit_km

    @property
    def perilune_radius_km(self) -> float:
        """Smallest distance to the Moon's centre over one period, km (from apse events, or the initial point)."""
        return float(self._apse_radii_km.min())

    @property
    def apolune_radius_km(self) -> float:
        """Largest distance to the Moon's centre over one period, km."""
        return float(self._apse_radii_km.max())


def _pack(x0: np.ndarray, tau: float, planar: bool) -> np.ndarray:
    return np.array([x0[0], x0[4], tau]) if planar else np.array([x0[0], x0[2], x0[4], tau])


def _unpack(X: np.ndarray, planar: bool) -> tuple[np.ndarray, float]:
    if planar:
        return np.array([X[0], 0.0, 0.0, 0.0, X[1], 0.0]), float(X[2])
    return np.array([X[0], 0.0, X[1], 0.0, X[2], 0.0]), float(X[3])


def _residual_jacobian(system: CR3BP, X: np.ndarray, planar: bool, tol: float, history=None):
    x0, tau = _unpack(X, planar)
    if not tau > 0:  # an iterate or a continuation predictor overshot: let the caller halve the step
        raise ConvergenceError(f"half period became non-positive ({tau:.6g} TU) during the correction",
                               history or [], X, reason="bad_iterate")
    try:
        tr = propagate_stm(system, x0, np.array([0.0, tau]), tol=tol, impact=False)  # iterates may graze the Moon
    except PropagationError as exc:
        raise ConvergenceError(f"an iterate could not be propagated ({exc})", history or [], X,
                               reason="non_finite") from exc
    xf, phi = tr.x[-1], tr.stm[-1]
    f = system.eom(xf)
    rows = [1, 3] if planar else [1, 3, 5]
    cols = [0, 4] if planar else [0, 2, 4]
    G = xf[rows]
    DG = np.hstack([phi[np.ix_(rows, cols)], f[rows, None]])
    return G, DG


def _newton(system, X, planar, fixed: int | None, arclength=None, *, tol=1e-12, max_iter=25, int_tol=DEFAULT_TOL):
    """Newton iteration on the symmetric-orbit constraints; ``fixed`` pins one free variable.

    ``arclength = (X_prev, tangent, ds)`` appends the pseudo-arclength equation instead.  Every failure (no
    convergence, a non-finite residual, an iterate with a non-positive half period or that cannot be propagated)
    raises :class:`ConvergenceError`.
    """
    X = np.array(X, dtype=float)
    history = []
    for _ in range(max_iter):
        G, DG = _residual_jacobian(system, X, planar, int_tol, history)
        if arclength is not None:
            Xp, tangent, ds = arclength
            G = np.append(G, (X - Xp) @ tangent - ds)
            DG = np.vstack([DG, tangent])
            J = DG
        else:
            keep = [i for i in range(X.size) if i != fixed]
            J = DG[:, keep]
        err = float(np.linalg.norm(G))
        history.append(err)
        if not np.isfinite(err):
            raise ConvergenceError("symmetric-orbit corrector produced a non-finite residual", history, X,
                                   reason="non_finite")
        if err < tol:
            return X, DG, history
        try:
            if arclength is not None or J.shape[0] == J.shape[1]:
                step = np.linalg.solve(J, -G)
            else:
                step = np.linalg.lstsq(J, -G, rcond=None)[0]
        except np.linalg.LinAlgError as exc:
            raise ConvergenceError(f"singular Newton Jacobian ({exc})", history, X, reason="non_finite") from exc
        # damp huge steps (they usually jump to another family or into a primary)
        scale = min(1.0, 0.1 / max(np.max(np.abs(step)), 1e-300))
        if arclength is not None:
            X = X + scale * step
        else:
            X[keep] = X[keep] + scale * step
    raise ConvergenceError(
        f"symmetric-orbit corrector did not reach |G| < {tol:g} in {max_iter} iterations", history, X,
        reason="max_iter")


def half_period_guess(system: CR3BP, x0, *, max_time: float = 20.0, tol: float = DEFAULT_TOL) -> float:
    """Time of the first return to the x-z plane (a half-period guess for a symmetric orbit), TU."""
    check_system(system)
    x0 = validation.as_state(x0, "x0", batch=False)
    max_time = validation.positive(max_time, "max_time")
    ev = find_events(system, x0, max_time, ("y_crossing",), tol=tol, impact=False)
    if ev.t.size == 0:
        raise ValueError(f"x0 does not return to the x-z plane within max_time = {max_time} TU")
    return float(ev.t[0])


#: A converged "orbit" whose state derivative is below this norm (LU/TU and LU/TU^2) is an equilibrium point.
EQUILIBRIUM_TOL = 1e-9


def _finish(system, X, planar, history, label, int_tol) -> PeriodicOrbit:
    """Build the orbit from converged free variables, refusing degenerate solutions.

    The full period is propagated with impact detection on (the corrector's own iterates are not), so an orbit
    that passes through the Earth or the Moon is refused, as is an equilibrium point (whose "period" is arbitrary).
    """
    x0, tau = _unpack(X, planar)
    speed = float(np.linalg.norm(system.eom(x0)))
    if speed < EQUILIBRIUM_TOL:
        raise ConvergenceError(f"the corrector converged to an equilibrium point (|f(x0)| = {speed:.2e}), not a "
                               "periodic orbit; start from a guess away from the libration point", history, X,
                               reason="equilibrium")
    try:
        tr = propagate_stm(system, x0, np.array([0.0, 2.0 * tau]), tol=int_tol, impact=True)
    except ImpactError as exc:
        raise ConvergenceError(f"the corrected orbit passes through a primary ({exc})", history, X,
                               reason="impact") from exc
    except PropagationError as exc:
        raise ConvergenceError(f"the corrected orbit cannot be propagated over its period ({exc})", history, X,
                               reason="non_finite") from exc
    closure = float(np.linalg.norm(tr.x[-1] - x0))
    return PeriodicOrbit(system=system, x0=x0, period=2.0 * tau, monodromy=tr.stm[-1], closure=closure,
                         residuals=tuple(history), label=label)


def correct_symmetric(system: CR3BP, x0_guess, half_period: float | None = None, *, fix: str = "x0",
                      tol: float = 1e-12, max_iter: int = 25, label: str = "",
                      int_tol: float = DEFAULT_TOL) -> PeriodicOrbit:
    """Correct a guess into an x-z symmetric periodic orbit by single shooting.

    Parameters
    ----------
    system : CR3BP
    x0_guess : array_like, shape (6,)
        Guess at a perpendicular x-z crossing; ``y0``, ``vx0`` and ``vz0`` are set to zero.  If ``z0`` and
        ``vz0`` are zero the orbit is corrected as planar.
    half_period : float, optional
        Half-period guess, TU; by default the first return to the x-z plane.
    fix : {"x0", "z0", "vy0", "half_period", "none"}
        Free variable held fixed (``"half_period"`` gives an orbit of prescribed period, e.g. a resonant orbit;
        ``"none"`` takes minimum-norm Newton steps).
    tol : float
        Convergence threshold on :math:`\\|[y, \\dot x, \\dot z](T/2)\\|`.
    max_iter : int
        Newton iterations before :class:`ConvergenceError`.
    label : str
        Name stored in the result.
    int_tol : float
        Integrator tolerance.

    Returns
    -------
    PeriodicOrbit

    Raises
    ------
    ValueError
        Bad shapes or values, or a fixed variable not among the free ones (``z0`` for a planar orbit).
    ConvergenceError
        Newton did not converge; carries the residual history.
    """
    check_system(system)
    x0 = validation.as_state(x0_guess, "x0_guess", batch=False).copy()
    x0[[1, 3, 5]] = 0.0
    planar = x0[2] == 0.0
    valid = ("x0", "vy0", "half_period", "none") if planar else _FREE_NAMES + ("none",)
    if not isinstance(fix, str):
        raise validation.ArgumentTypeError(f"fix must be one of {valid}; got {type(fix).__name__}")
    if fix not in valid:
        raise ValueError(f"fix must be one of {valid} for a {'planar' if planar else 'spatial'} orbit; got {fix!r}")
    validation.in_range(tol, "tol", 1e-15, 1e-3)
    max_iter = validation.integer(max_iter, "max_iter", minimum=1)
    int_tol = validation.in_range(int_tol, "int_tol", 1e-16, 1e-3)
    if not isinstance(label, str):
        raise validation.ArgumentTypeError(f"label must be a str; got {type(label).__name__}")
    r1, r2 = system.distances(x0)
    if r2 <= system.secondary_radius or r1 <= system.primary_radius:
        raise ValueError("x0_guess lies inside the Moon or the Earth")
    if half_period is None:
        half_period = half_period_guess(system, x0, tol=int_tol)
    half_period = validation.positive(half_period, "half_period")
    X = _pack(x0, half_period, planar)
    names = ("x0", "vy0", "half_period") if planar else _FREE_NAMES
    fixed = None if fix == "none" else names.index(fix)
    X, _, history = _newton(system, X, planar, fixed, tol=tol, max_iter=max_iter, int_tol=int_tol)
    return _finish(system, X, planar, history, label, int_tol)


def continue_family(system: CR3BP, orbit: PeriodicOrbit, n_steps: int, step: float, *,
                    method: str = "pseudo-arclength", parameter: str = "x0", stop=None, tol: float = 1e-12,
                    max_iter: int = 25, progress: bool = False, int_tol: float = DEFAULT_TOL) -> list:
    """Continue a family of symmetric periodic orbits from ``orbit``.

    Parameters
    ----------
    system : CR3BP
    orbit : PeriodicOrbit
        Converged starting member (included as the first element of the result).
    n_steps : int
        Number of new members to compute.
    step : float
        Pseudo-arclength step :math:`\\Delta s` in the free-variable space (non-dimensional), or the increment
        of ``parameter`` for natural-parameter continuation.  Its sign selects the direction.
    method : {"pseudo-arclength", "natural"}
    parameter : {"x0", "z0", "vy0", "half_period"}
        Natural continuation parameter; for pseudo-arclength, the initial direction is the one in which this
        variable moves with the sign of ``step``.
    stop : callable, optional
        ``stop(orbit) -> bool``; continuation ends (keeping that member) when it returns True.
    tol, max_iter, int_tol
        As in :func:`correct_symmetric`.
    progress : bool
        Show a tqdm progress bar.

    Returns
    -------
    list of PeriodicOrbit

    Raises
    ------
    ConvergenceError
        When a member fails to converge even after halving the step three times.
    """
    check_system(system)
    validation.instance(orbit, "orbit", PeriodicOrbit, "a cislunar.cr3bp.orbits.PeriodicOrbit")
    if orbit.system != system:
        raise ValueError("orbit belongs to another system than system")
    validation.choice(method, "method", ("pseudo-arclength", "natural"))
    n_steps = validation.integer(n_steps, "n_steps", minimum=1)
    step = validation.real(step, "step")
    if step == 0:
        raise ValueError(f"step must be finite and non-zero; got {step}")
    if stop is not None:
        validation.callable_(stop, "stop")
    validation.in_range(tol, "tol", 1e-15, 1e-3)
    max_iter = validation.integer(max_iter, "max_iter", minimum=1)
    int_tol = validation.in_range(int_tol, "int_tol", 1e-16, 1e-3)
    progress = validation.boolean(progress, "progress")
    planar = orbit.is_planar
    names = ("x0", "vy0", "half_period") if planar else _FREE_NAMES
    validation.choice(parameter, "parameter", names)
    p_index = names.index(parameter)
    X = _pack(orbit.x0, orbit.period / 2.0, planar)
    family = [orbit]
    tangent = None

    iterator = _bar(range(n_steps), desc=f"continuing {orbit.label or 'family'}", enabled=progress)
    for _ in iterator:
        ds = step
        for attempt in range(4):
            try:
                if method == "natural":
                    # first-order predictor: move along the family's tangent with the parameter advanced by ds
                    _, DG = _residual_jacobian(system, X, planar, int_tol)
                    keep = [i for i in range(X.size) if i != p_index]
                    v = np.zeros(X.size)
                    v[p_index] = 1.0
                    v[keep] = np.linalg.lstsq(DG[:, keep], -DG[:, p_index], rcond=None)[0]
                    Xg = X + ds * v
                    Xn, DG, hist = _newton(system, Xg, planar, p_index, tol=tol, max_iter=max_iter, int_tol=int_tol)
                else:
                    _, DG = _residual_jacobian(system, X, planar, int_tol)
                    t_new = np.linalg.svd(DG)[2][-1]
                    if tangent is None:
                        t_new = t_new * np.sign(t_new[p_index] * np.sign(step) or 1.0)
                    elif t_new @ tangent < 0:
                        t_new = -t_new
                    Xn, DG, hist = _newton(system, X + abs(ds) * t_new, planar, None, (X, t_new, abs(ds)),
                                           tol=tol, max_iter=max_iter, int_tol=int_tol)
                # a member through a primary (or an equilibrium) is refused like a failed correction
                member = _finish(system, Xn, planar, hist, orbit.label, int_tol)
                if method != "natural":
                    tangent = t_new
                break
            except ConvergenceError:
                if attempt == 3:
                    raise
                ds = ds / 2.0
        X = Xn
        family.append(member)
        if stop is not None and stop(member):
            break
    return family


# ----------------------------------------------------------------------------------------------------------
# Root finding along a family
# ----------------------------------------------------------------------------------------------------------
def refine_on_family(system: CR3BP, a: PeriodicOrbit, b: PeriodicOrbit, func, *, parameter: str = "half_period",
                     xtol: float = 1e-12, label: str = "") -> PeriodicOrbit:
    """Find the family member between ``a`` and ``b`` where ``func(orbit)`` vanishes.

    Members between the two are obtained by natural-parameter correction with ``parameter`` fixed, so the
    parameter must vary monotonically between ``a`` and ``b``; the root is bracketed and found with ``brentq``.

    Raises
    ------
    ValueError
        If ``func`` has the same sign at ``a`` and ``b``.
    """
    from scipy.optimize import brentq

    check_system(system)
    validation.instance(a, "a", PeriodicOrbit, "a cislunar.cr3bp.orbits.PeriodicOrbit")
    validation.instance(b, "b", PeriodicOrbit, "a cislunar.cr3bp.orbits.PeriodicOrbit")
    validation.callable_(func, "func")
    xtol = validation.positive(xtol, "xtol")
    planar = a.is_planar
    if b.is_planar != planar:
        raise ValueError("a and b must both be planar or both spatial members of one family")
    names = ("x0", "vy0", "half_period") if planar else _FREE_NAMES
    validation.choice(parameter, "parameter", names)
    k = names.index(parameter)
    Xa, Xb = _pack(a.x0, a.period / 2, planar), _pack(b.x0, b.period / 2, planar)
    fa, fb = func(a), func(b)
    if np.sign(fa) == np.sign(fb):
        raise ValueError(f"func does not change sign between the two members ({fa:.3e}, {fb:.3e})")
    cache = {}

    def member(p):
        w = (p - Xa[k]) / (Xb[k] - Xa[k])
        Xg = (1 - w) * Xa + w * Xb
        Xg[k] = p
        X, _, hist = _newton(system, Xg, planar, k)
        cache[p] = _finish(system, X, planar, hist, label, DEFAULT_TOL)
        return func(cache[p])

    p_root = brentq(member, Xa[k], Xb[k], xtol=xtol)
    if p_root not in cache:
        member(p_root)
    return cache[p_root]


# ----------------------------------------------------------------------------------------------------------
# Named reference orbits
# ----------------------------------------------------------------------------------------------------------
#: Apolune guess of the southern 9:2 L2 NRHO (public value, ``book/sources.md``; corrected, never used as is).
NRHO_9_2_GUESS = np.array([1.0219, 0.0, -0.182, 0.0, -0.103, 0.0])


def nrho_9_2(system: CR3BP) -> PeriodicOrbit:
    """The southern L2 9:2 synodic-resonant NRHO: period fixed to 2/9 of the synodic month (29.530589 d).

    Single shooting from apolune (``y0 = vx0 = vz0 = 0``) with the half period held fixed; the guess
    :data:`NRHO_9_2_GUESS` only seeds Newton's method.
    """
    check_system(system)
    half = system.synodic_month_tu() / 9.0
    return correct_symmetric(system, NRHO_9_2_GUESS, half, fix="half_period", label="9:2 NRHO")


def l2_southern_halo_family(system: CR3BP, *, step: float = 0.01, n_moonward: int = 40, n_l2ward: int = 200,
                            min_perilune_km: float = 1800.0, progress: bool = False) -> list:
    """Members of the southern L2 halo family, from the NRHOs near the Moon out to the planar-bifurcation end.

    Pseudo-arclength continuation starts at the 9:2 NRHO and runs both ways: towards the Moon until the perilune
    radius falls below ``min_perilune_km`` (or ``n_moonward`` steps), and towards L2 until ``|z0|`` at apolune
    falls below 0.005 LU (the halo family's bifurcation from the planar Lyapunov family) or ``n_l2ward`` steps.

    Returns
    -------
    list of PeriodicOrbit
        Ordered by decreasing period is not guaranteed; ordered along the family from the Moon side outwards.
    """
    check_system(system)
    step = validation.positive(step, "step")
    n_moonward = validation.integer(n_moonward, "n_moonward", minimum=1)
    n_l2ward = validation.integer(n_l2ward, "n_l2ward", minimum=1)
    min_perilune_km = validation.positive(min_perilune_km, "min_perilune_km")
    start = nrho_9_2(system)
    moonward = continue_family(system, start, n_moonward, -abs(step), parameter="half_period",
                               stop=lambda o: o.perilune_radius_km < min_perilune_km, progress=progress)
    outward = continue_family(system, start, n_l2ward, abs(step), parameter="half_period",
                              stop=lambda o: abs(o.x0[2]) < 0.005, progress=progress)
    return moonward[::-1] + outward[1:]


def _hyperbolic_margin(orbit: PeriodicOrbit) -> float:
    nu = orbit.broucke_indices
    return float(np.max(np.abs(nu.real)) - 1.0)


def stable_nrho(system: CR3BP, *, step: float = 0.01) -> PeriodicOrbit:
    """The southern L2 NRHO at which the stability index first reaches 1, continuing from the 9:2 NRHO Moonward.

    Along the family the one hyperbolic pair of the 9:2 NRHO (Broucke index about -1.32) turns elliptic through
    a period-doubling boundary (index -1).  The member on that boundary is located with ``brentq`` on the
    half period, so its stability index is 1 to the root-finding tolerance.  Greaves & Scheeres' Table 1 (which
    would give their member's state) is missing from the paper's text; this is the documented choice.
    """
    check_system(system)
    step = validation.positive(step, "step")
    start = nrho_9_2(system)
    fam = continue_family(system, start, 80, -abs(step), parameter="half_period",
                          stop=lambda o: _hyperbolic_margin(o) < 0)
    if _hyperbolic_margin(fam[-1]) >= 0:
        raise ConvergenceError("continuation from the 9:2 NRHO did not reach the stable region",
                               [_hyperbolic_margin(o) for o in fam], _pack(fam[-1].x0, fam[-1].period / 2, False))
    return refine_on_family(system, fam[-2], fam[-1], _hyperbolic_margin, label="stable NRHO (nu = 1)")


def stable_nrho_outer(system: CR3BP, *, step: float = 0.01) -> PeriodicOrbit:
    """The most stable member of the southern L2 halo family's outer stable band.

    Continuing from the 9:2 NRHO away from the Moon (increasing half period), the family's hyperbolic pair turns
    elliptic again at a perilune radius of about 13,400 km and stays so over a band of members ("roughly halfway to
    the Moon" from L2).  This continues into that band, through it, and returns the member with the smallest
    hyperbolic margin ``max |Broucke index| - 1`` (the most stable one; perilune about 16,200 km, period about
    10.1 d in the Earth-Moon system).  :func:`stable_nrho` is the inner band's edge next to the Moon; which of the
    two Greaves & Scheeres (2021) used is not stated (their Table 1 is missing), so notebooks 09, 09b and 10 carry
    both.

    Parameters
    ----------
    system : CR3BP
    step : float
        Continuation step in the half period, TU.

    Returns
    -------
    PeriodicOrbit

    Raises
    ------
    ConvergenceError
        If the continuation does not reach the band or does not leave it within its step budget.
    """
    check_system(system)
    step = abs(validation.positive(step, "step"))
    fam = continue_family(system, nrho_9_2(system), 120, step, parameter="half_period",
                          stop=lambda o: _hyperbolic_margin(o) < 0)
    if _hyperbolic_margin(fam[-1]) >= 0:
        raise ConvergenceError("continuation from the 9:2 NRHO away from the Moon did not reach the outer stable "
                               "band", [_hyperbolic_margin(o) for o in fam],
                               _pack(fam[-1].x0, fam[-1].period / 2, False))
    band = continue_family(system, fam[-1], 80, step, parameter="half_period",
                           stop=lambda o: _hyperbolic_margin(o) > 0)
    if _hyperbolic_margin(band[-1]) <= 0:
        raise ConvergenceError("continuation did not cross the outer stable band within its step budget",
                               [_hyperbolic_margin(o) for o in band], _pack(band[-1].x0, band[-1].period / 2, False))
    best = min(band, key=_hyperbolic_margin)
    return replace(best, label="stable NRHO (outer band)")


def dro_family(system: CR3BP, x0_values, *, seed=None) -> list:
    """Planar distant retrograde orbits with the given x-axis crossings (between Earth and Moon), LU.

    Each member is corrected with ``x0`` fixed (natural parameter), seeded by the previous member (or by
    ``seed``, a DRO state, for the first).  ``x0_values`` should be ordered so consecutive members are close.
    """
    check_system(system)
    xs = validation.as_array(x0_values, "x0_values", ndim=(1,), min_size=1)
    if np.any(xs >= 1.0 - system.mu) or np.any(xs <= 0.5):
        raise ValueError("x0_values must lie between 0.5 LU and the Moon (DRO crossings on the Earth side)")
    if np.any(1.0 - system.mu - xs <= system.secondary_radius):
        raise ValueError(f"x0_values must lie outside the Moon (more than {system.secondary_radius_km} km from its "
                         f"centre, i.e. below {1.0 - system.mu - system.secondary_radius:.6f} LU); got "
                         f"{xs[1.0 - system.mu - xs <= system.secondary_radius]}")
    guess = np.array([xs[0], 0, 0, 0, 0.0, 0]) if seed is None else validation.as_state(seed, "seed", batch=False)
    if seed is None:
        d = 1.0 - system.mu - xs[0]  # retrograde circular-orbit guess about the Moon, rotating-frame speed
        guess[4] = np.sqrt(system.mu / d) + d
    family = []
    half = None
    for i, x in enumerate(xs):
        g = guess.copy()
        g[0] = x
        if i == 1:  # Keplerian scaling about the Moon from the first member
            d0, d1 = 1.0 - system.mu - family[0].x0[0], 1.0 - system.mu - x
            g[4] = family[0].x0[4] + (np.sqrt(system.mu / d1) + d1) - (np.sqrt(system.mu / d0) + d0)
            half = family[0].period / 2 * (d1 / d0) ** 1.5
        if i >= 2:  # secant predictor along the family (x0 is the natural parameter)
            a, b = family[-2], family[-1]
            w = (x - b.x0[0]) / (b.x0[0] - a.x0[0])
            g = b.x0 + w * (b.x0 - a.x0)
            half = b.period / 2 + w * (b.period - a.period) / 2
        orb = correct_symmetric(system, g, half, fix="x0", label="DRO")
        family.append(orb)
        guess, half = orb.x0, orb.period / 2
    return family
