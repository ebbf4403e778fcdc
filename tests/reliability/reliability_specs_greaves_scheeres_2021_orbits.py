"""Malformed-argument specs for the Greaves & Scheeres 2021 reference orbits, observation strategy and exercises
(plugin of tests/reliability/test_reliability.py, issue 18).

Covers ``reference_orbits`` (notebook 01), ``observation_strategy`` (notebook 09) and ``exercises`` (the worked
exercises of notebooks 01, 09, 09b and 10).  ``tracking`` is a core module of the main table; the Wolf & Jones
``reference_tables`` module is swept by reliability_specs_wolf_jones_studies.py; the other modules of the package by
reliability_specs_greaves_scheeres_2021_studies.py, reliability_specs_detection.py and
reliability_specs_adaptive_ocbe.py.

Labels end in ``.gs21_orbits`` (the sweep keys coverage on the part before the first dot), so they cannot collide
with another plugin's.  Valid baselines run on small sizes: a 24-hour cadence over one 9:2 NRHO period, one Monte
Carlo run per cell, a 0.06 continuation step along the halo family, coarse site grids and a few samples; the
result objects that only feed a figure or a readout are built directly where a real run would add nothing.  Every
exercise runs at a size of a few seconds at most.  Figure calls close their figure.
"""

from __future__ import annotations

import functools

import numpy as np
from spec_helpers import closed as _closed
from spec_helpers import nrho

from cislunar.cr3bp import orbits
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.papers.greaves_scheeres_2021 import exercises as ex
from cislunar.papers.greaves_scheeres_2021 import observation_strategy as obs
from cislunar.papers.greaves_scheeres_2021 import reference_orbits as ro
from cislunar.papers.greaves_scheeres_2021.claims.observation_strategy import CLAIMS

MODULES = [ro, obs, ex]
EXEMPT: dict = {}

SUFFIX = ".gs21_orbits"
#: The OCBE control weight of notebook 09 (1e-20 km^2/s^3), LU^2/TU^3.
Q = 1e-20 * em.time_unit_s**3 / em.length_unit_km**2




# ---------------------------------------------------------------------------------------------------------------
# cached valid objects
# ---------------------------------------------------------------------------------------------------------------
@functools.lru_cache(maxsize=None)
def dros():
    return tuple(orbits.dro_family(em, np.array([0.78, 0.8, 0.82])))


@functools.lru_cache(maxsize=None)
def dro_groups():
    a, b, _ = dros()
    return [(a, "observer_t0 (Table 2)"), (b, "target 1 (Table 2)")]


@functools.lru_cache(maxsize=None)
def halo():
    return ro.halo_family_study(em, 0.06)


@functools.lru_cache(maxsize=None)
def var_check():
    return ro.VariationalCheck(np.logspace(-8.0, -3.0, 3), np.array([1e-6, 1e-9, 1e-5]),
                               np.array([1e-4, 1e-7, 1e-3]))


@functools.lru_cache(maxsize=None)
def visibility():
    return ro.observer_visibility(em, {"9:2": nrho()}, 20, 2.0, 3600.0)


@functools.lru_cache(maxsize=None)
def perilune():
    return ro.perilune_visibility(em, nrho(), (0, 1), half_width_h=1.0)


@functools.lru_cache(maxsize=None)
def demo():
    return obs.measurement_demo(em, nrho(), 24.0)


@functools.lru_cache(maxsize=None)
def typical():
    return obs.typical_run(em, nrho(), 24.0, Q, np.random.default_rng(0))


@functools.lru_cache(maxsize=None)
def study():
    """Angles + rates, one run per cell, two orbit names (the same orbit) at a 24-hour cadence."""
    return obs.strategy_study(em, {"9:2 NRHO": nrho(), "candidate": nrho()}, [24.0], Q, rates=True, n_runs=1,
                              seed=0)


@functools.lru_cache(maxsize=None)
def axes_study():
    return obs.filter_axes_study(em, {"9:2 NRHO": nrho()}, [24.0], Q, n_runs=1, seed=0, axes={"baseline": ({}, 1.0)},
                                 progress=False)


@functools.lru_cache(maxsize=None)
def rmap():
    return obs.regime_map(em, {"9:2 NRHO": nrho()}, [24.0], [1e-5], [1.0], {"rates, 1 s": 1.0}, Q, n_runs=1,
                          seed=0)


@functools.lru_cache(maxsize=None)
def cell():
    return ("9:2 NRHO", 24.0, 1e-5, "angles", 1.0)


@functools.lru_cache(maxsize=None)
def example():
    """A divergence example built from the typical run (the figure draws whatever run it is given)."""
    t = typical()
    return obs.DivergenceExample(cell(), t.scenario, t.truth, t.result, t.forward, 0, 0.0)


