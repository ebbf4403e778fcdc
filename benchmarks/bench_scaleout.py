"""Scale-out of a real study: the detection Monte Carlo of notebook 10 serially, on a 2-process pool and on a
2-worker Dask LocalCluster, in one run.

The quiet policy on the 9:2 NRHO (the paper's training set-up), ``n`` trials.  The three results must be
bit-identical (asserted): trial ``i`` always gets child ``i`` of the root seed.  Reported: wall-clock seconds of
each path (workers started outside the timing) and the ratios to serial.  On a 2-core machine the pool and the
cluster can at best halve the serial time; a cluster of more cores takes the same call with its scheduler
address (notebook parameter ``SCHEDULER``).  Run with ``python -m benchmarks scaleout``.
"""

import time

import numpy as np

from cislunar.cr3bp import orbits
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.papers.greaves_scheeres_2021 import detection as det
from cislunar.utils.executors import open_executor


def _timed(setup, policy, n, seed, executor):
    t0 = time.perf_counter()
    sample = det.run_detection_monte_carlo(setup, policy, n, seed, executor=executor, progress=False)
    return time.perf_counter() - t0, sample


def main(n: int = 512, seed: int = 0) -> dict:
    from dask.distributed import Client, LocalCluster

    policy = det.QUIET_POLICY
    setup = det.make_setup(em, orbits.nrho_9_2(em), det.window_control_weight(policy), 1e-18)
    det.run_detection_monte_carlo(setup, policy, 8, seed, progress=False)  # compile the integrators first
    t_serial, serial = _timed(setup, policy, n, seed, None)
    with open_executor(2) as pool:
        list(pool.map(abs, [1, 2]))  # start the workers outside the timing
        _timed(setup, policy, 8, seed, pool)  # and let them compile their integrators
        t_pool, pooled = _timed(setup, policy, n, seed, pool)
    with LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=None) as cluster, Client(cluster) as client:
        _timed(setup, policy, 8, seed, client)
        t_dask, dasked = _timed(setup, policy, n, seed, client)
    for other in (pooled, dasked):
        assert np.array_equal(serial.z, other.z) and np.array_equal(serial.nees_mean_smooth, other.nees_mean_smooth), "results depend on the executor"
    result = {"n": n, "serial_s": t_serial, "processes_s": t_pool, "dask_s": t_dask,
              "processes_over_serial": t_pool / t_serial, "dask_over_serial": t_dask / t_serial}
    print(f"detection Monte Carlo, {n} trials (quiet policy, 9:2 NRHO); results bit-identical on all three paths")
    print(f"  serial:                 {t_serial:7.2f} s  ({t_serial / n * 1e3:.2f} ms per trial)")
    print(f"  2-process pool:         {t_pool:7.2f} s  ({t_pool / t_serial:.2f}x serial)")
    print(f"  Dask LocalCluster(2):   {t_dask:7.2f} s  ({t_dask / t_serial:.2f}x serial)")
    return result


if __name__ == "__main__":
    main()
