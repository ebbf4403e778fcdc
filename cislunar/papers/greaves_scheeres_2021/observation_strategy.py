r"""The observation-strategy study of Greaves & Scheeres 2021 ("Observation Strategy": Fig. 4, Table 4, Fig. 5) as
functions returning frozen results (chapter 09).

* :func:`measurement_demo`: the noise-free angles and angle rates the L2 observer sees over one period;
* :func:`typical_run`: one OCBE filter/smoother run (the paper's Fig. 5 layout);
* :func:`strategy_study`: the Monte Carlo over orbits and cadences (angles only, or angles + rates; the
  :class:`StrategyStudy` rows are medians over runs, the analogue of the missing Table 4);
* :func:`regime_map`: the fraction of diverged runs over hand-off scale, angle noise, cadence, orbit and rate
  model (:class:`RegimeMap` analyses where the paper's contrast could hold);
* :func:`divergence_example`: the clearest diverged draw of an angles-only map cell (the paper's Fig. 4 analogue);
* :func:`filter_axes_study`: the regime map's key cells (the paper's hand-off, angles vs angles + rates) along
  filter-side axes: azimuth wrapping, a fixed reference, the control weight, a coarse time update
  (:class:`FilterAxesStudy`);
* figure functions (``figure_*``), each returning a Matplotlib figure.

A run is *diverged* when more than 5 % of its epochs have a NEES above the 99.9 % chi-square quantile, or when the
filter fails numerically (:mod:`cislunar.papers.greaves_scheeres_2021.tracking`).  Control weights are in
LU^2/TU^3 (non-dimensional), hand-off scales multiply the paper's 3-sigma 10 km and 10 cm/s per axis, angles are in
rad and cadences in hours.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import matplotlib.pyplot as plt
import numpy as np
from matplotlib import ticker
from scipy import stats

from cislunar.cr3bp.dynamics import CR3BP, check_system
from cislunar.cr3bp.orbits import PeriodicOrbit
from cislunar.estimation import batched_ocbe, consistency, ocbe
from cislunar.papers.greaves_scheeres_2021 import tracking
from cislunar.publish.claims import Claim
from cislunar.utils import validation
from cislunar.utils.montecarlo import map_tasks, trial_rng

__all__ = [
    "ONSETS",
    "DivergenceExample",
    "FILTER_AXES",
    "FilterAxesStudy",
    "MeasurementDemo",
    "RegimeMap",
    "StableCandidates",
    "StrategyStudy",
    "TypicalRun",
    "cadence_label",
    "compare_stable_candidates",
    "divergence_example",
    "figure_divergence",
    "figure_filter_axes",
    "figure_final_uncertainty",
    "figure_measurements",
    "figure_regime_map",
    "figure_typical_run",
    "filled",
    "filter_axes_study",
    "flagged_cells",
    "measurement_demo",
    "pct_span",
    "regime_map",
    "strategy_study",
    "typical_run",
]

#: Where a diverged run's inconsistency starts.
ONSETS = ("first update", "before perilune", "at or after perilune", "numerical failure")


def filled(claim, **fields):
    """``claim`` with the ``{name}`` fields of its quantity filled in (the cadences or noise a run used)."""
    validation.instance(claim, "claim", Claim, "a cislunar.publish.claims.Claim")
    try:
        quantity = claim.quantity.format(**fields)
    except (KeyError, IndexError) as exc:
        raise ValueError(f"fields must fill every {{name}} of the claim's quantity {claim.quantity!r}; missing "
                         f"{exc}") from None
    return dataclasses.replace(claim, quantity=quantity)


def _runs_at_cadence(cadence_h: float, n_runs: int, n_runs_one_minute: int) -> int:
    """Runs per cell at ``cadence_h`` (hours): ``n_runs_one_minute`` under 0.1 h (the 1-min cadence, about 9450
    updates per period), else ``n_runs``."""
    return n_runs_one_minute if cadence_h < 0.1 else n_runs


def cadence_label(cadence_h: float) -> str:
    """'10 min' or '2 h'."""
    cadence_h = validation.positive(cadence_h, "cadence_h")
    return f"{cadence_h * 60:g} min" if cadence_h < 1 else f"{cadence_h:g} h"


def _check_orbits(orbits_):
    what = "a dict of name -> cislunar.cr3bp.orbits.PeriodicOrbit"
    validation.instance(orbits_, "orbits_", dict, what)
    if not orbits_:
        raise ValueError("orbits_ must hold at least one orbit")
    for o in orbits_.values():
        validation.instance(o, "orbits_", PeriodicOrbit, what)
    return orbits_


def _positive_values(values, name: str) -> tuple:
    """A non-empty 1-D sequence of positive finite numbers, as a tuple of float."""
    arr = validation.as_array(values, name, ndim=(1,), min_size=1)
    if np.any(arr <= 0):
        raise ValueError(f"{name} must be positive; got {arr}")
    return tuple(float(v) for v in arr)


def _check_executor(executor):
    """``None`` (serial) or an object with a ``submit`` method (a concurrent.futures executor, a Dask Client)."""
    if executor is not None and not callable(getattr(executor, "submit", None)):
        raise validation.ArgumentTypeError(f"executor must be None or have a submit(fn, *args) method (a "
                                           f"concurrent.futures executor or a Dask Client); got "
                                           f"{type(executor).__name__}")
    return executor


def _bounds_3sigma(system, P):
    """3-sigma root-sum-square position (km) and velocity (m/s) bounds of covariances (N, 6, 6)."""
    return (3 * np.sqrt(np.trace(P[:, :3, :3], axis1=1, axis2=2)) * system.length_unit_km,
            3 * np.sqrt(np.trace(P[:, 3:, 3:], axis1=1, axis2=2)) * system.velocity_unit_km_s * 1e3)


# ---------------------------------------------------------------------------------------------------------------
# Section 1: what the L2 observer sees
# ---------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class MeasurementDemo:
    """Noise-free azimuth, elevation and their rates over one period from apoapsis.

    Attributes
    ----------
    days : ndarray, shape (N,)
        Time since apoapsis, days.
    y : ndarray, shape (N, 4)
        Azimuth, elevation (rad) and their rates (rad/TU).
    sigma : ndarray, shape (4,)
        1-sigma noise (rad, rad/TU) of Eq. 13 with a 1-s baseline.
    time_unit_s : float
    """

    days: np.ndarray
    y: np.ndarray
    sigma: np.ndarray
    time_unit_s: float

    @property
    def rates_urad_s(self) -> np.ndarray:
        """Absolute azimuth and elevation rates, micro-rad/s."""
        return np.abs(self.y[:, 2:]) / self.time_unit_s * 1e6

    @property
    def sigma_rate_urad_s(self) -> float:
        return float(self.sigma[2] / self.time_unit_s * 1e6)

    def report(self) -> str:
        s, T = self.sigma, self.time_unit_s
        rate, sig = self.rates_urad_s, self.sigma_rate_urad_s
        k = int(np.argmax(rate.max(axis=1)))
        return (f"1-sigma: azimuth, elevation {s[0] * 1e6:.1f}, {s[1] * 1e6:.1f} urad | rates "
                f"{s[2] / T * 1e6:.2f}, {s[3] / T * 1e6:.2f} urad/s\n"
                f"largest |rate| {rate.max():.1f} urad/s at day {self.days[k]:.2f} = {rate.max() / sig:.2f} of the "
                f"1-sigma rate noise ({sig:.1f} urad/s); |azimuth rate| at apoapsis {rate[0, 0]:.1f} urad/s")


def measurement_demo(system: CR3BP, orbit: PeriodicOrbit, cadence_hours: float = 2.0, *,
                     sigma_angle_rad: float = tracking.DEFAULT_SIGMA_ANGLE_RAD) -> MeasurementDemo:
    """The L2 observer's noise-free angles and rates of ``orbit`` over one period from apoapsis, with the 1-sigma
    noise of angles ``sigma_angle_rad`` (rad) and of their rates (Eq. 13, 1-s baseline)."""
    check_system(system)
    sigma_angle_rad = validation.positive(sigma_angle_rad, "sigma_angle_rad")
    sc = tracking.make_scenario(system, orbit, cadence_hours, start="apoapsis")
    y = sc.model(sc.observers[:, 0], tracking.simulate_truth(system, sc.x_start, sc.t))
    noise = np.sqrt(np.diag(tracking.angles_rates_covariance(system, sigma_angle_rad)))
    return MeasurementDemo(system.tu_to_days(sc.t), y, noise, system.time_unit_s)


def figure_measurements(demo: MeasurementDemo):
    """Angles (left) and signed rates on a symmetric-log axis with the 1-sigma rate noise (right)."""
    validation.instance(demo, "demo", MeasurementDemo, "a MeasurementDemo (measurement_demo)")
    days, y, T = demo.days, demo.y, demo.time_unit_s
    fig, axes = plt.subplots(1, 2, figsize=(12, 3.8))
    axes[0].plot(days, np.degrees(y[:, 0]), label="azimuth")
    axes[0].plot(days, np.degrees(y[:, 1]), label="elevation")
    axes[0].set_ylabel("angle [deg]")
    # signed rates on a symmetric-log axis: |rate| on a log axis dives wherever a rate changes sign
    axes[1].plot(days, y[:, 2] / T * 1e6, label="azimuth rate")
    axes[1].plot(days, y[:, 3] / T * 1e6, label="elevation rate")
    axes[1].set_yscale("symlog", linthresh=1.0)
    axes[1].axhspan(-demo.sigma_rate_urad_s, demo.sigma_rate_urad_s, color="0.85", zorder=0,
                    label="1-sigma rate noise")
    axes[1].set_ylabel("rate (symlog axis) [urad/s]")
    for ax in axes:
        ax.set_xlabel("time since apoapsis [d]")
    axes[0].legend(loc="upper left")
    axes[1].legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    fig.suptitle("What the L2 observer sees of the 9:2 NRHO over one period (noise-free)")
    fig.tight_layout()
    return fig


# ---------------------------------------------------------------------------------------------------------------
# Section 2: one typical run
# ---------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class TypicalRun:
    """One OCBE filter/smoother run with its truth.

    Attributes
    ----------
    scenario : TrackingScenario
    truth : ndarray, shape (N, 6)
    result : OCBEResult
        Forward-filtered and smoothed estimates and covariances.
    P0 : ndarray, shape (6, 6)
        Hand-off covariance.
    forward, smoothed : TrialSummary
    """

    scenario: tracking.TrackingScenario
    truth: np.ndarray
    result: object
    P0: np.ndarray
    forward: tracking.TrialSummary
    smoothed: tracking.TrialSummary

    def report(self) -> str:
        system, sc, run = self.scenario.system, self.scenario, self.result
        f, s = self.forward, self.smoothed
        lines = [(f"forward: mean NEES {f.nees_mean:.2f}, {100 * f.inconsistent_fraction:.1f} % of epochs above the "
                  f"99.9 % quantile; smoothed: mean NEES {s.nees_mean:.2f}, {100 * s.inconsistent_fraction:.1f} %; "
                  f"final 3-sigma position {3 * f.final_sigma_pos_km:.2f} km")]
        d = system.tu_to_days(sc.t)
        bound = {"forward": _bounds_3sigma(system, run.P_filt), "smoothed": _bounds_3sigma(system, run.P_smooth)}
        pos = bound["forward"][0]
        k_top, k_per = int(np.argmax(pos)), int(np.argmin(np.abs(sc.t - sc.orbit.period / 2)))
        lines.append(f"forward 3-sigma position: {pos[0]:.1f} km at the hand-off, largest {pos[k_top]:.1f} km at day "
                     f"{d[k_top]:.2f}, {pos[k_per]:.1f} km at perilune (day {d[k_per]:.2f}), {pos[-1]:.2f} km at "
                     "the end")
        for j, what in enumerate(("position", "velocity")):
            r = bound["smoothed"][j] / bound["forward"][j]
            lines.append(f"smoothed / forward 3-sigma {what}: largest {r[:-1].max():.3f} before the last epoch, "
                         f"{r[-1]:.3f} at the last epoch")
        return "\n".join(lines)

    def rate_noise_over_spread(self) -> np.ndarray:
        """Rate noise over the spread the hand-off covariance produces in the rates (azimuth, elevation rate)."""
        sc = self.scenario
        _, _, H = sc.model.evaluate(sc.observers[0], sc.x_start)
        return np.sqrt(np.diag(sc.meas_cov) / np.diag(H[0] @ self.P0 @ H[0].T))[2:]


def typical_run(system: CR3BP, orbit: PeriodicOrbit, cadence_hours: float, control_weight: float,
                rng: np.random.Generator, *, sigma_angle_rad: float = tracking.DEFAULT_SIGMA_ANGLE_RAD) -> TypicalRun:
    """Truth, measurements (L2, angles and rates, apoapsis start; angle noise ``sigma_angle_rad``, rad), hand-off
    draw and one OCBE filter/smoother run.

    ``rng`` draws the measurement noise first, then the hand-off error."""
    check_system(system)
    validation.rng(rng)
    control_weight = validation.positive(control_weight, "control_weight")
    sigma_angle_rad = validation.positive(sigma_angle_rad, "sigma_angle_rad")
    sc = tracking.make_scenario(system, orbit, cadence_hours, start="apoapsis", sigma_angle_rad=sigma_angle_rad)
    truth = tracking.simulate_truth(system, sc.x_start, sc.t)
    y = tracking.simulate_measurements(sc, truth, rng)
    x0, P0 = tracking.initial_estimate(system, sc.x_start, rng)
    run = ocbe.ocbe_filter_smoother(system, sc.t, y, sc.observers, sc.model, sc.meas_cov, x0, P0, control_weight,
                                    available=sc.available)
    return TypicalRun(sc, truth, run, P0, tracking.summarize(system, run.x_filt, run.P_filt, truth),
                      tracking.summarize(system, run.x_smooth, run.P_smooth, truth))


def _error_panels(system, ax_pos, ax_vel, t, x, P, truth, title):
    """Position/velocity error norms and 3-sigma bounds (the paper's Fig. 4/5 layout)."""
    d = system.tu_to_days(t)
    e = x - truth
    sp, sv = _bounds_3sigma(system, P)
    ax_pos.semilogy(d, np.linalg.norm(e[:, :3], axis=1) * system.length_unit_km, color="C0", label="|error|")
    ax_pos.semilogy(d, sp, color="C1", label="3 sigma")
    ax_vel.semilogy(d, np.linalg.norm(e[:, 3:], axis=1) * system.velocity_unit_km_s * 1e3, color="C0")
    ax_vel.semilogy(d, sv, color="C1")
    ax_pos.set_ylabel("position [km]")
    ax_vel.set_ylabel("velocity [m/s]")
    ax_vel.set_xlabel("time since apoapsis [d]")
    ax_pos.set_title(title)


def figure_typical_run(run: TypicalRun):
    """Forward filter (left) and smoother (right): error norms and 3-sigma bounds."""
    validation.instance(run, "run", TypicalRun, "a TypicalRun (typical_run)")
    system, sc, res = run.scenario.system, run.scenario, run.result
    fig, axes = plt.subplots(2, 2, figsize=(12, 6), sharex=True)
    _error_panels(system, axes[0, 0], axes[1, 0], sc.t, res.x_filt, res.P_filt, run.truth, "forward filter")
    _error_panels(system, axes[0, 1], axes[1, 1], sc.t, res.x_smooth, res.P_smooth, run.truth, "smoother")
    axes[0, 0].legend()
    fig.suptitle("9:2 NRHO, L2 observer, angles and rates every 2 hours (analogue of the paper's Fig. 5)")
    return fig


# ---------------------------------------------------------------------------------------------------------------
# Sections 4-5: Monte Carlo over orbits and cadences
# ---------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class StrategyStudy:
    """Monte Carlo runs per (orbit name, cadence in hours).

    Attributes
    ----------
    runs : dict of (str, float) -> tuple of TrialSummary
    rates : bool
        Angles and rates (True) or angles only.
    """

    runs: dict
    rates: bool

    @property
    def rows(self) -> list:
        """Per cell: (orbit, cadence h, diverged fraction, median mean NEES, median final 3-sigma position km,
        median final 3-sigma velocity m/s, runs)."""
        return [(name, cad, float(np.mean([r.diverged for r in runs])), float(np.nanmedian([r.nees_mean for r in runs])),
                 float(np.nanmedian([3 * r.final_sigma_pos_km for r in runs])),
                 float(np.nanmedian([3 * r.final_sigma_vel_m_s for r in runs])), len(runs))
                for (name, cad), runs in self.runs.items()]

    def by_cadence(self, orbit_name: str) -> dict:
        """The rows of one orbit, keyed by cadence."""
        return {r[1]: r for r in self.rows if r[0] == orbit_name}

    def diverged_cells(self) -> list:
        """(orbit, cadence) cells where most runs diverged."""
        return [(name, cad) for name, cad, div, *_ in self.rows if div > 0.5]

    def cells_diverged_before(self, t_limit_h: dict) -> list:
        """(orbit, cadence) cells where most runs (> 50 %) diverged *before* a time, per orbit.

        A run counts when it diverged (:class:`tracking.TrialSummary`) and its first epoch above the NEES 99.9 %
        quantile is earlier than ``t_limit_h[orbit]`` hours after the start of the track (epoch ``k`` lies ``k``
        cadences after the start, :func:`tracking.make_scenario`); a numerical failure, whose epoch is not
        recorded, counts as early.  With ``t_limit_h`` the time of the first perilune this reads the paper's "leads
        to filter divergence before periapsis".
        """
        def early(run, cad, limit):
            k = run.first_inconsistent_epoch
            return run.diverged and (k < 0 or k * cad < limit)

        return [(name, cad) for (name, cad), runs in self.runs.items()
                if np.mean([early(r, cad, t_limit_h[name]) for r in runs]) > 0.5]

    def orbits_diverging_before(self, t_limit_h: dict) -> list:
        """Orbits on which most runs diverged before ``t_limit_h[orbit]`` hours in every cadence cell
        (:meth:`cells_diverged_before`): the paper's "every strategy leads to filter divergence before periapsis"."""
        cells = set(self.cells_diverged_before(t_limit_h))
        names = dict.fromkeys(name for name, _ in self.runs)
        return [n for n in names if all((n, cad) in cells for name, cad in self.runs if name == n)]

    def diverged_fraction(self, orbit_name: str, cadences) -> float:
        """Fraction of diverged runs of one orbit over the given cadences together."""
        return float(np.mean([r.diverged for c in cadences for r in self.runs[orbit_name, c]]))

    def report(self, label: str) -> str:
        lines = [label, (f"{'orbit':>24} {'cadence [h]':>11} {'diverged':>9} {'median NEES':>12} "
                         f"{'3s pos [km]':>12} {'3s vel [m/s]':>13} {'runs':>5}")]
        for name, cad, div, ne, sp, sv, n in self.rows:
            lines.append(f"{name:>24} {cad:11.3g} {100 * div:8.0f}% {ne:12.2f} {sp:12.4f} {sv:13.5f} {n:5d}")
        return "\n".join(lines)


def flagged_cells(rows, limit: float = 0.10) -> list:
    """(orbit, cadence, fraction) of rows where more than ``limit`` of the runs were inconsistent.

    ``rows`` are :attr:`StrategyStudy.rows`: tuples ``(orbit, cadence h, diverged fraction, ...)``.
    """
    if isinstance(rows, (str, bytes, dict)) or not hasattr(rows, "__iter__"):
        raise validation.ArgumentTypeError(f"rows must be a sequence of StrategyStudy rows; got {type(rows).__name__}")
    rows = list(rows)
    for i, row in enumerate(rows):
        if not isinstance(row, (tuple, list)) or len(row) < 3:
            raise validation.ArgumentTypeError(f"rows[{i}] must be a StrategyStudy row (orbit, cadence, diverged "
                                               f"fraction, ...); got {row!r:.60}")
        validation.in_range(row[2], f"rows[{i}] diverged fraction", 0.0, 1.0)
    limit = validation.in_range(limit, "limit", 0.0, 1.0)
    return [(name, cad, div) for name, cad, div, *_ in rows if div > limit]


#: Most trials per executor task; a task's trials run in lockstep through the batched OCBE
#: (:func:`tracking.filter_trials`).
LOCKSTEP_TRIALS = 64


def _trial_batch(task):
    """One executor task (module level, picklable): ``(scenario, control_weight, draws)`` with ``draws`` a list of
    ``(seed, i, handoff_scale)``, optionally followed by a dict of filter options of :func:`tracking.filter_trials`;
    trial ``i`` of the Monte Carlo set ``seed`` draws from the generator
    :func:`cislunar.utils.montecarlo.run_monte_carlo` would give it (:func:`cislunar.utils.montecarlo.trial_rng`), and
    all run in one lockstep (:func:`tracking.filter_trials`).  Returns their :class:`tracking.TrialSummary`."""
    scenario, control_weight, draws, *options = task
    return tracking.filter_trials([trial_rng(sd, i) for sd, i, _ in draws], scenario, control_weight,
                                  handoff_scale=[h for _, _, h in draws], **(options[0] if options else {}))


def _run_sets(sets, control_weight, executor, desc, progress=True):
    """Monte Carlo sets ``[(scenario, [(seed, i, handoff), ...]), ...]`` as lockstep tasks of at most
    :data:`LOCKSTEP_TRIALS` trials (the executor's tasks); returns one tuple of summaries per set."""
    tasks, sizes = [], []
    for scn, draws in sets:
        sizes.append(len(draws))
        tasks += [(scn, control_weight, draws[a:a + LOCKSTEP_TRIALS]) for a in range(0, len(draws), LOCKSTEP_TRIALS)]
    flat = [r for part in map_tasks(_trial_batch, tasks, executor=executor, desc=desc, progress=progress)
            for r in part]
    out, a = [], 0
    for n in sizes:
        out.append(tuple(flat[a:a + n]))
        a += n
    return out


def strategy_study(system: CR3BP, orbits_: dict, cadences, control_weight: float, *, rates: bool, n_runs: int,
                   seed: int, n_runs_one_minute: int | None = None, observers: str = "L2",
                   sigma_angle_rad: float = tracking.DEFAULT_SIGMA_ANGLE_RAD, handoff_scale: float = 1.0,
                   executor=None) -> StrategyStudy:
    """Monte Carlo of :func:`tracking.filter_trial` over orbits and cadences (tracks start at apoapsis).

    Cell (orbit k, cadence j) uses the seed ``(seed, k, j, int(rates))`` (trial ``i`` draws from its child ``i``);
    cadences under 0.1 h run ``n_runs_one_minute`` trials (default ``n_runs``).  The trials of a cell run in
    lockstep through the batched OCBE (:func:`tracking.filter_trials`, equal to :func:`tracking.filter_trial` to
    round-off), one executor task per cell (or per :data:`LOCKSTEP_TRIALS` trials).
    """
    check_system(system)
    _check_orbits(orbits_)
    cadences = _positive_values(cadences, "cadences")
    control_weight = validation.positive(control_weight, "control_weight")
    rates = validation.boolean(rates, "rates")
    n_runs = validation.integer(n_runs, "n_runs", minimum=1)
    n_one = n_runs if n_runs_one_minute is None else validation.integer(n_runs_one_minute, "n_runs_one_minute",
                                                                        minimum=1)
    seed = validation.integer(seed, "seed", minimum=0)
    validation.choice(observers, "observers", ("L2", "all"))
    sigma_angle_rad = validation.positive(sigma_angle_rad, "sigma_angle_rad")
    handoff_scale = validation.positive(handoff_scale, "handoff_scale")
    _check_executor(executor)
    keys, sets = [], []
    for k, (name, orb) in enumerate(orbits_.items()):
        for j, cad in enumerate(cadences):
            scn = tracking.make_scenario(system, orb, cad, start="apoapsis", rates=rates, observers=observers,
                                         sigma_angle_rad=sigma_angle_rad)
            keys.append((name, cad))
            sets.append((scn, [((seed, k, j, int(rates)), i, handoff_scale)
                               for i in range(_runs_at_cadence(cad, n_runs, n_one))]))
    runs = _run_sets(sets, control_weight, executor, f"{'angles+rates' if rates else 'angles'} {observers}")
    return StrategyStudy(dict(zip(keys, runs)), rates)


def _names(value, name: str) -> tuple:
    """A non-empty sequence of str, or a dict keyed by them (a single str is refused: it would be read letter by
    letter)."""
    if isinstance(value, (str, bytes)) or not hasattr(value, "__iter__"):
        raise validation.ArgumentTypeError(f"{name} must be a sequence of names (str); got {type(value).__name__}")
    out = tuple(value)
    if not out:
        raise ValueError(f"{name} must hold at least one name")
    for i, v in enumerate(out):
        validation.instance(v, f"{name}[{i}]", str)
    return out


def figure_final_uncertainty(rates: StrategyStudy, angles: StrategyStudy, orbit_names):
    """Final 3-sigma position and velocity against cadence (medians over runs; the paper's Table 4 analogue)."""
    validation.instance(rates, "rates", StrategyStudy, "a StrategyStudy (strategy_study)")
    validation.instance(angles, "angles", StrategyStudy, "a StrategyStudy (strategy_study)")
    orbit_names = _names(orbit_names, "orbit_names")
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.2))
    for io, (name, marker) in enumerate(zip(orbit_names, "os^")):
        for rows, ls, lab, ms in ((rates.rows, "-", "angles + rates", 9), (angles.rows, ":", "angles only", 4)):
            r = [row for row in rows if row[0] == name]
            kw = {"marker": marker, "ms": ms, "mfc": "none" if ms > 5 else None, "color": f"C{io}"}
            ax1.loglog([row[1] for row in r], [row[4] for row in r], ls, label=f"{name}, {lab}", **kw)
            ax2.loglog([row[1] for row in r], [row[5] for row in r], ls, **kw)
    ax1.set_ylabel("final 3-sigma position [km]")
    ax2.set_ylabel("final 3-sigma velocity [m/s]")
    for ax in (ax1, ax2):
        ax.set_xlabel("measurement cadence [h]")
    fig.legend(*ax1.get_legend_handles_labels(), loc="lower center", ncol=3, fontsize=8, bbox_to_anchor=(0.5, -0.02))
    fig.suptitle("Final filter uncertainty after one period versus cadence (median over runs; analogue of Table 4)")
    fig.tight_layout(rect=(0, 0.1, 1, 0.95))
    return fig


