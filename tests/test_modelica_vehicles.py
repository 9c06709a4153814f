"""The Modelica vehicles of ``examples/modelica`` (source FMUs Rumoca generated from
``NavVehicles.mo``, checked in): compiled on first use by our master into a cache (one per
test session), valid by fmpy's checks, their truth against an independent integration of the
same equations (scipy), their body rates and specific force against finite differences of
their own truth with navcore's earth model, flown through ImuSensor -> GnssReceiver -> Kf; a
start at 100 s; the refusal of a source FMU on a machine without a compiler."""
from __future__ import annotations

import json
import math
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.validation import validate_fmu
from scipy.integrate import solve_ivp

from navcore.errors import NavfmuError
from navcore.ins import earth
from navcore.ins.rotations import euler_to_dcm_array
from orchestrator.building import build as fmu_build
from orchestrator.cosim import source_fmus
from orchestrator.cosim.fmi3_instance import open_fmu
from orchestrator.cosim.master import Simulation
from orchestrator.model.ssp_archive import load_model
from orchestrator.results import metrics as nav_metrics

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples" / "modelica"
FMUS = EXAMPLES / "fmus"
MODELS = {"FixedWingAircraft": EXAMPLES / "models" / "aircraft_fmi2",
          "GroundVehicle": EXAMPLES / "models" / "ground_vehicle_fmi2"}
STEP = 0.02
TRUTH = ("truth_lat", "truth_lon", "truth_h", "truth_vn", "truth_ve", "truth_vd",
         "truth_roll", "truth_pitch", "truth_yaw")
RATES = ("body_rate_x", "body_rate_y", "body_rate_z",
         "specific_force_x", "specific_force_y", "specific_force_z")
LAT0, LON0 = 0.6998770300497261, 2.069960492865275
G0 = 9.80665


@pytest.fixture(scope="module", autouse=True)
def source_cache(tmp_path_factory):
    """One cache of compiled source FMUs for the tests of this module (each FMU compiles
    once), and the FMUs navfmu builds."""
    folder = tmp_path_factory.mktemp("source-fmus")
    before = os.environ.get(source_fmus.CACHE_VARIABLE)
    os.environ[source_fmus.CACHE_VARIABLE] = str(folder)
    fmu_build.build(log=None)
    yield folder
    if before is None:
        del os.environ[source_fmus.CACHE_VARIABLE]
    else:
        os.environ[source_fmus.CACHE_VARIABLE] = before


# -- the profiles of NavVehicles.mo, written again for the reference -------------------------
def _window(t, t1, t2, tau):
    return 0.5 * (np.tanh((t - t1) / tau) - np.tanh((t - t2) / tau))


def aircraft_profile(t):
    """speed, yaw rate, flight-path angle, roll of FixedWingAircraft at time t."""
    turn = math.radians(3.0) * _window(t, 60.0, 120.0, 2.0)
    return 50.0, turn, math.radians(4.6) * _window(t, 200.0, 300.0, 2.0), \
        math.atan(50.0 * turn / G0)


def ground_profile(t, shift=0.0):
    """The same for GroundVehicle (its schedule shifted by ``shift`` seconds)."""
    t = t - shift
    turn_time = math.pi * 50.0 / 8.0
    slow = sum(_window(t, a - 4.0, a + turn_time + 4.0, 1.5) for a in (30.0, 85.0))
    turn = 8.0 / 50.0 * sum(_window(t, a, a + turn_time, 1.5) for a in (30.0, 85.0))
    grade = 0.02 * (_window(t, 55.0, 65.0, 1.5) - _window(t, 68.0, 78.0, 1.5))
    return 15.0 - 7.0 * slow, turn, grade, 0.0


PROFILES = {"FixedWingAircraft": (aircraft_profile, 1000.0, 360.0),
            "GroundVehicle": (ground_profile, 50.0, 130.0)}


def reference(model, times):
    """lat, lon, h, yaw at ``times``: the vehicle's kinematics integrated by scipy (DOP853)."""
    profile, h0, _ = PROFILES[model]

    def rhs(t, y):
        lat, _, h, yaw = y
        speed, turn, gamma, _ = profile(t)
        rn, re = earth.radii(lat)
        vn, ve = speed * math.cos(gamma) * math.cos(yaw), speed * math.cos(gamma) * math.sin(yaw)
        return [vn / (rn + h), ve / ((re + h) * math.cos(lat)), speed * math.sin(gamma), turn]

    sol = solve_ivp(rhs, (times[0], times[-1]), [LAT0, LON0, h0, 0.0], method="DOP853",
                    t_eval=times, rtol=1e-12, atol=[1e-15, 1e-15, 1e-9, 1e-14], max_step=0.5)
    assert sol.success
    return sol.y


