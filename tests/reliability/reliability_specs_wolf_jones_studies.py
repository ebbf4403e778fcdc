"""Malformed-argument specs for the Wolf & Jones studies, exercises and figures (plugin of
tests/reliability/test_reliability.py, issue 18).

Covers every module of :mod:`cislunar.papers.wolf_jones` that no other plugin covers: the chapter studies
(``mutual_information_study``, ``scvx_study``, ``nodes_study``, ``test_case_studies``), the closing-table readouts
of test case 2 (``case_2_closing``), the worked exercises (``exercises``) and the test-case figures (``figures``).
``scenarios`` is swept by reliability_specs_wolf_jones.py and ``reference`` by reliability_specs_estimation.py.

Valid baselines run on small sizes: test case 1 planned on 6 Sundman nodes at alpha_h = 0, test case 2 on 6 nodes
at alpha_h = 0 (built once per worker), a 3-measurement window for the mutual-information chapter, one arc and one
exponent for the node chapter.  The few calls whose valid run is a full two-way SCvx sweep are marked
``baseline=False``; their argument checks all come before any solve.  Figure calls close their figure.
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np
from spec_helpers import closed as _closed

from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.guidance import scvx
from cislunar.papers.wolf_jones import (
    _checks,
    case_2_closing,
    exercises,
    figures,
    nodes_study,
    reference_tables,
    scvx_study,
)
from cislunar.papers.wolf_jones import mutual_information_study as mis
from cislunar.papers.wolf_jones import scenarios as wj
from cislunar.papers.wolf_jones import test_case_studies as tcs

# _checks: the private argument checks these modules share (no public API; exercised through every spec here)
MODULES = [reference_tables, mis, scvx_study, nodes_study, tcs, case_2_closing, exercises, figures, _checks]
EXEMPT: dict = {}




# ---------------------------------------------------------------------------------------------------------------
# cached valid objects
# ---------------------------------------------------------------------------------------------------------------
@functools.lru_cache(maxsize=None)
def window():
    """Test case 2's window on its first three daily measurement times."""
    full_t = mis.case_2_window(em).t
    return mis.case_2_window(em, full_t[:3])


@functools.lru_cache(maxsize=None)
def window_gradient():
    return mis.gradient_check(window())


@functools.lru_cache(maxsize=None)
def window_crlb():
    return mis.window_crlb(window())


@functools.lru_cache(maxsize=None)
def baseline_curves():
    return mis.baseline_study(window(), 2)


@functools.lru_cache(maxsize=None)
def timing():
    return mis.timing_study(window(), (2, 3), min_time=1e-4, repeat=1)


@functools.lru_cache(maxsize=None)
def arcs():
    return {nodes_study.DRO_ARC: nodes_study.reference_arcs(em)[nodes_study.DRO_ARC]}


@functools.lru_cache(maxsize=None)
def node_sweep():
    return nodes_study.node_sweep(em, arcs(), (0.0, 1.0), 5)


@functools.lru_cache(maxsize=None)
def lin_sweep():
    return nodes_study.linearisation_sweep(em, node_sweep(), 1, np.random.default_rng(0), [], 1e-3)


@functools.lru_cache(maxsize=None)
def problem():
    return scvx_study.transfer_problem(6)


@functools.lru_cache(maxsize=None)
def transfer():
    return scvx_study.solve(problem())


@functools.lru_cache(maxsize=None)
def shooting():
    return scvx_study.single_shooting(problem(), transfer().u)


@functools.lru_cache(maxsize=None)
def sc1():
    return wj.test_case_1()


@functools.lru_cache(maxsize=None)
def sc2():
    return wj.test_case_2()


@functools.lru_cache(maxsize=None)
def case1():
    """Test case 1 planned on 6 nodes at alpha_h = 0."""
    return tcs.sweep_test_case_1(sc1(), 6, [0.0], forward_hessian=True)


@functools.lru_cache(maxsize=None)
def crlb1():
    return tcs.crlb_study(case1())


@functools.lru_cache(maxsize=None)
def penalty():
    return tcs.penalty_study(case1(), [1e3], 1, 1)


