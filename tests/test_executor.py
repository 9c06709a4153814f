"""The task executor: serial, process pool and Dask give the same results; errors name the task."""
from __future__ import annotations

import math
import operator

import pytest

from orchestrator.errors import NavfmuError
from orchestrator.campaigns.executor import Executor, Task, TaskError


def _tasks(n=6):
    return [Task(key=("run", i), func=operator.pow, args=(i + 2, 10)) for i in range(n)]


EXPECTED = {("run", i): (i + 2) ** 10 for i in range(6)}


@pytest.mark.parametrize("options", [dict(workers=1), dict(workers=2)],
                         ids=["serial", "pool"])
def test_same_results_serial_and_pool(options):
    seen = []
    with Executor(**options) as ex:
        results = ex.map(_tasks(), progress=lambda done, total: seen.append((done, total)))
    assert results == EXPECTED
    assert list(results) == list(EXPECTED)          # task order, not finishing order
    assert seen[0] == (0, 6) and seen[-1] == (6, 6) and len(seen) == 7


def test_same_results_dask_local_cluster():
    pytest.importorskip("dask.distributed", reason="Dask not installed (pip install navfmu[dask])")
    with Executor(workers=2, local_cluster=True) as ex:
        assert ex.mode == "dask"
        assert ex.map(_tasks()) == EXPECTED


@pytest.mark.parametrize("workers", [1, 2], ids=["serial", "pool"])
def test_failed_task_is_named(workers):
    tasks = _tasks(3) + [Task(key="bad", func=math.sqrt, args=(-1.0,))]
    with (
        Executor(workers=workers) as ex,
        pytest.raises(TaskError, match="task 'bad' failed: " "ValueError: math domain"),
    ):
        list(ex.run(tasks))


@pytest.mark.parametrize("options, message", [
    (dict(workers=0), "--workers: expected a whole number >= 1, got 0"),
    (dict(workers=2.5), "--workers: expected a whole number >= 1, got 2.5"),
    (dict(scheduler="tcp://127.0.0.1:1", local_cluster=True), "exclude each other"),
])
def test_bad_options(options, message):
    with pytest.raises(NavfmuError, match=message):
        Executor(**options)


def test_duplicate_keys_refused():
    with pytest.raises(NavfmuError, match="unique"):
        list(Executor().run([Task("a", abs, (1,)), Task("a", abs, (2,))]))
