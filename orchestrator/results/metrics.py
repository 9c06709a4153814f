"""Metric definitions: navigation errors of a filter against the truth, as in the papers' tables.

This is the only navigation knowledge of the master.  It reads recorded columns by the signal
names of the contract (``truth_*`` of the truth source, ``nav_*``/``std_*``/``nis`` of a
filter) and aligns truth and estimate by their times of validity (``truth_time``,
``nav_time``), interpolating the truth linearly at the filter's times, so the numbers do not
depend on the master's stepping order.

Definitions (errors are estimate - truth):

* position error in NED metres: north = dlat (R_N + h), east = dlon (R_E + h) cos(lat),
  down = -dh.
* velocity error per NED axis [m/s].
* Every table, key, column and figure gives the axes in one order, :data:`AXES`: north, east,
  down (docs/guide/index.md, "Axis order"); a paper's east/north/up numbers are rearranged
  (down RMS = up RMS).
* attitude error: roll, pitch, yaw differences wrapped to (-pi, pi] [deg], and the error angle
  phi (NED) with C_bn_est = (I - [phi x]) C_bn_true for NEES.
* RMS per axis over the window ``[t0, t1]`` of nav_time (every recorded row, or only the
  rows where a new GNSS fix arrived: ``samples="fixes"``); max |error| per axis.  Computed
  by :class:`MetricAccumulator` over one or several consecutive chunks of rows (streamed
  runs): root of (sum of squares / number of samples).
* NEES per group (position, velocity, attitude) from the filter's 1-sigma outputs: mean over
  the window of sum_i (e_i / sigma_i)^2, to compare with the group's dimension 3.  It uses the
  diagonal of the covariance only (the filters output their 1-sigmas, not the blocks), so
  correlations between the axes of a group are ignored.
* Inside +-3 sigma: per group and axis, the percentage of the window's samples with
  |e_i| <= 3 sigma_i (99.73 % for a consistent Gaussian error); samples without a sigma
  (sigma <= 0) are not counted.
* Inconsistent filter: its position errors (the N, E and D samples pooled) are outside
  +-3 sigma in more than :data:`INCONSISTENT_OUTSIDE_PCT` % of the samples
  (``position_outside_3sigma_pct``): most of the time its reported sigmas understate its
  error, so :func:`inconsistency_warning` says so on one line (the run's warnings, the
  output folder's metrics.json, the report).
* Only samples within the truth's span count: the first to the last finite ``truth_time``
  recorded (a replayed log's truth source outputs NaN outside its truth file's span); the
  result states that span (``truth_span_s``) next to the samples' ``window_s``.
* A filter with an ``aligned`` output counts only the samples where it is true (an AHRS
  before its initialization has no solution).
* An attitude-only (AHRS) filter has no nav_lat/nav_v*: only the attitude errors exist; its
  consistency is the normalized RMS per Euler angle, sqrt(mean((e / std)^2)) with the
  filter's ``std_roll``/``std_pitch``/``std_yaw`` (1 for a consistent filter).
* Attitude fitness (paper 003 eq. 20, the GA's objective): the RMS over the window's samples
  and the three Euler angles of the attitude error, sqrt(1/(n m) sum_k sum_j e_jk^2) [deg].
* NIS: mean of ``nis`` over the update epochs, with the two-sided 95 % band of the mean of
  N chi-square(dof) samples: chi2.ppf(0.025, N dof)/N .. chi2.ppf(0.975, N dof)/N.
* 3-D RMS, improvement, RMS ratio, the pooled RMS over runs and the RMS table:
  :mod:`orchestrator.results.metric_comparisons`.
* Outlier detection of a filter with an ``n_rejected`` output, at its update epochs (rows with
  ``updated``), against the ``gnss_outlier`` flag of the receiver (the component recording
  it) on the same rows: detection rate = injected epochs with n_rejected > 0 / injected
  epochs; false-alarm rate = clean epochs with n_rejected > 0 / clean epochs, and per
  observation = sum of n_rejected / sum of nis_dof over the clean epochs (the same sums
  over the injected epochs: detected and injected observations).
* Chi-square gates drawn with the statistics: ``chi2_threshold`` of a filter with
  ``chi2_max`` (default 6.635 = chi2(1) 99 %), ``ctfa_t1``/``ctfa_t2`` of a filter with
  ``chi2`` (0 or unset: 6.25/11.35 for a 3-dimensional measurement, else the 90 %/99 %
  chi-square quantiles of nis_dof), read from the run's parameter values
  (``results.metadata["parameters"]``); the defaults apply when the parameter is absent.
"""
from __future__ import annotations

