"""Monte Carlo results do not depend on the executor or the chunking."""

from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor

import numpy as np
import pytest

from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.utils.montecarlo import map_tasks, run_monte_carlo, spawn_rngs


def _trial(rng, scale):
    return float(scale * rng.standard_normal())


def _dispersed_final_x(rng, x0, t_final):
    from cislunar.cr3bp.propagation import propagate

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


def _normal_pair(rng, scale):
    return (float(scale * rng.standard_normal()), float(rng.uniform()))


def _vectorized_pairs(rngs, scale, fail_on=None):
    """Vectorized trial: draws per generator (in order), one result each; raises if a draw hits ``fail_on``."""
    out = [_normal_pair(r, scale) for r in rngs]
    if fail_on is not None and any(v[1] < fail_on for v in out):
        raise ValueError("injected failure")
    return out


def test_vectorized_trials_equal_per_trial_calls_whatever_the_executor():
    per_trial = run_monte_carlo(_normal_pair, 23, seed=4, args=(3.0,), progress=False)
    serial = run_monte_carlo(_vectorized_pairs, 23, seed=4, args=(3.0,), chunk_size=5, progress=False,
                             vectorized=True)
    with ThreadPoolExecutor(2) as pool:
        threaded = run_monte_carlo(_vectorized_pairs, 23, seed=4, args=(3.0,), executor=pool, chunk_size=4,
                                   progress=False, vectorized=True)
    with ProcessPoolExecutor(2) as pool:
        procs = run_monte_carlo(_vectorized_pairs, 23, seed=4, args=(3.0,), executor=pool, chunk_size=7,
                                progress=False, vectorized=True)
    assert per_trial == serial == threaded == procs


def test_a_failing_vectorized_chunk_is_rerun_per_trial_to_name_the_trial():
    from cislunar.utils.montecarlo import MonteCarloError, TrialFailure

    ref = run_monte_carlo(_normal_pair, 20, seed=9, args=(1.0,), progress=False)
    bad = [i for i, v in enumerate(ref) if v[1] < 0.15]
    assert bad  # the seed has at least one trial that fails below
    res = run_monte_carlo(_vectorized_pairs, 20, seed=9, args=(1.0, 0.15), chunk_size=6, progress=False,
                          vectorized=True, on_error="collect")
    assert [i for i, v in enumerate(res) if isinstance(v, TrialFailure)] == bad
    assert all(res[i] == ref[i] for i in range(20) if i not in bad)  # the others kept, with their own seeds
    with pytest.raises(MonteCarloError) as info:
        run_monte_carlo(_vectorized_pairs, 20, seed=9, args=(1.0, 0.15), chunk_size=6, progress=False,
                        vectorized=True)
    assert info.value.trial_index == bad[0] and f"spawn_key=({bad[0]},)" in info.value.seed
    assert all(info.value.completed[i] == ref[i] for i in info.value.completed)
    with pytest.raises(MonteCarloError, match="one result per generator"):
        run_monte_carlo(lambda rngs: [], 3, seed=1, progress=False, vectorized=True)
    with pytest.raises(ValueError, match="vectorized"):
        run_monte_carlo(_normal_pair, 3, seed=1, args=(1.0,), progress=False, vectorized=1)
