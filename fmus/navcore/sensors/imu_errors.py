"""IMU error model applied to ideal angle and velocity increments.

:class:`ImuErrorModel` corrupts the ideal body-axis increments of one IMU interval
``[t_end - dt, t_end]`` with the usual strapdown sensor errors (the IMU error model of Groves,
*Principles of GNSS, Inertial, and Multisensor Integrated Navigation Systems*, 2nd ed., ch. 4,
written for increments)::

    dtheta_meas = (I + S_g + M_g) dtheta + (b_g + b_gm(t) + G_g f) dt + w_g
    dvel_meas   = (I + S_a + M_a) dvel   + (b_a + b_am(t)) dt         + w_a

(with ``level_reference_g`` set, ``dvel`` and ``f`` in the scale-factor, misalignment and
g-sensitivity terms are taken relative to the level 1 g specific force, see the class
docstring) with ``S`` the diagonal scale-factor errors, ``M`` the misalignment (off-diagonal)
matrix,
``b`` the constant (turn-on) bias, ``b_m(t)`` a first-order Gauss-Markov bias, ``G_g`` the
gyro g-sensitivity matrix, ``f = dvel/dt`` the mean true specific force over the interval and
``w`` the white noise integrated over the interval (angle / velocity random walk, plus
vibration noise that grows with the manoeuvre intensity).  Paper 000 (Yang et al., Table 1)
gives the low-cost IMU (gyro bias 5 deg/h, ARW 0.06 deg/sqrt(h), accel bias 100 ug,
VRW 10 ug/sqrt(Hz)) and motivates the intensity-dependent noise: the accuracy of a low-cost
IMU "changes with the aircraft manoeuvre"; paper 001 (Yuan et al., sec. 3.1) the navigation
grade one (0.01 deg/h constant + 0.005 deg/h random gyro drift, 50 ug + 50 ug accel);
paper 003 (Xiao & Lu) the vibration from 121 s.

Unit conversions (done once in the constructor):

* deg/h -> rad/s: x * pi/180 / 3600
* deg/sqrt(h) -> rad/sqrt(s): x * pi/180 / 60
* ug -> m/s^2 and ug/sqrt(Hz) -> m/s^2/sqrt(Hz) = m/s/sqrt(s): x * 1e-6 * G0, with the
  standard gravity G0 = 9.80665 m/s^2 (the datasheet "g")
* ppm -> 1e-6; urad -> 1e-6 rad; deg/h/g -> rad/s per m/s^2: x * pi/180 / 3600 / G0

Random numbers: the constructor draws, from ``numpy.random.default_rng(seed)``, always in
this order and always all of them (a zero sigma just scales a draw to zero, so enabling one
error source never changes the realisation of another): 3 gyro biases, 3 accel biases,
3 gyro scale factors, 3 accel scale factors, 6 gyro misalignments, 6 accel misalignments,
9 g-sensitivity elements, 6 initial Gauss-Markov states.  Each :meth:`ImuErrorModel.apply`
uses exactly 12 standard normals (6 white noise, 6 Gauss-Markov driving noise), drawn for 64
calls at a time: numpy's generator gives the same stream in blocks as one call at a time,
and the block is part of the model's state.

The per-sample arithmetic is a kernel over a run axis (:func:`apply_rows`,
:mod:`navcore.core.kernels`); a model is a batch of one.
"""
from __future__ import annotations

import math
from typing import Any, Dict, List, Tuple

import numpy as np

from ..core.kernels import kernel
from ..core.limits import Limits
from ..errors import InputError, ParameterError
from ..ins.constants import DPH, DPSH, G0, UG
from .gnss_errors import TIME_LIMITS, bounded_float, check_known, parse_records, read_declared

#: reference angular rate [rad/s] of the recommended intensity measure (see ImuErrorModel)
INTENSITY_REFERENCE_RATE = 0.1

