"""Monte Carlo and parameter sweeps that scale out through any ``concurrent.futures``-style executor.

A trial is a picklable function of a ``numpy.random.Generator`` (plus optional fixed arguments).  Trial ``i``
always receives the generator of child ``i`` of ``numpy.random.SeedSequence(seed)``, so results do not depend on
how trials are chunked or which executor runs them: serial, ``ThreadPoolExecutor``, ``ProcessPoolExecutor`` or a
Dask ``distributed.Client`` (anything with ``submit(fn, *args)`` returning a future with ``result()``).

Seeding costs O(1) per trial whatever the chunking: child ``i`` is built directly from the root's entropy and the
spawn key ``(i,)`` (:func:`trial_seed_sequence`), which is exactly what ``SeedSequence(seed).spawn(n)[i]`` returns.

A *vectorized* trial (``run_monte_carlo(..., vectorized=True)``) receives the generators of a whole chunk at once
and returns one result per generator, so the trials of a chunk can run together (e.g. a batched filter in lockstep,
:func:`cislunar.papers.greaves_scheeres_2021.detection.run_detection_monte_carlo`) while each keeps its own seed.

Failures
--------
A trial that raises does not lose the run.  With ``on_error="raise"`` (default) :class:`MonteCarloError` names the
first failing trial and its seed, carries the original exception (and its traceback text) and every result that
completed, and the queued work is cancelled.  With ``on_error="collect"`` the run continues and the failed entries
of the result list are :class:`TrialFailure` records.  ``KeyboardInterrupt`` cancels the queued work and stops the
chunks still running in this process (threads) after their current trial; chunks already running in worker
processes finish (at most ``chunk_size`` trials each) since a process cannot be interrupted from outside without
killing the pool.  All of these objects pickle, so they cross process pools intact.
"""

from __future__ import annotations

import concurrent.futures as _cf
import functools
import itertools
import pickle
import threading
import traceback
from dataclasses import dataclass

import numpy as np

from cislunar.utils import validation
from cislunar.utils.progress import progress

__all__ = ["spawn_rngs", "trial_seed_sequence", "trial_rng", "run_monte_carlo", "map_tasks", "MonteCarloError",
           "TrialFailure"]


# ---------------------------------------------------------------------------------------------------------------
# seeding
# ---------------------------------------------------------------------------------------------------------------
def _root(seed) -> np.random.SeedSequence:
    seed = validation.seed_entropy(seed, "seed")
    return seed if isinstance(seed, np.random.SeedSequence) else np.random.SeedSequence(seed)


def trial_seed_sequence(seed, i: int) -> np.random.SeedSequence:
    """Child ``i`` of ``SeedSequence(seed)``, built in O(1) (equal to ``SeedSequence(seed).spawn(i + 1)[i]``).

    For a ``SeedSequence`` root, children are numbered from its ``n_children_spawned`` as ``spawn`` would.
    """
    root = _root(seed)
    i = validation.integer(i, "i", minimum=0)
    return np.random.SeedSequence(root.entropy, spawn_key=tuple(root.spawn_key) + (root.n_children_spawned + i,),
                                  pool_size=root.pool_size)


def trial_rng(seed, i: int) -> np.random.Generator:
    """The generator trial ``i`` of ``run_monte_carlo(..., seed)`` receives (to rerun one trial alone)."""
    return np.random.default_rng(trial_seed_sequence(seed, i))


def spawn_rngs(seed, n: int) -> list:
    """``n`` independent generators, child ``i`` of ``SeedSequence(seed)`` for trial ``i``."""
    n = validation.integer(n, "n", minimum=0)
    root = _root(seed)  # children built directly: a SeedSequence passed in is not advanced
    base, offset = tuple(root.spawn_key), root.n_children_spawned
    return [np.random.default_rng(np.random.SeedSequence(root.entropy, spawn_key=base + (offset + i,),
                                                         pool_size=root.pool_size)) for i in range(n)]


def _describe_seed(seed, i) -> str:
    ss = trial_seed_sequence(seed, i)
    return f"SeedSequence(entropy={ss.entropy}, spawn_key={tuple(ss.spawn_key)})"


