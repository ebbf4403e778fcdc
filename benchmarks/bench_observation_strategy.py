"""Notebook 09's Monte Carlo (observation strategy, regime map): single-trial OCBE vs the batched OCBE, in one run.

Each trial is one run of :func:`cislunar.papers.greaves_scheeres_2021.tracking.filter_trial`: one period from
apoapsis, L2 observer, the forward SRI OCBE (filter only, 2 sub-grid points, tolerance 1e-13) and its NEES summary.

* ``single``: the path notebook 09 took before, one :func:`cislunar.estimation.ocbe.ocbe_filter_smoother` per trial
  (12x12 variational integrator), trials through ``run_monte_carlo`` serially;
* ``batched``: the path it takes now, :func:`cislunar.papers.greaves_scheeres_2021.observation_strategy.strategy_study`'s
  tasks (:func:`tracking.filter_trials`: the same draws, all trials of a cell in one lockstep through
  :func:`cislunar.estimation.batched_ocbe.ocbe_batch`, filter only, failing trials flagged).

Both see the same seeds; the benchmark checks that every run is flagged alike and prints the largest relative
difference of the mean NEES.  Cells: the 9:2 NRHO at 2 h with angles and rates (20 runs, as a full-mode cell), at
12 h angles only (20 runs), at 10 min (4 runs, as the 1-min cells: many short intervals), and a regime-map group
(angles only, 12 h, the hand-offs 10 km and 10,000 km, 10 runs each: half the runs diverge).  Ratios come from one
run (the machine may be shared); no timed assertion.

:func:`sri_sets` (also run by :func:`main`): notebook 09's SRI / covariance-form ladder (Section 5d) filters M = 50
measurement sets of the linearised 9:2 NRHO in SRI form; ``per set`` runs
:func:`cislunar.estimation.srif.filter_smoother` once per set (the path first written), ``columns`` runs
:func:`cislunar.estimation.srif.filter_many` once with the sets as information-vector columns (the path the notebook
takes); the largest difference of the estimates is printed.  Run with ``OMP_NUM_THREADS=1 python -m benchmarks
observation_strategy``.
"""

import time

import numpy as np

from cislunar.cr3bp import orbits
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.papers.greaves_scheeres_2021 import observation_strategy as obs
from cislunar.papers.greaves_scheeres_2021 import tracking
from cislunar.utils.montecarlo import run_monte_carlo

Q_QUIET = 1e-20 * em.time_unit_s**3 / em.length_unit_km**2  # notebook 09's control weight, LU^2/TU^3


def _cells():
    nrho = orbits.nrho_9_2(em)
    return [("9:2 NRHO 2 h, angles + rates", tracking.make_scenario(em, nrho, 2.0, start="apoapsis"), [1.0], 20),
            ("9:2 NRHO 12 h, angles only", tracking.make_scenario(em, nrho, 12.0, start="apoapsis", rates=False),
             [1.0], 20),
            ("9:2 NRHO 10 min, angles + rates", tracking.make_scenario(em, nrho, 10 / 60, start="apoapsis"), [1.0], 4),
            ("map group 12 h, hand-off 10 + 10,000 km", tracking.make_scenario(em, nrho, 12.0, start="apoapsis",
                                                                               rates=False), [1.0, 1000.0], 10)]


def main(seed: int = 0) -> dict:
    cells = _cells()
    # compile every integrator outside the timings (the single-trial one and each lockstep size)
    for _, scn, hs, n in cells:
        tracking.filter_trial(np.random.default_rng(1), scn, Q_QUIET)
        obs._run_sets([(scn, [((seed, 99), i, h) for h in hs for i in range(n)])], Q_QUIET, None, "warm", progress=False)
    result = {}
    t_single = t_batched = n_all = 0
    for k, (label, scn, hs, n) in enumerate(cells):
        draws = [((seed, k, ih), i, h) for ih, h in enumerate(hs) for i in range(n)]
        t0 = time.perf_counter()
        old = [r for ih, h in enumerate(hs)
               for r in run_monte_carlo(tracking.filter_trial, n, (seed, k, ih), args=(scn, Q_QUIET),
                                        kwargs={"handoff_scale": h}, progress=False)]
        t1 = time.perf_counter()
        new = obs._run_sets([(scn, draws)], Q_QUIET, None, "batched", progress=False)[0]
        t2 = time.perf_counter()
        same = all(a.diverged == b.diverged and a.first_inconsistent_epoch == b.first_inconsistent_epoch
                   and (a.failure == "") == (b.failure == "") for a, b in zip(old, new))
        rel = max((abs(b.nees_mean / a.nees_mean - 1) for a, b in zip(old, new) if not a.failure), default=0.0)
        m = len(draws)
        print(f"{label:>42}: {m:3d} runs, {scn.t.size:4d} epochs | single {1e3 * (t1 - t0) / m:7.1f} ms/run, "
              f"batched {1e3 * (t2 - t1) / m:6.1f} ms/run, ratio {(t1 - t0) / (t2 - t1):5.1f}x | flags identical "
              f"{same}, diverged {sum(a.diverged for a in old)}/{m}, NEES rel. diff <= {rel:.1e}")
        result[label] = {"runs": m, "single_s": t1 - t0, "batched_s": t2 - t1, "identical_flags": same,
                         "nees_rel_diff": rel}
        t_single, t_batched, n_all = t_single + t1 - t0, t_batched + t2 - t1, n_all + m
    print(f"{'all cells':>42}: {n_all:3d} runs | single {t_single:.1f} s, batched {t_batched:.1f} s, ratio "
          f"{t_single / t_batched:.1f}x")
    result["ratio"] = t_single / t_batched
    result["sri_sets"] = sri_sets(seed)
    return result


def sri_sets(seed: int = 0, n_sets: int = 50) -> dict:
    """Per-set SRI filters against one multi-column SRI filter on notebook 09's linear problem (ratio)."""
    from cislunar.estimation import srif
    from cislunar.papers.greaves_scheeres_2021 import custody

    pb = custody.linear_problem(em, orbits.nrho_9_2(em))
    truth, ys, x0 = pb.simulate(np.random.default_rng(seed), n_sets)
    Hs = [H if m else np.zeros((0, 6)) for H, m in zip(pb.Hs, pb.measured)]
    covs, eyes = [pb.meas_cov] * pb.t.size, [np.eye(6)] * (pb.t.size - 1)
    t0 = time.perf_counter()
    old = np.array([srif.filter_smoother(x0[j], pb.P0, pb.Phis, Hs, list(ys[j]), covs, eyes, list(pb.Qs),
                                         smooth=False).x_filt for j in range(n_sets)])
    t1 = time.perf_counter()
    new = srif.filter_many(x0, pb.P0, pb.Phis, Hs, ys, covs, eyes, list(pb.Qs))[0]
    t2 = time.perf_counter()
    diff = float(np.max(np.abs(new - old)) / np.max(np.abs(old)))
    print(f"{'SRI ladder, ' + str(n_sets) + ' sets x ' + str(pb.t.size) + ' epochs':>42}: per set {t1 - t0:.2f} s, "
          f"columns {t2 - t1:.3f} s, ratio {(t1 - t0) / (t2 - t1):.0f}x | max relative difference {diff:.1e}")
    return {"per_set_s": t1 - t0, "columns_s": t2 - t1, "ratio": (t1 - t0) / (t2 - t1), "max_rel_diff": diff}


if __name__ == "__main__":
    main()
