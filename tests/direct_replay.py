"""A scenario's sensors run once through the product, then replayed into any number of filters.

A test helper over the product's own code, no SSD reading or stepping of its own: the
scenario folder is loaded by :func:`orchestrator.running.scenarios.load_scenario`, its sensor
components (``trajectory`` and ``gnss`` and the connections between them) are run by the
master on the direct backend (:class:`orchestrator.cosim.master.Simulation`: the trajectory every
base step, the receiver decimated by its step hint, Gauss-Seidel order), and a filter is
stepped on the recorded rows through the direct backend's instance
(:class:`orchestrator.cosim.direct_instance.DirectInstance`), at the base step, with the IMU
outputs of the step and the receiver's latest outputs: what the master does with the whole
scenario.

Usage::

    sensors = simulate_sensors(MODELS / "aircraft_500s", stop_time=200.0,
                               overrides={"trajectory": {"seed": 3}, "gnss": {"seed": 4}})
    run = run_filter(sensors, components.Iakf, overrides={"reserve_gamma": 2.0})
    run.position_error_ned()   # (N, 3) m, at the GNSS epochs
    run.outputs["fading_factor"]

The sensor record is computed once and replayed into any number of filters (what the
Monte Carlo tests do: the truth/IMU/GNSS of a seed are shared by every filter compared).
The error formulas here (:meth:`FilterRun.position_error_ned`, :func:`rms_table`) are the
tests' own, independent of :mod:`orchestrator.results.metrics`.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, Optional, Sequence

import numpy as np

from navcore.ins import earth
from navcore.core import signals
from orchestrator.cosim.direct_instance import DirectInstance
from orchestrator.cosim.master import Simulation
from orchestrator.running.scenarios import FILTER_COMPONENT, load_scenario, registry
from orchestrator.model.ssp import SystemModel

MODELS = Path(__file__).resolve().parents[1] / "models"
#: the components that make a scenario's sensor record
SENSOR_COMPONENTS = ("trajectory", "gnss")

FILTER_INPUT_NAMES = tuple(p.name for p in signals.FILTER_INPUTS)
FILTER_INPUT_STARTS = tuple((p.name, float(p.default())) for p in signals.FILTER_INPUTS)
TRUTH_NAMES = tuple(p.name for p in signals.TRUTH)


def scenario_parameters(model: SystemModel) -> Dict[str, Dict[str, object]]:
    """Component name -> parameter values the scenario binds (its .ssv files), as loaded."""
    return {c.name: {k: v for k, (_, v) in c.parameters.items()} for c in model.components}


def sensor_model(model: SystemModel) -> SystemModel:
    """``model`` with only its sensor components and the connections between them."""
    keep = set(SENSOR_COMPONENTS)
    return dataclasses.replace(
        model, components=[c for c in model.components if c.name in keep],
        connections=[c for c in model.connections
                     if c.start_component in keep and c.end_component in keep])


@dataclass
class SensorRecord:
    """Truth, IMU and GNSS of one scenario run, one row per base step (t = (k+1) h)."""

    model: SystemModel
    parameters: Dict[str, Dict[str, object]]  # component name -> parameter values
    time: np.ndarray                      # (N,) s, end of each base step: k h + h
    filter_inputs: np.ndarray             # (N, len(FILTER_INPUT_NAMES)) inputs of the filter
    truth: np.ndarray                     # (N, len(TRUTH_NAMES))
    gnss_outlier: np.ndarray              # (N,) bool: an outlier was injected in the latest fix
    epoch_rows: np.ndarray                # rows where a new GNSS fix arrived
    h: float

    @property
    def filter_model(self) -> str:
        """Model name of the scenario's ``filter`` component (its FMU's file name)."""
        return Path(self.model.component(FILTER_COMPONENT).source).stem


def simulate_sensors(folder, stop_time: Optional[float] = None,
                     overrides: Optional[Dict[str, Dict[str, object]]] = None) -> SensorRecord:
    """Run the sensor components of the scenario in ``folder`` on the direct backend;
    ``overrides`` maps a component name ('trajectory', 'gnss') to parameters replacing the
    .ssv values."""
    model = load_scenario(folder)
    sensors = sensor_model(model)
    parameters = {f"{comp}.{name}": value for comp, values in (overrides or {}).items()
                  for name, value in values.items()}
    res = Simulation(sensors, backend="direct", registry=registry(),
                     parameters=parameters).run(stop_time=stop_time)
    merged = {}
    for comp in SENSOR_COMPONENTS:
        merged.update({name: res.data[comp][1:, j] for j, name in enumerate(res.columns[comp])})
    epoch = merged["gnss_epoch"]
    new_fix = np.diff(np.concatenate([[0.0], epoch])) != 0
    params = scenario_parameters(model)
    for comp, values in (overrides or {}).items():
        params[comp] = {**params[comp], **values}
    h = sensors.base_step
    # the end of base step k as k h + h (the tests' time axis; the master's row time is
    # start + (k + 1) h, a rounding apart)
    time = np.arange(len(epoch)) * h + h
    return SensorRecord(model, params, time,
                        # an input no sensor drives keeps its start value, as in the master
                        np.column_stack([merged.get(n, np.full(len(epoch), start))
                                         for n, start in FILTER_INPUT_STARTS]),
                        np.column_stack([merged[n] for n in TRUTH_NAMES]),
                        merged["gnss_outlier"] > 0.5, np.flatnonzero(new_fix), h)


@dataclass
class FilterRun:
    """Outputs of one filter replayed over a :class:`SensorRecord`."""

    sensors: SensorRecord
    model: str
    rows: np.ndarray                       # recorded rows of the sensor record
    outputs: Dict[str, np.ndarray] = field(default_factory=dict)
    component: object = None               # the navcore component, to continue it

    def truth(self, name: str) -> np.ndarray:
        return self.sensors.truth[self.rows, TRUTH_NAMES.index(name)]

    def position_error_ned(self) -> np.ndarray:
        """(N, 3) estimated minus true position, NED metres."""
        lat = self.truth("truth_lat")
        h = self.truth("truth_h")
        rn, re = earth.radii(lat)
        dn = (self.outputs["nav_lat"] - lat) * (rn + h)
        de = (self.outputs["nav_lon"] - self.truth("truth_lon")) * (re + h) * np.cos(lat)
        dd = -(self.outputs["nav_h"] - h)
        return np.column_stack([dn, de, dd])

    def velocity_error_ned(self) -> np.ndarray:
        """(N, 3) estimated minus true velocity, m/s."""
        return np.column_stack([self.outputs[f"nav_v{a}"] - self.truth(f"truth_v{a}")
                                for a in "ned"])


def _started_instance(sensors: SensorRecord, filter_class, overrides) -> DirectInstance:
    """A direct-backend instance of ``filter_class`` (default: the scenario's filter) with the
    scenario's filter parameters it declares and ``overrides`` (any name: an undeclared one is
    an error, as in the master), started at the scenario's start time."""
    cls = filter_class or registry()[sensors.filter_model]
    declared = {p.name for p in cls.parameters}
    params = {k: v for k, v in sensors.parameters[FILTER_COMPONENT].items() if k in declared}
    params.update(overrides or {})
    instance = DirectInstance(cls(), FILTER_COMPONENT)
    instance.set_parameters(params)
    instance.initialize(sensors.model.start_time, sensors.model.stop_time)
    return instance


