"""Malformed-argument specs for ``cislunar.estimation.adaptive_ocbe`` (issue 11), swept by ``tests/test_reliability.py``.

One valid call per public function with the kind of each argument (kinds as in ``bad_values`` there).  The valid
calls are cheap: a half-period 9:2 NRHO track with a measurement every 24 h (4 epochs), two sub-steps per interval.
"""

from __future__ import annotations

import functools

import numpy as np

from cislunar.cr3bp import orbits
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.estimation import adaptive_ocbe, ocbe
from cislunar.papers.greaves_scheeres_2021 import panels, tracking
from cislunar.sensing import measurements

MODULES = [adaptive_ocbe, panels]


@functools.lru_cache(maxsize=None)
def _scenario():
    return tracking.make_scenario(em, orbits.nrho_9_2(em), 24.0, periods=0.5)


@functools.lru_cache(maxsize=None)
def _kwargs():
    """Valid arguments of the filter calls: noise-free measurements of the truth, a small prior."""
    sc = _scenario()
    truth = tracking.simulate_truth(em, sc.x_start, sc.t)
    y = sc.model(sc.observers[:, 0], truth)
    return dict(system=em, t=sc.t, y=y, observer_states=sc.observers[:, 0], model=sc.model, meas_cov=sc.meas_cov,
                x0=sc.x_start, P0=np.diag([1e-9] * 3 + [1e-9] * 3), control_weight=1e-8, n_sub=2, tol=1e-13,
                truth=truth)


@functools.lru_cache(maxsize=None)
def _result():
    k = _kwargs()
    return ocbe.ocbe_filter_smoother(em, k["t"], k["y"], k["observer_states"], k["model"], k["meas_cov"], k["x0"],
                                     k["P0"], k["control_weight"], n_sub=2, smooth=True, tol=1e-13)


