"""Run independent tasks (disorder realizations, parameter points) through an executor.

``run_tasks`` is the one place where sweeps meet parallelism and persistence:

* tasks are dicts of JSON-serialisable parameters; ``func(**task) -> dict`` is a top-level
  (picklable) function;
* tasks already in the :class:`~analysis.experiments.store.ResultStore` are skipped (resume
  after a crash);
* the rest run on a ``concurrent.futures.Executor``: the one given, a Dask distributed cluster
  (``scheduler`` address), a local process pool (``workers``), or serially in-process;
* each result is written to the store from the parent process as soon as it arrives, in one
  transaction, with the task's wall time measured in the worker;
* a task function may say how it runs several of its tasks in one call (``func.batching``, a
  :class:`Batching`; the ensemble's realizations side by side in the vector units): up to
  ``size`` consecutive pending tasks of one batching key then go to a worker together, and
  each still gets its own result and its own row in the store (a batch must give the bits of
  its tasks run alone, so resuming or spreading a run never changes a result).

Who writes the store: only the calling (client) process, as results arrive. Workers compute and
return their result over the executor's channel (a pipe, or Dask's TCP connection); they never
open the store. So there is exactly one writer (no SQLite locking across machines, which is
unreliable on network filesystems), and the workers of a cluster need no shared filesystem and
no write access anywhere: only the client machine holds the file.

The workers of a local process pool end with the client: each watches the client process
(``prctl(PR_SET_PDEATHSIG)`` on Linux, plus a thread that waits on a pidfd of the client or
polls its pid elsewhere) and exits when it dies, so a killed ``hyst`` leaves no orphaned
workers computing for nobody.

On a Dask cluster a worker that dies (killed, machine lost) costs only the tasks it held: the
scheduler reruns them on the surviving workers and their futures still complete, so the run
finishes by itself, with every task stored once. Losing the scheduler (or the client's
connection to it) ends the run with a ``ConnectionError``; what finished is stored, and running
the same sweep again against a new scheduler computes only the rest.
"""

from __future__ import annotations

import ctypes
import os
import select
import signal
import sys
import threading
import time
import warnings
from collections.abc import Callable, Hashable, Mapping, Sequence
from concurrent.futures import Executor, Future, ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from numbers import Integral
from typing import Any

import numpy as np

from analysis.experiments.store import ResultStore, StoreError, code_version, task_key
from hysteresis._progress import progress_bar
from hysteresis._validation import bounded_work, nonnegative_integer

__all__ = ["run_tasks", "spawn_seeds", "Batching", "TaskError", "end_with_client"]


class TaskError(RuntimeError):
    """A task raised; carries the task parameters. The original exception is the cause.

    The message is one line naming the experiment, the task and the error. A worker
    process's remote traceback is kept in :attr:`remote_traceback` (for debugging) rather
    than chained, so that printing the error shows the task and the cause, not the pool's
    internals.
    """

    def __init__(self, experiment: str, task: Mapping[str, Any], error: BaseException) -> None:
        first = str(error).strip().splitlines()[0] if str(error).strip() else ""
        super().__init__(
            f"{experiment}: task {dict(task)!r} failed with {type(error).__name__}: {first}"
        )
        self.task = dict(task)
        self.error = error
        remote = error.__cause__
        self.remote_traceback = str(remote) if remote is not None else None
        if remote is not None and type(remote).__name__ == "_RemoteTraceback":
            error.__cause__ = None
            error.__suppress_context__ = True


def spawn_seeds(base_seed: int, n: int) -> list[int]:
    """``n`` independent seeds from one base seed (``numpy.random.SeedSequence.spawn``).

    Each child sequence yields one 63-bit integer, so the seeds are plain JSON-serialisable
    ints that can be part of a task key, and ``numpy.random.default_rng(seed)`` gives
    statistically independent streams. The same ``(base_seed, n)`` always gives the same list,
    and the first ``m`` seeds do not depend on ``n``.
    """

    n = nonnegative_integer(n, "n")
    bounded_work(n, "n", 10_000_000, "seeds")
    base_seed = nonnegative_integer(base_seed, "base_seed")
    children = np.random.SeedSequence(int(base_seed)).spawn(n)
    return [int(c.generate_state(1, dtype=np.uint64)[0] >> np.uint64(1)) for c in children]