# ---------------------------------------------------------------------------------------------------------------
# Section 5b: the regime map
# ---------------------------------------------------------------------------------------------------------------
def _onset_class(run, t, t_perilune):
    k = run.first_inconsistent_epoch
    return ("numerical failure" if k < 0 else "first update" if k == 0 else
            "before perilune" if t[k] < t_perilune else "at or after perilune")


def pct_span(values) -> str:
    """'a-b %' of fractions (or 'a %' when both round alike)."""
    values = validation.as_array(values, "values", ndim=(1,), min_size=1)
    lo, hi = 100 * min(values), 100 * max(values)
    return f"{lo:.0f} %" if round(lo) == round(hi) else f"{lo:.0f}-{hi:.0f} %"


@dataclass(frozen=True)
class RegimeMap:
    """Fraction of diverged runs per (orbit, cadence h, angle noise rad, model, hand-off scale).

    Attributes
    ----------
    cells : dict
        Diverged fraction per key ``(orbit, cadence, sigma, model, handoff)``.
    onsets : dict
        Per key, where each diverged run's inconsistency starts (one of :data:`ONSETS`).
    model_names : tuple of str
        ``"angles"`` then the rate models.
    orbit_names : tuple of str
    cadences, sigmas, handoffs : tuple of float
    n_runs : int
        Runs per cell.
    paper_handoff : float
        The paper's hand-off scale (1: 10 km, 10 cm/s).
    """

    cells: dict
    onsets: dict
    model_names: tuple
    orbit_names: tuple
    cadences: tuple
    sigmas: tuple
    handoffs: tuple
    n_runs: int
    paper_handoff: float = 1.0

    def __getitem__(self, key):
        return self.cells[key]

    @property
    def map_cells(self) -> list:
        """(orbit, cadence, sigma, handoff) of every map cell."""
        return sorted({k[:3] + (k[4],) for k in self.cells})

    @property
    def rates_paper(self) -> str:
        """The rate model with the paper's 1-s differencing."""
        return self.model_names[1]

    def contrast_holds(self, oname, cad, sig, h, rates_model) -> bool:
        """The paper's contrast: most angles-only runs diverge while at most 10 % of the runs with rates do."""
        return self.cells[oname, cad, sig, "angles", h] > 0.5 and self.cells[oname, cad, sig, rates_model, h] <= 0.10

    @property
    def contrast(self) -> dict:
        """Per rate model, the map cells where the contrast holds."""
        return {m: [k for k in self.map_cells if self.contrast_holds(*k, m)] for m in self.model_names[1:]}

    @property
    def onset(self) -> dict:
        """The smallest hand-off (km) at which most angles-only runs diverge, per (orbit, cadence, sigma)."""
        out = {}
        for o in self.orbit_names:
            for c in self.cadences:
                for sg in self.sigmas:
                    hs = [10 * h for h in self.handoffs if self.cells[o, c, sg, "angles", h] > 0.5]
                    out[o, c, sg] = min(hs) if hs else None
        return out

    def at_paper_handoff(self, orbit_name) -> list:
        """Angles-only diverged fractions of one orbit at the paper's hand-off, over cadence and noise."""
        return [self.cells[orbit_name, c, sg, "angles", self.paper_handoff] for c in self.cadences
                for sg in self.sigmas]

    def noise_readings(self, orbit_name) -> dict:
        """Per angle noise (rad), the angles-only diverged fractions of one orbit at the paper's hand-off, one per
        cadence of the map (in the order of :attr:`cadences`)."""
        return {sg: [self.cells[orbit_name, c, sg, "angles", self.paper_handoff] for c in self.cadences]
                for sg in self.sigmas}

    def diverging_noises(self, orbit_name) -> list:
        """The angle noises (rad) of the map at which most angles-only runs (> 50 %) of one orbit diverge at the
        paper's hand-off at *every* cadence of the map: the paper's "every strategy [1 min-12 h] leads to filter
        divergence", stated at its one, unstated noise (Table 3 missing), read at each noise of the sweep."""
        return [sg for sg, fr in self.noise_readings(orbit_name).items() if min(fr) > 0.5]

    def onset_km(self, orbit_name):
        """Smallest hand-off (km) over noise and cadence at which most angles-only runs diverge (None: none)."""
        ons = [v for (o_, c, sg), v in self.onset.items() if o_ == orbit_name and v is not None]
        return min(ons) if ons else None

    def table_report(self) -> str:
        """The printed map: one line per (orbit, cadence, noise, model), one column per hand-off."""
        lines = [f"{'orbit':>24} {'cad':>4} {'sigma':>6} {'model':>27} "
                 + " ".join(f"{10.0 * h:>7g}km" for h in self.handoffs)]
        for oname, cad, sig, mname in dict.fromkeys(k[:4] for k in self.cells):
            lines.append(f"{oname:>24} {cad:4g} {sig * 1e6:6g} {mname:>27} "
                         + " ".join(f"{100 * self.cells[oname, cad, sig, mname, h]:8.0f}%" for h in self.handoffs))
        return "\n".join(lines)

    def analysis_report(self) -> str:
        """Contrast, exceptions, onsets, chance level and verdict (the printed analysis of the map)."""
        r, models, map_cells, lines = self.cells, self.model_names, self.map_cells, []
        contrast = self.contrast
        for m, ks in contrast.items():
            lines.append(f"cells where the paper's contrast holds with {m}: "
                         + ("; ".join(f"{o} {c:g} h {s * 1e6:g} urad hand-off {10 * h:g} km" for o, c, s, h in ks)
                            or "none"))
        angles_div = [k for k in map_cells if r[k[:3] + ("angles", k[3])] > 0.5]
        rates_div = {m: np.mean([r[k[:3] + (m, k[3])] > 0.5 for k in angles_div]) for m in models[1:]}
        lines.append(f"cells where most angles-only runs diverge: {len(angles_div)} of {len(map_cells)}; among them, "
                     "most runs with rates diverge too in "
                     + ", ".join(f"{100 * v:.0f} % ({m})" for m, v in rates_div.items()))
        for m in models[1:]:
            exceptions = [k for k in angles_div if r[k[:3] + (m, k[3])] <= 0.5]
            lines.append(f"   the exceptions with {m} (diverged, angles only -> with rates): "
                         + ("; ".join(f"{o} {c:g} h {s_ * 1e6:g} urad {10 * h:g} km "
                                      f"{100 * r[o, c, s_, 'angles', h]:.0f} % -> {100 * r[o, c, s_, m, h]:.0f} %"
                                      for o, c, s_, h in exceptions) or "none"))
        for o in self.orbit_names:
            ons = self.onset_km(o)
            lines.append(f"{o}: at the paper's 10-km hand-off, {pct_span(self.at_paper_handoff(o))} of angles-only "
                         "runs diverge (over noise and cadence); most of them diverge from a hand-off of "
                         + (f"{ons:g} km on (smallest over noise and cadence)" if ons is not None else
                            f"no map value (up to {10 * max(self.handoffs):g} km)"))
        for o in self.orbit_names:
            cls = [c for k, v in self.onsets.items() if k[0] == o and k[3] == "angles" for c in v]
            if cls:
                lines.append(f"{o}, angles only: {len(cls)} diverged runs; inconsistency starts at "
                             + ", ".join(f"{name} {100 * cls.count(name) / len(cls):.0f} %" for name in ONSETS))
        big_h = [h for h in self.handoffs if h >= 100.0]
        small_h = [h for h in self.handoffs if h <= 1.0]
        for label, hs in ((f"hand-off >= {10 * min(big_h):g} km", big_h),
                          (f"hand-off <= {10 * max(small_h):g} km", small_h)):
            cls = [c for k, v in self.onsets.items() if k[4] in hs for c in v]
            if cls:
                lines.append(f"all diverged runs with {label}: {len(cls)}; starting at the first update "
                             f"{100 * cls.count('first update') / len(cls):.0f} %, at or after perilune "
                             f"{100 * cls.count('at or after perilune') / len(cls):.0f} %")
                for o in self.orbit_names:
                    cls_o = [c for k, v in self.onsets.items() if k[4] in hs and k[0] == o for c in v]
                    if cls_o:
                        lines.append(f"   of which {o}: {len(cls_o)}; at the first update "
                                     f"{100 * cls_o.count('first update') / len(cls_o):.0f} %, at or after perilune "
                                     f"{100 * cls_o.count('at or after perilune') / len(cls_o):.0f} %")
        se_diff = np.sqrt(2 * 0.5 * 0.5 / self.n_runs)  # standard error of the difference of two fractions near 50 %
        lines.append(f"a difference of 30 points between two {self.n_runs}-run fractions near 50 % is "
                     f"{0.3 / se_diff:.1f} standard errors of chance")
        for m in models[1:]:
            k_best = max(map_cells, key=lambda k: r[k[:3] + ("angles", k[3])] - r[k[:3] + (m, k[3])])
            o, c, sg, h = k_best
            diff = np.array([r[k[:3] + ("angles", k[3])] - r[k[:3] + (m, k[3])] for k in map_cells])
            lines.append(f"largest drop with {m}: {o} {c:g} h {sg * 1e6:g} urad hand-off {10 * h:g} km, diverged "
                         f"{100 * r[o, c, sg, 'angles', h]:.0f} % -> {100 * r[o, c, sg, m, h]:.0f} %; over the map, "
                         f"angles only minus with rates: mean {100 * diff.mean():+.1f} points; 30+ points fewer "
                         f"diverged runs with rates in {np.sum(diff >= 0.3)} cell(s), 30+ points more in "
                         f"{np.sum(diff <= -0.3)}")
            ih = self.handoffs.index(h)
            lines.append("   the same orbit, cadence and noise at the neighbouring hand-offs: "
                         + "; ".join(f"{10 * hn:g} km {100 * r[o, c, sg, 'angles', hn]:.0f} % -> "
                                     f"{100 * r[o, c, sg, m, hn]:.0f} %"
                                     for hn in self.handoffs[max(ih - 1, 0):ih + 2] if hn != h))
        n_any = sum(len(v) for v in contrast.values())
        lines.append("verdict: " + (
            "the paper's contrast (most angles-only runs diverge, at most 10 % of the runs with rates do) "
            f"appears in no cell of the map ({len(map_cells)} cells x {len(models) - 1} rate models)"
            if n_any == 0 else
            f"the paper's contrast appears in {n_any} (cell, rate model) combinations: "
            + "; ".join(f"{o} {c:g} h {s * 1e6:g} urad {10 * h:g} km ({m})" for m, ks in contrast.items()
                        for o, c, s, h in ks)))
        return "\n".join(lines)

    def divergence_cells(self):
        """The two angles-only cells shown as Fig. 4 analogues: the 9:2 NRHO cell closest to the paper's set-up
        among those where most runs diverge (smallest hand-off, then largest fraction), and the cell of any orbit
        with the most diverged runs at the paper's hand-off."""
        r = self.cells
        angles_cells = [k for k in r if k[3] == "angles"]
        div_92 = [k for k in angles_cells if k[0] == "9:2 NRHO" and r[k] > 0.5]
        cell_92 = (min(div_92, key=lambda k: (k[4], -r[k])) if div_92 else
                   max((k for k in angles_cells if k[0] == "9:2 NRHO"), key=lambda k: (r[k], k[4])))
        h_paper = min(self.handoffs, key=lambda h: abs(h - self.paper_handoff))
        cell_paper = max((k for k in angles_cells if k[4] == h_paper), key=lambda k: r[k])
        return cell_92, cell_paper


