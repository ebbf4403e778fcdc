"""Malformed-argument specs for the Greaves & Scheeres 2021 studies and figures (plugin of
tests/reliability/test_reliability.py, issue 18).

Covers the modules of :mod:`cislunar.papers.greaves_scheeres_2021` that no other plugin covers among the chapter
studies and figures: ``adaptive_studies`` (notebook 09b), ``detection_studies`` (notebook 10) and ``figures``.
``detection`` is swept by the main table and reliability_specs_detection.py, ``panels`` by
reliability_specs_adaptive_ocbe.py.

Valid baselines run on small sizes: a 0.8-period 9:2 NRHO track with a measurement every 8 hours (quiet window
tuning at f = 0.1), one adaptive run with a 3 m/s burn, one-run studies; the result objects the figures and
readouts take are built directly from small arrays where a real run would add nothing.  The calls whose valid
run is a Monte Carlo on the paper's full-period track (the tuning map, the +-j search) or needs every orbit of
the chapter (notebook 10's closing rows) are marked ``baseline=False``; their argument checks all come before any
filtering.  Figure calls close their figure.
"""

from __future__ import annotations

import functools

import numpy as np
from spec_helpers import closed as _closed
from spec_helpers import detection_setup as setup
from spec_helpers import nrho

from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.papers.greaves_scheeres_2021 import adaptive_studies as ads
from cislunar.papers.greaves_scheeres_2021 import detection as det
from cislunar.papers.greaves_scheeres_2021 import detection_studies as ds
from cislunar.papers.greaves_scheeres_2021 import figures

MODULES = [ads, ds, figures]
EXEMPT: dict = {}




# ---------------------------------------------------------------------------------------------------------------
# cached valid objects
# ---------------------------------------------------------------------------------------------------------------
@functools.lru_cache(maxsize=None)
def constant_setup():
    """The same track with the window weight held over the whole period."""
    s = setup()
    return det.make_setup(em, nrho(), s.q_window_km2_s3, s.q_window_km2_s3, cadence_hours=8.0, window_hours=16.0,
                          periods=0.8, n_sub=3)


@functools.lru_cache(maxsize=None)
def full_setup():
    """The chapter's default track (full period, 2-hour cadence) at the quiet window tuning."""
    return det.make_setup(em, nrho(), 0.1 * det.window_control_weight(det.QUIET_POLICY), 1e-18)


@functools.lru_cache(maxsize=None)
def small_joint():
    return ds.run_joint_search(em, nrho(), {"quiet": det.QUIET_POLICY}, windows_hours=(8.0,), factors=(0.3,),
                               q_bases_km2_s3=(1e-18,), noise_urad=(10.0,), burn_offsets_hours=(0.0,), n_screen=(6, 6),
                               n_paper=(6, 8), n_boot=2, seed=[0, 95], paper_zlim={"quiet": 0.022}, batch_size=4)


@functools.lru_cache(maxsize=None)
def small_lead_grid():
    return ds.run_lead_grid(em, nrho(), factors=(0.3,), noise_urad=(20.0,), magnitudes_m_s=(0.5,), n_h0=10, n_h1=1,
                            seed=[0, 61], q_base_km2_s3=1e-18, window_hours=8.0, horizon_hours=2.0)


@functools.lru_cache(maxsize=None)
def burn_inputs():
    return det.draw_trial(np.random.default_rng(0), setup(), magnitude_m_s=3.0)


@functools.lru_cache(maxsize=None)
def variants():
    return ads.variant_study(setup(), np.array([3.0]), 1, np.random.default_rng(0))


@functools.lru_cache(maxsize=None)
def fig8():
    return ads.fig8_variants(setup(), burn_inputs())


@functools.lru_cache(maxsize=None)
def big_run():
    return ads.adaptive_run(setup(), burn_inputs())


@functools.lru_cache(maxsize=None)
def trial_result():
    return det.run_trial_filter(setup(), burn_inputs())


@functools.lru_cache(maxsize=None)
def demo():
    return ds.run_tuning_demo(setup(), [0, 7])


