"""The one default of each concept the commands share, so that ``montecarlo``, ``report``,
``tune`` and ``verify`` (and the functions behind them) agree and their help shows it.

* :data:`DEFAULT_WORKERS`: 1, every run in this process, one after the other: the reference
  the pool and Dask reproduce number for number, and no process started unasked;
* :data:`DEFAULT_SEED`: the campaign seed (run ``i`` uses ``seed + i``) and the genetic
  algorithm's own seed;
* :data:`DEFAULT_RUNS`: seeds per filter and case where a command picks the count itself
  (``report``, ``verify``);
* :data:`BENCH_RUNS`, :data:`BENCH_WORKERS`: the campaign ``navfmu bench --executors`` times
  serially and on a pool (a pool of one would measure no speed-up, hence its own default).
"""
from __future__ import annotations

DEFAULT_WORKERS = 1
DEFAULT_SEED = 1
DEFAULT_RUNS = 3
BENCH_RUNS = 8
BENCH_WORKERS = 2

__all__ = ["DEFAULT_WORKERS", "DEFAULT_SEED", "DEFAULT_RUNS", "BENCH_RUNS", "BENCH_WORKERS"]
