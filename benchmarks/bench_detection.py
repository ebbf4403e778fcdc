"""Detection Monte Carlo of notebook 10: the path before the batched draws against today's, in one run, one thread.

Each trial is one detection run of notebook 10 at the paper's setting: one period of the 9:2 NRHO from periapsis,
2-hour cadence (79 epochs), L2 angles and rates, quiet-policy maneuver at apoapsis, window tuning f = 0.1, full
OCBE filter and smoother, z from the smoothed control.

* ``old``: the Monte Carlo as it ran before (kept as the test oracle
  ``tests/papers/greaves_scheeres_2021/reference_detection.py``): each trial drawn on its own (magnitude through
  ``scipy.stats.truncnorm.rvs``, truth by three propagations, measurements and hand-off by the tracking module),
  one batched OCBE call per lockstep group of 128 trials, the NEES bookkeeping trial by trial.
* ``new``: :func:`cislunar.papers.greaves_scheeres_2021.detection.run_detection_monte_carlo` (the draws of a lockstep
  group at once: one vectorised inverse CDF, the arc before the burn propagated once and the arcs after it in one
  SIMD batch, the measurements in one call; the NEES of all trials at once).  Same seeds, same trials: the random
  streams are bit-identical, z equal to round-off (largest relative difference printed).
* ``pooled``: many small Monte Carlo runs (the tuning map of notebook 10: one per cell and hypothesis) one after
  the other through ``run_detection_monte_carlo`` against one pooled
  :func:`~cislunar.papers.greaves_scheeres_2021.detection.run_detection_monte_carlos` sweep, whose lockstep groups
  mix runs of the same track with different tunings (results bit-identical, asserted).

* ``arc check``: the Monte Carlo with the arc impact check of the OCBE transitions unscreened (the rigorous
  fall-time bound on every sub-grid interval of every trial, ``screen=False``; ``reference_detection.unscreened_arc_check``)
  against the screened check of :func:`cislunar.cr3bp.propagation._check_arcs_outside_primaries` (today's), run
  alternately in one process on the same trials; results bit-identical (asserted).

* ``lockstep``: the Monte Carlo through the lockstep OCBE loop of 2026-11-26c (16 integrator lanes, the generic
  SRI kernels, Phi_pp integrated: 114 states per trial; ``tests/estimation/reference_lockstep_ocbe.previous_lockstep``)
  against today's (the time-update and smoother arrays assembled in place, Phi_pp = K Phi_xx K^-1: 78 states), alternately in one process on the same trials.  Today's loop with the integrated Phi_pp is bit-identical
  to the previous one (asserted); with Phi_pp formed from Phi_xx the statistics move at round-off (largest relative
  change printed); 32 lanes per integrator instead of 16 is bit-identical (asserted) and timed too.
* ``lead``: the Fig. 22 race (:func:`~cislunar.papers.greaves_scheeres_2021.detection.health_lead_study`) with the
  filter and smoother rerun on every growing arc (``reference_detection.reference_arc_statistics``, the path
  before 2026-11-26d) against one forward pass and one backward pass per arc (``smooth_ends``); the study's
  results bit-identical (asserted).

Then the split of a trial's cost between drawing and filtering on both paths.  Times are CPU seconds of this
process (``time.process_time``, robust on a shared machine; wall seconds are printed too).  Ratios come from one
run; no timed assertion.  Run with ``OMP_NUM_THREADS=1 python -m benchmarks detection``.
"""

import sys
import time
from pathlib import Path

import numpy as np

from cislunar.cr3bp import orbits
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.estimation import batched_ocbe
from cislunar.papers.greaves_scheeres_2021 import detection as det

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "papers" / "greaves_scheeres_2021"))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "estimation"))
from reference_detection import (  # the test oracles, not part of the package
    reference_arc_statistics,
    reference_draw_trial,
    reference_monte_carlo,
    unscreened_arc_check,
)
from reference_lockstep_ocbe import previous_lockstep

_STATS = ("z", "z_step", "nees_mean_fwd", "nees_mean_smooth", "nees_over_fwd", "nees_over_smooth")


def _timed(fn):
    c0, w0 = time.process_time(), time.perf_counter()
    out = fn()
    return time.process_time() - c0, time.perf_counter() - w0, out


def arc_check(setup, pol, n_trials: int, seed: int, batch: int = 8, repeats: int = 2) -> dict:
    """The Monte Carlo with the unscreened arc impact check (before) against the screened one (today's), CPU
    seconds per trial, alternating ``repeats`` times (the smaller of each side is kept); z bit-identical."""
    def run():
        return det.run_detection_monte_carlo(setup, pol, n_trials, seed, batch_size=batch, progress=False)

    c_old, c_new = [], []
    for _ in range(repeats):
        with unscreened_arc_check():
            c, _, old = _timed(run)
        c_old.append(c)
        c, _, new = _timed(run)
        c_new.append(c)
        for name in ("z", "z_step", "nees_mean_fwd", "nees_mean_smooth", "nees_over_fwd", "nees_over_smooth"):
            assert np.array_equal(getattr(old, name), getattr(new, name)), name
    old_ms, new_ms = min(c_old) / n_trials * 1e3, min(c_new) / n_trials * 1e3
    print(f"arc impact check, {n_trials} trials (lockstep {min(det.LOCKSTEP_TRIALS, n_trials)}): unscreened "
          f"{old_ms:.2f} ms/trial, screened {new_ms:.2f} ms/trial (CPU, best of {repeats}), speed-up "
          f"{old_ms / new_ms:.3f}x; every detection statistic bit-identical")
    return {"arc_unscreened_ms_per_trial": old_ms, "arc_screened_ms_per_trial": new_ms,
            "arc_speedup": old_ms / new_ms}


