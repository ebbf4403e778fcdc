"""Malformed-argument specs for the pooled detection Monte Carlo of notebook 10 (issue 21 item 3): the batched
draws, pooled Monte Carlo runs and policy studies, pooled filtering of trial sets, the direction trials, and the
binomial standard error of a fraction (detection_studies).  Contributed by the owner of those functions; the
functions' older specs live in ``reliability_specs_detection.py`` and ``reliability_specs_greaves_scheeres_2021_studies.py``.
``HealthRuns.from_filter`` (the per-run Fig. 22 reading) and the standard errors of a difference from the paper's
Monte Carlo numbers (notebook 10's closing table) are swept here too.

Every argument is swept (``executor`` is checked by ``map_tasks``).  The items of ``jobs`` and ``sets`` are swept
through one-job wrappers (labels ``<function>.job`` / ``.set``), whose refusals name ``jobs[0] seed``,
``sets[0] inputs``, ...  Refusals that depend on two arguments (a ``direction`` with no burn) or that must come
before any Monte Carlo (``run_policy_studies``' options) are tested in
``tests/papers/greaves_scheeres_2021/test_detection_refusals.py``.
"""

from __future__ import annotations

import functools

import numpy as np
from spec_helpers import detection_setup as _setup

from cislunar.papers.greaves_scheeres_2021 import detection
from cislunar.papers.greaves_scheeres_2021 import detection_studies as ds

MODULES = []  # the modules are covered by the two plugins above; these specs add their new functions


@functools.lru_cache(maxsize=None)
def _inputs():
    return detection.draw_trials([np.random.default_rng(k) for k in range(2)], _setup(), detection.QUIET_POLICY)


@functools.lru_cache(maxsize=None)
def _filtered():
    return detection.filter_trials(_setup(), _inputs())


def _one_job(fn, container, fields):
    """``fn`` called with a one-item ``container`` built from keyword ``fields`` (the sweep then varies each field
    of the tuple; the refusals name it as ``jobs[0] seed``, ``sets[0] inputs``, ...)."""

    def call(**kwargs):
        rest = {k: v for k, v in kwargs.items() if k not in fields}
        return fn(**{container: [tuple(kwargs[f] for f in fields)]}, **rest)

    return call


def specs(Spec, lazy):
    S = Spec
    s = []
    rng = lazy(lambda: [np.random.default_rng(0)])
    quiet = detection.QUIET_POLICY
    s.append(S("draw_trials", detection.draw_trials,
               dict(rngs=rng, setup=lazy(_setup), policy=quiet, magnitude_m_s=None, direction=None,
                    burn_offset_hours=1.5),
               dict(rngs="iterable", setup="instance", policy="instance_opt", burn_offset_hours="real")))
    # the overrides swept from valid values (a None valid value gives no shape to derive bad ones from)
    s.append(S("draw_trials.overrides", detection.draw_trials,
               dict(rngs=rng, setup=lazy(_setup), policy=quiet, magnitude_m_s=0.5, direction=np.array([0.1, 0.2])),
               dict(magnitude_m_s="nonneg_opt", direction="arr_opt")))
    s.append(S("run_detection_monte_carlos", detection.run_detection_monte_carlos,
               dict(jobs=lazy(lambda: [(_setup(), None, 2, 1)]), batch_size=2, executor=None, progress=False,
                    desc="mc"),
               dict(jobs="iterable", batch_size="int1", executor="instance_opt", progress="bool",
                    desc="instance_str")))
    s.append(S("run_detection_monte_carlos.job",
               _one_job(detection.run_detection_monte_carlos, "jobs", ("setup", "policy", "n_trials", "seed")),
               dict(setup=lazy(_setup), policy=None, n_trials=2, seed=1, batch_size=2, progress=False),
               dict(setup="instance", policy="instance_opt", n_trials="int1", seed="seed")))
    s.append(S("run_policy_studies", detection.run_policy_studies,
               dict(jobs=lazy(lambda: [(_setup(), quiet, 2, 2, 0, 1)]), batch_size=2, executor=None,
                    bandwidth="scott", progress=False, desc="studies"),
               dict(jobs="iterable", batch_size="int1", executor="instance_opt", bandwidth="bandwidth",
                    progress="bool", desc="instance_str")))
    s.append(S("run_policy_studies.job",
               _one_job(detection.run_policy_studies, "jobs", ("setup", "policy", "n_h0", "n_h1", "n_test", "seed")),
               dict(setup=lazy(_setup), policy=quiet, n_h0=2, n_h1=2, n_test=0, seed=1, batch_size=2, progress=False),
               dict(setup="instance", policy="instance", n_h0="int2", n_h1="int2", n_test="int0", seed="seed")))
    s.append(S("filter_trial_sets", detection.filter_trial_sets,
               dict(sets=lazy(lambda: [(_setup(), _inputs())]), executor=None, progress=False),
               dict(sets="iterable", executor="instance_opt", progress="bool")))
    s.append(S("filter_trial_sets.set", _one_job(detection.filter_trial_sets, "sets", ("setup", "inputs")),
               dict(setup=lazy(_setup), inputs=lazy(_inputs), progress=False),
               dict(setup="instance", inputs="iterable")))
    s.append(S("direction_trials", detection.direction_trials,
               dict(setup=lazy(_setup), directions=np.array([[0.0, 0.0], [1.5, 0.2]]), magnitude_m_s=0.5,
                    n_repeats=1, seed=3, burn_offset_hours=0.0),
               dict(setup="instance", directions="arr", magnitude_m_s="pos", n_repeats="int1", seed="seed",
                    burn_offset_hours="real")))
    s.append(S("fraction_standard_error", ds.fraction_standard_error, dict(fraction=0.1, n=200),
               dict(fraction="range:0:1", n="int1")))
    # the standard errors of a difference from the paper's Monte Carlo numbers (notebook 10's closing table)
    s.append(S("accuracy_comparison_standard_error", ds.accuracy_comparison_standard_error,
               dict(paper=0.97, n=200, n_paper=200), dict(paper="range:0:1", n="int1", n_paper="int1")))
    s.append(S("paper_threshold_standard_error", ds.paper_threshold_standard_error,
               dict(se=0.0137, z_lim=0.614, paper=0.4106, n_h0=500, n_h1=3000),
               dict(se="nonneg", z_lim="pos", paper="pos", n_h0="int1", n_h1="int1")))
    s.append(S("threshold_comparison_standard_error", ds.threshold_comparison_standard_error,
               dict(se=0.0137, z_lim=0.614, paper=0.4106, n_h0=500, n_h1=3000),
               dict(se="nonneg", z_lim="pos", paper="pos", n_h0="int1", n_h1="int1")))
    s.append(S("one_run_comparison_standard_error", ds.one_run_comparison_standard_error, dict(sd=0.03, n=64),
               dict(sd="nonneg", n="int1")))
    # the per-run reading of Fig. 22 (notebook 10, Section 6): trials, their batched OCBE, the residual test's options
    s.append(S("HealthRuns.from_filter", ds.HealthRuns.from_filter,
               dict(setup=lazy(_setup), inputs=lazy(_inputs), result=lazy(_filtered), horizon_hours=24.0,
                    tail_probability=0.00135),
               dict(setup="instance", inputs="iterable", result="instance", horizon_hours="pos",
                    tail_probability="range:0:0.5")))
    return s
