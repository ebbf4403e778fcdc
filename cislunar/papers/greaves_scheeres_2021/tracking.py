r"""Optical tracking scenarios of the maneuver-detection paper (Greaves & Scheeres 2021): truth, measurements, filter.

A scenario fixes the target's reference orbit, where the track starts (periapsis or apoapsis), the measurement
epochs (a cadence over a number of periods), the observers (by default the L2 observer of :mod:`cislunar.sensing.sites`)
and the measurement model with its noise.  Truth trajectories may include impulsive maneuvers; measurements are
drawn with a caller-supplied random generator.

Noise model (the paper's Table 3 is missing from its text): angles with standard deviation
``sigma_angle_rad`` (default 10 micro-rad, the "high accuracy sensor" value the same authors use in their AMOS 2023
paper, from the same reference), and angle rates obtained by differencing two angles ``rate_dt_s`` = 1 s apart,
so that :math:`\sigma_{\dot\theta} = \sqrt2\,\sigma_\theta/\Delta t` (Eq. 13).  Angles in rad, rates in rad/TU
internally.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cislunar.cr3bp.dynamics import CR3BP, check_system
from cislunar.cr3bp.orbits import PeriodicOrbit
from cislunar.cr3bp.propagation import _check_tol, find_events, propagate
from cislunar.estimation.batched_ocbe import ocbe_batch
from cislunar.estimation.consistency import NEES_PROBABILITY, nees
from cislunar.estimation.ocbe import (
    FilterDivergenceError,
    control_weights,
    ocbe_filter_smoother,
)
from cislunar.sensing import measurements, sites
from cislunar.utils import validation

__all__ = [
    "TrackingScenario",
    "angles_rates_covariance",
    "make_scenario",
    "simulate_truth",
    "simulate_measurements",
    "initial_estimate",
    "apoapsis_window_weights",
    "DEFAULT_SIGMA_ANGLE_RAD",
    "TrialSummary",
    "nees",
    "summarize",
    "filter_trial",
    "filter_trials",
]

#: Default angular noise (1 sigma), rad: 10 micro-rad (see the module docstring).
DEFAULT_SIGMA_ANGLE_RAD = 10e-6
#: Earth-radar hand-off uncertainty of the paper (3 sigma): 10 km and 10 cm/s per axis.
HANDOFF_3SIGMA_KM = 10.0
HANDOFF_3SIGMA_KM_S = 1e-4


def angles_rates_covariance(system: CR3BP, sigma_angle_rad: float = DEFAULT_SIGMA_ANGLE_RAD, rate_dt_s: float = 1.0,
                            *, rates: bool = True) -> np.ndarray:
    """Measurement covariance of [azimuth, elevation(, rates)]: angles in rad, rates in rad/TU (Eq. 13)."""
    check_system(system)
    s = validation.positive(sigma_angle_rad, "sigma_angle_rad")
    dt = validation.positive(rate_dt_s, "rate_dt_s")
    rates = validation.boolean(rates, "rates")
    if not rates:
        return np.diag([s**2, s**2])
    sr = np.sqrt(2.0) * s / dt * system.time_unit_s  # rad/s -> rad/TU
    return np.diag([s**2, s**2, sr**2, sr**2])


@dataclass(frozen=True)
class TrackingScenario:
    """Everything a filter run needs except the random draws.

    Attributes
    ----------
    system : CR3BP
    orbit : PeriodicOrbit
        Target reference orbit.
    x_start : ndarray, shape (6,)
        Reference (maneuver-free) target state at ``t[0]``.
    t : ndarray, shape (N,)
        Measurement epochs, TU, starting at 0.
    observers : ndarray, shape (N, K, 6)
        State of each of the K observers at each epoch.
    available : ndarray of bool, shape (N, K)
        Whether each observer sees the target (Moon occultation for spacecraft, horizon for surface stations).
    observer_names : tuple of str
    model : MeasurementModel
    meas_cov : ndarray, shape (m, m)
        Non-dimensional measurement covariance.
    t_apoapsis : ndarray
        Apoapsis passage times within the track, TU.
    """

    system: CR3BP
    orbit: PeriodicOrbit
    x_start: np.ndarray
    t: np.ndarray
    observers: np.ndarray
    available: np.ndarray
    observer_names: tuple
    model: measurements.MeasurementModel
    meas_cov: np.ndarray
    t_apoapsis: np.ndarray

    @property
    def cadence_hours(self) -> float:
        return float(np.diff(self.t[:2])[0] * self.system.time_unit_s / 3600.0)


def make_scenario(system: CR3BP, orbit: PeriodicOrbit, cadence_hours: float, *, start: str = "periapsis",
                  periods: float = 1.0, observers: str = "L2", rates: bool = True,
                  sigma_angle_rad: float = DEFAULT_SIGMA_ANGLE_RAD) -> TrackingScenario:
    """Build a tracking scenario of one (or more) periods of ``orbit``.

    Parameters
    ----------
    cadence_hours : float
        Time between measurements, hours.
    start : {"periapsis", "apoapsis"}
        Where the track (and the filter's hand-off) begins.
    periods : float
        Track length in orbit periods.
    observers : {"L2", "all"}
        The L2 observer alone, or the five of the paper: L2, the DRO observer and the three lunar-surface
        stations of :mod:`cislunar.sensing.sites` (the DRO observer starts at its x-axis crossing at ``t = 0``).
    rates : bool
        Angles and angle rates (``True``) or angles only.
    sigma_angle_rad : float
        Angular noise (1 sigma), rad.
    """
    check_system(system)
    validation.instance(orbit, "orbit", PeriodicOrbit, "a cislunar.cr3bp.orbits.PeriodicOrbit")
    cadence = validation.positive(cadence_hours, "cadence_hours")
    periods = validation.positive(periods, "periods")
    validation.choice(start, "start", ("periapsis", "apoapsis"))
    validation.choice(observers, "observers", ("L2", "all"))
    rates = validation.boolean(rates, "rates")
    validation.positive(sigma_angle_rad, "sigma_angle_rad")
    if cadence * 3600.0 / system.time_unit_s >= periods * orbit.period:
        raise ValueError(f"cadence_hours = {cadence} leaves fewer than two epochs in {periods} period(s)")
    ev = find_events(system, orbit.x0, orbit.period * (1 + 1e-9), (start,), impact=False)
    if ev.t.size == 0:
        raise ValueError(f"orbit has no {start} passage")
    x_start = ev.x[0]
    dt = cadence * 3600.0 / system.time_unit_s
    t = np.arange(0.0, periods * orbit.period + 1e-12, dt)
    target = propagate(system, x_start, t).x
    obs = [np.tile(sites.l2_observer_state(system), (t.size, 1))]
    names = ["L2"]
    kinds = ["spacecraft"]
    if observers == "all":
        dro = sites.dro_observer_orbit(system)
        obs.append(propagate(system, dro.x0, t).x)
        names.append("DRO")
        kinds.append("spacecraft")
        for st in sites.DEFAULT_STATIONS:
            obs.append(np.tile(np.r_[st.position(system), 0.0, 0.0, 0.0], (t.size, 1)))
            names.append(st.name)
            kinds.append("station")
    obs = np.stack(obs, axis=1)
    avail = np.empty((t.size, len(names)), dtype=bool)
    for k, kind in enumerate(kinds):
        if kind == "spacecraft":
            avail[:, k] = sites.line_of_sight_clear(system, obs[:, k], target)
        else:
            avail[:, k] = sites.station_elevation(system, obs[0, k], target) > 0.0
    apo = find_events(system, x_start, t[-1] + 1e-9, ("apoapsis",), impact=False).t
    model = measurements.ANGLES_AND_RATES if rates else measurements.AZIMUTH_ELEVATION
    return TrackingScenario(system, orbit, x_start, t, obs, avail, tuple(names), model,
                            angles_rates_covariance(system, sigma_angle_rad, rates=rates), apo)


def simulate_truth(system: CR3BP, x_start, t, maneuvers=()) -> np.ndarray:
    """True states at the epochs ``t`` with impulsive maneuvers ``[(t_m, dv_vector_LU_TU), ...]``.

    A maneuver at ``t_m`` is applied to the state at ``t_m`` (between epochs); epochs at or before ``t_m`` see the
    pre-maneuver state.
    """
    check_system(system)
    x = validation.as_state(x_start, "x_start", batch=False)
    t = validation.time_grid(t, "t", increasing=True)
    try:
        pairs = [tuple(m) for m in maneuvers]
    except TypeError:
        raise validation.ArgumentTypeError("maneuvers must be a sequence of (t_m, dv) pairs") from None
    if any(len(m) != 2 for m in pairs):
        raise ValueError("maneuvers must be a sequence of (t_m, dv) pairs")
    events = sorted(((validation.real(tm, "maneuvers time"), validation.as_array(dv, "maneuvers dv", shape=(3,)))
                     for tm, dv in pairs), key=lambda e: e[0])
    if events and events[0][0] < t[0]:
        raise ValueError(f"maneuvers must not precede t[0] = {t[0]}")
    out = np.empty((t.size, 6))
    seg_t, seg_x, i = t[0], x.copy(), 0
    for tm, dv in events + [(np.inf, None)]:
        j = int(np.searchsorted(t, tm, side="right"))  # epochs up to and including tm see this segment
        if j > i:
            grid = t[i:j] if t[i] == seg_t else np.r_[seg_t, t[i:j]]
            out[i:j] = propagate(system, seg_x, grid).x[-(j - i):] if grid.size > 1 else seg_x
        i = j
        if dv is None:
            break
        if tm > seg_t:
            seg_x = propagate(system, seg_x, [seg_t, tm]).x[-1]
        seg_x = seg_x.copy()
        seg_x[3:] += dv
        seg_t = tm
    return out


def simulate_measurements(scenario: TrackingScenario, truth, rng: np.random.Generator) -> np.ndarray:
    """Noisy measurements (N, K, m) of ``truth`` (N, 6) by every observer; NaN where an observer has no view."""
    _check_scenario(scenario)
    truth = validation.as_array(truth, "truth", shape=(scenario.t.size, 6))
    validation.rng(rng)
    y = scenario.model(scenario.observers, truth[:, None, :])
    y = y + rng.standard_normal(y.shape) * np.sqrt(np.diag(scenario.meas_cov))
    y[..., 0] = measurements.wrap_angle(y[..., 0])
    y[~scenario.available] = np.nan
    return y


def initial_estimate(system: CR3BP, x_true0, rng: np.random.Generator, *, scale: float = 1.0):
    """Hand-off estimate: truth plus a draw from the Earth-radar covariance (3 sigma 10 km, 10 cm/s per axis).

    Returns ``(x0_estimate, P0)``; ``scale`` multiplies the standard deviations (the paper also tries 0.1).
    """
    check_system(system)
    x = validation.as_state(x_true0, "x_true0", batch=False)
    validation.rng(rng)
    s = validation.positive(scale, "scale")
    sp = s * system.km_to_lu(HANDOFF_3SIGMA_KM / 3.0)
    sv = s * HANDOFF_3SIGMA_KM_S / 3.0 / system.velocity_unit_km_s
    P0 = np.diag(np.r_[np.full(3, sp**2), np.full(3, sv**2)])
    return x + rng.standard_normal(6) * np.sqrt(np.diag(P0)), P0


def apoapsis_window_weights(t, t_apoapsis, q_base: float, q_window: float, window_hours: float,
                            system: CR3BP) -> np.ndarray:
    """Per-interval control weights: ``q_window`` on intervals overlapping +-window/2 around each apoapsis."""
    check_system(system)
    t = validation.time_grid(t, "t", increasing=True)
    t_apoapsis = validation.as_array(t_apoapsis, "t_apoapsis", ndim=(0, 1))
    qb = validation.positive(q_base, "q_base")
    qw = validation.positive(q_window, "q_window")
    half = validation.positive(window_hours, "window_hours") * 3600.0 / system.time_unit_s / 2.0
    q = np.full(t.size - 1, qb)
    for ta in np.atleast_1d(t_apoapsis):
        q[(t[1:] > ta - half) & (t[:-1] < ta + half)] = qw
    return q


#: A run counts as diverged when more than this fraction of epochs is inconsistent (a consistent filter has 0.1%).
DIVERGED_FRACTION = 0.05


@dataclass(frozen=True)
class TrialSummary:
    """Outcome of one filter run against its truth.

    Attributes
    ----------
    final_sigma_pos_km, final_sigma_vel_m_s : float
        Root-sum-square 1-sigma of the final filtered covariance (position, velocity).
    final_error_pos_km, final_error_vel_m_s : float
        Norm of the final filtered error.
    max_error_pos_km : float
        Largest filtered position error over the track.
    nees_mean : float
        Mean normalised estimation error squared (6 for a consistent filter).
    inconsistent_fraction : float
        Fraction of epochs whose NEES exceeds the 99.9% chi-square quantile.
    diverged : bool
        ``inconsistent_fraction > DIVERGED_FRACTION`` or the filter failed numerically.
    failure : str
        Exception message when the filter failed, else "".
    first_inconsistent_epoch : int
        Index of the first epoch whose NEES exceeds the 99.9% quantile (-1 if none; -1 too when the filter
        failed numerically).  Where a divergence starts tells its mechanism apart: at epoch 0 the first
        measurement update (a prior too wide for the linearised measurement), later the time update.
    """

    final_sigma_pos_km: float
    final_sigma_vel_m_s: float
    final_error_pos_km: float
    final_error_vel_m_s: float
    max_error_pos_km: float
    nees_mean: float
    inconsistent_fraction: float
    diverged: bool
    failure: str = ""
    first_inconsistent_epoch: int = -1


def summarize(system: CR3BP, x_est, P, truth) -> TrialSummary:
    """Consistency and accuracy summary of filtered estimates against the truth."""
    from scipy.stats import chi2

    check_system(system)
    x_est = validation.as_array(x_est, "x_est", ndim=(2,), last=6, min_size=6)
    truth = validation.as_array(truth, "truth", shape=x_est.shape)
    P = validation.spd(P, "P", n=6, batch=True)
    if P.shape != (x_est.shape[0], 6, 6):
        raise ValueError(f"P must have shape ({x_est.shape[0]}, 6, 6); got {P.shape}")
    e = x_est - truth
    n = nees(x_est, P, truth)
    over = n > chi2.ppf(NEES_PROBABILITY, 6)
    frac = float(np.mean(over))
    L, V = system.length_unit_km, system.velocity_unit_km_s * 1e3
    return TrialSummary(
        final_sigma_pos_km=float(np.sqrt(np.trace(P[-1][:3, :3])) * L),
        final_sigma_vel_m_s=float(np.sqrt(np.trace(P[-1][3:, 3:])) * V),
        final_error_pos_km=float(np.linalg.norm(e[-1, :3]) * L),
        final_error_vel_m_s=float(np.linalg.norm(e[-1, 3:]) * V),
        max_error_pos_km=float(np.max(np.linalg.norm(e[:, :3], axis=1)) * L),
        nees_mean=float(np.mean(n)),
        inconsistent_fraction=frac,
        diverged=bool(frac > DIVERGED_FRACTION),
        first_inconsistent_epoch=int(np.argmax(over)) if over.any() else -1,
    )


def _check_scenario(scenario, name: str = "scenario"):
    return validation.instance(scenario, name, TrackingScenario, "a cislunar.papers.greaves_scheeres_2021.tracking.TrackingScenario (make_scenario)")


def filter_trial(rng: np.random.Generator, scenario: TrackingScenario, control_weight, *,
                 handoff_scale: float = 1.0, tol: float = 1e-13) -> TrialSummary:
    """One Monte Carlo trial of the observation-strategy study: truth, measurements, hand-off, OCBE, summary.

    A filter that fails numerically while filtering (:class:`cislunar.estimation.ocbe.FilterDivergenceError`, e.g. a
    non-positive-definite update after divergence) is reported as diverged with the failure message, not raised:
    divergence is an outcome of this experiment.  A configuration error (a bad ``control_weight``,
    ``handoff_scale``, ``tol``, ``rng`` or ``scenario``) raises ``ValueError``/``TypeError`` before anything runs.
    """

    validation.rng(rng)
    _check_scenario(scenario)
    control_weight = control_weights(control_weight, scenario.t.size - 1)
    handoff_scale = validation.positive(handoff_scale, "handoff_scale")
    tol = _check_tol(tol)
    truth = simulate_truth(scenario.system, scenario.x_start, scenario.t)
    y = simulate_measurements(scenario, truth, rng)
    x0, P0 = initial_estimate(scenario.system, scenario.x_start, rng, scale=handoff_scale)
    try:
        res = ocbe_filter_smoother(scenario.system, scenario.t, y, scenario.observers, scenario.model,
                                   scenario.meas_cov, x0, P0, control_weight, available=scenario.available,
                                   smooth=False, n_sub=2, tol=tol)
    except FilterDivergenceError as exc:
        nan = float("nan")
        return TrialSummary(nan, nan, nan, nan, nan, nan, 1.0, True, str(exc)[:200])
    return summarize(scenario.system, res.x_filt, res.P_filt, truth)


def filter_trials(rngs, scenario: TrackingScenario, control_weight, *, handoff_scale=1.0,
                  tol: float = 1e-13, wrap_azimuth: bool = True, relinearize: bool = True,
                  coarse_stm: bool = False) -> list:
    """:func:`filter_trial` for several generators at once: the same draws, the filters in one lockstep batch.

    Each generator draws its measurement noise and hand-off error exactly as :func:`filter_trial` does; the filters
    run together through the batched OCBE (:func:`cislunar.estimation.batched_ocbe.ocbe_batch`, filter only, the
    scenario's observers and availability), which equals the single-trial filter to round-off and flags a trial
    that fails numerically at the epoch the single-trial filter would (reported as diverged, as in
    :func:`filter_trial`).  A vectorized trial for :func:`cislunar.utils.montecarlo.run_monte_carlo`
    (``vectorized=True``).

    Parameters
    ----------
    rngs : sequence of numpy.random.Generator
        One per trial.
    scenario : TrackingScenario
    control_weight : float or array_like, shape (N-1,)
        OCBE control weight per interval, LU^2/TU^3.
    handoff_scale : float or sequence of float
        Hand-off scale of every trial, or one per trial (trials of several hand-offs share one lockstep).
    tol : float
        Integrator tolerance.
    wrap_azimuth, relinearize, coarse_stm : bool
        Filter-side options of :func:`cislunar.estimation.batched_ocbe.ocbe_batch` (defaults: residual angles
        wrapped to :math:`[-\\pi, \\pi)`, re-linearised about each updated estimate, transition integrated through
        each interval); the measurements and hand-offs drawn do not depend on them.

    Returns
    -------
    list of TrialSummary
        In the order of ``rngs``.
    """
    if isinstance(rngs, np.random.Generator) or not hasattr(rngs, "__iter__"):
        raise validation.ArgumentTypeError(f"rngs must be a sequence of numpy.random.Generator; got "
                                           f"{type(rngs).__name__}")
    rngs = list(rngs)
    if not rngs:
        raise ValueError("rngs must hold at least one generator")
    for i, r in enumerate(rngs):
        validation.rng(r, f"rngs[{i}]")
    _check_scenario(scenario)
    control_weight = control_weights(control_weight, scenario.t.size - 1)
    scales = validation.as_array(handoff_scale, "handoff_scale", ndim=(0, 1))
    if scales.ndim == 1 and scales.size != len(rngs):
        raise ValueError(f"handoff_scale must be a number or hold one scale per generator ({len(rngs)}); got "
                         f"{scales.size}")
    scales = np.broadcast_to(scales, (len(rngs),))
    for s in scales:
        validation.positive(s, "handoff_scale")
    tol = _check_tol(tol)
    wrap_azimuth = validation.boolean(wrap_azimuth, "wrap_azimuth")
    relinearize = validation.boolean(relinearize, "relinearize")
    coarse_stm = validation.boolean(coarse_stm, "coarse_stm")
    system = scenario.system
    truth = simulate_truth(system, scenario.x_start, scenario.t)
    y, x0, P0 = [], [], []
    for r, s in zip(rngs, scales):  # the draws of filter_trial, generator by generator
        y.append(simulate_measurements(scenario, truth, r))
        x, P = initial_estimate(system, scenario.x_start, r, scale=float(s))
        x0.append(x)
        P0.append(P)
    res = ocbe_batch(system, scenario.t, np.array(y), scenario.observers, scenario.model, scenario.meas_cov,
                     np.array(x0), np.array(P0), control_weight, available=scenario.available, smooth=False, n_sub=2,
                     tol=tol, on_failure="flag", wrap_azimuth=wrap_azimuth, relinearize=relinearize,
                     coarse_stm=coarse_stm)
    nan = float("nan")
    return [TrialSummary(nan, nan, nan, nan, nan, nan, 1.0, True, str(res.failure[b])[:200]) if res.failed[b] else
            summarize(system, res.x_filt[b], res.P_filt[b], truth) for b in range(len(rngs))]
