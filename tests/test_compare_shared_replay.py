"""``navfmu compare --replay``: the filters stepped by one replay, each with the numbers, files
and warnings of its own ``navfmu run --replay``."""
from __future__ import annotations

import json

import pytest

from orchestrator.building import build as fmu_build

MODELS = fmu_build.ROOT / "models"
SCENARIO = MODELS / "replay_gnss_ins_sim"
LOG = SCENARIO / "log"
#: a scenario whose filter (CtfaUkf) is set a parameter the others lack (q_max_scale)
MEMS = MODELS / "uav_maneuver_mems"
FILTERS = ("CtfaUkf", "Kf", "InsOnly")
#: what differs between a shared run's metadata and its single run's: the clocks
TIMING = ("wall_time_s", "master_overhead_s_per_step")


def _lines(text, start):
    return sorted({ln for ln in text.splitlines() if ln.startswith(start)})


def _without_timing(metrics):
    return {f: {k: v for k, v in m.items() if k != "time_per_step_ms"}
            for f, m in metrics.items()}


def test_each_filter_of_a_replayed_comparison_has_its_single_run(tmp_path, navfmu_cli):
    common = ["--replay", LOG, "--stop", "15", "--backend", "direct", "--no-plots",
              "--set", "filter.r_pos_n=2.5", "--set", "replay.max_dt_jitter=1e-6"]
    code, out, err = navfmu_cli("compare", MEMS, "--filters", ",".join(FILTERS),
                                "--out", tmp_path / "cmp", *common)
    assert code == 0, err
    compared = json.loads((tmp_path / "cmp" / "metrics.json").read_text())
    warned = set()
    for f in FILTERS:
        code, single_out, single_err = navfmu_cli("run", MEMS, "--filter", f, "--out",
                                                  tmp_path / f, *common)
        assert code == 0, single_err
        warned.update(_lines(single_err, "navfmu: warning:"))
        single = json.loads((tmp_path / f / "metrics.json").read_text())[f]
        shared = compared[f]
        # the rows, bit for bit (the CSV's shortest round-trip text of every float)
        assert ((tmp_path / "cmp" / f"results_{f}.csv").read_bytes()
                == (tmp_path / f / "results.csv").read_bytes()), f
        assert _without_timing(shared["metrics"]) == _without_timing(single["metrics"]), f
        assert shared["metadata"].pop("shared_replay_filters") == len(FILTERS)
        for key in TIMING:
            shared["metadata"].pop(key)
            single["metadata"].pop(key)
        assert shared["metadata"] == single["metadata"], f
        assert shared["step_time_s"].keys() == single["step_time_s"].keys()
        row = _lines(single_out, f + " ")
        assert row and set(row) <= set(_lines(out, f + " ")), f
    # the warnings of the single runs, each once (Kf and InsOnly skip q_max_scale)
    assert any("skipped" in w for w in warned)
    assert _lines(err, "navfmu: warning:") == sorted(warned)


def test_a_filter_refused_in_a_replayed_comparison_fails_as_its_single_run(tmp_path,
                                                                           navfmu_cli):
    """The first filter refused mid-run (a receiver sigma of 0 at its first fix): the
    comparison's error is that of the filter's own run."""
    common = ["--replay", LOG, "--stop", "12", "--backend", "direct", "--no-plots",
              "--set", "filter.r_from_receiver=true", "--set", "filter.gnss_std_n=0"]
    code, _, err = navfmu_cli("compare", SCENARIO, "--filters", "Kf,Ukf", "--out",
                              tmp_path / "cmp", *common)
    single_code, _, single_err = navfmu_cli("run", SCENARIO, "--filter", "Kf", "--out",
                                            tmp_path / "kf", *common)
    assert code == single_code == 2
    assert "gnss_std_n" in single_err and "(step from t = " in single_err
    assert err.splitlines()[0] == single_err.splitlines()[0]
    assert not (tmp_path / "cmp").exists()