def run_filter(sensors: SensorRecord, filter_class=None, overrides: Optional[Dict] = None,
               names: Optional[Sequence[str]] = None,
               start_row: int = 0, stop_row: Optional[int] = None,
               component=None) -> FilterRun:
    """Replay ``sensors`` into a filter through the direct backend.

    ``filter_class``: a navcore InsGnssFilter subclass (default: the scenario's filter);
    ``overrides``: parameters replacing the scenario's filter.ssv values.  One row is recorded
    per GNSS fix, after the filter has processed it.  ``names``: outputs to record (default:
    every Real/Integer/Boolean output).
    ``component``/``start_row``/``stop_row``: continue an existing, already started
    component from a given row (used by the state save/restore tests).
    """
    if component is None:
        instance = _started_instance(sensors, filter_class, overrides)
    else:
        instance = DirectInstance(component, FILTER_COMPONENT)
    cls = type(instance.component)
    if names is None:
        names = [p.name for p in cls.outputs if p.type != "String"]
    instance.prepare(FILTER_INPUT_NAMES, names)
    real_in, int_in, bool_in = (instance.input_names[t] for t in ("Real", "Integer", "Boolean"))
    columns = [[FILTER_INPUT_NAMES.index(n) for n in group] for group in (real_in, int_in, bool_in)]
    order = np.argsort([names.index(n) for t in ("Real", "Integer", "Boolean")
                        for n in instance.output_names[t]])
    n = len(sensors.time) if stop_row is None else stop_row
    wanted = np.zeros(len(sensors.time), dtype=bool)
    wanted[sensors.epoch_rows] = True
    rows, values = [], []
    h = sensors.h
    for k in range(start_row, n):
        row = sensors.filter_inputs[k]
        instance.set_inputs(row[columns[0]], row[columns[1]], row[columns[2]])
        instance.do_step(k * h, h)
        if wanted[k]:
            rows.append(k)
            values.append(np.concatenate(instance.get_outputs())[order])
    arr = np.array(values, dtype=float) if values else np.zeros((0, len(names)))
    return FilterRun(sensors, cls.model_name, np.array(rows, dtype=int),
                     {name: arr[:, i] for i, name in enumerate(names)}, instance.component)


def rms(a, axis=0):
    return np.sqrt(np.mean(np.asarray(a) ** 2, axis=axis))


def rms_table(run: FilterRun, t_from: float = 0.0) -> Dict[str, np.ndarray]:
    """RMS of position (N/E/D m) and velocity (N/E/D m/s) errors at the GNSS epochs after
    ``t_from`` s."""
    sel = run.sensors.time[run.rows] > t_from - 1e-9
    return {"position_ned_m": rms(run.position_error_ned()[sel]),
            "velocity_ned_mps": rms(run.velocity_error_ned()[sel])}
