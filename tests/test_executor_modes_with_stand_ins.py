"""The task executor (orchestrator.campaigns.executor) piece by piece, without starting
processes or clusters: the serial runner's errors, the pool runner on a thread pool, the Dask
runner, the connection, the LocalCluster start-up and the pool's settings with recording
stand-ins, the waiting loops on a counting clock, closing and aborting, and the pool workers'
watch on the process that started them."""
from __future__ import annotations

import logging
import multiprocessing
import os
import signal
import sys
import threading
import warnings
from concurrent.futures import ThreadPoolExecutor
from types import SimpleNamespace

import pytest

from orchestrator.campaigns import executor as exe
from orchestrator.campaigns.executor import Executor, Task, TaskError
from orchestrator.cosim import interrupts
from orchestrator.errors import NavfmuError


class Clock:
    """Stands in for the module's ``time``: sleeping advances the clock (in whole
    nanoseconds, so that steps of 10 ms add up to 0.2 s exactly), nothing waits."""

    def __init__(self):
        self.now, self.sleeps = 1000.0, []

    def monotonic(self):
        return self.now

    def sleep(self, seconds):
        self.sleeps.append(seconds)
        self.now = round(self.now + seconds, 9)


@pytest.fixture
def clock(monkeypatch):
    c = Clock()
    monkeypatch.setattr(exe, "time", c)
    return c


def _interrupt_pending(monkeypatch):
    monkeypatch.setitem(interrupts._pending, "signal", signal.SIGINT)


def test_a_task_calls_its_function_with_its_arguments():
    assert Task("k", divmod, (17, 5))() == (3, 2)
    assert Task("k", int, ("11",), {"base": 2})() == 3
    assert Task("k", list)() == []


def test_a_task_error_names_the_key_and_the_cause():
    user = TaskError("run-1", NavfmuError("gnss: no such parameter"))
    assert str(user) == "task 'run-1' failed: gnss: no such parameter"
    other = TaskError(("run", 2), ValueError("math domain error"))
    assert str(other) == "task ('run', 2) failed: ValueError: math domain error"
    assert other.key == ("run", 2) and isinstance(other, NavfmuError)


def _warning_task():
    warnings.warn("settings skipped", UserWarning)
    return 7


def test_a_worker_runs_a_task_without_its_warnings():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert exe._run_task(Task("k", _warning_task)) == 7
        with pytest.raises(UserWarning):       # the driver's filters are left as they were
            _warning_task()


def test_the_serial_runner_stops_at_the_first_failure():
    ran = []
    tasks = [Task(i, ran.append, (i,)) for i in range(2)] + [Task("bad", int, ("x",))]
    tasks += [Task(9, ran.append, (9,))]
    with pytest.raises(TaskError) as failed:
        list(Executor().run(tasks))
    assert failed.value.key == "bad" and isinstance(failed.value.__cause__, ValueError)
    assert ran == [0, 1]
    for stop in (KeyboardInterrupt, SystemExit):
        def raising(stop=stop):
            raise stop()
        with pytest.raises(stop):
            list(Executor().run([Task("stop", raising)]))


def test_results_in_task_order_and_the_progress_of_each():
    seen = []
    tasks = [Task(k, abs, (v,)) for k, v in (("b", -2), ("a", 3), ("c", -1))]
    assert list(Executor().map(tasks, lambda d, t: seen.append((d, t))).items()) == [
        ("b", 2), ("a", 3), ("c", 1)]
    assert seen == [(0, 3), (1, 3), (2, 3), (3, 3)]
    assert list(Executor().run(iter(tasks))) == [("b", 2), ("a", 3), ("c", 1)]


@pytest.mark.parametrize("workers", [True, "2", 1.0, -1])
def test_workers_other_than_a_whole_number_from_1_are_refused(workers):
    with pytest.raises(NavfmuError, match="--workers"):
        Executor(workers=workers)


def test_the_mode_follows_the_options():
    assert Executor().mode == "serial" and Executor(workers=1).mode == "serial"
    assert Executor(workers=2).mode == "pool"
    assert Executor(scheduler="tcp://h:1").mode == "dask"
    assert Executor(workers=3, local_cluster=True).mode == "dask"
    assert Executor(workers=1, local_cluster=True).mode == "dask"
    assert Executor(scheduler="").mode == "serial"


