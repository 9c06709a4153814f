"""A run's output folder: written whole in a staging folder beside it, then moved into place.

The files of one command (results, metrics, report, plots) are written into a hidden staging
folder ``.<name>.<host>-<pid>.<random>.partial`` next to the target folder (a Parquet file
streamed while the run goes is written into another such folder and moved in,
:func:`move_into`).  Only when every file is there is the staging folder moved onto the
target: under an exclusive lock (``fcntl.flock`` on the parent folder) the previous folder
is renamed aside, the staging folder renamed to the
target, and the previous folder deleted.  So

* the target holds the files of exactly one command: a failed, interrupted or killed command
  leaves the previous folder as it was (plus, after a kill, a hidden ``.partial`` folder),
  never a mixture, and no file of an earlier command survives beside the new ones (``run``
  then ``compare`` into one folder leaves no stale ``results.csv``);
* two commands writing to one folder at the same time each stage their own files, and the
  lock serializes the moves: the folder ends up with one command's files, whole;
* the staging (and set-aside) folders of a command that was killed (SIGKILL, a power cut)
  are removed by the next command into the same target: their name holds the host and the
  process id that made them, and a folder of this host whose process is gone is stale.

A folder that exists already is only replaced if it is an output folder: it holds the
marker file :data:`MARKER` (written into every output folder) or only files of the kinds we
write (``.csv``, ``.npz``, ``.json``, ``.png``).  Anything else is refused before the run.
"""
from __future__ import annotations

import contextlib
import fcntl
import os
import shutil
import socket
import tempfile
from pathlib import Path
from typing import Iterator

from ..errors import NavfmuError
from .run_results import _umask

#: marker file listing the outputs of the command that wrote the folder
MARKER = ".navfmu-outputs"
#: file kinds an output folder written before the marker existed may hold
OUTPUT_SUFFIXES = (".csv", ".npz", ".json", ".png", ".parquet")


def _is_output_folder(path: Path) -> bool:
    if (path / MARKER).is_file():
        return True
    return all(p.is_file() and p.suffix in OUTPUT_SUFFIXES for p in path.iterdir())


def _temporary(target: Path, suffix: str) -> Path:
    """A new hidden folder beside ``target`` named after it, this host and this process."""
    return Path(tempfile.mkdtemp(prefix=f".{target.name}.{_OWNER}-{os.getpid()}.",
                                 suffix=suffix, dir=target.parent))


_OWNER = "".join(c if c.isalnum() else "_" for c in socket.gethostname())


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def remove_stale(target) -> None:
    """Remove the staging and set-aside folders beside ``target`` left by a killed command
    of this host (see the module docstring)."""
    target = Path(target).absolute()
    prefix = f".{target.name}.{_OWNER}-"
    try:
        entries = list(target.parent.iterdir())
    except OSError:
        return
    for p in entries:
        if not (p.name.startswith(prefix) and p.name.endswith((".partial", ".old"))):
            continue
        pid = p.name[len(prefix):].split(".", 1)[0]
        if pid.isdigit() and not _alive(int(pid)) and p.is_dir():
            shutil.rmtree(p, ignore_errors=True)


def check_target(target) -> Path:
    """Refuse, before any work, an output folder that could not be written or must not be
    replaced; a staging folder is created and removed beside it to prove it writable (and
    stale ones of killed commands are removed)."""
    target = Path(target)
    if not str(target).strip():
        raise NavfmuError("--out: empty path; give a folder")
    if target.exists() and not target.is_dir():
        raise NavfmuError(f"--out {target}: exists and is not a folder")
    if target.is_dir() and not _is_output_folder(target):
        raise NavfmuError(f"--out {target}: the folder holds files navfmu did not write (no "
                          f"{MARKER}); choose a new or empty folder")
    parent = target.absolute().parent
    try:
        parent.mkdir(parents=True, exist_ok=True)
        os.rmdir(_temporary(parent / target.name, ".partial"))
    except OSError as exc:
        raise NavfmuError(f"--out {target}: cannot write into {parent}: "
                          f"{exc.strerror or exc}") from None
    remove_stale(target)
    return target


def check_writable(path, what: str, folder: bool = False) -> Path:
    """Refuse, before any work, a file (or, ``folder``, a folder) ``path`` that cannot be
    written: it exists as the other kind, or no file can be created in its folder (the
    nearest existing one: missing folders are made when the output is written).  A probe
    file is created and removed there; nothing else is touched."""
    path = Path(path)
    if not str(path).strip():
        raise NavfmuError(f"{what}: empty path")
    if path.is_dir() and not folder:
        raise NavfmuError(f"{what} {path}: is a folder; give a file name")
    if path.exists() and folder and not path.is_dir():
        raise NavfmuError(f"{what} {path}: exists and is not a folder")
    parent = path.absolute().parent
    while not parent.exists():
        parent = parent.parent
    try:
        if not parent.is_dir():
            raise NotADirectoryError(20, "not a folder")
        fd, probe = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".probe", dir=parent)
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        raise NavfmuError(f"{what} {path}: cannot write into {parent}: "
                          f"{exc.strerror or exc}") from None
    return path


@contextlib.contextmanager
def _locked(folder: Path) -> Iterator[None]:
    """An exclusive lock on ``folder`` itself (no lock file left behind)."""
    fd = os.open(folder, os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)  # releases the lock


def _commit(stage: Path, target: Path, names) -> None:
    (stage / MARKER).write_text("".join(f"{n}\n" for n in sorted(names)), encoding="utf-8")
    os.chmod(stage, 0o777 & ~_umask())  # mkdtemp makes 0700; give the usual permissions
    with _locked(target.parent):
        old = None
        if target.exists():
            if not target.is_dir() or not _is_output_folder(target):
                raise NavfmuError(f"--out {target}: replaced meanwhile by something navfmu did "
                                  "not write; nothing was written")
            old = _temporary(target, ".old")
            os.rename(target, old / "previous")
        os.rename(stage, target)
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)


@contextlib.contextmanager
def staged(target) -> Iterator[Path]:
    """``with staged(out) as folder:`` write the files into ``folder``; when the block ends
    normally they replace ``out`` together, otherwise they are deleted (a write that fails
    for the disk, e.g. full, is one :class:`NavfmuError` naming ``out``)."""
    target = check_target(target).absolute()
    stage = _temporary(target, ".partial")
    try:
        try:
            yield stage
            _commit(stage, target, [p.name for p in stage.iterdir()])
        except (OSError, NavfmuError) as exc:
            cause = exc if isinstance(exc, OSError) else exc.__cause__
            if not isinstance(cause, OSError):
                raise
            # a full disk while writing: the target named, not the hidden staging folder
            raise NavfmuError(f"--out {target}: cannot write the results: "
                              f"{cause.strerror or cause}; nothing was written") from None
    finally:
        if stage.exists():
            shutil.rmtree(stage, ignore_errors=True)


def stream_folder(target) -> Path:
    """A hidden folder beside ``target`` (``.<name>.<random>.partial``, like a staging
    folder) for files a command streams while it runs; :func:`move_into` moves each into the
    staging folder and removes this folder with the last one."""
    target = check_target(target).absolute()
    return _temporary(target, ".partial")


def move_into(path, stage: Path) -> Path:
    """Move the streamed file ``path`` into the staging folder ``stage``; returns its path."""
    path = Path(path)
    dest = Path(stage) / path.name
    os.replace(path, dest)
    try:
        os.rmdir(path.parent)       # the stream folder, once empty
    except OSError:
        pass
    return dest


__all__ = ["MARKER", "check_target", "check_writable", "remove_stale", "staged",
           "stream_folder", "move_into"]
