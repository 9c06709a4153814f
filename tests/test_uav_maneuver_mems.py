"""Paper 000's mechanism on ``uav_maneuver_mems``: the manoeuvre phases in Ukf's NIS, CtfaUkf's
Q and ImmUkf's model probabilities (issue 16; numbers and reasoning in docs/uav_maneuver.md).

The scenario is ``uav_maneuver`` with a manoeuvre-dependent MEMS IMU and its own filter
settings (its SystemStructure.ssd says what differs).  The default tests share one 1200 s
stretch that keeps one strong (0-600 s) and one low (600-1200 s) phase; they assert what holds
with this model.  The 10-seed 60 min run against the issue's thresholds is slow and marked
``xfail(strict=True)`` where the measurements say it fails, so that a fix flips it.
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from navcore.components import registry as components
from orchestrator.model import ssp
from direct_replay import MODELS, rms, run_filter, simulate_sensors
from test_ukf_filters import EXTRA, FILTERS, NAMES, SHORT_STOP, rms_row

SCENARIO = MODELS / "uav_maneuver_mems"
#: the phases of the short stretch (models/uav_maneuver_mems/paper.json, clipped to 1200 s)
STRONG, LOW = (0.0, 600.0), (600.0, 1200.0)
#: the 60 min flight's phases (paper.json)
STRONG_60, LOW_60 = ((0.0, 600.0), (1200.0, 3000.0)), ((600.0, 1200.0), (3000.0, 3600.0))
#: our return of Q towards Qmin while the chi-square test passes (CtfaUkf ctfa_pass_decay)
PASS_DECAY = 0.5
#: the phase variable of each filter: Ukf's NIS, CtfaUkf's Q scale, ImmUkf's high-Q model
PHASE_VARIABLE = {"Ukf": "nis", "CtfaUkf": "q_scale", "ImmUkf": "model_prob_2"}


def scenario_filter_parameters(model: str) -> dict:
    """The scenario's filter parameters for ``model`` as the master sets them after a swap
    (filter.ssv, then the swap variant filter.MODEL.ssv), restricted to the model's own."""
    spec = ssp.load_ssd(SCENARIO).replace_source("filter", Path(f"{model}.fmu")).component(
        "filter")
    own = {p.name for p in components.REGISTRY[model].parameters}
    return {k: v for k, (_, v) in spec.parameters.items() if k in own}


def run_model(sensors, model, **overrides):
    return run_filter(sensors, components.REGISTRY[model],
                      overrides={**scenario_filter_parameters(model), **overrides},
                      names=NAMES + EXTRA.get(model, []))


@pytest.fixture(scope="module")
def short_runs():
    sensors = simulate_sensors(SCENARIO, stop_time=SHORT_STOP)
    runs = {m: run_model(sensors, m) for m in FILTERS}
    runs["CtfaUkf decay"] = run_model(sensors, "CtfaUkf", ctfa_pass_decay=PASS_DECAY)
    return runs


def mean_in(run, name, windows):
    t = run.sensors.time[run.rows]
    sel = np.zeros(t.shape, dtype=bool)
    for t0, t1 in windows:
        sel |= (t >= t0) & (t < t1)
    return float(run.outputs[name][sel].mean())


def test_scenario_settings_per_filter():
    """filter.ssv carries CtfaUkf's Qmax, the swap variant filter.ImmUkf.ssv the bank's."""
    assert scenario_filter_parameters("CtfaUkf")["q_max_scale"] == 300.0
    imm = scenario_filter_parameters("ImmUkf")
    assert (imm["imm_q_scale_2"], imm["imm_p_stay"]) == (300.0, 0.999)
    assert "q_max_scale" not in scenario_filter_parameters("Ukf")


