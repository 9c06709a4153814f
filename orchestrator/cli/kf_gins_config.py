"""``navfmu convert kf-gins --config``: KF-GINS's YAML configuration as a filter ``.ssv``.

KF-GINS (i2Nav, Wuhan University) configures a run with a YAML file (its
``dataset/kf-gins.yaml``).  What our INS/GNSS filters can take is written as their parameters
(SI units and the filters' own conventions, converted here once):

=====================  ========================================================================
KF-GINS key            filter parameter
=====================  ========================================================================
``initpos``            ``init_lat``, ``init_lon`` (deg -> rad), ``init_h`` [m]
``initvel``            ``init_vn/ve/vd`` [m/s]
``initatt``            ``init_roll/pitch/yaw`` (deg -> rad, yaw wrapped to (-180, 180] deg)
``initposstd``         ``p0_pos`` [m]: the largest of the three (one sigma for every axis)
``initvelstd``         ``p0_vel`` [m/s]: the largest of the three
``initattstd``         ``p0_att_level`` (the larger of roll, pitch), ``p0_att_yaw`` (deg -> rad)
``initbgstd``          ``p0_gyro_bias_dph`` (largest; default ``imunoise.gbstd``, as KF-GINS)
``initbastd``          ``p0_accel_bias_ug`` (mGal -> ug; default ``imunoise.abstd``)
``imunoise.arw``       ``q_gyro_arw_dpsh`` [deg/sqrt(h)]
``imunoise.vrw``       ``q_accel_vrw_ugpsHz`` (m/s/sqrt(h) -> ug/sqrt(Hz))
``imunoise.gbstd``     ``q_gyro_bias_instability_dph`` [deg/h]
``imunoise.abstd``     ``q_accel_bias_instability_ug`` (mGal -> ug)
``imunoise.corrtime``  ``q_gyro_bias_tau_s``, ``q_accel_bias_tau_s`` (h -> s)
``antlever``           ``lever_arm_x/y/z`` [m], body forward-right-down
(GNSS file)           ``r_from_receiver`` = true; ``measurement`` = ``position`` (7 columns) or
                       ``position_velocity`` with ``r_vel_n/e/d`` [m/s] (13 columns)
(not in KF-GINS)       ``imu_noise_factor``: 30 for a MEMS gyro (``arw`` 0.1 deg/sqrt(h) or
                       more; its figures are a datasheet's, and a real MEMS IMU does worse),
                       else 1 (:mod:`navcore.filters.process_noise_factor`);
                       ``gnss_corr_time`` = 4.5 s, the correlation time of an RTK receiver's
                       errors measured on a real drive (:mod:`navcore.filters.correlated_gnss`;
                       ``docs/guide/your_real_log.md`` measures one's own)
``starttime``          not a filter parameter: the replay's ``--start`` (stated in the
                       ``.ssv`` and printed), with ``endtime`` (-1: the end) as ``--stop``
=====================  ========================================================================

Not representable, and said so in the ``.ssv`` and on the command's output: scale-factor
states (``gsstd``, ``asstd``, ``initgyrscale``, ``initaccscale``: the filters have 15 states,
no scale factors) and a non-zero initial bias (``initgyrbias``, ``initaccbias``: the filters
start with zero bias).  Per-axis values become the largest of the three (a conservative
sigma).  KF-GINS weights each fix with the receiver's own sigmas: the ``.ssv`` sets
``r_from_receiver`` (the log's per-epoch ``std_n/e/d`` as R).  With a 7-column GNSS file
(positions only) ``measurement`` = ``position``; a 13-column file has the velocity and its
sigmas too (kept in the log as ``vn/ve/vd`` and ``std_vn/ve/vd``): the ``.ssv`` then sets
``measurement`` = ``position_velocity`` and ``r_vel_n/e/d`` [m/s] to the median of the file's
velocity sigmas per axis (:func:`with_gnss_velocity`: the filters take per-fix sigmas for the
position only, so the velocity's R is one value per axis).
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Dict, List

import numpy as np
from navcore.filters.correlated_gnss import MEASURED_CORR_TIME
from navcore.filters.process_noise_factor import recommended_factor
from navcore.ins.constants import UG

from ..errors import NavfmuError
from .cli_options import read_yaml_mapping

#: 1 mGal [m/s^2]
MGAL = 1e-5
SSV_NAME = "filter.ssv"


def _numbers(path, config, key, n=3) -> List[float]:
    value = config.get(key)
    if isinstance(value, (int, float)) and n == 1:
        value = [value]
    if (not isinstance(value, list) or len(value) != n
            or not all(isinstance(x, (int, float)) and math.isfinite(x) for x in value)):
        raise NavfmuError(f"{path}: key '{key}': expected {n} finite number"
                          f"{'s' if n > 1 else ''}, got {value!r}")
    return [float(x) for x in value]


def read_config(path) -> Dict[str, Any]:
    """The parameters of a KF-GINS YAML file (module docstring): ``parameters`` (name ->
    value), ``start``/``stop`` (or None) and ``notes`` (what was left out)."""
    path = Path(path)
    config = read_yaml_mapping(path, "KF-GINS keys (initpos, imunoise, ...)")
    noise = config.get("imunoise")
    if not isinstance(noise, dict):
        raise NavfmuError(f"{path}: key 'imunoise': expected a mapping (arw, vrw, gbstd, abstd, "
                          "corrtime)")
    where = f"{path} imunoise"
    lat, lon, h = _numbers(path, config, "initpos")
    if not (-90.0 <= lat <= 90.0 and -180.0 <= lon <= 360.0):
        raise NavfmuError(f"{path}: key 'initpos': latitude {lat:g} deg, longitude {lon:g} "
                          "deg: expected a latitude in [-90, 90] and a longitude in "
                          "[-180, 360] deg")
    roll, pitch, yaw = (math.radians(x) for x in _numbers(path, config, "initatt"))
    att_std = [math.radians(x) for x in _numbers(path, config, "initattstd")]
    gb = max(_numbers(where, noise, "gbstd"))
    ab = max(_numbers(where, noise, "abstd"))
    tau = _numbers(where, noise, "corrtime", 1)[0] * 3600.0
    p = {"init_lat": math.radians(lat), "init_lon": math.radians(lon), "init_h": h,
         **dict(zip(("init_vn", "init_ve", "init_vd"), _numbers(path, config, "initvel"))),
         "init_roll": roll, "init_pitch": pitch,
         "init_yaw": math.atan2(math.sin(yaw), math.cos(yaw)),
         "p0_pos": max(_numbers(path, config, "initposstd")),
         "p0_vel": max(_numbers(path, config, "initvelstd")),
         "p0_att_level": max(att_std[:2]), "p0_att_yaw": att_std[2],
         "p0_gyro_bias_dph": (max(_numbers(path, config, "initbgstd"))
                              if "initbgstd" in config else gb),
         "p0_accel_bias_ug": (max(_numbers(path, config, "initbastd"))
                              if "initbastd" in config else ab) * MGAL / UG,
         "q_gyro_arw_dpsh": max(_numbers(where, noise, "arw")),
         "q_accel_vrw_ugpsHz": max(_numbers(where, noise, "vrw")) / 60.0 / UG,
         "q_gyro_bias_instability_dph": gb, "q_gyro_bias_tau_s": tau,
         "q_accel_bias_instability_ug": ab * MGAL / UG, "q_accel_bias_tau_s": tau,
         **dict(zip(("lever_arm_x", "lever_arm_y", "lever_arm_z"),
                    _numbers(path, config, "antlever"))),
         "measurement": "position", "r_from_receiver": True,
         "imu_noise_factor": recommended_factor(max(_numbers(where, noise, "arw"))),
         "gnss_corr_time": MEASURED_CORR_TIME}
    notes = [f"{key} (scale factors are not filter states)" for key in
             ("gsstd", "asstd") if key in noise]
    notes += [f"{key} = {config[key]} (the filters start with zero bias)"
              for key in ("initgyrbias", "initaccbias")
              if key in config and any(_numbers(path, config, key))]
    start = config.get("starttime")
    stop = config.get("endtime")
    for key, value in (("starttime", start), ("endtime", stop)):
        if value is not None and not isinstance(value, (int, float)):
            raise NavfmuError(f"{path}: key '{key}': expected a number, got {value!r}")
    return {"parameters": p, "notes": notes, "source": str(path),
            "start": None if start is None else float(start),
            "stop": None if stop is None or stop < 0 else float(stop)}


def with_gnss_velocity(settings, gnss) -> Dict[str, Any]:
    """``settings`` for a log whose GNSS table ``gnss`` has the velocity and its sigmas:
    ``measurement`` = ``position_velocity``, ``r_vel_n/e/d`` the median ``std_vn/ve/vd``
    (module docstring); unchanged without them."""
    if "std_vn" not in gnss:
        return settings
    valid = gnss["valid"] == 1
    r_vel = {f"r_vel_{a}": float(np.median(gnss[f"std_v{a}"][valid])) for a in "ned"}
    return {**settings, "parameters": {**settings["parameters"],
                                       "measurement": "position_velocity", **r_vel}}


def seconds_text(t) -> str:
    """A time as the shortest text that reads back as the same float (``408640.97``, never
    the ``%g`` rounding ``408641``), a whole number without ``.0``."""
    text = repr(float(t))
    return text[:-2] if text.endswith(".0") else text


def _or_none(t) -> str:
    return "none" if t is None else seconds_text(t)


def _real_sensor_text(p) -> str:
    """Why the .ssv sets ``imu_noise_factor`` and ``gnss_corr_time`` (module docstring)."""
    grade = ("a MEMS gyro (arw >= 0.1 deg/sqrt(h)): its figures are a datasheet's, a real MEMS "
             "IMU does worse" if p["imu_noise_factor"] != 1.0 else
             "a gyro better than MEMS: its figures as given")
    return (f"imu_noise_factor {p['imu_noise_factor']:g} for {grade}; gnss_corr_time "
            f"{p['gnss_corr_time']:g} s for a receiver's errors correlated from fix to fix "
            "(both measured on a real drive; docs/guide/your_real_log.md has the recipes)")


def remove_stale_ssv(destination) -> str:
    """A log replaced without ``--config`` keeps no ``filter.ssv`` of the log it replaced
    (that file's initial state and start time belong to the old data): removed, said in a
    line (empty when there was none)."""
    ssv = Path(destination) / SSV_NAME
    if not ssv.is_file():
        return ""
    ssv.unlink()
    return (f"removed {ssv}: the configuration of the replaced log (give --config to write "
            "this log's)\n")


def write_filter_ssv(settings, destination) -> str:
    """Write ``destination/filter.ssv`` from :func:`read_config`'s ``settings``; one line
    saying what was written and how to replay with it."""
    from ..model.ssv_writer import ssv_text
    from ..results.run_results import atomic_write

    typed = {k: ["String" if isinstance(v, str) else "Boolean" if isinstance(v, bool)
                 else "Real", v] for k, v in settings["parameters"].items()}
    text = ssv_text("filter", {}, typed)
    head, rest = text.split("\n", 1)
    body = (f"from {settings['source']}; KF-GINS starttime {_or_none(settings['start'])} s and "
            f"endtime {_or_none(settings['stop'])} s: the replay's start and stop options; "
            + _real_sensor_text(settings["parameters"])
            + (f"; not representable: {'; '.join(settings['notes'])}"
               if settings["notes"] else ""))
    comment = f"<!-- {body.replace('--', '- -')} -->"     # a comment holds no double hyphen
    ssv = Path(destination) / SSV_NAME
    atomic_write(ssv, lambda f: f.write(head + "\n" + comment + "\n" + rest))
    start = "" if settings["start"] is None else f" --start {seconds_text(settings['start'])}"
    stop = "" if settings["stop"] is None else f" --stop {seconds_text(settings['stop'])}"
    left = (f"; left out: {'; '.join(settings['notes'])}" if settings["notes"] else "")
    return (f"wrote {ssv}: the filter's initial state, noise and lever arm; bind it to the "
            f"filter and replay with --replay {destination}{start}{stop}{left}")
