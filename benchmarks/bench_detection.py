"""Detection Monte Carlo: the batched (lockstep) OCBE vs the single-trial OCBE, per trial, on the 9:2 NRHO.

Each trial is one detection run of notebook 10: one period from periapsis, 2-hour cadence, L2 angles and rates,
quiet-policy maneuver at apoapsis, full OCBE filter and smoother.  The sequential side calls
:func:`cislunar.ocbe.ocbe_filter_smoother` per trial; the batched side runs ``batch`` trials in lockstep with
:func:`cislunar.detection.ocbe_batch`.  Both see the same inputs; the largest relative difference of z is printed.
Single thread.  Run with ``python -m benchmarks detection``.
"""

import time

import numpy as np

from cislunar import detection as det
from cislunar import orbits
from cislunar.dynamics import EARTH_MOON as em


def main(n_sequential: int = 8, batches=(4, 8, 20, 40), seed: int = 0) -> dict:
    setup = det.make_setup(em, orbits.nrho_9_2(em), 0.1 * det.window_control_weight(det.QUIET_POLICY), 1e-18)
    sc = setup.scenario
    kids = np.random.default_rng(seed).spawn(max(max(batches), n_sequential))
    inputs = [det.draw_trial(k, setup, det.QUIET_POLICY) for k in kids]
    det.run_trial_filter(setup, inputs[0])  # compile outside the timing
    t0 = time.perf_counter()
    z_seq = np.array([det.run_trial_filter(setup, inp).z_smooth for inp in inputs[:n_sequential]])
    t_seq = (time.perf_counter() - t0) / n_sequential
    result = {"sequential_s_per_trial": t_seq}
    print(f"sequential: {t_seq * 1e3:.1f} ms per trial")
    for B in batches:
        args = (em, sc.t, np.array([i.y for i in inputs[:B]]), setup.observer_states, sc.model, sc.meas_cov,
                np.array([i.x0 for i in inputs[:B]]), inputs[0].P0, setup.control_weight)
        det.ocbe_batch(*args)  # compile this batch size
        t0 = time.perf_counter()
        res = det.ocbe_batch(*args)
        t_b = (time.perf_counter() - t0) / B
        k = min(B, n_sequential)
        diff = float(np.max(np.abs(res.z_smooth[:k] / z_seq[:k] - 1)))
        result[f"batch_{B}_s_per_trial"] = t_b
        result[f"batch_{B}_speedup"] = t_seq / t_b
        print(f"batch {B:3d}: {t_b * 1e3:.1f} ms per trial, speed-up {t_seq / t_b:.1f}x, max |dz/z| {diff:.1e}")
    return result


if __name__ == "__main__":
    main()
