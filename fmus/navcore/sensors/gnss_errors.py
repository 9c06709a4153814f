"""GNSS receiver error model: per-axis white noise, noise steps, outliers and outages.

:class:`GnssErrorModel` turns the true position and velocity at the time a fix is taken into
a measured fix.  It reproduces the measurement disturbances of the papers:

* paper 001 (Yuan et al., secs. 3.1-3.2): position noise 5 m, velocity noise 0.3 m/s that steps to
  1.5 m/s at 50-100 s and 3 m/s at 200-300 s (``noise_steps``), and "a patch of outliers with
  peak 15 m/s" on the east and north velocity at 350-360 s (``outlier_patches``);
* paper 004 (Cai et al., sec. 3.1): "one epoch every 10 s carrying m times the nominal noise"
  (``outlier_period``, ``outlier_offset``, ``outlier_multiple``);
* paper 000 (Yang et al., Table 1): different position sigmas per axis (``pos_sigma_*``);
* GNSS outages (``outages``): the fix is flagged invalid;
* time-correlated errors and slowly varying biases of a real receiver (``pos_gm_*``,
  ``pos_bias_*``, ``vel_gm_*``; first-order Gauss-Markov, :mod:`navcore.sensors.gnss_correlated`;
  off by default, drawn from a stream of their own).

Random numbers
--------------
All randomness comes from one ``numpy.random.Generator`` seeded with ``seed``.  Every call of
:meth:`GnssErrorModel.measure` draws exactly 6 standard normals and 18 uniforms, whatever the
windows say, so editing a window (adding an outage, moving an outlier patch) never shifts the
noise of the other epochs: the same seed gives the same clean noise in every scenario variant
and for every filter compared on it.  The caller must therefore call ``measure`` once per fix
epoch, including epochs inside outages.

Time windows
------------
Every window ``[t0, t1)`` is tested with a tolerance of ``TIME_TOLERANCE`` (1e-6 s): a fix at
``t`` is inside when ``t0 - tol <= t < t1 - tol``.  Fix times computed by accumulating a step
(e.g. 349.99999999997 for the 350 s fix) thus fall on the side the user meant.
"""
from __future__ import annotations

import math
from typing import Any, Callable, Dict, List, Sequence, Tuple

import numpy as np

from ..core.limits import Limits
from ..errors import InputError, ParameterError
from ..ins.earth import ned_to_lla_delta
from .gnss_correlated import PARAMETERS as CORRELATED_PARAMETERS
from .gnss_correlated import CorrelatedGnssErrors

#: tolerance [s] used when comparing fix times with window edges and outlier epochs
TIME_TOLERANCE = 1e-6

#: accepted GNSS error sigmas: beyond 10 km / 100 m/s a fix carries no position or velocity
#: information for an INS (and the fix errors leave the range where a small-angle
#: position-to-latitude conversion holds); outlier peaks are bounded by ten times that
POS_SIGMA_LIMITS = Limits(0.0, 1e4)
VEL_SIGMA_LIMITS = Limits(0.0, 100.0)
POS_PEAK_LIMITS = Limits(0.0, 1e5)
VEL_PEAK_LIMITS = Limits(0.0, 1e3)
#: times of windows and epochs: within about 30 years of the start
TIME_LIMITS = Limits(-1e9, 1e9)
TIME_LIMITS_NONNEGATIVE = Limits(0.0, 1e9)

_AXIS_INDEX = {"n": 0, "e": 1, "d": 2}
_QUANTITIES = ("pos", "vel")


# -- parsing helpers ----------------------------------------------------------------------
def quantity_name(value: Any) -> str:
    """Field converter: ``pos`` or ``vel``."""
    q = str(value).strip().lower()
    if q not in _QUANTITIES:
        raise ValueError(f"quantity {value!r} is not 'pos' or 'vel'")
    return q


def ned_axes(value: Any) -> str:
    """Field converter: a non-empty subset of the letters ``n``, ``e``, ``d`` (e.g. ``ne``)."""
    axes = str(value).strip().lower()
    if not axes or any(a not in _AXIS_INDEX for a in axes) or len(set(axes)) != len(axes):
        raise ValueError(f"axes {value!r} is not a non-empty subset of 'ned'")
    return axes


