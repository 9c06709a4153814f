"""Direct (no FMI, no master) runs of a TrajectoryImu -> GnssReceiver -> filter scenario.

A plain helper for tests: it reads a scenario folder (``models/<name>/``: the .ssv files
bound to the components ``trajectory``, ``gnss`` and ``filter`` by SystemStructure.ssd),
steps the navcore components the way the scenario says and returns numpy arrays.

Stepping (the same semantics as the scenario's SSD and /tmp/direct_try.py): base step =
the trajectory's ``imu_period``; at every base step the trajectory steps first; the receiver
is stepped every ``fix_interval`` (decimated, in the same base step, after the trajectory,
with the truth just computed), then the filter at the IMU rate with the IMU outputs of this
step and the receiver's latest outputs.

Usage::

    sensors = simulate_sensors(MODELS / "aircraft_500s", stop_time=200.0,
                               overrides={"trajectory": {"seed": 3}, "gnss": {"seed": 4}})
    run = run_filter(sensors, components.Iakf, overrides={"reserve_gamma": 2.0})
    run.position_error_ned()   # (N, 3) m, at the GNSS epochs
    run.outputs["fading_factor"]

The sensor record is computed once and replayed into any number of filters (what the
Monte Carlo tests do: the truth/IMU/GNSS of a seed are shared by every filter compared).
"""
from __future__ import annotations

import time as _time
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, Optional, Sequence

import numpy as np

from navcore import components, earth, signals

MODELS = Path(__file__).resolve().parents[1] / "models"

_SSD = "{http://ssp-standard.org/SSP1/SystemStructureDescription}"
_SSV = "{http://ssp-standard.org/SSP1/SystemStructureParameterValues}"

FILTER_INPUT_NAMES = tuple(p.name for p in signals.FILTER_INPUTS)
TRUTH_NAMES = tuple(p.name for p in signals.TRUTH)


def read_ssv(path) -> Dict[str, object]:
    """Parameter name -> value (float / int / bool / str) of an .ssv file."""
    values = {}
    for p in ET.parse(path).getroot().iter(_SSV + "Parameter"):
        v = p[0]
        kind = v.tag.split("}")[1]
        text = v.get("value")
        if kind == "Real":
            values[p.get("name")] = float(text)
        elif kind == "Integer":
            values[p.get("name")] = int(text)
        elif kind == "Boolean":
            values[p.get("name")] = text.strip().lower() in ("true", "1")
        else:
            values[p.get("name")] = text
    return values


@dataclass
class Scenario:
    """Parameters of the three components of a scenario folder and its experiment."""

    folder: Path
    parameters: Dict[str, Dict[str, object]]     # component name -> parameter dict
    filter_model: str                            # model name of the 'filter' component
    stop_time: float
    base_step: float


def load_scenario(folder) -> Scenario:
    """Read SystemStructure.ssd and its .ssv parameter bindings."""
    folder = Path(folder)
    root = ET.parse(folder / "SystemStructure.ssd").getroot()
    params: Dict[str, Dict[str, object]] = {}
    filter_model = "Kf"
    for comp in root.iter(_SSD + "Component"):
        name = comp.get("name")
        values: Dict[str, object] = {}
        for binding in comp.iter(_SSD + "ParameterBinding"):
            if binding.get("source"):
                values.update(read_ssv(folder / binding.get("source")))
        params[name] = values
        if name == "filter":
            filter_model = Path(comp.get("source")).stem
    experiment = root.find(_SSD + "DefaultExperiment")
    stop = float(experiment.get("stopTime"))
    base = None
    for el in root.iter():
        if el.tag.endswith("FixedStepAlgorithm"):
            base = float(el.get("baseStepSize"))
    return Scenario(folder, params, filter_model, stop, base or 0.01)


@dataclass
class SensorRecord:
    """Truth, IMU and GNSS of one scenario run, one row per base step (t = (k+1) h)."""

    scenario: Scenario
    time: np.ndarray                      # (N,) s, end of each base step
    filter_inputs: np.ndarray             # (N, len(FILTER_INPUT_NAMES)) inputs of the filter
    truth: np.ndarray                     # (N, len(TRUTH_NAMES))
    gnss_outlier: np.ndarray              # (N,) bool: an outlier was injected in the latest fix
    epoch_rows: np.ndarray                # rows where a new GNSS fix arrived
    h: float

    def inputs_at(self, k: int) -> Dict[str, object]:
        row = self.filter_inputs[k]
        d = dict(zip(FILTER_INPUT_NAMES, row.tolist()))
        d["gnss_valid"] = bool(d["gnss_valid"])
        d["gnss_epoch"] = int(d["gnss_epoch"])
        return d