# Accepted ranges of the error parameters (one declaration each, used by PARAMETERS below).
# Upper bounds: beyond them the sensor measures nothing (a gyro bias of 1e5 deg/h is 28
# deg/s, an accelerometer bias of 1e6 ug is 1 g, a scale factor of 1e5 ppm is 10 %, a
# misalignment of 1e5 urad is 6 deg); noise densities and vibration at the same scale.
GYRO_BIAS_LIMITS = Limits(0.0, 1e5)           # deg/h
GYRO_ARW_LIMITS = Limits(0.0, 1e3)            # deg/sqrt(h)
ACCEL_BIAS_LIMITS = Limits(0.0, 1e6)          # ug
ACCEL_VRW_LIMITS = Limits(0.0, 1e5)           # ug/sqrt(Hz)
SCALE_FACTOR_LIMITS = Limits(0.0, 1e5)        # ppm
MISALIGNMENT_LIMITS = Limits(0.0, 1e5)        # urad
G_SENSITIVITY_LIMITS = Limits(0.0, 1e4)       # deg/h/g
#: correlation times: <= 0 disables the Gauss-Markov process
TAU_LIMITS = Limits(-1e9, 1e9)                # s
#: white-noise multipliers (windows, intensity gain)
NOISE_FACTOR_LIMITS = Limits(0.0, 1e3)
VIBRATION_GYRO_LIMITS = Limits(0.0, 10.0)     # rad/s
VIBRATION_ACCEL_LIMITS = Limits(0.0, 100.0)   # m/s^2

# off-diagonal (row, column) positions of a 3x3 misalignment matrix, in draw order
_OFF_DIAGONAL = ((0, 1), (0, 2), (1, 0), (1, 2), (2, 0), (2, 1))


def parse_windows(text: Any, name: str) -> List[Tuple[float, float, float]]:
    """Parse ``"t0,t1,factor; t0,t1,factor"`` into ``[(t0, t1, factor), ...]``.

    Times in s, ``t1 > t0``, ``factor >= 0`` (dimensionless).  An empty string gives ``[]``;
    a list of 3-tuples is accepted as well.  Malformed text raises :class:`ParameterError`
    naming the parameter ``name`` and the bad record.
    """
    time_field = bounded_float(TIME_LIMITS, "s")
    return parse_records(text, name, (("t0", time_field), ("t1", time_field),
                                      ("factor", bounded_float(NOISE_FACTOR_LIMITS))))


def _sensor_parameters(prefix: str, noun: str, bias_suffix: str, bias_unit: str,
                       bias_limits: Limits, white_noise: Tuple[str, str, str, Limits]
                       ) -> Dict[str, Tuple[Any, str, str, Limits]]:
    """The parameter declarations one sensor triad (gyro or accelerometer) shares in form:
    constant bias, white noise, Gauss-Markov bias, scale factor, misalignment, in this order."""
    noise_name, noise_unit, noise_description, noise_limits = white_noise
    return {
        f"{prefix}_bias_{bias_suffix}": (0.0, bias_unit, f"1-sigma constant {noun} bias, "
                                                         "drawn per axis", bias_limits),
        noise_name: (0.0, noise_unit, noise_description, noise_limits),
        f"{prefix}_bias_instability_{bias_suffix}": (
            0.0, bias_unit, f"steady-state sigma of the Gauss-Markov {noun} bias", bias_limits),
        f"{prefix}_bias_tau_s": (0.0, "s", f"correlation time of the Gauss-Markov {noun} bias "
                                           "(<= 0 disables)", TAU_LIMITS),
        f"{prefix}_scale_factor_ppm": (0.0, "ppm", f"1-sigma {noun} scale-factor error, per "
                                                   "axis", SCALE_FACTOR_LIMITS),
        f"{prefix}_misalignment_urad": (0.0, "urad", f"1-sigma {noun} misalignment, per "
                                                     "off-diagonal element", MISALIGNMENT_LIMITS),
    }