# ---------------------------------------------------------------------------------------------------------------
# failure records
# ---------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class TrialFailure:
    """A trial that raised.

    Attributes
    ----------
    index : int
        Trial (or task) index.
    seed : str
        The trial's seed sequence, e.g. ``"SeedSequence(entropy=11, spawn_key=(17,))"`` (``""`` for a sweep task);
        :func:`trial_rng` rebuilds its generator.
    error : BaseException
        The exception raised by the trial (replaced by a ``RuntimeError`` with the same text when the original
        cannot be pickled, so that it can leave a worker process).
    traceback : str
        Formatted traceback from the worker.
    """

    index: int
    seed: str
    error: BaseException
    traceback: str

    def __str__(self) -> str:
        where = f"trial {self.index}" + (f" (seed {self.seed})" if self.seed else "")
        return f"{where} raised {type(self.error).__name__}: {self.error}"


class MonteCarloError(RuntimeError):
    """A Monte Carlo trial (or sweep task) raised; the completed results are kept.

    Attributes
    ----------
    failure : TrialFailure
        The first failure: trial index, seed, original exception and worker traceback.
    trial_index : int
        ``failure.index``.
    seed : str
        ``failure.seed``.
    completed : dict
        ``{trial index: result}`` of every trial that finished before the run was stopped.
    n_trials : int
        Number of trials requested.

    The original exception is also chained as ``__cause__`` when raised in this process.
    """

    def __init__(self, failure: TrialFailure, completed: dict, n_trials: int):
        super().__init__(f"{failure} ({len(completed)} of {n_trials} trials completed; their results are in "
                         f".completed)\n--- worker traceback ---\n{failure.traceback}")
        self.failure = failure
        self.completed = dict(completed)
        self.n_trials = int(n_trials)

    @property
    def trial_index(self) -> int:
        return self.failure.index

    @property
    def seed(self) -> str:
        return self.failure.seed

    def __reduce__(self):
        return (type(self), (self.failure, self.completed, self.n_trials))


def _picklable(exc: BaseException) -> BaseException:
    try:
        pickle.loads(pickle.dumps(exc))
        return exc
    except Exception:
        return RuntimeError(f"{type(exc).__name__}: {exc} (original exception could not be pickled)")


# ---------------------------------------------------------------------------------------------------------------
# workers
# ---------------------------------------------------------------------------------------------------------------
#: Tokens of runs stopped in this process; chunks running in threads of this process check it between trials.
_STOPPED: set = set()
_STOP_LOCK = threading.Lock()
_TOKENS = itertools.count()


def _stop(token) -> None:
    with _STOP_LOCK:
        _STOPPED.add(token)


def _run_chunk(trial, seed, indices, args, kwargs, token=None, collect=False, vectorized=False):
    """Run trials ``indices``; returns ``[(index, ok, result_or_failure), ...]`` (never raises for a trial error).

    ``vectorized``: one call ``trial([rng_i for i in indices], ...)`` returning one result per generator; if it
    raises, the trials are rerun one at a time (``trial([rng_i])``, fresh generators) to name the failing one.
    """
    root = np.random.SeedSequence(seed) if not isinstance(seed, np.random.SeedSequence) else seed
    base = tuple(root.spawn_key)
    offset = root.n_children_spawned
    if vectorized:
        if token is not None and token in _STOPPED:
            return []
        try:
            rngs = [np.random.default_rng(_child(root, base, offset, i)) for i in indices]
            res = list(trial(rngs, *args, **kwargs))
            if len(res) != len(rngs):
                raise ValueError(f"a vectorized trial must return one result per generator: got {len(res)} for "
                                 f"{len(rngs)}")
            return [(i, True, r) for i, r in zip(indices, res)]
        except Exception as exc:  # noqa: BLE001 - rerun one by one to name the trial and keep the others
            if len(indices) > 1:
                return _run_chunk(functools.partial(_first_of_vectorized, trial), seed, indices, args, kwargs, token,
                                  collect)
            ss = _child(root, base, offset, indices[0])
            seed_txt = f"SeedSequence(entropy={ss.entropy}, spawn_key={tuple(ss.spawn_key)})"
            return [(indices[0], False, TrialFailure(indices[0], seed_txt, _picklable(exc), traceback.format_exc()))]
    out = []
    for i in indices:
        if token is not None and token in _STOPPED:
            break
        ss = _child(root, base, offset, i)
        try:
            out.append((i, True, trial(np.random.default_rng(ss), *args, **kwargs)))
        except Exception as exc:  # noqa: BLE001 - reported with index, seed and traceback
            seed_txt = f"SeedSequence(entropy={ss.entropy}, spawn_key={tuple(ss.spawn_key)})"
            out.append((i, False, TrialFailure(i, seed_txt, _picklable(exc), traceback.format_exc())))
            if not collect:
                break
    return out


def _child(root, base, offset, i) -> np.random.SeedSequence:
    """Child ``i`` of ``root`` (spawn key ``base + (offset + i,)``), built directly."""
    return np.random.SeedSequence(root.entropy, spawn_key=base + (offset + i,), pool_size=root.pool_size)


