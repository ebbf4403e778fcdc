"""STM propagation for a batch of 256 initial states over one 9:2 NRHO period: this package vs scipy DOP853.

Both sides integrate the state and the 6x6 STM (42 equations per trajectory) to the same accuracy: heyoka's
Taylor method at its default tolerance (1e-15) and ``solve_ivp(method="DOP853")`` with rtol = atol = 1e-13, the
tightest setting at which DOP853 is still well behaved; the final states agree to about 1e-10 (printed).  The
scipy side uses the same analytic Jacobian as the package's cross-check path.  Target: at least 30x.

Then the arc impact check of the OCBE transitions (:func:`cislunar.cr3bp.propagation._check_arcs_outside_primaries`)
on the batched OCBE's workload: 128 arcs near the 9:2 NRHO over one period, 2-hour epochs cut into sub-grids of 9
points (15 minutes), one call per epoch interval, CPU time of the same process, three paths:

* ``heuristic``: the check before 2026-11-26d, kept here verbatim as :func:`legacy_arc_check` (a 17-point test on
  the cubic Hermite interpolant of every interval behind a cheap screen; not a bound on the true arc: it misses a
  7.8-hour interval through a perilune 584 km under the lunar surface, see ``tests/cr3bp/test_propagation.py``);
* ``rigorous``: today's check (the fall-time bound from Jacobi's integral, one-piece screen then 16 pieces);
* ``rigorous, unscreened``: the 16-piece bound on every interval (``screen=False``; the same decisions).

The re-propagated sub-intervals of each are counted (the heuristic's and the bound's need not coincide).  Run with
``python -m benchmarks propagation``.
"""

import time

import numpy as np

from cislunar.cr3bp import orbits, propagation
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.cr3bp.propagation import default_threads, propagate, propagate_scipy, propagate_stm

#: Hermite sample points of :func:`legacy_arc_check` (fraction of a grid interval).
_HERMITE_S = np.linspace(0.0, 1.0, 17)[:, None, None]


def _norm3(a):
    return np.sqrt(a[..., 0] * a[..., 0] + a[..., 1] * a[..., 1] + a[..., 2] * a[..., 2])


def legacy_arc_check(system, t, states, tol=propagation.DEFAULT_TOL, *, first=0, screen=True):
    """The arc impact check of the OCBE transitions before 2026-11-26d (the "before" path of this benchmark).

    A heuristic: an interval whose cubic Hermite interpolant, sampled at 17 points, comes within ``R + h v_max / 2``
    of a primary's centre is re-propagated with the impact events of ``propagate``; ``screen`` skips the sampling
    where the Hermite-spread bound already shows the 17-point test cannot flag the interval.  Verbatim copy.
    """
    if t.size < 2:
        return
    X = states if states.ndim == 3 else states[:, None, :]
    h = np.diff(t)[:, None]
    r0, r1, v0, v1 = X[:-1, :, :3], X[1:, :, :3], X[:-1, :, 3:], X[1:, :, 3:]
    if screen:
        spread = _norm3(r1 - r0) + 4.0 / 27.0 * np.abs(h) * (_norm3(v0) + _norm3(v1))
        reach = 0.5 * np.abs(h) * np.maximum(_norm3(v0), _norm3(v1))
        cand = np.zeros(spread.shape, dtype=bool)
        for centre, radius in ((system.secondary_position, system.secondary_radius),
                               (system.primary_position, system.primary_radius)):
            clear = np.maximum(_norm3(r0 - centre), _norm3(r1 - centre)) - spread
            cand |= clear <= radius + reach + 1e-9
        ks, bs = np.nonzero(cand)
        if ks.size == 0:
            return
    else:
        ks, bs = np.nonzero(np.ones(h.shape[:1] + X.shape[1:2], dtype=bool))
    hk = h[ks]
    a0, a1, w0, w1 = r0[ks, bs], r1[ks, bs], v0[ks, bs], v1[ks, bs]
    s = _HERMITE_S
    h00, h10, h01, h11 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s, -2 * s**3 + 3 * s**2, s**3 - s**2
    p = h00 * a0 + h10 * hk * w0 + h01 * a1 + h11 * hk * w1
    reach = 0.5 * hk[:, 0] * np.maximum(np.linalg.norm(w0, axis=-1), np.linalg.norm(w1, axis=-1))
    near = np.zeros(ks.shape, dtype=bool)
    for centre, radius in ((system.secondary_position, system.secondary_radius),
                           (system.primary_position, system.primary_radius)):
        d = np.min(np.linalg.norm(p - centre, axis=-1), axis=0)
        near |= d <= radius + reach
    for k, b in zip(ks[near], bs[near]):
        grid = np.array([t[k], t[k + 1]])
        try:
            propagation._propagate_chunk(system, X[k, b][None], grid, 0, tol, 1, True, None)
        except propagation.ImpactError as exc:
            raise propagation.ImpactError(exc.body, exc.time, None if states.ndim == 2 else first + int(b),
                                          exc.state, detail="between grid points") from None


