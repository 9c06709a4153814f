"""Run independent tasks serially, on a local process pool, or on a Dask cluster.

One executor for everything that repeats a co-simulation with other seeds or parameters
(Monte Carlo campaigns, the genetic tuner).  A *task* is a picklable callable and its
arguments; the executor returns each task's result under the key it was given, in the order
tasks finish, so a caller can write each result as soon as it exists (and resume later).

Where tasks run
---------------
* ``workers=1`` and no scheduler: in this process, one after the other (the reference: same
  numbers as any other mode, tracebacks unchanged).
* ``workers=K > 1``: a :class:`concurrent.futures.ProcessPoolExecutor` of ``K`` processes
  started with ``spawn`` (never ``fork``: a forked copy of a process that has loaded FMU
  binaries and their embedded interpreter is not safe).  A worker ends itself when the
  process that started it disappears (a driver killed with SIGKILL leaves no worker behind).  All
  instances of pythonfmu FMUs in one process share one interpreter and its GIL, so processes, not
  threads, give parallelism.
* ``scheduler="tcp://HOST:PORT"``: the tasks go to that ``dask.distributed`` scheduler; its
  workers must be able to import navfmu and reach the FMU files.
* ``local_cluster=True``: a ``dask.distributed.LocalCluster`` of ``workers`` single-threaded
  worker processes on this machine, to try the Dask path without a cluster.

Dask is an optional dependency (``pip install navfmu[dask]``); asking for it without it
installed is a :class:`~orchestrator.errors.NavfmuError`.

A task that raises stops the whole batch: the remaining tasks are cancelled and
:class:`TaskError` names the failed task's key, chained to the original exception (a user
error inside, :class:`~orchestrator.errors.NavfmuError`, keeps its message).  Ctrl-C or
SIGTERM (deferred, :mod:`orchestrator.cosim.interrupts`) is looked for every
:data:`POLL_S` while the driver waits: it cancels what has not started and shuts the
workers (and a LocalCluster) down before
:class:`~orchestrator.cosim.interrupts.Interrupted` propagates; the results yielded so far
are kept by the caller (a campaign's run files), so the campaign resumes.
"""
from __future__ import annotations

import logging
import multiprocessing
import time
import warnings
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from dataclasses import dataclass, field
from typing import Any, Callable, Dict, Hashable, Iterable, Iterator, Optional, Tuple

from ..cosim import interrupts
from ..errors import NavfmuError
from .defaults import DEFAULT_WORKERS

#: how long the driver waits for tasks before it looks for a pending Ctrl-C or SIGTERM [s]
POLL_S = 0.2
#: how long Dask workers may take to start, a scheduler to answer, a cluster to close [s]
STARTUP_TIMEOUT_S = 120.0
CONNECT_TIMEOUT_S = 10.0
CLOSE_TIMEOUT_S = 10.0

#: progress callback: (tasks done, tasks in the batch)
Progress = Callable[[int, int], None]


@dataclass(frozen=True)
class Task:
    """One unit of work: ``func(*args, **kwargs)`` stored under ``key``."""

    key: Hashable
    func: Callable[..., Any]
    args: Tuple[Any, ...] = ()
    kwargs: Dict[str, Any] = field(default_factory=dict)

    def __call__(self):
        return self.func(*self.args, **self.kwargs)


class TaskError(NavfmuError):
    """A task raised; ``key`` names it and ``__cause__`` is the original exception."""

    def __init__(self, key: Hashable, cause: BaseException):
        message = f"task {key!r} failed: {cause}" if isinstance(cause, NavfmuError) else (
            f"task {key!r} failed: {type(cause).__name__}: {cause}")
        super().__init__(message)
        self.key = key


def _run_task(task: Task):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")   # the driver has shown the user its copy of these
        return task()


def _connect(client_class, address: str):
    """A Dask client of the scheduler at ``address``; a malformed or dead address is the
    user's error."""
    try:
        return client_class(address, timeout=CONNECT_TIMEOUT_S)
    except (OSError, ValueError, TypeError) as exc:
        raise NavfmuError(f"--scheduler {address}: cannot connect: {exc}") from None


