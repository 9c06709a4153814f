"""What a navigation FMU is, read from its model description: its role (INS/GNSS filter,
attitude filter, IMU sensor, GNSS receiver) and the ports the role's contract asks for.

A role is detected from the variables alone (nothing inside the FMU needs navfmu):

* ``ins_gnss_filter``: outputs ``nav_lat`` and takes ``gnss_lat`` and ``imu_dtheta_x``;
* ``attitude_filter``: outputs ``nav_roll`` but no ``nav_lat`` and takes ``imu_dtheta_x``;
* ``imu_sensor``: outputs ``imu_dtheta_x`` and no ``gnss_lat``;
* ``gnss_receiver``: outputs ``gnss_lat`` and takes ``truth_lat``;
* ``vehicle``: outputs ``truth_lat`` and ``truth_roll`` but no ``imu_dtheta_x`` (the truth of
  docs/guide/vehicle_in_the_loop.md; body rates and specific force optional).

The contract of each role comes from :mod:`navcore.signals`.  *Required* ports are those the
checks cannot do without (a filter's inputs and its solution); the others are *optional*: a
missing one is listed and the checks that need it are skipped, not failed.
"""
from __future__ import annotations

import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, Optional, Tuple

from navcore.components import imu_sensor
from navcore.core import signals

from ..cosim.fmi3_variables import SUPPORTED_VERSIONS, variables_of
from ..building.build import binary_platforms
from ..errors import NavfmuError

ROLES = ("ins_gnss_filter", "attitude_filter", "imu_sensor", "gnss_receiver", "vehicle")

ROLE_TITLES = {"ins_gnss_filter": "INS/GNSS filter", "attitude_filter": "attitude filter",
               "imu_sensor": "IMU sensor", "gnss_receiver": "GNSS receiver",
               "vehicle": "vehicle"}


@dataclass(frozen=True)
class Variable:
    name: str
    causality: str
    type: str
    unit: str
    start: Optional[str]


@dataclass
class FmuFacts:
    """What the model description of an FMU says (see :func:`read_fmu`)."""

    path: Path
    model_name: str
    variables: Dict[str, Variable]
    can_get_set_state: bool
    can_serialize_state: bool
    can_variable_step: bool
    default_step: Optional[float]
    notes: Tuple[str, ...] = field(default=())

    def outputs(self):
        return {n for n, v in self.variables.items() if v.causality == "output"}

    def inputs(self):
        return {n for n, v in self.variables.items() if v.causality == "input"}

    def parameters(self):
        return {n: v for n, v in self.variables.items() if v.causality == "parameter"}


def _check_runnable(path: Path, identifier: str, version: str = "2.0") -> None:
    """An FMU with neither a binary for this platform nor ``sources/`` to build one from
    cannot run at all: one line, instead of every check failing on it."""
    from fmpy import platform, platform_tuple, sharedLibraryExtension

    with zipfile.ZipFile(path) as z:
        names = z.namelist()
    folder = platform_tuple if version == "3.0" else platform
    binary = f"binaries/{folder}/{identifier}{sharedLibraryExtension}"
    if binary in names or any(n.startswith("sources/") and not n.endswith("/") for n in names):
        return
    have = ", ".join(sorted(binary_platforms(names))) or "none"
    raise NavfmuError(f"{path}: no binary for this platform ({binary}) and no sources/ to "
                      f"build one from (the FMU has binaries for: {have})")


def read_fmu(path) -> FmuFacts:
    """The facts of the FMU file ``path``; :class:`NavfmuError` naming the file when it is
    missing, not an FMU, or not a co-simulation FMU."""
    from fmpy import read_model_description

    p = Path(path)
    if not p.is_file():
        raise NavfmuError(f"{p}: FMU file not found")
    if not zipfile.is_zipfile(p):
        raise NavfmuError(f"{p}: not an FMU (an FMU is a zip archive)")
    try:
        md = read_model_description(str(p), validate=False)
    except Exception as exc:  # fmpy raises plain exceptions for broken archives
        raise NavfmuError(f"{p}: cannot read the FMU's model description: {exc}") from None
    cs = md.coSimulation
    if cs is None or md.fmiVersion not in SUPPORTED_VERSIONS:
        raise NavfmuError(f"{p}: not a co-simulation FMU of FMI {' or '.join(SUPPORTED_VERSIONS)} "
                          f"(verify runs FMI 2.0 and 3.0 co-simulation)")
    _check_runnable(p, cs.modelIdentifier, md.fmiVersion)
    units = {}
    variables = {}
    connector = variables_of(md, md.modelName, p)
    for v in md.modelVariables:
        unit = connector[v.name].unit
        units[v.name] = unit
        variables[v.name] = Variable(v.name, v.causality, connector[v.name].type, unit,
                                     None if v.start is None else str(v.start))
    step = md.defaultExperiment.stepSize if md.defaultExperiment is not None else None
    return FmuFacts(path=p.resolve(), model_name=md.modelName, variables=variables,
                    can_get_set_state=bool(cs.canGetAndSetFMUstate),
                    can_serialize_state=bool(cs.canSerializeFMUstate),
                    can_variable_step=bool(cs.canHandleVariableCommunicationStepSize),
                    default_step=float(step) if step else None)


