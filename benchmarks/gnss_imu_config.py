"""A configuration file of rtklibexplorer/GNSS_IMU (``drive_config.py``, ``walk_config.py``)
as navfmu's filter parameters, IMU preparation and outage schedule.

The peer's configurations are Python modules; this reads them without running them: the
module's top-level assignments of literals (numbers, lists, ``np.array([...])``, sums and
products of them, names assigned before, ``+=``), and attribute assignments such as
``init.att_unc = [...]`` under the dotted name.  Anything else (imports, ``Init()``) is
skipped, so a config is read the same whatever the peer's code does.

What each of the peer's names becomes (its ``GNSS_IMU.py`` says how it uses them):

* ``imu_misalign`` [deg], ``imu_t_off`` [s], ``imu_sample_rate`` [Hz]: the sensor-to-body
  rotation, the logging delay and the IMU grid of ``real_drive.py``.
* ``gnss_offset - imu_offset`` (forward, right, down from the IMU) [m]: the antenna's lever
  arm ``lever_arm_x/y/z``; ``-imu_offset``: the NHC point ``nhc_lever_x/y/z`` (the system
  origin, where the peer applies its non-holonomic constraint).
* Process noise: the peer's standard deviations are its densities times ``sqrt(imu_sample_rate)``
  times ``imu_noise_factors`` (attitude, velocity, accel bias, gyro bias), which is its
  effective density.  ``q_gyro_arw_dpsh`` and ``q_accel_vrw_ugpsHz`` take it as it is; the
  bias random walks (densities ``q``) become the first-order Gauss-Markov instabilities
  ``sigma = q sqrt(tau / 2)`` over ``tau`` (:data:`BIAS_TAU_S`; the two agree over times
  short against tau); ``imu_noise_factor`` is 1 (the factors are already in).
* ``init.att_unc`` [deg] (roll, pitch, yaw), ``init.bias_gyro_unc`` [deg/s],
  ``init.bias_acc_unc`` [m/s^2]: ``p0_att_level`` (the larger level sigma), ``p0_att_yaw``,
  ``p0_gyro_bias_dph``, ``p0_accel_bias_ug``.
* ``float_err_gain``, ``single_err_gain``: the fix sigmas' factors of ``convert rtklib
  --sigma-scale``.
* The fixes: the peer's GNSS update takes the position and the velocity of each fix, each
  with the receiver's sigmas times ``gnss_noise_factors`` (position, velocity):
  ``measurement = position_velocity``, ``r_from_receiver`` for the position; navfmu's
  filters take the velocity's R as the fixed ``r_vel_n/e/d``, which
  :func:`velocity_sigmas` makes the median of the receiver's velocity sigmas over the log's
  fixes times the factor.
* ``yaw_align_min_vel`` [m/s]: ``init_speed_min`` (the speed from which the course gives
  the heading).
* ZUPT: ``zupt_vel_SD`` [m/s] -> ``zupt_sigma``, ``zaru_gyro_SD`` [deg/s] -> ``zaru_sigma``;
  the detector's ``zupt_epcoh_count`` samples at ``imu_sample_rate`` -> ``stationary_window_s``,
  ``zupt_accel_thresh`` [m/s^2] (each sample's ``| |f| - g |``) -> ``stationary_accel_std``,
  ``zupt_gyro_thresh`` [deg/s] (each sample's ``|w|``) -> ``stationary_rate_rms``: a window
  whose every sample passes the peer's test passes navfmu's (a spread around the mean is at
  most the largest deviation; an RMS at most the largest value).
* NHC: ``nhc_vel_SD``, ``nhc_vel_SD_coast`` [m/s] -> ``nhc_sigma``, ``nhc_sigma_outage``;
  ``nhc_min_vel`` [m/s] -> ``nhc_speed_min``; ``nhc_gyro_thesh`` [deg/s] -> ``nhc_rate_max``.
* ``start_coast``, ``coast_len``, ``end_coast`` [s]: the outage schedule (:func:`schedule`).
"""
from __future__ import annotations

import ast
import math
from pathlib import Path

import numpy as np

