"""Bad input through the `navfmu` CLI: one clear message, non-zero exit, no traceback, and no
result file left behind."""
from __future__ import annotations

import json
import shutil
import subprocess
import sys

import pytest

from orchestrator.building import build as fmu_build
from orchestrator.cli.commands import main
from orchestrator.results.outputs import MARKER

MODEL = fmu_build.ROOT / "models" / "aircraft_500s"


@pytest.fixture(scope="module", autouse=True)
def _fmus():
    fmu_build.build(log=None)


@pytest.fixture
def scenario(tmp_path):
    """A private copy of aircraft_500s whose FMU sources point at the built FMUs."""
    dst = tmp_path / "scenario"
    shutil.copytree(MODEL, dst)
    ssd = dst / "SystemStructure.ssd"
    ssd.write_text(ssd.read_text().replace("../../fmus/dist/", f"{fmu_build.DIST}/"))
    return dst


def _navfmu(capsys, *args):
    with pytest.raises(SystemExit) as exc:
        main(list(args))
    out, err = capsys.readouterr()
    return exc.value.code, out, err


def _assert_clean_failure(capsys, out_dir, *args, expect):
    code, out, err = _navfmu(capsys, *args, "--out", str(out_dir), "--no-plots")
    assert code != 0
    assert "Traceback" not in err + out
    assert "navfmu: error:" in err
    for word in expect:
        assert word in err, (word, err)
    assert not out_dir.exists() or not any(out_dir.iterdir())
    return err


def _edit(path, old, new):
    text = path.read_text()
    assert old in text
    path.write_text(text.replace(old, new, 1))


# one edit of the scenario's SSD -> one clean error naming what is wrong
SSD_EDITS = {
    "malformed_xml": ("</ssd:Elements>", "</ssd:Elementz>", ["SystemStructure.ssd"]),
    "connection_to_unknown_component": ('endElement="filter" endConnector="gnss_epoch"',
                                        'endElement="filtre" endConnector="gnss_epoch"',
                                        ["filtre"]),
    # a source found nowhere on the search path (Kf.fmu would be found in fmus/dist by name)
    "missing_fmu_file": (f"{fmu_build.DIST}/Kf.fmu", "/nonexistent/NoSuchFilter.fmu",
                         ["/nonexistent/NoSuchFilter.fmu", "NAVFMU_FMU_PATH"]),
    "zero_base_step": ('baseStepSize="0.01"', 'baseStepSize="0"', ["baseStepSize"]),
    "negative_base_step": ('baseStepSize="0.01"', 'baseStepSize="-0.01"', ["baseStepSize"]),
    "step_hint_not_a_multiple_of_the_base_step": ('<osp:StepSizeHint value="0.1"/>',
                                                  '<osp:StepSizeHint value="0.015"/>',
                                                  ["0.015", "gnss"]),
}


@pytest.mark.parametrize("old, new, expect", SSD_EDITS.values(), ids=SSD_EDITS.keys())
def test_broken_ssd(capsys, scenario, tmp_path, old, new, expect):
    _edit(scenario / "SystemStructure.ssd", old, new)
    _assert_clean_failure(capsys, tmp_path / "out", "run", str(scenario), expect=expect)


def test_connection_to_unknown_variable(capsys, scenario, tmp_path):
    ssd = scenario / "SystemStructure.ssd"
    _edit(ssd, 'endConnector="gnss_epoch"/>', 'endConnector="gnss_epoc"/>')
    _edit(ssd, '<ssd:Connector name="gnss_epoch" kind="input">',
          '<ssd:Connector name="gnss_epoc" kind="input">')
    _assert_clean_failure(capsys, tmp_path / "out", "run", str(scenario), expect=["gnss_epoc"])


def test_swap_to_fmu_lacking_a_connected_variable(capsys, scenario, tmp_path):
    # the receiver FMU has none of the filter's IMU inputs
    _assert_clean_failure(capsys, tmp_path / "out", "run", str(scenario), "--filter",
                          "GnssReceiver", expect=["imu_time", "filter"])


def test_negative_noise_sigma(capsys, scenario, tmp_path):
    _assert_clean_failure(capsys, tmp_path / "out", "run", str(scenario), "--stop", "2",
                          "--set", "gnss.pos_sigma_n=-1", expect=["pos_sigma_n"])


