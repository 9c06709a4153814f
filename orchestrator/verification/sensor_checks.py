"""The checks of a sensor FMU: an IMU by the Allan deviation of a static run, a GNSS receiver
by the errors of its fixes against the truth and by its outage and outlier flags.

IMU.  The FMU runs alone for :data:`STATIC_S` seconds standing still (parameter ``profile``
set to ``static`` when it has one; truth inputs, when it has them, held at a static pose).
The overlapping Allan deviation (``allantools.oadev``) of each gyro rate and specific force
(increments over ``imu_dt``) gives:

* ARW / VRW: the slope -1/2 line fitted to the deviation at tau in :data:`WHITE_TAUS` (the
  declared Gauss-Markov part, below, taken off the Allan variance first), read at
  tau = 1 s (white rate noise of density N has sigma(tau) = N / sqrt(tau)), against the
  declared ``gyro_arw_dpsh`` [deg/sqrt(h)] / ``accel_vrw_ugpsHz`` [ug/sqrt(Hz)] or a
  datasheet value given with ``--set datasheet.NAME=VALUE``;
* bias instability: where a Gauss-Markov bias is declared (``*_bias_instability_*`` with
  ``*_bias_tau_s`` > 0), the deviation from tau = tau_c / 3 to 3 tau_c (up to a tenth of the
  run) against the one of the declared model, white noise plus the first-order Gauss-Markov
  process: AVAR(tau) = N^2 / tau + (2 s^2 T / tau) [1 - T / (2 tau) (3 - 4 e^(-tau/T) +
  e^(-2 tau/T))] (s: steady-state sigma, T: correlation time; IEEE Std 952-1997 annex C).

GNSS receiver.  The receiver stands in for ``gnss`` in its scenario for :data:`RECEIVER_S`
seconds with white noise only, an outage at :data:`OUTAGE` and a velocity outlier patch at
:data:`PATCH` (when it has the parameters ``outages`` / ``outlier_patches``).  The per-axis
sample standard deviation of the fix errors outside those windows must lie in the
chi-square band of the declared sigma that a correct receiver meets on all its axes at once
95 % of the time (:func:`noise_band`) (``pos_sigma_*``, ``vel_sigma_*``); a mean error
beyond 3 sigma / sqrt(n) warns (a bias the declared white model does not have).  Inside the
outage every fix must carry ``gnss_valid`` false and outside it true; ``gnss_outlier`` must
flag exactly the fixes of the patch.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Dict, List

import numpy as np

from navcore.ins.constants import DPH, DPSH, UG
from navcore.filters.innovation_stats import chi2_lower_quantile

from .setting import Setting
from .verdicts import Check

STATIC_S = 600.0
#: taus of the white-noise fit [s]
WHITE_TAUS = (0.05, 2.0)
#: declared / measured noise density accepted
DENSITY_BAND = (0.8, 1.25)
#: measured / modelled deviation accepted in the Gauss-Markov part
GM_BAND = (0.6, 1.6)
RECEIVER_S = 300.0
OUTAGE = (100.0, 130.0)
PATCH = (200.0, 210.0)
AXES = ("x", "y", "z")
#: per triad: (increment prefix, rate prefix, density parameter, its SI factor,
#:             bias-instability parameter, its SI factor, correlation-time parameter)
TRIADS = {"gyro": ("imu_dtheta_", "gyro_arw_dpsh", DPSH, "gyro_bias_instability_dph", DPH,
                   "gyro_bias_tau_s"),
          "accel": ("imu_dvel_", "accel_vrw_ugpsHz", UG, "accel_bias_instability_ug", UG,
                    "accel_bias_tau_s")}


@dataclass
class Plan:
    jobs: list


def _declared(setting: Setting, name: str):
    if name in setting.datasheet:
        return float(setting.datasheet[name]), "datasheet (--set)"
    if name in setting.parameters:
        return float(setting.parameters[name]), "declared parameter"
    var = setting.facts.variables.get(name)
    if var is not None and var.start is not None:
        return float(var.start), "declared parameter (start value)"
    return None, None


def plan(setting: Setting, runs: int, quick: bool = False) -> Plan:
    """The one run of a sensor's checks (``quick`` changes nothing)."""
    fmu = str(setting.facts.path)
    if setting.role == "imu_sensor":
        params = dict(setting.parameters)
        if "profile" in setting.facts.variables:
            params["profile"] = "static"
        job = {"kind": "imu_static", "fmu": fmu, "parameters": params, "stop": STATIC_S}
        return Plan([(("static", "imu", 0), job, True)])
    params = {"gnss.noise_steps": "", "gnss.outlier_period": 0.0}
    variables = setting.facts.variables
    params["gnss.outages"] = f"{OUTAGE[0]:g},{OUTAGE[1]:g}" if "outages" in variables else None
    params["gnss.outlier_patches"] = (f"{PATCH[0]:g},{PATCH[1]:g},vel,ne,15"
                                      if "outlier_patches" in variables else None)
    params = {k: v for k, v in params.items() if v is not None}
    params.update(setting.component_parameters())
    job = {"kind": "receiver", "ssd": str(setting.scenario), "component": setting.component,
           "fmu": fmu, "stop": RECEIVER_S, "parameters": params}
    return Plan([(("receiver", "gnss", 0), job, True)])


