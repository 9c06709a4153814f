"""Bad inputs of every command, one table: each row a command line, the exact first line it
must print (``navfmu: error: ...``, exit status 2, no traceback) and, checked for every row,
that nothing was written: the working folder holds after the command exactly what it held
before.  Plus the good side of the same inputs: a value given in km is taken in km.

Placeholders in a row: ``{scenario}`` (a private copy of aircraft_500s, edited by the row's
``edit``), ``{tmp}`` (the working folder), ``{dist}`` (the built FMUs), ``{full}`` (a folder on
a 64 KiB tmpfs: a full disk), ``{models}`` (the repository's models).  Inputs made for the
rows that name them (:data:`MADE`): KF-GINS files with a configuration of latitude 123 deg,
a sensor log whose header hides a zero-width space, an FMU without binaries or sources.
"""
from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import pytest

from orchestrator.building import build as fmu_build
from orchestrator.cli.commands import main

MODEL = fmu_build.ROOT / "models" / "aircraft_500s"
REPEAT_OVER = "99999999999999999999"


@pytest.fixture(scope="module", autouse=True)
def _fmus():
    fmu_build.build(log=None)


def _ssv(path: Path, name: str, value: str, unit: str = "") -> Path:
    """An .ssv file of one Real parameter, with a ``unit`` attribute when given."""
    unit_attr = f' unit="{unit}"' if unit else ""
    path.write_text(
        '<?xml version="1.0" encoding="UTF-8"?>\n<ssv:ParameterSet version="1.0" name="p" '
        'xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues">\n'
        f'<ssv:Parameters><ssv:Parameter name="{name}"><ssv:Real value="{value}"{unit_attr}/>'
        '</ssv:Parameter></ssv:Parameters></ssv:ParameterSet>\n')
    return path


def _edit(path: Path, old: str, new: str) -> None:
    text = path.read_text()
    assert old in text, old
    path.write_text(text.replace(old, new, 1))


# the edits of the scenario copy a row may ask for (file, old, new)
EDITS = {
    "connector_in_deg": ("SystemStructure.ssd",
                         '<ssd:Connector name="truth_lat" kind="output"><ssc:Real unit="rad"/>',
                         '<ssd:Connector name="truth_lat" kind="output"><ssc:Real unit="deg"/>'),
    "speed_into_height": ("SystemStructure.ssd",
                          'startConnector="truth_h" endElement="gnss" endConnector="truth_h"',
                          'startConnector="truth_vn" endElement="gnss" endConnector="truth_h"'),
    "bound_in_furlong": ("gnss.ssv", '<ssv:Real value="5"/>',
                         '<ssv:Real value="5" unit="furlong"/>'),
    "negative_sigma": ("gnss.ssv", '<ssv:Real value="5"/>', '<ssv:Real value="-5"/>'),
    "paper_row_text": ("paper.json", '"position_ned_m": [9.4141, 8.6003, 3.2837]',
                       '"position_ned_m": "9.4 8.6 3.3"'),
}

KF = "{dist}/Kf.fmu"
TRAJ = "{dist}/TrajectoryImu.fmu"
S = "{scenario}"
OUT = "{tmp}/out"
RUN = ["run", S, "--stop", "1", "--no-plots", "--out", OUT]
SSV_KM = "{tmp}/km.ssv"
KFG = "{tmp}/kfgins"
LOG = "{models}/replay_gnss_ins_sim/log"

