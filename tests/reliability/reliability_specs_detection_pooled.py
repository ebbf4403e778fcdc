"""Malformed-argument specs for the pooled detection Monte Carlo of notebook 10 (issue 21 item 3): the batched
draws, pooled Monte Carlo runs and policy studies, pooled filtering of trial sets, the direction trials, and the
binomial standard error of a fraction (detection_studies).  Contributed by the owner of those functions; the
functions' older specs live in ``reliability_specs_detection.py`` and ``reliability_specs_greaves_scheeres_2021_studies.py``.
"""

from __future__ import annotations

import functools

import numpy as np

from cislunar.cr3bp import orbits
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.papers.greaves_scheeres_2021 import detection
from cislunar.papers.greaves_scheeres_2021 import detection_studies as ds

MODULES = []  # the modules are covered by the two plugins above; these specs add their new functions


@functools.lru_cache(maxsize=None)
def _setup():
    return detection.make_setup(em, orbits.nrho_9_2(em), 0.1 * detection.window_control_weight(detection.QUIET_POLICY),
                                1e-18, cadence_hours=8.0, window_hours=16.0, periods=0.8, n_sub=3)


@functools.lru_cache(maxsize=None)
def _inputs():
    return detection.draw_trials([np.random.default_rng(k) for k in range(2)], _setup(), detection.QUIET_POLICY)


def specs(Spec, lazy):
    S = Spec
    s = []
    s.append(S("draw_trials", detection.draw_trials,
               dict(rngs=lazy(lambda: [np.random.default_rng(0)]), setup=lazy(_setup), policy=detection.QUIET_POLICY,
                    magnitude_m_s=None, direction=None, burn_offset_hours=1.5),
               dict(setup="instance", burn_offset_hours="real")))
    s.append(S("run_detection_monte_carlos", detection.run_detection_monte_carlos,
               dict(jobs=lazy(lambda: [(_setup(), None, 2, 1)]), batch_size=2, progress=False),
               dict(batch_size="int1", progress="bool")))
    s.append(S("run_policy_studies", detection.run_policy_studies,
               dict(jobs=lazy(lambda: [(_setup(), detection.QUIET_POLICY, 2, 2, 0, 1)]), batch_size=2, progress=False),
               dict(batch_size="int1", progress="bool")))
    s.append(S("filter_trial_sets", detection.filter_trial_sets,
               dict(sets=lazy(lambda: [(_setup(), _inputs())]), progress=False), dict(progress="bool")))
    s.append(S("direction_trials", detection.direction_trials,
               dict(setup=lazy(_setup), directions=np.array([[0.0, 0.0], [1.5, 0.2]]), magnitude_m_s=0.5,
                    n_repeats=1, seed=3, burn_offset_hours=0.0),
               dict(setup="instance", directions="arr", magnitude_m_s="pos", n_repeats="int1", seed="seed",
                    burn_offset_hours="real")))
    s.append(S("fraction_standard_error", ds.fraction_standard_error, dict(fraction=0.1, n=200),
               dict(fraction="range:0:1", n="int1")))
    return s