@dataclass(frozen=True)
class Batching:
    """How a task function runs several of its tasks in one call, set as its attribute
    ``func.batching`` (e.g. :func:`analysis.experiments.ensemble.ensemble_task`: disorder
    realizations side by side in the vector units).

    ``run(tasks)`` returns the results of ``func(**task)`` for every task, in order, **bit for
    bit** the same (so a result does not depend on how tasks were batched, resumed or spread
    over workers); :func:`run_tasks` hands it up to ``size`` consecutive pending tasks with the
    same ``key(task)``; a task whose key is None runs alone, as ``func(**task)``.
    """

    run: Callable[[list[dict]], list[Mapping[str, Any]]]
    size: int
    key: Callable[[Mapping[str, Any]], Hashable | None]


class _BatchTaskFailed(Exception):
    """Task ``index`` of a batch raised ``error`` (found by running the batch's tasks alone)."""

    def __init__(self, index: int, error: BaseException) -> None:
        super().__init__(index, error)
        self.index = index
        self.error = error


def _timed_batch(func: Callable[..., Mapping[str, Any]], tasks: list[dict]) -> list[tuple]:
    """Run a batch of tasks in the worker (``func.batching.run``); each task's wall time is the
    batch's share. If the batch raises, its tasks run alone, so that the error names its task
    (the results are the same either way)."""
    start = time.perf_counter()
    try:
        results = list(func.batching.run(tasks))  # type: ignore[attr-defined]
    except Exception:  # noqa: BLE001  (whatever it was, the task alone raises it again)
        out = []
        for i, task in enumerate(tasks):
            try:
                out.append(_timed_call(func, task))
            except Exception as exc:
                raise _BatchTaskFailed(i, exc) from None
        return out
    wall = (time.perf_counter() - start) / max(len(tasks), 1)
    if len(results) != len(tasks) or not all(isinstance(r, Mapping) for r in results):
        raise TypeError("a batch function must return one dict per task")
    return [(dict(r), wall) for r in results]


def _units(pending: dict[str, dict], func: Callable[..., Any]) -> list[list[str]]:
    """The pending task keys in submission units: runs of up to ``batching.size`` consecutive
    tasks with the same non-None batching key, else one task each."""
    batching = getattr(func, "batching", None)
    if batching is None or batching.size < 2:
        return [[k] for k in pending]
    units: list[list[str]] = []
    last = None
    for key, task in pending.items():
        group = batching.key(task)
        if group is not None and group == last and len(units[-1]) < batching.size:
            units[-1].append(key)
        else:
            units.append([key])
        last = group
    return units


def _timed_call(func: Callable[..., Mapping[str, Any]], task: dict) -> tuple[dict, float]:
    """Run one task in the worker and measure its wall time there (module level: picklable)."""
    start = time.perf_counter()
    result = func(**task)
    wall = time.perf_counter() - start
    if not isinstance(result, Mapping):
        raise TypeError(f"task function must return a dict, got {type(result).__name__}")
    return dict(result), wall


_PR_SET_PDEATHSIG = 1  # <linux/prctl.h>


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # exists, owned by another user
        return True
    return True


def _watch_client(client_pid: int, parent_pid: int) -> None:
    """Thread of a pool worker: end the worker as soon as the client process is gone."""
    pidfd_open = getattr(os, "pidfd_open", None)
    if pidfd_open is not None:
        try:
            fd = pidfd_open(client_pid)
        except OSError:
            fd = None
        if fd is not None:
            select.select([fd], [], [])  # readable once the client has exited
            os._exit(1)
    # portable fallback: a client that exited leaves this worker to another parent (fork), or
    # its pid vanishes (a zombie client still answers os.kill, hence the parent check too)
    while os.getppid() == parent_pid and _alive(client_pid):
        time.sleep(0.25)
    os._exit(1)


def end_with_client(client_pid: int) -> None:
    """Initializer of the pool's workers: a worker exits when the client process dies."""
    parent_pid = os.getppid()
    if sys.platform.startswith("linux") and parent_pid == client_pid:
        try:  # the kernel kills this worker when its parent (the client) dies
            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0)
        except (OSError, AttributeError):
            pass
    if not _alive(client_pid) or os.getppid() != parent_pid:  # died before we watched
        os._exit(1)
    threading.Thread(
        target=_watch_client, args=(client_pid, parent_pid), name="watch-client", daemon=True
    ).start()


def _dask_client(scheduler: str) -> Any:
    try:
        from distributed import Client
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise ImportError(
            "a scheduler address needs Dask distributed: "
            "pip install 'hysteresis-toolkit[distributed]'"
        ) from exc
    try:
        return Client(scheduler)
    except ValueError as exc:  # a malformed address (e.g. 'local': missing port number)
        raise ValueError(
            f"scheduler {scheduler!r} is not a Dask scheduler address ({exc}); give one such "
            "as tcp://HOST:8786 (this toolkit starts no local cluster: use --workers for "
            "local processes)"
        ) from None


