"""Invariant-torus solve time against the number of circle points N, and batched vs per-point STM propagation.

For each N the benchmark times

* ``one solve``: one Gauss-Newton correction of the 160-km torus about the 9:2 NRHO (the paper's 215-km mean-range
  member) from a guess whose circle is perturbed by 1e-6 (about 400 m), and
* ``from orbit``: seed at 2 km from the centre eigenvector and continue in 25-km steps to 160 km (8 solves),

and, for the dominant cost of each Gauss-Newton iteration (N states and STMs over one period), heyoka's batch
propagation of all N points at once against a loop over the points; finally the time to select the 215-km
mean-range member from scratch.  Ratios come from one run; nothing is asserted.
Run with ``python -m benchmarks torus``.
"""

import time
from dataclasses import replace

import numpy as np

from cislunar.cr3bp import torus as tm
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.cr3bp.orbits import nrho_9_2
from cislunar.cr3bp.propagation import propagate_stm


def _timed(fn, repeat: int = 3):
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def main(ns=(7, 11, 15, 21, 25, 31, 41), size_km: float = 160.0) -> dict:
    orbit = nrho_9_2(em)
    ref = tm.torus_from_orbit(orbit, 41, size_km)
    propagate_stm(em, ref.circle[:4], orbit.period)  # compile outside the timing (cached afterwards)
    propagate_stm(em, ref.circle[0], orbit.period)
    rows = []
    print(f"torus about the 9:2 NRHO, ring size {size_km:g} km (RMS), stroboscopic time = NRHO period")
    print(f"{'N':>4} {'one solve s':>12} {'iters':>6} {'from orbit s':>13} {'batch STM s':>12} {'loop STM s':>11} "
          f"{'loop/batch':>10} {'mid-point residual':>19}")
    for n in ns:
        guess = replace(ref, circle=ref.circle_at(2 * np.pi * np.arange(n) / n) * (1 + 1e-6), residuals=())
        t_one, solved = _timed(lambda g=guess: tm.solve_torus(g, fix={"size_km": size_km}))
        t_orbit, _ = _timed(lambda n=n: tm.torus_from_orbit(orbit, n, size_km), repeat=1)
        t_batch, _ = _timed(lambda s=solved: propagate_stm(em, s.circle, orbit.period))
        t_loop, _ = _timed(lambda s=solved: [propagate_stm(em, x, orbit.period) for x in s.circle])
        err = solved.invariance_error()
        rows.append({"N": n, "one_solve_s": t_one, "iterations": len(solved.residuals) - 1,
                     "from_orbit_s": t_orbit, "batch_stm_s": t_batch, "loop_stm_s": t_loop,
                     "loop_over_batch": t_loop / t_batch, "midpoint_residual": err})
        print(f"{n:>4} {t_one:>12.3f} {len(solved.residuals) - 1:>6d} {t_orbit:>13.3f} {t_batch:>12.4f} "
              f"{t_loop:>11.4f} {t_loop / t_batch:>10.1f} {err:>19.2e}")
    t0 = time.perf_counter()
    member, stats = tm.qpo_for_mean_range(orbit, 215.0, N=25)
    t_member = time.perf_counter() - t0
    print(f"215-km mean-range member (N = 25, from the orbit, with the mean-range quadrature): {t_member:.2f} s; "
          f"ring {member.size_km:.3f} km RMS, rho {member.rho:.6f} rad")
    return {"size_km": size_km, "rows": rows, "member_215_s": t_member}


if __name__ == "__main__":
    main()