import math

import numpy as np
from scipy import special

from navcore.ins.earth import radii as _radii
# the papers' gates: paper 004's when a run does not set chi2_threshold, paper 000's eq. 25
# thresholds for dof 3 when ctfa_t1/t2 are 0 or unset
from navcore.filters.innovation_stats import (CHI2_THRESHOLD_PAPER_004 as CHI2_GATE_DEFAULT,
                                      CTFA_THRESHOLDS_PAPER_000 as CTFA_THRESHOLDS_DOF3,
                                      chi2_lower_quantile)
from navcore.ins.rotations import euler_to_dcm_array as _dcm
from navcore.ins.rotations import wrap_angle as _wrap

from ..errors import NavfmuError

#: the one axis order of every table, metric key, column and figure: north, east, down
AXES = ("n", "e", "d")
ATTITUDE = ("roll", "pitch", "yaw")


def find_component(results, prefix, required):
    """Name of the recorded component whose columns include ``prefix + required``."""
    for comp in results.components:
        names = results.columns[comp]
        if all(prefix + r in names for r in required):
            return comp
    raise NavfmuError(f"no component records the '{prefix}*' signals {', '.join(required)}; "
                      "metrics need a truth source and a filter with the navigation contract")


def truth_rows(t_truth):
    """Rows holding a truth sample: the first row of each distinct ``truth_time`` (held
    outputs repeat), never a NaN one (a source outside its truth's span outputs NaN)."""
    keep = np.isfinite(t_truth)
    rows = np.flatnonzero(keep)
    keep[rows[1:]] = np.diff(t_truth[rows]) > 0
    return keep


def truth_span(results, truth_name=None):
    """First and last truth time recorded [s], or None when every row is NaN."""
    truth_name = truth_name or find_component(results, "truth_", ("time", "lat", "lon", "h"))
    t = results.column(truth_name, "truth_time")
    t = t[np.isfinite(t)]
    return (float(t[0]), float(t[-1])) if len(t) else None


def navigation_errors(results, filter_name, truth_name=None):
    """Aligned errors of ``filter_name`` against the truth; a dict of arrays over nav_time."""
    truth_name = truth_name or find_component(results, "truth_", ("time", "lat", "lon", "h"))
    col = results.column
    t_nav = col(filter_name, "nav_time")
    keep = truth_rows(col(truth_name, "truth_time"))
    if not keep.any():                 # no truth in these rows: nothing to score
        keep[0] = True
        t_truth = np.array([np.nan])
        inside = np.zeros(len(t_nav), dtype=bool)
    else:
        t_truth = col(truth_name, "truth_time")[keep]
        inside = (t_nav >= t_truth[0] - 1e-9) & (t_nav <= t_truth[-1] + 1e-9)
    if results.has(filter_name, "aligned"):
        inside &= col(filter_name, "aligned") > 0.5

    def truth(var, angle=False):
        y = col(truth_name, "truth_" + var)[keep]
        if angle:
            return _wrap(np.interp(t_nav, t_truth, np.unwrap(y)))
        return np.interp(t_nav, t_truth, y)

    e = {"time": t_nav, "valid": inside}
    if results.has(filter_name, "nav_lat"):
        lat_t, lon_t, h_t = truth("lat"), truth("lon"), truth("h")
        rn, re = _radii(lat_t)
        e["pos_n"] = (col(filter_name, "nav_lat") - lat_t) * (rn + h_t)
        e["pos_e"] = _wrap(col(filter_name, "nav_lon") - lon_t) * (re + h_t) * np.cos(lat_t)
        e["pos_d"] = -(col(filter_name, "nav_h") - h_t)
    if results.has(filter_name, "nav_vn"):
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


def filters_of(results):
    """The recorded components that are filters (every one with a ``nav_time`` output)."""
    return [c for c in results.components if results.has(c, "nav_time")]


#: which rows of a filter's output the metrics use
SAMPLES = ("all", "fixes")


def time_mask(t, window):
    """Samples of ``t`` inside the closed ``window`` (t0, t1) [s], 1e-9 s of slack; all if None."""
    if window is None:
        return np.ones(len(t), dtype=bool)
    return (t >= window[0] - 1e-9) & (t <= window[1] + 1e-9)


def _in_window(e, window):
    return e["valid"] & time_mask(e["time"], window)


