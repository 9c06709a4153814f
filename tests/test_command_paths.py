"""Every command path ends cleanly: bad options and unwritable outputs give one first line
``navfmu: error: ...`` (exit 2) and write nothing; Ctrl-C (130) and SIGTERM (143) end a
command, a Dask LocalCluster campaign included, with its one line, its workers gone and its
finished runs kept; a killed command's staging folder is removed by the next one; warnings
print once in the command line's voice.  One test (at least) per class of the catalog of
bad inputs the commands were tried with."""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
import warnings

import psutil
import pytest

from orchestrator.building import build as fmu_build
from orchestrator.campaigns.campaign import MANIFEST
from orchestrator.errors import NavfmuWarning
from orchestrator.cosim.interrupts import SIGNAL_AT_ENV
from orchestrator.results.outputs import MARKER
from orchestrator.cli.user_warnings import in_cli_voice

ROOT = fmu_build.ROOT
MODEL = ROOT / "models" / "aircraft_500s"
GIS = ROOT / "tests" / "data" / "gnss-ins-sim" / "motion_def-3d_mid_100Hz"
#: a path no file can be created in (procfs)
UNWRITABLE = "/proc/navfmu-test"


@pytest.fixture(scope="module", autouse=True)
def _fmus():
    fmu_build.build(log=None)


def _env(**extra):
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT / "fmus"), str(ROOT),
                                         env.get("PYTHONPATH", "")])
    env.update(extra)
    return env


def _refused(navfmu_cli, *args, words=()):
    """The command fails with exit 2 and one first line naming ``words``; returns stderr."""
    code, out, err = navfmu_cli(*args)
    assert code == 2, (code, out, err)
    lines = err.strip().splitlines()
    assert lines and lines[0].startswith("navfmu: error: "), err
    assert err.count("navfmu: error:") == 1 and "Traceback" not in err + out, err
    assert "internal error" not in err
    for word in words:
        assert word in lines[0], (word, err)
    return err


def _listing(folder):
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*"))


# -- not clean before: internal errors ---------------------------------------------------
@pytest.mark.parametrize("args, words", [
    (["export", MODEL, "--out", f"{UNWRITABLE}.fmu"], ["--out", "cannot write into /proc"]),
    (["package", MODEL, "--out", f"{UNWRITABLE}.ssp"], ["--out", "cannot write into /proc"]),
    (["convert", "gnss-ins-sim", GIS, UNWRITABLE], ["destination", "cannot write into /proc"]),
    (["tune", MODEL, "--params", "r_scale_max", "--out", UNWRITABLE],
     ["--out", "cannot write into /proc"]),
    (["montecarlo", MODEL, "--runs", "1", "--filters", "Kf", "--stop", "0.1", "--out",
      UNWRITABLE], ["--out", "cannot write"]),
], ids=["export", "package", "convert", "tune-out", "montecarlo"])
def test_unwritable_output_refused_before_the_work(navfmu_cli, tmp_path, monkeypatch, args,
                                                   words):
    monkeypatch.chdir(tmp_path)
    _refused(navfmu_cli, *args, words=words)
    assert _listing(tmp_path) == []


def test_montecarlo_unknown_scheduler_address_writes_nothing(navfmu_cli, tmp_path):
    out = tmp_path / "mc"
    _refused(navfmu_cli, "montecarlo", MODEL, "--runs", "1", "--filters", "Kf", "--out", out,
             "--scheduler", "foo", words=["--scheduler foo", "missing port number"])
    assert not out.exists()


# -- partly clean before: written before validated ---------------------------------------
@pytest.mark.parametrize("bad, words", [
    (["--stop", "-5"], ["--stop", "-5"]),
    (["--workers", "0"], ["--workers", "got 0"]),
    (["--workers", "-3"], ["--workers", "got -3"]),
    (["--set", "gnss.output_delay=nan"], ["output_delay", "nan"]),
    (["--seed", "2147483647"], ["--seed", "does not fit an FMI Integer"]),
    (["--window", "nan:3"], ["--window", "finite"]),
])
def test_montecarlo_refusal_leaves_no_campaign_behind(navfmu_cli, tmp_path, bad, words):
    """The refused command leaves no campaign.json: the corrected command then runs in the
    same folder (before, it was refused as 'holds another campaign')."""
    out = tmp_path / "mc"
    base = ["montecarlo", MODEL, "--runs", "1", "--filters", "Kf", "--out", out]
    _refused(navfmu_cli, *base, "--stop", "0.1", *bad, words=words)
    assert not out.exists()
    code, stdout, err = navfmu_cli(*base, "--stop", "0.1")
    assert code == 0, err
    assert (out / MANIFEST).is_file() and "1 runs x 1 filters = 1 filter runs: 1 now" in stdout