class Recorder:
    """An object that records the calls of its named methods."""

    def __init__(self, *names, **attributes):
        self.calls = []
        self.__dict__.update(attributes)
        for name in names:
            setattr(self, name, self._recording(name))

    def _recording(self, name):
        return lambda *args, **kwargs: self.calls.append((name, args, kwargs))


def _pool_with_processes(n):
    processes = {i: Recorder("terminate") for i in range(n)}
    return Recorder("shutdown", _processes=processes), processes


@pytest.mark.parametrize("abort", [False, True])
def test_closing_shuts_the_pool_down_and_an_abort_terminates_its_workers(abort):
    ex = Executor(workers=2)
    pool, processes = _pool_with_processes(2)
    ex._pool = pool
    ex.close(abort=abort)
    assert pool.calls == [("shutdown", (), {"wait": True, "cancel_futures": True})]
    assert [p.calls for p in processes.values()] == [[("terminate", (), {})] if abort else []] * 2
    assert ex._pool is None
    ex.close(abort=abort)                         # closing twice does nothing
    assert len(pool.calls) == 1
    bare = Recorder("shutdown")                   # a pool without a process table
    ex._pool = bare
    ex.close(abort=True)
    assert bare.calls == [("shutdown", (), {"wait": True, "cancel_futures": True})]


def test_closing_by_default_lets_the_workers_finish():
    ex = Executor(workers=2)
    pool, processes = _pool_with_processes(2)
    ex._pool = pool
    ex.close()
    assert [p.calls for p in processes.values()] == [[], []] and len(pool.calls) == 1


@pytest.fixture
def dask_loggers():
    loggers = [logging.getLogger(n) for n in ("distributed", "tornado")]
    levels = [lg.level for lg in loggers]
    for lg in loggers:
        lg.setLevel(logging.NOTSET)
    yield loggers
    for lg, level in zip(loggers, levels):
        lg.setLevel(level)


@pytest.mark.parametrize("client, cluster", [(True, True), (True, False), (False, True)])
def test_closing_closes_the_client_and_cluster_with_dask_quiet(dask_loggers, client, cluster):
    ex = Executor(local_cluster=True)
    ex._client = Recorder("close") if client else None
    ex._cluster = Recorder("close") if cluster else None
    made = [x for x in (ex._client, ex._cluster) if x is not None]
    ex.close()
    assert [x.calls for x in made] == [[("close", (), {"timeout": 10.0})]] * len(made)
    assert ex._client is None and ex._cluster is None
    assert [lg.level for lg in dask_loggers] == [logging.CRITICAL] * 2


def test_closing_without_dask_leaves_its_logs_alone(dask_loggers):
    Executor().close()
    assert [lg.level for lg in dask_loggers] == [logging.NOTSET] * 2


@pytest.mark.parametrize("raised, terminated", [
    (None, False), (ValueError, False), (KeyboardInterrupt, True),
    (interrupts.Interrupted, True)])
def test_leaving_the_block_aborts_only_on_an_interrupt(raised, terminated):
    pool, processes = _pool_with_processes(1)
    caught = None
    try:
        with Executor(workers=2) as ex:
            ex._pool = pool
            if raised:
                raise raised()
    except BaseException as exc:          # noqa: B902 - the test raised it
        caught = exc
    assert isinstance(ex, Executor)
    assert (type(caught) is raised) if raised else caught is None
    assert bool(processes[0].calls) is terminated and ex._pool is None


def test_the_pool_is_made_once_with_spawned_workers_that_watch_this_process(monkeypatch):
    made = []

    def pool_class(**kwargs):
        made.append(kwargs)
        return SimpleNamespace(kwargs=kwargs)

    monkeypatch.setattr(exe, "ProcessPoolExecutor", pool_class)
    ex = Executor(workers=3)
    pool = ex._process_pool()
    assert ex._process_pool() is pool and len(made) == 1
    settings = made[0]
    assert settings["max_workers"] == 3
    assert settings["mp_context"].get_start_method() == "spawn"
    assert settings["initializer"] is exe._exit_with_parent
    assert settings["initargs"] == (os.getpid(),)


def _slow_abs(x, started, release):
    started.set()
    release.wait(5.0)
    return abs(x)


def test_the_pool_runner_on_a_thread_pool():
    ex = Executor(workers=2)
    ex._pool = ThreadPoolExecutor(max_workers=2)
    tasks = [Task(i, pow, (i, 2)) for i in range(5)]
    assert ex.map(tasks) == {i: i * i for i in range(5)}
    ex.close()


