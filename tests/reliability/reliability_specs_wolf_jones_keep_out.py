"""Malformed-argument specs for :mod:`cislunar.papers.wolf_jones.keep_out_diagnosis`, the printed-method study of
:mod:`cislunar.papers.wolf_jones.scvx_study` and :func:`cislunar.sensing.information.range_noise_scale` (plugin of
tests/reliability/test_reliability.py; issue 22, item 4), with the diagnosis figure, now
:func:`cislunar.papers.wolf_jones.figures.figure_keep_out_diagnosis` (found by its label; the figures module is swept
by reliability_specs_wolf_jones_studies.py).

Valid baselines: test case 2 on 6 Sundman nodes with one SCvx iteration (the runs end unconverged, which the
functions report rather than raise), passes at 100 km, and test case 1's printed-method study on 6 nodes with two
iterations of the reference run only.
"""

from __future__ import annotations

import functools

import numpy as np
from spec_helpers import closed

from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.cr3bp.propagation import propagate
from cislunar.papers.wolf_jones import figures, scvx_study
from cislunar.papers.wolf_jones import keep_out_diagnosis as kd
from cislunar.papers.wolf_jones import scenarios as wj
from cislunar.sensing import information

MODULES = [kd]
EXEMPT: dict = {}


@functools.lru_cache(maxsize=None)
def sc2():
    return wj.test_case_2()


@functools.lru_cache(maxsize=None)
def info2():
    return sc2().information_model()


@functools.lru_cache(maxsize=None)
def grid2():
    t, k_ws, _ = sc2().node_times(6)
    x, u = sc2().ballistic_guess(t)
    return t, k_ws, x, u


@functools.lru_cache(maxsize=None)
def x_ws2():
    return propagate(em, sc2().observer_x0, [0.0, sc2().window[0]]).x[-1]


@functools.lru_cache(maxsize=None)
def lin2():
    return info2().linearization(x_ws2())


@functools.lru_cache(maxsize=None)
def scan2():
    return kd.pass_scan(sc2(), info2(), x_ws2(), [100.0])


@functools.lru_cache(maxsize=None)
def diag2():
    t, k_ws, x, u = grid2()
    return kd.free_run_diagnosis(sc2(), t, k_ws, info2(), 1e-2, x, u, 1, n_hessian=0)


@functools.lru_cache(maxsize=None)
def remedy2():
    t, k_ws, x, u = grid2()
    return kd.remedy_runs(sc2(), t, k_ws, info2(), 141.0, [1e-2], x, u, max_iter=1, keep_out=False)


@functools.lru_cache(maxsize=None)
def printed1():
    return scvx_study.printed_method_study(6, alpha=5e-3, max_iter=2, labels=[])


def specs(S, lazy):
    def lz(f):
        return lazy(lambda: f())

    s = []
    s.append(S("range_noise_scale", information.range_noise_scale,
               dict(lin=lz(lin2), range_scale=0.01, derivatives=True),
               dict(lin="instance", range_scale="pos", derivatives="bool")))
    s.append(S("regularised_range_rate_jacobian", information.regularised_range_rate_jacobian,
               dict(lin=lz(lin2), range_scale=0.01, derivatives=False),
               dict(lin="instance", range_scale="pos", derivatives="bool")))
    s.append(S("printed_method_study", scvx_study.printed_method_study,
               dict(n_nodes=6, alpha=5e-3, max_iter=2, sigma=1.0, labels=[], executor=None),
               dict(n_nodes="int1", alpha="range:0:1", max_iter="int1", sigma="nonneg")))
    s.append(S("figure_printed_method", closed(scvx_study.figure_printed_method), dict(study=lz(printed1)),
               dict(study="instance")))
    s.append(S("passing_state", kd.passing_state,
               dict(system=em, t_pass=lazy(lambda: np.array([lin2().t[0], lin2().t[3]])),
                    r_target=lazy(lambda: lin2().targets[0, 3, :3]), d_km=100.0, x0=lz(x_ws2), iterations=4),
               dict(system="system", t_pass="arr", r_target="arr", d_km="pos", x0="state", iterations="int1")))
    s.append(S("pass_scan", kd.pass_scan, dict(sc=lz(sc2), info=lz(info2), x_ws=lz(x_ws2), d_km=[100.0],
                                              hessian=False),
               dict(sc="instance", info="callable", x_ws="state", d_km="vec", hessian="bool")))
    s.append(S("free_run_diagnosis", kd.free_run_diagnosis,
               dict(sc=lz(sc2), t=lazy(lambda: grid2()[0]), k_ws=lazy(lambda: grid2()[1]), info=lz(info2),
                    alpha=1e-2, x_guess=lazy(lambda: grid2()[2]), u_guess=lazy(lambda: grid2()[3]), max_iter=1,
                    n_hessian=0, settings=None),
               dict(sc="instance", k_ws="int1", info="callable", alpha="range:0:1", max_iter="int1",
                    n_hessian="int0", settings="instance_opt")))
    s.append(S("remedy_runs", kd.remedy_runs,
               dict(sc=lz(sc2), t=lazy(lambda: grid2()[0]), k_ws=lazy(lambda: grid2()[1]), info=lz(info2),
                    range_scale_km=141.0, alphas=[1e-2], x_guess=lazy(lambda: grid2()[2]),
                    u_guess=lazy(lambda: grid2()[3]), max_iter=1, keep_out=False,
                    remedies=("range noise", "regularised J")),
               dict(sc="instance", k_ws="int1", info="instance", range_scale_km="pos", alphas="vec", max_iter="int1",
                    keep_out="bool")))
    s.append(S("remedy_table", kd.remedy_table, dict(runs=lz(remedy2)), dict(runs="instance")))
    s.append(S("brief_outcome", kd.brief_outcome, dict(outcome="no convergence in 3 iterations"),
               dict(outcome="instance_str")))
    s.append(S("figure_keep_out_diagnosis", closed(figures.figure_keep_out_diagnosis),
               dict(diagnosis=lz(diag2), plain=lz(scan2), remedy=lz(scan2), range_scale_km=141.0,
                    regularised=lz(scan2)),
               dict(diagnosis="instance", plain="instance", remedy="instance", range_scale_km="pos",
                    regularised="instance_opt")))
    return s
