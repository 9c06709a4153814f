"""The FMUs the verification tests verify: broken filters and a broken IMU made of navcore
components (built with the project's build function from a temporary source folder that
holds the scripts of tests/verify_fmus/ beside navcore and fmushell), and a filter written
without navfmu (built with plain pythonfmu).  Built once per session, in a child process
(a process that has run FMUs may import pythonfmu from an FMU's resources)."""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SCRIPTS = Path(__file__).resolve().parent / "verify_fmus"
NAVCORE_FMUS = ("OverconfidentKf", "WrongCoriolisKf", "IgnoresValidKf", "InexactRestoreKf",
                "CrashingKf", "NoisyImu")
PLAIN_FMUS = ("PvFilter",)

_BUILD = """
import sys
from pathlib import Path
from pythonfmu.builder import FmuBuilder
from orchestrator.building import build
src, dist = Path(sys.argv[1]), Path(sys.argv[2])
library = build.patched_library(log=None)
for name in sys.argv[3].split(","):
    build.build_one(src / f"{name}.py", dist, library)
for name in sys.argv[4].split(","):
    FmuBuilder.build_FMU(src / f"{name}.py", dest=dist)
"""


_BUILD_PLAIN = """
import json, sys
from pathlib import Path
from pythonfmu.builder import FmuBuilder
src, dist = Path(sys.argv[1]), Path(sys.argv[2])
for name, files in json.loads(sys.argv[3]).items():
    FmuBuilder.build_FMU(src / f"{name}.py", dest=dist, project_files=[src / f for f in files],
                         canGetAndSetFMUstate=True, canSerializeFMUstate=True)
"""


def variant_name(script: str, bug: str) -> str:
    """The model name of the test FMU ``script`` with ``bug`` (``script`` without one)."""
    return script + "".join(part.capitalize() for part in bug.split("_"))


def reference_name(bug: str) -> str:
    """The model name of the reference filter with ``bug`` (``RefEkf`` without one)."""
    return variant_name("RefEkf", bug)


def build_variants(folder: Path, script: str, bugs, project_files=None) -> Path:
    """The plain-pythonfmu test FMU tests/verify_fmus/SCRIPT.py once per bug of ``bugs``
    ("" = none), each its own FMU with its own module and class name, into ``folder/dist``
    (``project_files``: bug -> files of tests/verify_fmus/ it ships in its resources);
    returns that folder."""
    src, dist = folder / "src", folder / "dist"
    src.mkdir(parents=True)
    template = (SCRIPTS / f"{script}.py").read_text()
    names = {}
    for bug in bugs:
        name = variant_name(script, bug)
        text = template.replace('BUG = ""', f"BUG = {bug!r}", 1)
        text = text.replace(f"class {script}(Fmi2Slave)", f"class {name}(Fmi2Slave)", 1)
        (src / f"{name}.py").write_text(text)
        names[name] = list((project_files or {}).get(bug, ()))
        for extra in names[name]:
            (src / extra).write_text((SCRIPTS / extra).read_text())
    subprocess.run([sys.executable, "-c", _BUILD_PLAIN, str(src), str(dist), json.dumps(names)],
                   check=True, cwd=str(folder), capture_output=True, text=True)
    return dist


def build_reference_filters(folder: Path, bugs) -> Path:
    """The independent reference filter (tests/verify_fmus/RefEkf.py) once per bug of
    ``bugs`` (see :func:`build_variants`)."""
    return build_variants(folder, "RefEkf", bugs)


def build_test_fmus(folder: Path) -> Path:
    """Build every test FMU into ``folder/dist``; returns that folder."""
    src, dist = folder / "src", folder / "dist"
    src.mkdir(parents=True)
    for package in ("navcore", "fmushell"):
        (src / package).symlink_to(ROOT / "fmus" / package, target_is_directory=True)
    for name in NAVCORE_FMUS + PLAIN_FMUS:
        (src / f"{name}.py").write_text((SCRIPTS / f"{name}.py").read_text())
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), str(ROOT / "fmus")]))
    subprocess.run([sys.executable, "-c", _BUILD, str(src), str(dist), ",".join(NAVCORE_FMUS),
                    ",".join(PLAIN_FMUS)], check=True, cwd=str(folder), env=env,
                   capture_output=True, text=True)
    return dist
