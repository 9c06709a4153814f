"""Foreign FMUs in a host process of their own (orchestrator/cosim/hosted_instance.py): which
FMUs are foreign, the same numbers as in the master's process bit for bit, and a crash, a
hang or Ctrl-C of a hosted FMU ending ``navfmu run`` with one line and the right status,
every temporary folder removed and no result folder written.

The foreign FMU is tests/foreign_fmus/Faulty.py, built with plain pythonfmu: y integrates its
Real, Integer and Boolean inputs; at ``crash_at`` it kills its process with SIGSEGV (or reads
address 0), at ``hang_at`` it sleeps for ever (after touching the file $FAULTY_HANG_MARKER).
"""
from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import numpy as np
import pytest

from orchestrator.building import build as fmu_build
from orchestrator.cosim.host_process import child_environment
from orchestrator.cosim.isolation import Isolation
from orchestrator.cosim.master import Simulation
from orchestrator.model.fmu_origin import is_foreign
from orchestrator.model.ssp_archive import load_model
from orchestrator.running import scenarios

from conftest import component_xml, connection_xml, ssd_text

SCRIPT = Path(__file__).resolve().parent / "foreign_fmus" / "Faulty.py"
PORTS = [("u", "input", "Real"), ("k", "input", "Integer"), ("b", "input", "Boolean"),
         ("y", "output", "Real"), ("n", "output", "Integer"), ("odd", "output", "Boolean")]


@pytest.fixture(scope="module")
def faulty(tmp_path_factory):
    """Faulty.fmu, built with plain pythonfmu in a child process."""
    folder = tmp_path_factory.mktemp("foreign_fmus")
    shutil.copy(SCRIPT, folder / SCRIPT.name)
    subprocess.run([sys.executable, "-m", "pythonfmu", "build", "-f", SCRIPT.name, "-d", "dist"],
                   cwd=folder, check=True, capture_output=True)
    return folder / "dist" / "Faulty.fmu"


def _model(folder: Path, fmu: Path, crash_at=-1.0, hang_at=-1.0, null_read=False) -> Path:
    """source -> filter, both Faulty (the filter with the fault), 0.1 s steps to 20 s."""
    folder.mkdir(parents=True, exist_ok=True)
    shutil.copy(fmu, folder / "Faulty.fmu")
    fault = {"crash_at": ("Real", crash_at), "hang_at": ("Real", hang_at),
             "null_read": ("Boolean", str(null_read).lower())}
    elements = (component_xml("source", "Faulty.fmu", PORTS)
                + component_xml("filter", "Faulty.fmu", PORTS, parameters=fault))
    connections = (connection_xml("source.y", "filter.u") + connection_xml("source.n", "filter.k")
                   + connection_xml("source.odd", "filter.b"))
    ssd = folder / "SystemStructure.ssd"
    ssd.write_text(ssd_text(elements, connections, base_step=0.1, stop=20.0, name="toy"))
    return ssd


def _same_bits(a, b):
    assert a.columns == b.columns
    for c in a.data:
        assert a.data[c].shape == b.data[c].shape and a.data[c].size > 0, c
        assert np.array_equal(a.data[c].view(np.uint64), b.data[c].view(np.uint64)), c


def _cli(args, tmp_path, **popen):
    """``navfmu ARGS`` as a child process with its own temporary folder ``tmp_path/tmp``."""
    tmp = tmp_path / "tmp"
    tmp.mkdir(exist_ok=True)
    env = dict(child_environment(), TMPDIR=str(tmp), **popen.pop("env", {}))
    return subprocess.Popen([sys.executable, "-m", "orchestrator.cli", *map(str, args)],
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            **popen), tmp


def _host_processes(tmp: Path):
    """Processes still running with ``tmp`` in their command line (a host left behind)."""
    found = []
    for proc in Path("/proc").iterdir():
        try:
            if proc.name.isdigit() and str(tmp) in (proc / "cmdline").read_text(errors="ignore"):
                found.append(proc.name)
        except OSError:
            continue
    return found


def _code_changed_copy(original: Path, target: Path) -> Path:
    """A copy of ``original`` with one comment line added to a bundled Python file: the
    same build, its code changed after it."""
    with zipfile.ZipFile(original) as src, zipfile.ZipFile(target, "w") as dst:
        for info in src.infolist():
            data = src.read(info)
            if info.filename.endswith(".py") and "/navcore_" in info.filename \
                    and info.filename.endswith("/__init__.py") and data:
                data += b"# changed after the build\n"
            dst.writestr(info, data)
    return target


# -- which FMUs are foreign ---------------------------------------------------------------
def test_ours_is_this_builds_fmu_or_an_identical_copy_anything_else_is_foreign(tmp_path,
                                                                               faulty):
    fmu_build.build(["Kf"], log=None)
    ours = fmu_build.DIST / "Kf.fmu"
    assert not is_foreign(ours, "Kf")
    renamed = tmp_path / "MyFilter.fmu"
    shutil.copy(ours, renamed)
    assert not is_foreign(renamed, "Kf")              # the same bytes under another name
    with zipfile.ZipFile(renamed, "a") as z:          # other bytes, the same build and code
        z.comment = b"packed elsewhere"
    assert not is_foreign(renamed, "Kf")
    changed = _code_changed_copy(ours, tmp_path / "Changed.fmu")
    assert is_foreign(changed, "Kf")                  # its code changed after the build
    assert is_foreign(ours, "Iakf")                   # not the build of the model it claims
    assert is_foreign(faulty, "Faulty")               # no FMU of that model here