def regime_map(system: CR3BP, orbits_: dict, cadences, sigmas, handoffs, rate_models: dict, control_weight: float,
               *, n_runs: int, seed: int, executor=None) -> RegimeMap:
    """Diverged fractions of angles-only and angles + rates runs over the map.

    Cell indices ``(io, ic, isg, im, ih)`` seed run sets as ``(seed, 77, io, ic, isg, im, ih)`` (run ``i`` draws
    from its child ``i``).  The runs of all hand-offs of an (orbit, cadence, noise, model) share a scenario and run
    in lockstep through the batched OCBE (:func:`tracking.filter_trials`), one executor task per
    :data:`LOCKSTEP_TRIALS` runs.

    Parameters
    ----------
    rate_models : dict of str -> float
        Name of each rate model and the differencing baseline of Eq. 13 it uses, s.
    """
    check_system(system)
    _check_orbits(orbits_)
    cadences = _positive_values(cadences, "cadences")
    sigmas = _positive_values(sigmas, "sigmas")
    handoffs = _positive_values(handoffs, "handoffs")
    validation.instance(rate_models, "rate_models", dict, "a dict of name -> differencing baseline (s)")
    for m, b in rate_models.items():
        validation.instance(m, "rate_models", str, "a dict of name (str) -> differencing baseline (s)")
        validation.positive(b, "rate_models")
    control_weight = validation.positive(control_weight, "control_weight")
    n_runs = validation.integer(n_runs, "n_runs", minimum=1)
    seed = validation.integer(seed, "seed", minimum=0)
    _check_executor(executor)
    cells, onsets = {}, {}
    models = [("angles", False, 1.0)] + [(m, True, b) for m, b in rate_models.items()]
    keys, sets = [], []
    for io, (oname, orb) in enumerate(orbits_.items()):
        for ic, cad in enumerate(cadences):
            for isg, sig in enumerate(sigmas):
                for im, (mname, rates, base) in enumerate(models):
                    scn = tracking.make_scenario(system, orb, cad, start="apoapsis", rates=rates, sigma_angle_rad=sig)
                    if rates:
                        scn = dataclasses.replace(scn, meas_cov=tracking.angles_rates_covariance(system, sig, base))
                    keys += [((oname, cad, sig, mname, h), scn.t, orb.period / 2) for h in handoffs]
                    sets.append((scn, [((seed, 77, io, ic, isg, im, ih), i, h) for ih, h in enumerate(handoffs)
                                       for i in range(n_runs)]))
    flat = [r for runs in _run_sets(sets, control_weight, executor, "regime map") for r in runs]
    for j, (key, t, t_peri) in enumerate(keys):
        runs = flat[j * n_runs:(j + 1) * n_runs]
        cells[key] = float(np.mean([r.diverged for r in runs]))
        onsets[key] = [_onset_class(r, t, t_peri) for r in runs if r.diverged]
    return RegimeMap(cells, onsets, tuple(m[0] for m in models), tuple(orbits_), tuple(cadences), tuple(sigmas),
                     tuple(handoffs), n_runs)