def _first_of_vectorized(trial, rng, *args, **kwargs):
    """A vectorized trial called with one generator, returning its single result."""
    res = list(trial([rng], *args, **kwargs))
    if len(res) != 1:
        raise ValueError(f"a vectorized trial must return one result per generator: got {len(res)} for 1")
    return res[0]


def _run_tasks(fn, items, token=None, collect=False):
    out = []
    for i, task in items:
        if token is not None and token in _STOPPED:
            break
        try:
            out.append((i, True, fn(task)))
        except Exception as exc:  # noqa: BLE001
            out.append((i, False, TrialFailure(i, "", _picklable(exc), traceback.format_exc())))
            if not collect:
                break
    return out


def _progress(iterable, total, desc, enabled):

    return progress(iterable, total=total, desc=desc, enabled=enabled)


def _check_executor(executor):
    if not callable(getattr(executor, "submit", None)):
        raise validation.ArgumentTypeError(f"executor must have a submit(fn, *args) method (a concurrent.futures "
                                        f"executor or a Dask Client); got {type(executor).__name__}")


def _completion_order(futures):
    """Futures in completion order when they are standard futures, else in submission order (e.g. Dask)."""
    if futures and all(isinstance(f, _cf.Future) for f in futures):
        return _cf.as_completed(futures)
    try:  # Dask futures
        from distributed import Future as DaskFuture
        from distributed import as_completed as dask_as_completed

        if futures and all(isinstance(f, DaskFuture) for f in futures):
            return dask_as_completed(futures)
    except ImportError:  # pragma: no cover - dask is optional
        pass
    return iter(futures)


def _drive(submit_chunks, n_total, desc, progress, collect, serial_run):
    """Common driver: run chunks serially or through futures; returns the ordered results or raises."""
    done: dict = {}
    first_failure = None
    token = next(_TOKENS)

    def absorb(records):
        nonlocal first_failure
        for i, ok, value in records:
            done[i] = value
            if not ok and first_failure is None:
                first_failure = value

    if submit_chunks is None:  # serial
        bar = _progress(None, n_total, desc, progress)
        try:
            for records in serial_run():
                absorb(records)
                bar.update(len(records))
                if first_failure is not None and not collect:
                    break
        finally:
            bar.close()
    else:
        futures, sizes = submit_chunks(token)
        by_future = {id(f): k for k, f in enumerate(futures)}
        bar = _progress(None, n_total, desc, progress)
        try:
            for fut in _completion_order(futures):
                absorb(fut.result())
                bar.update(sizes[by_future[id(fut)]])
                if first_failure is not None and not collect:
                    break
        except BaseException:  # KeyboardInterrupt, a lost worker, ...: stop everything queued and running here
            _stop(token)
            for f in futures:
                f.cancel()
            raise
        finally:
            bar.close()
        if first_failure is not None and not collect:
            _stop(token)
            for f in futures:
                f.cancel()
    with _STOP_LOCK:
        _STOPPED.discard(token)
    if first_failure is not None and not collect:
        completed = {i: v for i, v in done.items() if not isinstance(v, TrialFailure)}
        err = MonteCarloError(first_failure, completed, n_total)
        raise err from first_failure.error
    return [done[i] for i in range(n_total)]