def run_tasks(
    experiment: str,
    tasks: Sequence[Mapping[str, Any]],
    func: Callable[..., Mapping[str, Any]],
    store: ResultStore | str | os.PathLike | None = None,
    executor: Executor | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: bool = True,
    allow_version_mismatch: bool = False,
) -> list[dict]:
    """Run ``func(**task)`` for every task and return the results in task order.

    Parameters
    ----------
    experiment:
        Name of the sweep; part of every task key, and the store's ``experiment`` column.
    tasks:
        Parameter dicts (JSON-serialisable; include the ``seed``). Equal tasks run once.
    func:
        Top-level function returning a dict (JSON scalars/lists/dicts and numpy arrays).
    store:
        A :class:`ResultStore` or a path to one. Stored tasks are not run again; new results
        are written as they complete. Without a store nothing is persisted.
    executor:
        Any ``concurrent.futures.Executor`` (used as is, not shut down).
    workers:
        Size of a local ``ProcessPoolExecutor`` when neither ``executor`` nor ``scheduler`` is
        given (default: ``os.cpu_count()``); ``workers=1`` runs serially in this process.
    scheduler:
        Address of a Dask distributed scheduler, e.g. ``"tcp://10.0.0.5:8786"``; the tasks go
        to ``Client(scheduler).get_executor()``. Needs the ``distributed`` extra. The workers
        never see the store: results come back to this process, which alone writes them. A
        worker lost mid-run only costs the work it held (Dask reruns it elsewhere).
    progress:
        Show a tqdm progress bar (counts, rate, ETA).
    allow_version_mismatch:
        A store whose ``experiment`` holds results of other code versions is refused
        (:class:`~analysis.experiments.store.StoreError`) unless this is ``True``; then they are
        reused with a warning.

    Returns
    -------
    list of dict
        One result per task, in task order. With a store, every result is read back from it,
        so fresh and resumed runs return identical objects (tuples become lists).

    Raises
    ------
    TaskError
        A task raised (the task's parameters and the original exception are kept).
    ConnectionError
        The Dask scheduler (or any executor) went away before the run finished; the message
        says how many tasks are stored. Running the same sweep again computes only the rest.
    """
    if sum(x is not None for x in (executor, scheduler)) > 1:
        raise ValueError("give at most one of executor and scheduler")
    if workers is not None and (
        isinstance(workers, bool) or not isinstance(workers, Integral) or workers < 1
    ):
        raise ValueError(f"workers must be an integer >= 1, got {workers!r}")
    if not callable(func):
        raise TypeError(f"func must be a callable returning a dict, got {type(func).__name__}")
    if isinstance(tasks, Mapping) or not isinstance(tasks, Sequence):
        raise TypeError(f"tasks must be a sequence of parameter dicts, got {type(tasks).__name__}")
    for i, t in enumerate(tasks):
        if not isinstance(t, Mapping):
            raise TypeError(f"tasks[{i}] must be a dict of parameters, got {type(t).__name__}")
    task_list = [dict(t) for t in tasks]
    keys = [task_key(experiment, t) for t in task_list]
    own_store = False
    if store is not None and not isinstance(store, ResultStore):
        store = ResultStore(store)
        own_store = True
    try:
        results: dict[str, dict] = {}
        pending: dict[str, dict] = {}
        other_versions: set[str] = set()
        current = code_version() if store is not None else ""
        if store is not None:
            store.check_versions(experiment, allow_version_mismatch)
        for key, task in zip(keys, task_list, strict=True):
            if key in results or key in pending:
                continue
            if store is not None and store.has(key):
                stored = store.get(key)
                results[key] = stored.results
                if stored.code_version != current:
                    other_versions.add(str(stored.code_version))
            else:
                pending[key] = task
        if pending and store is not None and store.read_only:
            raise StoreError(
                f"{store.path}: read-only (file or directory not writable), and {len(pending)} "
                f"of {len(results) + len(pending)} tasks are not stored in it; nothing was run"
            )
        if other_versions:
            # Resuming across code changes mixes results; say so instead of silently reusing.
            warnings.warn(
                f"{experiment}: reusing stored results computed by other code versions "
                f"{sorted(other_versions)} (now {current!r}); use a new store to recompute them",
                stacklevel=2,
            )

        bar = progress_bar(
            total=len(results) + len(pending),
            initial=len(results),
            desc=experiment,
            unit="task",
            disable=not progress,
        )
        try:
            _run_pending(
                experiment, pending, func, store, results, bar, executor, workers, scheduler
            )
        finally:
            bar.close()

        if store is not None:
            return [store.get(k).results for k in keys]
        return [results[k] for k in keys]
    finally:
        if own_store:
            store.close()