# -- IMU ---------------------------------------------------------------------------------------
def allan_curves(samples: Dict[str, List[float]], dt: float):
    """Overlapping Allan deviation of each rate series (octave taus up to a tenth of the
    run): {name: (taus, adev)}."""
    import allantools

    out = {}
    for name, values in samples.items():
        x = np.asarray(values, dtype=float)
        n_max = max(2, len(x) // 10)
        m = np.unique(np.round(np.logspace(0, math.log10(n_max), 40)).astype(int))
        taus, adev, _, _ = allantools.oadev(x, rate=1.0 / dt, data_type="freq", taus=m * dt)
        out[name] = (np.asarray(taus).tolist(), np.asarray(adev).tolist())
    return out


def white_density(taus, adev, gm_avar=None) -> float:
    """N of the slope -1/2 line fitted (in log-log) to the deviation within WHITE_TAUS, the
    declared Gauss-Markov part's variance ``gm_avar(taus)`` taken off first when given."""
    t, a2 = np.asarray(taus), np.asarray(adev) ** 2
    if gm_avar is not None:
        a2 = a2 - gm_avar(t)
    sel = (t >= WHITE_TAUS[0]) & (t <= WHITE_TAUS[1]) & (a2 > 0)
    return float(np.exp(np.mean(0.5 * np.log(a2[sel]) + 0.5 * np.log(t[sel]))))


def _declared_gm(setting, triad):
    """The declared Gauss-Markov bias's AVAR as a function of tau, or None."""
    _, _, _, bi_par, bi_si, tau_par = TRIADS[triad]
    sigma, _ = _declared(setting, bi_par)
    tau_c, _ = _declared(setting, tau_par)
    if not sigma or not tau_c or tau_c <= 0:
        return None
    return lambda taus: gm_allan_variance(taus, sigma * bi_si, tau_c)


def gm_allan_variance(taus, sigma, tau_c):
    """AVAR of a first-order Gauss-Markov process (module docstring)."""
    t = np.asarray(taus, dtype=float)
    r = tau_c / t
    return (2 * sigma ** 2 * tau_c / t) * (1 - 0.5 * r * (3 - 4 * np.exp(-1 / r)
                                                           + np.exp(-2 / r)))


def _density_check(setting, triad, curves):
    prefix, par, si, *_ = TRIADS[triad]
    what = "ARW" if triad == "gyro" else "VRW"
    cid = f"imu.{triad}_{what.lower()}"
    title = f"{triad} {what} from the Allan deviation"
    declared, source = _declared(setting, par)
    crit = (f"slope -1/2 line at tau = 1 s over the {source or 'declared'} {par}: within "
            f"{DENSITY_BAND[0]:g}-{DENSITY_BAND[1]:g} on every axis")
    if not declared:
        return Check(cid, title, crit, "nothing declared", "skip",
                     f"{par} is neither a parameter of the FMU nor given with --set "
                     f"datasheet.{par}=VALUE" if declared is None else f"{par} declared 0")
    gm = _declared_gm(setting, triad)
    ratios = {a: white_density(*curves[prefix + a], gm) / (declared * si) for a in AXES}
    measured = ", ".join(f"{a} {r:.3f}" for a, r in ratios.items())
    bad = [a for a, r in ratios.items() if not DENSITY_BAND[0] <= r <= DENSITY_BAND[1]]
    return Check(cid, title, crit, f"measured/declared {measured}",
                 "fail" if bad else "pass",
                 (f"axes {', '.join(bad)}: the noise is {max(ratios[a] for a in bad):.2f} "
                  f"times the declared {declared:g}") if bad else "",
                 {"ratios": ratios, "declared": declared, "source": source},
                 figure="allan.png")


def _gm_check(setting, triad, curves):
    prefix, par, si, bi_par, _, tau_par = TRIADS[triad]
    cid = f"imu.{triad}_bias_instability"
    title = f"{triad} bias instability from the Allan deviation"
    tau_c, _ = _declared(setting, tau_par)
    gm = _declared_gm(setting, triad)
    crit = (f"deviation at tau_c/3..3 tau_c over the declared white + Gauss-Markov model's: "
            f"within {GM_BAND[0]:g}-{GM_BAND[1]:g}")
    if gm is None:
        return Check(cid, title, crit, "no Gauss-Markov bias declared", "skip",
                     f"{bi_par} / {tau_par} declared 0 or absent: no flat part to check")
    density, _ = _declared(setting, par)
    worst = {}
    for a in AXES:
        taus, adev = (np.asarray(v) for v in curves[prefix + a])
        sel = (taus >= tau_c / 3) & (taus <= 3 * tau_c)
        if not sel.any():
            return Check(cid, title, crit, "run too short", "skip",
                         f"the {STATIC_S:g} s run reaches no tau near tau_c = {tau_c:g} s")
        model = np.sqrt((density or 0.0) ** 2 * si ** 2 / taus[sel] + gm(taus[sel]))
        r = adev[sel] / model
        worst[a] = float(r[np.argmax(np.abs(np.log(r)))])
    bad = [a for a, r in worst.items() if not GM_BAND[0] <= r <= GM_BAND[1]]
    return Check(cid, title, crit, "worst measured/model " + ", ".join(
        f"{a} {r:.2f}" for a, r in worst.items()), "fail" if bad else "pass",
        f"axes {', '.join(bad)} off the declared model" if bad else "", {"worst": worst},
        figure="allan.png")


def _allan_figure(curves, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    for ax, (triad, unit) in zip(axes, (("imu_dtheta_", "rad/s"), ("imu_dvel_", "m/s^2"))):
        for a in AXES:
            taus, adev = curves[triad + a]
            ax.loglog(taus, adev, label=a)
        ax.set_xlabel("tau [s]")
        ax.set_ylabel(f"Allan deviation [{unit}]")
        ax.set_title("gyro" if triad == "imu_dtheta_" else "accelerometer")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def _imu_checks(setting, result, workdir):
    if "error" in result:
        return [Check("imu.static_run", "static run", "the FMU runs standing still",
                      "run failed", "fail", result["error"])], {}
    curves = {k: tuple(v) for k, v in result["allan"].items()}
    figure = workdir / "allan.png"
    _allan_figure(curves, figure)
    checks = [_density_check(setting, "gyro", curves), _density_check(setting, "accel", curves),
              _gm_check(setting, "gyro", curves), _gm_check(setting, "accel", curves)]
    return checks, {"allan.png": figure}


# -- GNSS receiver -----------------------------------------------------------------------------
def noise_band(fixes: int, axes: int):
    """The band of sample variance / declared variance that a receiver with the declared
    white noise meets on all ``axes`` at once with 95 % probability (each axis's two-sided
    chi-square band at 0.95^(1/axes), Sidak; at 95 % per axis six correct axes would fail
    one in four runs)."""
    p = 0.95 ** (1.0 / max(axes, 1))
    return tuple(chi2_lower_quantile(q, fixes - 1) / (fixes - 1)
                 for q in ((1 - p) / 2, (1 + p) / 2))


def _noise_check(setting, fixes):
    t = np.asarray(fixes["time"])
    quiet = ~(((t >= OUTAGE[0]) & (t < OUTAGE[1])) | ((t >= PATCH[0]) & (t < PATCH[1])))
    n = int(quiet.sum())
    declared = [(q, a, key + a, _declared(setting, key + a)[0])
                for q, key in (("pos", "pos_sigma_"), ("vel", "vel_sigma_")) for a in "ned"]
    missing = [name for _, _, name, sigma in declared if not sigma]
    declared = [(q, a, sigma) for q, a, _, sigma in declared if sigma]
    lo, hi = noise_band(n, len(declared))
    crit = (f"per axis, sample variance / declared variance of {n} fixes in the chi-square "
            f"band {lo:.2f}-{hi:.2f} (all {len(declared)} axes together 95 %); |mean| <= "
            "3 sigma/sqrt(n) (else warn)")
    ratios, bad, biased = {}, [], []
    for q, a, sigma in declared:
        e = np.asarray(fixes[f"{q}_{a}"])[quiet]
        ratio = float(np.var(e, ddof=1) / sigma ** 2)
        ratios[f"{q}_{a}"] = ratio
        if not lo <= ratio <= hi:
            bad.append(f"{q} {a}: {ratio:.2f}")
        if abs(float(np.mean(e))) > 3 * sigma / math.sqrt(n):
            biased.append(f"{q} {a} mean {np.mean(e):.3g}")
    if not ratios:
        return Check("gnss.noise", "fix errors against the declared sigmas", crit,
                     "no sigma declared", "skip", "declared 0 or absent: " + ", ".join(missing))
    measured = "variance ratios " + ", ".join(f"{k} {v:.2f}" for k, v in ratios.items())
    verdict = "fail" if bad else ("warn" if biased else "pass")
    reason = "; ".join(([f"outside the band: {', '.join(bad)}"] if bad else [])
                       + ([f"biased: {', '.join(biased)}"] if biased else []))
    return Check("gnss.noise", "fix errors against the declared sigmas", crit, measured,
                 verdict, reason, {"ratios": ratios, "fixes": n})


def _flag_check(setting, fixes, cid, title, window, flag, expected_inside, parameter):
    t = np.asarray(fixes["time"])
    crit = (f"'{flag}' is {str(expected_inside).lower()} on every fix in "
            f"[{window[0]:g}, {window[1]:g}) s and {str(not expected_inside).lower()} "
            "elsewhere")
    if parameter not in setting.facts.variables:
        return Check(cid, title, crit, "not declared", "skip",
                     f"the FMU has no parameter '{parameter}' to declare one")
    key = "valid" if flag == "gnss_valid" else "outlier"
    if key not in fixes:
        return Check(cid, title, crit, "no output", "skip", f"the FMU has no output '{flag}'")
    values = np.asarray(fixes[key], dtype=bool)
    inside = (t >= window[0]) & (t < window[1])
    wrong = int((values[inside] != expected_inside).sum()
                + (values[~inside] == expected_inside).sum())
    return Check(cid, title, crit, f"{wrong} of {len(t)} fixes flagged wrong",
                 "fail" if wrong else "pass", f"{wrong} fixes flagged wrong" if wrong else "")


def _receiver_checks(setting, result):
    if "error" in result:
        return [Check("gnss.run", "receiver run", "the FMU runs in its scenario", "run failed",
                      "fail", result["error"])]
    fixes = result["fixes"]
    return [_noise_check(setting, fixes),
            _flag_check(setting, fixes, "gnss.outage", "outage flag", OUTAGE, "gnss_valid",
                        False, "outages"),
            _flag_check(setting, fixes, "gnss.outliers", "outlier flag", PATCH,
                        "gnss_outlier", True, "outlier_patches")]


def judge_plan(setting: Setting, planned: Plan, results, workdir):
    if setting.role == "imu_sensor":
        return _imu_checks(setting, results[("static", "imu", 0)], workdir)
    return _receiver_checks(setting, results[("receiver", "gnss", 0)]), {}


__all__ = ["plan", "judge_plan", "allan_curves", "white_density", "gm_allan_variance"]
