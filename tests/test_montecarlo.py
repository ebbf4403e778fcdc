"""Monte Carlo results do not depend on the executor or the chunking."""

from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor

import numpy as np
import pytest

from cislunar.dynamics import EARTH_MOON as em
from cislunar.montecarlo import map_tasks, run_monte_carlo, spawn_rngs


def _trial(rng, scale):
    return float(scale * rng.standard_normal())


def _dispersed_final_x(rng, x0, t_final):
    from cislunar.propagation import propagate

    return propagate(em, np.asarray(x0) + 1e-6 * rng.standard_normal(6), t_final).x[-1, 0]


def test_serial_threads_and_processes_agree():
    serial = run_monte_carlo(_trial, 37, seed=11, args=(2.0,), progress=False)
    with ThreadPoolExecutor(2) as pool:
        threaded = run_monte_carlo(_trial, 37, seed=11, args=(2.0,), executor=pool, chunk_size=5, progress=False)
    with ProcessPoolExecutor(2) as pool:
        procs = run_monte_carlo(_trial, 37, seed=11, args=(2.0,), executor=pool, chunk_size=8, progress=False)
    assert serial == threaded == procs
    assert serial != run_monte_carlo(_trial, 37, seed=12, args=(2.0,), progress=False)
    # trial i uses child i of the seed sequence
    assert serial[5] == 2.0 * spawn_rngs(11, 37)[5].standard_normal()


def test_propagation_trials_through_a_thread_pool():
    x0 = [0.8, 0, 0, 0, 0.5, 0]
    serial = run_monte_carlo(_dispersed_final_x, 6, seed=3, args=(x0, 0.5), progress=False)
    with ThreadPoolExecutor(2) as pool:
        pooled = run_monte_carlo(_dispersed_final_x, 6, seed=3, args=(x0, 0.5), executor=pool, progress=False)
    assert serial == pooled


def test_map_tasks_keeps_order_and_checks_executor():
    with ThreadPoolExecutor(2) as pool:
        assert map_tasks(lambda v: v * v, range(10), executor=pool, progress=False) == [v * v for v in range(10)]
    with pytest.raises(ValueError, match="executor"):
        map_tasks(abs, [1], executor=object(), progress=False)
    with pytest.raises(ValueError, match="n_trials"):
        run_monte_carlo(_trial, 0, seed=1, args=(1.0,))