# id: (edit or None, command line, exact first line)
BAD = {
    # -- units ----------------------------------------------------------------------------
    "ssv_unknown_unit": (None, [*RUN, "--ssv", "{tmp}/furlong.ssv"],
                         "--ssv {tmp}/furlong.ssv: parameter 'gnss.pos_sigma_n' = 1.0 furlong: "
                         "unknown unit 'furlong'"),
    "ssv_speed_into_metres": (None, [*RUN, "--ssv", "{tmp}/speed.ssv"],
                              "--ssv {tmp}/speed.ssv: parameter 'gnss.pos_sigma_n' = 1.0 m/s: "
                              "'m/s' cannot be converted to the variable's unit 'm'"),
    "ssd_bound_unknown_unit": ("bound_in_furlong", RUN,
                               "component 'gnss' ({dist}/GnssReceiver.fmu): parameter "
                               "'pos_sigma_n' = 5.0 furlong: unknown unit 'furlong'"),
    "connector_deg_against_fmu_rad": (
        "connector_in_deg", RUN,
        f"component 'trajectory' ({TRAJ}): the system structure's connector 'truth_lat' "
        "against the FMU's variable: unit 'deg' against 'rad' (a connection passes the value "
        "unchanged: give both ends one unit)"),
    "connection_speed_to_height": (
        "speed_into_height", RUN,
        "connection trajectory.truth_vn -> gnss.truth_h: unit 'm/s' against 'm' (a connection "
        "passes the value unchanged: give both ends one unit)"),
    # -- models ---------------------------------------------------------------------------
    "paper_json_of_the_wrong_shape": (
        "paper_row_text", RUN,
        "{scenario}/paper.json: table[0].position_ned_m: expected 3 numbers (north, east, "
        "down) or null, got '9.4 8.6 3.3'"),
    "ssd_without_connections": (
        "no_connections", RUN,
        "{scenario}/SystemStructure.ssd: the system structure has no <ssd:Connections>: no "
        "component receives another's output, so a run would measure nothing; connect the "
        "sensors to the filter"),
    "mistyped_model": (None, ["run", "{tmp}/scenaro", "--out", OUT],
                       "{tmp}/scenaro: no such model folder, .ssd or .ssp file; did you mean "
                       "'scenario'?"),
    "mistyped_parameter": (None, [*RUN, "--set", "filter.r_pos_nn=1"],
                           f"parameter override 'filter.r_pos_nn': component 'filter' ({KF}) "
                           "has no parameter 'r_pos_nn'; did you mean 'r_pos_n', 'r_pos_e' or "
                           "'r_pos_d'?"),
    "mistyped_component": (None, [*RUN, "--set", "filtr.r_pos_n=1"],
                           "parameter override 'filtr.r_pos_n': no component named 'filtr' "
                           "(components: trajectory, gnss, filter); did you mean 'filter'?"),
    "mistyped_filter": (None, [*RUN, "--filter", "Iakff"],
                        "unknown filter 'Iakff' (our filters: {filters}; or give the path of "
                        "an .fmu file); did you mean 'Iakf'?"),
    "ssv_without_its_component": (None, [*RUN, "--ssv", SSV_KM],
                                  f"--ssv {SSV_KM}: parameter 'pos_sigma_n' names no component; "
                                  f"bind the file to one with --ssv COMPONENT={SSV_KM} "
                                  "(components: trajectory, gnss, filter)"),
    "ssv_mistyped_component": (None, [*RUN, "--ssv", f"gnns={SSV_KM}"],
                               f"--ssv gnns={SSV_KM}: {{scenario}}/SystemStructure.ssd has no "
                               "component 'gnns' (components: trajectory, gnss, filter); did "
                               "you mean 'gnss'?"),
    "report_unknown_scenario": (None, ["report", "--scenario", "aircraft_50s", "--out", OUT],
                                "--scenario aircraft_50s: no scenario of that name in "
                                "{models} and no scenario folder at that path (scenarios: "
                                "{scenarios}); did you mean 'aircraft_500s' or "
                                "'aircraft_outliers'?"),
    # -- empty lists and names ------------------------------------------------------------
    "compare_trailing_comma": (None, ["compare", S, "--filters", "Kf,", "--out", OUT],
                               "--filters: an empty item in 'Kf,'; separate the items by "
                               "single commas"),
    "run_empty_filter": (None, [*RUN, "--filter", ""],
                         "Invalid value for '--filter': empty name"),
    "tune_empty_train_seeds": (None, ["tune", S, "--params", "r_pos_n", "--train-seeds", "",
                                      "--out", OUT],
                               "--train-seeds: empty list; give at least one"),
    # -- bench ----------------------------------------------------------------------------
    "bench_endless_repeat": (None, ["bench", S, "--repeat", REPEAT_OVER],
                             f"--repeat: at most 100 alternating runs per path, got "
                             f"{REPEAT_OVER}"),
    "bench_libcosim_and_executors": (None, ["bench", S, "--libcosim", "--executors"],
                                     "--libcosim and --executors are two measurements; give "
                                     "one"),
    "bench_runs_without_executors": (None, ["bench", S, "--runs", "3"],
                                     "--runs applies to --executors only (the campaign it "
                                     "times)"),
    "bench_workers_without_executors": (None, ["bench", S, "--workers", "2"],
                                        "--workers applies to --executors only (the campaign "
                                        "it times)"),
    # -- montecarlo -----------------------------------------------------------------------
    "montecarlo_mixed_roles": (
        None, ["montecarlo", S, "--runs", "1", "--filters", "Kf,UkfAhrs", "--stop", "1",
               "--out", OUT],
        "component 'filter' (Python component navcore.components.ahrs_components.UkfAhrs) has "
        "no variable 'gnss_time', which the connection gnss.gnss_time -> filter.gnss_time "
        "needs"),
    "montecarlo_seed_set": (
        None, ["montecarlo", S, "--runs", "1", "--filters", "Kf", "--stop", "1",
               "--set", "gnss.seed=5", "--out", OUT],
        "--set gnss.seed=5: a campaign gives each random component its seed (run i: --seed + "
        "i + the component's offset); choose them with --seed and --seed-offset gnss=K "
        "instead"),
    # -- verify ---------------------------------------------------------------------------
    "verify_datasheet_text": (None, ["verify", KF, "--set", "datasheet.foo=bar", "--out", OUT],
                              "--set datasheet.foo=bar: a datasheet value must be a finite "
                              "number >= 0"),
    "verify_junit_below_a_file": (None, ["verify", KF, "--junit", f"{SSV_KM}/junit.xml",
                                         "--out", OUT],
                                  f"--junit {SSV_KM}/junit.xml: cannot write into {SSV_KM}: "
                                  "not a folder"),
    "verify_nan_parameter": (
        None, ["verify", KF, "--set", "init_lat=nan", "--out", OUT],
        "Kf.fmu refuses the parameter values given (init_lat=nan): component 'filter' "
        "(Kf.fmu): parameter 'init_lat' = nan is outside the accepted range (-1.5708, 1.5708) "
        "rad"),
    "verify_fmu_without_binaries": (
        None, ["verify", "{tmp}/nobin.fmu", "--out", OUT],
        "{tmp}/nobin.fmu: no binary for this platform (binaries/linux64/Kf.so) and no "
        "sources/ to build one from (the FMU has binaries for: none)"),
    # -- package and export -----------------------------------------------------------------
    "package_negative_sigma": (
        "negative_sigma", ["package", S, "--out", "{tmp}/m.ssp"],
        "component 'gnss' (GnssReceiver.fmu): parameter 'pos_sigma_n' = -5.0 is outside the "
        "accepted range [0, 10000] m"),
    "export_negative_sigma": (
        "negative_sigma", ["export", S, "--out", "{tmp}/m.fmu"],
        "component 'gnss' (GnssReceiver.fmu): parameter 'pos_sigma_n' = -5.0 is outside the "
        "accepted range [0, 10000] m"),
    # -- convert and replay -----------------------------------------------------------------
    "kf_gins_latitude_123": (
        None, ["convert", "kf-gins", f"{KFG}/imu.txt", f"{KFG}/gnss.txt", f"{KFG}/log",
               "--config", f"{KFG}/lat123.yaml"],
        f"{KFG}/lat123.yaml: key 'initpos': latitude 123 deg, longitude 114.472 deg: expected "
        "a latitude in [-90, 90] and a longitude in [-180, 360] deg"),
    "replay_stop_after_the_log": (
        None, [*RUN[:2], "--replay", LOG, "--stop", "1000", "--no-plots", "--out", OUT],
        f"--stop 1000: after the end of the log {LOG} (80.05 s); give a stop time up to it, "
        "or no --stop to replay to the log's end"),
    "replay_header_with_a_zero_width_space": (
        None, [*RUN, "--replay", "{tmp}/zwsp_log"],
        "--replay: {tmp}/zwsp_log/imu.csv, line 1: unknown column '\\u200btime [s]' "
        "(columns of this file: time [s], dt [s], dtheta_x [rad], dtheta_y [rad], dtheta_z "
        "[rad], dvel_x [m/s], dvel_y [m/s], dvel_z [m/s])"),
    # -- a full disk ----------------------------------------------------------------------
    "disk_full_run": (None, ["run", S, "--stop", "20", "--backend", "direct", "--out",
                             "{full}/out"],
                      "--out {full}/out: cannot write the results: No space left on device; "
                      "nothing was written"),
    "disk_full_sensor_log": (None, ["run", S, "--stop", "2", "--backend", "direct",
                                    "--log-sensors", "{full}/log", "--out", OUT],
                             "cannot write the sensor log {full}/log: No space left on device"),
    "disk_full_tune": (None, ["tune", S, "--params", "r_pos_n", "--generations", "1",
                              "--population", "2", "--stop", "0.5", "--out", "{full}/tune"],
                       "cannot write {full}/tune/fitness.png: No space left on device"),
    "disk_full_convert": (None, ["convert", "kf-gins", f"{KFG}/imu.txt", f"{KFG}/gnss.txt",
                                 "{full}/log"],
                          "cannot write the sensor log {full}/log: No space left on device"),
    "disk_full_package": (None, ["package", S, "--out", "{full}/m.ssp"],
                          "cannot write {full}/m.ssp: No space left on device"),
    "disk_full_export": (None, ["export", S, "--out", "{full}/m.fmu"],
                         "cannot write {full}/m.fmu: No space left on device"),
}


