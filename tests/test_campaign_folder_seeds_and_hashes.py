"""Campaign bookkeeping (orchestrator.campaigns.campaign) without running a simulation where
it can: the options refused, the seed rule of the module docstring with the FMI Integer
limits, the scenario and code hashes written out with hashlib, the commit mark, the run
files' names and reading, the manifest checks, stale temporaries, the folder left as found
when a campaign fails before its first run, and the provenance line of the seeds."""
from __future__ import annotations

import hashlib
import json
import subprocess
from pathlib import Path
from types import SimpleNamespace

import pytest

from orchestrator.building import build as fmu_build
from orchestrator.campaigns import campaign as cp
from orchestrator.campaigns import campaign_runs
from orchestrator.campaigns import seeds
from orchestrator.campaigns.campaign import Campaign, CampaignSpec
from orchestrator.errors import NavfmuError

ROOT = Path(__file__).resolve().parent.parent
SCENARIO = str(ROOT / "models" / "aircraft_500s")


def _spec(**kw):
    return CampaignSpec(**{"scenario": SCENARIO, "filters": ("Kf",), "runs": 2, **kw})


@pytest.mark.parametrize("options", [
    {"runs": 0}, {"runs": True}, {"runs": 2.0}, {"filters": ()}, {"filters": ("Kf", "Kf")},
    {"backend": "libcosim"}, {"series": "hdf5"}, {"samples": "some"}])
def test_bad_options_are_refused(options):
    with pytest.raises(NavfmuError):
        _spec(**options)


def test_good_options_are_accepted():
    for options in ({"runs": 1}, {"backend": "fmu"}, {"series": "csv"},
                    {"series": "parquet"}, {"samples": "fixes"}):
        _spec(**options)


# ----------------------------------------------------------------------------------------
# seeds
# ----------------------------------------------------------------------------------------
def test_seed_rule_of_the_docstring():
    """seed = s + i + offset, offset 1000 j for the j-th random component unless given."""
    spec = _spec(seed=7, seed_offsets=(("gnss", 5),))
    offsets = seeds.seed_offsets(spec, ["trajectory", "imu", "gnss"])
    assert offsets == {"trajectory": 0, "imu": 1000, "gnss": 5}
    assert seeds.run_seeds(spec, offsets, 3) == {"trajectory": 10, "imu": 1010, "gnss": 15}
    with pytest.raises(NavfmuError, match="no random component baro"):
        seeds.seed_offsets(_spec(seed_offsets=(("baro", 1),)), ["gnss"])


def test_seed_offset_syntax():
    assert seeds.parse_seed_offsets(["gnss=100", "trajectory=-3"]) == (
        ("gnss", 100), ("trajectory", -3))
    for bad in ["gnss", "gnss=", "gnss=1.5", "=4", "gnss=x", "gnss==1"]:
        with pytest.raises(NavfmuError, match="--seed-offset"):
            seeds.parse_seed_offsets([bad])


def test_seeds_must_fit_an_fmi_integer_from_the_first_run_to_the_last():
    """FMI 2.0 Integers are 32-bit: the last run may reach 2**31 - 1, not 2**31; the first
    may reach -2**31."""
    top = 2 ** 31 - 1
    seeds.check_seed_range(_spec(seed=top - 2), {"gnss": 1}, 2)      # last: top
    with pytest.raises(NavfmuError, match="run 1 would give gnss.seed = 2147483648"):
        seeds.check_seed_range(_spec(seed=top - 1), {"gnss": 1}, 2)
    seeds.check_seed_range(_spec(seed=-2 ** 31), {"gnss": 0}, 1)
    with pytest.raises(NavfmuError, match="run 0 would give gnss.seed = -2147483649"):
        seeds.check_seed_range(_spec(seed=-2 ** 31), {"gnss": -1}, 2)    # run 1 would fit
    with pytest.raises(NavfmuError, match="run 0 would give gnss.seed"):
        seeds.check_seed_range(_spec(seed=-2 ** 31), {"gnss": -1}, 1)


