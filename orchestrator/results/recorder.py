"""Where the master's recorded rows go: in memory, or streamed to disk and to metrics in chunks.

The master fills the rows of a :class:`Recording` (one buffer per FMI type, rule 6 of
:mod:`orchestrator.cosim.master`).  Without a sink the buffers hold every row of the run and become
the :class:`~orchestrator.results.run_results.Results` the master returns (the default).  With a
*sink* the buffers hold ``chunk_rows`` rows (the sink's ``chunk_rows`` attribute when it has one,
else :data:`DEFAULT_CHUNK_ROWS`); every full buffer is handed over as one chunk (a
:class:`Results` of those rows, same columns and units) and then reused, so memory does not
grow with the flight length.  A sink has ``write(chunk)`` and ``close(header)`` (``header``:
the run's Results with zero rows and the complete metadata and step times) and ``abort()``
(the run failed: drop what was written).

Sinks:

* :class:`ParquetSink` -- one Parquet file (pyarrow; ``pandas.read_parquet`` or
  ``polars.read_parquet`` read it in one call), one row group per chunk, columns titled like
  the CSV (``time [s]``, ``Component.variable [unit]``), the run's metadata as JSON in the
  file's key-value metadata (``navfmu``).  Read back with :func:`read_parquet`.
* :class:`CsvSink` -- the CSV of :meth:`Results.to_csv`, appended chunk by chunk.
* :class:`MetricsSink` -- the metrics of every filter (:class:`~orchestrator.results.metrics.
  MetricAccumulator`) accumulated chunk by chunk, never holding the series.
* :class:`Tee` -- several sinks at once.

Files are written to a temporary name in the target's folder and renamed when the run ends,
so an interrupted or failed run leaves no half-written file.
"""
from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Sequence

import numpy as np

from ..errors import NavfmuError
from .run_results import Results, TIME_HEADER, _umask, write_csv_table

#: rows per chunk of a streamed run (about 1-3 MB of buffers for the scenarios' ~100 columns)
DEFAULT_CHUNK_ROWS = 4096
#: key of the run's metadata in a Parquet file's key-value metadata
PARQUET_METADATA_KEY = b"navfmu"

ChunkBuilder = Callable[[int, int, Dict[str, np.ndarray]], Results]


class Recording:
    """Row buffers per FMI type that the master fills, flushed to ``sink`` chunk by chunk.

    ``widths``: type -> number of recorded columns; ``to_chunk(first_row, n, buffers)`` turns
    the first ``n`` rows of the buffers into a Results (the master's column layout).
    """

    def __init__(self, n_rows: int, widths: Dict[str, int], dtypes: Dict[str, Any],
                 to_chunk: ChunkBuilder, sink=None, chunk_rows: int = DEFAULT_CHUNK_ROWS):
        self.n_rows = int(n_rows)
        self.sink = sink
        chunk_rows = getattr(sink, "chunk_rows", chunk_rows)
        self.size = self.n_rows if sink is None else max(1, min(self.n_rows, int(chunk_rows)))
        self.buffers = {t: np.zeros((self.size, w), dtype=dtypes[t]) for t, w in widths.items()}
        self.first_row = 0
        self._to_chunk = to_chunk

    def slot(self, row: int) -> int:
        """Buffer index of recorded row ``row`` (rows come in increasing order)."""
        index = row - self.first_row
        if index >= self.size:          # the buffer is full: hand it over and reuse it
            self._flush(self.size)
            index = row - self.first_row
        return index

    def _flush(self, n: int) -> None:
        if n > 0:
            self.sink.write(self._to_chunk(self.first_row, n, self.buffers))
        self.first_row += n

    def end_at(self, n_rows: int) -> None:
        """The recording ends after its first ``n_rows`` rows (a run that stopped early)."""
        self.n_rows = int(n_rows)
        if self.sink is None:
            self.size = self.n_rows

    def finish(self) -> None:
        """Hand over the rows not yet written (streamed runs)."""
        if self.sink is not None:
            self._flush(self.n_rows - self.first_row)


# ----------------------------------------------------------------------------------------
# sinks
# ----------------------------------------------------------------------------------------
class _FileSink:
    """A file written under a temporary name next to ``path`` and renamed by ``close``;
    ``_handle`` is the open writer once the first chunk came."""

    _handle: Any = None

    def __init__(self, path):
        self.path = Path(path)
        folder = self.path.parent if str(self.path.parent) else Path(".")
        if not folder.is_dir():
            raise NavfmuError(f"cannot write {self.path}: the folder {folder} does not exist")
        fd, self.tmp = tempfile.mkstemp(prefix=f".{self.path.name}.", suffix=".tmp", dir=folder)
        os.close(fd)

    def close(self, header: Results) -> Path:
        if self._handle is None:            # a run without rows: still a readable file
            self.write(header)
        self._finish(header)
        os.chmod(self.tmp, 0o666 & ~_umask())
        os.replace(self.tmp, self.path)
        return self.path

    def abort(self) -> None:
        if self._handle is not None:
            self._handle.close()
        try:
            os.unlink(self.tmp)
        except FileNotFoundError:
            pass


