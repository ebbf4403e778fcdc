"""Monte Carlo overhead: 20,000 trivial trials serially and through ThreadPoolExecutor(2) and ProcessPoolExecutor(2).

A trivial trial (one uniform draw) measures the scaffolding alone: seeding, chunking, futures, progress.  Trial
``i`` is seeded with child ``i`` of the root ``SeedSequence`` built in O(1) (before issue 11 every chunk spawned
``max(indices) + 1`` children, quadratic in the number of trials: 43x slower through a thread pool than serially).
Target: the thread pool within 2x of the serial time.  The results must be identical on every path (asserted).
Run with ``python -m benchmarks montecarlo``.
"""

import time
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor

from cislunar.utils.montecarlo import run_monte_carlo


def _trivial(rng):
    return rng.random()


def main(n: int = 20_000, seed: int = 0) -> dict:
    t0 = time.perf_counter()
    serial = run_monte_carlo(_trivial, n, seed, progress=False)
    t_serial = time.perf_counter() - t0
    with ThreadPoolExecutor(2) as pool:
        t0 = time.perf_counter()
        threaded = run_monte_carlo(_trivial, n, seed, executor=pool, progress=False)
        t_threads = time.perf_counter() - t0
    with ProcessPoolExecutor(2) as pool:
        pool.submit(abs, 1).result()  # start the workers outside the timing
        t0 = time.perf_counter()
        procs = run_monte_carlo(_trivial, n, seed, executor=pool, progress=False)
        t_procs = time.perf_counter() - t0
    assert serial == threaded == procs
    result = {"n": n, "serial_s": t_serial, "threads_s": t_threads, "processes_s": t_procs,
              "threads_over_serial": t_threads / t_serial, "processes_over_serial": t_procs / t_serial}
    print(f"{n} trivial Monte Carlo trials")
    print(f"  serial:                    {t_serial:7.3f} s")
    print(f"  ThreadPoolExecutor(2):     {t_threads:7.3f} s  ({t_threads / t_serial:.2f}x serial; target <= 2x)")
    print(f"  ProcessPoolExecutor(2):    {t_procs:7.3f} s  ({t_procs / t_serial:.2f}x serial)")
    return result


if __name__ == "__main__":
    main()