G0 = 9.80665                       # m/s^2 per g
#: [s] correlation time given the bias instabilities made from the peer's random walks
BIAS_TAU_S = 100.0
#: the peer's GNSS quality numbers of its error gains (RTKLIB's Q)
_GAINS = {"float": "float_err_gain", "single": "single_err_gain"}


class ConfigError(ValueError):
    """A configuration that cannot be read or lacks a value this needs."""


def _value(node, names):
    """The value of an expression of literals, lists, ``np.array``, + - * / and names."""
    if isinstance(node, ast.Constant) and isinstance(node.value, (int, float, bool, str)):
        return node.value
    if isinstance(node, (ast.List, ast.Tuple)):
        return [_value(e, names) for e in node.elts]
    if isinstance(node, ast.Name) and node.id in names:      # also a dotted name of +=
        return names[node.id]
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
        v = _value(node.operand, names)
        return _elementwise(lambda a: -a if isinstance(node.op, ast.USub) else a, v)
    if isinstance(node, ast.BinOp) and type(node.op) in _OPS:
        return _combine(_OPS[type(node.op)], _value(node.left, names), _value(node.right, names))
    if (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
            and node.func.attr in ("array", "asarray") and len(node.args) == 1):
        return _value(node.args[0], names)
    raise ConfigError(f"not a literal: {ast.unparse(node)[:40]}")


_OPS = {ast.Add: lambda a, b: a + b, ast.Sub: lambda a, b: a - b,
        ast.Mult: lambda a, b: a * b, ast.Div: lambda a, b: a / b}


def _elementwise(f, v):
    return [_elementwise(f, x) for x in v] if isinstance(v, list) else f(v)


def _combine(op, a, b):
    """``op`` element by element, as numpy does on arrays of one shape or with a scalar."""
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            raise ConfigError("arrays of different lengths")
        return [_combine(op, x, y) for x, y in zip(a, b)]
    if isinstance(a, list):
        return [_combine(op, x, b) for x in a]
    if isinstance(b, list):
        return [_combine(op, a, y) for y in b]
    return op(a, b)


def _target(node):
    """``name`` or ``obj.attr`` of an assignment's target, else None."""
    if isinstance(node, ast.Name):
        return node.id
    if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name):
        return f"{node.value.id}.{node.attr}"
    return None


def read_config(path: Path) -> dict:
    """The literal top-level assignments of the peer's configuration ``path`` (module
    docstring), name -> value (lists for arrays)."""
    try:
        tree = ast.parse(Path(path).read_text(), filename=str(path))
    except (OSError, SyntaxError, ValueError) as exc:
        raise ConfigError(f"{path}: cannot read: {exc}") from None
    names = {}
    for stmt in tree.body:
        if isinstance(stmt, ast.Assign) and len(stmt.targets) == 1:
            key, node = _target(stmt.targets[0]), stmt.value
        elif isinstance(stmt, ast.AugAssign) and type(stmt.op) in _OPS:
            key = _target(stmt.target)
            node = ast.BinOp(ast.Name(key, ast.Load()), stmt.op, stmt.value)
        else:
            continue
        if key is None:
            continue
        try:
            names[key] = _value(node, names)
        except ConfigError:
            names.pop(key, None)          # a value this cannot read is not a value
    return names


def _need(cfg: dict, name: str, path):
    if name not in cfg:
        raise ConfigError(f"{path}: no value for {name!r}")
    return cfg[name]