class ParquetSink(_FileSink):
    """Stream a run into one Parquet file (see the module docstring)."""

    def __init__(self, path, compression: str = "zstd"):
        super().__init__(path)
        self.compression = compression

    def _table(self, chunk: Results):
        import pyarrow as pa

        arrays = [pa.array(chunk.time)]
        for comp in chunk.data:
            arrays.extend(pa.array(np.ascontiguousarray(chunk.data[comp][:, j]))
                          for j in range(chunk.data[comp].shape[1]))
        return pa.Table.from_arrays(arrays, names=chunk.header())

    def write(self, chunk: Results) -> None:
        import pyarrow.parquet as pq

        table = self._table(chunk)
        if self._handle is None:
            self._handle = pq.ParquetWriter(self.tmp, table.schema, compression=self.compression,
                                            use_byte_stream_split=True, use_dictionary=False)
        self._handle.write_table(table)

    def _finish(self, header: Results) -> None:
        self._handle.add_key_value_metadata({PARQUET_METADATA_KEY: json.dumps(
            _metadata_document(header), default=str)})
        self._handle.close()


class CsvSink(_FileSink):
    """Stream a run into the CSV of :meth:`Results.to_csv` (the same bytes, written by
    :func:`~orchestrator.results.run_results.write_csv_table` chunk by chunk)."""

    def write(self, chunk: Results) -> None:
        titles = None
        if self._handle is None:
            self._handle = open(self.tmp, "wb")
            titles = chunk.header()
        write_csv_table(self._handle, chunk.table(), titles)

    def _finish(self, header: Results) -> None:
        self._handle.flush()
        os.fsync(self._handle.fileno())
        self._handle.close()


class MetricsSink:
    """Metrics of every filter of the run, accumulated chunk by chunk.

    ``window``/``samples`` as in :func:`orchestrator.results.metrics.filter_metrics`.  Each chunk is
    passed on with the last ``overlap`` rows of the previous one in front (the truth a held
    filter output is compared with may lie a few rows back); those rows are not counted
    twice.  After ``close``, :attr:`metrics` maps filter component -> metrics dict.
    """

    def __init__(self, window=None, samples: str = "all", overlap: int = 1):
        self.window = window
        self.samples = samples
        self.overlap = max(1, int(overlap))
        self.metrics: Dict[str, Dict[str, Any]] = {}
        self._acc: Optional[Dict[str, Any]] = None
        self._tail: Optional[Results] = None

    def write(self, chunk: Results) -> None:
        from . import metrics as nav_metrics

        if self._acc is None:         # no truth recorded (a replayed log without one): none
            truth = any(chunk.has(c, "truth_time") for c in chunk.components)
            self._acc = {f: nav_metrics.MetricAccumulator(chunk, f, window=self.window,
                                                          samples=self.samples)
                         for f in (nav_metrics.filters_of(chunk) if truth else ())}
        joined, skip = (chunk, 0) if self._tail is None else (_concat(self._tail, chunk),
                                                               len(self._tail.time))
        for acc in self._acc.values():
            acc.add(joined, first_row=skip)
        self._tail = _rows(joined, max(0, len(joined.time) - self.overlap))

    def close(self, header: Results) -> Dict[str, Dict[str, Any]]:
        self.metrics = {f: acc.result(header) for f, acc in (self._acc or {}).items()}
        return self.metrics

    def abort(self) -> None:
        self._acc, self._tail = None, None


class Tee:
    """Hand every chunk to each of ``sinks``."""

    def __init__(self, sinks: Sequence[Any]):
        self.sinks = [s for s in sinks if s is not None]
        self.chunk_rows = min([getattr(s, "chunk_rows", DEFAULT_CHUNK_ROWS) for s in self.sinks]
                              or [DEFAULT_CHUNK_ROWS])

    def write(self, chunk: Results) -> None:
        for s in self.sinks:
            s.write(chunk)

    def close(self, header: Results) -> List[Any]:
        return [s.close(header) for s in self.sinks]

    def abort(self) -> None:
        for s in self.sinks:
            s.abort()


def _rows(results: Results, start: int) -> Results:
    return Results(time=results.time[start:].copy(),
                   data={c: a[start:].copy() for c, a in results.data.items()},
                   columns=results.columns, units=results.units, metadata=results.metadata)


def _concat(a: Results, b: Results) -> Results:
    return Results(time=np.concatenate([a.time, b.time]),
                   data={c: np.concatenate([a.data[c], b.data[c]]) for c in b.data},
                   columns=b.columns, units=b.units, metadata=b.metadata)


