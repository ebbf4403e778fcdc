"""STM propagation for a batch of 256 initial states over one 9:2 NRHO period: this package vs scipy DOP853.

Both sides integrate the state and the 6x6 STM (42 equations per trajectory) to the same accuracy: heyoka's
Taylor method at its default tolerance (1e-15) and ``solve_ivp(method="DOP853")`` with rtol = atol = 1e-13, the
tightest setting at which DOP853 is still well behaved; the final states agree to about 1e-10 (printed).  The
scipy side uses the same analytic Jacobian as the package's cross-check path.  Target: at least 30x.

Then the arc impact check of the OCBE transitions (:func:`cislunar.cr3bp.propagation._check_arcs_outside_primaries`)
on the batched OCBE's workload: 128 arcs near the 9:2 NRHO over one period, 2-hour epochs cut into sub-grids of 9
points, one call per epoch interval; unscreened (``screen=False``: the 17-point Hermite test on every sub-interval,
the check before 2026-11-26c) against screened (today's), CPU time, with the decisions compared (the same
re-propagated sub-intervals).  Run with ``python -m benchmarks propagation``.
"""

import time

import numpy as np

from cislunar.cr3bp import orbits, propagation
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.cr3bp.propagation import default_threads, propagate, propagate_scipy, propagate_stm


def arc_check(n_arcs: int = 128, n_epochs: int = 79, n_sub: int = 9, repeats: int = 3, seed: int = 0) -> dict:
    """Screened against unscreened arc impact check on OCBE-shaped sub-grids (CPU seconds, best of ``repeats``)."""
    rng = np.random.default_rng(seed)
    nrho = orbits.nrho_9_2(em)
    X0 = nrho.x0 + 1e-5 * rng.standard_normal((n_arcs, 6))
    t = np.linspace(0.0, nrho.period, n_epochs)
    x = propagate(em, X0, t).x
    subs = [(g, np.moveaxis(propagate(em, x[:, n], g).x, 0, 1))
            for n, g in enumerate(np.linspace(t[:-1], t[1:], n_sub, axis=1))]
    kept = {}

    def run(screen):
        chunk, calls = propagation._propagate_chunk, []
        propagation._propagate_chunk = lambda *a: calls.append(tuple(a[2])) or chunk(*a)
        try:
            c0 = time.process_time()
            for g, ref in subs:
                propagation._check_arcs_outside_primaries(em, g, ref, screen=screen)
            kept[screen] = calls
            return time.process_time() - c0
        finally:
            propagation._propagate_chunk = chunk

    c_old = min(run(False) for _ in range(repeats))
    c_new = min(run(True) for _ in range(repeats))
    assert kept[True] == kept[False]  # the same sub-intervals re-propagated
    per = n_arcs * (n_epochs - 1)
    print(f"arc impact check, {n_arcs} arcs x {n_epochs - 1} epoch intervals x {n_sub - 1} sub-intervals (one 9:2 "
          f"NRHO period): unscreened {c_old / n_arcs * 1e3:.3f} ms per arc-period, screened "
          f"{c_new / n_arcs * 1e3:.3f} ms ({c_old / c_new:.1f}x); {len(kept[True])} sub-intervals re-propagated "
          f"by both")
    return {"arc_unscreened_us_per_interval": c_old / per * 1e6, "arc_screened_us_per_interval": c_new / per * 1e6,
            "arc_speedup": c_old / c_new, "arc_repropagated": len(kept[True])}


def main(n: int = 256, n_scipy: int | None = None, seed: int = 0) -> dict:
    rng = np.random.default_rng(seed)
    nrho = orbits.nrho_9_2(em)
    X0 = nrho.x0 + 1e-5 * rng.standard_normal((n, 6))  # a 4 km / 4 m/s cloud around the 9:2 NRHO
    grid = np.array([0.0, nrho.period])
    propagate_stm(em, X0[:4], grid)  # compile outside the timing (cached afterwards)
    propagate_stm(em, X0[0], grid)
    t0 = time.perf_counter()
    ours = propagate_stm(em, X0, grid)
    t_ours = time.perf_counter() - t0
    threads = default_threads()
    t0 = time.perf_counter()
    ours_mt = propagate_stm(em, X0, grid, threads=threads)
    t_ours_mt = time.perf_counter() - t0
    n_scipy = n if n_scipy is None else n_scipy
    t0 = time.perf_counter()
    ref = [propagate_scipy(em, X0[i], grid, stm=True, rtol=1e-13, atol=1e-13) for i in range(n_scipy)]
    t_scipy = (time.perf_counter() - t0) * n / n_scipy
    err = max(np.max(np.abs(r.x[-1] - ours.x[i, -1])) for i, r in enumerate(ref))
    assert np.array_equal(ours.x, ours_mt.x)
    result = {
        "n": n,
        "heyoka_s": t_ours,
        "heyoka_threads": threads,
        "heyoka_mt_s": t_ours_mt,
        "scipy_s": t_scipy,
        "ratio": t_scipy / t_ours,
        "ratio_mt": t_scipy / t_ours_mt,
        "max_state_difference": err,
    }
    print(f"{n} STMs over one 9:2 NRHO period ({nrho.period_days:.3f} d)")
    print(f"  cislunar (heyoka batch, 1 thread): {t_ours:8.3f} s")
    print(f"  cislunar (heyoka batch, {threads} threads): {t_ours_mt:8.3f} s")
    print(f"  scipy DOP853 (rtol=atol=1e-13):     {t_scipy:8.3f} s" + ("" if n_scipy == n else f" (from {n_scipy})"))
    print(f"  speed-up: {result['ratio']:.1f}x single-thread, {result['ratio_mt']:.1f}x threaded (target >= 30x)")
    print(f"  max |state difference| at the final time: {err:.2e}")
    result.update(arc_check())
    return result


if __name__ == "__main__":
    main()
