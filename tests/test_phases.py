"""Per-phase statistics of filter outputs over a scenario's declared phase windows
(orchestrator.results.phases), on hand-made results whose phase means are known exactly."""
from __future__ import annotations

import types

import numpy as np
import pytest

from orchestrator.results import phases
from orchestrator.errors import NavfmuError
from orchestrator.results.run_results import Results

REFERENCE = {"phases": {"windows": [{"label": "strong", "t0": 0, "t1": 10},
                                    {"label": "low", "t0": 10, "t1": 20},
                                    {"label": "strong", "t0": 20, "t1": 30}],
                        "variables": ["nis", "q_scale", "model_prob_2"]}}


def _run(label="Kf"):
    t = np.arange(0.5, 30.0, 0.5)                    # updates on whole seconds only
    updated = (t % 1.0 == 0.0).astype(float)
    nis = np.where((t < 10) | (t >= 20), 6.0, 2.0)
    nis[updated == 0] = 1e6                          # never counted: not an update epoch
    q = np.ones_like(t)                              # constant: left out
    data = np.column_stack([t, updated, nis, q])
    res = Results(time=t, data={"filter": data},
                  columns={"filter": ["nav_time", "updated", "nis", "q_scale"]},
                  units={"filter": ["s", "", "", ""]})
    return types.SimpleNamespace(label=label, results=res)


def test_means_per_phase_at_update_epochs_and_ratio():
    stats = phases.phase_statistics([_run()], REFERENCE, lambda r: ["filter"])
    assert stats["labels"] == ["strong", "low"]
    (row,) = stats["rows"]                           # q_scale constant, model_prob_2 absent
    assert row["variable"] == "nis"
    assert row["means"] == {"strong": 6.0, "low": 2.0}
    assert row["epochs"] == {"strong": 19, "low": 10}   # t = 1..9, 20..29 and 10..19
    assert row["ratio"] == pytest.approx(3.0)
    text = phases.format_phase_statistics(stats)
    assert "strong 0-10, 20-30 s; low 10-20 s" in text
    assert "6.000" in text and "2.000" in text and "3.00" in text


def test_no_phases_and_bad_windows():
    assert phases.phase_statistics([_run()], {}, lambda r: ["filter"]) is None
    assert phases.format_phase_statistics(None) == ""
    with pytest.raises(NavfmuError, match=r"phases.windows\[0\]"):
        phases.phase_windows({"phases": {"windows": [{"label": "a", "t0": 5, "t1": 5}]}})
    with pytest.raises(NavfmuError, match="windows"):
        phases.phase_windows({"phases": {"windows": "0-600"}})

