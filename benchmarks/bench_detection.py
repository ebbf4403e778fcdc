"""Detection Monte Carlo of notebook 10: today's path vs the first batched OCBE, in one run, single thread.

Each trial is one detection run of notebook 10 at the paper's setting: one period of the 9:2 NRHO from periapsis,
2-hour cadence (79 epochs), L2 angles and rates, quiet-policy maneuver at apoapsis, window tuning f = 0.1, full
OCBE filter and smoother, z from the smoothed control.

* ``reference``: the Monte Carlo as it ran before (batches of 8 trials: draws, then the first batched OCBE on the
  full 12x12 variational system, one batch per call; kept as the test oracle
  ``tests/estimation/reference_batched_ocbe.py``, imported from there).
* ``fast``: :func:`cislunar.papers.greaves_scheeres_2021.detection.run_detection_monte_carlo` with ``batch_size=8`` as notebook 10 calls it
  (same seeds and trials; the block integrator, several batches per lockstep call).

Both see the same seeds; the largest relative difference of z is printed.  Then the fast path at the paper's sizes
for one policy and orbit (500 runs without and 3000 with a maneuver), to show that its cost per trial does not
change with the size (trials are independent, so the reference path scales the same way), the filter alone (no
draws) per engine and lockstep size on the same inputs, the split between drawing and filtering, and the
single-trial OCBE.
Ratios come from one run (the machine may be shared); no timed assertion.
Run with ``OMP_NUM_THREADS=1 python -m benchmarks detection``.
"""

import sys
import time
from pathlib import Path

import numpy as np

from cislunar.cr3bp import orbits
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.estimation import batched_ocbe
from cislunar.papers.greaves_scheeres_2021 import detection as det
from cislunar.utils.montecarlo import trial_rng

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "estimation"))
from reference_batched_ocbe import ocbe_batch_reference  # the test oracle, not part of the package


def _best(fn, repeats):
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def main(n_trials: int = 128, batch: int = 8, lockstep=(8, 16, 32, 64, 128), n_single: int = 4, seed: int = 0,
         repeats: int = 2) -> dict:
    pol = det.QUIET_POLICY
    setup = det.make_setup(em, orbits.nrho_9_2(em), 0.1 * det.window_control_weight(pol), 1e-18)
    sc = setup.scenario
    n_batches = -(-n_trials // batch)

    def filter_args(inputs):
        return (em, sc.t, np.array([i.y for i in inputs]), setup.observer_states, sc.model, sc.meas_cov,
                np.array([i.x0 for i in inputs]), np.array([i.P0 for i in inputs]), setup.control_weight)

    def reference_mc():  # the Monte Carlo before this change: one reference-engine call per batch of 8
        z = []
        for k in range(n_batches):
            inputs = [det.draw_trial(c, setup, pol) for c in trial_rng(seed, k).spawn(batch)]
            res = ocbe_batch_reference(*filter_args(inputs), n_sub=setup.n_sub, tol=setup.tol)
            z.extend(res.z_smooth * em.velocity_unit_km_s * 1e3)
        return np.array(z[:n_trials])

    def fast_mc():
        return det.run_detection_monte_carlo(setup, pol, n_trials, seed, batch_size=batch, progress=False).z

    # compile every integrator outside the timings
    warm = [det.draw_trial(c, setup, pol) for c in np.random.default_rng(seed + 1).spawn(max(lockstep))]
    for B in sorted({batch, *lockstep}):
        if B == batch:
            ocbe_batch_reference(*filter_args(warm[:B]))
        batched_ocbe.ocbe_batch(*filter_args(warm[:B]))
    det.run_detection_monte_carlo(setup, pol, 2 * batch, seed + 1, batch_size=batch, progress=False)

    result = {"n_trials": n_trials, "batch_size": batch, "lockstep_trials": det.LOCKSTEP_TRIALS,
              "heyoka_lanes": batched_ocbe._LANES}
    t_ref, z_ref = _best(reference_mc, 1)
    t_new, z_new = _best(fast_mc, repeats)
    result["reference_mc_s_per_trial"] = t_ref / n_trials
    result["fast_mc_s_per_trial"] = t_new / n_trials
    result["mc_speedup"] = t_ref / t_new
    result["mc_max_rel_dz"] = float(np.max(np.abs(z_new / z_ref - 1)))
    print(f"Monte Carlo, {n_trials} trials, batch_size {batch}: reference {t_ref / n_trials * 1e3:.1f} ms/trial, "
          f"fast {t_new / n_trials * 1e3:.1f} ms/trial, speed-up {t_ref / t_new:.2f}x, "
          f"max |dz/z| {result['mc_max_rel_dz']:.1e}")

    # the paper's sizes for one policy and orbit (notebook 10 runs this for every policy and orbit, twice)
    t0 = time.perf_counter()
    det.run_detection_monte_carlo(setup, None, 500, seed + 2, batch_size=batch, progress=False)
    det.run_detection_monte_carlo(setup, pol, 3000, seed + 3, batch_size=batch, progress=False)
    t_paper = time.perf_counter() - t0
    result["paper_size_fast_s"] = t_paper
    result["paper_size_reference_projected_s"] = t_ref / n_trials * 3500
    print(f"paper's sizes (500 H0 + 3000 H1, one policy and orbit): fast {t_paper:.1f} s ({t_paper / 3500 * 1e3:.1f} "
          f"ms/trial); the reference path at its {t_ref / n_trials * 1e3:.1f} ms/trial would take "
          f"{t_ref / n_trials * 3500:.0f} s, {t_ref / n_trials * 3500 / t_paper:.1f}x as long")

    # where the time goes: drawing the trials vs filtering them
    t_draw, inputs = _best(lambda: [det.draw_trial(c, setup, pol)
                                    for k in range(n_batches) for c in trial_rng(seed, k).spawn(batch)], 1)
    result["draw_s_per_trial"] = t_draw / len(inputs)
    print(f"drawing (truth, measurements, hand-off error): {t_draw / len(inputs) * 1e3:.1f} ms/trial")
    t_f, _ = _best(lambda: [ocbe_batch_reference(*filter_args(inputs[k:k + batch]))
                            for k in range(0, len(inputs), batch)], 1)
    result[f"filter_reference_B{batch}_s_per_trial"] = t_f / len(inputs)
    print(f"filter, reference engine, lockstep {batch:3d}: {t_f / len(inputs) * 1e3:.1f} ms/trial")
    for B in lockstep:
        t_b, _ = _best(lambda: [batched_ocbe.ocbe_batch(*filter_args(inputs[k:k + B]))
                                for k in range(0, len(inputs) - B + 1, B)], repeats)
        per = t_b / (len(inputs) // B * B)
        result[f"filter_fast_B{B}_s_per_trial"] = per
        print(f"filter, fast engine,      lockstep {B:3d}: {per * 1e3:.1f} ms/trial "
              f"({t_f / len(inputs) / per:.1f}x the reference engine at {batch})")

    det.run_trial_filter(setup, inputs[0])
    t_s, _ = _best(lambda: [det.run_trial_filter(setup, inp) for inp in inputs[:n_single]], 1)
    result["single_trial_s_per_trial"] = t_s / n_single
    print(f"single-trial OCBE (cislunar.estimation.ocbe): {t_s / n_single * 1e3:.1f} ms/trial")
    return result


if __name__ == "__main__":
    main()
