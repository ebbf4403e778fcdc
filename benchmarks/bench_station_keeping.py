"""Station-keeping surface of notebook 08: batched (one heyoka batch per arrival time) against a plain loop.

Every maneuver of the surface is a two-burn transfer to the 215-km QPO about the 9:2 NRHO (Newton with the STM) plus
its own SSAT covariance analysis (hourly angles over two days).  The batched path solves all ring angles of one
arrival time together and runs one batched square-root-information covariance analysis for the whole surface; the
loop path solves and analyses one maneuver at a time with the same functions.  Both paths compute the same full
``n`` x ``n`` surface (40 x 40 = 1600 maneuvers by default, the notebook's full-mode size) in one run, and the results
are compared (printed).  Run with ``python -m benchmarks station_keeping``.
"""

import time

import numpy as np

from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.cr3bp.orbits import nrho_9_2
from cislunar.cr3bp.torus import qpo_for_mean_range
from cislunar.papers.greaves_scheeres_2023 import station_keeping as sk


def main(n: int = 40) -> dict:
    hr = 3600.0 / em.time_unit_s
    torus, _ = qpo_for_mean_range(nrho_9_2(em), 215.0)
    theta = 2 * np.pi * (np.arange(n) + 0.5) / n
    t_arr = np.linspace(-12.0, 12.0, n) * hr
    kw = dict(t_burn=-24 * hr, t_final=24 * hr, progress=False)
    sk.station_keeping_surface(em, torus, theta[:2], t_arr[:1], **kw)  # compile outside the timing
    t0 = time.perf_counter()
    batch = sk.station_keeping_surface(em, torus, theta, t_arr, **kw)
    t_batch = time.perf_counter() - t0
    t0 = time.perf_counter()
    loop = sk.station_keeping_surface(em, torus, theta, t_arr, batched=False, **kw)
    t_loop = time.perf_counter() - t0
    diff = float(np.max(np.abs(loop.range_sigma_km / batch.range_sigma_km - 1)))
    m = n * n
    result = {
        "n_maneuvers": m,
        "batched_s": t_batch,
        "batched_per_maneuver_ms": 1e3 * t_batch / m,
        "loop_s": t_loop,
        "loop_per_maneuver_ms": 1e3 * t_loop / m,
        "ratio": t_loop / t_batch,
        "max_relative_difference": diff,
        "max_transfer_miss_lu": float(max(batch.transfer_miss.max(), loop.transfer_miss.max())),
    }
    print(f"station-keeping surface: {n} arrival times x {n} ring angles = {m} maneuvers, each with a "
          f"{batch.t.size}-epoch covariance analysis")
    print(f"  batched:    {t_batch:7.2f} s ({result['batched_per_maneuver_ms']:.2f} ms per maneuver)")
    print(f"  plain loop: {t_loop:7.2f} s ({result['loop_per_maneuver_ms']:.2f} ms per maneuver)")
    print(f"  speed-up of the batched path: {result['ratio']:.1f}x")
    print(f"  loop vs batch max relative difference of sqrt(J_rho): {diff:.1e}; max transfer miss "
          f"{result['max_transfer_miss_lu']:.1e} LU")
    return result


if __name__ == "__main__":
    main()