def run_monte_carlo(trial, n_trials: int, seed, *, args=(), kwargs=None, executor=None, chunk_size: int | None = None,
                    progress: bool = True, desc: str = "Monte Carlo", on_error: str = "raise",
                    vectorized: bool = False) -> list:
    """Run ``trial(rng, *args, **kwargs)`` for ``n_trials`` independent generators.

    Parameters
    ----------
    trial : callable
        Picklable function (module level) when a process pool or a cluster runs it.
    n_trials : int
        Number of trials (>= 1).
    seed : int, sequence of int or numpy.random.SeedSequence
        Root seed; trial ``i`` gets child ``i`` (:func:`trial_rng`).  ``None`` is refused (it would make every run
        different).
    args, kwargs
        Fixed extra arguments passed to every trial.
    executor : object with ``submit``, optional
        ``None`` runs serially in this process.
    chunk_size : int, optional
        Trials per submitted task (default: about four tasks per worker, at most 64 trials); serially, trials per
        progress step (default: about a hundredth of the run, at most 64).
    progress : bool
        Progress bar over completed trials (:func:`cislunar.utils.progress.progress`).
    desc : str
        Progress-bar label.
    on_error : {"raise", "collect"}
        ``"raise"``: stop at the first failing trial with :class:`MonteCarloError` (queued work is cancelled; the
        completed results are on the exception).  ``"collect"``: run every trial; failed entries of the returned
        list are :class:`TrialFailure` records.
    vectorized : bool
        ``True``: ``trial(rngs, *args, **kwargs)`` receives the generators of a whole chunk (a list in trial order,
        trial ``i`` still getting child ``i``) and returns one result per generator, e.g. to run the trials of a
        chunk in lockstep.  Results are those of the per-trial calls as long as the trial treats each generator
        on its own.  If the call raises, the chunk's trials are rerun one at a time (``trial([rng])`` with a
        fresh generator of each seed) so the failure names its trial and the others are kept.

    Returns
    -------
    list
        Trial results in trial order (bit-identical whatever the executor and chunking).

    Raises
    ------
    MonteCarloError
        A trial raised (``on_error="raise"``); names the trial index and its seed.
    """
    validation.callable_(trial, "trial")
    n_trials = validation.integer(n_trials, "n_trials", minimum=1)
    root = _root(seed)
    if not isinstance(args, (tuple, list)):
        raise validation.ArgumentTypeError(f"args must be a tuple of extra positional arguments; got "
                                        f"{type(args).__name__}")
    if kwargs is None:
        kwargs = {}
    if not isinstance(kwargs, dict):
        raise validation.ArgumentTypeError(f"kwargs must be a dict of keyword arguments; got {type(kwargs).__name__}")
    validation.boolean(progress, "progress")
    if not isinstance(desc, str):
        raise validation.ArgumentTypeError(f"desc must be a str; got {type(desc).__name__}")
    validation.choice(on_error, "on_error", ("raise", "collect"))
    vectorized = validation.boolean(vectorized, "vectorized")
    collect = on_error == "collect"
    args = tuple(args)
    if executor is None:
        if chunk_size is not None:
            chunk_size = validation.integer(chunk_size, "chunk_size", minimum=1)

        def serial():  # chunks of up to 64 trials keep the bookkeeping off the per-trial cost
            step = chunk_size or max(1, min(64, n_trials // 100))
            for i in range(0, n_trials, step):
                yield _run_chunk(trial, root, range(i, min(i + step, n_trials)), args, kwargs, None, collect,
                                 vectorized)

        return _drive(None, n_trials, desc, progress, collect, serial)
    _check_executor(executor)
    if chunk_size is None:
        workers = getattr(executor, "_max_workers", None) or 2
        chunk_size = max(1, min(64, n_trials // (4 * workers) or 1))
    chunk_size = validation.integer(chunk_size, "chunk_size", minimum=1)
    chunks = [range(i, min(i + chunk_size, n_trials)) for i in range(0, n_trials, chunk_size)]

    def submit(token):
        futures = [executor.submit(_run_chunk, trial, root, c, args, kwargs, token, collect, vectorized)
                   for c in chunks]
        return futures, [len(c) for c in chunks]

    return _drive(submit, n_trials, desc, progress, collect, None)


def map_tasks(fn, tasks, *, executor=None, progress: bool = True, desc: str = "sweep", chunk_size: int = 1,
              on_error: str = "raise") -> list:
    """``[fn(task) for task in tasks]``, optionally through an executor, results in task order (parameter sweeps).

    Failures behave as in :func:`run_monte_carlo` (the :class:`MonteCarloError` names the task index; there is no
    seed).
    """
    validation.callable_(fn, "fn")
    if isinstance(tasks, (str, bytes)):
        raise validation.ArgumentTypeError("tasks must be a sequence of tasks, not a str")
    try:
        tasks = list(tasks)
    except TypeError:
        raise validation.ArgumentTypeError(f"tasks must be iterable; got {type(tasks).__name__}") from None
    validation.boolean(progress, "progress")
    validation.choice(on_error, "on_error", ("raise", "collect"))
    chunk_size = validation.integer(chunk_size, "chunk_size", minimum=1)
    collect = on_error == "collect"
    items = list(enumerate(tasks))
    if not items:
        return []
    if executor is None:
        def serial():
            for item in items:
                yield _run_tasks(fn, [item], None, collect)

        return _drive(None, len(items), desc, progress, collect, serial)
    _check_executor(executor)
    chunks = [items[i:i + chunk_size] for i in range(0, len(items), chunk_size)]

    def submit(token):
        return [executor.submit(_run_tasks, fn, c, token, collect) for c in chunks], [len(c) for c in chunks]

    return _drive(submit, len(items), desc, progress, collect, None)