#: The filter-side axes of :func:`filter_axes_study`: name -> (options of :func:`tracking.filter_trials`, factor on
#: the control weight).  The first is the chapter's filter; "unwrapped azimuth" is a deliberately mishandled branch
#: cut (a filter bug some implementations have), the others are filters a careful implementer might choose.
FILTER_AXES = {
    "baseline": ({}, 1.0),
    "unwrapped azimuth": ({"wrap_azimuth": False}, 1.0),
    "fixed reference": ({"relinearize": False}, 1.0),
    "control weight x0.01": ({}, 0.01),
    "control weight x100": ({}, 100.0),
    "control weight x1e8": ({}, 1e8),
    "coarse STM": ({"coarse_stm": True}, 1.0),
}


@dataclass(frozen=True)
class FilterAxesStudy:
    """Diverged fractions per (filter axis, orbit, cadence h, model) at one hand-off and angle noise.

    Every axis filters the same draws (common random numbers: a cell's measurements and hand-offs do not depend on
    the filter), so differences between axes are the filters'.

    Attributes
    ----------
    cells : dict
        Diverged fraction per key ``(axis, orbit, cadence, model)``, model ``"angles"`` or ``"angles+rates"``.
    onsets : dict
        Per key, where each diverged run's inconsistency starts (one of :data:`ONSETS`).
    axes : tuple of str
        Names of the axes (keys of :data:`FILTER_AXES` or the caller's).
    orbit_names : tuple of str
    cadences : tuple of float
        Cadences, hours, increasing (the table's and the figure's order; the draws follow the caller's order).
    n_runs : int
        Runs per cell (at cadences of 0.1 h and more; ``n_runs_one_minute`` below).
    n_runs_one_minute : int
    handoff : float
        Hand-off scale (1: the paper's 10 km, 10 cm/s, 3 sigma).
    sigma_angle_rad : float
    """

    cells: dict
    onsets: dict
    axes: tuple
    orbit_names: tuple
    cadences: tuple
    n_runs: int
    n_runs_one_minute: int
    handoff: float
    sigma_angle_rad: float

    MODELS = ("angles", "angles+rates")

    def runs_at(self, cadence: float) -> int:
        """Runs per cell at ``cadence`` (hours): ``n_runs_one_minute`` under 0.1 h, else ``n_runs``."""
        return _runs_at_cadence(cadence, self.n_runs, self.n_runs_one_minute)

    @property
    def total_runs(self) -> int:
        """Filter runs in the study (every axis, orbit, cadence and model)."""
        return len(self.axes) * len(self.orbit_names) * len(self.MODELS) * sum(self.runs_at(c) for c in self.cadences)

    def worst_cadence(self, axis: str, orbit_name: str, model: str) -> float:
        """The cadence (hours) at which ``axis`` has most diverged runs for ``orbit_name`` and ``model`` (ties: the
        shortest cadence)."""
        return max(self.cadences, key=lambda c: self.cells[axis, orbit_name, c, model])

    def contrast_holds(self, axis, orbit_name, cadence) -> bool:
        """The paper's contrast in one cell: most angles-only runs diverge, at most 10 % of the runs with rates do
        (the regime map's reading, :meth:`RegimeMap.contrast_holds`)."""
        return (self.cells[axis, orbit_name, cadence, "angles"] > 0.5
                and self.cells[axis, orbit_name, cadence, "angles+rates"] <= 0.10)

    @property
    def contrast(self) -> dict:
        """Per axis, the (orbit, cadence) cells where the contrast holds."""
        return {a: [(o, c) for o in self.orbit_names for c in self.cadences if self.contrast_holds(a, o, c)]
                for a in self.axes}

    @property
    def axes_with_full_contrast(self) -> list:
        """The axes whose contrast holds in every (orbit, cadence) cell (the paper: every cadence)."""
        n = len(self.orbit_names) * len(self.cadences)
        return [a for a, ks in self.contrast.items() if len(ks) == n]

    def report(self) -> str:
        """One line per (axis, orbit, model), one column per cadence (diverged runs, %), then the contrast."""
        lines = [f"{'filter':>22} {'orbit':>10} {'model':>13} " + " ".join(f"{cadence_label(c):>7}"
                                                                           for c in self.cadences)]
        for a in self.axes:
            for o in self.orbit_names:
                for m in self.MODELS:
                    lines.append(f"{a:>22} {o:>10} {m:>13} "
                                 + " ".join(f"{100 * self.cells[a, o, c, m]:6.0f}%" for c in self.cadences))
        n = len(self.orbit_names) * len(self.cadences)
        for a, ks in self.contrast.items():
            lines.append(f"contrast with {a}: {len(ks)} of {n} cells"
                         + (": " + ", ".join(f"{o} {cadence_label(c)}" for o, c in ks) if ks else ""))
        for a in self.axes:
            cls = [c for k, v in self.onsets.items() if k[0] == a for c in v]
            if cls:
                lines.append(f"{a}: {len(cls)} diverged runs; inconsistency starts at "
                             + ", ".join(f"{name} {100 * cls.count(name) / len(cls):.0f} %" for name in ONSETS))
        return "\n".join(lines)


