"""The patched pythonfmu library (orchestrator/building/native_library.py,
native/vendor/pythonfmu-export): it compiles here with the interface of the wheel's library,
every built FMU carries it, and without it (no compiler, Windows,
NAVFMU_PYTHONFMU_LIBRARY=wheel) a refused call reports as pythonfmu's own library allows:
fmi2OK, an Error-status message, fmi2Discard at the next step.  The fmi2Error answers
themselves are tested where the calls are (test_fmu_state.py, test_fmus.py)."""
from __future__ import annotations

import importlib.util
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest
from fmpy.fmi1 import FMICallException

from orchestrator.building import build as fmu_build
from orchestrator.building import native_library

FMI2_OK, FMI2_DISCARD, FMI2_ERROR = 0, 2, 3
#: the Python C-API functions the patch calls that upstream's library does not
PATCH_IMPORTS = {"PyErr_NormalizeException", "PyErr_Restore", "PyObject_SetAttrString",
                 "PyObject_Str", "PyUnicode_CompareWithASCIIString"}


def require_patched(fmu: Path):
    """Skip (saying why) unless ``fmu``'s Linux binary is the patched library."""
    if not native_library.fmu_has_patched_library(fmu):
        pytest.skip(f"{Path(fmu).name} carries pythonfmu's own library: "
                    f"{native_library.unavailable_reason() or 'built before the patch'}")


def wheel_library() -> Path:
    """The installed pythonfmu's Linux library (``import pythonfmu`` may resolve to the copy
    inside an FMU that ran in this process, which has none)."""
    from importlib.metadata import distribution

    return Path(distribution("pythonfmu").locate_file(
        f"pythonfmu/resources/binaries/linux64/{native_library.LIBRARY_NAME}"))


def dynamic_symbols(library: Path, undefined: bool):
    flag = "--undefined-only" if undefined else "--defined-only"
    out = subprocess.run(["nm", "-D", flag, str(library)], capture_output=True, text=True,
                         check=True).stdout
    return {line.split()[-1].split("@")[0] for line in out.splitlines() if line.strip()}


def test_patched_library_compiles_with_the_wheels_interface(tmp_path, monkeypatch):
    """A fresh compile (into an empty cache) exports exactly the C symbols of pythonfmu
    0.7.0's own Linux binary (the FMI 2.0 functions, built by pythonfmu's CI) and imports
    the same Python C-API functions plus the patch's few; no libpython dependency."""
    monkeypatch.setattr(native_library, "CACHE", tmp_path / "cache")
    reason = native_library.unavailable_reason()
    if reason is not None:
        pytest.skip(reason)
    if shutil.which("nm") is None or not wheel_library().is_file():
        pytest.skip("no nm (binutils) or no pythonfmu Linux library to compare with")
    built = native_library.build_library()
    assert built == native_library.cached_library() and built.is_file()
    assert native_library.MARKER in built.read_bytes()

    def c_exports(lib):
        return {s for s in dynamic_symbols(lib, undefined=False) if not s.startswith("_Z")}

    exports = c_exports(built)
    assert exports == c_exports(wheel_library())
    assert {"fmi2Instantiate", "fmi2DoStep", "fmi2DeSerializeFMUstate"} <= exports
    py_imports = {s for s in dynamic_symbols(built, undefined=True) if s.startswith("Py")}
    wheel_imports = {s for s in dynamic_symbols(wheel_library(), undefined=True)
                     if s.startswith("Py")}
    assert py_imports == wheel_imports | PATCH_IMPORTS
    dynamic = subprocess.run(["readelf", "-d", str(built)], capture_output=True,
                             text=True).stdout
    needed = [line for line in dynamic.splitlines() if "(NEEDED)" in line]
    assert needed and not any("libpython" in line for line in needed)


def test_every_built_fmu_carries_the_patched_linux_library():
    """The linux64 binary is the cached patched library; the win64 one is the wheel's."""
    fmu_build.build(log=None)
    dist = fmu_build.DIST
    require_patched(dist / "Kf.fmu")
    lib = native_library.cached_library().read_bytes()
    wheel_dll = wheel_library().parent.parent / "win64" / "pythonfmu-export.dll"
    for name in [s.stem for s in fmu_build.slave_scripts()]:
        with zipfile.ZipFile(dist / f"{name}.fmu") as z:
            assert z.read(f"binaries/linux64/{name}.so") == lib, name
            if wheel_dll.is_file():
                assert z.read(f"binaries/win64/{name}.dll") == wheel_dll.read_bytes(), name
        stamp = (dist / f"{name}.fmu.sha256").read_text()
        assert f"linux64 library: patched {native_library.sources_hash()}" in stamp


