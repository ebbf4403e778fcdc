r"""Studies of SSAT and MMD guidance (Greaves & Scheeres AMOS 2023, Secs. 3.1-4.1; notebook 07).

Each function runs one study of the chapter and returns a frozen result object:

* :func:`coordinate_checks`: the SSAT coordinate identities (Eqs. 1-7) on random states and covariances;
* :func:`demonstration_pair`: the agent-target pair on the 9:2 NRHO and its covariance analysis without maneuver;
* :func:`equation_checks`: Eqs. 11 and 18 typed in from the paper against the package;
* :func:`surrogate_check`: the MMD eigenvector (Eqs. 23-24) against brute-force maximisers of its surrogate;
* :func:`policy_study`: MMD, the true minimiser of :math:`J_\rho` and the perpendicular heuristic over coast times;
* :func:`direction_map`: :math:`\sqrt{J_\rho}` over the sphere of burn directions for one coast;
* :func:`timing_study`: computation time of MMD and of the true minimiser;
* :func:`tracking_arc_study`: the same comparison with a tracking arc before the burn, over arc lengths;
* :func:`qpo_pair_study`: the comparison with the agent on the 215-km quasi-periodic torus.

The three sweeps (:func:`policy_study`, :func:`tracking_arc_study`, :func:`qpo_pair_study`) take ``executor=`` (from
:func:`cislunar.utils.executors.open_executor`; ``None`` runs serially) and run one task per burn size, arc length or
ring angle through :func:`cislunar.utils.montecarlo.map_tasks`; every task is deterministic, so the results do not
depend on the executor.

Units: times in hours where named ``*_hours``/``*_h``, otherwise CR3BP time units (TU); :math:`\sqrt{J_\rho}` in
km; burn magnitudes in m/s where named ``*_m_s``; all states in the Earth-Moon rotating frame (LU, LU/TU).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from cislunar.cr3bp.dynamics import CR3BP, check_system
from cislunar.cr3bp.orbits import PeriodicOrbit
from cislunar.cr3bp.propagation import propagate
from cislunar.cr3bp.torus import InvariantTorus
from cislunar.guidance import ssat
from cislunar.sensing.measurements import AZIMUTH_ELEVATION
from cislunar.utils import validation
from cislunar.utils.montecarlo import map_tasks

__all__ = [
    "CoordinateChecks",
    "DemonstrationPair",
    "DirectionMap",
    "EquationChecks",
    "PolicyStudy",
    "QpoPairStudy",
    "SurrogateCheck",
    "TimingStudy",
    "TrackingArcStudy",
    "coordinate_checks",
    "demonstration_pair",
    "direction_map",
    "equation_checks",
    "leading_hours",
    "policy_study",
    "qpo_pair_study",
    "surrogate_check",
    "timing_study",
    "tracking_arc_study",
]


def _hour(system):
    return 3600.0 / system.time_unit_s


def _executor(value):
    """``None`` (serial) or an executor with ``submit`` (checked before any work)."""
    if value is not None and not callable(getattr(value, "submit", None)):
        raise validation.ArgumentTypeError(f"executor must be None or have a submit(fn, *args) method (a "
                                           f"concurrent.futures executor or a Dask Client); got {type(value).__name__}")
    return value


def _hours_on_grid(value, name, lo, hi=None):
    """Whole hours (rounded to the nearest hour) in ``[lo, hi]`` (``hi=None``: no upper bound) from a non-empty 1-D
    array, as a list of int."""
    hours = [int(np.rint(h)) for h in validation.as_array(value, name, ndim=(1,), min_size=1)]
    if min(hours) < lo or (hi is not None and max(hours) > hi):
        raise ValueError(f"{name} must lie in [{lo}, {'inf' if hi is None else hi}] h; got {value!r:.80}")
    return hours


def _result_key(results, value, name, what):
    """``value`` as a key of ``results`` (a study's dict), refused by name if it is not a number or was not run."""
    key = validation.real(value, name)
    if key not in results:
        raise ValueError(f"{name} must be one of the {what} of the study {tuple(results)}; got {value!r}")
    return key


def _positive_values(value, name):
    """A non-empty 1-D array of positive finite values."""
    arr = validation.as_array(value, name, ndim=(1,), min_size=1)
    if np.any(arr <= 0):
        raise ValueError(f"{name} must be positive; got {value!r:.80}")
    return arr


def leading_hours(coast_hours, ok) -> float:
    """Longest coast (h) up to which ``ok`` holds for every shorter coast (0 if not even the first).

    Parameters
    ----------
    coast_hours : array_like (m,)
        Coast times, h, increasing.
    ok : array_like (m,) of bool
    """
    coast_hours = validation.as_array(coast_hours, "coast_hours", ndim=(1,), min_size=1)
    try:
        ok = np.asarray(ok)
    except (TypeError, ValueError) as exc:  # ragged nested sequences
        raise validation.ArgumentTypeError(f"ok must be an array of booleans; got {type(ok).__name__}") from exc
    if ok.dtype.kind != "b":
        raise validation.ArgumentTypeError(f"ok must be an array of booleans; got dtype {ok.dtype}")
    if ok.shape != coast_hours.shape:
        raise ValueError(f"ok must have the shape of coast_hours {coast_hours.shape}; got {ok.shape}")
    n = ok.size if ok.all() else int(np.argmin(ok))
    return float(coast_hours[n - 1]) if n else 0.0


# ---------------------------------------------------------------------------------------------------------------
# Eqs. 1-7: coordinates
# ---------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class CoordinateChecks:
    """SSAT coordinate identities on random states and a random covariance (all relative errors, dimensionless).

    Attributes
    ----------
    state_round_trip : float
        Max :math:`|T^{-1}T\\mathbf x - \\mathbf x|` over the states.
    covariance_round_trip : float
        Max :math:`|T^{-1}(TPT^T)T^{-T} - P|` / max :math:`|P|` (Eq. 7).
    relative_block : float
        Max difference of the relative blocks of :math:`TPT^T` and :math:`T_aPT_a^T`, over max :math:`|TPT^T|`.
    range_variance_spread : float
        Spread (max - min) / mean of :math:`J_\\rho` evaluated in the inertial, relative and agent-based coordinates.
    """

    state_round_trip: float
    covariance_round_trip: float
    relative_block: float
    range_variance_spread: float


def coordinate_checks(rng: np.random.Generator, n_states: int = 4) -> CoordinateChecks:
    """Check Eqs. 1-7 on ``n_states`` random 12-dimensional states and one random SPD covariance drawn from ``rng``."""
    validation.rng(rng)
    n_states = validation.integer(n_states, "n_states", minimum=1)
    x = rng.standard_normal((n_states, 12))
    A = rng.standard_normal((12, 12))
    P = A @ A.T + 12 * np.eye(12)
    err_state = np.max(np.abs(ssat.from_relative(ssat.to_relative(x)) - x))
    err_cov = np.max(np.abs(ssat.inertial_covariance(ssat.relative_covariance(P)) - P)) / np.max(P)
    P_rel, P_agent = ssat.relative_covariance(P), ssat.agent_based_covariance(P)
    block = np.max(np.abs(P_rel[6:, 6:] - P_agent[6:, 6:])) / np.max(np.abs(P_rel))
    J3 = [ssat.range_variance(C, x[0], c) for C, c in ((P, "inertial"), (P_rel, "relative"), (P_agent, "agent"))]
    return CoordinateChecks(float(err_state), float(err_cov), float(block), float(np.ptp(J3) / np.mean(J3)))


# ---------------------------------------------------------------------------------------------------------------
# The demonstration pair
# ---------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class DemonstrationPair:
    """Target on a periodic orbit, agent on the same orbit a phase lag behind, and their covariance analysis.

    Attributes
    ----------
    lag_hours : float
        Phase lag of the agent behind the target, h.
    agent_x0, target_x0 : ndarray (6,)
        States at the burn epoch ``t[0]`` (rotating frame, LU, LU/TU).
    t : ndarray (N,)
        Hourly measurement grid from the burn epoch, TU.
    agent, target : ImpulsiveTrajectory
        Unmaneuvered trajectories on ``t`` with their STMs.
    P0 : ndarray (12, 12)
        Initial covariance of the inertial SSAT state.
    baseline : SSATCovariance
        Covariance analysis without maneuver (:func:`cislunar.guidance.ssat.ssat_covariance`).
    ekf_difference : dict
        Coordinates (``"inertial"``, ``"relative"``, ``"agent"``) -> max relative difference of :math:`J_\\rho` from the
        Joseph-form EKF recursion against the square-root information form.
    lead_hours : float
        Burn epoch before the target's apolune, h.
    hours : ndarray (N,)
        Measurement times since the burn epoch, h.
    """

    lag_hours: float
    agent_x0: np.ndarray
    target_x0: np.ndarray
    t: np.ndarray
    agent: ssat.ImpulsiveTrajectory
    target: ssat.ImpulsiveTrajectory
    P0: np.ndarray
    baseline: ssat.SSATCovariance
    ekf_difference: dict
    lead_hours: float
    hours: np.ndarray

    @property
    def first_hour_drop_percent(self) -> float:
        """Drop of :math:`\\sqrt{J_\\rho}` over the first hour of measurements, percent."""
        s = self.baseline.range_sigma_km[0]
        return float(100 * (1 - s[1] / s[0]))


def demonstration_pair(system: CR3BP, orbit, *, lead_days: float = 1.0, apolune_range_km: float = 215.0,
                       days: int = 3) -> DemonstrationPair:
    """The demonstration pair of notebook 07.

    The target flies ``orbit`` (its ``x0`` at apolune); the agent flies the same orbit with the phase lag that puts
    it ``apolune_range_km`` from the target at the target's apolune (found by Brent's method on 0.05-2 h).  Both
    start ``lead_days`` before apolune; azimuth/elevation every hour for ``days`` days, initial covariance
    :func:`cislunar.guidance.ssat.initial_covariance`, no process noise.
    """
    check_system(system)
    validation.instance(orbit, "orbit", PeriodicOrbit)
    lead_days = validation.positive(lead_days, "lead_days")
    apolune_range_km = validation.positive(apolune_range_km, "apolune_range_km")
    days = validation.integer(days, "days", minimum=1)
    HR, L = _hour(system), system.length_unit_km
    x_apo = validation.as_state(orbit.x0, "orbit.x0", batch=False)

    def miss(lag_hours):
        back = propagate(system, x_apo, np.array([0.0, -lag_hours * HR])).x[-1]
        return np.linalg.norm(back[:3] - x_apo[:3]) * L - apolune_range_km

    lag_h = brentq(miss, 0.05, 2.0, xtol=1e-12)
    t_lead = lead_days * 86400.0 / system.time_unit_s
    xa_apo = propagate(system, x_apo, np.array([0.0, -lag_h * HR])).x[-1]
    xt0 = propagate(system, x_apo, np.array([0.0, -t_lead])).x[-1]
    xa0 = propagate(system, xa_apo, np.array([0.0, -t_lead])).x[-1]
    P0 = ssat.initial_covariance(system)
    t = np.arange(0, 24 * days + 1) * HR
    tgt = ssat.propagate_with_impulses(system, xt0, t)
    agt = ssat.propagate_with_impulses(system, xa0, t)
    base = ssat.ssat_covariance(system, agt, tgt, P0)
    ekf = {c: float(np.max(np.abs(ssat.ssat_covariance_ekf(system, agt, tgt, P0, coordinates=c)[1] / base.J_rho[0]
                                  - 1))) for c in ("inertial", "relative", "agent")}
    return DemonstrationPair(float(lag_h), xa0, xt0, t, agt, tgt, P0, base, ekf, lead_days * 24.0, (t - t[0]) / HR)


# ---------------------------------------------------------------------------------------------------------------
# Eqs. 11 and 18 as printed
# ---------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class EquationChecks:
    """Eqs. 11 (acceleration) and 18 (angle Jacobian) typed in from the paper against the package (relative errors)."""

    eq11: float
    eq18: float


def equation_checks(system: CR3BP, agent_x, target_x) -> EquationChecks:
    """Eq. 11 with :math:`\\boldsymbol\\omega = \\hat{\\mathbf e}_z` at ``agent_x`` and Eq. 18 at the pair, against
    ``system.eom`` and :data:`cislunar.sensing.measurements.AZIMUTH_ELEVATION` (target block :math:`H_\\theta`, agent
    block :math:`-H_\\theta`)."""
    check_system(system)
    xa = validation.as_state(agent_x, "agent_x", batch=False)
    xt = validation.as_state(target_x, "target_x", batch=False)
    mu, w = system.mu, np.array([0.0, 0.0, 1.0])
    r, v = xa[:3], xa[3:]
    rho1, rho2 = r - [-mu, 0, 0], r - [1 - mu, 0, 0]
    a11 = (-2 * np.cross(w, v) - np.cross(w, np.cross(w, r)) - (1 - mu) * rho1 / np.linalg.norm(rho1) ** 3
           - mu * rho2 / np.linalg.norm(rho2) ** 3)
    err11 = np.max(np.abs(a11 - np.asarray(system.eom(xa))[3:])) / np.max(np.abs(a11))
    rx, ry, rz = xt[:3] - xa[:3]
    rr, rxy = np.sqrt(rx**2 + ry**2 + rz**2), np.sqrt(rx**2 + ry**2)
    H18 = np.array([[-ry / rxy**2, rx / rxy**2, 0, 0, 0, 0],
                    [-rx * rz / (rr**2 * rxy), -ry * rz / (rr**2 * rxy), rxy / rr**2, 0, 0, 0]])
    _, Ha, Ht = AZIMUTH_ELEVATION.evaluate(xa, xt)
    err18 = max(np.max(np.abs(Ht - H18)), np.max(np.abs(Ha + H18))) / np.max(np.abs(H18))
    return EquationChecks(float(err11), float(err18))


# ---------------------------------------------------------------------------------------------------------------
# Eqs. 23-24: the surrogate
# ---------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class SurrogateCheck:
    """The MMD eigenvector against brute-force maximisers over a Fibonacci sphere.

    Attributes
    ----------
    coast_hours : float
    eigenvalues : ndarray (3,)
        Of :math:`Q` (Eq. 24), ascending, rad^2 per (LU/TU)^2.
    direction : ndarray (3,)
        MMD unit eigenvector.
    angle_quadratic_deg, angle_nonlinear_deg : float
        Angle (deg, either sign) between the eigenvector and the sphere direction maximising
        :math:`\\mathbf u^TQ\\mathbf u`, and the nonlinear change of the final angles for a 0.1 mm/s burn.
    spacing_deg : float
        Grid spacing of the sphere, deg.
    Q, H_agent : ndarray
        Eq. 24 matrix (3, 3) and the agent block of the final Jacobian (2, 6).
    agent_stm : ndarray (6, 6)
        Agent STM over the coast.
    """

    coast_hours: float
    eigenvalues: np.ndarray
    direction: np.ndarray
    angle_quadratic_deg: float
    angle_nonlinear_deg: float
    spacing_deg: float
    Q: np.ndarray
    H_agent: np.ndarray
    agent_stm: np.ndarray

    @property
    def within_grid(self) -> bool:
        """Both maximisers lie within one grid spacing of the eigenvector."""
        return bool(max(self.angle_quadratic_deg, self.angle_nonlinear_deg) <= self.spacing_deg)


def surrogate_check(system: CR3BP, pair: DemonstrationPair, coast_hours: int = 12, n_grid: int = 3000,
                    probe_m_s: float = 1e-4) -> SurrogateCheck:
    """MMD (Eq. 23 read as the eigenvector of Eq. 24) for a coast of ``coast_hours`` against brute force over a
    ``n_grid``-direction Fibonacci sphere (``probe_m_s`` burn for the nonlinear change, in the linear regime)."""
    check_system(system)
    validation.instance(pair, "pair", DemonstrationPair)
    k = validation.integer(coast_hours, "coast_hours", minimum=1, maximum=pair.t.size - 1)
    n_grid = validation.integer(n_grid, "n_grid", minimum=2)
    probe = validation.positive(probe_m_s, "probe_m_s")
    V = system.velocity_unit_km_s
    tk = pair.t[:k + 1]
    nom = ssat.propagate_with_impulses(system, np.vstack([pair.agent_x0, pair.target_x0]), tk)
    _, Ha, _ = AZIMUTH_ELEVATION.evaluate(nom.x[0, -1], nom.x[1, -1])
    Q = ssat.mmd_matrix(nom.stm[0, -1], Ha)
    e = ssat.mmd_direction(Q)
    D = ssat.fibonacci_sphere(n_grid)
    quad = np.einsum("ni,ij,nj->n", D, Q, D)
    x = np.tile(pair.agent_x0, (n_grid, 1))
    x[:, 3:6] += probe / (V * 1e3) * D
    y = AZIMUTH_ELEVATION(propagate(system, x, tk).x[:, -1], nom.x[1, -1])
    dev = np.linalg.norm(AZIMUTH_ELEVATION.residual(y, AZIMUTH_ELEVATION(nom.x[0, -1], nom.x[1, -1])), axis=-1)
    ang = [float(np.degrees(np.arccos(min(1.0, abs(D[np.argmax(c)] @ e))))) for c in (quad, dev)]
    return SurrogateCheck(float(k), np.linalg.eigvalsh(Q), e, ang[0], ang[1],
                          float(np.degrees(np.sqrt(4 * np.pi / n_grid))), Q, Ha, nom.stm[0, -1])


# ---------------------------------------------------------------------------------------------------------------
# Policies over coast times
# ---------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class PolicyStudy:
    """:func:`cislunar.guidance.ssat.compare_burn_policies` for each burn magnitude.

    Attributes
    ----------
    results : dict
        Burn magnitude (m/s) -> :class:`cislunar.guidance.ssat.PolicyComparison`.
    coast_indices : tuple of int
        Grid indices of the coast ends (hours after the burn).
    """

    results: dict
    coast_indices: tuple

    def sign_percent(self, dv_m_s: float) -> np.ndarray:
        """How much worse the rejected sign of the MMD axis is, percent of :math:`\\sqrt{J_\\rho}`, per coast."""
        r = self.results[_result_key(self.results, dv_m_s, "dv_m_s", "burn magnitudes")]
        return 100 * (r.mmd_other / r.mmd - 1)

    def optimum_at(self, dv_m_s: float, coast_hours: float) -> float:
        """:math:`\\sqrt{J_\\rho}` (km) of the true minimiser for one burn and coast; NaN if that coast was not run."""
        r = self.results[_result_key(self.results, dv_m_s, "dv_m_s", "burn magnitudes")]
        coast_hours = validation.real(coast_hours, "coast_hours")
        hit = np.flatnonzero(np.isclose(r.coast_hours, coast_hours, rtol=0.0, atol=1e-6))
        return float(r.optimum[hit[0]]) if hit.size else float("nan")

    def perpendicular_hours(self, dv_m_s: float, tol: float = 0.02) -> float:
        """Longest coast (h) up to which the best perpendicular direction is within ``tol`` of the optimum."""
        r = self.results[_result_key(self.results, dv_m_s, "dv_m_s", "burn magnitudes")]
        tol = validation.positive(tol, "tol", allow_zero=True)
        return leading_hours(r.coast_hours, r.perp_best <= (1 + tol) * r.optimum)


def _compare_task(task):
    """One :func:`cislunar.guidance.ssat.compare_burn_policies` call from a picklable tuple (sweep task)."""
    system, xa, xt, t, coast_idx, dv, P0, kwargs = task
    return ssat.compare_burn_policies(system, xa, xt, t, coast_idx, dv, P0, **kwargs)


def _sweep(tasks, executor, desc):
    return map_tasks(_compare_task, tasks, executor=executor, progress=False, desc=desc)


def policy_study(system: CR3BP, pair: DemonstrationPair, coast_hours, dv_m_s, *, n_grid: int = 3000,
                 n_perp: int = 120, executor=None) -> PolicyStudy:
    """MMD vs the true minimiser and the perpendicular circle, burn at the start of tracking, for each burn
    magnitude in ``dv_m_s`` (m/s) and coast in ``coast_hours`` (whole hours, within the pair's grid); one task per
    burn magnitude on ``executor`` (``None``: serial)."""
    check_system(system)
    validation.instance(pair, "pair", DemonstrationPair)
    coast_idx = tuple(_hours_on_grid(coast_hours, "coast_hours", 1, pair.t.size - 1))
    dvs = [float(d) for d in _positive_values(dv_m_s, "dv_m_s")]
    n_grid = validation.integer(n_grid, "n_grid", minimum=2)
    n_perp = validation.integer(n_perp, "n_perp", minimum=1)
    _executor(executor)
    V = system.velocity_unit_km_s
    kw = {"n_grid": n_grid, "n_perp": n_perp}
    tasks = [(system, pair.agent_x0, pair.target_x0, pair.t, list(coast_idx), dv * 1e-3 / V, pair.P0, kw)
             for dv in dvs]
    return PolicyStudy(dict(zip(dvs, _sweep(tasks, executor, "burn sizes"))), coast_idx)


@dataclass(frozen=True)
class DirectionMap:
    """:math:`\\sqrt{J_\\rho}` at the end of one coast for every burn direction of a Fibonacci sphere.

    Attributes
    ----------
    directions : ndarray (n, 3)
        Unit burn directions (rotating frame).
    range_sigma_km : ndarray (n,)
    line_of_sight : ndarray (3,)
        Unit line of sight agent -> target at the burn.
    mmd_direction, optimum_direction : ndarray (3,)
        From the policy comparison of the same coast.
    optimum_perp_angle_deg : float
        Angle of the optimum out of the plane perpendicular to the line of sight, deg.
    coast_hours, dv_m_s : float
    """

    directions: np.ndarray
    range_sigma_km: np.ndarray
    line_of_sight: np.ndarray
    mmd_direction: np.ndarray
    optimum_direction: np.ndarray
    optimum_perp_angle_deg: float
    coast_hours: float
    dv_m_s: float

    @property
    def los_angle_deg(self) -> float:
        """Angle between the optimum and the line of sight (either sense), deg."""
        return 90.0 - self.optimum_perp_angle_deg

    @property
    def towards_target(self) -> bool:
        """The optimum points towards the target (positive component along the line of sight)."""
        return bool(self.optimum_direction @ self.line_of_sight > 0)


def direction_map(system: CR3BP, pair: DemonstrationPair, study: PolicyStudy, coast_hours: int = 12,
                  dv_m_s: float | None = None, n_grid: int = 3000) -> DirectionMap:
    """The cost over the sphere of burn directions for one coast (default 12 h) and burn (default the largest)."""
    check_system(system)
    validation.instance(pair, "pair", DemonstrationPair)
    validation.instance(study, "study", PolicyStudy)
    k = validation.integer(coast_hours, "coast_hours", minimum=1, maximum=pair.t.size - 1)
    dv = max(study.results) if dv_m_s is None else _result_key(study.results, dv_m_s, "dv_m_s", "burn magnitudes")
    r = study.results[dv]
    i = int(np.argmin(np.abs(r.coast_hours - k)))
    D = ssat.fibonacci_sphere(validation.integer(n_grid, "n_grid", minimum=2))
    tk = pair.t[:k + 1]
    tgt = ssat.ImpulsiveTrajectory(tk, pair.target.x[:, :k + 1], pair.target.stm[:, :k + 1])
    grid = ssat.range_sigma_over_directions(system, pair.agent_x0, None, tk, dv * 1e-3 / system.velocity_unit_km_s,
                                            D, pair.P0, target=tgt)
    los = pair.target_x0[:3] - pair.agent_x0[:3]
    return DirectionMap(D, grid.range_sigma_km[:, -1], los / np.linalg.norm(los), r.mmd_direction[i],
                        r.optimum_direction[i], float(r.optimum_perp_angle_deg[i]), float(k), dv)


# ---------------------------------------------------------------------------------------------------------------
# Computation time
# ---------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class TimingStudy:
    """Wall-clock times (s) of MMD and of the true minimiser for one coast and burn (machine-dependent).

    Attributes
    ----------
    mmd_core : float
        Eq. 24 and the eigenvector, given the STM and the Jacobian (best of ``repeat_core``).
    mmd_policy : float
        Full MMD policy with propagation and the sign check (best of 3).
    optimum : float
        Sphere of ``n_grid`` directions plus Nelder-Mead.
    optimum_range_sigma_km : float
        :math:`\\sqrt{J_\\rho}` of the timed minimiser, km.
    repeat_core : int
    """

    mmd_core: float
    mmd_policy: float
    optimum: float
    optimum_range_sigma_km: float
    repeat_core: int

    @property
    def ratio_core(self) -> float:
        return self.optimum / self.mmd_core

    @property
    def ratio_policy(self) -> float:
        return self.optimum / self.mmd_policy


def _best_time(fn, repeat):
    best, res = np.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        res = fn()
        best = min(best, time.perf_counter() - t0)
    return best, res


def timing_study(system: CR3BP, pair: DemonstrationPair, surrogate: SurrogateCheck, dv_m_s: float = 1.0, *,
                 n_grid: int = 3000, repeat_core: int = 200, repeat_optimum: int = 1) -> TimingStudy:
    """Time MMD (core and full policy) and the true minimiser for the coast of ``surrogate``."""
    check_system(system)
    validation.instance(pair, "pair", DemonstrationPair)
    validation.instance(surrogate, "surrogate", SurrogateCheck)
    dv = validation.positive(dv_m_s, "dv_m_s") * 1e-3 / system.velocity_unit_km_s
    n_grid = validation.integer(n_grid, "n_grid", minimum=2)
    repeat_core = validation.integer(repeat_core, "repeat_core", minimum=1)
    repeat_optimum = validation.integer(repeat_optimum, "repeat_optimum", minimum=1)
    tk = pair.t[:int(surrogate.coast_hours) + 1]
    t_core, _ = _best_time(lambda: ssat.mmd_direction(ssat.mmd_matrix(surrogate.agent_stm, surrogate.H_agent)),
                           repeat_core)
    t_pol, _ = _best_time(lambda: ssat.mmd_policy(system, pair.agent_x0, pair.target_x0, tk, dv, pair.P0), 3)
    t_opt, (_, J) = _best_time(lambda: ssat.minimize_range_sigma(system, pair.agent_x0, pair.target_x0, tk, dv,
                                                                 pair.P0, n_grid=n_grid), repeat_optimum)
    return TimingStudy(t_core, t_pol, t_opt, float(np.sqrt(J) * system.length_unit_km), repeat_core)


# ---------------------------------------------------------------------------------------------------------------
# A tracking arc before the burn
# ---------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class TrackingArcStudy:
    """The policy comparison with ``pre_arc_hours`` of tracking before the burn.

    Attributes
    ----------
    results : dict
        Arc length (h) -> :class:`cislunar.guidance.ssat.PolicyComparison`.
    tolerance_percent : float
        MMD excess over the optimum counted as "nearly optimal", percent.
    """

    results: dict
    tolerance_percent: float

    def within_hours(self, arc_hours) -> float:
        """Longest coast up to which MMD is within the tolerance for every coast, h."""
        r = self.results[_result_key(self.results, arc_hours, "arc_hours", "arc lengths")]
        return leading_hours(r.coast_hours, r.mmd_excess_percent <= self.tolerance_percent)

    def leading_run(self, arc_hours) -> int:
        """Number of leading coasts within the tolerance."""
        ok = self.results[_result_key(self.results, arc_hours, "arc_hours", "arc lengths")].mmd_excess_percent \
            <= self.tolerance_percent
        return ok.size if ok.all() else int(np.argmin(ok))

    @property
    def worst_excess_percent(self) -> np.ndarray:
        """Worst MMD excess of each arc length, percent."""
        return np.array([r.mmd_excess_percent.max() for r in self.results.values()])


def tracking_arc_study(system: CR3BP, pair: DemonstrationPair, arc_hours, coast_hours, dv_m_s: float = 1.0, *,
                       n_grid: int = 3000, n_perp: int = 120, tolerance_percent: float = 5.0,
                       executor=None) -> TrackingArcStudy:
    """The 1-burn comparison with a tracking arc of each length in ``arc_hours`` (whole hours) before the burn
    (``P0`` at the start of the arc; the pair propagated back from the burn epoch); one task per arc length on
    ``executor`` (``None``: serial)."""
    check_system(system)
    validation.instance(pair, "pair", DemonstrationPair)
    arcs = _hours_on_grid(arc_hours, "arc_hours", 0)
    coast_idx = _hours_on_grid(coast_hours, "coast_hours", 1)
    dv = validation.positive(dv_m_s, "dv_m_s") * 1e-3 / system.velocity_unit_km_s
    n_grid = validation.integer(n_grid, "n_grid", minimum=2)
    n_perp = validation.integer(n_perp, "n_perp", minimum=1)
    tol = validation.positive(tolerance_percent, "tolerance_percent")
    _executor(executor)
    HR = _hour(system)
    tasks = []
    for h in arcs:
        xa = propagate(system, pair.agent_x0, np.array([0.0, -h * HR])).x[-1]
        xt = propagate(system, pair.target_x0, np.array([0.0, -h * HR])).x[-1]
        t = np.arange(0, h + max(coast_idx) + 1) * HR
        tasks.append((system, xa, xt, t, [h + k for k in coast_idx], dv, pair.P0,
                      {"burn_index": h, "n_grid": n_grid, "n_perp": n_perp}))
    return TrackingArcStudy(dict(zip(arcs, _sweep(tasks, executor, "tracking arcs"))), tol)


# ---------------------------------------------------------------------------------------------------------------
# Agent on the quasi-periodic torus
# ---------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class QpoPairStudy:
    """The policy comparison with the agent on a torus at several initial ring angles.

    Attributes
    ----------
    results : dict
        Ring angle (deg) -> :class:`cislunar.guidance.ssat.PolicyComparison`.
    antipode : PolicyComparison
        Ring angle 180 deg (the antipode of 0 deg), for the independence check.
    offset_0, offset_180 : ndarray (3,)
        Agent-target relative position at the burn for ring angles 0 and 180 deg, km.
    """

    results: dict
    antipode: object
    offset_0: np.ndarray
    offset_180: np.ndarray

    @property
    def excess_percent(self) -> np.ndarray:
        """MMD excess over the optimum of every (ring angle, coast) case, percent."""
        return np.concatenate([r.mmd_excess_percent for r in self.results.values()])

    @property
    def percentile(self) -> np.ndarray:
        """Percent of sphere directions better than MMD, every case."""
        return np.concatenate([r.mmd_percentile for r in self.results.values()])

    @property
    def coast_hours(self) -> np.ndarray:
        return np.concatenate([r.coast_hours for r in self.results.values()])

    @property
    def mirror_ratio(self) -> float:
        """``|d_0 + d_180| / |d_0|``: 0 when the antipodal relative positions are exact mirror images."""
        return float(np.linalg.norm(self.offset_0 + self.offset_180) / np.linalg.norm(self.offset_0))

    def antipode_differences(self) -> tuple:
        """Max over coasts of the relative difference (percent) of the optimum's and MMD's :math:`\\sqrt{J_\\rho}`,
        and of the MMD percentile (points), between ring angles 180 and 0 deg."""
        r0, a = self.results[0.0], self.antipode
        return (float(np.max(np.abs(a.optimum / r0.optimum - 1)) * 100),
                float(np.max(np.abs(a.mmd / r0.mmd - 1)) * 100),
                float(np.max(np.abs(a.mmd_percentile - r0.mmd_percentile))))


def qpo_pair_study(system: CR3BP, torus, pair: DemonstrationPair, ring_angles_deg, coast_hours,
                   dv_m_s: float = 1.0, *, n_grid: int = 3000, n_perp: int = 120, executor=None) -> QpoPairStudy:
    """Agent on ``torus`` (its trajectory through ring angle ``a``, ``pair.lead_hours`` before apolune), target as
    in ``pair``; the comparison for each ring angle (deg, must include 0) and for 180 deg, one task per ring angle
    on ``executor`` (``None``: serial)."""
    check_system(system)
    validation.instance(torus, "torus", InvariantTorus)
    validation.instance(pair, "pair", DemonstrationPair)
    angles = [float(a) for a in validation.as_array(ring_angles_deg, "ring_angles_deg", ndim=(1,), min_size=1)]
    if 0.0 not in angles:
        raise ValueError(f"ring_angles_deg must include 0 (the antipodal check); got {angles}")
    coast_idx = _hours_on_grid(coast_hours, "coast_hours", 1, pair.t.size - 1)
    dv = validation.positive(dv_m_s, "dv_m_s") * 1e-3 / system.velocity_unit_km_s
    n_grid = validation.integer(n_grid, "n_grid", minimum=2)
    n_perp = validation.integer(n_perp, "n_perp", minimum=1)
    _executor(executor)
    t_lead = -pair.lead_hours * _hour(system)

    kw = {"n_grid": n_grid, "n_perp": n_perp}
    tasks = [(system, torus.states([rad], [t_lead])[0, 0], pair.target_x0, pair.t, coast_idx, dv, pair.P0, kw)
             for rad in [np.radians(a) for a in angles] + [np.pi]]
    *runs, anti = _sweep(tasks, executor, "ring angles")
    res = dict(zip(angles, runs))
    d0, d180 = ((torus.states([a], [t_lead])[0, 0, :3] - pair.target_x0[:3]) * system.length_unit_km
                for a in (0.0, np.pi))
    return QpoPairStudy(res, anti, d0, d180)
