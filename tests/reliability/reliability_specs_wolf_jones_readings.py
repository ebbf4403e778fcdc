"""Malformed-argument specs for the Wolf & Jones process-noise readings study (plugin of
tests/reliability/test_reliability.py; issue 22, item 3).

Covers :mod:`cislunar.papers.wolf_jones.readings_study` and its figure, now
:func:`cislunar.papers.wolf_jones.figures.figure_readings` (found by its label; the figures module is swept by
reliability_specs_wolf_jones_studies.py).  Valid baselines: test case 2's ballistic window start and
the same pushed 2 m/s out of the plane (no solve) for :func:`evaluate_readings` and the figure; the two sweep
adaptors run on the smallest sweeps that exist (6 Sundman nodes, alpha_h = 0 only).
"""

from __future__ import annotations

import functools

import numpy as np
from spec_helpers import closed as _closed

from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.cr3bp.propagation import propagate
from cislunar.guidance import scvx
from cislunar.papers.wolf_jones import figures
from cislunar.papers.wolf_jones import readings_study as rs
from cislunar.papers.wolf_jones import scenarios as wj
from cislunar.papers.wolf_jones import test_case_studies as tcs

MODULES = [rs]
EXEMPT: dict = {}


@functools.lru_cache(maxsize=None)
def sc2():
    return wj.test_case_2()


@functools.lru_cache(maxsize=None)
def starts():
    """Two window-start states of test case 2: ballistic, and 2 m/s out of the plane."""
    sc = sc2()
    x = propagate(sc.system, sc.observer_x0, [0.0, sc.window[0]]).x[-1]
    return np.array([x, x + np.array([0, 0, 0, 0, 0, 2e-3])])


@functools.lru_cache(maxsize=None)
def study():
    return rs.evaluate_readings(sc2(), [0.0, 1e-2], starts(), dv_mps=[1.0, 2.0], mi_planned=[1.0, 2.0])


@functools.lru_cache(maxsize=None)
def case1():
    return tcs.sweep_test_case_1(wj.test_case_1(), 6, [0.0], forward_hessian=True)


@functools.lru_cache(maxsize=None)
def case2():
    sc = sc2()
    t, k_ws, k_we = sc.node_times(6)
    x_ball, u_ball = sc.ballistic_guess(t)
    solver = wj.ScenarioSolver(sc, t, k_ws, information=sc.information_model(), keep_out=True,
                               settings=scvx.SCvxSettings(max_iter=60))
    return tcs.case2_rows(sc, solver, k_ws, k_we, wj.sweep_both_ways(solver, [0.0], x_ball, u_ball))


def specs(Spec, lazy):
    S = Spec
    return [
        S("evaluate_readings", rs.evaluate_readings,
          dict(scenario=lazy(sc2), alphas=[0.0, 1e-2], x_window_starts=lazy(starts), dv_mps=[1.0, 2.0],
               mi_planned=[1.0, 2.0], readings=dict(wj.PROCESS_NOISE_READINGS_KM2_S3)),
          dict(scenario="instance", alphas="vec", x_window_starts="arr", dv_mps="arr_opt", mi_planned="arr_opt",
               readings="instance_opt")),
        S("case2_readings", rs.case2_readings, dict(case=lazy(case2)), dict(case="instance")),
        S("case1_readings", rs.case1_readings, dict(case=lazy(case1)), dict(case="instance")),
        S("figure_readings", _closed(figures.figure_readings),
          dict(study=lazy(study), system=em, show_alphas=[0.0, 1e-2]),
          dict(study="instance", system="system", show_alphas="vec_opt")),
    ]
