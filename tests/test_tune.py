"""``navfmu tune``: reproducible with the seed and the same with 1 or 2 workers, a parameter
set the model binds with one line, clear errors.  (How much faster 2 workers are is measured,
not asserted: see docs/ahrs.md.)"""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from docs_tables import documented_parameters, parse_range
from orchestrator.campaigns import tune as tuner
from orchestrator.errors import NavfmuError
from orchestrator.model.ssp import load_ssd
from orchestrator.running.ssv_bindings import read_bindings

MODEL = Path(__file__).resolve().parent.parent / "models" / "ahrs_turntable"
PARAMS = ["fuzzy_e_z_right", "fuzzy_de_z_right"]


def _tune(workers, seed=3, batch=None):
    return tuner.run_tune(MODEL, "filter", PARAMS, generations=2, population=3,
                          workers=workers, seed=seed, stop_time=6.0, backend="direct",
                          log=lambda m: None, batch=batch)


@pytest.fixture(scope="module")
def serial():
    return _tune(1)


def test_same_seed_same_parameters_with_one_or_two_workers(serial):
    pooled = _tune(2)
    assert pooled["best_values"] == serial["best_values"]
    assert pooled["best_so_far"] == serial["best_so_far"]
    assert all(b <= a for a, b in zip(serial["best_so_far"], serial["best_so_far"][1:]))
    for name, (lo, hi) in serial["ranges"].items():
        assert lo <= serial["best_values"][name] <= hi


def test_candidates_evaluated_in_batches_cost_what_they_cost_one_by_one(serial):
    """The serial tune batches its 3 candidates (the default on the direct backend); one
    candidate per task gives the same costs, bit for bit."""
    one_by_one = _tune(1, batch=1)
    for key in ("best_values", "best_so_far", "generation_best", "generation_mean"):
        assert one_by_one[key] == serial[key]
    with pytest.raises(NavfmuError, match="--batch"):
        tuner.run_tune(MODEL, "filter", PARAMS, backend="fmu", batch=2, log=lambda m: None)


def test_self_consistency_ranges_come_from_the_declared_parameter_spec(serial):
    """Self-consistency (the tuner reads the table it is compared with; the documented
    ranges below are the independent check)."""
    from navcore.filters.fuzzy import FEET

    assert serial["ranges"]["fuzzy_e_z_right"] == list(FEET["fuzzy_e_z_right"][1:3])


def test_search_ranges_are_the_documented_ones(serial):
    """Every membership foot and output vertex of FuzzyUkfAhrs is searched over the range
    docs/signals.md states for it (read from the document; its table says the feet's
    accepted ranges are the GA's search ranges), and the run reports those ranges."""
    documented = {n: parse_range(row.range) for n, row in
                  documented_parameters()["FuzzyUkfAhrs"].items() if n.startswith("fuzzy_")
                  and n != "fuzzy_window"}
    assert len(documented) == 12
    assert all(r.low_closed and r.high_closed for r in documented.values())
    names = sorted(documented)
    lo, hi, _, _ = tuner.resolve_parameters(tuner.load_scenario(MODEL), "filter", names, {},
                                            "direct")
    assert dict(zip(names, zip(lo.tolist(), hi.tolist()))) == {
        n: (r.low, r.high) for n, r in documented.items()}
    assert serial["ranges"] == {n: [documented[n].low, documented[n].high] for n in PARAMS}


def test_tuned_set_is_written_into_out_only_and_bound_with_ssv(serial, tmp_path):
    before = {p.name: p.read_bytes() for p in MODEL.iterdir() if p.is_file()}
    out = tmp_path / "out"
    written = tuner.write_tune_outputs(serial, out)
    assert [p.name for p in written] == ["filter_tuned.ssv", "tune.json", "fitness.png"]
    assert sorted(p.name for p in out.iterdir()) == sorted(p.name for p in written)
    assert {p.name: p.read_bytes() for p in MODEL.iterdir() if p.is_file()} == before
    # the printed way to apply it: --ssv filter=OUT/filter_tuned.ssv
    bound = read_bindings([f"filter={written[0]}"], load_ssd(MODEL / "SystemStructure.ssd"))
    for name, value in serial["best_values"].items():
        assert bound[f"filter.{name}"][1] == pytest.approx(value, rel=1e-15)
    # the one file holds the component's other parameters too (libcosim: one binding)
    assert bound["filter.r_accel_mps2"] == ("Real", 0.0208)