def window_mask(e, window):
    """Samples of :func:`navigation_errors` ``e`` that are valid and within ``window``."""
    mask = _in_window(e, window)
    if not mask.any():
        raise NavfmuError(f"the metric window {window} contains no sample of the filter output")
    return mask


def _sample_mask(results, e, window, samples):
    mask = _in_window(e, window)
    if samples == "fixes":
        receiver = find_component(results, "gnss_", ("epoch",))
        epoch = results.column(receiver, "gnss_epoch")
        mask[0] = False
        mask[1:] &= np.diff(epoch) != 0
    return mask


class MetricAccumulator:
    """The metrics of one filter (see the module docstring), accumulated over consecutive
    chunks of a run's rows, so a long run never needs its whole series in memory.

    ``samples``: ``"all"`` (every recorded row, the default) or ``"fixes"`` (the rows where
    a new GNSS fix arrived, i.e. the receiver's ``gnss_epoch`` changed: the solution right
    after each update under Gauss-Seidel stepping).  :meth:`add` takes a chunk as a Results;
    its rows before ``first_row`` only give context (truth to interpolate, the previous
    epoch count) and are not counted.  :meth:`result` returns the dict of
    :func:`filter_metrics`; ``header`` supplies step times and parameters.
    """

    def __init__(self, results, filter_name, window=None, samples="all", truth_name=None):
        if samples not in SAMPLES:
            raise NavfmuError(f"samples: expected one of {', '.join(SAMPLES)}, got {samples!r}")
        self.filter_name, self.window, self.samples = filter_name, window, samples
        self.truth_name = truth_name or find_component(results, "truth_",
                                                       ("time", "lat", "lon", "h"))
        names = results.columns[filter_name]
        # attitude-only (AHRS) filters have no position/velocity outputs
        self.groups = [g for g, first in (("pos", "nav_lat"), ("vel", "nav_vn"))
                       if first in names]
        self.has_std = all(f"std_p{a}" in names for a in AXES)
        # a filter without some 1-sigma outputs (e.g. no attitude) has NEES of the others only
        self.nees_groups = [g for g, (_, std) in _NEES_GROUPS.items()
                            if all(f"{std}{a}" in names for a in AXES)]
        self.has_att_std = all(f"std_{a}" in names for a in ATTITUDE)
        self.normalized_sum = {a: 0.0 for a in ATTITUDE}
        self.normalized_n = {a: 0 for a in ATTITUDE}
        self.has_nis = "nis" in names and "updated" in names
        self.n = 0
        self.t_first = self.t_last = None
        self.truth_first = self.truth_last = None
        self.sq = {}
        self.peak = {}
        self.nees_sum = {g: 0.0 for g in _NEES_GROUPS}
        self.nees_n = {g: 0 for g in _NEES_GROUPS}
        self.inside_3sigma = {g: np.zeros(len(AXES)) for g in _NEES_GROUPS}
        self.sigma_n = {g: np.zeros(len(AXES)) for g in _NEES_GROUPS}
        self.nis_sum, self.nis_n, self.dof_counts = 0.0, 0, {}
        self.epochs = {"injected": [], "n_rejected": [], "dof": []}

    def _add_truth_span(self, results, first_row):
        t = results.column(self.truth_name, "truth_time")[first_row:]
        t = t[np.isfinite(t)]
        if len(t):
            self.truth_first = float(t[0]) if self.truth_first is None else self.truth_first
            self.truth_last = float(t[-1])

    def add(self, results, first_row=0):
        self._add_truth_span(results, first_row)
        e = navigation_errors(results, self.filter_name, self.truth_name)
        mask = _sample_mask(results, e, self.window, self.samples)
        mask[:first_row] = False
        if not mask.any():
            return
        t = e["time"][mask]
        self.t_first = float(t[0]) if self.t_first is None else self.t_first
        self.t_last = float(t[-1])
        self.n += int(mask.sum())
        for key in [f"{g}_{a}" for g in self.groups for a in AXES] + [
                "att_" + a for a in ATTITUDE]:
            x = e[key][mask]
            self.sq[key] = self.sq.get(key, 0.0) + float(np.dot(x, x))
            self.peak[key] = max(self.peak.get(key, 0.0), float(np.max(np.abs(x))))
        col = results.column
        if self.has_att_std:
            for a in ATTITUDE:
                sig = col(self.filter_name, "std_" + a)[mask]
                with np.errstate(divide="ignore", invalid="ignore"):
                    ratio2 = np.where(sig > 0, (e["att_" + a][mask] / sig) ** 2, np.nan)
                finite = ~np.isnan(ratio2)
                self.normalized_sum[a] += float(ratio2[finite].sum())
                self.normalized_n[a] += int(finite.sum())
        if self.has_std:
            for g in self.nees_groups:
                err, std = _NEES_GROUPS[g]
                sig = np.stack([col(self.filter_name, std + a)[mask] for a in AXES])
                err_ = np.stack([e[err + a][mask] for a in AXES])
                with np.errstate(divide="ignore", invalid="ignore"):
                    per_axis = np.where(sig > 0, (err_ / sig) ** 2, np.nan)
                    ratio2 = per_axis.sum(axis=0)
                finite = ~np.isnan(ratio2)
                self.nees_sum[g] += float(ratio2[finite].sum())
                self.nees_n[g] += int(finite.sum())
                counted = ~np.isnan(per_axis)
                self.sigma_n[g] += counted.sum(axis=1)
                self.inside_3sigma[g] += (counted & (per_axis <= 9.0)).sum(axis=1)
        if self.has_nis:
            upd = (col(self.filter_name, "updated") > 0.5) & mask
            if upd.any():
                self.nis_sum += float(col(self.filter_name, "nis")[upd].sum())
                self.nis_n += int(upd.sum())
                for d in np.round(col(self.filter_name, "nis_dof")[upd]).astype(int).tolist():
                    self.dof_counts[d] = self.dof_counts.get(d, 0) + 1
        epochs = update_epochs(results, self.filter_name, self.window, first_row=first_row)
        if epochs is not None and "n_rejected" in epochs and "injected" in epochs:
            for key in self.epochs:
                self.epochs[key].append(epochs[key])

    def _rms(self, key):
        return math.sqrt(self.sq[key] / self.n)

    def result(self, header=None):
        if self.n == 0:
            span = ("no truth sample at all" if self.truth_first is None else
                    f"the truth spans {self.truth_first:.10g} to {self.truth_last:.10g} s")
            raise NavfmuError(f"the metric window {self.window} contains no sample of the "
                              f"filter output ({self.filter_name}, samples '{self.samples}') "
                              f"within the truth's span ({span})")
        out = {"window_s": [self.t_first, self.t_last], "samples": self.n,
               "truth_span_s": [self.truth_first, self.truth_last]}
        if self.samples != "all":
            out["sampled_at"] = self.samples
        if "pos" in self.groups:
            out["position_rms_m"] = {a: self._rms("pos_" + a) for a in AXES}
            out["position_max_m"] = {a: self.peak["pos_" + a] for a in AXES}
        if "vel" in self.groups:
            out["velocity_rms_mps"] = {a: self._rms("vel_" + a) for a in AXES}
            out["velocity_max_mps"] = {a: self.peak["vel_" + a] for a in AXES}
        out["attitude_rms_deg"] = {a: math.degrees(self._rms("att_" + a)) for a in ATTITUDE}
        out["attitude_max_deg"] = {a: math.degrees(self.peak["att_" + a]) for a in ATTITUDE}
        # paper 003 eq. 20 over the accumulated squares (as attitude_fitness)
        att_sq = sum(self.sq["att_" + a] for a in ATTITUDE)
        out["attitude_fitness_deg"] = math.degrees(math.sqrt(att_sq / (len(ATTITUDE) * self.n)))
        if self.has_att_std:
            out["attitude_normalized_rms"] = {
                a: (math.sqrt(self.normalized_sum[a] / self.normalized_n[a])
                    if self.normalized_n[a] else float("nan")) for a in ATTITUDE}
        if self.has_std:
            out["nees"] = {g: (self.nees_sum[g] / self.nees_n[g] if self.nees_n[g]
                               else float("nan")) for g in self.nees_groups}
            out["inside_3sigma_pct"] = {
                g: {a: (100.0 * float(self.inside_3sigma[g][i] / self.sigma_n[g][i])
                        if self.sigma_n[g][i] else float("nan")) for i, a in enumerate(AXES)}
                for g in self.nees_groups}
            counted = float(self.sigma_n["position"].sum())
            if "position" in self.nees_groups and counted:
                out["position_outside_3sigma_pct"] = 100.0 * (
                    1.0 - float(self.inside_3sigma["position"].sum()) / counted)
        if self.nis_n:
            dof = _median_of_counts(self.dof_counts)
            n = self.nis_n
            out["nis"] = {"mean": self.nis_sum / n, "dof": dof, "updates": n,
                          "band95": nis_band95(n, dof)}
        if header is not None and self.filter_name in getattr(header, "step_time_s", {}):
            out["time_per_step_ms"] = 1e3 * float(header.step_time_s[self.filter_name])
        if self.epochs["dof"]:
            cat = {k: np.concatenate(v) for k, v in self.epochs.items()}
            detection = rejection_statistics(cat["injected"], cat["n_rejected"], cat["dof"])
            detection["receiver"] = find_receiver(header) if header is not None else None
            _add_gate(detection, header, self.filter_name)
            out["outlier_detection"] = detection
        return out