def test_the_pool_runner_runs_each_task_without_its_warnings():
    ex = Executor(workers=2)
    ex._pool = ThreadPoolExecutor(max_workers=1)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert list(ex.run([Task("w", _warning_task)])) == [("w", 7)]
    ex.close()


def test_the_pool_runner_takes_each_result_as_it_comes_polling_for_interrupts(monkeypatch):
    waits, real_wait = [], exe.wait

    def recording_wait(futures, **kwargs):
        waits.append(kwargs)
        return real_wait(futures, **kwargs)

    monkeypatch.setattr(exe, "wait", recording_wait)
    ex = Executor(workers=2)
    ex._pool = ThreadPoolExecutor(max_workers=2)
    assert sorted(ex.run([Task(i, abs, (-i,)) for i in range(3)])) == [(0, 0), (1, 1), (2, 2)]
    ex.close()
    assert waits and all(w == {"timeout": 0.2, "return_when": "FIRST_COMPLETED"} for w in waits)


def test_the_pool_runner_waits_at_the_safe_point_named_pool_waiting(monkeypatch):
    monkeypatch.setenv(interrupts.SIGNAL_AT_ENV, "pool-waiting:INT")
    monkeypatch.setitem(interrupts._pending, "fired", set())
    ex = Executor(workers=2)
    ex._pool = ThreadPoolExecutor(max_workers=1)
    with pytest.raises(interrupts.Interrupted), interrupts.deferred():
        list(ex.run([Task("a", abs, (-1,))]))
    ex.close()
    assert interrupts._pending["fired"] == {"pool-waiting"}


def test_the_pool_runner_names_a_failure_and_cancels_what_waits():
    ex = Executor(workers=2)
    ex._pool = ThreadPoolExecutor(max_workers=1)
    started, release = threading.Event(), threading.Event()
    ran = []
    tasks = [Task("bad", int, ("x",)), Task("slow", _slow_abs, (-1, started, release))]
    tasks += [Task(i, ran.append, (i,)) for i in range(3)]
    with pytest.raises(TaskError) as failed:
        list(ex.run(tasks))
    assert failed.value.key == "bad" and isinstance(failed.value.__cause__, ValueError)
    release.set()
    ex.close()
    assert ran == []


def test_the_pool_runner_stops_at_an_interrupt_and_cancels_what_waits(monkeypatch):
    ex = Executor(workers=2)
    ex._pool = ThreadPoolExecutor(max_workers=1)
    started, release = threading.Event(), threading.Event()
    ran = []
    tasks = [Task("slow", _slow_abs, (-1, started, release))]
    tasks += [Task(i, ran.append, (i,)) for i in range(3)]
    runs = ex.run(tasks)
    _interrupt_pending(monkeypatch)
    with pytest.raises(interrupts.Interrupted):
        next(runs)
    release.set()
    ex.close()
    assert started.is_set() and ran == []


class FakeFuture:
    def __init__(self, result=None, error=None):
        self.status = "error" if error else "finished"
        self._result, self._error = result, error

    def exception(self):
        return self._error

    def result(self):
        return self._result


class FakeClient:
    """Stands in for a dask.distributed Client: runs each submitted task at once."""

    def __init__(self):
        self.submitted, self.cancelled = [], []

    def submit(self, func, task, key, pure):
        self.submitted.append((func, task.key, key, pure))
        try:
            return FakeFuture(result=func(task))
        except Exception as exc:      # noqa: BLE001 - what a Dask future holds
            return FakeFuture(error=exc)

    def cancel(self, futures):
        self.cancelled.append(futures)


class FakeAsCompleted:
    """Stands in for dask.distributed.as_completed: one future ready at a time."""

    def __init__(self, futures):
        self.waiting = list(futures)

    def has_ready(self):
        return bool(self.waiting)

    def next_batch(self, block):
        assert block is False
        return [self.waiting.pop(0)]


@pytest.fixture
def fake_dask(monkeypatch):
    distributed = pytest.importorskip("dask.distributed")
    monkeypatch.setattr(distributed, "as_completed", FakeAsCompleted)
    client = FakeClient()
    return client


def test_the_dask_runner_submits_each_task_under_a_unique_key(fake_dask):
    ex = Executor(scheduler="tcp://h:1")
    ex._client = fake_dask
    tasks = [Task(("run", 1), pow, (2, 3)), Task("b", abs, (-4,))]
    assert list(ex.run(tasks)) == [(("run", 1), 8), ("b", 4)]
    assert fake_dask.submitted == [(exe._run_task, ("run", 1), "navfmu-0-('run', 1)", False),
                                   (exe._run_task, "b", "navfmu-1-'b'", False)]
    assert fake_dask.cancelled == []


