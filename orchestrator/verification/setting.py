"""Where a verified FMU runs: the scenario of its role, the component of that scenario it
stands in for, the parameter values it gets there, and the input table its FMI probes step
through.

Every role has a default scenario of ``models/`` and a component it replaces in it:

============== ====================== ============
role            default scenario       component
============== ====================== ============
INS/GNSS        ``aircraft_500s``      ``filter``
attitude        ``ahrs_turntable``     ``filter``
IMU sensor      ``aircraft_500s``      ``trajectory``
GNSS receiver   ``aircraft_500s``      ``gnss``
vehicle         ``uav_mission``        ``vehicle``
============== ====================== ============

The FMU gets the scenario's bindings of that component for the parameters it has (a swapped
FMU skips the others, as ``navfmu run --filter`` does) and then the user's ``--set`` values.
A scenario fits a role when it has that component and the FMU has every variable the
component's connections use (a vehicle: every output; the inputs it lacks, a vehicle not
guided on the navigation solution, are left unconnected).
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, List

import numpy as np

from ..running import scenarios
from ..building.build import ROOT
from ..errors import NavfmuError
from ..model.suggestions import did_you_mean
from .roles import FmuFacts

MODELS = ROOT / "models"
DEFAULT_SCENARIO = {"ins_gnss_filter": "aircraft_500s", "attitude_filter": "ahrs_turntable",
                    "imu_sensor": "aircraft_500s", "gnss_receiver": "aircraft_500s",
                    "vehicle": "uav_mission"}
COMPONENT = {"ins_gnss_filter": "filter", "attitude_filter": "filter",
             "imu_sensor": "trajectory", "gnss_receiver": "gnss", "vehicle": "vehicle"}
#: length of the input table the FMI probes step through [s]
PROBE_DURATION_S = 20.0
#: prefix of a ``--set`` name that gives a datasheet value instead of an FMU parameter
DATASHEET = "datasheet."


@dataclass
class Setting:
    """The FMU under test in its role's scenario (see the module docstring)."""

    facts: FmuFacts
    role: str
    scenario_paths: List[Path]
    component: str
    parameters: Dict[str, Any]
    user_sets: Dict[str, Any] = field(default_factory=dict)
    datasheet: Dict[str, float] = field(default_factory=dict)

    @property
    def scenario(self) -> Path:
        return self.scenario_paths[0]

    def model(self, path=None):
        return scenarios.load_scenario(path or self.scenario)

    def swapped(self, path=None):
        """The scenario with its component replaced by the FMU under test."""
        return self.model(path).replace_source(self.component, self.facts.path)

    def component_parameters(self) -> Dict[str, Any]:
        """``component.name`` -> value of the user's ``--set`` values, for a scenario run
        (the scenario's own bindings reach the swapped FMU through the swap)."""
        return {f"{self.component}.{k}": v for k, v in self.user_sets.items()}


def resolve_scenario(text: str) -> Path:
    """A scenario name of models/ or a path of a scenario folder or .ssd file."""
    p = Path(text)
    if not p.exists() and (MODELS / text).is_dir():
        p = MODELS / text
    if p.is_dir():
        p = p / "SystemStructure.ssd"
    if not p.is_file():
        raise NavfmuError(f"--scenario {text}: no such scenario (a folder of models/ or an "
                          ".ssd file)")
    return p.resolve()


def _check_fits(facts: FmuFacts, role: str, path: Path) -> None:
    model = scenarios.load_scenario(path)
    name = COMPONENT[role]
    if name not in [c.name for c in model.components]:
        raise NavfmuError(f"--scenario {path.parent.name}: does not fit a {role} (it has no "
                          f"component '{name}' for the FMU to stand in for)")
    inputs = ({c.end_connector for c in model.connections if c.end_component == name}
              if role != "vehicle" else set())
    needed = sorted(
        inputs | {c.start_connector for c in model.connections if c.start_component == name})
    missing = [n for n in needed if n not in facts.variables]
    if missing:
        raise NavfmuError(f"--scenario {path.parent.name}: does not fit this {role}: its "
                          f"component '{name}' is connected through {', '.join(missing)}, "
                          f"which {facts.path.name} does not have")


def _datasheet_value(key: str, value) -> float:
    """A datasheet value of ``--set datasheet.NAME=VALUE``: a finite number >= 0 (a noise
    density, a bias instability or a correlation time)."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        number = float("nan")
    if not (np.isfinite(number) and number >= 0):
        raise NavfmuError(f"--set {key}={value}: a datasheet value must be a finite number "
                          ">= 0")
    return number


def make_setting(facts: FmuFacts, role: str, scenario_names=(), sets=None) -> Setting:
    """The setting of ``facts`` in ``role`` (:class:`NavfmuError` for a scenario that does
    not fit, or a ``--set`` of a parameter the FMU does not have)."""
    paths = [resolve_scenario(s) for s in (scenario_names or [DEFAULT_SCENARIO[role]])]
    for p in paths:
        _check_fits(facts, role, p)
    component = COMPONENT[role]
    model = scenarios.load_scenario(paths[0])
    declared = facts.parameters()
    values = {k: v for k, (_, v) in model.component(component).parameters.items()
              if k in declared}
    datasheet, user_sets = {}, {}
    for key, value in (sets or {}).items():
        if key.startswith(DATASHEET):
            datasheet[key[len(DATASHEET):]] = _datasheet_value(key, value)
        elif key not in declared:
            raise NavfmuError(f"--set {key}: {facts.path.name} has no parameter '{key}'"
                              + did_you_mean(key, declared))
        else:
            values[key] = user_sets[key] = value
    return Setting(facts, role, paths, component, values, user_sets, datasheet)


def input_table(setting: Setting, duration: float = PROBE_DURATION_S):
    """``(table, h)``: the values the FMU's inputs take at each of its steps over the first
    ``duration`` seconds of the scenario (its own component run on the direct backend,
    Gauss-Seidel: step k sees its sources' outputs after their step k), and its step [s]."""
    model = setting.model()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        run = scenarios.simulate_scenario(model, backend="direct", stop_time=duration,
                                          log=lambda m: None)
    results = run.results
    spec = model.component(setting.component)
    h = (spec.step_hint or model.base_step)
    every = max(1, int(round(h / model.base_step)))
    table = {}
    for c in model.connections:
        if c.end_component == setting.component and c.end_connector in setting.facts.variables:
            column = results.column(c.start_component, c.start_connector)
            table[c.end_connector] = np.asarray(column[every::every], dtype=float)
    if not table:      # a source without inputs (an IMU of its own trajectory)
        n = int(round(duration / h))
        table["__steps__"] = np.zeros(n)
    return table, h


__all__ = ["Setting", "make_setting", "input_table", "resolve_scenario", "DEFAULT_SCENARIO",
           "COMPONENT", "DATASHEET"]
