"""open_executor: serial, local processes or a Dask client from the WORKERS and SCHEDULER parameters, with the
same Monte Carlo results whichever it is."""

from __future__ import annotations

from concurrent.futures import ProcessPoolExecutor

import numpy as np
import pytest

from cislunar.utils import montecarlo
from cislunar.utils.executors import describe_executor, open_executor


def _trial(rng):
    return float(rng.standard_normal())


def test_serial_and_processes_give_the_same_results():
    with open_executor(1) as ex:
        assert ex is None and describe_executor(ex) == "serial"
        serial = montecarlo.run_monte_carlo(_trial, 12, seed=3, executor=ex, progress=False)
    with open_executor(2) as ex:
        assert isinstance(ex, ProcessPoolExecutor) and describe_executor(ex) == "2 processes"
        pooled = montecarlo.run_monte_carlo(_trial, 12, seed=3, executor=ex, progress=False)
    assert np.array_equal(serial, pooled)


def test_a_dask_scheduler_address_gives_a_client():
    distributed = pytest.importorskip("dask.distributed")
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster:
        with open_executor(1, cluster.scheduler_address) as ex:
            assert describe_executor(ex).startswith("Dask ")
            got = montecarlo.run_monte_carlo(_trial, 6, seed=3, executor=ex, progress=False)
    assert np.array_equal(got, montecarlo.run_monte_carlo(_trial, 6, seed=3, progress=False))


@pytest.mark.parametrize("workers", [0, -1, 1.5, True, "2"])
def test_bad_workers_are_refused_by_name(workers):
    with pytest.raises(ValueError, match="workers"):
        with open_executor(workers):
            pass


def test_bad_scheduler_is_refused_by_name():
    with pytest.raises(TypeError, match="scheduler"):
        with open_executor(1, 8786):
            pass