# ----------------------------------------------------------------------------------------
# hashes and commit
# ----------------------------------------------------------------------------------------
def test_scenario_hash_covers_the_ssd_ssv_and_paper_files_only(tmp_path):
    files = {"SystemStructure.ssd": b"<ssd/>", "a.ssv": b"<ssv/>", "paper.json": b"{}"}
    for name, data in files.items():
        (tmp_path / name).write_bytes(data)
    (tmp_path / "notes.txt").write_bytes(b"not part of the scenario")
    model = SimpleNamespace(path=tmp_path / "SystemStructure.ssd")
    expected = hashlib.sha256()
    for name in sorted(files):
        expected.update(name.encode() + b"\0" + files[name])
    assert cp.scenario_hash(model) == expected.hexdigest()
    (tmp_path / "notes.txt").write_bytes(b"changed")
    assert cp.scenario_hash(model) == expected.hexdigest()
    (tmp_path / "a.ssv").write_bytes(b"<ssv />")
    assert cp.scenario_hash(model) != expected.hexdigest()


def test_code_hash_is_over_the_numeric_code_in_pattern_order(tmp_path, monkeypatch):
    files = {"fmus/slave.py": b"a", "fmus/navcore/filters/kf.py": b"b",
             "orchestrator/cosim/exchange.py": b"c", "orchestrator/cli/main.py": b"d"}
    for name, data in files.items():
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_bytes(data)
    monkeypatch.setattr(fmu_build, "ROOT", tmp_path)
    expected = hashlib.sha256(b"fmus/slave.py\0a" + b"fmus/navcore/filters/kf.py\0b"
                              + b"orchestrator/cosim/exchange.py\0c").hexdigest()
    assert cp.code_hash() == expected                      # the CLI is not numeric code


def _git(folder, *args):
    subprocess.run(["git", "-C", str(folder), *args], check=True, capture_output=True)


def _commit(folder, names):
    """Write "1" into each of ``names`` and commit them; the commit's hash."""
    for name in names:
        (folder / name).parent.mkdir(parents=True, exist_ok=True)
        (folder / name).write_text("1\n")
    _git(folder, "add", ".")
    _git(folder, "-c", "user.name=t", "-c", "user.email=t@t", "commit", "-qm", "x")
    return subprocess.run(["git", "-C", str(folder), "rev-parse", "HEAD"],
                          capture_output=True, text=True).stdout.strip()


def test_commit_is_marked_dirty_by_tracked_changes_of_the_code_only(tmp_path, monkeypatch):
    monkeypatch.setattr(fmu_build, "ROOT", tmp_path)
    assert cp.code_commit() == "unknown"                   # not a git checkout
    _git(tmp_path, "init", "-q")
    head = _commit(tmp_path, ["fmus/a.py", "docs/b.md"])
    assert cp.code_commit() == head
    (tmp_path / "docs" / "b.md").write_text("2\n")
    (tmp_path / "fmus" / "new.py").write_text("untracked\n")
    assert cp.code_commit() == head
    code = ["fmus/a.py", "orchestrator/c.py", "models/m.ssd"]
    head = _commit(tmp_path, code)
    for name in code:
        assert cp.code_commit() == head
        (tmp_path / name).write_text("2\n")
        assert cp.code_commit() == head + "+dirty", name
        _git(tmp_path, "checkout", "-q", "--", name)


def test_a_checkout_without_a_commit_has_an_unknown_commit(tmp_path, monkeypatch):
    monkeypatch.setattr(fmu_build, "ROOT", tmp_path)
    _git(tmp_path, "init", "-q")
    assert cp.code_commit() == "unknown"


# ----------------------------------------------------------------------------------------
# run files
# ----------------------------------------------------------------------------------------
def test_run_files_are_named_by_filter_and_four_digit_index(tmp_path):
    assert campaign_runs.run_path(tmp_path, "Kf", 7) == tmp_path / "runs" / "Kf" / "run-0007.json"
    assert campaign_runs.series_path(tmp_path, "Kf", 12, "csv") == (
        tmp_path / "series" / "Kf" / "run-0012.csv")


