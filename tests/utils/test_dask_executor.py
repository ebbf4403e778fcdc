"""Scale-out on a Dask cluster: ``cislunar.utils.montecarlo`` takes a ``distributed.Client`` as its executor.

A real ``LocalCluster`` with two worker *processes* (so trials, results and failures cross a pickle boundary) must
give results bit-identical to the serial run, in trial order, and report a failing trial with its index and seed.
Skipped only when the optional ``cluster`` extra (``dask[distributed]``) is absent; the bootstrap installs it.
"""


import numpy as np
import pytest

distributed = pytest.importorskip("distributed", reason="the optional 'cluster' extra (dask[distributed]) is absent")

from dask_cluster import local_client  # noqa: E402

from cislunar.utils import montecarlo  # noqa: E402


def _trial(rng, scale):
    """A trial with some linear algebra in it: eigenvalues of a random symmetric matrix, scaled."""
    a = rng.standard_normal((6, 6))
    return scale * np.linalg.eigvalsh(a + a.T)


def _fails_on_seven(rng):
    if rng.bit_generator.seed_seq.spawn_key[-1] == 7:  # trial 7 (its generator is child 7 of the root seed)
        raise ValueError("trial seven is bad")
    return rng.standard_normal()


def _square(task):
    return task * task


def _pid(task):
    import os

    return os.getpid()


@pytest.fixture(scope="module")
def client():
    with local_client(__name__) as cl:
        yield cl


def test_monte_carlo_on_a_dask_cluster_is_bit_identical_to_serial(client):
    serial = montecarlo.run_monte_carlo(_trial, 40, 2026, args=(3.0,), progress=False)
    on_dask = montecarlo.run_monte_carlo(_trial, 40, 2026, args=(3.0,), executor=client, chunk_size=3,
                                         progress=False)
    assert len(on_dask) == 40
    for a, b in zip(serial, on_dask):
        assert np.array_equal(a, b)
    other = montecarlo.run_monte_carlo(_trial, 40, 2027, args=(3.0,), executor=client, progress=False)
    assert not np.array_equal(other[0], on_dask[0])


def test_sweep_on_a_dask_cluster_keeps_task_order(client):
    assert montecarlo.map_tasks(_square, range(25), executor=client, chunk_size=4, progress=False) == \
        [k * k for k in range(25)]
    import os

    pids = set(montecarlo.map_tasks(_pid, range(8), executor=client, progress=False))
    assert os.getpid() not in pids  # the tasks ran in the cluster's worker processes


def test_a_failing_trial_on_a_dask_worker_is_reported_with_its_seed(client):
    with pytest.raises(montecarlo.MonteCarloError) as info:
        montecarlo.run_monte_carlo(_fails_on_seven, 12, 5, executor=client, chunk_size=2, progress=False)
    text = str(info.value)
    assert "7" in text and "SeedSequence" in text and "trial seven is bad" in text
    collected = montecarlo.run_monte_carlo(_fails_on_seven, 12, 5, executor=client, chunk_size=2, progress=False,
                                           on_error="collect")
    assert isinstance(collected[7], montecarlo.TrialFailure)
    assert all(not isinstance(v, montecarlo.TrialFailure) for k, v in enumerate(collected) if k != 7)
    assert collected[3] == montecarlo.trial_rng(5, 3).standard_normal()