def test_the_dask_runner_names_a_failure_and_cancels_the_rest(fake_dask):
    ex = Executor(scheduler="tcp://h:1")
    ex._client = fake_dask
    tasks = [Task("a", abs, (-1,)), Task("bad", int, ("x",)), Task("c", abs, (2,))]
    runs = ex.run(tasks)
    assert next(runs) == ("a", 1)
    with pytest.raises(TaskError) as failed:
        next(runs)
    assert failed.value.key == "bad" and isinstance(failed.value.__cause__, ValueError)
    (cancelled,), = fake_dask.cancelled
    assert cancelled.result() == 2 and len(fake_dask.cancelled[0]) == 1


class Finished:
    """A Dask as_completed iterator whose batch is ready after ``ready_after`` looks."""

    def __init__(self, ready_after):
        self.looks, self.ready_after = 0, ready_after

    def has_ready(self):
        self.looks += 1
        return self.looks > self.ready_after

    def next_batch(self, block):
        return ["done"] if block is False else None


def test_waiting_for_dask_polls_every_20_ms_for_at_most_the_poll_time(clock):
    assert exe._next_finished(Finished(3)) == ["done"]
    assert clock.sleeps == [0.02] * 3
    clock.sleeps.clear()
    assert exe._next_finished(Finished(10 ** 6)) == []
    assert clock.sleeps == [0.02] * 10          # 0.2 s in steps of 20 ms


def test_waiting_for_dask_is_a_safe_point(clock, monkeypatch):
    _interrupt_pending(monkeypatch)
    with pytest.raises(interrupts.Interrupted):
        exe._next_finished(Finished(0))


def test_quieting_dask_sets_its_loggers_to_critical(dask_loggers):
    exe._quiet_dask_logs()
    assert [lg.level for lg in dask_loggers] == [logging.CRITICAL] * 2


@pytest.mark.parametrize("error", [OSError, ValueError, TypeError])
def test_a_scheduler_that_cannot_be_reached_is_the_users_error(error):
    def client_class(address, timeout):
        raise error("refused")
    with pytest.raises(NavfmuError, match="^--scheduler tcp://h:1: cannot connect: refused"):
        exe._connect(client_class, "tcp://h:1")


def test_connecting_passes_the_address_and_the_timeout():
    def client_class(*args, **kwargs):
        return (args, kwargs)
    assert exe._connect(client_class, "tcp://h:1") == (("tcp://h:1",), {"timeout": 10.0})


def test_connect_reaches_dask_once_and_only_in_dask_mode(monkeypatch):
    distributed = pytest.importorskip("dask.distributed")
    made = []
    monkeypatch.setattr(distributed, "Client", lambda *a, **kw: made.append((a, kw)) or a)
    Executor().connect()
    Executor(workers=2).connect()
    assert made == []
    ex = Executor(scheduler="tcp://h:1")
    ex.connect()
    ex.connect()
    assert made == [(("tcp://h:1",), {"timeout": 10.0})] and ex._client == ("tcp://h:1",)
    cluster = SimpleNamespace()
    local = Executor(workers=2, local_cluster=True)
    monkeypatch.setattr(local, "_start_local_cluster", lambda: cluster)
    local.connect()
    assert made[1] == ((cluster,), {})


def test_dask_without_dask_installed_is_the_users_error(monkeypatch):
    monkeypatch.setitem(sys.modules, "dask.distributed", None)
    with pytest.raises(NavfmuError, match="Dask is not installed"):
        Executor(scheduler="tcp://h:1").connect()


class FakeCluster:
    """Stands in for a LocalCluster: ``scale`` starts ``n`` children, which register with
    the scheduler one look after another."""

    def __init__(self, children, registering=True, **kwargs):
        self.kwargs, self.children, self.registering = kwargs, children, registering
        self.scaled, self.sigint_while_scaling, self.looks = [], None, 0

    def scale(self, n):
        self.scaled.append(n)
        self.sigint_while_scaling = signal.getsignal(signal.SIGINT)
        self.children.pending = n

    @property
    def scheduler_info(self):
        self.looks += 1
        n = min(self.looks, self.scaled[-1]) if self.registering else 0
        return {"workers": {i: {} for i in range(n)}}


