"""The estimators: innovation statistics and chi-square gates (``innovation_stats``), the
adaptation laws of paper 001 (``adaptive_laws``) and the robust laws of paper 004
(``robust_laws``), the error-state Kalman filter engine and its adaptive and robust variants
(``ins_gnss_kf``, ``adaptive_filters``), the unscented core, CTFA and IMM of paper 000
(``unscented``, ``ctfa``, ``imm``, ``ukf_filters``, their time update ``ukf_time_update``),
the attitude filters and the fuzzy law of paper 003 (``ahrs``, ``fuzzy``), the history that
applies a late fix at its time (``latency``) and the input checks of the laws
(``array_checks``).

Wing order: imports ``core``, ``ins`` and ``sensors``; imported by ``components`` only.
"""
