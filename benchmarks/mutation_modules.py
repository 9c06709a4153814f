"""The modules the mutation tester runs on, each with the pytest arguments of the tests
that exercise it (benchmarks/mutation.py, docs/mutation.md)."""
from __future__ import annotations

# module -> the pytest arguments selecting the tests that exercise it; tests through built FMUs
# are left out (an FMU carries its own copy of navcore, not the mutated one)
MODULES: dict[str, list[str]] = {
    "navcore.filters.adaptive_laws": ["tests/test_law_arguments.py", "tests/test_adaptive_laws.py"],
    "navcore.filters.robust_laws": ["tests/test_law_arguments.py", "tests/test_adaptive_laws.py"],
    "navcore.filters.latency": ["tests/test_solution_history.py", "tests/test_latency.py",
                                "-k", "not through_the_fmus"],
    "navcore.core.state_format": ["tests/test_state_blob_nodes.py", "tests/test_state_format.py"],
    "navcore.filters.innovation_stats": ["tests/test_innovation_checks.py",
                                         "tests/test_innovation_stats.py",
                                         "tests/test_law_arguments.py",
                                         "tests/test_adaptive_laws.py"],
    "navcore.sensors.log_time": ["tests/test_log_time_stamps.py", "tests/test_log_time.py"],
    "orchestrator.campaigns.statistics": ["tests/test_statistics.py",
                                          "tests/test_statistics_by_hand.py"],
    # navcore filters, state and sensor log
    "navcore.filters.fuzzy": ["tests/test_fuzzy.py", "tests/test_fuzzy_set_edges.py"],
    "navcore.filters.imm": ["tests/test_imm.py", "tests/test_imm_arguments.py"],
    "navcore.filters.ctfa": ["tests/test_ctfa.py", "tests/test_ctfa_arguments.py"],
    "navcore.core.state": ["tests/test_state_format.py", "tests/test_state_blob_nodes.py",
                           "tests/test_solution_history.py", "tests/test_imu_errors.py",
                           "tests/test_ideal_track.py", "tests/test_state_tree_paths.py"],
}

# orchestrator campaigns and exchange
MODULES.update({
    "orchestrator.campaigns.genetic": ["tests/test_genetic.py",
                                       "tests/test_genetic_edges_and_bookkeeping.py"],
    # the tests through the module fixture of real tunes (test_tune.py's "serial") are left
    # out: half a minute a mutant; the fast file checks what they do piece by piece
    "orchestrator.campaigns.tune": ["tests/test_tune.py",
                                    "tests/test_tune_ranges_costs_and_summary.py", "-k",
                                    "not same_seed and not self_consistency and not "
                                    "search_ranges and not tuned_set_is_bound"],
    # the executor modes, the FMU backend and the kill-and-resume runs are left out (they
    # check the executor, the FMUs and the CLI, at many seconds a mutant)
    # (and the CSV series test: polars' thread pool hangs in mutmut's fork, block
    # "Co-simulation master")
    **{module: ["tests/test_campaign.py", "tests/test_campaign_folder_seeds_and_hashes.py",
                "tests/test_campaign_run_one_sinks.py", "-k",
                "not pool_and_dask and not fmu_and_direct and not killed_driver and not "
                "csv_when_asked"]
       for module in ("orchestrator.campaigns.campaign", "orchestrator.campaigns.campaign_runs",
                      "orchestrator.campaigns.seeds")},
    # test_master.py's CSV test is left out: polars' thread pool hangs in mutmut's fork
    # (block "Co-simulation master")
    "orchestrator.cosim.exchange": ["tests/test_jacobi.py", "tests/test_master.py",
                                    "tests/test_exchange_by_hand.py", "-k", "not csv_header"],
})

# Kf engines and recovery: the engines' own unit tests (the scenario runs of
# test_adaptive_filters.py and test_outage_recovery.py cost minutes a survivor)
MODULES.update({
    "navcore.filters.ins_gnss_kf": ["tests/test_kf_engine_by_hand.py",
                                    "tests/test_bias_covariance.py"],
    "navcore.filters.recovery": ["tests/test_recovery.py",
                                 "tests/test_recovery_guard_by_hand.py"],
    "navcore.filters.adaptive_filters": ["tests/test_adaptive_engines_by_hand.py"],
    "navcore.filters.robust_filters": ["tests/test_adaptive_engines_by_hand.py"],
})