_NEES_GROUPS = {"position": ("pos_", "std_p"), "velocity": ("vel_", "std_v"),
                "attitude": ("phi_", "std_att_")}

#: a filter whose position errors are outside +-3 sigma in more than this percentage of the
#: samples is inconsistent "for most of the time" (a consistent Gaussian error: 0.27 %)
INCONSISTENT_OUTSIDE_PCT = 50.0


def inconsistency_warning(label, metrics):
    """The one-line warning for filter ``label`` whose ``metrics`` (:func:`filter_metrics`)
    have most position errors outside +-3 sigma, or None (consistent enough, or no sigmas)."""
    outside = metrics.get("position_outside_3sigma_pct")
    if outside is None or not outside > INCONSISTENT_OUTSIDE_PCT:
        return None
    return (f"filter '{label}' is inconsistent: {outside:.0f} % of its position errors are "
            "outside +/-3 sigma (its reported sigmas understate its error; real GNSS errors "
            "are biased and time-correlated: gnss_corr_time; a real IMU does worse than its "
            "datasheet: imu_noise_factor)")


def nis_band95(updates, dof):
    """The two-sided 95 % band of the mean of ``updates`` chi-square(``dof``) samples (the
    NIS band of the module docstring)."""
    n = int(updates)
    return [float(chi2_lower_quantile(0.025, n * dof) / n),
            float(chi2_lower_quantile(0.975, n * dof) / n)]


