"""Bad input through the `navfmu` CLI: one clear message, non-zero exit, no traceback, and no
result file left behind."""
from __future__ import annotations

import json
import shutil
import subprocess
import sys

import pytest

from orchestrator import build as fmu_build
from orchestrator.cli import main

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
    "step_hint_not_a_multiple_of_the_base_step": ('<osp:StepSizeHint value="1.0"/>',
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
    assert not any(n.startswith(".") for n in names)  # no temporary files left