@functools.lru_cache(maxsize=None)
def null():
    return ads.NullMetricStudy(np.linspace(0.5, 8.0, 10), 4, 0.5, 0.0, 0, np.full((1, 5), 6.0), burn_inputs())


@functools.lru_cache(maxsize=None)
def delays():
    s = setup()
    k = ads.first_seen_epoch(s)
    return ads.DelayStudy({0.05: ads.delay_outcome(s, [-1, k + 1], 0.0), 3.0: ads.delay_outcome(s, [k, k], 0.0)},
                          {10.0: ads.delay_outcome(s, [-1, k + 1], 0.0)}, 90.0, 70.0, 2)


@functools.lru_cache(maxsize=None)
def rules():
    return ads.ResetRuleStudy(((0.05, "mean", True, 0.5, True, 2, False), (0.05, "likelihood", True, 0.0, False, 1, True),
                               (3.0, "mean", True, 0.0, False, 1, True), (3.0, "likelihood", True, 0.0, False, 1, True)),
                              (0.05, 3.0), ("mean", "likelihood"))


def _sample(z, n=6, seed=0):
    r = np.random.default_rng(seed)
    return det.MonteCarloSample(np.asarray(z, float), 0.5 * np.asarray(z, float), r.uniform(0.001, 0.002, n),
                                r.uniform(-np.pi, np.pi, n), r.uniform(-1.0, 1.0, n), *(np.zeros(n),) * 4)


@functools.lru_cache(maxsize=None)
def policy_study():
    """A PolicyStudy from six H0 and six H1 control integrals (m/s), thresholded and scored."""
    z0 = np.array([1.0, 1.2, 0.9, 1.1, 1.3, 1.05]) * 1e-4
    z1 = np.array([1.5, 1.8, 1.6, 2.0, 1.7, 1.9]) * 1e-3
    th = det.ml_threshold(z0, z1)
    return det.PolicyStudy(_sample(z0), _sample(z1, seed=1), None, None, th,
                           det.detection_accuracy(z0[:2], z1[:2], th.z_lim))


def studies():
    return {(o, p): policy_study() for o in ("9:2 NRHO", "stable NRHO") for p in ("active", "quiet")}


@functools.lru_cache(maxsize=None)
def lead():
    h = det.HealthLeadStudy(np.array([0.2, 0.5]), np.array([2.0, 4.0]), np.array([[0, -1], [0, 1]]),
                            np.array([[1, -1], [0, -1]]), 0.0, 0.1, np.array([[0.1, 0.2], [0.4, 0.5]]),
                            np.full(3, 0.01), 0.00135)
    return {"f = 0.1, 10 urad": h, "f_c = 0.3, 10 urad": h}


def tuning_cells():
    """A small map: two orbits, two policies, the base setting over (0.1, 0.3) and one side setting at 0.3."""
    cells = {}
    for v, o_set, fs in (("base", ("9:2 NRHO", "stable NRHO"), (0.1, 0.3)), ("other", ("9:2 NRHO",), (0.3,))):
        for o in o_set:
            for p in ("active", "quiet"):
                for f in fs:
                    cells[o, p, f, v] = {"z_lim": f * (1.0 if p == "active" else 0.1), "err": 0.05, "h0": (0.0, 0.0),
                                         "h1": (0.2 / f, 0.02), "n": (4, 4), "slope": 1.0}
    return cells


@functools.lru_cache(maxsize=None)
def tmap():
    return ds.TuningMap(tuning_cells(), ("9:2 NRHO", "stable NRHO"), ("active", "quiet"), ("base", "other"),
                        (0.1, 0.3), (0.3,), {"active": 0.2, "quiet": 0.02})


def pm_cells():
    z = np.ones(6)
    return {(f, s, o): (z, 1.0 + 0.1 * f) for f in (0.1, 0.3) for s in (10.0, 300.0) for o in (-3.0, 0.0)}