class ImuErrorModel:
    """Errors of a strapdown IMU applied to ideal increments (see module docstring).

    Parameters (``params`` dict; any key left out defaults to 0 / empty = error off):

    Gyroscope

    ``gyro_bias_dph`` [deg/h]
        1-sigma of the constant bias, drawn once per axis from N(0, sigma) with the seed.
    ``gyro_arw_dpsh`` [deg/sqrt(h)]
        angle random walk: white rate noise; the angle noise of one interval has
        sigma = ARW * sqrt(dt).
    ``gyro_bias_instability_dph`` [deg/h], ``gyro_bias_tau_s`` [s]
        first-order Gauss-Markov bias: steady-state 1-sigma (used as the process's sigma, not
        the Allan-deviation floor) and correlation time.  Discretised exactly,
        b_k+1 = exp(-dt/tau) b_k + sigma sqrt(1 - exp(-2 dt/tau)) w_k, started from its
        stationary distribution; ``tau <= 0`` or ``sigma == 0`` disables it.
    ``gyro_scale_factor_ppm`` [ppm]
        1-sigma of the scale-factor error, drawn per axis (diagonal of S_g).
    ``gyro_misalignment_urad`` [urad]
        1-sigma of each of the 6 off-diagonal elements of M_g, drawn independently (a
        general non-orthogonality + mounting misalignment, first order).
    ``g_sensitivity_dphpg`` [deg/h per g]
        1-sigma of each of the 9 elements of the gyro g-sensitivity matrix G_g (full 3x3:
        the diagonal is the sensitivity to specific force along the gyro's own axis, the
        off-diagonal elements the cross-axis terms), drawn once.  The rate error is
        G_g f with f the true specific force.

    Accelerometer

    ``accel_bias_ug`` [ug], ``accel_vrw_ugpsHz`` [ug/sqrt(Hz)] (velocity noise of one
    interval sigma = VRW * sqrt(dt) after conversion to m/s/sqrt(s)),
    ``accel_bias_instability_ug`` [ug], ``accel_bias_tau_s`` [s],
    ``accel_scale_factor_ppm`` [ppm], ``accel_misalignment_urad`` [urad]: as for the gyro.

    ``level_reference_g`` [g]
        0 (default): scale factor, misalignment and g-sensitivity act on the whole specific
        force.  ``r`` > 0: the constant biases are those of a calibration in level flight at
        ``r`` g (body specific force ``f_ref = (0, 0, -r G0)``, forward-right-down), so these
        three errors act on ``f - f_ref`` only: ``(S_a + M_a) f_ref`` and ``G_g f_ref`` are
        part of the measured bias in level flight, and the errors appear only when the
        vehicle accelerates, banks or rotates (datasheets state the bias in a static 1 g
        field, e.g. the zero-rate output of the MPU-6000 and ADIS16445).

    Time-varying white-noise level

    ``noise_level_windows`` (str "t0,t1,factor; ..." or list of tuples)
        the white noises (ARW, VRW and vibration) are multiplied by ``factor`` when the
        middle of the interval, ``t_end - dt/2``, lies in ``[t0, t1)``; overlapping windows
        multiply.
    ``noise_intensity_gain`` [-]
        the ARW/VRW noise level is multiplied by ``1 + gain * intensity``.
    ``vibration_gyro_rps`` [rad/s], ``vibration_accel_mps2`` [m/s^2]
        extra zero-mean white vibration noise: 1-sigma of the error of one output sample's
        mean rate / mean specific force at ``intensity == 1``, scaled by ``intensity`` (so
        the increment error has sigma = value * intensity * dt; unlike ARW/VRW it depends on
        the sample rate, as vibration seen through a sensor's bandwidth does).

    ``intensity`` (argument of :meth:`apply`) is a dimensionless, non-negative measure of how
    hard the vehicle manoeuvres or vibrates during the interval, supplied by the caller: 0
    when static or in straight, level, unaccelerated flight, 1 for a reference manoeuvre.
    Recommended: the norm of the true mean angular rate over the interval divided by
    ``INTENSITY_REFERENCE_RATE`` = 0.1 rad/s (a 3 deg/s standard-rate turn gives about 0.5),
    plus, inside a vibration segment of a motion profile, that segment's vibration level.

    ``seed`` seeds the one random generator.  All state (generator, Gauss-Markov biases,
    cached per-dt coefficients) is made of plain attributes, so ``copy.deepcopy`` of the
    model saves it and a deep copy continues bit for bit identically.
    """

    state_fields = ("rng", "_normals", "_n_used", "gm_bias", "_cached_dt", "_coefficients")
    derived_fields = ("noise_intensity_gain", "noise_level_windows", "seed", "constant_bias",
                      "g_sensitivity", "gyro_matrix", "accel_matrix", "_increment_matrix",
                      "_reference_offset", "_level_bias",
                      "_gm_sigma", "_gm_tau", "_white_density", "_vibration_sigma",
                      "_vibration_on", "_gain_row", "_vibration_row", "_unit_window")

    #: name -> (default, unit, description) of every parameter, for components declaring them
    PARAMETERS: Dict[str, Tuple[Any, str, str, Limits]] = {
        **_sensor_parameters("gyro", "gyro", "dph", "deg/h", GYRO_BIAS_LIMITS,
                             ("gyro_arw_dpsh", "deg/sqrt(h)", "gyro angle random walk",
                              GYRO_ARW_LIMITS)),
        "g_sensitivity_dphpg": (0.0, "deg/h/g", "1-sigma gyro g-sensitivity, per element of "
                                                "a 3x3 matrix", G_SENSITIVITY_LIMITS),
        **_sensor_parameters("accel", "accelerometer", "ug", "ug", ACCEL_BIAS_LIMITS,
                             ("accel_vrw_ugpsHz", "ug/sqrt(Hz)",
                              "accelerometer velocity random walk", ACCEL_VRW_LIMITS)),
        "level_reference_g": (0.0, "", "specific force [g] along body -z at which the constant "
                                        "biases are specified; scale factor, misalignment and "
                                        "g-sensitivity act on f minus it (0 = on all of f)",
                              Limits(0.0, 10.0)),
        "noise_level_windows": ("", "", "'t0,t1,factor; ...' white noise multiplied by factor "
                                        "inside [t0,t1)", None),
        "noise_intensity_gain": (0.0, "", "white noise multiplied by 1 + gain*intensity",
                                 NOISE_FACTOR_LIMITS),
        "vibration_gyro_rps": (0.0, "rad/s", "1-sigma vibration rate noise per sample at "
                                             "intensity 1", VIBRATION_GYRO_LIMITS),
        "vibration_accel_mps2": (0.0, "m/s2", "1-sigma vibration specific-force noise per "
                                              "sample at intensity 1", VIBRATION_ACCEL_LIMITS),
    }

    #: random numbers drawn per apply() call (6 white noise, 6 Gauss-Markov driving noise)
    NORMALS_PER_APPLY = 12
    #: apply() calls whose normals are drawn at once (the same sequence as one call at a time)
    NORMALS_BLOCK = 64

    def __init__(self, params: Dict[str, Any], seed: int):
        check_known(params, self.PARAMETERS, "ImuErrorModel")
        si = self._si_values(params)
        self.noise_intensity_gain = si["noise_intensity_gain"]
        self.noise_level_windows = parse_windows(params.get("noise_level_windows", ""),
                                                 "noise_level_windows")
        try:
            self.seed = int(seed)
        except (TypeError, ValueError):
            raise ParameterError(f"parameter 'seed' must be an integer, got {seed!r}") from None
        self.rng = np.random.default_rng(self.seed)
        gm_initial = self._draw_errors(si)
        self._build_increment_map(si["level_reference_g"])
        self._init_gauss_markov(si, gm_initial)

        # white noise densities (rad/sqrt(s), m/s/sqrt(s)) and vibration sigmas per sample
        self._white_density = np.repeat([si["gyro_arw"], si["accel_vrw"]], 3)
        self._vibration_sigma = np.repeat([si["vib_gyro"], si["vib_accel"]], 3)
        self._vibration_on = bool(si["vib_gyro"] > 0.0 or si["vib_accel"] > 0.0)
        # the per-run arguments of apply_rows for this model alone (a batch of one)
        self._gain_row = np.array([self.noise_intensity_gain])
        self._vibration_row = np.array([self._vibration_on])
        self._unit_window = np.ones(1)

        # coefficients that depend on dt only, recomputed when dt changes, rows of the
        # kernel's argument (state: a restored model keeps its dt and these): the Gauss-Markov
        # phi and driving sigma, the white and the vibration sigma per sample
        self._cached_dt = None
        self._coefficients = np.zeros((4, 1, 6))
        self._coefficients[0] = 1.0
        # the normals of the next apply() calls: row n_used is the next one's
        self._normals = np.zeros((self.NORMALS_BLOCK, self.NORMALS_PER_APPLY))
        self._n_used = self.NORMALS_BLOCK

    def _si_values(self, params: Dict[str, Any]) -> Dict[str, float]:
        """The numeric parameters, checked, in SI units (datasheet units converted once)."""
        def value(name: str) -> float:
            return read_declared(params, name, self.PARAMETERS)

        return {
            "gyro_bias": value("gyro_bias_dph") * DPH,
            "accel_bias": value("accel_bias_ug") * UG,
            "gyro_arw": value("gyro_arw_dpsh") * DPSH,                 # rad/sqrt(s)
            "accel_vrw": value("accel_vrw_ugpsHz") * UG,               # m/s/sqrt(s)
            "gyro_gm_sigma": value("gyro_bias_instability_dph") * DPH,
            "accel_gm_sigma": value("accel_bias_instability_ug") * UG,
            "gyro_tau": value("gyro_bias_tau_s"),
            "accel_tau": value("accel_bias_tau_s"),
            "gyro_sf": value("gyro_scale_factor_ppm") * 1e-6,
            "accel_sf": value("accel_scale_factor_ppm") * 1e-6,
            "gyro_mis": value("gyro_misalignment_urad") * 1e-6,
            "accel_mis": value("accel_misalignment_urad") * 1e-6,
            "g_sens": value("g_sensitivity_dphpg") * DPH / G0,         # rad/s per m/s^2
            "noise_intensity_gain": value("noise_intensity_gain"),
            "vib_gyro": value("vibration_gyro_rps"),
            "vib_accel": value("vibration_accel_mps2"),
            "level_reference_g": value("level_reference_g"),
        }

    def _draw_errors(self, si: Dict[str, float]) -> np.ndarray:
        """Draw the turn-on errors in the fixed order and count of the module docstring;
        returns the 6 standard normals of the initial Gauss-Markov state."""
        rng = self.rng
        #: constant biases, gyro [rad/s] then accel [m/s^2]
        self.constant_bias = np.concatenate((si["gyro_bias"] * rng.standard_normal(3),
                                             si["accel_bias"] * rng.standard_normal(3)))
        gyro_scale = si["gyro_sf"] * rng.standard_normal(3)
        accel_scale = si["accel_sf"] * rng.standard_normal(3)
        gyro_mis_draw = si["gyro_mis"] * rng.standard_normal(6)
        accel_mis_draw = si["accel_mis"] * rng.standard_normal(6)
        #: gyro g-sensitivity matrix G_g [rad/s per m/s^2]
        self.g_sensitivity = si["g_sens"] * rng.standard_normal((3, 3))
        gm_initial = rng.standard_normal(6)

        #: I + S_g + M_g and I + S_a + M_a
        self.gyro_matrix = np.eye(3) + np.diag(gyro_scale)
        self.accel_matrix = np.eye(3) + np.diag(accel_scale)
        for (i, j), mg, ma in zip(_OFF_DIAGONAL, gyro_mis_draw, accel_mis_draw):
            self.gyro_matrix[i, j] = mg
            self.accel_matrix[i, j] = ma
        return gm_initial

    def _build_increment_map(self, level_reference_g: float) -> None:
        """One 6x6 map from the stacked ideal increments (dtheta, dvel) to the measured ones
        without bias and noise (the g-sensitivity term G_g f dt equals G_g dvel), and the
        rate / specific-force error already contained in the biases of a level calibration."""
        self._increment_matrix = np.zeros((6, 6))
        self._increment_matrix[:3, :3] = self.gyro_matrix
        self._increment_matrix[:3, 3:] = self.g_sensitivity
        self._increment_matrix[3:, 3:] = self.accel_matrix
        f_ref = np.array([0.0, 0.0, -level_reference_g * G0])
        self._reference_offset = np.concatenate((self.g_sensitivity @ f_ref,
                                                 (self.accel_matrix - np.eye(3)) @ f_ref))
        #: constant bias minus the reference offset (the constant term of apply), one row
        self._level_bias = (self.constant_bias - self._reference_offset).reshape(1, 6)

    def _init_gauss_markov(self, si: Dict[str, float], gm_initial: np.ndarray) -> None:
        """Gauss-Markov biases (gyro 3, accel 3): steady-state sigma and correlation time;
        disabled axes get sigma 0 and tau = inf (phi = 1, no driving noise, state stays 0)."""
        gyro_tau, accel_tau = si["gyro_tau"], si["accel_tau"]
        gm_on_gyro = gyro_tau > 0.0 and si["gyro_gm_sigma"] > 0.0
        gm_on_accel = accel_tau > 0.0 and si["accel_gm_sigma"] > 0.0
        self._gm_sigma = np.repeat([si["gyro_gm_sigma"] if gm_on_gyro else 0.0,
                                    si["accel_gm_sigma"] if gm_on_accel else 0.0], 3)
        self._gm_tau = np.repeat([gyro_tau if gm_on_gyro else math.inf,
                                  accel_tau if gm_on_accel else math.inf], 3)
        #: current Gauss-Markov bias state, gyro [rad/s] then accel [m/s^2], one row
        self.gm_bias = (self._gm_sigma * gm_initial).reshape(1, 6)     # stationary start

    # -- queries ------------------------------------------------------------------------
    def true_biases(self) -> Tuple[np.ndarray, np.ndarray]:
        """Current total bias (constant + Gauss-Markov) of the gyro [rad/s] and the
        accelerometer [m/s^2], at the end of the latest interval.  Excludes the
        g-sensitivity, scale-factor and misalignment errors, which depend on the motion."""
        total = self.constant_bias + self.gm_bias[0]
        return total[:3].copy(), total[3:].copy()

    def noise_factor(self, t: float) -> float:
        """Product of the ``noise_level_windows`` factors whose window contains ``t``."""
        factor = 1.0
        for t0, t1, f in self.noise_level_windows:
            if t0 <= t < t1:
                factor *= f
        return factor

    # -- measurement --------------------------------------------------------------------
    def _set_dt(self, dt: float) -> None:
        phi = np.exp(-dt / self._gm_tau)
        coefficients = self._coefficients[:, 0]
        coefficients[0] = phi
        # exact discretisation: the stationary variance sigma^2 is preserved
        coefficients[1] = self._gm_sigma * np.sqrt(1.0 - phi * phi)
        coefficients[2] = self._white_density * math.sqrt(dt)
        coefficients[3] = self._vibration_sigma * dt
        self._cached_dt = dt

    def apply(self, t_end: float, dt: float, dtheta, dvel, intensity: float = 0.0):
        """Measured increments ``(dtheta_meas [rad], dvel_meas [m/s])`` (two 3-arrays) for the
        ideal body-axis increments ``dtheta``, ``dvel`` over ``[t_end - dt, t_end]``.

        The bias over the interval is the constant bias plus the mean of the Gauss-Markov
        state at the start and at the end of the interval (trapezoidal integral);
        :meth:`true_biases` afterwards returns the state at ``t_end``.  ``intensity`` is the
        caller's manoeuvre measure (see the class docstring).  Non-finite values, ``dt <= 0``
        or a negative intensity raise :class:`InputError`.
        """
        if not (math.isfinite(t_end) and math.isfinite(dt) and dt > 0.0):
            raise InputError(f"ImuErrorModel.apply: t_end={t_end}, dt={dt}: need finite times "
                             f"and dt > 0")
        if not (math.isfinite(intensity) and intensity >= 0.0):
            raise InputError(f"ImuErrorModel.apply: input 'intensity' is {intensity} "
                             f"(must be finite and >= 0)")
        if len(dtheta) != 3 or len(dvel) != 3:
            raise InputError("ImuErrorModel.apply: inputs 'dtheta' and 'dvel' must have "
                             "3 elements each")
        # (two tuples, as ImuSensor's inverse strapdown gives them: one array of their sum)
        x = (np.array(dtheta + dvel) if type(dtheta) is tuple and type(dvel) is tuple
             else np.concatenate((dtheta, dvel)))
        if x.shape != (6,):
            raise InputError("ImuErrorModel.apply: inputs 'dtheta' and 'dvel' must be "
                             "flat 3-vectors")
        if not math.isfinite(sum(x.tolist())):   # NaN or inf anywhere: a non-finite sum
            raise InputError(f"ImuErrorModel.apply: input dtheta={x[:3].tolist()} "
                             f"dvel={x[3:].tolist()} is not finite")
        if dt != self._cached_dt:
            self._set_dt(dt)

        n = self._n_used
        if n == self.NORMALS_BLOCK:
            self._normals = self.rng.standard_normal(self._normals.shape)
            n = 0
        self._n_used = n + 1
        window = (np.array((self.noise_factor(t_end - 0.5 * dt),))
                  if self.noise_level_windows else self._unit_window)
        out = np.empty((1, 6))
        phi, drive, white, vibration = self._coefficients
        apply_rows(out, (self._increment_matrix @ x).reshape(1, 6), self._normals[None], n,
                   self._level_bias, self.gm_bias, phi, drive, white, vibration, window,
                   self._gain_row, self._vibration_row, float(intensity), float(dt))
        return out[0, :3], out[0, 3:]


