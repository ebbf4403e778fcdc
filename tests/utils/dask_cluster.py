"""One way for the tests to start a Dask ``LocalCluster``: two worker processes of one thread each.

Worker processes cannot import the ``tests`` directory, so the calling test module is registered with cloudpickle
to travel by value (its trial functions are defined there).
"""

from __future__ import annotations

import contextlib
import sys


@contextlib.contextmanager
def local_client(module_name: str, *, silence_logs: int = 40, config: dict | None = None):
    """A ``distributed.Client`` of a fresh two-process ``LocalCluster``, closed on exit.

    Parameters
    ----------
    module_name : str
        ``__name__`` of the test module whose functions the workers must unpickle by value.
    silence_logs : int
        Logging level below which the cluster's messages are dropped.
    config : dict, optional
        Dask configuration set while the cluster starts (e.g. ``{"distributed.scheduler.allowed-failures": 0}``).
    """
    import cloudpickle
    import dask
    import distributed

    cloudpickle.register_pickle_by_value(sys.modules[module_name])
    with dask.config.set(config or {}):
        cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0",
                                           silence_logs=silence_logs)
        client = distributed.Client(cluster)
    try:
        yield client
    finally:
        client.close()
        cluster.close()
