"""Kf on paper 001's scenario: the same numbers through every path, reproducible, bounded."""
from __future__ import annotations

import numpy as np
import pytest

from orchestrator.building import build as fmu_build
from orchestrator.running import scenarios
from orchestrator.results.metric_comparisons import rms_table

MODEL = fmu_build.ROOT / "models" / "aircraft_500s"


@pytest.fixture(scope="module")
def runs():
    fmu_build.build(log=None)
    model = scenarios.load_scenario(MODEL)
    fmu = scenarios.simulate_scenario(model, backend="fmu", log=None)
    direct = scenarios.simulate_scenario(model, backend="direct", log=None)
    direct_again = scenarios.simulate_scenario(model, backend="direct", log=None)
    return fmu, direct, direct_again


def _same(a, b):
    assert a.components == b.components
    for c in a.components:
        assert a.columns[c] == b.columns[c]
        assert np.array_equal(a.data[c], b.data[c]), c


def test_fmu_and_direct_paths_give_identical_numbers(runs):
    fmu, direct, _ = runs
    _same(fmu.results, direct.results)


def test_fixed_seed_is_reproducible_bit_for_bit(runs):
    _, direct, again = runs
    _same(direct.results, again.results)


def test_kf_is_bounded_and_reported_next_to_the_paper(runs, capsys):
    fmu = runs[0]
    m = fmu.metrics["filter"]
    assert m["window_s"] == [0.0, 500.0]
    for group in ("position_rms_m", "velocity_rms_mps", "attitude_rms_deg"):
        for v in m[group].values():
            assert np.isfinite(v)
    assert max(m["position_rms_m"].values()) < 50.0
    assert max(m["velocity_rms_mps"].values()) < 5.0
    for c in fmu.results.components:
        assert np.isfinite(fmu.results.data[c]).all(), c
    # the GNSS fed the filter once per second: 500 updates, one per epoch
    upd = fmu.results.column("filter", "updated") > 0.5
    assert upd.sum() == 500
    table = rms_table([("Kf (ours)", m)], [("paper: standard KF", [8.6003, 9.4141, 3.2837],
                                            [0.5652, 0.9521, 0.3004])])
    print(table)
    assert "paper: standard KF" in table and "Kf (ours)" in table


def test_times_of_validity_align(runs):
    r = runs[0].results
    assert np.array_equal(r.column("filter", "nav_time"), r.column("trajectory", "truth_time"))
    assert np.allclose(r.column("trajectory", "imu_time")[1:], r.time[1:], rtol=0, atol=1e-9)
    upd = r.column("filter", "updated") > 0.5
    # a fix is used in the step it was taken: gnss_time equals the filter's time there
    assert np.allclose(r.column("gnss", "gnss_time")[upd], r.column("filter", "nav_time")[upd],
                       atol=1e-9)
