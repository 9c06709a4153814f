"""A run's output folder: written whole in a staging folder beside it, then moved into place.

The files of one command (results, metrics, report, plots) are written into a hidden staging
folder ``.<name>.<random>.partial`` next to the target folder (a Parquet file streamed while
the run goes is written into another such folder and moved in, :func:`move_into`).  Only when every
file is there is the staging folder moved onto the target: under an exclusive lock (``fcntl.flock``
on the parent folder) the previous folder is renamed aside, the staging folder renamed to the
target, and the previous folder deleted.  So

* the target holds the files of exactly one command: a failed, interrupted or killed command
  leaves the previous folder as it was (plus, after a kill, a hidden ``.partial`` folder),
  never a mixture, and no file of an earlier command survives beside the new ones (``run``
  then ``compare`` into one folder leaves no stale ``results.csv``);
* two commands writing to one folder at the same time each stage their own files, and the
  lock serializes the moves: the folder ends up with one command's files, whole.

A folder that exists already is only replaced if it is an output folder: it holds the
marker file :data:`MARKER` (written into every output folder) or only files of the kinds we
write (``.csv``, ``.npz``, ``.json``, ``.png``).  Anything else is refused before the run.
"""
from __future__ import annotations

import contextlib
import fcntl
import os
import shutil
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


def check_target(target) -> Path:
    """Refuse, before any work, an output folder that could not be written or must not be
    replaced; a staging folder is created and removed beside it to prove it writable."""
    target = Path(target)
    if target.exists() and not target.is_dir():
        raise NavfmuError(f"--out {target}: exists and is not a folder")
    if target.is_dir() and not _is_output_folder(target):
        raise NavfmuError(f"--out {target}: the folder holds files navfmu did not write (no "
                          f"{MARKER}); choose a new or empty folder")
    parent = target.absolute().parent
    try:
        parent.mkdir(parents=True, exist_ok=True)
        probe = tempfile.mkdtemp(prefix=f".{target.name}.", suffix=".partial", dir=parent)
        os.rmdir(probe)
    except OSError as exc:
        raise NavfmuError(f"--out {target}: cannot write into {parent}: "
                          f"{exc.strerror or exc}") from None
    return target


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
            old = Path(tempfile.mkdtemp(prefix=f".{target.name}.", suffix=".old",
                                        dir=target.parent))
            os.rename(target, old / "previous")
        os.rename(stage, target)
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)


@contextlib.contextmanager
def staged(target) -> Iterator[Path]:
    """``with staged(out) as folder:`` write the files into ``folder``; when the block ends
    normally they replace ``out`` together, otherwise they are deleted."""
    target = check_target(target).absolute()
    stage = Path(tempfile.mkdtemp(prefix=f".{target.name}.", suffix=".partial",
                                  dir=target.parent))
    try:
        yield stage
        _commit(stage, target, [p.name for p in stage.iterdir()])
    finally:
        if stage.exists():
            shutil.rmtree(stage, ignore_errors=True)


def stream_folder(target) -> Path:
    """A hidden folder beside ``target`` (``.<name>.<random>.partial``, like a staging
    folder) for files a command streams while it runs; :func:`move_into` moves each into the
    staging folder and removes this folder with the last one."""
    target = check_target(target).absolute()
    return Path(tempfile.mkdtemp(prefix=f".{target.name}.", suffix=".partial",
                                 dir=target.parent))


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


__all__ = ["MARKER", "check_target", "staged", "stream_folder", "move_into"]