@pytest.fixture
def full_disk(tmp_path):
    """A folder on a 64 KiB tmpfs, filled to leave 8 KiB (a disk about to be full)."""
    folder = tmp_path / "full"
    folder.mkdir()
    mounted = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(folder)],
                             capture_output=True, text=True)
    if mounted.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {mounted.stderr.strip()}")
    free = shutil.disk_usage(folder).free
    (folder / ".filler").write_bytes(b"\0" * max(free - 8192, 0))
    yield folder
    subprocess.run(["umount", str(folder)], check=True)


def _kf_gins_inputs(folder: Path) -> None:
    """KF-GINS IMU and GNSS files and a configuration whose latitude is 123 deg."""
    from test_kf_gins import CONFIG, _kf_gins_files

    folder.mkdir()
    _kf_gins_files(folder, velocity=False)
    config = CONFIG.replace("initpos: [ 30.4447873701,", "initpos: [ 123.0,")
    assert config != CONFIG
    (folder / "lat123.yaml").write_text(config)


def _zero_width_space_log(folder: Path) -> None:
    """The replay scenario's log with a zero-width space before its IMU header's first title
    (invisible in a terminal)."""
    shutil.copytree(fmu_build.ROOT / "models" / "replay_gnss_ins_sim" / "log", folder)
    imu = folder / "imu.csv"
    imu.write_text("\u200b" + imu.read_text(encoding="utf-8"), encoding="utf-8")


