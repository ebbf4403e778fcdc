"""Notebook 09b's adaptive OCBE: the old paths against the new ones, side by side in one run.

* reset-rule study (:func:`cislunar.papers.greaves_scheeres_2021.adaptive_studies.reset_rule_study`): ``single``, the
  path it took before, one single-trial adaptive filter per run and rule
  (:func:`cislunar.estimation.adaptive_ocbe.adaptive_ocbe`, forward only, each reset re-running the whole track;
  ``adaptive_studies._reset_rule_runs``), against ``batched``, the path it takes now, every run with every rule in
  one lockstep (:func:`cislunar.estimation.adaptive_ocbe.adaptive_ocbe_batch`, forward only, a reset rule per trial,
  failures flagged per trial, re-runs of only the trials with a new detection; ``adaptive_studies._reset_rule_batch``).
  The benchmark checks that both give the same rows.  Both share today's :func:`reset_factor` (the next item), so
  the ratio understates the gain over the code before this change;
* the reset's metric :math:`M_k(\\alpha)` as :func:`reset_factor` evaluates it in its root search: through the
  checked public SRI updates (before) against their unchecked kernels after one checked evaluation (now); same
  values;
* the state-covariance reset (``reset="inflate"``, the measurement-set study of
  :func:`cislunar.papers.greaves_scheeres_2021.adaptive_studies.variant_study`): one single-trial adaptive filter
  per run against the batched one (restarts from the detection epoch grouped by epoch); same detections and factors;
* the delay study's first pass (:func:`first_pass_detections`): the batched OCBE with the smoother (before) against
  the filter only (now); same first-detection epochs.

Ratios come from one run (the machine may be shared); no timed assertion.  Run with ``OMP_NUM_THREADS=1 python -m
benchmarks adaptive_ocbe``.
"""

import time

import numpy as np

from cislunar.cr3bp import orbits
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.estimation import adaptive_ocbe as ad
from cislunar.estimation import ocbe, srif
from cislunar.estimation.batched_ocbe import ocbe_batch
from cislunar.papers.greaves_scheeres_2021 import adaptive_studies as ads
from cislunar.papers.greaves_scheeres_2021 import detection as det

MAGNITUDES_M_S = (0.05, 0.3, 3.0)  # the quick notebook's sizes
RUNS_PER_SIZE = 6
DELAY_RUNS = 48


def _reset_metric_inputs(setup, inputs):
    """S, Phi, Q, H, dy, R of the reset at the first detection of a 3 m/s run (as reset_factor builds them)."""
    sc = setup.scenario
    first = ocbe.ocbe_filter_smoother(em, sc.t, inputs.y, setup.observer_states, sc.model, sc.meas_cov, inputs.x0,
                                      inputs.P0, setup.control_weight, smooth=False)
    metric, dof = ad.forward_metric(first, sc.model)
    k = ad.first_detection(metric, ad.metric_limit(dof))
    grid = np.linspace(sc.t[k - 1], sc.t[k], 9)
    tr = ocbe.ocbe_transition(em, first.x_filt[k - 1], grid, setup.control_weight[k - 1])
    val, _, Ht = sc.model.evaluate(setup.observer_states[k][None], tr.x[-1])
    S = srif.sri_from_covariance(np.zeros(6), first.P_filt[k - 1])[0]
    return (S, tr.phi[-1, :6, :6], ocbe.ocbe_process_noise(tr.phi[-1]), Ht.reshape(-1, 6),
            sc.model.residual(inputs.y[k][None], val).reshape(-1), np.asarray(sc.meas_cov, float))