def fly(fmu, stop, start=0.0):
    """Every output of the vehicle FMU at start, start + STEP, ..., stop, stepped through our
    master's FMU backend (which compiles the source FMU on first use)."""
    inst = open_fmu(fmu, "vehicle")
    try:
        names = [v.name for v in inst.variables.values() if v.causality == "output"]
        inst.prepare([], names)
        inst.initialize(start, stop)
        rows = [inst.get_outputs()[0].copy()]
        n = int(round((stop - start) / STEP))
        for k in range(n):
            inst.do_step(start + k * STEP, STEP)
            rows.append(inst.get_outputs()[0].copy())
    finally:
        inst.terminate()
    data = np.array(rows)
    return {name: data[:, j] for j, name in enumerate(names)}


@pytest.fixture(scope="module")
def flights():
    return {(m, v): fly(FMUS / v / f"{m}.fmu", PROFILES[m][2])
            for m in MODELS for v in ("fmi2", "fmi3")}


# -- the checked-in FMUs --------------------------------------------------------------------
@pytest.mark.parametrize("version", ["fmi2", "fmi3"])
@pytest.mark.parametrize("model", list(MODELS))
def test_the_checked_in_fmus_are_valid_source_fmus(model, version):
    fmu = FMUS / version / f"{model}.fmu"
    with zipfile.ZipFile(fmu) as z:
        names = z.namelist()
    assert any(n.startswith("sources/") and n.endswith(".c") for n in names)
    assert not any(n.startswith("binaries/") for n in names)
    assert validate_fmu(str(fmu)) == []


def test_a_source_fmu_compiles_once_into_the_cache_keyed_on_its_content(source_cache, tmp_path):
    fmu = FMUS / "fmi2" / "GroundVehicle.fmu"
    first = fly(fmu, 1.0)
    cached = sorted(source_cache.rglob("*.so"))
    key = source_fmus.fmu_builds.file_sha256(fmu)[:32]
    library = read_model_description(str(fmu)).coSimulation.modelIdentifier + ".so"
    mine = [p for p in cached if p.parent.name.startswith(key)]
    assert len(mine) == 1 and mine[0].name == library
    stamp = mine[0].stat().st_mtime_ns
    again = fly(fmu, 1.0)
    assert mine[0].stat().st_mtime_ns == stamp  # taken from the cache, not compiled again
    np.testing.assert_array_equal(first["truth_lat"], again["truth_lat"])
    # a changed FMU (another content) is another cache entry
    changed = tmp_path / "GroundVehicle.fmu"
    shutil.copyfile(fmu, changed)
    with zipfile.ZipFile(changed, "a") as z:
        z.writestr("documentation/note.txt", "changed")
    fly(changed, 0.1)
    assert len(list(source_cache.rglob(library))) == 2


# -- the truth ------------------------------------------------------------------------------
@pytest.mark.parametrize("version", ["fmi2", "fmi3"])
@pytest.mark.parametrize("model", list(MODELS))
def test_the_truth_matches_an_independent_integration(model, version, flights):
    out = flights[model, version]
    t = out["truth_time"]
    np.testing.assert_allclose(t, np.arange(len(t)) * STEP, rtol=0, atol=1e-9)
    lat, lon, h, yaw = reference(model, t)
    rn, re = earth.radii(lat)
    north = (out["truth_lat"] - lat) * (rn + h)
    east = (out["truth_lon"] - lon) * (re + h) * np.cos(lat)
    position = np.sqrt(north ** 2 + east ** 2 + (out["truth_h"] - h) ** 2)
    assert position.max() < 1e-7, position.max()  # measured 1.7e-8 m
    profile = PROFILES[model][0]
    speed, _, gamma, roll = np.array([profile(x) for x in t]).T
    np.testing.assert_allclose(out["truth_vn"], speed * np.cos(gamma) * np.cos(yaw), atol=1e-7)
    np.testing.assert_allclose(out["truth_ve"], speed * np.cos(gamma) * np.sin(yaw), atol=1e-7)
    np.testing.assert_allclose(out["truth_vd"], -speed * np.sin(gamma), atol=1e-9)
    np.testing.assert_allclose(out["truth_roll"], roll, atol=1e-12)
    np.testing.assert_allclose(out["truth_pitch"], gamma, atol=1e-12)
    np.testing.assert_allclose(np.exp(1j * out["truth_yaw"]), np.exp(1j * yaw), atol=1e-8)
    assert np.all(np.abs(out["truth_yaw"]) <= math.pi)


