"""Monte Carlo campaigns: same per-run numbers in every executor mode and backend, the same
numbers as the hand-written replay loop, resume after SIGKILL of the driver or of a worker
(at chosen runs, through the test hook)."""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import psutil
import pytest

from navcore.components import registry as components
from orchestrator.campaigns.campaign import CampaignSpec, run_campaign
from orchestrator.campaigns.campaign_runs import read_run, run_one
from orchestrator.errors import NavfmuError
from direct_replay import MODELS, rms_table, run_filter, simulate_sensors

ROOT = Path(__file__).resolve().parent.parent
SCENARIO = str(MODELS / "aircraft_500s")
#: numbers that depend on the machine's speed, not on the run
TIMING = ("time_per_step_ms",)


def _numbers(out, spec):
    """filter -> per-run metrics without timings."""
    result = {}
    for f in spec.filters:
        result[f] = []
        for i in range(spec.runs):
            m = dict(read_run(Path(out), f, i)["metrics"])
            for key in TIMING:
                m.pop(key, None)
            result[f].append(m)
    return result


def test_one_run_equals_the_replay_loop():
    """Run 2 (seeds 3/3) of a campaign (the whole system in the master, metrics of
    orchestrator.results.metrics at the GNSS fixes) equals the filter replayed on the sensors alone
    (tests/direct_replay.py) with that helper's own error formulas (the slow tests' numbers)."""
    sensors = simulate_sensors(MODELS / "aircraft_outliers", stop_time=60.0,
                               overrides={"trajectory": {"seed": 3}, "gnss": {"seed": 3}})
    for cls in (components.Kf, components.NewtonRobustKf):
        replay = run_filter(sensors, cls)
        table = rms_table(replay)
        job = {"ssd": str(MODELS / "aircraft_outliers" / "SystemStructure.ssd"),
               "filter": cls.model_name, "index": 2, "seeds": {"trajectory": 3, "gnss": 3},
               "parameters": [], "backend": "direct", "stop_time": 60.0, "window": None,
               "samples": "fixes", "series": None, "out": "/nonexistent-campaign-folder"}
        m = run_one(job)["metrics"]
        np.testing.assert_allclose([m["position_rms_m"][a] for a in "ned"],
                                   table["position_ned_m"], rtol=1e-12)
        np.testing.assert_allclose([m["velocity_rms_mps"][a] for a in "ned"],
                                   table["velocity_ned_mps"], rtol=1e-12)
        assert m["samples"] == len(replay.rows) == 60
        if cls is components.NewtonRobustKf:
            injected = sensors.gnss_outlier[replay.rows]
            det = m["outlier_detection"]
            assert det["injected_observations"] == 6 * injected.sum() > 0
            assert det["detected_observations"] == replay.outputs["n_rejected"][injected].sum()


def _spec(**kw):
    base = dict(scenario=SCENARIO, filters=("Kf", "Iakf"), runs=3, stop_time=4.0)
    base.update(kw)
    return CampaignSpec(**base)


@pytest.mark.parametrize("mode", ["pool", "dask"])
def test_serial_pool_and_dask_give_identical_runs(tmp_path, mode):
    spec = _spec()
    run_campaign(spec, tmp_path / "serial", workers=1, log=print)
    if mode == "dask":
        pytest.importorskip("dask.distributed")
        run_campaign(spec, tmp_path / mode, workers=2, local_cluster=True, log=print)
    else:
        run_campaign(spec, tmp_path / mode, workers=2, log=print)
    serial, other = _numbers(tmp_path / "serial", spec), _numbers(tmp_path / mode, spec)
    assert serial == other
    # different seeds give different numbers (the comparison can fail)
    assert serial["Kf"][0]["position_rms_m"] != serial["Kf"][1]["position_rms_m"]


def test_fmu_and_direct_backends_give_identical_runs(tmp_path):
    direct, fmu = _spec(runs=2, filters=("Iakf",)), _spec(runs=2, filters=("Iakf",),
                                                          backend="fmu")
    run_campaign(direct, tmp_path / "direct", log=print)
    run_campaign(fmu, tmp_path / "fmu", log=print)
    assert _numbers(tmp_path / "direct", direct) == _numbers(tmp_path / "fmu", fmu)


