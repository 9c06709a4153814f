"""Metric definitions: navigation errors of a filter against the truth, as in the papers' tables.

This is the only navigation knowledge of the master.  It reads recorded columns by the signal
names of the contract (``truth_*`` of the truth source, ``nav_*``/``std_*``/``nis`` of a
filter) and aligns truth and estimate by their times of validity (``truth_time``,
``nav_time``), interpolating the truth linearly at the filter's times, so the numbers do not
depend on the master's stepping order.

Definitions (errors are estimate - truth):

* position error in NED metres: north = dlat (R_N + h), east = dlon (R_E + h) cos(lat),
  down = -dh.  Paper 001's table lists "longitude, latitude, height" = east, north, up.
* velocity error per NED axis [m/s] (reported east/north/up as in paper 001).
* attitude error: roll, pitch, yaw differences wrapped to (-pi, pi] [deg], and the error angle
  phi (NED) with C_bn_est = (I - [phi x]) C_bn_true for NEES.
* RMS per axis over the window ``[t0, t1]`` of nav_time; max |error| per axis.
* NEES per group (position, velocity, attitude) from the filter's 1-sigma outputs (diagonal):
  mean over the window of sum_i (e_i / sigma_i)^2, to compare with the group's dimension 3.
* NIS: mean of ``nis`` over the update epochs, with the two-sided 95 % band of the mean of
  N chi-square(dof) samples: chi2.ppf(0.025, N dof)/N .. chi2.ppf(0.975, N dof)/N.
"""
from __future__ import annotations

import math

import numpy as np
from scipy import stats

from navcore.earth import radii as _radii
from navcore.rotations import wrap_angle as _wrap

from .errors import NavfmuError

AXES = ("n", "e", "d")


def _dcm(roll, pitch, yaw):
    """C_bn for arrays of ZYX Euler angles, shape (N, 3, 3)."""
    cr, sr, cp, sp, cy, sy = (np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch),
                              np.cos(yaw), np.sin(yaw))
    C = np.empty(roll.shape + (3, 3))
    C[..., 0, 0] = cy * cp
    C[..., 0, 1] = cy * sp * sr - sy * cr
    C[..., 0, 2] = cy * sp * cr + sy * sr
    C[..., 1, 0] = sy * cp
    C[..., 1, 1] = sy * sp * sr + cy * cr
    C[..., 1, 2] = sy * sp * cr - cy * sr
    C[..., 2, 0] = -sp
    C[..., 2, 1] = cp * sr
    C[..., 2, 2] = cp * cr
    return C


def find_component(results, prefix, required):
    """Name of the recorded component whose columns include ``prefix + required``."""
    for comp in results.components:
        names = results.columns[comp]
        if all(prefix + r in names for r in required):
            return comp
    raise NavfmuError(f"no component records the '{prefix}*' signals {', '.join(required)}; "
                      "metrics need a truth source and a filter with the navigation contract")


def navigation_errors(results, filter_name, truth_name=None):
    """Aligned errors of ``filter_name`` against the truth; a dict of arrays over nav_time."""
    truth_name = truth_name or find_component(results, "truth_", ("time", "lat", "lon", "h"))
    col = results.column
    t_nav = col(filter_name, "nav_time")
    t_truth = col(truth_name, "truth_time")
    # keep the first sample of each distinct truth time (held outputs repeat)
    keep = np.concatenate([[True], np.diff(t_truth) > 0])
    t_truth = t_truth[keep]
    inside = (t_nav >= t_truth[0] - 1e-9) & (t_nav <= t_truth[-1] + 1e-9)

    def truth(var, angle=False):
        y = col(truth_name, "truth_" + var)[keep]
        if angle:
            return _wrap(np.interp(t_nav, t_truth, np.unwrap(y)))
        return np.interp(t_nav, t_truth, y)

    lat_t, lon_t, h_t = truth("lat"), truth("lon"), truth("h")
    rn, re = _radii(lat_t)
    e = {"time": t_nav, "valid": inside}
    e["pos_n"] = (col(filter_name, "nav_lat") - lat_t) * (rn + h_t)
    e["pos_e"] = _wrap(col(filter_name, "nav_lon") - lon_t) * (re + h_t) * np.cos(lat_t)
    e["pos_d"] = -(col(filter_name, "nav_h") - h_t)
    for a in AXES:
        e["vel_" + a] = col(filter_name, "nav_v" + a) - truth("v" + a)
    angles_t = [truth(a, angle=True) for a in ("roll", "pitch", "yaw")]
    angles_e = [col(filter_name, "nav_" + a) for a in ("roll", "pitch", "yaw")]
    for a, at, ae in zip(("roll", "pitch", "yaw"), angles_t, angles_e):
        e["att_" + a] = _wrap(ae - at)
    # phi with C_est = (I - [phi x]) C_true:  [phi x] = I - C_est C_true'  (skew part)
    D = _dcm(*angles_e) @ np.swapaxes(_dcm(*angles_t), -1, -2)
    e["phi_n"] = 0.5 * (D[:, 2, 1] - D[:, 1, 2]) * -1.0
    e["phi_e"] = 0.5 * (D[:, 0, 2] - D[:, 2, 0]) * -1.0
    e["phi_d"] = 0.5 * (D[:, 1, 0] - D[:, 0, 1]) * -1.0
    return e