def specs(Spec, lazy):
    s = []
    S = Spec

    def kw(name):
        return lazy(functools.partial(lambda n: _kwargs()[n], name))

    s.append(S("metric_law", adaptive_ocbe.metric_law, dict(dof=4), dict(dof="int1")))
    s.append(S("metric_limit", adaptive_ocbe.metric_limit, dict(dof=np.array([4, 4, 0]), probability=0.99),
               dict(dof="arr_finite", probability="range:0:1")))
    # one epoch of a 3-state, 2-measurement linear system
    S3 = np.triu(np.arange(1.0, 10.0).reshape(3, 3)) + np.eye(3)
    s.append(S("metric_terms", adaptive_ocbe.metric_terms,
               dict(S=S3, Phi=np.eye(3) * 1.1, Q=np.diag([1.0, 2.0, 3.0]), H=np.ones((2, 3)),
                    dy=np.array([0.5, -0.2]), meas_cov=np.eye(2)),
               dict(S="upper", Phi="arr", Q="spd", H="arr", dy="arr", meas_cov="spd")))
    s.append(S("forward_metric", adaptive_ocbe.forward_metric,
               dict(result=lazy(_result), model=measurements.ANGLES_AND_RATES, available=None),
               dict(result="instance", model="instance", available="arr_opt")))
    s.append(S("smoothed_metric", adaptive_ocbe.smoothed_metric,
               dict(result=lazy(_result), y=kw("y"), observer_states=kw("observer_states"), model=kw("model"),
                    meas_cov=kw("meas_cov"), control_weight=1e-8, available=None),
               dict(result="instance", y="arr", observer_states="arr", model="instance", meas_cov="spd",
                    control_weight="weights", available="arr_opt")))
    s.append(S("first_detection", adaptive_ocbe.first_detection,
               dict(metric=np.array([1.0, 20.0, 20.0, 20.0, 1.0]), limit=13.28, start=1, consecutive=3),
               dict(metric="arr_any", limit="arr_any", start="int0", consecutive="int1")))

    def _reset_kwargs():
        k, r = _kwargs(), _result()
        return dict(system=em, t=k["t"], k=1, x_filt_prev=r.x_filt[0], P_filt_prev=r.P_filt[0], y_k=k["y"][1],
                    observers_k=k["observer_states"][1], model=k["model"], meas_cov=k["meas_cov"],
                    control_weight=1e-8, rule="mean", target=None, n_sub=2, tol=1e-13, max_factor=1e40)

    rk = {n: lazy(functools.partial(lambda n: _reset_kwargs()[n], n)) for n in
          ("system", "t", "k", "x_filt_prev", "P_filt_prev", "y_k", "observers_k", "model", "meas_cov",
           "control_weight", "rule", "target", "n_sub", "tol", "max_factor")}
    s.append(S("reset_factor", adaptive_ocbe.reset_factor, rk,
               dict(system="system", t="grid", k="int1", x_filt_prev="state", P_filt_prev="spd", y_k="arr",
                    observers_k="arr", model="instance", meas_cov="spd", control_weight="pos", rule="choice",
                    target="pos_opt", n_sub="int2", tol="range:1e-16:1e-3", max_factor="pos")))
    common = dict(system="system", t="grid", y="arr", observer_states="arr", model="instance", meas_cov="spd",
                  x0="state", P0="spd", control_weight="weights", probability="range:0:1", consecutive="int1",
                  reset="choice", n_sub="int2", tol="range:1e-16:1e-3", max_resets="int0")
    ok = {n: kw(n) for n in ("system", "t", "y", "observer_states", "model", "meas_cov", "x0", "P0",
                             "control_weight", "n_sub", "tol")}
    s.append(S("adaptive_ocbe", adaptive_ocbe.adaptive_ocbe,
               dict(ok, available=None, probability=0.99, consecutive=3, reset="mean", smooth=True, max_resets=5),
               dict(common, available="arr_opt", smooth="bool")))

    def _batch(name):
        v = _kwargs()[name]
        return np.stack([v, v]) if name in ("y", "x0") else v

    okb = {n: lazy(functools.partial(_batch, n)) for n in ok}
    s.append(S("adaptive_ocbe_batch", adaptive_ocbe.adaptive_ocbe_batch,
               dict(okb, probability=0.99, consecutive=3, reset="mean", max_resets=5), common, baseline=False))
    okf = {n: okb[n] for n in ok if n != "n_sub"}
    s.append(S("first_pass_detections", adaptive_ocbe.first_pass_detections,
               dict(okf, probability=0.99, consecutive=3, n_sub=2),
               {n: common[n] for n in list(okf) + ["probability", "consecutive", "n_sub"]}))
    s.append(S("panel_series", panels.panel_series,
               dict(system=em, result=lazy(_result), truth=kw("truth"), control_weight=1e-8, y=kw("y"),
                    observer_states=kw("observer_states"), model=kw("model"), meas_cov=kw("meas_cov"),
                    available=None),
               dict(system="system", result="instance", truth="arr", control_weight="weights", y="arr",
                    observer_states="arr", model="instance", meas_cov="spd", available="arr_opt")))

    def _panels():
        k = _kwargs()
        return panels.panel_series(em, _result(), k["truth"], 1e-8, k["y"], k["observer_states"], k["model"],
                                          k["meas_cov"])

    s.append(S("PanelSeries.spike_contrast", lazy(lambda: _panels().spike_contrast),
               dict(t_days=1.0, half_width_days=0.3), dict(t_days="real", half_width_days="pos")))
    s.append(S("figure_errors", panels.figure_errors,
               dict(panels=lazy(_panels), title="t", burn_days=0.5, detection_days=[1.0], velocity_unit="mm/s"),
               dict(panels="instance", title="instance_str", burn_days="real_opt", detection_days="arr_finite",
                    velocity_unit="choice")))
    s.append(S("figure_control_metric", panels.figure_control_metric,
               dict(panels=lazy(_panels), title="t", burn_days=0.5, detection_days=[1.0],
                    first_pass_metric=lazy(lambda: _panels().metric[0]), first_pass_until=2),
               dict(panels="instance", title="instance_str", burn_days="real_opt", detection_days="arr_finite",
                    first_pass_metric="arr_any_opt", first_pass_until="int0_opt")))
    return s