def parse_records(text: Any, name: str,
                  fields: Sequence[Tuple[str, Callable[[Any], Any]]]) -> List[tuple]:
    """Parse ``"a,b,c; a,b,c"`` into a list of tuples, one per record.

    ``fields`` lists ``(field_name, converter)`` pairs; each converter takes the field text
    and returns its value or raises ``ValueError``.  ``text`` may also be a sequence of
    records (tuples/lists) for callers working in Python.  An empty string gives ``[]``;
    empty records (``"1,2,3;"``) are skipped.  A record with the wrong number of fields or a
    field the converter rejects raises :class:`ParameterError` naming the parameter, the
    record and the field.  Windows (records whose first two fields are ``t0``, ``t1``) must
    have ``t1 > t0``.
    """
    if text is None:
        return []
    if isinstance(text, str):
        records = [r.strip() for r in text.split(";")]
        records = [[f.strip() for f in r.split(",")] for r in records if r]
    else:
        try:
            records = [[f.strip() for f in r.split(",")] if isinstance(r, str) else list(r)
                       for r in text]
        except TypeError:
            raise ParameterError(
                f"parameter '{name}' must be a string like "
                f"'{','.join(f for f, _ in fields)}; ...', got {text!r}") from None
    result = []
    expected = ",".join(f for f, _ in fields)
    for record in records:
        shown = ",".join(str(f) for f in record)
        if len(record) != len(fields):
            raise ParameterError(
                f"parameter '{name}': record '{shown}' has {len(record)} fields, "
                f"expected {len(fields)} ({expected})")
        values = []
        for (field, convert), raw in zip(fields, record):
            try:
                values.append(convert(raw))
            except (TypeError, ValueError) as exc:
                raise ParameterError(
                    f"parameter '{name}': record '{shown}': field '{field}' is invalid ({exc})"
                ) from None
        if len(fields) >= 2 and fields[0][0] == "t0" and fields[1][0] == "t1":
            if not values[1] > values[0]:
                raise ParameterError(
                    f"parameter '{name}': record '{shown}': window end t1 must be after t0")
        result.append(tuple(values))
    return result


def read_float(params: Dict[str, Any], name: str, default: float) -> float:
    """Read parameter ``name`` from ``params`` as a finite float."""
    value = params.get(name, default)
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ParameterError(f"parameter '{name}' must be a number, got {value!r}") from None
    if not math.isfinite(x):
        raise ParameterError(f"parameter '{name}' must be finite, got {x}")
    return x


def read_declared(params: Dict[str, Any], name: str, table) -> float:
    """Read parameter ``name`` as a float within the range its ``table`` entry
    ``(default, unit, description, limits)`` declares (the one declaration of that range)."""
    default, unit, _, limits = table[name]
    x = read_float(params, name, default)
    if not limits.contains(x):
        raise ParameterError(f"parameter '{name}' = {x!r} is outside the accepted range "
                             f"{limits.text(unit)}")
    return x


def bounded_float(limits: Limits, unit: str = "") -> Callable[[Any], float]:
    """Field converter: a float within ``limits``."""
    def convert(value: Any) -> float:
        x = float(value)
        if not limits.contains(x):
            raise ValueError(f"{value!r} is outside the accepted range {limits.text(unit)}")
        return x
    return convert


def check_known(params: Dict[str, Any], known, owner: str) -> None:
    """Raise :class:`ParameterError` for a key of ``params`` not in ``known`` (typos)."""
    for key in params:
        if key not in known:
            raise ParameterError(f"{owner}: unknown parameter '{key}'")


def _in_window(t: float, t0: float, t1: float) -> bool:
    return t0 - TIME_TOLERANCE <= t < t1 - TIME_TOLERANCE