@kernel
def apply_rows(out, ideal, normals, n, level_bias, gm, phi, drive, white, vibration, window,
               gain, vibration_on, intensity, dt):
    """The arithmetic of :meth:`ImuErrorModel.apply` for every run of a batch (B rows each):
    ``out`` the measured increments from ``ideal`` (the increment matrix times the ideal
    increments), sample ``n`` of each run's block of ``normals`` (B, block, 12: 6 white, then
    6 Gauss-Markov driving), the constant term ``level_bias``, the Gauss-Markov state ``gm``
    (advanced in place), its ``phi`` and ``drive``, the ``white`` and ``vibration`` sigmas
    per sample; per run the ``noise_level_windows`` factor ``window``, the
    ``noise_intensity_gain`` ``gain`` and whether its ``vibration_on``; the caller's
    manoeuvre ``intensity`` and ``dt``, shared."""
    for b in range(out.shape[0]):
        # white = white_sigma_dt * (window * (1 + gain * intensity)); vibration at
        # window * intensity when it is on and the caller reports a manoeuvre, else off
        scale = window[b] * (1.0 + gain[b] * intensity)
        vib_scale = window[b] * intensity if vibration_on[b] and intensity > 0.0 else -1.0
        z = normals[b, n]
        for i in range(6):
            g0 = gm[b, i]
            g1 = phi[b, i] * g0 + drive[b, i] * z[6 + i]     # gm_end = phi gm + drive z
            gm[b, i] = g1
            w = white[b, i] * scale
            if vib_scale >= 0.0:
                # independent Gaussian sources add in variance: one draw per axis suffices
                v = vibration[b, i] * vib_scale
                w = math.sqrt(w * w + v * v)
            # out = M x + ((constant - reference) + (gm_start + gm_end) / 2) dt + white z
            out[b, i] = (ideal[b, i] + (level_bias[b, i] + 0.5 * (g0 + g1)) * dt) + w * z[i]
