"""Hostile host calls on the built FMUs through raw fmpy calls, in a process of its own.

``python tests/fmi_probe.py DIST OUT.json`` runs every case of :data:`CASES` on a fresh
instance and writes, per case, the status of the hostile call (0 = fmi2OK, 2 = fmi2Discard,
3 = fmi2Error, 4 = fmi2Fatal), the values it returned, the messages logged, and the status
of the legal calls that follow.  Run in a subprocess by tests/test_fmi_host.py: a crash of
the host shows up there as a return code, not as a dead test process.
"""
from __future__ import annotations

import json
import math
import sys
from pathlib import Path

from fmpy.fmi1 import FMICallException

sys.path.insert(0, str(Path(__file__).resolve().parent))
from test_fmus import _Fmu  # noqa: E402

LAT = math.radians(40.0)


def _status(call):
    """(status, result) of an fmpy call."""
    try:
        return 0, call()
    except FMICallException as exc:
        return exc.status, None


def _imu(f, k, dt=0.01):
    f.set("imu_time", (k + 1) * dt)
    f.set("imu_dt", dt)
    f.set("imu_dvel_z", -9.8 * dt)


def _kf(dist, logs):
    return _Fmu(dist / "Kf.fmu", "kf", {"init_lat": LAT, "init_h": 100.0}, logs=logs)


def case_unknown_value_reference(dist, logs):
    f = _kf(dist, logs)
    _imu(f, 0)
    status, values = _status(lambda: f.fmu.getReal([99999, f.vr["nav_lat"]]))
    return f, status, values, 0


def case_wrong_type_value_reference(dist, logs):
    f = _kf(dist, logs)
    status, values = _status(lambda: f.fmu.getReal([f.vr["gnss_epoch"]]))
    return f, status, values, 0


def case_set_output(dist, logs):
    f = _kf(dist, logs)
    before = f.reals(["nav_lat"])[0]
    status, _ = _status(lambda: f.fmu.setReal([f.vr["nav_lat"]], [0.1]))
    return f, status, [before, f.reals(["nav_lat"])[0]], 0


def case_set_fixed_parameter(dist, logs):
    f = _kf(dist, logs)
    status, _ = _status(lambda: f.fmu.setReal([f.vr["init_lat"]], [0.1]))
    return f, status, None, 0


def case_step_back(dist, logs):
    f = _kf(dist, logs)
    _imu(f, 0)
    f.fmu.doStep(0.0, 0.01)
    status, _ = _status(lambda: f.fmu.doStep(-5.0, 0.01))
    return f, status, None, 1


def case_step_ahead(dist, logs):
    f = _kf(dist, logs)
    _imu(f, 0)
    f.fmu.doStep(0.0, 0.01)
    status, _ = _status(lambda: f.fmu.doStep(10.0, 0.01))
    return f, status, None, 1


def case_step_size_not_positive(dist, logs):
    f = _kf(dist, logs)
    status, _ = _status(lambda: f.fmu.doStep(0.0, -0.01))
    return f, status, None, 0


def case_skipped_imu_interval(dist, logs):
    f = _kf(dist, logs)
    _imu(f, 0)
    f.fmu.doStep(0.0, 0.01)
    _imu(f, 2)                      # imu_time jumps from 0.01 to 0.03: one interval lost
    status, _ = _status(lambda: f.fmu.doStep(0.01, 0.01))
    return f, status, None, 2


CASES = {name[5:]: fn for name, fn in globals().items() if name.startswith("case_")}


def run_case(dist, fn):
    logs = []
    f, status, values, k_next = fn(dist, logs)
    n_logs = len(logs)
    # then legal calls: a doStep from where the last successful one ended, twice (the
    # inputs are refused too after an error that put the instance into the error state)
    _status(lambda: _imu(f, k_next))
    follow_1, _ = _status(lambda: f.fmu.doStep(k_next * 0.01, 0.01))
    t2 = (k_next + 1) * 0.01 if follow_1 == 0 else k_next * 0.01
    _status(lambda: _imu(f, round(t2 / 0.01)))
    follow_2, _ = _status(lambda: f.fmu.doStep(t2, 0.01))
    get_status, nav = _status(lambda: f.reals(["nav_time", "nav_lat"]).tolist())
    f.close()
    return {"status": status, "values": None if values is None else [float(v) for v in values],
            "logs": logs[:n_logs], "later_logs": logs[n_logs:], "follow": [follow_1, follow_2],
            "get_after": get_status, "nav_after": nav}


def main(dist, out):
    results = {name: run_case(Path(dist), fn) for name, fn in CASES.items()}
    Path(out).write_text(json.dumps(results, indent=1, default=str))


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
