"""Recorded results of a run: time column, per-component arrays, units, timings, metadata.

Files are written atomically: to a temporary file in the target's directory, then moved over
the target with ``os.replace``, so a reader never sees a half-written file and a failed write
leaves the previous file (or none) in place.

* CSV: one file, header ``time [s]`` then ``Component.variable [unit]`` (no brackets for a
  variable without unit), each value the shortest decimal text that reads back as the same
  float64 (:func:`write_csv_table`, the one writer of results CSVs).
* NPZ: numpy's uncompressed archive; arrays plus one JSON document with the column names,
  units, step times and metadata.  No pickles; use it for long runs.
"""
from __future__ import annotations

import csv
import io
import json
import os
import re
import tempfile
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Dict, List

import numpy as np

from ..errors import NavfmuError

TIME_HEADER = "time [s]"
_HEADER_RE = re.compile(r"^(?P<name>.*?)(?: \[(?P<unit>[^\]]*)\])?$")
NPZ_FORMAT = "navfmu-results-1"
#: values formatted per polars call: about 5 MB of text, so the text of a long run is never
#: held whole in memory (and such blocks wrote faster than larger ones, docs/speed.md)
CSV_BLOCK_VALUES = 1 << 18


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


#: checks run just before a written file replaces its target; the command line's deferred
#: interrupts (:func:`orchestrator.cosim.interrupts.deferred`) add theirs, so a Ctrl-C that
#: arrives while a file is written commits nothing: a command ends either with its output
#: complete or with nothing of it written and the status of the interrupt
COMMIT_CHECKS: List[Callable[[], None]] = []


def check_commit() -> None:
    """Run :data:`COMMIT_CHECKS` (an output about to be moved into place)."""
    for check in COMMIT_CHECKS:
        check()


def atomic_write(path, write: Callable[[Any], None], binary: bool = False) -> Path:
    """Call ``write(file)`` on a temporary file next to ``path``, then move it onto ``path``.

    On any failure the temporary file is removed and ``path`` is left untouched; an
    :class:`OSError` (a full disk) becomes a :class:`NavfmuError` naming ``path`` (the
    ``OSError`` as its cause).
    """
    path = Path(path)
    directory = path.parent if str(path.parent) else Path(".")
    if not directory.is_dir():
        raise NavfmuError(f"cannot write {path}: the folder {directory} does not exist")
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=directory)
    except OSError as exc:
        raise NavfmuError(f"cannot write {path}: {exc.strerror or exc}") from None
    try:
        try:
            with os.fdopen(fd, "wb" if binary else "w", newline=None if binary else "") as f:
                write(f)
                f.flush()
                os.fsync(f.fileno())
            os.chmod(tmp, 0o666 & ~_umask())  # mkstemp creates 0600; the usual permissions
            check_commit()
            os.replace(tmp, path)
        except OSError as exc:      # a full disk, a quota: the file named, the cause kept
            raise NavfmuError(f"cannot write {path}: {exc.strerror or exc}") from exc
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise
    return path


