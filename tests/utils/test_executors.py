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
                                  dashboard_address=":0") as cluster:
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


def _long_task(folder):
    import os
    import time
    from pathlib import Path

    Path(folder, f"start-{os.getpid()}").touch()
    time.sleep(90.0)
    return 1


def test_ctrl_c_inside_open_executor_ends_its_workers_at_once(tmp_path):
    """Leaving the block by KeyboardInterrupt while both workers run a 90-s task: the block is left within 30 s
    (not after the tasks) and no worker process survives.  Synchronised on files the tasks write, not on sleeps."""
    import time

    import psutil

    with pytest.raises(KeyboardInterrupt):
        with open_executor(2) as ex:
            futures = [ex.submit(_long_task, str(tmp_path)) for _ in range(3)]
            end = time.monotonic() + 120
            while len(list(tmp_path.glob("start-*"))) < 2 and time.monotonic() < end:
                time.sleep(0.02)
            pids = set(ex._processes)
            raised = time.monotonic()
            raise KeyboardInterrupt
    left = time.monotonic()
    assert len(list(tmp_path.glob("start-*"))) == 2 and len(pids) == 2
    assert left - raised < 30.0
    alive = [p for p in pids if psutil.pid_exists(p) and psutil.Process(p).status() != psutil.STATUS_ZOMBIE]
    assert not alive, f"workers survived: {alive}"
    assert all(f.done() for f in futures)
