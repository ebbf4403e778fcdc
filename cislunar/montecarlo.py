"""Monte Carlo and parameter sweeps that scale out through any ``concurrent.futures``-style executor.

A trial is a picklable function of a ``numpy.random.Generator`` (plus optional fixed arguments).  Trial ``i``
always receives the generator spawned as child ``i`` of ``numpy.random.SeedSequence(seed)``, so results do not
depend on how trials are chunked or which executor runs them: serial, ``ThreadPoolExecutor``,
``ProcessPoolExecutor`` or a Dask ``distributed.Client`` (anything with ``submit(fn, *args)`` returning a future
with ``result()``).
"""

from __future__ import annotations

import numpy as np

__all__ = ["spawn_rngs", "run_monte_carlo", "map_tasks"]


def spawn_rngs(seed, n: int) -> list:
    """``n`` independent generators, child ``i`` of ``SeedSequence(seed)`` for trial ``i``."""
    n = int(n)
    if n < 0:
        raise ValueError(f"n must be non-negative; got {n}")
    return [np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(n)]


def _run_chunk(trial, seed, indices, args, kwargs):
    children = np.random.SeedSequence(seed).spawn(max(indices) + 1 if indices else 0)
    return [trial(np.random.default_rng(children[i]), *args, **kwargs) for i in indices]


def _progress(iterable, total, desc, enabled):
    from .progress import progress

    return progress(iterable, total=total, desc=desc, enabled=enabled)


def run_monte_carlo(trial, n_trials: int, seed, *, args=(), kwargs=None, executor=None, chunk_size: int | None = None,
                    progress: bool = True, desc: str = "Monte Carlo") -> list:
    """Run ``trial(rng, *args, **kwargs)`` for ``n_trials`` independent generators.

    Parameters
    ----------
    trial : callable
        Picklable function (module level) when a process pool or a cluster runs it.
    n_trials : int
        Number of trials (>= 1).
    seed : int or SeedSequence entropy
        Root seed; trial ``i`` gets child ``i``.
    args, kwargs
        Fixed extra arguments passed to every trial.
    executor : object with ``submit``, optional
        ``None`` runs serially in this process.
    chunk_size : int, optional
        Trials per submitted task (default: about four tasks per worker, at most 64 trials).
    progress : bool
        tqdm progress bar over completed chunks.

    Returns
    -------
    list
        Trial results in trial order.
    """
    n_trials = int(n_trials)
    if n_trials < 1:
        raise ValueError(f"n_trials must be >= 1; got {n_trials}")
    kwargs = kwargs or {}
    if executor is None:
        rngs = spawn_rngs(seed, n_trials)
        return [trial(r, *args, **kwargs) for r in _progress(rngs, n_trials, desc, progress)]
    if not hasattr(executor, "submit"):
        raise ValueError(f"executor must have a submit(fn, *args) method; got {type(executor).__name__}")
    if chunk_size is None:
        workers = getattr(executor, "_max_workers", None) or 2
        chunk_size = max(1, min(64, n_trials // (4 * workers) or 1))
    chunk_size = int(chunk_size)
    if chunk_size < 1:
        raise ValueError(f"chunk_size must be >= 1; got {chunk_size}")
    chunks = [list(range(i, min(i + chunk_size, n_trials))) for i in range(0, n_trials, chunk_size)]
    futures = [executor.submit(_run_chunk, trial, seed, c, tuple(args), kwargs) for c in chunks]
    out = []
    for fut in _progress(futures, len(futures), desc, progress):
        out.extend(fut.result())
    return out


def map_tasks(fn, tasks, *, executor=None, progress: bool = True, desc: str = "sweep") -> list:
    """``[fn(task) for task in tasks]``, optionally through an executor, results in task order (parameter sweeps)."""
    tasks = list(tasks)
    if executor is None:
        return [fn(t) for t in _progress(tasks, len(tasks), desc, progress)]
    if not hasattr(executor, "submit"):
        raise ValueError(f"executor must have a submit(fn, *args) method; got {type(executor).__name__}")
    futures = [executor.submit(fn, t) for t in tasks]
    return [f.result() for f in _progress(futures, len(futures), desc, progress)]