def test_a_run_file_is_read_back_and_a_bad_one_counts_as_missing(tmp_path):
    record = {"filter": "Kf", "index": 3, "metrics": {"x": float("nan"), "y": 1.5}}
    path = campaign_runs.write_run(tmp_path, record)
    assert path == campaign_runs.run_path(tmp_path, "Kf", 3)
    assert campaign_runs.read_run(tmp_path, "Kf", 3) == {"filter": "Kf", "index": 3,
                                              "metrics": {"x": None, "y": 1.5}}
    assert campaign_runs.read_run(tmp_path, "Kf", 4) is None
    path.write_text("{not json")
    assert campaign_runs.read_run(tmp_path, "Kf", 3) is None
    path.write_text(json.dumps({"filter": "Kf", "index": 4}))    # another run's content
    assert campaign_runs.read_run(tmp_path, "Kf", 3) is None
    path.write_text(json.dumps({"filter": "Iakf", "index": 3}))
    assert campaign_runs.read_run(tmp_path, "Kf", 3) is None


def test_stale_temporaries_go_and_results_stay(tmp_path):
    runs = tmp_path / "runs" / "Kf"
    series = tmp_path / "series" / "Kf"
    for folder in (runs, series):
        folder.mkdir(parents=True)
    kept = [runs / "run-0000.json", series / "run-0000.csv", runs / "notes.tmp"]
    gone = [runs / ".run-0001.json.abc.tmp", series / ".run-0001.csv.x.tmp"]
    for p in kept + gone:
        p.write_text("x")
    cp._remove_stale_temporaries(tmp_path)
    assert all(p.exists() for p in kept) and not any(p.exists() for p in gone)


# ----------------------------------------------------------------------------------------
# the manifest and the folder
# ----------------------------------------------------------------------------------------
def test_the_manifest_is_checked_against_the_folder(tmp_path):
    out = tmp_path / "c"
    first = Campaign(_spec(runs=3), out, log=lambda m: None)
    first.prepare()
    manifest = json.loads((out / cp.MANIFEST).read_text())
    assert manifest["format"] == cp.FORMAT and manifest["runs"] == 3
    assert manifest["identity"]["seed_offsets"] == {"trajectory": 0, "gnss": 1000}
    # fewer runs asked: the campaign keeps its three; more: they are added
    fewer = Campaign(_spec(runs=1), out, log=lambda m: None)
    fewer.check()
    assert fewer.runs == 3
    more = Campaign(_spec(runs=5), out, log=lambda m: None)
    more.check()
    assert more.runs == 5
    assert more.missing() == [("Kf", i) for i in range(5)]
    campaign_runs.write_run(out, {"filter": "Kf", "index": 1})
    assert ("Kf", 1) not in more.missing() and len(more.missing()) == 4
    with pytest.raises(NavfmuError, match=r"runs \[0, 2, 3, 4\] of Kf are missing"):
        more.records()
    # another format is another campaign; the folder's own path is not part of the identity
    manifest["identity"]["ssd"] = "/moved/SystemStructure.ssd"
    (out / cp.MANIFEST).write_text(json.dumps(manifest))
    Campaign(_spec(runs=3), out, log=lambda m: None).check()
    manifest["format"] = "navfmu-campaign-0"
    (out / cp.MANIFEST).write_text(json.dumps(manifest))
    with pytest.raises(NavfmuError, match="holds another campaign"):
        Campaign(_spec(runs=3), out, log=lambda m: None).check()


def test_a_folder_of_other_files_or_a_file_is_refused(tmp_path):
    (tmp_path / "other.txt").write_text("x")
    with pytest.raises(NavfmuError, match="holds files but no campaign.json"):
        Campaign(_spec(), tmp_path, log=lambda m: None).check()
    with pytest.raises(NavfmuError, match="not a folder"):
        Campaign(_spec(), tmp_path / "other.txt", log=lambda m: None).check()
    Campaign(_spec(), tmp_path / "empty", log=lambda m: None).check()   # a new folder is fine


def _failing_campaign(out):
    campaign = Campaign(_spec(), out, log=lambda m: None)
    campaign.check()
    with pytest.raises(RuntimeError):
        with cp._undone_if_nothing_ran(campaign):
            campaign.write_manifest()
            (out / "runs" / "Kf").mkdir(parents=True)
            (out / "series").mkdir()
            raise RuntimeError("stopped")
    return campaign


def test_a_campaign_failing_before_its_first_run_leaves_the_folder_as_found(tmp_path):
    _failing_campaign(tmp_path / "new" / "deeper")
    assert not (tmp_path / "new").exists()                   # the folders it made go
    existing = tmp_path / "existing"
    existing.mkdir()
    _failing_campaign(existing)
    assert existing.is_dir() and list(existing.iterdir()) == []