def specs(Spec, lazy):
    s = []
    lz = lazy

    def S(name, fn, kwargs, kinds, **kw):
        s.append(Spec(name + SUFFIX, fn, kwargs, kinds, **kw))

    # ------------------------------------------------------------------------------ reference_orbits
    S("variational_check", ro.variational_check,
      dict(system=em, orbit=lz(nrho), n_steps=2, log10_range=(-6.0, -3.0)),
      dict(system="system", orbit="instance", n_steps="int2", log10_range="arr"))
    S("figure_variational_check", _closed(ro.figure_variational_check), dict(check=lz(var_check)),
      dict(check="instance"))
    S("figure_dro_family", _closed(ro.figure_dro_family),
      dict(system=em, family=lz(dros), zoom_family=lz(dros), groups=lz(dro_groups),
           printed_state=np.array([0.79, 0.0, 0.0, 0.0, 0.5, 0.0])),
      dict(system="system", family="iterable", zoom_family="iterable", groups="iterable", printed_state="state"))
    S("halo_family_study", ro.halo_family_study, dict(system=em, step=0.06), dict(system="system", step="pos"))
    for name in ("figure_halo_stability", "figure_nrho_family"):
        S(name, _closed(getattr(ro, name)), dict(system=em, study=lz(halo)), dict(system="system", study="instance"))
    S("observer_visibility", ro.observer_visibility,
      dict(system=em, targets=lz(lambda: {"9:2": nrho()}), samples=20, span_days=2.0, step_s=3600.0),
      dict(system="system", targets="instance", samples="int2", span_days="pos", step_s="pos"))
    S("line_of_sight_samples", ro.line_of_sight_samples, dict(span_days=1.0, step_s=600.0),
      dict(span_days="pos", step_s="pos"))
    S("visibility_report", ro.visibility_report, dict(visibility=lz(visibility), span_days=2.0, step_s=3600.0),
      dict(visibility="instance", span_days="pos", step_s="pos"))
    S("station_pair_sweep", ro.station_pair_sweep,
      dict(system=em, orbit=lz(nrho), grid_deg=(90.0, 180.0), samples=20),
      dict(system="system", orbit="instance", grid_deg="arr", samples="int2"))
    S("perilune_visibility", ro.perilune_visibility,
      dict(system=em, orbit=lz(nrho), best_pair=(0, 1), half_width_h=1.0),
      dict(system="system", orbit="instance", best_pair="iterable", half_width_h="pos"))
    S("figure_observer_sites", _closed(ro.figure_observer_sites),
      dict(system=em, study=lz(halo), perilune=lz(perilune)),
      dict(system="system", study="instance", perilune="instance"))

    # ------------------------------------------------------------------------------ observation_strategy
    S("filled", obs.filled, dict(claim=CLAIMS["angles_only_l2"], span="2-12 h"), dict(claim="instance"))
    S("cadence_label", obs.cadence_label, dict(cadence_h=2.0), dict(cadence_h="pos"))
    S("measurement_demo", obs.measurement_demo,
      dict(system=em, orbit=lz(nrho), cadence_hours=24.0, sigma_angle_rad=1e-5),
      dict(system="system", orbit="instance", cadence_hours="pos", sigma_angle_rad="pos"))
    S("figure_measurements", _closed(obs.figure_measurements), dict(demo=lz(demo)), dict(demo="instance"))
    S("typical_run", obs.typical_run,
      dict(system=em, orbit=lz(nrho), cadence_hours=24.0, control_weight=Q, rng=lz(lambda: np.random.default_rng(0)),
           sigma_angle_rad=1e-5),
      dict(system="system", orbit="instance", cadence_hours="pos", control_weight="pos", rng="rng",
           sigma_angle_rad="pos"))
    S("figure_typical_run", _closed(obs.figure_typical_run), dict(run=lz(typical)), dict(run="instance"))
    S("flagged_cells", obs.flagged_cells,
      dict(rows=[("a", 2.0, 0.05, 3.0, 1.0, 0.1, 4), ("b", 12.0, 0.5, 9.0, 2.0, 0.2, 4)], limit=0.1),
      dict(rows="iterable", limit="range:0:1"))
    S("strategy_study", obs.strategy_study,
      dict(system=em, orbits_=lz(lambda: {"9:2 NRHO": nrho()}), cadences=[24.0], control_weight=Q, rates=False,
           n_runs=1, seed=0, n_runs_one_minute=None, observers="L2", sigma_angle_rad=1e-5, handoff_scale=1.0,
           executor=None),
      dict(system="system", orbits_="instance", cadences="vec", control_weight="pos", rates="bool", n_runs="int1",
           seed="int0", n_runs_one_minute="int1_opt", observers="choice", sigma_angle_rad="pos",
           handoff_scale="pos", executor="instance_opt"))
    S("figure_final_uncertainty", _closed(obs.figure_final_uncertainty),
      dict(rates=lz(study), angles=lz(study), orbit_names=("9:2 NRHO", "candidate")),
      dict(rates="instance", angles="instance", orbit_names="names"))
    S("pct_span", obs.pct_span, dict(values=[0.1, 0.5]), dict(values="vec"))
    S("regime_map", obs.regime_map,
      dict(system=em, orbits_=lz(lambda: {"9:2 NRHO": nrho()}), cadences=[24.0], sigmas=[1e-5], handoffs=[1.0],
           rate_models={"rates, 1 s": 1.0}, control_weight=Q, n_runs=1, seed=0, executor=None),
      dict(system="system", orbits_="instance", cadences="vec", sigmas="vec", handoffs="vec",
           rate_models="instance", control_weight="pos", n_runs="int1", seed="int0", executor="instance_opt"))
    S("figure_regime_map", _closed(obs.figure_regime_map), dict(rmap=lz(rmap)), dict(rmap="instance"))
    S("filter_axes_study", obs.filter_axes_study,
      dict(system=em, orbits_=lz(lambda: {"9:2 NRHO": nrho()}), cadences=[24.0], control_weight=Q, n_runs=1, seed=0,
           n_runs_one_minute=None, axes=None, handoff_scale=1.0, sigma_angle_rad=1e-5, executor=None, progress=False),
      dict(system="system", orbits_="instance", cadences="vec", control_weight="pos", n_runs="int1", seed="int0",
           n_runs_one_minute="int1_opt", axes="instance_opt", handoff_scale="pos", sigma_angle_rad="pos",
           executor="instance_opt", progress="bool"))
    S("figure_filter_axes", _closed(obs.figure_filter_axes), dict(study=lz(axes_study)), dict(study="instance"))
    S("divergence_example", obs.divergence_example,
      dict(system=em, orbit=lz(nrho), rmap=lz(rmap), cell=lz(cell), control_weight=Q, seed=0, n_draws=1),
      dict(system="system", orbit="instance", rmap="instance", cell="instance", control_weight="pos",
           seed="int0", n_draws="int1"))
    S("figure_divergence", _closed(obs.figure_divergence), dict(example=lz(example), what="example"),
      dict(example="instance", what="instance_str"))
    S("compare_stable_candidates", obs.compare_stable_candidates,
      dict(rates=lz(study), reference="9:2 NRHO", candidates=("candidate",), cadences=(24.0,)),
      dict(rates="instance", reference="instance_str", candidates="names", cadences="vec"))

    # ------------------------------------------------------------------------------ exercises
    S("exercise_09b_burn_size", ex.exercise_09b_burn_size, dict(magnitudes_m_s=(0.3, 3.0), n_runs=2, seed=0),
      dict(magnitudes_m_s="vec", n_runs="int2", seed="int0"))
    S("exercise_09b_base_weight", ex.exercise_09b_base_weight,
      dict(q_km2_s3=(1e-18, 1e-12), magnitude_m_s=0.3, n_null=1, n_runs=1, seed=0),
      dict(q_km2_s3="vec", magnitude_m_s="pos", n_null="int1", n_runs="int1", seed="int0"))
    S("exercise_10_window_factor", ex.exercise_10_window_factor, dict(f=(0.03, 0.3), n_runs=4, seed=0),
      dict(f="vec", n_runs="int1", seed="int0"))
    S("exercise_10_pm_j_noise", ex.exercise_10_pm_j_noise, dict(noise_urad=(10.0, 1000.0), f=0.03, n_repeats=1, seed=0),
      dict(noise_urad="vec", f="pos", n_repeats="int1", seed="int0"))
    S("exercise_01_halo_step", ex.exercise_01_halo_step, dict(steps=(0.08, 0.06)), dict(steps="vec"))
    S("exercise_01_site_grid", ex.exercise_01_site_grid, dict(grids_deg=((90.0, 180.0), (60.0, 120.0)), samples=20),
      dict(grids_deg="arr", samples="int2"))
    S("exercise_09_angle_noise", ex.exercise_09_angle_noise,
      dict(noise_urad=(10.0, 100.0), cadence_h=24.0, n_runs=1, seed=0),
      dict(noise_urad="vec", cadence_h="pos", n_runs="int1", seed="int0"))
    S("exercise_09_cadence", ex.exercise_09_cadence, dict(cadences_h=(48.0, 24.0), n_runs=1, seed=0),
      dict(cadences_h="vec", n_runs="int1", seed="int0"))
    S("exercise_09_handoff", ex.exercise_09_handoff, dict(scales=(1.0, 2.0), n_runs=1, seed=0),
      dict(scales="vec", n_runs="int1", seed="int0"))
    return s
