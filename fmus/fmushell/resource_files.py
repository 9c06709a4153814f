"""Files an FMU carries: a relative file parameter is looked up in its resources folder first.

A component's ``file_parameters`` (the replay's ``log``, a trajectory's ``profile`` file) name
files.  A relative value that names an entry of the FMU's resources folder
(``fmi2Instantiate``'s resource location) is taken from there, so an FMU that carries its
data (``navfmu package`` puts a scenario's files into the FMU copies it packs) finds it
whatever the host's working directory; any other value is passed on unchanged (a relative
path is then relative to the host's working directory, an absolute one is used as it is).
"""
from __future__ import annotations

from pathlib import Path


def resolved_file_parameters(slave, params: dict) -> dict:
    """``params`` with every relative file parameter found in the resources folder made
    absolute."""
    resources = getattr(slave, "resources", None)
    names = getattr(slave.component_class, "file_parameters", ())
    if not resources or not names:
        return params
    folder = Path(resources).resolve()
    resolved = dict(params)
    for name in names:
        value = params.get(name)
        if not isinstance(value, str) or not value or Path(value).is_absolute():
            continue
        candidate = (folder / value).resolve()
        if folder in candidate.parents and candidate.exists():
            resolved[name] = str(candidate)
    return resolved