def simulate_sensors(folder, stop_time: Optional[float] = None,
                     overrides: Optional[Dict[str, Dict[str, object]]] = None) -> SensorRecord:
    """Step trajectory and receiver of the scenario in ``folder``; ``overrides`` maps a
    component name ('trajectory', 'gnss') to parameters replacing the .ssv values."""
    sc = load_scenario(folder)
    overrides = overrides or {}
    tp = {**sc.parameters["trajectory"], **overrides.get("trajectory", {})}
    gp = {**sc.parameters["gnss"], **overrides.get("gnss", {})}
    traj = components.TrajectoryImu(**tp)
    gnss = components.GnssReceiver(**gp)
    o_t = traj.initialize(0.0)
    o_g = gnss.initialize(0.0)
    h = traj.params["imu_period"]
    fix = gnss.params["fix_interval"]
    decimation = int(round(fix / h))
    if abs(decimation * h - fix) > 1e-9:
        raise ValueError(f"fix_interval {fix} s is not a multiple of imu_period {h} s")
    stop = sc.stop_time if stop_time is None else stop_time
    n = int(round(stop / h))
    truth_in = TRUTH_NAMES[:7]
    time = np.empty(n)
    inputs = np.empty((n, len(FILTER_INPUT_NAMES)))
    truth = np.empty((n, len(TRUTH_NAMES)))
    outlier = np.zeros(n, dtype=bool)
    epoch_rows = []
    last_epoch = 0
    for k in range(n):
        t = k * h
        o_t = traj.step(t, h, {})
        if (k + 1) % decimation == 0:
            o_g = gnss.step(t + h - fix, fix, {name: o_t[name] for name in truth_in})
        merged = {**o_t, **o_g}
        inputs[k] = [float(merged[name]) for name in FILTER_INPUT_NAMES]
        truth[k] = [o_t[name] for name in TRUTH_NAMES]
        outlier[k] = bool(o_g["gnss_outlier"])
        if o_g["gnss_epoch"] != last_epoch:
            last_epoch = o_g["gnss_epoch"]
            epoch_rows.append(k)
        time[k] = t + h
    return SensorRecord(sc, time, inputs, truth, outlier, np.array(epoch_rows, dtype=int), h)


@dataclass
class FilterRun:
    """Outputs of one filter replayed over a :class:`SensorRecord`."""

    sensors: SensorRecord
    model: str
    rows: np.ndarray                       # recorded rows of the sensor record
    outputs: Dict[str, np.ndarray] = field(default_factory=dict)
    seconds_per_step: float = 0.0          # mean wall time of component.step

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


def run_filter(sensors: SensorRecord, filter_class=None, overrides: Optional[Dict] = None,
               record: str = "epochs", names: Optional[Sequence[str]] = None,
               start_row: int = 0, stop_row: Optional[int] = None,
               component=None) -> FilterRun:
    """Replay ``sensors`` into a filter component.

    ``filter_class``: a navcore InsGnssFilter subclass (default: the scenario's filter);
    ``overrides``: parameters replacing the scenario's filter.ssv values (parameters a class
    does not declare are an error, as in the component itself).  ``record``: 'epochs' (one
    row per GNSS fix, after the filter has processed it) or 'all' (every base step).
    ``names``: outputs to record (default: every Real/Integer/Boolean output).
    ``component``/``start_row``/``stop_row``: continue an existing, already initialized
    component from a given row (used by the state save/restore tests).
    """
    if component is None:
        cls = filter_class or components.REGISTRY[sensors.scenario.filter_model]
        params = {**sensors.scenario.parameters["filter"], **(overrides or {})}
        params = {k: v for k, v in params.items()
                  if any(p.name == k for p in cls.parameters) or k in (overrides or {})}
        component = cls(**params)
        component.initialize(0.0)
    cls = type(component)
    if names is None:
        names = [p.name for p in cls.outputs if p.type != "String"]
    n = len(sensors.time) if stop_row is None else stop_row
    rows_wanted = (set(sensors.epoch_rows.tolist()) if record == "epochs" else None)
    rows, values = [], []
    h = sensors.h
    elapsed = 0.0
    for k in range(start_row, n):
        u = sensors.inputs_at(k)
        t0 = _time.perf_counter()
        out = component.step(k * h, h, u)
        elapsed += _time.perf_counter() - t0
        if rows_wanted is None or k in rows_wanted:
            rows.append(k)
            values.append([out[name] for name in names])
    arr = np.array(values, dtype=float) if values else np.zeros((0, len(names)))
    run = FilterRun(sensors, cls.model_name, np.array(rows, dtype=int),
                    {name: arr[:, i] for i, name in enumerate(names)},
                    elapsed / max(1, n - start_row))
    run.component = component
    return run


def rms(a, axis=0):
    return np.sqrt(np.mean(np.asarray(a) ** 2, axis=axis))


def rms_table(run: FilterRun, t_from: float = 0.0) -> Dict[str, np.ndarray]:
    """RMS of position (N/E/D m) and velocity (N/E/D m/s) errors at the GNSS epochs after
    ``t_from`` s."""
    sel = run.sensors.time[run.rows] > t_from - 1e-9
    return {"position_ned_m": rms(run.position_error_ned()[sel]),
            "velocity_ned_mps": rms(run.velocity_error_ned()[sel])}


if __name__ == "__main__":  # quick look: python tests/scenario_runner.py aircraft_500s Kf Iakf
    import sys
    scenario = sys.argv[1] if len(sys.argv) > 1 else "aircraft_500s"
    sensors = simulate_sensors(MODELS / scenario)
    for model in sys.argv[2:] or ["Kf"]:
        run = run_filter(sensors, components.REGISTRY[model])
        table = rms_table(run)
        print(model, np.round(table["position_ned_m"], 3), np.round(table["velocity_ned_mps"], 4),
              f"{run.seconds_per_step * 1e6:.0f} us/step")