def filter_axes_study(system: CR3BP, orbits_: dict, cadences, control_weight: float, *, n_runs: int, seed: int,
                      n_runs_one_minute: int | None = None, axes: dict | None = None, handoff_scale: float = 1.0,
                      sigma_angle_rad: float = tracking.DEFAULT_SIGMA_ANGLE_RAD, executor=None,
                      progress: bool = True) -> FilterAxesStudy:
    """The regime map's key cells (tracks from apoapsis, one hand-off, angles only vs angles + the paper's 1-s rates)
    along filter-side axes.

    Parameters
    ----------
    system : CR3BP
    orbits_ : dict of str -> PeriodicOrbit
    cadences : sequence of float
        Measurement cadences, hours.  Their order fixes the draws (index ``ic`` in the seed below), so a cadence
        appended to the list leaves every earlier cell's runs as they were; the study lists them increasing.
    control_weight : float
        The chapter's OCBE control weight, LU^2/TU^3 (each axis multiplies it by its factor).
    n_runs : int
        Runs per (axis, orbit, cadence, model) cell.
    n_runs_one_minute : int, optional
        Runs per cell at cadences under 0.1 h (default ``n_runs``).
    seed : int
        Cell ``(orbit io, cadence ic, model im)`` draws run ``i`` from child ``i`` of ``(seed, 23, io, ic, im)``,
        the same for every axis.
    axes : dict of str -> (dict, float), optional
        Name -> (options of :func:`tracking.filter_trials`, control-weight factor); default :data:`FILTER_AXES`.
    handoff_scale : float
        Hand-off scale (1: the paper's 10 km, 10 cm/s, 3 sigma).
    sigma_angle_rad : float
        Angle noise (1 sigma), rad; the rates are Eq. 13's with a 1-s baseline.
    executor : optional
        As in :func:`strategy_study` (one task per :data:`LOCKSTEP_TRIALS` runs of a cell).
    """
    check_system(system)
    _check_orbits(orbits_)
    cadences = _positive_values(cadences, "cadences")
    control_weight = validation.positive(control_weight, "control_weight")
    n_runs = validation.integer(n_runs, "n_runs", minimum=1)
    n_one = n_runs if n_runs_one_minute is None else validation.integer(n_runs_one_minute, "n_runs_one_minute",
                                                                        minimum=1)
    seed = validation.integer(seed, "seed", minimum=0)
    axes = FILTER_AXES if axes is None else axes
    validation.instance(axes, "axes", dict, "a dict of name -> (filter options dict, control-weight factor)")
    allowed = {"wrap_azimuth", "relinearize", "coarse_stm"}
    for name, spec in axes.items():
        validation.instance(name, "axes", str, "a dict with str names")
        if not (isinstance(spec, tuple) and len(spec) == 2 and isinstance(spec[0], dict)):
            raise validation.ArgumentTypeError(f"axes[{name!r}] must be a (filter options dict, factor) pair")
        if set(spec[0]) - allowed:
            raise ValueError(f"axes[{name!r}] options must be among {sorted(allowed)}; got {sorted(spec[0])}")
        validation.positive(spec[1], f"axes[{name!r}] factor")
    handoff_scale = validation.positive(handoff_scale, "handoff_scale")
    sigma_angle_rad = validation.positive(sigma_angle_rad, "sigma_angle_rad")
    validation.boolean(progress, "progress")
    _check_executor(executor)
    keys, tasks, sizes = [], [], []
    for io, (oname, orb) in enumerate(orbits_.items()):
        for ic, cad in enumerate(cadences):
            for im, rates in enumerate((False, True)):
                scn = tracking.make_scenario(system, orb, cad, start="apoapsis", rates=rates,
                                             sigma_angle_rad=sigma_angle_rad)
                n = _runs_at_cadence(cad, n_runs, n_one)
                draws = [((seed, 23, io, ic, im), i, handoff_scale) for i in range(n)]
                for name, (options, factor) in axes.items():
                    keys.append(((name, oname, cad, FilterAxesStudy.MODELS[im]), scn.t, orb.period / 2))
                    parts = [draws[a:a + LOCKSTEP_TRIALS] for a in range(0, n, LOCKSTEP_TRIALS)]
                    sizes.append(len(parts))
                    tasks += [(scn, control_weight * factor, part, dict(options)) for part in parts]
    out = map_tasks(_trial_batch, tasks, executor=executor, desc="filter axes", progress=progress)
    cells, onsets, a = {}, {}, 0
    for (key, t, t_peri), n_parts in zip(keys, sizes):
        runs = [r for part in out[a:a + n_parts] for r in part]
        a += n_parts
        cells[key] = float(np.mean([r.diverged for r in runs]))
        onsets[key] = [_onset_class(r, t, t_peri) for r in runs if r.diverged]
    return FilterAxesStudy(cells, onsets, tuple(axes), tuple(orbits_), tuple(sorted(float(c) for c in cadences)),
                           n_runs, n_one, handoff_scale, sigma_angle_rad)


