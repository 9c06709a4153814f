"""The recording of a batch of runs (:mod:`orchestrator.cosim.batch`): one row buffer per FMI
type with a run axis, ``(rows, B, columns)``, filled by one copy per recorded row for every run
at once, handed to each run's own sink chunk by chunk (the chunks of
:class:`~orchestrator.results.recorder.Recording`, one per run).

Without sinks every row stays in memory, as for one run without a sink.  :meth:`keep` drops
runs (a run that failed: its sink was aborted by the master).
"""
from __future__ import annotations

from typing import Any, Dict, List, Optional, Sequence

import numpy as np

from .recorder import DEFAULT_CHUNK_ROWS, ChunkBuilder, Recording


class BatchRecording(Recording):
    """Row buffers ``(rows, B, width)`` per type; ``sinks[b]`` receives run b's chunks
    (all None: no sink, every row kept); :meth:`slot` and :meth:`finish` as for one run."""

    def __init__(self, n_rows: int, sinks: Sequence[Optional[Any]], widths: Dict[str, int],
                 dtypes: Dict[str, Any], to_chunk: ChunkBuilder,
                 chunk_rows: int = DEFAULT_CHUNK_ROWS):
        self.n_rows = int(n_rows)
        self.sinks: List[Optional[Any]] = list(sinks)
        self.streamed = any(s is not None for s in self.sinks)
        if self.streamed and not all(s is not None for s in self.sinks):
            raise ValueError("a batch's runs are all streamed to sinks or all kept in memory")
        if self.streamed:
            chunk_rows = min(getattr(s, "chunk_rows", chunk_rows) for s in self.sinks)
        self.size = max(1, min(self.n_rows, int(chunk_rows))) if self.streamed else self.n_rows
        runs = len(self.sinks)
        self.buffers = {t: np.zeros((self.size, runs, w), dtype=dtypes[t])
                        for t, w in widths.items()}
        self.first_row = 0
        self._to_chunk = to_chunk
        self.sink = self.sinks if self.streamed else None     # Recording.finish flushes

    def run_buffers(self, b: int, n: Optional[int] = None) -> Dict[str, np.ndarray]:
        """Run ``b``'s rows of the buffers (the first ``n``), as (rows, width) views."""
        n = self.size if n is None else n
        return {t: buf[:n, b, :] for t, buf in self.buffers.items()}

    def _flush(self, n: int) -> None:
        if n > 0:
            for b, sink in enumerate(self.sinks):
                sink.write(self._to_chunk(self.first_row, n, self.run_buffers(b, n)))
        self.first_row += n

    def keep(self, rows: Sequence[int]) -> None:
        """Keep the runs of batch ``rows`` (in that order); the buffers change in place in
        the dict (the master's row recorder reads them through it)."""
        rows = list(rows)
        for t in list(self.buffers):
            self.buffers[t] = np.ascontiguousarray(self.buffers[t][:, rows, :])
        self.sinks = [self.sinks[i] for i in rows]
        self.sink = self.sinks if self.streamed else None


__all__ = ["BatchRecording"]
