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
of the result list are :class:`TrialFailure` records.  All of these objects pickle, so they cross process pools
intact.

Two failures happen outside the trial, on the way back from a worker process (a process pool or a Dask cluster),
and are reported the same way, naming the trial and its seed:

* a result that cannot be pickled: each result is pickled in the worker, so only that trial fails (its chunk's
  other results are kept);
* a worker process that dies (``os._exit``, a segfault, SIGKILL by the out-of-memory killer): each worker notes in
  a small file of a run folder (in the temporary directory of this machine) which trial it is running, so the
  trial that was running in the dead process is named.  Trials of chunks that were running elsewhere and were
  lost with it (a ``ProcessPoolExecutor`` ends every worker when one dies) are reported as lost; every chunk that
  returned is in ``completed``.  On a remote cluster without this machine's temporary directory the failure names
  the first trial of the lost chunk and says so.

Interruption (Ctrl-C)
---------------------
``KeyboardInterrupt`` cancels the queued work and re-raises at once.  Chunks running in threads of this process stop
after their current trial.  With a ``concurrent.futures.ProcessPoolExecutor`` the pool's worker processes are
terminated (a process cannot be interrupted from outside otherwise): the call raises within about a second whatever
the trials' length (at most 5 s are spent ending the workers), no trial starts after the interrupt, no worker process
survives, and the pool is unusable afterwards (as after any crash).  On a Dask cluster the queued chunks are
cancelled; chunks already running on its workers (at most ``chunk_size`` trials each) finish there, the workers
are the cluster's, not this call's, to stop.
"""

from __future__ import annotations

import concurrent.futures as _cf
import functools
import itertools
import os
import pickle
import shutil
import signal
import socket
import tempfile
import threading
import time
import traceback
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass

import numpy as np
import psutil

from cislunar.utils import executors, validation
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
    what : str
        What went wrong: ``"raised"`` (the trial raised ``error``), ``"returned an unpicklable result"``, ``"died
        with its worker process"`` or ``"was lost"`` (it was running or queued in a worker that was ended).
    """

    index: int
    seed: str
    error: BaseException
    traceback: str
    what: str = "raised"

    def __str__(self) -> str:
        where = (f"trial {self.index} (seed {self.seed})" if self.seed else f"task {self.index}")
        if self.what == "raised":
            return f"{where} raised {type(self.error).__name__}: {self.error}"
        return f"{where} {self.what}: {self.error}"


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


#: Marks a chunk's records whose results were pickled one by one in a worker process.
_PICKLED = "cislunar.montecarlo.pickled-records"
_BLANK = b" " * 20 + b"\n"


class _Journal:
    """Which trial this worker thread is running, in ``<run folder>/<pid>-<thread>`` (read if the worker dies).

    ``origin`` is ``(host, pid, folder)`` of the calling process, or ``None`` (no transport: serial runs).  Inside
    the calling process (threads) nothing is written and nothing is pickled.
    """

    def __init__(self, origin):
        self.remote = origin is not None and (origin[0], origin[1]) != (socket.gethostname(), os.getpid())
        self._fd = None
        if self.remote and origin[2] and os.path.isdir(origin[2]):
            try:
                self._fd = os.open(os.path.join(origin[2], f"{os.getpid()}-{threading.get_ident()}"),
                                   os.O_WRONLY | os.O_CREAT, 0o600)
            except OSError:  # the run folder is not writable here: the failure is then named by its chunk
                self._fd = None

    def start(self, i) -> None:
        if self._fd is not None:
            os.pwrite(self._fd, f"{i:>20d}\n".encode(), 0)

    def close(self) -> None:
        if self._fd is not None:
            os.pwrite(self._fd, _BLANK, 0)
            os.close(self._fd)
            self._fd = None


def _dumps(value) -> bytes:
    try:
        return pickle.dumps(value, protocol=pickle.HIGHEST_PROTOCOL)
    except Exception as exc:  # noqa: BLE001 - Dask would try cloudpickle too (classes sent by value)
        try:
            import cloudpickle
        except ImportError:  # pragma: no cover - installed with dask
            raise exc from None
        return cloudpickle.dumps(value, protocol=pickle.HIGHEST_PROTOCOL)


def _encode(records, seed_text):
    """Pickle each result in the worker, so that one unpicklable result fails its trial only."""
    out = []
    for i, ok, value in records:
        if ok:
            try:
                value = _dumps(value)
            except Exception as exc:  # noqa: BLE001 - reported as that trial's failure
                ok, value = False, TrialFailure(i, seed_text(i), _picklable(exc), traceback.format_exc(),
                                                "returned an unpicklable result")
        out.append((i, ok, value))
    return (_PICKLED, out)


