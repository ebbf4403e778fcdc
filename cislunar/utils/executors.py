"""The executor a notebook's Monte Carlo and sweeps run on, from two parameters a reader sets.

Every notebook with a sweep or a Monte Carlo has the parameters ``WORKERS`` (processes on this machine; 1 runs
serially) and ``SCHEDULER`` (the address of a Dask scheduler, e.g. ``"tcp://10.0.0.5:8786"``; empty: none).
:func:`open_executor` turns them into an executor for :func:`cislunar.utils.montecarlo.run_monte_carlo` and
:func:`cislunar.utils.montecarlo.map_tasks` (``None`` for serial runs) and closes it afterwards.  Results do not
depend on the choice: trial *i* always gets child *i* of the root seed.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import time
from concurrent.futures import ProcessPoolExecutor

__all__ = ["open_executor", "describe_executor"]


def open_executor(workers: int = 1, scheduler: str = ""):
    """An executor for ``workers`` local processes, or a Dask client of ``scheduler``; ``None`` when serial.

    Parameters
    ----------
    workers : int
        Local worker processes (>= 1); 1 means serial (no executor).  Ignored when ``scheduler`` is given.
    scheduler : str
        Address of a running Dask scheduler; needs the ``cluster`` extra (``dask[distributed]``).

    Returns
    -------
    context manager
        Entering it gives a ``concurrent.futures.Executor``, a ``dask.distributed.Client`` or ``None``; leaving it
        shuts the pool down or closes the client.  Left by Ctrl-C (``KeyboardInterrupt``), the pool's worker
        processes are terminated at once instead of being waited for.  Arguments are checked when it is called.
    """
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ValueError(f"workers must be an int >= 1 (1 runs serially); got {workers!r}")
    if not isinstance(scheduler, str):
        raise TypeError(f"scheduler must be a str (a Dask scheduler address, or '' for none); got "
                        f"{type(scheduler).__name__}")
    return _executor(workers, scheduler)


@contextlib.contextmanager
def _executor(workers: int, scheduler: str):
    if scheduler.strip():
        try:
            from dask.distributed import Client
        except ImportError:  # pragma: no cover - the cluster extra is installed by the bootstrap
            raise ValueError("scheduler: a Dask address needs the cluster extra (pip install 'cislunar[cluster]')"
                             ) from None
        client = Client(scheduler.strip())
        try:
            yield client
        finally:
            client.close()
        return
    if workers == 1:
        yield None
        return
    # spawn: workers start clean (no copy of the kernel's state, no fork of threads held by heyoka or BLAS)
    pool = ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn"))
    try:
        yield pool
    except KeyboardInterrupt:  # Ctrl-C: end the workers now instead of waiting for the tasks they are running
        _end_process_pool(pool)
        raise
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def _end_process_pool(pool, timeout: float = 5.0) -> None:
    """Terminate the worker processes of a ``ProcessPoolExecutor`` and wait for them (after Ctrl-C).

    A worker process cannot be interrupted from outside, so this is the only prompt way to stop the tasks it is
    running.  Every pending future of the pool then fails with ``BrokenProcessPool`` and the pool cannot be used
    again.  Workers that ignore SIGTERM are killed after ``timeout`` seconds.

    Parameters
    ----------
    pool : concurrent.futures.ProcessPoolExecutor
    timeout : float
        Seconds to wait for the workers to end after SIGTERM before SIGKILL (> 0).
    """
    procs = list((getattr(pool, "_processes", None) or {}).values())
    for proc in procs:
        try:
            proc.terminate()
        except Exception:  # noqa: BLE001 - already gone
            pass
    deadline = time.monotonic() + timeout
    for proc in procs:
        proc.join(timeout=max(0.0, deadline - time.monotonic()))
        if proc.exitcode is None:  # pragma: no cover - a worker that ignored SIGTERM
            proc.kill()
            proc.join(timeout=1.0)


def describe_executor(executor) -> str:
    """A short description for a notebook's output: ``serial``, ``2 processes`` or ``Dask <address>``."""
    if executor is None:
        return "serial"
    if isinstance(executor, ProcessPoolExecutor):
        return f"{executor._max_workers} processes"
    scheduler = getattr(getattr(executor, "scheduler", None), "address", None)
    return f"Dask {scheduler}" if scheduler else type(executor).__name__