def _fmu_without_binaries(path: Path) -> None:
    """Kf.fmu without its binaries/ (and it has no sources/)."""
    import zipfile

    with zipfile.ZipFile(fmu_build.DIST / "Kf.fmu") as src, zipfile.ZipFile(path, "w") as dst:
        for item in src.infolist():
            if not item.filename.startswith("binaries/"):
                dst.writestr(item, src.read(item))


#: the inputs a row names, made before it runs: placeholder text -> maker(path)
MADE = {"{tmp}/kfgins": _kf_gins_inputs, "{tmp}/zwsp_log": _zero_width_space_log,
        "{tmp}/nobin.fmu": _fmu_without_binaries}


def _listing(folder: Path):
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*"))


def _scenario(tmp_path: Path, edit) -> Path:
    dst = tmp_path / "scenario"
    shutil.copytree(MODEL, dst)
    ssd = dst / "SystemStructure.ssd"
    ssd.write_text(ssd.read_text().replace("../../fmus/dist/", f"{fmu_build.DIST}/"))
    if edit == "no_connections":
        head, _, rest = ssd.read_text().partition("<ssd:Connections>")
        ssd.write_text(head + rest.partition("</ssd:Connections>")[2])
    elif edit is not None:
        name, old, new = EDITS[edit]
        _edit(dst / name, old, new)
    return dst