class Children:
    """Stands in for multiprocessing: one child process more at each look after a scale."""

    def __init__(self):
        self.started, self.pending = [SimpleNamespace(pid=1)], 0

    def active_children(self):
        if self.pending:
            self.pending -= 1
            self.started.append(SimpleNamespace(pid=100 + len(self.started)))
        return list(self.started)


@pytest.fixture
def local_cluster(monkeypatch, clock):
    distributed = pytest.importorskip("dask.distributed")
    children = Children()
    made = []

    def cluster_class(registering=True):
        def make(**kwargs):
            made.append(FakeCluster(children, registering, **kwargs))
            return made[-1]
        monkeypatch.setattr(distributed, "LocalCluster", make)

    monkeypatch.setattr(exe, "multiprocessing", children)
    return SimpleNamespace(made=made, children=children, clock=clock, use=cluster_class)


def test_a_local_cluster_of_single_threaded_workers_that_ignore_ctrl_c(local_cluster):
    local_cluster.use()
    ex = Executor(workers=2, local_cluster=True)
    before = signal.getsignal(signal.SIGINT)
    assert ex._start_local_cluster() is ex._cluster
    cluster, = local_cluster.made
    assert cluster.kwargs == {"n_workers": 0, "threads_per_worker": 1, "processes": True,
                              "dashboard_address": None, "silence_logs": logging.CRITICAL}
    assert cluster.scaled == [2] and cluster.sigint_while_scaling == signal.SIG_IGN
    assert signal.getsignal(signal.SIGINT) == before
    # two looks to see both children started (one sleep of 10 ms between), then two looks
    # at the scheduler (one of 50 ms)
    assert local_cluster.clock.sleeps == [0.01, 0.05]
    assert cluster.looks == 2


def test_a_local_cluster_whose_workers_do_not_register_gives_up(local_cluster):
    local_cluster.use(registering=False)
    ex = Executor(workers=2, local_cluster=True)
    with pytest.raises(NavfmuError, match="--local-cluster"):
        ex._start_local_cluster()
    sleeps = local_cluster.clock.sleeps
    assert sleeps[0] == 0.01 and set(sleeps[1:]) == {0.05}
    # 120 s in steps of 50 ms, and one more: at 120 s exactly it has not given up yet
    assert len(sleeps) == 1 + 2401


def test_a_local_cluster_start_is_a_safe_point(local_cluster, monkeypatch):
    local_cluster.use(registering=False)
    _interrupt_pending(monkeypatch)
    with pytest.raises(interrupts.Interrupted):
        Executor(workers=1, local_cluster=True)._start_local_cluster()


def test_a_local_cluster_whose_processes_do_not_start_waits_at_most_the_startup_time(
        local_cluster):
    local_cluster.use()
    local_cluster.children.active_children = lambda: [SimpleNamespace(pid=1)]
    ex = Executor(workers=2, local_cluster=True)
    ex._start_local_cluster()
    first = [s for s in local_cluster.clock.sleeps if s == 0.01]
    assert len(first) == 12000                   # 120 s in steps of 10 ms


class Parent:
    """Stands in for os.getppid: the parent is there for ``alive`` looks, then gone."""

    def __init__(self, pid, alive):
        self.pid, self.alive, self.looks = pid, alive, 0

    def __call__(self):
        self.looks += 1
        return self.pid if self.looks <= self.alive else 1


def test_a_pool_worker_ends_itself_when_its_parent_is_gone(monkeypatch):
    import time

    parent = Parent(pid=4242, alive=3)
    ended, naps = threading.Event(), []
    seen = {}

    def exit_now(code):
        thread = threading.current_thread()
        seen.update(code=code, name=thread.name, daemon=thread.daemon, looks=parent.looks)
        ended.set()

    sleep = time.sleep
    monkeypatch.setattr(os, "getppid", parent)
    monkeypatch.setattr(os, "_exit", exit_now)
    monkeypatch.setattr(time, "sleep", lambda s: naps.append(s) or sleep(0.001))
    exe._exit_with_parent(4242, interval_s=0.5)
    assert ended.wait(5.0)
    assert seen == {"code": 1, "name": "navfmu-parent-watch", "daemon": True, "looks": 4}
    assert naps[:3] == [0.5] * 3
    parent.looks, parent.alive = 0, 1
    naps.clear()
    ended.clear()
    exe._exit_with_parent(4242)
    assert ended.wait(5.0) and naps[:1] == [0.2]