def _closing_kwargs():
    """Arguments of notebook 10's closing rows that pass their checks (built from small arrays, not run)."""
    spike_cells = {(t, h): {"inc": (0.0, 0.0), "sig_km": 5.0, "contrast": np.ones((2, 2)), "after_burn": 0.5}
                   for t in ("constant", "apoapsis window") for h in ("H0", "H1")}
    return dict(ks_text="< 1e-300", tmap=tmap(), f_tune=0.1, q_window_quiet=(1e-12, 3e-12),
                counts=dict(n_h0=8, n_h1=8, n_test=2, outer_sizes=(8, 8, 2), n_spike=2, n_z05=2, n_lead=(10, 1),
                            n_pm_j_mc=4, pm_j_seeds=1),
                spike=ds.SpikeStudy(spike_cells, 2), train=ds.TrainingStudies({}, {}, {}, {}),
                pm_j=ds.PmJSearch(pm_cells(), (0.1, 0.3), (-3.0, 0.0), np.array([1.0, 0.0, 0.0]), 8e4),
                pm_mc={"active": _sample(np.full(6, 1e-3)), "quiet": _sample(np.full(6, 1e-4))},
                burn_z=ds.BurnZStudy({0.1: np.array([0.4, 0.5])}, 0.5), sig_level={"f = 0.1": 30.0, "f_c": 29.0},
                lead=lead(), health_nees_mean=30.0, health_residual_norms=np.array([1.0, 2.0]), sigma_angle_rad=1e-5)


