"""Malformed-argument specs (issue 11) for the mission modules: torus, ssat, station_keeping.

Loaded by ``tests/test_reliability.py`` (see its ``_load_plugins``).  One valid, cheap call per public function,
method and input dataclass, with the kind of every argument (kinds of ``test_reliability.bad_values``).  The valid
objects that cost a propagation (the 9:2 NRHO, one small converged torus, an agent/target pair, a small
station-keeping surface and a filter scenario) are built once, lazily, and shared.

Result containers that are also inputs (``SSATCovariance`` to ``minimize_range_sigma``, ``StationKeepingSurface`` to
``filter_scenario``) validate their fields and are swept; the pure outputs (``RangeStats``, ``PolicyComparison``,
``FilterTrialResult``, which holds NaN by design for epochs a diverged filter never reached) have no
argument-taking method and are not; the exception classes are covered by the pickling test of
``test_reliability.py``.
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np

from cislunar.cr3bp import orbits
from cislunar.cr3bp import torus as tm
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.cr3bp.propagation import propagate
from cislunar.guidance import ssat
from cislunar.papers.greaves_scheeres_2023 import station_keeping as sk

MODULES = [tm, ssat, sk]

HR = 3600.0 / em.time_unit_s


# ---------------------------------------------------------------------------------------------------------------
# valid objects (built once, on first use)
# ---------------------------------------------------------------------------------------------------------------
@functools.lru_cache(maxsize=None)
def _orbit():
    return orbits.nrho_9_2(em)


@functools.lru_cache(maxsize=None)
def _torus():
    """A 10-km torus about the 9:2 NRHO with N = 5 (converges in three Gauss-Newton steps, ~0.1 s)."""
    return tm.torus_from_orbit(_orbit(), 5, 10.0)


@functools.lru_cache(maxsize=None)
def _pair():
    """Target at the NRHO apolune, agent 0.6 h behind it on the same orbit (about 230 km apart)."""
    xt0 = _orbit().x0.copy()
    xa0 = propagate(em, xt0, np.array([0.0, -0.6 * HR])).x[-1]
    return xa0, xt0


T3 = np.array([0.0, 1.0, 2.0]) * HR
T4 = np.array([0.0, 1.0, 2.0, 3.0]) * HR


@functools.lru_cache(maxsize=None)
def _agent():
    return ssat.propagate_with_impulses(em, _pair()[0], T3)


@functools.lru_cache(maxsize=None)
def _target():
    return ssat.propagate_with_impulses(em, _pair()[1], T3)


@functools.lru_cache(maxsize=None)
def _surface():
    return sk.station_keeping_surface(em, _torus(), np.array([0.0, 2.0]), np.array([-1.0]) * HR, -3.0 * HR, 0.0,
                                      progress=False)


@functools.lru_cache(maxsize=None)
def _target_at_track_start():
    return propagate(em, _orbit().x0, np.array([0.0, _surface().t[0]])).x[-1]


@functools.lru_cache(maxsize=None)
def _scenario():
    return sk.filter_scenario(_surface(), 0, 1, _target_at_track_start(), em)


@functools.lru_cache(maxsize=None)
def _cov():
    return ssat.ssat_covariance(em, _agent(), _target(), ssat.initial_covariance(em))


_SSAT_COV_FIELDS = [f.name for f in dataclasses.fields(ssat.SSATCovariance)]
_SURFACE_FIELDS = [f.name for f in dataclasses.fields(sk.StationKeepingSurface)]


def _rng():
    return np.random.default_rng(0)


P12 = ssat.initial_covariance(em)
SPD3 = np.diag([1.0, 2.0, 3.0])


def specs(S, lazy):
    s = []
    orbit, torus = lazy(_orbit), lazy(_torus)
    xa0, xt0 = lazy(lambda: _pair()[0]), lazy(lambda: _pair()[1])
    rng = lazy(_rng)

    # ---------------------------------------------------------------------------------------------- torus
    s.append(S("InvariantTorus", tm.InvariantTorus,
               dict(orbit=orbit, circle=lazy(lambda: _torus().circle), period=lazy(lambda: _torus().period),
                    rho=lazy(lambda: _torus().rho), residuals=(1e-5, 1e-12), phase_component=lazy(
                        lambda: _torus().phase_component), label="t"),
               dict(orbit="instance", circle="arr", period="pos", rho="real", residuals="instance",
                    phase_component="int0", label="instance_str")))
    s.append(S("InvariantTorus.circle_at", lazy(lambda: _torus().circle_at), dict(theta=np.array([0.1, 2.0])),
               dict(theta="arr_finite")))
    s.append(S("InvariantTorus.states", lazy(lambda: _torus().states),
               dict(theta0=np.array([0.0, 1.0]), t=np.array([0.0, 0.1]), tol=1e-13),
               dict(theta0="arr_finite", t="arr_finite", tol="range:1e-16:1e-3")))
    s.append(S("InvariantTorus.ring", lazy(lambda: _torus().ring), dict(t=0.1, n_theta=4),
               dict(t="real", n_theta="int1_opt")))
    s.append(S("InvariantTorus.invariance_error", lazy(lambda: _torus().invariance_error),
               dict(theta=np.array([0.3]), tol=1e-13), dict(theta="arr_finite_opt", tol="range:1e-16:1e-3")))
    s.append(S("InvariantTorus.distance_to_ring", lazy(lambda: _torus().distance_to_ring),
               dict(x=lazy(lambda: _torus().circle[1]), t=0.0, n_search=36),
               dict(x="state", t="real", n_search="int2")))
    s.append(S("InvariantTorus.stability_multipliers", lazy(lambda: _torus().stability_multipliers),
               dict(tol=1e-13), dict(tol="range:1e-16:1e-3")))
    s.append(S("InvariantTorus.closest_approach", lazy(lambda: _torus().closest_approach),
               dict(body="Moon", n_theta=4, n_t=11, tol=1e-13),
               dict(body="choice", n_theta="int2", n_t="int2", tol="range:1e-16:1e-3")))
    s.append(S("fourier_weights", tm.fourier_weights, dict(theta=np.array([0.1, 0.2]), n=5, derivative=False),
               dict(theta="arr_finite", n="int2", derivative="bool")))
    s.append(S("centre_eigenpair", tm.centre_eigenpair, dict(orbit=orbit, unit_tol=1e-6, trivial_tol=1e-3),
               dict(orbit="instance", unit_tol="pos", trivial_tol="pos")))
    s.append(S("torus_seed", tm.torus_seed, dict(orbit=orbit, N=5, size_km=1.0),
               dict(orbit="instance", N="int2", size_km="pos")))
    s.append(S("solve_torus", tm.solve_torus,
               dict(guess=torus, fix=lazy(lambda: {"size_km": _torus().size_km}), free_period=False, tol=1e-10,
                    max_iter=3, int_tol=1e-14, label="x", check_midpoints=False),
               dict(guess="instance", fix="instance", free_period="bool", tol="range:1e-15:1e-3", max_iter="int1",
                    int_tol="range:1e-16:1e-3", label="instance_str", check_midpoints="bool")))
    s.append(S("torus_from_orbit", tm.torus_from_orbit,
               dict(orbit=orbit, N=5, size_km=4.0, start_km=2.0, step_km=5.0, progress=False),
               dict(orbit="instance", N="int2", size_km="pos", start_km="pos", step_km="pos", progress="bool")))
    s.append(S("continue_tori", tm.continue_tori,
               dict(torus=torus, values=np.array([11.0]), parameter="size_km", progress=False, max_halvings=2,
                    free_period=False, hold=None),
               dict(torus="instance", values="vec", parameter="choice", progress="bool", max_halvings="int0",
                    free_period="bool", hold="instance_opt")))
    s.append(S("mean_range", tm.mean_range, dict(torus=torus, n_theta=4, n_t=11, periods=1, tol=1e-13),
               dict(torus="instance", n_theta="int2", n_t="int2", periods="int1", tol="range:1e-16:1e-3")))
    s.append(S("qpo_for_mean_range", tm.qpo_for_mean_range,
               dict(orbit=orbit, target_km=30.0, N=5, statistic="ring_mean_km", rtol=1e-3, n_theta=4, n_t=11,
                    progress=False, max_iter=6),
               dict(orbit="instance", target_km="pos", N="int2", statistic="choice", rtol="range:1e-12:0.1",
                    n_theta="int2", n_t="int2", progress="bool", max_iter="int1"), baseline=False))

    # ---------------------------------------------------------------------------------------------- ssat
    x12 = lazy(lambda: np.r_[_pair()[0], _pair()[1]])
    for name in ("transform_matrix", "agent_transform_matrix"):
        s.append(S(name, getattr(ssat, name), dict(n=6), dict(n="int1")))
    for name, arg in (("to_relative", "x"), ("from_relative", "x_rel"), ("to_agent_based", "x"),
                      ("from_agent_based", "x_agent")):
        s.append(S(name, getattr(ssat, name), {arg: x12}, {arg: "arr_finite"}))
    for name, arg in (("relative_covariance", "P"), ("inertial_covariance", "P_rel"),
                      ("agent_based_covariance", "P")):
        s.append(S(name, getattr(ssat, name), {arg: P12}, {arg: "psd"}))
    s.append(S("control_matrix", ssat.control_matrix, dict(coordinates="relative"), dict(coordinates="choice")))
    s.append(S("apply_impulse", ssat.apply_impulse, dict(x=x12, u=np.array([1e-4, 0.0, 0.0])),
               dict(x="arr", u="arr")))
    s.append(S("range_projection", ssat.range_projection, dict(x=x12, coordinates="inertial"),
               dict(x="arr", coordinates="choice")))
    s.append(S("range_variance", ssat.range_variance, dict(P=P12, x=x12, coordinates="relative"),
               dict(P="psd", x="arr", coordinates="choice")))
    s.append(S("initial_covariance", ssat.initial_covariance,
               dict(system=em, sigma3_pos_km=60.0, sigma3_vel_km_s=6e-4),
               dict(system="system", sigma3_pos_km="pos", sigma3_vel_km_s="pos")))
    s.append(S("ImpulsiveTrajectory", ssat.ImpulsiveTrajectory,
               dict(t=T3, x=lazy(lambda: _agent().x), stm=lazy(lambda: _agent().stm)),
               dict(t="grid", x="arr", stm="arr")))
    s.append(S("propagate_with_impulses", ssat.propagate_with_impulses,
               dict(system=em, x0=xa0, t=T3, impulses=[(0.5 * HR, np.array([1e-4, 0.0, 0.0]))], threads=1),
               dict(system="system", x0="state", t="grid", impulses="instance", threads="int1_opt")))
    cov_kw = dict(system=em, agent=lazy(_agent), target=lazy(_target), P0=P12, sigma_min_rad=1e-5,
                  resolution_km=4e-3)
    cov_kinds = dict(system="system", agent="instance", target="instance", P0="spd", sigma_min_rad="nonneg",
                     resolution_km="nonneg")
    s.append(S("ssat_covariance", ssat.ssat_covariance, cov_kw, cov_kinds))
    s.append(S("ssat_covariance_ekf", ssat.ssat_covariance_ekf, dict(cov_kw, coordinates="agent"),
               dict(cov_kinds, coordinates="choice")))
    s.append(S("SSATCovariance", ssat.SSATCovariance,
               {k: lazy(functools.partial(lambda k: getattr(_cov(), k), k)) for k in _SSAT_COV_FIELDS},
               dict(t="grid", J_rho="arr", P_final="arr", range_km="arr", sigma_theta_rad="arr",
                    length_unit_km="pos")))
    s.append(S("mmd_matrix", ssat.mmd_matrix, dict(agent_stm=lazy(lambda: _agent().stm[0, -1]),
                                                   H_agent=np.arange(12.0).reshape(2, 6)),
               dict(agent_stm="arr", H_agent="arr")))
    s.append(S("mmd_direction", ssat.mmd_direction, dict(Q=SPD3), dict(Q="psd")))
    guid_kw = dict(system=em, agent_x0=xa0, target_x0=xt0, t=T3, dv_magnitude=1e-4, P0=P12)
    guid_kinds = dict(system="system", agent_x0="state", target_x0="state", t="grid", dv_magnitude="pos",
                      P0="spd")
    s.append(S("mmd_policy", ssat.mmd_policy, dict(guid_kw, burn_index=0, sigma_min_rad=1e-5, resolution_km=4e-3),
               dict(guid_kinds, burn_index="int0", sigma_min_rad="nonneg", resolution_km="nonneg")))
    s.append(S("fibonacci_sphere", ssat.fibonacci_sphere, dict(n=8), dict(n="int2")))
    s.append(S("perpendicular_directions", ssat.perpendicular_directions,
               dict(line_of_sight=np.array([1.0, 2.0, 0.5]), n=4), dict(line_of_sight="arr", n="int1")))
    s.append(S("range_sigma_over_directions", ssat.range_sigma_over_directions,
               dict(guid_kw, directions=np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]), burn_index=1, target=None,
                    threads=1, sigma_min_rad=1e-5, resolution_km=4e-3),
               dict(guid_kinds, dv_magnitude="nonneg", directions="arr", burn_index="int0", target="instance_opt",
                    threads="int1_opt", sigma_min_rad="nonneg", resolution_km="nonneg")))
    s.append(S("minimize_range_sigma", ssat.minimize_range_sigma,
               dict(guid_kw, n_grid=12, refine=False, burn_index=0, target=None, grid_result=None),
               dict(guid_kinds, n_grid="int2", refine="bool", burn_index="int0", target="instance_opt",
                    grid_result="instance_opt")))
    s.append(S("compare_burn_policies", ssat.compare_burn_policies,
               dict(guid_kw, t=T4, coast_indices=np.array([2, 3]), n_grid=12, n_perp=4, refine=False, burn_index=1,
                    sigma_min_rad=1e-5, resolution_km=4e-3),
               dict(guid_kinds, coast_indices="vec", n_grid="int2", n_perp="int1", refine="bool", burn_index="int0",
                    sigma_min_rad="nonneg", resolution_km="nonneg")))

    # ---------------------------------------------------------------------------------------------- station keeping
    goal = lazy(lambda: _torus().states([1.0], [0.0])[0, 0])
    s.append(S("position_transfer", sk.position_transfer,
               dict(system=em, x0=lazy(lambda: _torus().states([0.0], [-3.0 * HR])[0, 0]), t0=-3.0 * HR, t1=0.0,
                    r_target=lazy(lambda: _torus().states([1.0], [0.0])[0, 0, :3]), tol=1e-12, max_iter=10),
               dict(system="system", x0="state", t0="real", t1="real", r_target="arr", tol="pos", max_iter="int1")))
    s.append(S("two_burn_transfer", sk.two_burn_transfer,
               dict(system=em, x0=lazy(lambda: _torus().states([0.0], [-3.0 * HR])[0, 0]), t0=-3.0 * HR, t1=0.0,
                    x_target=goal, tol=1e-12, max_iter=10),
               dict(system="system", x0="state", t0="real", t1="real", x_target="arr", tol="pos", max_iter="int1")))
    s.append(S("target_trajectory", sk.target_trajectory,
               dict(system=em, apolune_state=lazy(lambda: _orbit().x0), t=np.array([-1.0, 0.0, 1.0]) * HR),
               dict(system="system", apolune_state="state", t="grid")))
    s.append(S("station_keeping_surface", sk.station_keeping_surface,
               dict(system=em, torus=torus, theta=np.array([0.0, 2.0]), t_arrival=np.array([-1.0]) * HR,
                    t_burn=-3.0 * HR, t_final=0.0, cadence=HR, t_track_start=-4.0 * HR, agent_theta=0.0,
                    agent_offset=np.zeros(6), P0=P12, sigma_min_rad=1e-5, resolution_km=4e-3, mmd_horizon="final",
                    batched=True, progress=False),
               dict(system="system", torus="instance", theta="vec", t_arrival="vec", t_burn="real", t_final="real",
                    cadence="pos_opt", t_track_start="real_opt", agent_theta="real", agent_offset="arr_opt",
                    P0="spd_opt", sigma_min_rad="nonneg", resolution_km="nonneg", mmd_horizon="choice",
                    batched="bool", progress="bool")))
    s.append(S("StationKeepingSurface", sk.StationKeepingSurface,
               {k: lazy(functools.partial(lambda k: getattr(_surface(), k), k)) for k in _SURFACE_FIELDS},
               dict({k: "arr" for k in _SURFACE_FIELDS}, t_burn="real", t="grid", agent_x0="state",
                    velocity_unit_km_s="pos", time_unit_s="pos")))
    s.append(S("informed_choice", sk.informed_choice,
               dict(dv1=np.array([[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]]), u_y=np.array([[1.0, 0.2, 0.0]]),
                    cost=np.array([[1.0, 2.0]]), criterion="projection"),
               dict(dv1="arr", u_y="arr", cost="arr", criterion="choice")))
    s.append(S("first_burn_only_range_sigma_km", sk.first_burn_only_range_sigma_km,
               dict(system=em, surface=lazy(_surface), target_apolune_state=lazy(lambda: _orbit().x0),
                    informed=lazy(lambda: _surface().informed), P0=P12, sigma_min_rad=1e-5, resolution_km=4e-3),
               dict(system="system", surface="instance", target_apolune_state="state", informed="arr_opt",
                    P0="spd_opt", sigma_min_rad="nonneg", resolution_km="nonneg")))
    s.append(S("execution_sigma", sk.execution_sigma, dict(dv=np.array([3.0, 4.0, 0.0]), sigma_abs=0.1,
                                                            sigma_rel=0.01),
               dict(dv="arr", sigma_abs="nonneg", sigma_rel="nonneg")))
    s.append(S("filter_scenario", sk.filter_scenario,
               dict(surface=lazy(_surface), j=0, i=1, target_x0=lazy(_target_at_track_start), system=em,
                    exec_sigma_abs_m_s=1e-3, exec_sigma_rel=0.01, P0=P12, label="x"),
               dict(surface="instance", j="int0", i="int0", target_x0="state", system="system",
                    exec_sigma_abs_m_s="nonneg", exec_sigma_rel="nonneg", P0="spd_opt", label="instance_str")))
    s.append(S("FilterScenario", sk.FilterScenario,
               dict(system=em, t=lazy(lambda: _scenario().t), agent_x0=lazy(lambda: _scenario().agent_x0),
                    target_x0=lazy(lambda: _scenario().target_x0), burns=lazy(lambda: _scenario().burns), P0=P12,
                    exec_sigma_abs=1e-6, exec_sigma_rel=0.01, sigma_min_rad=1e-5, resolution_km=4e-3, label="x"),
               dict(system="system", t="grid", agent_x0="state", target_x0="state", burns="instance", P0="spd",
                    exec_sigma_abs="nonneg", exec_sigma_rel="nonneg", sigma_min_rad="nonneg",
                    resolution_km="nonneg", label="instance_str")))
    s.append(S("station_keeping.filter_trial", sk.filter_trial, dict(rng=rng, scenario=lazy(_scenario), n_iter=3),
               dict(rng="rng", scenario="instance", n_iter="int1")))
    s.append(S("random_choice_trial", sk.random_choice_trial,
               dict(rng=rng, scenarios=lazy(lambda: [_scenario()])), dict(rng="rng", scenarios="iterable")))
    return s