def filter_parameters(cfg: dict, path="config") -> dict:
    """navfmu's ``filter.*`` parameters of the peer's configuration ``cfg`` (module
    docstring)."""
    need = lambda name: _need(cfg, name, path)  # noqa: E731
    root_hz = math.sqrt(need("imu_sample_rate"))
    f_att, f_vel, f_ba, f_bg = need("imu_noise_factors")[:4]
    half_tau = math.sqrt(BIAS_TAU_S / 2.0)
    lever = [g - i for g, i in zip(need("gnss_offset"), need("imu_offset"))]
    att = need("init.att_unc")
    out = {
        "filter.imu_noise_factor": 1.0, "filter.measurement": "position_velocity",
        "filter.q_gyro_arw_dpsh": need("gyro_noise_PSD") * 60.0 * root_hz * f_att,
        "filter.q_accel_vrw_ugpsHz": need("accel_noise_PSD") * root_hz * f_vel,
        "filter.q_accel_bias_instability_ug": need("accel_bias_PSD") * root_hz * f_ba * half_tau,
        "filter.q_gyro_bias_instability_dph": (need("gyro_bias_PSD") * 3600.0 * root_hz * f_bg
                                               * half_tau),
        "filter.q_accel_bias_tau_s": BIAS_TAU_S, "filter.q_gyro_bias_tau_s": BIAS_TAU_S,
        "filter.p0_att_level": math.radians(max(att[0], att[1])),
        "filter.p0_att_yaw": math.radians(att[2]),
        "filter.p0_gyro_bias_dph": need("init.bias_gyro_unc") * 3600.0,
        "filter.p0_accel_bias_ug": need("init.bias_acc_unc") / G0 * 1e6,
        **{f"filter.lever_arm_{a}": float(v) for a, v in zip("xyz", lever)},
        **{f"filter.nhc_lever_{a}": 0.0 - v for a, v in zip("xyz", need("imu_offset"))},
    }
    optional = {
        "yaw_align_min_vel": ("filter.init_speed_min", 1.0),
        "zupt_vel_SD": ("filter.zupt_sigma", 1.0),
        "zaru_gyro_SD": ("filter.zaru_sigma", math.radians(1.0)),
        "zupt_accel_thresh": ("filter.stationary_accel_std", 1.0),
        "zupt_gyro_thresh": ("filter.stationary_rate_rms", math.radians(1.0)),
        "nhc_vel_SD": ("filter.nhc_sigma", 1.0),
        "nhc_vel_SD_coast": ("filter.nhc_sigma_outage", 1.0),
        "nhc_min_vel": ("filter.nhc_speed_min", 1.0),
        "nhc_gyro_thesh": ("filter.nhc_rate_max", math.radians(1.0)),
    }
    for name, (key, unit) in optional.items():
        if name in cfg:
            out[key] = cfg[name] * unit
    if "zupt_epcoh_count" in cfg:
        out["filter.stationary_window_s"] = cfg["zupt_epcoh_count"] / need("imu_sample_rate")
    return out


def velocity_sigmas(cfg: dict, gnss) -> dict:
    """``r_vel_n/e/d`` [m/s]: per axis the median over the valid fixes of ``gnss`` (a sensor
    log's GNSS table) of the receiver's velocity sigmas, times the config's velocity factor
    (``gnss_noise_factors[1]``); empty without velocity sigmas in the log."""
    if "std_vn" not in gnss:
        return {}
    valid = gnss["valid"] > 0.5
    factor = float(cfg.get("gnss_noise_factors", [1.0, 1.0])[1])
    return {f"filter.r_vel_{a}": factor * float(np.median(gnss[f"std_v{a}"][valid]))
            for a in "ned"}


def sigma_scale(cfg: dict) -> str:
    """``convert rtklib --sigma-scale`` of the peer's error gains (``fix=1,float=2,...``)."""
    return ",".join(["fix=1"] + [f"{q}={cfg[name]!r}" for q, name in _GAINS.items()
                                 if name in cfg])


def imu_preparation(cfg: dict, path="config"):
    """(sensor-to-body Euler angles [deg], logging delay [s], sample rate [Hz])."""
    return ([float(x) for x in _need(cfg, "imu_misalign", path)],
            float(cfg.get("imu_t_off", 0.0)), float(_need(cfg, "imu_sample_rate", path)))


def schedule(cfg: dict, path="config"):
    """(first outage's start after the first epoch, length, period, margin before the last
    epoch) [s]: the peer's ``start_coast``, ``coast_len``, ``end_coast``; its ``GNSS_IMU.py``
    waits twice the length between outages, so the period is three lengths."""
    length = float(_need(cfg, "coast_len", path))
    return (float(_need(cfg, "start_coast", path)), length, 3.0 * length,
            float(_need(cfg, "end_coast", path)))
