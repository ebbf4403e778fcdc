"""Malformed-argument specs (issue 18) for the AMOS 2023 studies, exercises and figures (notebooks 07 and 08).

Plugin of ``tests/reliability/test_reliability.py`` (protocol: ``MODULES``, ``EXEMPT``, ``specs(Spec, lazy)``).
Covers every public function of :mod:`cislunar.papers.greaves_scheeres_2023.guidance_study`,
:mod:`~cislunar.papers.greaves_scheeres_2023.station_keeping_study`,
:mod:`~cislunar.papers.greaves_scheeres_2023.exercises` and :mod:`~cislunar.papers.greaves_scheeres_2023.figures`
(``station_keeping`` itself is swept by ``reliability_specs_missions.py``).  The valid objects the studies and the
figures take (the 9:2 NRHO, a one-day demonstration pair, a 10-km torus with N = 5, a 4 x 2 station-keeping
surface, tiny policy, tracking-arc, grid and Monte Carlo studies) are built once, lazily, at small sizes, so every
baseline call costs about a second or less, except ``member_study`` (2 s: it converges a 30-km torus) and the three
notebook-08 exercises (about 4 s each: they converge the paper's 215-km torus).  The result objects' methods that
take arguments (``SliceStatistics.format``, ``GridStudy.series``, ``PolicyStudy.*``, ``TrackingArcStudy.*``,
``MonteCarloStudy.ratio``, ``MonteCarloStudy.p_value``) are swept too.  Figure calls close the figure they draw.
"""

from __future__ import annotations

import functools

import numpy as np
from spec_helpers import closed as _drawn

from cislunar.cr3bp import orbits
from cislunar.cr3bp import torus as tm
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.papers.greaves_scheeres_2023 import exercises as ex
from cislunar.papers.greaves_scheeres_2023 import figures as fg
from cislunar.papers.greaves_scheeres_2023 import guidance_study as gs
from cislunar.papers.greaves_scheeres_2023 import station_keeping as sk
from cislunar.papers.greaves_scheeres_2023 import station_keeping_study as sks

MODULES = [gs, sks, ex, fg]
EXEMPT: dict = {}

HR = 3600.0 / em.time_unit_s
T_ARRIVAL = np.array([-6.0, 0.5]) * HR
T_BURN, T_FINAL = -18.0 * HR, 12.0 * HR
THETA = 2 * np.pi * np.arange(4) / 4


# ---------------------------------------------------------------------------------------------------------------
# valid objects (built once, on first use)
# ---------------------------------------------------------------------------------------------------------------
@functools.lru_cache(maxsize=None)
def _orbit():
    return orbits.nrho_9_2(em)


@functools.lru_cache(maxsize=None)
def _pair():
    """The demonstration pair with one day of hourly measurements (25 epochs)."""
    return gs.demonstration_pair(em, _orbit(), days=1)


@functools.lru_cache(maxsize=None)
def _policy():
    return gs.policy_study(em, _pair(), [1, 2], [1.0], n_grid=20, n_perp=4)


@functools.lru_cache(maxsize=None)
def _surrogate():
    return gs.surrogate_check(em, _pair(), coast_hours=2, n_grid=20)


@functools.lru_cache(maxsize=None)
def _dmap():
    return gs.direction_map(em, _pair(), _policy(), coast_hours=2, n_grid=20)


@functools.lru_cache(maxsize=None)
def _arcs():
    return gs.tracking_arc_study(em, _pair(), [1], [1, 2], n_grid=20, n_perp=4)


@functools.lru_cache(maxsize=None)
def _torus():
    """A 10-km torus about the 9:2 NRHO with N = 5 (converges in ~0.1 s)."""
    return tm.torus_from_orbit(_orbit(), 5, 10.0)


@functools.lru_cache(maxsize=None)
def _surface():
    return sk.station_keeping_surface(em, _torus(), THETA, T_ARRIVAL, T_BURN, T_FINAL, progress=False)


@functools.lru_cache(maxsize=None)
def _surface_projection():
    return _surface().reselect("projection")


@functools.lru_cache(maxsize=None)
def _grid():
    """Both agent phases the figure draws (0 and 0.75 of a turn)."""
    return sks.grid_resolution_study(em, _torus(), (3, 4), T_ARRIVAL, T_BURN, T_FINAL, agent_phases=(0.0, 0.75))