def main(seed: int = 0) -> dict:
    setup = det.make_setup(em, orbits.nrho_9_2(em), 1e-18, 1e-18)
    sc = setup.scenario
    rng = np.random.default_rng(seed)
    runs = [(m, det.draw_trial(rng, setup, magnitude_m_s=m)) for m in MAGNITUDES_M_S for _ in range(RUNS_PER_SIZE)]
    ads._reset_rule_batch((setup, runs[:1], 5))  # compile the integrators outside the timings
    ads._reset_rule_runs((setup, runs[0][0], runs[0][1], 5))
    result = {}

    t0 = time.perf_counter()
    old = [row for m, d in runs for row in ads._reset_rule_runs((setup, m, d, 5))]
    t1 = time.perf_counter()
    new = [row for i in range(0, len(runs), ads.RUNS_PER_TASK)
           for row in ads._reset_rule_batch((setup, runs[i:i + ads.RUNS_PER_TASK], 5))]
    t2 = time.perf_counter()
    n = len(old)
    result["reset_rule_study"] = {"runs": n, "single_s": t1 - t0, "batched_s": t2 - t1, "ratio": (t1 - t0) / (t2 - t1),
                                  "identical_rows": old == new}
    print(f"reset-rule study, {len(runs)} runs x {len(ad.RESET_RULES)} rules: single {1e3 * (t1 - t0) / n:.0f} ms/run, "
          f"batched {1e3 * (t2 - t1) / n:.0f} ms/run, ratio {(t1 - t0) / (t2 - t1):.1f}x; rows identical {old == new}; "
          f"resets {sum(r[5] for r in new)}, failed {sum(r[5] > 5 for r in new)}")

    S, Phi, Q, H, dy, R = _reset_metric_inputs(setup, next(d for m, d in runs if m == 3.0))
    zero, eye, alphas = np.zeros(6), np.eye(6), np.log(np.logspace(0, 40, 200))

    def checked(la):
        S_bar = srif.time_update(S, zero, Phi, eye, np.exp(la) * Q)[0]
        return srif.measurement_update(S_bar, zero, H, dy, R)[2] ** 2

    def kernels(la):
        S_bar = srif._time_update(S, zero, Phi, eye, np.exp(la) * Q)[0]
        return float(srif._measurement_update(S_bar, zero, H, dy, R)[2]) ** 2

    t0 = time.perf_counter()
    a = [checked(la) for la in alphas]
    t1 = time.perf_counter()
    b = [kernels(la) for la in alphas]
    t2 = time.perf_counter()
    result["reset_metric"] = {"checked_ms": 1e3 * (t1 - t0) / alphas.size, "kernels_ms": 1e3 * (t2 - t1) / alphas.size,
                              "ratio": (t1 - t0) / (t2 - t1), "identical": a == b}
    print(f"reset metric M(alpha): checked updates {1e3 * (t1 - t0) / alphas.size:.2f} ms, kernels "
          f"{1e3 * (t2 - t1) / alphas.size:.2f} ms per evaluation, ratio {(t1 - t0) / (t2 - t1):.1f}x; identical {a == b}")

    ys, x0s = np.array([d.y for _, d in runs]), np.array([d.x0 for _, d in runs])
    def one(d):
        try:
            return ad.adaptive_ocbe(em, sc.t, d.y, setup.observer_states, sc.model, sc.meas_cov, d.x0, d.P0,
                                    setup.control_weight, reset="inflate", smooth=False, max_resets=5).detections
        except (ad.ResetError, ocbe.FilterDivergenceError):
            return None  # flagged in the batch

    t0 = time.perf_counter()
    single = [one(d) for _, d in runs]
    t1 = time.perf_counter()
    batched = ad.adaptive_ocbe_batch(em, sc.t, ys, setup.observer_states, sc.model, sc.meas_cov, x0s, runs[0][1].P0,
                                     setup.control_weight, reset="inflate", smooth=False, max_resets=5,
                                     on_failure="flag")[3]
    t2 = time.perf_counter()
    same = all(a is None or [d.epoch for d in a] == [d.epoch for d in b] and
               np.allclose([d.factor for d in a], [d.factor for d in b], rtol=1e-7) for a, b in zip(single, batched))
    result["inflate_reset"] = {"runs": len(runs), "single_s": t1 - t0, "batched_s": t2 - t1,
                               "ratio": (t1 - t0) / (t2 - t1), "same_detections": same}
    print(f"inflation reset, {len(runs)} runs: single {1e3 * (t1 - t0) / len(runs):.0f} ms/run, batched "
          f"{1e3 * (t2 - t1) / len(runs):.0f} ms/run, ratio {(t1 - t0) / (t2 - t1):.1f}x; same detections {same}")

    draws = [det.draw_trial(rng, setup, magnitude_m_s=0.05) for _ in range(DELAY_RUNS)]
    args = (em, sc.t, np.array([d.y for d in draws]), setup.observer_states, sc.model, sc.meas_cov,
            np.array([d.x0 for d in draws]), draws[0].P0, setup.control_weight)
    t0 = time.perf_counter()
    m_old = ad.forward_metric(ocbe_batch(*args), sc.model)[0]
    t1 = time.perf_counter()
    m_new = ad.forward_metric(ocbe_batch(*args, smooth=False), sc.model)[0]
    t2 = time.perf_counter()
    lim = ad.metric_limit(4)
    same = all(ad.first_detection(x, lim) == ad.first_detection(y, lim) for x, y in zip(m_old, m_new))
    result["first_pass"] = {"runs": DELAY_RUNS, "smoothed_s": t1 - t0, "filter_s": t2 - t1,
                            "ratio": (t1 - t0) / (t2 - t1), "same_epochs": same,
                            "metric_max_abs_diff": float(np.nanmax(np.abs(m_old - m_new)))}
    print(f"delay study first pass, {DELAY_RUNS} runs of 50 mm/s: with smoother {1e3 * (t1 - t0) / DELAY_RUNS:.1f} "
          f"ms/run, filter only {1e3 * (t2 - t1) / DELAY_RUNS:.1f} ms/run, ratio {(t1 - t0) / (t2 - t1):.2f}x; "
          f"same epochs {same}, metric max |diff| {result['first_pass']['metric_max_abs_diff']:.1e}")
    return result


if __name__ == "__main__":
    main()
