"""The built FMUs: fmpy validation, units, state save/restore, errors through the FMI logger."""
from __future__ import annotations

import math
import subprocess
import sys
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave
from fmpy.validation import validate_fmu

from navcore.components.registry import REGISTRY
from navcore.core import signals
from orchestrator.building import build as fmu_build
from test_native_library import require_patched

FMU_NAMES = [s.stem for s in fmu_build.slave_scripts()]


@pytest.fixture(scope="session")
def dist():
    fmu_build.build(log=None)
    return fmu_build.DIST


@pytest.mark.parametrize("name", FMU_NAMES)
def test_fmu_passes_fmpy_validate(dist, name):
    assert validate_fmu(str(dist / f"{name}.fmu")) == []


@pytest.mark.parametrize("name", FMU_NAMES)
def test_model_description_units_and_attributes(dist, name):
    with zipfile.ZipFile(dist / f"{name}.fmu") as z:
        root = ET.fromstring(z.read("modelDescription.xml"))
    units = {u.get("name") for u in root.find("UnitDefinitions")}
    cosim = root.find("CoSimulation")
    assert cosim.get("canGetAndSetFMUstate") == "true"
    assert cosim.get("canSerializeFMUstate") == "true"
    assert root.find("DefaultExperiment") is not None
    n_real = 0
    for sv in root.find("ModelVariables"):
        child = sv[0]
        if child.tag == "Real":
            n_real += 1
            # every Real carries a declared unit: SI, a datasheet unit, or "1" (dimensionless)
            assert child.get("unit") in units, sv.get("name")
        if child.tag in ("Integer", "Boolean") and sv.get("causality") != "parameter":
            assert sv.get("variability") == "discrete"
    assert n_real > 0
    md = read_model_description(str(dist / f"{name}.fmu"))
    angles = [v for v in md.modelVariables
              if v.name in ("truth_lat", "nav_lat", "gnss_lat", "nav_roll")]
    assert angles and all(v.unit == "rad" for v in angles)


class _Fmu:
    """A bare fmpy instance for FMI-level checks."""

    def __init__(self, path, name, params=None, logs=None, exit_init=True):
        self.path = Path(path)
        self.md = read_model_description(str(path))
        self.dir = extract(str(path))
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.type = {v.name: v.type for v in self.md.modelVariables}
        self.fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=self.dir,
                             modelIdentifier=self.md.coSimulation.modelIdentifier,
                             instanceName=name)
        self.logs = logs if logs is not None else []
        #: (FMI status, message) of every log call
        self.records = []
        logs_, records = self.logs, self.records

        def logger(env, inst, status, category, message):
            logs_.append(message.decode(errors="replace"))
            records.append((status, logs_[-1]))

        from fmpy.fmi2 import fmi2CallbackLoggerTYPE

        self._logger = fmi2CallbackLoggerTYPE(logger)
        from fmpy.fmi2 import fmi2CallbackFunctions, fmi2CallbackAllocateMemoryTYPE, \
            fmi2CallbackFreeMemoryTYPE, calloc, free
        cb = fmi2CallbackFunctions()
        cb.logger = self._logger
        cb.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        cb.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        self._cb = cb
        self.fmu.instantiate(loggingOn=True, callbacks=cb)
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        for k, v in (params or {}).items():
            self.set(k, v)
        if exit_init:
            self.fmu.exitInitializationMode()

    def set(self, name, value):
        t = self.type[name]
        if t == "Real":
            self.fmu.setReal([self.vr[name]], [value])
        elif t == "Integer":
            self.fmu.setInteger([self.vr[name]], [value])
        elif t == "Boolean":
            self.fmu.setBoolean([self.vr[name]], [value])
        else:
            self.fmu.setString([self.vr[name]], [value])

    def reals(self, names):
        return np.array(self.fmu.getReal([self.vr[n] for n in names]))

    def close(self):
        try:
            self.fmu.terminate()
        except FMICallException:  # FMI 2.0: an instance in the error state does not terminate
            pass
        self.fmu.freeInstance()


TRAJ_PARAMS = {"profile": "aircraft_500s", "gyro_arw_dpsh": 0.05, "accel_vrw_ugpsHz": 50.0,
               "gyro_bias_instability_dph": 1.0, "gyro_bias_tau_s": 100.0, "seed": 7}
TRAJ_OUT = ["truth_lat", "truth_vn", "imu_dtheta_x", "imu_dvel_z", "imu_time"]


def _steps(f, t0, n, h=0.01):
    rows = []
    for k in range(n):
        f.fmu.doStep(t0 + k * h, h)
        rows.append(f.reals(TRAJ_OUT))
    return np.array(rows)