def figure_filter_axes(study: FilterAxesStudy):
    """Diverged runs against cadence, one row per orbit, one column per model (angles only, angles + rates), one
    curve per filter axis; the shaded band is the 10 % a consistent filter is allowed, the dotted line 50 %."""
    validation.instance(study, "study", FilterAxesStudy, "a FilterAxesStudy (filter_axes_study)")
    n_orb = len(study.orbit_names)
    fig, axes = plt.subplots(n_orb, 2, squeeze=False, figsize=(11.0, 3.8 * n_orb), sharex=True, sharey=True)
    for io, o in enumerate(study.orbit_names):
        for jm, m in enumerate(study.MODELS):
            ax = axes[io, jm]
            for ia, a in enumerate(study.axes):
                ax.plot(study.cadences, [100 * study.cells[a, o, c, m] for c in study.cadences],
                        ls=("-", "--", ":")[ia % 3], marker="osd^v<>"[ia % 7], mfc="none" if ia else None,
                        color=f"C{ia}", label=a if io == jm == 0 else None)
            ax.axhspan(-5, 10, color="0.9", zorder=0)
            ax.axhline(50, color="0.6", lw=0.8, ls=":")
            ax.set(xscale="log", ylim=(-5, 105), title=f"{o}, {m}, hand-off {10 * study.handoff:g} km")
            ax.set_xticks(study.cadences, [cadence_label(c) for c in study.cadences])  # the cadences run, by name
            ax.xaxis.set_minor_locator(ticker.NullLocator())
            if io == n_orb - 1:
                ax.set_xlabel("measurement cadence [min, h: as ticked]")
            if jm == 0:
                ax.set_ylabel("diverged runs [%]")
    fig.legend(loc="lower center", ncol=4, fontsize=8, bbox_to_anchor=(0.5, 0.0))
    fig.tight_layout(rect=(0, 0.1, 1, 1))
    return fig