def test_a_failing_resume_or_a_campaign_with_a_run_keeps_its_files(tmp_path):
    out = tmp_path / "c"
    campaign = Campaign(_spec(), out, log=lambda m: None)
    campaign.check()
    with pytest.raises(RuntimeError):
        with cp._undone_if_nothing_ran(campaign):
            campaign.write_manifest()
            campaign_runs.write_run(out, {"filter": "Kf", "index": 0})
            raise RuntimeError("stopped")
    assert (out / cp.MANIFEST).is_file() and campaign_runs.read_run(out, "Kf", 0) is not None
    campaign_runs.run_path(out, "Kf", 0).unlink()
    with pytest.raises(RuntimeError):
        with cp._undone_if_nothing_ran(campaign):   # the manifest was there before
            raise RuntimeError("stopped")
    assert (out / cp.MANIFEST).is_file()


def test_provenance_names_the_seed_ranges_and_the_commits(tmp_path):
    campaign = Campaign(_spec(runs=3, seed=5), tmp_path / "c", log=lambda m: None)
    campaign.check()
    records = {"Kf": [{"commit": "b"}, {"commit": "a"}, {"commit": "b"}]}
    prov = cp.provenance(campaign, records)
    assert prov["seeds"] == "trajectory.seed 5..7, gnss.seed 1005..1007"
    assert prov["commit"] == "a, b" and prov["runs"] == 3
    assert prov["code_sha256"] == cp.code_hash()
    campaign.offsets = {}
    assert cp.provenance(campaign, records)["seeds"] == "no random component"


# ----------------------------------------------------------------------------------------
# the identity, the checks before any run, one run's record
# ----------------------------------------------------------------------------------------
OVERRIDE = (("filter.r_pos_n", 2.5),)


def test_the_identity_holds_every_option_that_decides_the_numbers(tmp_path):
    spec = _spec(window=(1.0, 3.0), parameters=OVERRIDE, series="csv", stop_time=4.0,
                 samples="fixes", seed=3)
    campaign = Campaign(spec, tmp_path / "c", log=lambda m: None)
    campaign.check()
    ssd = Path(SCENARIO) / "SystemStructure.ssd"
    assert campaign.identity == {
        "scenario": "aircraft_500s", "ssd": str(ssd.resolve()),
        "scenario_sha256": cp.scenario_hash(campaign.model), "filters": ["Kf"], "seed": 3,
        "seed_offsets": {"trajectory": 0, "gnss": 1000}, "backend": "direct",
        "stop_time": 4.0, "window": [1.0, 3.0], "samples": "fixes",
        "parameters": [["filter.r_pos_n", 2.5]], "series": "csv",
        "code_sha256": cp.code_hash()}
    job = campaign.job("Kf", 1)
    assert job == {"ssd": str(ssd.resolve()), "filter": "Kf", "index": 1,
                   "seeds": {"trajectory": 4, "gnss": 1004}, "parameters": list(OVERRIDE),
                   "backend": "direct", "stop_time": 4.0, "window": (1.0, 3.0),
                   "samples": "fixes", "series": "csv",
                   "out": str((tmp_path / "c").resolve()), "commit": campaign.commit,
                   "isolation": {"mode": "foreign", "call_timeout": 120.0}}


def test_overrides_and_the_stop_time_are_checked_before_any_run(tmp_path):
    with pytest.raises(NavfmuError, match="nope"):
        Campaign(_spec(parameters=(("nope.x", 1.0),)), tmp_path, log=print).check()
    with pytest.raises(NavfmuError, match="nope"):
        seeds.random_components(cp_model(), "direct", {"nope.x": 1.0})
    with pytest.raises(NavfmuError, match="--stop"):
        Campaign(_spec(stop_time=0.0), tmp_path, log=print).check()


def cp_model():
    from orchestrator.running.scenarios import load_scenario
    return load_scenario(SCENARIO)