def test_seeds_follow_campaign_seed_and_run_index_and_series_on_request(tmp_path):
    spec = _spec(runs=2, filters=("Kf",), seed=7, seed_offsets=(("gnss", 100),),
                 series="parquet")
    run_campaign(spec, tmp_path, log=print)
    assert [read_run(tmp_path, "Kf", i)["seeds"] for i in range(2)] == [
        {"trajectory": 7, "gnss": 107}, {"trajectory": 8, "gnss": 108}]
    import pandas as pd

    frame = pd.read_parquet(tmp_path / "series" / "Kf" / "run-0001.parquet")
    assert len(frame) == 401 and "filter.nav_lat [rad]" in frame.columns
    # the metrics of the run are those of its kept series
    from orchestrator.results.metrics import filter_metrics
    from orchestrator.results.recorder import read_parquet

    again = filter_metrics(read_parquet(tmp_path / "series" / "Kf" / "run-0001.parquet"), "filter")
    assert again["position_rms_m"] == pytest.approx(
        read_run(tmp_path, "Kf", 1)["metrics"]["position_rms_m"], rel=1e-12)


def test_other_campaign_in_the_same_folder_is_refused(tmp_path):
    run_campaign(_spec(runs=1, filters=("Kf",)), tmp_path, log=print)
    with pytest.raises(NavfmuError, match=r"holds another campaign \(seed: 1 there, 2 here\)"):
        run_campaign(_spec(runs=1, filters=("Kf",), seed=2), tmp_path, log=print)
    more = run_campaign(_spec(runs=2, filters=("Kf",)), tmp_path, log=print)
    assert more["counts"] == {"done_before": 1, "ran": 1, "total": 2}


# ---------------------------------------------------------------------------------------
# kill and resume
# ---------------------------------------------------------------------------------------
COMMAND = [sys.executable, "-m", "orchestrator.cli", "montecarlo", SCENARIO, "--runs", "7",
           "--filters", "Kf,Iakf", "--stop", "20", "--batch", "1", "--workers", "2"]
TOTAL = 14


def _env():
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT / "fmus"), str(ROOT),
                                         env.get("PYTHONPATH", "")])
    return env


def _files(out):
    return {p: (p.stat().st_ino, p.stat().st_mtime_ns)
            for p in sorted((out / "runs").glob("*/run-*.json"))}


def _killed_at(out, point, workers):
    """The campaign with ``workers`` SIGKILLed by the test hook at safe point ``point`` (a
    crash at a chosen run: :data:`~orchestrator.cosim.interrupts.SIGNAL_AT_ENV`); returns the
    exit status and stderr once no process of it is left (its output goes to a file, which
    a worker outliving its driver cannot hold open)."""
    from orchestrator.cosim.interrupts import SIGNAL_AT_ENV

    marker = f"{out}:{point}"
    log = out.parent / f"{point}.stderr"
    with open(log, "w") as stderr:
        done = subprocess.run(COMMAND[:-1] + [str(workers), "--out", str(out)],
                              env={**_env(), SIGNAL_AT_ENV: f"{point}:KILL",
                                   "NAVFMU_TEST_CAMPAIGN": marker},
                              stdout=subprocess.DEVNULL, stderr=stderr, timeout=300)
    _, alive = psutil.wait_procs(_processes_marked(marker), timeout=30)
    for process in alive:
        process.kill()
    assert not alive, "a worker outlived its driver"   # it ends within 0.2 s of its driver
    return done.returncode, log.read_text()


def _processes_marked(marker):
    found = []
    for process in psutil.process_iter():
        try:
            if process.environ().get("NAVFMU_TEST_CAMPAIGN") == marker:
                found.append(process)
        except (psutil.Error, OSError):
            continue
    return found


def _check_resumed(before, after):
    assert all(after[p] == before[p] for p in before)      # no finished run done again
    for p in after:                                         # every file complete
        assert json.loads(p.read_text())["metrics"]["samples"] == 2001