@functools.lru_cache(maxsize=None)
def _sweep_rows():
    return sks.scenario_sweep(em, _torus(), THETA, T_ARRIVAL, -6.0, T_FINAL, pre_arcs_h=(0.0,), leads_h=(12.0,),
                              agent_thetas=(0.0,))


@functools.lru_cache(maxsize=None)
def _mcs():
    return sks.filter_monte_carlo(em, _surface(), _surface_projection(), _orbit().x0, n_trials=1, seed=0)


def _rng():
    return np.random.default_rng(0)


def specs(S, lazy):
    s = []
    orbit, torus, pair, surface = lazy(_orbit), lazy(_torus), lazy(_pair), lazy(_surface)
    rng = lazy(_rng)

    # ---------------------------------------------------------------------------------------------- guidance_study
    s.append(S("leading_hours", gs.leading_hours,
               dict(coast_hours=np.array([1.0, 2.0, 4.0]), ok=np.array([True, True, False])),
               dict(coast_hours="vec", ok="arr_any")))
    s.append(S("coordinate_checks", gs.coordinate_checks, dict(rng=rng, n_states=2), dict(rng="rng", n_states="int1")))
    s.append(S("demonstration_pair", gs.demonstration_pair,
               dict(system=em, orbit=orbit, lead_days=1.0, apolune_range_km=215.0, days=1),
               dict(system="system", orbit="instance", lead_days="pos", apolune_range_km="pos", days="int1")))
    s.append(S("equation_checks", gs.equation_checks,
               dict(system=em, agent_x=lazy(lambda: _pair().agent_x0), target_x=lazy(lambda: _pair().target_x0)),
               dict(system="system", agent_x="state", target_x="state")))
    s.append(S("surrogate_check", gs.surrogate_check,
               dict(system=em, pair=pair, coast_hours=2, n_grid=20, probe_m_s=1e-4),
               dict(system="system", pair="instance", coast_hours="int1", n_grid="int2", probe_m_s="pos")))
    s.append(S("policy_study", gs.policy_study,
               dict(system=em, pair=pair, coast_hours=np.array([1.0, 2.0]), dv_m_s=np.array([1.0]), n_grid=20,
                    n_perp=4, executor=None),
               dict(system="system", pair="instance", coast_hours="vec", dv_m_s="vec", n_grid="int2", n_perp="int1",
                    executor="instance_opt")))
    s.append(S("direction_map", gs.direction_map,
               dict(system=em, pair=pair, study=lazy(_policy), coast_hours=2, dv_m_s=1.0, n_grid=20),
               dict(system="system", pair="instance", study="instance", coast_hours="int1", dv_m_s="pos_opt",
                    n_grid="int2")))
    s.append(S("timing_study", gs.timing_study,
               dict(system=em, pair=pair, surrogate=lazy(_surrogate), dv_m_s=1.0, n_grid=20, repeat_core=2,
                    repeat_optimum=1),
               dict(system="system", pair="instance", surrogate="instance", dv_m_s="pos", n_grid="int2",
                    repeat_core="int1", repeat_optimum="int1")))
    s.append(S("tracking_arc_study", gs.tracking_arc_study,
               dict(system=em, pair=pair, arc_hours=np.array([1.0]), coast_hours=np.array([1.0, 2.0]), dv_m_s=1.0,
                    n_grid=20, n_perp=4, tolerance_percent=5.0, executor=None),
               dict(system="system", pair="instance", arc_hours="vec", coast_hours="vec", dv_m_s="pos",
                    n_grid="int2", n_perp="int1", tolerance_percent="pos", executor="instance_opt")))
    s.append(S("qpo_pair_study", gs.qpo_pair_study,
               dict(system=em, torus=torus, pair=pair, ring_angles_deg=np.array([0.0]),
                    coast_hours=np.array([1.0, 2.0]), dv_m_s=1.0, n_grid=20, n_perp=4, executor=None),
               dict(system="system", torus="instance", pair="instance", ring_angles_deg="vec", coast_hours="vec",
                    dv_m_s="pos", n_grid="int2", n_perp="int1", executor="instance_opt")))

    for meth, kw, kinds in (("sign_percent", dict(dv_m_s=1.0), dict(dv_m_s="real")),
                            ("optimum_at", dict(dv_m_s=1.0, coast_hours=2.0), dict(dv_m_s="real", coast_hours="real")),
                            ("perpendicular_hours", dict(dv_m_s=1.0, tol=0.02), dict(dv_m_s="real", tol="nonneg"))):
        s.append(S(f"PolicyStudy.{meth}", lazy(lambda m=meth: getattr(_policy(), m)), kw, kinds))
    for meth in ("within_hours", "leading_run"):
        s.append(S(f"TrackingArcStudy.{meth}", lazy(lambda m=meth: getattr(_arcs(), m)), dict(arc_hours=1),
                   dict(arc_hours="real")))

    # ------------------------------------------------------------------------------------ station_keeping_study
    times = dict(theta=THETA, t_arrival=T_ARRIVAL, t_burn=T_BURN, t_final=T_FINAL)
    time_kinds = dict(theta="vec", t_arrival="vec", t_burn="real", t_final="real")
    s.append(S("slice_statistics", sks.slice_statistics, dict(surface=surface), dict(surface="instance")))
    s.append(S("SliceStatistics.format", lazy(lambda: sks.slice_statistics(_surface()).format),
               dict(surface=surface), dict(surface="instance")))
    s.append(S("GridStudy.series", lazy(lambda: _grid().series), dict(agent_phase=0.75, reading="angle", key="sigma_m"),
               dict(agent_phase="real", reading="choice", key="choice")))
    s.append(S("MonteCarloStudy.ratio", lazy(lambda: _mcs().ratio), dict(policy=sks.POLICIES[1], level="exec"),
               dict(policy="choice", level="choice")))
    s.append(S("MonteCarloStudy.p_value", lazy(lambda: _mcs().p_value), dict(policy=sks.POLICIES[1], level="exec"),
               dict(policy="choice", level="choice")))
    s.append(S("valley_edge_ratio", sks.valley_edge_ratio, dict(surface=surface), dict(surface="instance")))
    s.append(S("second_burn_raises", sks.second_burn_raises, dict(ratio=np.array([0.5, 1.2])), dict(ratio="vec")))
    s.append(S("nees_p_value", sks.nees_p_value, dict(mean_nees=12.0, n_runs=40, dim=12),
               dict(mean_nees="nonneg", n_runs="int1", dim="int1")))
    s.append(S("grid_resolution_study", sks.grid_resolution_study,
               dict(system=em, torus=torus, n_grid=(3, 4), t_arrival=T_ARRIVAL, t_burn=T_BURN, t_final=T_FINAL,
                    agent_phases=(0.0,), executor=None),
               dict(system="system", torus="instance", n_grid="vec", t_arrival="vec", t_burn="real", t_final="real",
                    agent_phases="vec", executor="instance_opt")))
    s.append(S("scenario_sweep", sks.scenario_sweep,
               dict(system=em, torus=torus, theta=THETA, t_arrival=T_ARRIVAL, arrival_start_h=-6.0, t_final=T_FINAL,
                    pre_arcs_h=(0.0,), leads_h=(12.0,), agent_thetas=(0.0,), executor=None),
               dict(system="system", torus="instance", theta="vec", t_arrival="vec", arrival_start_h="real",
                    t_final="real", pre_arcs_h="vec", leads_h="vec", agent_thetas="vec", executor="instance_opt")))
    s.append(S("format_sweep", sks.format_sweep, dict(rows=lazy(_sweep_rows)), dict(rows="iterable")))
    s.append(S("offset_study", sks.offset_study,
               dict(system=em, torus=torus, **times, rng=rng, distances_km=(1.0,), n_directions=1, agent_theta=0.0,
                    executor=None),
               dict(system="system", torus="instance", **time_kinds, rng="rng", distances_km="vec",
                    n_directions="int1", agent_theta="real", executor="instance_opt")))
    s.append(S("member_study", sks.member_study,
               dict(system=em, orbit=orbit, **times, target_km=30.0, statistics=("ring_mean_km",), agent_theta=0.0),
               dict(system="system", orbit="instance", **time_kinds, target_km="pos", statistics="names",
                    agent_theta="real")))
    s.append(S("execution_levels", sks.execution_levels, dict(exec_abs_m_s=1e-3, exec_rel=0.01),
               dict(exec_abs_m_s="nonneg", exec_rel="nonneg")))
    s.append(S("filter_monte_carlo", sks.filter_monte_carlo,
               dict(system=em, surface=surface, surface_projection=lazy(_surface_projection),
                    target_apolune_state=lazy(lambda: _orbit().x0), n_trials=1, seed=0, exec_abs_m_s=1e-3,
                    exec_rel=0.01, executor=None),
               dict(system="system", surface="instance", surface_projection="instance", target_apolune_state="state",
                    n_trials="int1", seed="seed", exec_abs_m_s="nonneg", exec_rel="nonneg",
                    executor="instance_opt")))
    s.append(S("random_pick_study", sks.random_pick_study,
               dict(system=em, torus=torus, t_arrival=T_ARRIVAL, t_burn=T_BURN, t_final=T_FINAL, rng=rng, n_draws=2,
                    agent_theta=0.0, t_track_start=None),
               dict(system="system", torus="instance", t_arrival="vec", t_burn="real", t_final="real", rng="rng",
                    n_draws="int1", agent_theta="real", t_track_start="real_opt")))

    # ---------------------------------------------------------------------------------------------- exercises
    s.append(S("exercise_07_burn_magnitude", ex.exercise_07_burn_magnitude,
               dict(dv_m_s=(0.5, 1.0), coast_hours=2), dict(dv_m_s="vec", coast_hours="int1")))
    s.append(S("exercise_07_tracking_arc", ex.exercise_07_tracking_arc,
               dict(arc_hours=1, coast_hours=(1,), dv_m_s=1.0, n_grid=20),
               dict(arc_hours="int1", coast_hours="vec", dv_m_s="pos", n_grid="int2")))
    s.append(S("exercise_07_sphere_resolution", ex.exercise_07_sphere_resolution,
               dict(n_grid=(20, 30), coast_hours=2, dv_m_s=1.0),
               dict(n_grid="vec", coast_hours="int1", dv_m_s="pos")))
    s.append(S("exercise_08_ring_grid", ex.exercise_08_ring_grid, dict(n_ring=(4, 5), arrival_hours=(0.0,)),
               dict(n_ring="vec", arrival_hours="vec")))
    s.append(S("exercise_08_execution_errors", ex.exercise_08_execution_errors,
               dict(scales=(0.0, 0.1, 1.0), n_trials=2, n_ring=4, seed=0),
               dict(scales="vec", n_trials="int2", n_ring="int2", seed="seed")))
    s.append(S("exercise_08_agent_phase", ex.exercise_08_agent_phase,
               dict(agent_phases=(0.0, 0.25), n_ring=4, n_arrival=1),
               dict(agent_phases="vec", n_ring="int2", n_arrival="int1")))

    # ---------------------------------------------------------------------------------------------- figures
    s.append(S("ssat_scenario", _drawn(fg.ssat_scenario), dict(system=em, pair=pair),
               dict(system="system", pair="instance")))
    s.append(S("policies_vs_coast", _drawn(fg.policies_vs_coast), dict(study=lazy(_policy)), dict(study="instance")))
    s.append(S("cost_over_directions", _drawn(fg.cost_over_directions), dict(dmap=lazy(_dmap)),
               dict(dmap="instance")))
    s.append(S("torus_and_nrho", _drawn(fg.torus_and_nrho), dict(system=em, orbit=orbit, torus=torus),
               dict(system="system", orbit="instance", torus="instance")))
    s.append(S("surfaces", _drawn(fg.surfaces), dict(S=surface, which="range_fuel"),
               dict(S="instance", which="choice")))
    s.append(S("range_and_fuel_maps", _drawn(fg.range_and_fuel_maps), dict(S=surface), dict(S="instance")))
    s.append(S("informed_within_slices", _drawn(fg.informed_within_slices), dict(S=surface), dict(S="instance")))
    s.append(S("map_with_percentiles", _drawn(fg.map_with_percentiles),
               dict(S_map=surface, map_title="map",
                    panels=lazy(lambda: [("angle", _surface(), "o-"), ("projection", _surface_projection(), "s--")]),
                    panel_title="ranks", reading="projection"),
               dict(S_map="instance", map_title="instance_str", panels="iterable", panel_title="instance_str",
                    reading="choice")))
    s.append(S("grid_resolution", _drawn(fg.grid_resolution),
               dict(grid=lazy(_grid), no_maneuver_m=lazy(lambda: float(_surface().range_sigma_km[0, 0] * 1e3))),
               dict(grid="instance", no_maneuver_m="pos")))
    s.append(S("monte_carlo_range_errors", _drawn(fg.monte_carlo_range_errors), dict(mcs=lazy(_mcs)),
               dict(mcs="instance")))
    return s