def test_baseline_covers_its_error_in_calm_flight_only(short_runs):
    """Qmin is right in calm flight and too small in the manoeuvres (the paper's premise): the
    1-sigma position covers the error in the low phase and understates it in the strong one."""
    run = short_runs["Ukf"]
    err = run.position_error_ned()
    std = np.column_stack([run.outputs[f"std_p{a}"] for a in "ned"])
    t = run.sensors.time[run.rows]
    ratios = {}
    for name, (t0, t1) in (("strong", STRONG), ("low", LOW)):
        sel = (t >= t0 + 60.0) & (t < t1)
        ratios[name] = rms(err[sel]) / rms(std[sel])
    print("Ukf position RMS error / RMS 1-sigma per phase:", ratios)
    assert (ratios["low"] < 2.0).all(), ratios
    assert (ratios["strong"] > 1.5 * ratios["low"]).all(), ratios


def test_adaptive_filters_beat_ukf_in_position_and_velocity(short_runs):
    """Strong + calm block: CtfaUkf (eq. 25 and our decay) and ImmUkf beat the fixed-Q UKF in
    position and velocity; in heading only the bank and the decay variant do, not eq. 25 as
    printed, whose Q stays high in calm flight (docs/uav_maneuver.md lists every axis)."""
    table = {m: rms_row(short_runs[m]) for m in short_runs}
    for m in ("CtfaUkf", "ImmUkf", "CtfaUkf decay"):
        ratio = table[m] / table["Ukf"]
        assert (ratio[:6] < 0.8).all(), (m, ratio)           # position and velocity, each axis
    for m in ("ImmUkf", "CtfaUkf decay"):
        assert table[m][8] < 0.8 * table["Ukf"][8], (m, table[m] / table["Ukf"])


def test_phases_visible_in_the_baseline_and_the_adaptive_filters(short_runs):
    """One strong (0-600 s) and one low (600-1200 s) phase, numbers of docs/uav_maneuver.md.
    Ukf: mean NIS near its dimension 3 in calm flight and at least twice that in the
    manoeuvres.  CtfaUkf: Q higher in the strong phase than in the low one only once it may come
    back (our ctfa_pass_decay, ratio >= 1.4); with eq. 25 as printed barely (ratio near 1.1, the
    issue's 3x does not hold).  ImmUkf: the high-Q model below 0.3 in calm flight and at least
    twice as probable in the manoeuvres.  The adapted filters stay consistent in both phases."""
    def means(model, name):
        return mean_in(short_runs[model], name, [STRONG]), mean_in(short_runs[model], name, [LOW])

    nis_strong, nis_low = means("Ukf", "nis")
    assert 2.0 < nis_low < 4.0, nis_low
    assert nis_strong >= 2.0 * nis_low, (nis_strong, nis_low)
    q_strong, q_low = means("CtfaUkf decay", "q_scale")
    paper_strong, paper_low = means("CtfaUkf", "q_scale")
    assert q_strong >= 1.4 * q_low, (q_strong, q_low)
    assert q_strong / q_low > paper_strong / paper_low + 0.3, (q_strong, q_low, paper_strong,
                                                                paper_low)
    mu_strong, mu_low = means("ImmUkf", "model_prob_2")
    assert mu_low < 0.3 and mu_strong >= 2.0 * mu_low, (mu_strong, mu_low)
    for model in ("CtfaUkf", "CtfaUkf decay", "ImmUkf"):
        for window in (STRONG, LOW):
            assert mean_in(short_runs[model], "nis", [window]) < 4.0, (model, window)
    print("phase means strong/low: Ukf NIS %.2f/%.2f, CtfaUkf q_scale %.1f/%.1f (eq. 25: "
          "%.1f/%.1f), ImmUkf high-Q probability %.3f/%.3f"
          % (nis_strong, nis_low, q_strong, q_low, paper_strong, paper_low, mu_strong, mu_low))


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason="open (issue 16): over 10 x 60 min "
                   "(docs/uav_maneuver.md) Ukf NIS 2.54 and ImmUkf 0.78/0.14 hold, but "
                   "CtfaUkf q_scale strong/low 1.08 (target 3; eq. 25 as printed cannot exceed "
                   "2.52 here), CtfaUkf 7 % worse than Ukf in yaw and 11-15 % worse than "
                   "ImmUkf in position N/D and velocity N (target within 10 %)")