@functools.lru_cache(maxsize=None)
def grid2():
    """``(t, k_ws, k_we, x_ball, u_ball)`` of test case 2 on 6 nodes."""
    t, k_ws, k_we = sc2().node_times(6)
    x_ball, u_ball = sc2().ballistic_guess(t)
    return t, k_ws, k_we, x_ball, u_ball


@functools.lru_cache(maxsize=None)
def info2():
    return sc2().information_model()


@functools.lru_cache(maxsize=None)
def solver2():
    t, k_ws = grid2()[:2]
    return wj.ScenarioSolver(sc2(), t, k_ws, information=info2(), keep_out=True,
                             settings=scvx.SCvxSettings(max_iter=60))


@functools.lru_cache(maxsize=None)
def sweep2():
    t, k_ws, k_we, x_ball, u_ball = grid2()
    return wj.sweep_both_ways(solver2(), [0.0], x_ball, u_ball)


@functools.lru_cache(maxsize=None)
def case2():
    t, k_ws, k_we = grid2()[:3]
    return tcs.case2_rows(sc2(), solver2(), k_ws, k_we, sweep2())


@functools.lru_cache(maxsize=None)
def row6():
    return case2().ok[0]


def res2():
    return row6().res


def x_ws2():
    return grid2()[3][grid2()[1]]


@functools.lru_cache(maxsize=None)
def free2():
    t, k_ws, k_we, x_ball, u_ball = grid2()
    return tcs.free_run(sc2(), t, k_ws, info2(), 1e-2, x_ball, u_ball, 1)


@functools.lru_cache(maxsize=None)
def radius_rows():
    return [tcs.radius_row(sc2(), grid2()[1], sc2().keep_out_km, "sweep", res2(), res2().x)]


@functools.lru_cache(maxsize=None)
def keep_out_study():
    return tcs.keep_out_study(case2(), row6(), free2(), {}, {})


@functools.lru_cache(maxsize=None)
def front2():
    return tcs.front(case2().ok)


@functools.lru_cache(maxsize=None)
def scan2():
    return tcs.keep_out_scan(sc2(), info2(), x_ws2(), 2, d_range_km=(1e-3, 100.0))


@functools.lru_cache(maxsize=None)
def readings():
    t = np.array([0.0, 0.5, 1.0])
    return tcs.NoiseReadings([("adopted", 1e-17, 2.0, 3.0, 4.0, 5.0), ("small", 1e-20, 1.0, 3.0, 4.0, 2.5)],
                             [(t, np.array([3.0, 2.0, 1.0])), (t, np.array([3.0, 2.0, 1.0]))])


@functools.lru_cache(maxsize=None)
def case2_graded():
    """``case2`` with its alpha_h = 0 plan repeated at alpha_h = 1e-3: the closing table reads plans above zero."""
    c, r = case2(), row6()
    return dataclasses.replace(c, alphas=(0.0, 1e-3), rows=[r, dataclasses.replace(r, alpha=1e-3)])


@functools.lru_cache(maxsize=None)
def gradient2():
    return tcs.GradientCheck(1.0, 1.0, np.ones(6), np.ones(6), 1e-9, np.eye(6), 0.1, 0.1)


@functools.lru_cache(maxsize=None)
def mirror2():
    r = res2()
    return tcs.MirrorStudy(None, (0.0, 0.0), 0.0, r, r, 0.0, 0.0, {}, [])


@functools.lru_cache(maxsize=None)
def departures2():
    return case_2_closing.Departures([1000.0], 0.9, {6: 0.9}, [])


def budget_rows():
    return [tcs.BudgetRow(2.5, 1e-3, 2.5, 1.5, 1.6, 10.0, 1.8, 3)]