def test_isolation_modes_and_timeout_are_checked():
    with pytest.raises(Exception, match="--isolate: expected foreign, always, never"):
        Isolation("sometimes")
    for bad in (0.0, -1.0, float("inf"), float("nan")):
        with pytest.raises(Exception, match="--call-timeout"):
            Isolation("foreign", bad)


# -- the same numbers ---------------------------------------------------------------------
@pytest.mark.parametrize("algorithm", ["gauss-seidel", "jacobi"])
def test_a_hosted_fmu_gives_the_in_process_numbers_bit_for_bit(tmp_path, faulty, algorithm):
    ssd = _model(tmp_path / "toy", faulty)
    here = Simulation(load_model(ssd), isolation=Isolation("never"), algorithm=algorithm).run()
    hosted = Simulation(load_model(ssd), algorithm=algorithm).run()
    assert here.metadata["hosted"] == [] and hosted.metadata["hosted"] == ["source", "filter"]
    _same_bits(here, hosted)
    n = hosted.column("filter", "n")
    assert n[-1] == 200 and hosted.column("filter", "y")[-1] > 0   # it ran every step


def test_a_foreign_copy_of_kf_gives_the_in_process_numbers_bit_for_bit(tmp_path):
    """Our Kf, its code altered after its build, in the aircraft scenario: hosted by
    default, the same rows as in the master's process."""
    fmu_build.build(log=None)
    copy = _code_changed_copy(fmu_build.DIST / "Kf.fmu", tmp_path / "KfCopy.fmu")
    model = scenarios.load_scenario(Path(fmu_build.ROOT) / "models" / "aircraft_500s")
    runs = {mode: scenarios.simulate_scenario(model, filter=str(copy), stop_time=3.0,
                                              isolation=Isolation(mode), log=lambda m: None)
            for mode in ("never", "foreign")}
    assert runs["foreign"].results.metadata["hosted"] == ["filter"]
    _same_bits(runs["never"].results, runs["foreign"].results)
    assert np.isfinite(runs["foreign"].results.column("filter", "nav_lat")).all()


# -- a crash, a hang, Ctrl-C --------------------------------------------------------------
@pytest.mark.parametrize("null_read", [False, True], ids=["kill", "null_read"])
def test_a_segfault_in_do_step_is_one_line_status_2_and_nothing_left(tmp_path, faulty,
                                                                     null_read):
    ssd = _model(tmp_path / "toy", faulty, crash_at=12.3, null_read=null_read)
    out = tmp_path / "out"
    proc, tmp = _cli(["run", ssd.parent, "--out", out], tmp_path)
    stdout, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 2, stderr
    assert stderr.splitlines() == [
        "navfmu: error: component 'filter' (Faulty.fmu): the FMU process died with SIGSEGV "
        "in fmi2DoStep at t = 12.3 s"]
    assert not out.exists()
    assert list(tmp.iterdir()) == []
    assert _host_processes(tmp) == []


def test_a_hang_is_ended_by_the_call_timeout(tmp_path, faulty):
    ssd = _model(tmp_path / "toy", faulty, hang_at=5.0)
    out = tmp_path / "out"
    t0 = time.monotonic()
    proc, tmp = _cli(["run", ssd.parent, "--out", out, "--call-timeout", 1.5], tmp_path)
    _, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 2, stderr
    assert stderr.splitlines() == [
        "navfmu: error: component 'filter' (Faulty.fmu): the FMU process hung in fmi2DoStep "
        "at t = 5 s: no answer within the call timeout of 1.5 s; killed"]
    assert time.monotonic() - t0 > 1.5
    assert not out.exists() and list(tmp.iterdir()) == [] and _host_processes(tmp) == []


def test_ctrl_c_during_a_hang_ends_the_run_within_a_second_with_130(tmp_path, faulty):
    ssd = _model(tmp_path / "toy", faulty, hang_at=5.0)
    out, marker = tmp_path / "out", tmp_path / "hanging"
    proc, tmp = _cli(["run", ssd.parent, "--out", out], tmp_path,
                     env={"FAULTY_HANG_MARKER": str(marker)})
    deadline = time.monotonic() + 120
    while not marker.exists():
        assert proc.poll() is None and time.monotonic() < deadline, proc.communicate()
        time.sleep(0.02)
    time.sleep(0.2)                       # well inside the endless do_step
    t0 = time.monotonic()
    proc.send_signal(signal.SIGINT)
    _, stderr = proc.communicate(timeout=30)
    elapsed = time.monotonic() - t0
    assert proc.returncode == 130, stderr
    assert elapsed < 1.0, elapsed
    assert [line for line in stderr.splitlines() if line.strip()] == ["navfmu: interrupted"]
    assert not out.exists() and list(tmp.iterdir()) == [] and _host_processes(tmp) == []