def detect_role(facts: FmuFacts, forced: Optional[str] = None) -> str:
    """The role of ``facts`` (``forced``: the user's ``--role``, checked against ROLES)."""
    if forced is not None:
        if forced not in ROLES:
            raise NavfmuError(f"--role: expected one of {', '.join(ROLES)}, got {forced!r}")
        return forced
    outs, ins = facts.outputs(), facts.inputs()
    fits = []
    if "nav_lat" in outs and {"gnss_lat", "imu_dtheta_x"} <= ins:
        fits.append("ins_gnss_filter")
    if "nav_roll" in outs and "nav_lat" not in outs and "imu_dtheta_x" in ins:
        fits.append("attitude_filter")
    if "imu_dtheta_x" in outs and "gnss_lat" not in outs:
        fits.append("imu_sensor")
    if "gnss_lat" in outs and "truth_lat" in ins:
        fits.append("gnss_receiver")
    if {"truth_lat", "truth_roll"} <= outs and "imu_dtheta_x" not in outs:
        fits.append("vehicle")
    if len(fits) == 1:
        return fits[0]
    if not fits:
        raise NavfmuError(f"{facts.path}: an FMU of no known role (its variables fit none of "
                          f"{', '.join(ROLES)}; see docs/guide/verify.md); give --role to "
                          "force one")
    raise NavfmuError(f"{facts.path}: several roles fit ({', '.join(fits)}); give --role")


@dataclass(frozen=True)
class Port:
    name: str
    causality: str
    type: str
    unit: str
    required: bool


def _ports(ports, causality, required_names):
    return [Port(p.name, causality, p.type, p.unit, p.name in required_names) for p in ports]


_NAV_STATE = ("nav_time", "nav_lat", "nav_lon", "nav_h", "nav_vn", "nav_ve", "nav_vd")
_IMU_REQUIRED = tuple(p.name for p in signals.IMU[:8])


def contract(role: str):
    """The ports of ``role``'s contract: a list of :class:`Port`."""
    if role == "ins_gnss_filter":
        # the receiver's per-fix sigmas are read only with r_from_receiver: optional
        inputs = {p.name for p in signals.FILTER_INPUTS if p not in signals.GNSS_STD}
        return (_ports(signals.FILTER_INPUTS, "input", inputs)
                + _ports(signals.FILTER_OUTPUTS, "output", set(_NAV_STATE)))
    if role == "attitude_filter":
        return (_ports(signals.AHRS_INPUTS, "input", set(_IMU_REQUIRED))
                + _ports(signals.AHRS_OUTPUTS, "output",
                         {"nav_time", "nav_roll", "nav_pitch", "nav_yaw"}))
    if role == "imu_sensor":
        return _ports(signals.IMU, "output", set(_IMU_REQUIRED))
    if role == "gnss_receiver":
        truth = signals.TRUTH[:7]
        return (_ports(truth, "input", {p.name for p in truth})
                + _ports(signals.GNSS + signals.GNSS_INJECTED, "output",
                         {p.name for p in signals.GNSS}))
    if role == "vehicle":
        return (_ports(signals.TRUTH, "output", {p.name for p in signals.TRUTH})
                + _ports(imu_sensor.RATES, "output", set()))
    raise NavfmuError(f"unknown role {role!r}")


def missing_optional(facts: FmuFacts, role: str):
    """Names of the optional contract ports the FMU does not have."""
    return [p.name for p in contract(role)
            if not p.required and p.name not in facts.variables]


__all__ = ["ROLES", "ROLE_TITLES", "FmuFacts", "read_fmu", "detect_role", "contract",
           "missing_optional", "Port"]
