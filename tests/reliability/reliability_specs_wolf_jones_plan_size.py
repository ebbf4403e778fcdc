"""Malformed-argument specs for the Wolf & Jones plan-size study (plugin of tests/reliability/test_reliability.py;
issue 22, item 2).

Covers :mod:`cislunar.papers.wolf_jones.plan_size_study` and the control-term normalisation added to
:mod:`cislunar.papers.wolf_jones.scenarios` (``control_scale``; the scenarios module itself is swept by
reliability_specs_wolf_jones.py, which finds this spec by its label) and the study's figure
:func:`cislunar.papers.wolf_jones.figures.departure_figure` (the figures module is swept by
reliability_specs_wolf_jones_studies.py, which finds it the same way).  The sweep's valid call is the smallest that
reaches every stage: 6 nodes, one combination, one weight, SCvx limited to 3 iterations (the solve then fails the
same way each time, which the sweep records as a row), so it also serves the Dask bit-identity test of
tests/utils/test_every_executor_on_dask.py.
"""

from __future__ import annotations

import functools

from spec_helpers import closed as _closed

from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.guidance import scvx
from cislunar.papers.wolf_jones import figures
from cislunar.papers.wolf_jones import plan_size_study as ps
from cislunar.papers.wolf_jones import scenarios as wj

MODULES = [ps]
EXEMPT: dict = {}


@functools.lru_cache(maxsize=None)
def case1():
    return wj.test_case_1()


@functools.lru_cache(maxsize=None)
def grid():
    return case1().node_times(8)[0]


@functools.lru_cache(maxsize=None)
def toy_study():
    """A two-normalisation study with made-up rows (the figure needs no solve)."""
    rows = tuple(ps.PlanSizeRow(n, ps.ADOPTED_READING, c, 1e-11, a, True, 10.0 * a / c, 100.0, 1e4 * a / c, 1.2e5,
                                5, "") for n, c in ((ps.ADOPTED_NORMALISATION, 1.0), ("total, m/s", 1024.5))
                 for a in ps.PAPER_ALPHAS)
    base = ps.PlanSizeRow(ps.ADOPTED_NORMALISATION, ps.ADOPTED_READING, 1.0, 1e-11, 0.0, True, 0.5, 90.0, 20.0,
                          1.18e5, 5, "")
    return ps.PlanSizeStudy(rows, base, (ps.ADOPTED_NORMALISATION, "total, m/s"), (ps.ADOPTED_READING,),
                            ps.PAPER_ALPHAS, 8, 117_553.0, ps.FIT_FRACTION, 0.0)


def specs(Spec, lazy):
    s = []
    S = Spec
    # scenarios.control_scale (the rest of scenarios is in reliability_specs_wolf_jones.py)
    s.append(S("control_scale", wj.control_scale,
               dict(scenario=lazy(case1), t_nodes=lazy(grid), unit="m/s", average="day"),
               dict(scenario="instance", t_nodes="grid", unit="choice", average="choice")))
    s.append(S("q_reading_nd", ps.q_reading_nd, dict(reading=ps.LITERAL_READING, system=em),
               dict(reading="choice")))
    s.append(S("dro_size_km", ps.dro_size_km, dict(scenario=lazy(case1), n=50),
               dict(scenario="instance", n="int2")))
    s.append(S("plan_size_sweep", ps.plan_size_sweep,
               dict(n_nodes=6, normalisations=[ps.ADOPTED_NORMALISATION], readings=[ps.ADOPTED_READING],
                    alphas=(5e-3,), sigma=1.0, forward_hessian=True, settings=scvx.SCvxSettings(max_iter=3),
                    fraction=0.05, executor=None, progress=False),
               dict(n_nodes="int2", normalisations="names_opt", readings="names_opt", alphas="vec", sigma="real",
                    forward_hessian="bool", settings="instance_opt", fraction="range:0:1", progress="bool")))
    s.append(S("departure_figure", _closed(figures.departure_figure), dict(study=lazy(toy_study)),
               dict(study="instance")))
    return s