# -- the model ----------------------------------------------------------------------------
class GnssErrorModel:
    """Measured GNSS fixes from the truth: noise, noise steps, outliers, outages.

    Parameters (``params`` dict, SI units; any key left out takes the default in brackets):

    ``pos_sigma_n``, ``pos_sigma_e``, ``pos_sigma_d`` [m] (0)
        1-sigma of the white Gaussian position error along north, east, down.
    ``vel_sigma_n``, ``vel_sigma_e``, ``vel_sigma_d`` [m/s] (0)
        1-sigma of the white Gaussian velocity error along north, east, down.
    ``noise_steps`` (str, "")
        ``"t0,t1,quantity,sn,se,sd; ..."`` with times in s, quantity ``pos`` or ``vel`` and
        sigmas in m or m/s: inside ``[t0, t1)`` the three sigmas of that quantity are replaced
        by ``sn, se, sd``.  Where steps of the same quantity overlap the later record wins.
        Paper 001: ``"50,100,vel,1.5,1.5,1.5; 200,300,vel,3,3,3"``.
    ``outlier_patches`` (str, "")
        ``"t0,t1,quantity,axes,peak; ..."`` with ``axes`` a subset of ``ned`` and ``peak`` in
        m or m/s: every fix inside ``[t0, t1)`` gets, on each named axis, an added error of
        random sign (+/- with probability 1/2) and magnitude ``peak * U(0.5, 1)``.  The paper
        gives only the peak ("a patch of outliers with peak 15 m/s", paper 001 sec. 3.2); a
        magnitude between half the peak and the peak keeps every sample of the patch a gross
        error well above the nominal noise while still varying like a real burst.
        Overlapping patches add up (they share the fix's sign and magnitude draws).
        Paper 001: ``"350,360,vel,ne,15"``.
    ``outlier_period`` [s] (0 = off), ``outlier_offset`` [s] (0), ``outlier_multiple`` [-] (0)
        periodic m-times outliers, "one epoch every 10 s carrying m times the nominal noise"
        (paper 004 sec. 3.1): the fix nearest to ``outlier_offset + k * outlier_period``
        (k = 0, 1, ...), i.e. the one within half a fix interval of it, gets on every axis of
        position and velocity an added gross error of random sign and magnitude
        ``outlier_multiple`` times the sigma in force on that axis (after noise steps), on
        top of its ordinary noise.
    ``fix_interval`` [s] (1)
        interval between the receiver's fixes; only used to decide which fix is "nearest" to
        a periodic outlier epoch (the window is ``[-fix_interval/2, +fix_interval/2)`` around
        the epoch, shifted by ``TIME_TOLERANCE``).
    ``outages`` (str, "")
        ``"t0,t1; ..."``: fixes inside ``[t0, t1)`` are returned with ``valid`` False.
    ``pos_gm_sigma_*``, ``pos_bias_sigma_*`` [m], ``vel_gm_sigma_*`` [m/s] (0 = off) and their
        ``*_tau_s`` [s]: the time-correlated errors and biases of
        :mod:`navcore.sensors.gnss_correlated`, added to the white errors (before any outlier).

    ``seed`` seeds the one random generator; the state is made of plain attributes (the
    generator included) so ``copy.deepcopy`` saves and restores it bit for bit.
    """

    state_fields = ("rng", "correlated", "last_pos_error_ned", "last_vel_error_ned")
    derived_fields = ("pos_sigma", "vel_sigma", "noise_steps", "outlier_patches",
                      "outlier_period", "outlier_offset", "outlier_multiple", "fix_interval",
                      "outages", "seed")

    #: name -> (default, unit, description) of every parameter, for components declaring them
    PARAMETERS: Dict[str, Tuple[Any, str, str, Limits]] = {
        "pos_sigma_n": (0.0, "m", "1-sigma white position error, north", POS_SIGMA_LIMITS),
        "pos_sigma_e": (0.0, "m", "1-sigma white position error, east", POS_SIGMA_LIMITS),
        "pos_sigma_d": (0.0, "m", "1-sigma white position error, down", POS_SIGMA_LIMITS),
        "vel_sigma_n": (0.0, "m/s", "1-sigma white velocity error, north", VEL_SIGMA_LIMITS),
        "vel_sigma_e": (0.0, "m/s", "1-sigma white velocity error, east", VEL_SIGMA_LIMITS),
        "vel_sigma_d": (0.0, "m/s", "1-sigma white velocity error, down", VEL_SIGMA_LIMITS),
        "noise_steps": ("", "", "'t0,t1,pos|vel,sn,se,sd; ...' sigmas replaced inside [t0,t1)",
                        None),
        "outlier_patches": ("", "", "'t0,t1,pos|vel,axes,peak; ...' outliers of magnitude "
                                    "peak*U(0.5,1), random sign, on the axes (subset of ned)",
                            None),
        "outlier_period": (0.0, "s", "period of the m-times outlier epochs (0 = off)",
                           TIME_LIMITS_NONNEGATIVE),
        "outlier_offset": (0.0, "s", "time of the first m-times outlier epoch", TIME_LIMITS),
        "outlier_multiple": (0.0, "", "m: outlier magnitude in multiples of the sigma in force",
                             Limits(0.0, 1e4)),
        "fix_interval": (1.0, "s", "interval between fixes (to match outlier epochs to fixes)",
                         Limits(0.0, 3600.0, low_open=True)),
        "outages": ("", "", "'t0,t1; ...' fixes inside [t0,t1) are invalid", None),
        **CORRELATED_PARAMETERS,
    }

    #: random numbers drawn per fix (constant, see module docstring)
    NORMALS_PER_FIX = 6
    UNIFORMS_PER_FIX = 18

    def __init__(self, params: Dict[str, Any], seed: int):
        check_known(params, self.PARAMETERS, "GnssErrorModel")
        table = self.PARAMETERS
        self.pos_sigma = np.array([read_declared(params, f"pos_sigma_{a}", table)
                                   for a in "ned"])
        self.vel_sigma = np.array([read_declared(params, f"vel_sigma_{a}", table)
                                   for a in "ned"])
        time_field = bounded_float(TIME_LIMITS, "s")
        # a noise step's sigmas: the larger (position) bound, checked per quantity below
        sigma_field = bounded_float(POS_SIGMA_LIMITS)
        self.noise_steps = parse_records(params.get("noise_steps", ""), "noise_steps", (
            ("t0", time_field), ("t1", time_field), ("quantity", quantity_name),
            ("sn", sigma_field), ("se", sigma_field), ("sd", sigma_field)))
        self.outlier_patches = parse_records(
            params.get("outlier_patches", ""), "outlier_patches", (
                ("t0", time_field), ("t1", time_field), ("quantity", quantity_name),
                ("axes", ned_axes), ("peak", bounded_float(POS_PEAK_LIMITS))))
        for records, name, bounds, first in (
                (self.noise_steps, "noise_steps", {"vel": VEL_SIGMA_LIMITS}, 3),
                (self.outlier_patches, "outlier_patches", {"vel": VEL_PEAK_LIMITS}, 4)):
            for record in records:
                limits = bounds.get(record[2])
                if limits and not all(limits.contains(x) for x in record[first:]):
                    raise ParameterError(
                        f"parameter '{name}': record '{','.join(map(str, record))}': a velocity "
                        f"value is outside the accepted range {limits.text('m/s')}")
        self.outlier_period = read_declared(params, "outlier_period", table)
        self.outlier_offset = read_declared(params, "outlier_offset", table)
        self.outlier_multiple = read_declared(params, "outlier_multiple", table)
        self.fix_interval = read_declared(params, "fix_interval", table)
        self.outages = parse_records(params.get("outages", ""), "outages",
                                     (("t0", time_field), ("t1", time_field)))
        try:
            self.seed = int(seed)
        except (TypeError, ValueError):
            raise ParameterError(f"parameter 'seed' must be an integer, got {seed!r}") from None
        self.rng = np.random.default_rng(self.seed)
        self.correlated = CorrelatedGnssErrors(
            {name: read_declared(params, name, table) for name in CORRELATED_PARAMETERS},
            self.seed)
        #: NED position [m] and velocity [m/s] errors of the latest fix (for evaluation)
        self.last_pos_error_ned = np.zeros(3)
        self.last_vel_error_ned = np.zeros(3)

    # -- queries ------------------------------------------------------------------------
    def sigma_at(self, t: float) -> Tuple[np.ndarray, np.ndarray]:
        """Per-axis position [m] and velocity [m/s] sigmas in force for a fix at ``t``."""
        pos, vel = self.pos_sigma, self.vel_sigma
        for t0, t1, quantity, sn, se, sd in self.noise_steps:
            if _in_window(t, t0, t1):
                if quantity == "pos":
                    pos = np.array([sn, se, sd])
                else:
                    vel = np.array([sn, se, sd])
        return pos, vel

    def is_outage(self, t: float) -> bool:
        """True when a fix at ``t`` falls inside an outage window."""
        return any(_in_window(t, t0, t1) for t0, t1 in self.outages)

    def is_periodic_outlier_epoch(self, t: float) -> bool:
        """True when the fix at ``t`` is the one nearest a periodic m-times outlier epoch."""
        if self.outlier_period <= 0.0 or self.outlier_multiple <= 0.0:
            return False
        r = t - self.outlier_offset
        k = math.floor(r / self.outlier_period + 0.5)
        if k < 0:
            return False
        d = r - k * self.outlier_period
        half = 0.5 * self.fix_interval
        return -half - TIME_TOLERANCE <= d < half - TIME_TOLERANCE

    # -- measurement --------------------------------------------------------------------
    def measure(self, t: float, lat: float, lon: float, h: float, v_ned) -> Dict[str, Any]:
        """Measured fix taken at ``t`` [s] from the true ``lat``, ``lon`` [rad], ``h`` [m]
        and NED velocity ``v_ned`` [m/s].

        Returns ``dict(lat, lon, h, vn, ve, vd, valid, outlier)``: measured position (rad,
        rad, m) and velocity (m/s), ``valid`` False inside an outage (the values are still
        the noisy measurement, never NaN), ``outlier`` True when a patch or periodic outlier
        was injected into this fix.  NED position errors are converted to latitude,
        longitude and height at the true position with :func:`navcore.ins.earth.ned_to_lla_delta`.
        Non-finite inputs raise :class:`InputError`.
        """
        for label, value in (("t", t), ("lat", lat), ("lon", lon), ("h", h)):
            if not math.isfinite(value):
                raise InputError(f"GnssErrorModel.measure: input '{label}' is {value} "
                                 f"(must be finite)")
        v = np.asarray(v_ned, dtype=float)
        if v.shape != (3,):
            raise InputError(f"GnssErrorModel.measure: input 'v_ned' must have 3 elements, "
                             f"got shape {v.shape}")
        if not np.isfinite(v).all():
            raise InputError(f"GnssErrorModel.measure: input 'v_ned' is {v.tolist()} "
                             f"(must be finite)")

        # Fixed number of draws per fix, whatever the windows (see module docstring).
        z = self.rng.standard_normal(self.NORMALS_PER_FIX)
        u = self.rng.random(self.UNIFORMS_PER_FIX)

        pos_sigma, vel_sigma = self.sigma_at(t)
        errors = {"pos": pos_sigma * z[0:3], "vel": vel_sigma * z[3:6]}
        if self.correlated.active:
            pos_c, vel_c = self.correlated.step(t)
            errors["pos"] += pos_c
            errors["vel"] += vel_c
        outlier = False

        # u[0:6]: patch signs, u[6:12]: patch magnitudes (pos n,e,d then vel n,e,d)
        for t0, t1, quantity, axes, peak in self.outlier_patches:
            if _in_window(t, t0, t1):
                base = 0 if quantity == "pos" else 3
                for a in axes:
                    i = _AXIS_INDEX[a]
                    sign = -1.0 if u[base + i] < 0.5 else 1.0
                    errors[quantity][i] += sign * peak * (0.5 + 0.5 * u[6 + base + i])
                outlier = True

        # u[12:18]: signs of the periodic m-times outliers (pos n,e,d then vel n,e,d)
        if self.is_periodic_outlier_epoch(t):
            signs = np.where(u[12:18] < 0.5, -1.0, 1.0)
            errors["pos"] += signs[0:3] * self.outlier_multiple * pos_sigma
            errors["vel"] += signs[3:6] * self.outlier_multiple * vel_sigma
            outlier = True

        pos_err, vel_err = errors["pos"], errors["vel"]
        self.last_pos_error_ned = pos_err
        self.last_vel_error_ned = vel_err
        dlat, dlon, dh = ned_to_lla_delta(lat, h, pos_err)
        return {
            "lat": float(lat + dlat),
            "lon": float(lon + dlon),
            "h": float(h + dh),
            "vn": float(v[0] + vel_err[0]),
            "ve": float(v[1] + vel_err[1]),
            "vd": float(v[2] + vel_err[2]),
            "valid": not self.is_outage(t),
            "outlier": outlier,
        }