def _derivative(x):
    """Fourth-order central difference of samples ``x`` at STEP (all rows but two at
    either end)."""
    return (x[:-4] - 8 * x[1:-3] + 8 * x[3:-1] - x[4:]) / (12 * STEP)


@pytest.mark.parametrize("version", ["fmi2", "fmi3"])
@pytest.mark.parametrize("model", list(MODELS))
def test_body_rates_and_specific_force_match_the_truth(model, version, flights):
    """Fourth-order central differences of the FMU's attitude and velocity, with navcore's
    earth rate, transport rate and gravity: measured 3.7e-10 rad/s and 3.9e-8 m/s2 apart."""
    out = flights[model, version]
    c_bn = euler_to_dcm_array(out["truth_roll"], out["truth_pitch"], out["truth_yaw"])
    v = np.stack([out["truth_vn"], out["truth_ve"], out["truth_vd"]], axis=1)
    lat, h = out["truth_lat"], out["truth_h"]
    mid = slice(2, -2)
    skew = np.einsum("kji,kjl->kil", c_bn[mid], _derivative(c_bn))
    w_nb = np.stack([skew[:, 2, 1] - skew[:, 1, 2], skew[:, 0, 2] - skew[:, 2, 0],
                     skew[:, 1, 0] - skew[:, 0, 1]], axis=1) / 2
    w_ie = np.stack([earth.earth_rate_ned(x) for x in lat[mid]])
    w_en = np.stack([earth.transport_rate_ned(a, b, c)
                     for a, b, c in zip(lat[mid], h[mid], v[mid])])
    w_ib = w_nb + np.einsum("kji,kj->ki", c_bn[mid], w_ie + w_en)
    g = np.stack([earth.gravity_ned(a, b) for a, b in zip(lat[mid], h[mid])])
    f_n = _derivative(v) + np.cross(2 * w_ie + w_en, v[mid]) - g
    f_b = np.einsum("kji,kj->ki", c_bn[mid], f_n)
    rates = np.stack([out[n][mid] for n in RATES[:3]], axis=1)
    force = np.stack([out[n][mid] for n in RATES[3:]], axis=1)
    assert np.abs(rates - w_ib).max() < 1e-8, np.abs(rates - w_ib).max()
    assert np.abs(force - f_b).max() < 1e-6, np.abs(force - f_b).max()


# -- flown with Kf --------------------------------------------------------------------------
@pytest.mark.parametrize("model,limit", [("FixedWingAircraft", 1.5), ("GroundVehicle", 1.5)])
def test_a_modelica_vehicle_flies_our_sensors_and_kf(model, limit):
    results = Simulation(load_model(MODELS[model])).run()
    m = nav_metrics.filter_metrics(results, "filter")
    rms = m["position_rms_m"]
    assert all(0.05 < rms[a] < limit for a in ("n", "e")), rms
    assert 0.05 < rms["d"] < 2 * limit, rms
    assert results.column("gnss", "gnss_epoch")[-1] == PROFILES[model][2]


def _shifted_ground_vehicle(tmp_path, start):
    """models/ground_vehicle_fmi2 started at ``start`` with its schedule shifted as much."""
    folder = tmp_path / f"start_{start:g}"
    shutil.copytree(MODELS["GroundVehicle"], folder)
    ssd = folder / "SystemStructure.ssd"
    text = ssd.read_text().replace("../../fmus/", f"{FMUS}/").replace(
        "../../../../fmus/", f"{ROOT}/fmus/")
    text = text.replace('startTime="0.0" stopTime="130.0"',
                        f'startTime="{start}" stopTime="{start + 60.0}"')
    params = "".join(f'<ssv:Parameter name="{n}"><ssv:Real value="{v + start}"/></ssv:Parameter>'
                     for n, v in (("t_turn1", 30.0), ("t_turn2", 85.0), ("t_rise", 55.0)))
    text = text.replace(
        "</ssd:Connectors>\n      </ssd:Component>",
        "</ssd:Connectors>\n<ssd:ParameterBindings><ssd:ParameterBinding><ssd:ParameterValues>"
        '<ssv:ParameterSet version="1.0" name="vehicle"><ssv:Parameters>' + params +
        "</ssv:Parameters></ssv:ParameterSet></ssd:ParameterValues></ssd:ParameterBinding>"
        "</ssd:ParameterBindings>\n      </ssd:Component>", 1)
    ssd.write_text(text)
    return folder