def _run_names(files):
    return [f"{p.parent.name}/{p.name}" for p in files]


def test_killed_driver_then_killed_worker_then_restart_completes(tmp_path):
    """Crashes at chosen points, so every count is exact: the serial driver killed after its
    5th run (runs are in the order Kf 0, Iakf 0, Kf 1, ...); a pool worker killed as it
    starts the first missing run, Iakf 2 (the pool breaks, the other worker is stopped in
    its run: a run takes seconds); a pool's driver killed while it first waits for its
    workers (nothing can have finished); then the restart runs exactly the 9 missing."""
    out = tmp_path / "mc"
    code, _ = _killed_at(out, "campaign-ran-5", workers=1)
    assert code == -signal.SIGKILL
    first = _files(out)
    assert sorted(_run_names(first)) == sorted(
        [f"Kf/run-000{i}.json" for i in range(3)] + [f"Iakf/run-000{i}.json" for i in range(2)])
    code, stderr = _killed_at(out, "campaign-run-Iakf-2", workers=2)
    assert code == 2 and stderr.count("navfmu: error:") == 1 and "Traceback" not in stderr
    assert _files(out) == first
    code, _ = _killed_at(out, "pool-waiting", workers=2)
    assert code == -signal.SIGKILL
    assert _files(out) == first
    done = subprocess.run(COMMAND + ["--out", str(out)], env=_env(), capture_output=True,
                          text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    assert f"= {TOTAL} filter runs: 9 now, 5 done before" in done.stdout
    final = _files(out)
    assert len(final) == TOTAL
    _check_resumed(first, final)
    assert not list(out.rglob("*.tmp"))


@pytest.mark.parametrize("args, words", [
    (["--runs", "0", "--filters", "Kf"], ["--runs", "got 0"]),
    (["--runs", "2", "--filters", "Kf,Nope"], ["unknown filter 'Nope'", "Iakf"]),
    (["--runs", "2", "--filters", "Kf,Kf"], ["Kf listed more than once"]),
    (["--runs", "2", "--filters", "Kf", "--seed-offset", "gnss"], ["--seed-offset", "'gnss'"]),
    (["--runs", "2", "--filters", "Kf", "--seed-offset", "radar=3"], ["radar", "trajectory"]),
])
def test_bad_campaign_options_one_error_line(capsys, tmp_path, args, words):
    from orchestrator.cli.commands import main

    out = tmp_path / "mc"
    with pytest.raises(SystemExit) as exc:
        main(["montecarlo", SCENARIO, "--out", str(out), "--stop", "1"] + args)
    _, err = capsys.readouterr()
    assert exc.value.code == 2
    assert err.count("navfmu: error:") == 1 and "Traceback" not in err
    assert all(w in err for w in words), err
    assert not out.exists()


def test_a_resume_after_a_code_change_is_refused(tmp_path, monkeypatch):
    """The manifest's code hash: the same campaign with other numerical code is another
    campaign (its runs would not be comparable)."""
    from orchestrator.campaigns import campaign as campaign_module

    run_campaign(_spec(runs=1, filters=("Kf",)), tmp_path, log=print)
    monkeypatch.setattr(campaign_module, "code_hash", lambda: "0" * 64)
    with pytest.raises(NavfmuError, match=r"holds another campaign \(code_sha256: '[0-9a-f]{64}' "
                                          r"there, '0{64}' here\)"):
        run_campaign(_spec(runs=1, filters=("Kf",)), tmp_path, log=print)


def test_the_code_hash_covers_every_navcore_module():
    """Every module of navcore (in every wing) and every FMU script is in the hash."""
    from orchestrator.building.build import ROOT
    from orchestrator.campaigns.campaign import NUMERIC_CODE

    hashed = {p for pattern in NUMERIC_CODE for p in ROOT.glob(pattern)}
    navcore = set((ROOT / "fmus" / "navcore").rglob("*.py")) | set((ROOT / "fmus").glob("*.py"))
    assert navcore - hashed == set()
