"""The registry of the components wrapped by the FMUs: model name -> component class.

The components live in one module per family: :mod:`navcore.components.sensor_components`
(TrajectoryImu, GnssReceiver), :mod:`navcore.components.imu_sensor` (ImuSensor),
:mod:`navcore.components.guided_uav` (GuidedUav), :mod:`navcore.components.replay` (ImuGnssReplay),
:mod:`navcore.components.kf_components` (Kf and the adaptive/robust filters of papers 001 and 004),
:mod:`navcore.components.ukf_components` (the unscented filters of paper 000) and
:mod:`navcore.components.ahrs_components` (the attitude filters of paper 003); the shell the
INS/GNSS filters share is :mod:`navcore.components.filter_component`.  This module imports the
families and builds
``REGISTRY`` once, so the master can run the same objects directly; the registered classes are
importable from here too (``from navcore.components.registry import Kf``).
"""
from __future__ import annotations

from .ahrs_components import FuzzyUkfAhrs, UkfAhrs
from .kf_components import Iakf, Igg3RobustKf, InsOnly, Kf, NewtonRobustKf, SageHusaFading
from .replay import ImuGnssReplay
from .guided_uav import GuidedUav
from .imu_sensor import ImuSensor
from .sensor_components import GnssReceiver, TrajectoryImu
from .ukf_components import CtfaUkf, ImmUkf, Ukf

#: every component an FMU wraps, by model name (the FMU's name and its slave script's)
REGISTRY = {cls.model_name: cls for cls in (
    TrajectoryImu, GnssReceiver, ImuSensor,
    Kf, SageHusaFading, Iakf, NewtonRobustKf, Igg3RobustKf, InsOnly,
    Ukf, CtfaUkf, ImmUkf,
    ImuGnssReplay,
    GuidedUav,
    UkfAhrs, FuzzyUkfAhrs)}

__all__ = ["REGISTRY", *REGISTRY]