def _placeholders(tmp_path, scenario, request) -> dict:
    from orchestrator.reporting.report import MODELS, scenario_folders
    from orchestrator.running.scenarios import filter_fmus

    values = {"tmp": tmp_path, "scenario": scenario, "dist": fmu_build.DIST,
              "filters": ", ".join(filter_fmus()), "models": MODELS,
              "scenarios": ", ".join(p.name for p in scenario_folders(MODELS))}
    if "full" in " ".join(request.node.callspec.params["args"]):
        values["full"] = request.getfixturevalue("full_disk")
    return values


@pytest.mark.parametrize("edit, args, first", BAD.values(), ids=BAD.keys())
def test_bad_input_is_one_line_and_leaves_nothing(capsys, tmp_path, monkeypatch, request,
                                                  edit, args, first):
    scenario = _scenario(tmp_path, edit)
    _ssv(tmp_path / "furlong.ssv", "gnss.pos_sigma_n", "1", "furlong")
    _ssv(tmp_path / "speed.ssv", "gnss.pos_sigma_n", "1", "m/s")
    _ssv(tmp_path / "km.ssv", "pos_sigma_n", "0.005", "km")
    values = _placeholders(tmp_path, scenario, request)
    for name, make in MADE.items():
        if any(a.startswith(name) for a in args):
            make(Path(name.format(**values)))
    monkeypatch.chdir(tmp_path)
    before = _listing(tmp_path)
    with pytest.raises(SystemExit) as exc:
        main([a.format(**values) for a in args])
    out, err = capsys.readouterr()
    # the first line of navfmu's voice (a long command's progress log may come before)
    lines = [line for line in err.splitlines() if line.startswith("navfmu:")]
    assert exc.value.code == 2, err
    assert lines[0] == "navfmu: error: " + first.format(**values)
    assert "Traceback" not in out + err and err.count("navfmu: error:") == 1
    assert _listing(tmp_path) == before        # nothing partial, nothing stale


