"""From the signal vectors to the recorded rows and the
:class:`~orchestrator.results.run_results.Results` of a run (rules 6 and 7 of
:mod:`orchestrator.cosim.master`).

:func:`row_recorder` copies the recorded signals into a row of the recording buffers;
:class:`ResultAssembly`, the part of :class:`~orchestrator.cosim.master.Simulation` that reads
them back, turns buffer rows into per-component columns with their units, and a finished run
into Results with its step times and metadata.
"""
from __future__ import annotations

from typing import Dict

import numpy as np

from .backends import NUMERIC_TYPES
from ..results.run_results import Results

#: the array type each numeric FMI type is exchanged and recorded in
SIGNAL_DTYPES = {"Real": np.float64, "Integer": np.int32, "Boolean": np.int32}


def row_recorder(vectors, rec_index, recordings):
    """``record(row)``: copy the recorded signals into row ``row`` of the recording buffers;
    a type recorded whole, in vector order, is one row copy.  The vectors may carry a leading
    run axis (a batch, :mod:`orchestrator.cosim.batch`); the buffers' rows then do too."""
    whole = [t for t in NUMERIC_TYPES
             if np.array_equal(rec_index[t], np.arange(vectors[t].shape[-1]))]
    picked = [t for t in NUMERIC_TYPES if t not in whole and len(rec_index[t])]

    def record(row):
        for t in whole:
            recordings[t][row] = vectors[t]
        for t in picked:
            vectors[t].take(rec_index[t], axis=-1, out=recordings[t][row], mode="clip")

    return record


def _column_blocks(sources):
    """``sources[j]`` = (type, column) of output column j as blocks ``(j, type, column,
    width)`` of consecutive columns of one type on both sides (one slice copy each instead
    of one per column)."""
    blocks = []
    for j, (t, c) in enumerate(sources):
        if blocks:
            start, bt, bc, width = blocks[-1]
            if bt == t and bc + width == c:
                blocks[-1] = (start, bt, bc, width + 1)
                continue
        blocks.append((j, t, c, 1))
    return blocks


class ResultAssembly:
    """The run's recorded rows and Results, as methods of the simulation that runs it."""

    def _rec_index(self, position) -> Dict[str, np.ndarray]:
        """Per type, the positions of the recorded signals in the signal vector."""
        return {t: np.array([position[(n, v)][1] for n in self.names
                             for v in self.recorded[n] if position[(n, v)][0] == t],
                            dtype=np.intp) for t in NUMERIC_TYPES}

    def _chunk(self, first_row, n_rows, recordings, rec_index, position) -> Results:
        """Rows ``first_row ..`` of the recording from the first ``n_rows`` buffer rows."""
        time_column = (self.model.start_time + (first_row + np.arange(n_rows, dtype=np.float64))
                       * (self.record_every * self.base_step))
        # column of each recorded (component, variable) inside its type's recording
        rec_col = {t: {int(g): j for j, g in enumerate(rec_index[t])} for t in NUMERIC_TYPES}
        data, columns, units = {}, {}, {}
        for d in self.components:
            n = d.spec.name
            names = self.recorded[n]
            arr = np.empty((n_rows, len(names)), dtype=np.float64)
            sources = [position[(n, v)] for v in names]
            for j, t, c, width in _column_blocks([(t, rec_col[t][g]) for t, g in sources]):
                arr[:, j:j + width] = recordings[t][:n_rows, c:c + width]
            data[n] = arr
            columns[n] = list(names)
            units[n] = [d.variables[v].unit or d.spec.units.get(v, "") for v in names]
        return Results(time=time_column, data=data, columns=columns, units=units)

    def _results(self, start, stop, n_steps, n_rows, recordings, rec_index, position,
                 timing, loop_ns) -> Results:
        h = self.base_step
        chunk = self._chunk(0, n_rows, recordings, rec_index, position)
        time_column, data, columns, units = chunk.time, chunk.data, chunk.columns, chunk.units
        do_ns, all_ns, calls = timing.do_ns, timing.all_ns, timing.calls
        step_time = {}
        exchange_time = {}
        for i, n in enumerate(self.names):
            step_time[n] = do_ns[i] / calls[i] * 1e-9 if calls[i] else float("nan")
            exchange_time[n] = all_ns[i] / calls[i] * 1e-9 if calls[i] else float("nan")
        overhead = (loop_ns - sum(all_ns)) * 1e-9 / n_steps
        metadata = {
            "model": self.model.name,
            "ssd": str(self.model.path),
            "backend": self.backend,
            "algorithm": self.algorithm,
            "base_step": h,
            "start_time": start,
            "stop_time": stop,
            "n_steps": n_steps,
            "record_every": self.record_every,
            "order": list(self.order),
            "decimation": dict(self.decimation),
            "delayed_connections": [str(c) for c in self.delayed_connections],
            "sources": {d.spec.name: d.source for d in self.components},
            "model_names": {d.spec.name: d.model_name for d in self.components},
            "hosted": [d.spec.name for d in self.components if d.hosted],
            "replaced_sources": {k: str(v) for k, v in self.model.replaced_sources.items()},
            "skipped_parameters": list(self.skipped_parameters),
            "parameters": {n: {k: v for k, v in p.items()}
                           for n, p in self.parameter_values.items()},
            "step_calls": {n: calls[i] for i, n in enumerate(self.names)},
            "wall_time_s": loop_ns * 1e-9,
            "master_overhead_s_per_step": overhead,
        }
        return Results(time=time_column, data=data, columns=columns, units=units,
                       step_time_s=step_time, exchange_step_time_s=exchange_time,
                       metadata=metadata)
