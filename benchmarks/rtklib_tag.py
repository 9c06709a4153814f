"""The times of a logger's IMU samples from RTKLIB's time-tag file of the logged stream.

RTKLIB's ``str2str``/``strsvr`` writing a stream to ``FILE`` with time tags writes
``FILE.tag``: a 60-byte header, then uint32 tick (ms), uint32 seconds (UNIX, GPST) and a
float64 fraction (the start), then one record per write, (uint32 ms since the start, uint32
the file's length after the write), little-endian.  A record says the bytes up to its length
had arrived by its tick: the time each line of the log arrived.

Arrival is not sampling: a serial or USB link delivers lines in chunks, the first ones often
in a burst (the walk of the peer's data set delivers its first 17 lines, 100 ms of samples,
in one write 113 ms after the start).  The logger's own millisecond counter times the
samples evenly; :func:`sample_times` fits it to the arrivals (least squares, the arrivals more
than 3 sigma off the first fit left out, the burst among them), so each sample gets the time
of its counter on the GPST scale, the link's mean delay included (what a config's time
offset, such as the peer's ``imu_t_off``, then corrects).

The tag file counts the bytes as written by the logger; a log whose line ends were changed
since (CR LF to LF) is recognised by its length (its length plus one byte per line is the
last record's) and counted as written.
"""
from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

#: the header of a tag file [bytes] and where its start (seconds, fraction) is
_HEADER, _SECONDS_AT, _FRACTION_AT = 76, 64, 68


def tag_records(tag_file: Path):
    """(UNIX start time on GPST [s], records: (ms since the start, file length after the
    write) as a float array n x 2)."""
    raw = Path(tag_file).read_bytes()
    seconds, = struct.unpack_from("<I", raw, _SECONDS_AT)
    fraction, = struct.unpack_from("<d", raw, _FRACTION_AT)
    records = np.frombuffer(raw[_HEADER:_HEADER + (len(raw) - _HEADER) // 8 * 8],
                            dtype="<u4").reshape(-1, 2)
    return seconds + fraction, records.astype(float)


def line_arrivals(lines, records):
    """[ms] the tick at which each line of ``lines`` (bytes, without their line ends) had
    arrived, NaN after the last record; line ends of one byte, or of two when the records
    count them so (module docstring)."""
    lengths = np.array([len(line) + 1 for line in lines], dtype=float)
    total = lengths.sum()
    extra = 1.0 if abs(records[-1, 1] - total - len(lines)) < abs(records[-1, 1] - total) \
        else 0.0
    ends = np.cumsum(lengths + extra)
    k = np.searchsorted(records[:, 1], ends, side="left")
    out = np.full(len(lines), np.nan)
    inside = k < len(records)
    out[inside] = records[k[inside], 0]
    return out


def counter_fit(counter, arrival_ms):
    """(ms at counter[0], ms per count) of the least-squares line through the arrivals,
    fitted again without those more than 3 sigma off the first fit."""
    keep = np.isfinite(arrival_ms)
    x, y = counter[keep] - counter[0], arrival_ms[keep]
    use = np.ones(len(x), bool)
    for _ in range(2):
        a, b = np.polynomial.polynomial.polyfit(x[use], y[use], 1)
        residual = y - (a + b * x)
        use = np.abs(residual) <= 3.0 * residual[use].std()
    return float(a), float(b)


def sample_times(lines, counter, rows_of_lines, tag_file: Path):
    """[s] UNIX GPST time of each sample: its ``counter`` [ms] through :func:`counter_fit`
    of the arrivals of ``lines`` (all the file's lines, bytes); ``rows_of_lines`` the index in
    ``lines`` of each sample."""
    start, records = tag_records(tag_file)
    arrivals = line_arrivals(lines, records)[rows_of_lines]
    a, b = counter_fit(counter, arrivals)
    return start + (a + b * (counter - counter[0])) / 1000.0
