"""The master's Jacobi exchange (libcosim's fixed-step rules) with toy components, exact numbers
worked out by hand from rule 3J of orchestrator/cosim/master.py."""
from __future__ import annotations

import numpy as np
import pytest

from orchestrator.errors import NavfmuError
from orchestrator.cosim.master import Simulation
from test_master import REGISTRY, chain_model


def test_jacobi_one_step_late_decimated_inputs_at_window_start_outputs_at_its_end(write_ssd):
    sim = Simulation(chain_model(write_ssd), backend="direct", registry=REGISTRY,
                     algorithm="jacobi")
    res = sim.run()
    t = res.time  # base step 0.25; acc steps every 4 base steps (1.0 s)
    np.testing.assert_array_equal(res.column("ramp", "y"), t)
    # gain steps on the ramp's output of the previous macro step (row 0: initial output 0)
    np.testing.assert_array_equal(res.column("gain", "y"), np.r_[0.0, 2 * t[:-1]])
    # acc windows [0,1], [1,2], [2,3] start at rows 0, 4, 8 with u = gain.y at that row
    # (0, 1.5, 3.5); each window's output appears at its end, rows 4, 8, 12
    np.testing.assert_array_equal(res.column("acc", "s"),
                                  [0, 0, 0, 0, 0, 0, 0, 0, 1.5, 1.5, 1.5, 1.5, 5.0])
    np.testing.assert_array_equal(res.column("acc", "t0")[[3, 4, 7, 8, 12]], [0, 0, 0, 1, 2])
    np.testing.assert_array_equal(res.column("acc", "last_count")[[4, 8, 12]], [0, 4, 8])
    assert res.metadata["step_calls"] == {"acc": 3, "gain": 12, "ramp": 12}
    assert res.metadata["algorithm"] == "jacobi"


def test_jacobi_skips_a_window_that_would_end_after_the_stop(write_ssd):
    res = Simulation(chain_model(write_ssd, stop=2.5), backend="direct", registry=REGISTRY,
                     algorithm="jacobi").run()
    assert res.metadata["step_calls"]["acc"] == 2
    # the window [2, 3] is not started; the [1, 2] window's output holds to the end
    assert res.column("acc", "s")[-1] == 1.5 and res.column("acc", "t0")[-1] == 1.0


def test_unknown_algorithm_is_refused(write_ssd):
    with pytest.raises(NavfmuError, match="unknown algorithm 'seidel'"):
        Simulation(chain_model(write_ssd), backend="direct", registry=REGISTRY,
                   algorithm="seidel")
