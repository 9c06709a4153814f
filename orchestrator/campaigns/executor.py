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
error inside, :class:`~orchestrator.errors.NavfmuError`, keeps its message).  Ctrl-C cancels
what has not started and shuts the workers down before ``KeyboardInterrupt`` propagates.
"""
from __future__ import annotations

import multiprocessing
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from dataclasses import dataclass, field
from typing import Any, Callable, Dict, Hashable, Iterable, Iterator, Optional, Tuple

from ..errors import NavfmuError

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
    return task()


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

    workers: int = 1
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

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None
        if self._client is not None:
            self._client.close()
            self._client = None
        if self._cluster is not None:
            self._cluster.close()
            self._cluster = None

    def _dask_client(self):
        if self._client is None:
            try:
                from dask.distributed import Client, LocalCluster
            except ImportError:
                raise NavfmuError("Dask is not installed: pip install 'navfmu[dask]' "
                                  "(needed for --scheduler and --local-cluster)") from None
            if self.local_cluster:
                self._cluster = LocalCluster(n_workers=self.workers, threads_per_worker=1,
                                             processes=True, dashboard_address=None)
                self._client = Client(self._cluster)
            else:
                try:
                    self._client = Client(self.scheduler, timeout=30)
                except OSError as exc:
                    raise NavfmuError(
                        f"--scheduler {self.scheduler}: cannot connect: {exc}"
                    ) from None
        return self._client

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
                finished, _ = wait(pending, return_when=FIRST_COMPLETED)
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
            for future in as_completed(list(futures)):
                key = futures.pop(future)
                if future.status == "error":
                    exc = future.exception()
                    raise TaskError(key, exc) from exc
                yield key, future.result()
        finally:
            for future in futures:
                future.cancel()


__all__ = ["Executor", "Task", "TaskError", "Progress"]