def test_trajectory_state_save_restore_is_bit_identical(dist):
    f = _Fmu(dist / "TrajectoryImu.fmu", "traj", TRAJ_PARAMS)
    try:
        _steps(f, 0.0, 50)
        state = f.fmu.getFMUstate()
        first = _steps(f, 0.5, 80)
        f.fmu.setFMUstate(state)
        again = _steps(f, 0.5, 80)
        # serialize / deserialize too
        f.fmu.setFMUstate(state)
        blob = f.fmu.serializeFMUstate(state)
        state2 = f.fmu.deSerializeFMUstate(blob)
        f.fmu.setFMUstate(state2)
        third = _steps(f, 0.5, 80)
        f.fmu.freeFMUstate(state)
        f.fmu.freeFMUstate(state2)
    finally:
        f.close()
    assert np.array_equal(first, again)
    assert np.array_equal(first, third)
    assert np.all(np.diff(first[:, -1]) > 0)


def _runs_after_restore(f, run, k0, n, serialize=False):
    """``run(0, k0)``, save the FMU state, ``run(k0, n)``; restore, run again (and, with
    ``serialize``, once more from a serialized and deserialized copy): the runs' outputs."""
    run(0, k0)
    state = f.fmu.getFMUstate()
    runs = [run(k0, n)]
    f.fmu.setFMUstate(state)
    runs.append(run(k0, n))
    if serialize:
        copy = f.fmu.deSerializeFMUstate(f.fmu.serializeFMUstate(state))
        f.fmu.setFMUstate(copy)
        runs.append(run(k0, n))
        f.fmu.freeFMUstate(copy)
    f.fmu.freeFMUstate(state)
    return runs


REPLAY_LOG = fmu_build.ROOT / "models" / "replay_gnss_ins_sim" / "log"
REPLAY_OUT = ["imu_time", "imu_dtheta_z", "imu_dvel_x", "gnss_lat", "truth_yaw"]


def test_replay_state_save_restore_is_bit_identical(dist):
    """ImuGnssReplay: the read position in the log is in the FMU state (and the log data with
    it); a restored or deserialized state replays the same samples."""
    f = _Fmu(dist / "ImuGnssReplay.fmu", "replay", {"log": str(REPLAY_LOG)})

    def run(k0, n):
        rows = []
        for k in range(k0, k0 + n):
            f.fmu.doStep(k * 0.01, 0.01)
            rows.append(np.concatenate([f.reals(REPLAY_OUT),
                                        f.fmu.getInteger([f.vr["gnss_epoch"]])]))
        return np.array(rows)

    try:
        first, again, third = _runs_after_restore(f, run, 1195, 30, serialize=True)
    finally:
        f.close()
    assert np.array_equal(first, again) and np.array_equal(first, third)
    assert np.all(np.diff(first[:, 0]) > 0)
    assert first[0, -1] == 12 and first[-1, -1] == 13  # a fix at 12 s and 13 s


AHRS_FMUS = ["UkfAhrs", "FuzzyUkfAhrs"]
#: the INS/GNSS filters (the components with the filter contract's inputs)
FILTER_FMUS = [n for n in FMU_NAMES if REGISTRY[n].inputs == signals.FILTER_INPUTS]


