"""Malformed-argument specs for :mod:`cislunar.papers.greaves_scheeres_2021.custody` and for
:func:`cislunar.estimation.srif.filter_many` (plugin of tests/reliability/test_reliability.py; issue 23, item 5).

Valid baselines are small: one custody run of one period at a 12-h cadence, the linear problem over half a period
at 12 h, two cadences for the cost study, a 3-state filter for ``filter_many``.
"""

from __future__ import annotations

import functools

import numpy as np

from cislunar.cr3bp import orbits
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.estimation import srif
from cislunar.papers.greaves_scheeres_2021 import custody as cu
from cislunar.papers.greaves_scheeres_2021 import detection as det
from cislunar.papers.greaves_scheeres_2021 import figures

MODULES = [cu]
EXEMPT: dict = {}

_SPD3 = np.array([[2.0, 0.3, 0.0], [0.3, 1.5, 0.1], [0.0, 0.1, 1.0]])


@functools.lru_cache(maxsize=None)
def nrho():
    return orbits.nrho_9_2(em)


@functools.lru_cache(maxsize=None)
def problem():
    return cu.linear_problem(em, nrho(), cadence_hours=12.0, periods=0.5)


@functools.lru_cache(maxsize=None)
def sets():
    return problem().simulate(np.random.default_rng(0), 2)


@functools.lru_cache(maxsize=None)
def study():
    return cu.custody_study(em, nrho(), periods=1, cadence_hours=12.0, n_runs=1)


@functools.lru_cache(maxsize=None)
def case():
    return cu.conditioning_case(problem(), 2, np.random.default_rng(0))


@functools.lru_cache(maxsize=None)
def cost():
    return cu.cadence_cost_study(em, nrho(), [6.0, 12.0], 1e-20, repeats=1)


def specs(S, lazy):
    def lz(f):
        return lazy(lambda: f())

    s = []
    s.append(S("pointing_error", cu.pointing_error,
               dict(observers=np.zeros(6), x_est=np.r_[1.0, 0.1, 0.0, 0.0, 0.0, 0.0],
                    truth=np.r_[1.0, 0.0, 0.0, 0.0, 0.0, 0.0]),
               dict(observers="state", x_est="state", truth="state")))
    s.append(S("custody_study", cu.custody_study,
               dict(system=em, orbit=lz(nrho), orbit_name="9:2 NRHO", periods=1, cadence_hours=12.0,
                    policy=det.QUIET_POLICY, q_window_km2_s3=None, q_base_km2_s3=1e-18, window_hours=8.0, n_runs=1,
                    seed=0, sigma_angle_rad=1e-5, half_angle_rad=0.01, executor=None, progress=False),
               dict(system="system", orbit="instance", orbit_name="instance_str", periods="int1", cadence_hours="pos",
                    policy="instance", q_window_km2_s3="pos_opt", q_base_km2_s3="pos", window_hours="pos",
                    n_runs="int1", seed="int0", sigma_angle_rad="pos", half_angle_rad="pos",
                    executor="instance_opt", progress="bool")))
    s.append(S("linear_problem", cu.linear_problem,
               dict(system=em, orbit=lz(nrho), cadence_hours=12.0, periods=0.5, gap_hours=0.0, sigma_angle_rad=1e-5,
                    prior_scale=1.0, q_km2_s3=1e-20),
               dict(system="system", orbit="instance", cadence_hours="pos", periods="pos", gap_hours="nonneg",
                    sigma_angle_rad="pos", prior_scale="pos", q_km2_s3="pos")))
    s.append(S("covariance_filter", cu.covariance_filter,
               dict(problem=lz(problem), ys=lz(lambda: sets()[1]), x0=lz(lambda: sets()[2]), form="joseph"),
               dict(problem="instance", ys="arr", x0="arr", form="choice")))
    s.append(S("sri_filter", cu.sri_filter,
               dict(problem=lz(problem), ys=lz(lambda: sets()[1]), x0=lz(lambda: sets()[2])),
               dict(problem="instance", ys="arr", x0="arr")))
    s.append(S("conditioning_case", cu.conditioning_case,
               dict(problem=lz(problem), n_draws=2, rng=lz(lambda: np.random.default_rng(0)), label="case"),
               dict(problem="instance", n_draws="int2", rng="rng", label="instance_str")))
    s.append(S("cadence_cost_study", cu.cadence_cost_study,
               dict(system=em, orbit=lz(nrho), cadences=[6.0, 12.0], control_weight_km2_s3=1e-20, seed=0, repeats=1,
                    sigma_angle_rad=1e-5, max_repeat_seconds=2.0),
               dict(system="system", orbit="instance", cadences="vec", control_weight_km2_s3="pos", seed="int0",
                    repeats="int1", sigma_angle_rad="pos", max_repeat_seconds="pos")))
    s.append(S("figure_custody", figures.figure_custody, dict(studies=lz(lambda: [study()])), dict(studies="iterable")))
    s.append(S("figure_conditioning", figures.figure_conditioning, dict(case=lz(case)), dict(case="instance")))
    s.append(S("figure_cadence_cost", figures.figure_cadence_cost, dict(cost=lz(cost)), dict(cost="instance")))
    s.append(S("filter_many", srif.filter_many,
               dict(x0s=np.zeros((2, 3)), P0=_SPD3, Phis=np.array([np.eye(3)]), Hs=[np.eye(3), np.eye(3)],
                    ys=np.ones((2, 2, 3)), meas_covs=[np.eye(3), np.eye(3)], Gammas=[np.eye(3)], Qs=[_SPD3]),
               dict(x0s="arr", P0="spd", Phis="arr", ys="arr")))
    return s
