r"""Informed station keeping on a quasi-periodic orbit (Greaves & Scheeres AMOS 2023, Sections 4-5).

Station-keeping set
-------------------
The agent must return to the surface of a quasi-periodic torus about the target's orbit.  A point of the surface
is named by the **initial ring angle** :math:`\theta_0` (the angle on the invariant ring at apolune, see
:mod:`cislunar.cr3bp.torus`) and the **time from apoapsis** :math:`t_a`: it is the state at time :math:`t_a` of the
torus trajectory that crosses the apolune ring at :math:`u(\theta_0)`.  Any object with a
``states(theta0, t) -> (n_theta, n_t, 6)`` method and an ``orbit`` attribute (the base periodic orbit, whose
``x0`` is apolune) can serve as the surface.

Two-burn transfer
-----------------
From the agent state :math:`\mathbf x_a(t_b)` the first burn :math:`\Delta\mathbf v_1` at :math:`t_b` makes the
agent reach the *position* of the surface point at :math:`t_a`; the second burn :math:`\Delta\mathbf v_2` at
:math:`t_a` matches its *velocity*.  The first burn solves the two-point boundary-value problem
:math:`\mathbf r(t_a; \mathbf x_a + B\Delta\mathbf v_1) = \mathbf r^\star` by Newton's method with the
position-velocity block of the STM, :math:`\Phi_{rv}(t_a, t_b)` (a "Lambert problem" in the CR3BP), for all
surface points of one arrival time in one heyoka batch.

Informed maneuver (Eq. 25)
--------------------------
For each arrival time the MMD direction :math:`\mathbf u_y` (Eqs. 23-24) of the coast :math:`t_b \to t_a` is
computed on the unmaneuvered agent trajectory; the alignment
:math:`\cos\theta_u = \mathbf u_y^T\Delta\mathbf v_1/\|\Delta\mathbf v_1\|` (unit :math:`\mathbf u_y`; the
printed Eq. 25 divides by :math:`\|\mathbf u_y^T\mathbf u_{sk}\|`, which would make every angle 0 or
:math:`\pi`, so we read it as the angle between the vectors) selects two candidates
(:math:`\theta_u` nearest 0 and nearest :math:`\pi`, since :math:`\pm\mathbf u_y` are both MMD solutions) and a
covariance analysis of the two picks the informed maneuver :math:`\mathbf u^*`.

Every maneuver of the surface gets its own linear covariance analysis (:func:`cislunar.guidance.ssat.ssat_covariance`:
hourly azimuth/elevation, Eq. 20 noise, both burns, no execution errors), so the surfaces of
:math:`\sqrt{J_\rho}` and of total fuel :math:`\|\Delta\mathbf v_1\| + \|\Delta\mathbf v_2\|` can be compared with
the informed line.  :func:`filter_trial` runs an iterated EKF on simulated measurements with maneuver execution
errors (beyond the paper: its stated future work).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from cislunar.cr3bp.dynamics import CR3BP, check_system
from cislunar.cr3bp.propagation import (
    ImpactError,
    PropagationError,
    propagate,
    propagate_stm,
)
from cislunar.estimation.consistency import _nees
from cislunar.guidance.ssat import (
    ImpulsiveTrajectory,
    _initial_cov,
    _noise,
    initial_covariance,
    mmd_direction,
    mmd_matrix,
    propagate_with_impulses,
    range_projection,
    ssat_covariance,
)
from cislunar.sensing.measurements import (
    AMOS_RESOLUTION_KM,
    AMOS_SIGMA_MIN_RAD,
    AZIMUTH_ELEVATION,
    angular_sigma,
)
from cislunar.utils import validation
from cislunar.utils.progress import progress as _progress

__all__ = [
    "FilterScenario",
    "FilterTrialResult",
    "StationKeepingSurface",
    "TransferConvergenceError",
    "execution_sigma",
    "filter_scenario",
    "filter_trial",
    "first_burn_only_range_sigma_km",
    "informed_choice",
    "position_transfer",
    "random_choice_trial",
    "station_keeping_surface",
    "target_trajectory",
    "two_burn_transfer",
]


class TransferConvergenceError(RuntimeError):
    """Newton's method for the first burn did not converge.

    Attributes
    ----------
    residuals : list of float
        Largest position miss (LU) over the batch at each iteration.
    failed : list of int
        Batch indices that did not converge.
    reason : str
        ``"max_iter"`` (no convergence), ``"impact"`` (an iterate's arc reaches a primary), ``"propagation"`` (the
        integrator stopped), ``"singular"`` (the position-velocity block of the STM is singular) or
        ``"non_finite"``.
    """

    def __init__(self, message: str, residuals, failed, reason: str = "max_iter"):
        self.message = message
        self.residuals = [float(r) for r in residuals]
        self.failed = [int(i) for i in failed]
        self.reason = str(reason)
        hist = ", ".join(f"{r:.3e}" for r in self.residuals)
        super().__init__(f"{message}; residual history (max position miss, LU): [{hist}]; failed indices "
                         f"{self.failed[:10]}{'...' if len(self.failed) > 10 else ''}")

    def __reduce__(self):
        return (type(self), (self.message, self.residuals, self.failed, self.reason))


def _system(system):
    return check_system(system)


def position_transfer(system: CR3BP, x0, t0: float, t1: float, r_target, *, tol: float = 1e-12,
                      max_iter: int = 25):
    """First burn of the two-burn transfer: :math:`\\Delta\\mathbf v` at ``t0`` reaching ``r_target`` at ``t1`` (batched).

    Newton iteration :math:`\\Delta\\mathbf v \\leftarrow \\Delta\\mathbf v - \\Phi_{rv}^{-1}(\\mathbf r(t_1) -
    \\mathbf r^\\star)`, starting from zero (whose first step is the linear solution about the unmaneuvered arc).

    Parameters
    ----------
    system : CR3BP
    x0 : array_like (6,) or (n, 6)
        Pre-burn state(s) at ``t0``, LU and LU/TU.
    t0, t1 : float
        Burn and arrival times, TU (``t1 > t0``).
    r_target : array_like (3,) or (n, 3)
        Positions to reach at ``t1``, LU.
    tol : float
        Convergence threshold on the position miss, LU (1e-12 LU = 0.4 micrometre).
    max_iter : int
        Newton iterations.

    Returns
    -------
    dv : ndarray (n, 3)
        First-burn velocity change, LU/TU.
    x1 : ndarray (n, 6)
        Arrival states (before the second burn).
    residuals : list of float
        Max position miss over the batch at each iteration, LU.

    Raises
    ------
    TransferConvergenceError
        Some transfers did not reach ``tol`` (residual history and failed indices attached), an iterate's arc
        reaches the Earth or the Moon (``reason="impact"``: a transfer never passes through a primary), the
        integrator stops, or the Newton matrix is singular.
    ValueError, TypeError
        Bad arguments (named).
    """
    _system(system)
    t0 = validation.real(t0, "t0")
    t1 = validation.real(t1, "t1")
    if not t1 > t0:
        raise ValueError(f"t1 must be finite and later than t0; got t0 = {t0}, t1 = {t1}")
    tol = validation.positive(tol, "tol")
    max_iter = validation.integer(max_iter, "max_iter", minimum=1)
    r_target = validation.as_array(r_target, "r_target", ndim=(1, 2), last=3, min_size=1)
    rt = np.atleast_2d(r_target)
    xs = np.atleast_2d(validation.as_state(x0, "x0"))
    if xs.shape[0] not in (1, rt.shape[0]):
        raise ValueError(f"x0 and r_target must hold one state or as many as each other; got x0 {xs.shape} and "
                         f"r_target {rt.shape}")
    xs = np.broadcast_to(xs, (rt.shape[0], 6)).copy()
    n = rt.shape[0]
    dv = np.zeros((n, 3))
    hist = []
    grid = np.array([t0, t1])
    what = f"position transfer over {t1 - t0:.4g} TU"
    for _ in range(max_iter):
        x = xs.copy()
        x[:, 3:6] += dv
        try:
            tr = propagate_stm(system, x, grid)
        except (ImpactError, PropagationError) as exc:
            member = getattr(exc, "member", None)
            failed = range(n) if member is None else [member]
            reason = "impact" if isinstance(exc, ImpactError) else "propagation"
            raise TransferConvergenceError(f"{what}: an iterate cannot be flown ({exc})", hist, failed,
                                           reason) from None
        xf = (tr.x if tr.x.ndim == 3 else tr.x[None])[:, -1]
        stm = (tr.stm if tr.stm.ndim == 4 else tr.stm[None])[:, -1]
        miss = xf[:, :3] - rt
        err = np.linalg.norm(miss, axis=1)
        hist.append(float(err.max()))
        if err.max() <= tol:
            return dv, xf, hist
        try:
            dv = dv - np.linalg.solve(stm[:, :3, 3:6], miss[..., None])[..., 0]
        except np.linalg.LinAlgError as exc:
            raise TransferConvergenceError(f"{what}: singular position-velocity block of the STM ({exc})", hist,
                                           np.flatnonzero(err > tol), "singular") from None
        if not np.all(np.isfinite(dv)):
            raise TransferConvergenceError(f"{what}: non-finite Newton step", hist,
                                           np.flatnonzero(~np.all(np.isfinite(dv), axis=1)), "non_finite")
    raise TransferConvergenceError(f"position transfer over {t1 - t0:.4g} TU did not converge to {tol:g} LU "
                                   f"in {max_iter} iterations", hist, np.flatnonzero(err > tol))


def two_burn_transfer(system: CR3BP, x0, t0: float, t1: float, x_target, *, tol: float = 1e-12, max_iter: int = 25):
    """Two-burn transfer to full states ``x_target`` (n, 6) at ``t1``: position by :func:`position_transfer`, then velocity.

    Returns
    -------
    dv1, dv2 : ndarray (n, 3)
        Burns at ``t0`` and ``t1``, LU/TU.
    x1 : ndarray (n, 6)
        Post-second-burn arrival states (equal to ``x_target`` in velocity exactly, in position to ``tol``).
    """
    _system(system)
    xt = validation.as_array(x_target, "x_target", ndim=(1, 2), last=6, min_size=1)
    xt = np.atleast_2d(xt)
    n0 = np.atleast_2d(validation.as_state(x0, "x0")).shape[0]
    if n0 not in (1, xt.shape[0]):
        raise ValueError(f"x0 and x_target must hold one state or as many as each other; got {n0} and {xt.shape[0]}")
    dv1, x1, _ = position_transfer(system, x0, t0, t1, xt[:, :3], tol=tol, max_iter=max_iter)
    dv2 = xt[:, 3:6] - x1[:, 3:6]
    x1 = x1.copy()
    x1[:, 3:6] += dv2
    return dv1, dv2, x1


def target_trajectory(system: CR3BP, apolune_state, t) -> ImpulsiveTrajectory:
    """The target on its periodic orbit on grid ``t`` (TU from apolune, may start negative), with STMs from ``t[0]``."""
    _system(system)
    x = validation.as_state(apolune_state, "apolune_state", batch=False)
    t = validation.time_grid(t, "t", increasing=True)
    x_start = x if t[0] == 0 else propagate(system, x, np.array([0.0, t[0]])).x[-1]
    return propagate_with_impulses(system, x_start, t)


@dataclass(frozen=True)
class StationKeepingSurface:
    """Two-burn station-keeping maneuvers over (time of arrival, initial ring angle), each with its covariance analysis.

    Arrays indexed ``[j, i]`` are for arrival time ``t_arrival[j]`` and ring angle ``theta[i]``.

    Attributes
    ----------
    theta : ndarray (n_theta,)
        Initial ring angles of the surface points, rad.
    t_arrival : ndarray (n_t,)
        Times from apoapsis of the arrival (second burn), TU.
    t_burn : float
        Time from apoapsis of the first burn, TU.
    t : ndarray (N,)
        Measurement grid of the covariance analyses, TU from apoapsis.
    agent_x0 : ndarray (6,)
        Agent state at ``t[0]`` (start of tracking, before the first burn).
    dv1, dv2 : ndarray (n_t, n_theta, 3)
        First and second burns, LU/TU.
    range_sigma_km : ndarray (n_t, n_theta)
        :math:`\\sqrt{J_\\rho}` at ``t[-1]``, km.
    range_sigma_at_arrival_km : ndarray (n_t, n_theta)
        :math:`\\sqrt{J_\\rho}` at the last measurement before or at the arrival, km.
    u_y : ndarray (n_t, 3)
        MMD unit direction of the coast ``t_burn -> t_arrival[j]`` (or ``-> t_final`` with ``mmd_horizon="final"``;
        sign as returned by the eigen-solver).
    alignment : ndarray (n_t, n_theta)
        :math:`\\cos\\theta_u` of Eq. 25.
    candidates : ndarray (n_t, 2) of int
        Ring-angle indices most aligned with :math:`+\\mathbf u_y` and with :math:`-\\mathbf u_y`.
    informed : ndarray (n_t,) of int
        Index of :math:`\\mathbf u^*`: the candidate with the smaller :math:`J_\\rho`.
    transfer_miss : ndarray (n_t, n_theta)
        Position miss of the first burn at arrival, LU.
    velocity_unit_km_s : float
    """

    theta: np.ndarray
    t_arrival: np.ndarray
    t_burn: float
    t: np.ndarray
    agent_x0: np.ndarray
    dv1: np.ndarray
    dv2: np.ndarray
    range_sigma_km: np.ndarray
    range_sigma_at_arrival_km: np.ndarray
    u_y: np.ndarray
    alignment: np.ndarray
    candidates: np.ndarray
    informed: np.ndarray
    transfer_miss: np.ndarray
    velocity_unit_km_s: float
    time_unit_s: float

    def __post_init__(self):
        theta = validation.as_array(self.theta, "theta", ndim=(1,), min_size=1)
        t_arr = validation.as_array(self.t_arrival, "t_arrival", ndim=(1,), min_size=1)
        if np.any(np.diff(t_arr) <= 0):
            raise ValueError("t_arrival must be strictly increasing")
        nt, nth = t_arr.size, theta.size
        f = {"theta": theta, "t_arrival": t_arr, "t_burn": validation.real(self.t_burn, "t_burn"),
             "t": validation.time_grid(self.t, "t", increasing=True),
             "agent_x0": validation.as_state(self.agent_x0, "agent_x0", batch=False)}
        def sized(name, shape, what):
            a = validation.as_array(getattr(self, name), name, ndim=(len(shape),))
            if a.shape != shape:
                raise ValueError(f"{name} must have shape {what} = {shape} (n_t = t_arrival.size, n_theta = "
                                 f"theta.size); got {a.shape}")
            return a

        for name, shape, what in (("dv1", (nt, nth, 3), "(n_t, n_theta, 3)"),
                                  ("dv2", (nt, nth, 3), "(n_t, n_theta, 3)"),
                                  ("range_sigma_km", (nt, nth), "(n_t, n_theta)"),
                                  ("range_sigma_at_arrival_km", (nt, nth), "(n_t, n_theta)"),
                                  ("u_y", (nt, 3), "(n_t, 3)"), ("alignment", (nt, nth), "(n_t, n_theta)"),
                                  ("transfer_miss", (nt, nth), "(n_t, n_theta)")):
            f[name] = sized(name, shape, what)
        for name, shape, what in (("candidates", (nt, 2), "(n_t, 2)"), ("informed", (nt,), "(n_t,)")):
            a = sized(name, shape, what)
            if np.any(a != np.round(a)) or np.any(a < 0) or np.any(a >= nth):
                raise ValueError(f"{name} must hold ring-angle indices in 0..{nth - 1}")
            f[name] = a.astype(int)
        f["velocity_unit_km_s"] = validation.positive(self.velocity_unit_km_s, "velocity_unit_km_s")
        f["time_unit_s"] = validation.positive(self.time_unit_s, "time_unit_s")
        for name, value in f.items():
            object.__setattr__(self, name, value)

    @property
    def dv1_m_s(self) -> np.ndarray:
        """First-burn magnitude, m/s, (n_t, n_theta)."""
        return np.linalg.norm(self.dv1, axis=-1) * self.velocity_unit_km_s * 1e3

    @property
    def dv2_m_s(self) -> np.ndarray:
        """Second-burn magnitude, m/s, (n_t, n_theta)."""
        return np.linalg.norm(self.dv2, axis=-1) * self.velocity_unit_km_s * 1e3

    @property
    def fuel_m_s(self) -> np.ndarray:
        """Total :math:`\\|\\Delta v_1\\| + \\|\\Delta v_2\\|`, m/s, (n_t, n_theta)."""
        return self.dv1_m_s + self.dv2_m_s

    @property
    def t_arrival_hours(self) -> np.ndarray:
        """Arrival times from apoapsis, hours."""
        return self.t_arrival * self.time_unit_s / 3600.0

    @property
    def phase(self) -> np.ndarray:
        """Normalised phase :math:`\\theta_0/2\\pi` (the paper's axis)."""
        return self.theta / (2 * np.pi)

    def _rows(self):
        return np.arange(self.t_arrival.size)

    @property
    def informed_range_sigma_km(self) -> np.ndarray:
        """:math:`\\sqrt{J_\\rho}` of :math:`\\mathbf u^*` per arrival time, km."""
        return self.range_sigma_km[self._rows(), self.informed]

    @property
    def informed_fuel_m_s(self) -> np.ndarray:
        """Total fuel of :math:`\\mathbf u^*` per arrival time, m/s."""
        return self.fuel_m_s[self._rows(), self.informed]

    @property
    def informed_percentile(self) -> np.ndarray:
        """Percent of maneuvers of the same arrival time with a *smaller* :math:`J_\\rho` than :math:`\\mathbf u^*` (0 = best)."""
        s = self.range_sigma_km
        return 100.0 * np.mean(s < self.informed_range_sigma_km[:, None], axis=1)

    @property
    def best(self) -> np.ndarray:
        """Index of the maneuver with the smallest :math:`J_\\rho` at ``t[-1]`` per arrival time (the *valley* of the
        slice; first one on ties), (n_t,) of int."""
        return np.argmin(self.range_sigma_km, axis=1)

    @property
    def best_range_sigma_km(self) -> np.ndarray:
        """Smallest :math:`\\sqrt{J_\\rho}` at ``t[-1]`` per arrival time, km, (n_t,)."""
        return self.range_sigma_km[self._rows(), self.best]

    def reselect(self, criterion: str) -> StationKeepingSurface:
        """The same surface with :math:`\\mathbf u^*` chosen by another reading of Eq. 25 (see :func:`informed_choice`)."""
        align, cand, pick = informed_choice(self.dv1, self.u_y, self.range_sigma_km, criterion)
        return replace(self, alignment=align, candidates=cand, informed=pick)

    @property
    def informed_fuel_percentile(self) -> np.ndarray:
        """Percent of maneuvers of the same arrival time that use *more* fuel than :math:`\\mathbf u^*`."""
        return 100.0 * np.mean(self.fuel_m_s > self.informed_fuel_m_s[:, None], axis=1)


def _check_torus(torus):
    if not callable(getattr(torus, "states", None)) or not hasattr(torus, "orbit"):
        raise validation.ArgumentTypeError("torus must provide states(theta0, t) and an orbit attribute (e.g. "
                                        f"cislunar.cr3bp.torus.InvariantTorus); got {type(torus).__name__}")
    return torus


def _torus_states(torus, theta, t):
    _check_torus(torus)
    out = np.asarray(torus.states(theta, t), dtype=float)
    if out.shape != (np.size(theta), np.size(t), 6):
        raise ValueError(f"torus.states returned shape {out.shape}; expected {(np.size(theta), np.size(t), 6)}")
    return out


def informed_choice(dv1, u_y, cost, criterion: str = "angle"):
    r"""Eq. 25 selection of the informed maneuver in each row (time-of-arrival slice).

    Eq. 25 as printed divides :math:`\mathbf u_y^T\mathbf u_{sk}` by its own absolute value, so it needs a reading.
    ``criterion="angle"`` (default) ranks by :math:`\cos\theta_u`, the direction alone: on a finer set of ring
    angles it can pick ever smaller burns next to the agent's own phase.  ``criterion="projection"`` ranks by the
    component of the burn along the MMD direction, :math:`\mathbf u_y^T\Delta\mathbf v_1/\|\mathbf u_y\|`
    ("projecting the guidance policy onto the candidates"), which has a limit as the set is refined.

    Parameters
    ----------
    dv1 : array_like (n_t, n_theta, 3)
        First burns of the station-keeping set.
    u_y : array_like (n_t, 3)
        MMD directions (any sign, any non-zero length).
    cost : array_like (n_t, n_theta)
        Result of the quick covariance analysis used to choose between the two candidates (smaller is better).
    criterion : {"angle", "projection"}
        Reading of Eq. 25 (see above).

    Returns
    -------
    alignment : ndarray (n_t, n_theta)
        ``"angle"``: :math:`\cos\theta_u = \mathbf u_y^T\Delta\mathbf v_1/(\|\mathbf u_y\|\|\Delta\mathbf v_1\|)`
        (0 for a zero burn); ``"projection"``: :math:`\mathbf u_y^T\Delta\mathbf v_1/\|\mathbf u_y\|` (units of
        ``dv1``).
    candidates : ndarray (n_t, 2) of int
        Indices with the largest and the smallest ``alignment`` (:math:`\theta_u` closest to 0 and to :math:`\pi`,
        or the largest burn component along :math:`+\mathbf u_y` and along :math:`-\mathbf u_y`).
    informed : ndarray (n_t,) of int
        The candidate with the smaller ``cost``.
    """
    dv1 = validation.as_array(dv1, "dv1", ndim=(3,), last=3)
    if dv1.shape[0] == 0 or dv1.shape[1] == 0:
        raise ValueError(f"dv1 must hold at least one burn per row and one row; got shape {dv1.shape}")
    u_y = validation.as_array(u_y, "u_y", ndim=(2,), last=3)
    cost = validation.as_array(cost, "cost", ndim=(2,))
    if u_y.shape[0] != dv1.shape[0]:
        raise ValueError(f"u_y must have one direction per row of dv1: shape ({dv1.shape[0]}, 3) for dv1 "
                         f"{dv1.shape}; got {u_y.shape}")
    if cost.shape != dv1.shape[:2]:
        raise ValueError(f"cost must have the shape (n_t, n_theta) = {dv1.shape[:2]} of dv1 {dv1.shape}; got "
                         f"{cost.shape}")
    validation.choice(criterion, "criterion", ("angle", "projection"))
    un = np.linalg.norm(u_y, axis=-1)
    if np.any(un == 0):
        raise ValueError("u_y must hold non-zero directions")
    along = np.einsum("jik,jk->ji", dv1, u_y / un[:, None])
    if criterion == "projection":
        align = along
    else:
        norms = np.linalg.norm(dv1, axis=-1)
        with np.errstate(invalid="ignore", divide="ignore"):
            align = np.where(norms > 0, along / norms, 0.0)
    cand = np.stack([np.argmax(align, axis=1), np.argmin(align, axis=1)], axis=1)
    rows = np.arange(dv1.shape[0])
    pick = np.where(cost[rows, cand[:, 0]] <= cost[rows, cand[:, 1]], cand[:, 0], cand[:, 1])
    return align, cand, pick


def station_keeping_surface(system: CR3BP, torus, theta, t_arrival, t_burn: float, t_final: float, *,
                            cadence: float | None = None, t_track_start: float | None = None,
                            agent_theta: float = 0.0, agent_offset=None, P0=None,
                            sigma_min_rad: float = AMOS_SIGMA_MIN_RAD, resolution_km: float = AMOS_RESOLUTION_KM,
                            mmd_horizon: str = "arrival", batched: bool = True,
                            progress: bool = True) -> StationKeepingSurface:
    """All two-burn maneuvers from the agent's state at ``t_burn`` to the torus surface, with covariance analyses.

    Parameters
    ----------
    system : CR3BP
    torus : object with ``states(theta0, t)`` and ``orbit``
        The station-keeping surface (e.g. :class:`cislunar.cr3bp.torus.InvariantTorus`).
    theta : array_like (n_theta,)
        Initial ring angles of the surface points, rad.
    t_arrival : array_like (n_t,)
        Strictly increasing arrival times from apoapsis, TU, all later than ``t_burn``.
    t_burn : float
        First-burn time from apoapsis, TU.
    t_final : float
        End of the covariance analysis (where :math:`J_\\rho` is read), TU, not before ``t_arrival[-1]``.
    cadence : float, optional
        Measurement interval, TU (default one hour).
    t_track_start : float, optional
        Start of tracking (first measurement, where ``P0`` applies), TU from apoapsis, not after ``t_burn``
        (default ``t_burn``: the covariance analysis starts with the first burn).
    agent_theta : float
        The agent is on the torus trajectory of ring angle ``agent_theta`` (rad) until the first burn.
    agent_offset : array_like (6,), optional
        Added to the agent state at ``t_track_start`` (a station-keeping error to correct); default none.
    P0 : array_like (12, 12), optional
        Covariance at ``t_track_start`` (default :func:`cislunar.guidance.ssat.initial_covariance`).
    sigma_min_rad, resolution_km : float
        Eq. 20 noise parameters.
    mmd_horizon : {"arrival", "final"}
        End :math:`\\tau_f` of the MMD coast (Eq. 24) for :math:`\\mathbf u_y`: each row's arrival time (default) or
        ``t_final`` (where :math:`J_\\rho` is read); the paper does not say which.
    batched : bool
        One heyoka batch per arrival time (default) or a plain loop over maneuvers (for benchmarks).
    progress : bool
        Progress bar over arrival times.
    """

    _system(system)
    _check_torus(torus)
    theta = validation.as_array(theta, "theta", ndim=(1,))
    if theta.size < 1:
        raise ValueError("theta must hold at least one ring angle")
    t_arr = validation.as_array(t_arrival, "t_arrival", ndim=(1,))
    if t_arr.size < 1 or np.any(np.diff(t_arr) <= 0):
        raise ValueError("t_arrival must be a non-empty, strictly increasing array of times (TU)")
    t_burn = validation.real(t_burn, "t_burn")
    t_final = validation.real(t_final, "t_final")
    if not t_arr[0] > t_burn:
        raise ValueError(f"t_arrival must be later than t_burn = {t_burn}; got first arrival {t_arr[0]}")
    if t_final < t_arr[-1]:
        raise ValueError(f"t_final must not precede the last arrival {t_arr[-1]}; got {t_final}")
    validation.choice(mmd_horizon, "mmd_horizon", ("arrival", "final"))
    dt = 3600.0 / system.time_unit_s if cadence is None else validation.positive(cadence, "cadence")
    t_start = t_burn if t_track_start is None else validation.real(t_track_start, "t_track_start")
    if t_start > t_burn:
        raise ValueError(f"t_track_start must not be after t_burn = {t_burn}; got {t_start}")
    agent_theta = validation.real(agent_theta, "agent_theta")
    if agent_offset is not None:
        agent_offset = validation.as_array(agent_offset, "agent_offset", shape=(6,))
    if P0 is not None:
        _initial_cov(P0)
    _noise(sigma_min_rad, resolution_km)
    batched = validation.boolean(batched, "batched")
    progress = validation.boolean(progress, "progress")
    n_meas = int(np.floor((t_final - t_start) / dt + 1e-9)) + 1
    t = t_start + dt * np.arange(n_meas)
    if t[-1] < t_final - 1e-12:
        t = np.r_[t, t_final]
    P0 = initial_covariance(system) if P0 is None else P0
    xa0 = _torus_states(torus, np.array([agent_theta]), np.array([t_start]))[0, 0]
    if agent_offset is not None:
        xa0 = xa0 + agent_offset
    xa_burn = xa0 if t_start == t_burn else propagate(system, xa0, np.array([t_start, t_burn])).x[-1]
    goal = _torus_states(torus, theta, t_arr)  # (n_theta, n_t, 6)
    target = target_trajectory(system, torus.orbit.x0, t)
    # unmaneuvered agent and target at the arrival times for MMD (Eq. 24)
    t_mmd = t_arr if mmd_horizon == "arrival" else np.full(t_arr.shape, t_final)
    t_nom = np.unique(np.r_[t_burn, t_mmd])
    k_mmd = np.searchsorted(t_nom, t_mmd)
    nominal = propagate_with_impulses(system, xa_burn, t_nom)
    tgt_burn = (target.x[0, 0] if t_start == t_burn
                else propagate(system, target.x[0, 0], np.array([t_start, t_burn])).x[-1])
    tgt_mmd = propagate(system, tgt_burn, t_nom).x
    nt, nth = t_arr.size, theta.size
    dv1 = np.empty((nt, nth, 3))
    dv2 = np.empty((nt, nth, 3))
    miss = np.empty((nt, nth))
    sig = np.empty((nt, nth))
    sig_arr = np.empty((nt, nth))
    u_y = np.empty((nt, 3))
    if batched:
        agent_x = np.empty((nt, nth, t.size, 6))
        agent_stm = np.empty((nt, nth, t.size, 6, 6))
    k_arr = np.searchsorted(t, t_arr, side="right") - 1
    for j in _progress(range(nt), total=nt, desc="station-keeping surface", enabled=progress):
        _, Ha, _ = AZIMUTH_ELEVATION.evaluate(nominal.x[0, k_mmd[j]], tgt_mmd[k_mmd[j]])
        u_y[j] = mmd_direction(mmd_matrix(nominal.stm[0, k_mmd[j]], Ha))
        groups = [np.arange(nth)] if batched else [np.array([i]) for i in range(nth)]
        for g in groups:
            d1, d2, x1 = two_burn_transfer(system, xa_burn, t_burn, t_arr[j], goal[g, j])
            dv1[j, g], dv2[j, g] = d1, d2
            miss[j, g] = np.linalg.norm(x1[:, :3] - goal[g, j, :3], axis=1)
            ag = propagate_with_impulses(system, np.broadcast_to(xa0, (g.size, 6)), t,
                                         [(t_burn, d1), (float(t_arr[j]), d2)])
            if batched:  # one covariance analysis for the whole surface below
                agent_x[j], agent_stm[j] = ag.x, ag.stm
                continue
            cov = ssat_covariance(system, ag, target, P0, sigma_min_rad=sigma_min_rad, resolution_km=resolution_km)
            sig[j, g] = cov.final_range_sigma_km
            sig_arr[j, g] = cov.range_sigma_km[:, k_arr[j]]
    if batched:
        ag = ImpulsiveTrajectory(t, agent_x.reshape(nt * nth, t.size, 6), agent_stm.reshape(nt * nth, t.size, 6, 6))
        cov = ssat_covariance(system, ag, target, P0, sigma_min_rad=sigma_min_rad, resolution_km=resolution_km)
        rs = cov.range_sigma_km.reshape(nt, nth, t.size)
        sig[:] = rs[..., -1]
        sig_arr[:] = rs[np.arange(nt), :, k_arr]
    align, cand, pick = informed_choice(dv1, u_y, sig)
    return StationKeepingSurface(theta=theta, t_arrival=t_arr, t_burn=t_burn, t=t, agent_x0=xa0, dv1=dv1, dv2=dv2,
                                 range_sigma_km=sig, range_sigma_at_arrival_km=sig_arr, u_y=u_y, alignment=align,
                                 candidates=cand, informed=pick, transfer_miss=miss,
                                 velocity_unit_km_s=system.velocity_unit_km_s, time_unit_s=system.time_unit_s)


def first_burn_only_range_sigma_km(system: CR3BP, surface: StationKeepingSurface, target_apolune_state, *,
                                   informed=None, P0=None, sigma_min_rad: float = AMOS_SIGMA_MIN_RAD,
                                   resolution_km: float = AMOS_RESOLUTION_KM) -> np.ndarray:
    """:math:`\\sqrt{J_\\rho}` at ``surface.t[-1]`` of each slice's chosen maneuver flown with its first burn only.

    The paper attributes a local peak on its :math:`\\mathbf u^*` line to the second burn, "not accounted for in our
    prediction".  This reruns the covariance analysis of each slice's maneuver without the second burn (the agent
    coasts off the torus after the first), on the surface's measurement grid, so that the ratio
    ``surface.informed_range_sigma_km / first_burn_only_range_sigma_km(...)`` isolates the second burn's effect.

    Parameters
    ----------
    system : CR3BP
        The system the surface was computed in.
    surface : StationKeepingSurface
    target_apolune_state : array_like (6,)
        Target state at apoapsis (time 0), rotating frame, LU and LU/TU (``torus.orbit.x0``).
    informed : array_like (n_t,) of int, optional
        Ring-angle index of the maneuver of each slice (default ``surface.informed``).
    P0 : array_like (12, 12), optional
        Covariance at ``surface.t[0]`` (default :func:`cislunar.guidance.ssat.initial_covariance`); must be the one the
        surface was computed with for the ratio to mean anything.
    sigma_min_rad, resolution_km : float
        Eq. 20 noise parameters (as for :func:`station_keeping_surface`).

    Returns
    -------
    ndarray (n_t,)
        Range 1-sigma at ``surface.t[-1]``, km.
    """
    _system(system)
    validation.instance(surface, "surface", StationKeepingSurface, "a cislunar.papers.greaves_scheeres_2023.station_keeping.StationKeepingSurface")
    x_tgt = validation.as_state(target_apolune_state, "target_apolune_state", batch=False)
    nt, nth = surface.t_arrival.size, surface.theta.size
    if informed is None:
        informed = surface.informed
    else:
        informed = validation.as_array(informed, "informed", shape=(nt,))
        if np.any(informed != np.round(informed)) or np.any(informed < 0) or np.any(informed >= nth):
            raise ValueError(f"informed must hold ring-angle indices in 0..{nth - 1}, one per slice ({nt})")
        informed = informed.astype(int)
    if P0 is not None:
        _initial_cov(P0)
    _noise(sigma_min_rad, resolution_km)
    P0 = initial_covariance(system) if P0 is None else P0
    rows = np.arange(nt)
    target = target_trajectory(system, x_tgt, surface.t)
    agent = propagate_with_impulses(system, np.tile(surface.agent_x0, (nt, 1)), surface.t,
                                    [(surface.t_burn, surface.dv1[rows, informed])])
    cov = ssat_covariance(system, agent, target, P0, sigma_min_rad=sigma_min_rad, resolution_km=resolution_km)
    return cov.final_range_sigma_km


# --------------------------------------------------------------------------------------------------------------
# full-filter Monte Carlo (beyond the paper)
# --------------------------------------------------------------------------------------------------------------
def execution_sigma(dv, sigma_abs: float, sigma_rel: float) -> np.ndarray:
    """1-sigma per-axis execution error of a burn: :math:`\\sqrt{\\sigma_{abs}^2 + (\\sigma_{rel}\\|\\Delta v\\|)^2}` (units of ``dv``).

    A zero burn is a burn not made: its error is 0, not :math:`\\sigma_{abs}`.
    """
    dv = validation.as_array(dv, "dv", last=3, min_size=1)
    a = validation.positive(sigma_abs, "sigma_abs", allow_zero=True)
    r = validation.positive(sigma_rel, "sigma_rel", allow_zero=True)
    norm = np.linalg.norm(dv, axis=-1)
    return np.where(norm > 0, np.sqrt(a**2 + (r * norm) ** 2), 0.0)


@dataclass(frozen=True)
class FilterScenario:
    """Everything a filter trial needs (picklable).

    Attributes
    ----------
    system : CR3BP
    t : ndarray (N,)
        Measurement times, TU.
    agent_x0, target_x0 : ndarray (6,)
        True states at ``t[0]`` (agent before the first burn).
    burns : tuple of (float, ndarray (3,))
        Planned burns (time TU, dv LU/TU); the first at ``t[0]``.
    P0 : ndarray (12, 12)
    exec_sigma_abs, exec_sigma_rel : float
        Execution error model (LU/TU, fraction), see :func:`execution_sigma`.
    sigma_min_rad, resolution_km : float
        Eq. 20 noise parameters.
    label : str
    """

    system: CR3BP
    t: np.ndarray
    agent_x0: np.ndarray
    target_x0: np.ndarray
    burns: tuple
    P0: np.ndarray
    exec_sigma_abs: float
    exec_sigma_rel: float
    sigma_min_rad: float = AMOS_SIGMA_MIN_RAD
    resolution_km: float = AMOS_RESOLUTION_KM
    label: str = ""

    def __post_init__(self):
        _system(self.system)
        t = validation.time_grid(self.t, "t", increasing=True)
        agent_x0 = validation.as_state(self.agent_x0, "agent_x0", batch=False)
        target_x0 = validation.as_state(self.target_x0, "target_x0", batch=False)
        burns = self.burns
        if isinstance(burns, (str, bytes, dict)) or not isinstance(burns, (tuple, list)):
            raise validation.ArgumentTypeError(f"burns must be a sequence of (time, dv) pairs; got "
                                            f"{type(burns).__name__}")
        checked = []
        for k, item in enumerate(burns):
            if not isinstance(item, (tuple, list)) or len(item) != 2:
                raise ValueError(f"burns[{k}] must be a (time, dv) pair; got {item!r:.60}")
            tb = validation.real(item[0], f"burns[{k}] time")
            if not t[0] <= tb <= t[-1]:
                raise ValueError(f"burns[{k}] time {tb} must lie within the grid t [{t[0]}, {t[-1]}] TU")
            checked.append((tb, validation.as_array(item[1], f"burns[{k}] dv", shape=(3,))))
        P0 = validation.spd(self.P0, "P0", n=12)
        a = validation.positive(self.exec_sigma_abs, "exec_sigma_abs", allow_zero=True)
        r = validation.positive(self.exec_sigma_rel, "exec_sigma_rel", allow_zero=True)
        smin, dres = _noise(self.sigma_min_rad, self.resolution_km)
        validation.instance(self.label, "label", str)
        for name, value in (("t", t), ("agent_x0", agent_x0), ("target_x0", target_x0), ("burns", tuple(checked)),
                            ("P0", P0), ("exec_sigma_abs", a), ("exec_sigma_rel", r), ("sigma_min_rad", smin),
                            ("resolution_km", dres)):
            object.__setattr__(self, name, value)


def filter_scenario(surface: StationKeepingSurface, j: int, i: int, target_x0, system: CR3BP, *,
                    exec_sigma_abs_m_s: float = 1e-3, exec_sigma_rel: float = 0.01, P0=None,
                    label: str = "") -> FilterScenario:
    """The :class:`FilterScenario` of surface maneuver ``[j, i]`` (arrival ``t_arrival[j]``, ring angle ``theta[i]``).

    ``target_x0`` is the target state at ``surface.t[0]`` (start of tracking); execution errors: ``exec_sigma_abs_m_s`` (m/s) and
    ``exec_sigma_rel`` (fraction of the burn) per axis.
    """
    validation.instance(surface, "surface", StationKeepingSurface,
                     "a cislunar.papers.greaves_scheeres_2023.station_keeping.StationKeepingSurface (from station_keeping_surface)")
    _system(system)
    j = validation.integer(j, "j", minimum=0)
    i = validation.integer(i, "i", minimum=0)
    if P0 is not None:
        P0 = validation.spd(P0, "P0", n=12)
    validation.instance(label, "label", str)
    if not (0 <= j < surface.t_arrival.size and 0 <= i < surface.theta.size):
        raise ValueError(f"(j, i) must index the surface {surface.range_sigma_km.shape}; got ({j}, {i})")
    a = validation.positive(exec_sigma_abs_m_s, "exec_sigma_abs_m_s", allow_zero=True) / (system.velocity_unit_km_s * 1e3)
    r = validation.positive(exec_sigma_rel, "exec_sigma_rel", allow_zero=True)
    burns = ((float(surface.t_burn), surface.dv1[j, i].copy()), (float(surface.t_arrival[j]), surface.dv2[j, i].copy()))
    return FilterScenario(system=system, t=surface.t.copy(), agent_x0=surface.agent_x0.copy(),
                          target_x0=validation.as_state(target_x0, "target_x0", batch=False).copy(), burns=burns,
                          P0=initial_covariance(system) if P0 is None else np.asarray(P0, float), exec_sigma_abs=a,
                          exec_sigma_rel=r, label=label)


@dataclass(frozen=True)
class FilterTrialResult:
    """One EKF run against its truth.

    Attributes
    ----------
    nees : ndarray (N,)
        :math:`e^TP^{-1}e` of the 12-dimensional SSAT state after each measurement update.
    range_error_km : ndarray (N,)
        Estimated minus true range along the true line of sight, km.
    range_sigma_km : ndarray (N,)
        Filter's :math:`\\sqrt{J_\\rho}`, km.
    failure : str
        Exception text if the filter failed numerically, else "".
    """

    nees: np.ndarray
    range_error_km: np.ndarray
    range_sigma_km: np.ndarray
    failure: str = ""


def _iterated_update(system, x_prior, P, y, sc, n_iter):
    """Iterated EKF update (Gauss-Newton on the MAP cost) of azimuth/elevation; Joseph-form covariance at the end.

    The angles are strongly nonlinear at the start of a track (tens of km of position uncertainty at a few hundred
    km range against micro-radian noise), where a single-linearisation EKF update is inconsistent; relinearising at
    the updated estimate removes that (Bell & Cathey 1993).  Inputs are trusted (internal to :func:`filter_trial`);
    the 2x2 innovation covariance is inverted directly.
    """
    xi = x_prior.copy()
    scale = np.sqrt(np.diag(P))
    for _ in range(max(1, n_iter)):
        val, Ha, Ht = AZIMUTH_ELEVATION.evaluate(xi[:6], xi[6:])
        H = np.hstack([Ha, Ht])
        s_est = angular_sigma(np.linalg.norm(xi[6:9] - xi[:3]) * system.length_unit_km, sc.sigma_min_rad,
                              sc.resolution_km)
        PHt = P @ H.T
        S = H @ PHt + s_est**2 * np.eye(2)
        K = PHt @ np.linalg.inv(S)
        x_new = x_prior + K @ (AZIMUTH_ELEVATION.residual(y, val) - H @ (x_prior - xi))
        step = np.max(np.abs(x_new - xi) / scale)  # in prior standard deviations
        xi = x_new
        if step < 1e-6:
            break
    IKH = np.eye(12) - K @ H
    P_post = IKH @ P @ IKH.T + s_est**2 * (K @ K.T)
    return xi, 0.5 * (P_post + P_post.T)


def filter_trial(rng: np.random.Generator, scenario: FilterScenario, *, n_iter: int = 10) -> FilterTrialResult:
    """One EKF trial of SSAT with the scenario's two burns, execution errors and Eq. 20 angle noise.

    Truth: the agent flies the planned burns plus Gaussian execution errors, the target its natural orbit.
    Filter: iterated extended Kalman filter (``n_iter`` relinearisations per update; 1 = plain EKF) on the
    12-dimensional inertial SSAT state, initial estimate drawn from
    :math:`N(\\mathbf x_{true}, P_0)`; between epochs the estimate and its STM are propagated by heyoka; at a
    burn the *planned* :math:`\\Delta\\mathbf v` is added to the estimate and the execution covariance to
    :math:`P` (the filter knows the error model); azimuth/elevation updates every grid time (Joseph form).
    """
    validation.rng(rng)
    validation.instance(scenario, "scenario", FilterScenario, "a cislunar.papers.greaves_scheeres_2023.station_keeping.FilterScenario")
    n_iter = validation.integer(n_iter, "n_iter", minimum=1)
    sc = scenario
    sys_ = sc.system
    t = sc.t
    burn_t = [b[0] for b in sc.burns]
    epochs = np.unique(np.r_[t, burn_t])
    # truth with actual (perturbed) burns
    actual = []
    for tb, dv in sc.burns:
        s = execution_sigma(dv, sc.exec_sigma_abs, sc.exec_sigma_rel)
        actual.append((tb, dv + s * rng.standard_normal(3)))
    truth_a = propagate_with_impulses(sys_, sc.agent_x0, t, actual).x[0]
    truth_t = propagate(sys_, sc.target_x0, t).x
    sig = angular_sigma(np.linalg.norm(truth_t[:, :3] - truth_a[:, :3], axis=1) * sys_.length_unit_km,
                        sc.sigma_min_rad, sc.resolution_km)
    y = AZIMUTH_ELEVATION(truth_a, truth_t) + sig[:, None] * rng.standard_normal((t.size, 2))
    L0 = np.linalg.cholesky(sc.P0)
    x_true0 = np.r_[sc.agent_x0, sc.target_x0]
    x = x_true0 + L0 @ rng.standard_normal(12)
    P = sc.P0.copy()
    N = t.size
    nees = np.full(N, np.nan)
    err = np.full(N, np.nan)
    sdev = np.full(N, np.nan)
    k = 0
    try:
        for m, te in enumerate(epochs):
            if m > 0:
                tr = propagate_stm(sys_, np.vstack([x[:6], x[6:]]), np.array([epochs[m - 1], te]))
                Phi = np.zeros((12, 12))
                Phi[:6, :6], Phi[6:, 6:] = tr.stm[0, -1], tr.stm[1, -1]
                x = np.r_[tr.x[0, -1], tr.x[1, -1]]
                P = Phi @ P @ Phi.T
            for tb, dv in sc.burns:
                if tb == te:
                    x[3:6] += dv
                    s = execution_sigma(dv, sc.exec_sigma_abs, sc.exec_sigma_rel)
                    P[3:6, 3:6] += s**2 * np.eye(3)
            if k < N and t[k] == te:
                x, P = _iterated_update(sys_, x, P, y[k], sc, n_iter)
                e = x - np.r_[truth_a[k], truth_t[k]]
                nees[k] = _nees(x, P, np.r_[truth_a[k], truth_t[k]])
                M = range_projection(np.r_[truth_a[k], truth_t[k]])
                err[k] = (M @ e) * sys_.length_unit_km
                sdev[k] = np.sqrt(M @ P @ M) * sys_.length_unit_km
                k += 1
    except (ValueError, RuntimeError, np.linalg.LinAlgError) as exc:
        return FilterTrialResult(nees, err, sdev, str(exc)[:200])
    return FilterTrialResult(nees, err, sdev)


def random_choice_trial(rng: np.random.Generator, scenarios) -> FilterTrialResult:
    """:func:`filter_trial` of a scenario drawn uniformly from ``scenarios`` with the trial's own generator.

    Models an *uninformed* station-keeping choice: the target phase is picked without regard to information.
    """
    validation.rng(rng)
    scenarios = validation.sequence_of(scenarios, "scenarios", FilterScenario, "cislunar.papers.greaves_scheeres_2023.station_keeping.FilterScenario")
    return filter_trial(rng, scenarios[int(rng.integers(len(scenarios)))])