def _run_pending(
    experiment: str,
    pending: dict[str, dict],
    func: Callable[..., Mapping[str, Any]],
    store: ResultStore | None,
    results: dict[str, dict],
    bar: Any,
    executor: Executor | None,
    workers: int | None,
    scheduler: str | None,
) -> None:
    def record(key: str, result: dict, wall: float) -> None:
        if store is not None:
            store.put(experiment, pending[key], result, wall_time=wall, key=key)
        results[key] = result
        bar.update(1)

    if not pending:
        return
    units = _units(pending, func)

    def submit(ex: Executor, keys: list[str]) -> Future:
        if len(keys) == 1:
            return ex.submit(_timed_call, func, pending[keys[0]])
        return ex.submit(_timed_batch, func, [pending[k] for k in keys])

    def record_unit(keys: list[str], value: Any) -> None:
        for key, (result, wall) in zip(keys, [value] if len(keys) == 1 else value, strict=True):
            record(key, result, wall)

    def task_error(keys: list[str], exc: BaseException) -> TaskError:
        if isinstance(exc, _BatchTaskFailed):
            return TaskError(experiment, pending[keys[exc.index]], exc.error)
        return TaskError(experiment, pending[keys[0]], exc)

    serial = executor is None and scheduler is None and (workers == 1 or len(units) == 1)
    if serial:
        for keys in units:
            try:
                if len(keys) == 1:
                    value: Any = _timed_call(func, pending[keys[0]])
                else:
                    value = _timed_batch(func, [pending[k] for k in keys])
            except Exception as exc:
                error = task_error(keys, exc)
                raise error from error.error
            record_unit(keys, value)
        return

    shutdown: Callable[[], None] | None = None
    client = None
    if executor is not None:
        ex = executor
    elif scheduler is not None:
        client = _dask_client(scheduler)
        # pure=False: every submission runs (tasks are unique by key anyway; no result caching)
        ex, shutdown = client.get_executor(pure=False), client.close
    else:
        n = workers if workers is not None else (os.cpu_count() or 1)
        ex = ProcessPoolExecutor(
            max_workers=min(n, len(units)),
            initializer=end_with_client,
            initargs=(os.getpid(),),
        )
        shutdown = ex.shutdown
    futures: dict[Future, list[str]] = {}
    try:
        for keys in units:
            futures[submit(ex, keys)] = keys
        for fut in as_completed(futures):
            keys = futures[fut]
            try:
                if fut.cancelled():
                    # nobody here cancels a pending task: the executor dropped it (a Dask
                    # client that lost its scheduler cancels every future)
                    raise ConnectionError("the executor cancelled the task")
                value = fut.result()
            except Exception as exc:
                for other in futures:
                    other.cancel()
                lost = fut.cancelled() or (client is not None and client.status != "running")
                if lost:
                    # keep what had already arrived: a rerun then computes only the rest
                    for other, other_keys in futures.items():
                        if (
                            other_keys[0] not in results
                            and other.done()
                            and not other.cancelled()
                            and other.exception() is None
                        ):
                            record_unit(other_keys, other.result())
                    raise _cluster_lost(experiment, scheduler, store, results, pending) from exc
                error = task_error(keys, exc)
                raise error from error.error
            record_unit(keys, value)
    finally:
        if shutdown is not None:
            if isinstance(ex, ProcessPoolExecutor):
                ex.shutdown(wait=True, cancel_futures=True)
            else:
                shutdown()


def _cluster_lost(
    experiment: str,
    scheduler: str | None,
    store: ResultStore | None,
    results: dict[str, dict],
    pending: dict[str, dict],
) -> ConnectionError:
    """The error for a run whose executor went away: not a task's fault, so no TaskError."""
    total = len(results) + sum(k not in results for k in pending)
    where = f"the Dask scheduler {scheduler}" if scheduler is not None else "the executor"
    if store is not None:
        again = "again (with a running scheduler)" if scheduler is not None else "again"
        kept = (
            f"{len(results)} of {total} tasks are stored in {store.path}; run the same "
            f"sweep {again} to compute only the rest"
        )
    else:
        kept = f"{len(results)} of {total} tasks had finished; nothing was stored (no store)"
    return ConnectionError(f"{experiment}: lost {where} before the run finished: {kept}")
