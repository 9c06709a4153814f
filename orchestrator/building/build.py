"""Build the FMUs of ``fmus/`` into ``fmus/dist/`` with pythonfmu, only when stale.

An FMU is stale when it is missing, has no platform binaries, or when its build stamp
differs from the one recorded beside it in ``fmus/dist/<Model>.fmu.sha256``: the hash of its
Python inputs (its slave script and every file of the ``fmushell`` and ``navcore`` packages),
which Linux library it carries (the patched pythonfmu library of
:mod:`orchestrator.building.native_library` with the hash of its sources, or the wheel's when that
cannot be built here) and how its code is packed (under names private to the build:
:mod:`orchestrator.building.private_names`).  Each FMU is written to a temporary name and
renamed, so an interrupted build never leaves a broken ``.fmu`` behind.
:func:`ensure_fmus` builds those a system model uses before it runs.
"""
from __future__ import annotations

import shutil
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

from navcore import __version__ as navfmu_version
from navcore.core.state_format import build_hash

from . import native_library, private_names
from ..errors import NavfmuError
from ..results.run_results import atomic_write

ROOT = Path(__file__).resolve().parents[2]
FMU_SOURCES = ROOT / "fmus"
DIST = FMU_SOURCES / "dist"
SHELL = "fmushell"
LIBRARY = "navcore"


def slave_scripts(src: Path = FMU_SOURCES):
    """The FMU scripts: every ``fmus/*.py`` (the shared shell is the package ``fmushell``)."""
    if not src.is_dir():
        raise NavfmuError(f"FMU sources not found at {src} (navfmu build needs the source tree)")
    return sorted(src.glob("*.py"))


def source_hash(script: Path) -> str:
    """The FMU's build identity, also carried by its serialized states
    (navcore.core.state_format)."""
    return build_hash(script, SHELL, LIBRARY)


#: how the Python code is packed into an FMU (a change rebuilds every FMU)
PACKING = "private names 1"


def build_stamp(script: Path, patched: bool) -> str:
    """What ``<Model>.fmu.sha256`` records: the Python sources' hash, the Linux library and how
    the code is packed."""
    library = f"patched {native_library.sources_hash()}" if patched else "wheel"
    return f"{source_hash(script)}\nlinux64 library: {library}\npacking: {PACKING}"


def fmu_path(name: str, dist: Path = DIST) -> Path:
    return dist / f"{name}.fmu"


def is_stale(script: Path, dist: Path = DIST) -> bool:
    fmu = fmu_path(script.stem, dist)
    stamp = fmu.with_suffix(".fmu.sha256")
    if not fmu.exists() or not stamp.exists():
        return True
    patched = native_library.unavailable_reason() is None
    if stamp.read_text().strip() != build_stamp(script, patched):
        return True
    return not has_binaries(fmu)


def has_binaries(fmu: Path) -> bool:
    """True if the FMU archive holds at least one platform binary (an FMU built by a
    pythonfmu without them is unusable; see :func:`builder_usable`)."""
    try:
        with zipfile.ZipFile(fmu) as z:
            return any(n.startswith("binaries/") and not n.endswith("/") for n in z.namelist())
    except (OSError, zipfile.BadZipFile):
        return False


def binary_platforms(names) -> set:
    """The FMI 2.0 platforms (``binaries/<platform>/...``) the archive member ``names`` hold
    a binary for."""
    return {n.split("/")[1] for n in names
            if n.startswith("binaries/") and n.count("/") >= 2 and not n.endswith("/")}