def test_a_vehicle_started_at_100_s_flies_as_one_started_at_0(tmp_path):
    """The master, ImuSensor, GnssReceiver and Kf at a start time of 100 s: the same flight
    (the schedule shifted by 100 s) gives the same navigation errors as from 0 s."""
    runs = {}
    for start in (0.0, 100.0):
        results = Simulation(load_model(_shifted_ground_vehicle(tmp_path, start))).run()
        t = results.column("vehicle", "truth_time")
        assert t[0] == start and abs(t[-1] - (start + 60.0)) < 1e-9
        assert results.column("imu", "imu_time")[-1] == pytest.approx(start + 60.0, abs=1e-9)
        runs[start] = nav_metrics.filter_metrics(results, "filter")
    for a in ("n", "e", "d"):
        assert runs[100.0]["position_rms_m"][a] == pytest.approx(
            runs[0.0]["position_rms_m"][a], rel=1e-6)
        assert runs[0.0]["position_rms_m"][a] < 3.0


@pytest.mark.parametrize("model,stop", [("FixedWingAircraft", 240.0), ("GroundVehicle", 130.0)])
def test_the_fmi3_vehicle_navigates_as_the_fmi2_vehicle_of_the_same_model(model, stop):
    """The FMI 3.0 source FMU of the same Modelica model, compiled on first use and run by
    the FMI 3.0 instance: the same truth and the same navigation result, bit for bit."""
    model_ = load_model(MODELS[model])
    runs = {v: Simulation(model_.replace_source("vehicle", FMUS / v / f"{model}.fmu")).run(stop)
            for v in ("fmi2", "fmi3")}
    for component in ("vehicle", "imu", "filter"):
        assert runs["fmi3"].columns[component] == runs["fmi2"].columns[component]
        np.testing.assert_array_equal(runs["fmi3"].data[component],
                                      runs["fmi2"].data[component], err_msg=component)
    rms = nav_metrics.filter_metrics(runs["fmi3"], "filter")["position_rms_m"]
    assert max(rms.values()) < 3.0, rms


def test_verify_compiles_a_source_vehicle_and_checks_it(tmp_path):
    """`navfmu verify --role vehicle` on the source FMU: its probes in child processes get the
    compiled binary too; the vehicle's velocity, body rates and specific force pass its own
    checks (an independent account of the same outputs)."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), str(ROOT / "fmus")]))
    subprocess.run([sys.executable, "-m", "orchestrator.cli", "verify",
                    str(FMUS / "fmi2" / "GroundVehicle.fmu"), "--role", "vehicle",
                    "--out", str(tmp_path / "verify")], env=env, capture_output=True,
                   text=True, timeout=300)
    checks = json.loads((tmp_path / "verify" / "verify.json").read_text())["checks"]
    verdicts = {c["id"]: c["verdict"] for c in checks}
    for check in ("fmi.hostile", "vehicle.initial_outputs", "vehicle.velocity",
                  "vehicle.body_rates", "vehicle.specific_force", "vehicle.step_size",
                  "vehicle.flight"):
        assert verdicts[check] == "pass", (check, verdicts)


# -- no compiler ----------------------------------------------------------------------------
def test_a_source_fmu_without_a_compiler_is_refused_in_one_line(tmp_path):
    """With PATH stripped (no cmake, cc, make) and an empty cache, `navfmu run` of the
    aircraft says in its first line what is missing and writes nothing."""
    env = dict(os.environ, PATH=str(tmp_path / "empty"),
               **{source_fmus.CACHE_VARIABLE: str(tmp_path / "cache")})
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), str(ROOT / "fmus")])
    out = tmp_path / "out"
    done = subprocess.run([sys.executable, "-m", "orchestrator.cli", "run",
                           str(MODELS["FixedWingAircraft"]), "--out", str(out), "--stop", "1"],
                          env=env, capture_output=True, text=True, timeout=120)
    assert done.returncode != 0
    first = done.stderr.splitlines()[0]
    assert first.startswith("navfmu: error: component 'vehicle': "), done.stderr
    assert "FixedWingAircraft.fmu is a source FMU (no binary for linux64)" in first
    assert "needs cmake, a C compiler (cc, gcc or clang), make, not found on PATH" in first
    assert "Traceback" not in done.stderr and not out.exists()


def test_missing_tools_names_each_tool(monkeypatch, tmp_path):
    monkeypatch.setenv("PATH", str(tmp_path))
    monkeypatch.delenv("CC", raising=False)
    monkeypatch.delenv("CMAKE_GENERATOR", raising=False)
    assert source_fmus.missing_tools() == ["cmake", "a C compiler (cc, gcc or clang)", "make"]
    monkeypatch.setenv("CC", "my-cc")
    assert source_fmus.missing_tools()[1] == "a C compiler (CC=my-cc)"
