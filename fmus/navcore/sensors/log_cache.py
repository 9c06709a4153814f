"""Sensor logs read once per process: every run and every component replaying one log share
its parsed arrays.

Parsing a log's CSV text is the costly part of replaying it (about a second per 10 minutes of
200 Hz IMU lines); a campaign, a tuning run or a filter comparison replays the same log in
every run, and within a run both the master (to fit the run's span to the log) and the
replay component read it.  :func:`shared_log` keeps the parsed and checked
:class:`~navcore.sensors.sensorlog.SensorLog` per process, keyed on the folder, the
``max_dt_jitter`` bound it was checked with and the content of its files.  A use whose files
carry the stamps they had when they were read (device, inode, size, modification time and
status-change time, which the system sets on every write and on every change of the
modification time) takes the kept log; otherwise the files' bytes are hashed (BLAKE2b): a log
only touched is kept, a changed one is read and checked again.  So a file rewritten in any
way, even at the same size with its modification time set back, is parsed again.

Place and lifetime: in the memory of the process only (nothing is written next to the log or
anywhere else), at most :data:`MAX_LOGS` logs (the least recently used one is dropped first),
until the process ends.  The arrays are read-only: a caller that wants to change a log reads
its own copy with :func:`~navcore.sensors.sensorlog.read_log`.  ``NAVFMU_SHARED_LOGS=0`` turns
the cache off (every call parses), for measuring what a single run costs.
"""
from __future__ import annotations

import hashlib
import os
import threading
from collections import OrderedDict
from pathlib import Path
from typing import Optional, Tuple

from .log_time import DEFAULT_MAX_DT_JITTER
from .sensorlog import LOG_FILES, MAX_FILE_BYTES, SensorLog, read_log

#: the most logs a process keeps parsed
MAX_LOGS = 4
_CHUNK = 1 << 22

_lock = threading.Lock()
#: (folder, max_dt_jitter) -> (the files' stamps, their contents' hashes, the log)
_logs: "OrderedDict[Tuple[str, float], tuple]" = OrderedDict()
#: how many times a log was parsed by :func:`shared_log` in this process (tests read it)
parses = 0


def _file_hash(path: Path) -> Optional[str]:
    """The BLAKE2b digest of the file's bytes; None when there is no such file (or it is too
    large to be a log: :func:`read_log` then says so)."""
    try:
        if path.stat().st_size > MAX_FILE_BYTES:
            return None
        digest = hashlib.blake2b(digest_size=20)
        with open(path, "rb") as f:
            for chunk in iter(lambda: f.read(_CHUNK), b""):
                digest.update(chunk)
        return digest.hexdigest()
    except OSError:
        return None


def _content(folder: Path) -> Tuple[Optional[str], ...]:
    return tuple(_file_hash(folder / name) for name in LOG_FILES)


def _stamps(folder: Path) -> Tuple[Optional[tuple], ...]:
    """Per file: (device, inode, size, modification and status-change time [ns]), None
    when absent.  The system sets the status-change time on every write (and on setting
    the modification time back), so equal stamps mean files not written since."""
    stamps = []
    for name in LOG_FILES:
        try:
            st = os.stat(folder / name)
        except OSError:
            stamps.append(None)
            continue
        stamps.append((st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns, st.st_ctime_ns))
    return tuple(stamps)


def _frozen(log: SensorLog) -> SensorLog:
    for table in (log.imu, log.gnss, log.truth):
        for values in (table or {}).values():
            values.setflags(write=False)
    return log


def enabled() -> bool:
    return os.environ.get("NAVFMU_SHARED_LOGS", "1") != "0"


def shared_log(folder, max_dt_jitter: float = DEFAULT_MAX_DT_JITTER) -> SensorLog:
    """The log in ``folder`` as :func:`~navcore.sensors.sensorlog.read_log` reads it (the same
    checks, the same errors), parsed once per process and content (module docstring)."""
    global parses
    folder = Path(folder).resolve()
    if not enabled():
        parses += 1
        return read_log(folder, max_dt_jitter)
    key = (str(folder), float(max_dt_jitter))
    with _lock:
        if not folder.is_dir():
            parses += 1
            return read_log(folder, max_dt_jitter)      # its error
        stamps = _stamps(folder)
        held = _logs.get(key)
        if held is not None and held[0] == stamps:       # not written since it was read
            _logs.move_to_end(key)
            return held[2]
        content = _content(folder)
        if held is not None and held[1] == content:      # touched, not changed
            _logs[key] = (stamps, content, held[2])
            _logs.move_to_end(key)
            return held[2]
        parses += 1
        log = _frozen(read_log(folder, max_dt_jitter))
        # kept only when the files did not change while they were parsed
        if None not in content[:2] and _stamps(folder) == stamps:
            _logs[key] = (stamps, content, log)
            _logs.move_to_end(key)
            while len(_logs) > MAX_LOGS:
                _logs.popitem(last=False)
        return log


def derived(log: SensorLog, name: str, make):
    """``make(log)``, computed once per log object and kept with it: what every user of a
    shared log builds from it the same way (a replay's tables), held once per process;
    treat the result as read-only too."""
    held = log.__dict__.setdefault("_derived", {})
    value = held.get(name)
    if value is None:
        with _lock:
            value = held.get(name)
            if value is None:
                value = held[name] = make(log)
    return value


def clear() -> None:
    """Forget every log kept (the next call of each parses again)."""
    with _lock:
        _logs.clear()


__all__ = ["MAX_LOGS", "shared_log", "derived", "clear", "enabled"]
