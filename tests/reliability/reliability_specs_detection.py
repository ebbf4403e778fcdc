"""Malformed-argument specs for the study helpers of ``cislunar.papers.greaves_scheeres_2021.detection``, swept by ``tests/test_reliability.py``.

The rest of ``cislunar.papers.greaves_scheeres_2021.detection`` is in the main table there; this plugin adds the functions that follow the
paper's claims beyond its own runs (burn timing, filtering given trials, burn directions, the health-metric race).
The valid calls use a short, coarse 9:2 NRHO track (0.8 period from periapsis, one measurement every 8 hours).
"""

from __future__ import annotations

import functools

import numpy as np
from spec_helpers import detection_setup as _setup

from cislunar.papers.greaves_scheeres_2021 import detection

MODULES = [detection]


@functools.lru_cache(maxsize=None)
def _inputs():
    return [detection.draw_trial(np.random.default_rng(k), _setup(), detection.QUIET_POLICY) for k in range(2)]


@functools.lru_cache(maxsize=None)
def _filtered():
    return detection.filter_trials(_setup(), _inputs())


def specs(Spec, lazy):
    S = Spec
    s = []
    s.append(S("draw_trial_burn_offset", detection.draw_trial,
               dict(rng=lazy(lambda: np.random.default_rng(0)), setup=lazy(_setup), policy=detection.QUIET_POLICY,
                    burn_offset_hours=1.5),
               dict(burn_offset_hours="real")))
    s.append(S("filter_trials", detection.filter_trials, dict(setup=lazy(_setup), inputs=lazy(_inputs), n_epochs=4),
               dict(setup="instance", inputs="iterable", n_epochs="int2_opt")))
    s.append(S("threshold_bootstrap", detection.threshold_bootstrap,
               dict(z_h0=np.array([0.1, 0.3, 0.2, 0.25]), z_h1=np.array([1.0, 1.4, 0.9, 1.2]), n_resamples=2,
                    rng=lazy(lambda: np.random.default_rng(0)), bandwidth="scott", n_grid=101),
               dict(z_h0="vec", z_h1="vec", n_resamples="int1", rng="rng", bandwidth="bandwidth", n_grid="int2")))
    s.append(S("control_spike_contrast", detection.control_spike_contrast,
               dict(setup=lazy(_setup), result=lazy(_filtered), half_width_hours=6.0, burn_offset_hours=0.0),
               dict(setup="instance", result="instance", half_width_hours="pos", burn_offset_hours="real")))
    n = 4
    sample = detection.MonteCarloSample(np.ones(n), np.ones(n), np.ones(n), np.radians([90.0, 0.0, -90.0, 180.0]),
                                        np.zeros(n), *(np.zeros(n),) * 4)
    s.append(S("azimuth_contrast", detection.azimuth_contrast,
               dict(sample=sample, half_width_deg=30.0, max_elevation_deg=45.0),
               dict(sample="instance", half_width_deg="range:0:90", max_elevation_deg="range:0:90")))
    s.append(S("direction_response", detection.direction_response,
               dict(setup=lazy(_setup), directions=np.array([[0.0, 0.0], [1.5, 0.2]]), magnitude_m_s=0.5,
                    n_repeats=1, seed=3, burn_offset_hours=0.0),
               dict(setup="instance", directions="arr", magnitude_m_s="pos", n_repeats="int1", seed="seed",
                    burn_offset_hours="real")))
    s.append(S("health_lead_study", detection.health_lead_study,
               dict(setup=lazy(_setup), magnitudes_m_s=np.array([0.5]), n_h0=10, n_h1=1, seed=1, horizon_hours=10.0,
                    tail_probability=0.01, progress=False),
               dict(setup="instance", magnitudes_m_s="vec", n_h0="int1", n_h1="int1", seed="seed",
                    horizon_hours="pos", tail_probability="range:0:0.5", progress="bool")))
    return s
