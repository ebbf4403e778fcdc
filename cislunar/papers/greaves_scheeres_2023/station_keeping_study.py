r"""Studies of informed station keeping on the QPO (Greaves & Scheeres AMOS 2023, Secs. 4-5; notebook 08).

Each function runs one study over :func:`cislunar.papers.greaves_scheeres_2023.station_keeping.station_keeping_surface`
and returns a frozen result object:

* :func:`slice_statistics`: where :math:`\mathbf u^*` ranks within each arrival slice (range uncertainty, fuel);
* :func:`valley_edge_ratio`: :math:`\sqrt{J_\rho}` of :math:`\mathbf u^*` against the edge of its slice's valley;
* :func:`second_burn_raises`: whether the second burn raises :math:`\sqrt{J_\rho}` of :math:`\mathbf u^*` somewhere;
* :func:`grid_resolution_study`: both readings of Eq. 25 as the ring-angle grid is refined;
* :func:`scenario_sweep`: the unstated scenario inputs (tracking start, burn lead, agent phase, read-out time);
* :func:`offset_study`: an agent that has drifted off the torus;
* :func:`member_study`: torus members matching 215 km under other readings of "average range";
* :func:`random_pick_study`: uninformed station-keeping maneuvers (target ring angle drawn uniformly at random), the
  baseline that :math:`\mathbf u^*` is judged against;
* :func:`filter_monte_carlo`: the iterated-EKF Monte Carlo with execution errors (beyond the paper), and
  :func:`nees_p_value`, the chi-square consistency test of its mean NEES.

The sweeps (:func:`grid_resolution_study`, :func:`scenario_sweep`, :func:`offset_study`) and the Monte Carlo take
``executor=`` (from :func:`cislunar.utils.executors.open_executor`; ``None`` runs serially): one task per surface
through :func:`cislunar.utils.montecarlo.map_tasks`, one trial per filter run through
:func:`cislunar.utils.montecarlo.run_monte_carlo`.  Surfaces are deterministic and trials seeded by index, so the
results do not depend on the executor.

Units: times in hours where named ``*_h``/``*_hours``, otherwise CR3BP time units (TU); :math:`\sqrt{J_\rho}` in
km (``*_km``) or m (``*_m``); fuel in m/s; percentiles in percent of the maneuvers of a slice.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np
from scipy.stats import chi2, spearmanr

from cislunar.cr3bp.dynamics import CR3BP, check_system
from cislunar.cr3bp.orbits import PeriodicOrbit
from cislunar.cr3bp.propagation import propagate
from cislunar.cr3bp.torus import InvariantTorus, qpo_for_mean_range
from cislunar.guidance import ssat
from cislunar.papers.greaves_scheeres_2023 import station_keeping as sk
from cislunar.utils import validation
from cislunar.utils.montecarlo import map_tasks, run_monte_carlo

__all__ = [
    "POLICIES",
    "FUEL_PEAK_QUARTER",
    "RAISED_FRACTION",
    "VALLEY_PERCENT",
    "GridRow",
    "GridStudy",
    "MonteCarloStudy",
    "RandomPickStudy",
    "SliceStatistics",
    "SweepRow",
    "execution_levels",
    "filter_monte_carlo",
    "format_sweep",
    "grid_resolution_study",
    "member_study",
    "nees_p_value",
    "offset_study",
    "random_pick_study",
    "scenario_sweep",
    "second_burn_raises",
    "slice_statistics",
    "valley_edge_ratio",
]


def _surface(value, name="surface"):
    return validation.instance(value, name, sk.StationKeepingSurface, "a StationKeepingSurface")


def _torus(value):
    return validation.instance(value, "torus", InvariantTorus, "an InvariantTorus")


def _vector(value, name):
    """A non-empty 1-D array of finite values (angles, times)."""
    return validation.as_array(value, name, ndim=(1,), min_size=1)


def _non_negative_vector(value, name):
    arr = _vector(value, name)
    if np.any(arr < 0):
        raise ValueError(f"{name} must be non-negative; got {value!r:.80}")
    return arr


def _executor(value):
    """``None`` (serial) or an executor with ``submit`` (checked before any work)."""
    if value is not None and not callable(getattr(value, "submit", None)):
        raise validation.ArgumentTypeError(f"executor must be None or have a submit(fn, *args) method (a "
                                           f"concurrent.futures executor or a Dask Client); got {type(value).__name__}")
    return value


def _scenario_times(theta, t_arrival, t_burn, t_final):
    """The ring angles (rad), arrival times, first-burn time and read-out time (TU) of a surface, checked."""
    return (_vector(theta, "theta"), _vector(t_arrival, "t_arrival"), validation.real(t_burn, "t_burn"),
            validation.real(t_final, "t_final"))


# ---------------------------------------------------------------------------------------------------------------
# Where u* ranks within its slices
# ---------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class SliceStatistics:
    """The informed maneuver against the other maneuvers of its arrival slice.

    Attributes
    ----------
    percentile : ndarray (n_t,)
        Percent of the slice's maneuvers with a smaller :math:`\\sqrt{J_\\rho}` than :math:`\\mathbf u^*` (0 = best).
    fuel_percentile : ndarray (n_t,)
        Percent of the slice's maneuvers that use more fuel than :math:`\\mathbf u^*`.
    cheaper_best_km : ndarray (n_t,)
        Smallest :math:`\\sqrt{J_\\rho}` among the maneuvers using at most the fuel of :math:`\\mathbf u^*`, km.
    below_median_fuel : float
        Fraction of slices where :math:`\\mathbf u^*` uses at most the slice's median fuel.
    valley_phase, informed_phase, fuel_peak_phase : float
        Median normalised phase of the best maneuver, of :math:`\\mathbf u^*` and of the most expensive maneuver.
    rank_correlation : float
        Median over slices of Spearman's correlation of fuel and :math:`\\sqrt{J_\\rho}` (maneuvers only).
    raised_slices : tuple of int
        Interior slices where :math:`\\sqrt{J_\\rho}` of :math:`\\mathbf u^*` exceeds that of both neighbouring
        slices by more than :data:`RAISED_FRACTION` (the paper's "single point raised by a small local peak").
    """

    percentile: np.ndarray
    fuel_percentile: np.ndarray
    cheaper_best_km: np.ndarray
    below_median_fuel: float
    valley_phase: float
    informed_phase: float
    fuel_peak_phase: float
    rank_correlation: float
    raised_slices: tuple = ()

    @property
    def median_percentile(self) -> float:
        return float(np.median(self.percentile))

    @property
    def outside_fuel_peak_share(self) -> float:
        """Percent of slices where :math:`\\mathbf u^*` is not among the most expensive quarter of the slice's
        maneuvers (at least :data:`FUEL_PEAK_QUARTER` percent of them use more fuel than it)."""
        return _outside_peak_share(self.fuel_percentile)

    @property
    def best_quartile_share(self) -> float:
        """Percent of slices with :math:`\\mathbf u^*` in the best quartile."""
        return float(np.mean(self.percentile < 25) * 100)

    def format(self, surface) -> str:
        """One line per slice of ``surface`` (the one these statistics were computed from): arrival, phase of u*,
        its sqrt(J_rho), the slice's best, the best with at most its fuel, percentile, fuel, more-fuel share."""
        S = _surface(surface)
        lines = [("arrival h | u* phase | u* sqrt(J) m | best m | best with <= fuel m | percentile | fuel m/s | "
                 "more fuel %")]
        for j in range(S.t_arrival.size):
            lines.append(f" {S.t_arrival_hours[j]:8.2f} | {S.phase[S.informed[j]]:8.3f} | "
                         f"{S.informed_range_sigma_km[j] * 1e3:12.2f} | {S.best_range_sigma_km[j] * 1e3:6.2f} | "
                         f"{self.cheaper_best_km[j] * 1e3:19.2f} | {self.percentile[j]:10.1f} | "
                         f"{S.informed_fuel_m_s[j]:8.3f} | {self.fuel_percentile[j]:6.1f}")
        return "\n".join(lines)


#: Fig. 5's "peak fuel cost": the most expensive quarter of a slice's maneuvers.  u* avoids it when at least this
#: percent of the slice's maneuvers use more fuel than u* (the mirror of the valley rows' best quartile).
FUEL_PEAK_QUARTER = 25.0


def _outside_peak_share(more_fuel_percent) -> float:
    """Percent of slices whose ``more_fuel_percent`` (percent of the slice's maneuvers using more fuel than u*) is at
    least :data:`FUEL_PEAK_QUARTER`: u* outside the most expensive quarter of its slice."""
    return float(np.mean(np.asarray(more_fuel_percent, dtype=float) >= FUEL_PEAK_QUARTER) * 100)


#: A slice of the u* line is "raised" when its sqrt(J_rho) exceeds both neighbours' by more than this fraction.
RAISED_FRACTION = 0.10


def _raised(values, fraction=RAISED_FRACTION) -> tuple:
    """Interior indices where ``values`` exceed both neighbours by more than ``fraction`` (relative)."""
    v = np.asarray(values, dtype=float)
    if v.size < 3:
        return ()
    peak = v[1:-1] > (1 + fraction) * np.maximum(v[:-2], v[2:])
    return tuple(int(i) + 1 for i in np.flatnonzero(peak))


def slice_statistics(surface) -> SliceStatistics:
    """Rank the informed maneuver of every slice of ``surface`` by range uncertainty and by fuel."""
    S = _surface(surface)
    rows = np.arange(S.t_arrival.size)
    cheaper = np.array([S.range_sigma_km[j, S.fuel_m_s[j] <= S.informed_fuel_m_s[j] + 1e-12].min() for j in rows])
    moving = S.fuel_m_s > 1e-9
    rank = np.median([spearmanr(S.fuel_m_s[j, moving[j]], S.range_sigma_km[j, moving[j]])[0] for j in rows])
    return SliceStatistics(S.informed_percentile, S.informed_fuel_percentile, cheaper,
                           float(np.mean(S.informed_fuel_m_s <= np.median(S.fuel_m_s, axis=1))),
                           float(np.median(S.phase[S.best])), float(np.median(S.phase[S.informed])),
                           float(np.median(S.phase[np.argmax(S.fuel_m_s, axis=1)])), float(rank),
                           _raised(S.informed_range_sigma_km))


#: The valley of a slice (Fig. 4): its best quartile of maneuvers by :math:`\sqrt{J_\rho}` at :math:`t_f`, the
#: chapter's one reading of "in the valley" (the valley rows' percentile of u* at most this).
VALLEY_PERCENT = 25.0


def valley_edge_ratio(surface) -> np.ndarray:
    """:math:`\\sqrt{J_\\rho}` of :math:`\\mathbf u^*` over the edge of its slice's valley, per arrival slice.

    The edge is the :data:`VALLEY_PERCENT`-th percentile (linear interpolation) of the slice's :math:`\\sqrt{J_\\rho}`
    at :math:`t_f` over all its ring angles: a ratio at most 1 puts :math:`\\mathbf u^*` in the valley, a ratio of
    ``r`` means it is ``r`` times as uncertain as the valley's edge.  Dimensionless, shape ``(n_t,)``.
    """
    S = _surface(surface)
    return S.informed_range_sigma_km / np.percentile(S.range_sigma_km, VALLEY_PERCENT, axis=1)


def second_burn_raises(ratio) -> bool:
    """Whether the second burn raises :math:`\\sqrt{J_\\rho}` of :math:`\\mathbf u^*` in some slice.

    ``ratio``: per arrival slice, :math:`\\sqrt{J_\\rho}` of :math:`\\mathbf u^*` with both burns over the same with
    its first burn only (:func:`station_keeping.first_burn_only_range_sigma_km`), positive.  True when some ratio
    exceeds 1 (the paper's "small local peak ... induced by the secondary maneuver", Sec. 5).
    """
    r = _vector(ratio, "ratio")
    if np.any(r <= 0):
        raise ValueError(f"ratio must be positive (a ratio of two range sigmas); got {ratio!r:.80}")
    return bool(np.any(r > 1.0))


# ---------------------------------------------------------------------------------------------------------------
# Eq. 25 readings against the grid resolution
# ---------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class GridRow:
    """Medians over the arrival slices of one (agent phase, ring-angle count, reading).

    ``percentile``: of :math:`\\mathbf u^*` in its slice (percent); ``sigma_m``, ``fuel_m_s``: its
    :math:`\\sqrt{J_\\rho}` at :math:`t_f` (m) and total fuel (m/s); ``more_fuel_percent``: share of maneuvers using
    more fuel; ``best_m``: the slice's best :math:`\\sqrt{J_\\rho}` (m); ``ratio_best``: median over slices of
    :math:`\\sqrt{J_\\rho}` of :math:`\\mathbf u^*` over the slice's best; ``below_median_share``: percent of slices
    where :math:`\\mathbf u^*` uses at most the slice's median fuel; ``outside_peak_share``: percent of slices where
    :math:`\\mathbf u^*` is outside the most expensive quarter of the slice's maneuvers
    (:attr:`SliceStatistics.outside_fuel_peak_share`); ``beats_random``: percent of random picks
    (:func:`random_pick_study` on the same slices) with a larger :math:`\\sqrt{J_\\rho}` than :math:`\\mathbf u^*`
    (NaN when the study drew none); ``ratio_valley``: median over slices of :func:`valley_edge_ratio` (at most 1:
    :math:`\\mathbf u^*` within its slice's valley).
    """

    agent_phase: float
    n: int
    reading: str
    percentile: float
    sigma_m: float
    fuel_m_s: float
    more_fuel_percent: float
    best_m: float
    ratio_best: float = float("nan")
    below_median_share: float = float("nan")
    beats_random: float = float("nan")
    outside_peak_share: float = float("nan")
    ratio_valley: float = float("nan")


_GRID_KEYS = ("percentile", "sigma_m", "fuel_m_s", "more_fuel_percent", "best_m", "ratio_best", "below_median_share",
              "beats_random", "outside_peak_share", "ratio_valley")


@dataclass(frozen=True)
class GridStudy:
    """Rows of :func:`grid_resolution_study`; ``n_grid`` the ring-angle counts in order; ``random_theta`` the ring
    angles (rad) of the random picks, one ``(agent_phase, angles)`` pair per agent phase (empty without them)."""

    rows: tuple
    n_grid: tuple
    random_theta: tuple = ()

    def format(self) -> str:
        """The study as a text table, one line per row."""
        lines = [("agent phase | ring angles | reading    | percentile of u* % | sqrt(J) of u* m | fuel of u* m/s | "
                 "more fuel % | best of slice m | u*/best | u*/valley edge | <= median fuel % | beats random % | "
                 "off fuel peak %")]
        lines += [f" {g.agent_phase:10.2f} | {g.n:11d} | {g.reading:10s} | {g.percentile:18.1f} | {g.sigma_m:15.1f} | "
                  f"{g.fuel_m_s:14.3f} | {g.more_fuel_percent:11.1f} | {g.best_m:15.1f} | {g.ratio_best:7.2f} | "
                  f"{g.ratio_valley:14.2f} | {g.below_median_share:16.0f} | {g.beats_random:14.0f} | "
                  f"{g.outside_peak_share:15.0f}"
                  for g in self.rows]
        return "\n".join(lines)

    def series(self, agent_phase: float, reading: str, key: str) -> np.ndarray:
        """One column (``key`` a :class:`GridRow` field) against ``n_grid`` for an agent phase and a reading."""
        agent_phase = validation.real(agent_phase, "agent_phase")
        validation.choice(reading, "reading", ("angle", "projection"))
        validation.choice(key, "key", _GRID_KEYS)
        phases = tuple(dict.fromkeys(g.agent_phase for g in self.rows))
        if agent_phase not in phases:
            raise ValueError(f"agent_phase must be one of the agent phases of the study {phases}; got {agent_phase!r}")
        return np.array([getattr(g, key) for g in self.rows if g.agent_phase == agent_phase and g.reading == reading])


def _beats(informed_km, random_km) -> float:
    """Percent of the (slice, draw) pairs where the random pick has a larger sqrt(J_rho) than u* of its slice."""
    return float(100 * np.mean(random_km > np.asarray(informed_km)[:, None]))


def _grid_task(task):
    """The two :class:`GridRow` (angle, projection) of one surface and the u* range sigmas (sweep task); a task
    with ``n = None`` is the random-pick surface of an agent phase (its range sigmas at t_f)."""
    system, torus, n, phase, t_arrival, t_burn, t_final, theta = task
    s = sk.station_keeping_surface(system, torus, theta, t_arrival, t_burn, t_final, agent_theta=2 * np.pi * phase,
                                   progress=False)
    if n is None:
        return s.range_sigma_km
    rows = []
    for crit in ("angle", "projection"):
        r = s.reselect(crit)
        rows.append((GridRow(float(phase), n, crit, float(np.median(r.informed_percentile)),
                             float(np.median(r.informed_range_sigma_km) * 1e3),
                             float(np.median(r.informed_fuel_m_s)),
                             float(np.median(r.informed_fuel_percentile)),
                             float(np.median(r.best_range_sigma_km) * 1e3),
                             float(np.median(r.informed_range_sigma_km / r.best_range_sigma_km)),
                             float(np.mean(r.informed_fuel_m_s <= np.median(r.fuel_m_s, axis=1)) * 100),
                             outside_peak_share=_outside_peak_share(r.informed_fuel_percentile),
                             ratio_valley=float(np.median(valley_edge_ratio(r)))),
                     r.informed_range_sigma_km))
    return rows


def grid_resolution_study(system: CR3BP, torus, n_grid, t_arrival, t_burn: float, t_final: float, *,
                          agent_phases=(0.0, 0.75), rng: np.random.Generator | None = None, n_random: int = 0,
                          executor=None) -> GridStudy:
    """Both readings of Eq. 25 on surfaces with ``n`` equally spaced ring angles for each ``n`` in ``n_grid``, for
    each agent phase (fraction of a turn); arrival times ``t_arrival`` and burn/read-out times in TU; one task per
    surface on ``executor`` (``None``: serial).

    With ``n_random > 0`` (and ``rng``), ``n_random`` random picks per agent phase (target ring angles uniform on
    :math:`[0, 2\\pi)`, drawn from ``rng`` in the order of ``agent_phases`` before any work, the same angles for every
    slice, as in :func:`random_pick_study`) give each row its ``beats_random``.
    """
    check_system(system)
    _torus(torus)
    ns = tuple(validation.integer(n, "n_grid entry", minimum=2) for n in _vector(n_grid, "n_grid"))
    t_arrival = _vector(t_arrival, "t_arrival")
    t_burn, t_final = validation.real(t_burn, "t_burn"), validation.real(t_final, "t_final")
    agent_phases = _vector(agent_phases, "agent_phases")
    n_random = validation.integer(n_random, "n_random", minimum=0)
    if n_random or rng is not None:
        validation.rng(rng)
    _executor(executor)
    draws = {float(p): 2 * np.pi * rng.random(n_random) for p in agent_phases} if n_random else {}
    tasks = [(system, torus, n, float(phase), t_arrival, t_burn, t_final, 2 * np.pi * np.arange(n) / n)
             for phase in agent_phases for n in ns]
    tasks += [(system, torus, None, float(phase), t_arrival, t_burn, t_final, draws[float(phase)])
              for phase in agent_phases if n_random]
    out = map_tasks(_grid_task, tasks, executor=executor, progress=False, desc="ring-angle grids")
    n_rows = len(agent_phases) * len(ns)
    random_km = dict(zip((float(p) for p in agent_phases), out[n_rows:]))
    rows = []
    for pair in out[:n_rows]:
        for row, informed_km in pair:
            if n_random:
                row = replace(row, beats_random=_beats(informed_km, random_km[row.agent_phase]))
            rows.append(row)
    return GridStudy(tuple(rows), ns, tuple((p, tuple(float(a) for a in d)) for p, d in draws.items()))


# ---------------------------------------------------------------------------------------------------------------
# Sweep over the unstated scenario inputs
# ---------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class SweepRow:
    """One setting of :func:`scenario_sweep` (percentiles in percent, medians over slices).

    ``pct_tf``/``q_tf``: median percentile of :math:`\\mathbf u^*` and share of best-quartile slices with
    :math:`\\sqrt{J_\\rho}` read at :math:`t_f`; ``pct_arr``/``q_arr``: the same read at each arrival; ``fuel_pct``:
    share of maneuvers using more fuel; ``*_proj``: projection reading.
    """

    pre_h: float
    lead_h: float
    agent_phase: float
    pct_tf: float
    q_tf: float
    pct_arr: float
    q_arr: float
    fuel_pct: float
    pct_proj: float
    fuel_pct_proj: float


def _sweep_task(task):
    """The :class:`SweepRow` of one setting (sweep task)."""
    system, torus, theta, t_arrival, t_final, pre_h, lead_h, ang, t_b, t_track = task
    s = sk.station_keeping_surface(system, torus, theta, t_arrival, t_b, t_final, agent_theta=ang,
                                   t_track_start=t_track, progress=False)
    sig_a = s.range_sigma_at_arrival_km
    arr_pct = 100 * np.mean(sig_a < sig_a[np.arange(s.t_arrival.size), s.informed][:, None], axis=1)
    sp = s.reselect("projection")
    return SweepRow(float(pre_h), float(lead_h), float(ang / (2 * np.pi)), float(np.median(s.informed_percentile)),
                    float(np.mean(s.informed_percentile < 25) * 100), float(np.median(arr_pct)),
                    float(np.mean(arr_pct < 25) * 100), float(np.median(s.informed_fuel_percentile)),
                    float(np.median(sp.informed_percentile)), float(np.median(sp.informed_fuel_percentile)))


def scenario_sweep(system: CR3BP, torus, theta, t_arrival, arrival_start_h: float, t_final: float, *,
                   pre_arcs_h=(0.0, 24.0), leads_h=(12.0, 24.0, 48.0),
                   agent_thetas=(0.0, np.pi / 2, np.pi, 3 * np.pi / 2), executor=None) -> tuple:
    """One surface per (tracking arc before the first burn, burn lead before ``arrival_start_h``, agent ring angle);
    returns a tuple of :class:`SweepRow`; one task per setting on ``executor`` (``None``: serial)."""
    check_system(system)
    _torus(torus)
    theta, t_arrival = _vector(theta, "theta"), _vector(t_arrival, "t_arrival")
    arrival_start_h = validation.real(arrival_start_h, "arrival_start_h")
    t_final = validation.real(t_final, "t_final")
    pre_arcs_h = _non_negative_vector(pre_arcs_h, "pre_arcs_h")
    leads_h = _vector(leads_h, "leads_h")
    agent_thetas = _vector(agent_thetas, "agent_thetas")
    _executor(executor)
    HR = 3600.0 / system.time_unit_s
    tasks = []
    for pre_h in pre_arcs_h:
        for lead_h in leads_h:
            for ang in agent_thetas:
                t_b = (arrival_start_h - lead_h) * HR
                tasks.append((system, torus, theta, t_arrival, t_final, pre_h, lead_h, ang, t_b, t_b - pre_h * HR))
    return tuple(map_tasks(_sweep_task, tasks, executor=executor, progress=False, desc="scenario sweep"))


def format_sweep(rows) -> str:
    """The rows of :func:`scenario_sweep` as a text table."""
    rows = validation.sequence_of(rows, "rows", SweepRow, "SweepRow")
    lines = ["angle reading" + " " * 57 + "| projection reading",
             ("pre-arc h | lead h | agent phase | median pct (t_f) | best-quartile % (t_f) | median pct (arrival) | "
             "best-quartile % (arrival) | more-fuel % | median pct (t_f) | more-fuel %")]
    lines += [f" {r.pre_h:8.0f} | {r.lead_h:5.0f} | {r.agent_phase:11.2f} | {r.pct_tf:16.1f} | {r.q_tf:21.0f} | "
              f"{r.pct_arr:20.1f} | {r.q_arr:26.0f} | {r.fuel_pct:11.1f} | {r.pct_proj:16.1f} | "
              f"{r.fuel_pct_proj:10.1f}" for r in rows]
    return "\n".join(lines)


def offset_study(system: CR3BP, torus, theta, t_arrival, t_burn: float, t_final: float, rng: np.random.Generator,
                 *, distances_km=(0.0, 1.0, 10.0, 50.0), n_directions: int = 3, agent_theta: float = 0.0,
                 executor=None) -> dict:
    """Median percentile of :math:`\\mathbf u^*` (angle reading) for an agent off the torus at the first burn.

    For each distance ``d`` (km) and each of ``n_directions`` random directions drawn from ``rng``: position offset
    ``d`` km and velocity offset ``d`` times the ring's velocity-to-position size ratio.  Returns ``{d: [percentile,
    ...]}`` (percent); one task per surface on ``executor`` (``None``: serial).
    """
    check_system(system)
    _torus(torus)
    theta, t_arrival, t_burn, t_final = _scenario_times(theta, t_arrival, t_burn, t_final)
    validation.rng(rng)
    distances_km = _non_negative_vector(distances_km, "distances_km")
    n_directions = validation.integer(n_directions, "n_directions", minimum=1)
    agent_theta = validation.real(agent_theta, "agent_theta")
    _executor(executor)
    L, V = system.length_unit_km, system.velocity_unit_km_s
    vel_per_km = torus.velocity_size_mps / torus.size_km  # m/s per km
    tasks = []  # offsets drawn in order first, surfaces computed after: same numbers on any executor
    for d_km in distances_km:
        for _ in range(n_directions):
            dr, dv = rng.standard_normal(3), rng.standard_normal(3)
            off = np.r_[d_km * dr / np.linalg.norm(dr) / L, d_km * vel_per_km * 1e-3 * dv / np.linalg.norm(dv) / V]
            tasks.append((system, torus, theta, t_arrival, t_burn, t_final, agent_theta, off))
    vals = map_tasks(_offset_task, tasks, executor=executor, progress=False, desc="offsets")
    return {float(d): vals[i * n_directions:(i + 1) * n_directions] for i, d in enumerate(distances_km)}


def _offset_task(task):
    """Median percentile of u* (angle reading) for one offset agent (sweep task)."""
    system, torus, theta, t_arrival, t_burn, t_final, agent_theta, off = task
    s = sk.station_keeping_surface(system, torus, theta, t_arrival, t_burn, t_final, agent_theta=agent_theta,
                                   agent_offset=off, progress=False)
    return float(np.median(s.informed_percentile))


def member_study(system: CR3BP, orbit, theta, t_arrival, t_burn: float, t_final: float, *, target_km: float = 215.0,
                 statistics=("ring_mean_km", "rms_km"), agent_theta: float = 0.0) -> dict:
    """For the torus member whose ``statistic`` (another reading of "average range") equals ``target_km``: its torus
    mean range and ring size (km), and per reading of Eq. 25 the median percentile of :math:`\\mathbf u^*` and the
    percent of slices where it uses at most the median fuel.  Returns ``{statistic: dict}``."""
    check_system(system)
    validation.instance(orbit, "orbit", PeriodicOrbit)
    theta, t_arrival, t_burn, t_final = _scenario_times(theta, t_arrival, t_burn, t_final)
    target_km = validation.positive(target_km, "target_km")
    statistics = validation.one_or_many(statistics, "statistics", str, "str")
    for stat in statistics:
        validation.choice(stat, "statistics entry", ("mean_km", "ring_mean_km", "rms_km"))
    agent_theta = validation.real(agent_theta, "agent_theta")
    out = {}
    for stat in statistics:
        tor, st = qpo_for_mean_range(orbit, target_km, statistic=stat)
        s = sk.station_keeping_surface(system, tor, theta, t_arrival, t_burn, t_final, agent_theta=agent_theta,
                                       progress=False)
        row = {"mean_km": float(st.mean_km), "size_km": float(tor.size_km)}
        for crit in ("angle", "projection"):
            r = s.reselect(crit)
            row[crit] = (float(np.median(r.informed_percentile)),
                         float(np.mean(r.informed_fuel_m_s <= np.median(r.fuel_m_s, axis=1)) * 100))
        out[stat] = row
    return out


# ---------------------------------------------------------------------------------------------------------------
# u* against uninformed (random) station-keeping maneuvers
# ---------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class RandomPickStudy:
    """Random station-keeping maneuvers: for every arrival slice, the maneuvers to ``n_draws`` target ring angles
    drawn uniformly on :math:`[0, 2\\pi)` (the same angles for every slice), each with its covariance analysis.

    A uniformly random target ring angle is what an *uninformed* station-keeping choice does: the direction and the
    size of both burns follow from the transfer to that point of the torus.  The angles are continuous, not on the
    ring-angle grid of a surface, so the baseline does not depend on how finely that surface is sampled.

    Attributes
    ----------
    theta : ndarray (n_draws,)
        Drawn target ring angles, rad.
    t_arrival : ndarray (n_t,)
        Arrival times, TU from apoapsis.
    range_sigma_km : ndarray (n_t, n_draws)
        :math:`\\sqrt{J_\\rho}` at :math:`t_f` of every random pick, km.
    fuel_m_s : ndarray (n_t, n_draws)
        Total fuel of every random pick, m/s.
    """

    theta: np.ndarray
    t_arrival: np.ndarray
    range_sigma_km: np.ndarray
    fuel_m_s: np.ndarray

    def beaten_percent(self, surface) -> float:
        """Percent of the (slice, draw) pairs whose random pick has a *larger* :math:`\\sqrt{J_\\rho}` than the
        :math:`\\mathbf u^*` of ``surface`` in the same slice (same arrival times required)."""
        S = _surface(surface)
        if S.t_arrival.shape != self.t_arrival.shape or not np.allclose(S.t_arrival, self.t_arrival, rtol=0,
                                                                       atol=1e-12):
            raise ValueError(f"surface must have the arrival times of the random picks ({self.t_arrival.size} slices); "
                             f"got {S.t_arrival.size} slices at other times")
        return _beats(S.informed_range_sigma_km, self.range_sigma_km)

    def percentile_of(self, range_sigma_km) -> np.ndarray:
        """Per slice, percent of the random picks with a *smaller* :math:`\\sqrt{J_\\rho}` than ``range_sigma_km``
        (n_t,) km (0 = better than every random pick)."""
        v = validation.as_array(range_sigma_km, "range_sigma_km", shape=self.t_arrival.shape)
        return 100 * np.mean(self.range_sigma_km < v[:, None], axis=1)


def random_pick_study(system: CR3BP, torus, t_arrival, t_burn: float, t_final: float, rng: np.random.Generator, *,
                      n_draws: int, agent_theta: float = 0.0, t_track_start: float | None = None) -> RandomPickStudy:
    """``n_draws`` random station-keeping maneuvers per arrival slice (target ring angles uniform on
    :math:`[0, 2\\pi)` from ``rng``, shared by the slices) in the scenario of
    :func:`cislunar.papers.greaves_scheeres_2023.station_keeping.station_keeping_surface` (same times in TU, agent
    ring angle ``agent_theta`` rad, tracking from ``t_track_start``), with their covariance analyses.

    The draws come from ``rng`` only, so the same seed gives the same picks and the same numbers.
    """
    check_system(system)
    _torus(torus)
    t_arrival = _vector(t_arrival, "t_arrival")
    t_burn, t_final = validation.real(t_burn, "t_burn"), validation.real(t_final, "t_final")
    validation.rng(rng)
    n_draws = validation.integer(n_draws, "n_draws", minimum=1)
    agent_theta = validation.real(agent_theta, "agent_theta")
    if t_track_start is not None:
        t_track_start = validation.real(t_track_start, "t_track_start")
    theta = 2 * np.pi * rng.random(n_draws)
    s = sk.station_keeping_surface(system, torus, theta, t_arrival, t_burn, t_final, agent_theta=agent_theta,
                                   t_track_start=t_track_start, progress=False)
    return RandomPickStudy(theta, s.t_arrival, s.range_sigma_km, s.fuel_m_s)


# ---------------------------------------------------------------------------------------------------------------
# Full-filter Monte Carlo (beyond the paper)
# ---------------------------------------------------------------------------------------------------------------
#: Policy labels of :func:`filter_monte_carlo`, in order.
POLICIES = ("informed u*\n(angle reading)", "informed u*\n(projection)", "uninformed\n(random phase)", "no maneuver")


def execution_levels(exec_abs_m_s: float, exec_rel: float) -> dict:
    """Execution-error levels: tag -> (1-sigma absolute m/s, relative fraction) per axis."""
    exec_abs_m_s = validation.positive(exec_abs_m_s, "exec_abs_m_s", allow_zero=True)
    exec_rel = validation.positive(exec_rel, "exec_rel", allow_zero=True)
    return {"perfect": (0.0, 0.0), "small": (exec_abs_m_s / 10, exec_rel / 10), "exec": (exec_abs_m_s, exec_rel)}


def nees_p_value(mean_nees: float, n_runs: int, dim: int = 12) -> float:
    """Two-sided chi-square tail probability of a mean NEES over ``n_runs`` runs of a ``dim``-state filter.

    For a consistent filter ``n_runs * mean_nees`` is chi-square with ``dim * n_runs`` degrees of freedom; the value
    returned is ``2 * min(cdf, sf)`` of it (at most 1).  It is at least 0.05 exactly when ``mean_nees`` lies inside
    the 95 % band of :attr:`MonteCarloStudy.band` (``chi2.ppf([0.025, 0.975], dim * n_runs) / n_runs``), so the
    band's test becomes one number whose threshold does not depend on the run count.
    """
    m = validation.positive(mean_nees, "mean_nees", allow_zero=True)
    n = validation.integer(n_runs, "n_runs", minimum=1)
    k = validation.integer(dim, "dim", minimum=1) * n
    return float(min(1.0, 2 * min(chi2.cdf(n * m, k), chi2.sf(n * m, k))))


@dataclass(frozen=True)
class MonteCarloStudy:
    """Summary of the filter runs per (policy, execution level).

    Attributes
    ----------
    summary : dict
        ``(policy, level) -> dict(nees, rms, fsig, ca, failed)``: mean NEES of the 12-dimensional SSAT state at
        :math:`t_f`, RMS range error (m), filter RMS 1-sigma (m), covariance-analysis prediction (m), failed runs.
    levels : dict
        Level tag -> (m/s, fraction).
    n_trials : int
    band : tuple of float
        95 % chi-square band of the mean NEES over ``n_trials`` runs.
    seconds : float
        Wall-clock time of the runs.
    slice_index, no_maneuver_index : int
        Arrival slice used and the ring-angle index of the agent's own phase (no maneuver).
    prior_range_m : float
        Range 1-sigma of the prior at the start of tracking, m.
    """

    summary: dict
    levels: dict
    n_trials: int
    band: tuple
    seconds: float
    slice_index: int
    no_maneuver_index: int
    prior_range_m: float

    def format(self) -> str:
        """Runs, band and one line per (policy, level): failures, mean NEES, RMS error, filter and predicted sigma."""
        lo, hi = self.band
        lines = [(f"{len(self.summary)} x {self.n_trials} filter runs in {self.seconds:.1f} s; 95 % band of the mean "
                 f"NEES: [{lo:.2f}, {hi:.2f}]"),
                 ("policy                      | burns   | failed | mean NEES(t_f) | RMS range error m | filter sigma m | "
                 "cov. analysis m")]
        lines += [f"{pol.replace(chr(10), ' '):27s} | {tag:7s} | {s['failed']:6d} | {s['nees']:14.2f} | "
                  f"{s['rms']:17.1f} | {s['fsig']:14.1f} | {s['ca']:15.1f}" for (pol, tag), s in self.summary.items()]
        lines.append(f"range 1-sigma of the prior at the start of tracking: {self.prior_range_m:.0f} m")
        return "\n".join(lines)

    def p_value(self, policy: str, level: str = "perfect") -> float:
        """:func:`nees_p_value` of the mean NEES of ``policy`` at ``level`` over its runs that did not fail (12-state
        SSAT filter): at least 0.05 when the mean NEES is inside its 95 % band."""
        validation.choice(policy, "policy", POLICIES)
        validation.choice(level, "level", tuple(self.levels))
        if (policy, level) not in self.summary:
            raise ValueError(f"level must be 'perfect' for {policy!r} (no burn to execute); got {level!r}")
        s = self.summary[(policy, level)]
        return nees_p_value(s["nees"], self.n_trials - s["failed"])

    def ratio(self, policy: str, level: str = "perfect") -> float:
        """RMS range error of ``policy`` over that of the uninformed choice."""
        validation.choice(policy, "policy", POLICIES)
        validation.choice(level, "level", tuple(self.levels))
        if (policy, level) not in self.summary:
            raise ValueError(f"level must be 'perfect' for {policy!r} (no burn to execute); got {level!r}")
        return self.summary[(policy, level)]["rms"] / self.summary[(POLICIES[2], level)]["rms"]


def filter_monte_carlo(system: CR3BP, surface, surface_projection, target_apolune_state, *, n_trials: int,
                       seed: int, exec_abs_m_s: float = 1e-3, exec_rel: float = 0.01, executor=None) -> MonteCarloStudy:
    """Iterated-EKF runs (:func:`station_keeping.filter_trial`) for the arrival slice closest to apoapsis.

    Policies (:data:`POLICIES`): :math:`\\mathbf u^*` of ``surface`` (angle reading) and of ``surface_projection``,
    a ring angle drawn at random in each trial (the agent's own phase excluded), and no maneuver (perfect level only:
    no burn, nothing to execute); levels from :func:`execution_levels`.  Trial streams ``[seed, k]`` for the k-th (policy,
    level) pair, so the result does not depend on ``executor``.
    """
    check_system(system)
    S, SP = _surface(surface), _surface(surface_projection, "surface_projection")
    target_apolune_state = validation.as_state(target_apolune_state, "target_apolune_state", batch=False)
    n_trials = validation.integer(n_trials, "n_trials", minimum=1)
    seed = validation.integer(seed, "seed", minimum=0)
    levels = execution_levels(exec_abs_m_s, exec_rel)
    _executor(executor)
    inf, infp, uni, none = POLICIES
    j = int(np.argmin(np.abs(S.t_arrival_hours)))
    tgt_b = propagate(system, target_apolune_state, np.array([0.0, S.t[0]])).x[-1]  # target at start of tracking
    zero = int(np.argmin(S.fuel_m_s[j]))  # phase 0: no maneuver
    policies = {}
    for tag, (a, r) in levels.items():
        def mk(i, lab, a=a, r=r):
            return sk.filter_scenario(S, j, i, tgt_b, system, exec_sigma_abs_m_s=a, exec_sigma_rel=r, label=lab)
        policies[(inf, tag)] = (sk.filter_trial, (mk(S.informed[j], "informed"),))
        policies[(infp, tag)] = (sk.filter_trial, (mk(SP.informed[j], "informed, projection"),))
        policies[(uni, tag)] = (sk.random_choice_trial,
                                (tuple(mk(i, "random") for i in range(S.theta.size) if i != zero),))
        if tag == "perfect":
            policies[(none, tag)] = (sk.filter_trial, (mk(zero, "none"),))
    t0 = time.perf_counter()
    mc = {key: run_monte_carlo(fn, n_trials, [seed, k], args=args, executor=executor,
                               desc=f"{key[0].replace(chr(10), ' ')}, {key[1]}")
          for k, (key, (fn, args)) in enumerate(policies.items())}
    seconds = time.perf_counter() - t0
    lo, hi = chi2.ppf([0.025, 0.975], 12 * n_trials) / n_trials
    ca_of = {inf: S.informed_range_sigma_km[j], infp: SP.informed_range_sigma_km[j], none: S.range_sigma_km[j, zero],
             uni: np.sqrt(np.mean(np.delete(S.range_sigma_km[j], zero) ** 2))}
    summary = {}
    for (pol, tag), res in mc.items():
        ok = [r for r in res if not r.failure]
        summary[(pol, tag)] = {"nees": float(np.mean([r.nees[-1] for r in ok])),
                               "rms": float(np.sqrt(np.mean([r.range_error_km[-1] ** 2 for r in ok])) * 1e3),
                               "fsig": float(np.sqrt(np.mean([r.range_sigma_km[-1] ** 2 for r in ok])) * 1e3),
                               "ca": float(ca_of[pol] * 1e3), "failed": len(res) - len(ok)}
    M0 = ssat.range_projection(np.r_[S.agent_x0, tgt_b])
    prior = float(np.sqrt(M0 @ ssat.initial_covariance(system) @ M0) * system.length_unit_km * 1e3)
    return MonteCarloStudy(summary, levels, n_trials, (float(lo), float(hi)), seconds, j, zero, prior)