def lockstep(setup, pol, n_trials: int, seed: int, batch: int = 8, repeats: int = 2) -> dict:
    """The Monte Carlo through the lockstep loop of 2026-11-26c against today's, CPU seconds per trial, alternating
    ``repeats`` times (the smaller of each kept): today's with the integrated costate block (114 states; every
    statistic bit-identical, asserted), today's default (Phi_pp from Phi_xx, 78 states; largest relative change of
    each statistic printed) and that with 32 lanes instead of 16."""
    def run():
        return det.run_detection_monte_carlo(setup, pol, n_trials, seed, batch_size=batch, progress=False)

    lanes = batched_ocbe._LANES
    variants = {"previous": ({}, previous_lockstep), "today, 114 states": ({"_COSTATE_BLOCK": True}, None),
                "today": ({}, None), "today, 32 lanes": ({"_LANES": 32}, None)}
    times = {k: [] for k in variants}
    out = {}
    for _ in range(repeats):
        for name, (patch, ctx) in variants.items():
            saved = {k: getattr(batched_ocbe, k) for k in patch}
            for k, v in patch.items():
                setattr(batched_ocbe, k, v)
            try:
                if ctx is not None:
                    with ctx():
                        c, _, out[name] = _timed(run)
                else:
                    c, _, out[name] = _timed(run)
            finally:
                for k, v in saved.items():
                    setattr(batched_ocbe, k, v)
            times[name].append(c)
        for name in _STATS:
            assert np.array_equal(getattr(out["previous"], name), getattr(out["today, 114 states"], name)), name
            assert np.array_equal(getattr(out["today"], name), getattr(out["today, 32 lanes"], name)), name
    assert batched_ocbe._LANES == lanes
    old, new = out["previous"], out["today"]
    rel = {name: float(np.max(np.abs(getattr(new, name) - getattr(old, name)) / np.maximum(
        np.abs(getattr(old, name)), 1e-300))) for name in _STATS}
    ms = {k: min(v) / n_trials * 1e3 for k, v in times.items()}
    print(f"lockstep loop, {n_trials} trials (lockstep {min(det.LOCKSTEP_TRIALS, n_trials)}), CPU ms/trial, best of "
          f"{repeats}: previous {ms['previous']:.2f}; today with the integrated Phi_pp {ms['today, 114 states']:.2f} "
          f"({ms['previous'] / ms['today, 114 states']:.3f}x, bit-identical); today {ms['today']:.2f} "
          f"({ms['previous'] / ms['today']:.3f}x); today with 32 lanes per integrator instead of 16 "
          f"{ms['today, 32 lanes']:.2f} (speed relative to 16: {ms['today'] / ms['today, 32 lanes']:.3f}x, "
          f"bit-identical)")
    print("  today (Phi_pp from Phi_xx) against previous, largest relative change: "
          + ", ".join(f"{k} {v:.1e}" for k, v in rel.items()))
    return {"lockstep_previous_ms_per_trial": ms["previous"], "lockstep_114_ms_per_trial": ms["today, 114 states"],
            "lockstep_today_ms_per_trial": ms["today"], "lockstep_32_lanes_ms_per_trial": ms["today, 32 lanes"],
            "lockstep_speedup": ms["previous"] / ms["today"], "lockstep_max_rel_dz": rel["z"]}


def lead(setup, n_h0: int = 40, n_h1: int = 12, magnitudes=(0.05, 0.5), seed: int = 0) -> dict:
    """The Fig. 22 race with the filter rerun on every growing arc (before) against one forward pass and a backward
    pass per arc (today's), CPU seconds; the study's results bit-identical."""
    def run():
        return det.health_lead_study(setup, magnitudes, n_h0, n_h1, [seed, 60], horizon_hours=24.0)

    today = det._arc_statistics
    det._arc_statistics = reference_arc_statistics
    try:
        c_old, _, old = _timed(run)
    finally:
        det._arc_statistics = today
    c_new, _, new = _timed(run)
    for f in old.__dataclass_fields__:
        assert np.array_equal(getattr(old, f), getattr(new, f)), f
    n = 2 * n_h0 + len(magnitudes) * n_h1
    print(f"Fig. 22 race, {n} runs over {new.delay_hours.size} horizon epochs: filter rerun on every arc "
          f"{c_old:.2f} s, one forward pass {c_new:.2f} s (CPU), speed-up {c_old / c_new:.2f}x; results bit-identical")
    return {"lead_rerun_s": c_old, "lead_one_pass_s": c_new, "lead_speedup": c_old / c_new}