def _median_of_counts(counts):
    """Median (lower middle for an even count, as ``int(round(median))`` of the values for
    the usual single dof) of values given as value -> count."""
    values = sorted(counts)
    total = sum(counts.values())
    seen = 0
    for v in values:
        seen += counts[v]
        if 2 * seen >= total:
            return int(v)
    return int(values[-1])


def filter_metrics(results, filter_name, window=None, truth_name=None, samples="all"):
    """All metrics of one filter as a JSON-ready dict (see the module docstring)."""
    acc = MetricAccumulator(results, filter_name, window=window, samples=samples,
                            truth_name=truth_name)
    acc.add(results)
    return acc.result(results)


def attitude_fitness(errors, mask=None):
    """Paper 003 eq. 20: RMS over the samples (``mask``) and the three Euler angles of the
    attitude error of :func:`navigation_errors`, in deg."""
    mask = errors["valid"] if mask is None else mask
    squares = np.stack([errors["att_" + a][mask] ** 2 for a in ATTITUDE])
    return math.degrees(float(np.sqrt(np.mean(squares))))


# -- outlier detection ---------------------------------------------------------------------
def find_receiver(results):
    """Name of the component recording ``gnss_outlier`` (the receiver), or None."""
    try:
        return find_component(results, "gnss_", ("outlier",))
    except NavfmuError:
        return None


def update_epochs(results, filter_name, window=None, receiver_name=None, first_row=0):
    """The rows where ``filter_name`` updated (``updated`` output), within ``window`` of its
    nav_time: dict of arrays ``time``, ``dof`` (nis_dof) and, when recorded, ``chi2_max``,
    ``chi2``, ``nis``, ``n_rejected`` of the filter and ``injected`` (the receiver's
    gnss_outlier on the same rows, i.e. of the fix the update used).  None if the filter
    has no ``updated`` output."""
    names = results.columns.get(filter_name, ())
    if "updated" not in names:
        return None
    col = results.column
    rows = col(filter_name, "updated") > 0.5
    rows[:first_row] = False
    t = col(filter_name, "nav_time")
    rows &= time_mask(t, window)
    out = {"time": t[rows]}
    out["dof"] = (col(filter_name, "nis_dof")[rows] if "nis_dof" in names
                  else np.full(int(rows.sum()), np.nan))
    for var in ("chi2_max", "chi2", "nis", "n_rejected"):
        if var in names:
            out[var] = col(filter_name, var)[rows]
    receiver_name = receiver_name or find_receiver(results)
    if receiver_name is not None:
        out["injected"] = col(receiver_name, "gnss_outlier")[rows] > 0.5
    return out


