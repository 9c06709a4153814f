"""How a campaign groups its runs into batches (:mod:`orchestrator.cosim.batch`): on the direct
backend, the missing runs of each filter go in batches of B consecutive indices, one task
each; the FMU backend keeps one run per task (one run per FMU instance).

B is ``--batch`` when given, else chosen here: the missing runs go in about
``max(filters, 2 x workers)`` batches (one per filter when the runs are done one task at a
time; with a pool, enough tasks to keep every worker busy to the end), a filter's runs split
evenly among its batches, at most :data:`MAX_BATCH` runs, and no more than a quarter of the
memory available now holds at :data:`RUN_MEMORY_BYTES` per run.
"""
from __future__ import annotations

import math
import os
from typing import Dict, List, Optional, Sequence, Tuple

from ..errors import NavfmuError

#: the largest batch chosen automatically (a larger --batch is the user's choice)
MAX_BATCH = 64
#: memory one run of a batch needs beyond the batch's shared part [bytes]: its chunk of
#: recorded rows (4096 rows of about 100 columns, 3.3 MB), its sinks and its components'
#: state, rounded up (docs/speed.md gives the measured peak of a 64-run batch)
RUN_MEMORY_BYTES = 16 * 2 ** 20


def check_batch(batch: Optional[int], backend: str) -> None:
    """``--batch``: None (automatic) or a whole number >= 1; > 1 only on the direct backend."""
    if batch is None:
        return
    if isinstance(batch, bool) or not isinstance(batch, int) or batch < 1:
        raise NavfmuError(f"--batch: expected a whole number >= 1, got {batch!r}")
    if batch > 1 and backend != "direct":
        raise NavfmuError(f"--batch {batch}: batches run on the direct backend only (the "
                          "FMU backend runs one run per FMU instance); use --batch 1")


def available_memory() -> Optional[int]:
    """Bytes of physical memory available now, or None where the system does not say."""
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return None


def batch_size(batch: Optional[int], backend: str, missing: int, workers: int,
               filters: int = 1) -> int:
    """Runs per batch for a filter with ``missing`` runs to do, one of ``filters``, on
    ``workers`` workers (module docstring)."""
    if backend != "direct":
        return 1
    if batch is not None:
        return batch
    tasks = max(filters, 2 * workers) if workers > 1 else filters
    per_filter = max(1, math.ceil(tasks / max(1, filters)))
    size = min(MAX_BATCH, max(1, math.ceil(missing / per_filter)))
    memory = available_memory()
    if memory is not None:
        size = min(size, max(1, memory // 4 // RUN_MEMORY_BYTES))
    return size


def batches(todo: Sequence[Tuple[str, int]], batch: Optional[int], backend: str,
            workers: int) -> List[Tuple[str, List[int]]]:
    """``todo`` (filter, index) pairs grouped as (filter, indices) batches of consecutive
    missing indices of one filter, in the order of their first pair in ``todo`` (batches of
    one keep the order of ``todo``)."""
    by_filter: Dict[str, List[int]] = {}
    for name, index in todo:
        by_filter.setdefault(name, []).append(index)
    groups = []
    for name, indices in by_filter.items():
        size = batch_size(batch, backend, len(indices), workers, len(by_filter))
        groups.extend((name, indices[i:i + size]) for i in range(0, len(indices), size))
    position = {pair: k for k, pair in enumerate(todo)}
    return sorted(groups, key=lambda group: position[(group[0], group[1][0])])


__all__ = ["MAX_BATCH", "RUN_MEMORY_BYTES", "check_batch", "batch_size", "batches"]