def test_montecarlo_refusal_in_an_existing_folder_keeps_it_as_it_was(navfmu_cli, tmp_path):
    out = tmp_path / "mc"
    out.mkdir()
    _refused(navfmu_cli, "montecarlo", MODEL, "--runs", "1", "--filters", "Kf", "--out", out,
             "--set", "gnss.output_delay=nan", "--stop", "0.1", words=["output_delay"])
    assert out.is_dir() and _listing(out) == []


@pytest.mark.parametrize("args, words", [
    (["--runs", "0"], ["--runs", "got 0"]),
    (["--workers", "0"], ["--workers", "got 0"]),
    (["--stop", "-1"], ["--stop"]),
    (["--out", ""], ["--out", "empty path"]),
])
def test_report_refusal_writes_nothing(navfmu_cli, tmp_path, monkeypatch, args, words):
    monkeypatch.chdir(tmp_path)
    options = {"--out": str(tmp_path / "rep"), **dict(zip(args[::2], args[1::2]))}
    _refused(navfmu_cli, "report", *[x for kv in options.items() for x in kv], words=words)
    assert _listing(tmp_path) == []


def test_bench_executors_refuses_workers_before_the_serial_leg(navfmu_cli):
    err = _refused(navfmu_cli, "bench", MODEL, "--executors", "--workers", "0", "--stop", "1",
                   words=["--workers", "got 0"])
    assert "campaign of" not in err


def test_bench_executors_zero_workers_is_refused_before_any_campaign(tmp_path):
    """Refused before the serial campaign starts (a real process): nothing of a campaign is
    printed and the working folder stays empty."""
    done = subprocess.run([sys.executable, "-m", "orchestrator.cli", "bench", str(MODEL),
                           "--executors", "--workers", "0"], env=_env(), capture_output=True,
                          text=True, timeout=120, cwd=tmp_path)
    assert done.returncode == 2 and done.stderr.startswith("navfmu: error: --workers")
    assert "campaign of" not in done.stdout + done.stderr and not list(tmp_path.iterdir())


# -- silently accepted before ------------------------------------------------------------
@pytest.mark.parametrize("backend", ["fmu", "direct"])
@pytest.mark.parametrize("value", ["99999999999999999999", "3000000000", "-2147483649"])
def test_integer_outside_the_fmi_range_refused_as_given(navfmu_cli, tmp_path, backend, value):
    err = _refused(navfmu_cli, "run", MODEL, "--stop", "0.1", "--no-plots", "--backend",
                   backend, "--out", tmp_path / "o", "--set", f"gnss.seed={value}",
                   words=["gnss", "'seed'", f"= {value} does not fit an FMI Integer"])
    assert "-1294967296" not in err and "1661992959" not in err
    assert not (tmp_path / "o").exists()