def specs(Spec, lazy):
    s = []
    S = Spec
    lz = lazy
    marks = []

    def mark(module):
        marks.append((len(s), module))
    # ------------------------------------------------------------------------------ reference_tables
    mark("reference_tables")
    s.append(S("row_label", reference_tables.row_label, dict(table=2, label="observer_t0"),
               dict(table="int1", label="instance_str")))
    s.append(S("dro_table_study", reference_tables.dro_table_study,
               dict(system=em, n_members=2, zoom_margin_km=1500.0, n_zoom=2),
               dict(system="system", n_members="int2", zoom_margin_km="pos", n_zoom="int2")))
    s.append(S("mu_trials", reference_tables.mu_trials, dict(system=em, step=1e-9), dict(system="system", step="pos")))
    s.append(S("mu_closure_study", reference_tables.mu_closure_study, dict(system=em, mus=np.array([em.mu])),
               dict(system="system", mus="vec_opt")))
    s.append(S("window_study", reference_tables.window_study, dict(system=em, period_tu=5.0, tolerance_days=1.0),
               dict(system="system", period_tu="pos", tolerance_days="pos")))
    # ------------------------------------------------------------------------------ mutual_information_study
    mark("mutual_information_study")
    s.append(S("scalar_worked_example", mis.scalar_worked_example,
               dict(n_samples=10, rng=lz(lambda: np.random.default_rng(0)), p=4.0, h=1.0, r=1.0),
               dict(n_samples="int2", rng="rng", p="pos", h="real", r="pos")))
    s.append(S("constant_velocity_toy", mis.constant_velocity_toy, dict(dt=1.0, n_times=3, psd=0.01, r=0.25),
               dict(dt="pos", n_times="int2", psd="nonneg", r="pos")))
    s.append(S("reference_period", mis.reference_period, dict(system=em), dict(system="system")))
    s.append(S("case_2_window", mis.case_2_window,
               dict(system=em, t=lz(lambda: window().t), range_sigma_km=0.1, range_rate_sigma_km_s=1e-5),
               dict(system="system", t="grid_opt", range_sigma_km="pos", range_rate_sigma_km_s="pos")))
    s.append(S("window_crlb", mis.window_crlb, dict(window=lz(window)), dict(window="instance")))
    s.append(S("observer_information", mis.observer_information, dict(window=lz(window), x=lz(lambda: window().start[0])),
               dict(window="instance", x="state")))
    s.append(S("gradient_check", mis.gradient_check, dict(window=lz(window), step=1e-6),
               dict(window="instance", step="pos")))
    s.append(S("linearisation_check", mis.linearisation_check,
               dict(window=lz(window), gradient=lz(window_gradient), steps_km=np.array([1.0, 10.0])),
               dict(window="instance", gradient="instance", steps_km="vec")))
    s.append(S("baseline_study", mis.baseline_study,
               dict(window=lz(window), n_baselines=2, min_phase=0.002, max_phase=0.5, executor=None),
               dict(window="instance", n_baselines="int2", min_phase="range:0:1", max_phase="range:0:1",
                    executor="instance_opt")))
    s.append(S("crossover", mis.crossover, dict(sizes=[2, 4, 8], ratios=np.array([0.5, 0.9, 1.5])),
               dict(sizes="vec", ratios="vec")))
    s.append(S("timing_study", mis.timing_study, dict(window=lz(window), sizes=(2,), min_time=1e-4, repeat=1),
               dict(window="instance", sizes="iterable", min_time="pos", repeat="int1")))
    s.append(S("figure_angular_noise", _closed(mis.figure_angular_noise), dict(mean_range_km=215.0),
               dict(mean_range_km="pos")))
    s.append(S("figure_crlb", _closed(mis.figure_crlb), dict(crlb=lz(window_crlb)), dict(crlb="instance")))
    s.append(S("figure_baseline", _closed(mis.figure_baseline), dict(curves=lz(baseline_curves)),
               dict(curves="iterable")))
    s.append(S("figure_timing", _closed(mis.figure_timing), dict(timing=lz(timing)), dict(timing="instance")))
    # ------------------------------------------------------------------------------ nodes_study
    mark("nodes_study")
    x_dro = lz(lambda: arcs()[nodes_study.DRO_ARC][0])
    t_dro = lz(lambda: node_sweep().nodes[nodes_study.DRO_ARC, 0.0])
    s.append(S("reference_arcs", nodes_study.reference_arcs, dict(system=em), dict(system="system")))
    s.append(S("node_sweep", nodes_study.node_sweep, dict(system=em, arcs=lz(arcs), sigmas=(0.0, 1.0), n_nodes=5),
               dict(system="system", arcs="instance", sigmas="iterable", n_nodes="int2")))
    s.append(S("linearisation_error", nodes_study.linearisation_error,
               dict(system=em, x0=x_dro, t_nodes=t_dro, draws=1, rng=lz(lambda: np.random.default_rng(0)),
                    a_max=1e-3),
               dict(system="system", x0="state", t_nodes="grid", draws="int1", rng="rng", a_max="nonneg")))
    s.append(S("linearisation_sweep", nodes_study.linearisation_sweep,
               dict(system=em, sweep=lz(node_sweep), draws=1, rng=lz(lambda: np.random.default_rng(0)),
                    extra_seeds=[], a_max=1e-3, executor=None),
               dict(system="system", sweep="instance", draws="int1", rng="rng", extra_seeds="iterable",
                    a_max="nonneg", executor="instance_opt")))
    s.append(S("eq40_residual", nodes_study.eq40_residual, dict(t_nodes=np.array([0.0, 0.5, 1.2, 2.0]), a_max=1e-3),
               dict(t_nodes="grid", a_max="pos")))
    s.append(S("moon_distance_km", nodes_study.moon_distance_km, dict(system=em, x0=x_dro, tf=0.5, n=10),
               dict(system="system", x0="state", tf="pos", n="int2")))
    s.append(S("figure_node_spacing", _closed(nodes_study.figure_node_spacing), dict(system=em, sweep=lz(node_sweep)),
               dict(system="system", sweep="instance")))
    s.append(S("figure_nodes_on_orbits", _closed(nodes_study.figure_nodes_on_orbits),
               dict(system=em, sweep=lz(node_sweep)), dict(system="system", sweep="instance")))
    s.append(S("figure_linearisation_error", _closed(nodes_study.figure_linearisation_error),
               dict(sweep=lz(node_sweep), lin=lz(lin_sweep)), dict(sweep="instance", lin="instance")))
    s.append(S("figure_node_bounds", _closed(nodes_study.figure_node_bounds),
               dict(system=em, sweep=lz(node_sweep), arc=nodes_study.DRO_ARC, a_max=1e-3),
               dict(system="system", sweep="instance", arc="choice", a_max="pos")))
    # ------------------------------------------------------------------------------ scvx_study
    mark("scvx_study")
    s.append(S("transfer_problem", scvx_study.transfer_problem, dict(n_nodes=6, sigma=1.0, a_max_km_s2=None),
               dict(n_nodes="int1", sigma="nonneg", a_max_km_s2="pos_opt")))
    s.append(S("solve", scvx_study.solve, dict(problem=lz(problem), settings=None, x_guess=None, u_guess=None),
               dict(problem="instance", settings="instance_opt", x_guess="arr_opt", u_guess="arr_opt")))
    s.append(S("iteration_summary", scvx_study.iteration_summary,
               dict(result=lz(transfer), settings=scvx.SCvxSettings()), dict(result="instance", settings="instance")))
    s.append(S("single_shooting", scvx_study.single_shooting, dict(problem=lz(problem), u=lz(lambda: transfer().u)),
               dict(problem="instance", u="arr")))
    s.append(S("blended_guess", scvx_study.blended_guess, dict(problem=lz(problem)), dict(problem="instance")))
    s.append(S("guess_study", scvx_study.guess_study,
               dict(problem=lz(problem), n_guesses=1, rng=lz(lambda: np.random.default_rng(0)),
                    reference_impulse=lz(lambda: transfer().impulse), control_scale=0.05, max_iter=200,
                    executor=None),
               dict(problem="instance", n_guesses="int1", rng="rng", reference_impulse="pos", control_scale="nonneg",
                    max_iter="int1", executor="instance_opt")))
    s.append(S("figure_iterations", _closed(scvx_study.figure_iterations),
               dict(result=lz(transfer), settings=scvx.SCvxSettings(), velocity_unit_km_s=em.velocity_unit_km_s),
               dict(result="instance", settings="instance", velocity_unit_km_s="pos")))
    s.append(S("figure_converged_control", _closed(scvx_study.figure_converged_control),
               dict(problem=lz(problem), u=lz(lambda: transfer().u), shooting=lz(shooting)),
               dict(problem="instance", u="arr", shooting="instance")))
    # ------------------------------------------------------------------------------ test_case_studies: case 1
    mark("test_case_studies")
    s.append(S("case1_scenario_summary", tcs.case1_scenario_summary, dict(sc=lz(sc1)), dict(sc="instance")))
    s.append(S("table2_slip", tcs.table2_slip, dict(sc=lz(sc1), sc2=lz(sc2), n_nodes=6, sigma=1.0),
               dict(sc="instance", sc2="instance", n_nodes="int1", sigma="real")))
    s.append(S("sweep_test_case_1", tcs.sweep_test_case_1,
               dict(sc=lz(sc1), n_nodes=6, alphas=[0.0], sigma=1.0, forward_hessian=True, progress=False),
               dict(sc="instance", n_nodes="int1", alphas="vec", sigma="real", forward_hessian="bool",
                    progress="bool")))
    s.append(S("penalty_study", tcs.penalty_study,
               dict(case=lz(case1), gammas=[1e3], n_iter=1, n_iter_long=1, alpha=0.0, executor=None),
               dict(case="instance", gammas="vec", n_iter="int1", n_iter_long="int1", alpha="range:0:1",
                    executor="instance_opt")))
    s.append(S("reflight", tcs.reflight, dict(case=lz(case1)), dict(case="instance")))
    s.append(S("mesh_check", tcs.mesh_check, dict(case=lz(case1), n_alt=6, alpha=0.0, sigma=1.0),
               dict(case="instance", n_alt="int1", alpha="real", sigma="real")))
    s.append(S("dense_flight", tcs.dense_flight, dict(case=lz(case1), res=lz(lambda: case1().best[0]), n=20),
               dict(case="instance", res="instance", n="int2")))
    s.append(S("departures_km", tcs.departures_km, dict(case=lz(case1), n=20), dict(case="instance", n="int2")))
    s.append(S("crlb_study", tcs.crlb_study, dict(case=lz(case1)), dict(case="instance")))
    s.append(S("budget_study", tcs.budget_study,
               dict(case=lz(case1), term_obs=lz(lambda: crlb1().term_obs), extras_mps=[1e4], rtol=0.02),
               dict(case="instance", term_obs="vec", extras_mps="vec", rtol="range:0:1")))
    # ------------------------------------------------------------------------------ test_case_studies: case 2
    mark("test_case_studies")
    g = grid2
    s.append(S("gradient_check", tcs.gradient_check, dict(info=lz(info2), x=lz(x_ws2), system=em, h=2e-7),
               dict(info="callable", x="state", system="system", h="pos")))
    s.append(S("keep_out_scan", tcs.keep_out_scan,
               dict(sc=lz(sc2), info=lz(info2), x_ws=lz(x_ws2), n_points=2, d_range_km=(1e-3, 100.0)),
               dict(sc="instance", info="callable", x_ws="state", n_points="int2", d_range_km="arr")))
    s.append(S("plan_row", tcs.plan_row,
               dict(sc=lz(sc2), solver=lz(solver2), k_ws=lz(lambda: g()[1]), k_we=lz(lambda: g()[2]), alpha=0.0,
                    res=lz(res2), source="up"),
               dict(sc="instance", solver="instance", k_ws="int0", k_we="int0", alpha="real", res="instance",
                    source="instance_str")))
    s.append(S("case2_rows", tcs.case2_rows,
               dict(sc=lz(sc2), solver=lz(solver2), k_ws=lz(lambda: g()[1]), k_we=lz(lambda: g()[2]),
                    sweep=lz(sweep2), seconds=1.0),
               dict(sc="instance", solver="instance", k_ws="int0", k_we="int0", sweep="instance")))
    s.append(S("departure_km", tcs.departure_km, dict(sc=lz(sc2), t=lz(lambda: g()[0]), res=lz(res2)),
               dict(sc="instance", t="grid", res="instance")))
    s.append(S("grid_departures", tcs.grid_departures,
               dict(sc=lz(sc2), t=lz(lambda: g()[0]), k_ws=lz(lambda: g()[1]), sweep=lz(sweep2), weight=0.0),
               dict(sc="instance", t="grid", k_ws="int0", sweep="instance", weight="real")))
    s.append(S("mirror_pair", tcs.mirror_pair, dict(a=lz(res2), b=lz(res2), k_we=lz(lambda: g()[2]), system=em),
               dict(a="instance", b="instance", k_we="int0", system="system")))
    s.append(S("mirrored", tcs.mirrored, dict(res=lz(res2)), dict(res="instance")))
    s.append(S("relative_rms_km", tcs.relative_rms_km, dict(sc=lz(sc2), x_window_start=lz(x_ws2)),
               dict(sc="instance", x_window_start="state")))
    s.append(S("noise_readings", tcs.noise_readings,
               dict(sc2=lz(sc2), x2_ball_ws=lz(x_ws2), x2_plan_ws=lz(x_ws2), sc1=lz(sc1)),
               dict(sc2="instance", x2_ball_ws="state", x2_plan_ws="state", sc1="instance")))
    s.append(S("front", tcs.front, dict(ok=lz(lambda: case2().ok)), dict(ok="iterable")))
    s.append(S("free_run", tcs.free_run,
               dict(sc=lz(sc2), t=lz(lambda: g()[0]), k_ws=lz(lambda: g()[1]), info=lz(info2), alpha=1e-2,
                    x_guess=lz(lambda: g()[3]), u_guess=lz(lambda: g()[4]), max_iter=1),
               dict(sc="instance", t="grid", k_ws="int0", info="callable", alpha="range:0:1", x_guess="arr",
                    u_guess="arr", max_iter="int1")))
    s.append(S("radius_row", tcs.radius_row,
               dict(sc=lz(sc2), k_ws=lz(lambda: g()[1]), d=424.0, src="sweep", res=lz(res2),
                    reference_x=lz(lambda: res2().x)),
               dict(sc="instance", k_ws="int0", d="pos", src="instance_str", res="instance", reference_x="arr")))
    s.append(S("alt_grid_sweep", tcs.alt_grid_sweep,
               dict(sc=lz(sc2), info=lz(info2), n_nodes=6, alphas=[0.0], settings=scvx.SCvxSettings(max_iter=60),
                    sigma=1.0, executor=None, directions=("up",)),
               dict(sc="instance", info="callable", n_nodes="int1", alphas="vec", settings="instance", sigma="real",
                    executor="instance_opt", directions="directions"), baseline=False))
    s.append(S("mirror_study", tcs.mirror_study,
               dict(case=lz(case2), pair_rows=lz(lambda: (row6(), row6())), mirror_row=lz(row6), seeded={}),
               dict(case="instance", pair_rows="iterable", mirror_row="instance", seeded="instance")))
    s.append(S("case2_budget", tcs.case2_budget, dict(case=lz(case2), extra_mps=2.0, rtol=0.02),
               dict(case="instance", extra_mps="real", rtol="range:0:1")))
    s.append(S("radius_summary", tcs.radius_summary,
               dict(radius_rows=lz(radius_rows), row6=lz(row6), d_min_km=[424.0, 1500.0], keep_out_km=424.0,
                    alpha=0.0, same_plan_km=50.0),
               dict(radius_rows="iterable", row6="instance", d_min_km="vec", keep_out_km="pos", alpha="real",
                    same_plan_km="pos")))
    s.append(S("dominated_note", tcs.dominated_note,
               dict(case=lz(case2), dominated=[], row6=lz(row6), radius_rows=lz(radius_rows), amax_rows=[]),
               dict(case="instance", dominated="iterable", row6="instance", radius_rows="iterable",
                    amax_rows="iterable")))
    s.append(S("keep_out_study", tcs.keep_out_study,
               dict(case=lz(case2), row6=lz(row6), free=lz(free2), radius_results={}, amax_results={},
                    radius_start="cold"),
               dict(case="instance", row6="instance", free="instance", radius_results="instance",
                    amax_results="instance", radius_start="choice")))
    s.append(S("case2_runs", tcs.case2_runs,
               dict(sc=lz(sc2), solver=lz(solver2), alphas=[0.0], x_guess=lz(lambda: g()[3]),
                    u_guess=lz(lambda: g()[4]), seed_alphas=(), alt_nodes=(), sigma=1.0, executor=None,
                    alt_directions=("up", "down")),
               dict(sc="instance", solver="instance", alphas="vec", x_guess="arr", u_guess="arr",
                    seed_alphas="iterable", alt_nodes="iterable", sigma="real", executor="instance_opt",
                    alt_directions="directions"),
               baseline=False))
    s.append(S("queue_keep_out_runs", tcs.queue_keep_out_runs,
               dict(case=lz(case2), row6=lz(row6), d_min_km=[1500.0], warm=True, x_guess=None, u_guess=None,
                    executor=None),
               dict(case="instance", row6="instance", d_min_km="vec", warm="bool", x_guess="arr_opt",
                    u_guess="arr_opt", executor="instance_opt")))
    # ------------------------------------------------------------------------------ case_2_closing
    mark("case_2_closing")
    s.append(S("measurements", case_2_closing.measurements,
               dict(case=lz(case2_graded), row6=lz(row6), n_nodes=6, sigma=1.0, gc=lz(gradient2), ms=lz(mirror2),
                    ko=lz(keep_out_study), nr=lz(readings), fr=lz(front2), departures=lz(departures2), obs_mean={},
                    tgt_mean={}, common={}, budget_row=None, extra_mps=2.0, rtol=0.02, diagnosed=None),
               dict(case="instance", row6="instance", n_nodes="int1", sigma="real", gc="instance", ms="instance",
                    ko="instance", nr="instance", fr="instance", departures="instance", obs_mean="instance",
                    tgt_mean="instance", common="instance", budget_row="instance_opt", extra_mps="real",
                    rtol="range:0:1", diagnosed="instance_opt")))
    # ------------------------------------------------------------------------------ exercises
    mark("exercises")
    s.append(S("exercise_01_mu_step", exercises.exercise_01_mu_step,
               dict(steps=(1e-8,), reference_step=1e-9, system=em),
               dict(steps="vec", reference_step="pos", system="system")))
    s.append(S("exercise_02_monte_carlo_samples", exercises.exercise_02_monte_carlo_samples,
               dict(n_samples=100, factor=2, seed=0), dict(n_samples="int1", factor="int2", seed="int0")))
    s.append(S("exercise_02_range_noise", exercises.exercise_02_range_noise, dict(factor=0.5, n_days=2),
               dict(factor="range:0:1", n_days="int1_opt")))
    s.append(S("exercise_03_node_count", exercises.exercise_03_node_count, dict(n_nodes=(6, 7), sigma=1.0),
               dict(n_nodes="iterable", sigma="nonneg")))
    s.append(S("exercise_03_thrust_bound", exercises.exercise_03_thrust_bound, dict(scale=0.5, n_nodes=6),
               dict(scale="range:0:1", n_nodes="int1")))
    s.append(S("exercise_04_control_size", exercises.exercise_04_control_size,
               dict(factor=2.0, n_nodes=6, draws=1, seed=0),
               dict(factor="pos", n_nodes="int1", draws="int1", seed="int0")))
    s.append(S("exercise_04_node_count", exercises.exercise_04_node_count, dict(n_nodes=6, draws=1, seed=0),
               dict(n_nodes="int1", draws="int1", seed="int0")))
    s.append(S("exercise_05_node_count", exercises.exercise_05_node_count, dict(n_nodes=(6, 7), sigma=1.0),
               dict(n_nodes="iterable", sigma="real")))
    s.append(S("exercise_05_penalty_iterations", exercises.exercise_05_penalty_iterations,
               dict(max_iter=(1, 2), n_nodes=6, alpha=5e-3, gamma=1e3),
               dict(max_iter="iterable", n_nodes="int1", alpha="range:0:1", gamma="pos")))
    s.append(S("exercise_06_close_pass_scan", exercises.exercise_06_close_pass_scan,
               dict(d_range_km=(1e-6, 1e-2), n_points=3), dict(d_range_km="arr", n_points="int1")))
    s.append(S("exercise_06_free_run_iterations", exercises.exercise_06_free_run_iterations,
               dict(max_iter=(1, 2), n_nodes=6, alpha=1e-2),
               dict(max_iter="iterable", n_nodes="int1", alpha="range:0:1")))
    # ------------------------------------------------------------------------------ figures (test cases 1, 2)
    mark("figures")
    F = figures
    s.append(S("convergence", _closed(F.convergence), dict(penalty=lz(penalty)), dict(penalty="instance")))
    s.append(S("trajectories", _closed(F.trajectories), dict(case=lz(case1), show=[0]),
               dict(case="instance", show="iterable")))
    s.append(S("relative_motion", _closed(F.relative_motion),
               dict(alphas=[0.0, 1e-3], rel_km=[np.zeros((4, 3)), np.ones((4, 3))]),
               dict(alphas="vec", rel_km="iterable")))
    s.append(S("thrust", _closed(F.thrust), dict(case=lz(case1), show=[0]), dict(case="instance", show="iterable")))
    s.append(S("crlb_axes", _closed(F.crlb_axes), dict(system=em, alphas=[0.0], crlb=lz(lambda: crlb1().crlb)),
               dict(system="system", alphas="vec", crlb="iterable")))
    s.append(S("pareto", _closed(F.pareto),
               dict(alphas=[0.0, 1e-3], impulse_mps=[1.0, 2.0], term_obs=[3.0, 2.0], term_tgt=[4.0, 3.0]),
               dict(alphas="vec", impulse_mps="vec", term_obs="vec", term_tgt="vec")))
    s.append(S("equal_impulse", _closed(F.equal_impulse),
               dict(impulse_mps=np.array([1.0, 2.0, 3.0]), term_obs=np.array([3.0, 2.0, 1.0]),
                    budget_rows=lz(budget_rows)),
               dict(impulse_mps="vec", term_obs="vec", budget_rows="iterable")))
    s.append(S("keep_out_motivation", _closed(F.keep_out_motivation), dict(scan=lz(scan2), keep_out_km=424.0),
               dict(scan="instance", keep_out_km="pos")))
    s.append(S("absolute_trajectory", _closed(F.absolute_trajectory),
               dict(sc=lz(sc2), t=lz(lambda: g()[0]), res=lz(res2), alpha=0.0),
               dict(sc="instance", t="grid", res="instance", alpha="real")))
    s.append(S("relative_three_planes", _closed(F.relative_three_planes),
               dict(case=lz(case2), departure_km=[1000.0], show=[0.0]),
               dict(case="instance", departure_km="vec", show="iterable")))
    s.append(S("z_mirror", _closed(F.z_mirror),
               dict(sc=lz(sc2), t=lz(lambda: g()[0]), curves=lz(lambda: {(0.0, "sweep optimum"): res2()}),
                    window_days=(17.0, 32.0)),
               dict(sc="instance", t="grid", curves="instance", window_days="arr")))
    s.append(S("thrust_profiles", _closed(F.thrust_profiles),
               dict(sc=lz(sc2), t=lz(lambda: g()[0]), plans=lz(lambda: [(0.0, res2()), (0.0, res2())]),
                    window_days=(17.0, 32.0)),
               dict(sc="instance", t="grid", plans="iterable", window_days="arr")))
    s.append(S("crlb_objects", _closed(F.crlb_objects), dict(system=em, crlbs=lz(lambda: {0.0: row6().crlb})),
               dict(system="system", crlbs="instance")))
    s.append(S("noise_readings", _closed(F.noise_readings), dict(system=em, readings=lz(readings)),
               dict(system="system", readings="instance")))
    s.append(S("pareto_fronts", _closed(F.pareto_fronts), dict(fr=lz(front2)), dict(fr="instance")))
    s.append(S("keep_out_sweep", _closed(F.keep_out_sweep),
               dict(radius_rows=lz(radius_rows), neighbours=lz(lambda: [row6()]), keep_out_km=424.0, alpha=0.0),
               dict(radius_rows="iterable", neighbours="iterable", keep_out_km="pos", alpha="real")))
    # labels name the function and its module (``name.module``): names repeat across modules and papers
    for (start, module), (end, _) in zip(marks, marks[1:] + [(len(s), None)]):
        for spec in s[start:end]:
            spec.label = f"{spec.label}.{module}"
    return s