def _next_finished(finished):
    """The futures of Dask's ``as_completed`` iterator ``finished`` that are done now,
    waiting at most :data:`POLL_S` (a pending Ctrl-C or SIGTERM is a safe point here)."""
    deadline = time.monotonic() + POLL_S
    while not finished.has_ready() and time.monotonic() < deadline:
        time.sleep(0.02)
    interrupts.check()
    return finished.next_batch(block=False) if finished.has_ready() else []


def _quiet_dask_logs() -> None:
    for name in ("distributed", "tornado"):
        logging.getLogger(name).setLevel(logging.CRITICAL)


def _exit_with_parent(parent_pid: int, interval_s: float = 0.2) -> None:
    """Pool worker initializer: end this worker when the process that started it is gone
    (a killed driver must not leave workers behind, nor let them write results later)."""
    import os
    import threading
    import time

    def watch():
        while os.getppid() == parent_pid:
            time.sleep(interval_s)
        os._exit(1)

    threading.Thread(target=watch, name="navfmu-parent-watch", daemon=True).start()


@dataclass
class Executor:
    """Where tasks run (see the module docstring); reusable for several batches.

    Use as a context manager so the pool or cluster connection is closed::

        with Executor(workers=2) as ex:
            for key, result in ex.run(tasks, progress=bar):
                ...
    """

    workers: int = DEFAULT_WORKERS
    scheduler: Optional[str] = None
    local_cluster: bool = False
    _pool: Any = field(default=None, init=False, repr=False)
    _client: Any = field(default=None, init=False, repr=False)
    _cluster: Any = field(default=None, init=False, repr=False)

    def __post_init__(self):
        if isinstance(self.workers, bool) or not isinstance(self.workers, int) or self.workers < 1:
            raise NavfmuError(f"--workers: expected a whole number >= 1, got {self.workers!r}")
        if self.scheduler and self.local_cluster:
            raise NavfmuError("--scheduler and --local-cluster exclude each other: give one")

    @property
    def mode(self) -> str:
        """``serial``, ``pool`` or ``dask``."""
        if self.scheduler or self.local_cluster:
            return "dask"
        return "pool" if self.workers > 1 else "serial"

    # -- life cycle -----------------------------------------------------------------------
    def __enter__(self) -> "Executor":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        self.close(abort=exc_type is not None and issubclass(exc_type, KeyboardInterrupt))

    def close(self, abort: bool = False) -> None:
        """Shut the workers down; ``abort`` (the command was interrupted): pool workers are
        terminated at once instead of finishing the runs they are in (a run's file is
        written atomically: a terminated run leaves none)."""
        if self._pool is not None:
            if abort:
                for process in list(getattr(self._pool, "_processes", {}).values()):
                    process.terminate()
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None
        if self._client is not None or self._cluster is not None:
            _quiet_dask_logs()   # closing with tasks running: Dask logs each one it drops
        if self._client is not None:
            self._client.close(timeout=CLOSE_TIMEOUT_S)
            self._client = None
        if self._cluster is not None:
            self._cluster.close(timeout=CLOSE_TIMEOUT_S)
            self._cluster = None

    def connect(self) -> None:
        """Start or reach the workers now (a Dask scheduler or LocalCluster), so a bad
        address is refused before anything is written; pools start with the first batch."""
        if self.mode == "dask":
            self._dask_client()

    def _dask_client(self):
        if self._client is None:
            try:
                from dask.distributed import Client
            except ImportError:
                raise NavfmuError("Dask is not installed: pip install 'navfmu[dask]' "
                                  "(needed for --scheduler and --local-cluster)") from None
            if self.local_cluster:
                self._client = Client(self._start_local_cluster())
            else:
                self._client = _connect(Client, self.scheduler)
        return self._client

    def _start_local_cluster(self):
        """A LocalCluster whose worker processes ignore SIGINT (a terminal's Ctrl-C goes to
        the whole process group: the driver stops the campaign and shuts the workers down,
        they must not die mid-task with their own tracebacks).  SIGINT is ignored here only
        while the workers are being started: they inherit that, this process keeps its
        deferred handler for the rest of the wait."""
        from dask.distributed import LocalCluster

        self._cluster = LocalCluster(n_workers=0, threads_per_worker=1, processes=True,
                                     dashboard_address=None, silence_logs=logging.CRITICAL)
        before = {p.pid for p in multiprocessing.active_children()}
        with interrupts.ignored():
            self._cluster.scale(self.workers)
            deadline = time.monotonic() + STARTUP_TIMEOUT_S
            while (len({p.pid for p in multiprocessing.active_children()} - before)
                   < self.workers and time.monotonic() < deadline):
                time.sleep(0.01)
        deadline = time.monotonic() + STARTUP_TIMEOUT_S
        while len(self._cluster.scheduler_info.get("workers", {})) < self.workers:
            interrupts.check()
            if time.monotonic() > deadline:
                raise NavfmuError(f"--local-cluster: {self.workers} Dask workers did not "
                                  f"start within {STARTUP_TIMEOUT_S:.0f} s")
            time.sleep(0.05)
        return self._cluster

    def _process_pool(self):
        if self._pool is None:
            import os

            self._pool = ProcessPoolExecutor(max_workers=self.workers,
                                             mp_context=multiprocessing.get_context("spawn"),
                                             initializer=_exit_with_parent,
                                             initargs=(os.getpid(),))
        return self._pool

    # -- running ----------------------------------------------------------------------------
    def run(self, tasks: Iterable[Task], progress: Optional[Progress] = None
            ) -> Iterator[Tuple[Hashable, Any]]:
        """Yield ``(key, result)`` for every task, in the order they finish."""
        tasks = list(tasks)
        keys = [t.key for t in tasks]
        if len(set(keys)) != len(keys):
            raise NavfmuError("executor: task keys must be unique")
        total = len(tasks)
        if progress is not None:
            progress(0, total)
        runner = {"serial": self._run_serial, "pool": self._run_pool,
                  "dask": self._run_dask}[self.mode]
        for done, item in enumerate(runner(tasks), start=1):
            if progress is not None:
                progress(done, total)
            yield item

    def map(
        self, tasks: Iterable[Task], progress: Optional[Progress] = None
    ) -> Dict[Hashable, Any]:
        """All results as ``{key: result}`` (keys in task order)."""
        tasks = list(tasks)
        results = dict(self.run(tasks, progress))
        return {t.key: results[t.key] for t in tasks}

    @staticmethod
    def _run_serial(tasks):
        for task in tasks:
            try:
                result = task()
            except (KeyboardInterrupt, SystemExit):
                raise
            except Exception as exc:
                raise TaskError(task.key, exc) from exc
            yield task.key, result

    def _run_pool(self, tasks):
        pool = self._process_pool()
        pending = {pool.submit(_run_task, t): t.key for t in tasks}
        try:
            while pending:
                finished, _ = wait(pending, timeout=POLL_S, return_when=FIRST_COMPLETED)
                interrupts.safe_point("pool-waiting")
                for future in finished:
                    key = pending.pop(future)
                    exc = future.exception()
                    if exc is not None:
                        raise TaskError(key, exc) from exc
                    yield key, future.result()
        finally:
            for future in pending:
                future.cancel()

    def _run_dask(self, tasks):
        from dask.distributed import as_completed

        client = self._dask_client()
        futures = {client.submit(_run_task, t, key=f"navfmu-{i}-{t.key!r}", pure=False): t.key
                   for i, t in enumerate(tasks)}
        try:
            finished = as_completed(list(futures))
            while futures:
                for future in _next_finished(finished):
                    key = futures.pop(future)
                    if future.status == "error":
                        exc = future.exception()
                        raise TaskError(key, exc) from exc
                    yield key, future.result()
        finally:
            if futures:
                client.cancel(list(futures))


__all__ = ["Executor", "Task", "TaskError", "Progress"]