def figure_regime_map(rmap: RegimeMap):
    """One panel per orbit, cadence and noise: diverged runs against hand-off, one curve per model."""
    validation.instance(rmap, "rmap", RegimeMap, "a RegimeMap (regime_map)")
    n_cols = len(rmap.cadences) * len(rmap.sigmas)
    n_orb = len(rmap.orbit_names)
    handoff_km = [10.0 * h for h in rmap.handoffs]
    fig, axes = plt.subplots(n_orb, n_cols, squeeze=False, figsize=(3.3 * max(n_cols, 3), 3.0 * n_orb),
                             sharex=True, sharey=True)
    for io, oname in enumerate(rmap.orbit_names):
        for ic, cad in enumerate(rmap.cadences):
            for isg, sig in enumerate(rmap.sigmas):
                ax = axes[io, ic * len(rmap.sigmas) + isg]
                for im, mname in enumerate(rmap.model_names):
                    ax.plot(handoff_km, [100 * rmap[oname, cad, sig, mname, h] for h in rmap.handoffs],
                            marker="osd"[im % 3], ls=("-", "--", ":")[im % 3], ms=8 - 2 * im,
                            mfc="none" if im else None, color=f"C{im}", label=mname)
                ax.axvline(10.0, color="0.6", lw=0.8, ls="-.")
                ax.set(xscale="log", ylim=(-5, 105))
                ax.set_title(f"{oname.replace('stable NRHO', 'stable')}\n{cad:g} h, {sig * 1e6:g} urad", fontsize=9)
                if io == n_orb - 1:
                    ax.set_xlabel("hand-off 3-sigma [km]")
                if ic == isg == 0:
                    ax.set_ylabel("diverged runs [%]")
    handles, labels = axes[0, 0].get_legend_handles_labels()
    handles.append(plt.Line2D([], [], color="0.6", lw=0.8, ls="-."))
    labels.append("the paper's hand-off (10 km)")
    fig.legend(handles, labels, loc="lower center", ncol=4, fontsize=9, bbox_to_anchor=(0.5, 0.0))
    fig.tight_layout(rect=(0, 0.04, 1, 1))
    return fig


# ---------------------------------------------------------------------------------------------------------------
# Fig. 4 analogues
# ---------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class DivergenceExample:
    """The diverged draw with the largest mean NEES among fresh draws of an angles-only map cell.

    Attributes
    ----------
    cell : tuple
        ``(orbit, cadence, sigma, model, handoff)`` of the map.
    scenario : TrackingScenario
    truth : ndarray, shape (N, 6)
    result : OCBEResult or None
        The forward filter of the chosen draw (None: no completed diverged draw).
    summary : TrialSummary or None
    draw : int
        Index of the chosen draw.
    diverged_fraction : float
        The cell's diverged fraction in the map.
    """

    cell: tuple
    scenario: tracking.TrackingScenario
    truth: np.ndarray
    result: object
    summary: object
    draw: int
    diverged_fraction: float

    def report(self, what: str) -> str:
        orbit_name, cad, sig, _, h = self.cell
        if self.result is None:
            return (f"no completed diverged run among ten draws of {orbit_name}, {cad:g} h, {sig * 1e6:g} urad, "
                    f"{10 * h:g} km ({100 * self.diverged_fraction:.0f} % diverged in the map)")
        s, sc, system = self.summary, self.scenario, self.scenario.system
        k0 = s.first_inconsistent_epoch
        return (f"{what}: draw {self.draw}, mean NEES {s.nees_mean:.0f}, {100 * s.inconsistent_fraction:.0f} % of "
                f"epochs above the 99.9 % quantile, first at day {system.tu_to_days(sc.t[k0]):.2f} (perilune at day "
                f"{system.tu_to_days(sc.orbit.period / 2):.2f}); largest position error {s.max_error_pos_km:.0f} km; "
                f"{100 * self.diverged_fraction:.0f} % of this cell's runs diverged in the map")