def arc_check(n_arcs: int = 128, n_epochs: int = 79, n_sub: int = 9, repeats: int = 3, seed: int = 0) -> dict:
    """The heuristic arc check before 2026-11-26d against today's rigorous one, screened and unscreened, on
    OCBE-shaped sub-grids (CPU seconds, best of ``repeats``, the paths alternating)."""
    rng = np.random.default_rng(seed)
    nrho = orbits.nrho_9_2(em)
    X0 = nrho.x0 + 1e-5 * rng.standard_normal((n_arcs, 6))
    t = np.linspace(0.0, nrho.period, n_epochs)
    x = propagate(em, X0, t).x
    subs = [(g, np.moveaxis(propagate(em, x[:, n], g).x, 0, 1))
            for n, g in enumerate(np.linspace(t[:-1], t[1:], n_sub, axis=1))]
    paths = {"heuristic": lambda g, ref: legacy_arc_check(em, g, ref),
             "rigorous": lambda g, ref: propagation._check_arcs_outside_primaries(em, g, ref),
             "rigorous, unscreened": lambda g, ref: propagation._check_arcs_outside_primaries(em, g, ref,
                                                                                              screen=False)}
    cpu = {name: [] for name in paths}
    kept = {}

    def run(name):
        chunk, calls = propagation._propagate_chunk, []
        propagation._propagate_chunk = lambda *a: calls.append(tuple(a[2])) or chunk(*a)
        try:
            c0 = time.process_time()
            for g, ref in subs:
                paths[name](g, ref)
            cpu[name].append(time.process_time() - c0)
            kept[name] = calls
        finally:
            propagation._propagate_chunk = chunk

    for _ in range(repeats):
        for name in paths:
            run(name)
    best = {name: min(c) for name, c in cpu.items()}
    assert kept["rigorous"] == kept["rigorous, unscreened"]  # the screen changes no decision
    per = n_arcs * (n_epochs - 1)
    print(f"arc impact check, {n_arcs} arcs x {n_epochs - 1} epoch intervals x {n_sub - 1} sub-intervals (one 9:2 "
          f"NRHO period), CPU ms per arc-period (best of {repeats}), sub-intervals re-propagated:")
    for name in paths:
        print(f"  {name:22s} {best[name] / n_arcs * 1e3:8.3f} ms  ({best['heuristic'] / best[name]:.2f}x the "
              f"heuristic's speed)  {len(kept[name])} re-propagated")
    return {"arc_heuristic_us_per_interval": best["heuristic"] / per * 1e6,
            "arc_rigorous_us_per_interval": best["rigorous"] / per * 1e6,
            "arc_rigorous_unscreened_us_per_interval": best["rigorous, unscreened"] / per * 1e6,
            "arc_ratio_rigorous_over_heuristic": best["rigorous"] / best["heuristic"],
            "arc_repropagated_heuristic": len(kept["heuristic"]), "arc_repropagated_rigorous": len(kept["rigorous"])}


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