def main(n_trials: int = 256, batch: int = 8, n_cells: int = 12, n_cell_trials: int = 24, seed: int = 0) -> dict:
    pol = det.QUIET_POLICY
    nrho = orbits.nrho_9_2(em)
    setup = det.make_setup(em, nrho, 0.1 * det.window_control_weight(pol), 1e-18)
    # compile every integrator outside the timings
    det.run_detection_monte_carlo(setup, pol, 2 * batch, seed + 1, batch_size=batch, progress=False)
    reference_monte_carlo(setup, pol, 2 * batch, seed + 1, batch)

    result = {"n_trials": n_trials, "batch_size": batch, "lockstep_trials": det.LOCKSTEP_TRIALS}
    result.update(lockstep(setup, pol, max(n_trials, 4 * det.LOCKSTEP_TRIALS), seed + 5, batch))
    result.update(lead(setup))
    result.update(arc_check(setup, pol, max(n_trials, 4 * det.LOCKSTEP_TRIALS), seed + 4, batch))
    c_old, w_old, old = _timed(lambda: reference_monte_carlo(setup, pol, n_trials, seed, batch))
    c_new, w_new, new = _timed(lambda: det.run_detection_monte_carlo(setup, pol, n_trials, seed, batch_size=batch,
                                                                     progress=False))
    z_old = np.array([r.z_m_s for r in old])
    mag_old = np.array([r.magnitude_m_s for r in old])
    assert np.array_equal(mag_old, new.magnitude)  # the same trials
    result.update(old_ms_per_trial=c_old / n_trials * 1e3, new_ms_per_trial=c_new / n_trials * 1e3,
                  mc_speedup=c_old / c_new, mc_max_rel_dz=float(np.max(np.abs(new.z / z_old - 1))))
    print(f"Monte Carlo, {n_trials} trials (quiet H1), batch_size {batch}, lockstep {det.LOCKSTEP_TRIALS}: old "
          f"{c_old / n_trials * 1e3:.2f} ms/trial, new {c_new / n_trials * 1e3:.2f} ms/trial (CPU), speed-up "
          f"{c_old / c_new:.2f}x (wall {w_old / n_trials * 1e3:.1f} vs {w_new / n_trials * 1e3:.1f} ms/trial); "
          f"max |dz/z| {result['mc_max_rel_dz']:.1e}")

    # drawing alone, per trial: one at a time against one lockstep group at once
    rngs = np.random.default_rng(seed + 2).spawn(128)
    c_d_old, _, _ = _timed(lambda: [reference_draw_trial(np.random.default_rng(r.bit_generator.seed_seq), setup, pol)
                                    for r in rngs])
    c_d_new, _, _ = _timed(lambda: det.draw_trials([np.random.default_rng(r.bit_generator.seed_seq) for r in rngs],
                                                   setup, pol))
    result.update(draw_old_ms_per_trial=c_d_old / 128 * 1e3, draw_new_ms_per_trial=c_d_new / 128 * 1e3)
    print(f"drawing 128 burn trials (truth, measurements, hand-off): old {c_d_old / 128 * 1e3:.2f} ms/trial, new "
          f"{c_d_new / 128 * 1e3:.3f} ms/trial ({c_d_old / c_d_new:.0f}x); the filter and bookkeeping are the rest")

    # many small runs (tuning-map cells): one after the other against one pooled sweep
    factors = np.geomspace(0.03, 1.0, n_cells // 2)
    setups = [det.make_setup(em, nrho, f * det.window_control_weight(pol), 1e-18) for f in factors]
    jobs = [(s, p, n_cell_trials, [seed, 3, i, h]) for i, s in enumerate(setups) for h, p in enumerate((None, pol))]
    c_seq, w_seq, seq = _timed(lambda: [det.run_detection_monte_carlo(*j, batch_size=batch, progress=False)
                                        for j in jobs])
    c_pool, w_pool, pooled = _timed(lambda: det.run_detection_monte_carlos(jobs, batch_size=batch))
    for a, b in zip(seq, pooled):
        assert np.array_equal(a.z, b.z) and np.array_equal(a.nees_mean_fwd, b.nees_mean_fwd)
    n_small = len(jobs) * n_cell_trials
    result.update(small_runs=len(jobs), small_sequential_ms_per_trial=c_seq / n_small * 1e3,
                  small_pooled_ms_per_trial=c_pool / n_small * 1e3, pooled_speedup=c_seq / c_pool)
    print(f"{len(jobs)} runs of {n_cell_trials} trials (6 tunings x H0/H1, one track): one after the other "
          f"{c_seq / n_small * 1e3:.2f} ms/trial, pooled {c_pool / n_small * 1e3:.2f} ms/trial (CPU), "
          f"{c_seq / c_pool:.2f}x (wall {w_seq:.1f} vs {w_pool:.1f} s); results bit-identical")
    return result


if __name__ == "__main__":
    main()