def _decode(result, seed_text):
    if not (isinstance(result, tuple) and len(result) == 2 and result[0] == _PICKLED):
        return result
    out = []
    for i, ok, value in result[1]:
        if ok:
            try:
                value = pickle.loads(value)
            except Exception as exc:  # noqa: BLE001 - e.g. a class this process cannot import
                ok, value = False, TrialFailure(i, seed_text(i), _picklable(exc), traceback.format_exc(),
                                                "returned a result that cannot be unpickled here")
        out.append((i, ok, value))
    return out


def _run_chunk(trial, seed, indices, args, kwargs, token=None, collect=False, vectorized=False, origin=None):
    """Run trials ``indices``; returns ``[(index, ok, result_or_failure), ...]`` (never raises for a trial error).

    ``vectorized``: one call ``trial([rng_i for i in indices], ...)`` returning one result per generator; if it
    raises, the trials are rerun one at a time (``trial([rng_i])``, fresh generators) to name the failing one.
    ``origin``: see :class:`_Journal`; in a worker process the results come back pickled one by one.
    """
    root = np.random.SeedSequence(seed) if not isinstance(seed, np.random.SeedSequence) else seed
    journal = _Journal(origin)
    try:
        records = _run_chunk_here(trial, root, indices, args, kwargs, token, collect, vectorized, journal)
    finally:
        journal.close()
    if not journal.remote:
        return records
    base, offset = tuple(root.spawn_key), root.n_children_spawned
    return _encode(records, lambda i: _seed_text(_child(root, base, offset, i)))


def _seed_text(ss) -> str:
    return f"SeedSequence(entropy={ss.entropy}, spawn_key={tuple(ss.spawn_key)})"


def _run_chunk_here(trial, root, indices, args, kwargs, token, collect, vectorized, journal):
    base = tuple(root.spawn_key)
    offset = root.n_children_spawned
    if vectorized:
        journal.start(indices[0])
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
                return _run_chunk_here(functools.partial(_first_of_vectorized, trial), root, indices, args, kwargs,
                                       token, collect, False, journal)
            ss = _child(root, base, offset, indices[0])
            seed_txt = f"SeedSequence(entropy={ss.entropy}, spawn_key={tuple(ss.spawn_key)})"
            return [(indices[0], False, TrialFailure(indices[0], seed_txt, _picklable(exc), traceback.format_exc()))]
    out = []
    for i in indices:
        if token is not None and token in _STOPPED:
            break
        ss = _child(root, base, offset, i)
        journal.start(i)
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


def _run_tasks(fn, items, token=None, collect=False, origin=None):
    out = []
    journal = _Journal(origin)
    try:
        for i, task in items:
            if token is not None and token in _STOPPED:
                break
            journal.start(i)
            try:
                out.append((i, True, fn(task)))
            except Exception as exc:  # noqa: BLE001
                out.append((i, False, TrialFailure(i, "", _picklable(exc), traceback.format_exc())))
                if not collect:
                    break
    finally:
        journal.close()
    return _encode(out, lambda i: "") if journal.remote else out


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


def _dead(pid: int) -> bool:
    try:
        return psutil.Process(pid).status() == psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return True
    except psutil.Error:  # pragma: no cover - e.g. access denied: not ours
        return False


def _pool_exit_codes(executor) -> dict:
    """``{pid: exit code}`` of a broken ``ProcessPoolExecutor``'s workers (it ends them all; waits up to 5 s)."""
    procs = getattr(executor, "_processes", None) if isinstance(executor, _cf.ProcessPoolExecutor) else None
    out = {}
    deadline = time.monotonic() + 5.0
    for pid, proc in list((procs or {}).items()):
        proc.join(timeout=max(0.0, deadline - time.monotonic()))
        if proc.exitcode is not None:
            out[pid] = proc.exitcode
    return out


def _dead_workers_trials(folder, exc, executor) -> list:
    """``[(trial index, pid, exit code or None)]`` read from the journals of worker processes that died mid-trial.

    With a broken ``ProcessPoolExecutor`` the worker that crashed is the one whose exit code is not the SIGTERM the
    pool sends the others; elsewhere (Dask restarts a dead worker) a dead pid with a trial in its journal.
    """
    if not folder or not os.path.isdir(folder):
        return []
    codes = _pool_exit_codes(executor) if isinstance(exc, BrokenProcessPool) else {}
    try:  # shown if no journal names a trial
        exc._cislunar_exit_codes = codes
    except Exception:  # noqa: BLE001 - an exception that takes no attributes
        pass
    out = []
    for name in os.listdir(folder):
        try:
            pid = int(name.split("-")[0])
            with open(os.path.join(folder, name), "rb") as fh:
                text = fh.read().strip()
        except (ValueError, OSError):
            continue
        if not text:  # between chunks
            continue
        code = codes.get(pid)
        if code == -signal.SIGTERM:  # ended by the broken pool, not the one that broke it
            continue
        if code is None and not _dead(pid):  # exit code not known (yet): judge by the process itself
            continue
        out.append((int(text), pid, codes.get(pid)))
    return sorted(set(out))


