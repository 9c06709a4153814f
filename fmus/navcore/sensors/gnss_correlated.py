"""Time-correlated and biased GNSS receiver errors: first-order Gauss-Markov processes.

Real GNSS position errors are not white: multipath, residual atmospheric delays and satellite
geometry changes give errors correlated over tens of seconds to minutes, on top of biases of
0.5-2 m that drift over tens of minutes (Groves 2013, *Principles of GNSS, Inertial, and
Multisensor Integrated Navigation Systems*, 2nd ed., sec. 9.4; the usual model of such errors
in INS/GNSS simulation is a first-order Gauss-Markov process, Brown & Hwang 2012,
*Introduction to Random Signals and Applied Kalman Filtering*, 4th ed., sec. 2.9).

:class:`CorrelatedGnssErrors` adds, per NED axis, two such processes to the position error
(``pos_gm_*``: correlation time ``pos_gm_tau_s``, typically 10-100 s; ``pos_bias_*``: a bias
that varies slowly, correlation time ``pos_bias_tau_s``, typically 10-60 min) and one to the
velocity error (``vel_gm_*``).  Each process ``x`` is stationary: its first value is drawn from
``N(0, sigma^2)`` at the first fix and it moves between fixes ``dt`` apart exactly
(the discrete form of ``dx/dt = -x / tau + w``)::

    x_k = exp(-dt / tau) x_{k-1} + sigma sqrt(1 - exp(-2 dt / tau)) n_k,   n_k ~ N(0, 1)

All sigmas default to 0 (off): the receiver's errors are then exactly the white ones of
:mod:`navcore.sensors.gnss_errors`, bit for bit.  The processes draw from their own generator
(seeded from the receiver's ``seed``, a different stream), so switching them on never changes
the white noise, outliers or outages of the same seed.
"""
from __future__ import annotations

import math
from typing import Any, Dict, Tuple

import numpy as np

from ..core.limits import Limits

#: accepted correlated-error sigmas (the white errors' bounds of navcore.gnss_errors)
_POS = Limits(0.0, 1e4)
_VEL = Limits(0.0, 100.0)
#: correlation times: from a fraction of a second to about 30 years
_TAU = Limits(0.0, 1e9, low_open=True)

#: the processes: (name prefix, quantity, default tau [s], what it is)
PROCESSES = (
    ("pos_gm", "pos", 60.0, "Gauss-Markov (time-correlated) position error"),
    ("pos_bias", "pos", 1800.0, "slowly varying position bias (Gauss-Markov)"),
    ("vel_gm", "vel", 30.0, "Gauss-Markov (time-correlated) velocity error"),
)


def _parameter_table() -> Dict[str, Tuple[Any, str, str, Limits]]:
    table = {}
    for prefix, quantity, tau, what in PROCESSES:
        unit, limits = ("m", _POS) if quantity == "pos" else ("m/s", _VEL)
        for axis, name in zip("ned", ("north", "east", "down")):
            table[f"{prefix}_sigma_{axis}"] = (0.0, unit, f"1-sigma of the {what}, {name} "
                                               "(0 = off)", limits)
        table[f"{prefix}_tau_s"] = (tau, "s", f"correlation time of the {what}", _TAU)
    return table


#: name -> (default, unit, description, limits): merged into GnssErrorModel.PARAMETERS
PARAMETERS = _parameter_table()


class CorrelatedGnssErrors:
    """The Gauss-Markov position/velocity errors and biases of one receiver (module docstring).

    ``values`` holds the parameters of :data:`PARAMETERS` (already range-checked); ``seed`` is
    the receiver's.  :meth:`step` advances every process to the fix at ``t`` and returns the
    (position [m], velocity [m/s]) NED errors to add.
    """

    state_fields = ("rng", "values", "last_time")
    derived_fields = ("sigma", "tau", "active")

    def __init__(self, values: Dict[str, float], seed: int):
        self.sigma = np.array([[values[f"{p}_sigma_{a}"] for a in "ned"]
                               for p, _, _, _ in PROCESSES])
        self.tau = np.array([values[f"{p}_tau_s"] for p, _, _, _ in PROCESSES])
        self.active = bool(np.any(self.sigma > 0.0))
        # a stream of its own: the white errors of the same seed are unchanged
        self.rng = np.random.default_rng([int(seed), 1])
        self.values = np.zeros((len(PROCESSES), 3))
        self.last_time = None

    def step(self, t: float) -> Tuple[np.ndarray, np.ndarray]:
        """Advance to the fix at ``t`` [s]; (position error, velocity error), NED."""
        if not self.active:
            return np.zeros(3), np.zeros(3)
        n = self.rng.standard_normal(self.values.shape)
        if self.last_time is None:
            self.values = self.sigma * n                   # stationary start
        else:
            dt = max(t - self.last_time, 0.0)
            a = np.exp(-dt / self.tau)[:, None]
            self.values = a * self.values + self.sigma * np.sqrt(1.0 - a * a) * n
        self.last_time = float(t)
        pos = self.values[0] + self.values[1]
        return pos, self.values[2].copy()

    @staticmethod
    def steady_sigma(values: Dict[str, float]) -> Tuple[np.ndarray, np.ndarray]:
        """Steady-state 1-sigma per NED axis of the correlated position and velocity errors
        (the two position processes are independent: their variances add)."""
        pos = [math.hypot(values[f"pos_gm_sigma_{a}"], values[f"pos_bias_sigma_{a}"])
               for a in "ned"]
        vel = [values[f"vel_gm_sigma_{a}"] for a in "ned"]
        return np.array(pos), np.array(vel)


__all__ = ["CorrelatedGnssErrors", "PARAMETERS", "PROCESSES"]
