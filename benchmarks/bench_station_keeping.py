"""Station-keeping surface of notebook 08: batched (one heyoka batch per arrival time) against a plain loop.

Every maneuver of the surface is a two-burn transfer to the 215-km QPO about the 9:2 NRHO (Newton with the STM) plus
its own SSAT covariance analysis (hourly angles over two days).  The batched path solves all ring angles of one
arrival time together; the loop path solves and analyses one maneuver at a time with the same functions.  The full
40 x 40 surface is timed batched; the loop runs on a 10 x 10 sub-surface (the loop on 1600 maneuvers would take
minutes) and the per-maneuver times are compared, in one run.  Results agree to round-off (printed).
Run with ``python -m benchmarks station_keeping``.
"""

import time

import numpy as np

from cislunar import station_keeping as sk
from cislunar.dynamics import EARTH_MOON as em
from cislunar.orbits import nrho_9_2
from cislunar.torus import qpo_for_mean_range


def main(n: int = 40, n_loop: int = 10) -> dict:
    hr = 3600.0 / em.time_unit_s
    torus, _ = qpo_for_mean_range(nrho_9_2(em), 215.0)
    theta = 2 * np.pi * (np.arange(n) + 0.5) / n
    t_arr = np.linspace(-12.0, 12.0, n) * hr
    kw = dict(t_burn=-24 * hr, t_final=24 * hr, progress=False)
    sk.station_keeping_surface(em, torus, theta[:2], t_arr[:1], **kw)  # compile outside the timing
    t0 = time.perf_counter()
    full = sk.station_keeping_surface(em, torus, theta, t_arr, **kw)
    t_full = time.perf_counter() - t0
    sub_theta, sub_t = theta[:: n // n_loop][:n_loop], t_arr[:: n // n_loop][:n_loop]
    t0 = time.perf_counter()
    batch_sub = sk.station_keeping_surface(em, torus, sub_theta, sub_t, **kw)
    t_batch_sub = time.perf_counter() - t0
    t0 = time.perf_counter()
    loop_sub = sk.station_keeping_surface(em, torus, sub_theta, sub_t, batched=False, **kw)
    t_loop_sub = time.perf_counter() - t0
    diff = float(np.max(np.abs(loop_sub.range_sigma_km / batch_sub.range_sigma_km - 1)))
    m_full, m_sub = n * n, n_loop * n_loop
    result = {
        "n_maneuvers": m_full,
        "batched_full_s": t_full,
        "batched_per_maneuver_ms": 1e3 * t_full / m_full,
        "batched_sub_s": t_batch_sub,
        "loop_sub_s": t_loop_sub,
        "loop_per_maneuver_ms": 1e3 * t_loop_sub / m_sub,
        "ratio_sub": t_loop_sub / t_batch_sub,
        "ratio_per_maneuver": (t_loop_sub / m_sub) / (t_full / m_full),
        "max_relative_difference": diff,
        "max_transfer_miss_lu": float(full.transfer_miss.max()),
    }
    print(f"station-keeping surface: {n} arrival times x {n} ring angles = {m_full} maneuvers, each with a "
          f"{full.t.size}-epoch covariance analysis")
    print(f"  batched, full {n}x{n}:      {t_full:7.2f} s ({result['batched_per_maneuver_ms']:.2f} ms per maneuver)")
    print(f"  batched, {n_loop}x{n_loop} sub-surface: {t_batch_sub:7.2f} s")
    print(f"  plain loop, {n_loop}x{n_loop}:       {t_loop_sub:7.2f} s ({result['loop_per_maneuver_ms']:.2f} ms per maneuver)")
    print(f"  speed-up: {result['ratio_sub']:.1f}x on the same sub-surface, {result['ratio_per_maneuver']:.1f}x per "
          "maneuver against the full batched surface")
    print(f"  loop vs batch max relative difference of sqrt(J_rho): {diff:.1e}; max transfer miss "
          f"{result['max_transfer_miss_lu']:.1e} LU")
    return result


if __name__ == "__main__":
    main()