def _exit_codes_text(exc) -> str:
    codes = getattr(exc, "_cislunar_exit_codes", None)
    return f"; worker exit codes {codes}" if codes else ""


def _lost_chunk(indices, exc, seed_text, culprits) -> list:
    """Records for a chunk that did not come back (``exc``): the trial that killed its worker first, if known."""
    tb = "".join(traceback.format_exception(type(exc), exc, exc.__traceback__))
    why = f"{type(exc).__name__}: {exc}"
    out = []
    named = None
    if culprits:
        mine = [c for c in culprits if c[0] in indices]
        named, pid, code = (mine or culprits)[0]
        code_text = f", exit code {code}" if code is not None else ", exit code unknown (not yet reaped by the pool)"
        out.append((named, False, TrialFailure(
            named, seed_text(named), RuntimeError(f"worker process {pid} died while it ran this trial{code_text} "
                                                  f"({why})"), tb, "died with its worker process")))
    for j in indices:
        if j == named:
            continue
        if named is None and not out:  # nobody to blame: name the chunk by its first trial
            err = RuntimeError(f"its chunk (trials {indices[0]} to {indices[-1]}) did not come back from the "
                               f"executor, and no worker journal names the trial that was running ({why}"
                               f"{_exit_codes_text(exc)})")
        else:
            err = RuntimeError(f"its chunk did not come back from the executor ({why})")
        out.append((j, False, TrialFailure(j, seed_text(j), err, tb, "was lost")))
    return out


def _drive(submit_chunks, n_total, desc, progress, collect, serial_run, *, executor=None, chunks=(),
           seed_text=lambda i: ""):
    """Common driver: run chunks serially or through futures; returns the ordered results or raises.

    ``submit_chunks(token, origin)`` submits ``chunks`` (lists of indices) and returns their futures and sizes;
    ``origin`` tells the workers where to journal and whether to pickle their results (:class:`_Journal`).
    """
    done: dict = {}
    first_failure = None
    token = next(_TOKENS)

    def absorb(records):
        nonlocal first_failure
        for i, ok, value in records:
            if not ok and i in done and isinstance(done[i], TrialFailure) and done[i].what != "was lost":
                continue  # already named (e.g. the trial that killed a worker, seen from a lost chunk)
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
        folder = tempfile.mkdtemp(prefix="cislunar-mc-")
        try:
            futures, sizes = submit_chunks(token, (socket.gethostname(), os.getpid(), folder))
            by_future = {id(f): k for k, f in enumerate(futures)}
            seen = set()

            def records_of(fut, k):
                try:
                    return _decode(fut.result(), seed_text)
                except Exception as exc:  # noqa: BLE001 - not a trial's error (those come back as records)
                    return _lost_chunk(list(chunks[k]), exc, seed_text, _dead_workers_trials(folder, exc, executor))

            bar = _progress(None, n_total, desc, progress)
            try:
                for fut in _completion_order(futures):
                    k = by_future[id(fut)]
                    seen.add(k)
                    absorb(records_of(fut, k))
                    bar.update(sizes[k])
                    if first_failure is not None and not collect:
                        break
            except BaseException as exc:  # KeyboardInterrupt, ...: stop everything queued and running here
                _stop(token)
                if isinstance(exc, KeyboardInterrupt) and isinstance(executor, _cf.ProcessPoolExecutor):
                    # the pool then fails every pending future itself (cancelling them would race with it)
                    executors._end_process_pool(executor)
                else:
                    for f in futures:
                        f.cancel()
                raise
            finally:
                bar.close()
            if first_failure is not None and not collect:
                _stop(token)
                if not getattr(executor, "_broken", False):  # a broken pool fails its pending futures itself
                    for f in futures:
                        f.cancel()
                for k, f in enumerate(futures):  # keep every result that came back meanwhile
                    if k not in seen and f.done() and not f.cancelled():
                        try:
                            absorb(_decode(f.result(), seed_text))
                        except Exception:  # noqa: BLE001 - lost too: the first failure is reported
                            pass
        finally:
            shutil.rmtree(folder, ignore_errors=True)
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

    def submit(token, origin):
        futures = [executor.submit(_run_chunk, trial, root, c, args, kwargs, token, collect, vectorized, origin)
                   for c in chunks]
        return futures, [len(c) for c in chunks]

    return _drive(submit, n_trials, desc, progress, collect, None, executor=executor, chunks=chunks,
                  seed_text=functools.partial(_describe_seed, root))


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

    def submit(token, origin):
        return ([executor.submit(_run_tasks, fn, c, token, collect, origin) for c in chunks],
                [len(c) for c in chunks])

    return _drive(submit, len(items), desc, progress, collect, None, executor=executor,
                  chunks=[[i for i, _ in c] for c in chunks])
