"""Malformed-argument specs for :mod:`cislunar.papers.wolf_jones.global_search` (plugin of
tests/reliability/test_reliability.py; issue 22, item 1).

Valid baselines run on test case 1 planned on 6 Sundman nodes at alpha_h = 0: a multi-start of two starts (the
ballistic guess and one random perturbation), a mesh study on one other grid (warm start only) and its plan moved
back (and adopted: with_starts, with_moved_back), and the envelope of a few points.  The same valid calls are the
Dask cases of tests/utils/test_every_executor_on_dask.py.
"""

from __future__ import annotations

import functools

import numpy as np

from cislunar.guidance import scvx
from cislunar.papers.wolf_jones import global_search as gs
from cislunar.papers.wolf_jones import scenarios as wj

MODULES = [gs]
EXEMPT: dict = {}


@functools.lru_cache(maxsize=None)
def sc1():
    return wj.test_case_1()


@functools.lru_cache(maxsize=None)
def solver1():
    t, k, _ = sc1().node_times(6)
    return wj.ScenarioSolver(sc1(), t, k, settings=scvx.SCvxSettings())


@functools.lru_cache(maxsize=None)
def ms1():
    return gs.multi_start(solver1(), [0.0], rng=np.random.default_rng(0), n_random=1, seeds_z=False,
                          neighbours=False)


@functools.lru_cache(maxsize=None)
def mesh1():
    return gs.mesh_study(solver1(), {0.0: ms1().best[0]}, [7], cold=False)


def back1():  # a back_to_grid result holding the multi-start's own plan (as if moved back from the 7-node grid)
    return {0.0: (7, "warm", ms1().best[0], 0.0)}


def sweep1():
    return scvx.SweepResult(np.array([0.0]), [ms1().best[0]], ["up"], [])


def specs(S, lazy):
    def lz(f):
        return lazy(lambda: f())

    s = []
    s.append(S("multi_start", gs.multi_start,
               dict(solver=lz(solver1), alphas=[0.0], rng=lz(lambda: np.random.default_rng(0)), n_random=1,
                    random_scale=0.05, seeds_z=False, z_fraction=0.05, ballistic=True, neighbours=False, known=None,
                    cost_tol=1e-6, plan_km=100.0, executor=None),
               dict(solver="instance", alphas="vec", rng="rng", n_random="int0", random_scale="range:0:1",
                    seeds_z="bool", z_fraction="range:0:1", ballistic="bool", neighbours="bool", known="instance_opt",
                    cost_tol="pos", plan_km="pos", executor="instance_opt")))
    s.append(S("known_from_sweep", gs.known_from_sweep, dict(sweep=lz(sweep1), alphas=None),
               dict(sweep="instance", alphas="vec_opt")))
    s.append(S("adopt", gs.adopt, dict(sweep=lz(sweep1), ms=lz(ms1)), dict(sweep="instance", ms="instance")))
    s.append(S("lower_envelope", gs.lower_envelope,
               dict(x=np.array([1.0, 2.0, 3.0]), y=np.array([3.0, 1.0, 2.0]), sense="min"),
               dict(x="vec", y="arr", sense="choice")))
    s.append(S("front_points", gs.front_points,
               dict(ms=lz(ms1), scenario=lz(sc1), k_window=lz(lambda: solver1().k_window), others=None),
               dict(ms="instance", scenario="instance", k_window="int1", others="instance_opt")))
    s.append(S("mesh_study", gs.mesh_study,
               dict(solver=lz(solver1), plans=lz(lambda: {0.0: ms1().best[0]}), n_nodes=[7], sigma=1.0, rtol=0.05,
                    cold=False, executor=None),
               dict(solver="instance", plans="instance", n_nodes="iterable", sigma="real", rtol="range:0:1",
                    cold="bool", executor="instance_opt")))
    s.append(S("back_to_grid", gs.back_to_grid, dict(solver=lz(solver1), study=lz(mesh1), executor=None),
               dict(solver="instance", study="instance", executor="instance_opt")))
    s.append(S("with_starts", gs.with_starts,
               dict(solver=lz(solver1), ms=lz(ms1), extra=lz(lambda: {0.0: [("mesh 7", ms1().best[0])]})),
               dict(solver="instance", ms="instance", extra="instance")))
    s.append(S("with_moved_back", gs.with_moved_back, dict(solver=lz(solver1), study=lz(mesh1), back=lz(back1)),
               dict(solver="instance", study="instance", back="instance")))
    s.append(S("mesh_starts", gs.mesh_starts,
               dict(solver=lz(solver1), sweep=lz(sweep1), ms=lz(ms1), alphas=[0.0], n_nodes=[7], sigma=1.0,
                    rtol=0.05, cold=False, executor=None),
               dict(solver="instance", sweep="instance", ms="instance", alphas="vec", n_nodes="iterable",
                    sigma="real", rtol="range:0:1", cold="bool", executor="instance_opt")))
    return s