# UKF engines
MODULES.update({
    "navcore.filters.unscented": ["tests/test_unscented.py", "tests/test_ukf_process_model.py",
                                  "tests/test_unscented_checks_and_defaults.py"],
    "navcore.filters.ukf_filters": ["tests/test_ukf_process_model.py",
                                    "tests/test_bias_covariance.py",
                                    "tests/test_ukf_engines_by_hand.py",
                                    "tests/test_ukf_process_model_series_and_defaults.py"],
    "navcore.filters.ukf_time_update": ["tests/test_ukf_process_model.py",
                                        "tests/test_ukf_process_model_series_and_defaults.py",
                                        "tests/test_ukf_engines_by_hand.py",
                                        "tests/test_ukf_batch.py"],
})

# AHRS engines and sensor logs
MODULES.update({
    # the scenario replays of test_log_time.py and test_kf_gins.py are left out (seconds a
    # mutant); the fast files read, check and write logs directly
    "navcore.sensors.sensorlog": ["tests/test_sensorlog.py", "tests/test_log_time.py",
                                  "tests/test_kf_gins.py",
                                  "tests/test_sensorlog_rules_by_hand.py", "-k",
                                  "not replays_bit_for_bit and not integrated_as_recorded and "
                                  "not metrics_only and not receiver_sigmas_as_r and not "
                                  "start_and_stop"],
    # the turntable scenario runs (test_ahrs_scenario.py) are left out; the filter's short
    # runs without FMI and the engine by hand are fast
    "navcore.filters.ahrs": ["tests/test_ahrs.py", "tests/test_mrp.py", "tests/test_fuzzy.py",
                             "tests/test_ahrs_engine_by_hand.py"],
})

# Campaign summary, sweep and executor
MODULES.update({
    "orchestrator.campaigns.campaign_summary": ["tests/test_campaign_summary_by_hand.py",
                                                "tests/test_statistics.py"],
    "orchestrator.campaigns.sweep": ["tests/test_sweep.py",
                                     "tests/test_sweep_points_tasks_and_plot.py"],
    # the run on a real Dask LocalCluster is left out (a second a mutant, and a mutant that
    # breaks closing leaves its processes behind); the stand-ins check the Dask code instead
    "orchestrator.campaigns.executor": ["tests/test_executor.py",
                                        "tests/test_executor_modes_with_stand_ins.py", "-k",
                                        "not dask_local_cluster"],
})

# filter helpers and log converters
MODULES.update({
    "navcore.filters.array_checks": ["tests/test_array_checks.py",
                                     "tests/test_law_arguments.py",
                                     "tests/test_innovation_checks.py"],
    "navcore.filters.nis_monitor": ["tests/test_nis_monitor.py",
                                    "tests/test_nis_monitor_by_hand.py"],
    # test_initial_state.py's runs through the filters (seconds each) are left out
    "navcore.filters.initial_state": ["tests/test_initial_state_by_hand.py",
                                      "tests/test_initial_state.py", "-k",
                                      "by_hand or coarse_alignment_recovers"],
    # test_kf_gins.py's run of a filter on the converted log (seconds) is left out
    "navcore.sensors.log_converters": ["tests/test_sensorlog.py", "tests/test_kf_gins.py",
                                       "tests/test_log_converters_by_hand.py", "-k",
                                       "not receiver_sigmas_as_r"],
})

# Co-simulation master: its runs on the direct backend with toy components and with the tiny
# FMUs of test_master.py (the master runs in the test process).  test_master.py's CSV test is
# left out: polars, which writes the CSV, keeps a thread pool that does not survive mutmut's
# fork, so in a mutant's process it hangs and every mutant it reaches times out
_MASTER_TESTS = ["tests/test_master.py", "tests/test_jacobi.py", "tests/test_exchange_by_hand.py",
                 "tests/test_master_by_hand.py", "-k", "not csv_header"]
MODULES.update({module: _MASTER_TESTS for module in (
    "orchestrator.cosim.master", "orchestrator.cosim.model_checks",
    "orchestrator.cosim.macro_loop", "orchestrator.cosim.result_assembly")})