def test_the_fmu_backend_builds_each_filter_s_model_once_before_the_runs(tmp_path,
                                                                         monkeypatch):
    from orchestrator.running import scenarios

    built = []
    monkeypatch.setattr(scenarios, "ensure_fmus", lambda m, log: built.append((m, log)))
    monkeypatch.setattr(cp, "random_components", lambda model, backend, parameters: ["gnss"])
    say = []
    campaign = Campaign(_spec(backend="fmu", filters=("Kf", "Iakf")), tmp_path, log=say.append)
    campaign.check()
    assert [m.component("filter").source.stem for m, _ in built] == ["Kf", "Iakf"]
    assert all(log == say.append for _, log in built)


def test_a_manifest_without_identity_or_run_count(tmp_path):
    out = tmp_path / "c"
    Campaign(_spec(runs=2), out, log=print).prepare()
    manifest = json.loads((out / cp.MANIFEST).read_text())
    del manifest["runs"]
    (out / cp.MANIFEST).write_text(json.dumps(manifest))
    resumed = Campaign(_spec(runs=2), out, log=print)
    resumed.check()
    assert resumed.runs == 2
    manifest["identity"]["seed"] = 9
    manifest["identity"]["samples"] = "fixes"
    (out / cp.MANIFEST).write_text(json.dumps(manifest))
    with pytest.raises(NavfmuError, match=r"seed: 9 there, 1 here; samples: 'fixes' there"):
        Campaign(_spec(runs=2), out, log=print).check()
    (out / cp.MANIFEST).write_text(json.dumps({"format": "navfmu-campaign-0"}))
    with pytest.raises(NavfmuError, match="holds another campaign"):
        Campaign(_spec(runs=2), out, log=print).check()
    same = Campaign(_spec(runs=2), tmp_path / "d", log=print)
    same.prepare()
    manifest = json.loads((tmp_path / "d" / cp.MANIFEST).read_text())
    manifest["format"] = "navfmu-campaign-0"
    (tmp_path / "d" / cp.MANIFEST).write_text(json.dumps(manifest))
    with pytest.raises(NavfmuError, match=r"\(format 'navfmu-campaign-0'\)"):
        Campaign(_spec(runs=2), tmp_path / "d", log=print).check()


def _job(out, **kw):
    return {"ssd": str(Path(SCENARIO) / "SystemStructure.ssd"), "filter": "Kf", "index": 0,
            "seeds": {"trajectory": 1, "gnss": 1001}, "parameters": [], "backend": "direct",
            "stop_time": 4.0, "window": None, "samples": "all", "series": None,
            "out": str(out), **kw}


def test_one_run_s_record_and_its_window_and_series(tmp_path, monkeypatch):
    """The record names its run; its metrics over a window are those of its kept series
    over that window (the streaming sink against the metrics of the whole series)."""
    import time as clock

    points = []
    monkeypatch.setattr(cp.interrupts, "safe_point", points.append)

    from orchestrator.results.metrics import filter_metrics
    from orchestrator.results.recorder import read_parquet

    (tmp_path / "runs").mkdir()
    t0 = clock.perf_counter()
    record = campaign_runs.run_one(_job(tmp_path, window=(2.0, 4.0), series="parquet",
                                        commit="abc"))
    elapsed = clock.perf_counter() - t0
    assert set(record) == {"filter", "index", "seeds", "metrics", "stop_time", "wall_time_s",
                           "pid", "commit"}
    assert (record["stop_time"], record["commit"]) == (4.0, "abc")
    assert record["pid"] == __import__("os").getpid() and 0 < record["wall_time_s"] <= elapsed
    assert campaign_runs.read_run(tmp_path, "Kf", 0)["seeds"] == {"trajectory": 1, "gnss": 1001}
    series = campaign_runs.series_path(tmp_path, "Kf", 0, "parquet")
    whole = filter_metrics(read_parquet(series), "filter", window=(2.0, 4.0))
    assert record["metrics"]["position_rms_m"] == pytest.approx(whole["position_rms_m"],
                                                                rel=1e-12)
    unwindowed = campaign_runs.run_one(_job(tmp_path / "elsewhere", index=1))
    assert unwindowed["commit"] == ""
    assert points == ["campaign-run-Kf-0", "campaign-run-Kf-1"]
    assert unwindowed["metrics"]["position_rms_m"] != record["metrics"]["position_rms_m"]