def rejection_statistics(injected, n_rejected, n_observations):
    """Detection and false-alarm rates from per-update-epoch arrays: ``injected`` (bool),
    ``n_rejected`` (observations rejected/replaced), ``n_observations`` (the update's
    dimension).  Rates are nan when their denominator is 0."""
    injected = np.asarray(injected, dtype=bool)
    n_rejected = np.asarray(n_rejected, dtype=float)
    n_observations = np.asarray(n_observations, dtype=float)
    if not (injected.shape == n_rejected.shape == n_observations.shape):
        raise NavfmuError("rejection_statistics: injected, n_rejected and n_observations must "
                          f"have one value per epoch (shapes {injected.shape}, "
                          f"{n_rejected.shape}, {n_observations.shape})")
    detected = n_rejected > 0
    clean = ~injected
    n_inj, n_clean = int(injected.sum()), int(clean.sum())
    hits, alarms = int((detected & injected).sum()), int((detected & clean).sum())
    obs_clean = float(n_observations[clean].sum())
    rejected_clean = float(n_rejected[clean].sum())
    obs_injected = float(n_observations[injected].sum())
    rejected_injected = float(n_rejected[injected].sum())
    ratio = lambda a, b: float(a / b) if b > 0 else float("nan")  # noqa: E731
    return {"epochs": int(injected.size), "injected_epochs": n_inj, "detected_epochs": hits,
            "detection_rate": ratio(hits, n_inj),
            "clean_epochs": n_clean, "false_alarm_epochs": alarms,
            "false_alarm_rate": ratio(alarms, n_clean),
            "clean_observations": int(obs_clean),
            "false_alarm_observations": int(rejected_clean),
            "false_alarm_rate_per_observation": ratio(rejected_clean, obs_clean),
            "injected_observations": int(obs_injected),
            "detected_observations": int(rejected_injected)}


def _add_gate(detection, results, filter_name):
    """The chi2_threshold gate and its chi2(1) false-alarm probability, when there is one."""
    if results is None:
        return
    gates = [g for g in chi2_thresholds(results, filter_name) if g["name"] == "chi2_threshold"]
    if gates:
        detection["chi2_threshold"] = gates[0]
        # chi2(1).sf, as scipy.stats computes it
        detection["expected_false_alarm_rate_chi2_1"] = float(special.chdtrc(1,
                                                                            gates[0]["value"]))


def _parameter(results, component, name):
    params = (getattr(results, "metadata", None) or {}).get("parameters") or {}
    value = (params.get(component) or {}).get(name)
    try:
        return None if value is None else float(value)
    except (TypeError, ValueError):
        return None


def chi2_thresholds(results, filter_name):
    """Chi-square gates of a filter's statistics: list of dicts ``name``, ``value``,
    ``statistic`` (the output they apply to) and ``source`` ('parameter' if the run set the
    value, else the documented default)."""
    names = results.columns.get(filter_name, ())
    gates = []
    if "chi2_max" in names:
        value = _parameter(results, filter_name, "chi2_threshold")
        gates.append({"name": "chi2_threshold", "statistic": "chi2_max",
                      "value": value if value is not None else CHI2_GATE_DEFAULT,
                      "source": "parameter" if value is not None else "default"})
    if "chi2" in names:
        dof = None
        if "nis_dof" in names and "updated" in names:
            upd = results.column(filter_name, "updated") > 0.5
            if upd.any():
                dof = int(round(float(np.median(results.column(filter_name, "nis_dof")[upd]))))
        for i, (name, p) in enumerate((("ctfa_t1", 0.90), ("ctfa_t2", 0.99))):
            value = _parameter(results, filter_name, name)
            if value is not None and value > 0:
                gates.append({"name": name, "statistic": "chi2", "value": value,
                              "source": "parameter"})
            elif dof is None or dof == 3:
                gates.append({"name": name, "statistic": "chi2",
                              "value": CTFA_THRESHOLDS_DOF3[i], "source": "default for dof 3"})
            else:
                gates.append({"name": name, "statistic": "chi2",
                              "value": float(chi2_lower_quantile(p, dof)),
                              "source": f"default: chi2({dof}) {100 * p:.0f} %"})
    return gates