def test_ssv_value_in_km_is_taken_in_km(capsys, tmp_path):
    """0.005 km binds 5 m (the receiver's 5 m of the scenario: the same run, bit for bit);
    a value in a unit of another size is converted by its factor, not read as metres."""
    scenario = _scenario(tmp_path, None)
    km = _ssv(tmp_path / "km.ssv", "pos_sigma_n", "0.004", "km")
    metres = _ssv(tmp_path / "m.ssv", "pos_sigma_n", "4")
    results = {}
    for name, ssv in (("km", km), ("m", metres)):
        out = tmp_path / name
        with pytest.raises(SystemExit) as exc:
            main(["run", str(scenario), "--stop", "3", "--backend", "direct", "--no-plots",
                  "--ssv", f"gnss={ssv}", "--out", str(out)])
        assert exc.value.code == 0, capsys.readouterr().err
        results[name] = json.loads((out / "metrics.json").read_text())["Kf"]
    assert results["km"]["metadata"]["parameters"]["gnss"]["pos_sigma_n"] == 4.0
    timing = "time_per_step_ms"     # measured wall time: the one entry that may differ
    same = [{k: v for k, v in results[n]["metrics"]["filter"].items() if k != timing}
            for n in ("km", "m")]
    assert same[0] == same[1] and same[0]["position_rms_m"]["n"] > 0
    assert (tmp_path / "km" / "results.csv").read_bytes() == (
        tmp_path / "m" / "results.csv").read_bytes()


def _run_ok(capsys, args):
    with pytest.raises(SystemExit) as exc:
        main([str(a) for a in args])
    out, err = capsys.readouterr()
    assert exc.value.code == 0, err
    return out, err


def test_a_byte_order_mark_in_a_log_header_is_read_past(capsys, tmp_path):
    """A log whose CSV files start with a UTF-8 byte-order mark (as spreadsheet programs
    write them) replays exactly as the same log without it."""
    log = fmu_build.ROOT / "models" / "replay_gnss_ins_sim" / "log"
    bom = tmp_path / "bom_log"
    shutil.copytree(log, bom)
    for csv in bom.glob("*.csv"):
        csv.write_bytes(b"\xef\xbb\xbf" + csv.read_bytes())
    for name, folder in (("plain", log), ("bom", bom)):
        _run_ok(capsys, ["run", MODEL, "--replay", folder, "--stop", "2", "--no-plots",
                         "--backend", "direct", "--out", tmp_path / name])
    assert (tmp_path / "bom" / "results.csv").read_bytes() == (
        tmp_path / "plain" / "results.csv").read_bytes()


def test_convert_force_without_config_removes_the_replaced_logs_ssv(capsys, tmp_path):
    """filter.ssv written by --config describes the log it came with; replacing the log
    with --force and no --config removes it (and says so) instead of keeping it stale."""
    from test_kf_gins import CONFIG, _kf_gins_files

    _kf_gins_files(tmp_path, velocity=False)
    (tmp_path / "kf-gins.yaml").write_text(CONFIG)
    files = [tmp_path / "imu.txt", tmp_path / "gnss.txt", tmp_path / "log"]
    _run_ok(capsys, ["convert", "kf-gins", *files, "--config", tmp_path / "kf-gins.yaml"])
    assert (tmp_path / "log" / "filter.ssv").is_file()
    out, _ = _run_ok(capsys, ["convert", "kf-gins", *files, "--force"])
    assert not (tmp_path / "log" / "filter.ssv").exists()
    assert f"removed {tmp_path / 'log' / 'filter.ssv'}: the configuration of the replaced " \
        "log" in out
    assert sorted(p.name for p in (tmp_path / "log").iterdir()) == ["gnss.csv", "imu.csv"]


def test_a_model_started_later_prints_no_paper_rows(capsys, tmp_path):
    """The paper's 0-500 s numbers are not printed beside a run of the model started at
    100 s (its own stop time, no --stop): the run's span is not the paper's."""
    scenario = _scenario(tmp_path, None)
    _edit(scenario / "SystemStructure.ssd", '<ssd:DefaultExperiment startTime="0.0" '
          'stopTime="500.0">', '<ssd:DefaultExperiment startTime="100.0" stopTime="102.0">')
    out, _ = _run_ok(capsys, ["run", scenario, "--no-plots", "--backend", "direct", "--out",
                              tmp_path / "out"])
    assert "paper:" not in out
    assert ("(the paper's numbers are left out: the run spans 100-102 s, the paper's "
            "scenario 0-500 s)") in out