def _window_mask(e, window):
    t = e["time"]
    mask = e["valid"].copy()
    if window is not None:
        t0, t1 = window
        mask &= (t >= t0 - 1e-9) & (t <= t1 + 1e-9)
    if not mask.any():
        raise NavfmuError(f"the metric window {window} contains no sample of the filter output")
    return mask


def filter_metrics(results, filter_name, window=None, truth_name=None):
    """All metrics of one filter as a JSON-ready dict (see the module docstring)."""
    e = navigation_errors(results, filter_name, truth_name)
    mask = _window_mask(e, window)
    t = e["time"][mask]
    out = {"window_s": [float(t[0]), float(t[-1])], "samples": int(mask.sum())}
    rms = lambda x: float(np.sqrt(np.mean(x[mask] ** 2)))  # noqa: E731
    peak = lambda x: float(np.max(np.abs(x[mask])))  # noqa: E731
    out["position_rms_m"] = {a: rms(e["pos_" + a]) for a in AXES}
    out["velocity_rms_mps"] = {a: rms(e["vel_" + a]) for a in AXES}
    out["attitude_rms_deg"] = {a: math.degrees(rms(e["att_" + a]))
                               for a in ("roll", "pitch", "yaw")}
    out["position_max_m"] = {a: peak(e["pos_" + a]) for a in AXES}
    out["velocity_max_mps"] = {a: peak(e["vel_" + a]) for a in AXES}
    out["attitude_max_deg"] = {a: math.degrees(peak(e["att_" + a]))
                               for a in ("roll", "pitch", "yaw")}
    col = results.column
    names = results.columns[filter_name]
    if all(f"std_p{a}" in names for a in AXES):
        groups = {"position": ("pos_", "std_p"), "velocity": ("vel_", "std_v"),
                  "attitude": ("phi_", "std_att_")}
        nees = {}
        for g, (err, std) in groups.items():
            sig = np.stack([col(filter_name, std + a)[mask] for a in AXES])
            err_ = np.stack([e[err + a][mask] for a in AXES])
            with np.errstate(divide="ignore", invalid="ignore"):
                ratio2 = np.where(sig > 0, (err_ / sig) ** 2, np.nan)
            nees[g] = float(np.nanmean(ratio2.sum(axis=0)))
        out["nees"] = nees
    if "nis" in names and "updated" in names:
        upd = (col(filter_name, "updated") > 0.5) & mask
        if upd.any():
            nis = col(filter_name, "nis")[upd]
            dof = int(round(float(np.median(col(filter_name, "nis_dof")[upd]))))
            n = int(upd.sum())
            out["nis"] = {"mean": float(nis.mean()), "dof": dof, "updates": n,
                          "band95": [float(stats.chi2.ppf(0.025, n * dof) / n),
                                     float(stats.chi2.ppf(0.975, n * dof) / n)]}
    if filter_name in getattr(results, "step_time_s", {}):
        out["time_per_step_ms"] = 1e3 * float(results.step_time_s[filter_name])
    return out


def rms_table(rows, reference=None):
    """Text table in the shape of paper 001's Table 1, plus attitude RMS.

    ``rows``: list of (label, metrics dict); ``reference``: list of (label, pos_enu, vel_enu)
    from a paper, printed under our rows.
    """
    labels = [label for label, _ in rows] + [label for label, _, _ in reference or ()]
    w = max([len("RMS error")] + [len(x) for x in labels])
    head = (f"{'RMS error':{w}s} {'pos E/lon':>10s} {'pos N/lat':>10s} {'pos U/h':>10s} "
            f"{'vel E':>8s} {'vel N':>8s} {'vel U':>8s} {'roll':>7s} {'pitch':>7s} {'yaw':>7s}")
    units = (f"{'':{w}s} {'[m]':>10s} {'[m]':>10s} {'[m]':>10s} {'[m/s]':>8s} {'[m/s]':>8s} "
             f"{'[m/s]':>8s} {'[deg]':>7s} {'[deg]':>7s} {'[deg]':>7s}")
    lines = [head, units]
    for label, m in rows:
        p, v, a = m["position_rms_m"], m["velocity_rms_mps"], m["attitude_rms_deg"]
        lines.append(f"{label:{w}s} {p['e']:10.4f} {p['n']:10.4f} {p['d']:10.4f} "
                     f"{v['e']:8.4f} {v['n']:8.4f} {v['d']:8.4f} "
                     f"{a['roll']:7.4f} {a['pitch']:7.4f} {a['yaw']:7.4f}")
    for label, pos, vel in reference or ():
        lines.append(f"{label:{w}s} {pos[0]:10.4f} {pos[1]:10.4f} {pos[2]:10.4f} "
                     f"{vel[0]:8.4f} {vel[1]:8.4f} {vel[2]:8.4f} {'-':>7s} {'-':>7s} {'-':>7s}")
    return "\n".join(lines)
