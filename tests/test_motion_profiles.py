"""A user's own motion profile (docs/guide/motion_profiles.md): the example profile runs to
metre-level errors with the filter starting from the data, the scenario's given state is
refused by its consequences (the divergence the docs state), and the page lists every segment
type and parameter of the profile checker."""
from __future__ import annotations

import json
import re

import pytest

from navcore.ins import profile_segments
from orchestrator.building import build as fmu_build
from orchestrator.running import scenarios

ROOT = fmu_build.ROOT
PAGE = ROOT / "docs" / "guide" / "motion_profiles.md"
EXAMPLE = ROOT / "docs" / "guide" / "example_profile.json"
STOP = 185.0                      # the example's length


def _run(stop=STOP, **parameters):
    model = scenarios.load_scenario(ROOT / "models" / "aircraft_500s")
    params = {"trajectory.profile": str(EXAMPLE), "gnss.noise_steps": "",
              "gnss.outlier_patches": "", **parameters}
    return scenarios.simulate_scenario(model, backend="direct", parameters=params,
                                       stop_time=stop, log=None)


def test_example_profile_runs_to_metre_level_errors_from_the_data():
    run = _run(**{"filter.init_mode": "gnss"})
    m = run.metrics["filter"]
    aligned = run.results.column("filter", "aligned") > 0.5
    # the first fix above init_speed_min (1 m/s): 3 s into the acceleration from rest
    assert run.results.time[aligned][0] == pytest.approx(23.0)
    assert m["window_s"] == pytest.approx([23.0, STOP])
    for a in "ned":
        assert m["position_rms_m"][a] < 2.0        # GNSS 5 m per axis
        assert m["velocity_rms_mps"][a] < 0.2      # GNSS 0.3 m/s
    assert m["attitude_rms_deg"]["yaw"] < 2.0
    assert m["nis"]["band95"][0] < m["nis"]["mean"] < m["nis"]["band95"][1]


def test_example_profile_with_the_scenarios_given_state_diverges_as_documented():
    """What the page says happens without init_mode = gnss (the issue this page answers),
    already over the first 60 s."""
    m = _run(stop=60.0).metrics["filter"]
    assert m["position_rms_m"]["e"] > 1e5 and m["nis"]["mean"] > 1e6


def test_page_lists_every_segment_type_and_parameter():
    text = PAGE.read_text()
    for kind, params in profile_segments._ALLOWED.items():
        assert re.search(rf"`{kind}`", text), kind
        for p in params:
            assert f"`{p}`" in text, (kind, p)
    for key in profile_segments._START_KEYS + ("transition", "duration"):
        assert f"`{key}`" in text, key
    profile_segments.compile_profile(json.loads(EXAMPLE.read_text()))   # a valid profile