def test_empty_out_refused_not_the_default_folder(navfmu_cli, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    _refused(navfmu_cli, "run", MODEL, "--stop", "0.1", "--out", "", words=["--out", "empty"])
    _refused(navfmu_cli, "tune", MODEL, "--params", "r_scale_max", "--ssv", "",
             words=["--ssv", "empty"])
    assert _listing(tmp_path) == []


def test_tune_refuses_a_random_seed_as_a_parameter(navfmu_cli, tmp_path):
    _refused(navfmu_cli, "tune", MODEL, "--component", "gnss", "--params", "seed", "--out",
             tmp_path / "t", words=["--params seed", "--train-seeds"])
    assert not (tmp_path / "t").exists()


def test_resume_with_fewer_runs_keeps_every_finished_run(navfmu_cli, tmp_path):
    out = tmp_path / "mc"
    base = ["montecarlo", MODEL, "--filters", "Kf", "--stop", "0.5", "--out", out]
    code, first, err = navfmu_cli(*base, "--runs", "3")
    assert code == 0, err
    code, again, err = navfmu_cli(*base, "--runs", "1")
    assert code == 0, err
    assert "3 runs x 1 filters = 3 filter runs: 0 now, 3 done before" in again
    summary = json.loads((out / "summary.json").read_text())
    assert summary["runs"] == 3
    for entry in summary["axes"].values():
        interval = entry["filters"]["Kf"]
        assert interval["n"] == 3 and 0 < interval["low"] < interval["high"]
    one = tmp_path / "one"
    code, single, err = navfmu_cli(*base[:-1], one, "--runs", "1")
    assert code == 0 and "nan" not in single and "(n = 1)" in single


def test_kf_gins_files_swapped_refused(navfmu_cli, tmp_path):
    from test_sensorlog import _log, _write_kf_gins

    log = _log(n=400, dt=0.005, t0=456300.0)
    for k, s in (("std_n", 1.5), ("std_e", 1.2), ("std_d", 3.0)):
        log.gnss[k] = log.gnss["time"] * 0 + s
    _write_kf_gins(tmp_path, log)
    _refused(navfmu_cli, "convert", "kf-gins", tmp_path / "gnss.txt", tmp_path / "imu.txt",
             tmp_path / "log", words=["imu.txt", "swapped", "IMU_FILE GNSS_FILE"])
    assert not (tmp_path / "log").exists()


# -- small ---------------------------------------------------------------------------------
def test_unknown_filter_suggests_filters_only_and_compare_says_no_wrong_option(navfmu_cli,
                                                                              tmp_path):
    err = _refused(navfmu_cli, "compare", MODEL, "--filters", "Kf,Nope", "--stop", "0.1",
                   "--out", tmp_path / "o", words=["unknown filter 'Nope'", "Iakf", "Kf"])
    first = err.splitlines()[0]
    assert "--filter:" not in first
    for sensor in ("GnssReceiver", "TrajectoryImu", "ImuGnssReplay"):
        assert sensor not in first


def test_window_nan_names_the_problem(navfmu_cli, tmp_path):
    _refused(navfmu_cli, "run", MODEL, "--window", "nan:3", "--out", tmp_path / "o",
             words=["--window", "finite", "'nan:3'"])


def test_paper_rows_only_for_the_papers_scenario_over_its_length(navfmu_cli, tmp_path):
    code, out, err = navfmu_cli("run", MODEL, "--stop", "2", "--no-plots", "--out",
                                tmp_path / "o")
    assert code == 0, err
    assert "paper:" not in out and "no sample" not in err
    assert ("the paper's numbers are left out: the run spans 0-2 s, the paper's scenario "
            "0-500 s") in out
    assert not (tmp_path / "o" / "report.json").exists()


# -- warnings ------------------------------------------------------------------------------
def test_compare_ahrs_turntable_warns_once_in_the_cli_voice(navfmu_cli, tmp_path):
    code, out, err = navfmu_cli("compare", ROOT / "models" / "ahrs_turntable", "--filters",
                                "UkfAhrs,FuzzyUkfAhrs", "--stop", "2", "--no-plots", "--out",
                                tmp_path / "o")
    assert code == 0, err
    warned = [line for line in err.splitlines() if "warning" in line.lower()]
    assert len(warned) == 1, err
    assert warned[0].startswith("navfmu: warning: parameters not present in the swapped-in")
    assert "UserWarning" not in err and ".py:" not in err and "warnings.warn" not in err


def test_warnings_once_each_and_library_warnings_hidden(capsys):
    import matplotlib.pyplot as plt

    lines = []
    with in_cli_voice(lines.append):
        for _ in range(3):
            warnings.warn("a thing the user can act on", NavfmuWarning)
        warnings.warn("another one", NavfmuWarning)
        fig, ax = plt.subplots()
        ax.legend()              # matplotlib: "No artists with labels found to put in legend"
        plt.close(fig)
        warnings.warn("a library's deprecation", DeprecationWarning)
    assert lines == ["navfmu: warning: a thing the user can act on",
                     "navfmu: warning: another one"]
    assert capsys.readouterr().err == ""


# -- signals -------------------------------------------------------------------------------
def _staging(folder, name):
    return [p for p in folder.iterdir() if p.name.startswith(f".{name}.")]


def test_sigterm_while_writing_keeps_the_previous_folder(navfmu_cli, tmp_path):
    """SIGTERM arriving while the output files are written (sent at that point by the test
    hook): 'navfmu: terminated', exit 143, the previous output folder unchanged, no staging
    folder left."""
    out = tmp_path / "o"
    code, _, err = navfmu_cli("run", MODEL, "--stop", "1", "--no-plots", "--out", out)
    assert code == 0, err
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    done = subprocess.run([sys.executable, "-m", "orchestrator.cli", "run", str(MODEL),
                           "--stop", "2", "--out", str(out)],
                          env=_env(**{SIGNAL_AT_ENV: "writing:TERM"}), capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 128 + signal.SIGTERM, done.stderr
    assert done.stderr.strip().splitlines()[-1] == "navfmu: terminated"
    assert "Traceback" not in done.stderr and "navfmu: error" not in done.stderr
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    assert not _staging(tmp_path, "o")


@pytest.mark.parametrize("command", [
    ["export", MODEL, "--out", "{tmp}/m.fmu"],
    ["package", MODEL, "--out", "{tmp}/m.ssp"],
    ["convert", "gnss-ins-sim", GIS, "{tmp}/log"],
], ids=["export", "package", "convert"])
def test_ctrl_c_while_the_output_is_written_writes_nothing(tmp_path, command):
    """Ctrl-C arriving while a command writes its output (sent by the test hook when the
    first written file is about to be moved into place): exit 130 with 'navfmu: interrupted'
    and nothing written, not the complete output followed by 'interrupted'.  The command's
    temporary files are gone too."""
    work = tmp_path / "work"
    (work / "tmp").mkdir(parents=True)
    args = [str(a).format(tmp=work) for a in command]
    done = subprocess.run([sys.executable, "-m", "orchestrator.cli", *args],
                          env=_env(**{SIGNAL_AT_ENV: "commit:INT", "TMPDIR": str(work / "tmp")}),
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 130, done.stderr
    assert done.stderr.strip().splitlines()[-1] == "navfmu: interrupted"
    assert "Traceback" not in done.stderr and "navfmu: error" not in done.stderr
    assert _listing(work) == ["tmp"]


def test_ctrl_c_during_verify_stops_at_the_next_probe_and_leaves_no_temporary_files(tmp_path):
    """Ctrl-C during verify's FMI probes (at the first probe, by the test hook): exit 130
    without running the rest, no report and no temporary folder (tables, probes) left."""
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    done = subprocess.run([sys.executable, "-m", "orchestrator.cli", "verify",
                           str(fmu_build.DIST / "Kf.fmu"), "--out", str(tmp_path / "v")],
                          env=_env(**{SIGNAL_AT_ENV: "verify-probe:INT", "TMPDIR": str(tmp)}),
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 130, done.stderr
    assert done.stderr.strip().splitlines()[-1] == "navfmu: interrupted"
    assert "pass" not in done.stdout and not (tmp_path / "v").exists()
    assert list(tmp.iterdir()) == []


def test_stale_staging_folder_of_a_killed_run_removed_by_the_next(navfmu_cli, tmp_path):
    import socket

    from orchestrator.results.outputs import _OWNER

    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True).stdout.strip()
    assert _OWNER == "".join(c if c.isalnum() else "_" for c in socket.gethostname())
    stale = tmp_path / f".o.{_OWNER}-{dead}.abc123.partial"
    live = tmp_path / f".o.{_OWNER}-{os.getpid()}.def456.partial"   # a command still going
    other_host = tmp_path / f".o.otherhost-{dead}.ghi789.partial"
    for folder in (stale, live, other_host):
        folder.mkdir()
        (folder / "results.csv").write_text("12 MB of a killed run\n")
    code, _, err = navfmu_cli("run", MODEL, "--stop", "0.5", "--no-plots", "--out",
                              tmp_path / "o")
    assert code == 0, err
    assert not stale.exists() and live.is_dir() and other_host.is_dir()
    assert (tmp_path / "o" / MARKER).is_file()


def _group_alive(pgid):
    return [p for p in psutil.process_iter(["status"])
            if p.info["status"] != psutil.STATUS_ZOMBIE and _pgid(p) == pgid]


def _pgid(process):
    try:
        return os.getpgid(process.pid)
    except (ProcessLookupError, PermissionError):
        return None


@pytest.mark.parametrize("sig, to_group, last", [
    pytest.param(signal.SIGINT, True, "navfmu: interrupted", id="ctrl-c-to-the-group"),
    pytest.param(signal.SIGTERM, False, "navfmu: terminated", id="sigterm-to-the-driver",
                 marks=pytest.mark.slow),
])
def test_local_cluster_campaign_stops_on_ctrl_c_to_its_process_group(tmp_path, sig, to_group,
                                                                     last):
    """Ctrl-C to the whole process group (what a terminal sends: driver, nannies and Dask
    workers all get it), twice, or SIGTERM to the driver, once the first run file exists:
    the campaign ends within 15 s with its one line and status, no Dask traceback or log
    line, every process of the group gone, the finished runs kept; the same command then
    finishes the campaign, running only the missing runs."""
    out = tmp_path / "mc"
    command = [sys.executable, "-m", "orchestrator.cli", "montecarlo", str(MODEL), "--runs",
               "8", "--filters", "Kf", "--stop", "30", "--batch", "1", "--workers", "2",
               "--out", str(out)]
    proc = subprocess.Popen(command + ["--local-cluster"], env=_env(), cwd=tmp_path,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    deadline = time.monotonic() + 240
    while not list(out.glob("runs/*/run-*.json")):
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < deadline, "no run finished in time"
        time.sleep(0.05)
    t0 = time.monotonic()
    if to_group:
        os.killpg(proc.pid, sig)
        time.sleep(0.5)
        if proc.poll() is None:
            os.killpg(proc.pid, sig)
    else:
        proc.send_signal(sig)
    _, err = proc.communicate(timeout=60)
    assert time.monotonic() - t0 < 15
    assert proc.returncode == 128 + sig, err
    assert [line for line in err.splitlines() if line.strip()] == [last]
    settle = time.monotonic() + 15
    while _group_alive(proc.pid) and time.monotonic() < settle:
        time.sleep(0.2)
    assert not _group_alive(proc.pid)
    kept = sorted(out.glob("runs/*/run-*.json"))
    assert 1 <= len(kept) < 8 and not list(out.rglob("*.tmp"))
    mtimes = {p: p.stat().st_mtime_ns for p in kept}
    done = subprocess.run(command[:command.index("--workers")] + ["--out", str(out)],
                          env=_env(), capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    assert f"{8 - len(kept)} now, {len(kept)} done before" in done.stdout
    assert all(p.stat().st_mtime_ns == m for p, m in mtimes.items())


def test_interrupt_before_the_first_run_takes_the_manifest_back(tmp_path):
    """Ctrl-C (sent by the test hook) after the manifest was written, before any run
    finished: the folder made for the campaign is gone again."""
    out = tmp_path / "mc"
    done = subprocess.run([sys.executable, "-m", "orchestrator.cli", "montecarlo", str(MODEL),
                           "--runs", "2", "--filters", "Kf", "--stop", "5", "--out", str(out)],
                          env=_env(**{SIGNAL_AT_ENV: "campaign-started:INT"}),
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 130, done.stderr
    assert done.stderr.strip().splitlines()[-1] == "navfmu: interrupted"
    assert not out.exists()


def test_writing_the_outputs_reports_its_progress(tmp_path):
    """The output-writing phase (seconds for a long CSV) tells the progress bar of each
    part: the results file, metrics.json, the plots."""
    from orchestrator.running import scenarios
    from orchestrator.running.run_outputs import write_outputs

    run = scenarios.simulate_scenario(scenarios.load_scenario(MODEL), backend="direct",
                                      stop_time=1.0)
    calls = []
    written = write_outputs([run], tmp_path / "o", plots_on=True,
                            progress=lambda done, total: calls.append((done, total)))
    assert calls == [(0, 3), (1, 3), (2, 3), (3, 3)]
    assert {p.name for p in written} >= {"results.csv", "metrics.json", "errors.png"}


@pytest.mark.slow
def test_pool_campaign_sigterm_ends_it_without_finishing_the_runs_in_flight(tmp_path):
    """SIGTERM to the driver of a process-pool campaign of long runs: ended within 10 s (the
    pool's workers are terminated, not waited for), the finished runs kept."""
    out = tmp_path / "mc"
    proc = subprocess.Popen([sys.executable, "-m", "orchestrator.cli", "montecarlo",
                             str(MODEL), "--runs", "6", "--filters", "Kf", "--stop", "300",
                             "--workers", "2", "--out", str(out)], env=_env(),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 300
    while not list(out.glob("runs/*/run-*.json")):
        assert proc.poll() is None and time.monotonic() < deadline, proc.communicate()
        time.sleep(0.05)
    t0 = time.monotonic()
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=120)
    assert time.monotonic() - t0 < 10
    assert proc.returncode == 143 and err.strip() == "navfmu: terminated", err
    assert 1 <= len(list(out.glob("runs/*/run-*.json"))) < 6