def _metadata_document(header: Results) -> Dict[str, Any]:
    return {"components": list(header.data), "columns": header.columns, "units": header.units,
            "step_time_s": header.step_time_s,
            "exchange_step_time_s": header.exchange_step_time_s,
            "metadata": header.metadata}


# ----------------------------------------------------------------------------------------
# reading
# ----------------------------------------------------------------------------------------
def read_parquet(path, columns: Optional[Sequence[str]] = None) -> Results:
    """A Parquet file of :class:`ParquetSink` as Results (``columns``: only these
    ``Component.variable`` names, to read a long run in part)."""
    import pyarrow.parquet as pq

    path = Path(path)
    if not path.is_file():
        raise NavfmuError(f"results file not found: {path}")
    try:
        pf = pq.ParquetFile(path)
    except Exception as exc:  # pyarrow raises ArrowInvalid/OSError for a damaged file
        raise NavfmuError(f"{path}: not a readable Parquet file: {exc}") from None
    raw = (pf.metadata.metadata or {}).get(PARQUET_METADATA_KEY)
    if raw is None:
        raise NavfmuError(f"{path}: not a navfmu results file (no '{PARQUET_METADATA_KEY.decode()}'"
                          " metadata)")
    doc = json.loads(raw)
    wanted = None if columns is None else set(columns)
    names, units, titles = {}, {}, [TIME_HEADER]
    for comp in doc["components"]:
        for name, unit in zip(doc["columns"][comp], doc["units"][comp]):
            if wanted is not None and f"{comp}.{name}" not in wanted:
                continue
            names.setdefault(comp, []).append(name)
            units.setdefault(comp, []).append(unit)
            titles.append(f"{comp}.{name} [{unit}]" if unit else f"{comp}.{name}")
    if wanted is not None:
        missing = wanted - {f"{c}.{n}" for c in names for n in names[c]}
        if missing:
            raise NavfmuError(f"{path}: no column {', '.join(sorted(missing))}")
    table = pf.read(columns=titles)
    time = table.column(TIME_HEADER).to_numpy()
    data, j = {}, 1
    for comp, cols in names.items():
        data[comp] = np.column_stack([table.column(titles[j + i]).to_numpy()
                                      for i in range(len(cols))]) if cols else np.zeros(
            (len(time), 0))
        j += len(cols)
    return Results(time=time, data=data, columns=names, units=units,
                   step_time_s=doc.get("step_time_s", {}),
                   exchange_step_time_s=doc.get("exchange_step_time_s", {}),
                   metadata={**doc.get("metadata", {}), "source_file": str(path)})


def plot_view(path, max_rows: int = 20000) -> Results:
    """A bounded part of a long Parquet run for plots: every ``k``-th row (``k`` so that at
    most about ``max_rows`` rows remain) plus every row where a component's ``updated``
    output is set (NIS, chi-square and outlier plots need every update), read one row group
    at a time."""
    import pyarrow.parquet as pq

    full = read_parquet(path, columns=[])          # checks the file; gives the layout
    pf = pq.ParquetFile(path)
    n = pf.metadata.num_rows
    stride = max(1, -(-n // max_rows))
    doc = json.loads(pf.metadata.metadata[PARQUET_METADATA_KEY])
    titles = [TIME_HEADER] + Results(time=np.zeros(0), data={
        c: np.zeros((0, len(doc["columns"][c]))) for c in doc["components"]},
        columns=doc["columns"], units=doc["units"]).header()[1:]
    flags = [i for i, t in enumerate(titles) if t.split(" [")[0].endswith(".updated")]
    kept, first = [], 0
    for batch in pf.iter_batches(batch_size=DEFAULT_CHUNK_ROWS):
        table = np.column_stack([c.to_numpy(zero_copy_only=False) for c in batch.columns])
        rows = (first + np.arange(len(table))) % stride == 0
        for i in flags:
            rows |= table[:, i] > 0.5
        kept.append(table[rows])
        first += len(table)
    table = np.concatenate(kept) if kept else np.zeros((0, len(titles)))
    data, j = {}, 1
    for comp in doc["components"]:
        width = len(doc["columns"][comp])
        data[comp] = np.ascontiguousarray(table[:, j:j + width])
        j += width
    return Results(time=table[:, 0].copy(), data=data, columns=doc["columns"],
                   units=doc["units"], step_time_s=full.step_time_s,
                   exchange_step_time_s=full.exchange_step_time_s,
                   metadata={**full.metadata, "plot_stride": stride})


__all__ = ["plot_view", "Recording", "ParquetSink", "CsvSink", "MetricsSink", "Tee", "read_parquet",
           "DEFAULT_CHUNK_ROWS"]