def test_never_isolated_a_foreign_fmu_runs_in_the_masters_process(tmp_path, faulty):
    """--isolate never: no host (so a healthy foreign FMU runs as before)."""
    ssd = _model(tmp_path / "toy", faulty)
    proc, tmp = _cli(["run", ssd.parent, "--out", tmp_path / "out", "--isolate", "never",
                      "--no-plots"], tmp_path)
    stdout, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 0, stderr
    assert (tmp_path / "out").is_dir() and list(tmp.iterdir()) == []


def test_a_foreign_fmus_ordinary_error_keeps_its_in_process_message(tmp_path, faulty):
    """A parameter the FMU does not have is refused before anything runs; an FMI error
    status inside the host comes back as the in-process SimulationError (here: setting a
    Real parameter with text)."""
    ssd = _model(tmp_path / "toy", faulty)
    messages = {}
    for mode in ("never", "always"):
        sim = Simulation(load_model(ssd), isolation=Isolation(mode),
                         parameters={"filter.crash_at": "soon"})
        with pytest.raises(Exception) as exc:
            sim.run()
        messages[mode] = str(exc.value).splitlines()[0]
    assert messages["never"] == messages["always"]
    assert "crash_at" in messages["always"]


def test_a_montecarlo_run_of_a_crashing_foreign_filter_is_one_line(tmp_path, faulty):
    """The FMU backend of a campaign hosts the foreign filter too: its crash is the run's
    error, and the campaign folder is not left behind half made."""
    ssd = _model(tmp_path / "toy", faulty, crash_at=1.0)
    out = tmp_path / "campaign"
    proc, tmp = _cli(["montecarlo", ssd.parent, "--runs", 1, "--backend", "fmu",
                      "--filters", ssd.parent / "Faulty.fmu", "--out", out], tmp_path)
    _, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 2, stderr
    lines = stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("navfmu: error: ")
    assert lines[0].endswith("component 'filter' (Faulty.fmu): the FMU process died with "
                             "SIGSEGV in fmi2DoStep at t = 1 s")
    assert not out.exists() and list(tmp.iterdir()) == [] and _host_processes(tmp) == []


def test_a_hosted_fmus_state_is_saved_and_restored_in_its_host(tmp_path):
    """get_state / set_state of a hosted FMU (a foreign copy of our TrajectoryImu) keep the
    state in the host: the steps after a restore repeat the ones after the save, bit for
    bit, and equal the in-process instance's."""
    from orchestrator.cosim.fmu_instance import FmuInstance
    from orchestrator.cosim.hosted_instance import HostedFmuInstance

    fmu_build.build(["TrajectoryImu"], log=None)
    copy = _code_changed_copy(fmu_build.DIST / "TrajectoryImu.fmu", tmp_path / "Trajectory.fmu")
    outputs = ["truth_lat", "truth_vn", "imu_dvel_x", "imu_dtheta_z"]
    hosted, here = HostedFmuInstance(copy, "trajectory", 60.0), FmuInstance(copy, "here")
    rows = {"hosted": [], "restored": [], "here": []}
    try:
        for inst in (hosted, here):
            inst.prepare([], outputs)
            inst.initialize(0.0, 10.0)
        for k in range(20):
            if k == 10:
                saved = hosted.get_state()
            hosted.do_step(k * 0.01, 0.01)
            here.do_step(k * 0.01, 0.01)
            rows["hosted"].append(hosted.get_outputs()[0].copy())
            rows["here"].append(here.get_outputs()[0].copy())
        hosted.set_state(saved)
        for k in range(10, 20):
            hosted.do_step(k * 0.01, 0.01)
            rows["restored"].append(hosted.get_outputs()[0].copy())
        hosted.free_state(saved)
    finally:
        hosted.terminate()
        here.terminate()
    a, b, c = (np.array(rows[k]) for k in ("hosted", "restored", "here"))
    assert np.array_equal(a[10:].view(np.uint64), b.view(np.uint64))
    assert np.array_equal(a.view(np.uint64), c.view(np.uint64))
    assert np.ptp(a[:, 2]) > 0                        # the IMU increments move


def test_bench_against_libcosim_keeps_a_crashing_foreign_fmu_in_a_child(tmp_path, faulty):
    """libcosim loads the FMUs into the process that runs it: with a foreign FMU that is a
    child, whose crash is one line, status 2, its temporary files gone with it."""
    ssd = _model(tmp_path / "toy", faulty, crash_at=12.3)
    proc, tmp = _cli(["bench", ssd.parent, "--libcosim", "--stop", 20, "--repeat", 1],
                     tmp_path)
    _, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 2, stderr
    lines = stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("navfmu: error: ")
    assert "libcosim" in lines[0] and "ended with SIGSEGV" in lines[0]
    assert list(tmp.iterdir()) == []