def build_one(script: Path, dist: Path = DIST, library: Path = None) -> Path:
    """Build one FMU (always), with ``library`` as its Linux binary if given (else the
    wheel's), and return its path."""
    from pythonfmu.builder import FmuBuilder

    dist.mkdir(parents=True, exist_ok=True)
    target = fmu_path(script.stem, dist)
    # the sources' identity taken before they are read: a file edited during the build makes
    # the FMU stale, never an FMU of half-edited code stamped as current
    build, stamp = source_hash(script), build_stamp(script, library is not None)
    with tempfile.TemporaryDirectory(prefix="navfmu_build_") as tmp:
        built = FmuBuilder.build_FMU(
            script, dest=tmp,
            project_files=[script.parent / LIBRARY, script.parent / SHELL],
            canGetAndSetFMUstate=True, canSerializeFMUstate=True)
        built = Path(built)
        if built.stem != script.stem:
            raise NavfmuError(f"{script}: the FMU's model name '{built.stem}' differs from the "
                              f"script name '{script.stem}'")
        if not has_binaries(built):
            raise NavfmuError(f"{script}: pythonfmu built {built.name} without binaries "
                                  "(its installation lacks the FMI wrapper libraries)")
        if library is not None:
            native_library.replace_in_fmu(built, script.stem, library)
        private_names.make_private(built, script.stem, build, navfmu_version)
        with open(built, "rb") as src:  # atomic_write: the user's umask, not mkstemp's 0600
            atomic_write(target, lambda f: shutil.copyfileobj(src, f), binary=True)
    target.with_suffix(".fmu.sha256").write_text(stamp + "\n")
    return target


def build(names=None, force=False, dist: Path = DIST, log=print):
    """Build the named FMUs (all by default) that are stale (all with ``force``)."""
    scripts = slave_scripts()
    if names:
        known = {s.stem: s for s in scripts}
        unknown = [n for n in names if n not in known]
        if unknown:
            raise NavfmuError(f"unknown FMU {', '.join(unknown)}; known: {', '.join(known)}")
        scripts = [known[n] for n in names]
    todo = [s for s in scripts if force or is_stale(s, dist)]
    if not todo:
        return []
    library = patched_library(log)
    if not builder_usable():
        return _build_in_subprocess(todo, dist, log)
    built = []
    for script in todo:
        if log:
            log(f"building {script.stem}.fmu")
        built.append(build_one(script, dist, library))
    return built


def patched_library(log=print):
    """The patched pythonfmu library (built once and cached), or None after one line on
    ``log`` saying why the FMUs keep the wheel's."""
    reason = native_library.unavailable_reason()
    if reason is None:
        if log and not native_library.cached_library().is_file():
            log(f"building the patched pythonfmu library ({native_library.SOURCES.name})")
        try:
            return native_library.library()
        except native_library.NativeBuildError as exc:
            reason = str(exc)
    if log:
        log(native_library.fallback_note(reason))
    return None


def builder_usable() -> bool:
    """True if the pythonfmu this process imports is the installed one, with its FMI binaries.

    Once an FMU built by pythonfmu has run in this process, ``import pythonfmu`` may resolve
    to the copy in that FMU's resources, which has no binaries: building with it gives FMUs
    without binaries.  Checked before every in-process build."""
    try:
        from pythonfmu import builder
    except ImportError:
        return True  # build_one reports the missing package
    binaries = Path(builder.__file__).parent / "resources" / "binaries"
    return any(f.is_file() for f in binaries.rglob("*"))


def _build_in_subprocess(scripts, dist: Path, log):
    """Build ``scripts`` with a fresh interpreter (see :func:`builder_usable`)."""
    if log:
        for script in scripts:
            log(f"building {script.stem}.fmu (in a separate process)")
    code = ("import sys; from pathlib import Path; from orchestrator.building import build; "
            "build.build(sys.argv[2:], force=True, dist=Path(sys.argv[1]), log=None)")
    proc = subprocess.run([sys.executable, "-c", code, str(dist), *[s.stem for s in scripts]],
                          capture_output=True, text=True, cwd=str(ROOT))
    if proc.returncode != 0:
        detail = (proc.stderr.strip().splitlines() or ["no message"])[-1]
        raise NavfmuError(f"building {', '.join(s.stem for s in scripts)} failed: {detail}")
    return [fmu_path(s.stem, dist) for s in scripts]


def ensure_fmus(model, log=print) -> None:
    """Build the FMUs the system ``model`` uses that come from ``fmus/dist`` and are missing
    or stale (the FMUs it takes from elsewhere are left alone)."""
    names = []
    for component in model.components:
        src = Path(component.source).resolve()
        if src.parent == DIST.resolve() and (FMU_SOURCES / f"{src.stem}.py").is_file():
            names.append(src.stem)
    stale = [n for n in names if is_stale(FMU_SOURCES / f"{n}.py")]
    if stale:
        build(stale, log=log)