def test_without_the_patched_library_one_line_and_stale_fmus(monkeypatch, tmp_path):
    """No compiler: one line says what refused calls then do, and FMUs built with the
    patched library are stale (rebuilt with the wheel's, whose stamp says so)."""
    monkeypatch.setattr(native_library, "CACHE", tmp_path / "empty")
    monkeypatch.setattr(native_library, "_compiler", lambda: None)
    lines = []
    assert fmu_build.patched_library(lines.append) is None
    assert lines == [native_library.fallback_note("no C++ compiler found (c++, g++, clang++ "
                                                  "or $CXX)")]
    assert "fmi2Discard at the next doStep" in lines[0]
    script = fmu_build.FMU_SOURCES / "Kf.py"
    assert fmu_build.build_stamp(script, True) != fmu_build.build_stamp(script, False)
    assert "\nlinux64 library: wheel\n" in fmu_build.build_stamp(script, False)


@pytest.fixture(scope="module")
def wheel_kf(tmp_path_factory):
    """Kf.fmu built with pythonfmu's own library (a fresh process: the choice variable)."""
    dist = tmp_path_factory.mktemp("wheel_dist")
    env = dict(os.environ, **{native_library.CHOICE_VARIABLE: "wheel"})
    code = ("import sys; from pathlib import Path; from orchestrator.building import build; "
            "build.build(['Kf'], force=True, dist=Path(sys.argv[1]))")
    proc = subprocess.run([sys.executable, "-c", code, str(dist)], capture_output=True,
                          text=True, env=env, cwd=str(fmu_build.ROOT), timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "NAVFMU_PYTHONFMU_LIBRARY=wheel is set: the FMUs keep pythonfmu's own" in proc.stdout
    return dist / "Kf.fmu"


def test_wheel_library_reports_refusals_at_the_next_step(wheel_kf):
    """pythonfmu's own library: a refused blob and a refused parameter return fmi2OK with an
    Error-status message, and the next doStep is fmi2Discard; also while a Kf.fmu with the
    patched library is instantiated in the process (both share the script's class)."""
    from test_fmus import _Fmu

    assert not native_library.fmu_has_patched_library(wheel_kf)
    fmu_build.build(["Kf"], log=None)
    patched = _Fmu(fmu_build.DIST / "Kf.fmu", "kf_patched")
    f = _Fmu(wheel_kf, "kf_wheel")
    try:
        blob = f.fmu.serializeFMUstate(f.fmu.getFMUstate())
        handle = f.fmu.deSerializeFMUstate(blob[:-3])         # fmi2OK
        f.fmu.setFMUstate(handle)                              # fmi2OK
        assert f.records[-1][0] == FMI2_ERROR and "refused the state" in f.records[-1][1]
        with pytest.raises(FMICallException) as info:
            f.fmu.doStep(0.0, 0.01)
        assert info.value.status == FMI2_DISCARD
    finally:
        f.close()
        patched.close()
    bad = _Fmu(wheel_kf, "kf_wheel_bad", {"init_lat": 7.0})   # exit initialization: fmi2OK
    try:
        assert [s for s, m in bad.records if "init_lat" in m] == [FMI2_ERROR]
        with pytest.raises(FMICallException) as info:
            bad.fmu.doStep(0.0, 0.01)
        assert info.value.status == FMI2_DISCARD
    finally:
        bad.close()


def test_build_after_the_same_fmu_ran_from_a_deleted_folder(tmp_path, monkeypatch):
    """An FMU loaded in this process leaves its script module in sys.modules with the path of
    the folder it was unpacked to, which the host deletes after it; building that FMU again
    later in the same process reads the sources of the script being built, not that path."""
    resources = tmp_path / "unpacked" / "resources"
    resources.mkdir(parents=True)
    script = shutil.copy(fmu_build.FMU_SOURCES / "GnssReceiver.py", resources)
    monkeypatch.syspath_prepend(str(resources))
    shutil.copytree(fmu_build.FMU_SOURCES / "fmushell", resources / "fmushell")
    for name in [m for m in sys.modules if m == "fmushell" or m.startswith("fmushell.")]:
        monkeypatch.delitem(sys.modules, name)     # the script imports the shell beside it
    spec = importlib.util.spec_from_file_location("GnssReceiver", script)
    stale = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(stale)
    monkeypatch.setitem(sys.modules, "GnssReceiver", stale)
    shutil.rmtree(tmp_path / "unpacked")
    built = fmu_build.build(["GnssReceiver"], force=True, dist=tmp_path / "dist", log=None)
    assert [Path(b).name for b in built] == ["GnssReceiver.fmu"]


@pytest.mark.parametrize("umask", [0o022, 0o027])
def test_built_fmus_have_the_users_umask(tmp_path, umask):
    """A simulator running as another user must be able to read fmus/dist: the FMU and its
    stamp get 0666 & ~umask (the temporary file they are written through is 0600)."""
    previous = os.umask(umask)
    try:
        fmu_build.build(["GnssReceiver"], force=True, dist=tmp_path, log=None)
    finally:
        os.umask(previous)
    for path in (tmp_path / "GnssReceiver.fmu", tmp_path / "GnssReceiver.fmu.sha256"):
        assert path.stat().st_mode & 0o777 == 0o666 & ~umask, path.name