def test_bad_requests_are_user_errors():
    with pytest.raises(NavfmuError, match="no numeric parameter 'fuzzy_nope'"):
        tuner.run_tune(MODEL, "filter", ["fuzzy_nope"], backend="direct")
    with pytest.raises(NavfmuError, match="declares no range"):
        tuner.run_tune(MODEL, "filter", ["init_roll"], backend="direct")
    with pytest.raises(NavfmuError, match="--range"):
        tuner.parse_ranges(["r_accel_mps2=1:0"])
    with pytest.raises(NavfmuError, match="--component"):
        tuner.run_tune(MODEL, "filtre", PARAMS, backend="direct")


def test_cli_error_is_one_line():
    proc = subprocess.run([sys.executable, "-m", "orchestrator.cli", "tune", str(MODEL),
                           "--params", "fuzzy_nope"], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 2
    assert proc.stderr.strip().splitlines()[-1].startswith("navfmu: error:")
    assert "fuzzy_nope" in proc.stderr and "Traceback" not in proc.stderr


def test_the_tuned_values_are_never_worse_than_the_current_ones(monkeypatch):
    """The first population holds the model's current values: with a cost that is lowest
    exactly there (1, and 2 everywhere else: no other candidate can find it), the tune returns
    the current values and their cost."""
    import numpy as np

    model = tuner.load_scenario(MODEL)
    _, _, _, current = tuner.resolve_parameters(model, "filter", PARAMS, {}, "direct")

    def spike(spec, values):
        at = np.array([values[n] for n in PARAMS])
        return 1.0 if np.allclose(at, current, rtol=1e-12, atol=0.0) else 2.0

    monkeypatch.setattr(tuner, "evaluate", spike)
    res = tuner.run_tune(MODEL, "filter", PARAMS, generations=3, population=4, workers=1,
                         seed=3, stop_time=6.0, backend="direct", log=lambda m: None,
                         batch=1)          # one candidate per task: through evaluate
    assert res["best_cost"] == 1.0
    np.testing.assert_allclose([res["best_values"][n] for n in PARAMS], current, rtol=1e-12)


def test_tune_on_a_recorded_log_batches_the_replay(monkeypatch):
    """``--replay``: every candidate's runs replay the log (the tuned filter sees the log's
    sensors, not the scenario's), one replay component steps for a whole batch, and the
    costs are those of the candidates run one by one."""
    from navcore.components.replay_batch import ImuGnssReplayBatch

    log = MODEL.parent / "replay_gnss_ins_sim" / "log"
    batches = []
    started = ImuGnssReplayBatch._started
    monkeypatch.setattr(ImuGnssReplayBatch, "_started",
                        lambda self, t: batches.append(self.runs) or started(self, t))

    def tune(batch):
        return tuner.run_tune(MODEL.parent / "aircraft_500s", "filter", ["r_pos_n"],
                              generations=1, population=3, workers=1, seed=3, stop_time=15.0,
                              backend="direct", log=lambda m: None, batch=batch, replay=log)
    batched = tune(None)
    assert batches == [3]                        # one replay for the 3 candidates' runs
    one_by_one = tune(1)
    assert batches == [3]                        # single runs, no batch
    for key in ("best_values", "best_so_far", "generation_best", "generation_mean"):
        assert one_by_one[key] == batched[key]
    assert batched["replay"] == str(log.resolve())
    plain = tuner.run_tune(MODEL.parent / "aircraft_500s", "filter", ["r_pos_n"],
                           generations=1, population=3, workers=1, seed=3, stop_time=15.0,
                           backend="direct", log=lambda m: None)
    assert plain["generation_best"][0] != batched["generation_best"][0]