def specs(Spec, lazy):
    S = Spec
    s = []
    rng = lazy(lambda: np.random.default_rng(0))
    # adaptive_studies (notebook 09b) ------------------------------------------------------------------------------
    s.append(S("first_seen_epoch", ads.first_seen_epoch, dict(setup=lazy(setup)), dict(setup="instance")))
    s.append(S("nees_limit.adaptive_studies", ads.nees_limit, {}, {}))
    s.append(S("null_metric_study", ads.null_metric_study, dict(setup=lazy(setup), n_runs=1, rng=rng),
               dict(setup="instance", n_runs="int1", rng="rng")))
    s.append(S("measurement_spread", ads.measurement_spread, dict(setup=lazy(setup), P0=lazy(lambda: burn_inputs().P0)),
               dict(setup="instance", P0="spd")))
    s.append(S("adaptive_run", ads.adaptive_run,
               dict(setup=lazy(setup), inputs=lazy(burn_inputs), reset="mean", smooth=True, max_resets=5),
               dict(setup="instance", inputs="instance", reset="choice", smooth="bool", max_resets="int0")))
    s.append(S("delay_outcome", ads.delay_outcome,
               dict(setup=lazy(setup), epochs=np.array([-1.0, 3.0, 5.0]), late_from=2.0),
               dict(setup="instance", epochs="vec", late_from="real")))
    s.append(S("DelayOutcome.fraction", lazy(lambda: delays().by_size[3.0].fraction), dict(outcome="prompt"),
               dict(outcome="choice")))
    s.append(S("first_detection_epochs", ads.first_detection_epochs,
               dict(setup=lazy(setup), magnitude_m_s=0.5, n_runs=1, rng=rng),
               dict(setup="instance", magnitude_m_s="nonneg", n_runs="int1", rng="rng")))
    s.append(S("delay_study", ads.delay_study,
               dict(setup=lazy(setup), orbit=lazy(nrho), magnitudes_m_s=np.array([3.0]), noise_urad=np.array([10.0]),
                    n_runs=1, rng=rng, executor=None),
               dict(setup="instance", orbit="instance", magnitudes_m_s="vec", noise_urad="vec", n_runs="int1",
                    rng="rng", executor="instance_opt")))
    s.append(S("reset_rule_study", ads.reset_rule_study,
               dict(setup=lazy(setup), magnitudes_m_s=np.array([3.0]), n_per_magnitude=1, rng=rng, max_resets=5,
                    executor=None),
               dict(setup="instance", magnitudes_m_s="vec", n_per_magnitude="int1", rng="rng", max_resets="int1",
                    executor="instance_opt")))
    s.append(S("reset_rule_reading", ads.reset_rule_reading, dict(rules=lazy(rules)), dict(rules="instance")))
    s.append(S("chain_report", ads.chain_report, dict(rules=lazy(rules)), dict(rules="instance")))
    s.append(S("closing_rows.adaptive_studies", ads.closing_rows,
               dict(null=lazy(null), big=lazy(big_run), delays=lazy(delays), rules=lazy(rules), q_base_km2_s3=1e-18),
               dict(null="instance", big="instance", delays="instance", rules="instance", q_base_km2_s3="pos")))
    s.append(S("variant_setup", ads.variant_setup, dict(setup=lazy(setup), measurement_set="angles only"),
               dict(setup="instance", measurement_set="choice")))
    s.append(S("variant_data", ads.variant_data,
               dict(setup=lazy(setup), inputs=lazy(burn_inputs), measurement_set="rates 1 TU"),
               dict(setup="instance", inputs="instance", measurement_set="choice")))
    s.append(S("rate_noise_floor", ads.rate_noise_floor, dict(setup=lazy(setup), inputs=lazy(burn_inputs), epoch=2),
               dict(setup="instance", inputs="instance", epoch="int0")))
    s.append(S("variant_study", ads.variant_study,
               dict(setup=lazy(setup), magnitudes_m_s=np.array([3.0]), n_per_magnitude=1, rng=rng, max_resets=5,
                    executor=None),
               dict(setup="instance", magnitudes_m_s="vec", n_per_magnitude="int1", rng="rng", max_resets="int1",
                    executor="instance_opt")))
    s.append(S("fig8_variants", ads.fig8_variants, dict(setup=lazy(setup), inputs=lazy(burn_inputs), max_resets=5),
               dict(setup="instance", inputs="instance", max_resets="int1")))
    s.append(S("fig8_report", ads.fig8_report, dict(variants=lazy(fig8)), dict(variants="iterable")))
    s.append(S("variant_rows", ads.variant_rows, dict(variants=lazy(variants), fig8=lazy(fig8)),
               dict(variants="instance", fig8="iterable")))
    # detection_studies (notebook 10) ------------------------------------------------------------------------------
    s.append(S("accuracy_standard_error", ds.accuracy_standard_error, dict(paper=0.97, n=200),
               dict(paper="range:0:1", n="int1")))
    s.append(S("improvement_in_standard_errors", ds.improvement_in_standard_errors,
               dict(error=0.1, reference=0.2, se_error=0.03, se_reference=0.04),
               dict(error="real", reference="real", se_error="nonneg", se_reference="nonneg")))
    s.append(S("finite_or", ds.finite_or, dict(value=1.3, fallback=1.0), dict(value="arr_any", fallback="real")))
    s.append(S("ratio_text", ds.ratio_text, dict(v=1.2), dict(v="arr_any")))
    s.append(S("run_tuning_map", ds.run_tuning_map,
               dict(system=em, orbits=lazy(lambda: {"9:2 NRHO": nrho()}), policies={"quiet": det.QUIET_POLICY},
                    variants={"base": {}}, f_grid=(0.1,), f_side=(0.1,), n_map=(4, 4), seed=[0, 77],
                    paper_zlim={"quiet": 0.02}, q_base_km2_s3=1e-18, window_hours=8.0, sigma_angle_rad=1e-5,
                    half_size_orbits=(), batch_size=4, executor=None),
               dict(system="system", orbits="instance", policies="instance", variants="instance", f_grid="vec",
                    f_side="vec", n_map="instance", seed="seed", paper_zlim="instance", q_base_km2_s3="pos",
                    window_hours="pos", sigma_angle_rad="pos", half_size_orbits="iterable", batch_size="int0",
                    executor="instance_opt"), baseline=False))
    s.append(S("run_tuning_demo", ds.run_tuning_demo,
               dict(setup=lazy(setup), seed=[0, 7], magnitude_m_s=0.05, direction=np.array([np.pi / 2, 0.0])),
               dict(setup="instance", seed="seed", magnitude_m_s="pos", direction="arr_opt")))
    s.append(S("TuningDemo.summary", lazy(lambda: demo().summary),
               dict(tuning="constant"), dict(tuning="choice")))
    s.append(S("run_spike_study", ds.run_spike_study,
               dict(constant=lazy(constant_setup), window=lazy(setup), n=1, seed=[0, 41]),
               dict(constant="instance", window="instance", n="int1", seed="seed")))
    s.append(S("run_training_studies", ds.run_training_studies,
               dict(setups=lazy(lambda: {("9:2 NRHO", "quiet"): setup()}),
                    setups_c=lazy(lambda: {("9:2 NRHO", "quiet"): constant_setup()}),
                    policies={"quiet": det.QUIET_POLICY}, sizes={"9:2 NRHO": (4, 4, 0)}, seed=0, n_boot=2,
                    batch_size=4, executor=None),
               dict(setups="instance", setups_c="instance", policies="instance", sizes="instance", seed="int0",
                    n_boot="int1", batch_size="int0", executor="instance_opt")))
    s.append(S("run_pm_j_search", ds.run_pm_j_search,
               dict(system=em, orbit=lazy(nrho), f_values=(0.1,), noise_urad=(10.0,), offsets_h=(0.0,), n_repeats=1,
                    seed=[0, 31], q_base_km2_s3=1e-18, window_hours=8.0),
               dict(system="system", orbit="instance", f_values="vec", noise_urad="vec", offsets_h="vec",
                    n_repeats="int1", seed="seed", q_base_km2_s3="pos", window_hours="pos"), baseline=False))
    s.append(S("run_burn_z_study", ds.run_burn_z_study,
               dict(setup=lazy(full_setup), orbit=lazy(nrho), factors={0.1}, magnitude_m_s=0.5, n=1, seed=[0, 8],
                    q_base_km2_s3=1e-18, window_hours=8.0),
               dict(setup="instance", orbit="instance", factors="vec", magnitude_m_s="pos", n="int1", seed="seed",
                    q_base_km2_s3="pos", window_hours="pos")))
    s.append(S("lead_report", ds.lead_report, dict(lead=lazy(lead), n_h0=10), dict(lead="instance", n_h0="int1")))
    s.append(S("lead_reading", ds.lead_reading, dict(lead=lazy(lead)), dict(lead="instance")))
    ck = {k: lazy(functools.partial(lambda k: _closing_kwargs()[k], k)) for k in _closing_kwargs()}
    s.append(S("closing_rows.detection_studies", ds.closing_rows, ck,
               dict(ks_text="instance_str", tmap="instance", f_tune="pos", q_window_quiet="arr", counts="instance",
                    spike="instance", train="instance", pm_j="instance", pm_mc="instance", burn_z="instance",
                    sig_level="instance", lead="instance", health_nees_mean="real", health_residual_norms="vec",
                    sigma_angle_rad="pos"), baseline=False))
    # figures ----------------------------------------------------------------------------------------------------
    s.append(S("metric_law.figures", _closed(figures.metric_law), dict(null=lazy(null)), dict(null="instance")))
    for name in ("adaptive_errors", "adaptive_control_metric"):
        s.append(S(name, _closed(getattr(figures, name)), dict(setup=lazy(setup), run=lazy(big_run), title="3 m/s"),
                   dict(setup="instance", run="instance", title="instance_str")))
    s.append(S("accuracy_exact_text", ds.accuracy_exact_text, dict(accuracy=0.98, paper=1.0, n=200),
               dict(accuracy="real", paper="real", n="int1")))
    s.append(S("run_joint_search", ds.run_joint_search,
               dict(system=em, orbit=lazy(nrho), policies={"quiet": det.QUIET_POLICY}, windows_hours=(8.0,),
                    factors=(0.3,), q_bases_km2_s3=(1e-18,), noise_urad=(10.0,), burn_offsets_hours=(0.0,),
                    n_screen=(6, 6), n_paper=(6, 8), n_boot=2, seed=[0, 95], paper_zlim={"quiet": 0.022},
                    batch_size=4, executor=None),
               dict(system="system", orbit="instance", policies="instance", windows_hours="vec", factors="vec",
                    q_bases_km2_s3="vec", noise_urad="vec", burn_offsets_hours="vec", n_screen="instance",
                    n_paper="instance", n_boot="int2", seed="seed", paper_zlim="instance", batch_size="int1",
                    executor="instance_opt"), baseline=False))
    s.append(S("run_lead_grid", ds.run_lead_grid,
               dict(system=em, orbit=lazy(nrho), factors=(0.3,), noise_urad=(20.0,), magnitudes_m_s=(0.5,), n_h0=10,
                    n_h1=1, seed=[0, 61], q_base_km2_s3=1e-18, window_hours=8.0, judged_m_s=0.5, horizon_hours=2.0),
               dict(system="system", orbit="instance", factors="vec", noise_urad="vec", magnitudes_m_s="vec",
                    n_h0="int1", n_h1="int1", seed="seed", q_base_km2_s3="pos", window_hours="pos", judged_m_s="pos",
                    horizon_hours="pos"), baseline=False))
    s.append(S("joint_search", _closed(figures.joint_search), dict(joint=lazy(small_joint)),
               dict(joint="instance")))
    s.append(S("lead_grid", _closed(figures.lead_grid), dict(grid=lazy(small_lead_grid)), dict(grid="instance")))
    s.append(S("variant_figure", _closed(figures.variant_figure), dict(study=lazy(variants)), dict(study="instance")))
    s.append(S("delays", _closed(figures.delays), dict(study=lazy(delays)), dict(study="instance")))
    s.append(S("reset_rules", _closed(figures.reset_rules), dict(study=lazy(rules)), dict(study="instance")))
    pols = {"active": det.ACTIVE_POLICY, "quiet": det.QUIET_POLICY}
    s.append(S("station_keeping_policy", _closed(figures.station_keeping_policy),
               dict(magnitudes=lazy(lambda: {n: p.sample_magnitude(np.random.default_rng(0), 200)
                                             for n, p in pols.items()}),
                    policies=pols, uz=np.linspace(-0.9, 0.9, 50)),
               dict(magnitudes="instance", policies="instance", uz="vec")))
    for name in ("control_integral_pdfs", "z_vs_maneuver"):
        s.append(S(name, _closed(getattr(figures, name)),
                   dict(studies=lazy(studies), orbit_names=["9:2 NRHO", "stable NRHO"],
                        policy_names=["active", "quiet"]),
                   dict(studies="instance", orbit_names="names", policy_names="names")))
    s.append(S("control_integral_pdfs_one_orbit", _closed(figures.control_integral_pdfs),
               dict(studies=lazy(studies), orbit_names=["9:2 NRHO"], policy_names=["quiet"]),
               dict(orbit_names="names")))
    s.append(S("pm_j_search.figures", _closed(figures.pm_j_search),
               dict(pmj=pm_cells(), f_values=(0.1, 0.3), noise_urad=(10.0, 300.0), offsets_h=(-3.0, 0.0), f_pm=0.3,
                    sig_pm=300.0, active_sample=lazy(lambda: _sample(np.full(6, 1e-3)))),
               dict(pmj="instance", f_values="vec", noise_urad="vec", offsets_h="vec", f_pm="pos", sig_pm="pos",
                    active_sample="instance")))
    s.append(S("health_lead", _closed(figures.health_lead), dict(lead=lazy(lead)), dict(lead="instance")))
    s.append(S("health_lead_one_setting", _closed(figures.health_lead),
               dict(lead=lazy(lambda: dict(list(lead().items())[:1]))), dict(lead="instance")))
    s.append(S("health_metric", _closed(figures.health_metric),
               dict(setup=lazy(setup), inputs=lazy(burn_inputs), result=lazy(trial_result),
                    reference=lazy(policy_study), z_m_s=2.5),
               dict(setup="instance", inputs="instance", result="instance", reference="instance", z_m_s="pos")))
    s.append(S("tuning_map", _closed(figures.tuning_map),
               dict(tmap=tuning_cells(), orbit_names=["9:2 NRHO", "stable NRHO"], policy_names=["active", "quiet"],
                    variants=["base", "other"], base_variant="base", f_grid=(0.1, 0.3), f_side=(0.3,), f_c=0.3,
                    f_tune=0.1, paper_zlim={"active": 0.2, "quiet": 0.02}, worst=lazy(lambda: tmap().worst)),
               dict(tmap="instance", orbit_names="names", policy_names="names", variants="names",
                    base_variant="choice", f_grid="vec", f_side="vec", f_c="pos", f_tune="pos",
                    paper_zlim="instance", worst="callable")))
    return s
