"""The truth attitude a GNSS receiver's lever arm needs, wired into a system model.

A receiver with an antenna lever arm puts its fixes at the antenna, ``r + C_bn l``: it needs
the truth attitude ``truth_roll/pitch/yaw`` (and takes the body rate of the antenna velocity
term from the attitude change between two of its steps).  Every shipped model connects them;
for a user's model that does not, :func:`connect_receiver_attitude` (verify's lever-arm case)
adds those three connections from the component that feeds the receiver its ``truth_lat``,
and says why not when that source does not output them.
"""
from __future__ import annotations

import dataclasses

from ..errors import NavfmuError
from .ssp import Connection, SystemModel

#: the receiver's inputs its lever arm is rotated with
ATTITUDE = ("truth_roll", "truth_pitch", "truth_yaw")


def truth_source(model: SystemModel, receiver: str) -> str:
    """The component whose ``truth_lat`` drives ``receiver`` (NavfmuError when none does)."""
    for c in model.connections:
        if c.end_component == receiver and c.end_connector == "truth_lat":
            return c.start_component
    raise NavfmuError(f"{model.name}: component '{receiver}' takes no truth_lat from any "
                      "component (a receiver with a lever arm needs the truth's attitude)")


def connect_receiver_attitude(model: SystemModel, receiver: str = "gnss") -> SystemModel:
    """``model`` with ``truth_roll/pitch/yaw`` of the receiver's truth source connected to
    ``receiver`` (those already connected are kept); NavfmuError naming the component when
    the source declares no such outputs."""
    source = truth_source(model, receiver)
    src = model.component(source)
    missing = [n for n in ATTITUDE if src.connectors.get(n, ("",))[0] != "output"]
    if missing:
        raise NavfmuError(f"{model.name}: component '{source}' does not output "
                          f"{', '.join(missing)}, which the receiver '{receiver}' needs for "
                          "its lever arm")
    fed = {c.end_connector for c in model.connections if c.end_component == receiver}
    new = [n for n in ATTITUDE if n not in fed]
    rx = model.component(receiver)
    rx = dataclasses.replace(rx, connectors={**rx.connectors,
                                             **{n: ("input", "Real") for n in new}},
                             units={**rx.units, **{n: "rad" for n in new}})
    components = [rx if c.name == receiver else c for c in model.components]
    connections = list(model.connections) + [Connection(source, n, receiver, n) for n in new]
    return dataclasses.replace(model, components=components, connections=connections)


def receiver_has_attitude(model: SystemModel, receiver: str = "gnss") -> bool:
    """Whether ``receiver`` is fed every one of ``truth_roll/pitch/yaw``."""
    fed = {c.end_connector for c in model.connections if c.end_component == receiver}
    return all(n in fed for n in ATTITUDE)


__all__ = ["connect_receiver_attitude", "receiver_has_attitude", "truth_source", "ATTITUDE"]