def test_unknown_motion_segment_type(capsys, scenario, tmp_path):
    profile = tmp_path / "loop.json"
    profile.write_text(json.dumps({
        "start": {"lat_deg": 40.1, "lon_deg": 118.6, "h": 100.0, "speed": 50.0, "yaw_deg": 0.0},
        "segments": [{"type": "cruise", "duration": 10.0},
                     {"type": "barrel_roll", "duration": 5.0}]}))
    _assert_clean_failure(capsys, tmp_path / "out", "run", str(scenario), "--stop", "2",
                          "--set", f"trajectory.profile={profile}", expect=["barrel_roll"])


def test_nan_parameter_reaching_the_filter(capsys, scenario, tmp_path):
    _assert_clean_failure(capsys, tmp_path / "out", "run", str(scenario), "--stop", "1",
                          "--set", "filter.init_h=nan", expect=["init_h"])


def test_real_process_exit_code_and_no_traceback(scenario, tmp_path):
    _edit(scenario / "SystemStructure.ssd", "</ssd:Elements>", "</ssd:Elementz>")
    out_dir = tmp_path / "out"
    proc = subprocess.run([sys.executable, "-m", "orchestrator.cli", "run", str(scenario),
                           "--out", str(out_dir)], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr
    assert proc.stderr.count("navfmu: error:") == 1
    assert not out_dir.exists()


def test_successful_short_run_writes_results(capsys, scenario, tmp_path):
    out_dir = tmp_path / "ok"
    code, out, err = _navfmu(capsys, "run", str(scenario), "--stop", "20", "--out", str(out_dir))
    assert code == 0, err
    names = {p.name for p in out_dir.iterdir()}
    assert {"results.csv", "metrics.json", "errors.png", "nis.png", "trajectory.png"} <= names
    header = (out_dir / "results.csv").read_text().splitlines()[0].split(",")
    assert header[0] == "time [s]"
    assert "filter.nav_lat [rad]" in header and "trajectory.truth_vn [m/s]" in header
    metrics = json.loads((out_dir / "metrics.json").read_text())
    assert metrics["Kf"]["metrics"]["filter"]["window_s"] == [0.0, 20.0]
    assert not any(n.startswith(".") for n in names - {MARKER})  # no temporary files left
    assert not any(p.name.startswith(f".{out_dir.name}.") for p in tmp_path.iterdir())


# -- one first line for errors found inside an FMU ------------------------------------------
def _first_line(err):
    lines = [line for line in err.splitlines() if line.strip()]
    assert lines and lines[0].startswith("navfmu: error: "), err
    return lines[0]


FMU_SIDE = {
    "huge_gnss_sigma": ("gnss.pos_sigma_n=1e300",
                        "component 'gnss' (GnssReceiver.fmu): parameter 'pos_sigma_n' = 1e+300 "
                        "is outside the accepted range [0, 10000] m"),
    "huge_accel_bias": ("trajectory.accel_bias_ug=1e300",
                        "component 'trajectory' (TrajectoryImu.fmu): parameter 'accel_bias_ug' "
                        "= 1e+300 is outside the accepted range [0, 1e+06] ug"),
    "nan_latitude": ("filter.init_lat=nan",
                     "component 'filter' (Kf.fmu): parameter 'init_lat' = nan is outside the "
                     "accepted range (-1.5708, 1.5708) rad"),
    "bad_noise_steps_text": ("gnss.noise_steps=50,100,vel",
                             "component 'gnss' (GnssReceiver.fmu): parameter 'noise_steps': "
                             "record '50,100,vel' has 3 fields, expected 6"),
    "unknown_profile": ("trajectory.profile=no_such_profile",
                        "component 'trajectory' (TrajectoryImu.fmu): profile 'no_such_profile' "
                        "is neither a built-in profile"),
    "imu_faster_than_the_filter": ("trajectory.imu_period=0.005",
                                   "component 'filter' (Kf.fmu): input 'imu_time' = 0.01 s with "
                                   "'imu_dt' = 0.005 s starts at 0.005 s"),
    "negative_seed": ("gnss.seed=-3", "component 'gnss' (GnssReceiver.fmu): parameter 'seed' = "
                                      "-3 is outside the accepted range [0, 2.14748e+09]"),
}


@pytest.mark.parametrize("setting, first", FMU_SIDE.values(), ids=FMU_SIDE.keys())
def test_fmu_side_error_is_the_first_line(capsys, scenario, tmp_path, setting, first):
    err = _assert_clean_failure(capsys, tmp_path / "out", "run", str(scenario), "--stop", "2",
                                "--set", setting, expect=[])
    line = _first_line(err)
    assert line.startswith("navfmu: error: " + first), line
    assert "fmi2DoStep" not in line and "FMU log" not in err  # the call and log are details


def test_component_log_with_debug(capsys, scenario, tmp_path):
    code, _, err = _navfmu(capsys, "--debug", "run", str(scenario), "--stop", "2",
                           "--set", "gnss.pos_sigma_n=-1", "--out", str(tmp_path / "o"))
    assert code == 2 and _first_line(err).count("pos_sigma_n") == 1
    assert "component log:" in err and "[Error]" in err


# -- checks before the run -------------------------------------------------------------------
PRE_RUN = {
    "infinite_stop": (
        ["--stop", "inf"],
        "navfmu: error: --stop: the stop time must be a finite " "number of seconds, got inf",
    ),
    "stop_before_start": (
        ["--stop", "-5"],
        "navfmu: error: --stop: the stop time -5 s must be " "after the start time 0 s",
    ),
    "recording_too_large": (      # 79: the filter's outputs include 'aligned'
        ["--stop", "1e7"],
        "navfmu: error: --stop: the run would record " "1000000001 rows x 79 variables",
    ),
    "stop_beyond_the_profile": (
        ["--stop", "600"],
        "navfmu: error: component 'trajectory' (TrajectoryImu.fmu): the run "
        "ends at 600 s, after the end of profile 'aircraft_500s' at 500 s; "
        "stop by 500 s or set parameter 'extend_profile' = true",
    ),
}


@pytest.mark.parametrize("args, first", PRE_RUN.values(), ids=PRE_RUN.keys())
def test_refused_before_the_run(capsys, scenario, tmp_path, args, first):
    err = _assert_clean_failure(capsys, tmp_path / "out", "run", str(scenario), *args, expect=[])
    assert _first_line(err).startswith(first), err


def test_extend_profile_flies_on(capsys, scenario, tmp_path):
    profile = tmp_path / "short.json"
    profile.write_text(json.dumps({
        "start": {"lat_deg": 40.1, "lon_deg": 118.6, "h": 100.0, "speed": 50.0, "yaw_deg": 0.0},
        "segments": [{"type": "cruise", "duration": 2.0}]}))
    args = ["run", str(scenario), "--backend", "direct", "--stop", "3", "--no-plots",
            "--set", f"trajectory.profile={profile}"]
    code, _, err = _navfmu(capsys, *args, "--out", str(tmp_path / "refused"))
    assert code == 2 and "after the end of profile" in _first_line(err)
    code, _, err = _navfmu(capsys, *args, "--set", "trajectory.extend_profile=true",
                           "--out", str(tmp_path / "o"))
    assert code == 0, err
    res = json.loads((tmp_path / "o" / "metrics.json").read_text())
    assert res["Kf"]["metadata"]["stop_time"] == 3.0


def test_unwritable_out_refused_before_the_run(capsys, scenario, tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    code, _, err = _navfmu(capsys, "run", str(scenario), "--out", str(blocker / "out"))
    assert code == 2
    assert _first_line(err).startswith(f"navfmu: error: --out {blocker / 'out'}: cannot write "
                                       f"into {blocker}")
    assert "RMS errors" not in capsys.readouterr().out  # nothing ran


def test_out_holding_other_files_refused(capsys, scenario, tmp_path):
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "thesis.tex").write_text("precious")
    code, _, err = _navfmu(capsys, "run", str(scenario), "--stop", "1", "--out", str(mine))
    assert code == 2 and "holds files navfmu did not write" in _first_line(err)
    assert (mine / "thesis.tex").read_text() == "precious"


def test_validate_a_file_that_is_not_a_zip(capsys, tmp_path):
    fake = tmp_path / "Fake.fmu"
    fake.write_text("not a zip")
    code, _, err = _navfmu(capsys, "validate", str(fake))
    assert code == 2 and _first_line(err) == (f"navfmu: error: {fake}: not an FMU (an FMU is a "
                                              "zip archive)")


def test_filter_listed_twice(capsys, scenario, tmp_path):
    err = _assert_clean_failure(capsys, tmp_path / "out", "compare", str(scenario), "--filters",
                                "Kf,Iakf,Kf", expect=[])
    assert _first_line(err) == "navfmu: error: --filters: Kf listed more than once (Kf,Iakf,Kf)"


def test_bench_repeat_zero(capsys):
    code, _, err = _navfmu(capsys, "bench", "--repeat", "0")
    assert code == 2 and _first_line(err) == ("navfmu: error: --repeat: the number of runs per "
                                              "path must be a positive integer, got 0")


def test_bench_without_scenario_uses_the_package_models(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # no models/ here
    proc = subprocess.run([sys.executable, "-m", "orchestrator.cli", "bench", "--stop", "0.5",
                           "--repeat", "1", "--json"], capture_output=True, text=True,
                          timeout=300, env=_env())
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert out["fmu"]["steps"] == 50
    for path in ("direct", "fmu"):
        costs = out[path]
        assert costs["simulated_s_per_wall_s"] == pytest.approx(0.5 / costs["wall_s"])
        # per base step: the receiver (0.1 s hint on the 0.01 s base step) steps every 10th
        assert costs["exchange_us_per_step"]["gnss"] == pytest.approx(
            costs["exchange_us"]["gnss"] / 10)
        assert costs["exchange_us_per_step"]["filter"] == pytest.approx(
            costs["exchange_us"]["filter"])


def test_usage_error_is_one_navfmu_line(capsys):
    code, _, err = _navfmu(capsys, "run", "--no-such-option")
    assert code == 2 and _first_line(err).startswith("navfmu: error: No such option")


def test_top_level_help_keeps_whole_sentences(capsys):
    code, out, _ = _navfmu(capsys, "--help")
    commands = out.split("Commands:")[1]
    assert code == 0 and "..." not in commands
    assert "and report its metrics." in " ".join(commands.split())


# -- the output folder ---------------------------------------------------------------------------
def test_run_then_compare_leaves_no_stale_file(capsys, scenario, tmp_path):
    out_dir = tmp_path / "same"
    common = ["--backend", "direct", "--stop", "2", "--no-plots", "--out", str(out_dir)]
    assert _navfmu(capsys, "run", str(scenario), *common)[0] == 0
    assert (out_dir / "results.csv").is_file()
    assert _navfmu(capsys, "compare", str(scenario), "--filters", "Kf,Iakf", *common)[0] == 0
    names = sorted(p.name for p in out_dir.iterdir())
    # no report.json: a 2 s run is not the paper's scenario, there is nothing to compare
    assert names == [MARKER, "metrics.json", "results_Iakf.csv", "results_Kf.csv"]
    assert sorted((out_dir / MARKER).read_text().split()) == names[1:]


def _env():
    import os

    env = dict(os.environ)
    root = str(fmu_build.ROOT)
    env["PYTHONPATH"] = os.pathsep.join([str(fmu_build.FMU_SOURCES), root,
                                         env.get("PYTHONPATH", "")])
    return env


def test_two_runs_on_one_out_do_not_mix(scenario, tmp_path):
    """Two runs of different length writing to one folder at the same time: the folder ends
    with every file of one of them (results, metrics and marker agree)."""
    out_dir = tmp_path / "shared"
    procs = [subprocess.Popen([sys.executable, "-m", "orchestrator.cli", "run", str(scenario),
                               "--backend", "direct", "--stop", stop, "--no-plots", "--out",
                               str(out_dir)], stdout=subprocess.DEVNULL,
                              stderr=subprocess.PIPE, text=True, env=_env())
             for stop in ("3", "4")]
    for p in procs:
        assert p.wait(timeout=300) == 0, p.stderr.read()
    stop = json.loads((out_dir / "metrics.json").read_text())["Kf"]["metadata"]["stop_time"]
    last = (out_dir / "results.csv").read_text().splitlines()[-1].split(",")[0]
    assert float(last) == pytest.approx(stop)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scenario", "shared"]  # no leftovers