def divergence_example(system: CR3BP, orbit: PeriodicOrbit, rmap: RegimeMap, cell, control_weight: float, *,
                       seed: int, n_draws: int = 10) -> DivergenceExample:
    """Rerun ``n_draws`` fresh draws (seeds ``[seed, 404, k]``) of an angles-only map ``cell`` and keep the diverged
    one with the largest mean NEES.

    The draws are filtered in one lockstep (:func:`cislunar.estimation.batched_ocbe.ocbe_batch`, filter only, a
    numerical failure dropping the draw); the chosen draw is rerun with the single-trial filter
    (:func:`cislunar.estimation.ocbe.ocbe_filter_smoother`), whose result and summary are kept."""
    check_system(system)
    validation.instance(orbit, "orbit", PeriodicOrbit, "a cislunar.cr3bp.orbits.PeriodicOrbit")
    validation.instance(rmap, "rmap", RegimeMap, "a RegimeMap (regime_map)")
    if not isinstance(cell, tuple) or len(cell) != 5 or cell not in rmap.cells:
        raise ValueError(f"cell must be a key (orbit, cadence, sigma, model, handoff) of rmap.cells; got {cell!r:.80}")
    control_weight = validation.positive(control_weight, "control_weight")
    seed = validation.integer(seed, "seed", minimum=0)
    n_draws = validation.integer(n_draws, "n_draws", minimum=1)
    _, cad, sig, _, h = cell
    scn = tracking.make_scenario(system, orbit, cad, start="apoapsis", rates=False, sigma_angle_rad=sig)
    truth = tracking.simulate_truth(system, scn.x_start, scn.t)
    ys, x0s = [], []
    for k in range(n_draws):
        rng = np.random.default_rng([seed, 404, k])
        ys.append(tracking.simulate_measurements(scn, truth, rng))
        x0, P0 = tracking.initial_estimate(system, scn.x_start, rng, scale=h)
        x0s.append(x0)
    res = batched_ocbe.ocbe_batch(system, scn.t, np.array(ys), scn.observers, scn.model, scn.meas_cov,
                                  np.array(x0s), P0, control_weight, available=scn.available, smooth=False,
                                  on_failure="flag")
    best = None
    for k in np.flatnonzero(~res.failed):
        summ = tracking.summarize(system, res.x_filt[k], res.P_filt[k], truth)
        if summ.diverged and (best is None or summ.nees_mean > best[1]):
            best = (int(k), summ.nees_mean)
    if best is None:
        return DivergenceExample(tuple(cell), scn, truth, None, None, -1, rmap[cell])
    k = best[0]
    run = ocbe.ocbe_filter_smoother(system, scn.t, ys[k], scn.observers, scn.model, scn.meas_cov, x0s[k], P0,
                                    control_weight, available=scn.available, smooth=False)
    return DivergenceExample(tuple(cell), scn, truth, run, tracking.summarize(system, run.x_filt, run.P_filt, truth),
                             k, rmap[cell])


def figure_divergence(example: DivergenceExample, what: str):
    """Error norms, 3-sigma bounds and the NEES against its 99.9 % quantile; perilune dotted."""
    validation.instance(example, "example", DivergenceExample, "a DivergenceExample (divergence_example)")
    if example.result is None:
        raise ValueError("example holds no completed diverged run (result is None): nothing to draw")
    validation.instance(what, "what", str)
    orbit_name, cad, sig, _, h = example.cell
    sc, run, system = example.scenario, example.result, example.scenario.system
    fig, axes = plt.subplots(3, 1, figsize=(8, 7.5), sharex=True)
    _error_panels(system, axes[0], axes[1], sc.t, run.x_filt, run.P_filt, example.truth, "forward filter")
    axes[1].set_xlabel("")
    axes[2].semilogy(system.tu_to_days(sc.t), consistency.nees(run.x_filt, run.P_filt, example.truth), color="C0",
                     label="NEES")
    axes[2].axhline(stats.chi2.ppf(consistency.NEES_PROBABILITY, 6), color="C1", ls="--",
                    label=r"99.9 % quantile of $\chi^2_6$")
    axes[2].set(ylabel="NEES [-]", xlabel="time since apoapsis [d]")
    for ax in axes:
        ax.axvline(system.tu_to_days(sc.orbit.period / 2), color="0.5", ls=":", lw=1, label="perilune")
    for ax in axes:
        _plain_log_ticks(ax)
    axes[0].legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    axes[2].legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    fig.suptitle(f"{what}: angles only, {orbit_name}, {cad:g} h, {sig * 1e6:g} urad, hand-off 3-sigma {10 * h:g} km "
                 "(analogue of Fig. 4)", fontsize=10)
    fig.tight_layout()
    return fig


def _plain_log_ticks(ax) -> None:
    """Label a log y axis that spans less than two decades at 1, 2 and 5 times a power of ten, in plain numbers
    (matplotlib would otherwise label its minor ticks as 2x10^0, 3x10^0, ... and crowd the axis)."""
    lo, hi = ax.get_ylim()
    if lo > 0 and hi / lo < 100:
        ax.yaxis.set_major_locator(ticker.LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
        ax.yaxis.set_major_formatter(ticker.FuncFormatter(lambda v, _: f"{v:g}"))
        ax.yaxis.set_minor_formatter(ticker.NullFormatter())


# ---------------------------------------------------------------------------------------------------------------
# Which stable NRHO, by evidence
# ---------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class StableCandidates:
    """Both stable-NRHO candidates against the 9:2 NRHO on the paper's two remarks (angles + rates).

    Attributes
    ----------
    better : dict of str -> float
        Per candidate, fraction of cadences at which its median final 3-sigma position is below the 9:2 NRHO's.
    ratio : dict of str -> list of float
        Per candidate, its median final 3-sigma position over the 9:2 NRHO's, per cadence.
    inconsistent : dict of str -> float
        Per orbit (the 9:2 NRHO included), fraction of diverged runs at the long cadences.
    long_cadences : tuple of float
        Cadences of at least 6 h.
    """

    better: dict
    ratio: dict
    inconsistent: dict
    long_cadences: tuple

    def supports(self, name) -> bool:
        """Fits both remarks: better determined at half the cadences or more, at most 10 % inconsistent runs."""
        return self.better[name] >= 0.5 and self.inconsistent[name] <= 0.10

    def report(self) -> str:
        lines = [f"{name}: better determined than the 9:2 at {100 * b:.0f} % of cadences; inconsistent runs at "
                 f"{'/'.join(f'{c:g}' for c in self.long_cadences)} h: {100 * self.inconsistent[name]:.0f} %"
                 for name, b in self.better.items()]
        outer = next(k for k in self.ratio if "outer" in k)
        lines.append(f"outer band / 9:2 final 3-sigma position: {min(self.ratio[outer]):.2f}-"
                     f"{max(self.ratio[outer]):.2f}")
        ok = [("inner band" if "inner" in k else "outer band") for k in self.better if self.supports(k)]
        lines.append("candidates that fit both remarks: " + (", ".join(ok) or "neither"))
        return "\n".join(lines)


def compare_stable_candidates(rates: StrategyStudy, reference: str, candidates, cadences) -> StableCandidates:
    """Compare ``candidates`` (orbit names) with the ``reference`` orbit on the median final 3-sigma position and
    the diverged runs at cadences of 6 h or more."""
    validation.instance(rates, "rates", StrategyStudy, "a StrategyStudy (strategy_study)")
    names = {name for name, _ in rates.runs}
    validation.instance(reference, "reference", str)
    if reference not in names:
        raise ValueError(f"reference must be an orbit of the study {sorted(names)}; got {reference!r}")
    candidates = _names(candidates, "candidates")
    for c in candidates:
        if c not in names:
            raise ValueError(f"candidates must be orbits of the study {sorted(names)}; got {c!r}")
    study_cadences = {cad for _, cad in rates.runs}
    cadences = tuple(float(c) for c in validation.as_array(cadences, "cadences", ndim=(1,), min_size=1))
    if any(c not in study_cadences for c in cadences):
        raise ValueError(f"cadences must be cadences of the study {sorted(study_cadences)}; got {cadences}")
    r92 = rates.by_cadence(reference)
    rows = {name: rates.by_cadence(name) for name in candidates}
    long_gap = tuple(c for c in cadences if c >= 6.0)
    better = {n: float(np.mean([rows[n][c][4] < r92[c][4] for c in r92])) for n in candidates}
    ratio = {n: [rows[n][c][4] / r92[c][4] for c in r92] for n in candidates}
    incons = {n: rates.diverged_fraction(n, long_gap) for n in (reference, *candidates)}
    return StableCandidates(better, ratio, incons, long_gap)