@pytest.mark.parametrize("name", FILTER_FMUS)
def test_filter_state_save_restore_is_bit_identical(dist, name):
    """Every filter FMU driven by constant stationary increments and a fix every 10 steps:
    fmi2GetFMUstate / fmi2SetFMUstate continue bit-identically (the adaptive filters' R
    estimate, Newton history, sigma points and model probabilities are in the state)."""
    lat = math.radians(40.0)
    g = 9.80
    f = _Fmu(dist / f"{name}.fmu", name.lower(), {"init_lat": lat, "init_h": 100.0})
    out = ["nav_lat", "nav_vn", "nav_roll", "std_pn", "nis", "nav_ba_z"]

    def run(k0, n):
        rows = []
        for k in range(k0, k0 + n):
            t1 = (k + 1) * 0.01
            f.set("imu_time", t1)
            f.set("imu_dt", 0.01)
            f.set("imu_dvel_z", -g * 0.01)
            f.set("imu_dtheta_x", 1e-7 * math.sin(k))
            if (k + 1) % 10 == 0:
                f.set("gnss_time", t1)
                # every 7th fix 30 m off: the robust and adaptive branches run too
                jump = 30.0 / 6.4e6 if (k + 1) % 70 == 0 else 0.0
                f.set("gnss_lat", lat + 1e-7 * math.cos(k) + jump)
                f.set("gnss_h", 100.0)
                f.set("gnss_valid", True)
                f.set("gnss_epoch", (k + 1) // 10)
            f.fmu.doStep(k * 0.01, 0.01)
            rows.append(f.reals(out))
        return np.array(rows)

    try:
        first, again = _runs_after_restore(f, run, 135, 160)
    finally:
        f.close()
    assert np.array_equal(first, again)
    assert np.isfinite(first).all()


@pytest.mark.parametrize("name", AHRS_FMUS)
def test_ahrs_state_save_restore_is_bit_identical(dist, name):
    """The AHRS FMUs driven by the TrajectoryImu FMU on the vibrating turntable: state saved
    after 3 s (the fuzzy filter's innovation window full), serialized and restored, continues
    bit-identically."""
    traj = _Fmu(dist / "TrajectoryImu.fmu", "traj", {
        "profile": "turntable_240s", "imu_period": 0.02, "gyro_arw_dpsh": 0.5,
        "accel_vrw_ugpsHz": 300.0, "mag_field_T": 5.4e-5, "mag_inclination": 1.0,
        "mag_noise_T": 1e-7, "vibration_start_s": 2.0, "vibration_accel_noise_mps2": 1.0})
    f = _Fmu(dist / f"{name}.fmu", name.lower(), {
        "mag_field_T": 5.4e-5, "mag_inclination": 1.0, "fuzzy_window": 5} if name ==
        "FuzzyUkfAhrs" else {"mag_field_T": 5.4e-5, "mag_inclination": 1.0})
    links = ["imu_time", "imu_dt", "imu_dtheta_x", "imu_dtheta_y", "imu_dtheta_z",
             "imu_dvel_x", "imu_dvel_y", "imu_dvel_z", "mag_time", "mag_x", "mag_y", "mag_z"]
    out = ["nav_roll", "nav_pitch", "nav_yaw", "std_pitch", "nis", "r_scale_accel"]

    def run(k0, n):
        rows = []
        for k in range(k0, k0 + n):
            traj.fmu.doStep(k * 0.02, 0.02)
            for name_, value in zip(links, traj.reals(links)):
                f.set(name_, float(value))
            f.fmu.doStep(k * 0.02, 0.02)
            rows.append(f.reals(out))
        return np.array(rows)

    try:
        run(0, 150)
        states = (traj.fmu.getFMUstate(), f.fmu.getFMUstate())
        first = run(150, 100)
        blobs = [x.serializeFMUstate(s) for x, s in zip((traj.fmu, f.fmu), states)]
        for x, b in zip((traj.fmu, f.fmu), blobs):
            x.setFMUstate(x.deSerializeFMUstate(b))
        again = run(150, 100)
    finally:
        traj.close()
        f.close()
    assert np.array_equal(first, again)
    assert np.isfinite(first).all() and first[-1, 3] > 0


def test_nan_reaching_a_filter_input_is_a_clear_fmi_error(dist):
    logs = []
    f = _Fmu(dist / "Kf.fmu", "kf", {"init_lat": 0.7}, logs=logs)
    try:
        f.set("imu_time", 0.01)
        f.set("imu_dt", 0.01)
        f.set("imu_dvel_x", float("nan"))
        with pytest.raises(FMICallException):
            f.fmu.doStep(0.0, 0.01)
    finally:
        f.close()
    assert any("imu_dvel_x" in m and "nan" in m.lower() for m in logs), logs


def test_bad_parameter_is_fmi2error_at_exit_initialization(dist):
    """A parameter the component refuses: fmi2Error from fmi2ExitInitializationMode, one
    Error-status message naming it; the instance is in FMI's error state: its values are
    read, doStep is refused (fmi2Error) naming the same error, free works."""
    require_patched(dist / "GnssReceiver.fmu")
    f = _Fmu(dist / "GnssReceiver.fmu", "gnss", {"pos_sigma_n": -1.0}, exit_init=False)
    try:
        with pytest.raises(FMICallException) as info:
            f.fmu.exitInitializationMode()
        assert info.value.status == 3
        (message,) = [m for s, m in f.records if s == 3]
        assert message.startswith("gnss: ") and "pos_sigma_n" in message
        assert f.reals(["pos_sigma_n"]).tolist() == [-1.0]
        with pytest.raises(FMICallException) as info:
            f.fmu.doStep(0.0, 1.0)
        assert info.value.status == 3                 # the instance is in the error state
        assert "fmi2DoStep is not allowed in state error" in f.records[-1][1]
        assert "pos_sigma_n" in f.records[-1][1]
    finally:
        f.close()


def test_build_after_an_fmu_ran_in_the_process(dist, tmp_path):
    """An FMU run in a process leaves ``import pythonfmu`` pointing at the copy in the FMU's
    resources (no FMI binaries); a later build in that process must still produce a complete
    FMU.  A fresh interpreter, so that pythonfmu is first imported by the FMU."""
    script = f"""
import sys
from pathlib import Path
from fmpy import simulate_fmu
from orchestrator.building import build
simulate_fmu({str(dist / "InsOnly.fmu")!r}, stop_time=0.05, step_size=0.01)
print("usable", build.builder_usable())
build.build(["InsOnly"], force=True, dist=Path({str(tmp_path)!r}), log=None)
"""
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    built = tmp_path / "InsOnly.fmu"
    with zipfile.ZipFile(built) as z:
        assert any(n.startswith("binaries/") and n.endswith((".so", ".dll", ".dylib"))
                   for n in z.namelist())
    assert validate_fmu(str(built)) == []
