r"""Notebook 12's set-ups (Nychka & Bhattacharya §IV-B, Fig. 3): the designs of notebook 11 flown on the nonlinear
CR3BP with noisy angles, the criterion for "converge rapidly and stay accurate", and the re-run at the sampling
interval where the paper's H2 number holds.

Methods: :mod:`cislunar.estimation.lpv` (designs, guarantees) and :mod:`cislunar.estimation.observers` (the LPV
observer of Eq. 3a and the EKF).  Units: LU, TU, deg; planar rotating-frame states ``[x, y, vx, vy]``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cislunar.cr3bp.propagation import propagate
from cislunar.estimation import lpv
from cislunar.estimation.observers import (
    make_measurements,
    simulate_ekf,
    simulate_lpv_observer,
)
from cislunar.papers.nychka_bhattacharya.scenarios import (
    GAMMA,
    POLE_RADIUS,
    THETA1_SENSORS,
    Scenario,
)
from cislunar.utils import validation
from cislunar.utils.montecarlo import map_tasks

__all__ = ["INITIAL_ERROR", "E0_SCALES", "observer_designs", "ObserverDesigns", "AllowanceAtDt", "allowance_at",
           "Fig3Runs", "simulate_fig3",
           "first_and_rms", "Convergence", "convergence_study", "LineCrossings", "line_crossings", "WindowRerun",
           "window_rerun", "RANGE_CHANNELS", "RangeFree", "PAPER_ALLOWANCE_DEG", "RAPID_FRACTION", "Fig3Accuracy"]

#: Initial estimate error (LU, LU/TU): 0.02 LU in x and -0.02 LU in y (about 10,900 km), 0.01 LU/TU (10 m/s) in
#: each velocity.  The paper says only "large initial errors".
INITIAL_ERROR = np.array([0.02, -0.02, 0.01, 0.01])
#: Scales of the initial error swept by :func:`convergence_study`.
E0_SCALES = (0.003, 0.01, 0.03, 0.1, 0.3, 1.0)
#: The paper's allowable angle noise for gamma = 0.0013 (§IV-B, Eq. 24), deg: the noise level at which each design
#: is accurate to gamma by the paper's own reading.  Fig. 3 flies both at 0.1 deg.
PAPER_ALLOWANCE_DEG = {"h2": 0.1, "hinf": 0.08}
#: "Rapidly converge": first below the accuracy level within this fraction of the orbit period (fixed before the
#: first runs of the chapter; see ``claims.observer_simulation``).
RAPID_FRACTION = 0.05
#: Indices of the range-squared channels r13^2, r23^2 in the sensor model of Eq. 22 (``lpv.SENSOR_NAMES``).
RANGE_CHANNELS = (4, 5)


@dataclass(frozen=True)
class ObserverDesigns:
    """The theta1-only H2 and bandwidth-bounded H-infinity gains and their verification (keys ``"h2"``, ``"hinf"``)."""

    designs: dict
    verification: dict


def observer_designs(scenario: Scenario, n_verify: int, rng: np.random.Generator, *, gamma: float = GAMMA,
                     pole_radius: float = POLE_RADIUS) -> ObserverDesigns:
    """Solve both theorems on ``scenario``'s polytope and verify each gain at its vertices and ``n_verify`` random
    interior points (H2 first, drawing from ``rng``)."""
    scenario = validation.instance(scenario, "scenario", Scenario)
    n_verify = validation.integer(n_verify, "n_verify", minimum=1)
    rng = validation.rng(rng, "rng")
    gamma = validation.positive(gamma, "gamma")
    pole_radius = validation.positive(pole_radius, "pole_radius")
    V = scenario.box.vertices()
    m = scenario.model
    des = {"h2": lpv.design_observer(m, V, gamma, "h2", sensors=THETA1_SENSORS),
           "hinf": lpv.design_observer(m, V, gamma, "hinf", sensors=THETA1_SENSORS, pole_radius=pole_radius)}
    ver = {n: lpv.verify_observer(m, d, scenario.box, n_verify, rng) for n, d in des.items()}
    return ObserverDesigns(des, ver)


@dataclass(frozen=True)
class AllowanceAtDt:
    r"""What each design allows at the sampling interval ``dt`` (TU): the H2 allowance per sample and read as an
    intensity, the H-infinity allowance (an RMS), deg; ``dt_01``: the interval (TU) at which H2 allows exactly
    0.1 deg per sample, :math:`1/(\kappa_{H2}\sin 0.1°)^2`."""

    dt: float
    h2_per_sample_deg: float
    h2_intensity_deg: float
    hinf_deg: float
    dt_01: float


def allowance_at(designs: ObserverDesigns, dt: float) -> AllowanceAtDt:
    """Eq. 24 allowances of ``designs`` for a sensor sampled every ``dt`` TU (noise held over each interval)."""
    designs = validation.instance(designs, "designs", ObserverDesigns)
    dt = validation.positive(dt, "dt")
    h2, hinf = designs.designs["h2"], designs.designs["hinf"]
    return AllowanceAtDt(dt, float(h2.noise_per_sample_deg(dt)[0]), float(h2.noise_deg[0]), float(hinf.noise_deg[0]),
                         float(1.0 / (h2.kappa[0] * np.sin(np.radians(0.1))) ** 2))


@dataclass(frozen=True)
class Fig3Runs:
    """Truth, measurements and the observer runs of Fig. 3.

    Attributes
    ----------
    t : ndarray (m,)
        Measurement times, TU.
    truth : ndarray (m, 4)
    meas : Measurements
    x_hat0 : ndarray (4,)
        Initial estimate.
    runs : dict of str to ObserverRun
        ``"h2"``, ``"hinf"`` (triangulated rho), ``"ekf"``.
    exact : dict of str to ObserverRun
        The LPV observers scheduled on the true rho (diagnostic).
    dt, period : float
        Measurement interval and orbit period, TU.
    """

    t: np.ndarray
    truth: np.ndarray
    meas: object
    x_hat0: np.ndarray
    runs: dict
    exact: dict
    dt: float
    period: float

    @property
    def initial_error(self) -> float:
        """Initial position error, LU."""
        return float(self.runs["h2"].position_error[0])

    @property
    def settled(self) -> np.ndarray:
        """Samples after the first 10 % of the run."""
        return self.t > 0.1 * (self.t[-1] - self.t[0])

    def median_settled(self, name: str) -> float:
        """Median position error of run ``name`` after 10 % of the run, LU."""
        name = validation.choice(name, "name", tuple(self.runs))
        return float(np.median(self.runs[name].position_error[self.settled]))


def simulate_fig3(scenario: Scenario, designs: ObserverDesigns, dt: float, periods: float, sigma_deg: float,
                  rng: np.random.Generator, *, sigma_acc: float = 1e-3, p0_sigma: float = 0.03,
                  initial_error=INITIAL_ERROR) -> Fig3Runs:
    """Propagate the truth over ``periods`` periods, sample noisy angles every ``dt`` TU (``rng``) and run both LPV
    observers (triangulated and true rho) and the EKF (``sigma_acc`` LU/TU^2, initial sigma ``p0_sigma``) from
    ``truth[0] + initial_error`` (LU, LU/TU; default :data:`INITIAL_ERROR`)."""
    scenario = validation.instance(scenario, "scenario", Scenario)
    designs = validation.instance(designs, "designs", ObserverDesigns)
    dt = validation.positive(dt, "dt")
    periods = validation.positive(periods, "periods")
    sigma_deg = validation.positive(sigma_deg, "sigma_deg", allow_zero=True)
    rng = validation.rng(rng, "rng")
    sigma_acc = validation.positive(sigma_acc, "sigma_acc", allow_zero=True)
    p0_sigma = validation.positive(p0_sigma, "p0_sigma")
    initial_error = validation.as_array(initial_error, "initial_error", shape=(4,))
    m = scenario.model
    t = np.arange(0.0, periods * scenario.orbit.period, dt)
    truth = m.planar(propagate(m.system, scenario.orbit.x0, t).x)
    meas = make_measurements(m, t, truth, sigma_deg, rng)
    x0 = truth[0] + initial_error
    runs = {n: simulate_lpv_observer(m, d.gain(), meas, x0, truth) for n, d in designs.designs.items()}
    exact = {n: simulate_lpv_observer(m, d.gain(), meas, x0, truth, exact_rho=True)
             for n, d in designs.designs.items()}
    runs["ekf"] = simulate_ekf(m, meas, x0, np.diag([p0_sigma] * 4) ** 2, truth, sigma_acc=sigma_acc)
    return Fig3Runs(t, truth, meas, x0, runs, exact, dt, float(scenario.orbit.period))


def first_and_rms(t, position_error, bound: float, period: float) -> tuple:
    """First time (TU) the error falls below ``bound`` and the RMS error (LU) from 2 % of ``period`` after it
    (``(inf, inf)`` if never)."""
    t = validation.as_array(t, "t", ndim=(1,), min_size=1)
    e = validation.as_array(position_error, "position_error", shape=t.shape)
    bound = validation.positive(bound, "bound", allow_zero=True)
    period = validation.positive(period, "period")
    below = e < bound
    if not below.any():
        return np.inf, np.inf
    t_first = float(t[np.argmax(below)])
    after = t > t_first + 0.02 * period
    return t_first, float(np.sqrt(np.mean(e[after] ** 2))) if after.any() else np.inf


@dataclass(frozen=True)
class Convergence:
    r"""The Fig. 3 criterion and what sets the convergence time.

    Attributes
    ----------
    noise_rms_deg : float
        RMS of the simulated theta1 noise, deg.
    bound : dict
        Guaranteed RMS position error of each design for this noise (LU).
    first, rms, rms_exact : dict
        First time below the bound (TU), RMS after it (LU), and the RMS with exact rho (LU).
    level : dict
        The accuracy the paper designs each observer for at this noise (:meth:`Fig3Accuracy.paper_level`), LU: the
        level of the "converge rapidly and stay accurate" rows (:class:`Fig3Accuracy`).  ``bound``, ``first``,
        ``rms`` and ``rms_exact`` are the LMI-guarantee diagnostic; the fields below serve the rows and use it.
    decay : dict
        Slowest closed-loop decay rate along the orbit, 1/TU.
    t_pred : dict
        Predicted time from the initial error to the level, :math:`\ln(e_0/\mathrm{level})/\mathrm{decay}`, TU.
    first_clean : float
        H2, no noise, exact rho: first time below the level, TU.
    e0_scales, first_sweep, early_sweep : ndarray
        Initial-error scales and, for each, the H2 first time below the level (TU) and RMS error over 5-10 % of the
        period (LU).
    """

    noise_rms_deg: float
    bound: dict
    first: dict
    rms: dict
    rms_exact: dict
    level: dict
    decay: dict
    t_pred: dict
    first_clean: float
    e0_scales: np.ndarray
    first_sweep: np.ndarray
    early_sweep: np.ndarray

    def converges(self, name: str, period: float) -> bool:
        """First below the guarantee within :data:`RAPID_FRACTION` of ``period`` (diagnostic)."""
        name = validation.choice(name, "name", tuple(self.first))
        period = validation.positive(period, "period")
        return bool(self.first[name] <= RAPID_FRACTION * period)

    def stays(self, name: str) -> bool:
        """RMS after convergence below the guarantee (diagnostic)."""
        name = validation.choice(name, "name", tuple(self.rms))
        return bool(self.rms[name] <= self.bound[name])

    def e0_max_ok(self, initial_error: float, period: float) -> float:
        """Largest swept initial error (units of ``initial_error``) from which the H2 error settles "rapidly" as
        :meth:`Fig3Accuracy.rapid` reads it: first below the level within :data:`RAPID_FRACTION` of ``period`` and RMS
        over 5-10 % of it at most the level (NaN if none)."""
        initial_error = validation.positive(initial_error, "initial_error", allow_zero=True)
        period = validation.positive(period, "period")
        ok = [f * initial_error for f, tf, er in zip(self.e0_scales, self.first_sweep, self.early_sweep)
              if tf <= RAPID_FRACTION * period and er <= self.level["h2"]]
        return max(ok) if ok else float("nan")


def _first_below(task):
    """One run of the initial-error sweep of :func:`convergence_study` (module level: process pools pickle it): the
    first time below ``level`` and the RMS over 5-10 % of the period (the "rapidly" part of :class:`Fig3Accuracy`)."""
    m, gain, meas, x0, truth, level, period = task
    run = simulate_lpv_observer(m, gain, meas, x0, truth)
    return _rapid_parts(meas.t, run.position_error, level, period)


def convergence_study(scenario: Scenario, designs: ObserverDesigns, sim: Fig3Runs, sigma_deg: float, *,
                      e0_scales=E0_SCALES, seed: int = 0, executor=None) -> Convergence:
    """Compare ``sim`` with the LMI guarantees (``lpv.guaranteed_error_rms``, a diagnostic), predict the time to reach
    the paper's accuracy level (:meth:`Fig3Accuracy.paper_level` for ``sigma_deg``; at zero noise the level of
    0.1 deg) from the slowest closed-loop pole, re-run H2 without noise on the true rho and sweep the initial error
    (one task per scale through :func:`cislunar.utils.montecarlo.map_tasks` on ``executor``, default serial; the
    result does not depend on it)."""
    scenario = validation.instance(scenario, "scenario", Scenario)
    designs = validation.instance(designs, "designs", ObserverDesigns)
    sim = validation.instance(sim, "sim", Fig3Runs)
    sigma_deg = validation.positive(sigma_deg, "sigma_deg", allow_zero=True)
    scales = validation.as_array(e0_scales, "e0_scales", ndim=(1,), min_size=1)
    seed = validation.seed_entropy(seed, "seed")
    m, des, t, P = scenario.model, designs.designs, sim.t, sim.period
    dth = np.degrees(np.angle(np.exp(1j * (np.stack([sim.meas.theta1, sim.meas.theta2])
                                           - np.stack(m.angles(sim.truth))))))
    noise_rms = float(np.sqrt(np.mean(dth[0] ** 2)))
    bound = {"h2": lpv.guaranteed_error_rms(des["h2"], sigma_deg, sim.dt),
             "hinf": lpv.guaranteed_error_rms(des["hinf"], noise_rms)}
    first, rms, rms_exact = {}, {}, {}
    for n in bound:
        first[n], rms[n] = first_and_rms(t, sim.runs[n].position_error, bound[n], P)
        rms_exact[n] = first_and_rms(t, sim.exact[n].position_error, bound[n], P)[1]
    gammas = {d.gamma for d in des.values()}
    if len(gammas) != 1:
        raise ValueError(f"designs must share one gamma; got {sorted(gammas)}")
    level = Fig3Accuracy.paper_level(gammas.pop(), sigma_deg if sigma_deg > 0 else PAPER_ALLOWANCE_DEG["h2"])
    e0 = sim.initial_error
    decay, t_pred = {}, {}
    for n, d in des.items():
        Lg = d.gain()
        ev = np.array([np.linalg.eigvals(m.A(r) + Lg @ m.C(r)).real.max() for r in scenario.rho[::10]])
        decay[n] = float(-ev.max())
        t_pred[n] = float(max(np.log(e0 / level[n]), 0.0) / decay[n])
    clean_meas = make_measurements(m, t, sim.truth, 0.0, np.random.default_rng(seed))
    clean = simulate_lpv_observer(m, des["h2"].gain(), clean_meas, sim.x_hat0, sim.truth, exact_rho=True)
    first_clean = first_and_rms(t, clean.position_error, level["h2"], P)[0]
    tasks = [(m, des["h2"].gain(), sim.meas, sim.truth[0] + f * (sim.x_hat0 - sim.truth[0]), sim.truth, level["h2"], P)
             for f in scales]
    sweep = map_tasks(_first_below, tasks, executor=executor, progress=False, desc="initial-error sweep")
    return Convergence(noise_rms, bound, first, rms, rms_exact, level, decay, t_pred, first_clean, scales,
                       np.array([f for f, _ in sweep]), np.array([r for _, r in sweep]))


@dataclass(frozen=True)
class LineCrossings:
    """Where the spacecraft crosses the Earth-Moon line (rho from the estimate) and the running RMS errors.

    Attributes
    ----------
    starts : ndarray
        Times at which a stretch of samples with :math:`|\\sin\\theta_3| < 0.04` begins, TU.
    near : ndarray of bool (m,)
        Samples within ``window`` TU of a start.
    running_rms : dict of str to ndarray (m,)
        Running RMS of the position error over ``window`` TU, LU.
    window : float
    """

    starts: np.ndarray
    near: np.ndarray
    running_rms: dict
    window: float


def line_crossings(sim: Fig3Runs, window: float = 0.1) -> LineCrossings:
    """Earth-Moon line crossings of ``sim`` and the running RMS of each run over ``window`` TU."""
    sim = validation.instance(sim, "sim", Fig3Runs)
    window = validation.positive(window, "window")
    t = sim.t
    on_line = sim.runs["h2"].rho_from_estimate
    starts = t[on_line & ~np.r_[False, on_line[:-1]]]
    near = np.zeros(t.size, dtype=bool)
    for t0 in starts:
        near |= np.abs(t - t0) < window
    w = max(1, int(round(window / sim.dt)))
    n_win = np.convolve(np.ones(t.size), np.ones(w), mode="same")  # fewer samples in the windows at the ends
    run_rms = {n: np.sqrt(np.convolve(r.position_error**2, np.ones(w), mode="same") / n_win)
               for n, r in sim.runs.items()}
    return LineCrossings(starts, near, run_rms, window)


@dataclass(frozen=True)
class WindowRerun:
    """Both LPV observers re-run at another sampling interval ``dt`` (TU), with ``n`` samples; ``median``: median
    position error after 10 % of the run by observer, LU."""

    dt: float
    n: int
    median: dict


def window_rerun(scenario: Scenario, designs: ObserverDesigns, sim: Fig3Runs, dt: float, periods: float,
                 sigma_deg: float, rng: np.random.Generator) -> WindowRerun:
    """Repeat the LPV runs of ``sim`` (same initial error) with measurements every ``dt`` TU drawn from ``rng``."""
    scenario = validation.instance(scenario, "scenario", Scenario)
    designs = validation.instance(designs, "designs", ObserverDesigns)
    sim = validation.instance(sim, "sim", Fig3Runs)
    dt = validation.positive(dt, "dt")
    periods = validation.positive(periods, "periods")
    sigma_deg = validation.positive(sigma_deg, "sigma_deg", allow_zero=True)
    rng = validation.rng(rng, "rng")
    m = scenario.model
    t = np.arange(0.0, periods * scenario.orbit.period, dt)
    truth = m.planar(propagate(m.system, scenario.orbit.x0, t).x)
    meas = make_measurements(m, t, truth, sigma_deg, rng)
    x0 = truth[0] + (sim.x_hat0 - sim.truth[0])
    settle = t > 0.1 * (t[-1] - t[0])
    med = {n: float(np.median(simulate_lpv_observer(m, d.gain(), meas, x0, truth).position_error[settle]))
           for n, d in designs.designs.items()}
    return WindowRerun(float(dt), int(t.size), med)


def _peak_after_settling(t: np.ndarray, position_error: np.ndarray) -> tuple:
    """Largest position error after the first 10 % of the run (the chapter's settling window) and its time; ``inf``
    if there is no sample after it or the error is not finite there (a run that blew up)."""
    keep = t > t[0] + 0.1 * (t[-1] - t[0])
    after, t_after = position_error[keep], t[keep]
    if not after.size:
        return np.inf, float("nan")
    if not np.all(np.isfinite(after)):
        return np.inf, float(t_after[np.argmin(np.isfinite(after))])
    i = int(np.argmax(after))
    return float(after[i]), float(t_after[i])


@dataclass(frozen=True)
class RangeFree:
    r"""The row "observers function without range sensors" (§IV-B, after Fig. 3): no range information in the
    loop, and the error converges from the initial error and never comes back to it.

    Build it with :meth:`measure`.  The claim and why this is its reading: ``claims.observer_simulation``.

    Attributes
    ----------
    range_gain : dict of str to float
        Largest absolute entry of each design's gain columns for r13^2, r23^2 (:data:`RANGE_CHANNELS`), LU/TU per
        unit of measurement; 0 when the design drops them.
    range_used : dict of str to bool
        Whether each design keeps a range channel (``design.used``).
    initial_error : dict of (str, str) to float
        Initial position error of each run, LU, keyed ``(interval label, observer)``.
    peak : dict of (str, str) to float
        Largest position error after the first 10 % of the run, LU, same keys.
    peak_time : dict of (str, str) to float
        When it happens, TU (``nan`` if there is no sample after the first 10 % of the run).
    reference_peak : dict of (str, str) to float
        The same for the observer scheduled on the true rho (what range sensors would add), LU; empty if not given.
    """

    range_gain: dict
    range_used: dict
    initial_error: dict
    peak: dict
    peak_time: dict
    reference_peak: dict

    @classmethod
    def measure(cls, designs: ObserverDesigns, runs: dict, reference: dict | None = None) -> RangeFree:
        """Measure the row from ``designs`` and ``runs``: a dict of interval label (str) to ``(t, errors)``, ``t``
        the times (TU, increasing) and ``errors`` a dict of observer name to its position error (LU, one per time);
        ``reference`` the same for the observers given the true rho (optional).  A run whose error is not finite
        after the start is measured as unbounded."""
        designs = validation.instance(designs, "designs", ObserverDesigns)
        validation.instance(runs, "runs", dict)
        if not runs:
            raise ValueError("runs must hold at least one interval")

        def arrays(group, name):
            out = {}
            for label, pair in validation.instance(group, name, dict).items():
                if not isinstance(pair, tuple) or len(pair) != 2:
                    raise TypeError(f"{name}[{label!r}] must be a (t, errors) pair")
                t = validation.time_grid(pair[0], f"{name}[{label!r}] t", increasing=True)
                for obs_name, e in validation.instance(pair[1], f"{name}[{label!r}] errors", dict).items():
                    # not finite is allowed after the start: a diverged run is measured (as unbounded), not refused
                    e = validation.as_array(e, f"{name}[{label!r}][{obs_name!r}]", shape=t.shape, finite=False)
                    if not (np.isfinite(e[0]) and e[0] > 0) or np.any(e[np.isfinite(e)] < 0):
                        raise ValueError(f"{name}[{label!r}][{obs_name!r}] must be position errors (>= 0) with a "
                                         "finite, positive initial error")
                    out[(label, obs_name)] = (t, e)
            return out

        main = arrays(runs, "runs")
        ref = arrays(reference, "reference") if reference is not None else {}
        ch = list(RANGE_CHANNELS)
        gain = {n: float(np.max(np.abs(d.gain()[:, ch]))) for n, d in designs.designs.items()}
        used = {n: bool(np.asarray(d.used)[ch].any()) for n, d in designs.designs.items()}
        peaks = {k: _peak_after_settling(t, e) for k, (t, e) in main.items()}
        return cls(gain, used, {k: float(e[0]) for k, (t, e) in main.items()}, {k: p for k, (p, _) in peaks.items()},
                   {k: w for k, (_, w) in peaks.items()},
                   {k: _peak_after_settling(t, e)[0] for k, (t, e) in ref.items()})

    @property
    def no_range_channel(self) -> bool:
        """No design keeps a range channel and every range column of every gain is zero."""
        return not any(self.range_used.values()) and not any(self.range_gain.values())

    def bounded(self, label: str, name: str) -> bool:
        """The run's largest error after settling is below its initial error (converged, no divergence)."""
        key = (label, name)
        if key not in self.peak:
            raise ValueError(f"(label, name) must be one of {sorted(self.peak)}; got {key}")
        return bool(self.peak[key] < self.initial_error[key])

    @property
    def holds(self) -> bool:
        """The row's criterion: no range channel and every run bounded."""
        return self.no_range_channel and all(self.bounded(*k) for k in self.peak)

    def text(self, length_unit_km: float) -> str:
        """One line per run: initial error, largest error after settling (and with the true rho), km."""
        km = validation.positive(length_unit_km, "length_unit_km")
        lines = ["range channels r13^2, r23^2: " + ", ".join(
            f"{n} used {self.range_used[n]}, largest gain entry {self.range_gain[n]:.1e}" for n in self.range_gain)]
        for (label, n), p in self.peak.items():
            ref = self.reference_peak.get((label, n))
            lines.append(f"{n:4s} at {label:>9s}: initial {self.initial_error[(label, n)] * km:7.0f} km, largest after "
                         f"10 % of the run {p * km:7.0f} km ({p / self.initial_error[(label, n)]:.2f} of it) at t = "
                         f"{self.peak_time[(label, n)]:.3f} TU"
                         + (f"; with the true rho {ref * km:.0f} km" if ref is not None else "")
                         + f"; bounded: {self.bounded(label, n)}")
        return "\n".join(lines)

    def why(self, length_unit_km: float) -> str:
        """Why the row differs: the runs that came back to their initial error, with the same observer on the true
        rho beside them ("" when none did and no range channel is used)."""
        km = validation.positive(length_unit_km, "length_unit_km")
        parts = [] if self.no_range_channel else ["a range channel is used"]
        for (label, n), p in self.peak.items():
            if not self.bounded(label, n):
                ref = self.reference_peak.get((label, n))
                parts.append(f"{n} at {label} back to {p * km:,.0f} km = {p / self.initial_error[(label, n)]:.2f}x its "
                             f"initial error (t = {self.peak_time[(label, n)]:.2f} TU)"
                             + (f"; on the true rho {ref * km:,.0f} km" if ref is not None else ""))
        return "; ".join(parts)

    def shown(self) -> str:
        """The row's reproduced value: range columns, and each run's largest error after settling over its initial
        error."""
        labels = list(dict.fromkeys(k[0] for k in self.peak))
        return (f"gain columns of r13^2, r23^2 {'zero' if self.no_range_channel else 'non-zero'}; largest error after "
                "10 % of the run / initial: " + "; ".join(
                    ", ".join(f"{'H2' if n == 'h2' else 'Hinf' if n == 'hinf' else n} "
                              f"{self.peak[(lab, n)] / self.initial_error[(lab, n)]:.2f}"
                              for (lab_, n) in self.peak if lab_ == lab) + f" ({lab})" for lab in labels))


def _first_time_below(t: np.ndarray, position_error: np.ndarray, level: float) -> float:
    """First time (TU) the error is below ``level`` (``inf`` if never)."""
    below = position_error < level
    return float(t[np.argmax(below)]) if below.any() else np.inf


def _settled_rms(t: np.ndarray, position_error: np.ndarray) -> float:
    """RMS position error after the first 10 % of the run (the chapter's settling window); ``inf`` if there is no
    sample after it or the error is not finite there."""
    return _rms(position_error[t > t[0] + 0.1 * (t[-1] - t[0])])


def _rapid_parts(t: np.ndarray, position_error: np.ndarray, level: float, period: float) -> tuple:
    """First time (TU) below ``level`` and RMS (LU) over :math:`(fP, 2fP]` after the start, f = RAPID_FRACTION."""
    first = _first_time_below(t, np.where(np.isfinite(position_error), position_error, np.inf), level)
    window = (t > t[0] + RAPID_FRACTION * period) & (t <= t[0] + 2 * RAPID_FRACTION * period)
    return first, _rms(position_error[window])


def _rms(e: np.ndarray) -> float:
    """RMS of ``e``; ``inf`` if empty or not finite."""
    if not e.size or not np.all(np.isfinite(e)):
        return np.inf
    return float(np.sqrt(np.mean(e**2)))


@dataclass(frozen=True)
class Fig3Accuracy:
    r"""The rows "converges rapidly and stays accurate" (§IV-B after Fig. 3), one per observer, judged at every
    sampling interval given.

    The reading (why: ``claims.observer_simulation``): *accurate* = the RMS position error after the first 10 % of
    the run is at most the accuracy the paper designs the observer for at this noise (:meth:`paper_level`: gamma
    for H2 at 0.1 deg, 1.25 gamma for H-infinity); *rapidly* = the error is first below that level within
    :data:`RAPID_FRACTION` of the orbit period and its RMS from then to twice that time (5-10 % of the period) is at
    most the level (a dip below the level while the error still swings is not convergence).  Build it with
    :meth:`measure`.

    Attributes
    ----------
    level : dict of str to float
        Accuracy level of each observer, LU.
    period : float
        Orbit period, TU.
    first : dict of (str, str) to float
        First time below the level, TU (``inf`` if never), keyed ``(interval label, observer)``.
    early_rms : dict of (str, str) to float
        RMS position error over :math:`(f P, 2 f P]` after the start, :math:`f` = :data:`RAPID_FRACTION`, LU
        (``inf`` if no sample or not finite).
    rms : dict of (str, str) to float
        RMS position error after the first 10 % of the run, LU (``inf`` if not finite).
    reference_rms : dict of (str, str) to float
        The same for the observer scheduled on the true rho (where the LMIs' assumptions hold), LU; may be empty.
    """

    level: dict
    period: float
    first: dict
    early_rms: dict
    rms: dict
    reference_rms: dict

    @staticmethod
    def paper_level(gamma: float, sigma_deg: float) -> dict:
        r"""The accuracy the paper designs each observer for at angle noise ``sigma_deg`` (deg): the error bound
        ``gamma`` (LU) scaled by the noise over the paper's allowance, :math:`\gamma\,\sigma/\theta_{paper}` with
        :data:`PAPER_ALLOWANCE_DEG` (the error is linear in the noise).  At the paper's 0.1 deg: H2 :math:`\gamma`,
        H-infinity :math:`1.25\gamma` (the paper: the H-infinity error "is expected to be larger" for this reason).
        Returns a dict ``{"h2": ..., "hinf": ...}``, LU."""
        gamma = validation.positive(gamma, "gamma")
        sigma_deg = validation.positive(sigma_deg, "sigma_deg")
        return {n: gamma * sigma_deg / a for n, a in PAPER_ALLOWANCE_DEG.items()}

    @classmethod
    def measure(cls, runs: dict, level: dict, period: float, reference: dict | None = None) -> Fig3Accuracy:
        """Measure from ``runs``: a dict of interval label (str) to ``(t, errors)``, ``t`` the times (TU, increasing)
        and ``errors`` a dict of observer name to its position error (LU, one per time); ``level`` a dict of
        observer name to its accuracy level (LU, > 0; :meth:`paper_level`); ``period`` the orbit period (TU);
        ``reference`` the same as ``runs`` for the observers on the true rho (optional)."""
        validation.instance(runs, "runs", dict)
        if not runs:
            raise ValueError("runs must hold at least one interval")
        validation.instance(level, "level", dict)
        level = {n: validation.positive(v, f"level[{n!r}]") for n, v in level.items()}
        period = validation.positive(period, "period")

        def measured(group, name):
            first, early, rms = {}, {}, {}
            for label, pair in validation.instance(group, name, dict).items():
                if not isinstance(pair, tuple) or len(pair) != 2:
                    raise TypeError(f"{name}[{label!r}] must be a (t, errors) pair")
                t = validation.time_grid(pair[0], f"{name}[{label!r}] t", increasing=True)
                for n, e in validation.instance(pair[1], f"{name}[{label!r}] errors", dict).items():
                    if n not in level:
                        raise ValueError(f"{name}[{label!r}] observer {n!r} has no level; levels: {sorted(level)}")
                    e = validation.as_array(e, f"{name}[{label!r}][{n!r}]", shape=t.shape, finite=False)
                    if np.any(e[np.isfinite(e)] < 0):
                        raise ValueError(f"{name}[{label!r}][{n!r}] must be position errors (>= 0)")
                    first[(label, n)], early[(label, n)] = _rapid_parts(t, e, level[n], period)
                    rms[(label, n)] = _settled_rms(t, e)
            return first, early, rms

        first, early, rms = measured(runs, "runs")
        ref_rms = measured(reference, "reference")[2] if reference is not None else {}
        return cls(level, period, first, early, rms, ref_rms)

    def _key(self, label, name):
        key = (label, name)
        if key not in self.rms:
            raise ValueError(f"(label, name) must be one of {sorted(self.rms)}; got {key}")
        return key

    def rapid(self, label: str, name: str) -> bool:
        """First below the level within :data:`RAPID_FRACTION` of the period, and RMS at most the level from then
        to twice that time."""
        key = self._key(label, name)
        return bool(self.first[key] <= RAPID_FRACTION * self.period and self.early_rms[key] <= self.level[name])

    def accurate(self, label: str, name: str) -> bool:
        """RMS after the first 10 % of the run at most the level."""
        key = self._key(label, name)
        return bool(self.rms[key] <= self.level[name])

    def holds(self, name: str) -> bool:
        """The row of observer ``name``: rapid and accurate at every interval."""
        labels = [lab for lab, n in self.rms if n == name]
        if not labels:
            raise ValueError(f"name must be one of {sorted({n for _, n in self.rms})}; got {name!r}")
        return all(self.rapid(lab, name) and self.accurate(lab, name) for lab in labels)

    def shown(self, name: str, length_unit_km: float) -> str:
        """The row's reproduced value: per interval, the first time below the level and the RMS against it."""
        km = validation.positive(length_unit_km, "length_unit_km")
        return "; ".join(
            f"{lab}: below {self.level[n] * km:.0f} km at {100 * self.first[(lab, n)] / self.period:.1f} % of the "
            f"period, RMS {self.early_rms[(lab, n)] * km:.0f} km over 5-10 % of it, "
            f"{self.rms[(lab, n)] * km:.0f} km after 10 % of the run" for lab, n in self.rms if n == name)

    def why(self, name: str, length_unit_km: float) -> str:
        """Why the row of ``name`` differs (what failed at which interval; "" when it holds), with the true-rho RMS."""
        km = validation.positive(length_unit_km, "length_unit_km")
        parts = []
        for lab, n in self.rms:
            if n != name:
                continue
            bad = [w for w, ok in ((f"not settled below {self.level[n] * km:.0f} km within "
                                    f"{100 * RAPID_FRACTION:.0f} % of the period", self.rapid(lab, n)),
                                   (f"RMS above {self.level[n] * km:.0f} km", self.accurate(lab, n))) if not ok]
            ref = self.reference_rms.get((lab, n))
            if bad and ref is not None and not self.accurate(lab, n):
                bad[-1] += f" (on the true rho: RMS {ref * km:.0f} km)"
            if bad:
                parts.append(f"at {lab} " + " and ".join(bad))
        return "; ".join(parts)