def test_uav_maneuver_mems_monte_carlo_issue_targets():
    """Full 60 min, fixed seeds (NAVFMU_UAV_MC_RUNS runs, default 10): issue 16's phase
    ratios and paper 000's ordering on every axis."""
    n_runs = int(os.environ.get("NAVFMU_UAV_MC_RUNS", "10"))
    squares = {m: [] for m in FILTERS}
    phase = {(m, p): [] for m in FILTERS for p in ("strong", "low")}
    for seed in range(1, n_runs + 1):
        sensors = simulate_sensors(SCENARIO, overrides={"trajectory": {"seed": seed},
                                                        "gnss": {"seed": 100 + seed}})
        for m in FILTERS:
            run = run_model(sensors, m)
            row = rms_row(run)
            squares[m].append(row ** 2)
            phase[m, "strong"].append(mean_in(run, PHASE_VARIABLE[m], STRONG_60))
            phase[m, "low"].append(mean_in(run, PHASE_VARIABLE[m], LOW_60))
            print(f"seed {seed} {m:8s} " + " ".join(f"{x:.4f}" for x in row), flush=True)
    means = {key: float(np.mean(v)) for key, v in phase.items()}
    print("phase means over the seeds:", means)
    table = {m: np.sqrt(np.mean(squares[m], axis=0)) for m in FILTERS}
    for m in FILTERS:
        print(f"MC {m:8s} " + " ".join(f"{x:.4f}" for x in table[m]))
    assert means["Ukf", "strong"] >= 2.0 * means["Ukf", "low"], means
    assert means["CtfaUkf", "strong"] >= 3.0 * means["CtfaUkf", "low"], means
    assert means["ImmUkf", "strong"] > 0.7 and means["ImmUkf", "low"] < 0.3, means
    for m in ("CtfaUkf", "ImmUkf"):
        assert (table[m] < table["Ukf"]).all(), (m, table[m] / table["Ukf"])
    assert (table["CtfaUkf"] <= 1.10 * table["ImmUkf"]).all(), table["CtfaUkf"] / table["ImmUkf"]


#: the scenario with only the errors the filter models (Table 1), and the filter told the truth:
#: ARW and VRW as simulated, the turn-on biases random constants (no Gauss-Markov driver AND
#: no correlation time: a zero sigma with filter.ssv's 100 s tau would tell the filter that
#: the bias error decays to zero with certainty, tests/test_bias_covariance.py)
ORACLE_TRAJECTORY = {"gyro_scale_factor_ppm": 0.0, "gyro_misalignment_urad": 0.0,
                     "g_sensitivity_dphpg": 0.0, "accel_scale_factor_ppm": 0.0,
                     "accel_misalignment_urad": 0.0, "noise_intensity_gain": 0.0}
ORACLE_FILTER = {"q_gyro_bias_instability_dph": 0.0, "q_gyro_bias_tau_s": 0.0,
                 "q_accel_bias_instability_ug": 0.0, "q_accel_bias_tau_s": 0.0}


@pytest.mark.slow
def test_oracle_ukf_nees_within_20_percent():
    """Consistency where the model is right: IMU errors = Table 1 only, the filter's Q = the
    true noise (random-constant biases): NEES per group within 20 % of its dimension 3, mean
    of seeds 1-3 on 0-1200 s (measured 3.47 / 3.29 / 2.90, docs/uav_maneuver.md)."""
    from orchestrator.running import scenarios

    model = scenarios.load_scenario(SCENARIO)
    params = {f"trajectory.{k}": v for k, v in ORACLE_TRAJECTORY.items()}
    params.update({f"filter.{k}": v for k, v in ORACLE_FILTER.items()})
    nees = {g: [] for g in ("position", "velocity", "attitude")}
    for seed in (1, 2, 3):
        params.update({"trajectory.seed": seed, "gnss.seed": 100 + seed})
        run = scenarios.simulate_scenario(model, filter="Ukf", backend="direct",
                                          stop_time=SHORT_STOP, parameters=params, log=None)
        for g in nees:
            nees[g].append(run.metrics["filter"]["nees"][g])
    for g, values in nees.items():
        assert 2.4 <= np.mean(values) <= 3.6, (g, values)