def test_no_series_is_written_unless_asked_and_csv_when_asked(tmp_path):
    import pandas as pd

    campaign_runs.run_one(_job(tmp_path, index=3))
    assert campaign_runs.read_run(tmp_path, "Kf", 3) is not None
    assert not (tmp_path / "series").exists()
    campaign_runs.run_one(_job(tmp_path, index=4, series="csv", stop_time=1.0))
    frame = pd.read_csv(campaign_runs.series_path(tmp_path, "Kf", 4, "csv"))
    assert len(frame) == 101 and "filter.nav_lat [rad]" in frame.columns


# ----------------------------------------------------------------------------------------
# the driver with a stand-in executor
# ----------------------------------------------------------------------------------------
class StandInExecutor:
    """Yields a record per task without running it, and keeps what it was given."""

    mode = "stand-in"
    made = []

    def __init__(self, **options):
        self.options = options
        self.progress = []
        StandInExecutor.made.append(self)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False

    def connect(self):
        pass

    def run(self, tasks, progress=None):
        self.progress.append(progress)
        for task in tasks:
            jobs = task.args[0]            # a batch's jobs, or one run's
            records = [{"filter": job["filter"], "index": job["index"],
                        "commit": job["commit"], "metrics": {}}
                       for job in (jobs if isinstance(jobs, list) else [jobs])]
            yield task.key, records if isinstance(jobs, list) else records[0]


def test_the_driver_writes_the_records_it_gets_and_counts_them(tmp_path, monkeypatch):
    """Records that come back without a file (a worker that cannot see the folder) are
    written by the driver; the test hook's safe points are passed in order."""
    points = []
    monkeypatch.setattr(cp.interrupts, "safe_point", points.append)
    campaign = Campaign(_spec(runs=2, filters=("Kf", "Iakf")), tmp_path, log=print)
    campaign.prepare()
    campaign_runs.write_run(tmp_path, {"filter": "Iakf", "index": 1, "commit": "old"})
    ex = StandInExecutor()
    steps = []
    counts = campaign.run(ex, progress=lambda done, total: steps.append((done, total)))
    assert counts == {"done_before": 1, "ran": 3, "total": 4}
    assert steps[0] == (0, 3) and steps[-1] == (3, 3)     # in runs, not tasks
    assert [d for d, _ in steps] == sorted(d for d, _ in steps)
    assert points == ["campaign-started", "campaign-ran-1", "campaign-ran-2", "campaign-ran-3"]
    assert campaign_runs.read_run(tmp_path, "Iakf", 1)["commit"] == "old"       # not run again
    assert [campaign_runs.read_run(tmp_path, f, i)["commit"] for f, i in
            [("Kf", 0), ("Iakf", 0), ("Kf", 1)]] == [campaign.commit] * 3


def test_a_campaign_s_executor_options_and_summary_file(tmp_path, monkeypatch):
    monkeypatch.setattr(cp, "Executor", StandInExecutor)
    StandInExecutor.made.clear()
    steps = []
    summary = cp.run_campaign(_spec(runs=1), tmp_path / "a",
                              progress=lambda done, total: steps.append((done, total)),
                              log=lambda m: None)
    cp.run_campaign(_spec(runs=1), tmp_path / "b", workers=3, scheduler="tcp://x:1",
                    local_cluster=True, log=lambda m: None)
    assert [e.options for e in StandInExecutor.made] == [
        {"workers": 1, "scheduler": None, "local_cluster": False},
        {"workers": 3, "scheduler": "tcp://x:1", "local_cluster": True}]
    assert steps == [(0, 1), (1, 1)]                # the campaign's progress, in runs
    written = json.loads((tmp_path / "a" / "summary.json").read_text())
    assert summary["counts"] == {"done_before": 0, "ran": 1, "total": 1}
    assert written == json.loads(json.dumps({k: v for k, v in summary.items()
                                             if k != "counts"}))
    assert written["provenance"]["mode"] == "stand-in"


def test_a_campaign_s_log_reaches_the_fmu_build(tmp_path, monkeypatch):
    from orchestrator.running import scenarios

    logs = []
    monkeypatch.setattr(cp, "Executor", StandInExecutor)
    monkeypatch.setattr(scenarios, "ensure_fmus", lambda m, log: logs.append(log))
    monkeypatch.setattr(cp, "random_components", lambda model, backend, parameters: ["gnss"])
    say = []
    cp.run_campaign(_spec(runs=1, backend="fmu"), tmp_path, log=say.append)
    assert logs == [say.append]