def write_csv_table(f, table: np.ndarray, titles=None) -> None:
    """Append the rows of ``table`` (n_rows, n_columns) to the binary file ``f`` as CSV lines,
    after one title line if ``titles`` is given (``csv.writer``, UTF-8).

    The one definition of a results CSV's text: comma-separated, ``\\n`` line ends, every
    value the shortest decimal text that reads back as the same float64 (polars' writer:
    ``0.1``, ``3.0``, ``5e-324``, ``1.7976931348623157e+308``; the exponent form may vary
    between polars versions, the value does not), ``NaN``, ``inf`` and ``-inf`` for the
    non-finite values (the sign and payload of a NaN are not kept), ``-0.0`` for negative
    zero.  Python's ``float``, ``numpy.loadtxt`` and ``polars.read_csv`` read every value back
    bit for bit.  The lines of a table do not depend on how its rows are split between calls,
    so a run streamed chunk by chunk writes the bytes of the run written at once.  polars is
    imported here, on first use, not when the module is imported (it starts a thread pool).
    """
    if titles is not None:
        text = io.StringIO()
        csv.writer(text, lineterminator="\n").writerow(titles)
        f.write(text.getvalue().encode("utf-8"))
    table = np.asarray(table, dtype=np.float64)
    if table.shape[0] == 0:
        return
    import polars as pl

    rows = max(1, CSV_BLOCK_VALUES // max(1, table.shape[1]))
    # each block through a buffer of its own: polars writing to ``f`` itself may overtake
    # bytes still in ``f``'s Python buffer (the title line, with polars 1.0)
    block = io.BytesIO()
    for first in range(0, table.shape[0], rows):
        block.seek(0)
        block.truncate()
        pl.DataFrame(np.asfortranarray(table[first:first + rows]), orient="row").write_csv(
            block, include_header=False)
        with block.getbuffer() as text:
            f.write(text)


@dataclass
class Results:
    """``time`` (n_rows,), and per component: ``data[c]`` (n_rows, n_columns) float64,
    ``columns[c]`` variable names, ``units[c]`` their units ("" if none).
    ``step_time_s[c]``: mean wall time of one ``do_step`` call; ``exchange_step_time_s[c]``:
    mean wall time of set-inputs + do_step + get-outputs."""

    time: np.ndarray
    data: Dict[str, np.ndarray]
    columns: Dict[str, List[str]]
    units: Dict[str, List[str]]
    step_time_s: Dict[str, float] = field(default_factory=dict)
    exchange_step_time_s: Dict[str, float] = field(default_factory=dict)
    metadata: Dict[str, Any] = field(default_factory=dict)

    # -- access -------------------------------------------------------------------------
    @property
    def components(self) -> List[str]:
        return list(self.data)

    def _index(self, component: str, variable: str) -> int:
        if component not in self.data:
            raise NavfmuError(f"results have no component '{component}' "
                              f"(components: {', '.join(self.data)})")
        try:
            return self.columns[component].index(variable)
        except ValueError:
            raise NavfmuError(f"results have no variable '{variable}' for component "
                              f"'{component}' (recorded: {', '.join(self.columns[component])})"
                              ) from None

    def column(self, component: str, variable: str) -> np.ndarray:
        """The recorded values of ``component.variable`` (a view, one value per row)."""
        return self.data[component][:, self._index(component, variable)]

    def unit(self, component: str, variable: str) -> str:
        return self.units[component][self._index(component, variable)]

    def has(self, component: str, variable: str) -> bool:
        return component in self.columns and variable in self.columns[component]

    def header(self) -> List[str]:
        """CSV column titles: ``time [s]``, then ``Component.variable [unit]``."""
        titles = [TIME_HEADER]
        for comp in self.data:
            for name, unit in zip(self.columns[comp], self.units[comp]):
                titles.append(f"{comp}.{name} [{unit}]" if unit else f"{comp}.{name}")
        return titles

    def table(self) -> np.ndarray:
        """All values as one (n_rows, 1 + n_columns) array, time first."""
        return np.column_stack([self.time] + [self.data[c] for c in self.data])

    # -- files --------------------------------------------------------------------------
    def to_csv(self, path) -> Path:
        """Write one CSV file (atomically, :func:`write_csv_table`); returns the path."""
        table = self.table()
        return atomic_write(path, lambda f: write_csv_table(f, table, self.header()),
                            binary=True)

    def to_npz(self, path) -> Path:
        """Write a binary ``.npz`` archive (atomically); returns the path."""
        comps = list(self.data)
        index = {
            "format": NPZ_FORMAT,
            "components": comps,
            "columns": self.columns,
            "units": self.units,
            "step_time_s": self.step_time_s,
            "exchange_step_time_s": self.exchange_step_time_s,
            "metadata": self.metadata,
        }
        arrays = {"time": self.time, "index": np.array(json.dumps(index, default=str))}
        for i, c in enumerate(comps):
            arrays[f"data_{i}"] = self.data[c]
        return atomic_write(path, lambda f: np.savez(f, **arrays), binary=True)

    @classmethod
    def from_csv(cls, path) -> "Results":
        path = Path(path)
        if not path.is_file():
            raise NavfmuError(f"results file not found: {path}")
        with open(path, newline="", encoding="utf-8") as f:
            header = next(csv.reader([f.readline()]), None)
            if not header or header[0] != TIME_HEADER:
                raise NavfmuError(f"{path}: not a results CSV (the first column must be "
                                  f"'{TIME_HEADER}')")
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", UserWarning)  # "no data": header only
                    table = np.loadtxt(f, delimiter=",", ndmin=2)
            except ValueError as exc:
                raise NavfmuError(f"{path}: unreadable values: {exc}") from None
        if table.size == 0:
            table = np.zeros((0, len(header)))
        if table.shape[1] != len(header):
            raise NavfmuError(f"{path}: {table.shape[1]} values per row but {len(header)} titles")
        data_cols: Dict[str, List[int]] = {}
        columns: Dict[str, List[str]] = {}
        units: Dict[str, List[str]] = {}
        for j, title in enumerate(header[1:], start=1):
            m = _HEADER_RE.match(title)
            comp, dot, name = m.group("name").partition(".")
            if not dot:
                raise NavfmuError(f"{path}: column title '{title}' is not 'Component.variable "
                                  f"[unit]'")
            data_cols.setdefault(comp, []).append(j)
            columns.setdefault(comp, []).append(name)
            units.setdefault(comp, []).append(m.group("unit") or "")
        data = {c: np.ascontiguousarray(table[:, js]) for c, js in data_cols.items()}
        return cls(time=table[:, 0].copy(), data=data, columns=columns, units=units,
                   metadata={"source_file": str(path)})

    @classmethod
    def from_npz(cls, path) -> "Results":
        path = Path(path)
        if not path.is_file():
            raise NavfmuError(f"results file not found: {path}")
        with np.load(path, allow_pickle=False) as z:
            if "index" not in z or "time" not in z:
                raise NavfmuError(f"{path}: not a navfmu results archive")
            index = json.loads(str(z["index"]))
            if index.get("format") != NPZ_FORMAT:
                raise NavfmuError(f"{path}: unknown results format {index.get('format')!r}")
            comps = index["components"]
            data = {c: z[f"data_{i}"] for i, c in enumerate(comps)}
            time = z["time"]
        return cls(time=time, data=data, columns={c: list(index["columns"][c]) for c in comps},
                   units={c: list(index["units"][c]) for c in comps},
                   step_time_s=index.get("step_time_s", {}),
                   exchange_step_time_s=index.get("exchange_step_time_s", {}),
                   metadata=index.get("metadata", {}))


__all__ = ["Results", "atomic_write", "write_csv_table", "TIME_HEADER"]
